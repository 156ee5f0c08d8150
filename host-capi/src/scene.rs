//! Scenes from plain descriptions ([`SceneDesc`]): every index and value checked, then
//! built with the core's `SceneBuilder` as the Mitsuba reader builds the same scene from
//! XML (`ember-formats`, `mitsuba/materials.rs`, `textures.rs`, `build.rs`): the same
//! constructors with the same parameters and defaults, a textured parameter's value
//! where one value is needed being the texture's mean (its luminance for `roughness`),
//! normals and light directions normalised in double precision.
//!
//! Two things differ, both on purpose. Values the reader accepts with a warning (a
//! spot's beam wider than its cutoff, a zero normal) are refused here: a library has
//! no one to warn. And the reader moves the scene into a frame centred on the camera
//! (for precision far from the origin); here the scene stays where the caller put it,
//! since the engine's own ray tracer answers in its world frame. A description whose
//! camera sits at the origin is the same scene in both, bit for bit (`tests/scene2.rs`).
//!
//! Lights are added in this order: the emitting triangles', then `point_lights`, then
//! `lights` (the order the light-selection table, and so the random streams, follow).

use std::collections::HashMap;
use std::sync::OnceLock;

use ember_core::bsdf::{Material, MicrofacetKind, PlasticCoating, PrincipledParams, TextureSlot};
use ember_core::camera::{FovAxis, Lens, PerspectiveCamera};
use ember_core::light::{EnvMapError, Light};
use ember_core::math::{Vec2, Vec3};
use ember_core::pixel_filter::Filter;
use ember_core::scene::{AreaEmission, Scene, SceneBuilder, SceneGeometry};
use ember_core::spectrum::Rgb;
use ember_core::texture::{Bitmap, Texture, UvTransform, WrapMode, srgb_decode};
use ember_host::accel::Accel;

use crate::ffi::EmberCamera;
use crate::ffi::desc::{
    self, EmberBsdf, EmberBsdfKind as Kind, EmberFilterKind, EmberFovAxis, EmberLens, EmberLight, EmberLightKind, EmberMicrofacet, EmberPixelFilter,
    EmberPrincipled, EmberTextureFilter, EmberTextureKind, EmberWrapMode, flag, from_raw,
};
use crate::{Error, Result};

/// The largest bitmap side (and camera side) accepted.
pub const MAX_TEXTURE_SIDE: u32 = 65536;

/// A material of a scene description.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaterialDesc {
    /// Lambertian with this albedo.
    Diffuse([f32; 3]),
    /// A perfect mirror with this reflectance.
    Mirror([f32; 3]),
    /// Smooth glass with this interior index of refraction (outside: 1).
    Glass(f32),
    /// Any of the core's materials, as the C API's `EmberBsdf` (checked when built).
    Bsdf(EmberBsdf),
}

/// A texture of a scene description: `EmberTexture`'s values with its pixels copied
/// (empty for a checkerboard). Checked when the scene is built.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TextureDesc {
    pub kind: u32,
    pub pixels: Vec<f32>,
    pub width: u32,
    pub height: u32,
    pub channels: u32,
    pub srgb: u32,
    pub wrap_mode: u32,
    pub filter: u32,
    pub color0: [f32; 3],
    pub color1: [f32; 3],
    pub to_uv: [f32; 6],
}

/// A scene as plain data: triangles indexing positions (with optional per-vertex normals
/// and texture coordinates), a material and optional emitted radiance per triangle,
/// textures, lights and a camera: the C API's `EmberSceneDesc2` (and `EmberSceneDesc`,
/// whose fields are a subset) as owned arrays.
#[derive(Clone, Debug, Default)]
pub struct SceneDesc {
    pub positions: Vec<[f32; 3]>,
    /// Empty, or one per position.
    pub normals: Vec<[f32; 3]>,
    /// Empty, or one per position.
    pub uvs: Vec<[f32; 2]>,
    pub triangles: Vec<[u32; 3]>,
    pub triangle_materials: Vec<u32>,
    /// Per triangle, or empty: radiance emitted from the triangle's front.
    pub triangle_emission: Vec<[f32; 3]>,
    pub materials: Vec<MaterialDesc>,
    pub textures: Vec<TextureDesc>,
    /// (position, intensity): version 1's point lights.
    pub point_lights: Vec<([f32; 3], [f32; 3])>,
    pub lights: Vec<EmberLight>,
    /// The camera: the C struct itself (plain values, no pointers).
    pub camera: EmberCamera,
    /// An `EmberFovAxis` value.
    pub fov_axis: u32,
    pub lens: EmberLens,
    pub filter: EmberPixelFilter,
}

