//! The up-front memory estimate of a render (`Plan::memory_estimate`), checked against the
//! memory this process may still take ([`available_memory`], [`check`]) in `RenderJob::resolve`
//! and by `forecast-map` before any work.
//!
//! The memory a process may take is the least of: the machine's `MemAvailable`
//! (`/proc/meminfo`); its address-space limit `RLIMIT_AS` (`ulimit -v`, as `getrlimit` gives it:
//! the soft limit of `/proc/self/limits`) less the address space it already maps (`VmSize`); and
//! for each memory cgroup it is in, from its own up to the root, the limit less the usage that
//! cannot be reclaimed (cgroup v2: `memory.max` less `memory.current` − `file` of `memory.stat`;
//! v1: `memory.limit_in_bytes` less `memory.usage_in_bytes` − `total_cache`). A limit of 2^62
//! bytes or more, `max` or `unlimited` is none. Where none of these can be read (not Linux), no
//! check is made.
//!
//! Invariants: a lower bound (films and preprocess products only), saturating, never panicking.

use super::Plan;
use crate::integrators::Method;
use crate::scene::Scene;

impl Plan {
    /// Bytes this render needs on this node, at least, and of what (refused up front when they
    /// exceed the available memory). Film: 7 f64 per pixel (`render::film::STRIDE`), held by every
    /// rank, plus on rank 0 the reduced sums and the final copy (and with checkpoints or a resume
    /// the checkpoint's film, its clone and its encoding), plus the images (mean, variance, EXR,
    /// PNG: ≈ 64 bytes per pixel). Preprocess product: stored photons (`iws-pm`, ≈ 64 bytes each)
    /// or forecast photons (`iws-cf`, `pt-cf`, ≈ 128 bytes with their clusters and maps), three copies on
    /// rank 0 (built, encoded, decoded) and one on every other rank of the node. The camera values
    /// of a pass group (`render::pass_group_limit` passes for `pt` and `pt-cf`, else one; 12 bytes
    /// per pixel and pass) and, for `pt-cf` with light paths, one splat image per pass of the
    /// group (as much again), on every rank. The scene's decoded images, on every rank of the
    /// node.
    pub fn memory_estimate(&self, scene: &Scene, checkpoints: bool) -> (u64, String) {
        let pixels = self.resolution.0 as u64 * self.resolution.1 as u64;
        let film = pixels.saturating_mul((crate::render::film::STRIDE * 8) as u64);
        let local = local_ranks() as u64;
        let copies = if checkpoints { 6 } else { 3 };
        let product = match self.method {
            Method::IwsPm => self.args.pm.photons.saturating_mul(64),
            // pt-cf builds the same forecast from the same options (`--forecast-photons`)
            Method::IwsCf | Method::PtCf => {
                self.args.cf.forecast_photons.or(scene.forecast_photons).unwrap_or(200_000).saturating_mul(128)
            }
            _ => 0,
        };
        let film_total = film.saturating_mul(copies + local - 1).saturating_add(pixels.saturating_mul(64));
        // a pass group's camera values and pt-cf's splat images (3 f32 per pixel and pass) per rank
        let (w, h) = (self.resolution.0 as usize, self.resolution.1 as usize);
        let group = match self.method {
            Method::Pt | Method::PtCf => crate::render::pass_group_limit(w, h) as u64,
            _ => 1,
        };
        let splats = self.method == Method::PtCf && self.args.ptcf.light_paths != Some(0);
        let per_pass = 12 * local * if splats { 2 } else { 1 };
        let film_total = film_total.saturating_add(pixels.saturating_mul(per_pass * group));
        // every rank of the node holds the scene's decoded images
        let textures = scene.texture_bytes().saturating_mul(local);
        let need = film_total.saturating_add(product.saturating_mul(2 + local)).saturating_add(textures);
        let (w, h) = self.resolution;
        let mut what =
            format!("a {w}x{h} film of {:.1} GiB per copy; preprocess product {:.1} GiB", gib(film), gib(product));
        if textures > 0 {
            what += &format!("; textures {:.2} GiB", gib(textures));
        }
        (need, what)
    }
}

