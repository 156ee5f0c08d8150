//! The C types of the complete scene description (`EmberSceneDesc2` and what it holds)
//! and the conversion of the integers that cross as enum values and flags: plain values
//! both the safe layer (`crate::scene`, which checks them) and the functions of
//! `ffi::scene` (which read them from C) use; this module uses neither.

use crate::{Error, Result};

use super::EmberCamera;

/// Values of [`EmberBsdf`]'s `kind`: Mitsuba 3's BSDF plugins.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmberBsdfKind {
    /// `diffuse`: `diffuse` is the reflectance.
    Diffuse = 0,
    /// `conductor`: `eta`, `k`, `specular_reflectance` (η = 0, k = 1: a perfect mirror).
    Conductor = 1,
    /// `roughconductor`: as `conductor`, with `distribution` and `alpha`.
    RoughConductor = 2,
    /// `dielectric`: `int_ior`, `ext_ior`, `specular_reflectance`, `specular_transmittance`.
    Dielectric = 3,
    /// `roughdielectric`: as `dielectric`, with `distribution` and `alpha`.
    RoughDielectric = 4,
    /// `plastic`: `int_ior`, `ext_ior`, `diffuse` (its `diffuse_reflectance`),
    /// `specular_reflectance`, `nonlinear`.
    Plastic = 5,
    /// `roughplastic`: as `plastic`, with `distribution` and `alpha`.
    RoughPlastic = 6,
    /// `principled`: `diffuse` is its `base_color`, the rest are in `principled`.
    Principled = 7,
}

/// Values of [`EmberBsdf`]'s `distribution`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmberMicrofacet {
    /// Mitsuba's default.
    Beckmann = 0,
    Ggx = 1,
}

/// The indices of [`EmberBsdf`]'s `textures`: the parameters a texture can drive.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmberTextureSlot {
    /// `diffuse`: the diffuse albedo (`reflectance`, `diffuse_reflectance`, `base_color`).
    Diffuse = 0,
    /// `specular_reflectance` of conductors, dielectrics and plastics.
    SpecularReflectance = 1,
    /// `specular_transmittance` of dielectrics.
    SpecularTransmittance = 2,
    /// `principled.roughness` (the texel's luminance).
    Roughness = 3,
}

/// Values of [`EmberTexture`]'s `kind`: Mitsuba 3's texture plugins.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmberTextureKind {
    /// `bitmap`: `pixels`, `width`, `height`, `channels`, `srgb`, `wrap_mode`, `filter`.
    Bitmap = 0,
    /// `checkerboard`: `color0`, `color1`.
    Checkerboard = 1,
}

/// Values of [`EmberTexture`]'s `wrap_mode` (Mitsuba's).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmberWrapMode {
    Repeat = 0,
    Mirror = 1,
    Clamp = 2,
}

/// Values of [`EmberTexture`]'s `filter` (Mitsuba's `filter_type`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmberTextureFilter {
    Bilinear = 0,
    Nearest = 1,
}

/// Values of [`EmberLight`]'s `kind`: Mitsuba 3's emitters other than `area` (an
/// emitting triangle is `triangle_emission`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmberLightKind {
    /// `position`, `color` (the intensity).
    Point = 0,
    /// `position`, `direction` (the cone's axis), `color` (the intensity),
    /// `cutoff_angle`, `beam_width` (degrees).
    Spot = 1,
    /// `direction` (the light travels along it), `color` (the irradiance).
    Directional = 2,
    /// `color` (the radiance from every direction).
    Constant = 3,
    /// `texture` (a bitmap: a latitude-longitude image, row 0 at the zenith, +y of
    /// `to_world`), `scale`, `to_world` (a rotation).
    Envmap = 4,
}

/// Values of [`EmberPixelFilter`]'s `kind`: Mitsuba 3's `rfilter` plugins.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmberFilterKind {
    /// One pixel (ember's default; Mitsuba's is the gaussian of σ = 0.5).
    Box = 0,
    /// `tent` of half-width `radius` (0: Mitsuba's 1).
    Tent = 1,
    /// `gaussian` of standard deviation `radius` (0: Mitsuba's 0.5).
    Gaussian = 2,
}

/// Values of [`EmberSceneDesc2`]'s `fov_axis` (Mitsuba's): which extent `fov_degrees` spans.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmberFovAxis {
    X = 0,
    Y = 1,
    Smaller = 2,
    Larger = 3,
    Diagonal = 4,
}

/// A C enum crossing as an integer: its values and names, for the conversion and the
/// messages of [`from_raw`].
pub trait CEnum: Copy + 'static {
    const ALL: &'static [Self];
    /// Lower-case names, in value order.
    const NAMES: &'static [&'static str];
    const TYPE: &'static str;
    fn value(self) -> u32;
}

macro_rules! c_enum {
    ($t:ident: $($v:ident => $s:literal),+) => {
        impl CEnum for $t {
            const ALL: &'static [Self] = &[$($t::$v),+];
            const NAMES: &'static [&'static str] = &[$($s),+];
            const TYPE: &'static str = stringify!($t);
            fn value(self) -> u32 {
                self as u32
            }
        }
    };
}

