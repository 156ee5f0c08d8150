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
//! BDPT's connections (light sample, interior join, cached light source: so LVCBPT,
//! SPCBPT, VCM and segment BDPT's bridges) apply it at the camera-side end, read from
//! `path::Exit` with its own material, since a kernel may move that end onto another
//! surface. The filter estimators' node walks (MVF, BPF, PhF) record T on the
//! continuation that crossed the medium (`Continuation::medium`): a Dirac continuation
//! carries it in its throughput, a reused one where its reached node's value is read,
//! and a light node's arrival takes its predecessor's; PhF's camera walk puts it on β.
//! The filters' next-event segments take [`Scene::transmittance_to`] as PT's do. BPF's
//! bridge segments would need it in their end's row and are refused with a medium
//! (`estimators::RendererError::BridgesInMedium`).
//!
//! # What the rule cannot see, and is refused
//!
//! The rule needs both ends of every segment inside a medium to lie on the medium's own
//! boundary. A camera or a point or spot light inside a medium (a connection to it ends
//! on no surface: LT's and BDPT's camera connections, a light's direct connection to the
//! camera), or another shape inside or overlapping one (a segment from the medium's wall
//! to it ends on a surface without the interior; nested media are such shapes), would be
//! attenuated on some segments and not on others: estimators would disagree. So
//! [`SceneBuilder::medium_intrusion`] finds them and `build` refuses the scene
//! ([`super::SceneError::InsideMedium`]); the Mitsuba reader names the files' lines.
//! Tracking the medium along every path (Mitsuba's `volpath`) would lift this.

use alloc::vec::Vec;

use super::{Scene, SceneBuilder, TEXTURE_SLOTS};
use crate::geometry::{LightId, MaterialId, Ray, SurfaceHit};
use crate::math::{DVec3, Vec3, exp};
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

/// Something inside an absorbing medium that the stateless rule cannot attenuate
/// correctly (the module's notes): refused by [`SceneBuilder::build`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MediumIntruder {
    /// The camera (its pinhole or lens centre).
    Camera,
    /// A point or spot light.
    Light(LightId),
    /// A triangle of another surface (its index in `SceneGeometry::triangles`): inside
    /// the medium or crossing its boundary.
    Triangle(u32),
    /// A sphere (its index in `SceneGeometry::spheres`) whose centre is inside.
    Sphere(u32),
}

/// Directions of the parity test: three, far from any axis and from each other.
const PROBES: [DVec3; 3] = [
    DVec3::new(0.267_261_241_912_424_4, 0.534_522_483_824_848_8, 0.801_783_725_737_273_2),
    DVec3::new(-0.707_106_781_186_547_5, 0.141_421_356_237_309_5, 0.692_820_323_027_550_9),
    DVec3::new(0.436_435_780_471_984_8, -0.872_871_560_943_969_6, 0.218_217_890_235_992_4),
];

impl SceneBuilder {
    /// The first thing found inside an absorbing medium (or, for a triangle, crossing its
    /// boundary), with the medium's material: the camera, a point or spot light, a
    /// vertex of another material's triangle or an edge of it through the medium's
    /// surface (or an edge of the medium's through it), another sphere's centre.
    /// A point is inside a medium's closed mesh when rays in three fixed directions all
    /// cross it an odd number of times (inside a sphere: nearer its centre than its
    /// radius), so a point on the boundary (a shape resting on the glass) is not
    /// counted. Points outside the medium's bounding box cost nothing more; others cost
    /// three rays against the medium's triangles.
    pub fn medium_intrusion(&self) -> Option<(MaterialId, MediumIntruder)> {
        let geometry = &self.geometry;
        for (m, sigma) in self.interiors.iter().enumerate() {
            if sigma.is_none() {
                continue;
            }
            let m = m as MaterialId;
            let medium = Enclosure::of(self, m);
            if medium.is_empty() {
                continue;
            }
            if self.camera.as_ref().is_some_and(|c| medium.contains(c.position())) {
                return Some((m, MediumIntruder::Camera));
            }
            for (i, l) in self.lights.iter().enumerate() {
                if l.delta_position().is_some_and(|p| medium.contains(p)) {
                    return Some((m, MediumIntruder::Light(i as LightId)));
                }
            }
            for (i, t) in geometry.triangles.iter().enumerate() {
                if t.material != m && (t.p.iter().any(|&p| medium.contains(p)) || medium.crosses(t)) {
                    return Some((m, MediumIntruder::Triangle(i as u32)));
                }
            }
            for (i, s) in geometry.spheres.iter().enumerate() {
                if s.material != m && medium.contains(s.center) {
                    return Some((m, MediumIntruder::Sphere(i as u32)));
                }
            }
        }
        None
    }
}

