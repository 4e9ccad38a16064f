//! The forward stepwise reading of the balance's candidates: at each step the candidate
//! that explains most of the residual among those beyond their band is read jointly with
//! those already found, beside the [`BASELINE`] read throughout; candidates whose
//! signature the data cannot carry, or that the active ones already span, are said so
//! rather than read.

use super::fit::{self, Fit, Problem};
use super::{CheckSettings, NullBand, Param, Reading, Verdict, NPARAM};

/// The three scales of the balance, each a factor on one side of it: the body's mass
/// (on Σ m a and m g) and each plate's gain (on its load). Scaling all three alike
/// scales the whole residual, so read together they fit it to zero by shrinking both
/// sides; at most two of them can be read at once.
const SCALES: [Param; 3] = [Param::BodyMass, Param::GainRight, Param::GainLeft];

/// Whether `c` is the third of the balance's [`SCALES`] while the other two are read:
/// those two, which it cannot be told from.
fn scale_bound(c: Param, active: &[Param]) -> Option<Vec<Param>> {
    let others: Vec<Param> = SCALES.into_iter().filter(|&s| s != c).collect();
    (SCALES.contains(&c) && others.iter().all(|o| active.contains(o))).then_some(others)
}

/// Whether the signature of `c` is a near combination of the `active` ones, and if so
/// which of them it is most like: `1 − R²` of its column on theirs below 1 %.
fn collinear(b: &nalgebra::DMatrix<f64>, c: usize, active: &[usize]) -> Option<Vec<usize>> {
    if active.is_empty() {
        return None;
    }
    let baa = b.select_rows(active).select_columns(active);
    let bac = nalgebra::DVector::from_iterator(active.len(), active.iter().map(|&a| b[(a, c)]));
    let explained = baa
        .clone()
        .try_inverse()
        .map(|inv| (bac.transpose() * inv * &bac)[0])?;
    if 1.0 - explained / b[(c, c)] > 0.01 {
        return None;
    }
    let mut like: Vec<(usize, f64)> = active
        .iter()
        .map(|&a| (a, (b[(a, c)] / (b[(a, a)] * b[(c, c)]).sqrt()).abs()))
        .collect();
    like.sort_by(|x, y| y.1.total_cmp(&x.1));
    Some(
        like.into_iter()
            .filter(|l| l.1 > 0.3)
            .map(|l| l.0)
            .collect(),
    )
}

/// The largest standard deviation at which a candidate still counts as testable: a
/// reading looser than this says nothing a lab could act on.
fn testable_sd(p: Param) -> f64 {
    match p {
        Param::SharedClock | Param::ClockRight | Param::ClockLeft => 0.02,
        Param::GainRight | Param::GainLeft | Param::BodyMass => 0.2,
        Param::CopRight | Param::CopLeft | Param::TrunkCom => 0.05,
        Param::TrunkMass => 10.0,
        Param::Slope => 0.1,
    }
}

/// Least share of the window's vertical impulse a plate must carry for its own clock,
/// gain or CoP offset to be read: a plate that only touches the window's edge reads a
/// few newtons' ramp, whose shape the body model's error dominates.
pub const MIN_PLATE_SHARE: f64 = 0.15;

/// Why a plate's own candidate cannot be read in this window, if it cannot.
fn unloaded(p: &Problem, c: Param) -> Option<String> {
    let s = match c {
        Param::ClockRight | Param::GainRight | Param::CopRight => 0,
        Param::ClockLeft | Param::GainLeft | Param::CopLeft => 1,
        _ => return None,
    };
    let (mut own, mut all) = (0.0, 0.0);
    for at in p.instants {
        for side in 0..2 {
            if let Some(l) = p.signals.load(side, at.t, 0.0_f64) {
                let fy = l[1].max(0.0);
                all += fy;
                if side == s {
                    own += fy;
                }
            }
        }
    }
    let share = own / all;
    (share < MIN_PLATE_SHARE).then(|| {
        format!(
            "its plate carries {:.0} % of the window's vertical impulse (at least {:.0} % is needed)",
            100.0 * share,
            100.0 * MIN_PLATE_SHARE
        )
    })
}

