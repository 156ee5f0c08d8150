//! Chunk outputs as bytes, for hosts whose workers share no memory.
//!
//! The protocol's promise (module notes: *plain data*) is that a chunk's output is all a
//! reduction needs, so a host may map chunks in other address spaces: the browser's Web
//! Workers (`host-wasm`), or processes on other machines. This module is how such a host
//! moves an output: [`ChunkOutput::encode`] in the worker, [`ChunkOutput::decode`] where
//! it is reduced.
//!
//! An output travels in two **parts**, because its readers differ:
//! - [`Part::Film`]: the camera samples, the splats and the counters. Only the instance
//!   that holds the film reads them.
//! - [`Part::State`]: the estimator-specific data ([`PhaseData`]: light paths, features,
//!   sums, training records, filter rows). Every instance that reduces reads it, because
//!   each keeps its own copy of the estimator's state (light-vertex caches, Γ, Q) for
//!   the phases that follow.
//!
//! A worker that only maps reduces state parts alone, into a film of no pixels
//! (`Film::new(0, 0)` ignores camera samples and counts splats as outside), so the film's
//! bytes never reach the workers that do not need them.
//!
//! **Format.** A header (`EMBW`, [`WIRE_VERSION`], the part, the phase's id and pass and
//! the chunk's index range: an output of another phase or of an earlier pass is refused) and
//! then the part's fields in postcard, serde's compact no_std format (integers as varints,
//! floats as their bits, so values survive exactly). The field layout is the derived one,
//! so the version goes up whenever a type inside [`PhaseData`] changes; both ends of a
//! browser or a cluster run the same build anyway, and a part from another version is
//! refused, not misread.
//!
//! **Bad input.** Decoding any bytes returns a value or a [`WireError`], never panics
//! (the `wire_decode` fuzz target). The checks are structural: header, range, lengths
//! (one camera sample per item or none), and the indices a reduction dereferences
//! without a bound check of its own (light-path vertex materials and lights, path starts)
//! against the scene. Filter rows index nodes of other chunks; their producer is trusted
//! to be this build (the header checks that).

use alloc::vec::Vec;
use core::fmt;
use core::ops::Range;

use serde::{Deserialize, Serialize};

use super::{ChunkOutput, Phase, PhaseData};
#[cfg(feature = "path")]
use crate::path::{LightPaths, VertexKind};
use crate::scene::Scene;
use crate::spectrum::Rgb;
use crate::transport::{Counters, Splat};

/// Bumped whenever a type carried in a part changes its fields.
pub const WIRE_VERSION: u16 = 2;

const MAGIC: [u8; 4] = *b"EMBW";

/// Which part of a chunk's output (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Part {
    /// Camera samples, splats and counters: for the instance with the film.
    Film,
    /// Estimator-specific data: for every instance that reduces.
    State,
}

/// Why bytes were refused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum WireError {
    /// Not a chunk output of this format version.
    Header,
    /// A different part than the one asked for.
    WrongPart(Part),
    /// The output of another chunk, phase or pass than the one expected.
    WrongChunk {
        /// What the bytes hold.
        found: ChunkId,
        /// What the host expected.
        expected: ChunkId,
    },
    /// The fields do not parse.
    Malformed,
    /// The fields parse but are inconsistent (what is wrong).
    Invalid(&'static str),
}

impl fmt::Display for WireError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Header => write!(f, "not an ember chunk output of wire version {WIRE_VERSION}"),
            Self::WrongPart(p) => write!(f, "a {p:?} part where another was expected"),
            Self::WrongChunk { found, expected } => write!(f, "the output of {found} where {expected} was expected"),
            Self::Malformed => write!(f, "malformed chunk output"),
            Self::Invalid(what) => write!(f, "invalid chunk output: {what}"),
        }
    }
}

/// Which chunk of which phase of which pass an output belongs to.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChunkId {
    /// [`Phase::id`].
    pub phase: u8,
    /// [`Phase::pass`].
    pub pass: Option<u32>,
    /// The chunk's items.
    pub items: Range<u32>,
}

impl ChunkId {
    /// Chunk `chunk` of `phase`.
    pub fn of(phase: &Phase, chunk: usize) -> Self {
        Self { phase: phase.id, pass: phase.pass, items: phase.chunk_range(chunk) }
    }
}

impl fmt::Display for ChunkId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.pass {
            Some(p) => write!(f, "items {:?} of phase {} of pass {p}", self.items, self.phase),
            None => write!(f, "items {:?} of setup phase {}", self.items, self.phase),
        }
    }
}

#[derive(Serialize, Deserialize)]
struct Header {
    magic: [u8; 4],
    version: u16,
    part: Part,
    chunk: ChunkId,
}

