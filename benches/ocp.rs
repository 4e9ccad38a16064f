//! Criterion benchmarks of the OCP engine on the generic problems (same definitions as the
//! CasADi peer of the cart-pole and five-link biped): one forward-sensitivity sweep over all intervals,
//! one QP subproblem, and full solves from the problem's initial guess; and the
//! per-iteration evaluations and the whole solve of the CasADi gait peer's tracking
//! problem.

use criterion::{criterion_group, criterion_main, Criterion};
use footfall::integrate::IntegratorSettings;
use footfall::ocp::Transcription;
use footfall::problems::benchmarks::{read_problem_json, Benchmark};
use footfall::problems::peer_gait::stages;
use footfall::sqp::qp::{self, QpData, Triplets};
use footfall::sqp::{self, HessianMode, Nlp, Silent, SqpSettings};
use std::time::Duration;

fn bench(c: &mut Criterion) {
    for (file, hessian, max_iter) in [
        ("problems/cartpole_swingup.json", HessianMode::Exact, 100),
        ("problems/five_link_biped.json", HessianMode::Exact, 100),
    ] {
        let bench =
            Benchmark::from_json(read_problem_json(file).expect("problem")).expect("benchmark");
        let name = bench.name();
        let ocp = bench
            .ocp(IntegratorSettings {
                method: footfall::integrate::Method::Adams,
                ..Default::default()
            })
            .expect("ocp");
        let tr = Transcription::new(&ocp).expect("transcription");
        let (w_lb, w_ub, w0) = tr.variable_bounds_and_guess();
        let mut g = c.benchmark_group(name);
        g.sample_size(10).measurement_time(Duration::from_secs(3));
        g.bench_function("sensitivity_sweep", |b| {
            b.iter(|| tr.evaluate(&w0, true).expect("sweep"))
        });
        g.bench_function("plain_sweep", |b| {
            b.iter(|| tr.evaluate(&w0, false).expect("sweep"))
        });
        let ev = tr.evaluate(&w0, true).expect("evaluation");
        let (jr, jc) = Nlp::jacobian_pattern(&tr);
        let (hr, hc) = Nlp::gauss_newton_pattern(&tr);
        let (c_lb, c_ub) = tr.constraint_bounds();
        let mut h = Triplets {
            rows: hr,
            cols: hc,
            vals: ev.gauss_newton.clone(),
        };
        for i in 0..tr.n() {
            h.push(i, i, 1e-9);
        }
        let jac = Triplets {
            rows: jr,
            cols: jc,
            vals: ev.jac.clone(),
        };
        let d_lb: Vec<f64> = (0..tr.n()).map(|i| w_lb[i] - w0[i]).collect();
        let d_ub: Vec<f64> = (0..tr.n()).map(|i| w_ub[i] - w0[i]).collect();
        let weights = vec![1.0; tr.m()];
        let data = QpData {
            h: &h,
            g: &ev.grad,
            jac: &jac,
            c: &ev.c,
            c_lb: &c_lb,
            c_ub: &c_ub,
            d_lb: &d_lb,
            d_ub: &d_ub,
            elastic: Some(1e4),
            elastic_weights: &weights,
            hint: None,
        };
        g.bench_function("qp_solve_elastic", |b| {
            b.iter(|| qp::solve(&data).expect("qp"))
        });
        let settings = SqpSettings {
            tol_kkt: 1e-6,
            hessian,
            max_iter,
            ..Default::default()
        };
        let res = sqp::solve(&tr, &w0, &settings, &mut Silent);
        eprintln!(
            "{name}: {} after {} iterations, J = {:.9}, KKT {:.2e}, {:.3} s",
            res.status,
            res.history.len() - 1,
            res.objective,
            res.kkt,
            res.seconds
        );
        g.measurement_time(Duration::from_secs(if name == "five_link_biped" {
            15
        } else {
            5
        }));
        g.bench_function("full_solve", |b| {
            b.iter(|| sqp::solve(&tr, &w0, &settings, &mut Silent))
        });
        g.finish();
    }
}

/// The CasADi gait peer's tracking problem solved from its data guess in the two stages
/// `footfall solve` takes (`problems::peer_gait::stages`): the results of both.
fn peer_solve(bench: &Benchmark) -> (sqp::SqpResult, sqp::SqpResult) {
    let [first, second] = stages(1e-6);
    let r1 = bench
        .with_ocp(first.integrator.clone(), |ocp| {
            let tr = Transcription::new(ocp).expect("transcription");
            let (_, _, w0) = tr.variable_bounds_and_guess();
            sqp::solve(&tr, &w0, &first.settings, &mut Silent)
        })
        .expect("ocp");
    let r2 = bench
        .with_ocp(second.integrator.clone(), |ocp| {
            let tr = Transcription::new(ocp).expect("transcription");
            sqp::solve(&tr, &r1.w, &second.settings, &mut Silent)
        })
        .expect("ocp");
    (r1, r2)
}

/// The CasADi gait peer's tracking problem: what one SQP iteration costs at the data
/// guess (the sweep with first-order sensitivities of all 50 intervals, the same with the
/// exact Hessian of the Lagrangian, and the plain sweep of a line-search trial), and the
/// whole solve from the data guess as `footfall solve` takes it (about 13 s a sample, ten
/// samples: pick it with a filter, `cargo bench --bench ocp -- gait_track_ellipse/full_solve`).
fn gait(c: &mut Criterion) {
    let bench = Benchmark::load(std::path::Path::new(
        "problems/peer_gait_track_ellipse.json",
    ))
    .expect("problem");
    bench
        .with_ocp(IntegratorSettings::default(), |ocp| {
            let tr = Transcription::new(ocp).expect("transcription");
            let (_, _, w0) = tr.variable_bounds_and_guess();
            let lambda = vec![1e-2; tr.m()];
            let mut g = c.benchmark_group("gait_track_ellipse");
            g.sample_size(10).measurement_time(Duration::from_secs(10));
            g.bench_function("sensitivity_sweep", |b| {
                b.iter(|| tr.evaluate(&w0, true).expect("sweep"))
            });
            g.bench_function("sweep_with_exact_hessian", |b| {
                b.iter(|| tr.evaluate_with_hessian(&w0, &lambda).expect("sweep"))
            });
            g.bench_function("plain_sweep", |b| {
                b.iter(|| tr.evaluate(&w0, false).expect("sweep"))
            });
            g.finish();
        })
        .expect("ocp");
    let mut g = c.benchmark_group("gait_track_ellipse");
    // ten samples of one solve each (criterion's least)
    g.sample_size(10).measurement_time(Duration::from_secs(60));
    // criterion calls the routine again for each round of samples: the first run reports
    let reported = std::cell::Cell::new(false);
    g.bench_function("full_solve", |b| {
        b.iter(|| {
            let (r1, r2) = peer_solve(&bench);
            if !reported.replace(true) {
                for (stage, r) in [("block BFGS", &r1), ("exact Hessian", &r2)] {
                    eprintln!(
                        "{stage}: {} after {} iterations, J = {:.9}, KKT {:.2e}; {:.1} s: integration {:.1} s, QP {:.1} s",
                        r.status,
                        r.history.len().saturating_sub(1),
                        r.objective,
                        r.kkt,
                        r.seconds,
                        r.timings.evaluation_s,
                        r.timings.qp_s
                    );
                }
            }
        })
    });
    g.finish();
}

criterion_group!(benches, bench, gait);
criterion_main!(benches);
