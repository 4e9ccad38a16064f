//! The catalog of candidate effects `footfall diagnose` tries when the user names none:
//! the model's own physics.

use super::EffectSpec;

/// The candidate effects `footfall diagnose` tries, each at its null value (no effect)
/// with its identifiable parameters free: passive stiffness of hip, knee and ankle (both
/// legs, rest angle 0) and the actuators' properties (the MTGs' damping and strength, the
/// activation time constants). The diagnosis adds the heel pad on a foot with a heel
/// circle and the contact law on a volumetric foot.
///
/// The instruments (the plates' clocks, gains and CoP offsets) and the body (its mass,
/// the trunk, the ground's slope) are not candidates here: the measurement stage
/// (`footfall check`) reads them from the trial's own Newton–Euler balance, without the
/// contact model whose misfit confounds them in a track. They can still be named with
/// `--candidate`.
///
/// An actuator property changes what the effort regularisation charges, so it lowers J
/// whether or not the data ask for it: the diagnosis judges it against what it lowers
/// on the model's own trial (the model null, `workflows::diagnose::model_null`), and
/// leaves it out of the largest model whose residuals are the noise (one that explains
/// most of J would shrink that noise, and another candidate sharing part of its
/// signature would read as a finding).
pub fn catalog() -> Vec<EffectSpec> {
    let mut out: Vec<EffectSpec> = ["hip", "knee", "ankle"]
        .into_iter()
        .map(|joint| EffectSpec::PassiveJointStiffness {
            joint: joint.into(),
            side: "both".into(),
            stiffness: 0.0,
            rest_angle: 0.0,
            free: vec![],
        })
        .collect();
    out.extend([
        EffectSpec::MtgDamping {
            change: 0.0,
            free: vec![],
        },
        EffectSpec::MtgStrength {
            change: 0.0,
            free: vec![],
        },
        EffectSpec::ActivationTimeConstants {
            change: 0.0,
            free: vec![],
        },
    ]);
    for e in &mut out {
        e.free_all();
    }
    out
}

/// The instrument and body effects the measurement stage owns, each at its null value
/// with its parameters free: the ground slope, the trunk's mass and COM offset, each
/// plate's clock and CoP offset (both plates together and each foot's), each plate's gain
/// (and both read jointly) and the body mass. Each is also an effect a track can add
/// (`track --effect`), which is how a correction the check reads is applied to a model.
pub fn measurement_effects() -> Vec<EffectSpec> {
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
    for e in &mut out {
        e.free_all();
    }
    out
}
