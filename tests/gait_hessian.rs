//! Exact second derivatives of the gait tracking problem: every term's weighted Hessian
//! against central differences of its exact Jacobian, and the assembled Hessian of the
//! Lagrangian of the whole transcription against central differences of its gradient.

use crate::common;
use common::*;
use footfall::integrate::IntegratorSettings;
use footfall::ocp::{NodeFunction, Transcription};
use footfall::problems::gait::GaitCycle;
use footfall::sqp::Nlp;

/// Largest |H − FD(∇(wᵀf))| relative to max(1, |H|) over all entries.
fn term_hessian_error(f: &dyn NodeFunction, z: &[f64], wts: &[f64]) -> f64 {
    let (d, nz) = (f.dim(), z.len());
    let mut h = vec![0.0; nz * nz];
    f.weighted_hessian(z, wts, &mut h).unwrap();
    let grad = |z: &[f64]| {
        let mut v = vec![0.0; d];
        let mut j = vec![0.0; d * nz];
        f.eval(z, &mut v, Some(&mut j)).unwrap();
        (0..nz)
            .map(|c| (0..d).map(|i| wts[i] * j[i + c * d]).sum::<f64>())
            .collect::<Vec<f64>>()
    };
    let scale = h.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    let mut worst = 0.0f64;
    for c in 0..nz {
        let e = 1e-6 * z[c].abs().max(1.0);
        let mut zp = z.to_vec();
        zp[c] += e;
        let mut zm = z.to_vec();
        zm[c] -= e;
        let (gp, gm) = (grad(&zp), grad(&zm));
        for r in 0..nz {
            worst = worst.max(((gp[r] - gm[r]) / (2.0 * e) - h[r + c * nz]).abs() / scale);
        }
    }
    worst
}

/// The assembled Hessian of the Lagrangian (Gauss–Newton plus the curvature triplets,
/// upper triangle) applied to `d`, and central differences (step `e`) of `grad_l` along
/// `d`: `(H d, FD)`.
fn hessian_and_differences(
    gn: (&[usize], &[usize], &[f64]),
    curvature: (&[usize], &[usize], &[f64]),
    w0: &[f64],
    d: &[f64],
    e: f64,
    grad_l: impl Fn(&[f64]) -> Vec<f64>,
) -> (Vec<f64>, Vec<f64>) {
    let mut hd = vec![0.0; w0.len()];
    for (rows, cols, vals) in [gn, curvature] {
        for k in 0..rows.len() {
            let (r, c, v) = (rows[k], cols[k], vals[k]);
            hd[r] += v * d[c];
            if r != c {
                hd[c] += v * d[r];
            }
        }
    }
    let wp: Vec<f64> = w0.iter().zip(d).map(|(w, d)| w + e * d).collect();
    let wm: Vec<f64> = w0.iter().zip(d).map(|(w, d)| w - e * d).collect();
    let (gp, gm) = (grad_l(&wp), grad_l(&wm));
    let fd: Vec<f64> = gp
        .iter()
        .zip(&gm)
        .map(|(a, b)| (a - b) / (2.0 * e))
        .collect();
    (hd, fd)
}

/// Largest |H d − FD| ([`hessian_and_differences`]) relative to the differences' largest
/// entry; and that entry.
fn hessian_error(
    gn: (&[usize], &[usize], &[f64]),
    curvature: (&[usize], &[usize], &[f64]),
    w0: &[f64],
    d: &[f64],
    e: f64,
    grad_l: impl Fn(&[f64]) -> Vec<f64>,
) -> (f64, f64) {
    let (hd, fd) = hessian_and_differences(gn, curvature, w0, d, e, grad_l);
    let scale = fd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = hd
        .iter()
        .zip(&fd)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
        / scale;
    (worst, scale)
}

