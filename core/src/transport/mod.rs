//! The vocabulary every estimator speaks, below all of them: the settings they share
//! ([`RenderParams`], [`MaxDepth`], [`Heuristic`]), what a chunk counts ([`Counters`]) and
//! splats ([`Splat`]), Russian roulette ([`survives_roulette`]) and the surface point a
//! walk stands on ([`SurfacePoint`]). The estimators themselves live in
//! [`crate::estimators`]; the render protocol that drives them in [`crate::render`].
//!
//! Depth follows Mitsuba's `max_depth`: the largest number of path segments (edges)
//! from the camera to the emitter; 1 = emitters seen directly, 2 = direct lighting,
//! −1 = unbounded. Unbounded paths end by Russian roulette from the fifth segment on.

pub mod config;
pub(crate) mod lane_vertices;
pub mod lanes;
mod surface;
pub mod walk;

pub use surface::SurfacePoint;

use crate::math::Vec2;
use crate::spectrum::Rgb;

/// Mitsuba's `max_depth` as a type: a bound on the number of path segments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaxDepth(pub i32);

impl MaxDepth {
    pub const UNBOUNDED: Self = Self(-1);
    /// May a path have `segments` segments?
    #[inline]
    pub fn allows(self, segments: u32) -> bool {
        self.0 < 0 || segments <= self.0 as u32
    }
    /// A hard cap for fixed-capacity vertex storage: unbounded depth still stops here
    /// (Russian roulette makes reaching it vanishingly rare; the truncation is reported).
    #[inline]
    pub fn capped(self, cap: u32) -> u32 {
        if self.0 < 0 { cap } else { (self.0 as u32).min(cap) }
    }
}

/// MIS heuristic for combining two or more techniques.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Heuristic {
    Balance,
    Power,
}

impl Heuristic {
    /// Weight of technique `a` against `b` (both densities in the same measure,
    /// already multiplied by their sample counts).
    #[inline]
    pub fn weight(self, a: f32, b: f32) -> f32 {
        let (a, b) = match self {
            Self::Balance => (a, b),
            Self::Power => (a * a, b * b),
        };
        if a + b > 0.0 { a / (a + b) } else { 0.0 }
    }
}

/// Settings shared by the estimators.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderParams {
    pub max_depth: MaxDepth,
    pub seed: u64,
    pub heuristic: Heuristic,
    /// Surfaces a path meets before Russian roulette may end it (Mitsuba's `rr_depth`,
    /// 5; with 1, a path may end after the first surface it meets).
    pub rr_depth: u32,
    /// The instruction set lane kernels are compiled for (the host's choice for this
    /// machine; the images are the same at every level).
    pub simd: crate::math::simd::Level,
}

impl Default for RenderParams {
    fn default() -> Self {
        Self { max_depth: MaxDepth::UNBOUNDED, seed: 0, heuristic: Heuristic::Balance, rr_depth: 5, simd: crate::math::simd::Level::BASELINE }
    }
}

/// A contribution to the film at a position other than the sample's own pixel
/// (light tracing, BDPT's t = 1 strategy). The host scales a pass's splats by
/// 1 / (light paths per pass).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct Splat {
    /// Continuous pixel coordinates.
    pub film: Vec2,
    pub value: Rgb,
}

/// The interior connections (strategies with s ≥ 2 and t ≥ 2, [`crate::path::connect`])
/// whose shadow ray was traced, and the share the shadow ray found occluded, by count
/// and by value: `value` sums the luminance of each traced connection's unweighted f/p
/// (what it would have carried if visible), `occluded_value` that of the occluded ones.
/// What a connection strategy's choice of light vertices wastes (issue 18's first
/// measurement: LVCBPT's uniform choice against SPCBPT's Γ-guided one).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct ConnectionStats {
    pub traced: u64,
    pub occluded: u64,
    pub value: f64,
    pub occluded_value: f64,
}

impl ConnectionStats {
    /// Count one traced connection carrying `value` (if visible).
    #[inline]
    pub fn record(&mut self, value: Rgb, occluded: bool) {
        let y = value.luminance().abs() as f64;
        self.traced += 1;
        self.value += y;
        if occluded {
            self.occluded += 1;
            self.occluded_value += y;
        }
    }
}

impl core::ops::AddAssign for ConnectionStats {
    fn add_assign(&mut self, o: Self) {
        self.traced += o.traced;
        self.occluded += o.occluded;
        self.value += o.value;
        self.occluded_value += o.occluded_value;
    }
}

/// Work counters of one call, summed by the host.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct Counters {
    /// Rays traced (closest-hit and shadow).
    pub rays: u64,
    /// Contributions dropped because they were NaN, infinite or negative.
    pub discarded: u64,
    /// Paths truncated by the fixed vertex capacity with unbounded depth.
    pub truncated: u64,
    /// Interior connections traced and found occluded.
    pub connections: ConnectionStats,
    /// The lane loop's steps and busy lanes ([`lanes::LaneStats`]), for the estimators
    /// that walk on it (PT, LT).
    pub lanes: lanes::LaneStats,
}

