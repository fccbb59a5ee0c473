//! Command-line interface (clap derive). The `render` contract is fixed:
//! `forecast render SCENE [--method pt] [--spp N | --time DURATION] [--resolution WxH]
//! [--seed S] [--threads N] [--out PREFIX] [--quiet]`. Each method's flags come from its own
//! file (`integrators::MethodArgs`, flattened here); lists are typed (`--methods`, `--budgets`,
//! `--only` split by clap).
//!
//! A flag of another method is a usage error (exit 2) naming the methods it belongs to
//! ([`check_foreign_flags`], from clap's `ArgMatches::value_source`): at parse time when
//! `--method` names the method, else once the pipeline knows it (the scene's `render.method`),
//! from the explicit flags [`Cli::parse_checked`] records in `MethodArgs::explicit`. The render
//! settings and method options given (`MethodArgs::given`) win over the scene's `[render]` ones.
//!
//! The commands that reuse `render`'s options check them the same way, at parse time:
//! `reference` renders `pt` only (a flag of another method, or `--method` other than `pt`, is
//! refused); `compare` refuses `--method` (it takes `--methods`) and a method flag that none of
//! the compared methods takes; `forecast-map` accepts only the options it uses
//! ([`FORECAST_MAP_USES`], [`FORECAST_MAP_GROUPS`]), so a flag added later is refused by default.

use crate::compare::stability::StabilityConfig;
use crate::compare::CompareConfig;
use crate::integrators::{Method, MethodArgs, MethodChoice, RENDER_SETTINGS};
use crate::pipeline::RenderJob;
use clap::error::ErrorKind;
use clap::parser::ValueSource;
use clap::{ArgMatches, Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use std::path::PathBuf;
use std::time::Duration;

/// Unbiased global illumination with Caustic Forecasting (Budge, Anderson, Joy 2008).
#[derive(Parser, Debug)]
#[command(name = "forecast", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
    /// Mitsuba XML scenes: set the <default> parameter NAME ($NAME), as Mitsuba's -D.
    #[arg(short = 'D', value_name = "NAME=VALUE", global = true, value_parser = crate::scene::parse_define)]
    pub define: Vec<(String, String)>,
}

impl Cli {
    /// Parses the command line as [`Parser::try_parse`] does, then records in `render`'s
    /// `MethodArgs::explicit` the method options given explicitly and, when `--method` names the
    /// method, refuses a flag of another one ([`check_foreign_flags`]); `reference`, `compare`
    /// and `forecast-map` refuse, the same way, a flag they do not use.
    pub fn parse_checked() -> Result<Cli, clap::Error> {
        Cli::parse_checked_from(std::env::args_os())
    }

    /// [`Cli::parse_checked`] of the command line `args` (its first item is the program name).
    pub fn parse_checked_from<I, T>(args: I) -> Result<Cli, clap::Error>
    where
        I: IntoIterator<Item = T>,
        T: Into<std::ffi::OsString> + Clone,
    {
        let matches = Cli::command().try_get_matches_from(args)?;
        let mut cli = Cli::from_arg_matches(&matches)?;
        match (&mut cli.command, matches.subcommand()) {
            (Command::Render(a), Some(("render", sub))) => {
                a.method_args.explicit = explicit_method_flags(sub);
                a.method_args.given = given_flags(sub);
                if let Some(MethodChoice::Named(m)) = a.method {
                    check_foreign_flags(m, sub)?;
                }
            }
            (Command::Reference(a), Some(("reference", sub))) => {
                a.method_args.given = given_flags(sub);
                check_reference(a, sub)?
            }
            (Command::Compare(a), Some(("compare", sub))) => {
                a.render.method_args.given = given_flags(sub);
                check_compare(a, sub)?
            }
            (Command::ForecastMap(a), Some(("forecast-map", sub))) => {
                a.render.method_args.given = given_flags(sub);
                check_forecast_map(sub)?
            }
            _ => {}
        }
        Ok(cli)
    }
}

/// The ids of the method options that `matches` (a `render` command line) got from the command
/// line itself (not from a default).
pub fn explicit_method_flags(matches: &ArgMatches) -> Vec<String> {
    let ids = MethodArgs::group_flags().into_iter().flat_map(|(_, flags)| flags).map(|(id, _)| id);
    ids.filter(|id| matches.value_source(id) == Some(ValueSource::CommandLine)).collect()
}

