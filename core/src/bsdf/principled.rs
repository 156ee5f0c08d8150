//! Mitsuba 3's `principled` BSDF: Burley's "Physically Based Shading at Disney" (2012)
//! BRDF extended to a BSDF ("Extending the Disney BRDF to a BSDF with Integrated
//! Subsurface Scattering", 2015), in the form Mitsuba 3 gives it
//! (`src/bsdfs/principled.cpp`, `principledhelpers.h`), written here from that model.
//!
//! Notation: `wo` points toward where the path came from, `wi` is the other direction
//! (module docs of `bsdf`); cos θ is a direction's z; h is the half vector of (wo, wi),
//! h ∝ wo + wi for reflection and h ∝ wo + η wi for refraction (Walter et al. 2007,
//! eq. 16), turned to h.z > 0; η is η_int/η_ext seen from `wo` (its inverse from inside).
//! Lobe weights: brdf = (1 − metallic)(1 − spec_trans), bsdf = (1 − metallic) spec_trans.
//! Values below are f *without* the cosine |cos θi| (Mitsuba's `eval` carries it).
//!
//! - **Main specular reflection** (both sides): f = F_p D G / (4 |cos θo| |cos θi|), D the
//!   anisotropic GGX with α_x = max(10⁻³, r²/a), α_y = max(10⁻³, r² a),
//!   a = √(1 − 0.9 anisotropic) (Burley 2012, §B.2), G Smith's separable masking. On the
//!   front F_p = (1 − m)(1 − t) F_d + m S(base) + (1 − m) t S(c_tint R0(η)), with F_d the
//!   dielectric Fresnel of wo·h, S(R0) Schlick's R0 + (1 − R0)(1 − cos)⁵ (taken at the
//!   refracted cosine when η < 1), c_tint = base/lum(base), R0(η) = ((η − 1)/(η + 1))²;
//!   from the back F_p = bsdf F_d.
//! - **Specular transmission**: Walter's rough dielectric (eq. 21) times √base · bsdf,
//!   with the (1/η)² radiance compression in `Radiance` mode only (the adjoint otherwise).
//! - **Clearcoat** (front): f = ¼ clearcoat F_cc D_cc G_cc, with D_cc the GTR1
//!   distribution (Burley 2012, eq. 4) of α_cc = lerp(0.1, 0.001, clearcoat_gloss),
//!   F_cc = S(0.04) and G_cc the GGX Smith masking of α = 0.25. This is Mitsuba's form:
//!   without Burley's 1/(4 cos θo cos θi).
//! - **Diffuse** (front): f = brdf base/π · lerp(f_d + f_r, f_ss, flatness) with
//!   F_o, F_i the Schlick weights (1 − |cos|)⁵, f_d = (1 − F_o/2)(1 − F_i/2),
//!   R_r = 2 roughness cos²θ_d (cos θ_d = wi·h), f_r = R_r (F_o + F_i + F_o F_i (R_r − 1))
//!   (retro-reflection), and Hanrahan–Krueger's fake subsurface
//!   f_ss = 1.25 (F_ss (1/(|cos θo| + |cos θi|) − ½) + ½), F_ss = lerp(1, R_r/2, F_o)
//!   lerp(1, R_r/2, F_i) (Burley 2012, §5.3).
//! - **Sheen** (front, where brdf > 0): f = sheen (1 − m) (1 − |cos θ_d|)⁵ lerp(1, c_tint,
//!   sheen_tint).
//!
//! Every reflection lobe is symmetric in (wo, wi) (wo·h = wi·h), so f(wo, wi) = f(wi, wo);
//! transmission obeys the dielectric's rule (see `rough_dielectric.rs`).
//!
//! **Sampling** (Mitsuba's scheme). From the front, a lobe is chosen with probabilities
//! proportional to P_diff = brdf r_d, P_cc = ¼ clearcoat r_c and P_spec = r_s (the
//! `*_sampling_rate`s); the specular share splits into reflection 1 − bsdf(1 − F) and
//! transmission bsdf(1 − F), F the dielectric Fresnel at the sampled visible normal.
//! (Mitsuba writes the four probabilities with F inside; their sum does not depend on F,
//! so this is the same mixture.) From the back only the specular lobes are drawn:
//! reflection with probability F, refraction 1 − F. Diffuse draws cos θi/π; clearcoat
//! draws m ∝ D_cc cos θm (not visible normals, as Mitsuba) and reflects; the specular
//! lobes draw visible GGX normals (Heitz 2018) for ±wo. The density is
//!
//!   p(wi) = P_diff cos θi/π + (P_refl D_wo(h) + P_cc D_cc(h) cos θh) |∂h/∂wi| + P_trans D_wo(h) |∂h/∂wi|
//!
//! with |∂h/∂wi| = 1/(4 |wi·h|) for reflection and η² |wi·h| / (wo·h + η wi·h)² for
//! refraction (Walter et al. 2007, eqs. 14 and 17). Samples that land on the wrong side
//! of the macro-surface, or see the back of their facet, are absorbed (`None`), and their
//! mass is missing from the density too.
//!
//! Two deliberate differences from Mitsuba (docs/scene-features.md lists all):
//! - seen from the back without a transmission lobe (bsdf = 0), Mitsuba's `pdf` is
//!   positive where its `sample` draws nothing and its `eval` is zero; here the density is
//!   zero there, so that `sample` and `pdf` describe one distribution;
//! - sheen needs brdf > 0, as in Mitsuba's `scalar_rgb` variant (its vectorised variants
//!   add sheen also where brdf = 0, where no lobe samples it).

