//! Mitsuba XML `bumpmap` and the shading tangent in the scene model: what the reader makes of each
//! accepted form (both nestings with `twosided`, a texture by `<ref>` or without a name, the
//! default `scale`, anisotropic BSDFs flagged for their tangent), and the typed error, with its
//! line and key, for each refused one. The images are `tests/mitsuba_plugins.rs`'s.

mod common;
use common::root;
use forecast::scene::mitsuba::load_str;
use forecast::scene::{BumpMap, Scene, SceneError};
use std::path::PathBuf;

fn dir() -> PathBuf {
    root().join("tests/scenes/mitsuba-plugins")
}

const HEIGHT: &str = r#"<texture name="height" type="bitmap"><string name="filename" value="height32.png"/><boolean name="raw" value="true"/></texture>"#;
const DIFFUSE: &str = r#"<bsdf type="diffuse"/>"#;
const NORMALS: &str = r#"<texture name="normalmap" type="bitmap"><string name="filename" value="normals32.png"/><boolean name="raw" value="true"/></texture>"#;

/// A one-shape scene whose shape has `bsdf` (the BSDF element on line 5), with `top` before it.
fn scene(top: &str, bsdf: &str) -> String {
    format!(
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/><film type=\"hdrfilm\"><integer name=\"width\" value=\"8\"/>\
         <integer name=\"height\" value=\"8\"/></film></sensor>\n{top}\n<shape type=\"rectangle\">\n{bsdf}\n</shape>\n\
         <shape type=\"sphere\"><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter><transform name=\"to_world\"><translate z=\"3\"/></transform></shape>\n\
         </scene>\n"
    )
}

fn load(top: &str, bsdf: &str) -> Result<Scene, SceneError> {
    load_str(&scene(top, bsdf), "bump.xml", &dir(), &[])
}

/// The surface of the rectangle (the first material the shapes name).
fn surface(s: &Scene) -> forecast::scene::Surface {
    s.surfaces[s.triangles[0].material as usize].clone()
}

#[test]
fn the_plugin_scenes_read_as_written() {
    let s = forecast::scene::load(&dir().join("bumpmap-diffuse.xml")).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // back wall bumpmap(diffuse); bumpmap(twosided(..)) panel; twosided(bumpmap(..)) and
    // bumpmap(twosided(..)) turned away: (scale, two_sided, map_in_twosided)
    let mut bumps: Vec<(f32, bool, bool)> =
        s.surfaces.iter().filter_map(|f| f.bumpmap.map(|b| (b.scale, f.two_sided, f.map_in_twosided))).collect();
    bumps.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(bumps, [(0.15, true, false), (0.3, true, false), (0.3, true, true), (0.5, false, false)]);
    for name in ["roughconductor-aniso", "roughdielectric-aniso", "aniso-maps"] {
        let s = forecast::scene::load(&dir().join(format!("{name}.xml"))).unwrap();
        let aniso: Vec<_> = s.surfaces.iter().filter(|f| f.anisotropic).collect();
        assert!(!aniso.is_empty() && aniso.iter().all(|f| !f.is_constant()), "{name}");
    }
    let iso = forecast::scene::load(&dir().join("roughconductor-ggx.xml")).unwrap();
    assert!(iso.surfaces.iter().all(|f| !f.anisotropic && f.bumpmap.is_none()));
}

