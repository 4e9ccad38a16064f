//! How a tracking run was set up (`setup.json`): enough to rebuild its problem.

use super::IdentifiedParameter;
use crate::model::effects::EffectSpec;
use crate::problems::track::TargetSides;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// How a tracking run was set up: enough to rebuild its problem (`setup.json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrackingRunSetup {
    /// Model file.
    pub model: PathBuf,
    /// Foot argument (`ellipse`, `double-circle` or a foot file).
    pub foot: String,
    /// Phase file.
    pub phases: PathBuf,
    /// Data file (`None`: the bundled trial).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data: Option<PathBuf>,
    /// Whether a trial without a belt speed is taken as overground as it is
    /// (`--overground`; otherwise a treadmill trial without one is refused).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub overground: bool,
    /// OpenSim external loads going with an OpenSim `data` (`--forces`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub forces: Option<PathBuf>,
    /// Force-column prefix of each foot in `forces`, `r=PREFIX` / `l=PREFIX` (`--plate`;
    /// empty: detected).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub plates: Vec<String>,
    /// Lab axes `FORWARD,UP` of a C3D `forces` file (`--lab-axes`; `None`: the default
    /// `+x,+z`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lab_axes: Option<String>,
    /// Treadmill belt speed (m/s) moving the trial overground (`--belt-speed`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub belt_speed: Option<f64>,
    /// Kinematics low-pass cutoff (Hz).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kinematics_cutoff: Option<f64>,
    /// CVODES tolerance of the states.
    pub integrator_tol: f64,
    /// CVODES tolerance of the forward sensitivities when it differs from the states'
    /// (`None`: the same; a heel pad tightens only the states).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensitivity_tol: Option<f64>,
    /// Whether the model has residual actuators (`--residual-actuators`).
    #[serde(default)]
    pub residual_actuators: bool,
    /// Whether the pelvis position is tracked too (`--track-pelvis-position`).
    #[serde(default)]
    pub track_pelvis_position: bool,
    /// Weight of the excitation² and activation² regularisation (`None`: Millard & Mombaur's
    /// 1e-3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub regularisation: Option<f64>,
    /// Whether the node targets are one-sided at contact changes (`--one-sided-targets`).
    #[serde(default)]
    pub one_sided_targets: bool,
    /// Whether every sample is compared with the model at its own instant instead of node
    /// targets (`--sample-targets`).
    #[serde(default)]
    pub sample_targets: bool,
    /// Track the first half cycle inside this span (s, `--window T0,T1`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window: Option<(f64, f64)>,
    /// Track the n-th half cycle of the trial (1-based, `--stride N`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stride: Option<usize>,
    /// Track the trial with its legs swapped (`--mirror`, [`GaitData::swap_sides`]):
    /// the half cycles are then those from a right heel strike to the next left one,
    /// and the model's right leg follows the subject's left.
    ///
    /// [`GaitData::swap_sides`]: crate::data::GaitData::swap_sides
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub mirror: bool,
    /// Channels weighted by their noise (`--noise-weights`; `None`: Millard & Mombaur's weights).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise_weights: Option<crate::problems::tracking::ChannelNoise>,
    /// Weight of the velocity targets relative to the angles (`None`: Millard & Mombaur's 0.1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity_weight: Option<f64>,
    /// Where the solve from the data starts (`--guess`).
    #[serde(
        default,
        skip_serializing_if = "crate::problems::track::start::Guess::is_data"
    )]
    pub guess: crate::problems::track::start::Guess,
    /// Check points holding the contact constraints between the nodes, as (continuous
    /// phase, interval, τ): the run's problem has them, so a rebuild must too.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub check_points: Vec<(usize, usize, f64)>,
    /// Effects added on top of the model file (`--effect`).
    pub effects: Vec<EffectSpec>,
    /// Every effect parameter of the model at the solution.
    pub parameters: Vec<IdentifiedParameter>,
}

impl TrackingRunSetup {
    /// Read a `setup.json` (paths as recorded; see `workflows::track::read_run_setup`
    /// for a run folder's own inputs). Errors name the file and the field.
    pub fn read(path: &std::path::Path) -> Result<Self, crate::runfolder::RunFileError> {
        crate::runfolder::read_json(path)
    }

    /// How the run's node targets are read from the samples; one-sided targets win
    /// should both flags be set (the CLI refuses both).
    pub fn target_sides(&self) -> TargetSides {
        if self.one_sided_targets {
            TargetSides::OneSided {
                cutoff_hz: self.kinematics_cutoff,
            }
        } else if self.sample_targets {
            TargetSides::Samples
        } else {
            TargetSides::Interpolated
        }
    }
}
