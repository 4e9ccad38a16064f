//! `diagnose --profile-clocks`: the cost profiled over each force plate's clock offset.
//!
//! A score test is local. J is not convex in a clock offset of more than about a frame of
//! the kinematics, because the impact transients move across samples: on the real trial
//! whose right plate was delayed by 25 ms (`tests/data/real_hidden/real_clock_r+25ms`) the
//! truncated re-fit from zero stops at −4 ms, while re-fits with the offset held at
//! +20 ms lower J from 8.756 to 7.577 (`tests/real_hidden_refit.rs`). The profile re-fits the run
//! with the offset held at [`CLOCK_PROFILE`] and starts a free re-fit from the lowest
//! point; that re-fit is the candidate's test when it lowers J more than the score test's.
//! With sample or one-sided targets (a free offset cannot move its plate's events there)
//! the profile walks outwards while its outermost point is lowest, and the re-fit holds
//! the offset at the vertex of the parabola through the lowest point and its neighbours;
//! that reading is validated on a held-out half cycle like a score test's
//! (`heldout::validate_held_clock`). With sample targets the held offset also moves the
//! window's start or end, so the points hold different samples: they, the run and the
//! re-fit are compared by their data cost over the samples all of them hold
//! ([`common_samples`](crate::problems::diagnose::common_samples)), and that decrease,
//! over fewer samples than the score test's, is what the two tests are chosen by.

use super::{
    channel_changes, diff_with, refit_into, sibling, Baseline, DiagnoseRequest, FullModel,
    Residuals,
};
use crate::model::effects::{EffectSpec, ForcePlateTimeOffset};
use crate::problems::diagnose::common_samples::{common_sample_costs, CommonSamples, SampleCosts};
use crate::problems::diagnose::stats::{identifiability, Identifiability};
use crate::problems::diagnose::{
    chi2_1_upper, refit_test, ClockProfile, ComparedSamples, ProfilePoint, ProfileVertex,
    ScoreTest, TrackingRunSetup,
};
use crate::problems::evaluation::GaitSolution;
use crate::report::diff::RunDiff;
use crate::workflows::track::{tracking_sqp_settings, TrackedRun, TrackingProblem};
use crate::workflows::{note, Progress, Quiet};

/// The offsets (s) each plate's clock is held at first: steps of 20 ms (two frames of
/// 100 Hz motion capture, where the score test's reach of about one frame either side
/// ends) across the offset's first bounds (±50 ms). Chosen before any real trial was
/// profiled, from the frame rate and those bounds alone. A refined profile (sample or
/// one-sided targets) walks on by the same step while its outermost point is its lowest,
/// up to ±80 ms within today's ±100 ms bounds ([`ForcePlateTimeOffset::BOUNDS`]).
pub const CLOCK_PROFILE: [f64; 4] = [-0.04, -0.02, 0.02, 0.04];

/// KKT tolerance of a profile point's re-fit: its cost decides only where the free
/// re-fit starts (at 1e-3 the right-clock trial's +20 ms point reached J = 7.5772468,
/// the same to 8 digits as at 1e-5, in 20 iterations and 28 s instead of 28 and 74 s).
const POINT_TOL: f64 = 1e-3;

/// Iteration limit of a profile point's re-fit. A point far from the data's offset
/// converges slowly (the right-clock trial's −20 ms point: 133 iterations, 217 s, to
/// J = 10.14 against the run's 8.76). Its cost after this many iterations is not a bound
/// on its minimum: the Gauss–Newton steps of a compliant 600 Hz point leave the run
/// infeasible and J then rises as the violation falls, linearly at full steps (the gain
/// trial's left clock held at +20 ms: J 0.49179 at violation 7.7e-3 after 20
/// iterations, 0.492359 at 1.7e-4 after 40, still rising by 3e-6 an iteration). The profile compares points whose costs differ by 1e-2 and
/// more, so an error of 1e-4 does not move its lowest point or vertex. A compliant
/// foot's points switch to the exact Hessian once those steps stall, and that
/// point converges in 15 iterations ([`super::refit::solve_hessian`]).
const POINT_MAX_ITER: usize = 40;

