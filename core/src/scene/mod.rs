//! The scene description the estimators read, and the flat geometry hosts hand to
//! their ray-query structure.
//!
//! A host (or an embedding engine) builds a scene with [`SceneBuilder`]: materials,
//! shapes (triangle meshes, rectangles, cubes, spheres), emitters and a camera. `build`
//! validates and splits it into a [`Scene`] (camera, materials, lights and the light
//! selection distribution: what the estimators need) and a [`SceneGeometry`] (triangles
//! and spheres with material and emitter ids: what a tracer needs). Allocation happens
//! here, once, at setup.

pub mod builtin;
pub mod builtin_glass;
mod media;

pub use media::{MediumIntruder, absorption_transmittance};

use alloc::borrow::Cow;
use alloc::vec::Vec;

use crate::alias::AliasTable;
use crate::bsdf::{Material, TextureSlot};
use crate::camera::PerspectiveCamera;
use crate::geometry::{LightId, MaterialId};
use crate::light::Light;
use crate::math::{Bounds3, Mat4, Vec2, Vec3};
pub use crate::shapes::{SceneGeometry, Sphere, Triangle};
use crate::texture::Texture;

/// A scene with the host's ray queries over it: what every estimator reads, passed as
/// one value.
#[derive(Debug)]
pub struct Context<'a, Q: ?Sized> {
    /// The scene the estimators read.
    pub scene: &'a Scene,
    /// The host's ray queries over the same scene.
    pub tracer: &'a Q,
}

impl<Q: ?Sized> Clone for Context<'_, Q> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<Q: ?Sized> Copy for Context<'_, Q> {}
use crate::spectrum::Rgb;

/// What the estimators read.
#[derive(Clone, Debug)]
pub struct Scene {
    pub camera: PerspectiveCamera,
    pub materials: Vec<Material>,
    /// The textures materials read ([`Scene::material`]).
    pub textures: Vec<Texture>,
    /// Per material, the texture driving each [`TextureSlot`] (in the enum's order), if
    /// any; empty when no material has a texture.
    pub material_textures: Vec<[Option<u32>; TEXTURE_SLOTS]>,
    pub lights: Vec<Light>,
    /// Light selection proportional to power; `None` when the scene has no light.
    pub light_selection: Option<AliasTable>,
    /// Indices of the infinite lights (environment, directional), so escaped rays visit
    /// only these, and not at all when the scene has none.
    pub infinite: Vec<LightId>,
    pub bounds: Bounds3,
    /// Per material, σ_t of the absorbing medium behind its surfaces, if any
    /// ([`Scene::transmittance`]); empty when the scene has no medium.
    pub interiors: Vec<Option<Rgb>>,
}

/// How many [`TextureSlot`]s there are.
pub const TEXTURE_SLOTS: usize = 4;
const SLOTS: [TextureSlot; TEXTURE_SLOTS] =
    [TextureSlot::Diffuse, TextureSlot::SpecularReflectance, TextureSlot::SpecularTransmittance, TextureSlot::Roughness];

impl Scene {
    /// Material `id` at texture coordinates `uv`: the stored material itself, or, where
    /// textures drive some of its parameters, a copy with their values at `uv`.
    #[inline]
    pub fn material(&self, id: MaterialId, uv: Vec2) -> Cow<'_, Material> {
        let m = &self.materials[id as usize];
        match self.material_textures.get(id as usize) {
            Some(slots) if slots.iter().any(Option::is_some) => Cow::Owned(self.textured(m, slots, uv)),
            _ => Cow::Borrowed(m),
        }
    }

    #[cold]
    fn textured(&self, m: &Material, slots: &[Option<u32>; TEXTURE_SLOTS], uv: Vec2) -> Material {
        let mut out = *m;
        for (slot, t) in SLOTS.iter().zip(slots) {
            if let Some(tex) = t.and_then(|t| self.textures.get(t as usize)) {
                out = out.with_texel(*slot, tex.eval(uv));
            }
        }
        out
    }

    /// Does material `id` depend on texture coordinates?
    pub fn is_textured(&self, id: MaterialId) -> bool {
        self.material_textures.get(id as usize).is_some_and(|s| s.iter().any(Option::is_some))
    }

    /// Probability of selecting light `id` for next-event estimation or a light path.
    #[inline]
    pub fn light_pmf(&self, id: LightId) -> f32 {
        self.light_selection.as_ref().map_or(0.0, |t| t.pmf(id as usize))
    }
    /// The infinite lights (environment, directional), for rays that escape.
    pub fn infinite_lights(&self) -> impl Iterator<Item = (LightId, &Light)> {
        self.infinite.iter().map(|&i| (i, &self.lights[i as usize]))
    }
    /// Does any light emit from a surface a ray can hit (so s = 0 strategies exist)?
    pub fn has_area_lights(&self) -> bool {
        self.lights.iter().any(|l| !l.is_delta() && !l.is_infinite())
    }
}

