//! The independent segment samplers of §4.1 (Fig. 2a–c), each with its sample and its
//! density side by side. They draw x uniformly over the surfaces ([`SurfaceSampler`]);
//! they differ in how y follows:
//!
//! | sampler | y | p(s), per m⁴ |
//! |---|---|---|
//! | uniform (eq. 12) | uniform, independent of x | 1/|𝓜|² |
//! | ray-cast (eq. 13) | first hit along a cosine-distributed direction about x's geometric normal | G(s)/(π|𝓜|) |
//! | BSDF ray-cast (eq. 14) | first hit along a direction drawn from x's BSDF for an auxiliary incoming direction ŝ' | p_ω(ŝ | x, ŝ') |n_y·ŝ| V / (|𝓜| d²) |
//!
//! The ray-cast samplers shoot into the hemisphere of x's geometric normal (a mesh's
//! winding side), and a direction that escapes gives no segment: their densities
//! integrate to 1 − P(escape), which the tests check. BSDF ray-casting has no density for
//! a Dirac lobe (its segments lie on a set of measure zero); [`BsdfRaycast::sample`]
//! returns those with `is_delta` so an estimator can tell.
//! These samplers are the paper's baselines: none of them importance-samples g well
//! (Fig. 2), which is why the estimators use the sequential samplers of eq. (15).

use super::{Segment, SegmentPdf, SurfaceSampler};
use crate::bsdf::TransportMode;
use crate::geometry::{RayQuery, SurfaceHit, spawn_ray, spawn_ray_to};
use crate::math::{Frame, Vec2, Vec3};
use crate::measure::SolidAnglePdf;
use crate::scene::Scene;
use crate::shapes::SceneGeometry;
use crate::transport::SurfacePoint;
use crate::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere};

/// Random numbers for one segment: the primitive of x, the point on it, and two more for
/// y (a primitive and a point, or a lobe and a direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentUniforms {
    pub pick_x: f32,
    pub x: Vec2,
    pub pick_y: f32,
    pub y: Vec2,
}

/// Everything a sampler reads: the scene, its geometry, the area sampler and the tracer.
#[allow(missing_debug_implementations)] // the tracer need not be Debug
pub struct Surfaces<'a, Q: ?Sized> {
    pub scene: &'a Scene,
    pub geometry: &'a SceneGeometry,
    pub area: &'a SurfaceSampler,
    pub tracer: &'a Q,
}

impl<Q: RayQuery + ?Sized> Surfaces<'_, Q> {
    /// Is y the first surface seen from x (no occluder between them)?
    fn visible(&self, x: &SurfaceHit, y: &SurfaceHit) -> bool {
        !self.tracer.occluded(&spawn_ray_to(x.p, x.ng, y.p, y.ng))
    }

    /// The density of a ray-cast segment: (1/|𝓜|) · p_ω(ŝ) |n_y·ŝ| V / d², where
    /// `p_w` is the direction's density at x for the unit direction ŝ from x to y.
    fn raycast_pdf(&self, seg: &Segment, x: &SurfaceHit, p_w: impl FnOnce(Vec3) -> SolidAnglePdf) -> SegmentPdf {
        let d = seg.y.p - seg.x.p;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0) {
            return SegmentPdf::ZERO;
        }
        let w = d / crate::math::sqrt(dist2);
        let p_w = p_w(w);
        if !p_w.is_positive() || !self.visible(x, &seg.y) {
            return SegmentPdf::ZERO;
        }
        SegmentPdf::joint(self.area.pdf(), p_w.to_area(seg.y.ng.dot(w), dist2))
    }
}

/// Eq. (12): both endpoints uniform over the surfaces.
#[derive(Clone, Copy, Debug, Default)]
pub struct Uniform;

impl Uniform {
    pub fn sample<Q: RayQuery + ?Sized>(&self, s: &Surfaces<'_, Q>, u: SegmentUniforms) -> Option<Segment> {
        let x = s.area.sample(s.geometry, u.pick_x, u.x)?;
        let y = s.area.sample(s.geometry, u.pick_y, u.y)?;
        Some(Segment { x: super::Point::on(&x), y })
    }
    /// 1/|𝓜|², for any pair of surface points.
    pub fn pdf<Q: RayQuery + ?Sized>(&self, s: &Surfaces<'_, Q>, _seg: &Segment) -> SegmentPdf {
        SegmentPdf::joint(s.area.pdf(), s.area.pdf())
    }
}

/// Eq. (13): x uniform, then the first hit along a cosine-distributed direction.
#[derive(Clone, Copy, Debug, Default)]
pub struct Raycast;

impl Raycast {
    pub fn sample<Q: RayQuery + ?Sized>(&self, s: &Surfaces<'_, Q>, u: SegmentUniforms) -> Option<Segment> {
        let x = s.area.sample(s.geometry, u.pick_x, u.x)?;
        let dir = Frame::from_normal(x.ng).to_world(sample_cosine_hemisphere(u.y));
        let y = s.tracer.intersect(&spawn_ray(x.p, x.ng, dir))?;
        Some(Segment { x: super::Point::on(&x), y })
    }
    /// (1/|𝓜|) · cos_x cos_y V / (π d²) = G(s)/(π|𝓜|), zero behind x's normal.
    pub fn pdf<Q: RayQuery + ?Sized>(&self, s: &Surfaces<'_, Q>, seg: &Segment, x: &SurfaceHit) -> SegmentPdf {
        s.raycast_pdf(seg, x, |w| cosine_hemisphere_pdf(Frame::from_normal(x.ng).to_local(w)))
    }
}

/// A BSDF ray-cast segment, with whether its direction came from a Dirac lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSegment {
    pub segment: Segment,
    pub is_delta: bool,
}

/// Eq. (14): x uniform, then the first hit along a direction drawn from x's BSDF for the
/// auxiliary incoming direction ŝ' (`aux`: unit, pointing from x back toward where the
/// preceding segment would start, the BSDF's ω_o in radiance transport).
#[derive(Clone, Copy, Debug)]
pub struct BsdfRaycast {
    pub aux: Vec3,
}

impl BsdfRaycast {
    pub fn sample<Q: RayQuery + ?Sized>(&self, s: &Surfaces<'_, Q>, u: SegmentUniforms) -> Option<BsdfSegment> {
        let x = s.area.sample(s.geometry, u.pick_x, u.x)?;
        let sp = SurfacePoint::new(x, self.aux);
        let bs = sp.material(s.scene).sample(sp.frame.to_local(self.aux), u.pick_y, u.y, TransportMode::Radiance)?;
        if !bs.pdf.is_positive() {
            return None;
        }
        let y = s.tracer.intersect(&sp.spawn(sp.frame.to_world(bs.wi)))?;
        Some(BsdfSegment { segment: Segment { x: super::Point::on(&x), y }, is_delta: bs.is_delta })
    }
    /// (1/|𝓜|) · p_ω(ŝ | x, ŝ') |n_y·ŝ| V / d² (zero for directions only a Dirac lobe
    /// reaches).
    pub fn pdf<Q: RayQuery + ?Sized>(&self, s: &Surfaces<'_, Q>, seg: &Segment, x: &SurfaceHit) -> SegmentPdf {
        let sp = SurfacePoint::new(*x, self.aux);
        s.raycast_pdf(seg, x, |w| sp.material(s.scene).pdf(sp.frame.to_local(self.aux), sp.frame.to_local(w), TransportMode::Radiance))
    }
}
