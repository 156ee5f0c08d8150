//! Segment path tracing: the sequential segment sampler from the camera (eq. 15) with the
//! sequential estimator (eq. 16), and a light-sampled last segment combined with the
//! BSDF-sampled one by MIS (eq. 17).
//!
//! s₁ is the camera ray's segment (p ∝ W G). At the end y_i of each segment:
//!
//! 1. **Kernel.** The next segment's start x_{i+1} is drawn from K(s_i, ·) (p_K = K, so
//!    K / p_K = 1), or is y_i itself with the Dirac kernel.
//! 2. **Light-sampled last segment.** From x_{i+1}, a point y on a light: s_{i+1} = (x_{i+1}, y)
//!    ends the path with g's factors f_r(s_i, s_{i+1}) |n(x_{i+1})·ŝ| L_e per unit solid
//!    angle at x_{i+1}.
//! 3. **BSDF-sampled next segment.** ŝ_{i+1} from y_i's BSDF for the incoming direction
//!    of s_i (shift invariance, eq. 6), traced from x_{i+1}: β ← β f_r |n(x_{i+1})·ŝ| / p_ω,
//!    since eq. (15)'s p(y_{i+1} | x_{i+1}) = p_ω |n_y·ŝ| / d² cancels the rest of G.
//!
//! Steps 2 and 3 are two techniques for the same last segment given x_{i+1}, both with
//! densities per solid angle at x_{i+1}; they are weighted by the balance (or power)
//! heuristic exactly as in [`crate::estimators::pt`]. The walk is PT's with the kernel
//! plugged in: with the Dirac kernel segment PT is PT, bit for bit, with PT's random
//! numbers; the kernel's random numbers come from a stream of their own
//! ([`crate::segment::CAMERA_KERNEL_KEY`]).

use core::ops::Range;

use crate::estimators::pt;
use crate::geometry::RayQuery;
use crate::scene::Scene;
use crate::segment::Kernel;
use crate::spectrum::Rgb;
use crate::transport::{Counters, RenderParams};

/// Render one segment-PT sample for each pixel in `pixels` of pass `pass` into
/// `out[i − pixels.start]`.
pub fn render_pixels<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    kernel: Kernel,
    pass: u32,
    pixels: Range<u32>,
    out: &mut [Rgb],
) -> Counters {
    pt::render_pixels_with_kernel(scene, tracer, params, kernel, pass, pixels, out)
}