/// For multipliers λ drawn from `rng` (uniform in ±1), the assembled Hessian of the
/// Lagrangian `f + λᵀc` at `w0` against central differences (step 1e-5) of its exact
/// gradient `∇f + Jᵀλ`, along `directions` random directions drawn after λ: per direction
/// `(worst, scale)` as [`hessian_error`] gives them.
fn lagrangian_hessian_errors(
    tr: &Transcription,
    w0: &[f64],
    rng: &mut Rng,
    directions: usize,
) -> Vec<(f64, f64)> {
    let lambda: Vec<f64> = (0..tr.m()).map(|_| rng.uniform(-1.0, 1.0)).collect();
    let (ev, (hr, hc, hv)) =
        Nlp::evaluate_with_hessian(tr, w0, &lambda).unwrap_or_else(|e| panic!("{}", e.chain()));
    let (gr, gc) = tr.gauss_newton_pattern();
    let (jr, jc) = tr.jacobian_pattern();
    let grad_l = |w: &[f64]| {
        let e = Nlp::evaluate(tr, w, true).unwrap();
        let mut g = e.grad.clone();
        for k in 0..jr.len() {
            g[jc[k]] += lambda[jr[k]] * e.jac[k];
        }
        g
    };
    (0..directions)
        .map(|_| {
            let d: Vec<f64> = (0..tr.n()).map(|_| rng.uniform(-1.0, 1.0)).collect();
            hessian_error((gr, gc, &ev.gn), (&hr, &hc, &hv), w0, &d, 1e-5, &grad_l)
        })
        .collect()
}

#[test]
fn gait_term_hessians_match_finite_differences() {
    for (foot, phases) in [
        ("ellipse.json", "phases/ellipse_walk.json"),
        ("double_circle.json", "phases/double_circle_walk.json"),
    ] {
        let (m, sets, setup) = bundled_tracking(foot, phases);
        let cycle = GaitCycle::new(&m, &setup.seq, &sets).unwrap();
        let ocp = setup
            .ocp(&cycle, &m, &sets, IntegratorSettings::default())
            .unwrap();
        let tr = Transcription::new(&ocp).unwrap();
        let (_, _, w0) = tr.variable_bounds_and_guess();
        let mut rng = Rng::new(7);
        let mut seen = std::collections::BTreeMap::new();
        let mut terms: Vec<(&str, &dyn NodeFunction, Vec<footfall::ocp::Block>)> = Vec::new();
        for c in &ocp.constraints {
            terms.push((&c.term.name, &*c.term.f, c.term.args.clone()));
        }
        for t in ocp.transitions.iter().flatten() {
            terms.push((&t.name, &*t.f, t.args.clone()));
        }
        for t in &ocp.least_squares {
            terms.push((&t.name, &*t.f, t.args.clone()));
        }
        for (name, f, args) in terms {
            // a few instances of every kind of term
            let count = seen.entry(name.to_string()).or_insert(0usize);
            *count += 1;
            if *count > 3 || !f.has_hessian() {
                assert!(
                    f.has_hessian(),
                    "{foot}: term '{name}' has no exact Hessian"
                );
                continue;
            }
            let z: Vec<f64> = args
                .iter()
                .flat_map(|b| w0[tr.range(*b)].to_vec())
                .collect();
            let wts: Vec<f64> = (0..f.dim()).map(|_| rng.uniform(-1.0, 1.0)).collect();
            let err = term_hessian_error(f, &z, &wts);
            assert!(
                err < 1e-5,
                "{foot}: term '{name}': Hessian differs from FD by {err:e} (relative)"
            );
        }
        eprintln!("{foot}: terms checked: {seen:?}");
    }
}

/// The Hessian of the Lagrangian assembled by the transcription (Gauss–Newton + objective
/// curvature + term curvature + interval curvature from second-order sensitivities),
/// applied to random directions, matches central differences of the exact gradient of
/// the Lagrangian `∇f + Jᵀλ`.
#[test]
fn tracking_lagrangian_hessian_matches_finite_differences() {
    let (m, sets, setup) = bundled_tracking("ellipse.json", "phases/ellipse_walk.json");
    let cycle = GaitCycle::new(&m, &setup.seq, &sets).unwrap();
    let tight = IntegratorSettings {
        rtol: 1e-12,
        atol: 1e-12,
        ..Default::default()
    };
    let ocp = setup.ocp(&cycle, &m, &sets, tight).unwrap();
    let tr = Transcription::new(&ocp).unwrap();
    let (_, _, w0) = tr.variable_bounds_and_guess();
    let errors = lagrangian_hessian_errors(&tr, &w0, &mut Rng::new(11), 2);
    for (trial, (worst, scale)) in errors.into_iter().enumerate() {
        eprintln!("direction {trial}: |Hd − FD| / |FD|∞ = {worst:.2e} (|FD|∞ = {scale:.3e})");
        // the interval curvature is a Gauss–Legendre quadrature of the second-order
        // adjoint identity, the adjoint integrated backward: with these draws 4.7e-6 and
        // 1.5e-5 (6.2e-5 and 1.5e-4, largest in the first interval after the impact, with
        // the adjoint from the inverse of the transition matrix). Term Hessians alone are
        // checked to 1e-5 above.
        assert!(
            worst < 2e-4,
            "assembled Hessian differs from FD of the gradient by {worst:e} (relative)"
        );
    }
}