c_enum!(EmberBsdfKind: Diffuse => "diffuse", Conductor => "conductor", RoughConductor => "roughconductor", Dielectric => "dielectric",
    RoughDielectric => "roughdielectric", Plastic => "plastic", RoughPlastic => "roughplastic", Principled => "principled");
c_enum!(EmberMicrofacet: Beckmann => "beckmann", Ggx => "ggx");
c_enum!(EmberTextureKind: Bitmap => "bitmap", Checkerboard => "checkerboard");
c_enum!(EmberWrapMode: Repeat => "repeat", Mirror => "mirror", Clamp => "clamp");
c_enum!(EmberTextureFilter: Bilinear => "bilinear", Nearest => "nearest");
c_enum!(EmberLightKind: Point => "point", Spot => "spot", Directional => "directional", Constant => "constant", Envmap => "envmap");
c_enum!(EmberFilterKind: Box => "box", Tent => "tent", Gaussian => "gaussian");
c_enum!(EmberFovAxis: X => "x", Y => "y", Smaller => "smaller", Larger => "larger", Diagonal => "diagonal");

/// The `T` whose value is `raw`, or an error naming `field`, the type and its values.
pub fn from_raw<T: CEnum>(raw: u32, field: &str) -> Result<T> {
    T::ALL.iter().copied().find(|k| k.value() == raw).ok_or_else(|| {
        let last = T::ALL.len() - 1;
        Error::arg(format!("{field} {raw} is not an {} (0..={last}: {})", T::TYPE, T::NAMES.join(", ")))
    })
}

/// A flag crossing as an integer: 0 or 1, else an error naming `field`.
pub fn flag(raw: u32, field: &str) -> Result<bool> {
    match raw {
        0 => Ok(false),
        1 => Ok(true),
        _ => Err(Error::arg(format!("{field} {raw} is not 0 or 1"))),
    }
}

/// `principled`'s parameters besides `base_color` (Mitsuba's names; `ember_bsdf_init`
/// gives its defaults).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EmberPrincipled {
    /// ≥ 0 (default 0.5); a texture in slot `EMBER_TEXTURE_SLOT_ROUGHNESS` replaces it.
    pub roughness: f32,
    /// The weights below lie in [0, 1] (default 0).
    pub anisotropic: f32,
    pub metallic: f32,
    pub spec_tint: f32,
    /// ≥ 0 (default 0).
    pub sheen: f32,
    pub sheen_tint: f32,
    pub flatness: f32,
    /// ≥ 0 (default 0).
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
    pub spec_trans: f32,
    /// η_int/η_ext, > 0 (default 1.5, Mitsuba's `specular` = 0.5; with `spec_trans` > 0,
    /// η = 1 is read as 1.001, as Mitsuba does).
    pub eta: f32,
    /// ≥ 0 (default 1 each).
    pub diffuse_reflectance_sampling_rate: f32,
    pub main_specular_sampling_rate: f32,
    pub clearcoat_sampling_rate: f32,
}

/// A material: one of Mitsuba 3's BSDFs by `kind`; the fields a kind does not read are
/// ignored (see `EmberBsdfKind`). `ember_bsdf_init` fills Mitsuba's defaults.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmberBsdf {
    /// An `EmberBsdfKind` value; any other is refused.
    pub kind: u32,
    /// The diffuse albedo: `diffuse`'s `reflectance`, the plastics' `diffuse_reflectance`,
    /// `principled`'s `base_color` (≥ 0).
    pub diffuse: [f32; 3],
    /// Conductors, dielectrics and plastics (≥ 0).
    pub specular_reflectance: [f32; 3],
    /// Dielectrics (≥ 0).
    pub specular_transmittance: [f32; 3],
    /// Conductors: the relative complex index of refraction η + ik per channel (≥ 0).
    pub eta: [f32; 3],
    pub k: [f32; 3],
    /// Dielectrics and plastics: the indices inside and outside (> 0; plastics: not equal).
    pub int_ior: f32,
    pub ext_ior: f32,
    /// The rough kinds: an `EmberMicrofacet` value and the roughness α ≥ 0.
    pub distribution: u32,
    pub alpha: f32,
    /// Plastics: Mitsuba's `nonlinear` (0 or 1).
    pub nonlinear: u32,
    /// 1: Mitsuba's `twosided` around this BSDF (not for dielectrics); 0: one-sided.
    pub two_sided: u32,
    pub principled: EmberPrincipled,
    /// Per `EmberTextureSlot`, the index of the texture driving that parameter (its mean
    /// is the parameter's value where a single value is needed, as Mitsuba's), or -1.
    /// A slot the kind has not must be -1.
    pub textures: [i32; 4],
}

