//! Safe writing of every output (issue 14, item 11): a command never loses a file.
//!
//! Rules, applied by every command that writes:
//! - **Inputs are sacred.** An output path that is an input of the same run (same file,
//!   compared by device and inode), or an output folder that holds an input, is refused,
//!   even with `--force`.
//! - **No symlinks.** An output path that is a symbolic link is refused, even with
//!   `--force`; temporary files are created with `O_EXCL | O_NOFOLLOW`.
//! - **Existing files need `--force`.** A single-file output (`--json`, `--params-out`,
//!   `simulate --out`) that exists is refused without `--force`: the tool cannot tell
//!   whether it made that file.
//! - **Folders made by the tool are the tool's.** An output folder (`campaign synth`,
//!   `--report`, `frf --out`) carries a [`MARKER_FILE`] naming the command and every
//!   file it wrote. Such a folder, holding nothing else, is replaced as a whole by the same
//!   command. Any other non-empty folder is refused without `--force`; with `--force`
//!   the new files are moved into it one by one and its other files are left alone.
//! - **All or nothing.** Files are written to a temporary sibling and renamed; folders are
//!   built in a temporary sibling folder and renamed. A failure leaves the old content or
//!   nothing, never a truncated file or a half-written campaign.

use std::ffi::OsString;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// The file that marks a folder as made by this tool; it lists what it holds.
pub const MARKER_FILE: &str = ".shaketable-output";
/// First line of [`MARKER_FILE`]; the command follows it.
const MARKER_HEADER: &str = "# made by shaketable: ";

/// Why an output was refused or could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{path}: is an input of this run; refusing to write over it (even with --force)")]
    IsInput { path: String },
    #[error(
        "{path}: holds an input of this run ({input}); refusing to write there (even with --force)"
    )]
    HoldsInput { path: String, input: String },
    #[error("{path}: is a symbolic link; refusing to write through it (even with --force)")]
    Symlink { path: String },
    #[error("{path}: exists and is not a {expected}; refusing to replace it")]
    WrongType {
        path: String,
        expected: &'static str,
    },
    #[error("{path}: exists; refusing to overwrite it (use --force to replace it)")]
    Exists { path: String },
    #[error(
        "{path}: folder is not empty and is not {what} output made by this tool; \
         refusing to write into it (use --force to add the files, replacing same-named ones)"
    )]
    ForeignDir { path: String, what: String },
    #[error("{path}: given twice as an output")]
    Duplicate { path: String },
    #[error("{path}: cannot write: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
}

impl OutputError {
    /// The path the error is about.
    pub fn path(&self) -> &str {
        match self {
            OutputError::IsInput { path }
            | OutputError::HoldsInput { path, .. }
            | OutputError::Symlink { path }
            | OutputError::WrongType { path, .. }
            | OutputError::Exists { path }
            | OutputError::ForeignDir { path, .. }
            | OutputError::Duplicate { path }
            | OutputError::Io { path, .. } => path,
        }
    }
}

fn show(p: &Path) -> String {
    p.display().to_string()
}

fn io(p: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: show(p),
        source,
    }
}

/// The files a run reads: outputs may never replace them.
#[derive(Debug, Default, Clone)]
pub struct Inputs {
    files: Vec<(PathBuf, FileId)>,
}

/// Identity of an existing file (device and inode on Unix, the canonical path elsewhere).
#[derive(Debug, Clone, PartialEq, Eq)]
struct FileId(#[cfg(unix)] (u64, u64), #[cfg(not(unix))] PathBuf);

fn file_id(p: &Path) -> Option<FileId> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let m = std::fs::metadata(p).ok()?;
        Some(FileId((m.dev(), m.ino())))
    }
    #[cfg(not(unix))]
    {
        p.canonicalize().ok().map(FileId)
    }
}

impl Inputs {
    pub fn new() -> Self {
        Self::default()
    }

    /// Add an input file (ignored when it does not exist: nothing to protect).
    pub fn add(&mut self, p: &Path) -> &mut Self {
        if let Some(id) = file_id(p) {
            let canon = p.canonicalize().unwrap_or_else(|_| p.to_path_buf());
            self.files.push((canon, id));
        }
        self
    }

    fn is_input(&self, p: &Path) -> bool {
        file_id(p).is_some_and(|id| self.files.iter().any(|(_, f)| *f == id))
    }

    /// An input inside the folder `dir` (which exists), if any.
    fn inside(&self, dir: &Path) -> Option<&Path> {
        let dir = dir.canonicalize().ok()?;
        self.files
            .iter()
            .map(|(p, _)| p.as_path())
            .find(|p| p.starts_with(&dir))
    }
}

/// Refuse the output file `path` when the rules forbid writing it (call before any long
/// work, and again at writing time).
pub fn check_file(path: &Path, force: bool, inputs: &Inputs) -> Result<(), OutputError> {
    let Ok(m) = std::fs::symlink_metadata(path) else {
        return Ok(());
    };
    if m.file_type().is_symlink() {
        return Err(OutputError::Symlink { path: show(path) });
    }
    if !m.is_file() {
        return Err(OutputError::WrongType {
            path: show(path),
            expected: "regular file",
        });
    }
    if inputs.is_input(path) {
        return Err(OutputError::IsInput { path: show(path) });
    }
    if !force {
        return Err(OutputError::Exists { path: show(path) });
    }
    Ok(())
}

