//! Shape plugins: `rectangle`, `cube`, `sphere`, `disk`, `obj`, `ply`.
//!
//! Each takes `to_world` and `flip_normals`, one `bsdf` (nested or `ref`; Mitsuba's
//! default `diffuse` 0.5 when absent, black for an emitter, as Mitsuba 3), optionally one nested `area` emitter and one
//! absorbing `interior` medium ([`super::media`]).
//! - `rectangle`, `disk`: the normal is Mitsuba's, `to_world`'s inverse transpose applied
//!   to +z, so a mirroring `to_world` reverses the winding to keep it.
//! - `disk`: tessellated into [`DISK_SEGMENTS`] triangles (a fan), which covers
//!   sin(2π/n)·n/(2π) ≈ 99.96 % of the unit disk's area; the emitted power of an emitting
//!   disk is reduced by the same factor.
//! - `sphere`: analytic; `to_world` must be a similarity (rotation, uniform scale,
//!   translation), applied to `center` and `radius`.
//! - `obj`, `ply`: vertex normals from the file (transformed by the inverse transpose)
//!   unless `face_normals`; a file without normals gets Mitsuba's angle-weighted vertex
//!   normals, as Mitsuba computes them.

use glam::{DMat3, DMat4, DVec3, Vec2, Vec3};

use ember_core::geometry::MaterialId;
use ember_core::scene::AreaEmission;

use super::build::Ctx;
use super::mesh::{self, MeshData};
use super::props::Props;
use super::transform;
use super::xml::{Obj, Tag};
use super::{Fail, Loc, Res, ply};

/// Triangles in a tessellated `disk`.
pub(crate) const DISK_SEGMENTS: u32 = 128;

const SHAPE_TYPES: &str = "obj, ply, rectangle, cube, sphere, disk";

/// What a shape element describes, read before anything is added.
enum Geometry<'a> {
    Rectangle,
    Cube,
    Disk,
    Sphere { center: [f64; 3], radius: f64 },
    Mesh { filename: &'a str, file_loc: Loc, face_normals: bool, flip_uv: bool },
}