/// A built scene: what the estimators read, the tracer's geometry, the built-in BVH and,
/// per triangle of the description, its index in the geometry (`None`: dropped as
/// degenerate).
#[derive(Debug)]
pub struct SceneData {
    pub scene: Scene,
    pub geometry: SceneGeometry,
    pub accel: Accel,
    pub triangle_index: Vec<Option<u32>>,
    /// [`SceneData::hash`], computed the first time it is asked for.
    hash: OnceLock<u64>,
}

fn finite3(v: [f32; 3], what: &str) -> Result<Vec3> {
    if v.iter().all(|x| x.is_finite()) { Ok(Vec3::from(v)) } else { Err(Error::arg(format!("{what} is not finite"))) }
}

fn colour(v: [f32; 3], what: &str) -> Result<Rgb> {
    if v.iter().all(|x| x.is_finite() && *x >= 0.0) { Ok(Rgb::new(v[0], v[1], v[2])) } else { Err(Error::arg(format!("{what} is negative or not finite"))) }
}

/// A non-zero finite direction, normalised in double precision (as the reader does).
fn direction(v: [f32; 3], what: &str) -> Result<Vec3> {
    let d = finite3(v, what)?.as_dvec3();
    if !(d.length() > 0.0) {
        return Err(Error::arg(format!("{what} is zero")));
    }
    Ok(d.normalize().as_vec3())
}

fn in_range(v: f32, lo: f32, hi: f32, what: &str) -> Result<f32> {
    if v >= lo && v <= hi { Ok(v) } else { Err(Error::arg(format!("{what} {v} is outside [{lo}, {hi}]"))) }
}

fn non_negative(v: f32, what: &str) -> Result<f32> {
    if v.is_finite() && v >= 0.0 { Ok(v) } else { Err(Error::arg(format!("{what} {v} is negative or not finite"))) }
}

fn positive(v: f32, what: &str) -> Result<f32> {
    if v.is_finite() && v > 0.0 { Ok(v) } else { Err(Error::arg(format!("{what} {v} is not positive and finite"))) }
}

/// The per-vertex values of a triangle's corners, if the mesh has them (indices checked).
fn per_corner<T: Copy>(values: &[T], tri: &[u32; 3]) -> Option<[T; 3]> {
    (!values.is_empty()).then(|| tri.map(|i| values[i as usize]))
}

/// A texture checked and built, with its mean (a textured parameter's single value) and,
/// for a bitmap, its linear texels (an environment map's image).
#[derive(Debug)]
struct BuiltTexture {
    texture: Texture,
    mean: Rgb,
    image: Option<(u32, u32, Vec<Rgb>)>,
}

