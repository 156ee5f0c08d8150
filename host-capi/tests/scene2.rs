//! The complete scene description (`EmberSceneDesc2`, `ember_scene_create2`):
//!
//! - a scene with a textured rough plastic (an sRGB bitmap on per-vertex texture
//!   coordinates), a checkerboard, per-vertex normals, an environment map, a thin lens,
//!   a tent filter and a vertical field of view, built through the C functions, renders
//!   bit-identically to the same scene written as Mitsuba XML (OBJ meshes, a PNG, an
//!   EXR) and rendered by the command line's code (`prepare_file`, `CoreRenderer`), for
//!   PT and BDPT; and so does each other BSDF kind on the floor (conductor, rough
//!   conductor, dielectric, rough dielectric, plastic, principled, two-sided diffuse)
//!   with parameters off the defaults and textures on its slots, against its `<bsdf>`;
//!   and so do point, spot, directional and constant lights with a pinhole, a gaussian
//!   filter and a horizontal field of view;
//! - a table of bad descriptions, each refused with its status and a message naming the
//!   field;
//! - `ember_render_passes` runs on one pool per renderer: four calls on a renderer of
//!   two threads see two threads, not eight.
//!
//! Injected bugs seen to fail here (each run once, reverted), in `src/scene.rs`:
//! - texture coordinates handed to the builder as (v, u): the XML agreement fails (PT:
//!   1596 of 1728 pixels differ);
//! - a textured parameter given the struct's colour instead of the texture's mean (as
//!   the reader gives it): the XML agreement fails (PT: 1596 pixels differ; the rough
//!   plastic's lobe weights come from that value);
//! - the dielectrics' and plastics' `int_ior` and `ext_ior` swapped: the BSDF test's
//!   dielectric case fails (1589 pixels differ);
//! - `principled`'s `anisotropic` read from `sheen_tint`: its principled case fails
//!   (1590 pixels differ);
//! - the directional light's direction negated, and the gaussian's standard deviation
//!   ignored (0.5 always): the lights test fails (PT: 1716 pixels differ, each);
//! - the texture-index bound `>` for `>=`: the table's `materials[0].textures[0] 3` case
//!   panics (EMBER_STATUS_PANIC) instead of being refused;
//! - in `src/ffi.rs`, a pool started on every `ember_render_passes` (as before issue
//!   55): the pool test sees 4 threads.
#![allow(unsafe_code)]

use std::collections::HashSet;
use std::ffi::{CStr, CString, c_void};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::thread::ThreadId;
use std::time::Instant;

use ember_capi::EmberStatus;
use ember_capi::ffi::*;
use ember_cli::estimators::CoreRenderer;
use ember_cli::progress::DriverConfig;
use ember_core::estimators::EstimatorKind;
use ember_core::render::Film;
use ember_host::driver::Limits;

const W: u32 = 48;
const H: u32 = 36;
const PASSES: u32 = 3;

/// The scene as arrays, owning what the description points to.
#[derive(Clone)]
struct Arrays {
    positions: Vec<f32>,
    normals: Vec<f32>,
    uvs: Vec<f32>,
    indices: Vec<u32>,
    triangle_materials: Vec<u32>,
    materials: Vec<EmberBsdf>,
    /// Per texture, its pixels (empty for a checkerboard) and the struct.
    textures: Vec<(Vec<f32>, EmberTexture)>,
    lights: Vec<EmberLight>,
    camera: EmberCamera,
    fov_axis: u32,
    lens: EmberLens,
    filter: EmberPixelFilter,
}

/// The PNG's 4 × 4 RGB bytes (sRGB).
fn albedo_bytes() -> Vec<u8> {
    (0..16u32).flat_map(|i| [(40 + 13 * i) as u8, (200 - 9 * i) as u8, (90 + 37 * (i % 5)) as u8]).collect()
}

/// The environment map's 16 × 8 linear texels: a sky gradient with a bright patch.
fn sky() -> Vec<[f32; 3]> {
    (0..8u32)
        .flat_map(|y| (0..16u32).map(move |x| (x, y)))
        .map(|(x, y)| if (x, y) == (5, 2) { [40.0, 36.0, 30.0] } else { [0.3 + 0.05 * y as f32, 0.4 + 0.02 * x as f32, 0.8 - 0.07 * y as f32] })
        .collect()
}

/// The envmap's rotation: a quarter turn about +y (exact in binary), row-major.
const ENV_ROTATION: [[f32; 3]; 3] = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]];

