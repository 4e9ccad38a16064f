//! The measured trial a workflow reads, from either form a lab exports: a sagittal CSV
//! (with its `_meta.json`), or an OpenSim pair: inverse kinematics (`.mot`/`.sto`,
//! coordinate names `pelvis_tx`, `hip_flexion_r`, …) and external loads (`.mot`/`.sto`,
//! `ground_force_vx/vy/px` per foot). The format follows the extension of `data`.
//!
//! An OpenSim pair carries no meta file, so what a CSV's meta file says is given here:
//! the belt speed of a treadmill trial ([`TrialFiles::belt_speed`]) or that the trial is
//! overground ([`TrialFiles::overground`]), and which force columns belong to which foot
//! ([`TrialFiles::plates`], detected when not given). The body mass comes from the model
//! file in every workflow, so a trial needs none.

use crate::data::{
    read_storage, ColumnMap, DataError, ForceColumns, GaitData, Storage, StorageMap, Q_NAMES,
};
use anyhow::bail;
use std::path::{Path, PathBuf};

mod c3d;
pub use c3d::{lab_axes, DEFAULT_LAB_AXES};

/// Where a trial comes from and what its files do not say (the command line's `--data`,
/// `--forces`, `--plate`, `--belt-speed` and `--overground`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TrialFiles {
    /// Sagittal CSV, or OpenSim inverse kinematics (`.mot`/`.sto`); `None`: the bundled
    /// trial.
    pub data: Option<PathBuf>,
    /// OpenSim external loads (`.mot`/`.sto`) or a C3D file's force plates (`.c3d`),
    /// required with an OpenSim `data` and refused with a CSV (which holds its forces).
    pub forces: Option<PathBuf>,
    /// With OpenSim loads: force-column prefix of each foot, `r=PREFIX` / `l=PREFIX` (e.g.
    /// `r=1_`, `l=2_`, `r=` for the unprefixed `ground_force_*`); a foot not named is
    /// detected (`""` or `r_` right, `l_` left). With a C3D file: the 1-based plate
    /// number(s) of each foot, `r=1`, `l=2` (required; a foot may take several plates).
    pub plates: Vec<String>,
    /// Lab axes of a C3D `forces` file, `FORWARD,UP` (e.g. `+x,+z`, the default when
    /// `None`); refused with other forces.
    pub lab_axes: Option<String>,
    /// Treadmill belt speed (m/s): the trial is moved to the overground frame with it. With
    /// a CSV it may stand in for a meta file that gives none.
    pub belt_speed: Option<f64>,
    /// Take a trial without a belt speed as overground, as it is (otherwise a treadmill
    /// trial without one is refused).
    pub overground: bool,
}

/// The two forms a trial is read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrialFormat {
    /// A sagittal CSV (`.csv`) with its meta file.
    Csv,
    /// An OpenSim storage (`.mot`, `.sto`).
    Storage,
    /// A C3D file (`.c3d`): force plates, accepted as `--forces` only.
    C3d,
}

/// The format of a trial file by its extension (case-insensitive).
pub fn trial_format(path: &Path, option: &str) -> anyhow::Result<TrialFormat> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("csv") => Ok(TrialFormat::Csv),
        Some("mot") | Some("sto") => Ok(TrialFormat::Storage),
        Some("c3d") if option == "--forces" => Ok(TrialFormat::C3d),
        other => bail!(
            "{}: {option}: cannot tell the format from the extension {}: give {}",
            path.display(),
            other.map_or("(none)".to_string(), |e| format!("'.{e}'")),
            if option == "--forces" {
                "an OpenSim storage (.mot or .sto) or a C3D file with force plates (.c3d)"
            } else {
                "a sagittal CSV (.csv) or an OpenSim storage (.mot or .sto)"
            }
        ),
    }
}

