#!/usr/bin/env python3
"""Image means of a Mitsuba 3 scene: Mitsuba 3 `path` against forecast, over the whole image and
over fixed pixel masks, each side's standard error from K independent runs.

Two forms.

One shot (results/2026-12-07-materials.md §2, §3): Mitsuba K seeds against one forecast render,
forecast's standard error from its variance channel:
    mean-vs-mitsuba.py SCENE.xml W H [--mi-spp N] [--mi-runs K] [--spp N] [--method pt]
                       [--forecast BIN] [--out DIR] [--variant scalar_rgb]

Runs and masks (§3b): each side renders K runs into DIR, one .npy image per run (a rerun adds
runs after the last one kept; --budget stops starting runs after that many seconds):
    mean-vs-mitsuba.py mitsuba  SCENE.xml W H --spp N --runs K [--budget S] [--max-depth D]
                                [--filter box] [--seed0 S] [--tag T] [--variant llvm_ad_rgb]
    mean-vs-mitsuba.py forecast SCENE.xml W H --spp N --runs K [--budget S] [--method pt]
                                [--max-depth M] [--seed0 S] [--tag T] [--forecast BIN]
    mean-vs-mitsuba.py masks    SCENE.xml W H [--spp N]   (pilots: pt-cf seed 990, pt seed 991)
    mean-vs-mitsuba.py compare  SCENE.xml W H --a TAG --b TAG [--paired]
Every render is single-threaded (Mitsuba: `dr.set_thread_count(1)` after the scene is loaded,
since loading a scene with one thread deadlocks in 3.9.1; forecast: `--threads 1`), so CPU
seconds equal wall seconds on an idle core; both are recorded per run.

The masks (fixed before the compared runs, from pilots with their own seeds): a pixel's caustic
fraction is 1 − N/T, T a pt-cf pilot (its light paths resolve the caustics), N a `pt` pilot
filtered to the classes that end in a non-Dirac vertex lit by next-event estimation (`…DL`),
both averaged over 5×5 pixels; the rest (`…SL`, and `L`: the light seen directly) is the light
that `pt` and `path` find only by hitting the light with a BSDF sample, their heavy-tailed
noise. `direct`: fraction below 2%, and 3 px from any other pixel and from the image's border
(so that Mitsuba's Gaussian pixel filter, radius 2 px, against forecast's box moves no light
across its edge); `caustic`: fraction above 5%, grown by 3 px; `other`: the rest. `all` is the
whole image.

`compare` prints, per mask, each side's mean over its runs ± the standard error of that mean
(the runs' spread / √K), the ratio B/A ± its SE, and z; with --paired (the same seeds on both
sides, e.g. Mitsuba at two max_depth or two filters: common random numbers) the SE is that of the
per-run differences. It writes DIR/SCENE-WxH/zmap-A-B.npy, the per-pixel difference over its SE.

Needs the pip package `mitsuba` and numpy. Mitsuba renders from inside the scene's folder;
`<default>`s `width`, `height`, `spp` are passed as parameters.
"""
import argparse, glob, json, os, re, resource, subprocess, sys, time
import numpy as np
import drjit as dr
import mitsuba as mi


def scene_name(path):
    return os.path.basename(os.path.dirname(os.path.abspath(path)))