/// The plate (`right`, `left`, or `both` for one clock shared by both plates) of a clock
/// candidate; `None` for any other candidate.
pub(super) fn plate(c: &EffectSpec) -> Option<&str> {
    match c {
        EffectSpec::ForcePlateTimeOffset { side, .. } => Some(side),
        _ => None,
    }
}

fn clock(side: &str, offset: f64, free: bool) -> EffectSpec {
    EffectSpec::ForcePlateTimeOffset {
        side: side.to_string(),
        offset,
        free: if free { vec!["offset".into()] } else { vec![] },
    }
}

/// The problem of a profile's point: the run's with the plate's clock `held`.
fn point_setup(setup: &TrackingRunSetup, held: &EffectSpec) -> TrackingRunSetup {
    TrackingRunSetup {
        effects: setup.effects.iter().chain([held]).cloned().collect(),
        ..setup.clone()
    }
}

/// The folder, inside the diagnosis folder, that keeps the solution of the point of
/// `side`'s clock held at `offset` (s): `profile_left_+20.0ms`. A later diagnosis of the
/// run given the diagnosis folder with `--start` starts that point there.
pub fn point_folder(side: &str, offset: f64) -> String {
    format!("profile_{side}_{:+.1}ms", 1e3 * offset)
}

/// The test made of a profile's free re-fit, the re-fit and its per-channel errors
/// against the run.
pub(super) type ProfileTest = (ScoreTest, TrackedRun, RunDiff);

