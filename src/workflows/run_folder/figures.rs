//! The figures of a gait run's report: kinematics, ground forces and actuators against
//! the percent of the gait cycle, the phase legend and the body animation.

use super::evaluation::Evaluation;
use super::sections::body_animation;
use super::GaitRun;
use crate::report::body::BodyAnimation;
use crate::report::gait_figures::{phase_legend, ActuatorTraces, ChannelFigures, CycleAxis};
use crate::report::table::Table;

/// A gait run's figures, drawn.
pub(super) struct Figures {
    /// The percent-of-cycle axis.
    pub cycle: CycleAxis,
    /// Joint angles (SVG).
    pub angles: Vec<String>,
    /// Joint angular velocities (SVG).
    pub velocities: Vec<String>,
    /// Ground forces and centre of pressure (SVG).
    pub forces: Vec<String>,
    /// Actuator torques, activations and controls (SVG).
    pub actuators: Vec<String>,
    /// The phase legend.
    pub legend: Table,
    /// The body, moving.
    pub animation: BodyAnimation,
    /// The animation's key instants, for print (SVG).
    pub film_strip: String,
}

impl Figures {
    /// Draw the figures of `run` evaluated as `ev`; `verdict` is written across every
    /// plot unless it is `converged`.
    pub fn draw(run: &GaitRun, ev: &Evaluation, verdict: &str) -> Self {
        let (model, sol) = (run.model, run.solution);
        let (t0, t1) = sol.span();
        let line = ev.line();
        let cycle = CycleAxis::from_events(run.events, (t0, t1));
        let figures = ChannelFigures {
            line,
            nodes: &ev.cmp,
            line_label: ev.line_label(),
            cycle,
            window: (t0, t1),
            phases: sol
                .phase_spans()
                .iter()
                .map(|p| (p.t0, p.t1, p.name.clone()))
                .collect(),
            note: (verdict != "converged").then(|| verdict.to_string()),
        };
        let (angle_plots, velocity_plots) = figures.kinematics();
        let angles: Vec<String> = angle_plots.iter().map(|p| p.to_svg()).collect();
        let velocities: Vec<String> = velocity_plots.iter().map(|p| p.to_svg()).collect();
        let forces: Vec<String> = figures.loads().iter().map(|p| p.to_svg()).collect();
        let legend = phase_legend(run.sequence, &sol.phases, &cycle, (t0, t1));
        let states = ev.states();
        let (lo, hi) = run.control_bounds;
        let traces =
            ActuatorTraces::from_samples(model, sol, states, Some((lo.to_vec(), hi.to_vec())));
        let actuators: Vec<String> = figures
            .actuators(&traces)
            .iter()
            .map(|p| p.to_svg())
            .collect();
        let animation = body_animation(model, sol, line, states, &cycle, (t0, t1));
        let film_strip = animation.film_strip();
        Figures {
            cycle,
            angles,
            velocities,
            forces,
            actuators,
            legend,
            animation,
            film_strip,
        }
    }
}
