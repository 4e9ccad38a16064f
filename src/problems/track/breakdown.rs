//! Where a tracking cost comes from: per channel, continuous phase and node.

use super::{TrackingSetup, CLOCK_SHIFT_END};
use crate::model::{ConstraintSet, GaitModel};
use crate::ocp::shifted_instant;
use crate::problems::error::ProblemError;
use crate::problems::tracking::TrackingResidual;

impl TrackingSetup {
    /// Where the tracking cost of `solution` comes from: per channel
    /// ([`TrackingResidual::row_channels`]) and continuous phase, and per node (per sample
    /// for sample targets, the intervals integrated to them with `integrator`).
    pub fn cost_breakdown(
        &self,
        model: &GaitModel,
        sets: &[ConstraintSet],
        continuous: &[usize],
        solution: &crate::problems::evaluation::GaitSolution,
        integrator: &crate::integrate::IntegratorSettings,
    ) -> Result<CostBreakdown, ProblemError> {
        let linear = solution
            .phases
            .first()
            .is_none_or(|p| p.controls == crate::integrate::ControlShape::Linear);
        let mut channels: Vec<String> = Vec::new();
        let mut phases = Vec::new();
        let mut cost: Vec<Vec<f64>> = Vec::new();
        let mut rows: Vec<Vec<usize>> = Vec::new();
        let mut nodes = Vec::new();
        for (j, (tg, ph)) in self.targets.iter().zip(&solution.phases).enumerate() {
            phases.push(ph.name.clone());
            let n = ph.intervals();
            let last = j + 1 == self.targets.len();
            let h = ph.duration / n as f64;
            for (k, target) in tg.iter().enumerate() {
                if k == n && !last {
                    continue;
                }
                let r = self.node_residual(model, &sets[continuous[j]], (j, k), target.clone());
                let ku = if linear { k } else { k.min(n - 1) };
                let z: Vec<f64> = ph.x[k]
                    .iter()
                    .chain(&ph.u[ku])
                    .chain(&solution.theta)
                    .copied()
                    .collect();
                let (data, largest, _) = add_costs(&r, &z, j, &mut channels, &mut cost, &mut rows)?;
                if !largest.is_empty() {
                    nodes.push(NodeCost {
                        time: ph.t0 + k as f64 * h,
                        phase: ph.name.clone(),
                        data,
                        largest,
                    });
                }
            }
        }
        if !self.samples.is_empty() {
            // each residual's instant: (interval, τ, time), the loads' moved by the force
            // plates' clock offset as the OCP's shifted sample terms are
            let offsets = model
                .measurement_adjust::<f64>(&solution.theta)
                .force_time_offset;
            let mut parts = Vec::new();
            for (i, st) in self.samples.iter().enumerate() {
                for (r, shifted) in self.sample_residuals(model, sets, continuous, st) {
                    let (phase, interval, tau) = st.place_of(shifted);
                    let ph = &solution.phases[phase];
                    let (n, h) = (ph.intervals(), ph.duration / ph.intervals() as f64);
                    let (k, tau, time) = if let Some(side) = shifted {
                        let shift = st.load_offset[side] - offsets[side];
                        let (k, tau, _) = shifted_instant(interval, tau, shift, h, n);
                        // a phase's end is sampled before its impact
                        (
                            k,
                            tau,
                            (ph.t0 + (k as f64 + tau) * h)
                                .min(ph.t0 + ph.duration - CLOCK_SHIFT_END),
                        )
                    } else {
                        (st.interval, st.tau, st.target.time)
                    };
                    parts.push((i, phase, r, k, tau, time));
                }
            }
            let mut times: Vec<f64> = parts.iter().map(|p| p.5).collect();
            times.sort_by(f64::total_cmp);
            times.dedup();
            let states = solution
                .sample_at(model, sets, &times, integrator)
                .map_err(|source| ProblemError::Sampling { source })?;
            let mut data_by_sample = vec![(0.0, String::new(), 0.0); self.samples.len()];
            for (i, phase, r, k, tau, time) in &parts {
                let ph = &solution.phases[*phase];
                let at = &states[times.partition_point(|t| t < time)];
                let u: Vec<f64> = match ph.controls {
                    crate::integrate::ControlShape::Linear => ph.u[*k]
                        .iter()
                        .zip(&ph.u[k + 1])
                        .map(|(a, b)| (1.0 - tau) * a + tau * b)
                        .collect(),
                    crate::integrate::ControlShape::Constant => ph.u[*k].clone(),
                };
                let z: Vec<f64> =
                    at.x.iter()
                        .chain(&u)
                        .chain(&solution.theta)
                        .copied()
                        .collect();
                let (data, largest, largest_cost) =
                    add_costs(r, &z, *phase, &mut channels, &mut cost, &mut rows)?;
                // the parts' channels are disjoint: the sample's largest is the parts' largest
                let entry = &mut data_by_sample[*i];
                entry.0 += data;
                if entry.1.is_empty() || largest_cost > entry.2 {
                    (entry.1, entry.2) = (largest, largest_cost);
                }
            }
            for (st, (data, largest, _)) in self.samples.iter().zip(data_by_sample) {
                nodes.push(NodeCost {
                    time: st.target.time,
                    phase: solution.phases[st.phase].name.clone(),
                    data,
                    largest,
                });
            }
            nodes.sort_by(|a, b| a.time.total_cmp(&b.time));
        }
        for c in &mut cost {
            c.resize(phases.len(), 0.0);
        }
        for r in &mut rows {
            r.resize(phases.len(), 0);
        }
        Ok(CostBreakdown {
            channels,
            phases,
            cost,
            rows,
            nodes,
        })
    }
}