def legacy(argv):
    ap = argparse.ArgumentParser()
    ap.add_argument("scene"); ap.add_argument("width", type=int); ap.add_argument("height", type=int)
    ap.add_argument("--mi-spp", type=int, default=256); ap.add_argument("--mi-runs", type=int, default=4)
    ap.add_argument("--spp", type=int, default=1024); ap.add_argument("--method", default="pt")
    ap.add_argument("--forecast", default="target/release/forecast"); ap.add_argument("--out", default="out/mean-vs-mitsuba")
    ap.add_argument("--variant", default="scalar_rgb")
    a = ap.parse_args(argv)
    mi.set_variant(a.variant)
    os.makedirs(a.out, exist_ok=True)
    name = scene_name(a.scene)
    fc = os.path.abspath(a.forecast)
    out = os.path.abspath(a.out)
    cache = os.path.join(out, f"{name}-mitsuba-{a.width}x{a.height}-{a.mi_spp}x{a.mi_runs}.json")
    if os.path.exists(cache):
        means = json.load(open(cache))
    else:
        means = []
        cwd = os.getcwd()
        os.chdir(os.path.dirname(os.path.abspath(a.scene)))
        scene = mi.load_file(os.path.basename(a.scene), width=a.width, height=a.height, spp=a.mi_spp)
        for k in range(a.mi_runs):
            img = np.array(mi.render(scene, spp=a.mi_spp, seed=1000 + k))[..., :3]
            means.append(img.reshape(-1, 3).mean(0).tolist())
        os.chdir(cwd)
        json.dump(means, open(cache, "w"))
    means = np.array(means)
    mi_mean = means.mean(0)
    mi_se = means.std(0, ddof=1) / np.sqrt(len(means)) if len(means) > 1 else np.full(3, np.nan)
    prefix = os.path.join(out, f"{name}-{a.method}-{a.width}x{a.height}-{a.spp}")
    subprocess.run([fc, "render", a.scene, "--method", a.method, "--spp", str(a.spp), "--resolution",
                    f"{a.width}x{a.height}", "--seed", "1", "--out", prefix, "--quiet"], check=True)
    fc_img, var = read_forecast_exr(prefix + ".exr")
    n = fc_img.shape[0] * fc_img.shape[1]
    fc_mean = fc_img.reshape(-1, 3).mean(0)
    fc_se = np.sqrt(var.reshape(-1, 3).sum(0)) / n
    ratio = fc_mean / mi_mean
    ratio_se = ratio * np.sqrt((fc_se / fc_mean) ** 2 + (mi_se / mi_mean) ** 2)
    row = {"scene": name, "resolution": [a.width, a.height], "method": a.method,
           "mitsuba": {"spp": a.mi_spp, "runs": a.mi_runs, "mean": mi_mean.tolist(), "se": mi_se.tolist()},
           "forecast": {"spp": a.spp, "mean": fc_mean.tolist(), "se": fc_se.tolist()},
           "ratio": ratio.tolist(), "ratio_se": ratio_se.tolist(),
           "z": ((fc_mean - mi_mean) / np.sqrt(fc_se ** 2 + mi_se ** 2)).tolist()}
    print(json.dumps(row))


def read_forecast_exr(path):
    """forecast's EXR: RGB, and the variance of the pixel mean as var.R/G/B."""
    chans = dict(mi.Bitmap(path).split())
    return np.array(chans["<root>"])[..., :3], np.array(chans["var"])[..., :3]


def run_dir(a, tag):
    d = os.path.join(os.path.abspath(a.out), f"{scene_name(a.scene)}-{a.width}x{a.height}", tag)
    os.makedirs(d, exist_ok=True)
    return d


def next_run(d):
    done = [int(m.group(1)) for f in os.listdir(d) if (m := re.match(r"run(\d+)\.npy$", f))]
    return max(done) + 1 if done else 0


def save_run(d, k, img, info):
    np.save(os.path.join(d, f"run{k:03d}.npy"), img.astype(np.float32))
    with open(os.path.join(d, "runs.jsonl"), "a") as f:
        f.write(json.dumps({"run": k, **info}) + "\n")


def mitsuba_runs(a):
    mi.set_variant(a.variant)
    d = run_dir(a, a.tag)
    os.chdir(os.path.dirname(os.path.abspath(a.scene)))
    params = dict(width=a.width, height=a.height, spp=a.spp)
    if a.filter == "gaussian":
        scene = mi.load_file(os.path.basename(a.scene), **params)
    else:  # the same file with another pixel filter (a check of the filter's effect on the masks)
        xml = open(os.path.basename(a.scene)).read()
        xml, n = re.subn(r'<rfilter type="\w+"\s*/>', f'<rfilter type="{a.filter}"/>', xml)
        assert n == 1, "expected one <rfilter/>"
        scene = mi.load_string(xml, **params)
    integ = mi.load_dict({"type": "path", "max_depth": a.max_depth}) if a.max_depth else scene.integrator()
    dr.set_thread_count(a.threads)
    t0 = time.time()
    k0 = next_run(d)
    for k in range(k0, a.runs):
        if a.budget and time.time() - t0 > a.budget:
            break
        w, c = time.time(), time.process_time()
        acc, left, chunk = 0.0, a.spp, 0
        while left > 0:  # bounded launches: a run's spp in chunks, each its own seed
            s = min(left, a.chunk)
            img = np.array(mi.render(scene, integrator=integ, spp=s, seed=a.seed0 + 1000 * k + chunk))[..., :3]
            acc, left, chunk = acc + img * s, left - s, chunk + 1
        img = acc / a.spp
        save_run(d, k, img, {"seed0": a.seed0 + 1000 * k, "spp": a.spp, "wall_s": time.time() - w,
                             "cpu_s": time.process_time() - c, "mean": img.reshape(-1, 3).mean(0).tolist()})
        print(f"{a.tag} run {k} {time.time() - w:.1f}s mean {img.reshape(-1, 3).mean(0)}", flush=True)


