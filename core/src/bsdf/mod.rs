//! Materials: BSDFs evaluated, sampled and given densities in the local shading frame.
//!
//! Every function takes directions in the local shading frame (normal = +z), both
//! pointing away from the surface: `wo` toward where the path came from, `wi` the other
//! one (sampled or connected). [`Material::eval`] returns f(wo, wi) *without* the cosine
//! |cos θi|; [`Material::pdf`] is the solid-angle density with which
//! [`Material::sample`] draws `wi` given `wo` (continuous lobes only), and
//! [`Material::pdf_rev`] the density of drawing `wo` given `wi`.
//!
//! The models and their conventions are Mitsuba 3's (the suite's references are Mitsuba
//! renders): `diffuse`, `conductor`, `roughconductor`, `dielectric`, `roughdielectric`
//! `plastic`, `roughplastic`, `principled` and the `twosided` adapter. Smooth `plastic` is the one
//! model with lobes of both kinds: `eval` and `pdf` describe its continuous lobe, and a
//! sample says whether it drew the Dirac one (see `plastic.rs`). Microfacet models use Smith's separable masking and
//! sample visible normals (see `microfacet.rs`).
//!
//! [`TransportMode`] matters only for refraction: in `Radiance` mode (camera paths,
//! where `wi` points toward the light) transmitted values carry the (η_i/η_t)² radiance
//! compression; `Importance` mode (light paths) evaluates the adjoint BSDF
//! f*(wo, wi) = f(wi, wo), which does not. Shading-normal asymmetry is separate: see
//! [`shading_normal_correction`].
//!
//! Reciprocity, with η_w the index of the medium on `w`'s side: reflection is symmetric,
//! f(wo, wi) = f(wi, wo); Radiance-mode transmission obeys f(wo, wi)/η_wo² = f(wi, wo)/η_wi²
//! (Veach's thesis §5.2, with light flowing from wi to wo).

// `!(x > 0.0)` is used on purpose throughout: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod conductor;
mod dielectric;
mod diffuse;
mod fresnel;
mod microfacet;
mod plastic;
mod principled;
mod rough_conductor;
mod rough_dielectric;
mod rough_plastic;

use crate::math::{Frame, Vec2, Vec3};
use crate::measure::SolidAnglePdf;
use crate::spectrum::Rgb;
use conductor::Conductor;
use dielectric::Dielectric;
use diffuse::Diffuse;
pub(crate) use diffuse::LambertLane;
use microfacet::Microfacet;
use plastic::Plastic;
use principled::Principled;
pub use principled::PrincipledParams;
use rough_conductor::RoughConductor;
use rough_dielectric::RoughDielectric;
pub use rough_plastic::PlasticCoating;
use rough_plastic::RoughPlastic;

/// Which quantity a path carries, which decides whether a BSDF or its adjoint applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    /// Camera subpaths: radiance flows from `wi` toward `wo`.
    Radiance,
    /// Light subpaths: importance flows from `wi` toward `wo`; the adjoint BSDF applies.
    Importance,
}

impl TransportMode {
    /// The walk in the opposite direction.
    #[inline]
    pub fn flip(self) -> Self {
        match self {
            Self::Radiance => Self::Importance,
            Self::Importance => Self::Radiance,
        }
    }
}

/// Microfacet normal distribution (Mitsuba's `distribution` parameter).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MicrofacetKind {
    /// Beckmann (Gaussian slopes); `alpha` is the RMS slope. Mitsuba's default.
    Beckmann,
    /// GGX / Trowbridge–Reitz, long-tailed.
    Ggx,
}

/// A direction drawn by [`Material::sample`].
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Sampled direction in the local shading frame (normal = +z), unit, away from the surface.
    pub wi: Vec3,
    /// BSDF value f(wo, wi) for the mode (the adjoint for `Importance`), without the cosine.
    /// For a Dirac lobe, the value that makes f·|cos θi|/pdf the lobe's weight.
    pub f: Rgb,
    /// Density of `wi` given `wo`; for a Dirac lobe, the discrete probability of the lobe.
    pub pdf: SolidAnglePdf,
    /// Density of sampling `wo` given `wi` (same convention for Dirac lobes).
    pub pdf_rev: SolidAnglePdf,
    /// The sampled lobe is a Dirac distribution (mirror or smooth refraction).
    pub is_delta: bool,
    /// `wi` is on the other side of the surface from `wo`.
    pub is_transmission: bool,
    /// Relative index η_t/η_i crossed (seen from the `wo` side) for transmission, else 1.
    pub eta: f32,
}