#[derive(Serialize)]
struct FilmRef<'a> {
    pixels: &'a [Rgb],
    splats: &'a [Splat],
    counters: Counters,
}

#[derive(Deserialize)]
struct FilmOwned {
    pixels: Vec<Rgb>,
    splats: Vec<Splat>,
    counters: Counters,
}

impl ChunkOutput {
    /// Append part `part` of this output, mapped for `phase`, to `out` (see the module
    /// notes).
    pub fn encode(&self, phase: &Phase, part: Part, out: &mut Vec<u8>) {
        let chunk = ChunkId { phase: phase.id, pass: phase.pass, items: self.items.clone() };
        let header = Header { magic: MAGIC, version: WIRE_VERSION, part, chunk };
        // Serialising plain values into a growing vector cannot fail; on the impossible
        // error the vector is lost, never half-written into `out`.
        let buffer = core::mem::take(out);
        let written = match part {
            Part::Film => postcard::to_extend(&(header, FilmRef { pixels: &self.pixels, splats: &self.splats, counters: self.counters }), buffer),
            Part::State => postcard::to_extend(&(header, &self.data), buffer),
        };
        if let Ok(buffer) = written {
            *out = buffer;
        }
    }

    /// Replace this output's part `part` with the one in `bytes`, which must be the
    /// output of chunk `chunk` of `phase`. The other part is left as it was; on error
    /// nothing is changed.
    pub fn decode(&mut self, phase: &Phase, chunk: usize, part: Part, bytes: &[u8], scene: &Scene) -> Result<(), WireError> {
        let expected = ChunkId::of(phase, chunk);
        let (header, rest): (Header, &[u8]) = postcard::take_from_bytes(bytes).map_err(|_| WireError::Header)?;
        if header.magic != MAGIC || header.version != WIRE_VERSION {
            return Err(WireError::Header);
        }
        if header.part != part {
            return Err(WireError::WrongPart(header.part));
        }
        if header.chunk != expected {
            return Err(WireError::WrongChunk { found: header.chunk, expected });
        }
        let expected = expected.items;
        match part {
            Part::Film => {
                let film: FilmOwned = from_all(rest)?;
                if !film.pixels.is_empty() && film.pixels.len() != expected.len() {
                    return Err(WireError::Invalid("camera samples are neither one per item nor none"));
                }
                self.pixels = film.pixels;
                self.splats = film.splats;
                self.counters = film.counters;
            }
            Part::State => {
                let data: PhaseData = from_all(rest)?;
                validate(&data, scene)?;
                self.data = data;
            }
        }
        self.items = expected;
        Ok(())
    }
}

/// What part of which chunk `bytes` hold, from the header alone (a host routing parts
/// before decoding them).
pub fn peek(bytes: &[u8]) -> Result<(Part, ChunkId), WireError> {
    let (header, _): (Header, &[u8]) = postcard::take_from_bytes(bytes).map_err(|_| WireError::Header)?;
    if header.magic != MAGIC || header.version != WIRE_VERSION {
        return Err(WireError::Header);
    }
    Ok((header.part, header.chunk))
}

/// Parse `bytes` whole: trailing bytes are an error too.
fn from_all<'a, T: Deserialize<'a>>(bytes: &'a [u8]) -> Result<T, WireError> {
    match postcard::take_from_bytes(bytes) {
        Ok((value, [])) => Ok(value),
        Ok(_) => Err(WireError::Invalid("trailing bytes")),
        Err(_) => Err(WireError::Malformed),
    }
}

