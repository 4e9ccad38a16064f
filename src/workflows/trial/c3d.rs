//! An OpenSim kinematics file with its forces from the force plates of a C3D file
//! (`--forces trial.c3d --plate r=1 --plate l=2 [--lab-axes +x,+z]`).
//!
//! Time base: a C3D's analog sample k is at (first_frame − 1)/point rate + k/analog rate
//! (s), so a file whose first frame is 1 starts at t = 0; the kinematics' `time` column is
//! taken as is on the same clock (as OpenSim's own IK and GRF files of one trial are), and
//! the plates must cover the kinematic span.

use super::{check_radians_said_degrees, opensim_error, LoadedTrial, TrialFiles};
use crate::data::c3d::{feet_from_plates, read_c3d_plates, AxisMap, C3dForces};
use crate::data::{read_storage, ColumnMap, DataError, GaitData, Storage, StorageMap};
use crate::model::Side;
use anyhow::bail;
use std::path::Path;

/// The default `--lab-axes`: walking along the lab's +x, +z up.
pub const DEFAULT_LAB_AXES: &str = "+x,+z";

/// The axis map of `--lab-axes FORWARD,UP` (default [`DEFAULT_LAB_AXES`]).
pub fn lab_axes(text: Option<&str>) -> anyhow::Result<AxisMap> {
    let text = text.unwrap_or(DEFAULT_LAB_AXES);
    let Some((f, u)) = text.split_once(',') else {
        bail!("--lab-axes {text}: expected FORWARD,UP, two signed lab axes of the C3D file separated by a comma, e.g. +x,+z (the default) or -y,+z; each one of +x, -x, +y, -y, +z, -z");
    };
    AxisMap::new(f, u).map_err(|e| {
        let reason = match &e {
            DataError::Invalid { reason, .. } => reason.clone(),
            other => other.to_string(),
        };
        anyhow::anyhow!("--lab-axes {text}: {reason} (FORWARD,UP, e.g. +x,+z)")
    })
}