impl Ctx<'_> {
    /// Where a shape's triangles come from, for messages.
    fn label(&self, obj: &Obj) -> String {
        let id = obj.id.as_deref().map(|i| format!(" id=\"{i}\"")).unwrap_or_default();
        format!("line {}: <shape type=\"{}\"{id}>", self.line(obj.loc), obj.kind)
    }

    pub(crate) fn shape(&mut self, idx: usize) -> Res<()> {
        let obj = self.obj(idx)?;
        if !matches!(obj.kind.as_str(), "obj" | "ply" | "rectangle" | "cube" | "sphere" | "disk") {
            return Err(Fail::at(obj.loc, format!("unsupported shape type \"{}\" (supported: {SHAPE_TYPES})", obj.kind)));
        }
        self.check_children(obj, &[Tag::Bsdf, Tag::Emitter, Tag::Medium])?;
        let bsdf = self.single_child(obj, Tag::Bsdf)?;
        let emitter = self.single_child(obj, Tag::Emitter)?;

        // Read every property first, so an unreferenced one is reported before any work.
        let mut p = Props::new(obj);
        let to_world = self.render_frame * p.transform("to_world")?;
        let flip = p.bool("flip_normals", false)?;
        let geometry = match obj.kind.as_str() {
            "rectangle" => Geometry::Rectangle,
            "cube" => Geometry::Cube,
            "disk" => Geometry::Disk,
            "sphere" => {
                let center = p.point_opt("center")?.unwrap_or([0.0; 3]);
                let radius = p.float("radius", 1.0)?;
                if !(radius > 0.0) {
                    return Err(Fail::at(p.loc_of("radius"), format!("sphere `radius` must be positive, got {radius}")));
                }
                Geometry::Sphere { center, radius }
            }
            _ => {
                let file_loc = p.loc_of("filename");
                let filename =
                    p.string_opt("filename")?.ok_or_else(|| Fail::at(obj.loc, format!("<shape type=\"{}\"> needs a `filename` string", obj.kind)))?;
                let face_normals = p.bool("face_normals", false)?;
                // Mitsuba flips v (v' = 1 − v) for OBJ files by default, not for PLY.
                let flip_uv = p.bool("flip_tex_coords", obj.kind == "obj")?;
                Geometry::Mesh { filename, file_loc, face_normals, flip_uv }
            }
        };
        p.finish()?;

        let interior = self.interior_medium(obj)?;
        let material = match bsdf {
            Some(b) => self.material(b)?,
            None => self.default_material(emitter.is_some()),
        };
        // A shape enclosing a medium gets its own copy of the material, carrying σ_t.
        let material = match interior {
            Some(sigma_t) => self.sb.add_interior(material, sigma_t),
            None => material,
        };
        let emission = match emitter {
            Some(e) => Some(self.area_emission(e)?),
            None => None,
        };
        let mirrored = DMat3::from_mat4(to_world).determinant() < 0.0;
        match geometry {
            Geometry::Rectangle => {
                let m = to_world.as_mat4();
                // The corners and triangles `SceneBuilder::add_rectangle` makes, to check them.
                let local = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| Vec3::new(x, y, 0.0));
                let c = local.map(|p| m.transform_point3(p));
                self.check_finite(obj, &c)?;
                self.report_dropped(obj, &c, &local, &to_world, &[[0, 1, 2], [0, 2, 3]]);
                self.sb.add_rectangle(m, flip ^ mirrored, material, emission);
            }
            Geometry::Cube => {
                let m = to_world.as_mat4();
                let mut local = [Vec3::ZERO; 8];
                for (i, v) in local.iter_mut().enumerate() {
                    let s = |bit: usize| if i & bit != 0 { 1.0 } else { -1.0 };
                    *v = Vec3::new(s(1), s(2), s(4));
                }
                let c = local.map(|p| m.transform_point3(p));
                self.check_finite(obj, &c)?;
                if !(m.determinant().abs() > 0.0) {
                    self.warnings.push(format!("{}: the cube is flat: its zero-area faces are dropped", self.label(obj)));
                } else {
                    self.report_dropped(obj, &c, &local, &to_world, &CUBE_TRIANGLES);
                }
                self.sb.add_cube(m, flip, material, emission);
            }
            Geometry::Disk => {
                let mut positions = vec![transform::point(&to_world, Vec3::ZERO)];
                let mut local = vec![Vec3::ZERO];
                for i in 0..DISK_SEGMENTS {
                    let phi = std::f64::consts::TAU * i as f64 / DISK_SEGMENTS as f64;
                    let p = DVec3::new(phi.cos(), phi.sin(), 0.0);
                    positions.push(to_world.transform_point3(p).as_vec3());
                    local.push(p.as_vec3());
                }
                self.check_finite(obj, &positions)?;
                let tris: Vec<[u32; 3]> = (0..DISK_SEGMENTS).map(|i| [0, 1 + i, 1 + (i + 1) % DISK_SEGMENTS]).collect();
                let placed = Placed { positions: &positions, local: &local, to_world: &to_world };
                self.add_triangles_uv(obj, placed, None, None, &tris, flip ^ mirrored, material, emission)?;
            }
            Geometry::Sphere { center, radius } => {
                let scale = transform::similarity_scale(&to_world, 1e-4).ok_or_else(|| {
                    Fail::at(obj.loc, "a sphere's `to_world` must be a rotation, uniform scale and translation (ellipsoids are not supported)")
                })?;
                if flip && emission.is_some() {
                    return Err(Fail::at(obj.loc, "an emitting sphere with flip_normals (emitting inward) is not supported"));
                }
                let c = to_world.transform_point3(DVec3::from_array(center)).as_vec3();
                let r = (radius * scale) as f32;
                if !c.is_finite() || !r.is_finite() {
                    return Err(Fail::at(obj.loc, "the sphere's centre or radius is not finite after to_world"));
                }
                self.sb.add_sphere(c, r, flip, material, emission);
            }
            Geometry::Mesh { filename, file_loc, face_normals, flip_uv } => {
                let path = self.base_dir.join(filename);
                self.inputs.push(path.clone());
                let mut data = if obj.kind == "obj" { mesh::load_obj(&path) } else { super::read_input(&path).and_then(|b| ply::parse(&b)) }
                    .map_err(|e| Fail::at(file_loc, format!("cannot load the {} mesh \"{}\": {e}", obj.kind, path.display())))?;
                if flip_uv {
                    data.texcoords.iter_mut().flatten().for_each(|uv| uv.y = 1.0 - uv.y);
                }
                self.place_mesh(obj, file_loc, filename, data, &to_world, flip, face_normals, material, emission)?;
            }
        }
        Ok(())
    }

    fn check_finite(&self, obj: &Obj, points: &[Vec3]) -> Res<()> {
        if points.iter().all(|p| p.is_finite()) {
            Ok(())
        } else {
            Err(Fail::at(obj.loc, "the shape's vertices are not finite after to_world (the transform overflows)"))
        }
    }

    /// Transform a loaded mesh to world space and add it.
    fn place_mesh(
        &mut self,
        obj: &Obj,
        file_loc: Loc,
        filename: &str,
        data: MeshData,
        to_world: &DMat4,
        flip: bool,
        face_normals: bool,
        material: MaterialId,
        emission: Option<AreaEmission>,
    ) -> Res<()> {
        for note in &data.notes {
            self.warnings.push(format!("{}: \"{filename}\": {note}", self.label(obj)));
        }
        if data.triangles.is_empty() {
            self.warnings.push(format!("{}: \"{filename}\" has no triangles", self.label(obj)));
        }
        if let Some(i) = data.positions.iter().position(|p| !p.is_finite()) {
            return Err(Fail::at(file_loc, format!("mesh \"{filename}\": vertex {i} is not finite (NaN or infinite)")));
        }
        let positions: Vec<Vec3> = data.positions.iter().map(|&p| transform::point(to_world, p)).collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(Fail::at(file_loc, format!("mesh \"{filename}\": vertex {i} is not finite after to_world")));
        }
        let normals = match (face_normals, data.normals) {
            (true, _) => None,
            (false, Some(ns)) => {
                let bad = ns.iter().filter(|n| !(n.is_finite() && n.length_squared() > 0.0)).count();
                if bad > 0 {
                    self.warnings.push(format!(
                        "{}: \"{filename}\": {bad} vertex normals are zero or not finite; triangles using them get face normals",
                        self.label(obj)
                    ));
                }
                // A singular to_world flattens the mesh: its triangles are dropped anyway.
                transform::normal_matrix(to_world).map(|nm| ns.iter().map(|n| (nm * n.as_dvec3()).normalize_or_zero().as_vec3()).collect::<Vec<_>>())
            }
            (false, None) => Some(mesh::vertex_normals(&positions, &data.triangles)),
        };
        let texcoords = data.texcoords.filter(|t| t.len() == positions.len());
        let placed = Placed { positions: &positions, local: &data.positions, to_world };
        self.add_triangles_uv(obj, placed, normals.as_deref(), texcoords.as_deref(), &data.triangles, flip, material, emission)
    }

    /// Add triangles one by one (with per-vertex normals and texture coordinates when
    /// given), reporting those the builder drops and why.
    #[allow(clippy::too_many_arguments)]
    fn add_triangles_uv(
        &mut self,
        obj: &Obj,
        placed: Placed,
        normals: Option<&[Vec3]>,
        texcoords: Option<&[Vec2]>,
        triangles: &[[u32; 3]],
        flip: bool,
        material: MaterialId,
        emission: Option<AreaEmission>,
    ) -> Res<()> {
        let mut dropped = Dropped::default();
        for t in triangles {
            let t = if flip { [t[0], t[2], t[1]] } else { *t };
            let p = fetch(placed.positions, &t).ok_or_else(|| Fail::at(obj.loc, "internal error: mesh index out of range"))?;
            let n = normals.and_then(|ns| fetch(ns, &t)).map(|n| if flip { n.map(|v| -v) } else { n });
            let uv = texcoords.and_then(|uv| Some([*uv.get(t[0] as usize)?, *uv.get(t[1] as usize)?, *uv.get(t[2] as usize)?]));
            if !self.sb.add_triangle_uv(p, n, uv, material, emission) {
                dropped.add(p, placed.exact(&t));
            }
        }
        self.warn_dropped(obj, &dropped, triangles.len());
        Ok(())
    }

    /// Warn about the triangles of `corners` (placed from `local` by `to_world`) that
    /// `SceneBuilder` will drop, saying why.
    fn report_dropped(&mut self, obj: &Obj, corners: &[Vec3], local: &[Vec3], to_world: &DMat4, triangles: &[[u32; 3]]) {
        let placed = Placed { positions: corners, local, to_world };
        let mut dropped = Dropped::default();
        for t in triangles {
            if let Some(p) = fetch(corners, t)
                && !(area2(p) > 0.0 && area2(p).is_finite())
            {
                dropped.add(p, placed.exact(t));
            }
        }
        self.warn_dropped(obj, &dropped, triangles.len());
    }

    /// One warning per cause of the drops, naming the shape.
    fn warn_dropped(&mut self, obj: &Obj, d: &Dropped, total: usize) {
        let label = self.label(obj);
        if d.overflow > 0 {
            self.warnings.push(format!(
                "{label}: {} of {total} triangles have coordinates too large for single precision (up to {:.3e} from the camera): \
                 their area overflows to infinity, so they were dropped",
                d.overflow, d.overflow_extent
            ));
        }
        if d.far > 0 {
            let step = f32_step(d.far_distance);
            self.warnings.push(format!(
                "{label}: {} of {total} triangles collapse to zero area in single precision and were dropped: they lie up to {:.3e} from the camera, \
                 where coordinates are {step:.3e} apart (precision is lost far from the camera; bring the camera nearer or scale the scene down)",
                d.far, d.far_distance
            ));
        }
        if d.tiny > 0 {
            self.warnings
                .push(format!("{label}: {} of {total} triangles are too small for single precision (their area underflows to zero) and were dropped", d.tiny));
        }
        if d.degenerate > 0 {
            self.warnings.push(format!("{label}: {} of {total} triangles have zero area and were dropped", d.degenerate));
        }
    }
}