use super::{BsdfSample, TransportMode, fresnel};
use crate::math::{INV_PI, PI, Vec2, Vec3, lerp, ln, powf, reflect, safe_sqrt, sin_cos_turns, sqrt};
use crate::measure::SolidAnglePdf;
use crate::spectrum::Rgb;
use crate::warp;

/// The parameters of Mitsuba's `principled`, with its names; [`Default`] gives its
/// defaults. Weights are meant to lie in [0, 1] (the reader checks them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipledParams {
    /// `base_color` (default 0.5).
    pub base_color: Rgb,
    /// `roughness` (default 0.5): the specular lobes' α = roughness² and the retro-reflection.
    pub roughness: f32,
    /// `anisotropic` (default 0): stretches α along the shading frame's first tangent.
    pub anisotropic: f32,
    /// `metallic` (default 0).
    pub metallic: f32,
    /// `spec_tint` (default 0): the base colour's share in the dielectric reflection.
    pub spec_tint: f32,
    /// `sheen` (default 0).
    pub sheen: f32,
    /// `sheen_tint` (default 0).
    pub sheen_tint: f32,
    /// `flatness` (default 0): blends the diffuse lobe toward the fake subsurface one.
    pub flatness: f32,
    /// `clearcoat` (default 0).
    pub clearcoat: f32,
    /// `clearcoat_gloss` (default 0).
    pub clearcoat_gloss: f32,
    /// `spec_trans` (default 0): the share of the dielectric lobes that transmits.
    pub spec_trans: f32,
    /// η_int/η_ext; Mitsuba's default derives from `specular` = 0.5: 1.5
    /// ([`Self::eta_from_specular`]).
    pub eta: f32,
    /// `diffuse_reflectance_sampling_rate` (default 1).
    pub diffuse_sampling_rate: f32,
    /// `main_specular_sampling_rate` (default 1).
    pub specular_sampling_rate: f32,
    /// `clearcoat_sampling_rate` (default 1, as Mitsuba's code; its docs say 0).
    pub clearcoat_sampling_rate: f32,
}

impl Default for PrincipledParams {
    fn default() -> Self {
        Self {
            base_color: Rgb::splat(0.5),
            roughness: 0.5,
            anisotropic: 0.0,
            metallic: 0.0,
            spec_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            flatness: 0.0,
            clearcoat: 0.0,
            clearcoat_gloss: 0.0,
            spec_trans: 0.0,
            eta: Self::eta_from_specular(0.5),
            diffuse_sampling_rate: 1.0,
            specular_sampling_rate: 1.0,
            clearcoat_sampling_rate: 1.0,
        }
    }
}

impl PrincipledParams {
    /// Mitsuba's map from `specular` to η: R0 = 0.08 specular = ((η − 1)/(η + 1))²,
    /// η = 2/(1 − √(0.08 specular)) − 1.
    pub fn eta_from_specular(specular: f32) -> f32 {
        2.0 / (1.0 - sqrt(0.08 * specular)) - 1.0
    }
}

/// Anisotropic GGX (Trowbridge–Reitz) around +z, with its Smith masking and visible-normal
/// sampling side by side (the isotropic `Microfacet` does not stretch).
#[derive(Clone, Copy, Debug, PartialEq)]
struct AnisoGgx {
    ax: f32,
    ay: f32,
}