/// Emission attached to a shape: Mitsuba's `area` emitter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaEmission {
    pub radiance: Rgb,
    /// Emit from both sides (Mitsuba emits from the front only).
    pub two_sided: bool,
}

/// Problems `build` reports.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneError {
    NoCamera,
    /// A shape refers to a material id that was never added.
    UnknownMaterial(MaterialId),
    /// A texture binding names a texture that was never added, or a parameter the
    /// material does not have.
    BadTexture(MaterialId),
    /// A position, radius or radiance is NaN or infinite.
    NonFinite(&'static str),
    /// A medium given to this material's surfaces has a negative or non-finite σ_t.
    BadMedium(MaterialId),
    /// Something sits inside the absorbing medium behind this material's surfaces (the
    /// camera, a point light, another shape): not modelled (`media` notes).
    InsideMedium(MaterialId, MediumIntruder),
}

impl core::fmt::Display for SceneError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NoCamera => write!(f, "the scene has no camera"),
            Self::UnknownMaterial(m) => write!(f, "a shape refers to material {m}, which does not exist"),
            Self::BadTexture(m) => write!(f, "material {m} is bound to a texture that does not exist or to a parameter it does not have"),
            Self::NonFinite(what) => write!(f, "non-finite value in {what}"),
            Self::BadMedium(m) => write!(f, "the medium inside material {m}'s surfaces has a negative or non-finite sigma_t"),
            Self::InsideMedium(m, what) => write!(
                f,
                "{} is inside the absorbing medium of material {m}'s surfaces: only media whose boundary is the only thing inside them are modelled (no camera, light or other shape inside or crossing them)",
                match what {
                    MediumIntruder::Camera => alloc::string::String::from("the camera"),
                    MediumIntruder::Light(l) => alloc::format!("light {l}"),
                    MediumIntruder::Triangle(t) => alloc::format!("triangle {t} of another surface"),
                    MediumIntruder::Sphere(s) => alloc::format!("sphere {s}"),
                }
            ),
        }
    }
}

/// Counts of things `build` dropped, for the host to report as warnings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuildWarnings {
    /// Triangles with zero area (they cannot be hit or sampled).
    pub degenerate_triangles: usize,
    /// Lights dropped because they emit nothing (zero radiance, intensity or
    /// irradiance); an emitting mesh counts once per triangle. Lights that are kept are
    /// never counted here.
    pub dark_lights: usize,
}

/// Assembles a scene; see the module documentation.
#[derive(Clone, Debug, Default)]
pub struct SceneBuilder {
    camera: Option<PerspectiveCamera>,
    materials: Vec<Material>,
    textures: Vec<Texture>,
    material_textures: Vec<[Option<u32>; TEXTURE_SLOTS]>,
    interiors: Vec<Option<Rgb>>,
    lights: Vec<Light>,
    geometry: SceneGeometry,
    warnings: BuildWarnings,
    error: Option<SceneError>,
}

impl SceneBuilder {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn set_camera(&mut self, camera: PerspectiveCamera) {
        self.camera = Some(camera);
    }

    /// The geometry added so far (its triangles and spheres in the order added).
    pub fn geometry(&self) -> &SceneGeometry {
        &self.geometry
    }

    /// How many lights were added so far (the next light's id).
    pub fn light_count(&self) -> usize {
        self.lights.len()
    }

    pub fn add_material(&mut self, m: Material) -> MaterialId {
        self.materials.push(m);
        (self.materials.len() - 1) as MaterialId
    }

    /// A texture for materials to read ([`Self::bind_texture`]); returns its id.
    pub fn add_texture(&mut self, t: Texture) -> u32 {
        self.textures.push(t);
        (self.textures.len() - 1) as u32
    }

    /// Let texture `texture` drive parameter `slot` of material `material`.
    pub fn bind_texture(&mut self, material: MaterialId, slot: TextureSlot, texture: u32) {
        let ok = (texture as usize) < self.textures.len() && self.materials.get(material as usize).is_some_and(|m| m.has_slot(slot));
        if !ok {
            self.error.get_or_insert(SceneError::BadTexture(material));
            return;
        }
        self.material_textures.resize(self.materials.len(), [None; TEXTURE_SLOTS]);
        let i = SLOTS.iter().position(|s| *s == slot).unwrap_or(0);
        self.material_textures[material as usize][i] = Some(texture);
    }

