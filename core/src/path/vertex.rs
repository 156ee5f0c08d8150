//! Path vertices of BDPT and the densities between them (pbrt-v3's `Vertex`, in our
//! typed conventions).
//!
//! Every vertex stores `pdf_fwd`, the density with which its own sub-path generated it,
//! and `pdf_rev`, the density with which the opposite sub-path would have generated it,
//! both as [`VertexPdf`]: per unit area at a point, per unit solid angle at a vertex at
//! infinity (the type's constructors name the measure). The conversion from a sampler's
//! solid-angle density is [`Vertex::convert_density`].
//!
//! **Segments.** A vertex is also the junction of two segments (Wang et al. 2025, eq. 4):
//! `p` is where the BSDF is evaluated (y_i, the end of the segment arriving from the
//! camera side) and [`Vertex::exit`] is where the segment toward the light side starts
//! (x_{i+1}). The segment between path-order neighbours a (camera side) and b (light
//! side) runs from `a.exit` to `b.p`. With the Dirac kernel `exit` is `p` and every
//! density below is the vertex one bit for bit; segment BDPT
//! ([`crate::estimators::segment::sbdpt`]) moves `exit` on camera vertices and `p` on light vertices
//! (each sub-path moves the point its kernel samples). Which end of an edge a density
//! lives at depends on the direction it is sampled in, so densities take the
//! [`TransportMode`] of the walk that samples: `Radiance` walks toward the light side,
//! `Importance` toward the camera side.

use crate::bsdf::{TransportMode, shading_normal_correction};
use crate::geometry::LightId;
use crate::math::{Frame, Vec2, Vec3};
use crate::measure::{AreaPdf, SolidAnglePdf, VertexPdf};
use crate::scene::Scene;
use crate::spectrum::Rgb;

/// What a vertex is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub enum VertexKind {
    /// The pinhole.
    Camera,
    /// A point on a light (area, sphere, point or spot).
    Light(LightId),
    /// A direction toward the infinite lights (environment, directional); `p` is a
    /// point one unit (or a scene diameter) along that direction.
    InfiniteLight,
    /// A scattering surface point.
    Surface,
}

/// One vertex of a camera or light sub-path.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct Vertex {
    pub kind: VertexKind,
    pub p: Vec3,
    /// Geometric normal; `Vec3::ZERO` for vertices not on a surface (camera, point lights,
    /// infinite lights).
    pub ng: Vec3,
    /// Shading frame (surfaces only).
    pub frame: Frame,
    /// Unit direction toward the previous vertex of its own sub-path (surfaces only).
    pub wo: Vec3,
    pub material: u32,
    /// Texture coordinates of a surface vertex (what a textured material is read at).
    pub uv: Vec2,
    /// The light attached to a surface vertex, if it is an emitter.
    pub emitter: Option<LightId>,
    /// Sub-path throughput up to and including this vertex's arrival.
    pub beta: Rgb,
    /// Reached by (or, for lights, emitted from) a Dirac distribution.
    pub delta: bool,
    pub pdf_fwd: VertexPdf,
    pub pdf_rev: VertexPdf,
    /// Where the segment toward the light side starts (`p` but for segment BDPT).
    pub exit: Exit,
    /// K_other / K_own of the kernel sample joining `p` and `exit`: the kernel density
    /// with which the opposite sub-path would have drawn this junction over the one its
    /// own sub-path drew it with (1 for the Dirac kernel, for a kernel's miss mass, and at
    /// path ends).
    pub kernel_ratio: f32,
}

/// The start of a vertex's segment toward the light side.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct Exit {
    pub p: Vec3,
    /// Geometric normal (`Vec3::ZERO` off surfaces).
    pub ng: Vec3,
    /// Shading normal, for the cosine of the segment leaving here (eq. 6).
    pub ns: Vec3,
    /// The material of the surface here: a kernel may move the exit onto another
    /// surface than the vertex's own, and a connection from it crosses that surface's
    /// medium, if any (`Scene::transmittance_to`).
    pub material: u32,
}

