//! Atomic file writes: one file, or a set of files (a render's `PREFIX.{exr,png,json}`) that is
//! replaced as a whole or not at all.
//!
//! [`write_set_with`] (and [`FileSet::write`], [`atomic_write`]) runs three phases:
//! 1. **temporaries**: every file's bytes go to [`atomic_path`]`(path)` (`PATH.tmp`, same
//!    directory), each fsynced. A failure here (a full disk) removes every temporary and leaves
//!    the old files untouched.
//! 2. **backups** (sets of two or more files only): every existing target is hard-linked (or, where
//!    the file system has no hard links, copied) to [`backup_path`]`(path)` (`PATH.old`).
//! 3. **renames**: each temporary is renamed over its target, in order. If rename `k` fails,
//!    targets `0..k` are put back from their backups (or removed if they did not exist before),
//!    and every temporary and backup is removed: the old set is intact. On success the backups
//!    are removed and the directory is fsynced (best effort).
//!
//! The remaining window, honestly: a process killed (or a machine losing power) *during* phase 3
//! leaves a mixed set, with the `.old` backups of the files not yet replaced beside it; and if a
//! rollback rename itself fails, the error says which files are mixed. Phase 3 is a handful of
//! same-directory renames, microseconds long, that need no free space. A failure to remove a
//! temporary during cleanup is ignored (there is nothing better to do), so a file system that
//! refuses unlinks can leave a `.tmp` behind.
//!
//! All file-system calls go through [`FileOps`], so tests inject a failure at any single step
//! ([`RealFs`] is the real thing). Nothing here panics; errors are [`AtomicIoError`]s naming the
//! file (`error`).
//!
//! Every temporary is created new (never over an existing file) and held under an exclusive lock
//! (`flock`) from its creation until the set is renamed; a process killed meanwhile leaves it
//! unlocked, and the next run's guard removes it if it is a stale temporary of ours
//! ([`remove_stale_temporary`]) instead of refusing to start.
//!
//! Also the guards around them (`guard`): [`read_regular`] (every whole-file read of an input: a
//! FIFO would block forever, `/dev/zero` would fill the memory) and [`OutputSet`], the one output
//! guard of every command that writes (no output names an input or another output of the run).

mod error;
mod guard;
pub use error::{AtomicIoError, Sibling, SiblingClash};
pub use guard::{
    check_input, check_output_prefix, read_regular, remove_stale_temporary, require_regular, resolve, same_file,
    OutputSet,
};

use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The file-system operations a set write needs (a seam for injecting failures in tests).
pub trait FileOps {
    /// Creates or truncates `path`, writes `bytes`, fsyncs.
    fn write(&mut self, path: &Path, bytes: &[u8]) -> io::Result<()>;
    /// Renames `from` over `to`.
    fn rename(&mut self, from: &Path, to: &Path) -> io::Result<()>;
    /// Makes `backup` a copy of the existing `path` (hard link where possible).
    fn backup(&mut self, path: &Path, backup: &Path) -> io::Result<()>;
    /// Removes the file `path`.
    fn remove(&mut self, path: &Path) -> io::Result<()>;
    /// `true` if `path` exists (a dangling symbolic link counts).
    fn exists(&mut self, path: &Path) -> bool;
    /// `true` if `path` is a directory.
    fn is_dir(&mut self, path: &Path) -> bool;
    /// [`FileOps::write`] of a temporary, returning what marks it as being written until it is
    /// dropped (after its rename): the real file system's open file, holding an exclusive lock
    /// that a stale temporary of a killed process no longer has ([`remove_stale_temporary`]).
    fn write_held(&mut self, path: &Path, bytes: &[u8]) -> io::Result<Option<std::fs::File>> {
        self.write(path, bytes).map(|()| None)
    }
}

/// The real file system.
pub struct RealFs;