    /// A light that is not attached to a shape (point, spot, directional, environment).
    /// One that emits nothing is dropped (counted in the warnings' `dark_lights`) and
    /// gets no id.
    pub fn add_light(&mut self, light: Light) -> Option<LightId> {
        // The power of a light at infinity scales with the scene's radius, unknown until
        // `build` (before it, every environment's power is 0); whether it is positive does
        // not depend on the radius, so ask at radius 1.
        let mut probe = light.clone();
        probe.set_scene_bounds(Vec3::ZERO, 1.0);
        if !(probe.power() > 0.0) {
            self.warnings.dark_lights += 1;
            return None;
        }
        self.lights.push(light);
        Some((self.lights.len() - 1) as LightId)
    }

    fn check_material(&mut self, m: MaterialId) -> bool {
        if (m as usize) < self.materials.len() {
            return true;
        }
        self.error.get_or_insert(SceneError::UnknownMaterial(m));
        false
    }

    /// Add one triangle; zero-area and non-finite triangles are dropped (counted in the
    /// warnings; non-finite ones are an error). Returns whether it was kept.
    pub fn add_triangle(&mut self, p: [Vec3; 3], n: Option<[Vec3; 3]>, material: MaterialId, emission: Option<AreaEmission>) -> bool {
        self.add_triangle_uv(p, n, None, material, emission)
    }

    /// [`Self::add_triangle`] with per-vertex texture coordinates (dropped if not finite).
    pub fn add_triangle_uv(&mut self, p: [Vec3; 3], n: Option<[Vec3; 3]>, uv: Option<[Vec2; 3]>, material: MaterialId, emission: Option<AreaEmission>) -> bool {
        if !self.check_material(material) {
            return false;
        }
        if !p.iter().all(|v| v.is_finite()) {
            self.error.get_or_insert(SceneError::NonFinite("a triangle vertex"));
            return false;
        }
        let cross = (p[1] - p[0]).cross(p[2] - p[0]);
        let len2 = cross.length_squared();
        if !(len2 > 0.0) || !len2.is_finite() {
            self.warnings.degenerate_triangles += 1;
            return false;
        }
        // Shading normals must be finite and usable; otherwise fall back to the face.
        let n = n.filter(|ns| ns.iter().all(|v| v.is_finite() && v.length_squared() > 0.0)).map(|ns| ns.map(|v| v.normalize()));
        let emitter = emission.and_then(|e| {
            if !e.radiance.is_finite() {
                self.error.get_or_insert(SceneError::NonFinite("an emitter's radiance"));
                return None;
            }
            if e.radiance.is_black() {
                self.warnings.dark_lights += 1;
                return None;
            }
            self.lights.push(Light::triangle(p[0], p[1], p[2], e.radiance, e.two_sided));
            Some((self.lights.len() - 1) as LightId)
        });
        let uv = uv.filter(|t| t.iter().all(|v| v.is_finite()));
        self.geometry.triangles.push(Triangle { p, n, uv, material, emitter });
        true
    }

    /// Add an indexed triangle mesh with optional per-vertex normals.
    pub fn add_mesh(&mut self, positions: &[Vec3], normals: Option<&[Vec3]>, indices: &[[u32; 3]], material: MaterialId, emission: Option<AreaEmission>) {
        self.add_mesh_uv(positions, normals, None, indices, material, emission)
    }

    /// [`Self::add_mesh`] with optional per-vertex texture coordinates.
    pub fn add_mesh_uv(
        &mut self,
        positions: &[Vec3],
        normals: Option<&[Vec3]>,
        uvs: Option<&[Vec2]>,
        indices: &[[u32; 3]],
        material: MaterialId,
        emission: Option<AreaEmission>,
    ) {
        for tri in indices {
            let Some(p) = fetch3(positions, tri) else {
                self.error.get_or_insert(SceneError::NonFinite("a mesh index (out of range)"));
                return;
            };
            let n = normals.and_then(|ns| fetch3(ns, tri));
            let uv = uvs.and_then(|t| Some([*t.get(tri[0] as usize)?, *t.get(tri[1] as usize)?, *t.get(tri[2] as usize)?]));
            self.add_triangle_uv(p, n, uv, material, emission);
        }
    }

