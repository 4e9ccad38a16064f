//! Run folders that are either complete or absent, and that never replace a user's files.
//!
//! Files are written into a hidden sibling staging folder `.NAME.partial-PID`;
//! [`RunFolder::commit`] renames it into place as the last step, so a failed or interrupted
//! run never leaves a folder that looks complete. A target that another process made
//! meanwhile is left alone: the run goes to the first free sibling `NAME-2`, `NAME-3`, …
//! ([`take_relocations`] tells which). Every folder footfall writes holds a marker file
//! ([`MARKER`]) listing the files footfall wrote there; `--overwrite` replaces only a
//! folder that holds it and nothing else (or an empty one), never the current folder or
//! one of its parents, and the old folder is removed only after the new one is in place. Staging folders of processes that died
//! (`kill -9`, a power cut) are removed by the next run with the same output folder.
//! Staging folders of this process are registered, so that a Ctrl-C handler can remove
//! them before exiting ([`remove_unfinished`]). Every write into a staging folder
//! holds the same lock as that removal, so a second Ctrl-C during the writing of a run
//! cannot leave a staging folder that a write made again after the removal.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Name of the marker file footfall writes into every run folder it makes: `--overwrite`
/// replaces only folders that hold it.
pub const MARKER: &str = ".footfall-run";

/// First line of the marker.
const MARKER_TEXT: &str = "This folder was written by footfall; `--overwrite` may replace it.\n";

/// The line of a committed folder's marker before the list of what footfall wrote there,
/// one path a line (folders end in `/`); the list depends on the files only, so that
/// identical runs write identical folders.
const MANIFEST_HEADING: &str =
    "Written by footfall (`--overwrite` refuses a folder that holds anything else):";

/// Most siblings (`NAME-2` … ) tried for a run whose target another process made meanwhile.
const MAX_SIBLINGS: usize = 1000;

/// Failure to write a run folder.
#[derive(Debug, thiserror::Error)]
pub enum RunFolderError {
    /// The target exists and overwriting was not requested.
    #[error("output folder {0} already exists (pass --overwrite to replace it)")]
    Exists(PathBuf),
    /// `--overwrite` was asked for a folder footfall did not make.
    #[error(
        "output folder {path} was not written by footfall (it holds {entry} and no {MARKER} marker): \
         --overwrite replaces only footfall's own run folders; choose another --out or remove it yourself"
    )]
    Foreign {
        /// The target.
        path: PathBuf,
        /// One of the entries it holds.
        entry: String,
    },
    /// `--overwrite` was asked for a run folder that holds files footfall did not write.
    #[error(
        "output folder {path} holds {count} file(s) footfall did not write ({named}): \
         --overwrite would delete them, so nothing was replaced; move them out of the folder or choose another --out"
    )]
    UserFiles {
        /// The target.
        path: PathBuf,
        /// How many entries are not footfall's.
        count: usize,
        /// The first few of them, quoted, with "and N more" where there are more.
        named: String,
    },
    /// No free sibling was found for a run whose target another process made meanwhile.
    #[error("output folder {0} and its siblings {0}-2 … -{MAX_SIBLINGS} all exist: the results could not be placed; choose another --out")]
    NoFreeSibling(PathBuf),
    /// The target is the current folder or one of its parents.
    #[error("output folder {0} is the current folder or one of its parents: it cannot be replaced; choose another --out")]
    HoldsCurrentFolder(PathBuf),
    /// The target exists and is not a folder.
    #[error("output {0} exists and is not a folder: it cannot be replaced; choose another --out")]
    NotAFolder(PathBuf),
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
    move |source| RunFolderError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Staging folders this process created and has not committed yet.
