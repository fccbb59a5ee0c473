//! Cluster rendering with 2 MPI ranks on one node (needs `--features mpi` and MPICH's mpirun):
//! equivalence with the single-process render for every method, the broadcast round trip,
//! the time box, and checkpoint/resume across ranks.
#![cfg(feature = "mpi")]

mod common;
use common::{assert_same_image, tmp_dir};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

const METHODS: &[&str] = &["pt", "iws", "iws-pm", "iws-cf"];

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_forecast")
}

fn scene() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml").display().to_string()
}

fn mpirun(n: usize, args: &[&str]) -> std::process::Output {
    let o = Command::new("mpirun")
        .arg("-n")
        .arg(n.to_string())
        .env("RAYON_NUM_THREADS", "1")
        .arg(bin())
        .args(args)
        .output()
        .expect("mpirun not found: install MPICH (.ci/install-mpi.sh)");
    assert!(o.status.success(), "mpirun failed: {}", String::from_utf8_lossy(&o.stderr));
    o
}

fn json(prefix: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(format!("{}.json", prefix.display())).unwrap()).unwrap()
}

#[test]
fn selftest_of_every_collective() {
    let o = mpirun(2, &["mpi-selftest"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("passed on 2 rank"));
}

#[test]
fn two_ranks_equal_one_process_for_every_method() {
    let d = tmp_dir("equiv");
    for m in METHODS {
        let one = d.join(format!("{m}-1"));
        let two = d.join(format!("{m}-2"));
        let common = ["--spp", "8", "--resolution", "64x64", "--seed", "7", "--quiet", "--method", m];
        let st = Command::new(bin()).args(["render", &scene()]).args(common).arg("--out").arg(&one).status().unwrap();
        assert!(st.success());
        mpirun(2, &[&["render", &scene()][..], &common[..], &["--out", two.to_str().unwrap()][..]].concat());
        assert_same_image(&one.with_extension("exr"), &two.with_extension("exr"));
        let j = json(&two);
        assert_eq!(j["ranks"], 2);
        assert_eq!(j["spp"], 8);
        // broadcast round trip: every rank holds rank 0's preprocess product, byte for byte
        let ranks = j["per_rank"].as_array().unwrap();
        assert_eq!(ranks.len(), 2);
        assert_eq!(ranks[0]["product_hash"], ranks[1]["product_hash"]);
        assert_eq!(ranks[0]["bytes_broadcast"], ranks[1]["bytes_broadcast"]);
        assert_eq!(ranks[0]["passes"], 4);
        assert_eq!(ranks[1]["passes"], 4);
    }
}

#[test]
fn time_box_ends_within_budget_plus_one_pass() {
    let d = tmp_dir("time");
    let out = d.join("t");
    let t = Instant::now();
    mpirun(
        2,
        &[
            "render",
            &scene(),
            "--method",
            "pt",
            "--time",
            "5s",
            "--resolution",
            "64x64",
            "--seed",
            "1",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    let wall = t.elapsed().as_secs_f64();
    let j = json(&out);
    let ranks = j["per_rank"].as_array().unwrap();
    let passes: u64 = ranks.iter().map(|r| r["passes"].as_u64().unwrap()).sum();
    let max_pass = ranks
        .iter()
        .map(|r| r["render_s"].as_f64().unwrap() / r["passes"].as_f64().unwrap().max(1.0))
        .fold(0.0, f64::max);
    assert_eq!(j["spp"].as_u64().unwrap(), passes, "spp must equal the passes summed over ranks");
    assert_eq!(j["passes"].as_u64().unwrap(), passes);
    // budget + one pass + process start/finalize (mpirun start-up is ~0.2 s on this machine)
    assert!(wall <= 5.0 + max_pass + 1.0, "wall {wall:.2}s exceeds the 5 s budget plus one pass ({max_pass:.3}s)");
    assert!(passes >= 2);
}

#[test]
fn checkpoint_and_resume_across_ranks() {
    let d = tmp_dir("ckpt");
    let (full, part, res) = (d.join("full"), d.join("part"), d.join("res"));
    let ckpt = format!("{}.ckpt", part.display());
    // the same 12-pass render, with `extra` options, written to `out`
    let render12 = |extra: &[&str], out: &Path| {
        let common =
            ["render", &scene(), "--method", "pt", "--spp", "12", "--resolution", "32x32", "--seed", "5", "--quiet"];
        mpirun(2, &[&common[..], extra, &["--out", out.to_str().unwrap()][..]].concat());
    };
    render12(&[], &full);
    // stop after 2 rounds (4 passes) with a checkpoint, then resume to 12 passes
    render12(&["--checkpoint-every", "1ms", "--max-rounds", "2"], &part);
    let ck = forecast::checkpoint::Checkpoint::load(&PathBuf::from(&ckpt)).unwrap();
    assert_eq!(ck.passes_done, 4);
    render12(&["--resume", &ckpt], &res);
    assert_eq!(json(&res)["spp"], 12);
    assert_same_image(&res.with_extension("exr"), &full.with_extension("exr"));
}

/// Issue #9 §3: an error on one rank inside the pass loop used to leave rank 0 in `MPI_Finalize`
/// and rank 1 spinning in the round's all-reduce. Here the output directory is replaced by a
/// regular file once the first checkpoint is in it (an unwritable `--out` is refused before any
/// work, so it must break during the render; a regular file stops root too): every later
/// checkpoint write fails, which is a warning printed once per interval by rank 0, and the final
/// image write fails on rank 0, which every rank learns at the agreement after it: the job ends
/// non-zero, well before a hang could be mistaken for work, with the error printed exactly once.
#[test]
fn an_error_on_rank_0_ends_every_rank_and_is_printed_once() {
    let d = tmp_dir("mpi-error");
    let blocker = d.join("not-a-dir");
    std::fs::create_dir_all(&blocker).unwrap();
    let out = blocker.join("x");
    let mut child = Command::new("mpirun")
        .args(["-n", "2"])
        .env("RAYON_NUM_THREADS", "1")
        .arg(bin())
        .args([
            "render",
            &scene(),
            "--method",
            "pt",
            "--time",
            "6s",
            "--checkpoint-every",
            "1s",
            "--resolution",
            "32x32",
            "--quiet",
        ])
        .arg("--out")
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("mpirun not found: install MPICH (.ci/install-mpi.sh)");
    let t0 = Instant::now();
    while !blocker.join("x.ckpt").exists() && t0.elapsed() < std::time::Duration::from_secs(30) {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // a checkpoint being written at that moment may refill the directory: retry
    let removed = (0..100).any(|_| {
        std::fs::remove_dir_all(&blocker).is_ok() || {
            std::thread::sleep(std::time::Duration::from_millis(10));
            false
        }
    });
    assert!(removed, "could not remove {}", blocker.display());
    std::fs::write(&blocker, b"x").unwrap();
    let t = Instant::now();
    let limit = std::time::Duration::from_secs(60);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if t.elapsed() > limit {
            child.kill().ok();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    let status = status.unwrap_or_else(|| panic!("the job hung for {limit:?}; stderr: {err}"));
    assert!(!status.success(), "the job succeeded although nothing could be written: {err}");
    assert_eq!(err.matches("error: ").count(), 1, "the error must be printed once: {err}");
    assert!(err.contains("not-a-dir"), "the error must name the path: {err}");
    let warnings = err.matches("warning: checkpoint").count();
    assert!(warnings >= 1, "failed checkpoints must warn: {err}");
    assert!(!err.contains("panicked"), "{err}");
}

/// A failed checkpoint under two ranks is a warning: the render completes and its JSON says so.
#[test]
fn a_failed_checkpoint_under_two_ranks_warns_and_completes() {
    let d = tmp_dir("mpi-ckpt-warn");
    let blocker = d.join("not-a-dir");
    std::fs::write(&blocker, b"x").unwrap();
    let ckpt = blocker.join("x.ckpt");
    let out = d.join("ok");
    // 256 passes = 128 agreed rounds: far longer than the 1-ms interval on any machine (8 passes
    // once finished inside 1 ms, leaving only the final checkpoint to fail)
    let args = [
        "render",
        &scene(),
        "--method",
        "pt",
        "--spp",
        "256",
        "--resolution",
        "16x16",
        "--quiet",
        "--checkpoint-every",
        "1ms",
    ];
    let o = mpirun(
        2,
        &[&args[..], &["--checkpoint-path", ckpt.to_str().unwrap(), "--out", out.to_str().unwrap()]].concat(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    let j = json(&out);
    assert_eq!(j["spp"], 256);
    let failed = j["warnings"].as_array().unwrap().iter().filter(|w| w.to_string().contains("not written")).count();
    assert!(failed >= 2, "{j}");
    assert_eq!(err.matches("warning: ").count(), failed, "each warning printed once: {err}");
}

/// `pt-cf` (issue #12) on 2 ranks gives the 1-process image, guided (c = 0.3, splitting, two
/// guided depths) so that the broadcast tables are really used, with the light-path pilot (rank
/// 0's count broadcast). Self-contained.
#[test]
fn pt_cf_two_ranks_equal_one_process() {
    let d = tmp_dir("pt-cf-equiv");
    let (one, two) = (d.join("ptcf-1"), d.join("ptcf-2"));
    let common = [
        "--spp",
        "8",
        "--resolution",
        "48x48",
        "--seed",
        "7",
        "--quiet",
        "--method",
        "pt-cf",
        "--forecast-photons",
        "20000",
        "--guide-fraction",
        "0.3",
        "--split",
        "4",
        "--table-depth",
        "2",
    ];
    let st = Command::new(bin()).args(["render", &scene()]).args(common).arg("--out").arg(&one).status().unwrap();
    assert!(st.success());
    mpirun(2, &[&["render", &scene()][..], &common[..], &["--out", two.to_str().unwrap()][..]].concat());
    assert_same_image(&one.with_extension("exr"), &two.with_extension("exr"));
    let j = json(&two);
    assert_eq!(j["ranks"], 2);
    let ranks = j["per_rank"].as_array().unwrap();
    assert_eq!(ranks[0]["product_hash"], ranks[1]["product_hash"]);
    assert!(j["method_stats"]["guide"]["fraction_inside_clusters"].as_f64().unwrap() > 0.0);
    // rank 0's light-path pilot reached rank 1: the count both used is the one recorded
    assert_eq!(j["options"]["light_paths"], json(&one)["options"]["light_paths"]);
    assert_eq!(j["options"]["light_paths"], j["light_path_rule"]["light_paths"]);
}

#[test]
fn snapshots_under_two_ranks_leave_the_image_unchanged() {
    let d = tmp_dir("snapshots");
    let (plain, snapped) = (d.join("plain"), d.join("snapped"));
    let common =
        ["render", &scene(), "--method", "pt", "--spp", "40", "--resolution", "32x32", "--seed", "3", "--quiet"];
    mpirun(2, &[&common[..], &["--out", plain.to_str().unwrap()][..]].concat());
    // 1ms is due at the first round boundary (loading alone takes longer); 1h never comes
    let snaps = ["--snapshots", "1ms,1h", "--out", snapped.to_str().unwrap()];
    mpirun(2, &[&common[..], &snaps[..]].concat());
    assert_eq!(
        std::fs::read(plain.with_extension("exr")).unwrap(),
        std::fs::read(snapped.with_extension("exr")).unwrap()
    );
    let s = json(&snapped.with_extension("snap-1ms"));
    assert_eq!((s["ranks"].as_u64(), s["label"].as_str()), (Some(2), Some("1ms")));
    let passes = s["passes"].as_u64().unwrap();
    assert!(passes >= 2 && passes.is_multiple_of(2) && passes <= 40, "whole rounds of 2 passes: {passes}");
    assert!(s["elapsed_s"].as_f64().unwrap() >= 1e-3);
    let j = json(&snapped);
    assert_eq!(j["snapshots"].as_array().map(Vec::len), Some(1));
    assert!(j["warnings"].as_array().unwrap().iter().any(|w| w.as_str().unwrap().contains("snapshot 1h not written")));
}

/// Waits for `child` at most `limit`; kills it past that. (status or None, stderr).
fn wait_for(mut child: std::process::Child, limit: std::time::Duration) -> (Option<std::process::ExitStatus>, String) {
    let mut pipe = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut err = String::new();
        let _ = std::io::Read::read_to_string(&mut pipe, &mut err);
        err
    });
    let t = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if t.elapsed() > limit {
            child.kill().ok();
            child.wait().ok();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    (status, reader.join().unwrap())
}

/// `mpirun -n 1 A : -n 1 B`: ranks started with another method (a hang before), resolution (a
/// panic in a reduction), scene or seed (a mixed image, exit 0) are refused before any work:
/// exit 1, the differing field named, nothing written.
#[test]
fn ranks_with_different_jobs_are_refused_naming_the_field() {
    let d = tmp_dir("mpi-mpmd");
    let ring = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/ring.toml").display().to_string();
    let base = |scene: &str, res: &str, seed: &str, extra: &[&str]| -> Vec<String> {
        let a = ["render", scene, "--spp", "2", "--resolution", res, "--seed", seed, "--quiet", "--threads", "1"];
        a.iter().chain(extra).map(|s| s.to_string()).collect()
    };
    let cornell = scene();
    let cases: [(&str, Vec<String>, &str); 5] = [
        ("method", base(&cornell, "16x16", "1", &["--method", "iws"]), "--method differs"),
        ("resolution", base(&cornell, "32x32", "1", &[]), "--resolution differs"),
        ("scene", base(&ring, "16x16", "1", &[]), "the scene's content"),
        ("seed", base(&cornell, "16x16", "2", &[]), "--seed differs"),
        // issue #63: rank 1's own --out was ignored without a word (only rank 0 writes)
        ("out", base(&cornell, "16x16", "1", &[]), "--out differs"),
    ];
    for (name, other, field) in cases {
        let out = d.join(name);
        let other_out = if name == "out" { d.join("out-of-rank-1") } else { out.clone() };
        let mut cmd = Command::new("mpirun");
        cmd.env("RAYON_NUM_THREADS", "1").args(["-n", "1"]).arg(bin()).args(base(&cornell, "16x16", "1", &[]));
        cmd.arg("--out").arg(&out).args([":", "-n", "1"]).arg(bin()).args(&other).arg("--out").arg(&other_out);
        let child = cmd.stdout(std::process::Stdio::null()).stderr(std::process::Stdio::piped()).spawn().unwrap();
        let (status, err) = wait_for(child, std::time::Duration::from_secs(60));
        let status = status.unwrap_or_else(|| panic!("{name}: the job hung; stderr: {err}"));
        assert_eq!(status.code(), Some(1), "{name}: {err}");
        assert!(err.contains("different jobs") && err.contains(field), "{name}: {err}");
        assert_eq!(err.matches("error: ").count(), 1, "{name}: printed once: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert!(!out.with_extension("exr").exists(), "{name}: a refused job wrote an image");
        assert!(!other_out.with_extension("exr").exists(), "{name}: a refused job wrote an image");
    }
}

/// The pid of the process whose environment has `PMI_RANK=rank` and whose command line holds
/// `marker` (a unique output path), if it exists yet.
fn rank_pid(rank: usize, marker: &str) -> Option<u32> {
    for e in std::fs::read_dir("/proc").ok()?.flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<u32>() else { continue };
        let cmdline = std::fs::read(e.path().join("cmdline")).unwrap_or_default();
        let env = std::fs::read(e.path().join("environ")).unwrap_or_default();
        let has = |hay: &[u8], needle: &[u8]| hay.windows(needle.len()).any(|w| w == needle);
        if has(&cmdline, marker.as_bytes())
            && has(&cmdline, bin().as_bytes())
            && env.split(|&b| b == 0).any(|v| v == format!("PMI_RANK={rank}").as_bytes())
        {
            return Some(pid);
        }
    }
    None
}

/// Starts a 2-rank render of `args` (with `env`), stops rank 1 (SIGSTOP) once it is inside the
/// pass loop, and waits at most 60 s: (exit status, stderr, wall seconds from the start).
fn stop_rank_1(args: &[&str], env: &[(&str, &str)]) -> (std::process::ExitStatus, String, f64) {
    // a folder of its own per test: tmp_dir empties the folder it is given
    let name = format!("stopped-{}", args.join("-").replace('/', "_"));
    let out = tmp_dir(&format!("mpi-sigstop-{name}")).join(&name);
    let marker = out.display().to_string();
    let child = Command::new("mpirun")
        .args(["-n", "2"])
        .env("RAYON_NUM_THREADS", "1")
        .envs(env.iter().copied())
        .arg(bin())
        .args(["render", &scene(), "--resolution", "32x32", "--threads", "1", "--quiet"])
        .args(args)
        .arg("--out")
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("mpirun not found: install MPICH (.ci/install-mpi.sh)");
    let t = Instant::now();
    let pid = loop {
        if let Some(p) = rank_pid(1, &marker) {
            break p;
        }
        assert!(t.elapsed().as_secs() < 20, "rank 1 never started");
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    std::thread::sleep(std::time::Duration::from_millis(700)); // inside the pass loop
    assert!(Command::new("kill").args(["-STOP", &pid.to_string()]).status().unwrap().success());
    let (status, err) = wait_for(child, std::time::Duration::from_secs(60));
    let wall = t.elapsed().as_secs_f64();
    let _ = Command::new("kill").args(["-KILL", &pid.to_string()]).status(); // if still there
    let status = status.unwrap_or_else(|| panic!("the job hung with a stopped rank; stderr: {err}"));
    (status, err, wall)
}

/// A rank stopped by SIGSTOP in a `--time 2s` render used to hold the job forever; the others'
/// watchdog ends it through `MPI_Abort` with a message, 10 s + budget/4 past the budget.
#[test]
fn a_stopped_rank_ends_the_job_through_the_watchdog() {
    let (status, err, wall) = stop_rank_1(&["--time", "2s"], &[]);
    assert!(!status.success(), "{err}");
    assert!(err.contains("stopped responding") && err.contains("MPI_Abort"), "{err}");
    assert!(err.contains("past the time budget"), "{err}");
    // budget 2 s + grace 10.5 s, the watchdog's 0.2 s tick, MPI's teardown
    assert!(wall < 2.0 + 10.5 + 10.0, "took {wall:.1} s");
}

/// The same in an `--spp` render, which has no budget: the heartbeat (a wait in a collective
/// longer than max(floor, 10 x the slowest round); floor 2 s here through
/// `FORECAST_MPI_HEARTBEAT`, 60 s by default) ends it through `MPI_Abort` with a message.
#[test]
fn a_stopped_rank_in_an_spp_render_ends_the_job_through_the_heartbeat() {
    // far more passes than the test's 60 s allow (a 32x32 pass takes about a millisecond)
    let (status, err, wall) =
        stop_rank_1(&["--spp", "100000000", "--method", "pt"], &[("FORECAST_MPI_HEARTBEAT", "2")]);
    assert!(!status.success(), "{err}");
    assert!(err.contains("stopped responding") && err.contains("MPI_Abort"), "{err}");
    assert!(err.contains("past the heartbeat's"), "{err}");
    // start (up to the 0.7 s after rank 1 appears), a 2 s floor (rounds of a 32x32 pt pass group
    // are far under 0.2 s), the 0.2 s tick, MPI's teardown
    assert!(wall < 0.7 + 2.0 + 10.0 + 5.0, "took {wall:.1} s");
}

/// A heartbeat floor that is not a number of seconds is refused before any work, naming the
/// variable and the value.
#[test]
fn a_bad_heartbeat_floor_is_refused() {
    let o = Command::new("mpirun")
        .args(["-n", "2"])
        .env("FORECAST_MPI_HEARTBEAT", "soon")
        .arg(bin())
        .args(["mpi-selftest"])
        .output()
        .expect("mpirun not found: install MPICH (.ci/install-mpi.sh)");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("FORECAST_MPI_HEARTBEAT=`soon`"), "{err}");
}

/// The cluster of `scripts/mpi-netns.sh` (which runs the `netns_` tests): three hosts, each a
/// network namespace with its own address, joined by veths to a bridge; hydra starts two ranks
/// on each through an ssh stand-in that enters the host's namespace. The ranks run on the MPI
/// runtime the script names (MPICH 5.0.2, .ci/install-mpich-runtime.sh: Debian's MPICH 4.0.2
/// hangs in MPI_Finalize across hosts, docs/mpi.md), the binary being the one built against
/// Debian's MPICH (the same ABI).
struct Hosts {
    /// The script's folder: `hosts` (the hostfile), `launch` (the ssh stand-in), `iface` (the
    /// bridge, where mpiexec listens), `nodes` (`namespace link address`, one host a line).
    dir: PathBuf,
    /// Each host's namespace and the veth end on the bridge (its link).
    nodes: Vec<(String, String)>,
    /// Whether `tc netem` works here.
    netem: bool,
    /// The MPI runtime's folder (`bin/mpiexec`, `lib/libmpich.so.12`).
    mpi: PathBuf,
}

fn hosts() -> Hosts {
    let dir = std::env::var_os("FORECAST_NETNS_DIR")
        .map(PathBuf::from)
        .expect("the netns_ tests run through scripts/mpi-netns.sh (as root: it makes the hosts' namespaces)");
    let nodes = std::fs::read_to_string(dir.join("nodes"))
        .unwrap()
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (f[0].to_string(), f[1].to_string())
        })
        .collect();
    let netem = std::env::var("FORECAST_NETNS_NETEM").as_deref() == Ok("1");
    let mpi = std::env::var_os("FORECAST_NETNS_MPI").map(PathBuf::from).expect("run by scripts/mpi-netns.sh");
    Hosts { dir, nodes, netem, mpi }
}

impl Hosts {
    /// `mpiexec` of 6 ranks, 2 a host, running `forecast render SCENE args --out out`.
    fn render(&self, args: &[&str], heartbeat: &str, out: &Path) -> Command {
        let iface = std::fs::read_to_string(self.dir.join("iface")).unwrap();
        let mut c = Command::new(self.mpi.join("bin/mpiexec"));
        c.env("LD_LIBRARY_PATH", self.mpi.join("lib"))
            .arg("-f")
            .arg(self.dir.join("hosts"))
            .args(["-n", "6", "-launcher", "ssh", "-launcher-exec"])
            .arg(self.dir.join("launch"))
            .args(["-iface", iface.trim()])
            // UCX's TCP on eth0 between every pair of ranks: UCX's shared memory would join
            // ranks across namespaces (they share the kernel), bypassing the veths
            .env("UCX_TLS", "tcp,self")
            .env("UCX_NET_DEVICES", "eth0")
            .env("RAYON_NUM_THREADS", "1")
            .env("FORECAST_MPI_HEARTBEAT", heartbeat)
            .arg(bin())
            .args(["render", &scene(), "--threads", "1", "--quiet"])
            .args(args)
            .arg("--out")
            .arg(out)
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped());
        c
    }

    /// Runs `render` and, once the last rank is in its pass loop, `fault`; waits at most
    /// `limit` s. (exit status, stderr, seconds from the fault to the end).
    fn with_fault(
        &self,
        args: &[&str],
        heartbeat: &str,
        out: &Path,
        fault: impl FnOnce(),
        limit: u64,
    ) -> (std::process::ExitStatus, String, f64) {
        let child = self
            .render(args, heartbeat, out)
            .spawn()
            .expect("no mpiexec in the runtime (.ci/install-mpich-runtime.sh)");
        let t = Instant::now();
        while rank_pid(5, &out.display().to_string()).is_none() {
            assert!(t.elapsed().as_secs() < 30, "rank 5 never started");
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        std::thread::sleep(std::time::Duration::from_millis(1500)); // inside the pass loop
        fault();
        let t = Instant::now();
        let (status, err) = wait_for(child, std::time::Duration::from_secs(limit));
        let after = t.elapsed().as_secs_f64();
        eprintln!("{}: ended {after:.1} s after the fault", out.display());
        let status = status.unwrap_or_else(|| panic!("no end within {limit} s of the fault; stderr: {err}"));
        let first = err.lines().find(|l| !l.trim().is_empty()).unwrap_or("");
        eprintln!("{}: mpiexec {status}; stderr begins: {first}", out.display());
        (status, err, after)
    }

    /// Ends every process of host `i` (what a test left there).
    fn kill_all(&self, i: usize) {
        let pids = Command::new("ip").args(["netns", "pids", &self.nodes[i].0]).output().unwrap();
        for p in String::from_utf8_lossy(&pids.stdout).split_whitespace() {
            let _ = Command::new("kill").args(["-KILL", p]).status();
        }
    }
}

fn sh(cmd: &[&str]) {
    let st = Command::new(cmd[0]).args(&cmd[1..]).status().unwrap();
    assert!(st.success(), "{cmd:?} failed");
}

/// One process's image of `args` (the reference of the 6 ranks).
fn one_process(args: &[&str], out: &Path) {
    let st =
        Command::new(bin()).args(["render", &scene(), "--quiet"]).args(args).arg("--out").arg(out).status().unwrap();
    assert!(st.success());
}

/// 6 ranks on 3 hosts, talking TCP over the veths, give one process's image (`pt`, and `iws-cf`,
/// whose preprocess rank 0 broadcasts over the network).
#[test]
#[ignore = "run by scripts/mpi-netns.sh (root: network namespaces)"]
fn netns_1_six_ranks_on_three_hosts_equal_one_process() {
    let h = hosts();
    let d = tmp_dir("netns-equal");
    for m in ["pt", "iws-cf"] {
        let args = ["--spp", "12", "--resolution", "32x32", "--seed", "5", "--method", m];
        let (one, six) = (d.join(format!("{m}-1")), d.join(format!("{m}-6")));
        one_process(&args, &one);
        let t = Instant::now();
        let child =
            h.render(&args, "60", &six).spawn().expect("no mpiexec in the runtime (.ci/install-mpich-runtime.sh)");
        let (status, err) = wait_for(child, std::time::Duration::from_secs(90));
        eprintln!("netns {m}: 6 ranks in {:.1} s", t.elapsed().as_secs_f64());
        let status = status.unwrap_or_else(|| panic!("6 ranks did not end within 90 s; stderr: {err}"));
        assert!(status.success(), "{err}");
        assert_same_image(&one.with_extension("exr"), &six.with_extension("exr"));
        let j = json(&six);
        assert_eq!(j["ranks"], 6);
        let ranks = j["per_rank"].as_array().unwrap();
        assert!(ranks.iter().all(|r| r["product_hash"] == ranks[0]["product_hash"]));
        assert!(ranks.iter().all(|r| r["passes"] == 2), "{ranks:?}");
    }
}

/// Host 2's link goes down in the middle of an `--spp` render: the heartbeat (floor 3 s) of the
/// ranks left waiting ends the job with its message.
#[test]
#[ignore = "run by scripts/mpi-netns.sh (root: network namespaces)"]
fn netns_2_a_link_down_ends_the_job() {
    let h = hosts();
    let out = tmp_dir("netns-link").join("link");
    let link = h.nodes[2].1.clone();
    let args = ["--spp", "100000000", "--resolution", "32x32", "--method", "pt"];
    let (status, err, after) = h.with_fault(&args, "3", &out, || sh(&["ip", "link", "set", &link, "down"]), 60);
    sh(&["ip", "link", "set", &link, "up"]);
    h.kill_all(2);
    assert!(!status.success(), "{err}");
    assert!(err.contains("stopped responding") && err.contains("past the heartbeat's"), "{err}");
    // the 3 s floor, the watchdog's tick, MPI's teardown
    assert!(after < 3.0 + 20.0, "took {after:.1} s");
}

/// Every process of host 2 (its hydra proxy and both ranks) is killed in the middle of a render:
/// the job ends at once with hydra's report of the lost host (its control connection closed:
/// "process manager error waiting for completion"), or of the lost processes, and a failed exit
/// status (hydra's: 255 with MPICH 5.0.2; MPICH 4.0.2's hydra returned 0 in one of two runs).
#[test]
#[ignore = "run by scripts/mpi-netns.sh (root: network namespaces)"]
fn netns_3_a_killed_host_ends_the_job() {
    let h = hosts();
    let out = tmp_dir("netns-kill").join("kill");
    let args = ["--spp", "100000000", "--resolution", "32x32", "--method", "pt"];
    let (status, err, after) = h.with_fault(&args, "3", &out, || h.kill_all(2), 60);
    assert!(!status.success(), "{err}");
    // the image is never written
    assert!(!out.with_extension("exr").exists(), "{err}");
    assert!(
        err.contains("stopped responding")
            || err.contains("Failure during collective")
            || err.contains("process manager error")
            || err.contains("BAD TERMINATION")
            || err.contains("KILLED BY SIGNAL"),
        "{err}"
    );
    assert!(after < 3.0 + 20.0, "took {after:.1} s");
}

/// 100 ms of latency on host 2's link from the middle of a render on: the render completes with
/// one process's image.
#[test]
#[ignore = "run by scripts/mpi-netns.sh (root: network namespaces)"]
fn netns_4_100ms_latency_leaves_the_image_unchanged() {
    let h = hosts();
    let d = tmp_dir("netns-latency");
    let ns = h.nodes[2].0.clone();
    let args = ["--spp", "1000", "--resolution", "64x64", "--seed", "9", "--method", "pt"];
    let (one, six) = (d.join("one"), d.join("six"));
    one_process(&args, &one);
    // tc netem where the kernel has it; else the userspace delay of host 2's link
    // (scripts/netns-delay.py reads the milliseconds from this file)
    let file = std::env::var_os("FORECAST_NETNS_DELAY").map(PathBuf::from).expect("run by scripts/mpi-netns.sh");
    let nodes = std::fs::read_to_string(h.dir.join("nodes")).unwrap();
    let addr = nodes.lines().nth(2).and_then(|l| l.split_whitespace().nth(2)).unwrap().to_string();
    let host0 = h.nodes[0].0.clone();
    // host 0's TCP connect to host 2 (refused: the answer is host 2's reset), in seconds
    let rtt = || {
        let t = Instant::now();
        let probe = format!(": </dev/tcp/{addr}/9");
        let _ = Command::new("ip").args(["netns", "exec", &host0, "bash", "-c", &probe]).output();
        t.elapsed().as_secs_f64()
    };
    let delay = || {
        match h.netem {
            true => sh(&["tc", "-n", &ns, "qdisc", "add", "dev", "eth0", "root", "netem", "delay", "100ms"]),
            false => std::fs::write(&file, "100").unwrap(),
        }
        std::thread::sleep(std::time::Duration::from_millis(100)); // the delay's file is read every 50 ms
        let t = rtt();
        eprintln!("latency: host 0 -> host 2 connect {:.0} ms with the delay", t * 1e3);
        assert!(t >= 0.1, "the delay is not in effect: {t:.3} s");
    };
    let (status, err, after) = h.with_fault(&args, "60", &six, delay, 120);
    match h.netem {
        true => drop(Command::new("tc").args(["-n", &ns, "qdisc", "del", "dev", "eth0", "root"]).status()),
        false => std::fs::write(&file, "0").unwrap(),
    }
    assert!(status.success(), "{err}");
    eprintln!("latency: finished {after:.1} s after the delay was added");
    assert_same_image(&one.with_extension("exr"), &six.with_extension("exr"));
}
