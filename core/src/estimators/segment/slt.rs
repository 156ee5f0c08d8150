//! Segment light tracing: the sequential segment sampler from the lights (eq. 15) with
//! the sequential estimator (eq. 16), and a deterministic last segment to the pinhole.
//!
//! In light order the path starts with s_k: y_k on a light (its own measure: area, a
//! point's position, or a direction), ŝ_k from the emission, x_k the first hit;
//! β₀ = L_e |cos| / (p(y_k) p_ω) since p(x_k | y_k) = p_ω |n_x·ŝ| / d² cancels the rest of
//! G(s_k). At each x_{i+1} the path reaches:
//!
//! 1. **Kernel.** The previous segment's end y_i is drawn from K(·, s_{i+1}) around
//!    x_{i+1} (K / p_K = 1), or is x_{i+1} itself with the Dirac kernel. Eq. (6)
//!    evaluates f_r(s_i, s_{i+1}) at y_i, so the shading point moves there: its BSDF (in
//!    its adjoint form), its frame and its cosine.
//! 2. **Last segment to the pinhole.** s₁ = (pinhole, y_i): β f_r |cos| W_e |cos_c| / d²
//!    splatted where the pinhole sees y_i.
//! 3. **Next segment.** ŝ_i from the adjoint BSDF at y_i, traced from y_i:
//!    β ← β f_r |cos| / p_ω.
//!
//! The walk is [`crate::estimators::lt`]'s with the kernel plugged in: with the Dirac
//! kernel segment LT is LT, bit for bit, with LT's random numbers; the kernel's come from
//! a stream of their own.

use core::ops::Range;

use crate::estimators::lt;
use crate::geometry::RayQuery;
use crate::scene::Scene;
use crate::segment::Kernel;
use crate::transport::{Counters, RenderParams, Splat};

/// Trace segment light paths `paths` of pass `pass`; every camera connection goes to
/// `splat` (the host scales a pass's splats by 1 / (paths per pass)).
pub fn trace_paths<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    kernel: Kernel,
    pass: u32,
    paths: Range<u32>,
    splat: &mut dyn FnMut(Splat),
) -> Counters {
    lt::trace_paths_with_kernel(scene, tracer, params, kernel, pass, paths, splat)
}
