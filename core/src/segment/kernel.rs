//! The kernel K(s_i, s_{i+1}) that joins two segments (eq. 5): how the start x_{i+1} of
//! the next segment is spread around the end y_i of the previous one.
//!
//! - **Dirac**: x_{i+1} = y_i. The segment path is an ordinary path (eq. 1).
//! - **Disk** of radius r: a point d uniform on the disk of radius r in the tangent plane
//!   of y_i (area density 1/(πr²)), then the first surface below it, found by a ray from
//!   d + r·n toward −n (n: y_i's geometric normal on the side the path arrived from) over
//!   a length 2r. On a plane this is exactly the uniform disk kernel,
//!   K = 1/(πr²) = (∫_{𝒦(y_i)} dx)⁻¹ (§3.1); on a curved or folded surface the density at
//!   x is |n_x·n|/(πr²) over the points that ray finds first, and where the ray finds
//!   nothing (beyond an edge) x_{i+1} = y_i. So K is exactly what is sampled,
//!   ∫ K dx_{i+1} = 1 holds for every y_i (the miss mass sits on y_i), and a sequential
//!   sampler's K / p_K is 1. The kernel depends on the side of arrival, which eq. (4)
//!   allows (K is a function of two segments, not of two points).
//!
//! [`Kernel::density`] evaluates the continuous part for a given x (for the brute-force
//! tests and for estimators that reuse segments across kernels); it does not test the
//! first-hit condition, which holds on the planar neighbourhoods it is used on.

use crate::geometry::{Ray, RayQuery, SurfaceHit};
use crate::math::{Frame, Vec2, Vec3};
use crate::measure::AreaPdf;
use crate::warp::sample_concentric_disk;

/// The kernel joining consecutive segments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kernel {
    /// x_{i+1} = y_i: the vertex formulation.
    Dirac,
    /// Uniform over the surface within a disk of this radius around y_i.
    Disk { radius: f32 },
}

/// Where the next segment starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KernelSample {
    /// At y_i itself (the Dirac kernel, or the disk kernel's miss mass).
    AtEnd,
    /// At another surface point within the kernel's support.
    Moved(SurfaceHit),
}

impl KernelSample {
    /// The moved start, if any.
    #[inline]
    pub fn moved(&self) -> Option<&SurfaceHit> {
        match self {
            Self::AtEnd => None,
            Self::Moved(h) => Some(h),
        }
    }
}

impl Kernel {
    /// The kernel with its radius times `scale` (a node's own kernel, see
    /// `estimators::filter::nodes::Node::kernel_scale`); the Dirac kernel unchanged.
    #[inline]
    pub fn scaled(&self, scale: f32) -> Self {
        match *self {
            Self::Disk { radius } => Self::Disk { radius: radius * scale },
            Self::Dirac => Self::Dirac,
        }
    }

    /// Does sampling the kernel need random numbers (and rays)?
    #[inline]
    pub fn is_dirac(&self) -> bool {
        matches!(self, Self::Dirac)
    }

    /// The side normal: y's geometric normal turned toward `toward` (the direction back
    /// along the arriving segment).
    #[inline]
    pub fn side_normal(y: &SurfaceHit, toward: Vec3) -> Vec3 {
        if y.ng.dot(toward) < 0.0 { -y.ng } else { y.ng }
    }

    /// Sample x_{i+1} around `y` (= y_i), the path having arrived from direction
    /// `toward` (unit, pointing from y_i back to x_i), with `u` uniform on [0, 1)².
    pub fn sample<Q: RayQuery + ?Sized>(&self, tracer: &Q, y: &SurfaceHit, toward: Vec3, u: Vec2) -> KernelSample {
        let Self::Disk { radius } = *self else { return KernelSample::AtEnd };
        let n = Self::side_normal(y, toward);
        let frame = Frame::from_normal(n);
        let d = sample_concentric_disk(u) * radius;
        let origin = y.p + frame.to_world(Vec3::new(d.x, d.y, 0.0)) + n * radius;
        match tracer.intersect(&Ray::new(origin, -n, 2.0 * radius)) {
            Some(hit) => KernelSample::Moved(hit),
            None => KernelSample::AtEnd,
        }
    }

    /// Continuous density of x (position `x`, geometric normal `nx`) around `y` for a path
    /// that arrived from `toward`, per unit area at x: |n_x · n| / (π r²) inside the
    /// projected disk and within r of the tangent plane, else 0. The Dirac kernel has no
    /// continuous part (returns 0).
    pub fn density(&self, y: &SurfaceHit, toward: Vec3, x: Vec3, nx: Vec3) -> AreaPdf {
        self.density_around(y.p, Self::side_normal(y, toward), x, nx)
    }

