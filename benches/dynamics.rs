//! Criterion benchmarks of the model layer: one dynamics evaluation, one dynamics +
//! exact Jacobian evaluation (what the sensitivity right-hand side needs), one weighted
//! Hessian of the dynamics (what the exact Hessian's adjoint needs), and one 40 ms
//! shooting interval with full forward sensitivities (x0, piecewise-linear controls,
//! duration), alone and with the states and sensitivities at the samples inside it that
//! `track --sample-targets` compares (4 at 100 Hz, 40 at 1 kHz; CVODES dense output), for
//! the ellipse foot in single stance and the double-circle foot with both circles on the
//! ground.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use footfall::integrate::{ControlShape, Integrator, IntegratorSettings, ShootingInterval};
use footfall::model::GaitModel;
use footfall::problems::GaitOde;
use std::path::Path;

fn setup(foot: &str, contacts: &[(&str, bool)]) -> (GaitModel, Vec<f64>, Vec<f64>) {
    let m = GaitModel::load(Path::new("models/opensim_subject01.json"), Path::new(foot))
        .expect("model");
    let set = m.constraint_set("stance", contacts).expect("set");
    let q = [1.6, 1.0, 0.11, 0.09, -0.30, 0.11, 0.11, -1.17, -0.03];
    let qd = [1.08, 0.16, 0.20, -2.17, 1.51, 0.33, 2.22, -0.84, 1.40];
    let (q, qd, _) = m.project(&set, &q, &qd, &[]).expect("projection");
    let mut x = q;
    x.extend(qd);
    x.extend(vec![0.2; m.na()]);
    let u = vec![0.3; m.nu()];
    (m, x, u)
}

fn bench(c: &mut Criterion) {
    for (label, foot, contacts) in [
        (
            "ellipse_single_stance",
            "models/feet/ellipse.json",
            vec![("r.sole", true)],
        ),
        (
            "double_circle_both_circles",
            "models/feet/double_circle.json",
            vec![("r.heel", true), ("r.forefoot", false)],
        ),
    ] {
        let (m, x, u) = setup(foot, &contacts);
        let set = m.constraint_set("stance", &contacts).expect("set");
        let (nx, nu) = (m.nx(), m.nu());
        let mut xdot = vec![0.0; nx];
        let mut lam = vec![0.0; set.rows.len()];
        c.bench_function(&format!("dynamics/{label}"), |b| {
            b.iter(|| {
                m.dynamics(
                    &set,
                    black_box(&x),
                    black_box(&u),
                    &[],
                    &mut xdot,
                    &mut lam,
                    None,
                )
                .expect("dynamics")
            })
        });
        let mut jac = vec![0.0; nx * (nx + nu)];
        c.bench_function(&format!("dynamics_jacobian/{label}"), |b| {
            b.iter(|| {
                m.dynamics_jacobian(&set, black_box(&x), black_box(&u), &[], &mut xdot, &mut jac)
                    .expect("jacobian")
            })
        });
        let mu: Vec<f64> = (0..nx).map(|i| 1.0 + 0.1 * i as f64).collect();
        let nz = nx + nu;
        let mut hess = vec![0.0; nz * nz];
        c.bench_function(&format!("weighted_dynamics_hessian/{label}"), |b| {
            b.iter(|| {
                m.weighted_dynamics_hessian(
                    &set,
                    (black_box(&x), black_box(&u), &[]),
                    &mu,
                    &mut hess,
                )
                .expect("hessian")
            })
        });
        let ode = GaitOde {
            model: &m,
            set: &set,
        };
        let interval = ShootingInterval::new(&ode, ControlShape::Linear);
        let np = interval.np();
        let mut p = Vec::new();
        interval
            .pack_params(&u, Some(&vec![0.4; nu]), 0.040, &[], &mut p)
            .expect("params");
        let mut integ = Integrator::new(nx, np, IntegratorSettings::default()).expect("integrator");
        let mut x1 = vec![0.0; nx];
        let mut s1 = vec![0.0; nx * (nx + np)];
        let stats = integ
            .integrate_with_sensitivities(&interval, 0.0, 1.0, &x, &p, &mut x1, &mut s1)
            .expect("interval");
        eprintln!(
            "{label}: 40 ms interval, {} sensitivity columns: {stats:?}",
            nx + np
        );
        c.bench_function(&format!("interval_40ms_sensitivities/{label}"), |b| {
            b.iter(|| {
                integ
                    .integrate_with_sensitivities(
                        &interval,
                        0.0,
                        1.0,
                        black_box(&x),
                        &p,
                        &mut x1,
                        &mut s1,
                    )
                    .expect("interval")
            })
        });
        for (rate, n) in [("100Hz", 4), ("1kHz", 40)] {
            let times: Vec<f64> = (1..=n).map(|k| k as f64 / n as f64).collect();
            let (mut xs, mut ss) = (Vec::new(), Vec::new());
            c.bench_function(
                &format!("interval_40ms_sensitivities_samples_{rate}/{label}"),
                |b| {
                    b.iter(|| {
                        xs.clear();
                        ss.clear();
                        integ
                            .integrate_with_sensitivities_dense(
                                &interval,
                                0.0,
                                1.0,
                                black_box(&x),
                                &p,
                                &times,
                                &mut xs,
                                &mut ss,
                            )
                            .expect("interval")
                    })
                },
            );
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(4));
    targets = bench
}
criterion_main!(benches);
