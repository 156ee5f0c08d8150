//! FNV-1a, 64-bit: the checksum of stored SPCBPT models
//! ([`crate::estimators::spcbpt::model_file`]) and the content hash hosts give scenes and
//! images. Not cryptographic: it catches damage and mismatches, not forgery.
//!
//! Integers are hashed as their little-endian bytes, so a value hashes the same on every
//! machine (the hash of a scene is compared across the machines of a split render).

/// A running FNV-1a hash; also a [`core::hash::Hasher`] and a [`core::fmt::Write`] (to
/// hash a value's `Debug` form without building the string).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fnv1a(u64);

impl Fnv1a {
    const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;

    /// The hash of nothing.
    pub const fn new() -> Self {
        Self(Self::OFFSET)
    }

    /// Add `bytes`.
    #[inline]
    pub fn add(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(Self::PRIME);
        }
    }

    /// The hash so far.
    pub const fn value(&self) -> u64 {
        self.0
    }
}

impl Default for Fnv1a {
    fn default() -> Self {
        Self::new()
    }
}

/// The FNV-1a hash of `bytes`.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h = Fnv1a::new();
    h.add(bytes);
    h.value()
}

impl core::hash::Hasher for Fnv1a {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        self.add(bytes);
    }
    fn write_u16(&mut self, i: u16) {
        self.add(&i.to_le_bytes());
    }
    fn write_u32(&mut self, i: u32) {
        self.add(&i.to_le_bytes());
    }
    fn write_u64(&mut self, i: u64) {
        self.add(&i.to_le_bytes());
    }
    fn write_u128(&mut self, i: u128) {
        self.add(&i.to_le_bytes());
    }
    fn write_usize(&mut self, i: usize) {
        self.add(&(i as u64).to_le_bytes());
    }
}

impl core::fmt::Write for Fnv1a {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.add(s.as_bytes());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::hash::Hasher;

    /// The published FNV-1a 64 test vectors, and little-endian integers.
    #[test]
    fn matches_the_reference_values() {
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
        let mut h = Fnv1a::new();
        h.write_u32(0x0403_0201);
        assert_eq!(h.finish(), fnv1a(&[1, 2, 3, 4]));
    }
}