impl BuiltTexture {
    fn new(i: usize, t: &TextureDesc) -> Result<Self> {
        let field = |name: &str| format!("textures[{i}].{name}");
        let kind: EmberTextureKind = from_raw(t.kind, &field("kind"))?;
        let to_uv = if t.to_uv.iter().all(|&x| x == 0.0) {
            UvTransform::IDENTITY
        } else if t.to_uv.iter().all(|x| x.is_finite()) {
            let m = t.to_uv;
            UvTransform { x: Vec2::new(m[0], m[3]), y: Vec2::new(m[1], m[4]), t: Vec2::new(m[2], m[5]) }
        } else {
            return Err(Error::arg(format!("{} is not finite", field("to_uv"))));
        };
        let (texture, image) = match kind {
            EmberTextureKind::Checkerboard => {
                let (color0, color1) = (colour(t.color0, &field("color0"))?, colour(t.color1, &field("color1"))?);
                (Texture::Checkerboard { color0, color1, to_uv }, None)
            }
            EmberTextureKind::Bitmap => {
                for (side, name) in [(t.width, "width"), (t.height, "height")] {
                    if !(1..=MAX_TEXTURE_SIDE).contains(&side) {
                        return Err(Error::arg(format!("{} {side} is outside 1..={MAX_TEXTURE_SIDE}", field(name))));
                    }
                }
                if t.channels != 1 && t.channels != 3 {
                    return Err(Error::arg(format!("{} {} is not 1 or 3", field("channels"), t.channels)));
                }
                let need = t.width as usize * t.height as usize * t.channels as usize;
                if t.pixels.len() != need {
                    return Err(Error::arg(format!(
                        "{} holds {} floats, not {need} ({} x {} x {})",
                        field("pixels"),
                        t.pixels.len(),
                        t.width,
                        t.height,
                        t.channels
                    )));
                }
                let srgb = flag(t.srgb, &field("srgb"))?;
                let wrap = match from_raw::<EmberWrapMode>(t.wrap_mode, &field("wrap_mode"))? {
                    EmberWrapMode::Repeat => WrapMode::Repeat,
                    EmberWrapMode::Mirror => WrapMode::Mirror,
                    EmberWrapMode::Clamp => WrapMode::Clamp,
                };
                let bilinear = from_raw::<EmberTextureFilter>(t.filter, &field("filter"))? == EmberTextureFilter::Bilinear;
                let decode = |(j, &v): (usize, &f32)| -> Result<f32> {
                    match srgb {
                        true if (0.0..=1.0).contains(&v) => Ok(srgb_decode(v)),
                        true => Err(Error::arg(format!("{}[{j}] {v} is outside [0, 1] (srgb is 1)", field("pixels")))),
                        false => non_negative(v, &format!("{}[{j}]", field("pixels"))),
                    }
                };
                let linear: Vec<f32> = t.pixels.iter().enumerate().map(decode).collect::<Result<_>>()?;
                let texels: Vec<Rgb> = if t.channels == 1 {
                    linear.iter().map(|&v| Rgb::splat(v)).collect()
                } else {
                    linear.chunks_exact(3).map(|c| Rgb::new(c[0], c[1], c[2])).collect()
                };
                let bitmap = Bitmap::new(t.width, t.height, texels.clone(), wrap, bilinear).map_err(|e| Error::arg(format!("textures[{i}]: {e}")))?;
                (Texture::Bitmap { bitmap, to_uv }, Some((t.width, t.height, texels)))
            }
        };
        let mean = texture.mean();
        Ok(Self { texture, mean, image })
    }
}

/// The parameters of `EmberBsdf` a texture can drive, by `EmberTextureSlot` value.
const SLOTS: [(TextureSlot, &str); 4] = [
    (TextureSlot::Diffuse, "diffuse"),
    (TextureSlot::SpecularReflectance, "specular_reflectance"),
    (TextureSlot::SpecularTransmittance, "specular_transmittance"),
    (TextureSlot::Roughness, "principled.roughness"),
];

/// The slots (`EmberTextureSlot` values) a kind has (Mitsuba's textured parameters).
fn slots_of(kind: Kind) -> &'static [usize] {
    match kind {
        Kind::Diffuse => &[0],
        Kind::Conductor | Kind::RoughConductor => &[1],
        Kind::Dielectric | Kind::RoughDielectric => &[1, 2],
        Kind::Plastic | Kind::RoughPlastic => &[0, 1],
        Kind::Principled => &[0, 3],
    }
}

/// Mitsuba 3's defaults for a BSDF of `kind` (`ember_bsdf_init`).
pub fn default_bsdf(kind: Kind) -> EmberBsdf {
    let d = PrincipledParams::default();
    let int_ior = match kind {
        Kind::Plastic | Kind::RoughPlastic => 1.49,
        _ => 1.5046,
    };
    EmberBsdf {
        kind: kind as u32,
        diffuse: [0.5; 3],
        specular_reflectance: [1.0; 3],
        specular_transmittance: [1.0; 3],
        eta: [0.0; 3],
        k: [1.0; 3],
        int_ior,
        ext_ior: 1.000277,
        distribution: EmberMicrofacet::Beckmann as u32,
        alpha: 0.1,
        nonlinear: 0,
        two_sided: 0,
        principled: EmberPrincipled {
            roughness: d.roughness,
            anisotropic: d.anisotropic,
            metallic: d.metallic,
            spec_tint: d.spec_tint,
            sheen: d.sheen,
            sheen_tint: d.sheen_tint,
            flatness: d.flatness,
            clearcoat: d.clearcoat,
            clearcoat_gloss: d.clearcoat_gloss,
            spec_trans: d.spec_trans,
            eta: d.eta,
            diffuse_reflectance_sampling_rate: d.diffuse_sampling_rate,
            main_specular_sampling_rate: d.specular_sampling_rate,
            clearcoat_sampling_rate: d.clearcoat_sampling_rate,
        },
        textures: [-1; 4],
    }
}

