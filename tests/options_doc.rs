//! docs/options.md's option reference is generated from the clap definitions
//! (`forecast::cli::options_markdown`): the part between its markers must be exactly what the
//! code generates. After changing an option, regenerate it with
//! `FORECAST_BLESS=1 cargo test --release --test options_doc`.

use std::path::Path;

const BEGIN: &str = "<!-- BEGIN GENERATED OPTIONS";
const END: &str = "<!-- END GENERATED OPTIONS -->";

#[test]
fn options_md_is_generated_from_the_clap_definitions() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/options.md");
    let doc = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let begin = doc.find(BEGIN).unwrap_or_else(|| panic!("docs/options.md has no `{BEGIN}` marker"));
    let body = begin + doc[begin..].find('\n').expect("a line after the begin marker") + 1;
    let end = body + doc[body..].find(END).unwrap_or_else(|| panic!("docs/options.md has no `{END}` marker"));
    let generated = format!("\n{}", forecast::cli::options_markdown());
    if doc[body..end] == generated {
        return;
    }
    if std::env::var_os("FORECAST_BLESS").is_some_and(|v| v == "1") {
        std::fs::write(&path, format!("{}{generated}{}", &doc[..body], &doc[end..])).unwrap();
        eprintln!("docs/options.md regenerated");
        return;
    }
    let first = doc[body..end].lines().zip(generated.lines()).position(|(a, b)| a != b);
    panic!(
        "docs/options.md differs from the options the code defines (first differing line of the \
         generated part: {first:?}); regenerate it with `FORECAST_BLESS=1 cargo test --release --test \
         options_doc`\n--- generated:\n{generated}"
    );
}

/// The reference covers every heading of `render --help` and lists `--accel embree` in every
/// build, as the feature it needs.
#[test]
fn the_reference_is_grouped_and_independent_of_the_build() {
    let md = forecast::cli::options_markdown();
    for heading in
        ["## Render settings", "## Output", "## Checkpoints", "## Caustic Forecasting options (iws-cf, pt-cf)"]
    {
        assert!(md.contains(heading), "no `{heading}` in:\n{md}");
    }
    assert!(md.contains("`embree` (Intel Embree 3, in builds with --features embree only)"), "{md}");
    assert!(!md.contains("max-rounds"), "a hidden option is listed:\n{md}");
}

/// The help is in words a user reads: no Rust paths or rustdoc links (`integrators::pt`,
/// ``[`SLOTS`]``, `TableKind::Dual`).
#[test]
fn the_help_names_nothing_internal() {
    let mut cmd = <forecast::cli::Cli as clap::CommandFactory>::command();
    let help = cmd.find_subcommand_mut("render").expect("render").render_long_help().to_string();
    let md = forecast::cli::options_markdown();
    for text in [&help, &md] {
        for internal in ["::", "[`", "`]", "integrators", "crate"] {
            assert!(!text.contains(internal), "`{internal}` in:\n{text}");
        }
    }
}

/// `render --help` offers only the back ends the build has: no `embree` without the feature.
#[test]
fn the_help_offers_only_the_builds_back_ends() {
    let mut cmd = <forecast::cli::Cli as clap::CommandFactory>::command();
    let help = cmd.find_subcommand_mut("render").expect("render").render_long_help().to_string();
    assert_eq!(help.contains("embree"), cfg!(feature = "embree"), "{help}");
}
