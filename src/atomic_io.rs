//! Atomic file writes: one file, or a set of files (a render's `PREFIX.{exr,png,json}`) that is
//! replaced as a whole or not at all.
//!
//! [`write_set`] (and [`FileSet::commit`]) runs three phases:
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
//! ([`RealFs`] is the real thing). Nothing here panics; errors are `String`s naming the file.
//!
//! Also the guards around them: [`read_regular`] (every whole-file read of an input: a FIFO
//! would block forever, `/dev/zero` would fill the memory) and [`OutputSet`], the one output
//! guard of every command that writes (no output names an input or another output of the run).

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
}

/// The real file system.
pub struct RealFs;

impl FileOps for RealFs {
    fn write(&mut self, path: &Path, bytes: &[u8]) -> io::Result<()> {
        // never truncates a file that is not ours (`OutputSet::check` refused it up front)
        let mut f = std::fs::OpenOptions::new().write(true).create_new(true).open(path)?;
        f.write_all(bytes)?;
        f.sync_all()
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

/// Where [`write_set`] keeps the previous version of `path` while it renames: `PATH.old`.
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
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<(), String> {
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
    pub fn commit(self) -> Result<(), String> {
        write_set_with(&mut RealFs, &self.files)
    }

    /// Writes the set through `fs` (tests inject failures here).
    pub fn commit_with(self, fs: &mut dyn FileOps) -> Result<(), String> {
        write_set_with(fs, &self.files)
    }
}

/// Writes `files` as a whole or not at all through `fs` (see the module docs).
pub fn write_set_with(fs: &mut dyn FileOps, files: &[(PathBuf, Vec<u8>)]) -> Result<(), String> {
    for (i, (p, _)) in files.iter().enumerate() {
        if fs.is_dir(p) {
            return Err(format!("cannot write {}: it is a directory", p.display()));
        }
        if files[..i].iter().any(|(q, _)| q == p) {
            return Err(format!("cannot write {}: named twice in one set", p.display()));
        }
    }
    let tmps: Vec<PathBuf> = files.iter().map(|(p, _)| atomic_path(p)).collect();
    for (i, (_, bytes)) in files.iter().enumerate() {
        if let Err(e) = fs.write(&tmps[i], bytes) {
            // a temporary that was already there is not ours to remove
            let ours = if e.kind() == io::ErrorKind::AlreadyExists { i } else { i + 1 };
            remove_all(fs, &tmps[..ours]);
            return Err(format!("cannot write {}: {e}", tmps[i].display()));
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
        if let Err(e) = fs.rename(&tmps[i], p) {
            let restore = roll_back(fs, &files[..i], &backups[..i]);
            remove_all(fs, &tmps);
            remove_all(fs, &backups.iter().flatten().cloned().collect::<Vec<_>>());
            let mut msg = format!("cannot rename {} to {}: {e}", tmps[i].display(), p.display());
            if restore.is_empty() {
                msg.push_str(" (the previous files are unchanged)");
            } else {
                msg.push_str(&format!("; the set is now mixed: {}", restore.join("; ")));
            }
            return Err(msg);
        }
    }
    remove_all(fs, &backups.into_iter().flatten().collect::<Vec<_>>());
    sync_dirs(files);
    Ok(())
}

/// Phase 2: backups of the existing targets (none for a single file, whose rename is atomic).
fn make_backups(fs: &mut dyn FileOps, files: &[(PathBuf, Vec<u8>)]) -> Result<Vec<Option<PathBuf>>, String> {
    let mut backups: Vec<Option<PathBuf>> = Vec::with_capacity(files.len());
    for (p, _) in files {
        if files.len() < 2 || !fs.exists(p) {
            backups.push(None);
            continue;
        }
        let b = backup_path(p);
        if let Err(e) = fs.backup(p, &b) {
            if e.kind() != io::ErrorKind::AlreadyExists {
                backups.push(Some(b.clone()));
            }
            remove_all(fs, &backups.iter().flatten().cloned().collect::<Vec<_>>());
            return Err(format!("cannot keep the previous {} as {}: {e}", p.display(), b.display()));
        }
        backups.push(Some(b));
    }
    Ok(backups)
}

/// Puts back the targets already replaced; returns a description of each one that could not be.
fn roll_back(fs: &mut dyn FileOps, done: &[(PathBuf, Vec<u8>)], backups: &[Option<PathBuf>]) -> Vec<String> {
    let mut failed = Vec::new();
    for ((p, _), b) in done.iter().zip(backups) {
        let r = match b {
            Some(b) => fs.rename(b, p),
            None => fs.remove(p),
        };
        if let Err(e) = r {
            failed.push(format!("{} is the new version ({e})", p.display()));
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

/// Refuses an output prefix whose last component is empty, `.` or `..` (`--out dir/` would
/// otherwise write the hidden files `dir/.exr`, `dir/.png`, `dir/.json`).
pub fn check_output_prefix(prefix: &Path) -> Result<(), String> {
    let raw = prefix.as_os_str().to_string_lossy();
    let last = raw.rsplit(std::path::is_separator).next().unwrap_or("");
    if last.is_empty() || last == "." || last == ".." {
        return Err(format!(
            "output prefix `{raw}` has no file name (the files would be `{raw}.exr`, …); \
             give one, e.g. `--out {}`",
            Path::new(raw.as_ref()).join("render").display()
        ));
    }
    Ok(())
}

/// Refuses a path that is not a regular file (a FIFO, socket, device or directory) before it is
/// opened: reading a FIFO blocks until a writer comes, a device such as `/dev/zero` never ends.
pub fn require_regular(path: &Path) -> io::Result<()> {
    let m = std::fs::metadata(path)?;
    if m.is_file() {
        return Ok(());
    }
    let kind = if m.is_dir() { "a directory" } else { "not a regular file (a FIFO, socket or device?)" };
    Err(io::Error::new(io::ErrorKind::InvalidInput, format!("it is {kind}")))
}

/// `std::fs::read` of a regular file only ([`require_regular`]).
pub fn read_regular(path: &Path) -> io::Result<Vec<u8>> {
    require_regular(path)?;
    std::fs::read(path)
}

/// A file's identity for [`OutputSet`]: the device and inode of an existing file (so hard links,
/// symbolic links and `..` spellings agree), else its [`resolve`]d path.
#[derive(Clone, Debug, PartialEq, Eq)]
enum FileId {
    Inode(u64, u64),
    Path(PathBuf),
}

fn file_id(p: &Path) -> FileId {
    #[cfg(unix)]
    if let Ok(m) = std::fs::metadata(p) {
        use std::os::unix::fs::MetadataExt;
        return FileId::Inode(m.dev(), m.ino());
    }
    FileId::Path(resolve(p))
}

/// `p` made absolute with its symbolic links and `.`/`..` resolved: the longest existing
/// ancestor is canonicalized, the components below it (which do not exist, so cannot be links)
/// are applied lexically.
pub fn resolve(p: &Path) -> PathBuf {
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut base = abs.clone();
    let mut rest = Vec::new();
    let canon = loop {
        if let Ok(c) = base.canonicalize() {
            break c;
        }
        match (base.file_name().map(|n| n.to_os_string()), base.parent()) {
            (Some(name), Some(parent)) => {
                rest.push(name);
                base = parent.to_path_buf();
            }
            _ => break base, // a root that does not canonicalize: keep it as written
        }
    };
    let mut out = canon;
    for c in rest.iter().rev().map(Path::new).flat_map(|c| c.components()) {
        match c {
            std::path::Component::ParentDir => {
                out.pop();
            }
            std::path::Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// Refuses, before any work, an output that cannot be written: a file output that is a
/// directory, a directory output that is a file, or one whose nearest existing ancestor is not a
/// directory.
fn writable(flag: &str, out: &Path, want_dir: bool) -> Result<(), String> {
    if out.is_dir() != want_dir && out.exists() {
        let (is, want) = if want_dir { ("a file", "directory") } else { ("a directory", "file") };
        return Err(format!("{flag} `{}` is {is}; name a {want}", out.display()));
    }
    let abs = std::path::absolute(out).unwrap_or_else(|_| out.to_path_buf());
    match abs.ancestors().skip(1).find(|a| a.symlink_metadata().is_ok()) {
        Some(a) if !a.is_dir() => {
            Err(format!("{flag} `{}` cannot be created: `{}` is not a directory", out.display(), a.display()))
        }
        _ => Ok(()),
    }
}

/// True when `a` and `b` name the same file (see [`OutputSet`] for what "same" means).
pub fn same_file(a: &Path, b: &Path) -> bool {
    file_id(a) == file_id(b) || resolve(a) == resolve(b)
}

/// The output guard of one command run: every file it reads and every file (or directory) it
/// writes, checked together before anything is written. [`OutputSet::check`] refuses
/// * an output that is one of the inputs (the scene, its meshes, `--reference`, `--resume`, the
///   images given to `diff`): writing it would destroy that input;
/// * an output named twice (two outputs of the same run would overwrite each other);
/// * an input inside an output directory (compare's `DIR/charts/`, …);
/// * an output written through a temporary (`PATH.tmp`) or backup (`PATH.old`) that is an input,
///   another output or an existing file (the write would replace it and then delete it);
/// * an output that cannot be created: a directory, or under a path that is not a directory
///   (except [`OutputSet::best_effort`] ones, whose failure is only a warning).
///
/// Two paths are the same file when they are the same existing file (device and inode: hard
/// links, symbolic links and `..` spellings included) or resolve to the same absolute path
/// ([`resolve`]: links in the existing part followed, `..` applied). The one exception is
/// [`OutputSet::output_replacing`]: an output that supersedes its own input (a resumed render's
/// checkpoint, written over the checkpoint it resumed, holds everything that one held).
#[derive(Clone, Debug, Default)]
pub struct OutputSet {
    inputs: Vec<(String, PathBuf)>,
    outputs: Vec<(String, PathBuf, Option<PathBuf>)>,
    dirs: Vec<(String, PathBuf)>,
    /// Outputs whose failed write is only a warning (checkpoints): not checked for writability.
    best_effort: Vec<PathBuf>,
}

impl OutputSet {
    /// An empty guard.
    pub fn new() -> OutputSet {
        OutputSet::default()
    }

    /// An input; `what` names it in messages (`the scene`, `the mesh`, `--reference`).
    pub fn input(&mut self, what: &str, path: &Path) -> &mut Self {
        self.inputs.push((what.to_string(), path.to_path_buf()));
        self
    }

    /// The scene file and the mesh files it read (`Scene::mesh_files`): the inputs of every
    /// subcommand that loads a scene.
    pub fn scene_inputs(&mut self, scene: &Path, meshes: &[PathBuf]) -> &mut Self {
        self.input("the scene", scene);
        meshes.iter().for_each(|m| {
            self.input("the scene's mesh", m);
        });
        self
    }

    /// An output file; `flag` names where it comes from (`--out`, `--checkpoint-path`).
    pub fn output(&mut self, flag: &str, path: &Path) -> &mut Self {
        self.outputs.push((flag.to_string(), path.to_path_buf(), None));
        self
    }

    /// An output file that may replace the one input `replaces` (and nothing else).
    pub fn output_replacing(&mut self, flag: &str, path: &Path, replaces: &Path) -> &mut Self {
        self.outputs.push((flag.to_string(), path.to_path_buf(), Some(replaces.to_path_buf())));
        self
    }

    /// A directory whose files the command writes: no input may lie inside it.
    pub fn output_dir(&mut self, flag: &str, dir: &Path) -> &mut Self {
        self.dirs.push((flag.to_string(), dir.to_path_buf()));
        self
    }

    /// Marks the output `path` as best effort: the command warns and goes on if it cannot be
    /// written (a checkpoint), so an unwritable path is not refused up front.
    pub fn best_effort(&mut self, path: &Path) -> &mut Self {
        self.best_effort.push(path.to_path_buf());
        self
    }

    /// The outputs, in the order they were added.
    pub fn outputs(&self) -> impl Iterator<Item = &Path> {
        self.outputs.iter().map(|(_, p, _)| p.as_path())
    }

    /// Every output is written through its temporary `PATH.tmp` and, in a set, a backup
    /// `PATH.old` ([`atomic_path`], [`backup_path`]): neither may be an input or another output,
    /// nor an existing file, which the write would replace and then delete.
    fn check_siblings(&self, inputs: &[(FileId, PathBuf)]) -> Result<(), String> {
        let outs: Vec<PathBuf> = self.outputs.iter().map(|(_, p, _)| resolve(p)).collect();
        for (flag, out, _) in &self.outputs {
            for (role, sib) in [("temporary", atomic_path(out)), ("backup", backup_path(out))] {
                let (id, r) = (file_id(&sib), resolve(&sib));
                let why = |which: String| {
                    format!(
                        "{flag} `{}` is written through its {role} `{}`, which {which}",
                        out.display(),
                        sib.display()
                    )
                };
                if let Some(((w, p), _)) = self.inputs.iter().zip(inputs).find(|(_, (iid, ir))| *iid == id || *ir == r)
                {
                    return Err(why(format!(
                        "is {w} `{}`: writing would destroy it (name another output)",
                        p.display()
                    )));
                }
                if outs.contains(&r) {
                    return Err(why("is also an output of this run (name another output)".into()));
                }
                if sib.symlink_metadata().is_ok() {
                    return Err(why(
                        "exists (left by an interrupted write?): it would be replaced and then deleted; move it \
                         away, or name another output"
                            .into(),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The rules of [`OutputSet`]; the error names the output, where it comes from, and the file
    /// it would destroy.
    pub fn check(&self) -> Result<(), String> {
        let inputs: Vec<(FileId, PathBuf)> = self.inputs.iter().map(|(_, p)| (file_id(p), resolve(p))).collect();
        let mut seen: Vec<(FileId, PathBuf)> = Vec::new();
        for (flag, out, replaces) in &self.outputs {
            let (id, r) = (file_id(out), resolve(out));
            let allowed = replaces.as_ref().map(|p| (file_id(p), resolve(p)));
            for ((what, input), (iid, ir)) in self.inputs.iter().zip(&inputs) {
                let same = *iid == id || *ir == r;
                if same && allowed.as_ref().is_none_or(|(aid, ar)| aid != iid && ar != ir) {
                    return Err(format!(
                        "{flag} `{}` is {what} `{}`: writing it would destroy it (name another output)",
                        out.display(),
                        input.display()
                    ));
                }
            }
            if let Some(k) = seen.iter().position(|(sid, sr)| *sid == id || *sr == r) {
                let (other_flag, other, _) = &self.outputs[k];
                return Err(format!(
                    "{flag} `{}` is also the output `{}` ({other_flag}): one would overwrite the other",
                    out.display(),
                    other.display()
                ));
            }
            seen.push((id, r));
            if !self.best_effort.contains(out) {
                writable(flag, out, false)?;
            }
        }
        self.check_siblings(&inputs)?;
        for (flag, dir) in &self.dirs {
            writable(flag, dir, true)?;
            let d = resolve(dir);
            if let Some(((what, input), _)) = self.inputs.iter().zip(&inputs).find(|(_, (_, ir))| ir.starts_with(&d)) {
                return Err(format!(
                    "{what} `{}` lies in `{}`, which {flag} writes: it could be overwritten (move it or name \
                     another output)",
                    input.display(),
                    dir.display()
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fifos_devices_and_directories_are_not_read() {
        let dir = std::env::temp_dir().join(format!("forecast-read-regular-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("a.bin");
        std::fs::write(&file, b"abc").unwrap();
        assert_eq!(read_regular(&file).unwrap(), b"abc");
        for bad in [Path::new("/dev/zero"), dir.as_path()] {
            let e = read_regular(bad).unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{}: {e}", bad.display());
        }
        assert_eq!(read_regular(&dir.join("missing")).unwrap_err().kind(), io::ErrorKind::NotFound);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn clobbering_an_input_or_another_output_is_refused() {
        let dir = std::env::temp_dir().join(format!("forecast-clobber-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, b"x").unwrap();
        let via_dots = dir.join("sub").join("..").join("scene.toml");
        assert!(same_file(&scene, &via_dots));
        let check = |out: &Path, outputs: &[&Path]| {
            let mut g = OutputSet::new();
            g.input("the scene", &scene);
            outputs.iter().for_each(|o| {
                g.output("--out", o);
            });
            g.output("--checkpoint-path", out);
            g.check()
        };
        let e = check(&via_dots, &[]).unwrap_err();
        assert!(e.contains("--checkpoint-path") && e.contains("destroy"), "{e}");
        let out = dir.join("r.exr"); // not yet written: compared as resolved paths
        let e = check(&dir.join("sub/../r.exr"), &[&out]).unwrap_err();
        assert!(e.contains("overwrite"), "{e}");
        check(&dir.join("r.ckpt"), &[&out]).unwrap();
        // a hard link and a symbolic link to the scene are the scene
        std::fs::hard_link(&scene, dir.join("hard.toml")).unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink(&scene, dir.join("sub/link.toml")).unwrap();
        assert!(check(&dir.join("hard.toml"), &[]).is_err());
        #[cfg(unix)]
        assert!(check(&dir.join("sub/link.toml"), &[]).is_err());
        // an output may replace the one input it supersedes, and only that one
        let ckpt = dir.join("r.ckpt");
        std::fs::write(&ckpt, b"c").unwrap();
        let mut g = OutputSet::new();
        g.input("--resume", &ckpt).input("the scene", &scene).output_replacing("--checkpoint-path", &ckpt, &ckpt);
        g.check().unwrap();
        g.output_replacing("--out", &scene, &ckpt);
        assert!(g.check().unwrap_err().contains("the scene"));
        // an input inside an output directory
        let mut g = OutputSet::new();
        g.input("--reference", &dir.join("sub/ref.exr")).output_dir("compare --out", &dir.join("sub"));
        assert!(g.check().unwrap_err().contains("--reference"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn temporaries_backups_and_unwritable_outputs_are_refused() {
        let dir = std::env::temp_dir().join(format!("forecast-siblings-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("isdir/x.exr")).unwrap();
        let (scene, out) = (dir.join("t.exr.old"), dir.join("t.exr"));
        std::fs::write(&scene, b"scene").unwrap();
        std::fs::write(dir.join("afile"), b"x").unwrap();
        let check = |outs: &[&Path]| {
            let mut g = OutputSet::new();
            g.input("the scene", &scene);
            outs.iter().for_each(|o| {
                g.output("--out", o);
            });
            g.check()
        };
        // the scene is the backup of an output: refused, and kept
        let e = check(&[&out]).unwrap_err();
        assert!(e.contains("backup") && e.contains("the scene"), "{e}");
        // a user's file where a temporary goes is refused, not replaced
        let notes = dir.join("r.json.tmp");
        std::fs::write(&notes, b"notes").unwrap();
        let e = check(&[&dir.join("r.json")]).unwrap_err();
        assert!(e.contains("r.json.tmp") && e.contains("exists"), "{e}");
        // an output that is another output's temporary
        let e = check(&[&dir.join("c.exr"), &dir.join("c.exr.tmp")]).unwrap_err();
        assert!(e.contains("also an output"), "{e}");
        // a directory, and a path under a file
        assert!(check(&[&dir.join("isdir/x.exr")]).unwrap_err().contains("is a directory"));
        assert!(check(&[&dir.join("afile/x.exr")]).unwrap_err().contains("is not a directory"));
        let mut g = OutputSet::new();
        g.output("--checkpoint-path", &dir.join("afile/x.ckpt")).best_effort(&dir.join("afile/x.ckpt"));
        g.check().unwrap(); // a checkpoint that cannot be written only warns
        check(&[&dir.join("new/sub/r.exr")]).unwrap(); // missing directories are created
                                                       // the writer itself never truncates a temporary it did not create, nor removes it
        let e = write_set_with(&mut RealFs, &[(dir.join("r.json"), b"{}".to_vec())]).unwrap_err();
        assert!(e.contains("r.json.tmp"), "{e}");
        assert_eq!(std::fs::read(&notes).unwrap(), b"notes");
        assert_eq!(std::fs::read(&scene).unwrap(), b"scene");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn path_conventions() {
        assert_eq!(atomic_path(Path::new("/a/b/c.exr")), PathBuf::from("/a/b/c.exr.tmp"));
        assert_eq!(backup_path(Path::new("c.png")), PathBuf::from("c.png.old"));
    }

    #[test]
    fn prefixes_without_a_file_name_are_refused() {
        for bad in ["dir/", "dir/.", "dir/..", "", "/", "a/b//"] {
            let e = check_output_prefix(Path::new(bad)).unwrap_err();
            assert!(e.contains("no file name"), "{bad}: {e}");
        }
        for good in ["x", "dir/x", "dir/.x", "./x", "../x"] {
            check_output_prefix(Path::new(good)).unwrap();
        }
    }
}
