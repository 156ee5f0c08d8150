//! SPCBPT's model file (`core/src/estimators/spcbpt/model_file.rs`, issue 22's `ember
//! train`): a trained model round-trips to the same bytes and the same pass images; every
//! truncation, every single-byte change and every structurally invalid model with a
//! valid checksum is refused with an error, never a panic or a silently different model.
//!
//! Injected bugs checked (each run once, reverted):
//! - `DecisionTree::from_raw_nodes` without the "children after the node" check: the
//!   self-referencing tree below is accepted (and `classify` would loop forever).
//! - `decode` without the checksum comparison: byte flips in Γ are accepted as a
//!   different model.

use ember_core::estimators::EstimatorConfig;
use ember_core::estimators::spcbpt::Model;
use ember_core::estimators::spcbpt::model_file::{MAGIC, ModelError, VERSION};
use ember_core::scene::Scene;
use ember_core::transport::{MaxDepth, RenderParams};
use ember_tests::render::{Passes, spcbpt_config, spcbpt_model};
use ember_tests::scenes::cornell;
use ember_tests::tracer::BruteForce;

fn trained() -> (Scene, BruteForce, RenderParams, Model) {
    let (scene, geometry, _) = cornell(12, 12).build().expect("scene");
    let tracer = BruteForce::new(geometry);
    let params = RenderParams { max_depth: MaxDepth(5), seed: 4, ..Default::default() };
    let config = spcbpt_config(24, 6, 1500, 1500, 150, 0.2);
    let (model, _) = spcbpt_model(&scene, &tracer, &params, config);
    (scene, tracer, params, model)
}

fn with_checksum(mut body: Vec<u8>) -> Vec<u8> {
    // The file's checksum, recomputed (to build invalid models with valid checksums).
    let sum = ember_core::fnv::fnv1a(&body);
    body.extend_from_slice(&sum.to_le_bytes());
    body
}

#[test]
fn a_model_round_trips_to_the_same_bytes_and_images() {
    let (scene, tracer, params, model) = trained();
    assert!(model.caches_light_sources(), "the test model has light-source bins");
    let bytes = model.encode();
    let back = Model::decode(&bytes, &scene).expect("decodes");
    assert_eq!(back.encode(), bytes);

    let config = spcbpt_config(24, 6, 1500, 1500, 150, 0.2);
    let mut trained_here = Passes::new(&scene, &tracer, &params, EstimatorConfig::Spcbpt(config));
    let mut loaded = Passes::new(&scene, &tracer, &params, EstimatorConfig::Lt);
    loaded.renderer = ember_core::estimators::Renderer::new(&scene, params, EstimatorConfig::Spcbpt(config)).unwrap();
    loaded.spcbpt().unwrap().use_model(back).expect("model fits the configuration");
    for pass in 0..2 {
        assert_eq!(trained_here.pass_image(pass).0, loaded.pass_image(pass).0, "pass {pass}");
    }
    // A model trained for another N is refused.
    let mut other_n = config;
    other_n.connections = 5;
    let mut r = ember_core::estimators::Renderer::new(&scene, params, EstimatorConfig::Spcbpt(other_n)).unwrap();
    let ember_core::estimators::Renderer::Spcbpt(s) = &mut r else { unreachable!() };
    assert!(s.use_model(model).unwrap_err().contains("connections"));
}

#[test]
fn truncated_and_altered_files_are_refused() {
    let (scene, _, _, model) = trained();
    let bytes = model.encode();
    // Every length in the header, then every 13th (each costs a checksum pass).
    for len in (0..64).chain((64..bytes.len()).step_by(13)) {
        let Err(e) = Model::decode(&bytes[..len], &scene) else { panic!("length {len} accepted") };
        assert!(matches!(e, ModelError::NotAModel | ModelError::Truncated | ModelError::Checksum), "length {len}: {e:?}");
    }
    // Bytes changed in turn (past the magic and version): every one of the header and
    // the trees' first nodes, then every 7th.
    for i in (12..128).chain((128..bytes.len()).step_by(7)) {
        let mut b = bytes.clone();
        b[i] ^= 0x5a;
        assert_eq!(Model::decode(&b, &scene).err(), Some(ModelError::Checksum), "byte {i}");
    }
    let mut future = bytes.clone();
    future[8..12].copy_from_slice(&(VERSION + 1).to_le_bytes());
    assert_eq!(Model::decode(&future, &scene).err(), Some(ModelError::Version(VERSION + 1)));
    assert_eq!(Model::decode(b"P3\n4 4\n", &scene).err(), Some(ModelError::NotAModel));
}

/// A change to a model's bytes (before its checksum is recomputed).
type Edit<'a> = Box<dyn Fn(&mut Vec<u8>) + 'a>;

/// Models whose checksum is right but whose content the estimator could not use.
#[test]
fn inconsistent_models_are_refused_with_what_is_wrong() {
    let (scene, _, _, model) = trained();
    let body = |b: &[u8]| b[..b.len() - 8].to_vec();
    let bytes = model.encode();
    let word = |b: &mut Vec<u8>, at: usize, v: u32| b[at..at + 4].copy_from_slice(&v.to_le_bytes());
    // Header words: magic (8), version, connections, n_eye, n_light_surface, n_light;
    // the eye tree's node count at 28, its first node at 32 (axis, threshold, child, label).
    let cases: Vec<(&str, Edit)> = vec![
        ("no eye or light subspaces", Box::new(move |b| word(b, 16, 0))),
        ("disagrees with the bins", Box::new(move |b| word(b, 24, u32::from_le_bytes(bytes[24..28].try_into().unwrap()) + 1))),
        // The root made an inner node whose children are itself: a loop in `classify`.
        (
            "children are missing or come before it",
            Box::new(|b| {
                word(b, 32, 0);
                word(b, 40, 0);
            }),
        ),
        ("axis the features do not have", Box::new(|b| word(b, 32, 9))),
        ("label past the subspace count", Box::new(|b| word(b, 44, 1_000_000))),
    ];
    let bytes = model.encode();
    for (needle, edit) in &cases {
        let mut b = body(&bytes);
        edit(&mut b);
        match Model::decode(&with_checksum(b), &scene) {
            Ok(_) => panic!("{needle}: accepted"),
            Err(e) => assert!(e.to_string().contains(needle), "{needle}: {e}"),
        }
    }
    // Γ's last value made negative, then NaN.
    for bad in [-1.0f32, f32::NAN] {
        let mut b = body(&bytes);
        let n = b.len();
        b[n - 4..].copy_from_slice(&bad.to_bits().to_le_bytes());
        let e = Model::decode(&with_checksum(b), &scene).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("Γ holds a negative or non-finite value"), "{e}");
    }
    // A scene with another number of lights cannot use the light-source bins.
    let (other, _, _) = ember_tests::scenes::cornell_with_delta_lights(12, 12).build().unwrap();
    assert_ne!(other.lights.len(), scene.lights.len());
    let e = Model::decode(&bytes, &other).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("another number of lights"), "{e}");
    assert_eq!(&bytes[..8], &MAGIC);
}