/// What `forecast-map` needs at least, and of what: the forecast product of `photons` forecast
/// photons (≈ 128 bytes each with their clusters and maps, as [`Plan::memory_estimate`] counts
/// them; built once, not encoded), its `w`×`h` view (3 f32 per pixel and its PNG), and the
/// scene's decoded images. The caustic vertices of `--compare-paths` are not counted: they are
/// capped by what is left ([`forecast_map_vertex_cap`]).
pub fn forecast_map_estimate(scene: &Scene, photons: u64, (w, h): (u32, u32)) -> (u64, String) {
    let product = photons.saturating_mul(128);
    let view = (w as u64 * h as u64).saturating_mul(16);
    let textures = scene.texture_bytes();
    let need = product.saturating_add(view).saturating_add(textures);
    let mut what = format!("{photons} forecast photons: {:.1} GiB; a {w}x{h} view", gib(product));
    if textures > 0 {
        what += &format!("; textures {:.2} GiB", gib(textures));
    }
    (need, what)
}

/// The most caustic vertices (of `bytes` each) that `forecast-map`'s untargeted comparison may
/// keep beside `need` bytes: half of what [`available_memory`] leaves; unbounded where that is
/// unknown.
pub fn forecast_map_vertex_cap(need: u64, bytes: usize) -> u64 {
    available_memory().map_or(u64::MAX, |(avail, _)| avail.saturating_sub(need) / 2 / bytes.max(1) as u64)
}

fn gib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 30) as f64
}

/// Ranks on this node (MPICH's `MPI_LOCALNRANKS`, Open MPI's `OMPI_COMM_WORLD_LOCAL_SIZE`; 1).
pub(super) fn local_ranks() -> usize {
    ["MPI_LOCALNRANKS", "OMPI_COMM_WORLD_LOCAL_SIZE"]
        .iter()
        .find_map(|v| std::env::var(v).ok()?.parse::<usize>().ok())
        .unwrap_or(1)
        .max(1)
}

/// Bytes this process may still take and what bounds them (`MemAvailable`, `RLIMIT_AS`, a
/// cgroup's limit: the least of them, see the module documentation); `None` where none is known.
pub fn available_memory() -> Option<(u64, String)> {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let mut found: Vec<(u64, String)> = Vec::new();
    if let Some(m) = crate::param_limits::available_memory() {
        found.push((m, "MemAvailable".into()));
    }
    if let (Some(limits), Some(status)) = (read("/proc/self/limits"), read("/proc/self/status")) {
        if let Some(left) = rlimit_as_left(&limits, &status) {
            found.push((left, "RLIMIT_AS (ulimit -v) less the address space this process maps".into()));
        }
    }
    if let Some(cg) = read("/proc/self/cgroup") {
        found.extend(cgroup_left(&cg, &|p: &str| read(p)));
    }
    found.into_iter().min_by_key(|f| f.0)
}

/// Refuses a need of `need` bytes (`what` says of what) beyond [`available_memory`], naming the
/// bound that refused it.
pub fn check(need: u64, what: &str) -> Result<(), String> {
    let avail = available_memory();
    crate::param_limits::check_memory(need, avail.as_ref().map(|a| a.0), what)
        .map_err(|e| format!("{e} (the bound here: {})", avail.map_or(String::new(), |a| a.1)))
}

/// A byte count, `None` for no limit (`max`, `unlimited`, 2^62 or more).
fn limit_value(s: &str) -> Option<u64> {
    s.trim().parse::<u64>().ok().filter(|&v| v < 1 << 62)
}

/// `RLIMIT_AS`'s soft limit (from `/proc/self/limits`) less `VmSize` (from `/proc/self/status`).
fn rlimit_as_left(limits: &str, status: &str) -> Option<u64> {
    let line = limits.lines().find(|l| l.starts_with("Max address space"))?;
    let soft = limit_value(line["Max address space".len()..].split_whitespace().next()?)?;
    let vm = status.lines().find(|l| l.starts_with("VmSize:"))?;
    let kib: u64 = vm.split_whitespace().nth(1)?.parse().ok()?;
    Some(soft.saturating_sub(kib.saturating_mul(1024)))
}