def forecast_cmd(a, seed, prefix, extra=()):
    cmd = [os.path.abspath(a.forecast), "render", os.path.abspath(a.scene), "--method", a.method, "--spp", str(a.spp),
           "--resolution", f"{a.width}x{a.height}", "--seed", str(seed), "--threads", str(a.threads),
           "--emission-split", "1", "--out", prefix, "--quiet", *extra]
    if a.max_depth:
        cmd += ["--max-depth", str(a.max_depth)]
    return cmd


def forecast_runs(a):
    d = run_dir(a, a.tag)
    t0 = time.time()
    for k in range(next_run(d), a.runs):
        if a.budget and time.time() - t0 > a.budget:
            break
        prefix = os.path.join(d, "last")
        r0, w = resource.getrusage(resource.RUSAGE_CHILDREN), time.time()
        cmd = forecast_cmd(a, a.seed0 + k, prefix)
        subprocess.run(cmd, check=True, stderr=subprocess.DEVNULL)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        img, _ = read_forecast_exr(prefix + ".exr")
        save_run(d, k, img, {"seed": a.seed0 + k, "spp": a.spp, "wall_s": time.time() - w,
                             "cpu_s": (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime),
                             "mean": img.reshape(-1, 3).mean(0).tolist(), "cmd": " ".join(cmd[1:])})
        print(f"{a.tag} run {k} {time.time() - w:.1f}s mean {img.reshape(-1, 3).mean(0)}", flush=True)


def classes(tokens, last):
    """Every class of up to `tokens` D/S tokens (no two S in a row) whose last token is `last`,
    with its L."""
    out, frontier = [], [""]
    for _ in range(tokens):
        frontier = [c + t for c in frontier for t in "DS" if not (t == "S" and c.endswith("S"))]
        out += [c + "L" for c in frontier if c.endswith(last)]
    return out


def luminance(img):
    return img @ np.array([0.2126, 0.7152, 0.0722])


def box(x, r):
    """x averaged over (2r+1)² pixels (edge pixels repeated)."""
    p = np.pad(x, r, mode="edge")
    h, w = x.shape
    return sum(p[dy:dy + h, dx:dx + w] for dy in range(2 * r + 1) for dx in range(2 * r + 1)) / (2 * r + 1) ** 2


def grow(m, r):
    """m grown by r pixels (a square neighbourhood)."""
    p = np.pad(m, r, mode="constant")
    h, w = m.shape
    g = np.zeros_like(m)
    for dy in range(2 * r + 1):
        for dx in range(2 * r + 1):
            g |= p[dy:dy + h, dx:dx + w]
    return g


def make_masks(a):
    """The caustic fraction: 1 − N/T, T the pt-cf pilot (its light paths resolve the caustics),
    N a pt pilot filtered to the classes that end in a non-Dirac vertex lit by next-event
    estimation (`…DL`: low noise), both averaged over 5×5 pixels."""
    mi.set_variant("scalar_rgb")
    d = run_dir(a, "masks")
    if a.max_depth is None:
        a.max_depth = 5
    imgs = {}
    for tag, method, seed, extra in [("total", "pt-cf", 990, ()),
                                     ("nee", "pt", 991, ("--path-filter", ",".join(classes(10, "D"))))]:
        a.method = method
        prefix = os.path.join(d, f"pilot-{tag}-{a.spp}spp")
        if not os.path.exists(prefix + ".exr"):
            subprocess.run(forecast_cmd(a, seed, prefix, extra), check=True, stderr=subprocess.DEVNULL)
        imgs[tag] = box(luminance(read_forecast_exr(prefix + ".exr")[0]), 2)
    frac = np.maximum(imgs["total"] - imgs["nee"], 0) / np.maximum(imgs["total"], 1e-12)
    h, w = frac.shape
    border = np.ones((h, w), bool)
    border[3:-3, 3:-3] = False
    caustic = grow(frac > 0.05, 3)
    direct = ~grow((frac >= 0.02) | border, 3)
    other = ~caustic & ~direct
    np.savez(os.path.join(d, "masks.npz"), direct=direct, caustic=caustic, other=other, frac=frac)
    print(json.dumps({k: int(v.sum()) for k, v in dict(direct=direct, caustic=caustic, other=other).items()}))


def load_runs(d):
    files = sorted(glob.glob(os.path.join(d, "run*.npy")))
    info = [json.loads(l) for l in open(os.path.join(d, "runs.jsonl"))]
    return np.stack([np.load(f) for f in files]), info


