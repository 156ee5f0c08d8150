//! The image-based environment (Mitsuba 3 `envmap`): radiance at infinity from a
//! latitude–longitude image, importance-sampled by a piecewise-bilinear distribution
//! over the image, the interpolation the radiance itself uses.
//!
//! **Mapping** (Mitsuba 3.9's `EnvironmentMapEmitter`, so that its renders are the
//! references). A unit direction d in the map's local frame has
//! u = atan2(d.x, −d.z)/(2π) wrapped to [0, 1) and v = acos(d.y)/π, and back
//! d = (sin φ sin θ, cos θ, −cos φ sin θ) with φ = 2πu, θ = πv (+y is the zenith). The
//! radiance there is the bilinear interpolation of the texels at x = uW − ½ (texel
//! centres, wrapping around in φ) and y = v(H − 1) (rows at the poles' corners, clamped),
//! times `scale`. The local frame is `to_world`'s rotation.
//!
//! **Sampling.** The density follows the radiance's own interpolation. On the lattice of
//! the lookup, column k at x = k (texel centres, k = 0..W, column W being column 0) and
//! row j at y = j (j = 0..R−1, R = max(H, 2), reading texel row min(j, H − 1)), the
//! lattice value is g_jk = lum(texel) · s_j with s_j = sin θ_j, θ_j = πj/(R − 1), except
//! that the pole rows take the sine a quarter row inside (so that radiance there keeps a
//! density). Between lattice points the density of (x, y) is the bilinear interpolation
//! of g, divided by its integral T = Σ_cells (sum of the cell's corners)/4; it is
//! positive exactly where the radiance is, and L sin θ / p is nearly constant even
//! across a sun a few texels wide, where a piecewise-constant density is not (the
//! density before issue 52: cells weighted by the brightest texel a lookup reads, which
//! spread a 5-texel sun's samples over about 15 cells, most of them dim; ours was 1.6×
//! Mitsuba's relMSE on `scenes-extra/textured`, docs/pixel-filters.md).
//!
//! Drawing (x, y) (Mitsuba's `Hierarchical2D`, drawn as pbrt-v4's bilinear patches are):
//! the row cell j from an alias table of the cells' masses (G_j + G_{j+1})/2, G_j = Σ_k g_jk
//! the lattice row's integral; y − j from the linear density between G_j and G_{j+1}
//! ([`crate::warp::sample_linear`]); the column cell k from the mixture of the two
//! lattice rows' cell tables, row j with weight (1 − f_y) G_j and row j + 1 with f_y
//! G_{j+1} (each cell's mass at height f_y is that mixture); x − k from the linear
//! density between the cell's two edge values at f_y. Then u = (x + ½)/W wrapped to
//! [0, 1), v = y/(R − 1), and p(u, v) = p(x, y) W (R − 1); per unit solid angle
//! p_ω = p(u, v) / (2π² sin θ) (dω = 2π² sin θ du dv), with sin θ = √(d.x² + d.z²) of the
//! direction itself. The sampler evaluates the density at the (x, y) it drew, with the
//! function the density uses for a direction, which finds (x, y) again.

//! Direct lighting and emission then work as for the constant environment
//! ([`super::infinite`]): shadow-ray targets beyond the scene's bounding sphere, emission
//! through the scene disk.

use alloc::sync::Arc;
use alloc::vec::Vec;

use super::infinite::SceneDisk;
use super::{EmissionSample, LightSample};
use crate::alias::AliasTable;
use crate::math::{self, PI, Vec2, Vec3};
use crate::measure::{AreaPdf, SolidAnglePdf};
use crate::spectrum::Rgb;
use crate::warp::sample_linear;