static UNFINISHED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn unfinished() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    UNFINISHED
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Keeps other threads from writing into or committing a staging folder while held.
pub struct NoWrites(#[allow(dead_code)] std::sync::MutexGuard<'static, Vec<PathBuf>>);

/// Remove every staging folder this process has created and not committed; while the
/// returned guard is held no other thread writes into or commits one: for a Ctrl-C
/// handler that exits at once, holding it (the folders' `Drop` would not run).
pub fn remove_unfinished() -> NoWrites {
    let mut list = unfinished();
    for p in list.drain(..) {
        let _ = std::fs::remove_dir_all(&p);
    }
    NoWrites(list)
}

/// Prefix of the files that let a killed run be resumed (its command and the solver's
/// checkpoints): they live in the staging folder and are removed when the run commits,
/// unless a stop was asked ([`crate::interrupt`]): an interrupted run keeps them.
pub const RESUME_PREFIX: &str = ".resume-";

/// Write `dir/name` whole or not at all: written under a temporary name, then renamed.
/// `name` may name a file in a subfolder (`inputs/model/x.json`); the subfolders are made.
///
/// The write holds the lock of [`remove_unfinished`]: it either completes before
/// an interrupt removes the staging folders, or never starts (the handler keeps the lock
/// until the process exits), so it cannot make a removed folder again.
pub fn write_atomic(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), RunFolderError> {
    let _no_removal_meanwhile = unfinished();
    let p = dir.join(name);
    let (sub, file) = match (p.parent(), p.file_name()) {
        (Some(sub), Some(file)) => (sub.to_path_buf(), file.to_string_lossy().into_owned()),
        _ => (dir.to_path_buf(), name.to_string()),
    };
    if sub != dir {
        std::fs::create_dir_all(&sub).map_err(io(&sub))?;
    }
    let tmp = sub.join(format!(".{file}.tmp"));
    let mut f = std::fs::File::create(&tmp).map_err(io(&tmp))?;
    f.write_all(bytes).map_err(io(&tmp))?;
    drop(f);
    std::fs::rename(&tmp, &p).map_err(io(&p))
}

/// The folder name and parent of a target path (`run` for a path without a name).
fn name_and_parent(target: &Path) -> (String, PathBuf) {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    let parent = target
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf();
    (name, parent)
}

/// Whether the process `pid` is alive; `None` where this cannot be told (no `/proc`).
fn process_alive(pid: u32) -> Option<bool> {
    if !Path::new("/proc/self").exists() {
        return None;
    }
    Some(Path::new(&format!("/proc/{pid}")).exists())
}

/// Staging (`.NAME.partial-PID`) and replaced (`.NAME.old-PID`) folders of `target` left
/// by processes that are no longer alive, with their PIDs: only folders holding the marker
/// (footfall's own).
pub fn stale_staging(target: &Path) -> Vec<(PathBuf, u32)> {
    let (name, parent) = name_and_parent(target);
    let Ok(dir) = std::fs::read_dir(&parent) else {
        return Vec::new();
    };
    let own = std::process::id();
    let mut out = Vec::new();
    for entry in dir.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let pid = [".partial-", ".old-"].iter().find_map(|kind| {
            file.strip_prefix(&format!(".{name}{kind}"))
                .and_then(|p| p.parse::<u32>().ok())
        });
        let Some(pid) = pid else { continue };
        let path = entry.path();
        if pid != own && process_alive(pid) == Some(false) && path.join(MARKER).is_file() {
            out.push((path, pid));
        }
    }
    out.sort();
    out
}

/// Whether `target` is the current folder or one of its parents.
fn holds_current_folder(target: &Path) -> bool {
    let (Ok(t), Ok(cwd)) = (
        target.canonicalize(),
        std::env::current_dir().and_then(|c| c.canonicalize()),
    ) else {
        return false;
    };
    cwd.starts_with(&t)
}