/// The surfaces of one medium's material: what [`SceneBuilder::medium_intrusion`] tests
/// points against.
struct Enclosure<'a> {
    triangles: Vec<&'a super::Triangle>,
    spheres: Vec<&'a super::Sphere>,
    lo: Vec3,
    hi: Vec3,
}

impl<'a> Enclosure<'a> {
    fn of(b: &'a SceneBuilder, m: MaterialId) -> Self {
        let triangles: Vec<_> = b.geometry.triangles.iter().filter(|t| t.material == m).collect();
        let spheres: Vec<_> = b.geometry.spheres.iter().filter(|s| s.material == m).collect();
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for t in &triangles {
            for p in t.p {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        for s in &spheres {
            lo = lo.min(s.center - Vec3::splat(s.radius));
            hi = hi.max(s.center + Vec3::splat(s.radius));
        }
        Self { triangles, spheres, lo, hi }
    }

    fn is_empty(&self) -> bool {
        self.triangles.is_empty() && self.spheres.is_empty()
    }

    /// Strictly inside (see [`SceneBuilder::medium_intrusion`]).
    fn contains(&self, p: Vec3) -> bool {
        if !(p.cmpgt(self.lo).all() && p.cmplt(self.hi).all()) {
            return false;
        }
        if self.spheres.iter().any(|s| (p - s.center).length() < s.radius * (1.0 - 1e-4)) {
            return true;
        }
        !self.triangles.is_empty() && PROBES.iter().all(|&d| self.crossings(p.as_dvec3(), d) % 2 == 1)
    }

    /// Does triangle `t` cross the medium's mesh: an edge of either through the other's
    /// interior (touching, and lying in one plane, do not count)?
    fn crosses(&self, t: &super::Triangle) -> bool {
        let (lo, hi) = (t.p[0].min(t.p[1]).min(t.p[2]), t.p[0].max(t.p[1]).max(t.p[2]));
        if !(lo.cmplt(self.hi).all() && hi.cmpgt(self.lo).all()) {
            return false;
        }
        let edges = |p: [Vec3; 3]| [(p[0], p[1]), (p[1], p[2]), (p[2], p[0])].map(|(a, b)| (a.as_dvec3(), b.as_dvec3()));
        let tri = |p: [Vec3; 3]| p.map(|v| v.as_dvec3());
        self.triangles.iter().any(|m| {
            edges(t.p).iter().any(|&(a, b)| through(a, b - a, tri(m.p)).is_some_and(|s| s > 1e-6 && s < 1.0 - 1e-6))
                || edges(m.p).iter().any(|&(a, b)| through(a, b - a, tri(t.p)).is_some_and(|s| s > 1e-6 && s < 1.0 - 1e-6))
        })
    }

    /// How many of the triangles the ray from `o` along `d` crosses (Möller–Trumbore in
    /// f64; hits at the origin itself are not counted).
    fn crossings(&self, o: DVec3, d: DVec3) -> usize {
        let eps = 1e-9 * (1.0 + o.length());
        self.triangles.iter().filter(|t| through(o, d, t.p.map(|v| v.as_dvec3())).is_some_and(|s| s > eps)).count()
    }
}

/// Where the line o + s·d meets triangle `t` strictly inside its edges (Möller–Trumbore
/// in f64): s, or `None` when it misses, grazes an edge or lies in the triangle's plane.
fn through(o: DVec3, d: DVec3, [a, b, c]: [DVec3; 3]) -> Option<f64> {
    let (e1, e2) = (b - a, c - a);
    let h = d.cross(e2);
    let det = e1.dot(h);
    if !(det.abs() > 1e-12 * e1.length() * e2.length() * d.length()) {
        return None;
    }
    let s = o - a;
    let u = s.dot(h) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    (u > 0.0 && v > 0.0 && u + v < 1.0).then(|| e2.dot(q) / det)
}

/// Pad `interiors` to one entry per material when any is set (kept empty otherwise).
pub(super) fn finish_interiors(interiors: &mut Vec<Option<Rgb>>, materials: usize) {
    if !interiors.is_empty() {
        interiors.resize(materials, None);
    }
}