/// The ids of the render settings and method options (`MethodArgs`'s) that `matches` got from the
/// command line itself: they win over the scene's `[render]` options.
fn given_flags(matches: &ArgMatches) -> Vec<String> {
    let cmd = MethodArgs::augment_args(clap::Command::new("render"));
    let ids = cmd.get_arguments().map(|a| a.get_id().to_string()).collect::<Vec<_>>();
    ids.into_iter().filter(|id| matches.value_source(id) == Some(ValueSource::CommandLine)).collect()
}

/// Refuses, as a usage error (exit 2), a flag given in `matches` that the method `resolved`
/// does not take: `--clusters belongs to iws-cf/pt-cf, not pt`. Runs wherever the method is
/// known: at parse time for `--method M`, after the scene (or `auto`) resolves it otherwise.
pub fn check_foreign_flags(resolved: Method, matches: &ArgMatches) -> Result<(), clap::Error> {
    match MethodArgs::foreign_flag(resolved, &explicit_method_flags(matches)) {
        Some(e) => Err(render_usage_error(e.to_string())),
        None => Ok(()),
    }
}

/// `reference` renders `pt` only: `--method` other than `pt` and a flag of another method are
/// usage errors (`--light-paths belongs to pt-cf, not pt`), as under `render --method pt`.
fn check_reference(a: &RenderArgs, matches: &ArgMatches) -> Result<(), clap::Error> {
    let other = match a.method {
        Some(MethodChoice::Named(Method::Pt)) | None => None,
        Some(MethodChoice::Named(m)) => Some(m.name()),
        Some(MethodChoice::Auto) => Some("auto"),
    };
    if let Some(name) = other {
        let msg = format!("reference renders pt only (the unbiased reference), not {name}");
        return Err(usage_error("reference", msg));
    }
    match MethodArgs::foreign_flag(Method::Pt, &explicit_method_flags(matches)) {
        Some(e) => Err(usage_error("reference", e.to_string())),
        None => Ok(()),
    }
}

/// `compare` takes `--methods`, not `--method`, and hands its method flags to every compared
/// method: a flag that none of them takes is a usage error (`--vpl-paths belongs to
/// iws/iws-pm/iws-cf, none of the compared methods pt-cf,pt`); one that some take is kept.
fn check_compare(a: &CompareArgs, matches: &ArgMatches) -> Result<(), clap::Error> {
    if matches.value_source("method") == Some(ValueSource::CommandLine) {
        let msg = "compare takes --methods M1,M2,... (the methods compared), not --method".to_string();
        return Err(usage_error("compare", msg));
    }
    let explicit = explicit_method_flags(matches);
    for (group, flags) in MethodArgs::group_flags() {
        if a.methods.iter().any(|m| m.groups().contains(&group)) {
            continue;
        }
        if let Some((_, long)) = flags.iter().find(|(id, _)| explicit.contains(id)) {
            let names = a.methods.iter().map(|m| m.name()).collect::<Vec<_>>().join(",");
            let msg = format!("{long} belongs to {}, none of the compared methods {names}", owners(group));
            return Err(usage_error("compare", msg));
        }
    }
    Ok(())
}

/// The arguments `forecast-map` uses besides [`FORECAST_MAP_GROUPS`] (clap ids): the scene,
/// the view (`--resolution`), the preprocess's seed, threads and back end, the output, the
/// progress display and the untargeted-yield comparison. Any other is refused.
pub const FORECAST_MAP_USES: &[&str] =
    &["scene", "resolution", "seed", "threads", "out", "quiet", "accel", "compare_paths", "define"];

/// The method option groups `forecast-map` uses: the Caustic Forecasting preprocess (`cf`) and
/// `iws-cf`'s `--variant` (its table and split rule, `MethodArgs::forecast_options`).
pub const FORECAST_MAP_GROUPS: &[&str] = &["cf", "iwscf"];

