//! The gait figures of a run in the conventions of gait papers: every tracked channel
//! (angles, angular velocities, ground forces, CoP) against percent of the gait cycle,
//! each leg from its own heel strike, so that over a mirrored half cycle the left leg
//! fills 0–50 % and the right 50–100 % of one leg's cycle; the trial's clock on a second
//! axis along the top; the residual between model and measurement as a band; a phase
//! legend that names each phase's contacts and what begins and ends it.

mod actuators;
mod phase_legend;

pub use actuators::{ActuatorTraces, Trace};
pub use phase_legend::phase_legend;

use super::plot::{Band, LinePlot, LineStyle, Series, Span, TopAxis};
use crate::data::events::Events;
use crate::model::gait::COORDINATES;
use crate::problems::evaluation::{Comparison, LOAD_NAMES};

/// Sides in the order of [`Comparison::model_feet`].
const SIDES: [&str; 2] = ["right", "left"];

/// Leg joints in the order of a [`Trace::joint`].
const JOINTS: [&str; 3] = ["hip", "knee", "ankle"];

/// Percent of the gait cycle for each leg, from its own heel strike.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CycleAxis {
    /// Duration of one gait cycle (s).
    pub period: f64,
    /// Reference heel strike of each leg `[right, left]` (s): 0 % of its cycle.
    pub heel_strike: [f64; 2],
}

impl CycleAxis {
    /// From the measured events: each leg's last heel strike at or before the start of
    /// `window` (else its first one after, less a period), and the period of the cycles
    /// that contain the window's start (else twice the window: a half cycle).
    pub fn from_events(events: &Events, window: (f64, f64)) -> Self {
        let tol = 1e-6;
        let mut periods = Vec::new();
        for s in 0..2 {
            for w in events.heel_strike[s].windows(2) {
                if w[0] <= window.0 + tol && window.0 < w[1] {
                    periods.push(w[1] - w[0]);
                }
            }
        }
        let period = if periods.is_empty() {
            2.0 * (window.1 - window.0)
        } else {
            periods.iter().sum::<f64>() / periods.len() as f64
        };
        let heel_strike = [0, 1].map(|s| {
            let hs = &events.heel_strike[s];
            match hs.iter().rev().find(|&&t| t <= window.0 + tol) {
                Some(&t) => t,
                None => hs.first().map_or(window.0, |&t| t - period),
            }
        });
        Self {
            period,
            heel_strike,
        }
    }

    /// Percent of leg `side`'s gait cycle at time `t` (s).
    pub fn percent(&self, side: usize, t: f64) -> f64 {
        100.0 * (t - self.heel_strike[side]) / self.period
    }

    /// The leg whose cycle starts nearest the window's start (its percent axis carries
    /// the channels that belong to neither leg, such as the trunk).
    pub fn lead_side(&self, window: (f64, f64)) -> usize {
        let d = |s: usize| (window.0 - self.heel_strike[s]).abs();
        if d(1) < d(0) {
            1
        } else {
            0
        }
    }

    fn top_axis(&self, window: (f64, f64), sides: &[usize]) -> TopAxis {
        let label = if sides.len() == 2 {
            "trial time (s) of each leg's part".to_string()
        } else {
            "trial time (s)".to_string()
        };
        TopAxis {
            label,
            segments: sides
                .iter()
                .map(|&s| {
                    (
                        self.percent(s, window.0),
                        self.percent(s, window.1),
                        window.0,
                        window.1,
                    )
                })
                .collect(),
        }
    }
}

/// What the channel plots show.
pub struct ChannelFigures<'a> {
    /// Model and measurement on the line grid (the fine re-integration, or the nodes).
    pub line: &'a Comparison,
    /// The model at the shooting nodes.
    pub nodes: &'a Comparison,
    /// Legend of the model line.
    pub line_label: &'a str,
    /// The percent-of-cycle axis.
    pub cycle: CycleAxis,
    /// Tracked window (s).
    pub window: (f64, f64),
    /// Continuous phases `(start s, end s, name)`.
    pub phases: Vec<(f64, f64, String)>,
    /// A caution written across every plot (e.g. "not converged").
    pub note: Option<String>,
}

