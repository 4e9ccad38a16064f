//! Layout of the transcription: variable offsets, constraint rows, row labels and the
//! sparsity patterns of the Jacobian and the Gauss–Newton Hessian, built once.

use super::{
    add_instant, Instants, IntervalRef, RowLabel, TermKind, TermRef, Transcription,
    TranscriptionError,
};
use crate::integrate::{ControlShape, IntegrationStats};
use crate::ocp::problem::{Block, Ocp};
use std::sync::atomic::AtomicU64;
use std::sync::Mutex;

/// An invalid problem, with its reason.
fn inv(reason: String) -> TranscriptionError {
    TranscriptionError::Invalid(reason)
}

/// Where each phase's variables start: per node its state and (where it has one) its
/// control, then the phase's duration; θ after the last phase.
struct Offsets {
    /// Number of variables.
    n: usize,
    /// Per phase and node, the state's first variable.
    state: Vec<Vec<usize>>,
    /// Per phase and control node, the control's first variable.
    control: Vec<Vec<usize>>,
    /// Per phase, its duration's variable.
    duration: Vec<usize>,
    /// θ's first variable.
    theta: usize,
}

impl Offsets {
    /// The offsets of `ocp`'s variables, its phases checked against its parameters and
    /// their bounds and guesses against their sizes.
    fn of(ocp: &Ocp<'_>) -> Result<Self, TranscriptionError> {
        let mut n = 0;
        let mut state_off = Vec::new();
        let mut control_off = Vec::new();
        let mut duration_off = Vec::new();
        for (j, ph) in ocp.phases.iter().enumerate() {
            let (nx, nu) = (ph.ode.nx(), ph.ode.nu());
            if ph.intervals == 0 {
                return Err(inv(format!("phase '{}' has zero intervals", ph.name)));
            }
            if ph.ode.ntheta() != ocp.ntheta {
                return Err(inv(format!(
                    "phase '{}': dynamics have {} parameters, problem has {}",
                    ph.name,
                    ph.ode.ntheta(),
                    ocp.ntheta
                )));
            }
            let nodes = ph.intervals + 1;
            let cn = ph.control_nodes();
            for (what, v, len, width) in [
                ("x_lb", &ph.x_lb, nodes, nx),
                ("x_ub", &ph.x_ub, nodes, nx),
                ("x_guess", &ph.x_guess, nodes, nx),
                ("u_lb", &ph.u_lb, cn, nu),
                ("u_ub", &ph.u_ub, cn, nu),
                ("u_guess", &ph.u_guess, cn, nu),
            ] {
                if v.len() != len || v.iter().any(|r| r.len() != width) {
                    return Err(inv(format!(
                        "phase '{}' ({j}): {what} must be {len} rows of {width}",
                        ph.name
                    )));
                }
            }
            let mut so = Vec::new();
            let mut co = Vec::new();
            for k in 0..nodes {
                so.push(n);
                n += nx;
                if k < cn {
                    co.push(n);
                    n += nu;
                }
            }
            state_off.push(so);
            control_off.push(co);
            duration_off.push(n);
            n += 1;
        }
        let theta_off = n;
        n += ocp.ntheta;
        Ok(Self {
            n,
            state: state_off,
            control: control_off,
            duration: duration_off,
            theta: theta_off,
        })
    }
}

impl<'o, 'a> Transcription<'o, 'a> {
    /// Lay out variables and constraints and build the sparsity patterns.
    pub fn new(ocp: &'o Ocp<'a>) -> Result<Self, TranscriptionError> {
        if ocp.phases.is_empty() {
            return Err(inv("no phase".into()));
        }
        if ocp.transitions.len() + 1 != ocp.phases.len() {
            return Err(inv(format!(
                "{} transitions for {} phases (need one between each pair)",
                ocp.transitions.len(),
                ocp.phases.len()
            )));
        }
        let offsets = Offsets::of(ocp)?;
        let mut t = Self {
            ocp,
            n: offsets.n,
            state_off: offsets.state,
            control_off: offsets.control,
            duration_off: offsets.duration,
            theta_off: offsets.theta,
            m: 0,
            intervals: Vec::new(),
            terms: Vec::new(),
            jac_rows: Vec::new(),
            jac_cols: Vec::new(),
            gn_rows: Vec::new(),
            gn_cols: Vec::new(),
            pools: ocp.phases.iter().map(|_| Mutex::new(Vec::new())).collect(),
            labels: Vec::new(),
            shifted: Vec::new(),
            first_interval: Vec::new(),
            totals: Mutex::new(IntegrationStats::default()),
            tolerance_scale: AtomicU64::new(1f64.to_bits()),
        };
        let samples = t.fixed_samples()?;
        t.add_continuity_rows(samples);
        t.add_transition_rows()?;
        t.add_constraint_rows()?;
        let checks = t.checks_by_interval()?;
        t.add_check_rows(checks);
        t.add_objective_terms()?;
        Ok(t)
    }