/// `forecast-map` runs the CF preprocess only: a flag given on the command line that it does not
/// use ([`FORECAST_MAP_USES`], [`FORECAST_MAP_GROUPS`]) is a usage error naming it.
fn check_forecast_map(matches: &ArgMatches) -> Result<(), clap::Error> {
    let groups = MethodArgs::group_flags();
    let group_of = |id: &str| groups.iter().find(|(_, f)| f.iter().any(|(i, _)| i == id)).map(|(g, _)| *g);
    let cmd = Cli::command();
    let Some(map) = cmd.find_subcommand("forecast-map") else { return Ok(()) };
    for arg in map.get_arguments() {
        let id = arg.get_id().as_str();
        let given = matches.value_source(id) == Some(ValueSource::CommandLine);
        let group = group_of(id);
        if !given || FORECAST_MAP_USES.contains(&id) || group.is_some_and(|g| FORECAST_MAP_GROUPS.contains(&g)) {
            continue;
        }
        let flag = arg.get_long().map_or_else(|| id.to_string(), |l| format!("--{l}"));
        let owner = group.map_or(String::new(), |g| format!(" (it belongs to {})", owners(g)));
        let msg = format!(
            "forecast-map does not use {flag}{owner}: it runs the Caustic Forecasting preprocess only, \
             and takes SCENE, --resolution, --seed, --threads, --out, --quiet, --accel, --compare-paths \
             and the CF options of iws-cf/pt-cf (--forecast-photons, --clusters, ..., --variant)"
        );
        return Err(usage_error("forecast-map", msg));
    }
    Ok(())
}

/// The methods that take option group `group`, as `a/b` (e.g. `iws-cf/pt-cf`).
fn owners(group: &str) -> String {
    Method::ALL.iter().filter(|m| m.groups().contains(&group)).map(|m| m.name()).collect::<Vec<_>>().join("/")
}

/// `message` as a usage error of `forecast render` (clap's format and exit status 2).
pub fn render_usage_error(message: String) -> clap::Error {
    usage_error("render", message)
}

/// `message` as a usage error of `forecast SUBCOMMAND` (clap's format and exit status 2).
pub fn usage_error(subcommand: &str, message: String) -> clap::Error {
    let mut cmd = Cli::command();
    cmd.build();
    match cmd.find_subcommand_mut(subcommand) {
        Some(sub) => sub.error(ErrorKind::ArgumentConflict, message),
        None => cmd.error(ErrorKind::ArgumentConflict, message),
    }
}

/// The `--help` heading of the output options (`--out`, `--quiet`, `--snapshots`).
const OUTPUT: &str = "Output";
/// The `--help` heading of the checkpoint options.
const CHECKPOINTS: &str = "Checkpoints";

/// The generated part of docs/options.md: every `render` option under its `--help` heading, one
/// Markdown table per heading (the flag and its value, the default, the help), the same in every
/// build: a value that this build's `--help` hides (`--accel embree` without the `embree` feature)
/// is listed too, with its own help, which says which builds have it. `tests/options_doc.rs` checks
/// docs/options.md against it.
pub fn options_markdown() -> String {
    let mut cmd = Cli::command();
    cmd.build();
    let Some(render) = cmd.find_subcommand("render") else { return String::new() };
    let mut groups: Vec<(&str, Vec<&clap::Arg>)> = Vec::new();
    for arg in render.get_arguments() {
        let help = matches!(arg.get_action(), clap::ArgAction::Help | clap::ArgAction::Version);
        if arg.is_hide_set() || arg.is_positional() || help {
            continue;
        }
        let heading = arg.get_help_heading().unwrap_or("Other options");
        match groups.iter_mut().find(|(h, _)| *h == heading) {
            Some((_, args)) => args.push(arg),
            None => groups.push((heading, vec![arg])),
        }
    }
    let mut out = String::new();
    for (heading, args) in groups {
        out += &format!("## {heading}\n\n| option | default | |\n|---|---|---|\n");
        for arg in args {
            out += &option_row(arg);
        }
        out.push('\n');
    }
    out
}

/// One option's row of [`options_markdown`]: `| `--flag VALUE` | default | help; its values |`.
fn option_row(arg: &clap::Arg) -> String {
    let id = arg.get_id().as_str();
    let name = match (arg.get_long(), arg.get_short()) {
        (Some(long), _) => format!("--{long}"),
        (None, Some(short)) => format!("-{short}"),
        (None, None) => id.to_string(),
    };
    let value = match arg.get_value_names() {
        _ if !arg.get_action().takes_values() => String::new(),
        Some(names) => format!(" {}", names.iter().map(|n| n.as_str()).collect::<Vec<_>>().join(" ")),
        None => format!(" {}", id.to_uppercase()),
    };
    let defaults: Vec<String> = arg.get_default_values().iter().map(|d| format!("`{}`", d.to_string_lossy())).collect();
    let default = match () {
        _ if !arg.get_action().takes_values() => "off".to_string(), // a switch
        _ if defaults.is_empty() => "—".to_string(),
        _ => defaults.join(", "),
    };
    let mut help = arg.get_long_help().or(arg.get_help()).map_or(String::new(), |h| markdown_text(&h.to_string()));
    if !help.is_empty() && !help.ends_with('.') {
        help.push('.'); // clap drops a one-line help's final period
    }
    let values: Vec<String> = arg
        .get_possible_values()
        .iter()
        .map(|v| match v.get_help() {
            Some(h) => format!("`{}` ({})", v.get_name(), markdown_text(&h.to_string())),
            None => format!("`{}`", v.get_name()),
        })
        .collect();
    if !values.is_empty() {
        help += &format!(" Values: {}.", values.join(", "));
    }
    format!("| `{name}{value}` | {default} | {help} |\n")
}

