//! The planar model's bodies from its segments, and its segments from de Leva's (1996)
//! parameters ([`super::anthropometry`]) where a model file gives a body mass and stature
//! instead of segments.

use super::anthropometry::{PlanarBodySegments, SegmentParams, DE_LEVA_MALE};
use super::multibody::{Body, Joint};
use super::spec::{SegmentSpec, Segments};

/// Stature (m) estimated from the hip→knee→ankle length with de Leva's (1996) male
/// reference proportions ((thigh + shank length) / stature = 862.5 / 1741 mm).
pub fn estimated_stature(s: &Segments) -> f64 {
    let len = |v: [f64; 2]| (v[0] * v[0] + v[1] * v[1]).sqrt();
    let t = &DE_LEVA_MALE;
    (len(s.knee_in_thigh) + len(s.ankle_in_shank)) * t.stature_mm
        / (t.thigh.length_mm + t.shank.length_mm)
}

/// The planar bodies of the 9-DoF model from segment parameters.
pub fn build_bodies(s: &Segments) -> Vec<Body> {
    let virt = |name: &str, parent: Option<usize>, axis: [f64; 2]| Body {
        name: name.into(),
        parent,
        joint: Joint::Prismatic { axis },
        joint_in_parent: [0.0, 0.0],
        mass: 0.0,
        com: [0.0, 0.0],
        izz: 0.0,
    };
    let seg = |name: String, parent: usize, at: [f64; 2], sp: &SegmentSpec| Body {
        name,
        parent: Some(parent),
        joint: Joint::Revolute,
        joint_in_parent: at,
        mass: sp.mass,
        com: sp.com,
        izz: sp.izz,
    };
    let mut b = vec![
        virt("pelvis_x", None, [1.0, 0.0]),
        virt("pelvis_y", Some(0), [0.0, 1.0]),
    ];
    b.push(seg("hat".into(), 1, [0.0, 0.0], &s.hat));
    for side in ["r", "l"] {
        let base = b.len();
        b.push(seg(format!("thigh_{side}"), 2, s.hip_in_pelvis, &s.thigh));
        b.push(seg(
            format!("shank_{side}"),
            base,
            s.knee_in_thigh,
            &s.shank,
        ));
        b.push(seg(
            format!("foot_{side}"),
            base + 1,
            s.ankle_in_shank,
            &s.foot,
        ));
    }
    b
}

/// Horizontal distance heel → ankle as a fraction of foot length: 0.26, from the heel and
/// toe-tip markers of the OpenSim subject01 model (heel 0.075 m behind the ankle, toe tip
/// 0.216 m ahead of it, `data/opensim_subject01/model.json`).
pub const ANKLE_FROM_HEEL_FRACTION: f64 = 0.26;
/// Ankle height above the sole as a fraction of stature: 0.039 (Winter 2009,
/// *Biomechanics and Motor Control of Human Movement*, 4th ed., Fig. 4.1).
pub const ANKLE_HEIGHT_FRACTION: f64 = 0.039;

/// Segments of the planar model from de Leva (1996) parameters: HAT frame origin at the
/// hip midpoint, segments along their frames' −y axes; the foot's COM lies on the
/// heel→toe line at the documented height below the ankle.
pub fn segments_from_de_leva(p: &PlanarBodySegments) -> Segments {
    let down = |sp: &SegmentParams| SegmentSpec {
        mass: sp.mass,
        com: [0.0, -sp.com_from_proximal],
        izz: sp.inertia_com,
    };
    let foot = &p.foot;
    // The ankle sits above the foot at a fixed fraction of the foot length from the heel.
    let ankle_from_heel = ANKLE_FROM_HEEL_FRACTION * foot.length;
    let ankle_height = ANKLE_HEIGHT_FRACTION * p.height;
    Segments {
        hat: SegmentSpec {
            mass: p.hat.mass,
            com: [0.0, p.hat.com_from_proximal],
            izz: p.hat.inertia_com,
        },
        thigh: down(&p.thigh),
        shank: down(&p.shank),
        foot: SegmentSpec {
            mass: foot.mass,
            com: [
                foot.com_from_proximal - ankle_from_heel,
                -0.5 * ankle_height,
            ],
            izz: foot.inertia_com,
        },
        hip_in_pelvis: [0.0, 0.0],
        knee_in_thigh: [0.0, -p.thigh.length],
        ankle_in_shank: [0.0, -p.shank.length],
    }
}
