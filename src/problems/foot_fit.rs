//! Foot fitting (Millard & Mombaur 2019, §3.2, eq. 13): pose the foot at toe-off so that its contact
//! point sits on the measured CoP with the measured foot orientation, roll it backwards
//! without slipping along the measured CoP to heel strike, and minimise the
//! force-weighted ankle position and orientation errors
//! $$\sum_i \frac{f_{y,i}}{\max f_y}\Big(w_r\,\|r_{A,i} - r^{EXP}_{A,i}\|^2 + w_\alpha(\alpha_{A,i} - \alpha^{EXP}_{A,i})^2\Big),
//!   \quad w_r = (1/0.01)^2,\ w_\alpha = (1/(\pi/4))^2,$$
//! over the foot's parameters with its total length fixed, by Nelder–Mead.
//!
//! Works for any foot of JSON primitives: the foot's outline is the convex hull of its
//! primitives, sampled finely; rolling without slipping on flat ground moves the contact
//! point along the hull by the distance the CoP moves on the ground (a flat stretch of the
//! hull — e.g. between two circles — leaves the foot still while the CoP crosses it).

use crate::model::geometry::Shape;
use crate::model::spec::FootSpec;
use crate::problems::error::FootFitError;
use argmin::core::{CostFunction, Executor};
use argmin::solver::neldermead::NelderMead;

/// Weight of the ankle position error (1/m²): 1 cm counts as 1.
pub const W_POSITION: f64 = 1e4;
/// Weight of the orientation error (1/rad²): π/4 counts as 1.
pub const W_ANGLE: f64 = 16.0 / (std::f64::consts::PI * std::f64::consts::PI);

/// Measured stance samples of one foot (heel strike first, toe-off last).
#[derive(Debug, Clone, Default)]
pub struct StanceSamples {
    /// Time (s).
    pub t: Vec<f64>,
    /// Ankle joint centre in the world (m).
    pub ankle: Vec<[f64; 2]>,
    /// Foot (ankle frame) angle in the world (rad).
    pub angle: Vec<f64>,
    /// Measured CoP x (m).
    pub cop: Vec<f64>,
    /// Normal force / its maximum (eq. 13 weight).
    pub weight: Vec<f64>,
}

impl StanceSamples {
    /// Append another stance (samples are fitted jointly, each stance rolled separately).
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// The convex outline of a foot in its frame, as a fine polygon, counter-clockwise.
fn outline(foot: &FootSpec) -> Vec<[f64; 2]> {
    let mut pts = Vec::new();
    for p in &foot.primitives {
        match p.shape {
            Shape::Point { position } => pts.push(position),
            Shape::Circle { centre, radius } => {
                for k in 0..720 {
                    let a = k as f64 * std::f64::consts::TAU / 720.0;
                    pts.push([centre[0] + radius * a.cos(), centre[1] + radius * a.sin()]);
                }
            }
            Shape::Ellipse {
                centre,
                angle,
                semi_axes,
            } => {
                let (s, c) = angle.sin_cos();
                for k in 0..1440 {
                    let t = k as f64 * std::f64::consts::TAU / 1440.0;
                    let (x, y) = (semi_axes[0] * t.cos(), semi_axes[1] * t.sin());
                    pts.push([centre[0] + c * x - s * y, centre[1] + s * x + c * y]);
                }
            }
        }
    }
    convex_hull(pts)
}

/// Andrew's monotone chain, counter-clockwise, no repeated end point.
fn convex_hull(mut p: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut h: Vec<[f64; 2]> = Vec::new();
    for &pt in p.iter().chain(p.iter().rev().skip(1)) {
        while h.len() >= 2 && cross(h[h.len() - 2], h[h.len() - 1], pt) <= 0.0 {
            h.pop();
        }
        h.push(pt);
    }
    h.pop();
    h
}

/// Total length of the foot along its frame's x axis (m).
pub fn foot_length(foot: &FootSpec) -> f64 {
    let o = outline(foot);
    let (lo, hi) = o
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[0]), b.max(p[0]))
        });
    hi - lo
}