/// Help text as Markdown in a table cell: one line, with `|`, `<` and `*` escaped.
fn markdown_text(text: &str) -> String {
    let line = text.split_whitespace().collect::<Vec<_>>().join(" ");
    line.replace('|', "\\|").replace('<', "\\<").replace('*', "\\*")
}

/// Subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to PREFIX.exr, PREFIX.png and PREFIX.json.
    Render(RenderArgs),
    /// Compare two EXR images: RMSE, relMSE (ε = 0.01) and means.
    Diff(DiffArgs),
    /// Ray-casting and path-tracing throughput.
    Bench(BenchArgs),
    /// Regenerate the committed procedural meshes (ring, figurines) deterministically.
    GenerateScenes {
        /// Scenes directory.
        #[arg(long, default_value = "scenes")]
        dir: PathBuf,
    },
    /// Check every MPI collective with known data (run under mpirun).
    MpiSelftest,
    /// Caustic Forecasting preprocess only: caustic points coloured by cluster rank (PNG) and
    /// the preprocess figures (JSON), incl. the yield of targeted vs untargeted shooting.
    ForecastMap(ForecastMapArgs),
    /// Long `pt` reference: PREFIX.exr (mean + variance) and two independent halves
    /// PREFIX.half0/half1.exr; resumable (`--resume PREFIX`).
    Reference(RenderArgs),
    /// Time-boxed comparison of methods against a reference: tables, charts, crops, report.md/html.
    Compare(CompareArgs),
    /// Edge-case suite (scenes/stability): finishes, finite output, warnings; stability.md/html.
    Stability(StabilityArgs),
    /// Write a TOML scene as Mitsuba 3 XML (PLY meshes in OUT_STEM_meshes/ beside it).
    ExportMitsuba {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Output XML file.
        #[arg(long)]
        out: PathBuf,
    },
}

/// `render` options.
#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// Scene file (TOML, or Mitsuba XML by the .xml extension).
    pub scene: PathBuf,
    /// Rendering method; auto picks one from what the scene contains (default: the scene's
    /// [render] method, else auto).
    #[arg(long, value_parser = crate::integrators::auto::value_parser(), help_heading = RENDER_SETTINGS)]
    pub method: Option<MethodChoice>,
    /// Samples per pixel, one per pass; excludes --time (default: the scene's [render] spp or
    /// time, else 16).
    #[arg(long, value_name = "N", conflicts_with = "time", help_heading = RENDER_SETTINGS)]
    pub spp: Option<u64>,
    /// Time budget, every phase included (loading to writing; e.g. 30s, 4m); whole passes only; too short for loading and writing: refused with the time needed.
    #[arg(long, value_name = "DURATION", value_parser = parse_secs, help_heading = RENDER_SETTINGS)]
    pub time: Option<f64>,
    /// Image size (default: the scene camera's).
    #[arg(long, value_name = "WxH", value_parser = parse_resolution, help_heading = RENDER_SETTINGS)]
    pub resolution: Option<(u32, u32)>,
    /// Random seed; the image is a pure function of it (default: the scene's [render] seed, else 0).
    #[arg(long, help_heading = RENDER_SETTINGS)]
    pub seed: Option<u64>,
    /// Worker threads per process (default: all cores; with MPI, the cores over the local ranks).
    #[arg(long, value_name = "N", help_heading = RENDER_SETTINGS)]
    pub threads: Option<usize>,
    /// Output prefix: the image goes to PREFIX.exr and PREFIX.png, the report to PREFIX.json.
    #[arg(long, value_name = "PREFIX", default_value = "out/render", help_heading = OUTPUT)]
    pub out: PathBuf,
    /// No progress bar.
    #[arg(long, help_heading = OUTPUT)]
    pub quiet: bool,
    /// Write a checkpoint and the current image this often (e.g. 30s).
    #[arg(long, value_name = "DURATION", value_parser = parse_secs, help_heading = CHECKPOINTS)]
    pub checkpoint_every: Option<f64>,
    /// Continue from a checkpoint, adding new passes.
    #[arg(long, value_name = "CHECKPOINT", help_heading = CHECKPOINTS)]
    pub resume: Option<PathBuf>,
    /// Where checkpoints go, with --checkpoint-every (default: PREFIX.ckpt).
    #[arg(long, value_name = "PATH", requires = "checkpoint_every", help_heading = CHECKPOINTS)]
    pub checkpoint_path: Option<PathBuf>,
    /// Stop after this many rounds of passes, one pass per rank each (testing kill/resume; hidden).
    #[arg(long, hide = true)]
    pub max_rounds: Option<u64>,
    /// Also write the image as it stood at these times since the start, each before --time
    /// (e.g. 15s,30s,1m), to PREFIX.snap-LABEL.exr and .json (render only).
    #[arg(long, value_name = "TIMES", value_delimiter = ',', value_parser = parse_secs, help_heading = OUTPUT)]
    pub snapshots: Vec<f64>,
    /// The render settings and every method's options (flags from each method's file; a flag
    /// of another method than the one rendering is refused).
    #[command(flatten)]
    pub method_args: MethodArgs,
}