impl BsdfSample {
    /// A continuous reflection sample.
    #[inline]
    fn continuous_reflection(wi: Vec3, f: Rgb, pdf: SolidAnglePdf, pdf_rev: SolidAnglePdf) -> Self {
        Self { wi, f, pdf, pdf_rev, is_delta: false, is_transmission: false, eta: 1.0 }
    }

    /// [`Self::continuous_reflection`], or `None` unless the density is positive and
    /// finite and the value finite (the glossy reflection models' samplers).
    #[inline]
    fn checked_reflection(wi: Vec3, f: Rgb, pdf: SolidAnglePdf, pdf_rev: SolidAnglePdf) -> Option<Self> {
        (pdf.value() > 0.0 && pdf.value().is_finite() && f.is_finite()).then(|| Self::continuous_reflection(wi, f, pdf, pdf_rev))
    }
}

/// The closed set of scattering models.
// Rough plastic carries its 64-entry transmittance table inline (≈ 300 bytes) so that
// `Material` stays `Copy`; materials are read by reference from the scene's table, so
// the size costs memory per material, not copies per sample.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Diffuse(Diffuse),
    Conductor(Conductor),
    RoughConductor(RoughConductor),
    Dielectric(Dielectric),
    RoughDielectric(RoughDielectric),
    RoughPlastic(RoughPlastic),
    Plastic(Plastic),
    Principled(Principled),
}

/// A material parameter a texture can drive (Mitsuba's parameter names in brackets).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureSlot {
    /// The diffuse albedo: `reflectance` of `diffuse`, `diffuse_reflectance` of the
    /// plastics, `base_color` of `principled`.
    Diffuse,
    /// `specular_reflectance` of conductors, dielectrics and plastics.
    SpecularReflectance,
    /// `specular_transmittance` of dielectrics.
    SpecularTransmittance,
    /// `roughness` of `principled`, a float parameter: the texel's luminance.
    Roughness,
}

/// A surface's scattering model (a closed enum) and whether it is mirrored to the back.
#[derive(Clone, Copy, Debug)]
pub struct Material {
    kind: Kind,
    two_sided: bool,
}

/// Relative indices are clamped to [1/`MAX_RELATIVE_IOR`, `MAX_RELATIVE_IOR`]: far
/// beyond any material (diamond/air is 2.4), and it keeps η², 1/η² and the refraction
/// Jacobians finite (fuzzing found a NaN density at η = 2.6e-42).
const MAX_RELATIVE_IOR: f32 = 1e3;

/// η_int/η_ext, with invalid input (non-positive, non-finite) read as index-matched,
/// and extreme ratios clamped (see [`MAX_RELATIVE_IOR`]).
fn relative_ior(int_ior: f32, ext_ior: f32) -> f32 {
    let eta = int_ior / ext_ior;
    if eta > 0.0 && eta.is_finite() { eta.clamp(1.0 / MAX_RELATIVE_IOR, MAX_RELATIVE_IOR) } else { 1.0 }
}

/// Mirror a direction through the surface plane (Mitsuba's `twosided` flips z only).
#[inline]
fn flip_z(w: Vec3) -> Vec3 {
    Vec3::new(w.x, w.y, -w.z)
}

impl Material {
    fn new(kind: Kind) -> Self {
        Self { kind, two_sided: false }
    }

    /// Lambertian reflector, f = ρ/π (Mitsuba `diffuse`). Black from the back unless
    /// [`Self::two_sided`].
    pub fn diffuse(reflectance: Rgb) -> Self {
        Self::new(Kind::Diffuse(Diffuse { reflectance }))
    }

    /// Smooth conductor (Mitsuba `conductor`): a mirror weighted by the unpolarised
    /// Fresnel reflectance of the complex relative index `eta` + i`k` (per RGB channel,
    /// relative to the outside medium), times `specular_reflectance`. Mitsuba's default
    /// (η = 0, k = 1) is a perfect mirror.
    pub fn conductor(eta: Rgb, k: Rgb, specular_reflectance: Rgb) -> Self {
        Self::new(Kind::Conductor(Conductor { eta, k, specular_reflectance }))
    }