/// What a plot shows: a coordinate (index into [`COORDINATES`], the right leg's for a
/// joint), its velocity, or a load component of a foot (index into `LOAD_NAMES`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    /// A position or angle.
    Angle(usize),
    /// Its velocity.
    Velocity(usize),
    /// Tangential force, normal force or CoP x.
    Load(usize),
}

/// One plot of the gait figures: its title and unit, what it shows, whether both legs
/// are overlaid, the display scale, and how many line-grid samples make one drawn point
/// (smooth channels need no more than one per 3 ms; forces keep every sample, where
/// transients hide).
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelPlot {
    /// Title.
    pub title: String,
    /// y-axis label with unit.
    pub unit: &'static str,
    /// What it shows.
    pub channel: Channel,
    /// Whether both legs are overlaid (a joint or a foot).
    pub bilateral: bool,
    /// Display scale (e.g. rad → °).
    pub scale: f64,
    /// Draw every so many samples of the line grid.
    pub every: usize,
}

impl ChannelPlot {
    /// The coordinate index of a position or velocity channel for leg `side` (`None`:
    /// neither leg), in [`COORDINATES`] order.
    fn coordinate(&self, side: Option<usize>) -> Option<usize> {
        match self.channel {
            Channel::Angle(i) | Channel::Velocity(i) => Some(i + 3 * side.unwrap_or(0)),
            Channel::Load(_) => None,
        }
    }

    /// The column of a run's CSV files (`fine_grid.csv`, `tracking.csv`) holding the
    /// channel: `who` is `model` or `data`, `side` the leg (`None` for neither).
    pub fn csv_column(&self, who: &str, side: Option<usize>) -> String {
        let leg = ["r", "l"][side.unwrap_or(0)];
        match self.channel {
            Channel::Angle(_) => {
                format!("{who}_{}", COORDINATES[self.coordinate(side).unwrap_or(0)])
            }
            Channel::Velocity(_) => format!(
                "{who}_{}_dot",
                COORDINATES[self.coordinate(side).unwrap_or(0)]
            ),
            Channel::Load(c) => format!("{who}_{}_{leg}", LOAD_NAMES[c]),
        }
    }
}

/// The plots of the gait figures, each group in report order: positions and angles
/// (pelvis x, y, trunk, then hip, knee, ankle with both legs), their velocities, and the
/// normal force, tangential force and CoP of both feet.
pub fn channel_plots() -> [Vec<ChannelPlot>; 3] {
    let deg = 180.0 / std::f64::consts::PI;
    let (mut angles, mut velocities) = (Vec::new(), Vec::new());
    let plot = |title: String, unit, channel, bilateral, scale, every| ChannelPlot {
        title,
        unit,
        channel,
        bilateral,
        scale,
        every,
    };
    for (i, coordinate) in COORDINATES.iter().enumerate().take(3) {
        let name = coordinate.replace('_', " ");
        let (unit, vunit, scale) = if i < 2 {
            ("position (m)", "velocity (m/s)", 1.0)
        } else {
            ("angle (°)", "angular velocity (°/s)", deg)
        };
        angles.push(plot(name.clone(), unit, Channel::Angle(i), false, scale, 3));
        velocities.push(plot(
            format!("{name} velocity"),
            vunit,
            Channel::Velocity(i),
            false,
            scale,
            3,
        ));
    }
    for (j, joint) in JOINTS.iter().enumerate() {
        angles.push(plot(
            format!("{joint} angle"),
            "angle (°)",
            Channel::Angle(3 + j),
            true,
            deg,
            3,
        ));
        velocities.push(plot(
            format!("{joint} angular velocity"),
            "angular velocity (°/s)",
            Channel::Velocity(3 + j),
            true,
            deg,
            3,
        ));
    }
    let loads = [
        (1, "normal GRF", "force (N)"),
        (0, "tangential GRF", "force (N)"),
        (2, "CoP", "x (m)"),
    ]
    .into_iter()
    .map(|(c, title, unit)| plot(title.to_string(), unit, Channel::Load(c), true, 1.0, 1))
    .collect();
    [angles, velocities, loads]
}