impl Exit {
    /// The exit at `p` on a surface of `material` (0 off surfaces, where `ng` is zero
    /// and no medium is read).
    #[inline]
    pub fn at(p: Vec3, ng: Vec3, ns: Vec3, material: u32) -> Self {
        Self { p, ng, ns, material }
    }
}

impl Vertex {
    pub fn camera(p: Vec3, beta: Rgb) -> Self {
        Self {
            kind: VertexKind::Camera,
            p,
            ng: Vec3::ZERO,
            frame: Frame::from_normal(Vec3::Z),
            wo: Vec3::ZERO,
            material: 0,
            uv: Vec2::ZERO,
            emitter: None,
            beta,
            delta: false,
            pdf_fwd: VertexPdf::ZERO,
            pdf_rev: VertexPdf::ZERO,
            exit: Exit::at(p, Vec3::ZERO, Vec3::Z, 0),
            kernel_ratio: 1.0,
        }
    }

    pub fn light(id: LightId, p: Vec3, n: Vec3, beta: Rgb, pdf_fwd: VertexPdf, delta: bool) -> Self {
        Self {
            kind: VertexKind::Light(id),
            p,
            ng: n,
            frame: Frame::from_normal(if n == Vec3::ZERO { Vec3::Z } else { n }),
            wo: Vec3::ZERO,
            material: 0,
            uv: Vec2::ZERO,
            emitter: Some(id),
            beta,
            delta,
            pdf_fwd,
            pdf_rev: VertexPdf::ZERO,
            exit: Exit::at(p, n, if n == Vec3::ZERO { Vec3::Z } else { n }, 0),
            kernel_ratio: 1.0,
        }
    }

    pub fn infinite(p: Vec3, beta: Rgb, pdf_fwd: VertexPdf) -> Self {
        Self {
            kind: VertexKind::InfiniteLight,
            p,
            ng: Vec3::ZERO,
            frame: Frame::from_normal(Vec3::Z),
            wo: Vec3::ZERO,
            material: 0,
            uv: Vec2::ZERO,
            emitter: None,
            beta,
            delta: false,
            pdf_fwd,
            pdf_rev: VertexPdf::ZERO,
            exit: Exit::at(p, Vec3::ZERO, Vec3::Z, 0),
            kernel_ratio: 1.0,
        }
    }

    /// The segment between this vertex and `next`, sampled from here by a walk in
    /// `mode`: (start, end, the end's geometric normal). Radiance walks go toward the
    /// light side (from `self.exit` to `next.p`), importance walks toward the camera
    /// side (from `self.p` to `next.exit`).
    #[inline]
    pub fn edge(&self, next: &Vertex, mode: TransportMode) -> (Vec3, Vec3, Vec3) {
        match mode {
            TransportMode::Radiance => (self.exit.p, next.p, next.ng),
            TransportMode::Importance => (self.p, next.exit.p, next.exit.ng),
        }
    }

    /// Unit direction from this vertex toward `next` along their segment (see [`Self::edge`]).
    #[inline]
    pub fn dir_to(&self, next: &Vertex, mode: TransportMode) -> Vec3 {
        let (a, b, _) = self.edge(next, mode);
        (b - a).normalize_or_zero()
    }

    #[inline]
    pub fn is_on_surface(&self) -> bool {
        self.ng != Vec3::ZERO
    }

    #[inline]
    pub fn is_light(&self) -> bool {
        matches!(self.kind, VertexKind::Light(_) | VertexKind::InfiniteLight) || self.emitter.is_some()
    }

    /// Is the vertex a light whose position or direction is a Dirac (point, spot,
    /// directional)? Strategies that would have to hit such a light are impossible.
    pub fn is_delta_light(&self, scene: &Scene) -> bool {
        match self.kind {
            VertexKind::Light(id) => scene.lights[id as usize].is_delta(),
            VertexKind::InfiniteLight => false,
            _ => false,
        }
    }