/// A trial read, and what was chosen on the way that the user should hear (which plate
/// was taken for which foot).
#[derive(Debug, Clone)]
pub struct LoadedTrial {
    /// The trial, in the overground frame when a belt speed was given.
    pub data: GaitData,
    /// Choices to report, one line each.
    pub notes: Vec<String>,
}

/// Read the trial `t` describes and check its units and conventions ([`check_trial`]); a
/// treadmill trial is moved overground with its belt
/// speed (the CSV's meta file or [`TrialFiles::belt_speed`]).
///
/// Errors: an unknown extension; `--forces` or `--plate` with a CSV; an OpenSim `data`
/// without `forces`; `--belt-speed` with `--overground`, or contradicting the CSV's meta
/// file; any [`DataError`] of the files (naming file, column and what would be valid).
pub fn load_trial(t: &TrialFiles) -> anyhow::Result<LoadedTrial> {
    if t.overground && t.belt_speed.is_some() {
        bail!("--belt-speed and --overground: give one (a belt speed moves a treadmill trial overground; --overground takes the trial as it is)");
    }
    if let Some(v) = t.belt_speed {
        if !v.is_finite() {
            bail!("--belt-speed {v}: expected a finite speed in m/s");
        }
    }
    let Some(path) = t.data.as_deref() else {
        if t.forces.is_some()
            || !t.plates.is_empty()
            || t.belt_speed.is_some()
            || t.lab_axes.is_some()
        {
            bail!("--forces, --plate, --lab-axes and --belt-speed describe an OpenSim trial given with --data IK.mot (without --data the bundled trial is read, whose meta file gives all of it)");
        }
        // the compiled-in copy, wherever footfall is started
        let root = crate::bundled::root()?;
        let data = GaitData::bundled(&root)?;
        check_trial(&data, t.overground)?;
        return Ok(LoadedTrial {
            data,
            notes: vec![],
        });
    };
    if let Some(a) = &t.lab_axes {
        let c3d = t.forces.as_deref().map(|f| trial_format(f, "--forces"));
        if !matches!(c3d, Some(Ok(TrialFormat::C3d))) {
            bail!("--lab-axes {a}: the lab axes are those of a C3D force-plate file given with --forces trial.c3d; OpenSim loads and a sagittal CSV are already in the model's frame");
        }
    }
    match trial_format(path, "--data")? {
        TrialFormat::Csv => load_csv(path, t),
        TrialFormat::Storage => load_opensim(path, t),
        TrialFormat::C3d => unreachable!("trial_format accepts .c3d for --forces only"),
    }
}

/// The trial's units and conventions ([`GaitData::check_conventions`]) and the forward
/// force's braking-then-propulsion sign
/// ([`check_forward_force_sign`](crate::problems::check::plausibility::check_forward_force_sign)),
/// which every command reads the trial through.
pub fn check_trial(data: &GaitData, overground: bool) -> Result<(), DataError> {
    data.check_conventions(overground)?;
    crate::problems::check::plausibility::check_forward_force_sign(data)
}

fn load_csv(path: &Path, t: &TrialFiles) -> anyhow::Result<LoadedTrial> {
    if let Some(f) = &t.forces {
        bail!(
            "--forces {}: a sagittal CSV ({}) holds its own forces (grf_x_r, grf_y_r, cop_x_r, …); --forces (OpenSim loads or a C3D file) goes with an OpenSim --data IK.mot",
            f.display(),
            path.display()
        );
    }
    if !t.plates.is_empty() {
        bail!(
            "--plate {}: a sagittal CSV ({}) names its feet in its columns (_r, _l); --plate goes with an OpenSim --forces GRF.mot",
            t.plates.join(" --plate "),
            path.display()
        );
    }
    let mut data = crate::data::read_sagittal_csv(path)?;
    let belt = match (data.belt_speed, t.belt_speed) {
        (Some(meta), Some(arg)) if (meta - arg).abs() > 1e-9 * meta.abs().max(1.0) => {
            return Err(DataError::invalid(
                path,
                "belt_speed_m_s",
                format!(
                    "the meta file gives {meta} m/s but --belt-speed gives {arg} m/s: give one"
                ),
            )
            .into())
        }
        (m, a) => m.or(a),
    };
    if let Some(v) = belt {
        if !data.overground {
            data = data.to_overground(v)?;
        }
    }
    check_trial(&data, t.overground)?;
    Ok(LoadedTrial {
        data,
        notes: vec![],
    })
}