/// Every entry under `dir`, as paths relative to it with `/` between components (folders
/// end in `/`), sorted; the marker at the top is left out.
fn tree(dir: &Path) -> Result<Vec<String>, RunFolderError> {
    fn walk(dir: &Path, prefix: &str, out: &mut Vec<String>) -> Result<(), RunFolderError> {
        for entry in std::fs::read_dir(dir).map_err(io(dir))?.flatten() {
            let name = format!("{prefix}{}", entry.file_name().to_string_lossy());
            // a symbolic link is an entry of its own, never followed
            let is_dir = entry.file_type().map(|t| t.is_dir()).unwrap_or(false);
            if is_dir {
                out.push(format!("{name}/"));
                walk(&entry.path(), &format!("{name}/"), out)?;
            } else if name != MARKER {
                out.push(name);
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(dir, "", &mut out)?;
    out.sort();
    Ok(out)
}

/// The marker's text for a folder holding `entries` (see [`MANIFEST_HEADING`]).
fn marker_with_manifest(entries: &[String]) -> String {
    let mut text = format!("{MARKER_TEXT}{MANIFEST_HEADING}\n");
    for e in entries {
        text.push_str(e);
        text.push('\n');
    }
    text
}

/// What the marker of `target` lists as footfall's, or None for a marker without a list
/// (a folder being staged, or one written before footfall listed its files).
fn manifest(target: &Path) -> Option<std::collections::BTreeSet<String>> {
    let text = std::fs::read_to_string(target.join(MARKER)).ok()?;
    let (_, list) = text.split_once(&format!("{MANIFEST_HEADING}\n"))?;
    Some(list.lines().map(str::to_string).collect())
}

/// The entries of a marked `target` that its marker does not list: files a user put
/// into footfall's run folder.
pub fn user_files(target: &Path) -> Result<Vec<String>, RunFolderError> {
    let Some(listed) = manifest(target) else {
        return Ok(Vec::new());
    };
    let unlisted: Vec<String> = tree(target)?
        .into_iter()
        .filter(|e| !listed.contains(e))
        .collect();
    // a user's folder is named once, not with everything inside it
    Ok(unlisted
        .iter()
        .filter(|e| {
            !unlisted
                .iter()
                .any(|f| f.ends_with('/') && f != *e && e.starts_with(f.as_str()))
        })
        .cloned()
        .collect())
}

/// Check that an existing `target` may be replaced: a folder footfall made (it holds the
/// marker) holding nothing but what footfall wrote there, or an empty one, and not the
/// current folder or one of its parents.
pub fn check_replaceable(target: &Path) -> Result<(), RunFolderError> {
    let meta = std::fs::symlink_metadata(target).map_err(io(target))?;
    if !meta.is_dir() {
        return Err(RunFolderError::NotAFolder(target.to_path_buf()));
    }
    if holds_current_folder(target) {
        return Err(RunFolderError::HoldsCurrentFolder(target.to_path_buf()));
    }
    if target.join(MARKER).is_file() {
        let users = user_files(target)?;
        if users.is_empty() {
            return Ok(());
        }
        return Err(RunFolderError::UserFiles {
            path: target.to_path_buf(),
            count: users.len(),
            named: crate::limits::first_few(
                &users.iter().map(|u| format!("'{u}'")).collect::<Vec<_>>(),
            ),
        });
    }
    let mut entries: Vec<String> = std::fs::read_dir(target)
        .map_err(io(target))?
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    entries.sort();
    match entries.first() {
        None => Ok(()),
        Some(e) => Err(RunFolderError::Foreign {
            path: target.to_path_buf(),
            entry: format!("'{e}'"),
        }),
    }
}

/// Run folders committed to a sibling because their target appeared meanwhile: (target,
/// where the run went).
static RELOCATED: Mutex<Vec<(PathBuf, PathBuf)>> = Mutex::new(Vec::new());

/// The run folders of this process that went to a sibling of their target because
/// another process made the target while the run was working, as (target, sibling); the
/// list is emptied.
pub fn take_relocations() -> Vec<(PathBuf, PathBuf)> {
    std::mem::take(&mut *RELOCATED.lock().unwrap_or_else(|p| p.into_inner()))
}

/// The `n`-th sibling of `target` (`NAME-n`).
fn sibling(target: &Path, n: usize) -> PathBuf {
    let (name, parent) = name_and_parent(target);
    let sibling = format!("{name}-{n}");
    match target.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(_) => parent.join(sibling),
        None => PathBuf::from(sibling),
    }
}

/// How [`RunFolder::place`] went.
enum Placement {
    /// The run is in place; a folder it replaced was moved to this path, to be removed.
    Placed(Option<PathBuf>),
    /// The path is taken by a folder that is not to be replaced.
    Taken,
}

impl RunFolder {
    /// Start writing the folder `target`. An existing `target` is refused unless it may be
    /// replaced ([`check_replaceable`]) and `overwrite` is set; the refusal comes before
    /// any work. Stale staging folders of dead processes for the same target are
    /// removed.
    pub fn create(target: &Path, overwrite: bool) -> Result<Self, RunFolderError> {
        if std::fs::symlink_metadata(target).is_ok() {
            // one that cannot be replaced is refused as such, not with a hint at --overwrite
            check_replaceable(target)?;
            if !overwrite {
                return Err(RunFolderError::Exists(target.to_path_buf()));
            }
        }
        let (name, parent) = name_and_parent(target);
        let mut list = unfinished();
        // under the lock: a nested run folder's parent is a staging folder, which an
        // interrupt may be removing
        std::fs::create_dir_all(&parent).map_err(io(&parent))?;
        for (stale, _) in stale_staging(target) {
            std::fs::remove_dir_all(&stale).map_err(io(&stale))?;
        }
        let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
        if staging.exists() {
            std::fs::remove_dir_all(&staging).map_err(io(&staging))?;
        }
        std::fs::create_dir_all(&staging).map_err(io(&staging))?;
        list.push(staging.clone());
        drop(list);
        let folder = Self {
            target: target.to_path_buf(),
            staging,
            overwrite,
            committed: false,
        };
        folder.write(MARKER, MARKER_TEXT.as_bytes())?;
        Ok(folder)
    }

    /// Write a file into the folder: written under a temporary name, then renamed, so a
    /// file is either whole or absent (a checkpoint written every iteration stays readable
    /// whenever the process is killed).
    pub fn write(&self, name: &str, bytes: &[u8]) -> Result<(), RunFolderError> {
        write_atomic(&self.staging, name, bytes)
    }

    /// Where files are being written until [`commit`](Self::commit): nested run folders
    /// go here, so that they appear with their parent.
    pub fn staging_path(&self) -> &Path {
        &self.staging
    }

    /// The folder the run will have once committed.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Move the folder into place. A folder it replaces is moved aside first and removed
    /// only once the new one is in place (it is moved back if that fails). A target that
    /// appeared meanwhile and may not be replaced (`--overwrite` not given, or a folder
    /// that is not footfall's alone) is left as it is: the run goes to the first free
    /// sibling `NAME-2`, `NAME-3`, …, recorded for [`take_relocations`]. Returns where the
    /// run is.
    pub fn commit(mut self) -> Result<PathBuf, RunFolderError> {
        let mut list = unfinished();
        let Some(pos) = list.iter().position(|p| p == &self.staging) else {
            // removed by remove_unfinished (an interrupt): nothing to commit
            return Err(io(&self.staging)(std::io::Error::new(
                std::io::ErrorKind::Interrupted,
                "the run was interrupted",
            )));
        };
        // an interrupted run keeps its checkpoints, for `--resume`
        let keep_checkpoints = crate::interrupt::requested();
        for entry in std::fs::read_dir(&self.staging)
            .map_err(io(&self.staging))?
            .flatten()
        {
            if !keep_checkpoints
                && entry
                    .file_name()
                    .to_string_lossy()
                    .starts_with(RESUME_PREFIX)
            {
                std::fs::remove_file(entry.path()).map_err(io(&entry.path()))?;
            }
        }
        // under the lock already held: written directly
        let marker = marker_with_manifest(&tree(&self.staging)?);
        let tmp = self.staging.join(format!(".{MARKER}.tmp"));
        std::fs::write(&tmp, marker).map_err(io(&tmp))?;
        std::fs::rename(&tmp, self.staging.join(MARKER)).map_err(io(&self.staging))?;
        let mut dest = self.target.clone();
        let mut n = 1;
        let aside = loop {
            match self.place(&dest, n == 1 && self.overwrite)? {
                Placement::Placed(aside) => break aside,
                Placement::Taken if n < MAX_SIBLINGS => {
                    n += 1;
                    dest = sibling(&self.target, n);
                }
                Placement::Taken => return Err(RunFolderError::NoFreeSibling(self.target.clone())),
            }
        };
        list.remove(pos);
        self.committed = true;
        drop(list);
        if dest != self.target {
            RELOCATED
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .push((self.target.clone(), dest.clone()));
        }
        if let Some(old) = aside {
            std::fs::remove_dir_all(&old).map_err(io(&old))?;
        }
        Ok(dest)
    }

    /// Rename the staging folder to `dest`, replacing a folder there if `replace` is set
    /// and it may be replaced ([`check_replaceable`]).
    fn place(&self, dest: &Path, replace: bool) -> Result<Placement, RunFolderError> {
        let mut aside = None;
        if std::fs::symlink_metadata(dest).is_ok() {
            if !replace || check_replaceable(dest).is_err() {
                return Ok(Placement::Taken);
            }
            let (name, parent) = name_and_parent(dest);
            let old = parent.join(format!(".{name}.old-{}", std::process::id()));
            if old.exists() {
                std::fs::remove_dir_all(&old).map_err(io(&old))?;
            }
            // an empty folder gets the marker, so a crash before the removal leaves a
            // folder the next run recognises as its own
            if !dest.join(MARKER).exists() {
                std::fs::write(dest.join(MARKER), MARKER_TEXT).map_err(io(dest))?;
            }
            std::fs::rename(dest, &old).map_err(io(dest))?;
            aside = Some(old);
        }
        match std::fs::rename(&self.staging, dest) {
            Ok(()) => Ok(Placement::Placed(aside)),
            Err(e) => {
                if let Some(old) = &aside {
                    let _ = std::fs::rename(old, dest);
                }
                // a folder that another process made between the check and the rename
                match e.kind() {
                    std::io::ErrorKind::DirectoryNotEmpty | std::io::ErrorKind::AlreadyExists
                        if aside.is_none() =>
                    {
                        Ok(Placement::Taken)
                    }
                    _ => Err(io(dest)(e)),
                }
            }
        }
    }
}

impl Drop for RunFolder {
    fn drop(&mut self) {
        if !self.committed {
            let mut list = unfinished();
            if let Some(pos) = list.iter().position(|p| p == &self.staging) {
                list.remove(pos);
                let _ = std::fs::remove_dir_all(&self.staging);
            }
        }
    }
}

/// Failure to read a JSON file of a run folder (`setup.json`, `summary.json`): every
/// message names the file, and the field (as a JSON path such as `errors[2].stats.mean`)
/// where one is at fault.
#[derive(Debug, thiserror::Error)]
pub enum RunFileError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// The file is not JSON.
    #[error("{path}: not valid JSON: {source}")]
    Json {
        /// The file.
        path: PathBuf,
        /// Cause (with line and column).
        source: serde_json::Error,
    },
    /// A field is missing or has the wrong type or value.
    #[error("{path}: field `{field}`: {message}")]
    Field {
        /// The file.
        path: PathBuf,
        /// JSON path of the field, e.g. `errors[2].stats.mean`.
        field: String,
        /// What is wrong.
        message: String,
    },
}

impl RunFileError {
    /// A field of `path` at fault.
    pub fn field(path: &Path, field: impl Into<String>, message: impl Into<String>) -> Self {
        RunFileError::Field {
            path: path.to_path_buf(),
            field: field.into(),
            message: message.into(),
        }
    }
}

/// A JSON value's kind in words, for error messages.
pub fn json_kind(v: &serde_json::Value) -> String {
    use serde_json::Value;
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => format!("the boolean {b}"),
        Value::Number(n) => format!("the number {n}"),
        Value::String(s) => format!("the string {s:?}"),
        Value::Array(_) => "an array".into(),
        Value::Object(_) => "an object".into(),
    }
}