    /// Can a deterministic connection reach this vertex?
    pub fn is_connectible(&self, scene: &Scene) -> bool {
        match self.kind {
            VertexKind::Camera => true,
            // A directional light emits along one direction only: nothing can connect to it.
            VertexKind::Light(id) => !scene.lights[id as usize].is_delta_direction(),
            VertexKind::InfiniteLight => false,
            VertexKind::Surface => !scene.materials[self.material as usize].is_delta(),
        }
    }

    /// BSDF value toward `next` (no cosine), with the adjoint shading-normal correction;
    /// `mode` is the walk's: `next` lies toward the light side for `Radiance`.
    pub fn f(&self, scene: &Scene, next: &Vertex, mode: TransportMode) -> Rgb {
        if self.kind != VertexKind::Surface {
            return Rgb::ZERO;
        }
        let wi = self.dir_to(next, mode);
        let m = scene.material(self.material, self.uv);
        m.eval(self.frame.to_local(self.wo), self.frame.to_local(wi), mode) * shading_normal_correction(mode, self.wo, wi, self.ng, self.frame.n)
    }

    /// Convert a solid-angle density of sampling `next` from here (by a walk in `mode`)
    /// into `next`'s vertex density: per area at the segment's end, unchanged for a
    /// vertex at infinity.
    pub fn convert_density(&self, pdf: SolidAnglePdf, next: &Vertex, mode: TransportMode) -> VertexPdf {
        if next.kind == VertexKind::InfiniteLight {
            return VertexPdf::of_direction(pdf);
        }
        let (a, b, nb) = self.edge(next, mode);
        // In f64 (`to_area_f64`): near-grazing cosines lose most of their digits in f32.
        let w = b.as_dvec3() - a.as_dvec3();
        let d2 = w.length_squared();
        if !(d2 > 0.0) {
            return VertexPdf::ZERO;
        }
        let cos = if next.is_on_surface() { nb.as_dvec3().dot(w).abs() / crate::math::sqrt_f64(d2) } else { 1.0 };
        VertexPdf::at_point(pdf.to_area_f64(cos, d2))
    }

    /// Area density of sampling `next` from this vertex by a walk in `mode`, given it
    /// was reached from `prev` on the other side (pbrt-v3's `Vertex::Pdf`).
    pub fn pdf(&self, scene: &Scene, prev: Option<&Vertex>, next: &Vertex, mode: TransportMode) -> VertexPdf {
        match self.kind {
            VertexKind::Light(_) | VertexKind::InfiniteLight => return self.pdf_light(scene, next),
            _ => {}
        }
        let wn = self.dir_to(next, mode);
        let pdf = match self.kind {
            VertexKind::Camera => scene.camera.pdf_dir_from(self.p, wn),
            _ => {
                let Some(prev) = prev else { return VertexPdf::ZERO };
                let m = scene.material(self.material, self.uv);
                if m.is_delta() {
                    // A Dirac lobe: the unit Dirac in solid angle, which every technique able
                    // to produce the path has once per specular vertex (it cancels in their
                    // ratios), converted to area like any density, so the segment's
                    // cos/d² stays. Zeroing it instead (pbrt-v3's convention, ours before)
                    // drops that factor from the ratios: BDPT and VCM then weighted a
                    // caustic seen on the floor 0.01 below a glass sphere 0.68 toward
                    // hitting the light through the glass instead of ≈ 0.
                    return self.convert_density(SolidAnglePdf(1.0), next, mode);
                }
                let wp = self.dir_to(prev, mode.flip());
                m.pdf(self.frame.to_local(wp), self.frame.to_local(wn), TransportMode::Radiance)
            }
        };
        self.convert_density(pdf, next, mode)
    }

