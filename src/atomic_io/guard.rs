//! The guards around the writes of `atomic_io`: inputs are regular files ([`require_regular`],
//! [`read_regular`]), and [`OutputSet`] checks every output of a command run against its inputs,
//! its other outputs, their temporaries and backups, and whether it can be created, before
//! anything is written.

use super::{AtomicIoError, Sibling, SiblingClash};
use std::io;
use std::path::{Path, PathBuf};

/// Refuses an output prefix whose last component is empty, `.` or `..` (`--out dir/` would
/// otherwise write the hidden files `dir/.exr`, `dir/.png`, `dir/.json`).
pub fn check_output_prefix(prefix: &Path) -> Result<(), AtomicIoError> {
    let raw = prefix.as_os_str().to_string_lossy();
    let last = raw.rsplit(std::path::is_separator).next().unwrap_or("");
    if last.is_empty() || last == "." || last == ".." {
        return Err(AtomicIoError::NoFileName { prefix: prefix.to_path_buf() });
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

/// An input the command line names (a scene file), checked before anything reads it: a regular
/// file ([`require_regular`]) this process can open. The error names the file and no line.
pub fn check_input(what: &str, path: &Path) -> Result<(), AtomicIoError> {
    require_regular(path)
        .and_then(|()| std::fs::File::open(path).map(drop))
        .map_err(|source| AtomicIoError::Unreadable { what: what.to_string(), path: path.to_path_buf(), source })
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
/// directory, a directory output that is a file, one whose nearest existing ancestor is not a
/// directory, or (where `probe`: the process that writes) one whose nearest existing ancestor
/// takes no new file ([`probe_write`]).
fn writable(flag: &str, out: &Path, want_dir: bool, probe: bool) -> Result<(), AtomicIoError> {
    if out.is_dir() != want_dir && out.exists() {
        return Err(AtomicIoError::WrongKind { flag: flag.to_string(), output: out.to_path_buf(), want_dir });
    }
    let abs = std::path::absolute(out).unwrap_or_else(|_| out.to_path_buf());
    match abs.ancestors().skip(1).find(|a| a.symlink_metadata().is_ok()) {
        Some(a) if !a.is_dir() => Err(AtomicIoError::NotCreatable {
            flag: flag.to_string(),
            output: out.to_path_buf(),
            blocker: a.to_path_buf(),
        }),
        Some(a) if probe => probe_write(a).map_err(|source| AtomicIoError::NotWritable {
            flag: flag.to_string(),
            output: out.to_path_buf(),
            dir: a.to_path_buf(),
            source,
        }),
        _ => Ok(()),
    }
}

/// Whether files can be created in the directory `dir` (permissions, a read-only mount, an ACL:
/// whatever the write at the end would meet): creates a new empty file there, under a name no
/// other file has, and removes it.
fn probe_write(dir: &Path) -> io::Result<()> {
    for n in 0..16 {
        let probe = dir.join(format!(".forecast-write-probe-{}-{n}", std::process::id()));
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
            Ok(f) => {
                drop(f);
                return std::fs::remove_file(&probe);
            }
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
    Ok(()) // sixteen probes of this process already there: the directory takes files
}

/// The first bytes of every file forecast writes with extension `ext` (the formats a stale
/// temporary may be recognised by): EXR, PNG, the JSON reports, checkpoints.
fn format_magic(ext: &str) -> Option<&'static [u8]> {
    match ext {
        "exr" => Some(&[0x76, 0x2f, 0x31, 0x01]),
        "png" => Some(b"\x89PNG\r\n\x1a\n"),
        "json" => Some(b"{\n  \""), // serde_json's pretty form, as every report is written
        "ckpt" => Some(&crate::checkpoint::MAGIC),
        _ => None,
    }
}

/// Removes `PATH.tmp`, the temporary of the output `out` ([`super::atomic_path`]), when it is
/// a write of ours that a killed process left, and says whether it did. It is one when
/// * it is a regular file (not a link, a directory or a device);
/// * no process holds its lock: every writer locks its temporary from creation until the
///   rename, and the kernel drops the lock of a killed process, so a locked one is being
///   written (`false`: the caller refuses, as two runs then write one output);
/// * its first bytes are those of the format forecast writes to `out` (EXR, PNG, JSON,
///   checkpoint; an empty or shorter file, a write killed early, matches their beginning).
///
/// Anything else (another program's file of that name, an extension forecast does not write) is
/// left alone. The caller checks first that the temporary is no input of the run.
pub fn remove_stale_temporary(out: &Path) -> bool {
    use std::io::Read;
    let tmp = super::atomic_path(out);
    let Some(magic) = out.extension().and_then(|e| e.to_str()).and_then(format_magic) else { return false };
    if !tmp.symlink_metadata().is_ok_and(|m| m.file_type().is_file()) {
        return false;
    }
    let Ok(mut f) = std::fs::File::open(&tmp) else { return false };
    if f.try_lock().is_err() {
        return false;
    }
    let mut head = Vec::with_capacity(magic.len());
    if (&mut f).take(magic.len() as u64).read_to_end(&mut head).is_err() || !magic.starts_with(&head) {
        return false;
    }
    std::fs::remove_file(&tmp).is_ok()
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
///   another output or an existing file (the write would replace it and then delete it); a
///   stale temporary that a killed write of ours left is removed instead
///   ([`remove_stale_temporary`]);
/// * an output that cannot be created: a directory, under a path that is not a directory, or in
///   a directory where no file can be created (probed by creating one: permissions, read-only
///   mounts), so that no render runs to the end only to fail there (except
///   [`OutputSet::best_effort`] ones, whose failure is only a warning).
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
    /// This process does not write the outputs (an MPI rank other than 0): see
    /// [`OutputSet::not_writer`].
    not_writer: bool,
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

    /// This process only checks the outputs that another writes (an MPI rank other than 0, whose
    /// directory may be another node's or shared with rank 0): [`OutputSet::check`] then keeps
    /// the checks of names (inputs, outputs named twice, kinds) and leaves to the writer what
    /// touches its file system: the write probe, and temporaries that exist (a stale one rank 0
    /// removes, which a second rank must not race for).
    pub fn not_writer(&mut self, not_writer: bool) -> &mut Self {
        self.not_writer = not_writer;
        self
    }

    /// The outputs, in the order they were added.
    pub fn outputs(&self) -> impl Iterator<Item = &Path> {
        self.outputs.iter().map(|(_, p, _)| p.as_path())
    }

    /// Every output is written through its temporary `PATH.tmp` and, in a set, a backup
    /// `PATH.old` ([`Sibling`]: [`super::atomic_path`], [`super::backup_path`]): neither may be an
    /// input or another output, nor an existing file, which the write would replace and then
    /// delete.
    fn check_siblings(&self, inputs: &[(FileId, PathBuf)]) -> Result<(), AtomicIoError> {
        let outs: Vec<PathBuf> = self.outputs.iter().map(|(_, p, _)| resolve(p)).collect();
        for (flag, out, _) in &self.outputs {
            for sibling in [Sibling::Temporary, Sibling::Backup] {
                let sib = sibling.path(out);
                let (id, r) = (file_id(&sib), resolve(&sib));
                let clash = if let Some(((what, path), _)) =
                    self.inputs.iter().zip(inputs).find(|(_, (iid, ir))| *iid == id || *ir == r)
                {
                    SiblingClash::Input { what: what.clone(), path: path.clone() }
                } else if outs.contains(&r) {
                    SiblingClash::Output
                } else if self.not_writer {
                    continue;
                } else if sibling == Sibling::Temporary && remove_stale_temporary(out) {
                    // a killed write's leftover: removed, the output is free again
                    continue;
                } else if sib.symlink_metadata().is_ok() {
                    SiblingClash::Exists
                } else {
                    continue;
                };
                return Err(AtomicIoError::Sibling { flag: flag.clone(), output: out.clone(), sibling, clash });
            }
        }
        Ok(())
    }

    /// The rules of [`OutputSet`]; the error names the output, where it comes from, and the file
    /// it would destroy.
    pub fn check(&self) -> Result<(), AtomicIoError> {
        let inputs: Vec<(FileId, PathBuf)> = self.inputs.iter().map(|(_, p)| (file_id(p), resolve(p))).collect();
        let mut seen: Vec<(FileId, PathBuf)> = Vec::new();
        for (flag, out, replaces) in &self.outputs {
            let (id, r) = (file_id(out), resolve(out));
            let allowed = replaces.as_ref().map(|p| (file_id(p), resolve(p)));
            for ((what, input), (iid, ir)) in self.inputs.iter().zip(&inputs) {
                let same = *iid == id || *ir == r;
                if same && allowed.as_ref().is_none_or(|(aid, ar)| aid != iid && ar != ir) {
                    return Err(AtomicIoError::OutputIsInput {
                        flag: flag.clone(),
                        output: out.clone(),
                        what: what.clone(),
                        input: input.clone(),
                    });
                }
            }
            if let Some(k) = seen.iter().position(|(sid, sr)| *sid == id || *sr == r) {
                let (other_flag, other, _) = &self.outputs[k];
                return Err(AtomicIoError::OutputTwice {
                    flag: flag.clone(),
                    output: out.clone(),
                    other_flag: other_flag.clone(),
                    other: other.clone(),
                });
            }
            seen.push((id, r));
            if !self.best_effort.contains(out) {
                writable(flag, out, false, !self.not_writer)?;
            }
        }
        self.check_siblings(&inputs)?;
        for (flag, dir) in &self.dirs {
            writable(flag, dir, true, !self.not_writer)?;
            let d = resolve(dir);
            if let Some(((what, input), _)) = self.inputs.iter().zip(&inputs).find(|(_, (_, ir))| ir.starts_with(&d)) {
                return Err(AtomicIoError::InputInOutputDir {
                    what: what.clone(),
                    input: input.clone(),
                    flag: flag.clone(),
                    dir: dir.clone(),
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atomic_io::{write_set_with, RealFs};

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
            g.check().map_err(|e| e.to_string())
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
        assert!(matches!(g.check().unwrap_err(), AtomicIoError::OutputIsInput { what, .. } if what == "the scene"));
        // an input inside an output directory
        let mut g = OutputSet::new();
        g.input("--reference", &dir.join("sub/ref.exr")).output_dir("compare --out", &dir.join("sub"));
        let e = g.check().unwrap_err();
        assert!(matches!(&e, AtomicIoError::InputInOutputDir { what, .. } if what == "--reference"), "{e}");
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
            g.check().map_err(|e| e.to_string())
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
        // a checkpoint that cannot be written only warns
        g.check().unwrap();
        // missing directories are created
        check(&[&dir.join("new/sub/r.exr")]).unwrap();
        // the writer itself never truncates a temporary it did not create, nor removes it
        let e = write_set_with(&mut RealFs, &[(dir.join("r.json"), b"{}".to_vec())]).unwrap_err();
        assert!(e.to_string().contains("r.json.tmp"), "{e}");
        assert!(matches!(&e, AtomicIoError::Write { source, .. } if source.kind() == io::ErrorKind::AlreadyExists));
        assert_eq!(std::fs::read(&notes).unwrap(), b"notes");
        assert_eq!(std::fs::read(&scene).unwrap(), b"scene");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn prefixes_without_a_file_name_are_refused() {
        for bad in ["dir/", "dir/.", "dir/..", "", "/", "a/b//"] {
            let e = check_output_prefix(Path::new(bad)).unwrap_err();
            assert!(e.to_string().contains("no file name"), "{bad}: {e}");
            assert_eq!(e.path(), Path::new(bad));
        }
        for good in ["x", "dir/x", "dir/.x", "./x", "../x"] {
            check_output_prefix(Path::new(good)).unwrap();
        }
    }
}
