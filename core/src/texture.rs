//! Textures: colours that vary over a surface with its (u, v) coordinates, as Mitsuba 3
//! defines `bitmap` and `checkerboard`.
//!
//! A texture is looked up at a hit's texture coordinates ([`crate::geometry::SurfaceHit`]'s
//! `uv`: a mesh's interpolated per-vertex coordinates, or its barycentrics (b₁, b₂) where it
//! has none; (φ/2π, θ/π) on a sphere; Mitsuba's conventions for `rectangle` and `cube`).
//! `to_uv`, an affine map of the plane, is applied first.
//!
//! - **Bitmap** (Mitsuba `bitmap`): the host decodes the file to linear RGB texels (8-bit
//!   sRGB is decoded per texel, before any interpolation, as Mitsuba's 8-bit storage does
//!   on lookup). Row 0 is the image's top row and sits at v = 0. Bilinear lookup reads the
//!   four texels around x = u·W − ½, y = v·H − ½ (texel centres at half-integers), each
//!   index wrapped by the [`WrapMode`]; nearest lookup reads the texel containing (u·W, v·H).
//! - **Checkerboard** (Mitsuba `checkerboard`): `color0` where the fractional parts of u and
//!   v are on the same side of ½, `color1` elsewhere.
//!
//! Textures are evaluated, never sampled: materials take the value at the hit and stay
//! what they are (see [`crate::scene::Scene::material`]).

use alloc::sync::Arc;
use alloc::vec::Vec;

use crate::math::{Vec2, floor, powf};
use crate::spectrum::Rgb;

/// An affine map of texture coordinates, uv' = M uv + t (Mitsuba's `to_uv`, the upper-left
/// 2 × 3 part of its 3 × 3 or 4 × 4 matrix).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// Columns of the linear part.
    pub x: Vec2,
    pub y: Vec2,
    pub t: Vec2,
}

impl UvTransform {
    pub const IDENTITY: Self = Self { x: Vec2::X, y: Vec2::Y, t: Vec2::ZERO };

    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        self.x * uv.x + self.y * uv.y + self.t
    }
}

/// How a bitmap's texel indices outside the image are brought back (Mitsuba's `wrap_mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WrapMode {
    /// Tile the plane (Mitsuba's default).
    Repeat,
    /// Tile with every other copy mirrored.
    Mirror,
    /// Use the nearest edge texel.
    Clamp,
}

impl WrapMode {
    /// Index `i` wrapped into [0, n).
    #[inline]
    fn wrap(self, i: i64, n: i64) -> usize {
        let w = match self {
            Self::Repeat => i.rem_euclid(n),
            Self::Clamp => i.clamp(0, n - 1),
            Self::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n { m } else { 2 * n - 1 - m }
            }
        };
        w as usize
    }
}

/// Why a bitmap cannot be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureError {
    /// Zero width or height.
    Empty,
    /// The texel count is not width × height.
    Size,
    /// A texel is negative, NaN or infinite.
    BadTexel,
}

impl core::fmt::Display for TextureError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Empty => "the image has no pixels",
            Self::Size => "the texel count is not width x height",
            Self::BadTexel => "a texel is negative, NaN or infinite",
        })
    }
}

/// A linear-RGB image looked up by texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Bitmap {
    texels: Arc<[Rgb]>,
    width: u32,
    height: u32,
    wrap: WrapMode,
    bilinear: bool,
}

/// A colour over the surface.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// Mitsuba `bitmap`.
    Bitmap { bitmap: Bitmap, to_uv: UvTransform },
    /// Mitsuba `checkerboard`.
    Checkerboard { color0: Rgb, color1: Rgb, to_uv: UvTransform },
}

impl Bitmap {
    /// An image of `width × height` linear texels, row 0 at the top (v = 0).
    pub fn new(width: u32, height: u32, texels: Vec<Rgb>, wrap: WrapMode, bilinear: bool) -> Result<Self, TextureError> {
        if width == 0 || height == 0 {
            return Err(TextureError::Empty);
        }
        if texels.len() as u64 != width as u64 * height as u64 {
            return Err(TextureError::Size);
        }
        if !texels.iter().all(|t| t.is_valid_radiance()) {
            return Err(TextureError::BadTexel);
        }
        Ok(Self { texels: texels.into(), width, height, wrap, bilinear })
    }

    #[inline]
    fn texel(&self, x: i64, y: i64) -> Rgb {
        let (w, h) = (self.width as i64, self.height as i64);
        self.texels[self.wrap.wrap(y, h) * self.width as usize + self.wrap.wrap(x, w)]
    }

    /// The value at `uv` (see the module notes).
    pub fn eval(&self, uv: Vec2) -> Rgb {
        if !uv.is_finite() {
            return Rgb::ZERO;
        }
        // Texture coordinates far beyond the image lose all precision in f32; f64 keeps
        // the index exact up to 2⁵³ and the integer conversion saturates.
        let x = uv.x as f64 * self.width as f64;
        let y = uv.y as f64 * self.height as f64;
        if !self.bilinear {
            return self.texel(libm::floor(x) as i64, libm::floor(y) as i64);
        }
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (libm::floor(x), libm::floor(y));
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0) * (1.0 - fx) + self.texel(x0 + 1, y0) * fx;
        let bottom = self.texel(x0, y0 + 1) * (1.0 - fx) + self.texel(x0 + 1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    pub fn width(&self) -> u32 {
        self.width
    }
    pub fn height(&self) -> u32 {
        self.height
    }
    /// The largest channel of any texel (what a material's bound on its albedo needs).
    pub fn max_value(&self) -> f32 {
        self.texels.iter().fold(0.0f32, |m, t| m.max(t.max_component()))
    }
    /// The mean texel (for features that want one representative colour).
    pub fn mean(&self) -> Rgb {
        let n = self.texels.len() as f64;
        let s = self.texels.iter().fold([0.0f64; 3], |a, t| [a[0] + t.r as f64, a[1] + t.g as f64, a[2] + t.b as f64]);
        Rgb::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32)
    }
}

