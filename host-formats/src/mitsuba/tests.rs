//! Loading tests: the suite's scenes, transforms, parameters, meshes, shapes.

use std::path::{Path, PathBuf};
use std::time::Duration;

use glam::Vec3;

use ember_core::scene::builtin;
use ember_core::scene::{Scene, SceneGeometry, Triangle};

use super::positions::Positions;
use super::{LoadOptions, LoadedScene, Loc, Progress, SceneFileError, load_positions, load_scene};

pub(super) fn suite_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes")
}

/// A fresh directory for one test's files.
pub(super) fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ember-mitsuba-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// A camera and film every test scene can use.
pub(super) const SENSOR: &str = r#"<sensor type="perspective"><float name="fov" value="45"/>
<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/><rfilter type="box"/></film></sensor>"#;

/// Write `body` inside `<scene>` (with [`SENSOR`]) to `dir/scene.xml` and load it.
pub(super) fn load_body(dir: &Path, body: &str, options: &LoadOptions) -> Result<LoadedScene, SceneFileError> {
    let text = format!("<scene version=\"3.0.0\">\n{SENSOR}\n{body}\n</scene>\n");
    let path = dir.join("scene.xml");
    std::fs::write(&path, text).expect("write scene");
    load_scene(&path, options)
}

pub(super) fn build(loaded: LoadedScene) -> (Scene, SceneGeometry) {
    let (scene, geometry, _) = loaded.builder.build().expect("scene builds");
    (scene, geometry)
}