/// Two quads: a floor (rough plastic, the PNG on texture coordinates tiling it 3 × 3,
/// tilted per-vertex normals) and a back wall (diffuse, a checkerboard); 8 vertices.
const FLOOR: [[f32; 3]; 4] = [[-3.0, -1.0, 0.5], [-3.0, -1.0, 6.0], [3.0, -1.0, 6.0], [3.0, -1.0, 0.5]];
const FLOOR_NORMALS: [[f32; 3]; 4] = [[0.1, 1.0, 0.0], [-0.1, 1.0, 0.05], [0.0, 0.9, -0.1], [0.2, 1.0, 0.1]];
const FLOOR_UVS: [[f32; 2]; 4] = [[0.0, 0.0], [0.0, 3.0], [3.0, 3.0], [3.0, 0.0]];
const WALL: [[f32; 3]; 4] = [[-3.0, -1.0, 6.0], [-3.0, 3.0, 6.0], [3.0, 3.0, 6.0], [3.0, -1.0, 6.0]];
const WALL_NORMALS: [[f32; 3]; 4] = [[0.0, 0.0, -1.0]; 4];
const WALL_UVS: [[f32; 2]; 4] = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]];
const QUAD: [u32; 6] = [0, 1, 2, 0, 2, 3];
const CHECKER: ([f32; 3], [f32; 3]) = ([0.7, 0.2, 0.1], [0.1, 0.3, 0.6]);
const ALPHA: f32 = 0.2;
const APERTURE: f32 = 0.04;
const FOCUS: f32 = 3.0;
const TENT: f32 = 1.25;
const FOV_Y: f32 = 50.0;
const ENV_SCALE: f32 = 1.5;
const TARGET: [f32; 3] = [0.1, -0.25, 1.0];

fn init<T>(f: unsafe extern "C" fn(u32, *mut T) -> EmberStatus, kind: u32) -> T {
    let mut v = std::mem::MaybeUninit::<T>::uninit();
    assert_eq!(unsafe { f(kind, v.as_mut_ptr()) }, EmberStatus::Ok);
    // SAFETY: the init function wrote the whole struct.
    unsafe { v.assume_init() }
}

fn arrays() -> Arrays {
    let flat3 = |a: &[[f32; 3]]| a.iter().flatten().copied().collect::<Vec<_>>();
    let flat2 = |a: &[[f32; 2]]| a.iter().flatten().copied().collect::<Vec<_>>();
    let mut plastic = init(ember_bsdf_init, EmberBsdfKind::RoughPlastic as u32);
    plastic.distribution = EmberMicrofacet::Ggx as u32;
    plastic.alpha = ALPHA;
    plastic.textures[EmberTextureSlot::Diffuse as usize] = 0;
    let mut wall = init(ember_bsdf_init, EmberBsdfKind::Diffuse as u32);
    wall.textures[EmberTextureSlot::Diffuse as usize] = 1;
    let mut png = init(ember_texture_init, EmberTextureKind::Bitmap as u32);
    (png.width, png.height, png.srgb) = (4, 4, 1);
    // As Mitsuba decodes an 8-bit PNG: byte / 255, then the sRGB curve.
    let png_pixels: Vec<f32> = albedo_bytes().iter().map(|&b| b as f32 / 255.0).collect();
    let mut checker = init(ember_texture_init, EmberTextureKind::Checkerboard as u32);
    (checker.color0, checker.color1) = CHECKER;
    checker.to_uv = [4.0, 0.0, 0.0, 0.0, 4.0, 0.0];
    let mut sky_texture = init(ember_texture_init, EmberTextureKind::Bitmap as u32);
    (sky_texture.width, sky_texture.height) = (16, 8);
    let mut env = init(ember_light_init, EmberLightKind::Envmap as u32);
    (env.texture, env.scale, env.to_world) = (2, ENV_SCALE, ENV_ROTATION);
    Arrays {
        positions: [flat3(&FLOOR), flat3(&WALL)].concat(),
        normals: [flat3(&FLOOR_NORMALS), flat3(&WALL_NORMALS)].concat(),
        uvs: [flat2(&FLOOR_UVS), flat2(&WALL_UVS)].concat(),
        indices: [QUAD, QUAD.map(|i| i + 4)].concat(),
        triangle_materials: vec![0, 0, 1, 1],
        materials: vec![plastic, wall],
        textures: vec![(png_pixels, png), (Vec::new(), checker), (sky().concat(), sky_texture)],
        lights: vec![env],
        camera: EmberCamera { origin: [0.0; 3], target: TARGET, up: [0.0, 1.0, 0.0], fov_degrees: FOV_Y, width: W, height: H },
        fov_axis: EmberFovAxis::Y as u32,
        lens: EmberLens { aperture_radius: APERTURE, focus_distance: FOCUS },
        filter: EmberPixelFilter { kind: EmberFilterKind::Tent as u32, radius: TENT },
    }
}

