//! Seed mixing: derive independent RNG streams from a user seed and a few keys.

/// SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mix.
#[inline]
pub(crate) fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Mixes a user seed with keys into one 64-bit seed; order matters.
pub(crate) fn derive(seed: u64, keys: &[u64]) -> u64 {
    keys.iter()
        .fold(splitmix64(seed), |acc, &k| splitmix64(acc ^ k))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derive_depends_on_every_key_and_order() {
        let a = derive(1, &[2, 3]);
        assert_ne!(a, derive(1, &[3, 2]));
        assert_ne!(a, derive(2, &[2, 3]));
        assert_ne!(a, derive(1, &[2, 4]));
        assert_eq!(a, derive(1, &[2, 3]));
    }
}