/// Refuse two outputs of one run that name the same file.
pub fn check_distinct(paths: &[&Path]) -> Result<(), OutputError> {
    for (i, a) in paths.iter().enumerate() {
        let key = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        if paths[..i].iter().any(|b| key(a) == key(b)) {
            return Err(OutputError::Duplicate { path: show(a) });
        }
    }
    Ok(())
}

/// Check `path` by the rules, then write it atomically (creating its parent folders).
pub fn write_file(
    path: &Path,
    bytes: &[u8],
    force: bool,
    inputs: &Inputs,
) -> Result<(), OutputError> {
    check_file(path, force, inputs)?;
    if let Some(parent) = parent_of(path) {
        std::fs::create_dir_all(parent).map_err(io(parent))?;
    }
    atomic_write(path, bytes)
}

fn parent_of(path: &Path) -> Option<&Path> {
    path.parent().filter(|p| !p.as_os_str().is_empty())
}

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// A fresh name `.WHAT-PID-N.NAME` next to `path` (hidden; the extension kept for
/// writers that pick the format by it).
fn temp_sibling(path: &Path, what: &str) -> PathBuf {
    let name = path.file_name().map(OsString::from).unwrap_or_default();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut t = OsString::from(format!(".{what}-{}-{n}.", std::process::id()));
    t.push(&name);
    match parent_of(path) {
        Some(p) => p.join(t),
        None => PathBuf::from(t),
    }
}

/// Create a new file (never an existing one, never through a symlink).
fn create_new(path: &Path) -> std::io::Result<File> {
    let mut o = OpenOptions::new();
    o.write(true).create_new(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.custom_flags(libc::O_NOFOLLOW).mode(0o644);
    }
    o.open(path)
}

/// Write `bytes` to `path` through a temporary sibling and a rename: readers see the old
/// file or the new one, never a part. A symlink or non-file at `path` is refused.
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    if let Ok(m) = std::fs::symlink_metadata(path) {
        if m.file_type().is_symlink() {
            return Err(OutputError::Symlink { path: show(path) });
        }
        if !m.is_file() {
            return Err(OutputError::WrongType {
                path: show(path),
                expected: "regular file",
            });
        }
    }
    let tmp = loop {
        let t = temp_sibling(path, "tmp");
        match create_new(&t) {
            Ok(f) => break (t, f),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(io(path)(e)),
        }
    };
    let (tmp, mut f) = tmp;
    let result = f
        .write_all(bytes)
        .and_then(|_| f.sync_all())
        .and_then(|_| std::fs::rename(&tmp, path));
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(path)(e));
    }
    Ok(())
}

/// Let `write` fill a new, empty temporary sibling of `path` (created without following
/// symlinks), then rename it onto `path`: for writers that want a path (PNG encoders).
/// `wrap` turns a refusal or an OS error into the writer's error type.
pub fn write_via_temp<E>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
    wrap: impl Fn(OutputError) -> E,
) -> Result<(), E> {
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(wrap(OutputError::Symlink { path: show(path) }));
    }
    let tmp = loop {
        let t = temp_sibling(path, "tmp");
        match create_new(&t) {
            Ok(_) => break t,
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(wrap(io(path)(e))),
        }
    };
    let result =
        write(&tmp).and_then(|_| std::fs::rename(&tmp, path).map_err(|e| wrap(io(path)(e))));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// How an output folder will be put in place.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum DirKind {
    /// Missing or empty: the new folder takes its place.
    Fresh,
    /// Made by the same command and holding only its files: replaced as a whole.
    Replace,
    /// Someone else's folder, with `--force`: the new files are moved in one by one.
    Merge,
}

/// An output folder checked by the rules, before any long work.
#[derive(Debug, Clone)]
pub struct DirPlan {
    target: PathBuf,
    command: String,
    kind: DirKind,
    inputs: Inputs,
}

/// The names listed in `dir`'s marker when it was made by `command`.
fn marker_names(dir: &Path, command: &str) -> Option<Vec<String>> {
    let text = std::fs::read_to_string(dir.join(MARKER_FILE)).ok()?;
    let mut lines = text.lines();
    (lines.next()? == format!("{MARKER_HEADER}{command}"))
        .then(|| lines.map(str::to_string).collect())
}

/// Whether `dir` holds only regular files its marker lists.
fn is_ours(dir: &Path, command: &str) -> Result<bool, OutputError> {
    let Some(names) = marker_names(dir, command) else {
        return Ok(false);
    };
    for e in std::fs::read_dir(dir).map_err(io(dir))? {
        let e = e.map_err(io(dir))?;
        let name = e.file_name().to_string_lossy().into_owned();
        let file = e.file_type().map_err(io(dir))?.is_file();
        if !(file && (name == MARKER_FILE || names.contains(&name))) {
            return Ok(false);
        }
    }
    Ok(true)
}

