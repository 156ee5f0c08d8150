//! SPCBPT's trained model as bytes: what `ember train` stores so that the workers of a
//! split render load κ, Q and Γ instead of each repeating the preprocessing
//! (docs/distributed.md).
//!
//! Layout, little-endian: the magic `EMBRSPCM`, the format version (u32), then
//! `connections`, `n_eye`, `n_light_surface`, `n_light` (u32 each); the eye tree and the
//! light tree (a node count, then per node axis, threshold (f32 bits), first child,
//! label); the light-source bins (a flag, then the first id and the two arrays, each
//! with its length); Q (length, f32s); Γ (rows, columns, f32s eye-major); last an FNV-1a
//! 64 checksum of everything before it.
//!
//! Decoding never panics and never accepts what the estimator could not use: a wrong
//! magic or version, a truncated or altered file (the checksum), trees that would not
//! reach a leaf, labels or bins past the subspace counts, bins for another number of
//! lights, negative or non-finite Q or Γ are each an error that says which.

use alloc::vec::Vec;

use super::{Classifier, Model};
use crate::fnv::fnv1a;
use crate::scene::Scene;
use crate::subspace::{DecisionTree, LightSourceBins, SubspaceMatrix};

/// The file's first eight bytes.
pub const MAGIC: [u8; 8] = *b"EMBRSPCM";
/// The layout's version; a file of another is refused.
pub const VERSION: u32 = 1;

/// Why bytes are not a model this program can use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelError {
    /// The bytes do not start with [`MAGIC`].
    NotAModel,
    /// Another layout version.
    Version(u32),
    /// The bytes end early.
    Truncated,
    /// The checksum does not match: the file was altered or damaged.
    Checksum,
    /// The content is inconsistent; says what.
    Invalid(&'static str),
}

impl core::fmt::Display for ModelError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NotAModel => f.write_str("not an SPCBPT model (no EMBRSPCM magic)"),
            Self::Version(v) => write!(f, "model format version {v}, this program reads version {VERSION}"),
            Self::Truncated => f.write_str("the model is truncated"),
            Self::Checksum => f.write_str("the model's checksum does not match: the file is damaged"),
            Self::Invalid(what) => write!(f, "the model is inconsistent: {what}"),
        }
    }
}

struct Writer(Vec<u8>);

impl Writer {
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }
    fn u32s(&mut self, v: &[u32]) {
        self.u32(v.len() as u32);
        v.iter().for_each(|&x| self.u32(x));
    }
    fn f32s(&mut self, v: &[f32]) {
        self.u32(v.len() as u32);
        v.iter().for_each(|&x| self.f32(x));
    }
    fn tree(&mut self, t: &DecisionTree) {
        self.u32(t.node_count() as u32);
        for (axis, threshold, first_child, label) in t.raw_nodes() {
            self.u32(axis as u32);
            self.f32(threshold);
            self.u32(first_child);
            self.u32(label);
        }
    }
}

struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn u32(&mut self) -> Result<u32, ModelError> {
        let (head, rest) = self.0.split_at_checked(4).ok_or(ModelError::Truncated)?;
        self.0 = rest;
        Ok(u32::from_le_bytes([head[0], head[1], head[2], head[3]]))
    }
    fn f32(&mut self) -> Result<f32, ModelError> {
        self.u32().map(f32::from_bits)
    }
    /// A length, refused when the bytes left cannot hold that many `size`-byte items
    /// (so a damaged length cannot make the reader allocate without bound).
    fn len(&mut self, size: usize) -> Result<usize, ModelError> {
        let n = self.u32()? as usize;
        if n.saturating_mul(size) > self.0.len() {
            return Err(ModelError::Truncated);
        }
        Ok(n)
    }
    fn u32s(&mut self) -> Result<Vec<u32>, ModelError> {
        let n = self.len(4)?;
        (0..n).map(|_| self.u32()).collect()
    }
    fn f32s(&mut self) -> Result<Vec<f32>, ModelError> {
        let n = self.len(4)?;
        (0..n).map(|_| self.f32()).collect()
    }
    fn tree(&mut self, labels: u32) -> Result<DecisionTree, ModelError> {
        let n = self.len(16)?;
        let mut raw = Vec::with_capacity(n);
        for _ in 0..n {
            let axis = u8::try_from(self.u32()?).map_err(|_| ModelError::Invalid("a tree node's axis is not a byte"))?;
            raw.push((axis, self.f32()?, self.u32()?, self.u32()?));
        }
        DecisionTree::from_raw_nodes(&raw, labels).map_err(ModelError::Invalid)
    }
}