    /// Rough conductor (Mitsuba `roughconductor`, isotropic): microfacet reflection with
    /// distribution `kind` of roughness `alpha` (clamped to ≥ 10⁻⁴), Smith masking, and
    /// the conductor Fresnel term of [`Self::conductor`].
    pub fn rough_conductor(kind: MicrofacetKind, alpha: f32, eta: Rgb, k: Rgb, specular_reflectance: Rgb) -> Self {
        Self::new(Kind::RoughConductor(RoughConductor { distr: Microfacet::new(kind, alpha), eta, k, specular_reflectance }))
    }

    /// Smooth dielectric interface (Mitsuba `dielectric`) between an inside of index
    /// `int_ior` (below the surface, z < 0) and an outside of index `ext_ior`. Reflects
    /// with probability F and refracts with 1 − F. Invalid indices (non-positive or
    /// non-finite ratio) are read as index-matched.
    pub fn dielectric(int_ior: f32, ext_ior: f32, specular_reflectance: Rgb, specular_transmittance: Rgb) -> Self {
        Self::new(Kind::Dielectric(Dielectric { eta: relative_ior(int_ior, ext_ior), specular_reflectance, specular_transmittance }))
    }

    /// Rough dielectric interface (Mitsuba `roughdielectric`, isotropic): Walter et al.'s
    /// microfacet reflection and refraction, roughness `alpha` clamped to ≥ 10⁻⁴.
    pub fn rough_dielectric(kind: MicrofacetKind, alpha: f32, int_ior: f32, ext_ior: f32, specular_reflectance: Rgb, specular_transmittance: Rgb) -> Self {
        Self::new(Kind::RoughDielectric(RoughDielectric {
            distr: Microfacet::new(kind, alpha),
            eta: relative_ior(int_ior, ext_ior),
            specular_reflectance,
            specular_transmittance,
        }))
    }

    /// Rough plastic (Mitsuba `roughplastic`, isotropic): a diffuse base of reflectance
    /// `diffuse` under a rough dielectric coating of index `int_ior` in a medium of index
    /// `ext_ior`, roughness `alpha` (clamped to ≥ 10⁻⁴); `nonlinear` as Mitsuba's. Builds the
    /// coating's tables (see `rough_plastic.rs`; [`Self::rough_plastic_coated`] shares them).
    pub fn rough_plastic(kind: MicrofacetKind, alpha: f32, int_ior: f32, ext_ior: f32, diffuse: Rgb, specular_reflectance: Rgb, nonlinear: bool) -> Self {
        Self::rough_plastic_coated(&Self::plastic_coating(kind, alpha, int_ior, ext_ior), diffuse, specular_reflectance, nonlinear)
    }

    /// The coating of [`Self::rough_plastic`], to build once and share.
    pub fn plastic_coating(kind: MicrofacetKind, alpha: f32, int_ior: f32, ext_ior: f32) -> PlasticCoating {
        PlasticCoating::new(Microfacet::new(kind, alpha), relative_ior(int_ior, ext_ior))
    }

    /// Rough plastic with a coating built before.
    pub fn rough_plastic_coated(coating: &PlasticCoating, diffuse: Rgb, specular_reflectance: Rgb, nonlinear: bool) -> Self {
        Self::new(Kind::RoughPlastic(RoughPlastic::new(coating, diffuse, specular_reflectance, nonlinear)))
    }

    /// Smooth plastic (Mitsuba `plastic`): a diffuse base of reflectance `diffuse` under a
    /// smooth dielectric coating of index `int_ior` in a medium of index `ext_ior`;
    /// `nonlinear` as Mitsuba's. Its mirror lobe is a Dirac distribution and its diffuse
    /// lobe continuous (see `plastic.rs`).
    pub fn plastic(int_ior: f32, ext_ior: f32, diffuse: Rgb, specular_reflectance: Rgb, nonlinear: bool) -> Self {
        Self::new(Kind::Plastic(Plastic::new(relative_ior(int_ior, ext_ior), diffuse, specular_reflectance, nonlinear)))
    }

