//! Linear RGB radiometric quantities (the suite's references are RGB renders).

use core::ops::{Add, AddAssign, Div, DivAssign, Index, Mul, MulAssign, Sub};

/// A linear-RGB triple: radiance, throughput, reflectance or importance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct Rgb {
    pub r: f32,
    pub g: f32,
    pub b: f32,
}

impl Rgb {
    pub const ZERO: Self = Self { r: 0.0, g: 0.0, b: 0.0 };
    pub const ONE: Self = Self { r: 1.0, g: 1.0, b: 1.0 };

    #[inline]
    pub const fn new(r: f32, g: f32, b: f32) -> Self {
        Self { r, g, b }
    }
    #[inline]
    pub const fn splat(v: f32) -> Self {
        Self { r: v, g: v, b: v }
    }
    #[inline]
    pub fn is_black(self) -> bool {
        self.r == 0.0 && self.g == 0.0 && self.b == 0.0
    }
    #[inline]
    pub fn is_finite(self) -> bool {
        self.r.is_finite() && self.g.is_finite() && self.b.is_finite()
    }
    /// True when every channel is finite and non-negative.
    #[inline]
    pub fn is_valid_radiance(self) -> bool {
        self.is_finite() && self.r >= 0.0 && self.g >= 0.0 && self.b >= 0.0
    }
    #[inline]
    pub fn max_component(self) -> f32 {
        self.r.max(self.g).max(self.b)
    }
    /// Sum of the channels (SPCBPT's scalar weight).
    #[inline]
    pub fn sum(self) -> f32 {
        self.r + self.g + self.b
    }
    #[inline]
    pub fn average(self) -> f32 {
        self.sum() * (1.0 / 3.0)
    }
    /// Rec. 709 luminance.
    #[inline]
    pub fn luminance(self) -> f32 {
        0.212_671 * self.r + 0.715_160 * self.g + 0.072_169 * self.b
    }
    #[inline]
    pub fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Self::new(f(self.r), f(self.g), f(self.b))
    }
    #[inline]
    pub fn to_array(self) -> [f32; 3] {
        [self.r, self.g, self.b]
    }
    #[inline]
    pub fn to_f64(self) -> [f64; 3] {
        [self.r as f64, self.g as f64, self.b as f64]
    }
}

impl From<[f32; 3]> for Rgb {
    fn from(a: [f32; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }
}

impl Index<usize> for Rgb {
    type Output = f32;
    fn index(&self, i: usize) -> &f32 {
        match i {
            0 => &self.r,
            1 => &self.g,
            _ => &self.b,
        }
    }
}

impl Add for Rgb {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self::new(self.r + o.r, self.g + o.g, self.b + o.b)
    }
}
impl Sub for Rgb {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self::new(self.r - o.r, self.g - o.g, self.b - o.b)
    }
}
impl AddAssign for Rgb {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl Mul for Rgb {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        Self::new(self.r * o.r, self.g * o.g, self.b * o.b)
    }
}
impl MulAssign for Rgb {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}
impl Mul<f32> for Rgb {
    type Output = Self;
    #[inline]
    fn mul(self, s: f32) -> Self {
        Self::new(self.r * s, self.g * s, self.b * s)
    }
}
impl Mul<Rgb> for f32 {
    type Output = Rgb;
    #[inline]
    fn mul(self, c: Rgb) -> Rgb {
        c * self
    }
}
impl MulAssign<f32> for Rgb {
    #[inline]
    fn mul_assign(&mut self, s: f32) {
        *self = *self * s;
    }
}
impl Div<f32> for Rgb {
    type Output = Self;
    #[inline]
    fn div(self, s: f32) -> Self {
        let inv = 1.0 / s;
        Self::new(self.r * inv, self.g * inv, self.b * inv)
    }
}
impl DivAssign<f32> for Rgb {
    #[inline]
    fn div_assign(&mut self, s: f32) {
        *self = *self / s;
    }
}