/// Mitsuba 3's defaults for a texture of `kind` (`ember_texture_init`).
pub fn default_texture(k: EmberTextureKind) -> desc::EmberTexture {
    desc::EmberTexture {
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
    }
}

/// Mitsuba 3's defaults for a light of `kind` (`ember_light_init`).
pub fn default_light(k: EmberLightKind) -> EmberLight {
    EmberLight {
        kind: k as u32,
        position: [0.0; 3],
        direction: [0.0, 0.0, 1.0],
        color: [1.0; 3],
        cutoff_angle: 20.0,
        beam_width: 15.0,
        scale: 1.0,
        to_world: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        texture: -1,
    }
}

/// Rough plastic coatings built so far, by (GGX, α, int_ior, ext_ior): each costs up to
/// a second (the reader shares them the same way).
type Coatings = HashMap<(bool, u32, u32, u32), PlasticCoating>;

/// Material `i`, checked, with the textures it binds: (slot, index into the textures).
fn bsdf(i: usize, m: &EmberBsdf, textures: &[BuiltTexture], coatings: &mut Coatings) -> Result<(Material, Vec<(TextureSlot, usize)>)> {
    let field = |name: &str| format!("materials[{i}].{name}");
    let kind: Kind = from_raw(m.kind, &field("kind"))?;
    // The textures first: each -1 or an index, on a slot the kind has.
    let mut bound: [Option<usize>; 4] = [None; 4];
    for (s, &t) in m.textures.iter().enumerate() {
        if t == -1 {
            continue;
        }
        let name = format!("{} ({})", field(&format!("textures[{s}]")), SLOTS[s].1);
        if !slots_of(kind).contains(&s) {
            return Err(Error::arg(format!("{name} is {t}, but a {} material has no such parameter (give -1)", desc::kind_name(kind))));
        }
        if t < 0 || t as usize >= textures.len() {
            return Err(Error::arg(format!("{name} {t} is neither -1 nor a texture index (0..{})", textures.len())));
        }
        bound[s] = Some(t as usize);
    }
    let col = |s: usize, name: &str, v: [f32; 3]| -> Result<Rgb> {
        match bound[s] {
            Some(t) => Ok(textures[t].mean),
            None => colour(v, &field(name)),
        }
    };
    let microfacet = || -> Result<(MicrofacetKind, f32)> {
        let kind = match from_raw::<EmberMicrofacet>(m.distribution, &field("distribution"))? {
            EmberMicrofacet::Beckmann => MicrofacetKind::Beckmann,
            EmberMicrofacet::Ggx => MicrofacetKind::Ggx,
        };
        Ok((kind, non_negative(m.alpha, &field("alpha"))?))
    };
    let iors = || -> Result<(f32, f32)> { Ok((positive(m.int_ior, &field("int_ior"))?, positive(m.ext_ior, &field("ext_ior"))?)) };
    let nonlinear = flag(m.nonlinear, &field("nonlinear"))?;
    let two_sided = flag(m.two_sided, &field("two_sided"))?;
    let material = match kind {
        Kind::Diffuse => Material::diffuse(col(0, "diffuse", m.diffuse)?),
        Kind::Conductor | Kind::RoughConductor => {
            let (eta, k) = (colour(m.eta, &field("eta"))?, colour(m.k, &field("k"))?);
            let spec = col(1, "specular_reflectance", m.specular_reflectance)?;
            if kind == Kind::Conductor {
                Material::conductor(eta, k, spec)
            } else {
                let (distr, alpha) = microfacet()?;
                Material::rough_conductor(distr, alpha, eta, k, spec)
            }
        }
        Kind::Dielectric | Kind::RoughDielectric => {
            let (int_ior, ext_ior) = iors()?;
            let refl = col(1, "specular_reflectance", m.specular_reflectance)?;
            let trans = col(2, "specular_transmittance", m.specular_transmittance)?;
            if kind == Kind::Dielectric {
                Material::dielectric(int_ior, ext_ior, refl, trans)
            } else {
                let (distr, alpha) = microfacet()?;
                Material::rough_dielectric(distr, alpha, int_ior, ext_ior, refl, trans)
            }
        }
        Kind::Plastic | Kind::RoughPlastic => {
            let (int_ior, ext_ior) = iors()?;
            if int_ior == ext_ior {
                return Err(Error::arg(format!("{} and ext_ior are both {int_ior}: a coating needs an interface", field("int_ior"))));
            }
            let diffuse = col(0, "diffuse", m.diffuse)?;
            let spec = col(1, "specular_reflectance", m.specular_reflectance)?;
            if kind == Kind::Plastic {
                Material::plastic(int_ior, ext_ior, diffuse, spec, nonlinear)
            } else {
                let (distr, alpha) = microfacet()?;
                let key = (distr == MicrofacetKind::Ggx, alpha.to_bits(), int_ior.to_bits(), ext_ior.to_bits());
                let coating = coatings.entry(key).or_insert_with(|| Material::plastic_coating(distr, alpha, int_ior, ext_ior));
                Material::rough_plastic_coated(coating, diffuse, spec, nonlinear)
            }
        }
        Kind::Principled => Material::principled(principled(&field, &m.principled, col(0, "diffuse", m.diffuse)?, bound[3].map(|t| textures[t].mean))?),
    };
    let material = match two_sided {
        true if material.has_transmission() => {
            return Err(Error::arg(format!("{} is 1, but the material transmits: it is two-sided already", field("two_sided"))));
        }
        true => material.two_sided(),
        false => material,
    };
    let bindings = bound.iter().enumerate().filter_map(|(s, t)| t.map(|t| (SLOTS[s].0, t))).collect();
    Ok((material, bindings))
}