/// The largest f32 below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON * 0.5;

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
    /// Lattice rows R = max(H, 2) (see the module notes).
    lattice_rows: usize,
    /// g_jk, R × W, row-major.
    lattice: Vec<f32>,
    /// G_j = Σ_k g_jk per lattice row.
    row_sums: Vec<f32>,
    /// The R − 1 row cells, weighted (G_j + G_{j+1})/2; `None` when the map is black.
    rows: Option<AliasTable>,
    /// Per lattice row, its W column cells weighted (g_jk + g_j,k+1)/2.
    cells: Vec<Option<AliasTable>>,
    /// W (R − 1) / T: turns a lattice cell's interpolated g into p(u, v).
    density_scale: f32,
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
        // The power: texel means times sin θ at the texel rows' centres.
        let mut integral = 0.0f64;
        for j in 0..h {
            let sin_theta = f64::from(math::sin((j as f32 + 0.5) / h as f32 * PI));
            integral += texels[j * w..(j + 1) * w].iter().map(|t| f64::from(t.average())).sum::<f64>() * sin_theta;
        }
        let integral = (integral * 2.0 * f64::from(PI) * f64::from(PI) / n as f64) as f32;
        // The lattice g_jk = lum · s_j, its rows' integrals and cell tables.
        let r = h.max(2);
        let last = (r - 1) as f32;
        let mut lattice = Vec::with_capacity(r * w);
        for j in 0..r {
            let s = math::sin(PI * (j as f32).clamp(0.25, last - 0.25) / last);
            let texel_row = j.min(h - 1) * w;
            lattice.extend(texels[texel_row..texel_row + w].iter().map(|&t| luminance(t) * s));
        }
        let mut row_sums = Vec::with_capacity(r);
        let mut cells = Vec::with_capacity(r);
        let mut masses = Vec::with_capacity(w);
        for row in lattice.chunks_exact(w) {
            masses.clear();
            masses.extend((0..w).map(|k| 0.5 * (row[k] + row[(k + 1) % w])));
            row_sums.push(row.iter().map(|&g| f64::from(g)).sum::<f64>() as f32);
            cells.push(AliasTable::new(&masses));
        }
        let row_cells: Vec<f32> = row_sums.windows(2).map(|p| 0.5 * (p[0] + p[1])).collect();
        let total: f64 = row_cells.iter().map(|&m| f64::from(m)).sum();
        let rows = AliasTable::new(&row_cells);
        let density_scale = if total > 0.0 { (w as f64 * f64::from(last) / total) as f32 } else { 0.0 };
        let map = Map { width: w, height: h, texels, to_world, to_local, lattice_rows: r, lattice, row_sums, rows, cells, density_scale, integral };
        Ok(Self { map: Arc::new(map), disk: SceneDisk::default() })
    }

    /// p(u, v) in lattice cell (`k`, `j`) at (`fx`, `fy`) ∈ [0, 1]²: the bilinear
    /// interpolation of its corners' g, times W (R − 1) / T.
    #[inline]
    fn density_uv(m: &Map, k: usize, j: usize, fx: f32, fy: f32) -> f32 {
        let w = m.width;
        let g = |j: usize, k: usize| m.lattice[j * w + k % w];
        let top = g(j, k) * (1.0 - fx) + g(j, k + 1) * fx;
        let bottom = g(j + 1, k) * (1.0 - fx) + g(j + 1, k + 1) * fx;
        (top * (1.0 - fy) + bottom * fy) * m.density_scale
    }

    /// (u, v) of a local unit direction.
    #[inline]
    fn uv(d: Vec3) -> Vec2 {
        let u = math::atan2(d.x, -d.z) * (0.5 / PI);
        let u = u - math::floor(u);
        let v = math::safe_acos(d.y) / PI;
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
        let x0 = math::floor(x);
        let fx = x - x0;
        let i0 = (x0 as i64).rem_euclid(m.width as i64) as usize;
        let i1 = (i0 + 1) % m.width;
        let y = uv.y * (m.height - 1) as f32;
        let y0 = (math::floor(y) as usize).min(m.height - 1);
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
        // Draw the row cell, then the height within it.
        let row = m.rows.as_ref()?.sample(u.y);
        let j = row.index;
        let (a, b) = (m.row_sums[j], m.row_sums[j + 1]);
        let fy = sample_linear(row.u_remapped, a, b);
        // Draw the column cell from the two lattice rows' tables, mixed at that height.
        let (wa, wb) = ((1.0 - fy) * a, fy * b);
        let p_top = if wa + wb > 0.0 { wa / (wa + wb) } else { f32::from(u8::from(a > 0.0)) };
        let (table, uc) = if u.x < p_top { (j, u.x / p_top) } else { (j + 1, (u.x - p_top) / (1.0 - p_top)) };
        let cell = m.cells[table].as_ref()?.sample(uc.min(ONE_BELOW));
        let k = cell.index;
        // Draw the position within the cell, between its edges' values at that height.
        let w = m.width;
        let edge = |k: usize| (1.0 - fy) * m.lattice[j * w + k % w] + fy * m.lattice[(j + 1) * w + k % w];
        let fx = sample_linear(cell.u_remapped, edge(k), edge(k + 1));
        let uu = (k as f32 + fx + 0.5) / w as f32;
        let uu = if uu < 1.0 { uu } else { uu - 1.0 };
        let vv = (j as f32 + fy) / (m.lattice_rows - 1) as f32;
        let (sin_phi, cos_phi) = math::sin_cos_turns(uu);
        let (sin_t, cos_t) = math::sin_cos_turns(0.5 * vv);
        let local = Vec3::new(sin_phi * sin_t, cos_t, -cos_phi * sin_t);
        // The density at the drawn lattice point (what `pdf_local` finds again from the
        // direction, without its atan2 and acos).
        let pdf = Self::solid_angle(Self::density_uv(m, k, j, fx, fy), local);
        (pdf.value() > 0.0).then(|| (apply(&m.to_world, local).normalize(), pdf))
    }

    /// p_ω = p(u, v) / (2π² sin θ), with sin θ of the local direction `d`.
    #[inline]
    fn solid_angle(p_uv: f32, d: Vec3) -> SolidAnglePdf {
        let sin_theta = math::sqrt(d.x * d.x + d.z * d.z);
        if !(sin_theta > 0.0) {
            return SolidAnglePdf::ZERO;
        }
        super::finite_or_zero(SolidAnglePdf(p_uv / (2.0 * PI * PI * sin_theta)))
    }

    /// Density per steradian of a local unit direction.
    fn pdf_local(&self, d: Vec3) -> SolidAnglePdf {
        let m = &*self.map;
        if m.rows.is_none() {
            return SolidAnglePdf::ZERO;
        }
        let uv = Self::uv(d);
        // The lattice point of (u, v): x = uW − ½ wrapped to [0, W), y = v (R − 1).
        let w = m.width as f32;
        let x = uv.x * w - 0.5;
        let x = if x < 0.0 { x + w } else { x };
        let k = (math::floor(x) as usize).min(m.width - 1);
        let y = uv.y * (m.lattice_rows - 1) as f32;
        let j = (math::floor(y) as usize).min(m.lattice_rows - 2);
        let (fx, fy) = ((x - k as f32).clamp(0.0, 1.0), (y - j as f32).clamp(0.0, 1.0));
        Self::solid_angle(Self::density_uv(m, k, j, fx, fy), d)
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
