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
//!
//! # Thin lens (Mitsuba 3 `thinlens`)
//! With a lens of radius R focused at distance F, a primary ray starts at the lens point
//! ℓ = R · concentric_disk(u_lens) on the plane z = 0 of camera space and goes through
//! the focus point q = F · (s_x, s_y, 1), where (s_x, s_y, 1) is the pinhole's direction
//! through the film point: every ray through one film point meets at q, so the plane
//! z = F is sharp. No lens draws no lens sample: [`PerspectiveCamera::lens_u`] takes
//! nothing from the stream, and the pinhole's images are unchanged bit for bit.
//!
//! Importance with a lens (pbrt-v4 `PerspectiveCamera::We` / `SampleWi`): the sensor's
//! importance is W_e(ℓ, ω) = W_pixel(ω)/A_lens with A_lens = πR² and W_pixel(ω) =
//! 1/(A_pixel cos⁴θ), θ the angle of the actual ray ω from ℓ. It stays normalised: seen
//! from ℓ, the focus-plane patch over a film patch dA (at z = 1) subtends
//! dω = cos θ F² dA/(F/cos θ)² = cos³θ dA, so ∫_pixel W_pixel cosθ dω = 1 for every ℓ and
//! the mean over the lens is 1. A connection ([`PerspectiveCamera::sample_wi`]) draws ℓ
//! uniformly by area (density 1/A_lens); the estimate
//!   W_e(ℓ, ω) · cos θ/d² / (1/A_lens) = W_pixel(ω) cos θ / d²
//! is the pinhole's [`PerspectiveCamera::arriving_importance`] with ℓ for the pinhole:
//! the 1/A_lens factors cancel. Its film position is where the ray from `p_ref` through
//! ℓ meets the focus plane, mapped like a pinhole direction. The directional density of
//! a ray leaving ℓ when the film point is uniform over the film keeps the pinhole's form:
//! the focus point is uniform over the focus rectangle (area A_film F²), and
//! dω = cos θ dA_q/(F/cos θ)², so p(ω) = 1/(A_film cos³θ) ([`PerspectiveCamera::pdf_dir_from`]).
//! The lens is no scene geometry: no path hits it (no t = 0 strategy), as for the
//! pinhole, and the camera vertex keeps the pinhole's MIS bookkeeping.
//!
//! # Pixel filter
//! Every camera sample's film point is uniform in its pixel, x = pixel corner + u, for
//! every filter, as Mitsuba's `hdrfilm` draws it; the filter enters only where the film
//! spreads the sample over the pixels around x (`crate::render::Film`, `crate::pixel_filter`'s
//! "Camera samples"). The film does not receive x: it draws it again from the pass's
//! [`CameraPass`] ([`camera_film_point`]), the same numbers [`PerspectiveCamera::sample_ray`]
//! drew, so no estimator carries film points in its chunks.

use crate::geometry::Ray;
use crate::math::{Mat3, Mat4, Vec2, Vec3, sqrt, tan};
use crate::measure::SolidAnglePdf;
use crate::pixel_filter::Filter;
use crate::rng::{SampleStream, Stream};
use crate::warp::sample_concentric_disk;

/// Mitsuba `thinlens`'s aperture: radius and focus distance, in scene units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lens {
    /// Radius of the aperture disk (> 0).
    pub radius: f32,
    /// Distance from the lens plane to the plane in focus, along the axis (> 0).
    pub focus_distance: f32,
}

impl Lens {
    /// A lens; `None` unless both values are finite and positive.
    pub fn new(radius: f32, focus_distance: f32) -> Option<Self> {
        let ok = radius.is_finite() && radius > 0.0 && focus_distance.is_finite() && focus_distance > 0.0;
        ok.then_some(Self { radius, focus_distance })
    }
}

/// A pixel's primary ray, drawn by [`PerspectiveCamera::sample_ray`].
#[derive(Clone, Copy, Debug)]
pub struct PrimaryRay {
    /// From the lens point (the pinhole without a lens), unit direction.
    pub ray: Ray,
    /// The film point, continuous pixel coordinates (uniform in the pixel).
    pub film: Vec2,
}

/// Which pass a film's staged camera samples belong to: with it the film draws each
/// sample's film point again ([`camera_film_point`]) to spread it under a wide filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CameraPass {
    /// The render's seed.
    pub seed: u64,
    /// The pass index (the sample index of every pixel's camera stream).
    pub pass: u32,
}