/// With sample targets (every measured sample compared at its own instant inside a
/// shooting interval) the objective's curvature includes the residuals' own
/// `2 Σ r ∇²r` through `x(τ)`: its direct part and the residuals' weight on the state's
/// second-order sensitivity (`2 r ∂r/∂x` at τ, by the interval's curvature identity on
/// pieces split at the sample instants). The case where it matters: the heel pad's
/// stiffness multiplies its compression, so its column of the Hessian is mostly that
/// curvature. Measured at the kept solution of a 100 Hz synthetic trial: with the data
/// terms' curvature left out (Gauss–Newton in them) the stiffness column was off by 91 %
/// of its largest entry and the heel-pad re-fit converged linearly (107 iterations,
/// rate 0.91 per iteration, 179 s in the release build); with it 0.2 % and 22 iterations
/// (38 s).
#[test]
fn sample_target_hessian_matches_finite_differences_with_a_heel_pad() {
    use footfall::model::effects::EffectSpec;
    use footfall::workflows::synth::SynthRequest;
    use footfall::workflows::track::{TrackRequest, TrackingProblem};
    let trial = root().join("tests/data/hidden/double_circle_none");
    let mut req = TrackRequest::new("double-circle");
    req.run.model = root().join("models/opensim_subject01.json");
    req.run.data = Some(trial.join("synthetic.csv"));
    req.run.sample_targets = true;
    req.run.noise_weights = Some(SynthRequest::default_noise());
    let pad = EffectSpec::parse_cli("heel_pad_compliance").unwrap();
    let mut prob = TrackingProblem::build(&req.run, &[pad]).unwrap();
    let start = footfall::workflows::read_solution(&trial.join("tracked_samples")).unwrap();
    prob.setup.start_from(&start).unwrap();
    prob.integrator.rtol = 1e-12;
    prob.integrator.atol = 1e-12;
    prob.integrator.sens_tol = Some(1e-12);
    prob.with_transcription(|tr, _, w0| {
        let n = tr.n();
        let theta = tr.range(footfall::ocp::Block::Params);
        // the objective's curvature alone (λ = 0)
        let lambda = vec![0.0; tr.m()];
        let (ev, (hr, hc, hv)) = Nlp::evaluate_with_hessian(tr, &w0, &lambda).unwrap();
        let (gr, gc) = tr.gauss_newton_pattern();
        let grad = |w: &[f64]| Nlp::evaluate(tr, w, true).unwrap().grad;
        let mut rng = Rng::new(5);
        let random: Vec<f64> = (0..n).map(|_| rng.uniform(-1.0, 1.0)).collect();
        let mut stiffness = vec![0.0; n];
        stiffness[theta.start] = 1.0;
        // (direction, tolerance): measured 2.2e-3 and 1.8e-5; 0.91 and 1.2e-3 with the
        // data terms Gauss–Newton
        for (what, d, tol) in [
            ("the pad's stiffness", stiffness, 1e-2),
            ("a random direction", random, 2e-4),
        ] {
            let (worst, scale) =
                hessian_error((gr, gc, &ev.gn), (&hr, &hc, &hv), &w0, &d, 1e-5, grad);
            eprintln!("{what}: |Hd − FD| / |FD|∞ = {worst:.2e} (|FD|∞ = {scale:.3e})");
            assert!(
                worst < tol,
                "{what}: the Hessian differs from differences of the gradient by {worst:e}"
            );
        }
        Ok(())
    })
    .unwrap();
}

