//! [`HugeArray`]: a fixed-length array of plain data in memory the operating system may back with
//! 2 MiB pages (Linux's transparent huge pages, asked for with `madvise`).
//!
//! Why: an incoherent ray visits a handful of nodes and triangle blocks scattered over tens of
//! megabytes. With 4 KiB pages nearly every such visit is also a TLB miss, and the page walk is
//! itself a chain of cache misses; 2 MiB pages cover the whole structure with a few dozen TLB
//! entries. Embree does the same for its BVH. Where the kernel does not honor the advice (huge
//! pages set to `never`, or another operating system) this is an ordinary aligned allocation.

use std::alloc::{alloc, dealloc, handle_alloc_error, Layout};
use std::ops::{Deref, DerefMut};
use std::ptr::NonNull;

/// Size (and alignment) of a huge page on x86-64 and AArch64 Linux with 4 KiB base pages.
const HUGE_PAGE: usize = 2 << 20;

/// A fixed-length array of `T` whose memory, when it spans at least one huge page, starts on a
/// 2 MiB boundary and is advised to the kernel as huge-page memory (its whole 2 MiB pages; the
/// tail stays in ordinary pages, so nothing is padded) before it is first touched. Smaller arrays
/// are plain allocations. Dereferences to `[T]`.
pub struct HugeArray<T: Copy> {
    ptr: NonNull<T>,
    len: usize,
    /// The allocation's layout; `None` for an array without memory (empty, or of zero-sized `T`).
    layout: Option<Layout>,
}

// SAFETY: a HugeArray owns its elements like a Box<[T]> does.
unsafe impl<T: Copy + Send> Send for HugeArray<T> {}
// SAFETY: as above; `&HugeArray` gives only `&[T]`.
unsafe impl<T: Copy + Sync> Sync for HugeArray<T> {}

impl<T: Copy> HugeArray<T> {
    /// A copy of `items`.
    pub fn from_slice(items: &[T]) -> HugeArray<T> {
        HugeArray::from_exact_iter(items.len(), items.iter().copied())
    }

    /// The `len` items of `iter`, written straight into the array's memory (no intermediate
    /// vector: the peak memory of building it is the array's). Panics if `iter` yields another
    /// number of items.
    pub fn from_exact_iter(len: usize, iter: impl IntoIterator<Item = T>) -> HugeArray<T> {
        let bytes = len.checked_mul(size_of::<T>()).expect("array size overflows");
        let mut iter = iter.into_iter();
        if bytes == 0 {
            // Nothing to allocate (no items, or zero-sized ones): a dangling, aligned pointer.
            let n = iter.by_ref().take(len.saturating_add(1)).count();
            assert_eq!(n, len, "the iterator yielded {n} items, not {len}");
            return HugeArray { ptr: NonNull::dangling(), len, layout: None };
        }
        let huge = bytes >= HUGE_PAGE;
        let align = if huge { HUGE_PAGE.max(align_of::<T>()) } else { align_of::<T>() };
        let layout = Layout::from_size_align(bytes, align).expect("array size overflows");
        // SAFETY: the layout has a non-zero size.
        let raw = unsafe { alloc(layout) };
        let Some(ptr) = NonNull::new(raw as *mut T) else { handle_alloc_error(layout) };
        if huge {
            // The whole huge pages; the tail, less than one, stays in ordinary pages.
            advise_huge_pages(raw, bytes / HUGE_PAGE * HUGE_PAGE);
        }
        let mut written = 0;
        for item in iter.by_ref().take(len) {
            // SAFETY: the allocation holds `len` elements of `T` (its size, at T's alignment or
            // more) and `written < len`.
            unsafe { ptr.as_ptr().add(written).write(item) };
            written += 1;
        }
        if written != len || iter.next().is_some() {
            // SAFETY: allocated above with this layout; the elements are `Copy` (no drop).
            unsafe { dealloc(raw, layout) };
            panic!("the iterator yielded {} than {len} items", if written == len { "more" } else { "fewer" });
        }
        HugeArray { ptr, len, layout: Some(layout) }
    }

    /// Whether the array's memory was advised as huge pages (it spans at least one).
    pub fn huge(&self) -> bool {
        self.layout.is_some_and(|l| l.align() >= HUGE_PAGE)
    }
}