/// Check the output folder `target` of `command` (e.g. "campaign synth").
pub fn plan_dir(
    target: &Path,
    command: &str,
    force: bool,
    inputs: &Inputs,
) -> Result<DirPlan, OutputError> {
    // `.`, `..` or `/` name no folder to put beside: use the real path
    let lexical: PathBuf = target.components().collect(); // drops `out/.`'s dot
    let resolved = match lexical.file_name() {
        Some(_) => lexical,
        None => target.canonicalize().map_err(io(target))?,
    };
    let target = resolved.as_path();
    let plan = |kind| DirPlan {
        target: target.to_path_buf(),
        command: command.to_string(),
        kind,
        inputs: inputs.clone(),
    };
    let Ok(m) = std::fs::symlink_metadata(target) else {
        return Ok(plan(DirKind::Fresh));
    };
    if m.file_type().is_symlink() {
        return Err(OutputError::Symlink { path: show(target) });
    }
    if !m.is_dir() {
        return Err(OutputError::WrongType {
            path: show(target),
            expected: "folder",
        });
    }
    if let Some(input) = inputs.inside(target) {
        return Err(OutputError::HoldsInput {
            path: show(target),
            input: show(input),
        });
    }
    let empty = std::fs::read_dir(target)
        .map_err(io(target))?
        .next()
        .is_none();
    if empty {
        Ok(plan(DirKind::Fresh))
    } else if is_ours(target, command)? {
        Ok(plan(DirKind::Replace))
    } else if force {
        Ok(plan(DirKind::Merge))
    } else {
        Err(OutputError::ForeignDir {
            path: show(target),
            what: command.to_string(),
        })
    }
}

impl DirPlan {
    /// The folder the output will end up in.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Make the temporary sibling folder to write into.
    pub fn stage(&self) -> Result<Staging, OutputError> {
        if let Some(parent) = parent_of(&self.target) {
            std::fs::create_dir_all(parent).map_err(io(parent))?;
        }
        loop {
            let t = temp_sibling(&self.target, "partial");
            match std::fs::create_dir(&t) {
                Ok(()) => {
                    return Ok(Staging {
                        dir: t,
                        plan: self.clone(),
                        done: false,
                    })
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(io(&self.target)(e)),
            }
        }
    }
}

/// A temporary folder being filled; [`Staging::commit`] puts it in place, dropping it
/// removes it.
#[derive(Debug)]
pub struct Staging {
    dir: PathBuf,
    plan: DirPlan,
    done: bool,
}

impl Staging {
    /// Where to write the files.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Put the folder in place (by the plan checked before; the checks are repeated).
    pub fn commit(mut self) -> Result<(), OutputError> {
        let p = self.plan.clone();
        let again = plan_dir(&p.target, &p.command, p.kind == DirKind::Merge, &p.inputs)?;
        let mut names = self.names()?;
        match again.kind {
            DirKind::Merge => self.merge(&names)?,
            DirKind::Fresh if p.target.exists() => {
                // an empty folder (maybe the working folder): keep it, move the files in
                self.write_marker(&names)?;
                names.push(MARKER_FILE.into());
                self.merge(&names)?;
            }
            kind => {
                self.write_marker(&names)?;
                self.swap(kind)?;
            }
        }
        self.done = true;
        Ok(())
    }

    fn names(&self) -> Result<Vec<OsString>, OutputError> {
        let mut names = Vec::new();
        for e in std::fs::read_dir(&self.dir).map_err(io(&self.dir))? {
            names.push(e.map_err(io(&self.dir))?.file_name());
        }
        names.sort();
        Ok(names)
    }

    fn write_marker(&self, names: &[OsString]) -> Result<(), OutputError> {
        let mut text = format!("{MARKER_HEADER}{}\n", self.plan.command);
        for n in names {
            text.push_str(&n.to_string_lossy());
            text.push('\n');
        }
        atomic_write(&self.dir.join(MARKER_FILE), text.as_bytes())
    }

    /// Fresh (no folder yet) or Replace: rename the staged folder onto the target.
    fn swap(&self, kind: DirKind) -> Result<(), OutputError> {
        let target = &self.plan.target;
        if kind == DirKind::Fresh {
            return std::fs::rename(&self.dir, target).map_err(io(target));
        }
        let old = temp_sibling(target, "old");
        std::fs::rename(target, &old).map_err(io(target))?;
        if let Err(e) = std::fs::rename(&self.dir, target) {
            let _ = std::fs::rename(&old, target);
            return Err(io(target)(e));
        }
        std::fs::remove_dir_all(&old).map_err(io(&old))
    }

    /// Merge (with --force into someone else's folder, or into an empty one): move each
    /// file in.
    fn merge(&self, names: &[OsString]) -> Result<(), OutputError> {
        let target = &self.plan.target;
        for n in names {
            check_file(&target.join(n), true, &self.plan.inputs)?;
        }
        for n in names {
            let dest = target.join(n);
            std::fs::rename(self.dir.join(n), &dest).map_err(io(&dest))?;
        }
        std::fs::remove_dir(&self.dir).map_err(io(&self.dir))
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.done {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

#[cfg(test)]
mod tests;
