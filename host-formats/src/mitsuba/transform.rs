//! The `<transform>` operations, in double precision (the parser composes them with
//! each new one left-multiplying the product so far, as Mitsuba does).

use glam::{DMat3, DMat4, DVec3, Vec3};

use ember_core::scene::builtin;

pub(crate) fn translate(v: [f64; 3]) -> DMat4 {
    DMat4::from_translation(DVec3::from_array(v))
}

pub(crate) fn scale(v: [f64; 3]) -> DMat4 {
    DMat4::from_scale(DVec3::from_array(v))
}

/// Right-handed rotation by `angle_deg` degrees about `axis` (normalised); `None` for a
/// zero axis. Same matrix as Mitsuba's `Transform4f::rotate`.
pub(crate) fn rotate(axis: [f64; 3], angle_deg: f64) -> Option<DMat4> {
    let axis = DVec3::from_array(axis);
    let len = axis.length();
    if !(len > 0.0) || !len.is_finite() {
        return None;
    }
    Some(DMat4::from_axis_angle(axis / len, angle_deg.to_radians()))
}

/// Mitsuba's `lookat` (through [`builtin::look_at`]); an error text when the frame is
/// degenerate (origin = target, or `up` parallel to the view direction).
pub(crate) fn look_at(origin: [f64; 3], target: [f64; 3], up: [f64; 3]) -> Result<DMat4, String> {
    let o = DVec3::from_array(origin);
    let t = DVec3::from_array(target);
    let u = DVec3::from_array(up);
    let dir = t - o;
    if !(dir.length() > 0.0) {
        return Err("<lookat> origin and target coincide".into());
    }
    let left = u.cross(dir.normalize());
    if !(left.length() > 1e-9 * u.length().max(1e-300)) {
        return Err("<lookat> `up` is zero or parallel to the viewing direction".into());
    }
    let m = builtin::look_at(o.as_vec3(), t.as_vec3(), u.as_vec3()).as_dmat4();
    if !m.is_finite() {
        return Err("<lookat> gives a degenerate frame in single precision".into());
    }
    Ok(m)
}

/// The linear part is a rotation (or reflection) times a uniform scale: returns the scale.
pub(crate) fn similarity_scale(m: &DMat4, tolerance: f64) -> Option<f64> {
    let l = DMat3::from_mat4(*m);
    let s2 = [l.x_axis, l.y_axis, l.z_axis].map(|c| c.length_squared());
    let mean = (s2[0] + s2[1] + s2[2]) / 3.0;
    if !(mean > 0.0) || !mean.is_finite() {
        return None;
    }
    let g = l.transpose() * l;
    let off = [g.x_axis.y, g.x_axis.z, g.y_axis.z];
    let ok = s2.iter().all(|v| (v - mean).abs() <= tolerance * mean) && off.iter().all(|v| v.abs() <= tolerance * mean);
    ok.then(|| mean.sqrt())
}

/// Transform of normals: the inverse transpose of the linear part; `None` if singular.
pub(crate) fn normal_matrix(m: &DMat4) -> Option<DMat3> {
    let l = DMat3::from_mat4(*m);
    let det = l.determinant();
    (det != 0.0 && det.is_finite()).then(|| l.inverse().transpose())
}

/// Apply to a point, in double precision, rounding once to `f32`.
#[inline]
pub(crate) fn point(m: &DMat4, p: Vec3) -> Vec3 {
    m.transform_point3(p.as_dvec3()).as_vec3()
}
