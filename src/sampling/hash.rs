//! Integer hashing, hashed permutations and Owen scrambling: the deterministic randomness that
//! samplers derive from (seed, pixel, sample index, dimension).

/// A 64-bit bit mixer (the SplitMix64 finalizer): every input bit affects every output bit.
#[inline]
pub fn mix_bits(mut v: u64) -> u64 {
    v ^= v >> 30;
    v = v.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    v ^= v >> 27;
    v = v.wrapping_mul(0x94d0_49bb_1331_11eb);
    v ^ (v >> 31)
}

/// Hash of a sequence of integers (order matters).
#[inline]
pub fn hash(values: &[u64]) -> u64 {
    let mut h = 0x9e37_79b9_7f4a_7c15u64;
    for &v in values {
        h = mix_bits(h ^ mix_bits(v.wrapping_add(0x632b_e59b_d9b4_e019)));
    }
    h
}

/// Element `i` of a pseudo-random permutation of `0..n` chosen by `seed` (Kensler 2013,
/// "Correlated Multi-Jittered Sampling"): an invertible hash on the next power of two, cycled
/// until it lands below `n`. O(1) memory, so every (pixel, dimension) can have its own
/// permutation. Requires `i < n`.
#[inline]
pub fn permutation_element(mut i: u32, n: u32, seed: u32) -> u32 {
    debug_assert!(i < n);
    let mut w = n - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    let p = seed;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | (p >> 27));
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < n {
            break;
        }
    }
    (i.wrapping_add(p)) % n
}

/// Owen scrambling of a 32-bit binary fraction `v` (most significant bit = 1/2), by the
/// hash-based construction of Burley 2020 ("Practical Hash-based Owen Scrambling"): in
/// bit-reversed order, a Laine–Karras style hash flips each bit depending only on the bits
/// *above* it in the fraction (`x ^= x·(even constant)` propagates only upward), which is
/// exactly nested uniform scrambling's structure. Preserves (t, m, s)-net properties.
#[inline]
pub fn owen_scramble(v: u32, seed: u32) -> u32 {
    let mut x = v.reverse_bits();
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x.reverse_bits()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutation_element_is_a_permutation() {
        for n in [1u32, 2, 3, 7, 16, 100, 257] {
            for seed in [0u32, 1, 0xdead_beef, 12345] {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let j = permutation_element(i, n, seed) as usize;
                    assert!(!seen[j], "n={n} seed={seed}: {j} twice");
                    seen[j] = true;
                }
            }
        }
        // Different seeds give different permutations.
        let a: Vec<u32> = (0..64).map(|i| permutation_element(i, 64, 1)).collect();
        let b: Vec<u32> = (0..64).map(|i| permutation_element(i, 64, 2)).collect();
        assert_ne!(a, b);
    }

    #[test]
    fn owen_scramble_is_a_nested_bijection() {
        // Points sharing their top k bits still share their top k bits after scrambling.
        for seed in [0u32, 7, 0x1234_5678] {
            for k in 1..12 {
                let mask = !0u32 << (32 - k);
                for v in (0..2000u32).map(|i| i.wrapping_mul(0x9e37_79b9)) {
                    let w = v ^ (0x0000_0fff >> (k - 1).min(11)) ^ 1; // differs only below bit 32-k
                    if v & mask == w & mask {
                        assert_eq!(owen_scramble(v, seed) & mask, owen_scramble(w, seed) & mask);
                    }
                }
            }
            // Bijective on 16-bit prefixes.
            let mut seen = std::collections::HashSet::new();
            for i in 0..(1u32 << 16) {
                assert!(seen.insert(owen_scramble(i << 16, seed) >> 16));
            }
        }
    }

    #[test]
    fn hash_depends_on_order_and_value() {
        assert_ne!(hash(&[1, 2]), hash(&[2, 1]));
        assert_ne!(hash(&[0]), hash(&[0, 0]));
        assert_eq!(hash(&[5, 6, 7]), hash(&[5, 6, 7]));
        assert_ne!(mix_bits(0), mix_bits(1));
    }
}
