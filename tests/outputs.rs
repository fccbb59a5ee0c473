//! A render's outputs `PREFIX.{exr,png,json}` are replaced as a whole or not at all
//! (`forecast::atomic_io`), and a failed write leaves no temporaries.
//!
//! * Injected failures (deterministic): a successful set write performs a fixed sequence of
//!   file-system operations; for every position `k` in it, a run that fails at operation `k`
//!   (a write on a full disk, a refused backup, a rename failing midway) must return an error
//!   naming a file, leave the old set byte for byte, and leave no `.tmp` or `.old` file.
//! * The same for a first write (no old set): nothing at all remains.
//! * End to end: a render whose `PREFIX.json` cannot be replaced (it is a directory) fails and
//!   leaves the old `PREFIX.exr` and `PREFIX.png` untouched, with no temporaries.

mod common;

use common::{root, tmp_dir};
use forecast::atomic_io::{FileOps, FileSet, RealFs};
use std::collections::BTreeMap;
use std::io;
use std::path::Path;

/// The real file system, failing the `fail_at`-th operation that can fail a write (write,
/// backup, rename), counting from 0. Removals always succeed (cleanup).
struct FailAt {
    fail_at: Option<usize>,
    ops: usize,
    log: Vec<String>,
}

impl FailAt {
    fn new(fail_at: Option<usize>) -> FailAt {
        FailAt { fail_at, ops: 0, log: Vec::new() }
    }
    fn step(&mut self, what: &str, p: &Path) -> io::Result<()> {
        let k = self.ops;
        self.ops += 1;
        self.log.push(format!("{what} {}", p.display()));
        if self.fail_at == Some(k) {
            return Err(io::Error::other(format!("injected failure at operation {k}")));
        }
        Ok(())
    }
}

impl FileOps for FailAt {
    fn write(&mut self, path: &Path, bytes: &[u8]) -> io::Result<()> {
        self.step("write", path)?;
        RealFs.write(path, bytes)
    }
    fn rename(&mut self, from: &Path, to: &Path) -> io::Result<()> {
        self.step("rename", from)?;
        RealFs.rename(from, to)
    }
    fn backup(&mut self, path: &Path, backup: &Path) -> io::Result<()> {
        self.step("backup", path)?;
        RealFs.backup(path, backup)
    }
    fn remove(&mut self, path: &Path) -> io::Result<()> {
        RealFs.remove(path)
    }
    fn exists(&mut self, path: &Path) -> bool {
        RealFs.exists(path)
    }
    fn is_dir(&mut self, path: &Path) -> bool {
        RealFs.is_dir(path)
    }
}

/// Every file in `dir`, name → bytes.
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .map(|e| (e.file_name().to_string_lossy().to_string(), std::fs::read(e.path()).unwrap_or_default()))
        .collect()
}

fn set(dir: &Path, tag: &str) -> FileSet {
    let mut s = FileSet::new();
    for ext in ["exr", "png", "json"] {
        s.add(dir.join(format!("out.{ext}")), format!("{tag} {ext}").into_bytes());
    }
    s
}

/// Runs the set write failing at every operation in turn; returns how many operations a
/// successful write takes.
fn every_failure_keeps(dir: &Path, before: &BTreeMap<String, Vec<u8>>) -> usize {
    let mut clean = FailAt::new(None);
    // dry count on a copy of the directory, so `dir` keeps the old set
    let count_dir = dir.with_extension("count");
    let _ = std::fs::remove_dir_all(&count_dir);
    std::fs::create_dir_all(&count_dir).unwrap();
    for (name, bytes) in before {
        std::fs::write(count_dir.join(name), bytes).unwrap();
    }
    set(&count_dir, "new").commit_with(&mut clean).unwrap();
    let n = clean.ops;
    assert!(n >= 6, "expected at least 3 writes and 3 renames, got {:?}", clean.log);
    for k in 0..n {
        let mut fs = FailAt::new(Some(k));
        let err = set(dir, "new").commit_with(&mut fs).unwrap_err();
        assert!(err.contains("out."), "failure at {k} ({}): error names no file: {err}", fs.log[k]);
        assert_eq!(&snapshot(dir), before, "failure at operation {k} ({}) changed the directory: {err}", fs.log[k]);
    }
    let _ = std::fs::remove_dir_all(&count_dir);
    n
}

