//! `--method auto`, the default when neither the command line nor the scene names a method:
//! "model no more than a scene needs". [`choose`] picks a method from what the scene contains,
//! by a rule whose evidence (the equal-time tables) is in `docs/auto.md`:
//!
//! 1. No Dirac (mirror/glass) objects: `pt`, the cheapest method that is unbiased for the scene.
//! 2. Dirac objects: `pt-cf`. Lit by point lights only, its light paths (issue #34) are the only
//!    technique that samples their caustics (L S+ D); the reason says so. Lit by area lights, it
//!    has the best whole image of the unbiased methods at equal time since its light paths
//!    (`cornell-box` 1 min: 0.49× `pt`'s whole-image RMSE, `iws-cf` 0.64×; `ring`, before the light
//!    paths: 0.38–0.50×, `iws-cf` 0.44–0.53×). Until 2026-12-03 closed rooms of diffuse walls went to `iws-cf`; the
//!    light paths moved that line (`results/2026-12-03-auto-rule.md`). Glossy receivers change
//!    nothing; the reason says so (docs/auto.md).
//!
//! Invariants: a pure function of the scene (never of time, seed or machine); every choice is
//! unbiased for what it renders; the reason is one short line naming the rule
//! ([`REASON_MAX_CHARS`], printed on every run), and [`evidence`] the figures it rests on (the
//! report's `method_evidence`).

use super::Method;
use crate::scene::Scene;

/// The name of the automatic choice (`--method auto`, `[render] method = "auto"`).
pub const AUTO: &str = crate::scene::AUTO_METHOD;

/// What `--method` (or the scene's `[render] method`) asks for: a method, or [`AUTO`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MethodChoice {
    /// Let [`choose`] pick from the scene.
    Auto,
    /// This method.
    Named(Method),
}

impl From<Method> for MethodChoice {
    fn from(m: Method) -> Self {
        MethodChoice::Named(m)
    }
}

impl MethodChoice {
    /// Parses `auto` or a method name.
    pub fn from_name(s: &str) -> Option<MethodChoice> {
        if s.eq_ignore_ascii_case(AUTO) {
            return Some(MethodChoice::Auto);
        }
        Method::from_name(s).map(MethodChoice::Named)
    }

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            MethodChoice::Auto => AUTO,
            MethodChoice::Named(m) => m.name(),
        }
    }

    /// Every name `--method` takes: `auto`, then the methods in registry order.
    pub fn names() -> impl Iterator<Item = &'static str> {
        std::iter::once(AUTO).chain(Method::ALL.iter().map(|m| m.name()))
    }
}

/// The clap value parser of `--method`: `auto` or a method name (listed in `--help`).
pub fn value_parser() -> impl clap::builder::TypedValueParser<Value = MethodChoice> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(MethodChoice::names())
        .map(|s| MethodChoice::from_name(&s).unwrap_or(MethodChoice::Auto))
}

/// True when the scene has a Dirac (mirror, conductor, glass) primitive.
fn has_dirac(scene: &Scene) -> bool {
    scene.dirac_bounds().is_some()
}

/// The note on caustics lit by point lights, when the scene has both point lights and Dirac
/// objects.
fn point_light_note(scene: &Scene) -> &'static str {
    if has_dirac(scene) && !(scene.point_lights.is_empty() && scene.directional_lights.is_empty()) {
        "; caustics lit by point, spot or directional lights (L S+ D) are rendered only by pt-cf's light paths (issue #34)"
    } else {
        ""
    }
}

/// The note on glossy receivers, where the scene has a glossy material (docs/auto.md).
fn glossy_note(scene: &Scene) -> &'static str {
    use crate::bsdf::Material;
    let glossy = |m: &Material| {
        matches!(
            m,
            Material::Glossy { .. }
                | Material::RoughConductor(_)
                | Material::RoughPlastic(_)
                | Material::RoughDielectric(_)
        )
    };
    if scene.materials.iter().any(glossy) {
        "; its glossy receivers are guided, a lone microfacet lobe only from roughness --guide-min-alpha (0.15: below it \
         guiding did not pay; results/2026-12-07-glossy-caustics.md)"
    } else {
        ""
    }
}