impl AnisoGgx {
    /// D(m) = 1 / (π α_x α_y ((m_x/α_x)² + (m_y/α_y)² + m_z²)²), zero below the horizon
    /// and where D cos θm < 10⁻²⁰ (as Mitsuba).
    fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let t = (m.x / self.ax) * (m.x / self.ax) + (m.y / self.ay) * (m.y / self.ay) + m.z * m.z;
        let r = 1.0 / (PI * self.ax * self.ay * t * t);
        if r * m.z > 1e-20 { r } else { 0.0 }
    }

    /// Smith's G1 = 2 / (1 + √(1 + (α_x² v_x² + α_y² v_y²)/v_z²)), zero where `v` sees the
    /// back of the facet.
    fn g1(&self, v: Vec3, m: Vec3) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let t2 = (self.ax * self.ax * v.x * v.x + self.ay * self.ay * v.y * v.y) / (v.z * v.z);
        let g = 2.0 / (1.0 + sqrt(1.0 + t2));
        if g.is_finite() { g } else { 0.0 }
    }

    /// A visible normal for `wo` (upper hemisphere): Heitz, "Sampling the GGX Distribution
    /// of Visible Normals", JCGT 7(4), 2018. Density [`Self::visible_pdf`].
    fn sample_visible(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        let vh = Vec3::new(self.ax * wo.x, self.ay * wo.y, wo.z).normalize_or_zero();
        if !(vh.z > 0.0) {
            return None;
        }
        let nh = super::microfacet::ggx_visible_stretched(vh, u);
        let m = Vec3::new(self.ax * nh.x, self.ay * nh.y, nh.z.max(0.0)).normalize_or_zero();
        (m.z > 0.0 && m.is_finite()).then_some(m)
    }

    /// D_wo(m) = G1(wo, m) max(0, wo·m) D(m) / cos θo (Heitz & d'Eon 2014), `wo.z > 0`.
    fn visible_pdf(&self, wo: Vec3, m: Vec3) -> f32 {
        let c = wo.dot(m);
        if !(wo.z > 0.0) || c <= 0.0 {
            return 0.0;
        }
        self.g1(wo, m) * c * self.d(m) / wo.z
    }
}

/// Burley's GTR1 ("generalised Trowbridge–Reitz", γ = 1) for the clearcoat, sampled by
/// its normals (density D cos θm per steradian of m).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Gtr1 {
    alpha: f32,
}

impl Gtr1 {
    /// D(m) = (α² − 1) / (π ln α² (1 + (α² − 1) cos²θm)) (Burley 2012, eq. 4, normalised).
    fn d(&self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let r = (a2 - 1.0) / (PI * ln(a2) * (1.0 + (a2 - 1.0) * m.z * m.z));
        if r * m.z > 1e-20 { r } else { 0.0 }
    }

    /// Density of [`Self::sample`]: D(m) cos θm.
    fn pdf(&self, m: Vec3) -> f32 {
        if m.z < 0.0 { 0.0 } else { m.z * self.d(m) }
    }

    /// Inverts the CDF: cos²θm = (1 − α^(2(1 − u_y))) / (1 − α²), φ = 2π u_x.
    fn sample(&self, u: Vec2) -> Vec3 {
        let a2 = self.alpha * self.alpha;
        let cos2 = (1.0 - powf(a2, 1.0 - u.y)) / (1.0 - a2);
        let (sin_t, cos_t) = (safe_sqrt(1.0 - cos2), safe_sqrt(cos2));
        let (sp, cp) = sin_cos_turns(u.x);
        Vec3::new(cp * sin_t, sp * sin_t, cos_t)
    }
}

/// GGX Smith G1 of the clearcoat (fixed α = 0.25): 2 / (1 + √(1 + α² tan²θ)).
fn clearcoat_g1(v: Vec3, h: Vec3) -> f32 {
    if v.dot(h) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let c2 = v.z * v.z;
    let g = 2.0 / (1.0 + sqrt(1.0 + 0.0625 * (1.0 - c2) / c2));
    if g.is_finite() { g } else { 0.0 }
}

/// Schlick's weight (1 − cos)⁵, cos clamped to [0, 1].
fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// The weight w of Schlick's F = R0 + (1 − R0) w at cosine `cos_i` (signed, against h)
/// for relative index `eta`: (1 − |cos θi|)⁵ entering a denser medium, (1 − cos θt)⁵
/// (the refracted cosine; 0 under total internal reflection gives 1) otherwise.
fn schlick_fresnel_weight(cos_i: f32, eta: f32) -> f32 {
    let eta_it = if cos_i >= 0.0 { eta } else { 1.0 / eta };
    if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        let eta_ti = 1.0 / eta_it;
        schlick_weight(safe_sqrt(1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti))
    }
}

