//! The surface vertices of one lane-loop step that lane kernels shade together, in
//! structure-of-arrays form ([`crate::math::soa`]): what every estimator's Lambertian
//! kernel (`estimators::pt_lanes`, `lt_lanes`) reads of a vertex.

use crate::bsdf::LambertLane;
use crate::math::Frame;
use crate::math::soa::{LANES, Vec3s};
use crate::transport::SurfacePoint;

/// Vertices on Lambertian surfaces, one per lane, with their paths' random streams.
pub(crate) struct LambertVertices {
    pub len: usize,
    /// The vertex's index among the step's traced lanes (its `arrivals` slot).
    pub slot: [u8; LANES],
    pub p: Vec3s,
    pub ng: Vec3s,
    pub ns: Vec3s,
    /// Unit world direction back along the arriving segment.
    pub wo: Vec3s,
    pub rho: Vec3s,
    pub two_sided: [bool; LANES],
    /// The path's random stream ([`crate::rng::SampleStream::base`]) and the first
    /// dimension of this bounce.
    pub base: [u64; LANES],
    pub dim: [u32; LANES],
}

impl LambertVertices {
    pub fn new() -> Self {
        Self {
            len: 0,
            slot: [0; LANES],
            p: Vec3s::ZERO,
            ng: Vec3s::ZERO,
            ns: Vec3s::ZERO,
            wo: Vec3s::ZERO,
            rho: Vec3s::ZERO,
            two_sided: [false; LANES],
            base: [0; LANES],
            dim: [0; LANES],
        }
    }

    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Add the vertex at `sp` (traced lane `slot`) with Lambertian lobe `lobe`, whose
    /// path's random stream is `base` and whose bounce draws from dimension `dim` on;
    /// its lane.
    #[inline(always)]
    pub fn push(&mut self, slot: u8, sp: &SurfacePoint, lobe: LambertLane, base: u64, dim: u32) -> usize {
        let i = self.len;
        self.slot[i] = slot;
        self.p.set(i, sp.hit.p);
        self.ng.set(i, sp.hit.ng);
        self.ns.set(i, sp.frame.n);
        self.wo.set(i, sp.wo);
        self.rho.set_rgb(i, lobe.rho);
        self.two_sided[i] = lobe.two_sided;
        self.base[i] = base;
        self.dim[i] = dim;
        self.len += 1;
        i
    }

    /// Lane `i`'s lobe.
    #[inline(always)]
    pub fn lobe(&self, i: usize) -> LambertLane {
        LambertLane { rho: self.rho.rgb(i), two_sided: self.two_sided[i] }
    }

    /// Lane `i`'s shading frame, `SurfacePoint::new`'s, built again in a kernel's first
    /// phase: the scalar `reach` built it too, but copying its two vectors into the batch
    /// measured no faster than recomputing them over lanes.
    #[inline(always)]
    pub fn frame(&self, i: usize) -> Frame {
        Frame::from_normal(self.ns.get(i))
    }
}