/// What lights a scene's caustics, for the reason: area lights, else its environment.
fn lit_by(scene: &Scene) -> &'static str {
    if scene.emitters.is_empty() {
        "an environment"
    } else {
        "area lights"
    }
}

/// The note on an environment light, where the scene has one: the one scene measured.
fn environment_note(scene: &Scene) -> &'static str {
    if scene.environment.is_some() {
        "; lit by an environment, measured on sms-pool only (60 s: 0.81x pt's noise on the pool floor, 1.08x on \
         the whole image; results/2026-12-07-pool.md)"
    } else {
        ""
    }
}

/// The longest [`choose`] reason: one line of the terminal's `method:` line. The figures it rests
/// on are [`evidence`]'s (the report's `method_evidence`, and `docs/auto.md`).
pub const REASON_MAX_CHARS: usize = 110;

/// The method `auto` picks for `scene`, and why in one short line (the rule of the module docs;
/// the figures and the notes are [`evidence`]'s).
pub fn choose(scene: &Scene) -> (Method, String) {
    if !has_dirac(scene) {
        return (Method::Pt, "no mirror or glass objects: pt, the cheapest unbiased method".into());
    }
    if scene.emitters.is_empty() && scene.environment.is_none() {
        return (
            Method::PtCf,
            "mirror/glass lit by point lights only (point, spot, directional): pt-cf, its light paths render L S+ D"
                .into(),
        );
    }
    (Method::PtCf, format!("caustics from {}: pt-cf, the best unbiased whole image at equal time", lit_by(scene)))
}

/// What [`choose`]'s pick for `scene` rests on: the equal-time figures of `docs/auto.md` and the
/// notes on the scene's point lights and glossy receivers (the report's `method_evidence`).
pub fn evidence(scene: &Scene) -> String {
    let note = point_light_note(scene);
    if !has_dirac(scene) {
        return "no mirror or glass objects: pt, the cheapest unbiased method (every other method adds work that \
                only caustics repay; docs/auto.md)"
            .into();
    }
    if scene.emitters.is_empty() && scene.environment.is_none() {
        return "mirror/glass objects lit by point lights only (point, spot or directional): pt-cf, whose light paths \
                render their caustics (L S+ D; pt and iws-cf cannot sample them; docs/auto.md)"
            .to_string();
    }
    format!(
        "caustics from {}: pt-cf, the best whole image of the unbiased methods at equal time \
         (cornell-box 1 min: 0.49x pt's whole-image RMSE, iws-cf 0.64x; ring, before the light paths: 0.38-0.50x, \
         iws-cf 0.44-0.53x; docs/auto.md){note}{}{}",
        lit_by(scene),
        glossy_note(scene),
        environment_note(scene)
    )
}

/// [`evidence`] where `requested` (else the scene's `[render] method`) is `auto`; `None` where a
/// method is named (the reason then says by whom).
pub fn resolve_evidence(requested: Option<MethodChoice>, scene: &Scene) -> Option<String> {
    let choice = requested.or_else(|| MethodChoice::from_name(&scene.render.method))?;
    (choice == MethodChoice::Auto).then(|| evidence(scene))
}

/// The method of a render: `requested` (the command line's `--method`) first, else the scene's
/// `[render] method`, else `auto`; with the reason the report and the terminal give.
pub fn resolve(requested: Option<MethodChoice>, scene: &Scene) -> Result<(Method, String), String> {
    let from_scene = || {
        MethodChoice::from_name(&scene.render.method)
            .ok_or_else(|| format!("{}: method `{}` is not available", scene.path, scene.render.method))
    };
    let (choice, source) = match requested {
        Some(c) => (c, "--method"),
        None => (from_scene()?, "the scene's [render] method"),
    };
    Ok(match choice {
        MethodChoice::Named(m) => (m, format!("{} named by {source}", m.name())),
        MethodChoice::Auto => {
            let (m, why) = choose(scene);
            let by = if requested.is_some() { "--method auto" } else { "the default" };
            (m, format!("auto ({by}): {why}"))
        }
    })
}