    /// (`self.pdf(scene, Some(a), b, mode)`, `self.pdf(scene, Some(b), a, mode.flip())`):
    /// the densities of the two ways through this vertex between neighbours `a` and `b`,
    /// as a connection's MIS weight needs them at both connection vertices. At a surface
    /// vertex the two share the material lookup and both directions (each one's `wn` is
    /// the other's `wp`), so they cost about one and a half evaluations instead of two;
    /// the operations are those of [`Self::pdf`], bit for bit.
    pub fn pdf_both_ways(&self, scene: &Scene, a: &Vertex, b: &Vertex, mode: TransportMode) -> (VertexPdf, VertexPdf) {
        if self.kind != VertexKind::Surface {
            return (self.pdf(scene, Some(a), b, mode), self.pdf(scene, Some(b), a, mode.flip()));
        }
        let m = scene.material(self.material, self.uv);
        if m.is_delta() {
            return (self.convert_density(SolidAnglePdf(1.0), b, mode), self.convert_density(SolidAnglePdf(1.0), a, mode.flip()));
        }
        let (wb, wa) = (self.frame.to_local(self.dir_to(b, mode)), self.frame.to_local(self.dir_to(a, mode.flip())));
        let to_b = m.pdf(wa, wb, TransportMode::Radiance);
        let to_a = m.pdf(wb, wa, TransportMode::Radiance);
        (self.convert_density(to_b, b, mode), self.convert_density(to_a, a, mode.flip()))
    }

    /// [`Self::pdf`] for the bounce this vertex's own walk took (`prev` and `next` its
    /// neighbours on its sub-path): where that bounce drew a Dirac lobe of a material that
    /// also has continuous ones (smooth plastic's mirror), the unit Dirac as for a
    /// specular material, both ways. Connections and merges join a vertex through its
    /// continuous lobes, so they use [`Self::pdf`].
    pub fn pdf_along(&self, scene: &Scene, prev: Option<&Vertex>, next: &Vertex, mode: TransportMode) -> VertexPdf {
        if self.delta && self.kind == VertexKind::Surface && prev.is_some() {
            return self.convert_density(SolidAnglePdf(1.0), next, mode);
        }
        self.pdf(scene, prev, next, mode)
    }

    /// (`pdf_along(Some(a), b, mode)`, `pdf_along(Some(b), a, mode.flip())`) together, as
    /// [`Self::pdf_both_ways`] does for [`Self::pdf`]: the walk's forward density of a new
    /// vertex `b` and the reverse density of the vertex `a` before this one.
    pub fn pdf_along_both_ways(&self, scene: &Scene, a: &Vertex, b: &Vertex, mode: TransportMode) -> (VertexPdf, VertexPdf) {
        if self.delta && self.kind == VertexKind::Surface {
            return (self.convert_density(SolidAnglePdf(1.0), b, mode), self.convert_density(SolidAnglePdf(1.0), a, mode.flip()));
        }
        self.pdf_both_ways(scene, a, b, mode)
    }

    /// Area density at `next` (toward the camera side) of a light path leaving this
    /// light vertex toward it.
    pub fn pdf_light(&self, scene: &Scene, next: &Vertex) -> VertexPdf {
        let (a, b, nb) = self.edge(next, TransportMode::Importance);
        let wd = b.as_dvec3() - a.as_dvec3();
        let d2 = wd.length_squared();
        if !(d2 > 0.0) {
            return VertexPdf::ZERO;
        }
        let wd = wd / crate::math::sqrt_f64(d2);
        let w = wd.as_vec3();
        let mut pdf = match self.kind {
            VertexKind::InfiniteLight => {
                // Rays from infinite lights start on a disk of the scene's bounding radius.
                let (_, r) = scene.bounds.bounding_sphere();
                1.0 / (core::f64::consts::PI * r as f64 * r as f64)
            }
            VertexKind::Light(id) => scene.lights[id as usize].pdf_le(self.p, self.ng, w).1.0 as f64 / d2,
            VertexKind::Surface => match self.emitter {
                Some(id) => scene.lights[id as usize].pdf_le(self.p, self.ng, w).1.0 as f64 / d2,
                None => 0.0,
            },
            VertexKind::Camera => 0.0,
        };
        if next.is_on_surface() {
            pdf *= nb.as_dvec3().dot(wd).abs();
        }
        VertexPdf::at_point(AreaPdf(pdf as f32))
    }

