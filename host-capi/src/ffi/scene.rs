//! The complete scene description: `ember_scene_create2` and the init functions (the
//! types are `ffi::desc`'s).
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

use super::desc::{EmberBsdf, EmberBsdfKind, EmberLight, EmberLightKind, EmberSceneDesc2, EmberTexture, EmberTextureKind, from_raw};

use crate::scene::{MaterialDesc, TextureDesc};

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
        *unsafe { out(texture, "texture") }? = crate::scene::default_texture(k);
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
        *unsafe { out(light, "light") }? = crate::scene::default_light(k);
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