/// Asks the kernel to back `[p, p + size)` (2 MiB aligned, whole pages) with huge pages. A
/// hint: failure (no transparent huge pages on this kernel) changes nothing but speed.
fn advise_huge_pages(p: *mut u8, size: usize) {
    #[cfg(target_os = "linux")]
    // SAFETY: the range is an allocation of ours; madvise with MADV_HUGEPAGE only changes how
    // the kernel backs it, never its contents or validity.
    unsafe {
        libc::madvise(p as *mut libc::c_void, size, libc::MADV_HUGEPAGE);
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (p, size);
}

impl<T: Copy> Drop for HugeArray<T> {
    fn drop(&mut self) {
        if let Some(layout) = self.layout {
            // SAFETY: allocated in `from_slice` with this layout; elements are `Copy` (no drop).
            unsafe { dealloc(self.ptr.as_ptr() as *mut u8, layout) };
        }
    }
}

impl<T: Copy> Default for HugeArray<T> {
    fn default() -> Self {
        HugeArray { ptr: NonNull::dangling(), len: 0, layout: None }
    }
}

impl<T: Copy> Deref for HugeArray<T> {
    type Target = [T];
    #[inline(always)]
    fn deref(&self) -> &[T] {
        // SAFETY: `ptr` holds `len` initialized elements (or is dangling and well aligned with
        // `len == 0`), alive as long as `self`.
        unsafe { std::slice::from_raw_parts(self.ptr.as_ptr(), self.len) }
    }
}

impl<T: Copy> DerefMut for HugeArray<T> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [T] {
        // SAFETY: as in `deref`, and `&mut self` makes this the only reference.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.as_ptr(), self.len) }
    }
}

impl<T: Copy> From<Vec<T>> for HugeArray<T> {
    fn from(v: Vec<T>) -> Self {
        HugeArray::from_slice(&v)
    }
}

impl<T: Copy> Clone for HugeArray<T> {
    fn clone(&self) -> Self {
        HugeArray::from_slice(self)
    }
}

impl<T: Copy + std::fmt::Debug> std::fmt::Debug for HugeArray<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holds_a_copy_of_its_items() {
        for n in [0usize, 1, 7, 1000, (3 * HUGE_PAGE) / 8 + 5] {
            let items: Vec<u64> = (0..n as u64).map(|i| i.wrapping_mul(0x9e37_79b9_7f4a_7c15)).collect();
            let a = HugeArray::from_slice(&items);
            assert_eq!(&a[..], &items[..]);
            assert_eq!(a.huge(), n * 8 >= HUGE_PAGE, "{n}");
            if a.huge() {
                assert_eq!(a.as_ptr() as usize % HUGE_PAGE, 0, "huge arrays start on a huge page");
            }
            let b = a.clone();
            drop(a);
            assert_eq!(&b[..], &items[..]);
        }
    }

    #[test]
    fn fills_from_an_iterator_of_the_stated_length() {
        let n = HUGE_PAGE / 4 + 3;
        let a = HugeArray::from_exact_iter(n, (0..n as u32).map(|i| i ^ 0x5a5a));
        assert!(a.huge() && a.len() == n);
        assert!(a.iter().enumerate().all(|(i, &v)| v == i as u32 ^ 0x5a5a));
        for (len, items) in [(3usize, 2u32), (3, 4), (0, 1)] {
            let r = std::panic::catch_unwind(|| HugeArray::from_exact_iter(len, 0..items));
            assert!(r.is_err(), "{items} items for a length of {len} must be refused");
        }
    }

    #[test]
    fn keeps_the_alignment_of_its_type() {
        #[derive(Clone, Copy, Debug, PartialEq)]
        #[repr(align(64))]
        struct Line([u8; 64]);
        for n in [1usize, 3, HUGE_PAGE / 64 + 1] {
            let a = HugeArray::from(vec![Line([n as u8; 64]); n]);
            assert_eq!(a.as_ptr() as usize % 64, 0);
            assert_eq!(a.len(), n);
            assert!(a.iter().all(|l| *l == Line([n as u8; 64])));
        }
        assert_eq!(HugeArray::from_slice(&[(); 5]).len(), 5, "zero-sized items keep their count");
        let empty: HugeArray<Line> = HugeArray::default();
        assert!(empty.is_empty() && !empty.huge());
        assert_eq!(format!("{:?}", HugeArray::from_slice(&[1u8, 2])), "[1, 2]");
    }
}
