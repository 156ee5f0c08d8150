//! Pinhole camera with Mitsuba 3's `perspective` conventions.
//!
//! Camera space is Mitsuba's (left, up, forward): the camera looks along local +z, local
//! +y is up, and local +x is *left* in the image, because `lookat` builds x as
//! cross(up, forward). Mitsuba maps a camera-space direction (x, y, z) to the film by
//! (`perspective_projection` in `sensor.h`)
//!   s_x = (1 − x/(z·t_x)) / 2,   s_y = (1 − y/(z·t_y)) / 2,   film = (s_x W, s_y H),
//! with t_x = tan(fov_x/2), t_y = t_x·H/W, and film (0, 0) the top-left corner of the image.
//! So a point on the camera's +x side lands in the left half and a point above the axis in
//! the top half; a pbrt-style camera would render the suite's scenes mirrored.
//!
//! Densities and importance (pbrt-v4 `PerspectiveCamera::PDF_We` / `We`; Veach's thesis
//! §8.1): on the image plane at distance 1 the film covers A_film = 4 t_x t_y, and a point
//! there maps to a direction at angle θ from the axis with dω = cos³θ dA. Hence
//! - `pdf_dir` (film uniform over the whole film): p(ω) = 1 / (A_film cos³θ);
//! - `importance` per pixel, We(ω) = 1 / (A_pixel cos⁴θ), A_pixel = A_film/(W·H), so that
//!   ∫_pixel We(ω) cosθ dω = 1: a pixel's value is I_j = ∫ We(ω) L(ω) cosθ dω, and a
//!   light-tracing connection from a point at distance d adds, to the pixel it lands in,
//!   β · f · |cos_surface| · We · cosθ / d² (the pinhole is a delta in position: the
//!   sample's density is 1, like a point light's, and cosθ/d² is the geometry term's
//!   camera half, which the caller applies).

use crate::geometry::Ray;
use crate::math::{Mat3, Mat4, Vec2, Vec3, sqrt, tan};
use crate::measure::SolidAnglePdf;

/// Which image extent Mitsuba's `fov` spans (`fov_axis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    /// Horizontal (Mitsuba's default).
    X,
    /// Vertical.
    Y,
    /// The smaller of the two extents.
    Smaller,
    /// The larger of the two extents.
    Larger,
    /// The image diagonal.
    Diagonal,
}

/// A connection from a scene point to the pinhole (light tracing, BDPT t = 1).
#[derive(Clone, Copy, Debug)]
pub struct CameraSample {
    /// Continuous pixel coordinates in [0, W) × [0, H).
    pub film: Vec2,
    /// Unit direction from the reference point toward the camera.
    pub wi: Vec3,
    /// Distance from the reference point to the pinhole.
    pub dist: f32,
    /// We(−wi), per pixel (see the module notes); the caller multiplies by cosθ/dist².
    pub importance: f32,
    /// 1: the pinhole is a delta in position (as for delta lights).
    pub pdf: SolidAnglePdf,
}

impl PerspectiveCamera {
    /// Importance arriving at the connected point per unit projected area there,
    /// W_e |cos θ_c| / d²: what a light-path vertex multiplies its throughput by when it
    /// connects to the pinhole (the pinhole's counterpart of a delta light's I / d²).
    #[inline]
    pub fn arriving_importance(&self, cs: &CameraSample) -> f32 {
        let cos_c = self.forward().dot(-cs.wi).abs();
        cs.importance * cos_c / (cs.dist * cs.dist)
    }
}

/// Pinhole perspective camera (Mitsuba 3 `perspective`, no near/far clipping).
#[derive(Clone, Copy, Debug)]
pub struct PerspectiveCamera {
    to_world: Mat4,
    /// Inverse of `to_world`'s linear part: world vectors to camera space.
    to_local: Mat3,
    position: Vec3,
    forward: Vec3,
    width: u32,
    height: u32,
    /// Half-extents of the film on the plane z = 1: (t_x, t_y).
    tan_half: Vec2,
    film_area: f32,
    pixel_area: f32,
}