impl Arrays {
    /// `ember_scene_create2` on these arrays: the scene, or the status and message.
    fn create(&self) -> Result<EmberScene, (EmberStatus, String)> {
        let textures: Vec<EmberTexture> =
            self.textures.iter().map(|(p, t)| EmberTexture { pixels: if p.is_empty() { t.pixels } else { p.as_ptr() }, ..*t }).collect();
        let ptr = |v: &[f32]| if v.is_empty() { std::ptr::null() } else { v.as_ptr() };
        let desc = EmberSceneDesc2 {
            positions: self.positions.as_ptr(),
            vertex_count: (self.positions.len() / 3) as u32,
            normals: ptr(&self.normals),
            uvs: ptr(&self.uvs),
            indices: self.indices.as_ptr(),
            triangle_count: (self.indices.len() / 3) as u32,
            triangle_materials: self.triangle_materials.as_ptr(),
            triangle_emission: std::ptr::null(),
            materials: self.materials.as_ptr(),
            material_count: self.materials.len() as u32,
            textures: textures.as_ptr(),
            texture_count: textures.len() as u32,
            lights: self.lights.as_ptr(),
            light_count: self.lights.len() as u32,
            camera: self.camera,
            fov_axis: self.fov_axis,
            lens: self.lens,
            filter: self.filter,
        };
        let mut scene = 0;
        match unsafe { ember_scene_create2(&desc, &mut scene) } {
            EmberStatus::Ok => Ok(scene),
            s => Err((s, last_error())),
        }
    }
}

fn last_error() -> String {
    unsafe { CStr::from_ptr(ember_last_error()) }.to_string_lossy().into_owned()
}

/// A float as XML and OBJ text that reads back as the same f32 through f64 (the
/// reader parses in double precision and normalises directions there).
fn f(x: f32) -> String {
    format!("{:?}", x as f64)
}

fn v3(v: [f32; 3]) -> String {
    v.map(f).join(", ")
}

fn obj(positions: &[[f32; 3]], normals: &[[f32; 3]], uvs: &[[f32; 2]]) -> String {
    let mut s = String::new();
    for p in positions {
        s += &format!("v {} {} {}\n", f(p[0]), f(p[1]), f(p[2]));
    }
    for t in uvs {
        s += &format!("vt {} {}\n", f(t[0]), f(t[1]));
    }
    for n in normals {
        s += &format!("vn {} {} {}\n", f(n[0]), f(n[1]), f(n[2]));
    }
    for t in QUAD.chunks_exact(3) {
        let c = t.iter().map(|i| format!("{0}/{0}/{0}", i + 1)).collect::<Vec<_>>().join(" ");
        s += &format!("f {c}\n");
    }
    s
}

/// The same scene as Mitsuba 3 XML in `dir`, with its meshes and images.
/// The floor's rough plastic in XML.
fn plastic_xml() -> String {
    format!(
        r#"<bsdf type="roughplastic" id="floor"><string name="distribution" value="ggx"/><float name="alpha" value="{}"/>
    <texture type="bitmap" name="diffuse_reflectance"><string name="filename" value="albedo.png"/></texture></bsdf>"#,
        f(ALPHA)
    )
}

/// The thin-lens sensor of [`arrays`] in XML.
fn thinlens_xml() -> String {
    format!(
        r#"<sensor type="thinlens">
    <float name="fov" value="{}"/><string name="fov_axis" value="y"/>
    <float name="aperture_radius" value="{}"/><float name="focus_distance" value="{}"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="{}" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{W}"/><integer name="height" value="{H}"/>
      <rfilter type="tent"><float name="radius" value="{}"/></rfilter></film>
  </sensor>"#,
        f(FOV_Y),
        f(APERTURE),
        f(FOCUS),
        v3(TARGET),
        f(TENT)
    )
}

/// The environment map of [`arrays`] in XML.
fn envmap_xml() -> String {
    let row = |r: [f32; 3]| format!("{} {} {} 0", f(r[0]), f(r[1]), f(r[2]));
    let m = ENV_ROTATION;
    let matrix = format!("{} {} {} 0 0 0 1", row(m[0]), row(m[1]), row(m[2]));
    format!(
        r#"<emitter type="envmap"><string name="filename" value="sky.exr"/><float name="scale" value="{}"/>
    <transform name="to_world"><matrix value="{matrix}"/></transform></emitter>"#,
        f(ENV_SCALE)
    )
}