/// `principled`'s parameters, checked as the reader checks them; `roughness_texture` is
/// the mean of a texture driving the roughness.
fn principled(field: &dyn Fn(&str) -> String, p: &EmberPrincipled, base_color: Rgb, roughness_texture: Option<Rgb>) -> Result<PrincipledParams> {
    let f = |name: &str| field(&format!("principled.{name}"));
    let unit = |v: f32, name: &str| in_range(v, 0.0, 1.0, &f(name));
    let roughness = match roughness_texture {
        Some(mean) => mean.luminance(),
        None => non_negative(p.roughness, &f("roughness"))?,
    };
    let spec_trans = unit(p.spec_trans, "spec_trans")?;
    let eta = positive(p.eta, &f("eta"))?;
    Ok(PrincipledParams {
        base_color,
        roughness,
        anisotropic: unit(p.anisotropic, "anisotropic")?,
        metallic: unit(p.metallic, "metallic")?,
        spec_tint: unit(p.spec_tint, "spec_tint")?,
        sheen: non_negative(p.sheen, &f("sheen"))?,
        sheen_tint: unit(p.sheen_tint, "sheen_tint")?,
        flatness: unit(p.flatness, "flatness")?,
        clearcoat: non_negative(p.clearcoat, &f("clearcoat"))?,
        clearcoat_gloss: unit(p.clearcoat_gloss, "clearcoat_gloss")?,
        spec_trans,
        // Mitsuba moves an index-matched η off 1 when the transmission lobe is on.
        eta: if spec_trans > 0.0 && eta == 1.0 { 1.001 } else { eta },
        diffuse_sampling_rate: non_negative(p.diffuse_reflectance_sampling_rate, &f("diffuse_reflectance_sampling_rate"))?,
        specular_sampling_rate: non_negative(p.main_specular_sampling_rate, &f("main_specular_sampling_rate"))?,
        clearcoat_sampling_rate: non_negative(p.clearcoat_sampling_rate, &f("clearcoat_sampling_rate"))?,
    })
}

