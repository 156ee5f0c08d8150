//! The image-based environment (Mitsuba 3 `envmap`): radiance at infinity from a
//! latitude–longitude image, importance-sampled by a piecewise-constant distribution
//! over the image.
//!
//! **Mapping** (Mitsuba 3.9's `EnvironmentMapEmitter`, so that its renders are the
//! references). A unit direction d in the map's local frame has
//! u = atan2(d.x, −d.z)/(2π) wrapped to [0, 1) and v = acos(d.y)/π, and back
//! d = (sin φ sin θ, cos θ, −cos φ sin θ) with φ = 2πu, θ = πv (+y is the zenith). The
//! radiance there is the bilinear interpolation of the texels at x = uW − ½ (texel
//! centres, wrapping around in φ) and y = v(H − 1) (rows at the poles' corners, clamped),
//! times `scale`. The local frame is `to_world`'s rotation.
//!
//! **Sampling.** The image is cut into W × H cells in (u, v), cell (i, j) covering
//! [i/W, (i+1)/W) × [j/H, (j+1)/H), weighted by the largest luminance of the texels its
//! bilinear interpolation reads (so every direction with radiance has density: light
//! tracing draws its directions only from here) times sin θ at the cell's centre. Rows
//! are drawn from one alias table and the cell within the row from the row's own; the
//! remapped uniforms place the point inside the cell. The density of (u, v) is
//! p(u, v) = P(j) P(i | j) W H, and per unit solid angle p_ω = p(u, v) / (2π² sin θ)
//! (dω = 2π² sin θ du dv), with sin θ = √(d.x² + d.z²) of the direction itself on both
//! the sampling and the density side (the sampler takes the drawn cell's probabilities,
//! the density finds the cell again from the direction). Mitsuba samples a bilinear (`Hierarchical2D`)
//! distribution instead; any density positive where the radiance is gives the same
//! expectation.
//!
//! Direct lighting and emission then work as for the constant environment
//! ([`super::infinite`]): shadow-ray targets beyond the scene's bounding sphere, emission
//! through the scene disk.

use alloc::sync::Arc;
use alloc::vec::Vec;

use super::infinite::SceneDisk;
use super::{EmissionSample, LightSample};
use crate::alias::AliasTable;
use crate::math::{PI, Vec2, Vec3};
use crate::measure::{AreaPdf, SolidAnglePdf};
use crate::spectrum::Rgb;

/// Why an image cannot be an environment map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvMapError {
    /// Width or height zero, or pixels fewer than width × height.
    Size,
    /// A texel that is negative, NaN or infinite (its index).
    Texel(usize),
    /// `to_world` is not a rotation (its linear part is not orthonormal to 10⁻³).
    NotRotation,
}

impl core::fmt::Display for EnvMapError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Size => write!(f, "the image has no pixels or fewer than its size says"),
            Self::Texel(i) => write!(f, "pixel {i} is negative, NaN or infinite"),
            Self::NotRotation => write!(f, "`to_world` must be a rotation (no scale, shear or mirror)"),
        }
    }
}

/// The image and its sampling tables, shared by every copy of the light.
#[derive(Debug)]
struct Map {
    width: usize,
    height: usize,
    /// Texels times `scale`, row 0 at the zenith.
    texels: Vec<Rgb>,
    /// Local → world rotation (columns) and its inverse.
    to_world: [Vec3; 3],
    to_local: [Vec3; 3],
    /// Rows, then cells within each row; `None` when the map is black.
    rows: Option<AliasTable>,
    cells: Vec<Option<AliasTable>>,
    /// ∫ L̄ dω over the sphere (channel mean), for the light's power.
    integral: f32,
}

/// Mitsuba's `envmap` (see the module notes). Cheap to clone: the image is shared.
#[derive(Clone, Debug)]
pub(super) struct EnvMapLight {
    map: Arc<Map>,
    pub(super) disk: SceneDisk,
}

#[inline]
fn luminance(c: Rgb) -> f32 {
    0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b
}

#[inline]
fn apply(m: &[Vec3; 3], v: Vec3) -> Vec3 {
    m[0] * v.x + m[1] * v.y + m[2] * v.z
}