fn validate(data: &PhaseData, scene: &Scene) -> Result<(), WireError> {
    // Without the `path` feature the light-path variants have no values (`super::Absent`).
    #[cfg(not(feature = "path"))]
    let _ = scene;
    match data {
        #[cfg(feature = "path")]
        PhaseData::LightPaths { paths, memo } => {
            validate_paths(paths, scene)?;
            if !memo.is_empty() && memo.len() != paths.vertices.len() {
                return Err(WireError::Invalid("prefix memos are neither one per vertex nor none"));
            }
            Ok(())
        }
        #[cfg(feature = "path")]
        PhaseData::PathsWithSums { paths, sums } => {
            validate_paths(paths, scene)?;
            if sums.len() != paths.vertices.len() {
                return Err(WireError::Invalid("vertex sums are not one per vertex"));
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

/// Path starts ascending within the vertices; materials and lights of the scene.
#[cfg(feature = "path")]
fn validate_paths(paths: &LightPaths, scene: &Scene) -> Result<(), WireError> {
    let n = paths.vertices.len() as u64;
    let mut last = 0u64;
    for (i, &s) in paths.starts.iter().enumerate() {
        if (i == 0 && s != 0) || u64::from(s) < last || u64::from(s) > n {
            return Err(WireError::Invalid("light-path starts out of order"));
        }
        last = u64::from(s);
    }
    if paths.starts.is_empty() && n > 0 {
        return Err(WireError::Invalid("light-path vertices without paths"));
    }
    let lights = scene.lights.len() as u64;
    let materials = scene.materials.len() as u64;
    for v in &paths.vertices {
        let light_ok = |id: u32| u64::from(id) < lights;
        let ok = match v.kind {
            VertexKind::Light(id) => light_ok(id),
            VertexKind::Surface => u64::from(v.material) < materials,
            VertexKind::Camera | VertexKind::InfiniteLight => true,
        } && v.emitter.is_none_or(light_ok);
        if !ok {
            return Err(WireError::Invalid("a light-path vertex names a material or light the scene lacks"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    #[test]
    fn refuses_what_it_cannot_trust() {
        let (scene, _, _) = builtin::cornell_box(4, 4).build().expect("builds");
        let phase = Phase { name: "camera", id: 0, pass: Some(3), items: 8, chunk: 4, samples: true };
        let mut out = ChunkOutput::default();
        out.reset(0..4);
        out.pixel_buffer();
        let mut film = Vec::new();
        out.encode(&phase, Part::Film, &mut film);
        let mut got = ChunkOutput::default();
        assert_eq!(got.decode(&phase, 0, Part::Film, &film, &scene), Ok(()));
        assert_eq!(got.decode(&phase, 0, Part::State, &film, &scene), Err(WireError::WrongPart(Part::Film)));
        assert!(matches!(got.decode(&phase, 1, Part::Film, &film, &scene), Err(WireError::WrongChunk { .. })));
        // The same chunk of the next pass, or of another phase: stale, refused.
        let next = Phase { pass: Some(4), ..phase };
        assert!(matches!(got.decode(&next, 0, Part::Film, &film, &scene), Err(WireError::WrongChunk { .. })));
        let other = Phase { id: 1, ..phase };
        assert!(matches!(got.decode(&other, 0, Part::Film, &film, &scene), Err(WireError::WrongChunk { .. })));
        assert_eq!(got.decode(&phase, 0, Part::Film, &film[..film.len() - 1], &scene), Err(WireError::Malformed));
        let mut long = film.clone();
        long.push(0);
        assert_eq!(got.decode(&phase, 0, Part::Film, &long, &scene), Err(WireError::Invalid("trailing bytes")));
        let mut old = film.clone();
        old[4] ^= 1; // the version's varint
        assert_eq!(got.decode(&phase, 0, Part::Film, &old, &scene), Err(WireError::Header));
        #[cfg(feature = "path")]
        refuses_unknown_materials(&scene, &mut got);
    }

    /// The variant numbers do not move with the core's features (docs/features.md):
    /// `Count` is variant 3 in every build, and a build without `path` refuses the
    /// number of `LightPaths`, whose payload it cannot hold, instead of misreading it.
    #[test]
    fn variant_numbers_do_not_depend_on_features() {
        let phase = Phase { name: "probe", id: 0, pass: None, items: 1, chunk: 1, samples: false };
        let mut out = ChunkOutput::default();
        out.reset(0..1);
        out.data = PhaseData::Count(5);
        let mut bytes = Vec::new();
        out.encode(&phase, Part::State, &mut bytes);
        let n = bytes.len();
        assert_eq!(bytes[n - 2..], [3, 5], "Count(5): variant 3, then 5");
        #[cfg(not(feature = "path"))]
        {
            let (scene, _, _) = builtin::cornell_box(4, 4).build().expect("builds");
            bytes[n - 2] = 1;
            let mut got = ChunkOutput::default();
            assert_eq!(got.decode(&phase, 0, Part::State, &bytes, &scene), Err(WireError::Malformed));
        }
    }

    #[cfg(feature = "path")]
    fn refuses_unknown_materials(scene: &Scene, got: &mut ChunkOutput) {
        // A light vertex naming a material the scene lacks.
        let light = Phase { name: "light paths", id: 0, pass: Some(0), items: 1, chunk: 1, samples: true };
        let mut paths = ChunkOutput::default();
        paths.reset(0..1);
        let (store, _) = paths.light_paths();
        let mut v = crate::path::Vertex::camera(crate::math::Vec3::ZERO, Rgb::ZERO);
        v.kind = VertexKind::Surface;
        v.material = scene.materials.len() as u32;
        store.push(&[v]);
        let mut state = Vec::new();
        paths.encode(&light, Part::State, &mut state);
        assert!(matches!(got.decode(&light, 0, Part::State, &state, scene), Err(WireError::Invalid(_))));
    }
}
