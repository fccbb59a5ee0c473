//! Defensive mixture of the BSDF sampler and the forecast tables, one-sample MIS with the mixture
//! pdf (Veach 1997 §9.2.4 "one-sample model" with the balance heuristic; Hesterberg 1995 defensive
//! importance sampling), drawn at `pt-cf`'s guided vertices (`docs/methods/pt-cf.md`):
//!
//! `q(ω) = c_B·p_BSDF(ω) + c_1·p_T1(ω) + c_2·p_T2(ω)`: pick a component with probability `c_k`,
//! sample it, and weight by `f·|cos|/q(ω)` with **all** component pdfs evaluated at `ω`. Hence
//! `f·|cos|/q ≤ (f·|cos|/p_BSDF)/c_B`: no sample is worth more than `1/c_B` BSDF samples, which caps
//! the fireflies of an empty T1 bin; the estimate of `∫ f·|cos|·L dω` is unbiased because `c_B > 0`
//! and `p_BSDF > 0` wherever `f > 0`.
//!
//! Domain: directions `ω` with `ω·n_g > 0` and `ω·n_s > 0` (normals on `ω_o`'s side), where `f` can be
//! non-zero. Samples outside it are refused (`None`) and [`DefensiveMixture::pdf_w`] is 0 there, so
//! `pdf_w` is exactly the density of the returned directions. Dirac materials (mirror, glass) and
//! mixtures whose only component is the BSDF use `bsdf::sample` unchanged (same uniforms, same
//! weight, bit for bit). Radiance transport only (eye paths).
//!
//! Invariants: component weights are a pure function of the vertex (which tables exist), never of
//! the samples; the returned `pdf_w` equals `pdf_w(wi)` (up to f32 rounding of the frame change).

// `!(x > 0.0)`-style tests are deliberate: they are true for NaN (bad input is rejected).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::direction_table::{bin_of, DirectionTable, ForecastTables, BIN_SOLID_ANGLE};
use crate::bsdf::{self, BsdfSample, Mode, ShadingPoint};
use crate::math::{Frame, Rgb, Vec3};
use crate::sampling::rng::Rng;
use crate::scene::Material;

/// Mixture weights `(c_B, c_1, c_2)`, validated and normalised to sum 1.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MixtureWeights {
    /// BSDF share `c_B > 0`.
    pub bsdf: f32,
    /// T1 share `c_1 ≥ 0`.
    pub t1: f32,
    /// T2 share `c_2 ≥ 0`.
    pub t2: f32,
}

impl MixtureWeights {
    /// Checks `c_B > 0`, `c_1, c_2 ≥ 0`, all finite, and normalises; the error names the weight.
    pub fn new(bsdf: f32, t1: f32, t2: f32) -> Result<Self, String> {
        for (name, c) in [("BSDF", bsdf), ("T1", t1), ("T2", t2)] {
            if !c.is_finite() || c < 0.0 {
                return Err(format!("mixture weight of {name} = {c}: must be finite and ≥ 0"));
            }
        }
        if !(bsdf > 0.0) {
            return Err(format!("mixture weight of the BSDF = {bsdf}: must be > 0 (it bounds the weights)"));
        }
        let s = bsdf + t1 + t2;
        Ok(MixtureWeights { bsdf: bsdf / s, t1: t1 / s, t2: t2 / s })
    }

    /// `pt-cf`'s `q = c·p_BSDF + (1−c)·p_CF` with the guide share split evenly over T1 and T2.
    pub fn guide_fraction(c: f32) -> Result<Self, String> {
        if !(c > 0.0 && c <= 1.0) {
            return Err(format!("guide fraction c = {c}: must be in (0, 1]"));
        }
        Self::new(c, 0.5 * (1.0 - c), 0.5 * (1.0 - c))
    }
}