impl EnvMapLight {
    /// `texels`: `width × height` linear RGB values, row 0 at the zenith (+y of the local
    /// frame); `to_world`: the local frame's axes in world space (a rotation).
    pub(super) fn new(width: u32, height: u32, texels: &[Rgb], scale: f32, to_world: [Vec3; 3]) -> Result<Self, EnvMapError> {
        let (w, h) = (width as usize, height as usize);
        let n = w.checked_mul(h).ok_or(EnvMapError::Size)?;
        if n == 0 || texels.len() < n {
            return Err(EnvMapError::Size);
        }
        if let Some(i) = texels[..n].iter().position(|t| !(t.r >= 0.0 && t.g >= 0.0 && t.b >= 0.0 && t.is_finite())) {
            return Err(EnvMapError::Texel(i));
        }
        let orthonormal = (0..3).all(|a| (0..3).all(|b| (to_world[a].dot(to_world[b]) - f32::from(a == b)).abs() <= 1e-3));
        let right_handed = to_world[0].cross(to_world[1]).dot(to_world[2]) > 0.0;
        if !(orthonormal && right_handed) {
            return Err(EnvMapError::NotRotation);
        }
        let scale = if scale.is_finite() && scale > 0.0 { scale } else { 0.0 };
        let texels: Vec<Rgb> = texels[..n].iter().map(|&t| t * scale).collect();
        let to_world = [to_world[0].normalize(), to_world[1].normalize(), to_world[2].normalize()];
        // The inverse of a rotation is its transpose.
        let to_local = [
            Vec3::new(to_world[0].x, to_world[1].x, to_world[2].x),
            Vec3::new(to_world[0].y, to_world[1].y, to_world[2].y),
            Vec3::new(to_world[0].z, to_world[1].z, to_world[2].z),
        ];
        // Cell weights: the largest luminance among the texels the cell's bilinear
        // lookups read (columns i−1..=i+1, wrapped; the rows its v range touches).
        let lum: Vec<f32> = texels.iter().map(|&t| luminance(t)).collect();
        let mut weights = Vec::with_capacity(n);
        let mut integral = 0.0f64;
        for j in 0..h {
            let y0 = (j * (h - 1)) / h;
            let y1 = (((j + 1) * (h - 1)) / h + 1).min(h - 1);
            let theta = (j as f32 + 0.5) / h as f32 * PI;
            let sin_theta = libm::sinf(theta);
            for i in 0..w {
                let mut m = 0.0f32;
                for y in y0..=y1 {
                    for di in [w - 1, 0, 1] {
                        m = m.max(lum[y * w + (i + di) % w]);
                    }
                }
                weights.push(m * sin_theta);
                integral += f64::from(texels[j * w + i].average()) * f64::from(sin_theta);
            }
        }
        let integral = (integral * 2.0 * f64::from(PI) * f64::from(PI) / n as f64) as f32;
        let row_sums: Vec<f32> = weights.chunks_exact(w).map(|r| r.iter().sum()).collect();
        let rows = AliasTable::new(&row_sums);
        let cells = weights.chunks_exact(w).map(AliasTable::new).collect();
        Ok(Self { map: Arc::new(Map { width: w, height: h, texels, to_world, to_local, rows, cells, integral }), disk: SceneDisk::default() })
    }

    /// (u, v) of a local unit direction.
    #[inline]
    fn uv(d: Vec3) -> Vec2 {
        let u = libm::atan2f(d.x, -d.z) * (0.5 / PI);
        let u = u - libm::floorf(u);
        let v = libm::acosf(d.y.clamp(-1.0, 1.0)) / PI;
        Vec2::new(if u < 1.0 { u } else { 0.0 }, v)
    }