/// Why a plate item `FOOT=VALUE` is refused ([`split_plate`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PlateItemError {
    /// The item has no `=`.
    #[error("expected FOOT=PREFIX (OpenSim loads, e.g. r=1_ or l=2_; r= for the unprefixed ground_force_*) or FOOT=N (a C3D plate number, e.g. r=1)")]
    NoValue {
        /// The item as given.
        item: String,
    },
    /// The foot is neither right nor left.
    #[error("foot '{foot}' is neither r (right) nor l (left)")]
    Foot {
        /// The foot as given (trimmed, lower case).
        foot: String,
    },
}

/// A `--plate FOOT=VALUE` item split into its foot (`r`/`right`, `l`/`left`, any case)
/// and its value (trimmed); the error says what the item should look like.
pub fn split_plate(p: &str) -> Result<(crate::model::Side, &str), PlateItemError> {
    let Some((side, value)) = p.split_once('=') else {
        return Err(PlateItemError::NoValue {
            item: p.to_string(),
        });
    };
    match side.trim().to_ascii_lowercase().as_str() {
        "r" | "right" => Ok((crate::model::Side::Right, value.trim())),
        "l" | "left" => Ok((crate::model::Side::Left, value.trim())),
        other => Err(PlateItemError::Foot {
            foot: other.to_string(),
        }),
    }
}