/// The triangles `SceneBuilder::add_cube` makes from the corners of [−1, 1]³ (corner
/// `i` has x, y, z = ±1 by bits 0, 1, 2), windings aside: two per face.
const CUBE_TRIANGLES: [[u32; 3]; 12] =
    [[0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5], [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3], [0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6]];

/// A shape's vertices as added (render frame, f32) and where they came from (object
/// space and `to_world`), to recompute a dropped triangle in f64.
#[derive(Clone, Copy)]
struct Placed<'a> {
    positions: &'a [Vec3],
    local: &'a [Vec3],
    to_world: &'a DMat4,
}

impl Placed<'_> {
    /// Triangle `t` transformed in f64, before rounding to f32.
    fn exact(&self, t: &[u32; 3]) -> Option<[DVec3; 3]> {
        let p = fetch(self.local, t)?;
        Some(p.map(|v| self.to_world.transform_point3(v.as_dvec3())))
    }
}

/// Triangles the scene builder dropped, by cause.
#[derive(Debug, Default)]
struct Dropped {
    /// The f32 edge cross product overflows (coordinates near f32's range).
    overflow: usize,
    /// The largest coordinate among those.
    overflow_extent: f64,
    /// Non-degenerate in f64 but collapsed by rounding to f32 far from the camera.
    far: usize,
    /// The farthest vertex among those (the render frame is centred on the camera).
    far_distance: f64,
    /// Non-degenerate but so small that the f32 area underflows.
    tiny: usize,
    /// Zero area in the file (or after a singular `to_world`).
    degenerate: usize,
}

