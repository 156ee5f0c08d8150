//! Segment-based light transport [Wang, West and Hachisuka 2025, "Segment-based Light
//! Transport Simulation", SIGGRAPH; cited below as eq. (n)].
//!
//! # What it estimates
//!
//! The unit of integration is a *segment* s = (x, y), a pair of surface points, and a
//! segment path s̄ = (s₁ … s_k) is k of them, not necessarily joined end to end. The pixel
//! value is the segment path integral J_ρ = Σ_k ∫_{𝓜^{2k}} g_ρ(s̄) ds̄ (eq. 3), with
//!
//! ```text
//!   g_ρ(s̄) = W_ρ(s₁) · Π_i G(s_i) · Π_{i<k} K(s_i, s_{i+1}) f_r(s_i, s_{i+1}) · L_e(s_k)   (eq. 4)
//! ```
//!
//! x₁ is the pinhole, y₁ the first surface seen; y_k lies on an emitter and L_e(s_k) is
//! the radiance it sends from y_k toward x_k. Between two segments the *kernel*
//! K(s_i, s_{i+1}) spreads light from y_i to the start x_{i+1} of the next segment; any
//! kernel with ∫ K dx_{i+1} = 1 keeps energy (eq. 5). With the Dirac kernel
//! (x_{i+1} = y_i) the segment path is an ordinary path and J_ρ the path integral (eq. 1);
//! with the disk kernel ([`Kernel::Disk`]) it is the path integral blurred over a disk of
//! radius r at every bounce, the bias that photon mapping and path filtering trade for
//! reuse. The *throughput* across a disconnection is shift invariant (eq. 6): the next
//! segment is translated so that it starts at y_i, and the BSDF of y_i is evaluated for
//! the incoming direction of s_i and the outgoing direction of s_{i+1}
//! ([`start_cosine`]). G(s) = |n_x·ŝ| |n_y·ŝ| V(x, y) / |x − y|² is the geometry term
//! of the segment itself.
//!
//! The recursive form (eq. 7, 8) L(s) = L_e(s) + ∫ K f_r G L(s') ds',
//! J_ρ = ∫ W_ρ G L ds is what the sequential estimators below walk.
//!
//! # Measures
//!
//! A segment's density is per unit area at x times per unit area at y: [`SegmentPdf`],
//! per m⁴, built only from two [`AreaPdf`]s. Sequential samplers never form it: they
//! divide each factor of g by the matching factor of eq. (15) as they go (the kernel's
//! K / p_K, the BSDF's f_r |cos| / p_ω), which is the same number with less rounding.
//!
//! # How each kind of light enters
//!
//! The kernel acts only *between* two segments, at a surface point y_i with i < k. The
//! path's two ends, the pinhole x₁ and the emitting end y_k, are never smoothed, so every
//! light enters exactly as in the vertex formulation, in its own measure: an area or
//! sphere light's y_k per unit area; a point or spot light's y_k is its position (a Dirac
//! point, the light's position as the segment's start in light tracing); a directional
//! or environment light's y_k is a direction at infinity (per unit solid angle). No
//! light is refused by the segment estimators here. (The independent samplers
//! [`sampler`] draw both endpoints on surfaces and so only ever reach area lights; they
//! are the paper's baselines of Fig. 2, not estimators.)
//!
//! # What is here
//!
//! - [`Kernel`]: the Dirac and disk kernels, with sample and density side by side.
//! - [`SurfaceSampler`]: uniform points over every surface, triangles and spheres alike.
//! - [`sampler`]: the uniform (eq. 12), ray-cast (eq. 13) and BSDF ray-cast (eq. 14)
//!   segment samplers.
//! - [`contribution`]: g (eq. 4) of an explicit segment path.
//!
//! The estimators built on them live with the other estimators: segment PT, LT and BDPT
//! (the sequential samplers of eq. (15) from the camera and from the lights with the
//! sequential estimator (eq. 16), and in segment PT the light-sampled last segment
//! combined by eq. (17)) in `crate::estimators::segment`, path filtering in
//! `crate::estimators::filter`.
//!
//! The kernels and [`start_cosine`] are always compiled: PT, LT and BDPT walk with an
//! optional kernel, and with none they are the vertex estimators. The samplers and
//! `contribution` need the cargo feature `segments` (docs/features.md).
//!
//! docs/segments.md has the derivations and what each test proves.