fn non_negative(values: &[f32], what: &'static str) -> Result<(), ModelError> {
    if values.iter().all(|v| v.is_finite() && *v >= 0.0) { Ok(()) } else { Err(ModelError::Invalid(what)) }
}

impl Model {
    /// The model as bytes (see the module notes).
    pub fn encode(&self) -> Vec<u8> {
        let c = &self.classifier;
        let mut w = Writer(Vec::new());
        w.0.extend_from_slice(&MAGIC);
        w.u32(VERSION);
        for v in [self.connections, c.n_eye, c.n_light_surface, c.n_light] {
            w.u32(v);
        }
        w.tree(&c.eye);
        w.tree(&c.light);
        match &c.sources {
            None => w.u32(0),
            Some(bins) => {
                let (first_id, light_first, light_rows) = bins.parts();
                w.u32(1);
                w.u32(first_id);
                w.u32s(light_first);
                w.u32s(light_rows);
            }
        }
        w.f32s(&self.q);
        w.u32(self.gamma.n_light() as u32);
        w.u32(self.gamma.n_eye() as u32);
        w.f32s(self.gamma.as_slice());
        let sum = fnv1a(&w.0);
        w.0.extend_from_slice(&sum.to_le_bytes());
        w.0
    }

    /// A model from [`Model::encode`]'s bytes, for `scene` (its light count checks the
    /// light-source bins). Never panics; every inconsistency is an error.
    pub fn decode(bytes: &[u8], scene: &Scene) -> Result<Self, ModelError> {
        if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
            return Err(ModelError::NotAModel);
        }
        let mut r = Reader(&bytes[MAGIC.len()..]);
        let version = r.u32()?;
        if version != VERSION {
            return Err(ModelError::Version(version));
        }
        let (body, sum) = bytes.split_at_checked(bytes.len().saturating_sub(8)).ok_or(ModelError::Truncated)?;
        if body.len() < MAGIC.len() + 4 || fnv1a(body).to_le_bytes() != sum {
            return Err(ModelError::Checksum);
        }
        let mut r = Reader(&body[MAGIC.len() + 4..]);
        let (connections, n_eye, n_light_surface, n_light) = (r.u32()?, r.u32()?, r.u32()?, r.u32()?);
        if n_eye == 0 || n_light_surface == 0 || n_light < n_light_surface {
            return Err(ModelError::Invalid("no eye or light subspaces"));
        }
        let eye = r.tree(n_eye)?;
        let light = r.tree(n_light_surface)?;
        let sources = match r.u32()? {
            0 => None,
            1 => {
                let first_id = r.u32()?;
                let (light_first, light_rows) = (r.u32s()?, r.u32s()?);
                let bins = LightSourceBins::from_parts(first_id, light_first, light_rows, scene.lights.len()).map_err(ModelError::Invalid)?;
                if first_id != n_light_surface {
                    return Err(ModelError::Invalid("light-source bins not numbered after the surface subspaces"));
                }
                Some(bins)
            }
            _ => return Err(ModelError::Invalid("the light-source bin flag is neither 0 nor 1")),
        };
        let classifier = Classifier::new(eye, n_eye, light, n_light_surface, sources);
        if classifier.n_light != n_light {
            return Err(ModelError::Invalid("the light subspace count disagrees with the bins"));
        }
        let q = r.f32s()?;
        if q.len() != n_light as usize {
            return Err(ModelError::Invalid("Q has another length than the light subspaces"));
        }
        non_negative(&q, "Q holds a negative or non-finite value")?;
        let (rows, cols) = (r.u32()?, r.u32()?);
        let values = r.f32s()?;
        if (rows, cols) != (n_light, n_eye) || values.len() != rows as usize * cols as usize {
            return Err(ModelError::Invalid("Γ's size is not light × eye subspaces"));
        }
        non_negative(&values, "Γ holds a negative or non-finite value")?;
        if !r.0.is_empty() {
            return Err(ModelError::Invalid("bytes left after Γ"));
        }
        let gamma = SubspaceMatrix::from_gamma(values, rows as usize, cols as usize);
        Ok(Self { classifier, q, gamma, connections })
    }
}