    /// Mitsuba 3's `principled` (see `principled.rs`): Burley's Disney BSDF with its
    /// diffuse, sheen, anisotropic GGX specular, clearcoat and rough transmission lobes.
    pub fn principled(params: PrincipledParams) -> Self {
        Self::new(Kind::Principled(Principled::new(params)))
    }

    /// Which texture slots this model has.
    pub fn has_slot(&self, slot: TextureSlot) -> bool {
        use TextureSlot as S;
        match (&self.kind, slot) {
            (Kind::Diffuse(_) | Kind::Plastic(_) | Kind::RoughPlastic(_) | Kind::Principled(_), S::Diffuse) => true,
            (Kind::Principled(_), S::Roughness) => true,
            (_, S::SpecularReflectance) => !matches!(self.kind, Kind::Diffuse(_) | Kind::Principled(_)),
            (Kind::Dielectric(_) | Kind::RoughDielectric(_), S::SpecularTransmittance) => true,
            _ => false,
        }
    }

    /// This material with parameter `slot` set to `value` (a texture's value at a hit);
    /// unchanged where the model has no such slot ([`Self::has_slot`]). Lobe-selection
    /// weights stay those the material was built with, as Mitsuba's stay those of the
    /// texture's mean.
    pub fn with_texel(&self, slot: TextureSlot, value: Rgb) -> Self {
        use TextureSlot as S;
        let mut m = *self;
        match (&mut m.kind, slot) {
            (Kind::Diffuse(b), S::Diffuse) => b.reflectance = value,
            (Kind::Plastic(b), S::Diffuse) => *b = b.with_diffuse(value),
            (Kind::RoughPlastic(b), S::Diffuse) => *b = b.with_diffuse(value),
            (Kind::Plastic(b), S::SpecularReflectance) => b.specular_reflectance = value,
            (Kind::RoughPlastic(b), S::SpecularReflectance) => b.specular_reflectance = value,
            (Kind::Conductor(b), S::SpecularReflectance) => b.specular_reflectance = value,
            (Kind::RoughConductor(b), S::SpecularReflectance) => b.specular_reflectance = value,
            (Kind::Dielectric(b), S::SpecularReflectance) => b.specular_reflectance = value,
            (Kind::RoughDielectric(b), S::SpecularReflectance) => b.specular_reflectance = value,
            (Kind::Dielectric(b), S::SpecularTransmittance) => b.specular_transmittance = value,
            (Kind::RoughDielectric(b), S::SpecularTransmittance) => b.specular_transmittance = value,
            (Kind::Principled(b), S::Diffuse) => b.p.base_color = value,
            (Kind::Principled(b), S::Roughness) => *b = Principled::new(PrincipledParams { roughness: value.luminance(), ..b.p }),
            _ => {}
        }
        m
    }

    /// Mitsuba's `twosided`: the back side (wo.z < 0) behaves like the front, mirrored
    /// through the surface plane. No effect on dielectrics, which are two-sided already.
    pub fn two_sided(self) -> Self {
        Self { two_sided: !self.has_transmission(), ..self }
    }

    /// True when a two-sided material is seen from the back, so directions are mirrored.
    #[inline]
    fn mirrored(&self, wo: Vec3) -> bool {
        self.two_sided && wo.z < 0.0
    }