/// The foot prefixes of a GRF storage: `[right, left]` and the sentence that says how
/// they were chosen.
pub fn foot_prefixes(grf: &Storage, plates: &[String]) -> anyhow::Result<([String; 2], String)> {
    const SUFFIX: &str = "ground_force_vy";
    let found: Vec<String> = grf
        .columns
        .iter()
        .filter_map(|c| c.strip_suffix(SUFFIX).map(str::to_string))
        .collect();
    let listed = || {
        if found.is_empty() {
            "none".to_string()
        } else {
            found
                .iter()
                .map(|p| format!("'{p}' ({p}{SUFFIX})"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let mut given: [Option<String>; 2] = [None, None];
    for p in plates {
        let (side, prefix) = split_plate(p).map_err(|r| anyhow::anyhow!("--plate {p}: {r}"))?;
        let s = match side {
            crate::model::Side::Right => 0,
            crate::model::Side::Left => 1,
        };
        if given[s].is_some() {
            bail!(
                "--plate {p}: the {} foot is given twice",
                ["right", "left"][s]
            );
        }
        let prefix = prefix.to_string();
        if !found.contains(&prefix) {
            return Err(DataError::MissingColumn {
                path: grf.path.clone(),
                row: grf.label_line,
                column: format!("{prefix}{SUFFIX}"),
                reason: format!(
                    "--plate {p} names it; the file's vertical-force prefixes are {}",
                    listed()
                ),
            }
            .into());
        }
        given[s] = Some(prefix);
    }
    let detect = |candidates: &[&str]| {
        candidates
            .iter()
            .find(|c| found.iter().any(|f| f == *c))
            .map(|c| c.to_string())
    };
    let detected = [!given[0].is_some(), !given[1].is_some()];
    let right = match given[0].take().or_else(|| detect(&["", "r_", "R_"])) {
        Some(p) => p,
        None => bail!(
            "{}: cannot tell which force columns belong to the right foot (none named ground_force_vy or r_ground_force_vy); its vertical-force prefixes are {}: name them with --plate r=PREFIX --plate l=PREFIX",
            grf.path.display(),
            listed()
        ),
    };
    let left = match given[1].take().or_else(|| detect(&["l_", "L_"])) {
        Some(p) => p,
        None => bail!(
            "{}: cannot tell which force columns belong to the left foot (none named l_ground_force_vy); its vertical-force prefixes are {}: name them with --plate l=PREFIX",
            grf.path.display(),
            listed()
        ),
    };
    if right == left {
        bail!("--plate: both feet would read the columns {right}{SUFFIX}; give each foot its own plate");
    }
    let how = |d: bool| if d { "detected" } else { "--plate" };
    let text = format!(
        "forces of {}: right foot {right}ground_force_vx/vy/px ({}), left foot {left}ground_force_vx/vy/px ({}); --plate r=PREFIX --plate l=PREFIX chooses others",
        grf.path.display(),
        how(detected[0]),
        how(detected[1])
    );
    Ok(([right, left], text))
}

/// The map of an OpenSim pair: the gait10dof18musc coordinate names, the extras the
/// kinematics hold, and the feet's force columns.
fn opensim_map(ik: &Storage, prefixes: &[String; 2]) -> StorageMap {
    let mut map = StorageMap::gait10dof18musc();
    map.extras
        .retain(|(_, c): &(String, ColumnMap)| ik.column_index(&c.column).is_some());
    map.feet = [
        Some(ForceColumns::opensim(&prefixes[0])),
        Some(ForceColumns::opensim(&prefixes[1])),
    ];
    map
}

fn load_opensim(ik_path: &Path, t: &TrialFiles) -> anyhow::Result<LoadedTrial> {
    let Some(grf_path) = t.forces.as_deref() else {
        bail!(
            "{}: an OpenSim kinematics file holds no forces: give the trial's external loads with --forces GRF.mot (ground_force_vx/vy/px of each foot)",
            ik_path.display()
        );
    };
    match trial_format(grf_path, "--forces")? {
        TrialFormat::Storage => {}
        TrialFormat::C3d => return c3d::load(ik_path, grf_path, t),
        TrialFormat::Csv => bail!(
            "--forces {}: expected an OpenSim external-loads storage (.mot or .sto) or a C3D file (.c3d); a CSV trial is given whole with --data",
            grf_path.display()
        ),
    }
    let ik = read_storage(ik_path)?;
    let grf = read_storage(grf_path)?;
    check_not_swapped(&ik, &grf)?;
    require_angle_unit(&ik)?;
    let (prefixes, note) = foot_prefixes(&grf, &t.plates)?;
    let map = opensim_map(&ik, &prefixes);
    let mut data = GaitData::from_storage(&ik, Some(&grf), &map)?;
    if let Some(v) = t.belt_speed {
        data = data.to_overground(v)?;
    }
    // a declared unit the data contradict is the more telling diagnosis than the
    // conventions' (a knee that barely moves, read in the wrong unit)
    check_radians_said_degrees(&data, &ik, &map)?;
    check_trial(&data, t.overground).map_err(|e| opensim_error(e, &ik, &grf, &map))?;
    Ok(LoadedTrial {
        data,
        notes: vec![note],
    })
}

/// Kinematics given with --forces and forces with --data: named as such, before either
/// file is judged by the other's rules.
fn check_not_swapped(ik: &Storage, grf: &Storage) -> anyhow::Result<()> {
    let forces = |s: &Storage| s.columns.iter().any(|c| c.ends_with("ground_force_vy"));
    let kinematics = |s: &Storage| s.column("pelvis_tilt").is_some();
    if forces(ik) && !kinematics(ik) && kinematics(grf) {
        bail!(
            "--data {} holds ground forces and --forces {} holds kinematics (pelvis_tilt): the two are swapped; give the inverse kinematics with --data and the external loads with --forces",
            ik.path.display(),
            grf.path.display()
        );
    }
    Ok(())
}

/// An OpenSim kinematics file must say its angle unit.
fn require_angle_unit(ik: &Storage) -> Result<(), DataError> {
    if !ik.angle_unit_stated {
        return Err(DataError::Units {
            path: ik.path.clone(),
            row: None,
            column: "inDegrees".into(),
            text: String::new(),
            reason: "the header states neither 'inDegrees=yes|no' nor 'Angles are in degrees|radians': add the line 'inDegrees=yes' (or 'inDegrees=no' for radians) above 'endheader'".into(),
        });
    }
    Ok(())
}

pub use crate::data::conventions::{MIN_LEG_SPAN_RAD, MIN_SPAN_DURATION};

/// Radians in a file whose header says degrees: after the conversion every leg joint
/// barely moves.
fn check_radians_said_degrees(
    data: &GaitData,
    ik: &Storage,
    map: &StorageMap,
) -> Result<(), DataError> {
    let Some((widest, s, duration)) = data.still_legs().filter(|_| ik.in_degrees) else {
        return Ok(());
    };
    Err(DataError::invalid(
        &ik.path,
        map.q[widest].column.clone(),
        format!(
            "spans only {:.3}° in {duration:.2} s, the most of any leg joint, read as degrees as the header says: a walking knee spans about 60°, so the values look like radians; set 'inDegrees=no' above 'endheader' if they are",
            s.to_degrees()
        ),
    ))
}

/// A convention error of a trial read from an OpenSim pair, told in that pair's terms:
/// the file and column it came from and what to change there.
fn opensim_error(e: DataError, ik: &Storage, grf: &Storage, map: &StorageMap) -> DataError {
    let DataError::Invalid { field, reason, .. } = &e else {
        return e;
    };
    if let Some(i) = Q_NAMES.iter().position(|n| n == field) {
        let column = map.q[i].column.clone();
        if i == 0 {
            return DataError::invalid(
                &ik.path,
                column,
                format!(
                    "{}: a treadmill trial, and no belt speed is given; an OpenSim pair has no meta file, so give the belt speed with --belt-speed M/S, or pass --overground to take the trial as it is",
                    reason.split(": a treadmill trial").next().unwrap_or(reason)
                ),
            );
        }
        let head = reason
            .split(": this looks like degrees")
            .next()
            .unwrap_or(reason);
        let advice = if ik.in_degrees {
            "after converting from degrees, as the header says: the values are beyond a joint's range in degrees too; check the column"
        } else {
            "read as radians, as the header says: this looks like degrees; set 'inDegrees=yes' above 'endheader' if the values are in degrees"
        };
        return DataError::invalid(&ik.path, column, format!("{head}; {advice}"));
    }
    for (s, side) in ["r", "l"].iter().enumerate() {
        let Some(cols) = &map.feet[s] else { continue };
        for (name, column) in [
            ("grf_x", &cols.fx),
            ("grf_y", &cols.fy),
            ("cop_x", &cols.cop_x),
        ] {
            if field == &format!("{name}_{side}") {
                return DataError::invalid(&grf.path, column.clone(), reason.clone());
            }
        }
    }
    e
}

impl From<&crate::problems::diagnose::TrackingRunSetup> for TrialFiles {
    /// The trial a tracking run describes (its `setup.json`).
    fn from(run: &crate::problems::diagnose::TrackingRunSetup) -> Self {
        TrialFiles {
            data: run.data.clone(),
            forces: run.forces.clone(),
            plates: run.plates.clone(),
            lab_axes: run.lab_axes.clone(),
            belt_speed: run.belt_speed,
            overground: run.overground,
        }
    }
}

impl TrialFiles {
    /// The trial of `data` and `overground` alone (a CSV or the bundled trial).
    pub fn csv(data: Option<PathBuf>, overground: bool) -> Self {
        TrialFiles {
            data,
            overground,
            ..Default::default()
        }
    }
}
