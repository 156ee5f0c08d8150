//! Absorbing media inside closed shapes: coloured glass (issue 56).
//!
//! # What is modelled
//!
//! A shape may hold a homogeneous medium that only absorbs (Mitsuba's `homogeneous`
//! with albedo 0): radiance crossing a distance d inside it is multiplied by the
//! transmittance T(d) = exp(−σ_t d), per colour channel, with σ_t the extinction
//! coefficient (per unit of scene length). Nothing is scattered inside, so no vertex
//! ever lies in the medium: paths still go from surface to surface, and only the
//! throughput of the segments inside changes. The densities of the techniques do not
//! change either (no distance is sampled), so MIS weights are untouched: T is part of
//! the integrand, not of any pdf.
//!
//! # Which segments are inside
//!
//! The medium fills the side of its shape's surface opposite to the geometric normal
//! (Mitsuba's "interior", `SurfaceInteraction::target_medium`: a direction against the
//! normal enters it). For a closed, consistently wound shape that does not overlap
//! another medium, a segment lies inside exactly when it *ends* on the shape from the
//! inside, i.e. it reaches the surface's back face (ray direction · n_g > 0). That rule
//! needs nothing but the segment and the hit it reached, so no estimator has to carry a
//! medium stack on its path state, and it holds whichever way the path goes (radiance or
//! importance): a camera walk and a light walk through the same glass see the same T.
//!
//! # Where it is applied
//!
//! [`Scene::transmittance`] gives T for a traced segment; the walks multiply β by it
//! where a segment arrives (`transport::walk::Walk::pass_medium`: PT, LT, segment PT/LT
//! and the BDPT family's sub-paths, so BDPT, LVCBPT, SPCBPT and VCM/PPM/BPM, whose
//! merges read the sub-paths' β). A smooth dielectric boundary blocks shadow rays, so
//! no connection crosses its medium; a rough one does not, and there
//! [`Scene::transmittance_to`] gives T for a connection: PT's next-event estimation and
//! BDPT's connections (light sample, interior join, cached light source) apply it. The
//! filter estimators' node walks (MVF, BPF, PhF) put T on the continuation that crossed
//! the medium, and PhF's camera walk on its β. Not covered yet (`docs/scene-features.md`):
//! a camera or a light inside a medium, and the filters' next-event and connection
//! segments across a rough boundary.

use alloc::vec::Vec;

use super::{Scene, SceneBuilder, TEXTURE_SLOTS};
use crate::geometry::{MaterialId, Ray, SurfaceHit};
use crate::math::{Vec3, exp};
use crate::spectrum::Rgb;

/// exp(−σ_t d) per channel.
#[inline]
pub fn absorption_transmittance(sigma_t: Rgb, d: f32) -> Rgb {
    Rgb::new(exp(-sigma_t.r * d), exp(-sigma_t.g * d), exp(-sigma_t.b * d))
}

impl Scene {
    /// The extinction coefficient σ_t of the medium behind material `id`'s surface (on
    /// the side opposite to its geometric normal), if it has one.
    #[inline]
    pub fn interior(&self, id: MaterialId) -> Option<Rgb> {
        self.interiors.get(id as usize).copied().flatten()
    }

    /// The transmittance of the segment `ray` traced to `hit`: `Some(T)` when it ran
    /// inside a medium (it reached the back face of a surface with an interior), `None`
    /// otherwise (T = 1). Cheap when the scene has no medium.
    #[inline]
    pub fn transmittance(&self, ray: &Ray, hit: &SurfaceHit) -> Option<Rgb> {
        if self.interiors.is_empty() {
            return None;
        }
        self.transmittance_to(ray.origin, hit.p, hit.ng, hit.material)
    }

    /// The transmittance of a connection from `from` to the surface point `to` (normal
    /// `to_ng`, material `to_material`): next-event and bidirectional connections, by the
    /// same rule as [`Self::transmittance`]. `None` (T = 1) outside media, and for a
    /// segment of infinite length (a direction toward a light at infinity, whose shadow
    /// ray the shape's far side blocks).
    #[inline]
    pub fn transmittance_to(&self, from: Vec3, to: Vec3, to_ng: Vec3, to_material: MaterialId) -> Option<Rgb> {
        if self.interiors.is_empty() {
            return None;
        }
        let sigma_t = self.interior(to_material)?;
        let d = to - from;
        if !(to_ng.dot(d) > 0.0) {
            return None;
        }
        let len = d.length();
        if !len.is_finite() {
            return None;
        }
        Some(absorption_transmittance(sigma_t, len))
    }
}

impl SceneBuilder {
    /// A copy of material `material` (its texture bindings included) whose surfaces
    /// enclose an absorbing medium of extinction `sigma_t` (per unit length, every
    /// channel non-negative and finite); returns the copy's id. The copy keeps the medium
    /// to the shapes that declare it when several share one BSDF.
    pub fn add_interior(&mut self, material: MaterialId, sigma_t: Rgb) -> MaterialId {
        if !self.check_material(material) {
            return material;
        }
        if !(sigma_t.r >= 0.0 && sigma_t.g >= 0.0 && sigma_t.b >= 0.0 && sigma_t.is_finite()) {
            self.error.get_or_insert(super::SceneError::BadMedium(material));
            return material;
        }
        let id = self.add_material(self.materials[material as usize]);
        if let Some(&slots) = self.material_textures.get(material as usize) {
            self.material_textures.resize(self.materials.len(), [None; TEXTURE_SLOTS]);
            self.material_textures[id as usize] = slots;
        }
        self.interiors.resize(self.materials.len(), None);
        self.interiors[id as usize] = Some(sigma_t);
        id
    }
}

/// Pad `interiors` to one entry per material when any is set (kept empty otherwise).
pub(super) fn finish_interiors(interiors: &mut Vec<Option<Rgb>>, materials: usize) {
    if !interiors.is_empty() {
        interiors.resize(materials, None);
    }
}