/// One sampled direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MixtureSample {
    /// World direction (unit, away from the surface).
    pub wi: Vec3,
    /// `f·|cos θ_i|/q(wi)` (for Dirac materials: `bsdf::sample`'s weight).
    pub weight: Rgb,
    /// `q(wi)`, the mixture's solid-angle pdf (Dirac: the discrete lobe probability).
    pub pdf_w: f32,
    /// Which component drew it: 0 BSDF, 1 T1, 2 T2.
    pub component: u8,
    /// Dirac lobe (only for Dirac materials).
    pub is_delta: bool,
    /// Relative index of a refraction (`BsdfSample::eta`), else 1.
    pub eta: f32,
    /// The BSDF's own pdf of `wi` (`p_BSDF`; `pdf_w` when the BSDF drew it alone): roulette
    /// after a guided vertex uses `pdf_w / bsdf_pdf_w` (`Throughput::guided`).
    pub bsdf_pdf_w: f32,
}

impl MixtureSample {
    /// The same continuation as a [`BsdfSample`] (its pdf the mixture's).
    pub fn as_bsdf_sample(&self) -> BsdfSample {
        BsdfSample { wi: self.wi, weight: self.weight, pdf_w: self.pdf_w, is_delta: self.is_delta, eta: self.eta }
    }
}

/// The mixture at one vertex: the BSDF `(m, sp, wo)` and the vertex's tables in `frame`.
#[derive(Clone, Copy, Debug)]
pub struct DefensiveMixture<'a> {
    m: &'a Material,
    sp: &'a ShadingPoint,
    wo: Vec3,
    /// Geometric and shading normal on `wo`'s side.
    ng: Vec3,
    ns: Vec3,
    frame: Frame,
    tables: [Option<&'a DirectionTable>; 2],
    /// Normalised over the components that exist: (c_B, c_1, c_2).
    c: [f32; 3],
}

impl<'a> DefensiveMixture<'a> {
    /// The mixture for material `m` at `sp` seen from `wo`, with `tables` expressed in `frame`
    /// (z = the normal the tables were built around). Missing tables get weight 0 and the rest is
    /// renormalised; a Dirac material uses its BSDF only.
    pub fn new(
        m: &'a Material,
        sp: &'a ShadingPoint,
        wo: Vec3,
        tables: &'a ForecastTables,
        frame: Frame,
        weights: MixtureWeights,
    ) -> Self {
        let (ng, ns) = if wo.dot(sp.ng) >= 0.0 { (sp.ng, sp.ns) } else { (-sp.ng, -sp.ns) };
        let tables = if m.is_dirac() { [None, None] } else { [tables.t1.as_ref(), tables.t2.as_ref()] };
        let mut c = [weights.bsdf, weights.t1, weights.t2];
        for k in 0..2 {
            if tables[k].is_none() {
                c[k + 1] = 0.0;
            }
        }
        let s: f32 = c.iter().sum();
        let c = if s > 0.0 && c[0] < s { c.map(|x| x / s) } else { [1.0, 0.0, 0.0] };
        DefensiveMixture { m, sp, wo, ng, ns, frame, tables, c }
    }

    /// The normalised component weights `(c_B, c_1, c_2)` in use.
    pub fn weights(&self) -> [f32; 3] {
        self.c
    }

    /// True when only the BSDF is sampled (Dirac material, no table, or `c_B = 1`).
    pub fn is_bsdf_only(&self) -> bool {
        self.c[0] >= 1.0
    }

    #[inline]
    fn in_domain(&self, wi: Vec3) -> bool {
        wi.dot(self.ng) > 0.0 && wi.dot(self.ns) > 0.0 && self.wo.dot(self.ns) > 0.0
    }

    /// `q` at world `wi` whose table-frame coordinates are `local` (0 outside the domain).
    #[inline]
    fn q(&self, wi: Vec3, local: Vec3) -> f32 {
        self.q_and_bsdf(wi, local).0
    }

    /// True for a direction the tables do not cover but the BSDF may sample: the far side of a
    /// material that transmits (the tables hold the reflection hemisphere).
    #[inline]
    fn transmits_to(&self, wi: Vec3) -> bool {
        wi.dot(self.ng) < 0.0 && self.m.is_two_sided_by_nature()
    }