mod kernel;
#[cfg(feature = "segments")]
mod surfaces;

#[cfg(feature = "segments")]
pub mod contribution;
#[cfg(feature = "segments")]
pub mod sampler;

#[cfg(feature = "segments")]
pub use contribution::{contribution, geometry_term};
pub use kernel::{CAMERA_KERNEL_KEY, Junctions, Kernel, KernelSample, LIGHT_KERNEL_KEY};
#[cfg(feature = "segments")]
pub use surfaces::SurfaceSampler;

use crate::bsdf::{TransportMode, shading_normal_correction};
use crate::geometry::SurfaceHit;
use crate::math::Vec3;
use crate::measure::AreaPdf;

/// A segment endpoint: a position and its unit geometric normal (zero at the pinhole and
/// at a point light, where the cosine factor is 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    pub p: Vec3,
    pub n: Vec3,
}

impl Point {
    /// The pinhole or a point light: no surface.
    pub fn bare(p: Vec3) -> Self {
        Self { p, n: Vec3::ZERO }
    }
    /// A surface point.
    pub fn on(hit: &SurfaceHit) -> Self {
        Self { p: hit.p, n: hit.ng }
    }
    /// |n · w|, or 1 without a surface.
    #[inline]
    pub fn cos(&self, w: Vec3) -> f32 {
        if self.n == Vec3::ZERO { 1.0 } else { self.n.dot(w).abs() }
    }
}

/// A segment s = (x, y): where light is transported from y toward x (the camera side is
/// x). y carries its material and emitter, since the throughput f_r(s, s') is the BSDF of
/// y (eq. 6) and L_e(s) is emitted at y; x needs only a position and a normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub x: Point,
    pub y: SurfaceHit,
}

impl Segment {
    /// Unit direction from x to y.
    #[inline]
    pub fn dir(&self) -> Vec3 {
        (self.y.p - self.x.p).normalize_or_zero()
    }
}

/// A segment's density: per unit area at x times per unit area at y (per m⁴), in f64
/// because it is a product of two area densities that may each be tiny.
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
pub struct SegmentPdf(pub f64);

impl SegmentPdf {
    pub const ZERO: Self = Self(0.0);
    /// p(x) p(y | x).
    #[inline]
    pub fn joint(px: AreaPdf, py_given_x: AreaPdf) -> Self {
        Self(px.0 as f64 * py_given_x.0 as f64)
    }
    #[inline]
    pub fn value(self) -> f64 {
        self.0
    }
}

/// The shift-invariant throughput across the junction of s_i and s_{i+1} (eq. 6), with
/// the cosine that G(s_{i+1}) has at its start x_{i+1}, the factor a sequential sampler
/// divides by its directional density:
///
/// The cosine factor of eq. 6's f_r(x_i, y_i, y_i + ŝ_{i+1}) · |n(x_{i+1}) · ŝ_{i+1}|:
/// multiply the BSDF value of `y` by it.
///
/// `y` is the shading point at y_i (its `wo` points back along s_i), `wi` the unit
/// direction of s_{i+1} (the direction light arrives from, in radiance transport) and
/// `wi_local` the same in `y`'s shading frame, `start` the surface x_{i+1} when the
/// kernel moved it off y_i. When it did not (the Dirac kernel), the product is
/// [`crate::transport::SurfacePoint::f_cos`] exactly, the vertex formulation's factor
/// with its shading-normal cosine. When it did, the cosine is taken with the shading
/// normal of x_{i+1}; the adjoint shading-normal correction stays the one of y_i, whose
/// BSDF is evaluated. The caller evaluates the BSDF (PT together with its density).
#[inline]
pub fn start_cosine(y: &crate::transport::SurfacePoint, start: Option<&SurfaceHit>, wi: Vec3, wi_local: Vec3, mode: TransportMode) -> f32 {
    let cos = match start {
        None => wi_local.z.abs(),
        Some(x) => x.ns.dot(wi).abs(),
    };
    cos * shading_normal_correction(mode, y.wo, wi, y.hit.ng, y.hit.ns)
}