impl RenderArgs {
    /// The render job these arguments describe (as `forecast render` runs it).
    pub fn job(&self) -> RenderJob {
        RenderJob {
            scene: self.scene.clone(),
            method: self.method,
            args: self.method_args.clone(),
            spp: self.spp,
            time: self.time,
            seed: self.seed,
            resolution: self.resolution,
            out: self.out.clone(),
            progress: !self.quiet,
            checkpoint_every: self.checkpoint_every,
            resume: self.resume.clone(),
            checkpoint_path: self.checkpoint_path.clone(),
            max_rounds: self.max_rounds,
            threads: self.threads,
            defines: Vec::new(),
            snapshots: self.snapshots.clone(),
            interrupt: Default::default(),
        }
    }
}

/// `forecast-map` options (the CF options of `render` are reused).
#[derive(Args, Debug, Clone)]
pub struct ForecastMapArgs {
    /// The render options (scene, resolution, seed, CF options, `--out PREFIX`).
    #[command(flatten)]
    pub render: RenderArgs,
    /// Light paths for the untargeted-yield comparison (0: skip it; at most 2^30).
    #[arg(long, default_value_t = 1_000_000)]
    pub compare_paths: u64,
}

/// `diff` options.
#[derive(Args, Debug)]
pub struct DiffArgs {
    /// Test image.
    pub a: PathBuf,
    /// Reference image.
    pub b: PathBuf,
    /// Crop x,y,w,h.
    #[arg(long, value_parser = parse_crop)]
    pub crop: Option<(usize, usize, usize, usize)>,
    /// Write a false-colour difference PNG.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Reference half image 0 (with --half1: the noise-consistency check against B).
    #[arg(long, requires = "half1")]
    pub half0: Option<PathBuf>,
    /// Reference half image 1.
    #[arg(long, requires = "half0")]
    pub half1: Option<PathBuf>,
}

/// `bench` options.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scene (default scenes/cornell-box.toml).
    #[arg(default_value = "scenes/cornell-box.toml")]
    pub scene: PathBuf,
    /// Repetitions (the median is reported).
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Resolution for the pt measurement, WxH.
    #[arg(long, value_parser = parse_resolution, default_value = "640x640")]
    pub resolution: (u32, u32),
    /// Worker threads.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Also profile this method per phase (`--spp` passes at `--resolution`, default flags).
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    /// Passes for the `--method` profile.
    #[arg(long, default_value_t = 2)]
    pub spp: u64,
    /// Ray-tracing back end.
    #[arg(long, value_enum, default_value_t = crate::accel::AccelKind::Wide)]
    pub accel: crate::accel::AccelKind,
}

fn parse_secs(s: &str) -> Result<f64, String> {
    crate::param_limits::parse_duration(s)
}

