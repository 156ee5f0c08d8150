//! Probability densities typed by their measure.
//!
//! Mixing a density per steradian with one per square metre is the classic MIS bug; here
//! it does not compile. The only conversions are [`SolidAnglePdf::to_area`] and
//! [`AreaPdf::to_solid_angle`] (SmallVCM's `PdfWtoA` / `PdfAtoW`).
//!
//! Dirac distributions (mirrors, point lights, the pinhole's position) have no density;
//! their samples carry an `is_delta` flag and, in the pdf field, the discrete
//! probability of having chosen that lobe.

use core::ops::{Add, AddAssign, Mul};

/// Density with respect to solid angle (per steradian).
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
pub struct SolidAnglePdf(pub f32);

/// Density with respect to surface area (per square metre).
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
pub struct AreaPdf(pub f32);

impl SolidAnglePdf {
    pub const ZERO: Self = Self(0.0);
    #[inline]
    pub fn value(self) -> f32 {
        self.0
    }
    #[inline]
    pub fn is_positive(self) -> bool {
        self.0 > 0.0
    }
    /// Solid-angle density seen from a point at distance² `dist2`, converted to a density
    /// over the area of the surface it lands on, whose normal makes cosine `cos_at_target`
    /// with the direction: p_A = p_ω |cos| / d².
    #[inline]
    pub fn to_area(self, cos_at_target: f32, dist2: f32) -> AreaPdf {
        AreaPdf(self.0 * cos_at_target.abs() / dist2)
    }
}

impl AreaPdf {
    pub const ZERO: Self = Self(0.0);
    #[inline]
    pub fn value(self) -> f32 {
        self.0
    }
    #[inline]
    pub fn is_positive(self) -> bool {
        self.0 > 0.0
    }
    /// Area density of a point converted to a solid-angle density seen from a point at
    /// distance² `dist2`, where the surface's normal makes cosine `cos_at_surface` with
    /// the direction: p_ω = p_A d² / |cos|. A grazing surface (cos = 0) has no solid-angle
    /// density: returns 0 rather than infinity.
    #[inline]
    pub fn to_solid_angle(self, cos_at_surface: f32, dist2: f32) -> SolidAnglePdf {
        let c = cos_at_surface.abs();
        if c == 0.0 { SolidAnglePdf(0.0) } else { SolidAnglePdf(self.0 * dist2 / c) }
    }
}

macro_rules! density_ops {
    ($t:ty) => {
        impl Add for $t {
            type Output = Self;
            #[inline]
            fn add(self, o: Self) -> Self {
                Self(self.0 + o.0)
            }
        }
        impl AddAssign for $t {
            #[inline]
            fn add_assign(&mut self, o: Self) {
                self.0 += o.0;
            }
        }
        /// Scaling by a probability (lobe or light selection) keeps the measure.
        impl Mul<f32> for $t {
            type Output = Self;
            #[inline]
            fn mul(self, s: f32) -> Self {
                Self(self.0 * s)
            }
        }
    };
}
density_ops!(SolidAnglePdf);
density_ops!(AreaPdf);
