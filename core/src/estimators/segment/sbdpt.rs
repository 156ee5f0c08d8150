//! Segment BDPT: a camera sequence and a light sequence of segments (eq. 15 from each
//! end), every pair of prefixes joined by a bridge segment, all combined by MIS over the
//! segment path techniques (eq. 17) with the balance heuristic.
//!
//! **Junctions.** A segment path s₁ … s_k with s_i = (x_i, y_i) has a junction
//! (y_i, x_{i+1}) between consecutive segments, where the kernel K(s_i, s_{i+1}) sits.
//! Each sub-path draws the junction's second point around the first it reaches:
//! - the camera sequence reaches y_i (ray cast from x_i) and draws x_{i+1} ~ K around it;
//! - the light sequence reaches x_{i+1} (ray cast from y_{i+1}) and draws y_i ~ K around it.
//!
//! f_r(s_i, s_{i+1}) is evaluated at y_i in both cases (eq. 6), so a light vertex moves
//! its shading point to the kernel's sample, as segment LT does, and a camera vertex
//! keeps it at the hit, as segment PT does ([`crate::path::Vertex::exit`] holds the other
//! point). Every surface vertex of both sub-paths is such a junction, the last one too.
//!
//! **Bridge segments.** Technique (s, t) joins camera vertex z_{t−1} (its junction
//! (y_j, x_{j+1})) and light vertex y_{s−1} (its junction (y_{j+1}, x_{j+2})) by the bridge
//! s_{j+1} = (x_{j+1}, y_{j+1}): both of its points are kernel samples that the two
//! sub-paths have already drawn, so the bridge costs one shadow ray and no sampling. Its
//! density is the product of those two kernel densities, which eq. (4)'s K factors on
//! either side of the bridge cancel exactly (K / p_K = 1 twice); what remains is
//! f_r at y_j · G(x_{j+1}, y_{j+1}) V · f_r at y_{j+1}, the vertex connection with the
//! bridge's own ends. The pinhole (t = 1) and a light point sampled by next-event
//! estimation (s = 1) are path ends, which no kernel moves: their bridges have one
//! kernel-sampled end.
//!
//! **Weights.** Under technique (s, t) each junction carries one area density (of the
//! point its sub-path reached by ray casting: y_j from the camera side, x_{j+1} from the
//! light side) and one kernel density (of the other point, drawn around it). Moving a
//! vertex from one sub-path to the other changes both, so BDPT's ratio of reverse to
//! forward vertex density ([`crate::path::mis`]) gains the factor K_other / K_own
//! ([`crate::path::Vertex::kernel_ratio`]). On planar neighbourhoods the disk kernel is
//! symmetric and that factor is 1; across folds it is not. The weights of all the
//! techniques that produce one segment path sum to one, so the estimator is unbiased for
//! the segment path integral with this kernel; the kernel's own bias (∝ r² on smooth
//! radiance) is what the disk kernel's consistency test measures.
//!
//! With the Dirac kernel the junctions do not move and segment BDPT is BDPT bit for bit
//! ([`crate::estimators::bdpt`], whose loop this is, with the kernels plugged into the
//! walks); the kernels draw from random streams of their own
//! ([`crate::segment::CAMERA_KERNEL_KEY`], [`crate::segment::LIGHT_KERNEL_KEY`]).

use core::ops::Range;

use crate::estimators::bdpt;
use crate::geometry::RayQuery;
use crate::scene::Scene;
use crate::segment::Kernel;
use crate::spectrum::Rgb;
use crate::transport::{Counters, RenderParams, Splat};

/// Render one segment BDPT sample for each pixel in `pixels` of pass `pass` into
/// `out[i − pixels.start]`; bridges to the pinhole (t = 1) go to `splat` (scaled by
/// 1 / (W·H) per pass by the host).
#[allow(clippy::too_many_arguments)]
pub fn render_pixels<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    kernel: Kernel,
    pass: u32,
    pixels: Range<u32>,
    out: &mut [Rgb],
    splat: &mut dyn FnMut(Splat),
) -> Counters {
    bdpt::render_pixels_with_kernel(scene, tracer, params, kernel, pass, pixels, out, splat)
}