/// A positive duration (`30s`, `4m`, `500ms`).
fn parse_budget(s: &str) -> Result<Duration, String> {
    let v = crate::param_limits::parse_duration(s)?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("budget `{s}` must be a positive duration"));
    }
    Ok(Duration::from_secs_f64(v))
}

/// Parses `WxH`.
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (a, b) =
        s.split_once(['x', 'X']).ok_or_else(|| format!("bad resolution `{s}` (expected WxH, e.g. 640x480)"))?;
    let w: u32 = a.trim().parse().map_err(|_| format!("bad width in `{s}`"))?;
    let h: u32 = b.trim().parse().map_err(|_| format!("bad height in `{s}`"))?;
    if w == 0 || h == 0 || w > 65536 || h > 65536 {
        return Err(format!("resolution `{s}` must be 1..=65536 per axis"));
    }
    Ok((w, h))
}

fn parse_crop(s: &str) -> Result<(usize, usize, usize, usize), String> {
    let v: Vec<usize> = s
        .split(',')
        .map(|x| x.trim().parse::<usize>().map_err(|_| format!("bad crop `{s}` (expected x,y,w,h)")))
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [x, y, w, h] if *w > 0 && *h > 0 => Ok((*x, *y, *w, *h)),
        _ => Err(format!("bad crop `{s}` (expected x,y,w,h with w,h > 0)")),
    }
}

/// `compare` options (the render options are reused; `--out` is the report directory).
#[derive(Args, Debug, Clone)]
pub struct CompareArgs {
    /// Render options: scene, resolution, threads, method options; `--out DIR` is the output directory.
    #[command(flatten)]
    pub render: RenderArgs,
    /// Methods to compare, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "pt,iws-pm,iws-cf,pt-cf")]
    pub methods: Vec<Method>,
    /// Time budgets, comma-separated (preprocess included).
    #[arg(long, value_delimiter = ',', value_parser = parse_budget, default_value = "30s,1m,2m,4m")]
    pub budgets: Vec<Duration>,
    /// Seeds per method and budget (seed, seed+1, ...).
    #[arg(long, default_value_t = 3)]
    pub seeds: u64,
    /// Reference image (from `forecast reference`).
    #[arg(long)]
    pub reference: PathBuf,
    /// Render each (method, seed) once, at the largest budget, and measure the smaller budgets
    /// from snapshots of that run (`render --snapshots`) instead of separate runs.
    #[arg(long)]
    pub single_run: bool,
}

impl CompareArgs {
    /// The comparison these arguments describe.
    pub fn config(&self) -> CompareConfig {
        CompareConfig {
            base: self.render.job(),
            methods: self.methods.clone(),
            budgets: self.budgets.iter().map(Duration::as_secs_f64).collect(),
            seeds: self.seeds,
            reference: self.reference.clone(),
            out: self.render.out.clone(),
            single_run: self.single_run,
        }
    }
}

/// `stability` options.
#[derive(Args, Debug, Clone)]
pub struct StabilityArgs {
    /// Directory of the suite's scenes.
    #[arg(long, default_value = "scenes/stability")]
    pub scenes: PathBuf,
    /// Resolution override, WxH (default: the scenes' 64x64).
    #[arg(long, value_parser = parse_resolution)]
    pub resolution: Option<(u32, u32)>,
    /// Time box per run.
    #[arg(long, value_parser = parse_secs, default_value = "3s")]
    pub time_per_run: f64,
    /// Time of each scene's pt reference (default: 4 x --time-per-run).
    #[arg(long, value_parser = parse_secs)]
    pub reference_time: Option<f64>,
    /// Methods, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "pt,iws,iws-pm,iws-cf,pt-cf")]
    pub methods: Vec<Method>,
    /// Only these cases, comma-separated (default: all).
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// Worker threads.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Output directory.
    #[arg(long, default_value = "out/stability")]
    pub out: PathBuf,
}

impl StabilityArgs {
    /// The suite run these arguments describe.
    pub fn config(&self) -> StabilityConfig {
        StabilityConfig {
            scenes: self.scenes.clone(),
            resolution: self.resolution,
            time_per_run: self.time_per_run,
            reference_time: self.reference_time.unwrap_or(4.0 * self.time_per_run),
            methods: self.methods.clone(),
            only: self.only.iter().map(|t| t.trim().to_string()).filter(|t| !t.is_empty()).collect(),
            threads: self.threads,
            out: self.out.clone(),
        }
    }
}