    /// BSDF value f(wo, wi) for `mode` (the adjoint in `Importance` mode), without the
    /// cosine. Zero for Dirac materials.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        if self.mirrored(wo) {
            return self.eval_front(flip_z(wo), flip_z(wi), mode);
        }
        self.eval_front(wo, wi, mode)
    }

    fn eval_front(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        let f = match &self.kind {
            Kind::Diffuse(b) => b.eval(wo, wi),
            Kind::RoughConductor(b) => b.eval(wo, wi),
            Kind::RoughDielectric(b) => b.eval(wo, wi, mode),
            Kind::RoughPlastic(b) => b.eval(wo, wi),
            Kind::Plastic(b) => b.eval(wo, wi),
            Kind::Principled(b) => b.eval(wo, wi, mode),
            Kind::Conductor(_) | Kind::Dielectric(_) => Rgb::ZERO,
        };
        if f.is_finite() { f } else { Rgb::ZERO }
    }

    /// Solid-angle density with which [`Self::sample`] draws `wi` given `wo` (continuous
    /// lobes; 0 for Dirac materials). Independent of the mode.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> SolidAnglePdf {
        let (wo, wi) = if self.mirrored(wo) { (flip_z(wo), flip_z(wi)) } else { (wo, wi) };
        self.pdf_front(wo, wi)
    }

    /// (`eval`, `pdf`) together: the same bits as calling both, sharing what the model's
    /// two evaluations have in common (the rough conductor's half vector, D and G1).
    #[inline]
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (Rgb, SolidAnglePdf) {
        let (wo, wi) = if self.mirrored(wo) { (flip_z(wo), flip_z(wi)) } else { (wo, wi) };
        match &self.kind {
            Kind::RoughConductor(b) => {
                let (f, pdf) = b.eval_pdf(wo, wi);
                (if f.is_finite() { f } else { Rgb::ZERO }, Self::checked_pdf(pdf))
            }
            _ => (self.eval_front(wo, wi, mode), self.pdf_front(wo, wi)),
        }
    }

    /// (`eval`, `pdf`, `pdf_rev`) together: the same bits as calling the three, sharing
    /// what the model's evaluations have in common (the rough conductor's half vector, D
    /// and both G1). A two-sided material seen from different sides by `wo` and `wi`
    /// mirrors each call differently, so those calls are made one by one.
    pub fn eval_pdfs(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (Rgb, SolidAnglePdf, SolidAnglePdf) {
        if self.mirrored(wo) != self.mirrored(wi) {
            return (self.eval(wo, wi, mode), self.pdf(wo, wi, mode), self.pdf_rev(wo, wi, mode));
        }
        let (wo, wi) = if self.mirrored(wo) { (flip_z(wo), flip_z(wi)) } else { (wo, wi) };
        match &self.kind {
            Kind::RoughConductor(b) => {
                let (f, pdf, pdf_rev) = b.eval_pdfs(wo, wi);
                (if f.is_finite() { f } else { Rgb::ZERO }, Self::checked_pdf(pdf), Self::checked_pdf(pdf_rev))
            }
            _ => (self.eval_front(wo, wi, mode), self.pdf_front(wo, wi), self.pdf_front(wi, wo)),
        }
    }

    fn pdf_front(&self, wo: Vec3, wi: Vec3) -> SolidAnglePdf {
        let pdf = match &self.kind {
            Kind::Diffuse(b) => b.pdf(wo, wi),
            Kind::RoughConductor(b) => b.pdf(wo, wi),
            Kind::RoughDielectric(b) => b.pdf(wo, wi),
            Kind::RoughPlastic(b) => b.pdf(wo, wi),
            Kind::Plastic(b) => b.pdf(wo, wi),
            Kind::Principled(b) => b.pdf(wo, wi),
            Kind::Conductor(_) | Kind::Dielectric(_) => SolidAnglePdf::ZERO,
        };
        Self::checked_pdf(pdf)
    }

    /// [`Self::eval`] for `wo` already local to `frame` (whose normal is the shading
    /// normal) and `wi` in world space: the same bits as `eval(wo, frame.to_local(wi))`.
    /// A lobe that reads only the cosines (the Lambertian one) skips the rest of the
    /// transform: a local direction's z is its dot with the normal, bit for bit. The
    /// segment filters evaluate each node's BSDF for dozens of neighbours' directions.
    #[inline]
    pub fn eval_from_local(&self, frame: &Frame, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        match self.cosine_directions(wo.z, frame.n.dot(wi)) {
            Some((o, i)) => self.eval(o, i, mode),
            None => self.eval(wo, frame.to_local(wi), mode),
        }
    }

    /// [`Self::eval`] for world-space `wo` and `wi` at a point of shading normal `ns`: the
    /// same bits as through `Frame::from_normal(ns)`, which is built only for lobes that
    /// read more than the cosines.
    #[inline]
    pub fn eval_world(&self, ns: Vec3, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        let (o, i) = self.local_directions(ns, wo, wi);
        self.eval(o, i, mode)
    }

    /// [`Self::pdf`] as [`Self::eval_world`].
    #[inline]
    pub fn pdf_world(&self, ns: Vec3, wo: Vec3, wi: Vec3, mode: TransportMode) -> SolidAnglePdf {
        let (o, i) = self.local_directions(ns, wo, wi);
        self.pdf(o, i, mode)
    }

    /// World-space `wo` and `wi` in the shading frame of normal `ns`, as far as this lobe
    /// reads them: the cosines alone for the Lambertian one, through the frame otherwise.
    #[inline]
    fn local_directions(&self, ns: Vec3, wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
        self.cosine_directions(ns.dot(wo), ns.dot(wi)).unwrap_or_else(|| {
            let frame = Frame::from_normal(ns);
            (frame.to_local(wo), frame.to_local(wi))
        })
    }

    /// For a lobe whose value and density read only the directions' cosines to the normal
    /// (the Lambertian one), local directions with the cosines `cos_o` and `cos_i` as z;
    /// `None` for every other lobe.
    #[inline]
    fn cosine_directions(&self, cos_o: f32, cos_i: f32) -> Option<(Vec3, Vec3)> {
        let Kind::Diffuse(_) = &self.kind else { return None };
        Some((Vec3::new(0.0, 0.0, cos_o), Vec3::new(0.0, 0.0, cos_i)))
    }

    /// Denormal cosines can overflow the Jacobians (found by fuzzing): no density.
    #[inline]
    fn checked_pdf(pdf: SolidAnglePdf) -> SolidAnglePdf {
        if pdf.value().is_finite() && pdf.value() >= 0.0 { pdf } else { SolidAnglePdf::ZERO }
    }

    /// Density of sampling `wo` given `wi`: `pdf(wi, wo)`.
    #[inline]
    pub fn pdf_rev(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> SolidAnglePdf {
        self.pdf(wi, wo, mode)
    }

    /// Draw `wi` given `wo`: `u_lobe` chooses between reflection and refraction
    /// (dielectrics), `u` draws the direction. `None` when nothing is scattered (back side
    /// of a one-sided material, grazing `wo`, an absorbed microfacet sample).
    #[inline]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        if self.mirrored(wo) {
            let mut s = self.sample_front(flip_z(wo), u_lobe, u, mode)?;
            s.wi = flip_z(s.wi);
            return Some(s);
        }
        self.sample_front(wo, u_lobe, u, mode)
    }

    fn sample_front(&self, wo: Vec3, u_lobe: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        // Denormal cos θo counts as grazing: Dirac values f = R/|cos θi| overflow there
        // (found by fuzzing).
        if !(wo.z.abs() >= f32::MIN_POSITIVE && wo.is_finite()) {
            return None;
        }
        let s = match &self.kind {
            Kind::Diffuse(b) => b.sample(wo, u),
            Kind::Conductor(b) => b.sample(wo),
            Kind::RoughConductor(b) => b.sample(wo, u),
            Kind::Dielectric(b) => b.sample(wo, u_lobe, mode),
            Kind::RoughDielectric(b) => b.sample(wo, u_lobe, u, mode),
            Kind::RoughPlastic(b) => b.sample(wo, u_lobe, u),
            Kind::Plastic(b) => b.sample(wo, u_lobe, u),
            Kind::Principled(b) => b.sample(wo, u_lobe, u, mode),
        }?;
        // No sample rather than a non-finite one.
        (s.f.is_finite() && s.pdf.value().is_finite() && s.pdf_rev.value().is_finite()).then_some(s)
    }

    /// The Lambertian model as lane code evaluates and samples it; `None` for every other
    /// model. The lane kernels shade such surfaces over many paths at once.
    #[inline]
    pub(crate) fn lambertian(&self) -> Option<LambertLane> {
        match &self.kind {
            Kind::Diffuse(b) => Some(LambertLane { rho: b.reflectance, two_sided: self.two_sided }),
            _ => None,
        }
    }

    /// Every lobe is a Dirac distribution (smooth conductor, smooth dielectric): nothing
    /// can connect to it.
    pub fn is_delta(&self) -> bool {
        matches!(self.kind, Kind::Conductor(_) | Kind::Dielectric(_))
    }

    /// Some lobe is a Dirac distribution, so a sample may have `is_delta` set (the
    /// smooth conductor and dielectric, and smooth plastic's mirror lobe).
    pub fn has_delta_lobe(&self) -> bool {
        matches!(self.kind, Kind::Conductor(_) | Kind::Dielectric(_) | Kind::Plastic(_))
    }

    /// The smallest microfacet roughness α of a rough model (its distribution's own α);
    /// `None` for diffuse and the smooth models. The scene plan tells glossy from rough
    /// surfaces with it.
    pub fn roughness(&self) -> Option<f32> {
        match &self.kind {
            Kind::RoughConductor(b) => Some(b.distr.alpha),
            Kind::RoughDielectric(b) => Some(b.distr.alpha),
            Kind::RoughPlastic(b) => Some(b.distr.alpha),
            Kind::Principled(b) => Some(b.min_alpha()),
            _ => None,
        }
    }

    /// The material can transmit light to the other side.
    pub fn has_transmission(&self) -> bool {
        match &self.kind {
            Kind::Principled(b) => b.has_transmission(),
            k => matches!(k, Kind::Dielectric(_) | Kind::RoughDielectric(_)),
        }
    }

    /// A rough reflectance-like colour, for Russian roulette and SPCBPT features:
    /// ρ for diffuse, the normal-incidence Fresnel reflectance times the specular
    /// reflectance for conductors, F0·R_s + (1 − F0)·T_s for dielectrics.
    pub fn albedo_hint(&self) -> Rgb {
        match &self.kind {
            Kind::Diffuse(b) => b.reflectance,
            Kind::Conductor(b) => b.reflectance(1.0),
            Kind::RoughConductor(b) => fresnel::conductor(1.0, b.eta, b.k) * b.specular_reflectance,
            Kind::Dielectric(b) => b.albedo_hint(),
            Kind::RoughDielectric(b) => b.albedo_hint(),
            Kind::RoughPlastic(b) => b.albedo_hint(),
            Kind::Plastic(b) => b.albedo_hint(),
            Kind::Principled(b) => b.albedo_hint(),
        }
    }
}