    /// [`Self::density`] around the point `y` whose side normal ([`Self::side_normal`])
    /// is `n`. Only |n_x · n| enters, so either orientation of `nx` gives the same value.
    #[inline]
    pub fn density_around(&self, y: Vec3, n: Vec3, x: Vec3, nx: Vec3) -> AreaPdf {
        let Self::Disk { radius } = *self else { return AreaPdf::ZERO };
        let (density, inside) = Self::disk_density(y, n, radius, x, nx);
        if inside { AreaPdf(density) } else { AreaPdf::ZERO }
    }

    /// The disk of `radius` around `y` (side normal `n`): the density |n_x · n| / (π r²)
    /// of `x` (normal `nx`) and whether `x` lies inside (within r of the tangent plane and
    /// in the projected disk), computed without a branch. [`Self::density_around`] is the
    /// density where inside, zero elsewhere; the segment filters test eight neighbours at
    /// a time with it (`NodeGrid::query_kernel`), the same bits.
    #[inline(always)]
    pub fn disk_density(y: Vec3, n: Vec3, radius: f32, x: Vec3, nx: Vec3) -> (f32, bool) {
        let d = x - y;
        let h = d.dot(n);
        let tangential = d - n * h;
        let inside = !(tangential.length_squared() >= radius * radius) & !(h.abs() > radius);
        (nx.dot(n).abs() / (core::f32::consts::PI * radius * radius), inside)
    }

    /// ∫ K dx over the surfaces, the continuous part's mass: the share of the disk whose
    /// projection ray finds a surface (1 on a plane, about ½ at an edge), estimated by
    /// `n`×`n` stratified rays jittered by `rng`. A kernel normalised by it,
    /// K / ∫ K, is the segment paper's uniform kernel over the part of 𝒦(y) that lies on
    /// surfaces, (∫_𝒦 dx)⁻¹ (§3.1): a density estimate with it does not fall short near
    /// edges. 1 for the Dirac kernel.
    pub fn surface_share<Q: RayQuery + ?Sized>(&self, tracer: &Q, y: &SurfaceHit, toward: Vec3, n: u32, rng: &mut crate::rng::SampleStream) -> f32 {
        let Self::Disk { .. } = *self else { return 1.0 };
        let n = n.max(1);
        let mut hits = 0u32;
        for i in 0..n * n {
            let j = rng.next_2d();
            let u = Vec2::new(((i % n) as f32 + j.x) / n as f32, ((i / n) as f32 + j.y) / n as f32);
            if matches!(self.sample(tracer, y, toward, u), KernelSample::Moved(_)) {
                hits += 1;
            }
        }
        hits as f32 / (n * n) as f32
    }

    /// K(x → y) / K(y → x) for a sample `x` drawn around `y`: the continuous density of
    /// drawing `y` around `x` over that of drawing `x` around `y` (1 where the latter
    /// vanishes, and for the Dirac kernel). The segment path integral's K joins y_i to
    /// x_{i+1} in the camera's direction (segment PT draws it as it is); a light walk
    /// reaches x_{i+1} and draws y_i around it, so it weighs each junction by this ratio
    /// to estimate the same integral. On planar neighbourhoods the disk kernel is
    /// symmetric and the ratio is 1; across folds it is not.
    pub fn reversed_ratio(&self, y: &SurfaceHit, x: &SurfaceHit) -> f32 {
        // The density does not depend on the side, only on the tangent plane.
        let own = self.density(y, y.ng, x.p, x.ng).0;
        let other = self.density(x, x.ng, y.p, y.ng).0;
        if own > 0.0 { other / own } else { 1.0 }
    }
}

/// The kernel with the random stream its samples come from: one per camera or light
/// path, kept apart from the path's own stream so that the walk's random-number layout is
/// the vertex estimator's.
#[derive(Clone, Debug)]
pub struct Junctions {
    pub kernel: Kernel,
    rng: crate::rng::SampleStream,
}

/// Last key of the kernel's random stream on camera paths (`Stream::Aux`, index = pixel).
pub const CAMERA_KERNEL_KEY: u32 = 0x5e00;
/// Last key of the kernel's random stream on light paths (`Stream::Aux`, index = path).
pub const LIGHT_KERNEL_KEY: u32 = 0x5e01;

impl Junctions {
    pub fn new(kernel: Kernel, rng: crate::rng::SampleStream) -> Self {
        Self { kernel, rng }
    }
    /// The junctions of path `index` of pass `pass`, drawing from the `Stream::Aux`
    /// stream with last key `key`; `None` for the Dirac kernel, which samples nothing.
    pub fn for_path(kernel: Kernel, seed: u64, index: u32, pass: u32, key: u32) -> Option<Self> {
        (!kernel.is_dirac()).then(|| Self::new(kernel, crate::rng::SampleStream::for_sample(seed, crate::rng::Stream::Aux, index, pass, key)))
    }
    /// The start of the next segment around `y`, the path having arrived from `toward`.
    pub fn sample<Q: RayQuery + ?Sized>(&mut self, tracer: &Q, y: &SurfaceHit, toward: Vec3) -> KernelSample {
        let u = self.rng.next_2d();
        self.kernel.sample(tracer, y, toward, u)
    }
}