    /// The light this vertex lies on: a light path's first vertex, or an emitting surface
    /// a camera path hit. `None` elsewhere, and for infinite lights (no single one).
    #[inline]
    pub fn light_id(&self) -> Option<LightId> {
        match self.kind {
            VertexKind::Light(id) => Some(id),
            VertexKind::Surface => self.emitter,
            VertexKind::InfiniteLight | VertexKind::Camera => None,
        }
    }

    /// Density of this light vertex as the origin of a light path (light selection ×
    /// position density; for infinite lights, the selection-weighted direction density).
    pub fn pdf_light_origin(&self, scene: &Scene, next: &Vertex) -> VertexPdf {
        let w = self.dir_to(next, TransportMode::Importance);
        match self.kind {
            VertexKind::InfiniteLight => VertexPdf::of_direction(infinite_light_density(scene, -w)),
            _ => self.light_id().map_or(VertexPdf::ZERO, |id| light_origin(scene, id, self.p, self.ng, w)),
        }
    }

    /// Radiance emitted from this vertex toward `toward` (on the camera side; emitters
    /// and infinite lights).
    pub fn le(&self, scene: &Scene, toward: &Vertex) -> Rgb {
        let w = self.dir_to(toward, TransportMode::Importance);
        match self.kind {
            VertexKind::InfiniteLight => scene.infinite_lights().fold(Rgb::ZERO, |acc, (_, l)| acc + l.environment_radiance(-w)),
            _ => self.emitter.map_or(Rgb::ZERO, |id| scene.lights[id as usize].radiance(self.p, self.ng, w)),
        }
    }
}

/// |n_a · ŵ| |n_b · ŵ| / d² between vertices `a` and `b` with the normals given (a vertex
/// not on a surface contributes 1). BDPT's connections take shading normals at both ends;
/// SPCBPT's prefix weights the shading normal at `a` and the geometric one at `b` (their
/// area densities convert with it).
#[inline]
pub fn cosines_over_distance2(a: &Vertex, na: Vec3, b: &Vertex, nb: Vec3) -> f32 {
    let d = b.p - a.p;
    let d2 = d.length_squared();
    if !(d2 > 0.0) {
        return 0.0;
    }
    let w = d / crate::math::sqrt(d2);
    let ca = if a.is_on_surface() { na.dot(w).abs() } else { 1.0 };
    let cb = if b.is_on_surface() { nb.dot(w).abs() } else { 1.0 };
    ca * cb / d2
}

/// Light selection × position density of a point on light `id` (a point light's position
/// is a Dirac: its selection probability alone).
fn light_origin(scene: &Scene, id: LightId, p: Vec3, n: Vec3, w: Vec3) -> VertexPdf {
    let light = &scene.lights[id as usize];
    let pmf = scene.light_pmf(id);
    if light.is_delta_position() {
        return VertexPdf::discrete(pmf);
    }
    VertexPdf::at_point(light.pdf_le(p, n, w).0 * pmf)
}

/// Σ over infinite lights of P(light) · p_light(ω), ω pointing toward the sky.
pub fn infinite_light_density(scene: &Scene, dir_to_sky: Vec3) -> SolidAnglePdf {
    SolidAnglePdf(scene.infinite_lights().map(|(id, l)| scene.light_pmf(id) * l.pdf_li(Vec3::ZERO, dir_to_sky, Vec3::ZERO, Vec3::ZERO).0).sum())
}