/// What the profile of candidate `c` (a plate's clock) found: the profile, and when a
/// point lay below the run's cost, the test made of the free re-fit from it with that
/// re-fit and its per-channel errors against the run. `local` is the candidate's score
/// test (its testability and hint carry over), `noise` the largest model.
#[allow(clippy::too_many_arguments)]
pub(super) fn profile_clock(
    args: &DiagnoseRequest,
    setup: &TrackingRunSetup,
    c: &EffectSpec,
    base: &Baseline<'_>,
    resid: &Residuals,
    local: &ScoreTest,
    noise: Option<&FullModel>,
    keep: &std::path::Path,
    progress: &dyn Progress,
) -> anyhow::Result<(ClockProfile, Option<ProfileTest>)> {
    let side = plate(c).unwrap_or("both");
    let whose = if side == "both" {
        "both plates'".to_string()
    } else {
        format!("the {side} plate's")
    };
    // a point started at a kept solution of its own problem (`--start`) is a KKT point
    // at its first evaluation: the Gauss–Newton QP's multipliers show it without the
    // curvature
    let settings = |p: &TrackingProblem| crate::sqp::SqpSettings {
        gauss_newton_check: true,
        ..tracking_sqp_settings(
            POINT_TOL,
            POINT_MAX_ITER.min(args.max_iter),
            None,
            super::refit::solve_hessian(p),
            None,
        )
    };
    // with one-sided or sample targets a free offset cannot move its plate's events (they
    // stay where its start value puts them), so its re-fit would read the loads' offset
    // against events held elsewhere: the profile is refined by a held re-fit instead,
    // and walks outwards while its lowest point is its outermost
    let refine = setup.sample_targets || setup.one_sided_targets;
    // with sample targets the held offset moves the window's start or end with its
    // plate's events, so the points compare different samples: they are compared by
    // their data cost over the samples all of them and the run compare
    let base_costs = if setup.sample_targets {
        match TrackingProblem::build(setup, &[]).and_then(|p| p.sample_costs(base.solution)) {
            Ok(costs) => Some(costs),
            Err(e) => {
                note!(
                    progress,
                    "  the profile of {whose} clock was not made: the run's cost per sample could not be evaluated ({e:#}); the candidate keeps its score test"
                );
                return Ok((
                    ClockProfile {
                        points: Vec::new(),
                        start: None,
                        refit: None,
                        family: 1,
                        chosen: false,
                        refined: refine,
                        refit_error: Some(format!("the run's cost per sample: {e:#}")),
                        refit_unconverged: None,
                        compared: None,
                        vertex: None,
                    },
                    None,
                ));
            }
        }
    } else {
        None
    };
    let mut points: Vec<ProfilePoint> = Vec::new();
    // each point's solution and, with sample targets, its cost per sample
    let mut solved_points: Vec<Option<(GaitSolution, SampleCosts)>> = Vec::new();
    let mut offsets: Vec<f64> = args.profile_clocks.clone();
    let mut next = 0;
    loop {
        if next == offsets.len() {
            let run_cost = compared_run(&mut points, &solved_points, base_costs.as_ref(), base);
            let known = known_points(&points, run_cost, base_costs.is_some());
            match extension(&known, ForcePlateTimeOffset::BOUNDS).filter(|_| refine) {
                Some(o) => {
                    note!(
                        progress,
                        "  the profile of {whose} clock still falls at its outermost point: extended to {:+.0} ms",
                        1e3 * o
                    );
                    offsets.push(o);
                }
                None => break,
            }
        }
        let offset = offsets[next];
        next += 1;
        let t0 = std::time::Instant::now();
        let held = clock(side, offset, false);
        let want = point_setup(setup, &held);
        let solved =
            TrackingProblem::build(setup, std::slice::from_ref(&held)).and_then(|mut p| {
                // the point's kept solution (`--start`, an earlier diagnosis's
                // `profile_*`) when it fits, otherwise the run's
                let started = super::starts::start_from_kept(
                    args,
                    &want,
                    &mut p,
                    || TrackingProblem::build(setup, std::slice::from_ref(&held)),
                    "starting from the run's solution",
                    progress,
                )?;
                if !started {
                    p.setup
                        .start_from(base.solution)
                        .map_err(|e| anyhow::anyhow!(e))?;
                }
                let (res, sol) = p.solve(&settings(&p), &Quiet)?;
                let costs = match base_costs {
                    Some(_) if res.objective.is_finite() => p.sample_costs(&sol)?,
                    _ => Vec::new(),
                };
                if res.objective.is_finite() {
                    super::starts::keep(&keep.join(point_folder(side, offset)), &want, &sol)?;
                }
                Ok((res, sol, costs))
            });
        let seconds = t0.elapsed().as_secs_f64();
        let (point, kept) = match solved {
            Ok((res, sol, costs)) => {
                let j = res.objective;
                (
                    ProfilePoint {
                        offset,
                        objective: j.is_finite().then_some(j),
                        status: res.status.to_string(),
                        iterations: res.history.len().saturating_sub(1),
                        seconds,
                        compared: None,
                    },
                    j.is_finite().then_some((sol, costs)),
                )
            }
            Err(e) => (
                ProfilePoint {
                    offset,
                    objective: None,
                    status: format!("failed: {e:#}"),
                    iterations: 0,
                    seconds,
                    compared: None,
                },
                None,
            ),
        };
        note!(
            progress,
            "  profile of {whose} clock: held at {:+.0} ms, J = {} ({}, {} iterations) [{:.1} s]",
            1e3 * offset,
            point.objective.map_or("—".into(), |j| format!("{j:.6}")),
            point.status,
            point.iterations,
            seconds
        );
        points.push(point);
        solved_points.push(kept);
    }
    let common = base_costs
        .as_ref()
        .map(|b| compare(&mut points, &solved_points, b, None));
    let run_cost = common.as_ref().map_or(base.objective, |c| c.costs[0]);
    if let Some(common) = &common {
        note!(
            progress,
            "  the profile of {whose} clock compares its points over the {} samples (J's data part) that each of them and the run compare, {:.3}–{:.3} s (a held offset moves the window with its plate's events): the run's {:.6}; {}",
            common.samples,
            common.span.map_or(f64::NAN, |s| s.0),
            common.span.map_or(f64::NAN, |s| s.1),
            run_cost,
            points
                .iter()
                .filter_map(|q| Some(format!("{:+.0} ms: {:.6}", 1e3 * q.offset, q.compared?)))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let family = points.len() + 1;
    let mut profile = ClockProfile {
        points,
        start: None,
        refit: None,
        family,
        chosen: false,
        refined: false,
        refit_error: None,
        refit_unconverged: None,
        compared: None,
        vertex: None,
    };
    let name = local.parameters.first().cloned().unwrap_or_default();
    // a refined profile's parabola through the lowest point (the run's among them): its
    // vertex and curvature, read once for the profile's own reading and its re-fit
    let known = known_points(&profile.points, run_cost, base_costs.is_some());
    let fit = parabola(&known);
    let coefficients = fit.map(|p| (p.a, p.b));
    let parabola = refine.then(|| vertex(fit, &known, ForcePlateTimeOffset::BOUNDS));
    // the profile's reading, kept even when its re-fit does not become the candidate's
    // test or no point lies below the run, its sd with the score test's inflation
    if let Some((offset, curvature)) = parabola {
        profile.vertex = Some(ProfileVertex {
            parabola: coefficients,
            offset,
            sd: curvature_identifiability(
                &name,
                curvature,
                resid.mean_square(noise),
                local.inflation,
            )
            .sd[0],
        });
    }
    // the lowest point, when it lies below the run
    let lowest = profile
        .points
        .iter()
        .enumerate()
        .filter_map(|(i, q)| Some((i, q.offset, point_value(q, base_costs.is_some())?)))
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .filter(|b| b.2 < run_cost);
    let Some((index, start, j_start)) = lowest else {
        return Ok((profile, None));
    };
    let Some(solution) = solved_points[index].as_ref().map(|s| s.0.clone()) else {
        return Ok((profile, None));
    };
    profile.start = Some(start);
    let dir = sibling(
        &args.run,
        &format!("+force_plate_time_offset_{side}_profile"),
    );
    let (effect, curvature) = if let Some((at, curvature)) = parabola {
        note!(
            progress,
            "  the profile of {whose} clock is lowest at {:+.0} ms ({} {j_start:.6} against the run's {run_cost:.6}); its parabola's vertex at {:+.1} ms: a re-fit held there (with sample or one-sided targets a free offset cannot move its plate's events)",
            1e3 * start,
            if base_costs.is_some() { "over the common samples" } else { "J =" },
            1e3 * at
        );
        (clock(side, at, false), curvature)
    } else {
        note!(
            progress,
            "  the profile of {whose} clock is lowest at {:+.0} ms (J = {j_start:.6} against the run's {:.6}): a free re-fit from there",
            1e3 * start,
            base.objective
        );
        (clock(side, start, true), None)
    };
    // a failed re-fit costs this candidate its profile test, not the whole diagnosis
    let run = match refit_into(args, setup, &effect, &solution, dir, progress) {
        Ok(run) => run,
        Err(e) => {
            note!(
                progress,
                "  the profile's re-fit of {whose} clock failed ({e:#}): the candidate keeps its score test"
            );
            profile.refined = refine;
            profile.refit_error = Some(format!("{e:#}"));
            return Ok((profile, None));
        }
    };
    // the held vertex, or where the free offset ended
    let value = run
        .record
        .parameters
        .iter()
        .find(|p| p.name == name)
        .map(|p| p.value)
        .ok_or_else(|| anyhow::anyhow!("the profile's re-fit does not record {name}"))?;
    profile.refined = refine;
    profile.refit = Some((value, run.result.objective));
    if !run.converged {
        profile.refit_unconverged = Some(format!(
            "{}, KKT {:.1e} after {} iterations",
            run.result.status,
            run.result.kkt,
            run.result.history.len().saturating_sub(1)
        ));
    }
    // with sample targets the re-fit's decrease is read over the samples it, the run and
    // every point compare, as the points were
    let (before, after) = match &base_costs {
        Some(b) => {
            let refit_costs: SampleCosts = match &run.breakdown {
                Some(bd) => bd.sample_costs(),
                None => TrackingProblem::build(setup, std::slice::from_ref(&effect))
                    .and_then(|p| p.sample_costs(&run.solution))?,
            };
            let common = compare(&mut profile.points, &solved_points, b, Some(&refit_costs));
            let Some(span) = common.span else {
                profile.refit_error = Some(
                    "the re-fit, the run and the profile's points compare no sample in common"
                        .into(),
                );
                return Ok((profile, None));
            };
            let (run_c, refit_c) = (common.costs[0], common.costs[common.costs.len() - 1]);
            profile.compared = Some(ComparedSamples {
                samples: common.samples,
                span,
                run: run_c,
                refit: Some(refit_c),
            });
            (run_c, refit_c)
        }
        None => (base.objective, run.result.objective),
    };
    let mut t = refit_test(
        c,
        vec![name.clone()],
        vec![value],
        before,
        after,
        base.rows,
        run.result.history.len().saturating_sub(1),
    );
    t.threshold = chi2_1_upper(1e-3 / family as f64);
    // an offset held or ending at its bound is a limit the data pushed against, not a
    // reading (the real right-clock trial at the identification cost: the rigid model's
    // own +25 ms and the edit's +25 ms put the vertex beyond +50 ms)
    if at_bound(value) {
        t.at_bound = vec![name.clone()];
    }
    let diff = diff_with(base.summary, &run)?;
    t.expected_channels = channel_changes(&diff);
    // the statistic as the score tests': the largest model's residuals' inflation,
    // weighted by the channels this re-fit improves, and its residual mean square
    let noise_series = noise.map_or(&[][..], |f| &f.series[..]);
    let phi = resid.inflation_after(noise_series, &t.expected_channels);
    t.testable = local.testable;
    t.identifiability = local.identifiability.clone();
    t.hint = local.hint.clone();
    t.set_inflation(phi);
    let mean_square = resid.mean_square(noise);
    t.set_mean_square(mean_square);
    if refine {
        let id = curvature_identifiability(&name, curvature, mean_square, t.inflation);
        t.set_identifiability(id, local.hint.clone());
        // the re-fit's own reading: the held vertex with the sd of its test
        profile.vertex = Some(ProfileVertex {
            parabola: coefficients,
            offset: value,
            sd: t
                .identifiability
                .as_ref()
                .and_then(|i| i.sd.first().copied().flatten()),
        });
    }
    Ok((profile, Some((t, run, diff))))
}

/// Whether a clock offset (s) held or read is at a bound of its range: a limit the data
/// pushed against, not a reading.
pub(super) fn at_bound(offset: f64) -> bool {
    let (lo, hi) = ForcePlateTimeOffset::BOUNDS;
    offset <= lo + 1e-9 || offset >= hi - 1e-9
}

/// The identifiability of the offset `name` read from a profile's `curvature` `a`: J ≈
/// J* + a (δ − δ*)², so the reduced Hessian inverse is 1/(2a), and one sd is where the
/// statistic rises by one, a (δ − δ*)² = φ s² (residual mean square `s2`, inflation
/// `phi`); unknown without a curvature.
fn curvature_identifiability(
    name: &str,
    curvature: Option<f64>,
    s2: f64,
    phi: f64,
) -> Identifiability {
    let span = vec![ForcePlateTimeOffset::BOUNDS.1 - ForcePlateTimeOffset::BOUNDS.0];
    match curvature {
        Some(a) => identifiability(vec![name.to_string()], vec![vec![0.5 / a]], span, s2, phi),
        None => Identifiability::unknown(
            vec![name.to_string()],
            span,
            "the profile has fewer than three points or bends downwards at its lowest: no curvature to read the offset from".into(),
        ),
    }
}

/// The profile's points with a cost, (offset, cost), and the run's own at zero.
fn known_points(points: &[ProfilePoint], run_value: f64, by_samples: bool) -> Vec<(f64, f64)> {
    let mut known: Vec<(f64, f64)> = points
        .iter()
        .filter_map(|q| Some((q.offset, point_value(q, by_samples)?)))
        .collect();
    known.push((0.0, run_value));
    known
}

/// What a profile point is compared by: with sample targets (`by_samples`) its data cost
/// over the samples all compare, else its cost J.
fn point_value(q: &ProfilePoint, by_samples: bool) -> Option<f64> {
    if by_samples {
        q.compared
    } else {
        q.objective
    }
}

/// Set every solved point's `compared` cost over the samples that it, every other solved
/// point, the run (`base_costs`) and `extra` (the re-fit's) compare. The returned costs
/// are the run's first and `extra`'s last.
fn compare(
    points: &mut [ProfilePoint],
    solved: &[Option<(GaitSolution, SampleCosts)>],
    base_costs: &SampleCosts,
    extra: Option<&SampleCosts>,
) -> CommonSamples {
    let which: Vec<usize> = (0..points.len()).filter(|&i| solved[i].is_some()).collect();
    let mut all: Vec<&[(f64, u8, f64)]> = vec![base_costs];
    all.extend(
        which
            .iter()
            .filter_map(|&i| solved[i].as_ref().map(|s| &s.1[..])),
    );
    all.extend(extra.map(|e| &e[..]));
    let common = common_sample_costs(&all);
    for (k, &i) in which.iter().enumerate() {
        points[i].compared = Some(common.costs[k + 1]);
    }
    common
}

/// What the run (at zero) is compared by: with sample targets its data cost over the
/// samples it and every solved point compare (which sets the points'), else its J.
fn compared_run(
    points: &mut [ProfilePoint],
    solved: &[Option<(GaitSolution, SampleCosts)>],
    base_costs: Option<&SampleCosts>,
    base: &Baseline<'_>,
) -> f64 {
    match base_costs {
        Some(b) => compare(points, solved, b, None).costs[0],
        None => base.objective,
    }
}

/// Where a refined profile goes next: when its lowest point (the run's at zero among
/// `points`) is its outermost on one side, one more step outwards, the step being the
/// spacing of its two outermost points on that side, while the vertex it may lead to
/// (up to half a step beyond) stays within `bounds`. `None` when the lowest point is
/// inside the profile or the bounds leave no room.
fn extension(points: &[(f64, f64)], bounds: (f64, f64)) -> Option<f64> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    let low = (0..p.len()).min_by(|&i, &j| p[i].1.total_cmp(&p[j].1))?;
    let n = p.len();
    if n < 2 {
        return None;
    }
    let next = if low == n - 1 && p[low].0 > 0.0 {
        let step = p[n - 1].0 - p[n - 2].0;
        Some((p[n - 1].0 + step, step))
    } else if low == 0 && p[0].0 < 0.0 {
        let step = p[1].0 - p[0].0;
        Some((p[0].0 - step, step))
    } else {
        None
    };
    next.filter(|&(x, step)| {
        step > 0.0 && x - 0.5 * step >= bounds.0 - 1e-12 && x + 0.5 * step <= bounds.1 + 1e-12
    })
    .map(|(x, _)| x)
}

/// The vertex of the parabola through the lowest of the profile's `points` (offset,
/// cost; the run at zero among them) and its two neighbours in offset (its two nearest
/// on one side at an end of the profile), kept within half a step beyond those three and
/// within `bounds`; with the parabola's curvature `a` of `J ≈ J* + a (δ − δ*)²` (`None`
/// with fewer than three points). A parabola open downwards gives the lowest point.
/// `fit` is `parabola(points)`, read once by the caller.
fn vertex(fit: Option<Parabola>, points: &[(f64, f64)], bounds: (f64, f64)) -> (f64, Option<f64>) {
    let Some(p) = fit else {
        let low = points.iter().min_by(|a, b| a.1.total_cmp(&b.1));
        return (low.map_or(0.0, |l| l.0), None);
    };
    if !(p.a > 0.0 && p.a.is_finite()) {
        return (p.lowest, None);
    }
    let lo = (p.span.0 - 0.5 * p.steps.0).max(bounds.0);
    let hi = (p.span.1 + 0.5 * p.steps.1).min(bounds.1);
    ((-p.b / (2.0 * p.a)).clamp(lo, hi), Some(p.a))
}

/// The parabola `a δ² + b δ + c` through the lowest of a profile's `points` (offset,
/// cost) and its two neighbours in offset (its two nearest on one side at an end); `c`
/// is not needed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Parabola {
    pub a: f64,
    pub b: f64,
    /// The lowest point's offset.
    pub lowest: f64,
    /// The three points' first and last offsets.
    pub span: (f64, f64),
    /// The spacings of the first two and the last two of them.
    pub steps: (f64, f64),
}

