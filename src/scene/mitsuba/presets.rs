//! Mitsuba's named material presets: dielectric indices of refraction (Mitsuba's IOR table) and
//! conductor complex indices η + ik as RGB triples: the measured spectra of Mitsuba's preset list
//! reduced to linear RGB, as other renderers tabulate them (e.g. Tungsten's `ComplexIorData`).
//! Mitsuba 3 reduces the spectra itself, so its RGB triples may differ in the last digits (`Au`:
//! η, k within 0.1% of Mitsuba 3.9.1's, its Fresnel reflectance within 3e-4; tested below).
//!
//! And the colour Mitsuba 3's RGB variants give a uniform `<spectrum value="v"/>` inside an
//! emitter: the equal-energy spectrum (CIE illuminant E) of height v, whose linear sRGB (D65
//! white) is v·[`UNIFORM_EMISSION_RGB`], not the grey v; in a BSDF a uniform spectrum stays v
//! (a reflectance of 0.5 is grey under any light). `<rgb>` and `<float>` stay as written in both.

/// Linear sRGB of Mitsuba 3's uniform emitter spectrum of height 1: the equal-energy spectrum
/// through the CIE 1931 2° curves (normalised to Y = 1) and the XYZ → sRGB matrix. The digits are
/// Mitsuba 3.9.1's (`scalar_rgb`: `<spectrum name="radiance" value="1"/>` in an `area` emitter,
/// read back with `mi.traverse`; the `point` emitter's `intensity` gets the same). Its luminance
/// is 1, its channel mean 1.0207: read as grey, a scene lit so renders 2% darker in image mean
/// (the SMS ring: docs/mitsuba.md).
pub(super) const UNIFORM_EMISSION_RGB: [f32; 3] = [1.204_793_9, 0.948_291, 0.908_916_06];

/// Dielectric IOR by Mitsuba's preset name.
pub(in crate::scene) fn dielectric_ior(name: &str) -> Option<f32> {
    Some(match name {
        "vacuum" => 1.0,
        "helium" => 1.000036,
        "hydrogen" => 1.000132,
        "air" => 1.000277,
        "carbon dioxide" => 1.00045,
        "water" => 1.3330,
        "acetone" => 1.36,
        "ethanol" => 1.361,
        "carbon tetrachloride" => 1.461,
        "glycerol" => 1.4729,
        "benzene" => 1.501,
        "silicone oil" => 1.52045,
        "bromine" => 1.661,
        "water ice" => 1.31,
        "fused quartz" => 1.458,
        "pyrex" => 1.470,
        "acrylic glass" => 1.49,
        "polypropylene" => 1.49,
        "bk7" => 1.5046,
        "sodium chloride" => 1.544,
        "amber" => 1.55,
        "pet" => 1.5750,
        "diamond" => 2.419,
        _ => return None,
    })
}

