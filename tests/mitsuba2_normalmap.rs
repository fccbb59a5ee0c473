//! Mitsuba 2's `normalmap` as the SMS repository's fork writes it (issue #62): a `filename`
//! child, `tiles`, `use_slopes`, read as Mitsuba 3's `normalmap` around a raw `bitmap` with
//! `to_uv` scale `tiles` (the same scene, with a warning naming what differs); what cannot be
//! mapped (`lean_fallback` true, both forms at once, `tiles` ≤ 0, an absent image) is an error
//! naming the file, line and key.

mod common;
use common::{root, xml};
use forecast::scene::Scene;

/// A sphere lit by a point light with `bsdf` (lines 4 on).
fn scene(bsdf: &str) -> String {
    format!(
        "<scene version=\"2.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/></sensor>\n\
         <emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"3\" z=\"0\"/></emitter>\n\
         <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0\" z=\"-3\"/>\n{bsdf}\n</shape>\n</scene>"
    )
}

fn dir() -> std::path::PathBuf {
    root().join("tests/scenes/mitsuba-plugins")
}

fn image_of(s: &Scene) -> String {
    format!("{:?}|{:?}|{:?}", s.materials, s.surfaces, s.textures)
}

#[test]
fn filename_form_is_mitsuba3s_normalmap_with_tiles_as_to_uv() {
    let m2 = "<bsdf type=\"normalmap\">\n<bsdf type=\"dielectric\"/>\n<string name=\"filename\" value=\"normals32.png\"/>\n\
              <float name=\"tiles\" value=\"4\"/>\n<boolean name=\"use_slopes\" value=\"true\"/>\n\
              <boolean name=\"lean_fallback\" value=\"false\"/><float name=\"lean_fallback_alpha\" value=\"0.01\"/>\n</bsdf>";
    let m3 = "<bsdf type=\"normalmap\"><bsdf type=\"dielectric\"/><texture name=\"normalmap\" type=\"bitmap\">\
              <string name=\"filename\" value=\"normals32.png\"/><boolean name=\"raw\" value=\"true\"/>\
              <transform name=\"to_uv\"><scale x=\"4\" y=\"4\"/></transform></texture></bsdf>";
    let (a, b) = (xml(&scene(m2), &dir()).unwrap(), xml(&scene(m3), &dir()).unwrap());
    assert_eq!(image_of(&a), image_of(&b));
    assert!(b.warnings.is_empty(), "{:?}", b.warnings);
    let [w] = &a.warnings[..] else { panic!("one warning: {:?}", a.warnings) };
    assert!(
        w.contains("t.xml:5:") && w.contains("Mitsuba 2's form (`filename`)") && w.contains("not the slopes"),
        "{w}"
    );
    // use_slopes false: the same map, the warning without the slopes
    let a =
        xml(&scene(&m2.replace("\"use_slopes\" value=\"true\"", "\"use_slopes\" value=\"false\"")), &dir()).unwrap();
    assert_eq!(image_of(&a), image_of(&b));
    assert!(!a.warnings[0].contains("slopes"), "{:?}", a.warnings);
}

#[test]
fn what_cannot_be_mapped_is_refused_at_file_line_and_key() {
    let base =
        "<bsdf type=\"normalmap\">\n<bsdf type=\"diffuse\"/>\n<string name=\"filename\" value=\"normals32.png\"/>\n";
    let cases = [
        (format!("{base}<boolean name=\"lean_fallback\" value=\"true\"/>\n</bsdf>"), 8, "normalmap.lean_fallback", "LEAN"),
        (format!("{base}<float name=\"tiles\" value=\"0\"/>\n</bsdf>"), 8, "normalmap.tiles", "must be positive"),
        (
            format!("{base}<texture name=\"normalmap\" type=\"bitmap\"><string name=\"filename\" value=\"normals32.png\"/></texture>\n</bsdf>"),
            8,
            "normalmap.normalmap",
            "give one",
        ),
        (base.replace("normals32.png", "absent.png") + "</bsdf>", 7, "bitmap.filename", "absent.png"),
    ];
    for (bsdf, line, key, words) in cases {
        let e = xml(&scene(&bsdf), &dir()).unwrap_err();
        assert_eq!((e.file.as_str(), e.line, e.key.as_str()), ("t.xml", line, key), "{e}");
        assert!(e.message.contains(words), "{e}");
    }
}