/// The [`Parabola`] through the lowest of `points` and its neighbours (`None` with
/// fewer than three points).
pub(super) fn parabola(points: &[(f64, f64)]) -> Option<Parabola> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    let low = (0..p.len()).min_by(|&i, &j| p[i].1.total_cmp(&p[j].1))?;
    if p.len() < 3 {
        return None;
    }
    let i = low.clamp(1, p.len() - 2);
    let [(x0, y0), (x1, y1), (x2, y2)] = [p[i - 1], p[i], p[i + 1]];
    let (s01, s12) = ((y1 - y0) / (x1 - x0), (y2 - y1) / (x2 - x1));
    let a = (s12 - s01) / (x2 - x0);
    let b = s01 - a * (x0 + x1);
    Some(Parabola {
        a,
        b,
        lowest: p[low].0,
        span: (x0, x2),
        steps: (x1 - x0, x2 - x1),
    })
}

#[cfg(test)]
mod tests {
    use super::{extension, parabola, vertex};

    /// The vertex and curvature of a parabola sampled at the profile's points, at an end
    /// of them too, and the lowest point where the three around it bend downwards.
    #[test]
    fn the_vertex_of_three_profile_points() {
        let j = |d: f64| 1.5 + 300.0 * (d - 0.013) * (d - 0.013);
        let at = |xs: &[f64]| xs.iter().map(|&x| (x, j(x))).collect::<Vec<_>>();
        let pts = at(&[-0.04, -0.02, 0.0, 0.02, 0.04]);
        let (v, a) = vertex(parabola(&pts), &pts, (-0.05, 0.05));
        assert!((v - 0.013).abs() < 1e-12 && (a.unwrap() - 300.0).abs() < 1e-9);
        // lowest at the end: the two nearest on one side, kept within half a step
        let far = |d: f64| 1.5 + 300.0 * (d - 0.09) * (d - 0.09);
        let pts: Vec<_> = [-0.04, -0.02, 0.0, 0.02, 0.04]
            .iter()
            .map(|&x| (x, far(x)))
            .collect();
        let (v, _) = vertex(parabola(&pts), &pts, (-0.05, 0.05));
        assert!((v - 0.05).abs() < 1e-12, "{v}");
        // bent downwards (at an end): the lowest point
        let pts = [(0.02, 0.99), (-0.02, 1.2), (0.04, 0.5), (0.0, 1.0)];
        assert_eq!(vertex(parabola(&pts), &pts, (-0.05, 0.05)), (0.04, None));
    }

