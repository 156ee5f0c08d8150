//! Probability densities typed by their measure.
//!
//! Mixing a density per steradian with one per square metre is the classic MIS bug; here
//! it does not compile. The only conversions are [`SolidAnglePdf::to_area`] (and its f64
//! form [`SolidAnglePdf::to_area_f64`]) and [`AreaPdf::to_solid_angle`] (SmallVCM's
//! `PdfWtoA` / `PdfAtoW`). Path vertices carry [`VertexPdf`], whose constructors name the
//! measure of the vertex (area at a point, solid angle at infinity).
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
    /// [`Self::to_area`] computed in f64 from f64 geometry: near-grazing cosines lose most
    /// of their digits in f32, and path-vertex densities feed ratios that must match a
    /// brute-force evaluation to 1e-5.
    #[inline]
    pub fn to_area_f64(self, cos_at_target: f64, dist2: f64) -> AreaPdf {
        AreaPdf((self.0 as f64 * cos_at_target.abs() / dist2) as f32)
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

/// Density of a path vertex with respect to the path-space measure AT THAT VERTEX: per
/// unit area for a point (surfaces, lights, the lens), per unit solid angle for a
/// direction toward the lights at infinity (area on the unit sphere of directions, the
/// measure of a vertex at infinity). A Dirac vertex (a point light's position) carries
/// its discrete probability. It is built only through the named constructors, so a
/// solid-angle density never becomes a vertex density without its conversion; the MIS
/// walk takes ratios of two densities of the SAME vertex, which are measure-free.
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct VertexPdf(f32);

impl VertexPdf {
    pub const ZERO: Self = Self(0.0);
    /// A point's density per unit area.
    #[inline]
    pub fn at_point(pdf: AreaPdf) -> Self {
        Self(pdf.0)
    }
    /// A direction's density per unit solid angle (a vertex at infinity).
    #[inline]
    pub fn of_direction(pdf: SolidAnglePdf) -> Self {
        Self(pdf.0)
    }
    /// The discrete probability of a Dirac vertex (e.g. choosing a point light).
    #[inline]
    pub fn discrete(probability: f32) -> Self {
        Self(probability)
    }
    #[inline]
    pub fn value(self) -> f32 {
        self.0
    }
    #[inline]
    pub fn is_positive(self) -> bool {
        self.0 > 0.0
    }
}

/// Scaling by a probability (light selection) keeps the measure.
impl Mul<f32> for VertexPdf {
    type Output = Self;
    #[inline]
    fn mul(self, s: f32) -> Self {
        Self(self.0 * s)
    }
}