impl ChannelFigures<'_> {
    /// The values of plot `cp` in `cmp` for leg `side` (`None`: a channel of neither leg).
    fn pick<'c>(
        cmp: &'c Comparison,
        cp: &ChannelPlot,
        side: Option<usize>,
        model: bool,
    ) -> &'c [f64] {
        let i = cp.coordinate(side).unwrap_or(0);
        match (cp.channel, model) {
            (Channel::Angle(_), true) => &cmp.model_q[i],
            (Channel::Angle(_), false) => &cmp.data_q[i],
            (Channel::Velocity(_), true) => &cmp.model_qd[i],
            (Channel::Velocity(_), false) => &cmp.data_qd[i],
            (Channel::Load(c), true) => &cmp.model_feet[side.unwrap_or(0)][c],
            (Channel::Load(c), false) => &cmp.data_feet[side.unwrap_or(0)][c],
        }
    }

    /// Percent of leg `side`'s cycle at each of `times`.
    pub fn percent(&self, side: usize, times: &[f64]) -> Vec<f64> {
        times.iter().map(|&t| self.cycle.percent(side, t)).collect()
    }

    /// An empty plot over percent of the cycle of `sides`: phases shaded on each leg's
    /// axis, the trial's clock along the top, the caution note.
    pub fn cycle_plot(&self, title: &str, unit: &str, sides: &[usize]) -> LinePlot {
        let mut p = LinePlot::new(
            title,
            if sides.len() == 2 {
                "% of gait cycle (each leg from its heel strike)"
            } else {
                "% of gait cycle"
            },
            unit,
        );
        for &s in sides {
            for (t0, t1, name) in &self.phases {
                p.shaded.push(Span::new(
                    self.cycle.percent(s, *t0),
                    self.cycle.percent(s, *t1),
                    name.clone(),
                ));
            }
        }
        p.top_axis = Some(self.cycle.top_axis(self.window, sides));
        p.note = self.note.clone();
        p
    }

    /// One plot of a channel: both legs overlaid on their own percent of the cycle (or
    /// one series on the lead leg's axis for a coordinate of neither leg), model line,
    /// model at the nodes, measurement dashed, and the residual band between them.
    pub fn plot(&self, cp: &ChannelPlot) -> LinePlot {
        let (bilateral, scale, every) = (cp.bilateral, cp.scale, cp.every);
        let lead = self.cycle.lead_side(self.window);
        let sides: Vec<usize> = if bilateral { vec![0, 1] } else { vec![lead] };
        let mut p = self.cycle_plot(&cp.title, cp.unit, &sides);
        let n = self.line.times.len();
        let keep = |i: usize| i.is_multiple_of(every.max(1)) || i + 1 == n;
        let thin = |v: &[f64]| {
            v.iter()
                .enumerate()
                .filter(|(i, _)| keep(*i))
                .map(|(_, x)| *x)
                .collect::<Vec<f64>>()
        };
        let line_times = thin(&self.line.times);
        let pct = |s: usize, t: &[f64]| self.percent(s, t);
        let scaled = |v: &[f64]| thin(v).iter().map(|x| x * scale).collect::<Vec<f64>>();
        let scaled_nodes = |v: &[f64]| v.iter().map(|x| x * scale).collect::<Vec<f64>>();
        for &s in &sides {
            let who = if bilateral {
                format!("{}, ", SIDES[s])
            } else {
                String::new()
            };
            let leg = bilateral.then_some(s);
            let (m, d) = (
                Self::pick(self.line, cp, leg, true),
                Self::pick(self.line, cp, leg, false),
            );
            p.bands.push(Band {
                name: if s == sides[0] {
                    "residual".into()
                } else {
                    String::new()
                },
                x: pct(s, &line_times),
                y0: scaled(m),
                y1: scaled(d),
            });
            p.series.push(
                Series::new(
                    format!("{who}{}", self.line_label),
                    pct(s, &line_times),
                    scaled(m),
                    LineStyle::Solid,
                )
                .coloured(2 * s),
            );
            p.series.push(
                Series::new(
                    format!("{who}measured"),
                    pct(s, &line_times),
                    scaled(d),
                    LineStyle::Dashed,
                )
                .coloured(2 * s + 1),
            );
            p.series.push(
                Series::new(
                    if s == sides[0] {
                        "model at the nodes"
                    } else {
                        ""
                    },
                    pct(s, &self.nodes.times),
                    scaled_nodes(Self::pick(self.nodes, cp, leg, true)),
                    LineStyle::Markers,
                )
                .coloured(2 * s),
            );
        }
        p
    }

    /// Angle plots (pelvis position, trunk, then hip, knee, ankle with both legs) and the
    /// matching velocity plots, in display units (°, °/s, m, m/s).
    pub fn kinematics(&self) -> (Vec<LinePlot>, Vec<LinePlot>) {
        let [angles, velocities, _] = channel_plots();
        (
            angles.iter().map(|c| self.plot(c)).collect(),
            velocities.iter().map(|c| self.plot(c)).collect(),
        )
    }

    /// Normal and tangential ground force and CoP, both feet overlaid.
    pub fn loads(&self) -> Vec<LinePlot> {
        let [_, _, loads] = channel_plots();
        loads.iter().map(|c| self.plot(c)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A comparison whose every series holds its own index: coordinate `i` is `i` (its
    /// velocity `10 + i`, its measurement `100 + i`), load `c` of foot `s` is `20 + 3s + c`.
    fn labelled(n: usize) -> Comparison {
        let fill = |v: f64| vec![v; n];
        Comparison {
            times: (0..n).map(|k| 1.0 + 0.01 * k as f64).collect(),
            phase: vec![0; n],
            model_q: (0..9).map(|i| fill(i as f64)).collect(),
            data_q: (0..9).map(|i| fill(100.0 + i as f64)).collect(),
            model_qd: (0..9).map(|i| fill(10.0 + i as f64)).collect(),
            data_qd: (0..9).map(|i| fill(110.0 + i as f64)).collect(),
            model_feet: [0, 1].map(|s| [0, 1, 2].map(|c| fill((20 + 3 * s + c) as f64))),
            data_feet: [0, 1].map(|s| [0, 1, 2].map(|c| fill((120 + 3 * s + c) as f64))),
            cop_threshold: 20.0,
        }
    }

    #[test]
    fn every_plot_draws_its_own_channel_whichever_leg_leads() {
        let cmp = labelled(5);
        for lead in [0, 1] {
            // the window starts at the lead leg's heel strike
            let mut heel_strike = [0.4, 0.4];
            heel_strike[lead] = 1.0;
            let figures = ChannelFigures {
                line: &cmp,
                nodes: &cmp,
                line_label: "model",
                cycle: CycleAxis {
                    period: 1.2,
                    heel_strike,
                },
                window: (1.0, 1.6),
                phases: vec![],
                note: None,
            };
            assert_eq!(figures.cycle.lead_side(figures.window), lead);
            for cp in channel_plots().iter().flatten() {
                let p = figures.plot(cp);
                let sides: Vec<Option<usize>> = if cp.bilateral {
                    vec![Some(0), Some(1)]
                } else {
                    vec![None]
                };
                for (k, side) in sides.iter().enumerate() {
                    let expected = match (cp.channel, side) {
                        (Channel::Angle(i), s) => (i + 3 * s.unwrap_or(0)) as f64,
                        (Channel::Velocity(i), s) => 10.0 + (i + 3 * s.unwrap_or(0)) as f64,
                        (Channel::Load(c), Some(s)) => (20 + 3 * s + c) as f64,
                        (Channel::Load(_), None) => unreachable!("loads belong to a foot"),
                    };
                    // model line, measurement, model at the nodes, per leg
                    let model = &p.series[3 * k];
                    let measured = &p.series[3 * k + 1];
                    assert!(
                        model.y.iter().all(|&y| y == expected * cp.scale),
                        "{} (lead {lead}): {:?}",
                        cp.title,
                        model.y
                    );
                    assert!(
                        measured
                            .y
                            .iter()
                            .all(|&y| y == (expected + 100.0) * cp.scale),
                        "{}",
                        cp.title
                    );
                    // the run CSV column of the same channel
                    let column = cp.csv_column("model", *side);
                    let name = match cp.channel {
                        Channel::Load(c) => {
                            format!("model_{}_{}", LOAD_NAMES[c], ["r", "l"][side.unwrap_or(0)])
                        }
                        Channel::Angle(_) => format!("model_{}", COORDINATES[expected as usize]),
                        Channel::Velocity(_) => {
                            format!("model_{}_dot", COORDINATES[(expected - 10.0) as usize])
                        }
                    };
                    assert_eq!(column, name, "{}", cp.title);
                }
            }
        }
    }
}