/// Light `i`, checked.
fn light(i: usize, l: &EmberLight, textures: &[BuiltTexture]) -> Result<Light> {
    let field = |name: &str| format!("lights[{i}].{name}");
    let kind: EmberLightKind = from_raw(l.kind, &field("kind"))?;
    let color = || colour(l.color, &field("color"));
    Ok(match kind {
        EmberLightKind::Point => Light::point(finite3(l.position, &field("position"))?, color()?),
        EmberLightKind::Spot => {
            let cutoff = l.cutoff_angle;
            if !(cutoff > 0.0 && cutoff <= 180.0) {
                return Err(Error::arg(format!("{} {cutoff} is outside (0, 180] degrees", field("cutoff_angle"))));
            }
            let beam = in_range(l.beam_width, 0.0, cutoff, &field("beam_width"))?;
            Light::spot(finite3(l.position, &field("position"))?, direction(l.direction, &field("direction"))?, color()?, cutoff, beam)
        }
        EmberLightKind::Directional => Light::directional(direction(l.direction, &field("direction"))?, color()?),
        EmberLightKind::Constant => Light::constant_environment(color()?),
        EmberLightKind::Envmap => {
            let t = l.texture;
            let image = usize::try_from(t).ok().and_then(|t| textures.get(t)).ok_or_else(|| {
                Error::arg(format!("{} {t} is not a texture index (0..{}): an envmap needs a bitmap texture", field("texture"), textures.len()))
            })?;
            let Some((width, height, texels)) = &image.image else {
                return Err(Error::arg(format!("{} {t} is a checkerboard: an envmap needs a bitmap texture", field("texture"))));
            };
            let scale = non_negative(l.scale, &field("scale"))?;
            let m = l.to_world;
            if !m.iter().flatten().all(|x| x.is_finite()) {
                return Err(Error::arg(format!("{} is not finite", field("to_world"))));
            }
            // Row-major: the image frame's axes are the matrix's columns.
            let axes = [0, 1, 2].map(|c| Vec3::new(m[0][c], m[1][c], m[2][c]));
            Light::environment_map(*width, *height, texels, scale, axes).map_err(|e| match e {
                EnvMapError::NotRotation => Error::arg(format!("{} is not a rotation (no scale, shear or mirror)", field("to_world"))),
                e => Error::arg(format!("lights[{i}]'s image: {e}")),
            })?
        }
    })
}

/// The camera: version 1's checks, then the field-of-view axis, the lens and the filter.
fn camera(desc: &SceneDesc) -> Result<PerspectiveCamera> {
    let cam = &desc.camera;
    if cam.width == 0 || cam.height == 0 || cam.width > MAX_TEXTURE_SIDE || cam.height > MAX_TEXTURE_SIDE {
        return Err(Error::arg(format!("camera size {}x{} is outside 1..={MAX_TEXTURE_SIDE}", cam.width, cam.height)));
    }
    if !(cam.fov_degrees > 0.0 && cam.fov_degrees < 180.0) {
        return Err(Error::arg(format!("camera fov_degrees {} is outside (0, 180)", cam.fov_degrees)));
    }
    let (origin, target, up) = (finite3(cam.origin, "camera origin")?, finite3(cam.target, "camera target")?, finite3(cam.up, "camera up")?);
    let forward = target - origin;
    if forward.length_squared() == 0.0 || forward.cross(up).length_squared() == 0.0 {
        return Err(Error::arg("camera target equals its origin, or up is parallel to the view direction"));
    }
    let fov_axis = match from_raw::<EmberFovAxis>(desc.fov_axis, "fov_axis")? {
        EmberFovAxis::X => FovAxis::X,
        EmberFovAxis::Y => FovAxis::Y,
        EmberFovAxis::Smaller => FovAxis::Smaller,
        EmberFovAxis::Larger => FovAxis::Larger,
        EmberFovAxis::Diagonal => FovAxis::Diagonal,
    };
    let lens = match non_negative(desc.lens.aperture_radius, "lens.aperture_radius")? {
        0.0 => None,
        radius => {
            let focus = positive(desc.lens.focus_distance, "lens.focus_distance")?;
            Some(Lens::new(radius, focus).ok_or_else(|| Error::arg("the lens is not finite"))?)
        }
    };
    let radius = non_negative(desc.filter.radius, "filter.radius")?;
    let filter = match from_raw::<EmberFilterKind>(desc.filter.kind, "filter.kind")? {
        EmberFilterKind::Box => Some(Filter::Box),
        EmberFilterKind::Tent => Filter::tent(if radius == 0.0 { 1.0 } else { radius }),
        EmberFilterKind::Gaussian => Filter::gaussian(if radius == 0.0 { 0.5 } else { radius }),
    }
    .ok_or_else(|| Error::arg(format!("filter.radius {radius} is too large")))?;
    let to_world = ember_core::scene::builtin::look_at(origin, target, up);
    Ok(PerspectiveCamera::new(to_world, cam.fov_degrees, fov_axis, cam.width, cam.height).with_lens(lens).with_filter(filter))
}