#[test]
fn a_failed_set_write_keeps_the_old_set_and_leaves_no_temporaries() {
    let dir = tmp_dir("outputs-replace");
    set(&dir, "old").commit().unwrap();
    let before = snapshot(&dir);
    assert_eq!(before.len(), 3);
    let n = every_failure_keeps(&dir, &before);
    // 3 writes, 3 backups of the existing files, 3 renames
    assert_eq!(n, 9);
    set(&dir, "new").commit().unwrap();
    let after = snapshot(&dir);
    assert_eq!(after.keys().collect::<Vec<_>>(), ["out.exr", "out.json", "out.png"]);
    assert_eq!(after["out.json"], b"new json");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_failed_first_write_leaves_nothing() {
    let dir = tmp_dir("outputs-first");
    let n = every_failure_keeps(&dir, &BTreeMap::new());
    assert_eq!(n, 6, "no backups when nothing exists yet");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_single_atomic_write_removes_its_temporary_on_failure() {
    let dir = tmp_dir("outputs-single");
    let p = dir.join("a.json");
    std::fs::write(&p, b"old").unwrap();
    for k in 0..2 {
        let mut s = FileSet::new();
        s.add(p.clone(), b"new".to_vec());
        assert!(s.commit_with(&mut FailAt::new(Some(k))).is_err());
        assert_eq!(snapshot(&dir), BTreeMap::from([("a.json".to_string(), b"old".to_vec())]));
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_render_that_cannot_write_its_json_keeps_the_old_images() {
    let dir = tmp_dir("outputs-render");
    let prefix = dir.join("r");
    let scene = root().join("scenes/cornell-box.toml");
    let mut job = common::job(&scene, forecast::integrators::Method::Pt, 1, 3, (8, 8), 1, &prefix);
    common::render_film(&job);
    let old = snapshot(&dir);
    assert_eq!(old.keys().collect::<Vec<_>>(), ["r.exr", "r.json", "r.png"]);
    // PREFIX.json becomes a directory: the JSON cannot be replaced, so neither may the images.
    std::fs::remove_file(dir.join("r.json")).unwrap();
    std::fs::create_dir(dir.join("r.json")).unwrap();
    job.seed = Some(4);
    let err = match forecast::pipeline::render(
        &job,
        &forecast::distributed::local::Local::new(),
        std::time::Instant::now(),
    ) {
        Ok(_) => panic!("the render replaced its outputs although r.json is a directory"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("r.json"), "{err}");
    let after = snapshot(&dir);
    assert_eq!(after.keys().collect::<Vec<_>>(), ["r.exr", "r.json", "r.png"], "leftovers: {after:?}");
    assert_eq!(after["r.exr"], old["r.exr"]);
    assert_eq!(after["r.png"], old["r.png"]);
    let _ = std::fs::remove_dir_all(dir);
}

/// The output guard's one allowed overlap: a resumed render writes its checkpoint (and its
/// `PREFIX.*`) over the checkpoint it resumed from, which the new one supersedes.
#[test]
fn a_resumed_render_may_replace_the_checkpoint_it_resumed() {
    let d = tmp_dir("outputs-resume-in-place");
    let prefix = d.join("r");
    let render = |spp: &str, resume: bool| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_forecast"));
        c.args(["render", root().join("scenes/cornell-box.toml").to_str().unwrap(), "--spp", spp]);
        c.args(["--resolution", "8x8", "--threads", "1", "--quiet", "--checkpoint-every", "1h", "--out"]).arg(&prefix);
        if resume {
            c.arg("--resume").arg(prefix.with_extension("ckpt"));
        }
        c.output().unwrap()
    };
    assert!(render("2", false).status.success());
    let o = render("4", true);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ck = forecast::checkpoint::Checkpoint::load(&prefix.with_extension("ckpt")).unwrap();
    assert_eq!(ck.passes_done, 4);
    let _ = std::fs::remove_dir_all(d);
}

/// `forecast render SCENE` with no `--out` writes `out/render.{exr,png,json}` under the working
/// directory, creating `out/` (ignored by git), and nothing beside it.
#[test]
fn the_default_outputs_go_to_out() {
    let d = tmp_dir("outputs-default-out");
    std::fs::copy(root().join("scenes/stability/no-dirac.toml"), d.join("s.toml")).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_forecast"))
        .current_dir(&d)
        .args(["render", "s.toml", "--spp", "1", "--resolution", "8x8", "--threads", "1", "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut top: Vec<String> =
        std::fs::read_dir(&d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    top.sort();
    assert_eq!(top, ["out", "s.toml"]);
    assert_eq!(snapshot(&d.join("out")).keys().collect::<Vec<_>>(), ["render.exr", "render.json", "render.png"]);
    let _ = std::fs::remove_dir_all(d);
}

/// The temporaries a killed write leaves (`kill -9` during a checkpoint set's write,
/// `killwrite4.py`) no longer block the same command: a run removes a `PREFIX.EXT.tmp` that is a
/// regular file, locked by no writer, beginning as forecast's EXT does (empty, or cut short, too).
/// It leaves alone a temporary that another program wrote (other bytes), one a live writer holds
/// (its lock), and one that is an input of the run (`--resume` given as the checkpoint's
/// temporary), and refuses to start instead.
#[test]
fn a_killed_writes_temporaries_are_removed_and_nothing_else() {
    use forecast::atomic_io::remove_stale_temporary;
    let d = tmp_dir("outputs-stale-tmp");
    let prefix = d.join("r");
    let render = |extra: &[&str]| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_forecast"));
        c.args(["render", root().join("scenes/stability/no-dirac.toml").to_str().unwrap()]);
        c.args(["--resolution", "8x8", "--threads", "1", "--quiet", "--checkpoint-every", "1h", "--out"]).arg(&prefix);
        c.args(extra).output().unwrap()
    };
    assert!(render(&["--spp", "2"]).status.success());
    let ext = |e: &str| prefix.with_extension(e);
    let exr = std::fs::read(ext("exr")).unwrap();
    let ckpt = std::fs::read(ext("ckpt")).unwrap();
    // a killed set write: a cut EXR, an empty JSON, a whole checkpoint
    std::fs::write(ext("exr.tmp"), &exr[..exr.len() / 2]).unwrap();
    std::fs::write(ext("json.tmp"), b"").unwrap();
    std::fs::write(ext("ckpt.tmp"), &ckpt).unwrap();
    let o = render(&["--resume", ext("ckpt").to_str().unwrap(), "--spp", "3"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for e in ["exr.tmp", "json.tmp", "ckpt.tmp", "png.tmp"] {
        assert!(!ext(e).exists(), "{e} left");
    }
    // another program's file under a temporary's name: refused, kept byte for byte
    std::fs::write(ext("png.tmp"), b"notes, not a PNG").unwrap();
    let o = render(&["--spp", "2"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("r.png.tmp") && err.contains("no stale temporary"), "{err}");
    assert_eq!(std::fs::read(ext("png.tmp")).unwrap(), b"notes, not a PNG");
    std::fs::remove_file(ext("png.tmp")).unwrap();
    // a live writer's temporary (it holds the lock): refused, kept
    std::fs::write(ext("exr.tmp"), &exr[..8]).unwrap();
    let held = std::fs::File::open(ext("exr.tmp")).unwrap();
    held.lock().unwrap();
    assert!(!remove_stale_temporary(&ext("exr")));
    let o = render(&["--spp", "2"]);
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(ext("exr.tmp").exists());
    drop(held);
    assert!(remove_stale_temporary(&ext("exr")) && !ext("exr.tmp").exists());
    // an input is never a temporary to remove: the checkpoint resumed from, named as the
    // checkpoint's temporary, is refused as an input and kept
    std::fs::write(ext("ckpt.tmp"), &ckpt).unwrap();
    let o = render(&["--resume", ext("ckpt.tmp").to_str().unwrap(), "--spp", "3"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("--resume") && err.contains("r.ckpt.tmp"), "{err}");
    assert_eq!(std::fs::read(ext("ckpt.tmp")).unwrap(), ckpt);
    // a directory, a link, an extension forecast does not write: never removed
    std::fs::remove_file(ext("ckpt.tmp")).unwrap();
    std::fs::create_dir(ext("exr.tmp")).unwrap();
    assert!(!remove_stale_temporary(&ext("exr")) && ext("exr.tmp").is_dir());
    std::fs::write(d.join("notes.txt.tmp"), b"").unwrap();
    assert!(!remove_stale_temporary(&d.join("notes.txt")) && d.join("notes.txt.tmp").exists());
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(ext("exr"), ext("png.tmp")).unwrap();
        assert!(!remove_stale_temporary(&ext("png")) && ext("png.tmp").symlink_metadata().is_ok());
    }
    let _ = std::fs::remove_dir_all(d);
}

/// An `--out` in a directory where no file can be created is refused before any work
/// (`out_readonly_dir_work_lost.sh`: the whole render ran, then the write failed). The directory
/// is read-only to the user running the render: as root (who may write anywhere), the render runs
/// as `nobody` through `setpriv`; without `setpriv` the test says so and checks nothing.
#[cfg(unix)]
#[test]
fn an_unwritable_output_directory_is_refused_before_any_work() {
    use std::os::unix::fs::PermissionsExt;
    let d = tmp_dir("outputs-readonly");
    std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o777)).unwrap();
    std::fs::copy(root().join("scenes/stability/no-dirac.toml"), d.join("s.toml")).unwrap();
    std::fs::create_dir(d.join("ro")).unwrap();
    std::fs::set_permissions(d.join("ro"), std::fs::Permissions::from_mode(0o555)).unwrap();
    let bin = env!("CARGO_BIN_EXE_forecast");
    let root_user =
        std::fs::metadata("/proc/self").map(|m| std::os::unix::fs::MetadataExt::uid(&m) == 0).unwrap_or(false);
    let mut c = if root_user {
        let mut c = std::process::Command::new("setpriv");
        c.args(["--reuid", "65534", "--regid", "65534", "--clear-groups", bin]);
        c
    } else {
        std::process::Command::new(bin)
    };
    // a render of minutes, were it started
    c.current_dir(&d).args(["render", "s.toml", "--spp", "1000000", "--resolution", "64x64", "--threads", "1"]);
    let t = std::time::Instant::now();
    let o = match c.args(["--quiet", "--out", "ro/x"]).output() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("skipped: cannot run setpriv ({e}); the check needs a user who cannot write ro/");
            return;
        }
    };
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("ro/x") && err.contains("no file can be created in"), "{err}");
    assert!(t.elapsed() < std::time::Duration::from_secs(20), "refused only after {:?}", t.elapsed());
    assert_eq!(std::fs::read_dir(d.join("ro")).unwrap().count(), 0);
    let _ = std::fs::remove_dir_all(d);
}