/// Base colour over its luminance (white for a black base).
fn tint(base: Rgb) -> Rgb {
    let lum = base.luminance();
    if lum > 0.0 { base * (1.0 / lum) } else { Rgb::ONE }
}

/// The configuration linking `wo` and `wi`: side, half vector and what the lobes share.
#[derive(Clone, Copy, Debug)]
struct Config {
    front: bool,
    reflect: bool,
    /// η seen from `wo`.
    eta_path: f32,
    /// Half vector, h.z ≥ 0.
    h: Vec3,
    /// Dielectric Fresnel reflectance of wo·h.
    f_d: f32,
    /// Both directions see the front of h on their sides (Mitsuba's `mac_mic_compatibility`).
    compatible: bool,
}

/// Mitsuba's `principled` (module docs), resolved: parameters and the derived roughnesses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Principled {
    pub p: PrincipledParams,
    spec: AnisoGgx,
    coat: Gtr1,
}

impl Principled {
    pub fn new(p: PrincipledParams) -> Self {
        // η as the other models read indices: invalid → index-matched, extremes clamped.
        let p = PrincipledParams { eta: super::relative_ior(p.eta, 1.0), ..p };
        let r2 = p.roughness * p.roughness;
        let aspect = sqrt(1.0 - 0.9 * p.anisotropic);
        let (ax, ay) = if p.anisotropic == 0.0 { (r2, r2) } else { (r2 / aspect, r2 * aspect) };
        // `max` also sends NaN to the floor.
        let spec = AnisoGgx { ax: ax.max(1e-3), ay: ay.max(1e-3) };
        let coat = Gtr1 { alpha: lerp(p.clearcoat_gloss, 0.1, 0.001) };
        Self { p, spec, coat }
    }

    /// The diffuse weight (1 − metallic)(1 − spec_trans).
    fn brdf(&self) -> f32 {
        (1.0 - self.p.metallic) * (1.0 - self.p.spec_trans)
    }

    /// The transmission weight (1 − metallic) spec_trans.
    fn bsdf(&self) -> f32 {
        (1.0 - self.p.metallic) * self.p.spec_trans
    }

    /// The model transmits (some light reaches the other side).
    pub fn has_transmission(&self) -> bool {
        self.bsdf() > 0.0
    }

    /// The smallest roughness of its glossy lobes.
    pub fn min_alpha(&self) -> f32 {
        let a = self.spec.ax.min(self.spec.ay);
        if self.p.clearcoat > 0.0 { a.min(self.coat.alpha) } else { a }
    }

    /// Lobe probabilities (P_diff, P_cc, P_spec) from the front, normalised; `None` when
    /// all vanish. From the back the specular lobes take everything.
    fn front_probabilities(&self) -> Option<(f32, f32, f32)> {
        let p_diff = (self.brdf() * self.p.diffuse_sampling_rate).max(0.0);
        let p_cc = if self.p.clearcoat > 0.0 { (0.25 * self.p.clearcoat * self.p.clearcoat_sampling_rate).max(0.0) } else { 0.0 };
        let p_spec = self.p.specular_sampling_rate.max(0.0);
        let total = p_diff + p_cc + p_spec;
        (total > 0.0 && total.is_finite()).then(|| (p_diff / total, p_cc / total, p_spec / total))
    }

    /// (P_reflect, P_transmit) of the specular lobes given the Fresnel reflectance `f_d`
    /// at the facet: the split 1 − bsdf(1 − F) : bsdf(1 − F) from the front, F : 1 − F
    /// from the back.
    fn specular_split(&self, front: bool, f_d: f32) -> (f32, f32) {
        let t = if front { self.bsdf() * (1.0 - f_d) } else { 1.0 - f_d };
        (1.0 - t, t)
    }