impl SceneData {
    /// Build `desc`, checking every index and value.
    pub fn from_desc(desc: &SceneDesc) -> Result<Self> {
        let mut b = SceneBuilder::new();
        b.set_camera(camera(desc)?);
        let textures: Vec<BuiltTexture> = desc.textures.iter().enumerate().map(|(i, t)| BuiltTexture::new(i, t)).collect::<Result<_>>()?;
        // A texture joins the scene when a material first binds it, as in the reader.
        let mut texture_ids: Vec<Option<u32>> = vec![None; textures.len()];
        let mut coatings = Coatings::new();
        let mut materials = Vec::with_capacity(desc.materials.len());
        for (i, m) in desc.materials.iter().enumerate() {
            let (material, bindings) = match *m {
                MaterialDesc::Diffuse(c) => (Material::diffuse(colour(c, &format!("material {i}'s albedo"))?), Vec::new()),
                MaterialDesc::Mirror(c) => (Material::conductor(Rgb::ZERO, Rgb::ONE, colour(c, &format!("material {i}'s reflectance"))?), Vec::new()),
                MaterialDesc::Glass(ior) if ior.is_finite() && ior > 0.0 => (Material::dielectric(ior, 1.0, Rgb::ONE, Rgb::ONE), Vec::new()),
                MaterialDesc::Glass(ior) => return Err(Error::arg(format!("material {i}'s index of refraction {ior} is not positive and finite"))),
                MaterialDesc::Bsdf(ref m) => bsdf(i, m, &textures, &mut coatings)?,
            };
            let id = b.add_material(material);
            for (slot, t) in bindings {
                let texture = *texture_ids[t].get_or_insert_with(|| b.add_texture(textures[t].texture.clone()));
                b.bind_texture(id, slot, texture);
            }
            materials.push(id);
        }
        let n = desc.triangles.len();
        if desc.triangle_materials.len() != n {
            return Err(Error::arg(format!("{} triangle materials for {n} triangles", desc.triangle_materials.len())));
        }
        if !desc.triangle_emission.is_empty() && desc.triangle_emission.len() != n {
            return Err(Error::arg(format!("{} triangle emissions for {n} triangles (give none or one per triangle)", desc.triangle_emission.len())));
        }
        let positions: Vec<Vec3> = desc.positions.iter().enumerate().map(|(i, p)| finite3(*p, &format!("position {i}"))).collect::<Result<_>>()?;
        let per_vertex = |len: usize, what: &str| {
            if len == 0 || len == positions.len() {
                Ok(())
            } else {
                Err(Error::arg(format!("{len} {what} for {} positions (give none or one per position)", positions.len())))
            }
        };
        per_vertex(desc.normals.len(), "normals")?;
        per_vertex(desc.uvs.len(), "uvs")?;
        // Normalised in double precision, as the reader normalises a mesh's normals.
        let normals: Vec<Vec3> = desc.normals.iter().enumerate().map(|(i, n)| direction(*n, &format!("normals[{i}]"))).collect::<Result<_>>()?;
        let uvs: Vec<Vec2> = desc
            .uvs
            .iter()
            .enumerate()
            .map(|(i, t)| if t.iter().all(|x| x.is_finite()) { Ok(Vec2::from(*t)) } else { Err(Error::arg(format!("uvs[{i}] is not finite"))) })
            .collect::<Result<_>>()?;
        let mut triangle_index = Vec::with_capacity(n);
        let mut kept = 0u32;
        for (t, tri) in desc.triangles.iter().enumerate() {
            let p = tri.map(|v| positions.get(v as usize).copied());
            let [Some(p0), Some(p1), Some(p2)] = p else {
                return Err(Error::arg(format!("triangle {t} indexes a vertex past the {} positions", positions.len())));
            };
            let m = desc.triangle_materials[t];
            let material =
                *materials.get(m as usize).ok_or_else(|| Error::arg(format!("triangle {t}'s material {m} is past the {} materials", materials.len())))?;
            let emission = match desc.triangle_emission.get(t) {
                Some(e) if e.iter().any(|&x| x != 0.0) => Some(AreaEmission { radiance: colour(*e, &format!("triangle {t}'s emission"))?, two_sided: false }),
                _ => None,
            };
            if b.add_triangle_uv([p0, p1, p2], per_corner(&normals, tri), per_corner(&uvs, tri), material, emission) {
                triangle_index.push(Some(kept));
                kept += 1;
            } else {
                triangle_index.push(None);
            }
        }
        for (i, (p, intensity)) in desc.point_lights.iter().enumerate() {
            let light = Light::point(finite3(*p, &format!("point light {i}'s position"))?, colour(*intensity, &format!("point light {i}'s intensity"))?);
            b.add_light(light);
        }
        for (i, l) in desc.lights.iter().enumerate() {
            b.add_light(light(i, l, &textures)?);
        }
        let (scene, geometry, _) = b.build().map_err(|e| Error::arg(format!("the scene cannot be built: {e}")))?;
        Self::new(scene, geometry, triangle_index)
    }