/// One candidate added to `fit` for one Gauss–Newton step: its reading and the share of
/// the residual it explains.
fn one_step(p: &Problem, fit: &Fit, c: Param) -> (f64, f64, f64) {
    let mut cols = fit.active.clone();
    cols.push(c);
    let k = cols.len();
    let lin = p.linearise(&fit.theta, &cols);
    let (b, g) = fit::normal_equations(&lin, &p.weights, k);
    let Some(chol) = b.clone().cholesky() else {
        return (f64::NAN, f64::NAN, 0.0);
    };
    let step = chol.solve(&(-&g));
    let decrease = -(g.transpose() * &step)[0];
    let mut moved = lin;
    for (r, j) in moved.r.iter_mut().zip(&moved.jac) {
        for i in 0..3 {
            r[i] += (0..k).map(|a| j[i * k + a] * step[a]).sum::<f64>();
        }
    }
    let cov = fit::sandwich(&moved, &p.weights, k, &b, p.bandwidth);
    let est = fit.theta[c.index()] + step[k - 1];
    let sd = cov[(k - 1) * k + (k - 1)].max(0.0).sqrt();
    (est, sd, decrease / fit.rss)
}

/// Read beside every candidate from the start, as the trial's baseline: the moment
/// balance's constant. The body model's own centre-of-mass error and a CoP offset common
/// to both plates both add a near-constant moment, which untouched recordings read as
/// several centimetres either way ([`super::NULL`]); read beside every candidate, it
/// leaves a one-plate CoP offset to be told by how that plate's load differs from the
/// other's.
pub const BASELINE: [Param; 1] = [Param::TrunkCom];

/// One candidate's reading judged against its null band.
fn judged(c: Param, estimate: f64, within: f64, explained: f64, null: &NullBand) -> Reading {
    let sd = within.hypot(null.sd);
    Reading {
        param: c,
        estimate,
        sd,
        sd_within: within,
        z: (estimate - null.mean) / sd,
        baseline: *null,
        threshold: f64::NAN,
        explained,
        verdict: Verdict::NotSignificant,
        alternatives: vec![],
    }
}

/// Why candidate `c` cannot be read beside the `fit`'s active ones, if it cannot.
fn unreadable(p: &Problem, fit: &Fit, b: &nalgebra::DMatrix<f64>, c: Param) -> Option<Verdict> {
    if c == Param::TrunkMass {
        // its signature is the body mass's but for the limbs' share of Σ m a: read as
        // the body mass, never beside it
        return Some(Verdict::NotSeparable {
            from: vec![Param::BodyMass],
        });
    }
    if let Some(from) = scale_bound(c, &fit.active) {
        return Some(Verdict::NotSeparable { from });
    }
    let active: Vec<usize> = fit.active.iter().map(|a| a.index()).collect();
    if let Some(from) = collinear(b, c.index(), &active) {
        return Some(Verdict::NotSeparable {
            from: from.into_iter().map(|i| Param::ALL[i]).collect(),
        });
    }
    unloaded(p, c).map(|reason| Verdict::NotTestable { reason })
}