    /// Half vector and side tests of (wo, wi), or `None` for grazing directions, a
    /// degenerate half vector, or the back side of a model that does not transmit.
    fn config(&self, wo: Vec3, wi: Vec3) -> Option<Config> {
        let (co, ci) = (wo.z, wi.z);
        if co == 0.0 || ci == 0.0 || !(wo.is_finite() && wi.is_finite()) {
            return None;
        }
        let front = co > 0.0;
        if !front && !self.has_transmission() {
            return None;
        }
        let reflect = co * ci > 0.0;
        let eta_path = if front { self.p.eta } else { 1.0 / self.p.eta };
        let h = super::microfacet::half_vector(wo, wi, reflect, eta_path)?;
        let s = if front { 1.0 } else { -1.0 };
        let (dot_o, dot_i) = (wo.dot(h) * s, wi.dot(h) * s);
        let compatible = dot_o > 0.0 && if reflect { dot_i > 0.0 } else { dot_i < 0.0 };
        let f_d = fresnel::dielectric(wo.dot(h), self.p.eta).f;
        Some(Config { front, reflect, eta_path, h, f_d, compatible })
    }

    /// The front's specular Fresnel term F_p (module docs) at wo·h = `cos`.
    fn principled_fresnel(&self, f_d: f32, cos: f32) -> Rgb {
        let (m, t, eta) = (self.p.metallic, self.p.spec_tint, self.p.eta);
        let eta_it = if cos >= 0.0 { eta } else { 1.0 / eta };
        let w = schlick_fresnel_weight(cos, eta);
        let schlick = |r0: Rgb| r0 + (Rgb::ONE - r0) * w;
        let r0_tint = tint(self.p.base_color) * (((eta_it - 1.0) / (eta_it + 1.0)) * ((eta_it - 1.0) / (eta_it + 1.0)));
        Rgb::splat((1.0 - m) * (1.0 - t) * f_d) + schlick(self.p.base_color) * m + schlick(r0_tint) * ((1.0 - m) * t)
    }