/// Predicted ankle positions and angles when the foot rolls along the measured CoP,
/// posed at the last sample (toe-off), for a ground at height `ground`.
pub fn roll(
    foot: &FootSpec,
    stance: &StanceSamples,
    ground: f64,
) -> Option<(Vec<[f64; 2]>, Vec<f64>)> {
    let hull = outline(foot);
    let n = hull.len();
    if n < 3 || stance.is_empty() {
        return None;
    }
    // arc length along the hull, counter-clockwise from vertex 0
    let mut s = vec![0.0; n + 1];
    for i in 0..n {
        let (a, b) = (hull[i], hull[(i + 1) % n]);
        s[i + 1] = s[i] + ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    }
    let perimeter = s[n];
    // point and edge direction at arc length u (mod perimeter)
    let at = |u: f64| -> ([f64; 2], f64) {
        let u = u.rem_euclid(perimeter);
        let i = s.partition_point(|&v| v <= u).clamp(1, n) - 1;
        let (a, b) = (hull[i], hull[(i + 1) % n]);
        let len = s[i + 1] - s[i];
        let w = if len > 0.0 { (u - s[i]) / len } else { 0.0 };
        (
            [a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1])],
            (b[1] - a[1]).atan2(b[0] - a[0]),
        )
    };
    let last = stance.len() - 1;
    // toe-off pose: lowest hull vertex at the measured orientation
    let psi_n = stance.angle[last];
    let (sn, cn) = psi_n.sin_cos();
    let k = (0..n).min_by(|&i, &j| {
        let yi = sn * hull[i][0] + cn * hull[i][1];
        let yj = sn * hull[j][0] + cn * hull[j][1];
        yi.total_cmp(&yj)
    })?;
    let u_n = s[k];
    let mut ankle = Vec::with_capacity(stance.len());
    let mut angle = Vec::with_capacity(stance.len());
    for i in 0..stance.len() {
        // counter-clockwise along the bottom runs heel → toe; going back in time the
        // contact moves towards the heel by the distance the CoP moves back
        let u = u_n + (stance.cop[i] - stance.cop[last]);
        let (p, beta) = if i == last {
            (hull[k], f64::NAN)
        } else {
            at(u)
        };
        // orientation that makes the contact edge horizontal (the toe-off pose keeps the
        // measured angle)
        let psi = if i == last { psi_n } else { -beta };
        let (sp, cp) = psi.sin_cos();
        let rp = [cp * p[0] - sp * p[1], sp * p[0] + cp * p[1]];
        ankle.push([stance.cop[i] - rp[0], ground - rp[1]]);
        angle.push(psi);
    }
    Some((ankle, angle))
}

/// Eq. 13 and the per-sample errors.
pub fn fit_cost(
    foot: &FootSpec,
    stances: &[StanceSamples],
    ground: f64,
) -> Option<(f64, Vec<f64>, Vec<f64>)> {
    let mut cost = 0.0;
    let (mut pos, mut ang) = (Vec::new(), Vec::new());
    for st in stances {
        let (a, psi) = roll(foot, st, ground)?;
        for i in 0..st.len() {
            let dr2 = (a[i][0] - st.ankle[i][0]).powi(2) + (a[i][1] - st.ankle[i][1]).powi(2);
            let da = psi[i] - st.angle[i];
            cost += st.weight[i] * (W_POSITION * dr2 + W_ANGLE * da * da);
            pos.push(dr2.sqrt());
            ang.push(da.abs());
        }
    }
    Some((cost, pos, ang))
}

/// The numeric parameters of a foot, in order, and a way to write them back.
pub fn parameters(foot: &FootSpec) -> Vec<f64> {
    let mut p = Vec::new();
    for pr in &foot.primitives {
        match pr.shape {
            Shape::Point { position } => p.extend(position),
            Shape::Circle { centre, radius } => {
                p.extend(centre);
                p.push(radius);
            }
            Shape::Ellipse {
                centre,
                angle,
                semi_axes,
            } => {
                p.extend(centre);
                p.push(angle);
                p.extend(semi_axes);
            }
        }
    }
    p
}

/// `foot` with the parameters `p` (same order as [`parameters`]).
pub fn with_parameters(foot: &FootSpec, p: &[f64]) -> FootSpec {
    let mut f = foot.clone();
    let mut k = 0;
    for pr in &mut f.primitives {
        match &mut pr.shape {
            Shape::Point { position } => {
                *position = [p[k], p[k + 1]];
                k += 2;
            }
            Shape::Circle { centre, radius } => {
                *centre = [p[k], p[k + 1]];
                *radius = p[k + 2];
                k += 3;
            }
            Shape::Ellipse {
                centre,
                angle,
                semi_axes,
            } => {
                *centre = [p[k], p[k + 1]];
                *angle = p[k + 2];
                *semi_axes = [p[k + 3], p[k + 4]];
                k += 5;
            }
        }
    }
    f
}