/// The film point of pixel `pixel`'s (y·`width` + x) camera sample in `at`: the first
/// 2-D number of its camera stream, which every estimator's camera sample draws first
/// ([`PerspectiveCamera::sample_ray`]), put in the pixel.
pub fn camera_film_point(at: CameraPass, pixel: u32, width: u32) -> Vec2 {
    let width = width.max(1);
    let mut rng = SampleStream::for_sample(at.seed, Stream::Camera, pixel, at.pass, 0);
    film_point(pixel % width, pixel / width, rng.next_2d())
}

/// The film point of pixel (`x`, `y`) for `u` ∈ [0, 1)²: its corner + u (the box's
/// historical arithmetic, now every filter's).
#[inline]
fn film_point(x: u32, y: u32, u: Vec2) -> Vec2 {
    Vec2::new(x as f32, y as f32) + u
}

/// Last key of the lens streams of splatting estimators ([`lens_stream`]), apart from
/// every other `Stream::Aux` stream.
const LENS_KEY: u32 = 0x1e45;

/// The stream a light path `path` of pass `pass` draws its lens points from when it
/// connects to the camera (t = 1) outside a per-vertex stream. Creating it draws nothing.
pub fn lens_stream(seed: u64, path: u32, pass: u32) -> SampleStream {
    SampleStream::for_sample(seed, Stream::Aux, path, pass, LENS_KEY)
}

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

/// A connection from a scene point to the lens (light tracing, BDPT t = 1).
#[derive(Clone, Copy, Debug)]
pub struct CameraSample {
    /// Continuous pixel coordinates in [0, W) × [0, H).
    pub film: Vec2,
    /// Unit direction from the reference point toward the camera.
    pub wi: Vec3,
    /// Distance from the reference point to `position`.
    pub dist: f32,
    /// The lens point (the pinhole without a lens): the shadow ray's end and the camera
    /// vertex.
    pub position: Vec3,
    /// We(−wi), per pixel (see the module notes); the caller multiplies by cosθ/dist².
    pub importance: f32,
    /// 1: the pinhole is a delta in position (as for delta lights); with a lens, the lens
    /// point's area density 1/A_lens has cancelled against W_e's (module notes).
    pub pdf: SolidAnglePdf,
}