    /// BSDF value (module docs), without the cosine.
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        let Some(c) = self.config(wo, wi) else { return Rgb::ZERO };
        let (co, ci) = (wo.z.abs(), wi.z.abs());
        let h = c.h;
        let mut value = Rgb::ZERO;
        if c.compatible {
            // Step 1: the specular lobes (one of the two, by side).
            let d = self.spec.d(h);
            let g = self.spec.g1(wo, h) * self.spec.g1(wi, h);
            if c.reflect && c.f_d > 0.0 {
                let f_p = if c.front { self.principled_fresnel(c.f_d, wo.dot(h)) } else { Rgb::splat(self.bsdf() * c.f_d) };
                value += f_p * (d * g / (4.0 * co * ci));
            } else if !c.reflect && self.bsdf() > 0.0 && c.f_d < 1.0 {
                let scale = match mode {
                    TransportMode::Radiance => 1.0 / (c.eta_path * c.eta_path),
                    TransportMode::Importance => 1.0,
                };
                let (dot_o, dot_i) = (wo.dot(h), wi.dot(h));
                let denom = dot_o + c.eta_path * dot_i;
                let t = scale * (1.0 - c.f_d) * d * g * c.eta_path * c.eta_path * dot_o * dot_i / (wo.z * denom * denom);
                value += self.p.base_color.map(sqrt) * (self.bsdf() * t.abs() / ci);
            }
            // Step 2: the clearcoat (front reflection).
            if c.reflect && c.front && self.p.clearcoat > 0.0 {
                let f_cc = 0.04 + 0.96 * schlick_fresnel_weight(wo.dot(h), self.p.eta);
                let g_cc = clearcoat_g1(wo, h) * clearcoat_g1(wi, h);
                value += Rgb::splat(0.25 * self.p.clearcoat * f_cc * self.coat.d(h) * g_cc);
            }
        }
        // Step 3: diffuse, retro-reflection, fake subsurface and sheen (front reflection).
        let brdf = self.brdf();
        if c.reflect && c.front && brdf > 0.0 {
            let (f_o, f_i) = (schlick_weight(ci), schlick_weight(co));
            let f_diff = (1.0 - 0.5 * f_i) * (1.0 - 0.5 * f_o);
            let cos_d = h.dot(wi);
            let rr = 2.0 * self.p.roughness * cos_d * cos_d;
            let f_retro = rr * (f_o + f_i + f_o * f_i * (rr - 1.0));
            let mut shape = f_diff + f_retro;
            if self.p.flatness != 0.0 {
                let fss90 = 0.5 * rr;
                let fss = lerp(f_o, 1.0, fss90) * lerp(f_i, 1.0, fss90);
                let f_ss = 1.25 * (fss * (1.0 / (co + ci) - 0.5) + 0.5);
                shape = lerp(self.p.flatness, shape, f_ss);
            }
            value += self.p.base_color * (brdf * INV_PI * shape);
            if self.p.sheen > 0.0 && self.p.metallic < 1.0 {
                let c_sheen = Rgb::ONE + (tint(self.p.base_color) - Rgb::ONE) * self.p.sheen_tint;
                value += c_sheen * (self.p.sheen * (1.0 - self.p.metallic) * schlick_weight(cos_d.abs()));
            }
        }
        if value.is_finite() { value } else { Rgb::ZERO }
    }

    /// Density of [`Self::sample`] (module docs).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> SolidAnglePdf {
        let Some(c) = self.config(wo, wi) else { return SolidAnglePdf::ZERO };
        let (p_diff, p_cc, p_spec) = if c.front {
            let Some(p) = self.front_probabilities() else { return SolidAnglePdf::ZERO };
            p
        } else {
            (0.0, 0.0, 1.0)
        };
        let (p_refl, p_trans) = self.specular_split(c.front, c.f_d);
        let mut pdf = 0.0;
        if c.reflect {
            pdf += p_diff * warp::cosine_hemisphere_pdf(wi).value();
        }
        if c.compatible {
            let h = c.h;
            let dot_i = wi.dot(h);
            let wo_up = if c.front { wo } else { -wo };
            let d_vis = self.spec.visible_pdf(wo_up, h);
            if c.reflect {
                let jacobian = 1.0 / (4.0 * dot_i.abs());
                pdf += (p_spec * p_refl * d_vis + p_cc * self.coat.pdf(h)) * jacobian;
            } else {
                let denom = wo.dot(h) + c.eta_path * dot_i;
                let jacobian = c.eta_path * c.eta_path * dot_i.abs() / (denom * denom);
                pdf += p_spec * p_trans * d_vis * jacobian;
            }
        }
        SolidAnglePdf(pdf)
    }

    /// Choose a lobe with `u_lobe` (diffuse, clearcoat, transmission, reflection, in
    /// Mitsuba's order), draw its direction with `u`; value and densities from
    /// [`Self::eval`] and [`Self::pdf`].
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let front = wo.z > 0.0;
        if wo.z == 0.0 || (!front && !self.has_transmission()) {
            return None;
        }
        let (p_diff, p_cc, p_spec) = if front { self.front_probabilities()? } else { (0.0, 0.0, 1.0) };
        let wi = if u_lobe < p_diff {
            warp::sample_cosine_hemisphere(u)
        } else if u_lobe < p_diff + p_cc {
            let m = self.coat.sample(u);
            let wi = reflect(wo, m);
            if !(wi.z > 0.0 && wo.dot(m) > 0.0) {
                return None;
            }
            wi
        } else {
            // Step: a visible normal for ±wo, then refract or reflect by the split at it.
            let wo_up = if front { wo } else { -wo };
            let m = self.spec.sample_visible(wo_up, u)?;
            let fr = fresnel::dielectric(wo.dot(m), self.p.eta);
            let (_, p_trans) = self.specular_split(front, fr.f);
            let refracts = u_lobe < p_diff + p_cc + p_spec * p_trans;
            let wi = if refracts { fresnel::refract(wo, m, fr.cos_t, fr.eta_ti).normalize_or_zero() } else { reflect(wo, m) };
            if (wi.z * wo.z < 0.0) != refracts || wi.z == 0.0 {
                return None;
            }
            wi
        };
        let transmission = wi.z * wo.z < 0.0;
        let pdf = self.pdf(wo, wi);
        let f = self.eval(wo, wi, mode);
        if !(pdf.value() > 0.0 && pdf.value().is_finite() && f.is_finite()) {
            return None;
        }
        let eta = if transmission { if front { self.p.eta } else { 1.0 / self.p.eta } } else { 1.0 };
        Some(BsdfSample { wi, f, pdf, pdf_rev: self.pdf(wi, wo), is_delta: false, is_transmission: transmission, eta })
    }

    /// A rough albedo: the diffuse and metallic base, the transmitted √base and the
    /// dielectric reflection at normal incidence.
    pub fn albedo_hint(&self) -> Rgb {
        let f0 = fresnel::dielectric(1.0, self.p.eta).f;
        let b = self.p.base_color;
        let hint = b * (self.brdf() + self.p.metallic) + b.map(sqrt) * (self.bsdf() * (1.0 - f0)) + Rgb::splat(f0 * (1.0 - self.p.metallic));
        hint.map(|v| v.clamp(0.0, 1.0))
    }
}