    /// A built-in scene: `cornell-box` or `glass-spheres`, as `ember render --builtin`.
    pub fn builtin(name: &str, width: u32, height: u32) -> Result<Self> {
        if width == 0 || height == 0 || width > 65536 || height > 65536 {
            return Err(Error::arg(format!("size {width}x{height} is outside 1..=65536")));
        }
        let builder = match name {
            "cornell-box" => ember_core::scene::builtin::cornell_box(width, height),
            "glass-spheres" => ember_core::scene::builtin_glass::glass_spheres(width, height),
            other => return Err(Error::arg(format!("no built-in scene '{other}' (cornell-box, glass-spheres)"))),
        };
        let (scene, geometry, _) = builder.build().map_err(|e| Error::arg(format!("built-in scene: {e}")))?;
        let triangle_index = (0..geometry.triangles.len() as u32).map(Some).collect();
        Self::new(scene, geometry, triangle_index)
    }

    /// The scene with its BVH, whose queries run with the instruction set the
    /// environment's `EMBER_SIMD` names (as `ember render`'s; the default otherwise:
    /// `ember_host::accel::Isa::best`). A name this machine does not offer is refused.
    /// Images do not depend on it.
    fn new(scene: Scene, geometry: SceneGeometry, triangle_index: Vec<Option<u32>>) -> Result<Self> {
        let mut accel = Accel::new(&geometry);
        let isa = ember_host::accel::Isa::select_with_env(None).map_err(|e| Error::arg(e.message))?;
        accel.set_isa(isa).map_err(|e| Error::arg(e.message))?;
        // The lane kernels: the same set if `EMBER_SIMD` names one, else the widest.
        accel.set_shading_level(ember_host::accel::Isa::select_shading_with_env(None).map_err(|e| Error::arg(e.message))?);
        Ok(Self { scene, geometry, accel, triangle_index, hash: OnceLock::new() })
    }

    /// FNV-1a of everything a render reads, as the CLI hashes its scenes
    /// (`ember_host::scene::PreparedScene::hash`): the scene's `Debug` form (camera,
    /// materials, lights), the BVH's geometry as raw bits, and each description
    /// triangle's index in the geometry (the callbacks name triangles by it; `u32::MAX`
    /// for a dropped one). Computed once, when an
    /// exported film first needs it.
    pub fn hash(&self) -> u64 {
        *self.hash.get_or_init(|| {
            let mut h = ember_host::scene::scene_hasher(&self.scene, &self.accel);
            for index in &self.triangle_index {
                std::hash::Hasher::write_u32(&mut h, index.unwrap_or(u32::MAX));
            }
            h.value()
        })
    }
}