impl PerspectiveCamera {
    /// `to_world`: Mitsuba convention: camera looks along local +z, local +x is LEFT in
    /// the image (image columns run toward camera −x), +y up. See
    /// /work/shared/scenes/README.md. `fov_deg` is clamped to (0, 180); a singular
    /// `to_world` is replaced by the identity, a zero size by 1. `to_world` is expected to
    /// be rigid (Mitsuba's `lookat`): importance and densities are measured in camera space.
    pub fn new(to_world: Mat4, fov_deg: f32, fov_axis: FovAxis, width: u32, height: u32) -> Self {
        let width = width.max(1);
        let height = height.max(1);
        let aspect = width as f32 / height as f32;
        let linear = Mat3::from_mat4(to_world);
        let det = linear.determinant();
        let (to_world, linear) = if det != 0.0 && det.is_finite() { (to_world, linear) } else { (Mat4::IDENTITY, Mat3::IDENTITY) };
        let to_local = linear.inverse();
        // Mitsuba's parse_fov, in tangents: every axis is converted to the x extent.
        let t = tan(0.5 * fov_deg.clamp(1e-3, 179.9).to_radians());
        let axis = match fov_axis {
            FovAxis::Smaller if aspect > 1.0 => FovAxis::Y,
            FovAxis::Smaller => FovAxis::X,
            FovAxis::Larger if aspect > 1.0 => FovAxis::X,
            FovAxis::Larger => FovAxis::Y,
            a => a,
        };
        let tan_half_x = match axis {
            FovAxis::Y => t * aspect,
            FovAxis::Diagonal => t / sqrt(1.0 + 1.0 / (aspect * aspect)),
            _ => t,
        };
        let tan_half = Vec2::new(tan_half_x, tan_half_x / aspect);
        let film_area = 4.0 * tan_half.x * tan_half.y;
        Self {
            to_world,
            to_local,
            position: to_world.transform_point3(Vec3::ZERO),
            forward: to_world.transform_vector3(Vec3::Z).normalize_or(Vec3::Z),
            width,
            height,
            tan_half,
            film_area,
            pixel_area: film_area / (width as f32 * height as f32),
        }
    }

    #[inline]
    pub fn width(&self) -> u32 {
        self.width
    }
    #[inline]
    pub fn height(&self) -> u32 {
        self.height
    }
    /// The pinhole.
    #[inline]
    pub fn position(&self) -> Vec3 {
        self.position
    }
    /// tan of half the horizontal field of view (the film's half-width on the plane
    /// at unit distance).
    #[inline]
    pub fn tan_half_x(&self) -> f32 {
        self.tan_half.x
    }
    /// Unit viewing direction (camera +z in world space).
    #[inline]
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// Primary ray through continuous pixel coordinates `film` ((0, 0) = top-left corner
    /// of the image, (W, H) = bottom-right), from the pinhole, unit direction.
    pub fn generate_ray(&self, film: Vec2) -> Ray {
        let s = film / Vec2::new(self.width as f32, self.height as f32);
        let local = Vec3::new((1.0 - 2.0 * s.x) * self.tan_half.x, (1.0 - 2.0 * s.y) * self.tan_half.y, 1.0);
        let dir = self.to_world.transform_vector3(local).normalize_or(self.forward);
        Ray::new(self.position, dir, f32::INFINITY)
    }

    /// Where a world direction leaving the pinhole lands on the film (pixel coordinates),
    /// or `None` if it misses [0, W) × [0, H). Inverse of [`Self::generate_ray`].
    pub fn film_position(&self, dir: Vec3) -> Option<Vec2> {
        let local = self.to_local * dir;
        if local.z <= 0.0 {
            return None;
        }
        let plane = Vec2::new(local.x, local.y) / (local.z * self.tan_half);
        let film = 0.5 * (Vec2::ONE - plane) * Vec2::new(self.width as f32, self.height as f32);
        let inside = film.x >= 0.0 && film.y >= 0.0 && film.x < self.width as f32 && film.y < self.height as f32;
        inside.then_some(film)
    }

    /// cos θ between a world direction and the viewing axis, if it lands on the film.
    #[inline]
    fn cos_on_film(&self, dir: Vec3) -> Option<f32> {
        self.film_position(dir)?;
        let local = self.to_local * dir;
        let len = local.length();
        if len <= 0.0 {
            return None;
        }
        Some(local.z / len)
    }

    /// Importance per pixel, We(ω) = 1/(A_pixel cos⁴θ) inside the frustum, 0 outside.
    pub fn importance(&self, dir: Vec3) -> f32 {
        match self.cos_on_film(dir) {
            Some(c) => {
                let c2 = c * c;
                let we = 1.0 / (self.pixel_area * c2 * c2);
                if we.is_finite() { we } else { 0.0 }
            }
            None => 0.0,
        }
    }

    /// Density of [`Self::generate_ray`]'s direction for film positions uniform over the
    /// whole film: 1/(A_film cos³θ) inside the frustum, 0 outside.
    pub fn pdf_dir(&self, dir: Vec3) -> SolidAnglePdf {
        match self.cos_on_film(dir) {
            Some(c) => {
                let pdf = 1.0 / (self.film_area * c * c * c);
                SolidAnglePdf(if pdf.is_finite() { pdf } else { 0.0 })
            }
            None => SolidAnglePdf::ZERO,
        }
    }

    /// Connect scene point `p_ref` to the pinhole: `None` if it is at the pinhole or
    /// outside the frustum.
    pub fn sample_wi(&self, p_ref: Vec3) -> Option<CameraSample> {
        let d = self.position - p_ref;
        let dist2 = d.length_squared();
        if dist2 <= 0.0 || !dist2.is_finite() {
            return None;
        }
        let dist = sqrt(dist2);
        let wi = d / dist;
        let film = self.film_position(-wi)?;
        let importance = self.importance(-wi);
        if importance <= 0.0 {
            return None;
        }
        Some(CameraSample { film, wi, dist, importance, pdf: SolidAnglePdf(1.0) })
    }
}
