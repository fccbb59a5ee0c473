//! The TOML format's Mitsuba materials (issue #61): `tests/scenes/toml-materials/every-material.toml`
//! (every new type, a texture in every kind of slot, normal maps, a one-sided BSDF) loads into the
//! materials, surfaces and textures it says and renders with `pt`; `export-mitsuba` writes it as
//! Mitsuba 3 XML (images copied beside it) that loads back to the same materials, surfaces,
//! textures (every texel) and scene, rendering bit for bit the same image; TOML and XML give the
//! same material for the same plugin with no parameters (Mitsuba's defaults, written once in
//! `scene::plugins`); the export never overwrites an input image. The refused inputs (file, line,
//! key) are tests/bad_scenes.rs's.

mod common;
use common::{render_passes, root, scene_fingerprint as fingerprint, texture_print, tmp_dir};
use forecast::accel::World;
use forecast::bsdf::Slot;
use forecast::integrators::{Integrator, Method, MethodArgs};
use forecast::scene::{Material, Scene};
use forecast::texture::Texture;
use std::path::{Path, PathBuf};

fn every_material() -> PathBuf {
    root().join("tests/scenes/toml-materials/every-material.toml")
}

/// `pt` with a cap of 64 vertices.
fn pt(w: &World) -> Box<dyn Integrator> {
    let mut o = MethodArgs::default();
    o.settings.max_depth = Some(64);
    let bytes = Method::Pt.preprocess(w, &o, 1).unwrap();
    Method::Pt.build(w, &o, &bytes).unwrap()
}

/// The scene's material by its TOML name (materials are registered in name order after the
/// black material 0).
fn by_name<'s>(s: &'s Scene, src: &str, name: &str) -> (usize, &'s Material) {
    let doc: toml::Table = toml::from_str(src).unwrap();
    let names: Vec<&String> = doc["materials"].as_table().unwrap().keys().collect();
    let i = 1 + names.iter().position(|n| *n == name).unwrap_or_else(|| panic!("no material {name}"));
    (i, &s.materials[i])
}

#[test]
fn every_material_loads_as_written_and_renders() {
    let path = every_material();
    let src = std::fs::read_to_string(&path).unwrap();
    let s = forecast::scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let m = |name: &str| by_name(&s, &src, name);
    let surface = |name: &str| &s.surfaces[m(name).0];
    // each type is its Mitsuba plugin's Material
    assert!(matches!(m("ceiling").1, Material::Diffuse { albedo } if *albedo == forecast::math::Vec3::splat(0.7)));
    assert!(matches!(m("right").1, Material::Conductor { .. }));
    assert!(matches!(m("floor").1, Material::Plastic(_)));
    assert!(matches!(m("gold").1, Material::RoughConductor(_)));
    assert!(matches!(m("coated").1, Material::RoughPlastic(_)));
    assert!(matches!(m("pane").1, Material::ThinDielectric(_)));
    assert!(matches!(m("bumpy_glass").1, Material::Glass { ior } if *ior == 1.5 / 1.000277));
    let Material::RoughDielectric(d) = m("frosted").1 else { panic!("frosted: {:?}", m("frosted").1) };
    assert_eq!((d.distribution.alpha_u, d.distribution.alpha_v, d.eta), (0.05, 0.2, 1.5046));
    // a texture in each kind of slot, on the material that names it
    for (name, slot) in [
        ("back", Slot::Reflectance),
        ("floor", Slot::DiffuseReflectance),
        ("right", Slot::SpecularReflectance),
        ("pane", Slot::SpecularTransmittance),
        ("gold", Slot::Alpha),
    ] {
        let t = &surface(name).textures;
        assert!(t.len() == 1 && t[0].slot == slot, "{name}: {t:?}");
    }
    // the textured parameter holds its texture's mean until a hit looks it up
    let back = &s.textures[surface("back").textures[0].texture as usize];
    assert!(matches!(m("back").1, Material::Diffuse { albedo } if albedo.x == back.mean()));
    // sides: TOML materials are two-sided unless they say so; the dielectrics scatter from both
    for (name, two) in [("left", false), ("back", true), ("coated", true), ("pane", true), ("frosted", true)] {
        assert_eq!(surface(name).two_sided, two, "{name}");
    }
    // the normal maps: raw (linear) bitmaps, after the material's own textures
    for name in ["bumpy_glass", "coated"] {
        let t = surface(name).normalmap.unwrap_or_else(|| panic!("{name} has no normal map")) as usize;
        let Texture::Bitmap(b) = &s.textures[t] else { panic!("{name}: not a bitmap") };
        assert!(b.image.raw() && b.image.path().ends_with("normals32.png"), "{name}");
    }
    // 5 slot textures (the floor's checkerboard holds its bitmap inside) and 2 normal maps
    assert_eq!(s.textures.len(), 7);
    // the images are inputs that no output may overwrite
    assert!(s.mesh_files.iter().any(|f| f.ends_with("tex8.exr")));
    // renders: finite, and lit
    let w = World::build(s).unwrap();
    let f = render_passes(&w, pt(&w).as_mut(), 16, 16, 2, 1);
    let mean = f.mean();
    assert!(mean.iter().flatten().all(|v| v.is_finite()));
    assert!(mean.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() > 0.0);
}

