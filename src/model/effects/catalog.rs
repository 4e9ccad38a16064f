//! The catalog of candidate effects `footfall diagnose` tries when the user names none.

use super::EffectSpec;

/// The candidate effects `footfall diagnose` tries, each at its null value (no effect)
/// with its identifiable parameters free: ground slope, trunk mass and COM offset, passive
/// stiffness of hip, knee and ankle (both legs, rest angle 0); the instruments, each
/// force plate its own (clock offset and CoP offset of both plates together and of each
/// foot's plate), gain of each foot's plate and of both read jointly) and the body mass.
pub fn catalog() -> Vec<EffectSpec> {
    let mut out = vec![
        EffectSpec::GroundSlope {
            angle: 0.0,
            free: vec![],
        },
        EffectSpec::TrunkMass {
            added_mass: 0.0,
            com_offset: 0.0,
            free: vec![],
        },
    ];
    for joint in ["hip", "knee", "ankle"] {
        out.push(EffectSpec::PassiveJointStiffness {
            joint: joint.into(),
            side: "both".into(),
            stiffness: 0.0,
            rest_angle: 0.0,
            free: vec![],
        });
    }
    for side in ["both", "right", "left"] {
        out.push(EffectSpec::ForcePlateTimeOffset {
            side: side.into(),
            offset: 0.0,
            free: vec![],
        });
        out.push(EffectSpec::CopOffset {
            side: side.into(),
            offset: 0.0,
            free: vec![],
        });
    }
    // each foot's plate's gain, and both plates' gains read jointly: a one-plate gain
    // holds the other plate's at zero, so it takes up a load the two plates share in
    // double support; the joint reading says whether one plate or both alike (as a
    // body-mass error makes them) read high (`diagnose::plate_gains`)
    for side in ["right", "left", "each"] {
        out.push(EffectSpec::ForcePlateGain {
            side: side.into(),
            error: 0.0,
            free: vec![],
        });
    }
    out.push(EffectSpec::BodyMassError {
        relative: 0.0,
        free: vec![],
    });
    // The actuator properties (mtg_damping, mtg_strength, activation_time_constants) are
    // not default candidates: they change what the effort regularisation charges, so they
    // lower J without the data asking (on the synthetic trials MTG strength was "found"
    // with no hidden effect, MTG damping ranked above a hidden heel pad). Ask for them
    // with `--candidate`.
    for e in &mut out {
        e.free_all();
    }
    out
}
