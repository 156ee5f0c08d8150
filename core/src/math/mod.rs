//! The one place where float intrinsics are chosen.
//!
//! `core` is `no_std`, so `f32::sqrt` and friends do not exist here. The shading code's
//! elementary functions (sin, cos, tan, exp, ln, pow, atan2, acos, asin) are our own
//! ([`elementary`]): straight-line f64 arithmetic that every SIMD width evaluates to the
//! same bits, nearly always the correctly rounded f32. The rest (square roots, which are
//! correctly rounded everywhere; rounding; erf; the f64 functions of statistics) go
//! through `libm`. Either way CLI and browser images are bit-identical (a host that
//! pulls glam with `std` would otherwise switch glam's transcendental functions to the
//! platform's, which differ in the last bits). Nothing else in the crate calls `libm`
//! directly, and nothing calls glam methods that hide a transcendental function
//! (`Vec3::length` is fine).

pub use glam::{DVec3, Mat3, Mat4, Vec2, Vec3, Vec4};

pub mod elementary;
pub mod simd;
pub mod soa;
pub use elementary::{atan2, cos, exp, ln, powf, safe_acos, safe_asin, sin, sin_cos, sin_cos_quarter, sin_cos_small, sin_cos_turns, tan};

/// π as f32.
pub const PI: f32 = core::f32::consts::PI;
/// 1/π.
pub const INV_PI: f32 = core::f32::consts::FRAC_1_PI;
/// 1/(2π).
pub const INV_2PI: f32 = 0.5 * core::f32::consts::FRAC_1_PI;
/// 1/(4π).
pub const INV_4PI: f32 = 0.25 * core::f32::consts::FRAC_1_PI;
/// 2π.
pub const TWO_PI: f32 = 2.0 * core::f32::consts::PI;

/// Round half away from zero (as `f32::round`).
#[inline]
pub fn round(x: f32) -> f32 {
    libm::roundf(x)
}

/// The square root, correctly rounded (IEEE 754), so the same bits on every target,
/// instruction set and lane width. On x86-64 it is the `sqrtss` intrinsic, which LLVM
/// knows as a square root and so vectorises in a loop over lanes; `libm`'s is the same
/// instruction behind inline assembly, which no loop around it can vectorise
/// (scripts/lane-probe: a cosine-weighted bounce over 16 lanes ran 0.9× the scalar
/// speed through `libm::sqrtf` and 1.5× / 2.8× / 6.5× with SSE2 / AVX2 / AVX-512
/// through the intrinsic). Elsewhere (x86-64 without SSE, as `x86_64-unknown-none`;
/// other architectures) `libm`'s, which is correctly rounded too.
#[inline]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    return simd::sqrt(x);
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
    libm::sqrtf(x)
}
/// `sqrt(max(x, 0))`: for quantities that are non-negative in exact arithmetic.
#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    sqrt(x.max(0.0))
}
/// [`sqrt`] in f64.
#[inline]
pub fn sqrt_f64(x: f64) -> f64 {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    return simd::sqrt_f64(x);
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
    libm::sqrt(x)
}

#[inline]
pub fn exp_f64(x: f64) -> f64 {
    libm::exp(x)
}
#[inline]
pub fn ln_f64(x: f64) -> f64 {
    libm::log(x)
}
#[inline]
pub fn pow_f64(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}
/// Round toward −∞: the bits of `libm::floorf` without its call (`perf` put 1.4 % of
/// light tracing's time in that call, from the film's and the hash grid's pixel and cell
/// indices; callgrind counts 0.4 % fewer instructions for LT and PPM without it). An f32
/// of magnitude 2²³ or more is an integer already (infinities and NaN pass through), and
/// below that truncation through i32 is exact; the sign bit keeps −0 as −0.
#[inline]
pub fn floor(x: f32) -> f32 {
    if !(x.abs() < 8_388_608.0) {
        return x;
    }
    let t = x as i32 as f32;
    if t > x { t - 1.0 } else { f32::from_bits(t.to_bits() | (x.to_bits() & 0x8000_0000)) }
}
#[inline]
pub fn ceil(x: f32) -> f32 {
    libm::ceilf(x)
}
#[inline]
pub fn erf(x: f32) -> f32 {
    libm::erff(x)
}
#[inline]
pub fn erfinv(x: f32) -> f32 {
    // Giles' single-precision approximation ("Approximating the erfinv function", 2010),
    // refined by two Newton steps on erf so it is accurate to a few ulps on (-1, 1).
    let x = x.clamp(-1.0 + f32::EPSILON, 1.0 - f32::EPSILON);
    let w = -ln((1.0 - x) * (1.0 + x));
    let mut p;
    if w < 5.0 {
        let w = w - 2.5;
        p = 2.810_226_4e-8;
        p = 3.432_739_4e-7 + p * w;
        p = -3.523_387_7e-6 + p * w;
        p = -4.391_506_5e-6 + p * w;
        p = 0.000_218_580_87 + p * w;
        p = -0.001_253_725 + p * w;
        p = -0.004_177_681_6 + p * w;
        p = 0.246_640_73 + p * w;
        p = 1.501_409_4 + p * w;
    } else {
        let w = sqrt(w) - 3.0;
        p = -0.000_200_214_26;
        p = 0.000_100_950_56 + p * w;
        p = 0.001_349_343_2 + p * w;
        p = -0.003_673_428_4 + p * w;
        p = 0.005_739_507_7 + p * w;
        p = -0.007_622_461 + p * w;
        p = 0.009_438_870_5 + p * w;
        p = 1.001_674_1 + p * w;
        p = 2.832_976_8 + p * w;
    }
    let mut y = p * x;
    // Newton on erf(y) - x; derivative 2/sqrt(pi) exp(-y^2).
    for _ in 0..2 {
        let err = erf(y) - x;
        y -= err / (core::f32::consts::FRAC_2_SQRT_PI * exp(-y * y));
    }
    y
}