/// Forward stepwise reading of every candidate, the [`BASELINE`] read throughout, each
/// reading judged against its null band: the readings, the first step's (each candidate
/// read alone beside the baseline), and the final fit.
pub(super) fn read(p: &Problem, settings: &CheckSettings) -> (Vec<Reading>, Vec<Reading>, Fit) {
    let null = &settings.null;
    let mut fit = p.fit(&BASELINE, &[0.0; NPARAM]);
    let mut found: Vec<Reading> = Vec::new();
    let mut last: Vec<Reading> = Vec::new();
    let mut first_readings: Vec<Reading> = Vec::new();
    let mut first = true;
    loop {
        let lin = p.linearise(&fit.theta, &Param::ALL);
        let (b, _) = fit::normal_equations(&lin, &p.weights, NPARAM);
        let mut tested = Vec::new();
        last.clear();
        for c in Param::ALL.into_iter().filter(|c| !fit.active.contains(c)) {
            if let Some(verdict) = unreadable(p, &fit, &b, c) {
                last.push(untested(c, verdict));
                continue;
            }
            let (estimate, within, explained) = one_step(p, &fit, c);
            let r = judged(c, estimate, within, explained, &null[c.index()]);
            if first {
                first_readings.push(r.clone());
            }
            if !(r.sd.is_finite() && r.sd <= testable_sd(c)) {
                last.push(untested(
                    c,
                    Verdict::NotTestable {
                        reason: too_loose(&r),
                    },
                ));
                continue;
            }
            tested.push(r);
        }
        let threshold = if tested.is_empty() {
            f64::INFINITY
        } else {
            crate::problems::distributions::chi2_1_upper(settings.level / tested.len() as f64)
                .sqrt()
        };
        first = false;
        for t in tested.iter_mut() {
            t.threshold = threshold;
        }
        // of the candidates beyond the band, the one that explains most: a reading that
        // explains more but lies inside its band (a clock the body model's error also
        // reads) does not stop a significant one from being found
        let best = tested
            .iter()
            .enumerate()
            .filter(|(_, t)| t.z.abs() > threshold)
            .max_by(|a, b| a.1.explained.total_cmp(&b.1.explained))
            .map(|(i, _)| i);
        match best {
            Some(i) => {
                let mut r = tested.swap_remove(i);
                r.alternatives = tested
                    .iter()
                    .filter(|t| t.z.abs() > threshold)
                    .map(|t| (t.param, t.estimate, t.z))
                    .collect();
                let mut cols = fit.active.clone();
                cols.push(r.param);
                fit = p.fit(&cols, &fit.theta);
                r.verdict = Verdict::Found;
                found.push(r);
            }
            _ => {
                last.extend(tested);
                break;
            }
        }
    }
    // the found effects' final joint readings, and the baseline's
    for r in found.iter_mut() {
        let n = &null[r.param.index()];
        *r = Reading {
            threshold: r.threshold,
            verdict: Verdict::Found,
            alternatives: std::mem::take(&mut r.alternatives),
            ..judged(
                r.param,
                fit.theta[r.param.index()],
                fit.sd(r.param),
                r.explained,
                n,
            )
        };
    }
    for c in BASELINE {
        let r = judged(c, fit.theta[c.index()], fit.sd(c), 0.0, &null[c.index()]);
        first_readings.push(r.clone());
        // the baseline's own uncertainty: it is shown, not judged
        last.push(Reading {
            verdict: Verdict::Baseline,
            sd: r.sd_within,
            z: f64::NAN,
            ..r
        });
    }
    last.sort_by_key(|r| r.param);
    found.extend(last);
    (found, first_readings, fit)
}

/// Why a reading looser than [`testable_sd`] says nothing: the window's own noise, or
/// the spread of untouched trials (the body model's error), whichever is the wider.
fn too_loose(r: &Reading) -> String {
    let c = r.param;
    if !r.sd_within.is_finite() || r.sd_within >= r.baseline.sd {
        format!(
            "read only to ±{} here: the window's loads do not carry its signature",
            fmt_sd(c, r.sd)
        )
    } else {
        format!(
            "read to ±{} here, but untouched trials read it to ±{} (the body model's own error), so it can say nothing a lab could act on",
            fmt_sd(c, r.sd_within),
            fmt_sd(c, r.baseline.sd)
        )
    }
}

fn untested(c: Param, verdict: Verdict) -> Reading {
    Reading {
        param: c,
        estimate: f64::NAN,
        sd: f64::NAN,
        sd_within: f64::NAN,
        z: f64::NAN,
        baseline: NullBand {
            mean: f64::NAN,
            sd: f64::NAN,
        },
        threshold: f64::NAN,
        explained: 0.0,
        verdict,
        alternatives: vec![],
    }
}

/// A standard deviation in the candidate's reporting unit.
fn fmt_sd(c: Param, sd: f64) -> String {
    let (v, unit) = c.display_value(sd);
    format!("{v:.3} {unit}")
}
