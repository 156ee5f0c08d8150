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
//! - [`Part::State`]: the estimator-specific data (the estimator's [`WirePayload`]: light
//!   paths, features, sums, training records, filter rows). Every instance that reduces reads it, because
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
//! so the version goes up whenever a type inside a payload changes; both ends of a
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

use super::{ChunkOutput, Payload, Phase};
use crate::scene::Scene;
use crate::spectrum::Rgb;
use crate::transport::{Counters, Splat};

/// Bumped whenever a type carried in a part changes its fields.
pub const WIRE_VERSION: u16 = 3;

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

/// Chunk data that can travel as bytes: serde's derived layout, and the checks a
/// reduction needs of data it did not produce (indices it dereferences without a bound
/// check of its own).
pub trait WirePayload: Payload + Serialize + for<'de> Deserialize<'de> {
    /// Refuse data inconsistent with itself or with `scene`.
    fn validate(&self, scene: &Scene) -> Result<(), WireError>;
}

/// No data: nothing to check.
impl WirePayload for () {
    fn validate(&self, _scene: &Scene) -> Result<(), WireError> {
        Ok(())
    }
}

impl<D: WirePayload> ChunkOutput<D> {
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
                let data: D = from_all(rest)?;
                data.validate(scene)?;
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
pub(crate) fn from_all<'a, T: Deserialize<'a>>(bytes: &'a [u8]) -> Result<T, WireError> {
    match postcard::take_from_bytes(bytes) {
        Ok((value, [])) => Ok(value),
        Ok(_) => Err(WireError::Invalid("trailing bytes")),
        Err(_) => Err(WireError::Malformed),
    }
}