/// Conductor (η, k) as RGB by Mitsuba's preset name; `none` is (0, 1), a perfect mirror.
#[allow(clippy::excessive_precision)] // measured data, kept as tabulated
pub(in crate::scene) fn conductor(name: &str) -> Option<([f32; 3], [f32; 3])> {
    const T: &[(&str, [f32; 3], [f32; 3])] = &[
        ("a-C", [2.9440999, 2.2271503, 1.9681669], [0.8874329, 0.7993216, 0.8152863]),
        ("Ag", [0.15526465, 0.1167233, 0.1383807], [4.8283433, 3.122246, 2.1469504]),
        ("Al", [1.65746, 0.88036896, 0.52122873], [9.223869, 6.269523, 4.8370012]),
        ("Au", [0.14311896, 0.37495704, 1.4424786], [3.9831604, 2.3857207, 1.6032153]),
        ("Be", [4.1850593, 3.1850604, 2.7840913], [3.8354398, 3.010126, 2.8690089]),
        ("Cr", [4.369683, 2.9167025, 1.6547005], [5.206434, 4.2313645, 3.7549467]),
        ("CsI", [2.144903, 1.7023165, 1.6624194], [0.0, 0.0, 0.0]),
        ("Cu", [0.2004377, 0.92403343, 1.102212], [3.9129485, 2.4528477, 2.142188]),
        ("Cu2O", [3.5492834, 2.9520622, 2.7369202], [0.11321793, 0.19466597, 0.60016813]),
        ("CuO", [3.2453822, 2.4496294, 2.1974114], [0.52027396, 0.57073728, 0.71722506]),
        ("d-C", [2.7112525, 2.3185813, 2.2288565], [0.0, 0.0, 0.0]),
        ("Hg", [2.3989315, 1.4400255, 0.9095512], [6.327627, 4.3719414, 3.42179]),
        ("HgTe", [4.7795268, 3.2309985, 2.6600252], [1.6319827, 1.5808189, 1.7295754]),
        ("Ir", [3.0864098, 2.0821938, 1.6178867], [5.592151, 4.0671757, 3.2672611]),
        ("K", [0.064049307, 0.046410062, 0.038184202], [2.1042156, 1.3489364, 0.9132114]),
        ("Li", [0.2657872, 0.19561024, 0.22091985], [3.5401743, 2.3111307, 1.668593]),
        ("MgO", [2.0895886, 1.6507225, 1.594876], [0.0, 0.0, 0.0]),
        ("Mo", [4.483701, 3.5254578, 2.776077], [4.111131, 3.4208716, 3.1506031]),
        ("Na_palik", [0.060266532, 0.056141243, 0.06199095], [3.1792907, 2.11248, 1.579094]),
        ("Nb", [3.4201354, 2.7901921, 2.3955857], [3.4413818, 2.7376438, 2.5799133]),
        ("Ni_palik", [2.3672754, 1.6633583, 1.4670554], [4.498833, 3.0501644, 2.3454274]),
        ("Rh", [2.5857955, 1.8601866, 1.554428], [6.7822927, 4.70295, 3.9760892]),
        ("Se", [4.059261, 2.8426947, 2.8207583], [0.7543792, 0.63851506, 0.5215872]),
        ("SnTe", [4.5251866, 1.9811526, 1.2816819], [0.0, 0.0, 0.0]),
        ("Ta", [2.0625847, 2.3930916, 2.6280685], [2.4080468, 1.7413706, 1.9470377]),
        ("Te", [7.3908396, 4.482103, 2.6370708], [3.2561413, 3.5273908, 3.2921683]),
        ("ThF4", [1.8307187, 1.4422274, 1.3876489], [0.0, 0.0, 0.0]),
        ("TiC", [3.7004673, 2.8374357, 2.582303], [3.2656906, 2.3515586, 2.1727858]),
        ("TiN", [1.6484692, 1.1504483, 1.3797795], [3.3684597, 1.9434888, 1.1020123]),
        ("VC", [3.6575666, 2.7527298, 2.5326815], [3.0683517, 2.1986687, 1.9631816]),
        ("V_palik", [4.2775126, 3.5131538, 2.7611257], [3.4911845, 2.889358, 3.1116965]),
        ("VN", [2.8656012, 2.1191818, 1.9400767], [3.0323265, 2.0561075, 1.616293]),
        ("W", [4.370703, 3.3002973, 2.9982667], [3.5006779, 2.6048653, 2.273193]),
    ];
    if name == "none" {
        return Some(([0.0; 3], [1.0; 3]));
    }
    T.iter().find(|(n, _, _)| *n == name).map(|(_, e, k)| (*e, *k))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::fresnel_conductor;
    use crate::math::Rgb;

    /// sRGB of CIE illuminant E: the XYZ → linear sRGB matrix (IEC 61966-2-1) applied to
    /// X = Y = Z = 1; Mitsuba's tabulated curves (360–830 nm) move the blue channel by 1e-4.
    #[test]
    fn uniform_emission_is_illuminant_e_in_srgb() {
        let m = [
            [3.240_454_2, -1.537_138_5, -0.498_531_4],
            [-0.969_266, 1.876_010_8, 0.041_556],
            [0.055_643_4, -0.204_025_9, 1.057_225_2],
        ];
        for (c, row) in m.iter().enumerate() {
            let want: f32 = row.iter().sum();
            assert!(
                (UNIFORM_EMISSION_RGB[c] - want).abs() < 2e-4,
                "channel {c}: {} vs {want}",
                UNIFORM_EMISSION_RGB[c]
            );
        }
        let y = 0.212_672_9 * UNIFORM_EMISSION_RGB[0]
            + 0.715_152_2 * UNIFORM_EMISSION_RGB[1]
            + 0.072_175 * UNIFORM_EMISSION_RGB[2];
        assert!((y - 1.0).abs() < 2e-4, "luminance {y}");
    }

    /// `Au` against Mitsuba 3.9.1 (`scalar_rgb`, `conductor` with `material="Au"`): its η, k (read
    /// with `mi.traverse`) and the weight of `sample()` (= F) at cos θ = 1, 0.8, 0.5, 0.2, 0.05.
    #[test]
    fn gold_matches_mitsuba() {
        let (e, k) = conductor("Au").unwrap();
        let (me, mk) = ([0.143_035_98, 0.375_307_08, 1.442_045_3], [3.982_997, 2.385_556_5, 1.603_359_2]);
        for c in 0..3 {
            // the table's η, k are Mitsuba's to 0.1% (η_G: 0.374957 against 0.375307)
            assert!((e[c] - me[c]).abs() < 1e-3 * me[c] && (k[c] - mk[c]).abs() < 1e-3 * mk[c], "{c}");
        }
        let mitsuba_f: [(f32, [f32; 3]); 5] = [
            (1.0, [0.966_679_3, 0.802_009_9, 0.324_121_48]),
            (0.8, [0.966_069_2, 0.801_276_9, 0.329_045_2]),
            (0.5, [0.962_210_4, 0.804_370_8, 0.371_175_17]),
            (0.2, [0.961_299_6, 0.863_161_2, 0.557_283_8]),
            (0.05, [0.985_211_8, 0.957_128_2, 0.840_001]),
        ];
        for (cos, want) in mitsuba_f {
            // Mitsuba's own η, k through our Fresnel: the formula itself (f32 rounding only)
            let f = fresnel_conductor(cos, Rgb::from_array(me), Rgb::from_array(mk));
            assert!((f - Rgb::from_array(want)).abs().max_element() < 1e-5, "cos {cos}: {f} vs {want:?}");
            // the preset's η, k: the table's last digits
            let f = fresnel_conductor(cos, Rgb::from_array(e), Rgb::from_array(k));
            assert!((f - Rgb::from_array(want)).abs().max_element() < 3e-4, "cos {cos}: {f} vs {want:?}");
        }
    }
}
