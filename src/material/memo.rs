//! What a BSDF has already looked up at one shading point.
//!
//! A path vertex asks its BSDF for a sample, a value and a density (`sample`, `eval` and `pdf`
//! for next-event estimation and MIS), with the same context each time. A textured parameter
//! or a normal map would be looked up, filtered and decoded again by each call; a
//! [`TextureMemo`] beside the [`super::BsdfContext`] keeps the values of the first lookups, so
//! that the others read them back. Lookups are pure functions of the texture and the point, so
//! the values are the same bits either way.

use std::cell::Cell;
use std::mem::MaybeUninit;

/// Values remembered per shading point.
const SLOTS: usize = 4;

/// What a memo entry holds: which lookup (a texture's or a perturbation's address, with the
/// kind of lookup in its two low bits) and its value.
type Entry = (usize, [f32; 3]);

/// The kind of lookup, in the low bits of an entry's key (textures and perturbations are
/// aligned to at least four bytes, so their addresses leave these bits clear).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Lookup {
    /// A texture's colour (`BsdfContext::eval`).
    Color = 0,
    /// A texture's scalar value (`BsdfContext::scalar`).
    Scalar = 1,
    /// A perturbed shading normal, before it is turned toward the viewer.
    Normal = 2,
}

/// The first four lookups (`SLOTS`) made at one shading point (later ones are not remembered, but
/// still correct). Create one per path vertex, next to its [`super::BsdfContext`].
#[derive(Debug)]
pub struct TextureMemo {
    /// Entries `..len` are written; the rest are not (a memo costs nothing to create, which
    /// matters at the vertices of untextured scenes, most of them).
    entries: [Cell<MaybeUninit<Entry>>; SLOTS],
    len: Cell<usize>,
}

impl Default for TextureMemo {
    #[inline]
    fn default() -> Self {
        TextureMemo { entries: [const { Cell::new(MaybeUninit::uninit()) }; SLOTS], len: Cell::new(0) }
    }
}

impl TextureMemo {
    /// The value of lookup `kind` of the object at `of`: remembered, or `f()` (then remembered
    /// while slots are free).
    #[inline]
    pub(crate) fn get_or<T>(&self, of: &T, kind: Lookup, f: impl FnOnce() -> [f32; 3]) -> [f32; 3] {
        const { assert!(std::mem::align_of::<T>() >= 4, "the key's low bits hold the kind") };
        let key = std::ptr::from_ref(of) as usize | kind as usize;
        let len = self.len.get();
        for entry in &self.entries[..len] {
            // SAFETY: entries below `len` have been written.
            let (k, v) = unsafe { entry.get().assume_init() };
            if k == key {
                return v;
            }
        }
        let v = f();
        if len < SLOTS {
            self.entries[len].set(MaybeUninit::new((key, v)));
            self.len.set(len + 1);
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell as Counter;

    #[test]
    fn remembers_each_lookup_of_each_object_once() {
        let memo = TextureMemo::default();
        let objects = [[0u32; 4]; 6];
        let calls = Counter::new(0);
        let look = |k: usize, kind: Lookup| {
            memo.get_or(&objects[k], kind, || {
                calls.set(calls.get() + 1);
                [k as f32, kind as u32 as f32, 0.5]
            })
        };
        // Two objects, two kinds of lookup each: four slots, each computed once.
        for _ in 0..3 {
            for (k, kind) in [(0, Lookup::Color), (0, Lookup::Scalar), (1, Lookup::Color), (1, Lookup::Normal)] {
                assert_eq!(look(k, kind), [k as f32, kind as u32 as f32, 0.5]);
            }
        }
        assert_eq!(calls.get(), 4);
        // Beyond the slots: still the right values, computed each time.
        assert_eq!(look(5, Lookup::Color), [5.0, 0.0, 0.5]);
        assert_eq!(look(5, Lookup::Color), [5.0, 0.0, 0.5]);
        assert_eq!(calls.get(), 6);
        assert_eq!(look(0, Lookup::Color), [0.0, 0.0, 0.5], "the first entries stay");
        assert_eq!(calls.get(), 6);
    }
}