#[test]
fn export_loads_back_the_same_materials_surfaces_and_textures() {
    let dir = tmp_dir("toml-materials-export");
    let out = dir.join("every.xml");
    let rep = forecast::scene::export::export_mitsuba(&every_material(), &out).unwrap_or_else(|e| panic!("{e}"));
    assert!(rep.warnings.is_empty(), "{:?}", rep.warnings);
    let a = forecast::scene::load(&every_material()).unwrap();
    let b = forecast::scene::load(&out).unwrap_or_else(|e| panic!("{e}"));
    assert!(b.warnings.is_empty(), "{:?}", b.warnings);
    assert_eq!(a.materials, b.materials);
    assert_eq!(a.surfaces, b.surfaces);
    let (ta, tb): (Vec<String>, Vec<String>) =
        (a.textures.iter().map(texture_print).collect(), b.textures.iter().map(texture_print).collect());
    assert_eq!(ta, tb);
    assert!(fingerprint(&a) == fingerprint(&b), "the exported scene differs");
    // the images are copies beside the XML, byte for byte; the XML reads the copies
    let plugins = root().join("tests/scenes/mitsuba-plugins");
    for f in ["tex16.png", "tex8.exr", "normals32.png"] {
        let copy = dir.join("every_textures").join(f);
        assert_eq!(std::fs::read(&copy).unwrap(), std::fs::read(plugins.join(f)).unwrap(), "{f}");
        assert!(b.mesh_files.iter().any(|p| p == &copy), "{f} is not read from the copy");
    }
    // hence the same image, bit for bit
    let (wa, wb) = (World::build(a).unwrap(), World::build(b).unwrap());
    let fa = render_passes(&wa, pt(&wa).as_mut(), 16, 16, 2, 7);
    let fb = render_passes(&wb, pt(&wb).as_mut(), 16, 16, 2, 7);
    assert!(fa.data.iter().zip(&fb.data).all(|(x, y)| x.to_bits() == y.to_bits()));
}