    /// `(q, p_BSDF)` at `wi` (both 0 outside the BSDF's support and the domain; the BSDF's
    /// alone across a transmitting material).
    #[inline]
    fn q_and_bsdf(&self, wi: Vec3, local: Vec3) -> (f32, f32) {
        if !self.in_domain(wi) {
            if self.transmits_to(wi) {
                let p_bsdf = bsdf::pdf_w(self.m, self.sp, self.wo, wi);
                return (self.c[0] * p_bsdf, p_bsdf);
            }
            return (0.0, 0.0);
        }
        let p_bsdf = bsdf::pdf_w(self.m, self.sp, self.wo, wi);
        let mut q = self.c[0] * p_bsdf;
        // one bin lookup for both tables (`DirectionTable::pdf_w` = pmf of the bin / ΔΩ)
        if let Some(bin) = bin_of(local) {
            for k in 0..2 {
                if let Some(t) = self.tables[k].filter(|_| self.c[k + 1] > 0.0) {
                    q += self.c[k + 1] * (t.bin_pmf(bin) / BIN_SOLID_ANGLE);
                }
            }
        }
        (q, p_bsdf)
    }

    /// Solid-angle pdf `q(wi)` of [`Self::sample`] (world `wi`). For a Dirac material: 0.
    pub fn pdf_w(&self, wi: Vec3) -> f32 {
        if self.m.is_dirac() {
            return 0.0;
        }
        if self.is_bsdf_only() {
            let support = self.in_domain(wi) || self.transmits_to(wi);
            return if support { bsdf::pdf_w(self.m, self.sp, self.wo, wi) } else { 0.0 };
        }
        self.q(wi, self.frame.to_local(wi))
    }

    /// Draws one direction: 3 uniforms from `rng` when [`Self::is_bsdf_only`] (the very draws
    /// `bsdf::sample` would get), else 4 (the first picks the component).
    pub fn sample(&self, rng: &mut Rng) -> Option<MixtureSample> {
        if self.is_bsdf_only() {
            let u = rng.next_3d();
            return self.sample_u(0.0, u);
        }
        let pick = rng.next_f32();
        self.sample_u(pick, rng.next_3d())
    }

    /// [`Self::sample`] with explicit uniforms: `pick` chooses the component (unused when
    /// BSDF-only), `u` drives it.
    pub fn sample_u(&self, pick: f32, u: [f32; 3]) -> Option<MixtureSample> {
        if self.is_bsdf_only() {
            let bs = bsdf::sample(self.m, self.sp, self.wo, u, Mode::Radiance)?;
            if !bs.is_delta && !self.in_domain(bs.wi) && !self.transmits_to(bs.wi) {
                return None;
            }
            let (wi, weight, pdf_w, is_delta, eta) = (bs.wi, bs.weight, bs.pdf_w, bs.is_delta, bs.eta);
            return Some(MixtureSample { wi, weight, pdf_w, component: 0, is_delta, eta, bsdf_pdf_w: pdf_w });
        }
        let component = if pick < self.c[0] {
            0
        } else if pick < self.c[0] + self.c[1] || self.c[2] <= 0.0 {
            1
        } else {
            2
        };
        let (wi, local) = if component == 0 {
            let bs = bsdf::sample(self.m, self.sp, self.wo, u, Mode::Radiance)?;
            if bs.is_delta {
                // a mixed material's Dirac lobe: a discrete sample of probability c_B times the
                // lobe's (which its weight already divides by); the tables have no mass there
                let (wi, eta, bsdf_pdf_w) = (bs.wi, bs.eta, bs.pdf_w);
                let (weight, pdf_w) = (bs.weight / self.c[0], bs.pdf_w * self.c[0]);
                return Some(MixtureSample { wi, weight, pdf_w, component: 0, is_delta: true, eta, bsdf_pdf_w });
            }
            (bs.wi, self.frame.to_local(bs.wi))
        } else {
            let t = self.tables[component - 1]?;
            let (local, _) = t.sample(u);
            (self.frame.to_world(local), local)
        };
        let (q, bsdf_pdf_w) = self.q_and_bsdf(wi, local);
        if !(q > 0.0) {
            return None; // outside the domain (f = 0 there)
        }
        let f = bsdf::eval(self.m, self.sp, self.wo, wi, Mode::Radiance);
        let weight = f * (wi.dot(self.sp.ns).abs() / q);
        let component = component as u8;
        Some(MixtureSample { wi, weight, pdf_w: q, component, is_delta: false, eta: 1.0, bsdf_pdf_w })
    }
}
