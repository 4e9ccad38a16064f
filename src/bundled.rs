//! The files footfall ships with — the models, feet and phase files of `models/` and
//! `phases/`, and the bundled trial of `data/` with its meta file and OpenSim model —
//! compiled into the binary, so that the command line's defaults (`--model
//! models/opensim_subject01.json`, `--foot ellipse`, the phase files, the bundled trial)
//! work wherever `footfall` is started, also after `cargo install`.
//!
//! A path is read as given, relative to the current folder. Only when it does not exist
//! there and it is one of the bundled names ([`FILES`], e.g. `models/feet/ellipse.json`)
//! does [`resolve`] give the bundled copy instead. The copies are unpacked once per
//! content into a folder under the system's temporary folder (each file written under a
//! temporary name and renamed, so a reader never sees half a file), keeping their relative
//! layout: a model's `"file": "../data/…"` finds its OpenSim model there too.

use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// Why a bundled file cannot be had.
#[derive(Debug, Clone, thiserror::Error)]
pub enum BundledError {
    /// The bundled files cannot be written into the system's temporary folder.
    #[error("cannot unpack footfall's bundled files into {}: {source}", dir.display())]
    Unpack {
        /// The folder they were to be unpacked into.
        dir: PathBuf,
        /// The cause (shared: the outcome of unpacking is kept for the whole process).
        source: Arc<std::io::Error>,
    },
    /// The name asked for is not one of [`FILES`].
    #[error("{name} is not one of footfall's bundled files")]
    NotBundled {
        /// The name asked for.
        name: String,
    },
}

macro_rules! bundle {
    ($($p:literal),* $(,)?) => {
        &[$(($p, include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/", $p)) as &[u8])),*]
    };
}

/// The bundled files: (path relative to the repository root, contents).
pub const FILES: &[(&str, &[u8])] = bundle!(
    "models/gait9dof.json",
    "models/opencap_s4.json",
    "models/opensim_subject01.json",
    "models/opensim_subject01_seed_damping.json",
    "models/opensim_subject01_torque.json",
    "models/pig_c3dorg_D123.json",
    "models/feet/double_circle.json",
    "models/feet/ellipse.json",
    "models/feet/heel_circle_forefoot_ellipse.json",
    "models/feet/peer_ellipse.json",
    "models/feet/volumetric_ellipse.json",
    "phases/double_circle_walk.json",
    "phases/ellipse_walk.json",
    "phases/heel_circle_forefoot_ellipse_walk.json",
    "phases/sim_controls_cocontraction.csv",
    "phases/sim_double_circle_step.json",
    "phases/sim_ellipse_step.json",
    "phases/sim_volumetric_ellipse_step.json",
    "phases/volumetric_ellipse_walk.json",
    "data/opensim_subject01_meta.json",
    "data/opensim_subject01_model.json",
    "data/opensim_subject01_sagittal.csv",
);

/// The bundled foot files (`models/feet/…`).
pub fn feet() -> Vec<&'static str> {
    FILES
        .iter()
        .map(|(name, _)| *name)
        .filter(|name| name.starts_with("models/feet/"))
        .collect()
}

/// The bundled name of `path`: its components without `.`, with `/` between, when that
/// is one of [`FILES`].
fn bundled_name(path: &Path) -> Option<&'static str> {
    let mut parts = Vec::new();
    for c in path.components() {
        match c {
            Component::Normal(s) => parts.push(s.to_str()?),
            Component::CurDir => {}
            _ => return None,
        }
    }
    let name = parts.join("/");
    FILES.iter().map(|(n, _)| *n).find(|n| *n == name)
}

/// FNV-1a over the bundled names and contents: the unpacked folder's name, so that two
/// versions of footfall never share one.
fn fingerprint() -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for (name, bytes) in FILES {
        for b in name.bytes().chain([0u8]).chain(bytes.iter().copied()) {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// Unpack the bundled files into `dir` (files already there with the same contents are
/// kept; others are written under a temporary name and renamed into place).
fn unpack(dir: &Path) -> std::io::Result<()> {
    for (name, bytes) in FILES {
        let target = dir.join(name);
        if std::fs::read(&target).is_ok_and(|b| b == *bytes) {
            continue;
        }
        let parent = target.parent().unwrap_or(dir);
        std::fs::create_dir_all(parent)?;
        let file = target.file_name().unwrap_or_default().to_string_lossy();
        let tmp = parent.join(format!(".{file}.{}.tmp", std::process::id()));
        std::fs::write(&tmp, bytes)?;
        std::fs::rename(&tmp, &target)?;
    }
    Ok(())
}

/// The folder holding the unpacked bundled files, unpacked on first use.
///
/// Errors: the system's temporary folder is not writable (the message names the folder).
pub fn root() -> Result<PathBuf, BundledError> {
    static ROOT: OnceLock<Result<PathBuf, BundledError>> = OnceLock::new();
    ROOT.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!(
            "footfall-{}-bundled-{:016x}",
            env!("CARGO_PKG_VERSION"),
            fingerprint()
        ));
        unpack(&dir)
            .map(|_| dir.clone())
            .map_err(|e| BundledError::Unpack {
                dir: dir.clone(),
                source: Arc::new(e),
            })
    })
    .clone()
}

