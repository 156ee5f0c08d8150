//! The complete scene description: `EmberSceneDesc2` and `ember_scene_create2`.
//!
//! Version 2 of the description, beside version 1 (`EmberSceneDesc`, unchanged, so its
//! callers keep working): per-vertex normals and texture coordinates, every material
//! of the core ([`EmberBsdf`], Mitsuba 3's `bsdf` plugins and parameters), textures
//! given as pixel arrays or checkerboards ([`EmberTexture`]), point, spot, directional,
//! constant and environment-map lights ([`EmberLight`]), the thin lens and the pixel
//! filters. The parameters are Mitsuba 3's, named as in its XML, so a scene described
//! here and the same scene written as XML for `ember render` render the same
//! (`tests/scene2.rs` checks the bits).
//!
//! Every struct is plain values (no pointer but a texture's pixels), tagged by a `kind`
//! that crosses as a `uint32_t` and is checked on entry, as are its flags (`0` or `1`),
//! its texture indices (`-1`: none) and its floats. `ember_bsdf_init`, `ember_texture_init`
//! and `ember_light_init` fill a struct with Mitsuba's defaults for its kind; a struct
//! set up field by field starts from zero, and a zero where the kind needs a value is
//! refused with a message naming the field (a zero texture index on a slot the material
//! has not is refused too: set it to -1).
//!
//! The checks themselves are the safe layer's (`crate::scene`), so a description built
//! in Rust goes through them too; this module turns pointers into arrays.

use super::*;

use crate::scene::{MaterialDesc, TextureDesc};

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

/// Fill `*bsdf` with Mitsuba 3's defaults for `kind` (an `EmberBsdfKind` value): every
/// texture -1, one-sided, linear; reflectances 1, diffuse 0.5; η = 0, k = 1 (a mirror);
/// dielectrics in BK7 (1.5046), plastics in polypropylene (1.49), both in air
/// (1.000277); Beckmann, α = 0.1; `principled`'s own defaults.
///
/// # Safety
/// A non-null `bsdf` must point to a writable `EmberBsdf`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_bsdf_init(kind: u32, bsdf: *mut EmberBsdf) -> EmberStatus {
    guard(|| {
        let k: EmberBsdfKind = from_raw(kind, "kind")?;
        *unsafe { out(bsdf, "bsdf") }? = crate::scene::default_bsdf(k);
        Ok(EmberStatus::Ok)
    })
}

/// Fill `*texture` with Mitsuba 3's defaults for `kind` (an `EmberTextureKind` value):
/// no pixels (set `pixels`, `width` and `height`), 3 linear channels, repeat, bilinear;
/// checkerboard colours 0.4 and 0.2; `to_uv` the identity.
///
/// # Safety
/// A non-null `texture` must point to a writable `EmberTexture`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_texture_init(kind: u32, texture: *mut EmberTexture) -> EmberStatus {
    guard(|| {
        let k: EmberTextureKind = from_raw(kind, "kind")?;
        *unsafe { out(texture, "texture") }? = EmberTexture {
            kind: k as u32,
            pixels: std::ptr::null(),
            width: 0,
            height: 0,
            channels: 3,
            srgb: 0,
            wrap_mode: EmberWrapMode::Repeat as u32,
            filter: EmberTextureFilter::Bilinear as u32,
            color0: [0.4; 3],
            color1: [0.2; 3],
            to_uv: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        };
        Ok(EmberStatus::Ok)
    })
}

/// Fill `*light` with Mitsuba 3's defaults for `kind` (an `EmberLightKind` value): at
/// the origin, along +z, colour 1, cutoff 20° and beam 15°, scale 1, `to_world` the
/// identity, no texture (an envmap needs one).
///
/// # Safety
/// A non-null `light` must point to a writable `EmberLight`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_light_init(kind: u32, light: *mut EmberLight) -> EmberStatus {
    guard(|| {
        let k: EmberLightKind = from_raw(kind, "kind")?;
        *unsafe { out(light, "light") }? = EmberLight {
            kind: k as u32,
            position: [0.0; 3],
            direction: [0.0, 0.0, 1.0],
            color: [1.0; 3],
            cutoff_angle: 20.0,
            beam_width: 15.0,
            scale: 1.0,
            to_world: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            texture: -1,
        };
        Ok(EmberStatus::Ok)
    })
}