impl FileOps for RealFs {
    fn write(&mut self, path: &Path, bytes: &[u8]) -> io::Result<()> {
        self.write_held(path, bytes).map(drop)
    }
    fn write_held(&mut self, path: &Path, bytes: &[u8]) -> io::Result<Option<std::fs::File>> {
        // never truncates a file that is not ours (`OutputSet::check` refused it up front)
        let mut f = std::fs::OpenOptions::new().write(true).create_new(true).open(path)?;
        // live until dropped: a second run's guard leaves a locked temporary alone
        f.lock()?;
        f.write_all(bytes)?;
        f.sync_all()?;
        Ok(Some(f))
    }
    fn rename(&mut self, from: &Path, to: &Path) -> io::Result<()> {
        std::fs::rename(from, to)
    }
    fn backup(&mut self, path: &Path, backup: &Path) -> io::Result<()> {
        match std::fs::hard_link(path, backup) {
            Err(e) if e.kind() != io::ErrorKind::AlreadyExists => {
                let mut to = std::fs::OpenOptions::new().write(true).create_new(true).open(backup)?;
                io::copy(&mut std::fs::File::open(path)?, &mut to).map(|_| ())
            }
            r => r,
        }
    }
    fn remove(&mut self, path: &Path) -> io::Result<()> {
        std::fs::remove_file(path)
    }
    fn exists(&mut self, path: &Path) -> bool {
        path.symlink_metadata().is_ok()
    }
    fn is_dir(&mut self, path: &Path) -> bool {
        path.is_dir()
    }
}

/// The temporary path a writer uses before renaming onto `path`: `path` with `.tmp` appended to
/// its file name, in the same directory (so the rename is atomic on one file system).
pub fn atomic_path(path: &Path) -> PathBuf {
    suffixed(path, ".tmp")
}

/// Where [`write_set_with`] keeps the previous version of `path` while it renames: `PATH.old`.
pub fn backup_path(path: &Path) -> PathBuf {
    suffixed(path, ".old")
}

fn suffixed(path: &Path, suffix: &str) -> PathBuf {
    let mut name = path.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    name.push(suffix);
    path.with_file_name(name)
}

/// Writes `bytes` to [`atomic_path`]`(path)`, fsyncs, then renames it to `path`; on failure the
/// temporary is removed and `path` is untouched. Creates no directories.
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<(), AtomicIoError> {
    write_set_with(&mut RealFs, &[(path.to_path_buf(), bytes.to_vec())])
}

/// A set of files to be replaced as a whole or not at all (see the module docs).
#[derive(Default)]
pub struct FileSet {
    files: Vec<(PathBuf, Vec<u8>)>,
}

impl FileSet {
    /// An empty set.
    pub fn new() -> FileSet {
        FileSet::default()
    }

    /// Adds a file; files are renamed into place in the order they were added.
    pub fn add(&mut self, path: PathBuf, bytes: Vec<u8>) {
        self.files.push((path, bytes));
    }

    /// The target paths, in order.
    pub fn paths(&self) -> Vec<&Path> {
        self.files.iter().map(|(p, _)| p.as_path()).collect()
    }

    /// Writes the set on the real file system.
    pub fn write(self) -> Result<(), AtomicIoError> {
        write_set_with(&mut RealFs, &self.files)
    }

    /// Writes the set through `fs` (tests inject failures here).
    pub fn write_with(self, fs: &mut dyn FileOps) -> Result<(), AtomicIoError> {
        write_set_with(fs, &self.files)
    }

    /// [`FileSet::write`] with the error as its message, for the callers whose own errors are
    /// still messages (`scene::export`, `chart`).
    pub fn commit(self) -> Result<(), String> {
        Ok(self.write()?)
    }

    /// [`FileSet::write_with`] with the error as its message (the failure-injection tests match
    /// on it).
    pub fn commit_with(self, fs: &mut dyn FileOps) -> Result<(), String> {
        Ok(self.write_with(fs)?)
    }
}

