//! Chunk outputs from bytes (`core/src/render/wire.rs`, issue 19): decoding arbitrary
//! bytes never panics, whatever the part and chunk their header names; what decodes is
//! stable (encoding it and decoding again gives the same bytes once more), and accepted
//! light paths are safe to walk: every path slice exists and every vertex's material and
//! light are the scene's (a vertex naming material 9 of a 4-material scene would panic in
//! the connection code). Seeded with real outputs of every phase of PT, LVCBPT, SPCBPT
//! (setup included), VCM and MVF on the 8 × 8 box, and light paths of LVCBPT, SPCBPT and
//! VCM on a 2 × 2 one (`seeds/wire_decode/`). Injected bug it caught: the light-path
//! check left out of `decode` (a vertex naming a material past the scene's reached
//! `is_connectible` within
//! a second of fuzzing).
#![no_main]

use std::sync::OnceLock;

use ember_core::render::wire::{Part, peek};
use ember_core::estimators::{ChunkOutput, PhaseData};
use ember_core::render::{Phase};
use ember_core::scene::Scene;
use libfuzzer_sys::fuzz_target;

fn scene() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| ember_core::scene::builtin::cornell_box(8, 8).build().expect("built-in box").0)
}

fuzz_target!(|data: &[u8]| {
    let Ok((part, id)) = peek(data) else { return };
    // The phase whose chunk 0 the header names (chunk = its items).
    let len = id.items.end.saturating_sub(id.items.start).max(1);
    let phase = Phase { name: "fuzz", id: id.phase, pass: id.pass, items: id.items.end, chunk: len, samples: false };
    let chunk = (id.items.start / len) as usize;
    let mut out = ChunkOutput::default();
    if out.decode(&phase, chunk, part, data, scene()).is_err() {
        return;
    }
    let mut again = Vec::new();
    out.encode(&phase, part, &mut again);
    let mut second = ChunkOutput::default();
    second.decode(&phase, chunk, part, &again, scene()).expect("re-encoded bytes decode");
    let mut third = Vec::new();
    second.encode(&phase, part, &mut third);
    assert_eq!(again, third, "decode ∘ encode is stable");
    if part == Part::State
        && let PhaseData::LightPaths { paths, .. } | PhaseData::PathsWithSums { paths, .. } = &out.data
    {
        for i in 0..paths.len() {
            for v in paths.path(i) {
                let _ = v.is_connectible(scene());
            }
        }
    }
});