    /// The sample terms at fixed instants, grouped by phase, interval and τ (ascending);
    /// the shifted ones are listed in `shifted`.
    fn fixed_samples(&mut self) -> Result<Vec<Vec<Instants>>, TranscriptionError> {
        let ocp = self.ocp;
        let mut samples: Vec<Vec<Instants>> = ocp
            .phases
            .iter()
            .map(|p| vec![Vec::new(); p.intervals])
            .collect();
        for (si, st) in ocp.samples.iter().enumerate() {
            let Some(list) = samples
                .get_mut(st.phase)
                .and_then(|p| p.get_mut(st.interval))
            else {
                return Err(inv(format!(
                    "sample term '{}': phase {} has no interval {}",
                    st.name, st.phase, st.interval
                )));
            };
            if !(st.tau > 0.0 && st.tau <= 1.0) {
                return Err(inv(format!(
                    "sample term '{}': τ = {} is not in (0, 1]",
                    st.name, st.tau
                )));
            }
            if let Some(shift) = &st.shift {
                let ph = &ocp.phases[st.phase];
                if ph.duration.is_free() {
                    return Err(inv(format!("sample term '{}': a shifted instant needs phase '{}' to have a fixed duration", st.name, ph.name)));
                }
                if shift.dim() != 1 {
                    return Err(inv(format!(
                        "sample term '{}': its shift has dimension {}, not 1",
                        st.name,
                        shift.dim()
                    )));
                }
                self.shifted.push(si);
                continue;
            }
            add_instant(list, st.tau, si);
        }
        for list in samples.iter_mut().flatten() {
            list.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        Ok(samples)
    }

    /// The shooting intervals, each with its fixed sample terms (`samples`, by phase and
    /// interval), and their continuity rows.
    fn add_continuity_rows(&mut self, mut samples: Vec<Vec<Instants>>) {
        let ocp = self.ocp;
        let mut shifted_phase = vec![false; ocp.phases.len()];
        for &si in &self.shifted {
            shifted_phase[ocp.samples[si].phase] = true;
        }
        for (j, ph) in ocp.phases.iter().enumerate() {
            let nx = ph.ode.nx();
            self.first_interval.push(self.intervals.len());
            for k in 0..ph.intervals {
                let row = self.m;
                let fixed = std::mem::take(&mut samples[j][k]);
                let sample_block = shifted_phase[j] || !fixed.is_empty();
                self.intervals.push(IntervalRef {
                    phase: j,
                    k,
                    row,
                    samples: fixed,
                    sample_block,
                    checks: Vec::new(),
                });
                let cols = self.interval_cols(j, k);
                for i in 0..nx {
                    for &c in &cols {
                        self.jac_rows.push(row + i);
                        self.jac_cols.push(c);
                    }
                    self.jac_rows.push(row + i);
                    self.jac_cols.push(self.state_off[j][k + 1] + i);
                    self.labels.push(RowLabel {
                        phase: ph.name.clone(),
                        node: k,
                        name: format!("continuity[{i}]"),
                    });
                }
                self.m += nx;
            }
        }
    }

    /// The rows joining each phase to the next: its transition term, or the states equal.
    fn add_transition_rows(&mut self) -> Result<(), TranscriptionError> {
        let ocp = self.ocp;
        for (j, tr) in ocp.transitions.iter().enumerate() {
            let next = &ocp.phases[j + 1];
            let nx1 = next.ode.nx();
            let row = self.m;
            match tr {
                Some(term) => {
                    if term.f.dim() != nx1 {
                        return Err(inv(format!(
                            "transition '{}' has dimension {}, phase '{}' has {nx1} states",
                            term.name,
                            term.f.dim(),
                            next.name
                        )));
                    }
                    let cols = self.term_cols(&term.args)?;
                    self.terms.push(TermRef {
                        term: j,
                        kind: TermKind::Transition,
                        row,
                        cols: cols.clone(),
                    });
                    for i in 0..nx1 {
                        for &c in &cols {
                            self.jac_rows.push(row + i);
                            self.jac_cols.push(c);
                        }
                    }
                }
                None => {
                    let prev = &ocp.phases[j];
                    if prev.ode.nx() != nx1 {
                        return Err(inv(format!(
                            "phases '{}' and '{}' differ in state dimension and need a transition",
                            prev.name, next.name
                        )));
                    }
                    for i in 0..nx1 {
                        self.jac_rows.push(row + i);
                        self.jac_cols.push(self.state_off[j][prev.intervals] + i);
                    }
                }
            }
            for i in 0..nx1 {
                self.jac_rows.push(row + i);
                self.jac_cols.push(self.state_off[j + 1][0] + i);
                self.labels.push(RowLabel {
                    phase: next.name.clone(),
                    node: 0,
                    name: format!("transition[{i}]"),
                });
            }
            self.m += nx1;
        }
        Ok(())
    }

    /// The rows of the user constraints.
    fn add_constraint_rows(&mut self) -> Result<(), TranscriptionError> {
        for (ci, con) in self.ocp.constraints.iter().enumerate() {
            let d = con.term.f.dim();
            if con.lb.len() != d || con.ub.len() != d {
                return Err(inv(format!(
                    "constraint '{}': bounds must have {d} entries",
                    con.term.name
                )));
            }
            let cols = self.term_cols(&con.term.args)?;
            let row = self.m;
            self.terms.push(TermRef {
                term: ci,
                kind: TermKind::Constraint,
                row,
                cols: cols.clone(),
            });
            let (phase, node) = self.locate(&con.term.args);
            for i in 0..d {
                for &c in &cols {
                    self.jac_rows.push(row + i);
                    self.jac_cols.push(c);
                }
                self.labels.push(RowLabel {
                    phase: phase.clone(),
                    node,
                    name: format!("{}[{i}]", con.term.name),
                });
            }
            self.m += d;
        }
        Ok(())
    }

    /// The check points per interval (in transcription order), each as (τ, index in
    /// `Ocp::checks`), validated.
    fn checks_by_interval(&self) -> Result<Vec<Vec<(f64, usize)>>, TranscriptionError> {
        let ocp = self.ocp;
        let mut per_interval: Vec<Vec<(f64, usize)>> = vec![Vec::new(); self.intervals.len()];
        for (ci, cp) in ocp.checks.iter().enumerate() {
            let Some(ph) = ocp
                .phases
                .get(cp.phase)
                .filter(|ph| cp.interval < ph.intervals)
            else {
                return Err(inv(format!(
                    "check point '{}': phase {} has no interval {}",
                    cp.name, cp.phase, cp.interval
                )));
            };
            if !(cp.tau > 0.0 && cp.tau < 1.0) {
                return Err(inv(format!(
                    "check point '{}' in phase '{}': τ = {} is not in (0, 1)",
                    cp.name, ph.name, cp.tau
                )));
            }
            let d = cp.f.dim();
            if cp.lb.len() != d || cp.ub.len() != d {
                return Err(inv(format!(
                    "check point '{}': bounds must have {d} entries",
                    cp.name
                )));
            }
            per_interval[self.first_interval[cp.phase] + cp.interval].push((cp.tau, ci));
        }
        Ok(per_interval)
    }

    /// The check points' rows: in interval order, by τ within an interval.
    fn add_check_rows(&mut self, per_interval: Vec<Vec<(f64, usize)>>) {
        let ocp = self.ocp;
        for (i, mut list) in per_interval.into_iter().enumerate() {
            list.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let (j, k) = (self.intervals[i].phase, self.intervals[i].k);
            let cols = self.interval_cols(j, k);
            for (tau, ci) in list {
                let cp = &ocp.checks[ci];
                let row = self.m;
                self.intervals[i].checks.push((tau, ci, row));
                for r in 0..cp.f.dim() {
                    for &c in &cols {
                        self.jac_rows.push(row + r);
                        self.jac_cols.push(c);
                    }
                    self.labels.push(RowLabel {
                        phase: ocp.phases[j].name.clone(),
                        node: k,
                        name: format!("{}@τ={tau:.3}[{r}]", cp.name),
                    });
                }
                self.m += cp.f.dim();
            }
        }
    }

    /// The objective's terms and the Gauss–Newton pattern: the least-squares terms', then
    /// the sample terms' blocks in interval order, then the general costs.
    fn add_objective_terms(&mut self) -> Result<(), TranscriptionError> {
        let ocp = self.ocp;
        for (li, ls) in ocp.least_squares.iter().enumerate() {
            let cols = self.term_cols(&ls.args)?;
            for (a, &ca) in cols.iter().enumerate() {
                for &cb in &cols[a..] {
                    self.gn_rows.push(ca.min(cb));
                    self.gn_cols.push(ca.max(cb));
                }
            }
            self.terms.push(TermRef {
                term: li,
                kind: TermKind::LeastSquares,
                row: 0,
                cols,
            });
        }
        // the sample terms' Gauss–Newton blocks, after the least-squares terms', in
        // interval order
        for iv in self.intervals.iter().filter(|iv| iv.sample_block) {
            let cols = self.interval_cols(iv.phase, iv.k);
            for (a, &ca) in cols.iter().enumerate() {
                for &cb in &cols[a..] {
                    self.gn_rows.push(ca.min(cb));
                    self.gn_cols.push(ca.max(cb));
                }
            }
        }
        for (gi, g) in ocp.costs.iter().enumerate() {
            if g.f.dim() != 1 {
                return Err(inv(format!("cost '{}' must be scalar", g.name)));
            }
            let cols = self.term_cols(&g.args)?;
            self.terms.push(TermRef {
                term: gi,
                kind: TermKind::Cost,
                row: 0,
                cols,
            });
        }
        Ok(())
    }

    /// The columns an interval depends on: its start state, its control(s), its phase's
    /// duration and θ (the order of its sensitivity columns).
    pub(super) fn interval_cols(&self, j: usize, k: usize) -> Vec<usize> {
        let ph = &self.ocp.phases[j];
        let mut cols: Vec<usize> = Vec::new();
        cols.extend(self.range(Block::State { phase: j, node: k }));
        cols.extend(self.range(Block::Control { phase: j, node: k }));
        if ph.controls == ControlShape::Linear {
            cols.extend(self.range(Block::Control {
                phase: j,
                node: k + 1,
            }));
        }
        cols.push(self.duration_off[j]);
        cols.extend(self.range(Block::Params));
        cols
    }

    fn locate(&self, args: &[Block]) -> (String, usize) {
        for b in args {
            match *b {
                Block::State { phase, node } | Block::Control { phase, node } => {
                    return (self.ocp.phases[phase].name.clone(), node)
                }
                Block::Duration { phase } => return (self.ocp.phases[phase].name.clone(), 0),
                Block::Params => {}
            }
        }
        ("problem".into(), 0)
    }

    fn term_cols(&self, args: &[Block]) -> Result<Vec<usize>, TranscriptionError> {
        let mut cols = Vec::new();
        for &b in args {
            self.check_block(b)?;
            cols.extend(self.range(b));
        }
        Ok(cols)
    }

    fn check_block(&self, b: Block) -> Result<(), TranscriptionError> {
        let ok = match b {
            Block::State { phase, node } => {
                phase < self.ocp.phases.len() && node <= self.ocp.phases[phase].intervals
            }
            Block::Control { phase, node } => {
                phase < self.ocp.phases.len() && node < self.ocp.phases[phase].control_nodes()
            }
            Block::Duration { phase } => phase < self.ocp.phases.len(),
            Block::Params => true,
        };
        if ok {
            Ok(())
        } else {
            Err(TranscriptionError::Invalid(format!(
                "block {b:?} does not exist"
            )))
        }
    }
}