impl core::ops::AddAssign for Counters {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.discarded += o.discarded;
        self.truncated += o.truncated;
        self.connections += o.connections;
        self.lanes += o.lanes;
    }
}

impl Counters {
    /// Pass `c` through if it is a valid radiance, else count it and return black.
    #[inline]
    pub fn sanitize(&mut self, c: Rgb) -> Rgb {
        if c.is_valid_radiance() {
            c
        } else {
            self.discarded += 1;
            Rgb::ZERO
        }
    }
}

/// Russian roulette before tracing segment number `segments` (the direction just drawn
/// at the path's (`segments` − 1)-th surface). Mitsuba's rule: survive with probability
/// q = min(max component of β / `reference`, 0.95) once the path has met `rr_depth`
/// surfaces, that is for `segments` > `rr_depth` (Mitsuba's `path.cpp` counts the
/// surfaces met, `depth`, and rolls while `depth >= rr_depth`). Returns false when the
/// path ends; a surviving β is divided by q, which keeps the estimate unbiased. Draws a
/// random number only when q < 1.
///
/// This rolled one surface early (from `segments` ≥ `rr_depth`) until 2026-11-25: PT's
/// relMSE at equal samples was 1.10× Mitsuba 3's on the Cornell box (64 passes, 8 seeds
/// each, every seed of ours above every seed of Mitsuba's) and 1.15× on glossy; with the
/// rule above they match (1.000 and 1.007). docs/performance.md has the runs.
///
/// `reference` is 1 for camera paths, whose β is dimensionless (Mitsuba's rule exactly),
/// and [`light_roulette_reference`] for light paths, whose β carries the light's power
/// and so the scene's units: comparing it with 1 made light paths die at their first
/// roulette at scale 10⁻² and almost never at scale 1, so BDPT's image mean moved by
/// 0.5 % with the scene's scale (docs/stability.md).
#[inline]
pub fn survives_roulette(params: &RenderParams, segments: u32, beta: &mut Rgb, reference: f32, rng: &mut crate::rng::SampleStream) -> bool {
    if segments <= params.rr_depth {
        return true;
    }
    let q = (beta.max_component() / reference).min(0.95);
    if q >= 1.0 {
        return true;
    }
    if !(q > 0.0) || rng.next_f32() >= q {
        return false;
    }
    *beta /= q;
    true
}

/// How far a light path's throughput may fall below its throughput at emission, β₀,
/// before roulette starts ending it: q = min(10 β / β₀, 0.95), scale-free (β/β₀ is the
/// path's attenuation). 10 keeps unit-scale scenes near their old behaviour (the Cornell
/// box's light has β₀ ≈ 9.6) and was measured against 1 (roulette on the attenuation
/// alone), which cost up to 2× relMSE per pass on ajar (docs/stability.md).
pub const LIGHT_ROULETTE_GAIN: f32 = 10.0;

/// The roulette reference of a light path that left its light with throughput `beta0`.
#[inline]
pub fn light_roulette_reference(beta0: Rgb) -> f32 {
    let m = beta0.max_component() / LIGHT_ROULETTE_GAIN;
    if m > 0.0 && m.is_finite() { m } else { 1.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{SampleStream, Stream};

    /// Roulette rolls once a path has met `rr_depth` surfaces (Mitsuba's `depth >=
    /// rr_depth`): not before segment `rr_depth` + 1 is traced. Seen failing with the
    /// previous rule, which rolled before segment `rr_depth` (one surface early: PT's
    /// relMSE per sample was 1.10–1.15× Mitsuba 3's).
    #[test]
    fn roulette_starts_after_rr_depth_surfaces() {
        for rr_depth in [1, 5] {
            let params = RenderParams { rr_depth, ..RenderParams::default() };
            let mut rng = SampleStream::for_sample(7, Stream::Aux, 0, 0, 0);
            let dim = Rgb::new(1e-3, 1e-3, 1e-3);
            for segments in 1..=rr_depth {
                let (mut beta, before) = (dim, rng.dimension());
                assert!(survives_roulette(&params, segments, &mut beta, 1.0, &mut rng), "rr_depth {rr_depth}, segment {segments}");
                assert_eq!((beta, rng.dimension()), (dim, before), "no roll, no draw before segment {}", rr_depth + 1);
            }
            // Before segment rr_depth + 1 it rolls: q = 10⁻³, so nearly every path ends and
            // a survivor carries β / q.
            let mut survivors = 0;
            for _ in 0..2000 {
                let mut beta = dim;
                if survives_roulette(&params, rr_depth + 1, &mut beta, 1.0, &mut rng) {
                    survivors += 1;
                    assert!((beta.r - 1.0).abs() < 1e-5, "β / q = {beta:?}");
                }
            }
            assert!(survivors < 20, "rr_depth {rr_depth}: {survivors} of 2000 survived q = 1e-3");
        }
    }
}