impl PerspectiveCamera {
    /// Importance arriving at the connected point per unit projected area there,
    /// W_e |cos θ_c| / d²: what a light-path vertex multiplies its throughput by when it
    /// connects to the pinhole (the pinhole's counterpart of a delta light's I / d²).
    #[inline(always)]
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
    lens: Option<Lens>,
    filter: Filter,
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
            lens: None,
            filter: Filter::Box,
        }
    }

    /// This camera with a thin lens (`None`: the pinhole).
    pub fn with_lens(mut self, lens: Option<Lens>) -> Self {
        self.lens = lens;
        self
    }

    /// This camera with pixel filter `filter`.
    pub fn with_filter(mut self, filter: Filter) -> Self {
        self.filter = filter;
        self
    }

    /// The thin lens, if any.
    #[inline]
    pub fn lens(&self) -> Option<Lens> {
        self.lens
    }

    /// Whether rays start on a lens (and so need a lens sample).
    #[inline]
    pub fn has_lens(&self) -> bool {
        self.lens.is_some()
    }

    /// The pixel filter.
    #[inline]
    pub fn filter(&self) -> Filter {
        self.filter
    }

    /// The lens sample: two numbers from `rng` with a lens, none (and zero) without.
    #[inline]
    pub fn lens_u(&self, rng: &mut SampleStream) -> Vec2 {
        if self.lens.is_some() { rng.next_2d() } else { Vec2::ZERO }
    }

    /// The lens point of `u_lens` in camera space (z = 0): R · concentric disk; the
    /// origin without a lens.
    #[inline]
    fn lens_point(&self, u_lens: Vec2) -> Vec2 {
        match self.lens {
            Some(l) => l.radius * sample_concentric_disk(u_lens),
            None => Vec2::ZERO,
        }
    }

    /// The primary ray of pixel (`x`, `y`): a film point uniform in the pixel (one 2-D
    /// number; the film applies the filter, module notes) and a lens point (another, only
    /// with a lens). Always `Some` today: the `Option` is kept for callers that trace
    /// nothing for a sample without a ray.
    pub fn sample_ray(&self, x: u32, y: u32, rng: &mut SampleStream) -> Option<PrimaryRay> {
        let film = film_point(x, y, rng.next_2d());
        let u_lens = self.lens_u(rng);
        Some(PrimaryRay { ray: self.generate_ray_lens(film, u_lens), film })
    }

    #[inline]
    pub fn width(&self) -> u32 {
        self.width
    }
    #[inline]
    pub fn height(&self) -> u32 {
        self.height
    }
    /// The pinhole, or the centre of the lens.
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
    /// of the image, (W, H) = bottom-right), from the pinhole or the lens centre, unit
    /// direction.
    #[inline]
    pub fn generate_ray(&self, film: Vec2) -> Ray {
        let dir = self.to_world.transform_vector3(self.film_to_local(film)).normalize_or(self.forward);
        Ray::new(self.position, dir, f32::INFINITY)
    }

    /// Primary ray through `film` from the lens point of `u_lens` toward the film point's
    /// focus point (module notes); [`Self::generate_ray`] without a lens.
    pub fn generate_ray_lens(&self, film: Vec2, u_lens: Vec2) -> Ray {
        let Some(lens) = self.lens else { return self.generate_ray(film) };
        let l = self.lens_point(u_lens);
        let focus = self.film_to_local(film) * lens.focus_distance;
        let local = focus - Vec3::new(l.x, l.y, 0.0);
        let dir = self.to_world.transform_vector3(local).normalize_or(self.forward);
        Ray::new(self.to_world.transform_point3(Vec3::new(l.x, l.y, 0.0)), dir, f32::INFINITY)
    }

    /// The pinhole direction (camera space, z = 1) through film point `film`.
    #[inline]
    fn film_to_local(&self, film: Vec2) -> Vec3 {
        let s = film / Vec2::new(self.width as f32, self.height as f32);
        Vec3::new((1.0 - 2.0 * s.x) * self.tan_half.x, (1.0 - 2.0 * s.y) * self.tan_half.y, 1.0)
    }

    /// Where a world direction leaving the pinhole lands on the film (pixel coordinates),
    /// or `None` if it misses [0, W) × [0, H). Inverse of [`Self::generate_ray`].
    pub fn film_position(&self, dir: Vec3) -> Option<Vec2> {
        self.local_film_position(self.to_local * dir)
    }

    /// [`Self::film_position`] of a camera-space direction from the pinhole.
    fn local_film_position(&self, local: Vec3) -> Option<Vec2> {
        let (film, inside) = self.local_film_position_lane(local);
        inside.then_some(film)
    }

    /// [`Self::local_film_position`] without branches: the point and whether it is on
    /// the film.
    #[inline(always)]
    fn local_film_position_lane(&self, local: Vec3) -> (Vec2, bool) {
        let plane = Vec2::new(local.x, local.y) / (local.z * self.tan_half);
        let film = 0.5 * (Vec2::ONE - plane) * Vec2::new(self.width as f32, self.height as f32);
        let inside = (film.x >= 0.0) & (film.y >= 0.0) & (film.x < self.width as f32) & (film.y < self.height as f32);
        (film, (local.z > 0.0) & inside)
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

    /// Importance per pixel, We(ω) = 1/(A_pixel cos⁴θ) inside the frustum, 0 outside
    /// (a direction from the pinhole or the lens centre).
    pub fn importance(&self, dir: Vec3) -> f32 {
        match self.cos_on_film(dir) {
            Some(c) => self.we_of_cos(c),
            None => 0.0,
        }
    }

    /// 1/(A_pixel cos⁴θ), 0 where not finite.
    #[inline(always)]
    fn we_of_cos(&self, c: f32) -> f32 {
        let c2 = c * c;
        let we = 1.0 / (self.pixel_area * c2 * c2);
        if we.is_finite() { we } else { 0.0 }
    }

    /// 1/(A_film cos³θ), 0 where not finite.
    #[inline]
    fn pdf_of_cos(&self, c: f32) -> SolidAnglePdf {
        let pdf = 1.0 / (self.film_area * c * c * c);
        SolidAnglePdf(if pdf.is_finite() { pdf } else { 0.0 })
    }

    /// Density of [`Self::generate_ray`]'s direction for film positions uniform over the
    /// whole film: 1/(A_film cos³θ) inside the frustum, 0 outside.
    pub fn pdf_dir(&self, dir: Vec3) -> SolidAnglePdf {
        match self.cos_on_film(dir) {
            Some(c) => self.pdf_of_cos(c),
            None => SolidAnglePdf::ZERO,
        }
    }

    /// Density of the direction `dir` of a primary ray leaving `origin` (a lens point),
    /// film positions uniform over the whole film: 1/(A_film cos³θ) where the ray's focus
    /// point lands on the film (module notes); [`Self::pdf_dir`] without a lens.
    pub fn pdf_dir_from(&self, origin: Vec3, dir: Vec3) -> SolidAnglePdf {
        if self.lens.is_none() {
            return self.pdf_dir(dir);
        }
        let l = self.to_local * (origin - self.position);
        let d = self.to_local * dir;
        match self.lens_film_position(Vec2::new(l.x, l.y), d) {
            Some(_) => self.pdf_of_cos(d.z / d.length()),
            None => SolidAnglePdf::ZERO,
        }
    }

    /// Film position of a ray leaving camera-space lens point `l` (z = 0) along
    /// camera-space direction `d`: its focus point's, as a pinhole direction.
    fn lens_film_position(&self, l: Vec2, d: Vec3) -> Option<Vec2> {
        let lens = self.lens?;
        if !(d.z > 0.0) {
            return None;
        }
        let q = Vec3::new(l.x, l.y, 0.0) + d * (lens.focus_distance / d.z);
        self.local_film_position(q)
    }

    /// Connect scene point `p_ref` to the camera: to the pinhole, or to the lens point of
    /// `u_lens` (uniform by area; `u_lens` is ignored without a lens, see
    /// [`Self::lens_u`]). `None` if it is at that point or its ray misses the film.
    pub fn sample_wi(&self, p_ref: Vec3, u_lens: Vec2) -> Option<CameraSample> {
        if self.lens.is_none() {
            return self.connect_pinhole(p_ref);
        }
        let l = self.lens_point(u_lens);
        self.connect_lens(Vec2::new(l.x, l.y), p_ref)
    }

    /// [`Self::sample_wi`] to a given lens point `lens_point` (world space, on the lens:
    /// e.g. a camera path's first vertex); the pinhole without a lens.
    pub fn connect_from(&self, lens_point: Vec3, p_ref: Vec3) -> Option<CameraSample> {
        if self.lens.is_none() {
            return self.connect_pinhole(p_ref);
        }
        let l = self.to_local * (lens_point - self.position);
        self.connect_lens(Vec2::new(l.x, l.y), p_ref)
    }

    fn connect_pinhole(&self, p_ref: Vec3) -> Option<CameraSample> {
        let (sample, exists) = self.connect_pinhole_lane(p_ref);
        exists.then_some(sample)
    }

    /// [`Self::sample_wi`] of a pinhole camera without branches, for lanes of paths: the
    /// sample and whether it exists; where it does, the bits of `sample_wi`'s.
    #[inline(always)]
    pub fn connect_pinhole_lane(&self, p_ref: Vec3) -> (CameraSample, bool) {
        let d = self.position - p_ref;
        let dist2 = d.length_squared();
        let dist = sqrt(dist2);
        let wi = d / dist;
        // `film_position` and `importance` of -wi, with the direction taken to camera
        // space once (they each did it, and `importance` found the film point again).
        let local = self.to_local * -wi;
        let (film, on_film) = self.local_film_position_lane(local);
        // `local.length()` with the core's square root (glam's would be libm's, the same
        // bits, but a call no lane loop vectorises).
        let len = sqrt(local.length_squared());
        let importance = if len > 0.0 { self.we_of_cos(local.z / len) } else { 0.0 };
        let exists = (dist2 > 0.0) & dist2.is_finite() & on_film & (importance > 0.0);
        (CameraSample { film, wi, dist, position: self.position, importance, pdf: SolidAnglePdf(1.0) }, exists)
    }

    /// Connect `p_ref` to camera-space lens point `l`.
    fn connect_lens(&self, l: Vec2, p_ref: Vec3) -> Option<CameraSample> {
        let position = self.to_world.transform_point3(Vec3::new(l.x, l.y, 0.0));
        let d = position - p_ref;
        let dist2 = d.length_squared();
        if dist2 <= 0.0 || !dist2.is_finite() {
            return None;
        }
        let dist = sqrt(dist2);
        let wi = d / dist;
        let local = self.to_local * -wi;
        let film = self.lens_film_position(l, local)?;
        let importance = self.we_of_cos(local.z / local.length());
        if importance <= 0.0 {
            return None;
        }
        Some(CameraSample { film, wi, dist, position, importance, pdf: SolidAnglePdf(1.0) })
    }
}