/// Writes `files` as a whole or not at all through `fs` (see the module docs).
pub fn write_set_with(fs: &mut dyn FileOps, files: &[(PathBuf, Vec<u8>)]) -> Result<(), AtomicIoError> {
    for (i, (p, _)) in files.iter().enumerate() {
        if fs.is_dir(p) {
            return Err(AtomicIoError::IsDirectory { path: p.clone() });
        }
        if files[..i].iter().any(|(q, _)| q == p) {
            return Err(AtomicIoError::NamedTwice { path: p.clone() });
        }
    }
    let tmps: Vec<PathBuf> = files.iter().map(|(p, _)| atomic_path(p)).collect();
    // each temporary stays locked until the set is renamed (or rolled back): released on return
    let mut held: Vec<std::fs::File> = Vec::with_capacity(files.len());
    for (i, (_, bytes)) in files.iter().enumerate() {
        if let Err(e) = fs.write_held(&tmps[i], bytes).map(|h| held.extend(h)) {
            // a temporary that was already there is not ours to remove
            let ours = if e.kind() == io::ErrorKind::AlreadyExists { i } else { i + 1 };
            remove_all(fs, &tmps[..ours]);
            return Err(AtomicIoError::Write { path: tmps[i].clone(), source: e });
        }
    }
    let backups = match make_backups(fs, files) {
        Ok(b) => b,
        Err(e) => {
            remove_all(fs, &tmps);
            return Err(e);
        }
    };
    for (i, (p, _)) in files.iter().enumerate() {
        if let Err(source) = fs.rename(&tmps[i], p) {
            let mixed = roll_back(fs, &files[..i], &backups[..i]);
            remove_all(fs, &tmps);
            remove_all(fs, &backups.iter().flatten().cloned().collect::<Vec<_>>());
            return Err(AtomicIoError::Rename { from: tmps[i].clone(), to: p.clone(), source, mixed });
        }
    }
    remove_all(fs, &backups.into_iter().flatten().collect::<Vec<_>>());
    sync_dirs(files);
    Ok(())
}

/// Phase 2: backups of the existing targets (none for a single file, whose rename is atomic).
fn make_backups(fs: &mut dyn FileOps, files: &[(PathBuf, Vec<u8>)]) -> Result<Vec<Option<PathBuf>>, AtomicIoError> {
    let mut backups: Vec<Option<PathBuf>> = Vec::with_capacity(files.len());
    for (p, _) in files {
        if files.len() < 2 || !fs.exists(p) {
            backups.push(None);
            continue;
        }
        let b = backup_path(p);
        if let Err(source) = fs.backup(p, &b) {
            if source.kind() != io::ErrorKind::AlreadyExists {
                backups.push(Some(b.clone()));
            }
            remove_all(fs, &backups.iter().flatten().cloned().collect::<Vec<_>>());
            return Err(AtomicIoError::Backup { path: p.clone(), backup: b, source });
        }
        backups.push(Some(b));
    }
    Ok(backups)
}

/// Puts back the targets already replaced; returns each one that could not be, with its error.
fn roll_back(
    fs: &mut dyn FileOps,
    done: &[(PathBuf, Vec<u8>)],
    backups: &[Option<PathBuf>],
) -> Vec<(PathBuf, io::Error)> {
    let mut failed = Vec::new();
    for ((p, _), b) in done.iter().zip(backups) {
        let r = match b {
            Some(b) => fs.rename(b, p),
            None => fs.remove(p),
        };
        if let Err(e) = r {
            failed.push((p.clone(), e));
        }
    }
    failed
}

fn remove_all(fs: &mut dyn FileOps, paths: &[PathBuf]) {
    for p in paths {
        let _ = fs.remove(p);
    }
}

/// Persists the renames (best effort: not every platform can fsync a directory).
fn sync_dirs(files: &[(PathBuf, Vec<u8>)]) {
    let mut dirs: Vec<&Path> =
        files.iter().map(|(p, _)| p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."))).collect();
    dirs.dedup();
    for d in dirs {
        if let Ok(f) = std::fs::File::open(d) {
            let _ = f.sync_all();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_conventions() {
        assert_eq!(atomic_path(Path::new("/a/b/c.exr")), PathBuf::from("/a/b/c.exr.tmp"));
        assert_eq!(backup_path(Path::new("c.png")), PathBuf::from("c.png.old"));
    }
}