    /// A refined profile walks outwards while its outermost point is its lowest, by the
    /// spacing of its outer points, until the bounds leave no room for the vertex; a
    /// minimum inside it, or at zero, stops it. Walked on a parabola with its minimum at
    /// +57 ms, it ends with +80 ms, and the vertex read from it is the minimum.
    #[test]
    fn a_profile_extends_while_its_outermost_point_is_lowest() {
        let bounds = (-0.1, 0.1);
        // the offsets a profile from ±20 and ±40 ms adds on the cost `f`, and its points
        let walk = |f: &dyn Fn(f64) -> f64| {
            let mut pts: Vec<(f64, f64)> = [-0.04, -0.02, 0.0, 0.02, 0.04]
                .iter()
                .map(|&x| (x, f(x)))
                .collect();
            let mut added = Vec::new();
            while let Some(x) = extension(&pts, bounds) {
                added.push(x);
                pts.push((x, f(x)));
                assert!(added.len() < 10, "{added:?}");
            }
            (added, pts)
        };
        let j = |d: f64| 1.3 + 500.0 * (d - 0.057) * (d - 0.057);
        let (added, pts) = walk(&j);
        assert_eq!(added.len(), 2, "{added:?}");
        assert!((added[0] - 0.06).abs() < 1e-12 && (added[1] - 0.08).abs() < 1e-12);
        let (v, a) = vertex(parabola(&pts), &pts, bounds);
        assert!(
            (v - 0.057).abs() < 1e-9 && (a.unwrap() - 500.0).abs() < 1e-6,
            "{v} {a:?}"
        );
        // the other side, and no room beyond ±90 ms
        let (added, _) = walk(&|d: f64| 1.3 + 500.0 * (d + 0.2) * (d + 0.2));
        assert_eq!(added.len(), 2, "{added:?}");
        assert!((added[1] + 0.08).abs() < 1e-12);
        // a minimum inside the profile, or at zero: no extension
        let (added, _) = walk(&|d: f64| 1.3 + 500.0 * (d - 0.025) * (d - 0.025));
        assert!(added.is_empty(), "{added:?}");
        let at_zero: Vec<(f64, f64)> = [-0.04, 0.0, 0.04]
            .iter()
            .map(|&x| (x, 1.0 + x * x))
            .collect();
        assert_eq!(extension(&at_zero, bounds), None);
        // the old ±50 ms bounds leave no room beyond +40 ms
        let pts: Vec<(f64, f64)> = [-0.04, -0.02, 0.0, 0.02, 0.04]
            .iter()
            .map(|&x| (x, j(x)))
            .collect();
        assert_eq!(extension(&pts, (-0.05, 0.05)), None);
    }
}