/// serde's "expected …" in words (`f64` → a number).
fn expected_in_words(what: &str) -> String {
    let w = what.trim();
    if ["f64", "f32", "i64", "u64", "usize", "u32", "i32"].contains(&w) {
        "a number".into()
    } else if w == "a sequence" || w.starts_with("an array") || w.starts_with("a tuple") {
        "an array".into()
    } else if w.starts_with("struct ") || w == "a map" {
        "an object".into()
    } else if w == "a boolean" {
        "true or false".into()
    } else {
        w.into()
    }
}

/// Decode `value` (read from `path`) as `T`: a field of the wrong type or missing is
/// named by its JSON path, with what was expected and what was found.
pub fn decode_json<T: serde::de::DeserializeOwned>(
    value: &serde_json::Value,
    path: &Path,
) -> Result<T, RunFileError> {
    match serde_path_to_error::deserialize::<_, T>(value) {
        Ok(v) => Ok(v),
        Err(e) => {
            let at = e.path().to_string();
            let at = if at == "." { String::new() } else { at };
            let inner = e.into_inner().to_string();
            let join = |a: &str, b: &str| {
                if a.is_empty() {
                    b.to_string()
                } else {
                    format!("{a}.{b}")
                }
            };
            let found = || {
                // the value at the path, for "found …"
                let mut v = Some(value);
                for seg in at.split('.').filter(|s| !s.is_empty()) {
                    let (key, idx) = match seg.find('[') {
                        Some(i) => (&seg[..i], Some(&seg[i..])),
                        None => (seg, None),
                    };
                    v = v.and_then(|x| x.get(key));
                    for ix in idx.into_iter().flat_map(|s| s.split(['[', ']'])) {
                        if let Ok(k) = ix.parse::<usize>() {
                            v = v.and_then(|x| x.get(k));
                        }
                    }
                }
                v.map(json_kind)
            };
            let (field, message) = if let Some(rest) = inner.strip_prefix("missing field `") {
                let name = rest.split('`').next().unwrap_or_default();
                (join(&at, name), "missing".to_string())
            } else if let Some(i) = inner.find(", expected ") {
                let expected = expected_in_words(&inner[i + ", expected ".len()..]);
                let found = found().unwrap_or_else(|| inner[..i].to_string());
                (at, format!("expected {expected}, found {found}"))
            } else {
                (at, inner)
            };
            let field = if field.is_empty() {
                "(top level)".to_string()
            } else {
                field
            };
            Err(RunFileError::field(path, field, message))
        }
    }
}