struct FitProblem<'a> {
    foot: &'a FootSpec,
    stances: &'a [StanceSamples],
    ground: f64,
    length: f64,
}

impl CostFunction for FitProblem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Self::Param) -> Result<f64, argmin::core::Error> {
        let f = with_parameters(self.foot, p);
        if f.primitives.iter().any(|pr| pr.shape.validate().is_err()) {
            return Ok(1e12);
        }
        // total length fixed (seed: 30.5 cm) by a stiff penalty
        let dl = foot_length(&f) - self.length;
        Ok(fit_cost(&f, self.stances, self.ground).map_or(1e12, |c| c.0) + 1e8 * dl * dl)
    }
}

/// Result of a fit.
#[derive(Debug, Clone)]
pub struct FitResult {
    /// The fitted foot.
    pub foot: FootSpec,
    /// Eq. 13 before and after.
    pub cost: (f64, f64),
    /// Nelder–Mead iterations.
    pub iterations: u64,
    /// Ankle position errors (m) and orientation errors (rad) of every sample, fitted.
    pub errors: (Vec<f64>, Vec<f64>),
}

/// Fit `foot` to the stances by Nelder–Mead (simplex steps of 5 mm / 0.05 rad, stopping
/// when the simplex's cost spread falls below `tol`) with its length fixed.
pub fn fit(
    foot: &FootSpec,
    stances: &[StanceSamples],
    ground: f64,
    tol: f64,
    max_iter: u64,
) -> Result<FitResult, FootFitError> {
    let p0 = parameters(foot);
    let length = foot_length(foot);
    let before = fit_cost(foot, stances, ground)
        .ok_or(FootFitError::CannotRoll)?
        .0;
    let mut simplex = vec![p0.clone()];
    for i in 0..p0.len() {
        let mut p = p0.clone();
        p[i] += 0.005;
        simplex.push(p);
    }
    let problem = FitProblem {
        foot,
        stances,
        ground,
        length,
    };
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(tol)
        .map_err(|e| FootFitError::Search(e.into()))?;
    let res = Executor::new(problem, solver)
        .configure(|s| s.max_iters(max_iter))
        .run()
        .map_err(|e| FootFitError::Search(e.into()))?;
    let best = res.state().best_param.clone().unwrap_or(p0);
    let fitted = with_parameters(foot, &best);
    let (after, pos, ang) =
        fit_cost(&fitted, stances, ground).ok_or(FootFitError::FittedCannotRoll)?;
    Ok(FitResult {
        foot: fitted,
        cost: (before, after),
        iterations: res.state().iter,
        errors: (pos, ang),
    })
}

/// The complete stances of both feet in `data` (heel strike to toe-off of the 5 % events,
/// samples above the threshold with a measured CoP), with the ankle poses from the
/// model's forward kinematics of the measured joint angles.
pub fn stances_from_data(
    model: &crate::model::GaitModel,
    data: &crate::data::GaitData,
) -> Result<Vec<StanceSamples>, FootFitError> {
    use crate::data::{detect_events, DEFAULT_EVENT_FRACTION};
    let events = detect_events(data, DEFAULT_EVENT_FRACTION)?;
    let peak = data.peak_vertical_force();
    let mut out = Vec::new();
    for (s, side) in ["r", "l"].iter().enumerate() {
        let name = format!("foot_{side}");
        let body = model
            .tree()
            .body_index(&name)
            .ok_or(FootFitError::NoFootBody { body: name })?;
        for &hs in &events.heel_strike[s] {
            let Some(&to) = events.toe_off[s].iter().find(|&&t| t > hs) else {
                continue;
            };
            let mut st = StanceSamples::default();
            for (k, &t) in data.time.iter().enumerate() {
                let (fy, cop) = (data.feet[s].fy[k], data.feet[s].cop_x[k]);
                if t < hs || t > to || fy <= events.threshold || !cop.is_finite() {
                    continue;
                }
                let q: Vec<f64> = (0..9).map(|i| data.q[i][k]).collect();
                let o = 3 + 3 * s;
                st.t.push(t);
                st.ankle.push(model.body_point(body, [0.0, 0.0], &q));
                st.angle.push(q[2] + q[o] + q[o + 1] + q[o + 2]);
                st.cop.push(cop);
                st.weight.push(fy / peak);
            }
            if st.len() >= 5 {
                out.push(st);
            }
        }
    }
    if out.is_empty() {
        return Err(FootFitError::NoStance);
    }
    Ok(out)
}