/// Veach's adjoint correction for shading normals (thesis §5.3; pbrt-v3
/// `CorrectShadingNormal`): for `Importance` mode |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|), 1 for
/// `Radiance`. World-space directions and normals. Returns 0 instead of ∞ or NaN.
#[inline(always)]
pub fn shading_normal_correction(mode: TransportMode, wo: Vec3, wi: Vec3, ng: Vec3, ns: Vec3) -> f32 {
    match mode {
        TransportMode::Radiance => 1.0,
        TransportMode::Importance => {
            let num = wo.dot(ns).abs() * wi.dot(ng).abs();
            let denom = wo.dot(ng).abs() * wi.dot(ns).abs();
            let r = num / denom;
            if denom > 0.0 && r.is_finite() { r } else { 0.0 }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`Material::eval_from_local`], [`Material::eval_world`] and
    /// [`Material::pdf_world`] give the bits of [`Material::eval`] and [`Material::pdf`]
    /// of the local directions, for one- and two-sided Lambertian materials (the cosine
    /// shortcut) and a rough conductor (the frame), from above and below. Seen failing
    /// with the two cosines swapped (the density is cos θi / π).
    #[test]
    fn cosine_forms_equal_the_framed_ones() {
        let mut state = 3u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) as f32) / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        let diffuse = Material::diffuse(Rgb::new(0.2, 0.5, 0.8));
        let glossy = Material::rough_conductor(MicrofacetKind::Ggx, 0.3, Rgb::splat(0.2), Rgb::splat(3.0), Rgb::ONE);
        for m in [diffuse, diffuse.two_sided(), glossy] {
            for _ in 0..2000 {
                let n = Vec3::new(next(), next(), next()).normalize_or(Vec3::Z);
                let (wo, wi) = (Vec3::new(next(), next(), next()).normalize_or(Vec3::X), Vec3::new(next(), next(), next()).normalize_or(Vec3::Y));
                let f = Frame::from_normal(n);
                let (lo, li) = (f.to_local(wo), f.to_local(wi));
                for mode in [TransportMode::Radiance, TransportMode::Importance] {
                    let bits = |f: Rgb| [f.r.to_bits(), f.g.to_bits(), f.b.to_bits()];
                    let want = bits(m.eval(lo, li, mode));
                    assert_eq!(bits(m.eval_from_local(&f, lo, wi, mode)), want);
                    assert_eq!(bits(m.eval_world(n, wo, wi, mode)), want);
                    assert_eq!(m.pdf_world(n, wo, wi, mode).0.to_bits(), m.pdf(lo, li, mode).0.to_bits());
                }
            }
        }
    }
}