    /// Mitsuba's `rectangle`: [−1, 1]² in the z = 0 plane, normal +z (−z when flipped), then `to_world`.
    pub fn add_rectangle(&mut self, to_world: Mat4, flip_normals: bool, material: MaterialId, emission: Option<AreaEmission>) {
        let c = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| to_world.transform_point3(Vec3::new(x, y, 0.0)));
        let quads = [[0u32, 1, 2], [0, 2, 3]];
        let idx = if flip_normals { quads.map(|[a, b, c]| [a, c, b]) } else { quads };
        // Mitsuba's rectangle parameterisation: uv = ((x + 1)/2, (y + 1)/2).
        let uv = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)];
        self.add_mesh_uv(&c, None, Some(&uv), &idx, material, emission);
    }

    /// Mitsuba's `cube`: [−1, 1]³ with outward normals, then `to_world`; each face maps
    /// onto [0, 1]² in uv as Mitsuba's does ([`cube_texcoords`]).
    pub fn add_cube(&mut self, to_world: Mat4, flip_normals: bool, material: MaterialId, emission: Option<AreaEmission>) {
        let mut local = [Vec3::ZERO; 8];
        for (i, p) in local.iter_mut().enumerate() {
            let s = |bit: usize| if i & bit != 0 { 1.0 } else { -1.0 };
            *p = Vec3::new(s(1), s(2), s(4));
        }
        let v = local.map(|p| to_world.transform_point3(p));
        // Faces as quads with counter-clockwise winding seen from outside.
        const FACES: [[u32; 4]; 6] = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];
        let mut idx = [[0u32; 3]; 12];
        for (f, q) in FACES.iter().enumerate() {
            idx[2 * f] = [q[0], q[1], q[2]];
            idx[2 * f + 1] = [q[0], q[2], q[3]];
            if flip_normals {
                idx[2 * f].swap(1, 2);
                idx[2 * f + 1].swap(1, 2);
            }
        }
        // A to_world with negative determinant mirrors the winding; undo it so normals stay outward.
        if to_world.determinant() < 0.0 {
            for t in &mut idx {
                t.swap(1, 2);
            }
        }
        for (f, tri) in idx.iter().enumerate() {
            let face = FACES[f / 2];
            let normal = (local[face[1] as usize] - local[face[0] as usize]).cross(local[face[2] as usize] - local[face[0] as usize]);
            let uv = tri.map(|k| cube_texcoords(local[k as usize], normal));
            self.add_triangle_uv(tri.map(|k| v[k as usize]), None, Some(uv), material, emission);
        }
    }

    /// An analytic sphere, optionally emitting (sampled by solid angle, see `Light::sphere`).
    pub fn add_sphere(&mut self, center: Vec3, radius: f32, flip_normals: bool, material: MaterialId, emission: Option<AreaEmission>) {
        if !self.check_material(material) {
            return;
        }
        if !center.is_finite() || !radius.is_finite() {
            self.error.get_or_insert(SceneError::NonFinite("a sphere"));
            return;
        }
        if !(radius > 0.0) {
            self.warnings.degenerate_triangles += 1;
            return;
        }
        // Emission of zero radiance is dropped, as for triangles (the sphere stays).
        let emission = match emission {
            Some(e) if e.radiance.is_black() => {
                self.warnings.dark_lights += 1;
                None
            }
            other => other,
        };
        let emitter = emission.map(|e| {
            self.lights.push(Light::sphere(center, radius, e.radiance));
            (self.lights.len() - 1) as LightId
        });
        self.geometry.spheres.push(Sphere { center, radius, flip_normals, material, emitter });
    }

    /// Validate and split into the estimators' scene and the tracer's geometry.
    pub fn build(mut self) -> Result<(Scene, SceneGeometry, BuildWarnings), SceneError> {
        if let Some(e) = self.error {
            return Err(e);
        }
        if let Some((m, what)) = self.medium_intrusion() {
            return Err(SceneError::InsideMedium(m, what));
        }
        let camera = self.camera.ok_or(SceneError::NoCamera)?;
        let bounds = self.geometry.bounds();
        let (center, radius) = bounds.bounding_sphere();
        for l in &mut self.lights {
            l.set_scene_bounds(center, radius.max(1e-3));
        }
        let power: Vec<f32> = self.lights.iter().map(|l| l.power()).collect();
        let light_selection = AliasTable::new(&power);
        let infinite = (0..self.lights.len() as LightId).filter(|&i| self.lights[i as usize].is_infinite()).collect();
        if !self.material_textures.is_empty() {
            self.material_textures.resize(self.materials.len(), [None; TEXTURE_SLOTS]);
        }
        media::finish_interiors(&mut self.interiors, self.materials.len());
        let scene = Scene {
            camera,
            materials: self.materials,
            textures: self.textures,
            material_textures: self.material_textures,
            lights: self.lights,
            light_selection,
            infinite,
            bounds,
            interiors: self.interiors,
        };
        Ok((scene, self.geometry, self.warnings))
    }
}

