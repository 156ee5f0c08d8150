//! What the classifiers look at: the end vertex of a sub-path [SPCBPT eq. 18].
//!
//! The distance of eq. 18 compares the last vertices of two sub-paths by position, surface
//! normal and incident direction, because those are what the connection term `f_yz`
//! depends on. A feature is therefore nine floats; the decision tree splits on them by
//! index (`attribute_axis`), so the layout is fixed here, in one place.

use crate::math::Vec3;

/// The end vertex of a sub-path as the classifiers see it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct SubpathFeature {
    /// World-space position of the end vertex.
    pub position: Vec3,
    /// Unit shading normal at the end vertex.
    pub normal: Vec3,
    /// Unit direction toward the previous vertex of the same sub-path (`Vec3::ZERO` if none).
    pub incident: Vec3,
}

/// The three attributes a tree node may split on (each a 3-vector).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attribute {
    Position = 0,
    Normal = 1,
    Incident = 2,
}

impl Attribute {
    /// All attributes, in axis order.
    pub const ALL: [Attribute; 3] = [Attribute::Position, Attribute::Normal, Attribute::Incident];
}

/// Number of scalar coordinates of a feature (3 attributes × 3 axes).
pub const FEATURE_AXES: usize = 9;

impl SubpathFeature {
    /// A feature from its three attributes.
    pub fn new(position: Vec3, normal: Vec3, incident: Vec3) -> Self {
        Self { position, normal, incident }
    }

    /// The attribute's 3-vector.
    #[inline]
    pub fn attribute(&self, attribute: Attribute) -> Vec3 {
        match attribute {
            Attribute::Position => self.position,
            Attribute::Normal => self.normal,
            Attribute::Incident => self.incident,
        }
    }

    /// The nine coordinates (position xyz, normal xyz, incident xyz), for loops that index
    /// by axis many times (tree traversal).
    #[inline]
    pub fn to_array(&self) -> [f32; FEATURE_AXES] {
        let (p, n, w) = (self.position, self.normal, self.incident);
        [p.x, p.y, p.z, n.x, n.y, n.z, w.x, w.y, w.z]
    }

    /// Scalar coordinate `axis` in 0..9 (position xyz, normal xyz, incident xyz);
    /// out-of-range axes read 0.
    #[inline]
    pub fn attribute_axis(&self, axis: usize) -> f32 {
        let v = match axis / 3 {
            0 => self.position,
            1 => self.normal,
            2 => self.incident,
            _ => return 0.0,
        };
        match axis % 3 {
            0 => v.x,
            1 => v.y,
            _ => v.z,
        }
    }
}