impl Texture {
    /// The colour at texture coordinates `uv` (before `to_uv`).
    pub fn eval(&self, uv: Vec2) -> Rgb {
        match self {
            Self::Bitmap { bitmap, to_uv } => bitmap.eval(to_uv.apply(uv)),
            Self::Checkerboard { color0, color1, to_uv } => {
                let uv = to_uv.apply(uv);
                if !uv.is_finite() {
                    return *color0;
                }
                let fu = uv.x - floor(uv.x) > 0.5;
                let fv = uv.y - floor(uv.y) > 0.5;
                if fu == fv { *color0 } else { *color1 }
            }
        }
    }

    /// The texture's average colour over its unit square (the representative value
    /// features and hints use).
    pub fn mean(&self) -> Rgb {
        match self {
            Self::Bitmap { bitmap, .. } => bitmap.mean(),
            Self::Checkerboard { color0, color1, .. } => (*color0 + *color1) * 0.5,
        }
    }
}

/// Mitsuba's sRGB transfer function, decoded: an 8-bit texel's stored value to linear.
pub fn srgb_to_linear(v: u8) -> f32 {
    srgb_decode(v as f32 / 255.0)
}

/// The sRGB transfer function, decoded, for an encoded value `c` in [0, 1] (16-bit
/// texels, and [`srgb_to_linear`]).
pub fn srgb_decode(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { powf((c + 0.055) / 1.055, 2.4) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    fn grey(v: f32) -> Rgb {
        Rgb::splat(v)
    }

    /// A 2 × 2 image 0, 1 / 2, 3.
    fn four(wrap: WrapMode, bilinear: bool) -> Bitmap {
        Bitmap::new(2, 2, vec![grey(0.0), grey(1.0), grey(2.0), grey(3.0)], wrap, bilinear).unwrap()
    }

    #[test]
    fn texel_centres_read_their_texel_and_row_zero_is_v_zero() {
        let b = four(WrapMode::Clamp, true);
        assert_eq!(b.eval(Vec2::new(0.25, 0.25)), grey(0.0));
        assert_eq!(b.eval(Vec2::new(0.75, 0.25)), grey(1.0));
        assert_eq!(b.eval(Vec2::new(0.25, 0.75)), grey(2.0));
        assert_eq!(b.eval(Vec2::new(0.5, 0.5)), grey(1.5));
    }

    #[test]
    fn wrap_modes_at_the_border() {
        // Halfway between texel 1 and the texel beyond it.
        let at = Vec2::new(1.0, 0.25);
        assert_eq!(four(WrapMode::Repeat, true).eval(at), grey(0.5));
        assert_eq!(four(WrapMode::Clamp, true).eval(at), grey(1.0));
        assert_eq!(four(WrapMode::Mirror, true).eval(at), grey(1.0));
        assert_eq!(four(WrapMode::Repeat, false).eval(Vec2::new(1.25, -0.25)), grey(2.0));
        assert_eq!(four(WrapMode::Mirror, false).eval(Vec2::new(1.25, 0.25)), grey(1.0));
        assert_eq!(four(WrapMode::Clamp, false).eval(Vec2::new(-7.0, 9.0)), grey(2.0));
    }

    #[test]
    fn checkerboard_matches_mitsuba_parity() {
        let t = Texture::Checkerboard {
            color0: grey(1.0),
            color1: grey(0.0),
            to_uv: UvTransform { x: Vec2::new(2.0, 0.0), y: Vec2::new(0.0, 2.0), t: Vec2::ZERO },
        };
        assert_eq!(t.eval(Vec2::new(0.1, 0.1)), grey(1.0));
        assert_eq!(t.eval(Vec2::new(0.3, 0.1)), grey(0.0));
        assert_eq!(t.eval(Vec2::new(0.3, 0.3)), grey(1.0));
        assert_eq!(t.eval(Vec2::new(-0.1, 0.1)), grey(0.0));
    }

    #[test]
    fn srgb_decoding() {
        assert_eq!(srgb_to_linear(0), 0.0);
        assert!((srgb_to_linear(255) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(128) - 0.21586).abs() < 1e-4);
    }

    #[test]
    fn bad_input_is_refused_and_huge_coordinates_do_not_panic() {
        assert_eq!(Bitmap::new(0, 1, vec![], WrapMode::Repeat, true), Err(TextureError::Empty));
        assert_eq!(Bitmap::new(2, 1, vec![grey(1.0)], WrapMode::Repeat, true), Err(TextureError::Size));
        assert_eq!(Bitmap::new(1, 1, vec![grey(f32::NAN)], WrapMode::Repeat, true), Err(TextureError::BadTexel));
        let b = four(WrapMode::Mirror, true);
        for uv in [Vec2::splat(3e38), Vec2::splat(-3e38), Vec2::new(f32::NAN, 0.0)] {
            assert!(b.eval(uv).is_finite());
        }
    }
}
