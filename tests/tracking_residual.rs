//! Tracking residuals: zero at the model's own motion and forces, exact Jacobians, and
//! generic foot loads equal to the reported ground reaction forces and CoP.

mod common;
use common::*;
use footfall::model::gait::ContactReport;
use footfall::ocp::NodeFunction;
use footfall::problems::tracking::{NodeTarget, TrackingResidual, TrackingWeights};
use footfall::problems::AdTerm;

fn state(m: &footfall::model::GaitModel, set: &footfall::model::ConstraintSet) -> Vec<f64> {
    let q = [1.6, 0.95, 0.11, 0.3, -0.2, 0.1, -0.3, -0.5, 0.05];
    let qd = [1.1, 0.1, 0.2, -1.0, 1.0, 0.3, 1.5, -0.8, 1.0];
    let (q, qd, _) = m.project(set, &q, &qd, &m.theta0()).unwrap();
    let mut x = q;
    x.extend(qd);
    x.extend(vec![0.2; m.na()]);
    x
}

#[test]
fn residual_vanishes_at_the_models_own_motion_and_has_exact_jacobian() {
    for (foot, contacts) in [("ellipse.json", vec![("r.sole", true), ("l.sole", true)]), ("double_circle.json", vec![("r.heel", true), ("r.forefoot", false)])] {
        let m = model("opensim_subject01.json", foot);
        let set = m.constraint_set("s", &contacts).unwrap();
        let x = state(&m, &set);
        let u = vec![0.3; m.nu()];
        // the model's own forces and CoP, from the f64 report path
        let mut xdot = vec![0.0; m.nx()];
        let mut lam = vec![0.0; set.rows.len()];
        let mut rep = ContactReport::default();
        m.dynamics(&set, &x, &u, &[], &mut xdot, &mut lam, Some(&mut rep)).unwrap();
        let loads = m.foot_loads(&set, &rep);
        let generic = m.foot_loads_generic::<f64>(&set, &x, &u, &[]).unwrap();
        for s in 0..2 {
            assert!((generic[s].0 - loads[s].fx).abs() < 1e-9 && (generic[s].1 - loads[s].fy).abs() < 1e-9);
            if loads[s].fy.abs() > 1e-6 {
                assert!((generic[s].2 / generic[s].1 - loads[s].cop_x).abs() < 1e-9, "CoP");
            }
        }
        let nq = m.nq();
        let target = NodeTarget {
            q: x[..nq].iter().map(|v| Some(*v)).collect(),
            qd: x[nq..2 * nq].iter().map(|v| Some(*v)).collect(),
            feet: [0, 1].map(|s| Some((loads[s].fx, loads[s].fy, if loads[s].fy > 1.0 { Some(loads[s].cop_x) } else { None }))),
        };
        let mut w = TrackingWeights::seed(nq, 800.0, 0.305);
        w.excitation = 0.0;
        w.activation = 0.0;
        let r = AdTerm(TrackingResidual::new(&m, set.clone(), target, w));
        let z: Vec<f64> = x.iter().chain(&u).copied().collect();
        let mut v = vec![0.0; r.dim()];
        let mut jac = vec![0.0; r.dim() * z.len()];
        r.eval(&z, &mut v, Some(&mut jac)).unwrap();
        let worst = v.iter().map(|a| a.abs()).fold(0.0, f64::max);
        assert!(worst < 1e-9, "{foot}: residual at the model's own motion {worst:e}");
        // Jacobian vs central differences (perturbed point so all terms are active)
        let mut zp = z.clone();
        let mut rng = Rng::new(4);
        for v in zp.iter_mut() {
            *v += rng.uniform(-0.01, 0.01);
        }
        r.eval(&zp, &mut v, Some(&mut jac)).unwrap();
        let d = r.dim();
        let mut err = 0.0f64;
        for c in 0..zp.len() {
            let h = 1e-6 * zp[c].abs().max(1.0);
            let (mut a, mut b) = (zp.clone(), zp.clone());
            a[c] += h;
            b[c] -= h;
            let (mut va, mut vb) = (vec![0.0; d], vec![0.0; d]);
            r.eval(&a, &mut va, None).unwrap();
            r.eval(&b, &mut vb, None).unwrap();
            for i in 0..d {
                err = err.max(((va[i] - vb[i]) / (2.0 * h) - jac[i + c * d]).abs());
            }
        }
        assert!(err < 1e-5, "{foot}: Jacobian vs FD {err:e}");
    }
}