/// The memory left under every memory cgroup of `/proc/self/cgroup` (`cgroup`), its own and
/// its ancestors', read through `read` from `/sys/fs/cgroup` (v2: `0::PATH`; v1: a
/// `N:…memory…:PATH` line, mounted at `/sys/fs/cgroup/memory`). A path that is not there (a
/// cgroup namespace's root shown as a host path) is looked up from the mount's root.
fn cgroup_left(cgroup: &str, read: &dyn Fn(&str) -> Option<String>) -> Vec<(u64, String)> {
    let mut out = Vec::new();
    for line in cgroup.lines() {
        let mut f = line.splitn(3, ':');
        let (Some(_), Some(ctrl), Some(path)) = (f.next(), f.next(), f.next()) else { continue };
        let (root, files) = if ctrl.is_empty() {
            ("/sys/fs/cgroup", ["memory.max", "memory.current", "file"])
        } else if ctrl.split(',').any(|c| c == "memory") {
            ("/sys/fs/cgroup/memory", ["memory.limit_in_bytes", "memory.usage_in_bytes", "total_cache"])
        } else {
            continue;
        };
        let mut dir = format!("{root}{}", path.trim_end_matches('/'));
        if read(&format!("{dir}/{}", files[0])).is_none() {
            dir = root.to_string();
        }
        // this cgroup and its ancestors up to the mount's root
        loop {
            if let Some(limit) = read(&format!("{dir}/{}", files[0])).as_deref().and_then(limit_value) {
                let used = read(&format!("{dir}/{}", files[1])).and_then(|u| u.trim().parse::<u64>().ok());
                let cache = read(&format!("{dir}/memory.stat")).and_then(|st| {
                    st.lines().find_map(|l| l.strip_prefix(files[2])?.strip_prefix(' ')?.trim().parse::<u64>().ok())
                });
                let used = used.unwrap_or(0).saturating_sub(cache.unwrap_or(0));
                out.push((limit.saturating_sub(used), format!("{dir}/{} less the cgroup's usage", files[0])));
            }
            if dir.len() <= root.len() {
                break;
            }
            dir.truncate(dir.rfind('/').unwrap_or(root.len()).max(root.len()));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    #[test]
    fn rlimit_as_is_the_soft_limit_less_the_mapped_address_space() {
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
Max stack size            8388608              unlimited            bytes\n\
Max address space         3072000000           unlimited            bytes\n";
        let status = "Name:\tforecast\nVmPeak:\t  100 kB\nVmSize:\t   1000 kB\n";
        assert_eq!(rlimit_as_left(limits, status), Some(3_072_000_000 - 1_024_000));
        let unlimited = limits.replace("3072000000", "unlimited");
        assert_eq!(rlimit_as_left(&unlimited, status), None);
        assert_eq!(rlimit_as_left(limits, "Name: x\n"), None);
    }

    #[test]
    fn cgroup_limits_of_v2_and_v1_and_their_ancestors() {
        let files: HashMap<&str, &str> = [
            ("/sys/fs/cgroup/job/step/memory.max", "max\n"),
            ("/sys/fs/cgroup/job/step/memory.current", "100\n"),
            ("/sys/fs/cgroup/job/memory.max", "5000\n"),
            ("/sys/fs/cgroup/job/memory.current", "3000\n"),
            ("/sys/fs/cgroup/job/memory.stat", "anon 1000\nfile 1500\nfile_mapped 7\n"),
            ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "2000000\n"),
            ("/sys/fs/cgroup/memory/memory.usage_in_bytes", "1500000\n"),
            ("/sys/fs/cgroup/memory/memory.stat", "cache 5\ntotal_cache 400000\n"),
        ]
        .into_iter()
        .collect();
        let read = |p: &str| files.get(p).map(|s| s.to_string());
        // v2: the step has no limit, its parent 5000 with 3000 used of which 1500 is page cache
        let v2 = cgroup_left("0::/job/step\n", &read);
        assert_eq!(v2.iter().map(|f| f.0).collect::<Vec<_>>(), [3500]);
        assert!(v2[0].1.contains("/sys/fs/cgroup/job/memory.max"), "{v2:?}");
        // v1, its path not under the mount (a namespace's root): the mount's root
        let v1 = cgroup_left("4:memory:/process_api/abc\n3:cpuset:/\n", &read);
        assert_eq!(v1.iter().map(|f| f.0).collect::<Vec<_>>(), [2_000_000 - 1_100_000]);
        assert!(v1[0].1.contains("memory.limit_in_bytes"), "{v1:?}");
        assert!(cgroup_left("1:cpu:/\n", &read).is_empty());
        assert_eq!(limit_value("9223372036854771712"), None);
    }
}