/// The scene as XML in `dir`: the floor's material `floor` (a `<bsdf id="floor">`), the
/// `sensor` and the `emitters`.
fn write_xml(dir: &Path, floor: &str, sensor: &str, emitters: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("floor.obj"), obj(&FLOOR, &FLOOR_NORMALS, &FLOOR_UVS)).unwrap();
    std::fs::write(dir.join("wall.obj"), obj(&WALL, &WALL_NORMALS, &WALL_UVS)).unwrap();
    let file = std::fs::File::create(dir.join("albedo.png")).unwrap();
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), 4, 4);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.write_header().unwrap().write_image_data(&albedo_bytes()).unwrap();
    ember_formats::image_io::write_exr(&dir.join("sky.exr"), 16, 8, &sky()).unwrap();
    let xml = format!(
        r#"<scene version="3.0.0">
  {sensor}
  {floor}
  <bsdf type="diffuse" id="wall">
    <texture type="checkerboard" name="reflectance">
      <rgb name="color0" value="{c0}"/><rgb name="color1" value="{c1}"/>
      <transform name="to_uv"><scale x="4" y="4"/></transform>
    </texture>
  </bsdf>
  <shape type="obj"><string name="filename" value="floor.obj"/><boolean name="flip_tex_coords" value="false"/><ref id="floor"/></shape>
  <shape type="obj"><string name="filename" value="wall.obj"/><boolean name="flip_tex_coords" value="false"/><ref id="wall"/></shape>
  {emitters}
</scene>
"#,
        c0 = v3(CHECKER.0),
        c1 = v3(CHECKER.1),
    );
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    path
}

fn render_c(scene: EmberScene, estimator: EstimatorKind, seed: u64) -> Vec<[f32; 3]> {
    let name = CString::new(estimator.name()).unwrap();
    let settings = EmberRenderSettings {
        estimator: name.as_ptr(),
        seed,
        max_depth: -1,
        threads: 2,
        light_paths: 0,
        connections: 0,
        radius_footprints: 0.0,
        options: std::ptr::null(),
    };
    let mut r = 0;
    assert_eq!(unsafe { ember_renderer_create(scene, &settings, std::ptr::null(), &mut r) }, EmberStatus::Ok, "{}", last_error());
    assert_eq!(ember_render_passes(r, PASSES), EmberStatus::Ok, "{}", last_error());
    let mut rgb = vec![0.0f32; (W * H * 3) as usize];
    assert_eq!(unsafe { ember_renderer_image(r, rgb.as_mut_ptr(), rgb.len()) }, EmberStatus::Ok);
    assert_eq!(ember_renderer_destroy(r), EmberStatus::Ok);
    rgb.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect()
}

fn render_cli(path: &Path, estimator: EstimatorKind, seed: u64) -> Vec<[f32; 3]> {
    let prepared = ember_cli::setup::prepare_file(path, None, None, Vec::new()).unwrap();
    assert!(prepared.warnings.is_empty(), "{:?}", prepared.warnings);
    let mut film = Film::for_camera(&prepared.scene.camera);
    let mut r = CoreRenderer::with_config(prepared, estimator.default_config(), -1, seed, 2).unwrap();
    let limits = Limits { spp: PASSES, deadline: None, interrupt: None, first_pass: 0 };
    r.render(&mut film, limits, DriverConfig { threads: 2, progress: false }, Instant::now()).unwrap();
    film.to_rgb_f32()
}

