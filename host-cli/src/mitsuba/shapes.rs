//! Shape plugins: `rectangle`, `cube`, `sphere`, `disk`, `obj`, `ply`.
//!
//! Each takes `to_world` and `flip_normals`, one `bsdf` (nested or `ref`; Mitsuba's
//! default `diffuse` 0.5 when absent) and optionally one nested `area` emitter.
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

/// Where a shape's triangles come from, for messages.
fn label(obj: &Obj) -> String {
    let id = obj.id.as_deref().map(|i| format!(" id=\"{i}\"")).unwrap_or_default();
    format!("line {}: <shape type=\"{}\"{id}>", obj.loc.line, obj.kind)
}

impl Ctx<'_> {
    pub(crate) fn shape(&mut self, idx: usize) -> Res<()> {
        let obj = self.obj(idx)?;
        if !matches!(obj.kind.as_str(), "obj" | "ply" | "rectangle" | "cube" | "sphere" | "disk") {
            return Err(Fail::at(obj.loc, format!("unsupported shape type \"{}\" (supported: {SHAPE_TYPES})", obj.kind)));
        }
        self.check_children(obj, &[Tag::Bsdf, Tag::Emitter])?;
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

        let material = match bsdf {
            Some(b) => self.material(b)?,
            None => self.default_material(),
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
                let c = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| m.transform_point3(Vec3::new(x, y, 0.0)));
                self.check_finite(obj, &c)?;
                let dropped = [[0, 1, 2], [0, 2, 3]].iter().filter(|t| !(area2(c[t[0]], c[t[1]], c[t[2]]) > 0.0)).count();
                if dropped > 0 {
                    self.warnings.push(format!("{}: {dropped} of 2 triangles have zero area and were dropped", label(obj)));
                }
                self.sb.add_rectangle(m, flip ^ mirrored, material, emission);
            }
            Geometry::Cube => {
                let m = to_world.as_mat4();
                let mut c = [Vec3::ZERO; 8];
                for (i, v) in c.iter_mut().enumerate() {
                    let s = |bit: usize| if i & bit != 0 { 1.0 } else { -1.0 };
                    *v = m.transform_point3(Vec3::new(s(1), s(2), s(4)));
                }
                self.check_finite(obj, &c)?;
                if !(m.determinant().abs() > 0.0) {
                    self.warnings.push(format!("{}: the cube is flat: its zero-area faces are dropped", label(obj)));
                }
                self.sb.add_cube(m, flip, material, emission);
            }
            Geometry::Disk => {
                let mut positions = vec![transform::point(&to_world, Vec3::ZERO)];
                for i in 0..DISK_SEGMENTS {
                    let phi = std::f64::consts::TAU * i as f64 / DISK_SEGMENTS as f64;
                    let local = DVec3::new(phi.cos(), phi.sin(), 0.0);
                    positions.push(to_world.transform_point3(local).as_vec3());
                }
                self.check_finite(obj, &positions)?;
                let tris: Vec<[u32; 3]> = (0..DISK_SEGMENTS).map(|i| [0, 1 + i, 1 + (i + 1) % DISK_SEGMENTS]).collect();
                self.add_triangles(obj, &positions, None, &tris, flip ^ mirrored, material, emission)?;
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
                let mut data =
                    if obj.kind == "obj" { mesh::load_obj(&path) } else { std::fs::read(&path).map_err(|e| e.to_string()).and_then(|b| ply::parse(&b)) }
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
            self.warnings.push(format!("{}: \"{filename}\": {note}", label(obj)));
        }
        if data.triangles.is_empty() {
            self.warnings.push(format!("{}: \"{filename}\" has no triangles", label(obj)));
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
                    self.warnings
                        .push(format!("{}: \"{filename}\": {bad} vertex normals are zero or not finite; triangles using them get face normals", label(obj)));
                }
                // A singular to_world flattens the mesh: its triangles are dropped anyway.
                transform::normal_matrix(to_world).map(|nm| ns.iter().map(|n| (nm * n.as_dvec3()).normalize_or_zero().as_vec3()).collect::<Vec<_>>())
            }
            (false, None) => Some(mesh::vertex_normals(&positions, &data.triangles)),
        };
        let texcoords = data.texcoords.filter(|t| t.len() == positions.len());
        self.add_triangles_uv(obj, &positions, normals.as_deref(), texcoords.as_deref(), &data.triangles, flip, material, emission)
    }

    /// Add triangles one by one, reporting those the builder drops for zero area.
    #[allow(clippy::too_many_arguments)]
    fn add_triangles(
        &mut self,
        obj: &Obj,
        positions: &[Vec3],
        normals: Option<&[Vec3]>,
        triangles: &[[u32; 3]],
        flip: bool,
        material: MaterialId,
        emission: Option<AreaEmission>,
    ) -> Res<()> {
        self.add_triangles_uv(obj, positions, normals, None, triangles, flip, material, emission)
    }

    /// [`Self::add_triangles`] with per-vertex texture coordinates.
    #[allow(clippy::too_many_arguments)]
    fn add_triangles_uv(
        &mut self,
        obj: &Obj,
        positions: &[Vec3],
        normals: Option<&[Vec3]>,
        texcoords: Option<&[Vec2]>,
        triangles: &[[u32; 3]],
        flip: bool,
        material: MaterialId,
        emission: Option<AreaEmission>,
    ) -> Res<()> {
        let mut dropped = 0usize;
        for t in triangles {
            let t = if flip { [t[0], t[2], t[1]] } else { *t };
            let p = fetch(positions, &t).ok_or_else(|| Fail::at(obj.loc, "internal error: mesh index out of range"))?;
            let n = normals.and_then(|ns| fetch(ns, &t)).map(|n| if flip { n.map(|v| -v) } else { n });
            let uv = texcoords.and_then(|uv| Some([*uv.get(t[0] as usize)?, *uv.get(t[1] as usize)?, *uv.get(t[2] as usize)?]));
            if !self.sb.add_triangle_uv(p, n, uv, material, emission) {
                dropped += 1;
            }
        }
        if dropped > 0 {
            self.warnings.push(format!("{}: {dropped} of {} triangles have zero area and were dropped", label(obj), triangles.len()));
        }
        Ok(())
    }
}

/// The squared length of the edge cross product (4 × area²), as `SceneBuilder::add_triangle` tests it.
fn area2(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let l = (b - a).cross(c - a).length_squared();
    if l.is_finite() { l } else { 0.0 }
}

fn fetch(v: &[Vec3], t: &[u32; 3]) -> Option<[Vec3; 3]> {
    Some([*v.get(t[0] as usize)?, *v.get(t[1] as usize)?, *v.get(t[2] as usize)?])
}