/// The compliant foot (volumetric ellipse) at the kept solution of the bundled trial's
/// identification track (tests/data/real_compliant/untouched): the assembled Hessian of
/// the Lagrangian (random multipliers) applied to a random direction against central
/// differences of its gradient, node block by node block. The contact force's curvature
/// changes within milliseconds at heel strike, in the first interval, which the 4-point
/// rule per piece missed: measured with these draws, the first node's block was off by
/// 0.23 of the largest difference (0.67 of its own) with each piece undivided, 0.067 in
/// two parts (the stiff models' rule), 1.4e-3 in four; and the SQP's steps alternated
/// in sign near the optimum, its KKT residual falling by 7 % per iteration.
#[test]
fn compliant_heel_strike_curvature_matches_finite_differences() {
    use footfall::ocp::Block;
    use footfall::workflows::track::TrackingProblem;
    let req = compliant_identification_request();
    let mut prob = TrackingProblem::build(&req.run, &[]).unwrap();
    let start =
        footfall::workflows::read_solution(&root().join("tests/data/real_compliant/untouched"))
            .unwrap();
    prob.start_at(&start).unwrap();
    prob.integrator.rtol = 1e-12;
    prob.integrator.atol = 1e-12;
    prob.integrator.sens_tol = Some(1e-12);
    prob.with_transcription(|tr, _, w0| {
        let n = tr.n();
        let mut rng = Rng::new(7);
        let d: Vec<f64> = (0..n).map(|_| rng.uniform(-1.0, 1.0)).collect();
        let lambda: Vec<f64> = (0..tr.m()).map(|_| rng.uniform(-1.0, 1.0)).collect();
        let (ev, (hr, hc, hv)) = Nlp::evaluate_with_hessian(tr, &w0, &lambda).unwrap();
        let (gr, gc) = tr.gauss_newton_pattern();
        let (jr, jc) = tr.jacobian_pattern();
        let grad_l = |w: &[f64]| {
            let e = Nlp::evaluate(tr, w, true).unwrap();
            let mut g = e.grad.clone();
            for k in 0..jr.len() {
                g[jc[k]] += lambda[jr[k]] * e.jac[k];
            }
            g
        };
        let (hd, fd) =
            hessian_and_differences((gr, gc, &ev.gn), (&hr, &hc, &hv), &w0, &d, 1e-6, grad_l);
        let scale = fd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let intervals = tr.ocp().phases[0].intervals;
        let mut worst = (0.0f64, 0);
        for node in 0..=intervals {
            let r = tr.range(Block::State { phase: 0, node });
            let err = r.clone().map(|i| (hd[i] - fd[i]).abs()).fold(0.0, f64::max) / scale;
            eprintln!("node {node:>2}: |Hd − FD|∞ = {err:.2e} of |FD|∞ = {scale:.3e}");
            if err > worst.0 {
                worst = (err, node);
            }
        }
        assert!(
            worst.0 < 0.1,
            "node {}'s Hessian differs from differences of the gradient by {:.2e} of their largest entry",
            worst.1,
            worst.0
        );
        Ok(())
    })
    .unwrap();
}

/// At the kept point of `tests/data/singular_transition` (OpenCap subject 4) integrated at
/// 1e-10, the state transition matrices of the shooting intervals are ill-conditioned
/// (condition numbers 1e2 to 1e21: the swing ankle's velocity decays within milliseconds)
/// and singular at a node of several single-stance intervals, so the adjoint cannot come
/// from `μ(τ)ᵀ = λᵀΨ(1)Ψ(τ)⁻¹`; it is integrated backward. The assembled Hessian of the
/// Lagrangian (random multipliers) applied to random directions matches central
/// differences of its exact gradient: measured 1.6e-6 and 6.5e-7 of the differences'
/// largest entry, against 0.37 with the adjoint from Ψ(τ)⁻¹ where Ψ(τ) could be inverted.
#[test]
fn an_ill_conditioned_transition_matrix_leaves_the_curvature_exact() {
    use footfall::workflows::track::{TrackRequest, TrackingProblem};
    let mut req = TrackRequest::new("ellipse");
    req.run.model = root().join("models/opencap_s4.json");
    req.run.data =
        Some(root().join("tests/data/check/trials/opencap_s4_walking1/clock_r+20ms/trial.csv"));
    req.run.check_points = vec![(0, 0, 0.2901952810842129)];
    let mut prob = TrackingProblem::build(&req.run, &[]).unwrap();
    let start =
        footfall::workflows::read_solution(&root().join("tests/data/singular_transition")).unwrap();
    prob.start_at(&start).unwrap();
    prob.integrator.rtol = 1e-10;
    prob.integrator.atol = 1e-10;
    prob.with_transcription(|tr, _, w0| {
        let errors = lagrangian_hessian_errors(tr, &w0, &mut Rng::new(3), 2);
        for (trial, (worst, scale)) in errors.into_iter().enumerate() {
            eprintln!("direction {trial}: |Hd − FD| / |FD|∞ = {worst:.2e} (|FD|∞ = {scale:.3e})");
            assert!(
                worst < 1e-4,
                "assembled Hessian differs from FD of the gradient by {worst:e} (relative)"
            );
        }
        Ok(())
    })
    .unwrap();
}