#[test]
fn accepted_forms() {
    // any texture name, or none; scale defaults to 1
    for tex in [HEIGHT.replace("name=\"height\" ", ""), HEIGHT.replace("\"height\"", "\"arbitrary\"")] {
        let s = load("", &format!("<bsdf type=\"bumpmap\">{DIFFUSE}{tex}</bsdf>")).unwrap();
        let f = surface(&s);
        assert_eq!(f.bumpmap.map(|b| b.scale), Some(1.0));
        assert!(!f.two_sided && !f.map_in_twosided, "{f:?}");
        // every parameter read (the one warning is the emitter's dropped BSDF)
        assert!(!s.warnings.iter().any(|w| w.contains("ignored") || w.contains("`bumpmap`")), "{:?}", s.warnings);
    }
    // a top-level texture by `<ref>`, a BSDF by `<ref>`, inside twosided
    let top = r#"<texture type="bitmap" id="h"><string name="filename" value="height32.png"/></texture><bsdf type="diffuse" id="d"/>"#;
    let s = load(top, r#"<bsdf type="twosided"><bsdf type="bumpmap"><ref id="h"/><ref id="d"/><float name="scale" value="0.25"/></bsdf></bsdf>"#)
        .unwrap();
    let f = surface(&s);
    assert_eq!(f.bumpmap.map(|b| b.scale), Some(0.25));
    assert!(f.two_sided && f.map_in_twosided);
    // twosided inside: the map sees the real direction
    let s =
        load("", &format!("<bsdf type=\"bumpmap\">{HEIGHT}<bsdf type=\"twosided\">{DIFFUSE}</bsdf></bsdf>")).unwrap();
    let f = surface(&s);
    assert!(f.two_sided && !f.map_in_twosided && f.bumpmap.is_some());
    // a normal map inside twosided is mirrored from behind too
    let nm = format!("<bsdf type=\"normalmap\">{NORMALS}{DIFFUSE}</bsdf>");
    let f = surface(&load("", &format!("<bsdf type=\"twosided\">{nm}</bsdf>")).unwrap());
    assert!(f.normalmap.is_some() && f.map_in_twosided);
    // an anisotropic BSDF under the map keeps its flag
    let rough =
        r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf>"#;
    let f = surface(&load("", &format!("<bsdf type=\"bumpmap\">{HEIGHT}{rough}</bsdf>")).unwrap());
    assert!(f.anisotropic && matches!(f.bumpmap, Some(BumpMap { scale: 1.0, .. })));
}

/// Each refused form is an error naming the file, the line and the key.
#[test]
fn refused_forms_name_the_line_and_key() {
    let checker = r#"<texture name="height" type="checkerboard"/>"#;
    let nm = format!("<bsdf type=\"normalmap\">{NORMALS}{DIFFUSE}</bsdf>");
    let bump = format!("<bsdf type=\"bumpmap\">{HEIGHT}{DIFFUSE}</bsdf>");
    let cases: Vec<(String, &str, &str)> = vec![
        (format!("<bsdf type=\"bumpmap\">{DIFFUSE}</bsdf>"), "bumpmap.texture", "exactly one nested texture"),
        (
            format!("<bsdf type=\"bumpmap\"><string name=\"filename\" value=\"height32.png\"/>{DIFFUSE}</bsdf>"),
            "bumpmap.texture",
            "Mitsuba 2's `filename` form",
        ),
        (format!("<bsdf type=\"bumpmap\">{HEIGHT}{HEIGHT}{DIFFUSE}</bsdf>"), "bumpmap.texture", "exactly one"),
        (format!("<bsdf type=\"bumpmap\">{HEIGHT}</bsdf>"), "bumpmap.bsdf", "exactly one nested BSDF"),
        (format!("<bsdf type=\"bumpmap\">{checker}{DIFFUSE}</bsdf>"), "bumpmap.height", "no gradient"),
        (format!("<bsdf type=\"bumpmap\">{HEIGHT}{nm}</bsdf>"), "bumpmap.bsdf", "not supported"),
        (format!("<bsdf type=\"bumpmap\">{HEIGHT}{bump}</bsdf>"), "bumpmap.bsdf", "not supported"),
        (format!("<bsdf type=\"normalmap\">{NORMALS}{bump}</bsdf>"), "normalmap.bsdf", "not supported"),
        (
            format!("<bsdf type=\"bumpmap\">{HEIGHT}{DIFFUSE}<boolean name=\"flip_invalid_normals\" value=\"false\"/></bsdf>"),
            "bumpmap.flip_invalid_normals",
            "default, true",
        ),
        (
            format!("<bsdf type=\"bumpmap\">{HEIGHT}{DIFFUSE}<float name=\"scale\" value=\"x\"/></bsdf>"),
            "bumpmap.scale",
            "not a finite number",
        ),
    ];
    for (bsdf, key, what) in cases {
        let e = load("", &bsdf).err().unwrap_or_else(|| panic!("{bsdf}: accepted"));
        assert_eq!((e.file.as_str(), e.line, e.key.as_str()), ("bump.xml", 5, key), "{bsdf}: {e}");
        assert!(e.message.contains(what), "{bsdf}: {e}");
    }
}
