//! The structure-aware mutator of the Mitsuba XML targets (`xml`, `render`): it copies a run of
//! elements to another element boundary (nesting, repetition, reference chains), deletes one, or
//! replaces an attribute's value by a hostile number or a `$parameter`, so most inputs stay
//! well-formed enough to reach the plugins; otherwise libFuzzer's own byte-level mutations.
use libfuzzer_sys::{fuzz_mutator, fuzzer_mutate};

/// Values that stress the plugins' checks.
const VALUES: &[&str] = &[
    "0",
    "-1",
    "1",
    "2",
    "0.5",
    "1e38",
    "-1e38",
    "3.4e39",
    "1e-45",
    "NaN",
    "inf",
    "-inf",
    "100000",
    "4294967296",
    "1, 2",
    "1 2 3",
    "",
    "$res",
    "0, 0, 0",
    "1e300",
];

/// A small generator for the mutator's choices.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % n.max(1) as u64) as usize
    }
}

fuzz_mutator!(|data: &mut [u8], size: usize, max_size: usize, seed: u32| {
    let mut rng = Rng(u64::from(seed).wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let text = data[..size].to_vec();
    // Element starts ('<' not followed by '/', '?' or '!') and attribute values ("...").
    let starts: Vec<usize> =
        (0..size).filter(|&i| text[i] == b'<' && !matches!(text.get(i + 1), Some(b'/' | b'?' | b'!'))).collect();
    let values: Vec<(usize, usize)> = {
        let quotes: Vec<usize> = (0..size).filter(|&i| text[i] == b'"').collect();
        quotes.chunks_exact(2).map(|q| (q[0] + 1, q[1])).collect()
    };
    let edited: Option<Vec<u8>> = match rng.below(4) {
        // Copy the text between two element starts to a third.
        0 if starts.len() >= 2 => {
            let (a, b) = (starts[rng.below(starts.len())], starts[rng.below(starts.len())]);
            let (a, b) = (a.min(b), a.max(b));
            let at = starts[rng.below(starts.len())];
            let mut out = text[..at].to_vec();
            out.extend_from_slice(&text[a..b]);
            out.extend_from_slice(&text[at..]);
            Some(out)
        }
        // Delete the text between two element starts.
        1 if starts.len() >= 2 => {
            let (a, b) = (starts[rng.below(starts.len())], starts[rng.below(starts.len())]);
            let (a, b) = (a.min(b), a.max(b));
            let mut out = text[..a].to_vec();
            out.extend_from_slice(&text[b..]);
            Some(out)
        }
        // Replace an attribute value.
        2 if !values.is_empty() => {
            let (a, b) = values[rng.below(values.len())];
            let mut out = text[..a].to_vec();
            out.extend_from_slice(VALUES[rng.below(VALUES.len())].as_bytes());
            out.extend_from_slice(&text[b..]);
            Some(out)
        }
        _ => None,
    };
    match edited {
        Some(out) if out.len() <= max_size => {
            data[..out.len()].copy_from_slice(&out);
            out.len()
        }
        _ => fuzzer_mutate(data, size, max_size),
    }
});
