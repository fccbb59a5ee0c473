//! `--method auto`, the default when neither the command line nor the scene names a method:
//! "model no more than a scene needs". [`choose`] picks a method from what the scene contains,
//! by a rule whose evidence (the equal-time tables) is in `docs/auto.md`:
//!
//! 1. No Dirac (mirror/glass) objects: `pt`, the cheapest method that is unbiased for the scene.
//!    Dirac objects lit by point lights only: `pt-cf`, whose light paths (issue #34) are the only
//!    technique that samples their caustics (L S+ D); the reason says so.
//! 2. Caustics from area lights in a closed room of Lambertian surfaces (every non-Dirac surface
//!    diffuse, [`enclosure`] ≥ [`CLOSED_ROOM`]): `iws-cf`, whose VPLs carry the room's diffuse
//!    interreflection (`cornell-box`: 0.64–0.71× `pt`'s whole-image RMSE at 1 and 4 min, `pt-cf`
//!    0.95–0.98×).
//! 3. Other caustics from area lights (open scenes, glossy receivers): `pt-cf` (`ring`: 0.38–0.50×
//!    `pt`, `iws-cf` 0.44–0.53×; `figurines`: 1.07–1.08×, `iws-cf` 1.26–1.38×).
//!
//! Invariants: a pure function of the scene (never of time, seed or machine); every choice is
//! unbiased for what it renders; the reason names the rule and the figures it rests on.

use super::Method;
use crate::scene::{Material, Scene, NO_EMITTER};

/// The name of the automatic choice (`--method auto`, `[render] method = "auto"`).
pub const AUTO: &str = crate::scene::AUTO_METHOD;

/// The [`enclosure`] from which a scene counts as a closed room: four of a box's six sides of
/// diffuse surface (a ground plane under an open sky is at most 1/2, a box open on one side 5/6).
pub const CLOSED_ROOM: f32 = 2.0 / 3.0;

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

/// Diffuse surface area over the surface area of the scene's bounding box: ≈ 1 for a closed
/// room, 5/6 for a box open on one side, at most 1/2 for a ground plane. A room made of an
/// inward sphere reads as about 1/2 (its box is larger than the sphere): such a scene gets
/// `pt-cf`, which is unbiased all the same.
pub fn enclosure(scene: &Scene) -> f32 {
    let d = scene.bounds.1 - scene.bounds.0;
    let box_area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    if !(box_area.is_finite() && box_area > 0.0) {
        return 0.0;
    }
    scene.non_specular_area() / box_area
}

/// True when every non-Dirac, non-emitting surface of the scene is Lambertian.
fn lambertian_only(scene: &Scene) -> bool {
    let diffuse = |m: u32, e: u32| {
        let m = &scene.materials[m as usize];
        e != NO_EMITTER || m.is_dirac() || m.is_black() || matches!(m, Material::Diffuse { .. })
    };
    scene.triangles.iter().all(|t| diffuse(t.material, t.emitter))
        && scene.spheres.iter().all(|s| diffuse(s.material, s.emitter))
}

/// True when the scene has a Dirac (mirror, conductor, glass) primitive.
fn has_dirac(scene: &Scene) -> bool {
    scene.dirac_bounds().is_some()
}

/// The note on caustics lit by point lights, when the scene has both point lights and Dirac
/// objects.
fn point_light_note(scene: &Scene) -> &'static str {
    if has_dirac(scene) && !scene.point_lights.is_empty() {
        "; caustics lit by point lights (L S+ D) are rendered only by pt-cf's light paths (issue #34)"
    } else {
        ""
    }
}

/// The method `auto` picks for `scene`, and why (the rule of the module docs).
pub fn choose(scene: &Scene) -> (Method, String) {
    let note = point_light_note(scene);
    if !has_dirac(scene) {
        return (Method::Pt, "no mirror or glass objects: pt, the cheapest unbiased method".into());
    }
    if scene.emitters.is_empty() {
        let why = "mirror/glass objects lit by point lights only: pt-cf, whose light paths render their caustics \
                   (L S+ D; pt and iws-cf cannot sample them)"
            .to_string();
        return (Method::PtCf, why);
    }
    let closed = enclosure(scene);
    if lambertian_only(scene) && closed >= CLOSED_ROOM {
        let why = format!(
            "caustics from area lights in a closed room of diffuse surfaces (enclosure {closed:.2} >= {CLOSED_ROOM:.2}): \
             iws-cf, whose VPLs carry the diffuse interreflection (cornell-box: 0.64-0.71x pt's whole-image RMSE \
             at equal time, pt-cf 0.95-0.98x; docs/auto.md){note}"
        );
        return (Method::IwsCf, why);
    }
    let what = if lambertian_only(scene) {
        format!("an open scene (enclosure {closed:.2} < {CLOSED_ROOM:.2})")
    } else {
        "glossy surfaces".to_string()
    };
    let why = format!(
        "caustics from area lights, {what}: pt-cf, the best unbiased caustic method there by the equal-time \
         tables (ring: 0.38-0.50x pt's whole-image RMSE, iws-cf 0.44-0.53x; figurines: 1.07-1.08x, iws-cf \
         1.26-1.38x; docs/auto.md){note}"
    );
    (Method::PtCf, why)
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
            let by = if requested.is_some() {
                "--method auto"
            } else {
                "no --method; the scene's method is auto, its default"
            };
            (m, format!("auto ({by}): {why}"))
        }
    })
}
