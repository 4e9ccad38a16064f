//! Which storage columns become which [`GaitData`](crate::data::GaitData) channels: OpenSim's coordinate
//! names and external-loads columns, mapped onto the sagittal model's.

/// OpenSim's names (gait10dof18musc, gait2354) of the coordinates in [`Q_NAMES`] order:
/// what [`StorageMap::gait10dof18musc`] reads and what run folders' `kinematics.sto`
/// holds, so a result loads onto the subject's OpenSim model.
pub const OPENSIM_COORDINATES: [&str; 9] = [
    "pelvis_tx",
    "pelvis_ty",
    "pelvis_tilt",
    "hip_flexion_r",
    "knee_angle_r",
    "ankle_angle_r",
    "hip_flexion_l",
    "knee_angle_l",
    "ankle_angle_l",
];

/// A storage column that becomes one generalised coordinate or extra channel.
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnMap {
    /// Column name in the storage.
    pub column: String,
    /// Whether it is a rotational coordinate (converted from degrees when `inDegrees=yes`).
    pub rotational: bool,
}

impl ColumnMap {
    fn new(column: &str, rotational: bool) -> Self {
        Self {
            column: column.to_string(),
            rotational,
        }
    }
}

/// The force-plate columns of one foot in a GRF storage.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceColumns {
    /// Horizontal (forward) force on the foot (N).
    pub fx: String,
    /// Vertical force on the foot (N).
    pub fy: String,
    /// Centre-of-pressure x (m).
    pub cop_x: String,
    /// Centre-of-pressure y (m), the force-plate surface height; optional.
    pub cop_y: Option<String>,
}

impl ForceColumns {
    /// OpenSim's external-loads names with `prefix`: `PREFIXground_force_vx`, `…_vy`,
    /// `…_px`, `…_py`. Files name the feet differently: the bundled trial uses `""` (right)
    /// and `"l_"` (left); others use `"r_"`/`"l_"` or `""`/`"1_"`.
    pub fn opensim(prefix: &str) -> Self {
        Self {
            fx: format!("{prefix}ground_force_vx"),
            fy: format!("{prefix}ground_force_vy"),
            cop_x: format!("{prefix}ground_force_px"),
            cop_y: Some(format!("{prefix}ground_force_py")),
        }
    }
}

/// Which storage columns become which [`GaitData`] channels.
#[derive(Debug, Clone, PartialEq)]
pub struct StorageMap {
    /// The nine coordinates in [`Q_NAMES`] order.
    pub q: [ColumnMap; 9],
    /// Extra channels: `(name in GaitData::extra, column)`.
    pub extras: Vec<(String, ColumnMap)>,
    /// Force columns of `[right, left]`; `None`: that foot's forces are NaN.
    pub feet: [Option<ForceColumns>; 2],
    /// Hip-joint centre in the pelvis frame (m): adds `hip_center_x`, `hip_center_y`
    /// $= p + R(\text{pelvis\_tilt})\,o$ when given.
    pub hip_offset_in_pelvis: Option<[f64; 2]>,
    /// CoP is set to NaN where the resampled normal force is below this (N).
    pub cop_threshold: f64,
}

impl Default for StorageMap {
    fn default() -> Self {
        Self::gait10dof18musc()
    }
}

impl StorageMap {
    /// OpenSim's gait10dof18musc / gait2354 coordinate names (`pelvis_tx`, `pelvis_ty`,
    /// `pelvis_tilt`, `hip_flexion_r`, `knee_angle_r`, `ankle_angle_r`, the same `_l`),
    /// `lumbar_extension` as an extra, GRF columns `ground_force_*` (right) and
    /// `l_ground_force_*` (left) as in the bundled trial, the subject01 hip offset
    /// (−0.072437806, −0.067724738) m and the 20 N CoP threshold of `data/README.md`.
    pub fn gait10dof18musc() -> Self {
        let c = ColumnMap::new;
        Self {
            q: [
                c("pelvis_tx", false),
                c("pelvis_ty", false),
                c("pelvis_tilt", true),
                c("hip_flexion_r", true),
                c("knee_angle_r", true),
                c("ankle_angle_r", true),
                c("hip_flexion_l", true),
                c("knee_angle_l", true),
                c("ankle_angle_l", true),
            ],
            extras: vec![("lumbar_extension".into(), c("lumbar_extension", true))],
            feet: [
                Some(ForceColumns::opensim("")),
                Some(ForceColumns::opensim("l_")),
            ],
            hip_offset_in_pelvis: Some([-0.072437806, -0.067724738]),
            cop_threshold: crate::data::DEFAULT_COP_THRESHOLD,
        }
    }
}