/// The file to read for `path`: `path` itself when it exists (or is not a bundled name),
/// else the bundled copy of that name. When the bundled files cannot be unpacked, `path`
/// is returned unchanged (reading it then fails with an error that names it).
pub fn resolve(path: &Path) -> PathBuf {
    if path.exists() {
        return path.to_path_buf();
    }
    match (bundled_name(path), root()) {
        (Some(name), Ok(root)) => root.join(name),
        _ => path.to_path_buf(),
    }
}

/// The bundled file `name` (one of [`FILES`]) unpacked, whatever the current folder holds.
pub fn path_of(name: &str) -> Result<PathBuf, BundledError> {
    if !FILES.iter().any(|(n, _)| *n == name) {
        return Err(BundledError::NotBundled {
            name: name.to_string(),
        });
    }
    root().map(|r| r.join(name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bundled_copies_match_the_repository_files() {
        let root = root().unwrap();
        for (name, bytes) in FILES {
            let repo = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join(name)).unwrap();
            assert_eq!(&repo[..], *bytes, "{name}");
            assert_eq!(std::fs::read(root.join(name)).unwrap(), repo, "{name}");
        }
    }

    /// Every file of `models/`, `models/feet/` and `phases/` ships with the binary, so that
    /// a shipped foot or phase file never works only inside the repository.
    #[test]
    fn every_shipped_model_foot_and_phase_file_is_bundled() {
        let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
        for dir in ["models", "models/feet", "phases"] {
            for entry in std::fs::read_dir(repo.join(dir)).unwrap() {
                let path = entry.unwrap().path();
                if path.is_file() {
                    let name = format!("{dir}/{}", path.file_name().unwrap().to_string_lossy());
                    assert!(
                        FILES.iter().any(|(n, _)| *n == name),
                        "{name} is not in bundled::FILES"
                    );
                }
            }
        }
    }

    #[test]
    fn only_missing_bundled_names_fall_back() {
        let root = root().unwrap();
        assert_eq!(
            resolve(Path::new("./models/feet/ellipse.json.nope")),
            PathBuf::from("./models/feet/ellipse.json.nope")
        );
        assert_eq!(
            resolve(Path::new("/nonexistent/models/feet/ellipse.json")),
            PathBuf::from("/nonexistent/models/feet/ellipse.json")
        );
        // the test runs in the repository: an existing path is read as it is
        let here = Path::new("models/feet/ellipse.json");
        if here.exists() {
            assert_eq!(resolve(here), here);
        }
        assert_eq!(
            bundled_name(Path::new("./phases/ellipse_walk.json")),
            Some("phases/ellipse_walk.json")
        );
        assert!(path_of("phases/ellipse_walk.json")
            .unwrap()
            .starts_with(&root));
        assert!(path_of("Cargo.toml").is_err());
    }
}