/// Read the JSON file `path` of a run folder as `T` (see [`decode_json`]).
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, RunFileError> {
    let text = std::fs::read_to_string(path).map_err(|source| RunFileError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|source| RunFileError::Json {
            path: path.to_path_buf(),
            source,
        })?;
    decode_json(&value, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An interrupt's removal holds the lock until the process exits: a write that comes
    /// meanwhile waits instead of making the removed staging folder again.
    #[test]
    fn a_write_waits_while_the_staging_folders_are_being_removed() {
        let tmp = tempfile::tempdir().unwrap();
        let staging = tmp.path().join(".run.partial-1");
        let removal = unfinished();
        let writer = {
            let staging = staging.clone();
            std::thread::spawn(move || write_atomic(&staging, "inputs/model.json", b"{}"))
        };
        std::thread::sleep(std::time::Duration::from_millis(100));
        assert!(
            !staging.exists(),
            "the write made the folder under the removal"
        );
        drop(removal);
        writer.join().unwrap().unwrap();
        assert_eq!(
            std::fs::read(staging.join("inputs/model.json")).unwrap(),
            b"{}"
        );
    }

    /// A finished run whose target another process made between the start and the
    /// commit goes to the first free sibling, leaving the other folder as it is.
    #[test]
    fn a_target_made_meanwhile_sends_the_run_to_the_first_free_sibling() {
        let tmp = tempfile::tempdir().unwrap();
        let t = tmp.path();
        for (overwrite, name, taken, want) in [
            (false, "run", &["run", "run-2"][..], "run-3"),
            (true, "other", &["other"][..], "other-2"),
        ] {
            let target = t.join(name);
            let f = RunFolder::create(&target, overwrite).unwrap();
            f.write("summary.json", b"{}").unwrap();
            // made meanwhile, by someone else
            for d in taken {
                std::fs::create_dir(t.join(d)).unwrap();
                std::fs::write(t.join(d).join("theirs.txt"), "theirs").unwrap();
            }
            let went = f.commit().unwrap();
            assert_eq!(went, t.join(want));
            assert_eq!(std::fs::read(went.join("summary.json")).unwrap(), b"{}");
            for d in taken {
                assert_eq!(
                    std::fs::read_to_string(t.join(d).join("theirs.txt")).unwrap(),
                    "theirs"
                );
            }
            assert_eq!(take_relocations(), vec![(target, t.join(want))]);
        }
        let mut left = std::fs::read_dir(t)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect::<Vec<_>>();
        left.sort();
        assert_eq!(
            left,
            ["other", "other-2", "run", "run-2", "run-3"],
            "a staging folder left behind"
        );
    }

    /// The marker lists what footfall wrote; `--overwrite` refuses a folder holding
    /// anything else, naming a few entries and counting the rest, and deletes nothing.
    #[test]
    fn overwrite_refuses_a_run_folder_holding_a_user_file() {
        let tmp = tempfile::tempdir().unwrap();
        let target = tmp.path().join("run");
        let f = RunFolder::create(&target, false).unwrap();
        f.write("inputs/model.json", b"{}").unwrap();
        f.write("summary.json", b"{}").unwrap();
        f.commit().unwrap();
        // footfall's own files alone: replaceable
        check_replaceable(&target).unwrap();
        std::fs::write(target.join("inputs/notes.txt"), "mine").unwrap();
        std::fs::create_dir(target.join("mine")).unwrap();
        for k in 0..7 {
            std::fs::write(target.join(format!("mine/{k}.txt")), "mine").unwrap();
            std::fs::write(target.join(format!("z{k}.txt")), "mine").unwrap();
        }
        let e = RunFolder::create(&target, true).unwrap_err().to_string();
        assert!(
            e.contains("holds 9 file(s) footfall did not write ('inputs/notes.txt', 'mine/', 'z0.txt', 'z1.txt', 'z2.txt', and 4 more)"),
            "{e}"
        );
        assert!(e.len() < 400, "{e}");
        assert!(target.join("inputs/notes.txt").is_file() && target.join("summary.json").is_file());
        // once the user's files are gone, the run folder is replaced again
        std::fs::remove_file(target.join("inputs/notes.txt")).unwrap();
        std::fs::remove_dir_all(target.join("mine")).unwrap();
        for k in 0..7 {
            std::fs::remove_file(target.join(format!("z{k}.txt"))).unwrap();
        }
        RunFolder::create(&target, true).unwrap().commit().unwrap();
        assert!(!target.join("summary.json").exists());
    }

    #[test]
    fn a_dead_process_staging_folder_is_stale_and_a_live_one_is_not() {
        let tmp = tempfile::tempdir().unwrap();
        let target = tmp.path().join("run");
        // PID 0 is never a user process; our own parent is alive
        let dead = tmp.path().join(format!(".run.partial-{}", u32::MAX - 1));
        let alive = tmp.path().join(format!(
            ".run.partial-{}",
            std::os::unix::process::parent_id()
        ));
        let foreign = tmp.path().join(format!(".run.partial-{}", u32::MAX - 2));
        for d in [&dead, &alive, &foreign] {
            std::fs::create_dir(d).unwrap();
        }
        std::fs::write(dead.join(MARKER), MARKER_TEXT).unwrap();
        std::fs::write(alive.join(MARKER), MARKER_TEXT).unwrap();
        // no marker: not footfall's, never removed
        std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
        let stale: Vec<PathBuf> = stale_staging(&target).into_iter().map(|(p, _)| p).collect();
        assert_eq!(stale, vec![dead.clone()]);
        let f = RunFolder::create(&target, false).unwrap();
        assert!(!dead.exists() && alive.exists() && foreign.join("notes.txt").exists());
        f.commit().unwrap();
        assert!(target.join(MARKER).is_file());
    }
}
