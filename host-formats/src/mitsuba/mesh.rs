//! Triangle meshes from files: Wavefront OBJ (through `tobj`) and the data both loaders
//! share; Mitsuba's vertex-normal reconstruction for files without normals.

use std::io::{BufReader, Read};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use glam::{DVec3, Vec2, Vec3};

use crate::files::{MAX_INPUT_BYTES, open_regular};

/// A mesh in object space.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct MeshData {
    pub positions: Vec<Vec3>,
    /// Per-vertex normals, when the file has them for every vertex.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates as stored, when the file has them for every vertex.
    pub texcoords: Option<Vec<Vec2>>,
    pub triangles: Vec<[u32; 3]>,
    /// What the file contained that the renderer does not use.
    pub notes: Vec<String>,
}

/// Load an OBJ file: every object and group merged into one mesh (as Mitsuba does),
/// polygons triangulated as fans, points, lines and materials not read.
/// Only a regular file is read, and no more of it than its size when opened (see
/// [`super::read_input`]).
pub(crate) fn load_obj(path: &Path) -> Result<MeshData, String> {
    let (file, len) = open_regular(path)?;
    if len > MAX_INPUT_BYTES {
        return Err(format!("holds {len} bytes, more than the {MAX_INPUT_BYTES} a mesh may have"));
    }
    let mut reader = BufReader::new(file.take(len));
    // `..Default::default()` keeps this compiling if another crate turns on tobj's
    // optional features (which add fields).
    #[allow(clippy::needless_update)]
    let opts = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true, ..Default::default() };
    // tobj indexes with unchecked arithmetic in a few places; a malformed file must not
    // take the process down, so a panic inside it becomes an error.
    let loaded = catch_unwind(AssertUnwindSafe(|| tobj::load_obj_buf(&mut reader, &opts, |_| Ok(Default::default()))))
        .map_err(|_| "malformed OBJ file (the OBJ parser failed)".to_string())?;
    let (models, _materials) = loaded.map_err(|e| format!("malformed OBJ file: {e}"))?;
    let mut out = MeshData::default();
    let mut normals = Vec::new();
    let mut all_normals = true;
    let mut texcoords = Vec::new();
    let mut all_texcoords = true;
    for model in &models {
        let m = &model.mesh;
        let base = u32::try_from(out.positions.len()).map_err(|_| "too many vertices")?;
        if m.positions.len() % 3 != 0 || m.indices.len() % 3 != 0 {
            return Err("malformed OBJ file (inconsistent vertex data)".into());
        }
        let count = m.positions.len() / 3;
        out.positions.extend(m.positions.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        if m.normals.len() == m.positions.len() {
            normals.extend(m.normals.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        } else {
            all_normals = false;
        }
        if m.texcoords.len() == 2 * count {
            texcoords.extend(m.texcoords.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])));
        } else {
            all_texcoords = false;
        }
        for t in m.indices.chunks_exact(3) {
            let mut tri = [0u32; 3];
            for (k, &i) in t.iter().enumerate() {
                if i as usize >= count {
                    return Err(format!("face index {} out of range ({count} vertices)", i as u64 + 1));
                }
                tri[k] = base.checked_add(i).ok_or("too many vertices")?;
            }
            out.triangles.push(tri);
        }
    }
    if all_texcoords && !texcoords.is_empty() {
        out.texcoords = Some(texcoords);
    } else if !texcoords.is_empty() {
        out.notes.push("only some vertices have texture coordinates: the mesh uses barycentrics instead".into());
    }
    if all_normals && !normals.is_empty() {
        out.normals = Some(normals);
    } else if !normals.is_empty() {
        out.notes.push("only some vertices have normals: normals are recomputed for the whole mesh".into());
    }
    Ok(out)
}

/// Mitsuba's `Mesh::recompute_vertex_normals`: each vertex gets the sum of the unit
/// normals of its faces weighted by the face's angle at that vertex (Thürmer and Wüthrich
/// 1998), normalised; a vertex with no usable face keeps a zero normal, which the scene
/// builder replaces by the face normal.
pub(crate) fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut acc = vec![DVec3::ZERO; positions.len()];
    for tri in triangles {
        let Some(v) = fetch(positions, tri) else { continue };
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let len = n.length();
        if !(len > 0.0) || !len.is_finite() {
            continue;
        }
        let n = n / len;
        for i in 0..3 {
            let d0 = (v[(i + 1) % 3] - v[i]).normalize_or_zero();
            let d1 = (v[(i + 2) % 3] - v[i]).normalize_or_zero();
            let angle = unit_angle(d0, d1);
            if let Some(a) = acc.get_mut(tri[i] as usize) {
                *a += n * angle;
            }
        }
    }
    acc.into_iter().map(|n| n.normalize_or_zero().as_vec3()).collect()
}

fn fetch(p: &[Vec3], tri: &[u32; 3]) -> Option<[DVec3; 3]> {
    Some([p.get(tri[0] as usize)?.as_dvec3(), p.get(tri[1] as usize)?.as_dvec3(), p.get(tri[2] as usize)?.as_dvec3()])
}

/// The angle between two unit vectors, accurate near 0 and π (Mitsuba's `unit_angle`).
fn unit_angle(a: DVec3, b: DVec3) -> f64 {
    if a.dot(b) < 0.0 { std::f64::consts::PI - 2.0 * ((a + b).length() / 2.0).min(1.0).asin() } else { 2.0 * ((a - b).length() / 2.0).min(1.0).asin() }
}
