//! A film's accumulators saved to a file and read back: the checkpoint of an interrupted render,
//! which `--resume` continues (the same sums, so the same image as a render that never stopped).
//!
//! Layout (little-endian): the 16 bytes `NEUMANN-FILM-1\0\0`; width, height, term count, AOV
//! count (u32 each); dropped samples (u64); the render's fingerprint (u64: the scene and the
//! settings that must match to resume), samples per pixel done (u32), seed (u64); the AOV names
//! (u32 length and UTF-8 bytes each); then per pixel the 9 accumulators (f64: Σ w L, Σ w L², Σ w, Σ w², Σ w a) and the sample
//! count (u32), the terms (3 f64 each) and the AOV sums (f64 each). Reading checks every size
//! against the file's length before allocating.

use super::{Acc, Film};

const MAGIC: &[u8; 16] = b"NEUMANN-FILM-1\0\0";

/// What a saved film says about the render it belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StateInfo {
    /// A hash of the scene and of the settings a continuation must share.
    pub fingerprint: u64,
    /// Samples per pixel the film holds.
    pub spp_done: u32,
    /// The sampling seed.
    pub seed: u64,
}

impl Film {
    /// The film's accumulators with `info`, as bytes.
    pub fn state_bytes(&self, info: &StateInfo) -> Vec<u8> {
        let px = &self.px;
        let mut out = MAGIC.to_vec();
        for v in [self.width, self.height, px.term_count as u32, px.aov_count as u32] {
            out.extend(v.to_le_bytes());
        }
        out.extend(px.dropped.to_le_bytes());
        out.extend(info.fingerprint.to_le_bytes());
        out.extend(info.spp_done.to_le_bytes());
        out.extend(info.seed.to_le_bytes());
        for name in &self.aov_names {
            out.extend((name.len() as u32).to_le_bytes());
            out.extend(name.as_bytes());
        }
        for (a, c) in px.acc.iter().zip(&px.count) {
            // Written as before the sums were grouped with their weights: R G B sums, R G B squares,
            // weight, squared weight, coverage.
            for v in a.sum[..3].iter().chain(&a.wl2[..3]).chain(&[a.w(), a.w2(), a.alpha]) {
                out.extend(v.to_le_bytes());
            }
            out.extend(c.to_le_bytes());
        }
        for t in px.terms.iter().flatten().chain(&px.aovs) {
            out.extend(t.to_le_bytes());
        }
        out
    }

    /// Reads a film saved by [`Film::state_bytes`].
    pub fn from_state_bytes(bytes: &[u8]) -> Result<(Film, StateInfo), String> {
        let mut r = Reader { bytes, pos: 0 };
        if r.take(16)? != MAGIC {
            return Err("not a neumann film state (no NEUMANN-FILM-1 header)".into());
        }
        let (width, height, terms, aovs) = (r.u32()?, r.u32()?, r.u32()? as usize, r.u32()? as usize);
        let dropped = r.u64()?;
        let info = StateInfo { fingerprint: r.u64()?, spp_done: r.u32()?, seed: r.u64()? };
        let mut names = Vec::new();
        for _ in 0..aovs.min(1 << 16) {
            let n = r.u32()? as usize;
            names.push(String::from_utf8(r.take(n)?.to_vec()).map_err(|_| "an AOV name is not UTF-8")?);
        }
        let pixels = (width as usize).checked_mul(height as usize).ok_or("the film's size overflows")?;
        let per_pixel = 9 * 8 + 4 + terms.checked_mul(24).ok_or("too many terms")? + aovs.checked_mul(8).ok_or("too many AOVs")?;
        let need = pixels.checked_mul(per_pixel).ok_or("the film's size overflows")?;
        if width == 0 || height == 0 || bytes.len() - r.pos != need || aovs != names.len() {
            return Err(format!(
                "the state holds {} bytes of pixels, a {width}×{height} film with {terms} terms and {aovs} AOVs needs {need}",
                bytes.len() - r.pos
            ));
        }
        let mut film = Film::new(width, height).with_terms(terms).with_aovs(names);
        film.px.dropped = dropped;
        for i in 0..pixels {
            let mut f = [0.0f64; 9];
            for v in &mut f {
                *v = r.f64()?;
            }
            film.px.acc[i] = Acc { sum: [f[0], f[1], f[2], f[6]], wl2: [f[3], f[4], f[5], f[7]], alpha: f[8] };
            film.px.count[i] = r.u32()?;
        }
        for t in film.px.terms.iter_mut().flatten() {
            *t = r.f64()?;
        }
        for v in film.px.aovs.iter_mut() {
            *v = r.f64()?;
        }
        Ok((film, info))
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len()).ok_or("the state file is truncated")?;
        let s = &self.bytes[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }
}