/// Mitsuba 3's texture coordinates of cube corner `p` (in [−1, 1]³) on the face with
/// outward normal along `normal` (`src/shapes/cube.cpp`: every face maps onto [0, 1]²,
/// by these affine maps of the corner's two in-face coordinates).
pub fn cube_texcoords(p: Vec3, normal: Vec3) -> Vec2 {
    let h = |x: f32| 0.5 * (x + 1.0);
    let a = normal.abs();
    let (u, v) = if a.x >= a.y && a.x >= a.z {
        if normal.x > 0.0 { (p.y, -p.z) } else { (p.y, p.z) }
    } else if a.y >= a.z {
        if normal.y > 0.0 { (-p.x, -p.z) } else { (p.z, p.x) }
    } else if normal.z > 0.0 {
        (p.y, p.x)
    } else {
        (-p.y, p.x)
    };
    Vec2::new(h(u), h(v))
}

fn fetch3(v: &[Vec3], idx: &[u32; 3]) -> Option<[Vec3; 3]> {
    Some([*v.get(idx[0] as usize)?, *v.get(idx[1] as usize)?, *v.get(idx[2] as usize)?])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::FovAxis;
    use crate::spectrum::Rgb;

    /// A builder with a camera, one diffuse material and one unit triangle.
    fn builder() -> (SceneBuilder, MaterialId) {
        let mut b = SceneBuilder::new();
        b.set_camera(PerspectiveCamera::new(Mat4::IDENTITY, 40.0, FovAxis::X, 4, 4));
        let m = b.add_material(Material::diffuse(Rgb::splat(0.5)));
        b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::Y], None, m, None);
        (b, m)
    }

    /// Regression: every `constant` and `directional` emitter was counted as dark (its
    /// power is 0 until `build` knows the scene's radius) though it was kept. Injected
    /// bug checked: testing `light.power()` instead of the probe at radius 1 fails here.
    #[test]
    fn lights_at_infinity_are_not_counted_as_dark() {
        let (mut b, _) = builder();
        assert!(b.add_light(Light::constant_environment(Rgb::splat(1.0))).is_some());
        assert!(b.add_light(Light::directional(Vec3::NEG_Z, Rgb::splat(2.0))).is_some());
        let (scene, _, warnings) = b.build().unwrap();
        assert_eq!(warnings.dark_lights, 0);
        assert_eq!(scene.lights.len(), 2);
        assert!(scene.lights.iter().all(|l| l.power() > 0.0));
    }

    /// Lights that emit nothing are dropped and counted, each once: a point light, a
    /// sphere's emission and each triangle of an emitting mesh. Injected bug checked:
    /// keeping the dark point light (pushing it after counting) fails the light count.
    #[test]
    fn dark_lights_are_dropped_and_counted() {
        let (mut b, m) = builder();
        assert!(b.add_light(Light::point(Vec3::Z, Rgb::ZERO)).is_none());
        assert!(b.add_light(Light::constant_environment(Rgb::ZERO)).is_none());
        let dark = Some(AreaEmission { radiance: Rgb::ZERO, two_sided: false });
        b.add_sphere(Vec3::Z, 0.5, false, m, dark);
        b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::Z], None, m, dark);
        b.add_light(Light::point(Vec3::Z, Rgb::splat(1.0)));
        let (scene, geometry, warnings) = b.build().unwrap();
        assert_eq!(warnings.dark_lights, 4);
        assert_eq!(scene.lights.len(), 1, "only the bright point light is kept");
        assert!(geometry.spheres[0].emitter.is_none() && geometry.triangles[1].emitter.is_none());
    }

    /// Regression: a light whose power overflows f32 (here 4π·1e38) got an infinite
    /// weight, which the selection table drops, so the scene had no light selection
    /// ("the scene has no light", a black image under next-event estimation). Injected
    /// bug checked: removing the saturation in `Light::power` fails here.
    #[test]
    fn a_light_too_bright_for_f32_is_still_selected() {
        let (mut b, _) = builder();
        b.add_light(Light::point(Vec3::Z, Rgb::splat(1e38)));
        b.add_light(Light::point(Vec3::Y, Rgb::splat(1.0)));
        let (scene, _, warnings) = b.build().unwrap();
        assert_eq!(warnings.dark_lights, 0);
        assert_eq!(scene.lights[0].power(), f32::MAX);
        assert!(scene.light_selection.is_some());
        assert!(scene.light_pmf(0) > 0.99 && scene.light_pmf(1) > 0.0, "{} {}", scene.light_pmf(0), scene.light_pmf(1));
    }
}