    /// Radiance arriving from world direction `dir` (toward the sky).
    pub(super) fn radiance(&self, dir: Vec3) -> Rgb {
        let m = &*self.map;
        let d = apply(&m.to_local, dir).normalize_or_zero();
        if d == Vec3::ZERO {
            return Rgb::ZERO;
        }
        let uv = Self::uv(d);
        let x = uv.x * m.width as f32 - 0.5;
        let x0 = libm::floorf(x);
        let fx = x - x0;
        let i0 = (x0 as i64).rem_euclid(m.width as i64) as usize;
        let i1 = (i0 + 1) % m.width;
        let y = uv.y * (m.height - 1) as f32;
        let y0 = (libm::floorf(y) as usize).min(m.height - 1);
        let y1 = (y0 + 1).min(m.height - 1);
        let fy = (y - y0 as f32).clamp(0.0, 1.0);
        let t = |x: usize, y: usize| m.texels[y * m.width + x];
        let top = t(i0, y0) * (1.0 - fx) + t(i1, y0) * fx;
        let bottom = t(i0, y1) * (1.0 - fx) + t(i1, y1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// A world direction toward the sky drawn from the image's distribution, with its
    /// density per steradian.
    fn sample_dir(&self, u: Vec2) -> Option<(Vec3, SolidAnglePdf)> {
        let m = &*self.map;
        let row = m.rows.as_ref()?.sample(u.y);
        let cell = m.cells[row.index].as_ref()?.sample(u.x);
        let uu = (cell.index as f32 + cell.u_remapped) / m.width as f32;
        let vv = (row.index as f32 + row.u_remapped) / m.height as f32;
        let (sin_phi, cos_phi) = libm::sincosf(2.0 * PI * uu);
        let (sin_t, cos_t) = libm::sincosf(PI * vv);
        let local = Vec3::new(sin_phi * sin_t, cos_t, -cos_phi * sin_t);
        // The sampled cell's own probabilities (what `pdf_local` finds again from the
        // direction, without its atan2 and acos).
        let pdf = Self::solid_angle(row.pmf * cell.pmf * (m.width * m.height) as f32, local);
        (pdf.value() > 0.0).then(|| (apply(&m.to_world, local).normalize(), pdf))
    }

    /// p_ω = p(u, v) / (2π² sin θ), with sin θ of the local direction `d`.
    #[inline]
    fn solid_angle(p_uv: f32, d: Vec3) -> SolidAnglePdf {
        let sin_theta = libm::sqrtf(d.x * d.x + d.z * d.z);
        if !(sin_theta > 0.0) {
            return SolidAnglePdf::ZERO;
        }
        super::finite_or_zero(SolidAnglePdf(p_uv / (2.0 * PI * PI * sin_theta)))
    }

    /// Density per steradian of a local unit direction.
    fn pdf_local(&self, d: Vec3) -> SolidAnglePdf {
        let m = &*self.map;
        let Some(rows) = &m.rows else { return SolidAnglePdf::ZERO };
        let uv = Self::uv(d);
        let i = ((uv.x * m.width as f32) as usize).min(m.width - 1);
        let j = ((uv.y * m.height as f32) as usize).min(m.height - 1);
        let Some(cells) = &m.cells[j] else { return SolidAnglePdf::ZERO };
        Self::solid_angle(rows.pmf(j) * cells.pmf(i) * (m.width * m.height) as f32, d)
    }

    /// Density per steradian with which [`Self::sample_li`] returns world direction `wi`.
    pub(super) fn pdf_li(&self, wi: Vec3) -> SolidAnglePdf {
        let d = apply(&self.map.to_local, wi).normalize_or_zero();
        self.pdf_local(d)
    }

    pub(super) fn sample_li(&self, p_ref: Vec3, u: Vec2) -> Option<LightSample> {
        let (wi, pdf) = self.sample_dir(u)?;
        Some(self.disk.environment_li(p_ref, wi, self.radiance(wi), pdf))
    }

    /// A direction from the image's distribution, travelling the opposite way, and a
    /// uniform point on the scene disk across it.
    pub(super) fn sample_le(&self, u_pos: Vec2, u_dir: Vec2) -> Option<EmissionSample> {
        let (toward_sky, pdf_dir) = self.sample_dir(u_dir)?;
        self.disk.environment_le(u_pos, -toward_sky, self.radiance(toward_sky), pdf_dir)
    }

    /// (1/(πR²), the density of the direction the path came from).
    pub(super) fn pdf_le(&self, dir: Vec3) -> (AreaPdf, SolidAnglePdf) {
        (self.disk.pdf(), self.pdf_li(-dir))
    }

    /// Φ = πR² ∫ L̄ dω (pbrt-v4 `ImageInfiniteLight::Phi`, with the channel mean).
    pub(super) fn power(&self) -> f32 {
        self.disk.area() * self.map.integral
    }
}