impl Dropped {
    /// Classify a dropped triangle from its f32 vertices `p` and its f64 ones `exact`.
    fn add(&mut self, p: [Vec3; 3], exact: Option<[DVec3; 3]>) {
        if !area2(p).is_finite() {
            self.overflow += 1;
            let extent = p.iter().map(|v| v.abs().max_element() as f64).fold(0.0, f64::max);
            self.overflow_extent = self.overflow_extent.max(extent);
            return;
        }
        let Some(e) = exact else {
            self.degenerate += 1;
            return;
        };
        let (a, b) = (e[1] - e[0], e[2] - e[0]);
        let cross = a.cross(b).length();
        // The sine of the corner angle: a triangle that is flat in f64 (to f32's
        // precision near the origin) is degenerate in the file, whatever the rounding.
        let sine = cross / (a.length() * b.length());
        if !(sine > 1e-6) {
            self.degenerate += 1;
        } else if cross * cross < f32::MIN_POSITIVE as f64 * 16.0 {
            self.tiny += 1;
        } else {
            self.far += 1;
            let distance = e.iter().map(|v| v.length()).fold(0.0, f64::max);
            self.far_distance = self.far_distance.max(distance);
        }
    }
}

/// The squared length of the edge cross product (4 × area²), as
/// `SceneBuilder::add_triangle` tests it (> 0 and finite to be kept).
fn area2(p: [Vec3; 3]) -> f32 {
    (p[1] - p[0]).cross(p[2] - p[0]).length_squared()
}

/// The spacing of f32 values at magnitude `x`.
fn f32_step(x: f64) -> f64 {
    let x = (x as f32).abs();
    if x.is_finite() { (f32::from_bits(x.to_bits() + 1) - x) as f64 } else { f64::INFINITY }
}

fn fetch(v: &[Vec3], t: &[u32; 3]) -> Option<[Vec3; 3]> {
    Some([*v.get(t[0] as usize)?, *v.get(t[1] as usize)?, *v.get(t[2] as usize)?])
}