/// Build a scene from a version-2 description; `*scene` receives its handle. Every
/// value is checked (`EMBER_STATUS_INVALID_ARGUMENT`, the message naming the field, e.g.
/// `materials[2].alpha`, and its range; `EMBER_STATUS_NULL_POINTER` for a null array with
/// a count above 0).
///
/// # Safety
/// `desc` must be null or point to a valid description whose non-null pointers (the
/// textures' `pixels` included) hold as many elements as its counts say.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_scene_create2(desc: *const EmberSceneDesc2, scene: *mut EmberScene) -> EmberStatus {
    guard(|| {
        // SAFETY: null or valid, by the caller's contract.
        let d = unsafe { desc.as_ref() }.ok_or_else(|| null("desc"))?;
        let out = unsafe { out(scene, "scene") }?;
        let (n, v) = (d.triangle_count, d.vertex_count);
        for (count, what) in [(n, "triangle_count"), (v, "vertex_count")] {
            if count > u32::MAX / 3 {
                return Err(Error::arg(format!("{what} {count} is too large")));
            }
        }
        // SAFETY (each `slice`): the caller's contract on the description's pointers.
        let positions = unsafe { slice(d.positions, v * 3, "positions") }?;
        let normals = if d.normals.is_null() { &[][..] } else { unsafe { slice(d.normals, v * 3, "normals") }? };
        let uvs = if d.uvs.is_null() { &[][..] } else { unsafe { slice(d.uvs, v * 2, "uvs") }? };
        let indices = unsafe { slice(d.indices, n * 3, "indices") }?;
        let materials = unsafe { slice(d.triangle_materials, n, "triangle_materials") }?;
        let emission = if d.triangle_emission.is_null() { &[][..] } else { unsafe { slice(d.triangle_emission, n * 3, "triangle_emission") }? };
        let bsdfs = unsafe { slice(d.materials, d.material_count, "materials") }?;
        let textures = unsafe { slice(d.textures, d.texture_count, "textures") }?;
        let lights = unsafe { slice(d.lights, d.light_count, "lights") }?;
        let desc = SceneDesc {
            positions: positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
            normals: normals.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
            uvs: uvs.chunks_exact(2).map(|p| [p[0], p[1]]).collect(),
            triangles: indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
            triangle_materials: materials.to_vec(),
            triangle_emission: emission.chunks_exact(3).map(|e| [e[0], e[1], e[2]]).collect(),
            materials: bsdfs.iter().copied().map(MaterialDesc::Bsdf).collect(),
            // SAFETY: each texture's pixels as the caller's contract says.
            textures: textures.iter().enumerate().map(|(i, t)| unsafe { texture(i, t) }).collect::<Result<_>>()?,
            lights: lights.to_vec(),
            point_lights: Vec::new(),
            camera: d.camera,
            fov_axis: d.fov_axis,
            lens: d.lens,
            filter: d.filter,
        };
        let data = SceneData::from_desc(&desc)?;
        *out = scenes()?.insert(Arc::new(data));
        Ok(EmberStatus::Ok)
    })
}

/// Texture `i` with its pixels copied (a checkerboard's pointer is not read). The size is
/// checked here, before the pixels are read; the values in `crate::scene`.
///
/// # Safety
/// A bitmap's non-null `pixels` must hold `width × height × channels` floats.
unsafe fn texture(i: usize, t: &EmberTexture) -> Result<TextureDesc> {
    let kind: EmberTextureKind = from_raw(t.kind, &format!("textures[{i}].kind"))?;
    let pixels = match kind {
        EmberTextureKind::Checkerboard => Vec::new(),
        EmberTextureKind::Bitmap => {
            for (side, what) in [(t.width, "width"), (t.height, "height")] {
                if !(1..=crate::scene::MAX_TEXTURE_SIDE).contains(&side) {
                    return Err(Error::arg(format!("textures[{i}].{what} {side} is outside 1..={}", crate::scene::MAX_TEXTURE_SIDE)));
                }
            }
            if t.channels != 1 && t.channels != 3 {
                return Err(Error::arg(format!("textures[{i}].channels {} is not 1 or 3", t.channels)));
            }
            let count = t.width as usize * t.height as usize * t.channels as usize;
            if t.pixels.is_null() {
                return Err(null(&format!("textures[{i}].pixels (for {count} floats)")));
            }
            // SAFETY: `count` floats at a non-null `pixels`, by the caller's contract.
            unsafe { std::slice::from_raw_parts(t.pixels, count) }.to_vec()
        }
    };
    Ok(TextureDesc {
        kind: t.kind,
        pixels,
        width: t.width,
        height: t.height,
        channels: t.channels,
        srgb: t.srgb,
        wrap_mode: t.wrap_mode,
        filter: t.filter,
        color0: t.color0,
        color1: t.color1,
        to_uv: t.to_uv,
    })
}

/// `kind`'s name in messages (Mitsuba's plugin name).
pub fn kind_name(kind: EmberBsdfKind) -> &'static str {
    EmberBsdfKind::NAMES[kind as usize]
}
