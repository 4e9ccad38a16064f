//! Run folders that are either complete or absent.
//!
//! Files are written into a hidden sibling staging folder; [`RunFolder::commit`] renames it
//! into place as the last step, so a failed or interrupted run never leaves a folder that
//! looks complete.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Failure to write a run folder.
#[derive(Debug, thiserror::Error)]
pub enum RunFolderError {
    /// The target exists and overwriting was not requested.
    #[error("output folder {0} already exists (pass --overwrite to replace it)")]
    Exists(PathBuf),
    /// An I/O error on a path.
    #[error("{path}: {source}")]
    Io {
        /// Path.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
}

/// A run folder being written.
#[derive(Debug)]
pub struct RunFolder {
    target: PathBuf,
    staging: PathBuf,
    overwrite: bool,
    committed: bool,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> RunFolderError + '_ {
    move |source| RunFolderError::Io { path: path.to_path_buf(), source }
}

impl RunFolder {
    /// Start writing the folder `target`.
    pub fn create(target: &Path, overwrite: bool) -> Result<Self, RunFolderError> {
        if target.exists() && !overwrite {
            return Err(RunFolderError::Exists(target.to_path_buf()));
        }
        let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "run".into());
        let parent = target.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        std::fs::create_dir_all(parent).map_err(io(parent))?;
        let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
        if staging.exists() {
            std::fs::remove_dir_all(&staging).map_err(io(&staging))?;
        }
        std::fs::create_dir_all(&staging).map_err(io(&staging))?;
        Ok(Self { target: target.to_path_buf(), staging, overwrite, committed: false })
    }

    /// Write a file into the folder.
    pub fn write(&self, name: &str, bytes: &[u8]) -> Result<(), RunFolderError> {
        let p = self.staging.join(name);
        let mut f = std::fs::File::create(&p).map_err(io(&p))?;
        f.write_all(bytes).map_err(io(&p))
    }

    /// Where files are being written until [`commit`](Self::commit): nested run folders
    /// go here, so that they appear with their parent.
    pub fn staging_path(&self) -> &Path {
        &self.staging
    }

    /// Move the folder into place.
    pub fn commit(mut self) -> Result<PathBuf, RunFolderError> {
        if self.target.exists() {
            if !self.overwrite {
                return Err(RunFolderError::Exists(self.target.clone()));
            }
            std::fs::remove_dir_all(&self.target).map_err(io(&self.target))?;
        }
        std::fs::rename(&self.staging, &self.target).map_err(io(&self.target))?;
        self.committed = true;
        Ok(self.target.clone())
    }
}

impl Drop for RunFolder {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}