/// A scene of one quad per material (TOML `body`, XML `xml`), loaded from `dir`.
fn one_each(toml_types: &[&str], xml_bsdfs: &[String], dir: &Path) -> (Scene, Scene) {
    let mut t = String::from(
        "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\nresolution = [8, 8]\n",
    );
    let mut x = String::from(
        "<scene version=\"3.0.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>\
         <string name=\"fov_axis\" value=\"y\"/><transform name=\"to_world\"><lookat origin=\"0, 0, 3\" \
         target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform><film type=\"hdrfilm\"><integer name=\"width\" \
         value=\"8\"/><integer name=\"height\" value=\"8\"/></film></sensor>",
    );
    for (i, (ty, b)) in toml_types.iter().zip(xml_bsdfs).enumerate() {
        t += &format!("[materials.m{i:02}]\ntype = \"{ty}\"\n");
        x += &format!("<bsdf id=\"m{i:02}\" {}", &b[1..]);
    }
    for i in 0..toml_types.len() {
        let y = i as f32 * 0.1;
        t += &format!(
            "[[shape]]\ntype = \"quad\"\ncorner = [0.0, {y}, 0.0]\nu = [0.1, 0.0, 0.0]\nv = [0.0, 0.1, 0.0]\nmaterial = \"m{i:02}\"\n"
        );
        x += &format!(
            "<shape type=\"obj\"><string name=\"filename\" value=\"q.obj\"/><transform name=\"to_world\">\
             <translate y=\"{y}\"/></transform><ref id=\"m{i:02}\"/></shape>"
        );
    }
    t += "[[light]]\ntype = \"point\"\nposition = [0.0, 0.0, 2.0]\nintensity = [1.0, 1.0, 1.0]\n";
    x += "<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"0\" z=\"2\"/></emitter></scene>";
    let a = forecast::scene::load_str(&t, "defaults.toml", dir).unwrap_or_else(|e| panic!("{e}"));
    let b = common::xml(&x, dir).unwrap_or_else(|e| panic!("{e}"));
    (a, b)
}

#[test]
fn a_plugin_without_parameters_is_mitsubas_default_in_both_formats() {
    let dir = tmp_dir("toml-materials-defaults");
    std::fs::write(dir.join("q.obj"), "v 0 0 0\nv 0.1 0 0\nv 0.1 0.1 0\nf 1 2 3\n").unwrap();
    let types =
        ["conductor", "roughconductor", "dielectric", "roughdielectric", "thindielectric", "plastic", "roughplastic"];
    // TOML materials are two-sided: Mitsuba's `twosided` around the reflecting ones
    let xml: Vec<String> = types
        .iter()
        .map(|t| {
            if t.contains("dielectric") {
                format!(" type=\"{t}\"/>")
            } else {
                format!(" type=\"twosided\"><bsdf type=\"{t}\"/></bsdf>")
            }
        })
        .collect();
    let (a, b) = one_each(&types, &xml, &dir);
    assert_eq!(a.materials, b.materials);
    assert_eq!(a.surfaces, b.surfaces);
    // and they are Mitsuba's: the smooth conductor `none` is the plain mirror, glass is bk7 in air
    assert_eq!(a.materials[1], Material::Mirror { reflectance: forecast::math::Vec3::ONE });
    assert_eq!(a.materials[3], Material::Glass { ior: 1.5046 / 1.000277 });
}

#[test]
fn export_never_overwrites_an_input_image() {
    let dir = tmp_dir("toml-materials-guard");
    std::fs::create_dir_all(dir.join("out_textures")).unwrap();
    let image = dir.join("out_textures/tex16.png");
    let bytes = std::fs::read(root().join("tests/scenes/mitsuba-plugins/tex16.png")).unwrap();
    std::fs::write(&image, &bytes).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\nresolution = [8, 8]\n\
         [materials.m]\ntype = \"diffuse\"\nalbedo = { type = \"bitmap\", filename = \"out_textures/tex16.png\" }\n\
         [[shape]]\ntype = \"quad\"\ncorner = [0.0, 0.0, 0.0]\nu = [1.0, 0.0, 0.0]\nv = [0.0, 1.0, 0.0]\nmaterial = \"m\"\n\
         [[light]]\ntype = \"point\"\nposition = [0.0, 0.0, 2.0]\nintensity = [1.0, 1.0, 1.0]\n",
    )
    .unwrap();
    // `--out out.xml` would copy the image onto itself: refused before anything is written
    let e = forecast::scene::export::export_mitsuba(&scene, &dir.join("out.xml")).unwrap_err();
    assert!(e.contains("tex16.png"), "{e}");
    assert!(!dir.join("out.xml").exists());
    assert_eq!(std::fs::read(&image).unwrap(), bytes);
    // elsewhere it is copied
    forecast::scene::export::export_mitsuba(&scene, &dir.join("other.xml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(std::fs::read(dir.join("other_textures/tex16.png")).unwrap(), bytes);
}