/// Add the squared rows of residual `r` at `z` to the cost of phase `j` per channel
/// (new channels appended); returns the data cost (without regularisation) and the
/// channel contributing most to it with its cost (empty and 0 without data rows).
fn add_costs(
    r: &TrackingResidual,
    z: &[f64],
    j: usize,
    channels: &mut Vec<String>,
    cost: &mut Vec<Vec<f64>>,
    rows: &mut Vec<Vec<usize>>,
) -> Result<(f64, String, f64), ProblemError> {
    let mut v = vec![0.0; crate::problems::GenericFunction::dim(r)];
    crate::problems::GenericFunction::eval(r, z, &mut v)?;
    let mut node_data: Vec<(String, f64)> = Vec::new();
    for (label, value) in r.row_channels().into_iter().zip(&v) {
        let c = match channels.iter().position(|x| *x == label) {
            Some(c) => c,
            None => {
                channels.push(label.clone());
                cost.push(Vec::new());
                rows.push(Vec::new());
                channels.len() - 1
            }
        };
        if cost[c].len() <= j {
            cost[c].resize(j + 1, 0.0);
            rows[c].resize(j + 1, 0);
        }
        cost[c][j] += value * value;
        rows[c][j] += 1;
        if label != "excitations"
            && label != "joint torques"
            && label != "activations"
            && !label.ends_with("residual")
        {
            match node_data.iter_mut().find(|(l, _)| *l == label) {
                Some(e) => e.1 += value * value,
                None => node_data.push((label, value * value)),
            }
        }
    }
    let data = node_data.iter().map(|e| e.1).sum();
    let (largest, largest_cost) = node_data
        .into_iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or_default();
    Ok((data, largest, largest_cost))
}

/// Where a tracking cost comes from.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CostBreakdown {
    /// Channels, in order of first appearance.
    pub channels: Vec<String>,
    /// Continuous phases, in order.
    pub phases: Vec<String>,
    /// Cost `[channel][phase]` (Σ of squared weighted residuals).
    pub cost: Vec<Vec<f64>>,
    /// Number of residual rows `[channel][phase]` behind each cost.
    pub rows: Vec<Vec<usize>>,
    /// Per node: data cost and the channel contributing most.
    pub nodes: Vec<NodeCost>,
}

/// The data cost of one node.
#[derive(Debug, Clone, serde::Serialize)]
pub struct NodeCost {
    /// Time (s).
    pub time: f64,
    /// Phase name.
    pub phase: String,
    /// Σ of the squared weighted data residuals (without regularisation).
    pub data: f64,
    /// The channel contributing most.
    pub largest: String,
}

impl CostBreakdown {
    /// Total cost.
    pub fn total(&self) -> f64 {
        self.cost.iter().flatten().sum()
    }

    /// Normalised error `[channel][phase]`: the RMS of the weighted residual, i.e. the
    /// error in units of the channel's weighting scale (1 = an error as large as the
    /// scale, e.g. π/4 for an angle); None where the channel has no rows in the phase.
    pub fn normalised_rms(&self) -> Vec<Vec<Option<f64>>> {
        self.cost
            .iter()
            .zip(&self.rows)
            .map(|(c, r)| {
                c.iter()
                    .zip(r)
                    .map(|(&v, &n)| (n > 0).then(|| (v / n as f64).sqrt()))
                    .collect()
            })
            .collect()
    }

    /// The `n` windows of `width` consecutive nodes with the largest data cost, not
    /// overlapping: `(start time, end time, cost, channel contributing most)`.
    pub fn worst_windows(&self, width: usize, n: usize) -> Vec<(f64, f64, f64, String)> {
        let m = self.nodes.len();
        if m == 0 {
            return Vec::new();
        }
        let w = width.clamp(1, m);
        let mut sums: Vec<(usize, f64)> = (0..=m - w)
            .map(|i| (i, self.nodes[i..i + w].iter().map(|c| c.data).sum()))
            .collect();
        sums.sort_by(|a, b| b.1.total_cmp(&a.1));
        let mut taken: Vec<(usize, f64)> = Vec::new();
        for (i, v) in sums {
            if taken.iter().all(|&(j, _)| i + w <= j || j + w <= i) {
                taken.push((i, v));
                if taken.len() == n {
                    break;
                }
            }
        }
        taken
            .into_iter()
            .map(|(i, v)| {
                let win = &self.nodes[i..i + w];
                let mut by: Vec<(String, f64)> = Vec::new();
                for c in win {
                    match by.iter_mut().find(|e| e.0 == c.largest) {
                        Some(e) => e.1 += c.data,
                        None => by.push((c.largest.clone(), c.data)),
                    }
                }
                let top = by
                    .into_iter()
                    .max_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|e| e.0)
                    .unwrap_or_default();
                (win[0].time, win[w - 1].time, v, top)
            })
            .collect()
    }
}