/// The file's plates as the user should see them: number and surface centre in the lab.
fn plate_list(forces: &C3dForces) -> String {
    forces
        .plates
        .iter()
        .map(|p| {
            format!(
                "plate {} centred at ({:.3}, {:.3}, {:.3}) m",
                p.plate, p.centre[0], p.centre[1], p.centre[2]
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// `--plate FOOT=N` items as (foot, 1-based plate number), checked against the file.
fn plate_assignment(forces: &C3dForces, plates: &[String]) -> anyhow::Result<Vec<(Side, usize)>> {
    let path = forces.path.display();
    if plates.is_empty() {
        bail!(
            "--forces {path}: say which plate each foot stepped on with --plate FOOT=N (1-based plate number; repeat for a foot on several plates), e.g. --plate r=1 --plate l=2; the file has {}",
            plate_list(forces)
        );
    }
    let mut out = Vec::new();
    for p in plates {
        let (side, n) = super::split_plate(p).map_err(|r| anyhow::anyhow!("--plate {p}: {r}"))?;
        let Ok(n) = n.parse::<usize>() else {
            bail!(
                "--plate {p}: '{n}' is not a plate number; {path} has {}",
                plate_list(forces)
            );
        };
        if !forces.plates.iter().any(|q| q.plate == n) {
            bail!(
                "--plate {p}: {path} has no plate {n}; it has {}",
                plate_list(forces)
            );
        }
        if out.iter().any(|&(_, m)| m == n) {
            bail!("--plate {p}: plate {n} is given twice; a plate belongs to one foot");
        }
        out.push((side, n));
    }
    for (side, name) in [(Side::Right, "right (r)"), (Side::Left, "left (l)")] {
        if !out.iter().any(|&(s, _)| s == side) {
            bail!(
                "--plate: the {name} foot has no plate in {path}; give it one with --plate {}=N; the file has {}",
                &name[name.len() - 2..name.len() - 1],
                plate_list(forces)
            );
        }
    }
    Ok(out)
}

/// Read kinematics `ik_path` (OpenSim) with the forces of the C3D file `c3d_path`.
pub(super) fn load(ik_path: &Path, c3d_path: &Path, t: &TrialFiles) -> anyhow::Result<LoadedTrial> {
    let map_axes = lab_axes(t.lab_axes.as_deref())?;
    let forces = read_c3d_plates(c3d_path, crate::data::DEFAULT_COP_THRESHOLD)?;
    let assign = plate_assignment(&forces, &t.plates)?;
    let ik = read_storage(ik_path)?;
    super::require_angle_unit(&ik)?;
    let map = kinematics_map(&ik);
    let mut data = GaitData::from_storage(&ik, None, &map)?;
    data.feet = feet_from_plates(&forces, &assign, map_axes, &data.time).map_err(|e| match e {
        DataError::Invalid { field, reason, .. } if field == "time" => DataError::invalid(
            c3d_path,
            "time",
            format!(
                "{reason}; the C3D's samples start at (first frame − 1)/point rate, and the kinematics ({}) are read on that clock",
                ik_path.display()
            ),
        ),
        e => e,
    })?;
    // the forces at their own instants too, over the kinematic span (one sample beyond
    // either end, for interpolation), as `from_storage` keeps an OpenSim force record
    if let Some(plate) = forces.plates.first() {
        let (t0, t1) = (data.time[0], data.time[data.time.len() - 1]);
        let k0 = plate.time.partition_point(|&t| t < t0).saturating_sub(1);
        let k1 = (plate.time.partition_point(|&t| t <= t1) + 1).min(plate.time.len());
        let time = plate.time[k0..k1].to_vec();
        let feet = feet_from_plates(&forces, &assign, map_axes, &time)?;
        data.forces = Some(crate::data::ForceSamples { time, feet });
    }
    // The surface height: the mean up-coordinate of the loaded CoP samples of the feet's
    // plates (as `from_storage` pools the loaded ground_force_py of both feet).
    let heights: Vec<f64> = assign
        .iter()
        .filter_map(|&(_, n)| forces.plates.iter().find(|p| p.plate == n))
        .flat_map(|p| {
            p.cop
                .iter()
                .map(|c| f64::from(map_axes.up.sign) * c[map_axes.up.index])
        })
        .filter(|h| h.is_finite())
        .collect();
    data.force_plate_height =
        (!heights.is_empty()).then(|| heights.iter().sum::<f64>() / heights.len() as f64);
    if let Some(v) = t.belt_speed {
        data = data.to_overground(v)?;
    }
    // Convention errors of the forces name the C3D and the plates.
    super::check_trial(&data, t.overground).map_err(|e| match e {
        DataError::Invalid { field, reason, .. } if field.starts_with("grf_") => {
            DataError::invalid(
                c3d_path,
                format!("{field} (plates {})", t.plates.join(", ")),
                format!(
                    "{reason}; check --plate and --lab-axes {}",
                    t.lab_axes.as_deref().unwrap_or(DEFAULT_LAB_AXES)
                ),
            )
        }
        e => opensim_error(e, &ik, &ik, &map),
    })?;
    check_radians_said_degrees(&data, &ik, &map)?;
    let axes_note = match t.lab_axes.as_deref() {
        Some(a) => format!("lab axes {a} (--lab-axes)"),
        None => format!("lab axes {DEFAULT_LAB_AXES} (forward, up: the default; --lab-axes FORWARD,UP chooses others)"),
    };
    let feet = |side: Side| {
        assign
            .iter()
            .filter(|&&(s, _)| s == side)
            .map(|&(_, n)| n.to_string())
            .collect::<Vec<_>>()
            .join("+")
    };
    let note = format!(
        "forces of {}: right foot plate {}, left foot plate {}, {axes_note}; forces resampled onto the kinematic instants, the C3D's first sample at t = {} s",
        c3d_path.display(),
        feet(Side::Right),
        feet(Side::Left),
        forces.plates[0].time[0]
    );
    Ok(LoadedTrial {
        data,
        notes: vec![note],
    })
}

/// The gait10dof18musc coordinates and the extras the kinematics hold, without forces.
fn kinematics_map(ik: &Storage) -> StorageMap {
    let mut map = StorageMap::gait10dof18musc();
    map.extras
        .retain(|(_, c): &(String, ColumnMap)| ik.column_index(&c.column).is_some());
    map.feet = [None, None];
    map
}
