//! SPCBPT's model file (`core/src/estimators/spcbpt/model_file.rs`, issue 22) never
//! panics on arbitrary bytes, and what it accepts is canonical and usable: decoding then
//! encoding gives the input back, and both trees reach a leaf for any feature (a tree
//! with a cycle would loop forever here). Each input is tried as given and again with its
//! checksum recomputed, so mutations reach the structural checks behind the checksum.
//! Seeded with models `ember train` wrote for the built-in box (`seeds/model_file/`).
#![no_main]

use std::sync::OnceLock;

use ember_core::estimators::spcbpt::Model;
use ember_core::scene::Scene;
use ember_core::subspace::SubpathFeature;
use glam::Vec3;
use libfuzzer_sys::fuzz_target;

fn scene() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| ember_core::scene::builtin::cornell_box(8, 8).build().expect("built-in box").0)
}

fn check(bytes: &[u8]) {
    let Ok(model) = Model::decode(bytes, scene()) else { return };
    assert_eq!(model.encode(), bytes, "an accepted model re-encodes to its bytes");
    let c = &model.classifier;
    for (p, n, w) in [(Vec3::ZERO, Vec3::Y, Vec3::X), (Vec3::splat(1e30), -Vec3::Z, Vec3::splat(f32::NAN)), (Vec3::new(-0.3, 0.9, 0.1), Vec3::X, Vec3::Y)] {
        let f = SubpathFeature::new(p, n, w);
        assert!(c.eye.classify(&f) < c.n_eye);
        assert!(c.light.classify(&f) < c.n_light_surface);
    }
}

fuzz_target!(|data: &[u8]| {
    check(data);
    if data.len() > 8 {
        let mut fixed = data[..data.len() - 8].to_vec();
        let sum = ember_core::fnv::fnv1a(&fixed);
        fixed.extend_from_slice(&sum.to_le_bytes());
        check(&fixed);
    }
});