/// The C description and the XML give the same bits: the same constructors with the
/// same parameters, textures, normals, lens and filter.
#[test]
fn the_c_description_renders_as_the_same_scene_in_xml() {
    let scene = arrays().create().unwrap_or_else(|e| panic!("{e:?}"));
    let dir = std::env::temp_dir().join(format!("ember-capi-scene2-{}", std::process::id()));
    let xml = write_xml(&dir, &plastic_xml(), &thinlens_xml(), &envmap_xml());
    for estimator in [EstimatorKind::Pt, EstimatorKind::Bdpt] {
        let (mine, cli) = (render_c(scene, estimator, 11), render_cli(&xml, estimator, 11));
        let mean = |img: &[[f32; 3]]| img.iter().flatten().map(|&x| x as f64).sum::<f64>() / (3 * img.len()) as f64;
        assert!(mean(&mine) > 0.05 && mine.iter().flatten().all(|x| x.is_finite()), "{}: a black or broken image", estimator.name());
        let differing = mine.iter().zip(&cli).filter(|(a, b)| a != b).count();
        assert_eq!(
            differing,
            0,
            "{}: {differing} of {} pixels differ from the XML scene's (means {} and {})",
            estimator.name(),
            cli.len(),
            mean(&mine),
            mean(&cli)
        );
    }
    assert_eq!(ember_scene_destroy(scene), EmberStatus::Ok);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every other BSDF kind on the floor, with parameters off Mitsuba's defaults and
/// textures on their slots, against the same `<bsdf>` in XML: the same bits (PT).
#[test]
fn every_bsdf_kind_renders_as_its_xml() {
    let png = r#"<texture type="bitmap" name="NAME"><string name="filename" value="albedo.png"/></texture>"#;
    let checker = |name: &str| {
        format!(
            r#"<texture type="checkerboard" name="{name}"><rgb name="color0" value="{}"/><rgb name="color1" value="{}"/><transform name="to_uv"><scale x="4" y="4"/></transform></texture>"#,
            v3(CHECKER.0),
            v3(CHECKER.1)
        )
    };
    let bsdf = |kind: EmberBsdfKind, edit: &dyn Fn(&mut EmberBsdf)| {
        let mut b = init(ember_bsdf_init, kind as u32);
        edit(&mut b);
        b
    };
    let cases: Vec<(EmberBsdf, String)> = vec![
        (
            bsdf(EmberBsdfKind::Conductor, &|b| (b.eta, b.k, b.specular_reflectance) = ([0.2, 0.9, 1.1], [3.9, 2.4, 2.1], [0.9, 0.8, 0.7])),
            r#"<bsdf type="conductor" id="floor"><rgb name="eta" value="0.2, 0.9, 1.1"/><rgb name="k" value="3.9, 2.4, 2.1"/><rgb name="specular_reflectance" value="0.9, 0.8, 0.7"/></bsdf>"#.into(),
        ),
        (
            bsdf(EmberBsdfKind::RoughConductor, &|b| (b.alpha, b.textures[1]) = (0.3, 0)),
            format!(r#"<bsdf type="roughconductor" id="floor"><float name="alpha" value="{}"/>{}</bsdf>"#, f(0.3), png.replace("NAME", "specular_reflectance")),
        ),
        (
            bsdf(EmberBsdfKind::Dielectric, &|b| (b.int_ior, b.ext_ior, b.specular_transmittance) = (1.6, 1.1, [0.9, 0.95, 1.0])),
            format!(
                r#"<bsdf type="dielectric" id="floor"><float name="int_ior" value="{}"/><float name="ext_ior" value="{}"/><rgb name="specular_transmittance" value="{}"/></bsdf>"#,
                f(1.6),
                f(1.1),
                v3([0.9, 0.95, 1.0])
            ),
        ),
        (
            bsdf(EmberBsdfKind::RoughDielectric, &|b| (b.distribution, b.alpha, b.int_ior, b.ext_ior, b.textures[2]) = (1, 0.25, 1.33, 1.0, 1)),
            format!(
                r#"<bsdf type="roughdielectric" id="floor"><string name="distribution" value="ggx"/><float name="alpha" value="{}"/><float name="int_ior" value="{}"/><float name="ext_ior" value="1"/>{}</bsdf>"#,
                f(0.25),
                f(1.33),
                checker("specular_transmittance")
            ),
        ),
        (
            bsdf(EmberBsdfKind::Plastic, &|b| (b.int_ior, b.ext_ior, b.nonlinear, b.textures[0]) = (1.6, 1.0, 1, 0)),
            format!(
                r#"<bsdf type="plastic" id="floor"><float name="int_ior" value="{}"/><float name="ext_ior" value="1"/><boolean name="nonlinear" value="true"/>{}</bsdf>"#,
                f(1.6),
                png.replace("NAME", "diffuse_reflectance")
            ),
        ),
        (
            bsdf(EmberBsdfKind::Principled, &|b| {
                let p = &mut b.principled;
                (p.metallic, p.spec_trans, p.sheen, p.clearcoat, p.anisotropic, p.eta) = (0.4, 0.2, 0.5, 0.3, 0.3, 1.45);
                b.textures[0] = 0;
                b.textures[3] = 1;
            }),
            format!(
                r#"<bsdf type="principled" id="floor"><float name="metallic" value="{}"/><float name="spec_trans" value="{}"/><float name="sheen" value="0.5"/><float name="clearcoat" value="{}"/><float name="anisotropic" value="{}"/><float name="eta" value="{}"/>{}{}</bsdf>"#,
                f(0.4),
                f(0.2),
                f(0.3),
                f(0.3),
                f(1.45),
                png.replace("NAME", "base_color"),
                checker("roughness")
            ),
        ),
        (
            bsdf(EmberBsdfKind::Diffuse, &|b| (b.two_sided, b.diffuse) = (1, [0.3, 0.6, 0.2])),
            format!(r#"<bsdf type="twosided" id="floor"><bsdf type="diffuse"><rgb name="reflectance" value="{}"/></bsdf></bsdf>"#, v3([0.3, 0.6, 0.2])),
        ),
    ];
    let dir = std::env::temp_dir().join(format!("ember-capi-bsdfs-{}", std::process::id()));
    for (i, (floor, xml)) in cases.iter().enumerate() {
        let mut a = arrays();
        a.materials[0] = *floor;
        let scene = a.create().unwrap_or_else(|e| panic!("case {i}: {e:?}"));
        let path = write_xml(&dir.join(i.to_string()), xml, &thinlens_xml(), &envmap_xml());
        let (mine, cli) = (render_c(scene, EstimatorKind::Pt, 3), render_cli(&path, EstimatorKind::Pt, 3));
        let differing = mine.iter().zip(&cli).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "case {i} ({xml}): {differing} of {} pixels differ from the XML scene's", cli.len());
        assert_eq!(ember_scene_destroy(scene), EmberStatus::Ok);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Point, spot, directional and constant lights with a pinhole camera, a gaussian filter
/// and a horizontal field of view, against the same in XML: the same bits (PT, BDPT).
#[test]
fn every_light_kind_and_the_pinhole_render_as_their_xml() {
    let light = |kind: EmberLightKind, edit: &dyn Fn(&mut EmberLight)| {
        let mut l = init(ember_light_init, kind as u32);
        edit(&mut l);
        l
    };
    let mut a = arrays();
    a.lights = vec![
        light(EmberLightKind::Point, &|l| (l.position, l.color) = ([0.5, 1.5, 3.0], [4.0, 3.0, 2.0])),
        // Straight down: the XML's `lookat` gives the same axis to the bit.
        light(EmberLightKind::Spot, &|l| {
            (l.position, l.direction, l.color, l.cutoff_angle, l.beam_width) = ([-1.0, 2.0, 4.0], [0.0, -1.0, 0.0], [30.0; 3], 35.0, 20.0)
        }),
        light(EmberLightKind::Directional, &|l| (l.direction, l.color) = ([0.3, -1.0, 0.4], [0.8, 0.7, 0.6])),
        light(EmberLightKind::Constant, &|l| l.color = [0.05, 0.06, 0.08]),
    ];
    a.lens = EmberLens::default();
    a.filter = EmberPixelFilter { kind: EmberFilterKind::Gaussian as u32, radius: 0.7 };
    a.fov_axis = EmberFovAxis::X as u32;
    let sensor = format!(
        r#"<sensor type="perspective"><float name="fov" value="{}"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="{}" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{W}"/><integer name="height" value="{H}"/>
      <rfilter type="gaussian"><float name="stddev" value="{}"/></rfilter></film></sensor>"#,
        f(FOV_Y),
        v3(TARGET),
        f(0.7)
    );
    let emitters = format!(
        r#"<emitter type="point"><point name="position" value="{}"/><rgb name="intensity" value="{}"/></emitter>
  <emitter type="spot"><transform name="to_world"><lookat origin="{}" target="{}" up="0, 0, 1"/></transform><rgb name="intensity" value="30"/><float name="cutoff_angle" value="35"/><float name="beam_width" value="20"/></emitter>
  <emitter type="directional"><vector name="direction" value="{}"/><rgb name="irradiance" value="{}"/></emitter>
  <emitter type="constant"><rgb name="radiance" value="{}"/></emitter>"#,
        v3([0.5, 1.5, 3.0]),
        v3([4.0, 3.0, 2.0]),
        v3([-1.0, 2.0, 4.0]),
        v3([-1.0, 1.0, 4.0]),
        v3([0.3, -1.0, 0.4]),
        v3([0.8, 0.7, 0.6]),
        v3([0.05, 0.06, 0.08])
    );
    let scene = a.create().unwrap_or_else(|e| panic!("{e:?}"));
    let dir = std::env::temp_dir().join(format!("ember-capi-lights-{}", std::process::id()));
    let xml = write_xml(&dir, &plastic_xml(), &sensor, &emitters);
    for estimator in [EstimatorKind::Pt, EstimatorKind::Bdpt] {
        let (mine, cli) = (render_c(scene, estimator, 13), render_cli(&xml, estimator, 13));
        let differing = mine.iter().zip(&cli).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{}: {differing} of {} pixels differ from the XML scene's", estimator.name(), cli.len());
    }
    assert_eq!(ember_scene_destroy(scene), EmberStatus::Ok);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad descriptions: each refused with its status and a message naming the field.
#[test]
fn bad_descriptions_are_refused_with_the_field_named() {
    type Edit = fn(&mut Arrays);
    use EmberStatus::{InvalidArgument as Bad, NullPointer as Null};
    fn spot(a: &mut Arrays, edit: fn(&mut EmberLight)) {
        let mut l = init(ember_light_init, EmberLightKind::Spot as u32);
        edit(&mut l);
        a.lights.push(l);
    }
    let cases: Vec<(&str, Edit, EmberStatus, &str)> = vec![
        ("bsdf kind", |a| a.materials[0].kind = 8, Bad, "materials[0].kind 8 is not an EmberBsdfKind (0..=7: diffuse,"),
        ("distribution", |a| a.materials[0].distribution = 2, Bad, "materials[0].distribution 2 is not an EmberMicrofacet (0..=1: beckmann, ggx)"),
        ("alpha", |a| a.materials[0].alpha = f32::NAN, Bad, "materials[0].alpha NaN is negative or not finite"),
        ("texture index", |a| a.materials[0].textures[0] = 3, Bad, "materials[0].textures[0] (diffuse) 3 is neither -1 nor a texture index (0..3)"),
        ("negative index", |a| a.materials[0].textures[0] = -2, Bad, "-2 is neither -1 nor a texture index"),
        (
            "slot absent",
            |a| a.materials[1].textures[1] = 0,
            Bad,
            "materials[1].textures[1] (specular_reflectance) is 0, but a diffuse material has no such parameter (give -1)",
        ),
        ("nonlinear", |a| a.materials[0].nonlinear = 2, Bad, "materials[0].nonlinear 2 is not 0 or 1"),
        ("coating", |a| a.materials[0].ext_ior = a.materials[0].int_ior, Bad, "materials[0].int_ior and ext_ior are both 1.49"),
        (
            "diffuse colour",
            |a| a.materials[1] = EmberBsdf { diffuse: [0.5, -0.1, 0.5], ..init(ember_bsdf_init, 0) },
            Bad,
            "materials[1].diffuse is negative or not finite",
        ),
        (
            "two-sided glass",
            |a| a.materials[1] = EmberBsdf { two_sided: 1, ..init(ember_bsdf_init, EmberBsdfKind::Dielectric as u32) },
            Bad,
            "materials[1].two_sided is 1, but the material transmits",
        ),
        (
            "principled",
            |a| a.materials[1] = EmberBsdf { principled: EmberPrincipled { metallic: 1.5, ..init(ember_bsdf_init, 7).principled }, ..init(ember_bsdf_init, 7) },
            Bad,
            "materials[1].principled.metallic 1.5 is outside [0, 1]",
        ),
        ("texture kind", |a| a.textures[1].1.kind = 2, Bad, "textures[1].kind 2 is not an EmberTextureKind (0..=1: bitmap, checkerboard)"),
        ("texture width", |a| a.textures[0].1.width = 0, Bad, "textures[0].width 0 is outside 1..=65536"),
        ("channels", |a| a.textures[0].1.channels = 4, Bad, "textures[0].channels 4 is not 1 or 3"),
        ("no pixels", |a| a.textures[0].0.clear(), Null, "textures[0].pixels (for 48 floats) is null"),
        ("srgb flag", |a| a.textures[0].1.srgb = 3, Bad, "textures[0].srgb 3 is not 0 or 1"),
        ("srgb range", |a| a.textures[0].0[7] = 1.5, Bad, "textures[0].pixels[7] 1.5 is outside [0, 1] (srgb is 1)"),
        ("linear texel", |a| a.textures[2].0[5] = -1.0, Bad, "textures[2].pixels[5] -1 is negative or not finite"),
        ("wrap mode", |a| a.textures[0].1.wrap_mode = 3, Bad, "textures[0].wrap_mode 3 is not an EmberWrapMode"),
        ("texture filter", |a| a.textures[0].1.filter = 9, Bad, "textures[0].filter 9 is not an EmberTextureFilter"),
        ("to_uv", |a| a.textures[1].1.to_uv[2] = f32::INFINITY, Bad, "textures[1].to_uv is not finite"),
        ("checker colour", |a| a.textures[1].1.color1[0] = -0.5, Bad, "textures[1].color1 is negative or not finite"),
        ("light kind", |a| a.lights[0].kind = 5, Bad, "lights[0].kind 5 is not an EmberLightKind (0..=4: point, spot, directional, constant, envmap)"),
        ("envmap texture", |a| a.lights[0].texture = 7, Bad, "lights[0].texture 7 is not a texture index (0..3): an envmap needs a bitmap texture"),
        ("envmap checker", |a| a.lights[0].texture = 1, Bad, "lights[0].texture 1 is a checkerboard"),
        ("envmap rotation", |a| a.lights[0].to_world[0][0] = 2.0, Bad, "lights[0].to_world is not a rotation"),
        ("envmap scale", |a| a.lights[0].scale = -1.0, Bad, "lights[0].scale -1 is negative or not finite"),
        ("spot beam", |a| spot(a, |l| l.beam_width = 30.0), Bad, "lights[1].beam_width 30 is outside [0, 20]"),
        ("spot cutoff", |a| spot(a, |l| l.cutoff_angle = 0.0), Bad, "lights[1].cutoff_angle 0 is outside (0, 180] degrees"),
        ("spot direction", |a| spot(a, |l| l.direction = [0.0; 3]), Bad, "lights[1].direction is zero"),
        ("light colour", |a| spot(a, |l| l.color[2] = f32::NAN), Bad, "lights[1].color is negative or not finite"),
        ("zero normal", |a| a.normals[6..9].fill(0.0), Bad, "normals[2] is zero"),
        ("uv", |a| a.uvs[3] = f32::NAN, Bad, "uvs[1] is not finite"),
        ("fov axis", |a| a.fov_axis = 5, Bad, "fov_axis 5 is not an EmberFovAxis (0..=4: x, y, smaller, larger, diagonal)"),
        ("lens focus", |a| a.lens.focus_distance = 0.0, Bad, "lens.focus_distance 0 is not positive and finite"),
        ("aperture", |a| a.lens.aperture_radius = -0.1, Bad, "lens.aperture_radius -0.1 is negative or not finite"),
        ("filter kind", |a| a.filter.kind = 3, Bad, "filter.kind 3 is not an EmberFilterKind (0..=2: box, tent, gaussian)"),
        ("filter radius", |a| a.filter.radius = f32::INFINITY, Bad, "filter.radius inf is negative or not finite"),
        ("no materials", |a| a.materials.clear(), Bad, "triangle 0's material 0 is past the 0 materials"),
    ];
    let mut failures = Vec::new();
    for (name, edit, status, fragment) in cases {
        let mut a = arrays();
        edit(&mut a);
        match a.create() {
            Ok(scene) => {
                failures.push(format!("{name}: accepted"));
                ember_scene_destroy(scene);
            }
            Err((s, message)) if s == status && message.contains(fragment) => {}
            Err((s, message)) => failures.push(format!("{name}: {s:?} \"{message}\", expected {status:?} with \"{fragment}\"")),
        }
    }
    // The init functions check their kind and pointer too.
    let mut b = std::mem::MaybeUninit::<EmberBsdf>::uninit();
    assert_eq!(unsafe { ember_bsdf_init(8, b.as_mut_ptr()) }, Bad);
    assert!(last_error().contains("kind 8 is not an EmberBsdfKind"), "{}", last_error());
    assert_eq!(unsafe { ember_light_init(0, std::ptr::null_mut()) }, Null);
    assert!(failures.is_empty(), "{} of the cases failed:\n{}", failures.len(), failures.join("\n"));
}

/// The Rust-side description is checked the same way (the counts C cannot get wrong).
#[test]
fn rust_descriptions_with_per_vertex_arrays_of_the_wrong_length_are_refused() {
    let a = arrays();
    let desc = ember_capi::SceneDesc {
        positions: a.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
        normals: vec![[0.0, 1.0, 0.0]; 3],
        triangles: vec![[0, 1, 2]],
        triangle_materials: vec![0],
        materials: vec![ember_capi::MaterialDesc::Diffuse([0.5; 3])],
        camera: a.camera,
        ..Default::default()
    };
    let e = ember_capi::SceneData::from_desc(&desc).unwrap_err();
    assert_eq!((e.status, e.message.as_str()), (EmberStatus::InvalidArgument, "3 normals for 8 positions (give none or one per position)"));
}

static THREADS: Mutex<Option<HashSet<ThreadId>>> = Mutex::new(None);

extern "C-unwind" fn miss(_: *mut c_void, _: *const EmberRay, _: *mut EmberHit) -> bool {
    THREADS.lock().unwrap().get_or_insert_with(HashSet::new).insert(std::thread::current().id());
    false
}

extern "C-unwind" fn clear(_: *mut c_void, _: *const EmberRay) -> bool {
    false
}

/// One pool per renderer: four `ember_render_passes` calls on two threads run on the
/// same two threads (a pool per call started new ones every time: 4 were seen).
#[test]
fn render_passes_reuses_the_renderers_threads() {
    let (mut scene, mut r) = (0, 0);
    let name = CString::new("cornell-box").unwrap();
    assert_eq!(unsafe { ember_scene_builtin(name.as_ptr(), 16, 16, &mut scene) }, EmberStatus::Ok);
    let est = CString::new("pt").unwrap();
    let settings = EmberRenderSettings {
        estimator: est.as_ptr(),
        seed: 1,
        max_depth: -1,
        threads: 2,
        light_paths: 0,
        connections: 0,
        radius_footprints: 0.0,
        options: std::ptr::null(),
    };
    let callbacks = EmberRayCallbacks { user_data: std::ptr::null_mut(), intersect: Some(miss), occluded: Some(clear) };
    assert_eq!(unsafe { ember_renderer_create(scene, &settings, &callbacks, &mut r) }, EmberStatus::Ok);
    for _ in 0..4 {
        assert_eq!(ember_render_passes(r, 1), EmberStatus::Ok);
    }
    let seen = THREADS.lock().unwrap().as_ref().map_or(0, HashSet::len);
    assert!((1..=2).contains(&seen), "4 calls on 2 threads ran on {seen} threads");
    assert_eq!(ember_renderer_destroy(r), EmberStatus::Ok);
    assert_eq!(ember_scene_destroy(scene), EmberStatus::Ok);
}