/// Square.
#[inline]
pub fn sqr(x: f32) -> f32 {
    x * x
}

/// Linear interpolation `a + t (b - a)`.
#[inline]
pub fn lerp(t: f32, a: f32, b: f32) -> f32 {
    a + t * (b - a)
}

/// Orthonormal frame (tangent `s`, bitangent `t`, normal `n`), right-handed.
///
/// Local coordinates put the normal on +z, so `cos_theta(w) = w.z`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// Frame around a unit normal, branchless (Duff et al., "Building an orthonormal
    /// basis, revisited", JCGT 2017). Continuous except across n.z = 0 for n.x = 0.
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }
    #[inline]
    pub fn to_local(&self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.s), w.dot(self.t), w.dot(self.n))
    }
    #[inline]
    pub fn to_world(&self, w: Vec3) -> Vec3 {
        self.s * w.x + self.t * w.y + self.n * w.z
    }
}

/// Helpers on directions expressed in a local [`Frame`] (normal = +z).
pub mod local {
    use super::{Vec3, safe_sqrt};
    #[inline]
    pub fn cos_theta(w: Vec3) -> f32 {
        w.z
    }
    #[inline]
    pub fn abs_cos_theta(w: Vec3) -> f32 {
        w.z.abs()
    }
    #[inline]
    pub fn cos2_theta(w: Vec3) -> f32 {
        w.z * w.z
    }
    #[inline]
    pub fn sin2_theta(w: Vec3) -> f32 {
        (1.0 - w.z * w.z).max(0.0)
    }
    #[inline]
    pub fn sin_theta(w: Vec3) -> f32 {
        safe_sqrt(1.0 - w.z * w.z)
    }
    #[inline]
    pub fn tan2_theta(w: Vec3) -> f32 {
        sin2_theta(w) / cos2_theta(w)
    }
    #[inline]
    pub fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
        a.z * b.z > 0.0
    }
    /// Mirror reflection about the +z normal.
    #[inline]
    pub fn reflect(w: Vec3) -> Vec3 {
        Vec3::new(-w.x, -w.y, w.z)
    }
}

/// Reflect `w` about the unit vector `n` (both pointing away from the surface).
#[inline]
pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    2.0 * w.dot(n) * n - w
}

/// Refract `wi` (pointing away from the surface) through the interface with normal `n`
/// (on the same side as `wi`) and relative index `eta` = η_transmitted / η_incident.
/// Returns `None` on total internal reflection.
#[inline]
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wi.dot(n);
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    Some(-wi / eta + (cos_i / eta - cos_t) * n)
}

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds3 {
    pub min: Vec3,
    pub max: Vec3,
}

impl Bounds3 {
    pub const EMPTY: Self = Self { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };
    #[inline]
    pub fn union_point(self, p: Vec3) -> Self {
        Self { min: self.min.min(p), max: self.max.max(p) }
    }
    #[inline]
    pub fn union(self, o: Self) -> Self {
        Self { min: self.min.min(o.min), max: self.max.max(o.max) }
    }
    #[inline]
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }
    /// Centre and radius of the bounding sphere of the box.
    #[inline]
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        if self.is_empty() {
            return (Vec3::ZERO, 0.0);
        }
        let c = 0.5 * (self.min + self.max);
        (c, (self.max - c).length())
    }
}

#[cfg(test)]
mod floor_tests {
    /// `floor` is `libm::floorf` bit for bit: every 257th f32 bit pattern (both signs,
    /// subnormals, NaNs and infinities among them) and the edges of the fast path. Seen
    /// to fail with the sign bit left off (−0 → +0) and with `t >= x` in place of `t > x`.
    #[test]
    fn floor_is_libm_floorf_bit_for_bit() {
        let check = |x: f32| {
            let (a, b) = (super::floor(x), libm::floorf(x));
            assert!(a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()), "floor({x:e}) = {a:e}, libm {b:e}");
        };
        for bits in (0..=u32::MAX).step_by(257) {
            check(f32::from_bits(bits));
        }
        for x in [0.0f32, -0.0, 0.5, -0.5, 1.0, -1.0, 1.5, -1.5, 8_388_607.5, -8_388_607.5, 8_388_608.0, -8_388_608.0, 8_388_609.0, 16_777_217.0] {
            for d in [x, f32::from_bits(x.to_bits().wrapping_add(1)), f32::from_bits(x.to_bits().wrapping_sub(1))] {
                check(d);
            }
        }
        for x in [
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            2_147_483_520.0,
            -2_147_483_648.0,
        ] {
            check(x);
        }
    }
}