/// A texture: a pixel array (`bitmap`) or a checkerboard, by `kind`. Looked up at a
/// hit's texture coordinates (the mesh's `uvs`, else the triangle's barycentrics), after
/// `to_uv`. `ember_texture_init` fills Mitsuba's defaults.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct EmberTexture {
    /// An `EmberTextureKind` value; any other is refused.
    pub kind: u32,
    /// Bitmap: `width` × `height` × `channels` floats, row 0 at the top (v = 0), read
    /// during `ember_scene_create2` only.
    pub pixels: *const f32,
    /// Bitmap: 1..=65536 each.
    pub width: u32,
    pub height: u32,
    /// Bitmap: 1 (grey) or 3 (RGB).
    pub channels: u32,
    /// Bitmap: 1 if the values are sRGB-encoded in [0, 1] (decoded per texel before any
    /// interpolation, as Mitsuba decodes an 8-bit PNG: give byte / 255.0f for its bits),
    /// 0 if linear (≥ 0).
    pub srgb: u32,
    /// Bitmap: an `EmberWrapMode` value and an `EmberTextureFilter` value.
    pub wrap_mode: u32,
    pub filter: u32,
    /// Checkerboard: the colours (≥ 0) where the fractional parts of u and v are on the
    /// same side of ½ (`color0`) and elsewhere (`color1`).
    pub color0: [f32; 3],
    pub color1: [f32; 3],
    /// Mitsuba's `to_uv`, the affine map (u, v) → (m₀u + m₁v + m₂, m₃u + m₄v + m₅), row by
    /// row; all zero: the identity.
    pub to_uv: [f32; 6],
}

/// A light by `kind`; the fields a kind does not read are ignored (see
/// `EmberLightKind`). `ember_light_init` fills Mitsuba's defaults.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EmberLight {
    /// An `EmberLightKind` value; any other is refused.
    pub kind: u32,
    pub position: [f32; 3],
    /// Not zero; normalised.
    pub direction: [f32; 3],
    /// The intensity (point, spot), irradiance (directional) or radiance (constant), ≥ 0.
    pub color: [f32; 3],
    /// Spot: the cone's half-angle in (0, 180] and the half-angle of full intensity in
    /// [0, cutoff_angle], in degrees.
    pub cutoff_angle: f32,
    pub beam_width: f32,
    /// Envmap: the image's factor (≥ 0).
    pub scale: f32,
    /// Envmap: the rotation from the image's frame to the world, row-major (Mitsuba's
    /// `to_world` matrix's upper-left 3 × 3).
    pub to_world: [[f32; 3]; 3],
    /// Envmap: the index of a bitmap texture holding the image (its wrap mode, filter and
    /// `to_uv` are not used).
    pub texture: i32,
}

/// A thin lens (Mitsuba's `thinlens`): `aperture_radius` 0 is the pinhole (Mitsuba's
/// `perspective`), else > 0 with `focus_distance` > 0, the distance to the plane in focus.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EmberLens {
    pub aperture_radius: f32,
    pub focus_distance: f32,
}

/// The film's pixel filter (Mitsuba's `rfilter`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EmberPixelFilter {
    /// An `EmberFilterKind` value; any other is refused.
    pub kind: u32,
    /// The tent's radius or the gaussian's standard deviation, in pixels (> 0; 0:
    /// Mitsuba's default for the kind; not read by the box).
    pub radius: f32,
}

/// A scene as arrays, version 2 (`ember_scene_create2`): version 1's arrays and camera,
/// with per-vertex normals and texture coordinates, `EmberBsdf` materials, textures,
/// lights of every kind, the camera's field-of-view axis, lens and pixel filter. Null
/// with a count of 0 is an empty array; the optional per-vertex arrays are null or hold
/// one entry per vertex. Read during `ember_scene_create2` only.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct EmberSceneDesc2 {
    /// `vertex_count` × 3 floats.
    pub positions: *const f32,
    pub vertex_count: u32,
    /// Null, or `vertex_count` × 3 floats: shading normals (not zero; normalised).
    pub normals: *const f32,
    /// Null, or `vertex_count` × 2 floats: texture coordinates (u, v), v = 0 at an
    /// image's top row (Mitsuba's convention after loading: an OBJ file's v is flipped).
    pub uvs: *const f32,
    /// `triangle_count` × 3 vertex indices; the triangle's front is counter-clockwise.
    pub indices: *const u32,
    pub triangle_count: u32,
    /// `triangle_count` indices into `materials`.
    pub triangle_materials: *const u32,
    /// Null, or `triangle_count` × 3 floats: radiance emitted from each triangle's front.
    pub triangle_emission: *const f32,
    pub materials: *const EmberBsdf,
    pub material_count: u32,
    pub textures: *const EmberTexture,
    pub texture_count: u32,
    pub lights: *const EmberLight,
    pub light_count: u32,
    /// As version 1's: `lookat`, `fov_degrees` along `fov_axis`, the film's size.
    pub camera: EmberCamera,
    /// An `EmberFovAxis` value (0: x, Mitsuba's default).
    pub fov_axis: u32,
    pub lens: EmberLens,
    pub filter: EmberPixelFilter,
}

/// `kind`'s name in messages (Mitsuba's plugin name).
pub fn kind_name(kind: EmberBsdfKind) -> &'static str {
    EmberBsdfKind::NAMES[kind as usize]
}
