//! The catalog of candidate effects `footfall diagnose` tries when the user names none:
//! the model's own physics.

use super::EffectSpec;

/// The candidate effects `footfall diagnose` tries, each at its null value (no effect)
/// with its identifiable parameters free: passive stiffness of hip, knee and ankle (both
/// legs, rest angle 0). The diagnosis adds the heel pad on a foot with a heel circle and
/// the contact law on a volumetric foot.
///
/// The instruments (the plates' clocks, gains and CoP offsets) and the body (its mass,
/// the trunk, the ground's slope) are not candidates here: the measurement stage
/// (`footfall check`) reads them from the trial's own Newton–Euler balance, without the
/// contact model whose misfit confounds them in a track. They can still be named with
/// `--candidate`.
///
/// The actuator properties (`mtg_damping`, `mtg_strength`,
/// `activation_time_constants`) are not default candidates either. They change what the
/// effort regularisation charges, so they lower J whether or not the data ask for them;
/// the diagnosis judges that against what they lower on the model's own trial (the model
/// null, `workflows::diagnose::model_null`). But one that explains most of J shrinks
/// the largest model's residual, in which every other candidate's statistic is measured,
/// while each other's decrease is measured alone (on the bundled trial a free damping
/// takes the largest model's J from 7.9 to 0.85, and the hip stiffness's 8 % of J reads as
/// a finding). Ask for them with `--candidate`, and add what is found one at a time.
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