def compare(a):
    base = os.path.join(os.path.abspath(a.out), f"{scene_name(a.scene)}-{a.width}x{a.height}")
    masks = dict(np.load(os.path.join(base, "masks", "masks.npz")))
    masks = {"all": np.ones_like(masks["direct"]), **{k: masks[k] for k in ("direct", "caustic", "other")}}
    (ra, ia), (rb, ib) = load_runs(os.path.join(base, a.a)), load_runs(os.path.join(base, a.b))
    if a.paired:
        k = min(len(ra), len(rb))
        ra, rb = ra[:k], rb[:k]
    res = {"scene": scene_name(a.scene), "resolution": [a.width, a.height], "a": a.a, "b": a.b,
           "runs": [len(ra), len(rb)], "spp": [ia[0]["spp"], ib[0]["spp"]],
           "wall_s": [sum(i["wall_s"] for i in ia[:len(ra)]), sum(i["wall_s"] for i in ib[:len(rb)])],
           "cpu_s": [sum(i["cpu_s"] for i in ia[:len(ra)]), sum(i["cpu_s"] for i in ib[:len(rb)])], "masks": {}}
    for name, m in masks.items():
        ma, mb = ra[:, m].mean(1), rb[:, m].mean(1)  # per-run mask means, (K, 3)
        ya, yb = ma.mean(0), mb.mean(0)
        sa, sb = ma.std(0, ddof=1) / np.sqrt(len(ma)), mb.std(0, ddof=1) / np.sqrt(len(mb))
        if a.paired:
            dd = mb - ma
            sd = dd.std(0, ddof=1) / np.sqrt(len(dd))
        else:
            sd = np.sqrt(sa ** 2 + sb ** 2)
        ratio = yb / ya
        res["masks"][name] = {"pixels": int(m.sum()), "mean_a": ya.tolist(), "se_a": sa.tolist(),
                              "mean_b": yb.tolist(), "se_b": sb.tolist(), "ratio": ratio.tolist(),
                              "ratio_se": ((sd if a.paired else np.sqrt(sb ** 2 + (ratio * sa) ** 2)) / ya).tolist(),
                              "z": ((yb - ya) / sd).tolist()}
    pa, pb = ra.mean(0), rb.mean(0)
    se = np.sqrt(ra.var(0, ddof=1) / len(ra) + rb.var(0, ddof=1) / len(rb))
    np.save(os.path.join(base, f"zmap-{a.a}-{a.b}.npy"), ((pb - pa) / np.maximum(se, 1e-30)).astype(np.float32))
    print(json.dumps(res))


def main():
    if len(sys.argv) > 1 and sys.argv[1].endswith(".xml"):
        return legacy(sys.argv[1:])
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=["mitsuba", "forecast", "masks", "compare"])
    ap.add_argument("scene"); ap.add_argument("width", type=int); ap.add_argument("height", type=int)
    ap.add_argument("--spp", type=int, default=256); ap.add_argument("--runs", type=int, default=16)
    ap.add_argument("--budget", type=float, default=0, help="seconds after which no new run starts")
    ap.add_argument("--max-depth", type=int, default=None,
                    help="Mitsuba: the path integrator's max_depth (default: the scene's); forecast: --max-depth")
    ap.add_argument("--filter", default="gaussian", help="Mitsuba's rfilter (the file's is gaussian)")
    ap.add_argument("--seed0", type=int, default=None); ap.add_argument("--tag", default=None)
    ap.add_argument("--variant", default="llvm_ad_rgb"); ap.add_argument("--chunk", type=int, default=256)
    ap.add_argument("--threads", type=int, default=1); ap.add_argument("--method", default="pt")
    ap.add_argument("--forecast", default="target/release/forecast"); ap.add_argument("--out", default="out/mean-vs-mitsuba")
    ap.add_argument("--a"); ap.add_argument("--b"); ap.add_argument("--paired", action="store_true")
    a = ap.parse_args()
    if a.what == "mitsuba":
        a.seed0 = 100000 if a.seed0 is None else a.seed0
        a.tag = a.tag or f"mitsuba-{a.variant}-d{a.max_depth or 'scene'}-{a.filter}-{a.spp}spp-s{a.seed0}"
        mitsuba_runs(a)
    elif a.what == "forecast":
        mi.set_variant("scalar_rgb")
        a.seed0 = 1 if a.seed0 is None else a.seed0
        a.tag = a.tag or f"{a.method}-m{a.max_depth or 'scene'}-{a.spp}spp-s{a.seed0}"
        forecast_runs(a)
    elif a.what == "masks":
        make_masks(a)
    else:
        mi.set_variant("scalar_rgb")
        compare(a)


if __name__ == "__main__":
    main()
