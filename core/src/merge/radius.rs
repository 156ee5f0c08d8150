//! The merging radius: its initial value r₀ and its progressive schedule.
//!
//! **Schedule.** r_i = r₀ · (i + 1)^((α − 1)/2) for global pass i (Knaus and Zwicker
//! 2011: the kernel's area shrinks as (i + 1)^(α − 1), so its bias vanishes while the
//! variance it adds grows slower than the number of passes). α ∈ (0, 1]; α = 1 keeps the
//! radius fixed. The radius is floored at r₀ · 10⁻⁶ so it stays positive and finite at any
//! pass count (reached only after about 10^36 passes at α = 0.67).
//!
//! **Initial radius.** The segment paper sets r₀ to 4 × the average pixel footprint, the
//! width of one pixel's cone at the distance of the surface it sees: for a pinhole of
//! horizontal half-angle θ over W columns, a surface at distance d is covered by a pixel
//! of width d · 2 tan θ / W. [`Footprint`] is the mean of that over the pixels whose
//! primary ray hits something (sums of distances and counts, so hosts can add chunks).
//! SmallVCM's rule, a fraction (0.003) of the scene's bounding-sphere radius, and an
//! absolute radius are the alternatives.

use crate::camera::PerspectiveCamera;
use crate::math::Vec2;
use crate::scene::Scene;

/// How r₀ is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RadiusRule {
    /// r₀ = k × the mean pixel footprint (the segment paper: k = 4).
    Footprints(f32),
    /// r₀ = f × the scene's bounding-sphere radius (SmallVCM: f = 0.003).
    SceneFraction(f32),
    /// r₀ in scene units.
    Absolute(f32),
}

impl RadiusRule {
    /// The segment paper's default: 4 pixel footprints.
    pub const DEFAULT: Self = Self::Footprints(4.0);

    /// The factor or radius, for validation messages.
    pub fn value(&self) -> f32 {
        match *self {
            Self::Footprints(k) | Self::SceneFraction(k) | Self::Absolute(k) => k,
        }
    }

    /// Does this rule need the footprint measured (a setup phase)?
    pub fn needs_footprint(&self) -> bool {
        matches!(self, Self::Footprints(_))
    }

    /// r₀ for `scene`, given the measured footprint (ignored by the other rules). Falls
    /// back to the scene-fraction rule when no primary ray hit anything.
    pub fn initial_radius(&self, scene: &Scene, footprint: &Footprint) -> f32 {
        let (_, scene_radius) = scene.bounds.bounding_sphere();
        let fallback = 0.003 * if scene_radius > 0.0 && scene_radius.is_finite() { scene_radius } else { 1.0 };
        let r = match *self {
            Self::Footprints(k) => footprint.mean(&scene.camera).map_or(fallback, |f| k * f),
            Self::SceneFraction(f) => f * scene_radius,
            Self::Absolute(r) => r,
        };
        if r > 0.0 && r.is_finite() { r } else { fallback }
    }
}

/// Radius of global pass `pass`: r₀ (pass + 1)^((α − 1)/2), floored at r₀ · 10⁻⁶.
pub fn progressive_radius(r0: f32, alpha: f32, pass: u32) -> f32 {
    let scale = crate::math::pow_f64(pass as f64 + 1.0, (alpha as f64 - 1.0) * 0.5);
    let r = (r0 as f64 * scale) as f32;
    r.max(r0 * 1e-6)
}

/// Sums toward the mean pixel footprint: Σ d over pixels whose primary ray hit, and
/// their count.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    /// Σ hit distance.
    pub distance: f64,
    /// Pixels whose primary ray hit.
    pub hits: u64,
}

impl Footprint {
    /// Add another chunk's sums.
    pub fn add(&mut self, other: Footprint) {
        self.distance += other.distance;
        self.hits += other.hits;
    }

    /// The sums a chunk carries ([`Self::from_sums`] reads them back).
    pub fn sums(&self) -> [f64; 2] {
        [self.distance, self.hits as f64]
    }

    /// The footprint whose [`Self::sums`] are `s` (zero when `s` is short).
    pub fn from_sums(s: &[f64]) -> Self {
        match s {
            [distance, hits, ..] => Self { distance: *distance, hits: *hits as u64 },
            _ => Self::default(),
        }
    }

    /// The mean footprint d̄ · 2 tan θ_x / W, or `None` without hits.
    pub fn mean(&self, camera: &PerspectiveCamera) -> Option<f32> {
        if self.hits == 0 {
            return None;
        }
        let d = self.distance / self.hits as f64;
        let f = (d * 2.0 * camera.tan_half_x() as f64 / camera.width() as f64) as f32;
        (f > 0.0 && f.is_finite()).then_some(f)
    }

    /// Trace the primary ray through the centre of each pixel in `pixels`.
    pub fn measure<Q: crate::geometry::RayQuery + ?Sized>(scene: &Scene, tracer: &Q, pixels: core::ops::Range<u32>) -> Self {
        let width = scene.camera.width().max(1);
        let mut sums = Self::default();
        for pixel in pixels {
            let film = Vec2::new((pixel % width) as f32 + 0.5, (pixel / width) as f32 + 0.5);
            let ray = scene.camera.generate_ray(film);
            if let Some(hit) = tracer.intersect(&ray) {
                let d = (hit.p - ray.origin).length();
                if d.is_finite() {
                    sums.distance += d as f64;
                    sums.hits += 1;
                }
            }
        }
        sums
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedule_shrinks_as_the_power_law_and_stays_positive() {
        assert_eq!(progressive_radius(2.0, 0.67, 0), 2.0);
        let r = progressive_radius(2.0, 0.67, 99);
        assert!((r / 2.0 - 100f32.powf(-0.165)).abs() < 1e-6, "{r}");
        assert_eq!(progressive_radius(2.0, 1.0, 12345), 2.0);
        let tiny = progressive_radius(1.0, 1e-3, u32::MAX);
        assert!(tiny >= 1e-6 && tiny.is_finite());
    }
}
