//! Hash maps and sets for integer keys in hot loops: a multiply-rotate hasher finished by
//! [`crate::noise::mix64`]. The standard library's SipHash guards against keys chosen to
//! collide, which mesh indices and grid cells are not, at several times the cost; and
//! with no random state the maps behave the same on every run.

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// The hasher: each word folded in by a rotate, xor and multiply.
#[derive(Debug, Default, Clone, Copy)]
pub struct IntHasher(u64);

const K: u64 = 0x517c_c1b7_2722_0a95;

impl IntHasher {
    #[inline(always)]
    fn add(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(K);
    }
}

impl Hasher for IntHasher {
    #[inline(always)]
    fn finish(&self) -> u64 {
        crate::noise::mix64(self.0)
    }

    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.add(u64::from_le_bytes(word));
        }
    }

    #[inline(always)]
    fn write_u32(&mut self, x: u32) {
        self.add(u64::from(x));
    }

    #[inline(always)]
    fn write_i32(&mut self, x: i32) {
        self.add(x as u32 as u64);
    }

    #[inline(always)]
    fn write_u64(&mut self, x: u64) {
        self.add(x);
    }

    #[inline(always)]
    fn write_usize(&mut self, x: usize) {
        self.add(x as u64);
    }
}

/// A hash map keyed by integers (or arrays and tuples of them).
pub type IntMap<K, V> = HashMap<K, V, BuildHasherDefault<IntHasher>>;

/// A hash set of integers (or arrays and tuples of them).
pub type IntSet<K> = HashSet<K, BuildHasherDefault<IntHasher>>;

#[cfg(test)]
mod tests {
    use super::*;

    /// Keys that differ in one word hash apart, arrays and tuples included, and a map of
    /// a million neighbouring keys finds each (no collapse into few buckets).
    #[test]
    fn neighbouring_keys_hash_apart_and_are_found() {
        use std::hash::BuildHasher;
        let build = BuildHasherDefault::<IntHasher>::default();
        assert_ne!(build.hash_one([1i32, 2, 3]), build.hash_one([1i32, 2, 4]));
        assert_ne!(build.hash_one((1u32, 2u32)), build.hash_one((2u32, 1u32)));
        let mut map: IntMap<u64, u32> = IntMap::default();
        for i in 0..1_000_000u64 {
            map.insert(i << 32 | (i + 1), i as u32);
        }
        assert!((0..1_000_000u64).step_by(997).all(|i| map[&(i << 32 | (i + 1))] == i as u32));
        let buckets: IntSet<u64> = (0..4096u64).map(|i| build.hash_one(i) & 4095).collect();
        assert!(buckets.len() > 2000, "{} of 4096 buckets used by 4096 neighbouring keys", buckets.len());
    }
}