fn tri_normal(t: &Triangle) -> Vec3 {
    (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize()
}

/// (scene, width, height, max_depth, spp)
type Expected = (&'static str, u32, u32, Option<i32>, Option<u32>);

#[test]
fn every_suite_scene_loads_with_sensible_counts() {
    let expected: [Expected; 9] = [
        ("cornell-box", 256, 256, Some(30), Some(64)),
        ("veach-bidir", 320, 320, Some(7), Some(64)),
        ("veach-mis", 384, 216, Some(3), Some(64)),
        ("ajar", 320, 240, Some(-1), None),
        ("caustic", 320, 240, Some(-1), None),
        ("enclosed", 320, 240, Some(-1), None),
        ("glossy", 320, 240, Some(-1), None),
        ("spot_mirror", 320, 240, Some(-1), None),
        ("window_env", 320, 240, Some(-1), None),
    ];
    let found = std::fs::read_dir(suite_dir()).expect("suite dir").filter(|e| e.as_ref().is_ok_and(|e| e.path().join("scene.xml").exists())).count();
    assert_eq!(found, expected.len(), "every suite scene is listed here");
    for (name, w, h, depth, spp) in expected {
        let path = suite_dir().join(name).join("scene.xml");
        let loaded = load_scene(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((loaded.width, loaded.height), (w, h), "{name}");
        assert_eq!(loaded.max_depth, depth, "{name}");
        assert_eq!(loaded.spp, spp, "{name}");
        assert!(loaded.warnings.is_empty(), "{name}: unexpected warnings {:?}", loaded.warnings);
        let (scene, geometry) = build(loaded);
        assert_eq!((scene.camera.width(), scene.camera.height()), (w, h), "{name}");
        assert!(!scene.lights.is_empty(), "{name} has no light");
        assert!(!geometry.triangles.is_empty(), "{name} has no triangles");
        assert!(scene.lights.iter().all(|l| l.power() > 0.0), "{name}: a dark light");
    }
}

#[test]
fn suite_scenes_have_the_expected_contents() {
    let load = |name: &str| build(load_scene(&suite_dir().join(name).join("scene.xml"), &LoadOptions::default()).unwrap());
    // Cornell box: 5 walls (2 triangles each), 2 boxes (12 each), 1 light (2).
    let (scene, g) = load("cornell-box");
    assert_eq!((g.triangles.len(), g.spheres.len(), scene.lights.len()), (36, 0, 2));
    // veach-mis: three emitting spheres, four plates (cubes) and two walls.
    let (scene, g) = load("veach-mis");
    assert_eq!((g.triangles.len(), g.spheres.len(), scene.lights.len()), (4 * 12 + 4, 3, 3));
    // veach-bidir: 12 OBJ meshes (11540 triangles) and two emitting rectangles.
    let (scene, g) = load("veach-bidir");
    assert_eq!(scene.lights.len(), 4);
    assert_eq!(g.triangles.len(), 11540 + 4);
    assert!(g.triangles.iter().any(|t| t.n.is_some()) && g.triangles.iter().any(|t| t.n.is_none()), "face_normals honoured");
    // enclosed: twelve shaded lights.
    let (scene, _) = load("enclosed");
    assert_eq!(scene.lights.len(), 24);
    // spot_mirror: one spot light, a sphere; window_env: one environment.
    let (scene, g) = load("spot_mirror");
    assert_eq!((scene.lights.len(), g.spheres.len()), (1, 1));
    assert!(scene.lights[0].is_delta_position());
    let (scene, _) = load("window_env");
    assert_eq!(scene.lights.len(), 1);
    assert!(scene.lights[0].is_infinite());
    // glossy: the bulb has no bsdf and emits: Mitsuba 3's default for an emitter, a black
    // diffuse (seen failing with the grey 0.5 every shape without a BSDF had before).
    let (scene, g) = load("glossy");
    assert_eq!(g.spheres.len(), 1);
    let bulb = format!("{:?}", scene.materials[g.spheres[0].material as usize]);
    assert_eq!(bulb, format!("{:?}", ember_core::bsdf::Material::diffuse(ember_core::spectrum::Rgb::ZERO)));
}

#[test]
fn cornell_box_from_xml_equals_the_builtin_one() {
    let loaded = load_scene(&suite_dir().join("cornell-box/scene.xml"), &LoadOptions::default()).unwrap();
    // The loader builds camera-centred; shift back to the file's world frame.
    let origin = loaded.world_origin.as_vec3();
    let (xml, xml_geo) = build(loaded);
    let (builtin, builtin_geo, _) = builtin::cornell_box(256, 256).build().unwrap();
    assert_eq!(xml_geo.triangles.len(), builtin_geo.triangles.len());
    assert_eq!(xml.lights.len(), builtin.lights.len());
    // Match triangles as sets: same vertices (same cyclic order, so same winding) within
    // 1e-5, same material, same emission.
    let close = |a: &Triangle, b: &Triangle| (0..3).any(|r| (0..3).all(|i| (a.p[i] - (b.p[(i + r) % 3] + origin)).abs().max_element() < 1e-5));
    let mut unmatched: Vec<&Triangle> = xml_geo.triangles.iter().collect();
    for t in &builtin_geo.triangles {
        let pos = unmatched.iter().position(|u| close(t, u)).unwrap_or_else(|| panic!("builtin triangle {t:?} not in the XML scene"));
        let u = unmatched.swap_remove(pos);
        let (ma, mb) = (&builtin.materials[t.material as usize], &xml.materials[u.material as usize]);
        assert_eq!(format!("{ma:?}"), format!("{mb:?}"));
        assert_eq!(t.emitter.is_some(), u.emitter.is_some());
        if let (Some(a), Some(b)) = (t.emitter, u.emitter) {
            let (pa, pb) = (builtin.lights[a as usize].power(), xml.lights[b as usize].power());
            assert!((pa - pb).abs() <= 1e-5 * pa, "{pa} vs {pb}");
        }
    }
    // Same camera: same rays through the same pixels.
    for film in [glam::Vec2::new(0.5, 0.5), glam::Vec2::new(200.25, 17.0), glam::Vec2::new(255.9, 255.9)] {
        let (a, b) = (builtin.camera.generate_ray(film), xml.camera.generate_ray(film));
        assert!((a.origin - (b.origin + origin)).length() < 1e-6 && (a.dir - b.dir).length() < 1e-6, "{a:?} vs {b:?}");
    }
}

#[test]
fn transforms_compose_in_the_order_written() {
    let dir = temp_dir("order");
    // scale 2, then rotate 90° about y, then translate (1, 0, 0): the corner (1, 1, 0)
    // goes to (2, 2, 0), then (0, 2, −2) (rotation about y maps x to −z), then (1, 2, −2).
    let body = r#"<shape type="rectangle"><transform name="to_world">
        <scale value="2"/><rotate y="1" angle="90"/><translate x="1"/></transform></shape>"#;
    let (_, g) = build(load_body(&dir, body, &LoadOptions::default()).unwrap());
    let want = Vec3::new(1.0, 2.0, -2.0);
    assert!(g.triangles.iter().flat_map(|t| t.p).any(|p| (p - want).length() < 1e-5), "{:?}", g.triangles);
    // The normal +z rotates to +x.
    assert!((tri_normal(&g.triangles[0]) - Vec3::X).length() < 1e-5);

    // A row-major matrix: the last column is the translation; composition with a later
    // translate adds to it; a lookat is a rigid frame at its origin.
    let body = r#"<shape type="rectangle"><transform name="to_world">
        <matrix value="1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1"/><scale x="3" y="1" z="1"/></transform></shape>"#;
    let (_, g) = build(load_body(&dir, body, &LoadOptions::default()).unwrap());
    // (1, 1, 0) → (6, 7, 7) → scaled by x 3 → (18, 7, 7).
    assert!(g.triangles.iter().flat_map(|t| t.p).any(|p| (p - Vec3::new(18.0, 7.0, 7.0)).length() < 1e-4));
}

#[test]
fn lookat_camera_follows_mitsuba() {
    let dir = temp_dir("lookat");
    let text = r#"<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="90"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0 0 0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/><rfilter type="box"/></film></sensor>
        <emitter type="point"><point name="position" x="0" y="3" z="0"/></emitter>
        <shape type="cube"/></scene>"#;
    std::fs::write(dir.join("s.xml"), text).unwrap();
    let loaded = load_scene(&dir.join("s.xml"), &LoadOptions::default()).unwrap();
    // Built camera-centred: the camera sits at the render frame's origin, the file's
    // world origin at −(0, 0, 5), and the point light with it.
    assert!((loaded.world_origin - glam::DVec3::new(0.0, 0.0, 5.0)).length() < 1e-12, "{:?}", loaded.world_origin);
    let (scene, _) = build(loaded);
    let cam = &scene.camera;
    assert!(cam.position().length() < 1e-6, "{:?}", cam.position());
    let light = scene.lights[0].sample_li(Vec3::new(0.0, 3.0, -4.0), glam::Vec2::ZERO).unwrap();
    assert!((light.p - Vec3::new(0.0, 3.0, -5.0)).length() < 1e-6 && (light.wi + Vec3::Z).length() < 1e-5, "{light:?}");
    assert!((cam.forward() - Vec3::NEG_Z).length() < 1e-6);
    // Camera +x is cross(up, forward) = world −x, and it is the image's left.
    let left = cam.generate_ray(glam::Vec2::new(0.0, 2.0)).dir;
    assert!(left.x < -0.5, "{left:?}");
}

#[test]
fn parameters_substitute_everywhere_and_overrides_win() {
    let dir = temp_dir("params");
    let body = r#"<default name="kind" value="diffuse"/><default name="refl" value="0.25"/><default name="shape" value="cube"/>
        <shape type="$shape"><bsdf type="$kind"><rgb name="reflectance" value="${refl}, 0.5, $refl"/></bsdf></shape>
        <emitter type="constant"/>"#;
    let loaded = load_body(&dir, body, &LoadOptions::default()).unwrap();
    let (scene, g) = build(loaded);
    assert_eq!(g.triangles.len(), 12);
    let m = format!("{:?}", scene.materials[0]);
    assert!(m.contains("r: 0.25, g: 0.5, b: 0.25"), "{m}");

    let options = LoadOptions { defaults: vec![("refl".into(), "0.75".into()), ("unused".into(), "1".into())], ..Default::default() };
    let loaded = load_body(&dir, body, &options).unwrap();
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(loaded.warnings[0].contains("unused"));
    let (scene, _) = build(loaded);
    let m = format!("{:?}", scene.materials[0]);
    assert!(m.contains("r: 0.75, g: 0.5, b: 0.75"), "{m}");

    // A parameter without a <default> comes from the caller; the film size too.
    let body = r#"<shape type="$shape"/><emitter type="constant"/>"#;
    let options = LoadOptions { defaults: vec![("shape".into(), "sphere".into())], width: Some(20), height: Some(10) };
    let loaded = load_body(&dir, body, &options).unwrap();
    assert_eq!((loaded.width, loaded.height), (20, 10));
    let (scene, g) = build(loaded);
    assert_eq!((g.spheres.len(), scene.camera.width(), scene.camera.height()), (1, 20, 10));

    // Suite scene: -D resx/resy and max_depth.
    let options = LoadOptions { defaults: vec![("resx".into(), "64".into()), ("max_depth".into(), "5".into())], ..Default::default() };
    let loaded = load_scene(&suite_dir().join("veach-mis/scene.xml"), &options).unwrap();
    assert_eq!((loaded.width, loaded.height, loaded.max_depth), (64, 216, Some(5)));
}

#[test]
fn rectangle_flip_normals_reverses_the_normal() {
    let dir = temp_dir("flip");
    let normal = |flip: &str| {
        let body = format!(r#"<shape type="rectangle"><boolean name="flip_normals" value="{flip}"/><emitter type="area"/></shape>"#);
        let (scene, g) = build(load_body(&dir, &body, &LoadOptions::default()).unwrap());
        assert_eq!(scene.lights.len(), 2);
        let n: Vec<Vec3> = g.triangles.iter().map(tri_normal).collect();
        assert!(n.iter().all(|v| (*v - n[0]).length() < 1e-6));
        n[0]
    };
    assert!((normal("false") - Vec3::Z).length() < 1e-6);
    assert!((normal("true") + Vec3::Z).length() < 1e-6);
    // A mirroring to_world keeps Mitsuba's normal (inverse transpose of +z = +z here).
    let body = r#"<shape type="rectangle"><transform name="to_world"><scale x="-1"/></transform></shape><emitter type="constant"/>"#;
    let (_, g) = build(load_body(&dir, body, &LoadOptions::default()).unwrap());
    assert!(g.triangles.iter().all(|t| (tri_normal(t) - Vec3::Z).length() < 1e-6));
}

#[test]
fn disk_is_a_fine_fan_and_sphere_takes_its_transform() {
    let dir = temp_dir("disk");
    let body = r#"<shape type="disk"><transform name="to_world"><scale value="2"/><translate z="1"/></transform></shape>
        <shape type="sphere"><point name="center" x="1" y="0" z="0"/><float name="radius" value="0.5"/>
          <transform name="to_world"><scale value="3"/><rotate z="1" angle="90"/><translate x="10"/></transform></shape>
        <emitter type="directional"><vector name="direction" x="0" y="0" z="-1"/></emitter>"#;
    let (_, g) = build(load_body(&dir, body, &LoadOptions::default()).unwrap());
    assert_eq!(g.triangles.len(), super::shapes::DISK_SEGMENTS as usize);
    let area: f32 = g.triangles.iter().map(|t| 0.5 * (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).length()).sum();
    let n = super::shapes::DISK_SEGMENTS as f32;
    assert!((area - 4.0 * 0.5 * n * (std::f32::consts::TAU / n).sin()).abs() < 1e-3, "{area}");
    assert!(g.triangles.iter().all(|t| (tri_normal(t) - Vec3::Z).length() < 1e-5 && (t.p[0].z - 1.0).abs() < 1e-6));
    // Centre (1,0,0) → ×3 → (3,0,0) → rotate z 90° → (0,3,0) → (10,3,0); radius 1.5.
    let s = g.spheres[0];
    assert!((s.center - Vec3::new(10.0, 3.0, 0.0)).length() < 1e-5 && (s.radius - 1.5).abs() < 1e-6, "{s:?}");
}

/// A small mesh: a unit square as a quad plus a triangle, with normals.
fn small_mesh() -> (Vec<[f32; 6]>, Vec<Vec<u32>>) {
    let v = vec![
        [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        [1.0, 1.0, 0.0, 0.0, 0.6, 0.8],
        [0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        [0.5, 0.5, 1.0, 1.0, 0.0, 0.0],
    ];
    (v, vec![vec![0, 1, 2, 3], vec![1, 4, 2]])
}

fn write_ply(path: &Path, binary: bool) {
    let (v, f) = small_mesh();
    let format = if binary { "binary_little_endian" } else { "ascii" };
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment test\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        v.len(),
        f.len()
    )
    .into_bytes();
    for row in &v {
        if binary {
            row.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
        } else {
            out.extend_from_slice(format!("{} {} {} {} {} {}\n", row[0], row[1], row[2], row[3], row[4], row[5]).as_bytes());
        }
    }
    for face in &f {
        if binary {
            out.push(face.len() as u8);
            face.iter().for_each(|i| out.extend_from_slice(&(*i as i32).to_le_bytes()));
        } else {
            let idx: Vec<String> = face.iter().map(|i| i.to_string()).collect();
            out.extend_from_slice(format!("{} {}\n", face.len(), idx.join(" ")).as_bytes());
        }
    }
    std::fs::write(path, out).unwrap();
}

#[test]
fn ply_ascii_and_binary_readers_agree() {
    let dir = temp_dir("ply");
    write_ply(&dir.join("a.ply"), false);
    write_ply(&dir.join("b.ply"), true);
    let a = super::ply::parse(&std::fs::read(dir.join("a.ply")).unwrap()).unwrap();
    let b = super::ply::parse(&std::fs::read(dir.join("b.ply")).unwrap()).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.triangles, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
    assert_eq!(a.normals.as_ref().map(Vec::len), Some(5));
    // Through the scene: normals transformed, kept unless face_normals.
    let body = |file: &str, face: bool| {
        format!(
            r#"<shape type="ply"><string name="filename" value="{file}"/><boolean name="face_normals" value="{face}"/>
            <transform name="to_world"><translate x="1"/></transform></shape><emitter type="constant"/>"#
        )
    };
    let (_, g) = build(load_body(&dir, &body("b.ply", false), &LoadOptions::default()).unwrap());
    assert_eq!(g.triangles.len(), 3);
    assert!((g.triangles[0].p[1] - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6);
    let n = g.triangles[0].n.expect("vertex normals");
    assert!((n[2] - Vec3::new(0.0, 0.6, 0.8)).length() < 1e-6);
    let (_, g) = build(load_body(&dir, &body("a.ply", true), &LoadOptions::default()).unwrap());
    assert!(g.triangles.iter().all(|t| t.n.is_none()));
}

#[test]
fn obj_meshes_load_with_vertex_or_face_normals() {
    let dir = temp_dir("obj");
    std::fs::write(dir.join("n.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0.6 0.8\nf 1//1 2//1 3//2 4//1\n").unwrap();
    // No normals: Mitsuba recomputes smooth ones (here all +z).
    std::fs::write(dir.join("plain.obj"), "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\no b\nv 0 0 1\nv 1 0 1\nv 1 1 1\nf 4 5 6\n").unwrap();
    let body = |file: &str, face: bool, flip: bool| {
        format!(
            r#"<shape type="obj"><string name="filename" value="{file}"/><boolean name="face_normals" value="{face}"/>
            <boolean name="flip_normals" value="{flip}"/></shape><emitter type="constant"/>"#
        )
    };
    let (_, g) = build(load_body(&dir, &body("n.obj", false, false), &LoadOptions::default()).unwrap());
    assert_eq!(g.triangles.len(), 2);
    assert!(g.triangles.iter().flat_map(|t| t.n.unwrap()).any(|n| (n - Vec3::new(0.0, 0.6, 0.8)).length() < 1e-6));
    let (_, g) = build(load_body(&dir, &body("n.obj", true, false), &LoadOptions::default()).unwrap());
    assert!(g.triangles.iter().all(|t| t.n.is_none() && (tri_normal(t) - Vec3::Z).length() < 1e-6));
    let (_, g) = build(load_body(&dir, &body("plain.obj", false, true), &LoadOptions::default()).unwrap());
    assert_eq!(g.triangles.len(), 2, "objects are merged");
    for t in &g.triangles {
        assert!((tri_normal(t) + Vec3::Z).length() < 1e-6, "flipped winding");
        assert!(t.n.unwrap().iter().all(|n| (*n + Vec3::Z).length() < 1e-6), "flipped recomputed normals");
    }
}

#[test]
fn degenerate_triangles_are_reported() {
    let dir = temp_dir("degenerate");
    std::fs::write(dir.join("d.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n").unwrap();
    let body = r#"<shape type="obj"><string name="filename" value="d.obj"/></shape>
        <shape type="rectangle"><transform name="to_world"><scale y="0"/></transform></shape><emitter type="constant"/>"#;
    let loaded = load_body(&dir, body, &LoadOptions::default()).unwrap();
    assert_eq!(loaded.warnings.len(), 2, "{:?}", loaded.warnings);
    assert!(loaded.warnings[0].contains("1 of 2 triangles have zero area"), "{:?}", loaded.warnings);
    assert!(loaded.warnings[1].contains("2 of 2 triangles have zero area"), "{:?}", loaded.warnings);
    let (_, g) = build(loaded);
    assert_eq!(g.triangles.len(), 1);
}

#[test]
fn materials_follow_mitsuba_parameters() {
    let dir = temp_dir("materials");
    let body = r#"
        <bsdf type="roughconductor" id="cu"><string name="material" value="Cu"/><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/></bsdf>
        <bsdf type="dielectric" id="water"><string name="int_ior" value="water"/><float name="ext_ior" value="1"/></bsdf>
        <bsdf type="twosided" id="two"><ref id="cu"/></bsdf>
        <shape type="cube"><ref id="cu"/></shape>
        <shape type="cube"><ref id="cu"/></shape>
        <shape type="cube"><ref name="bsdf" id="water"/></shape>
        <shape type="cube"><ref id="two"/></shape>
        <shape type="cube"><bsdf type="roughdielectric"><float name="alpha" value="0.3"/><spectrum name="specular_transmittance" value="0.5"/></bsdf></shape>
        <emitter type="spot"><rgb name="intensity" value="1 2 3"/><float name="cutoff_angle" value="30"/></emitter>"#;
    let loaded = load_body(&dir, body, &LoadOptions::default()).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let (scene, g) = build(loaded);
    assert_eq!(scene.materials.len(), 4, "a ref'd bsdf is one material");
    assert_eq!(g.triangles[0].material, g.triangles[12].material);
    let m: Vec<String> = scene.materials.iter().map(|m| format!("{m:?}")).collect();
    assert!(m[0].contains("RoughConductor") && m[0].contains("Ggx") && m[0].contains("0.201005"), "{}", m[0]);
    assert!(m[1].contains("Dielectric") && m[1].contains("1.333"), "{}", m[1]);
    assert!(m[2].contains("RoughConductor") && m[2].contains("two_sided: true"), "{}", m[2]);
    assert!(m[3].contains("RoughDielectric") && m[3].contains("Beckmann"), "{}", m[3]);
    // The unused id'd twosided's inner ref does not create a material of its own.
    assert_eq!(scene.lights.len(), 1);
}

#[test]
fn accepted_but_unmodelled_things_warn() {
    let dir = temp_dir("warn");
    let text = r#"<scene version="3.0.0">
        <integrator type="volpath"><integer name="max_depth" value="4"/></integrator>
        <sensor type="perspective"><float name="fov" value="45"/>
          <sampler type="stratified"><integer name="sample_count" value="16"/></sampler>
          <film type="hdrfilm"><string name="file_format" value="png"/></film></sensor>
        <bsdf type="diffuse" id="never"/>
        <shape type="cube"/><emitter type="constant"/></scene>"#;
    std::fs::write(dir.join("s.xml"), text).unwrap();
    let loaded = load_scene(&dir.join("s.xml"), &LoadOptions::default()).unwrap();
    assert_eq!((loaded.width, loaded.height, loaded.spp, loaded.max_depth), (768, 576, Some(16), Some(4)));
    let w = loaded.warnings.join("\n");
    for needle in ["\"volpath\" is rendered as \"path\"", "stratified", "png", "never"] {
        assert!(w.contains(needle), "no warning about {needle}: {w}");
    }
}

/// Camera-centred frame at load (issue 8): the Cornell box translated by (1e5, −5e4,
/// 2.5e4), camera included, loads to the same f32 triangles as the untranslated file
/// (within 1e-5; the light's 0.02 gap below the ceiling survives), because transforms
/// are composed with the translation by minus the camera position in f64 before rounding.
/// Without the frame, f32 world coordinates at 1e5 are 0.0078 apart.
#[test]
fn far_translated_scene_loads_camera_centred_without_losing_precision() {
    let path = suite_dir().join("cornell-box/scene.xml");
    let text = std::fs::read_to_string(&path).unwrap();
    let shifted = text.replace("</transform>", "<translate x=\"100000\" y=\"-50000\" z=\"25000\"/></transform>");
    assert!(shifted.len() > text.len());
    let near = crate::mitsuba::load_scene_from_str(&text, &path, &LoadOptions::default()).unwrap();
    let far = crate::mitsuba::load_scene_from_str(&shifted, &path, &LoadOptions::default()).unwrap();
    assert!((far.world_origin - near.world_origin - glam::DVec3::new(1e5, -5e4, 2.5e4)).length() < 1e-9, "{:?}", far.world_origin);
    let (_, a) = build(near);
    let (_, b) = build(far);
    assert_eq!(a.triangles.len(), b.triangles.len());
    for (s, t) in a.triangles.iter().zip(&b.triangles) {
        for i in 0..3 {
            assert!((s.p[i] - t.p[i]).abs().max_element() < 1e-5, "{:?} vs {:?}", s.p, t.p);
        }
    }
}

/// Regression: a width override alone kept the file's height (stretching the image); one
/// side alone now keeps the film's aspect ratio, and a derived side past the limit is
/// refused. Injected bug checked: `(width.unwrap_or(w), height.unwrap_or(h))` in
/// `film_size` fails here.
#[test]
fn one_film_side_keeps_the_aspect_ratio() {
    let dir = temp_dir("aspect");
    let body = r#"<shape type="cube"/><emitter type="constant"/>"#;
    for ((width, height), expected) in [((Some(16), None), (16, 12)), ((None, Some(3)), (4, 3)), ((Some(5), Some(5)), (5, 5)), ((None, None), (8, 6))] {
        let loaded = load_body(&dir, body, &LoadOptions { width, height, ..Default::default() }).unwrap();
        assert_eq!((loaded.width, loaded.height), expected, "{width:?} {height:?}");
    }
    let e = load_body(&dir, body, &LoadOptions { height: Some(65536), ..Default::default() }).unwrap_err();
    assert!(e.to_string().contains("the film would be 87381x65536") && e.to_string().contains("give both"), "{e}");
}

/// A scene of `n` small spheres in a row in front of [`SENSOR`]'s camera, and a light.
pub(super) fn spheres(n: usize) -> String {
    let mut text = format!("<scene version=\"3.0.0\">\n{SENSOR}\n<emitter type=\"constant\"/>\n");
    for i in 0..n {
        text.push_str(&format!(
            "<shape type=\"sphere\"><point name=\"center\" x=\"{}\" y=\"0\" z=\"5\"/><float name=\"radius\" value=\"0.01\"/></shape>\n",
            i as f64 * 0.03
        ));
    }
    text.push_str("</scene>\n");
    text
}

/// Issue 51: loading was quadratic in the file's size (10 000 spheres took 22 s), because
/// every element's and attribute's place was resolved into a line and column (roxmltree's
/// `text_pos_at`, a scan from the start) although only an error shows one. Places are
/// byte offsets now, resolved when a message needs them: a valid scene without warnings
/// resolves none, and an error resolves only its own. Injected bug checked: `Parser::loc`
/// resolving its offset at once (`self.positions.line_col(..)`, as `text_pos_at` was
/// called) resolves 14 020 places here and fails.
#[test]
fn a_valid_scene_resolves_no_places() {
    let text = spheres(2000);
    let path = Path::new("/nowhere/scene.xml");
    let positions = Positions::new(&text);
    let mut quiet = Progress::to(path, Duration::from_secs(3600), Duration::from_secs(3600), Box::new(std::io::sink()));
    let loaded = load_positions(&positions, path, &LoadOptions::default(), &mut quiet).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(positions.resolutions(), 0, "places resolved while loading a valid scene");
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let (_, g) = build(loaded);
    assert_eq!(g.spheres.len(), 2000);
    // The last sphere's radius made invalid: one place resolved, at the right line.
    let bad = text.replace("value=\"0.01\"/></shape>\n</scene>", "value=\"-1\"/></shape>\n</scene>");
    let positions = Positions::new(&bad);
    let e = load_positions(&positions, path, &LoadOptions::default(), &mut quiet).unwrap_err();
    assert_eq!((e.line, positions.resolutions()), (Some(2004), 1), "{e}");
    assert!(e.message.contains("sphere `radius` must be positive"), "{e}");
}

/// The lazily resolved places equal roxmltree's `text_pos_at` (the parser's positions
/// before issue 51) for every element, attribute, attribute value and text node of a
/// file with multi-byte characters, CRLF line ends and a long line, and for its end.
/// Injected bugs checked: counting the column in bytes (`end - start`) fails after a
/// `☃☃` comment (column 17 for 13); `partition_point(|&s| s < offset)` (a node at the
/// start of a line counted on the line before) fails at `<scene`, which starts line 2.
#[test]
fn lazy_positions_equal_roxmltree_ones() {
    let cornell = std::fs::read_to_string(suite_dir().join("cornell-box/scene.xml")).unwrap();
    let text = cornell.replacen("<scene", "<!-- é€😀 -->\r\n<scene", 1).replacen("<shape", "<!-- ☃☃ --><shape", 3).replace("<bsdf", "\r\n  <bsdf");
    let doc = roxmltree::Document::parse(&text).unwrap();
    let positions = Positions::new(&text);
    let mut offsets = vec![0, text.len()];
    for node in doc.descendants() {
        offsets.push(node.range().start);
        for a in node.attributes() {
            offsets.extend([a.range().start, a.range_value().start]);
        }
    }
    assert!(offsets.len() > 200, "{}", offsets.len());
    for o in offsets {
        let p = doc.text_pos_at(o);
        assert_eq!(positions.line_col(Loc::Offset(o)), (p.row, p.col), "offset {o}");
        assert_eq!(positions.line(Loc::Offset(o)), p.row, "offset {o}");
    }
}

/// A sink that tests can read back.
#[derive(Clone, Default)]
struct Shared(std::rc::Rc<std::cell::RefCell<Vec<u8>>>);

impl std::io::Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.borrow_mut().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Issue 51: a large scene loaded for many seconds without a word. Past a second,
/// "loading <file>: N of M shapes" lines appear on stderr (at most one a second); a
/// scene that loads sooner prints nothing. Injected bugs checked: `Progress::due`
/// without its `quiet_for` test prints for the quick load below (first assertion);
/// `shape_done` never called from `instantiate` leaves out the "64 of 130" line.
#[test]
fn progress_is_printed_only_for_slow_loads() {
    let text = spheres(130);
    let path = Path::new("/nowhere/big.xml");
    let quiet = Shared::default();
    let mut progress = Progress::to(path, Duration::from_secs(1), Duration::from_secs(1), Box::new(quiet.clone()));
    load_positions(&Positions::new(&text), path, &LoadOptions::default(), &mut progress).unwrap();
    assert!(quiet.0.borrow().is_empty(), "a quick load printed {:?}", String::from_utf8_lossy(&quiet.0.borrow()));
    // As if every moment were a second past the start.
    let log = Shared::default();
    let mut progress = Progress::to(path, Duration::ZERO, Duration::ZERO, Box::new(log.clone()));
    load_positions(&Positions::new(&text), path, &LoadOptions::default(), &mut progress).unwrap();
    let printed = String::from_utf8(log.0.borrow().clone()).unwrap();
    let lines: Vec<&str> = printed.lines().map(|l| l.split(" (").next().unwrap_or("")).collect();
    assert_eq!(
        lines,
        [
            "loading /nowhere/big.xml: XML read, 130 shapes to build",
            "loading /nowhere/big.xml: 64 of 130 shapes",
            "loading /nowhere/big.xml: 128 of 130 shapes",
            "loading /nowhere/big.xml: done, 130 shapes"
        ],
        "{printed}"
    );
    assert!(printed.lines().all(|l| l.ends_with(" s)")), "{printed}");
}
