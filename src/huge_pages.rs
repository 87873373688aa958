//! The program's memory allocator: the system's, with transparent huge pages advised for large
//! blocks (Linux).
//!
//! What it does: every block of at least [`THRESHOLD_BYTES`] (64 MiB) that the system
//! allocator returns — fresh from the kernel at that size, so not yet touched — is advised
//! `MADV_HUGEPAGE` over its whole 2 MiB pages before the caller first writes it. The kernel
//! then backs it with 2 MiB pages where it can (the system's transparent-huge-page mode
//! `madvise` or `always`; with `never` the advice does nothing), so touching it costs one
//! page fault per 2 MiB instead of per 4 KiB, and the dense kernels that sweep it miss the TLB
//! less. The sparse factors of the contact patch's submodels (GBs) are where it shows: the
//! default model's patch built in 82 s instead of 103 s (its half problems one after the
//! other; docs/log/performance.md §8.1).
//!
//! Assumptions: a block's memory is the system allocator's to return (it is: the advice
//! changes how pages are backed, not what the block holds); smaller blocks keep the system's
//! behaviour unchanged. Other systems get the system allocator as it is.

use std::alloc::{GlobalAlloc, Layout, System};

/// Blocks from this size (bytes) on are advised huge pages.
pub const THRESHOLD_BYTES: usize = 64 << 20;

/// The huge page size the advice is aligned to (bytes; x86-64 and aarch64 with 4 KiB base
/// pages).
const HUGE_PAGE_BYTES: usize = 2 << 20;

/// The system allocator, advising transparent huge pages for blocks of at least
/// [`THRESHOLD_BYTES`] (see the module doc). Install it in a binary with
/// `#[global_allocator] static A: HugePageAlloc = HugePageAlloc;`.
#[derive(Debug, Clone, Copy, Default)]
pub struct HugePageAlloc;

// SAFETY: every call is forwarded to `System` with the caller's arguments; `advise` only
// gives the kernel advice about pages of the block `System` returned.
unsafe impl GlobalAlloc for HugePageAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `GlobalAlloc::alloc` is `System`'s.
        let p = unsafe { System.alloc(layout) };
        advise(p, layout.size());
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        advise(p, layout.size());
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was returned by `System` for `layout` (every path above).
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as `dealloc`, with the caller's `new_size` contract.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        advise(p, new_size);
        p
    }
}

/// The whole 2 MiB pages inside the block `[p, p + size)` (addresses), if any.
fn huge_range(p: usize, size: usize) -> Option<(usize, usize)> {
    let start = p.checked_add(HUGE_PAGE_BYTES - 1)? & !(HUGE_PAGE_BYTES - 1);
    let end = p.checked_add(size)? & !(HUGE_PAGE_BYTES - 1);
    (end > start).then_some((start, end - start))
}

/// Advises huge pages for the block `[p, p + size)` when it is large (Linux; nothing
/// elsewhere). A refusal by the kernel (a kernel without transparent huge pages) is ignored:
/// the block stays as the system gave it.
fn advise(p: *mut u8, size: usize) {
    if p.is_null() || size < THRESHOLD_BYTES {
        return;
    }
    #[cfg(target_os = "linux")]
    if let Some((start, len)) = huge_range(p as usize, size) {
        // SAFETY: `[start, start + len)` lies inside the block just returned to us, which is
        // mapped; madvise(MADV_HUGEPAGE) does not change its contents.
        unsafe {
            libc::madvise(start as *mut libc::c_void, len, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{huge_range, HugePageAlloc, HUGE_PAGE_BYTES, THRESHOLD_BYTES};
    use std::alloc::{GlobalAlloc, Layout};

    /// The advised range is the whole huge pages inside the block, by hand.
    #[test]
    fn the_advised_range_is_the_whole_huge_pages_inside_the_block() {
        let h = HUGE_PAGE_BYTES;
        assert_eq!(huge_range(h, 3 * h), Some((h, 3 * h)));
        assert_eq!(huge_range(h + 16, 3 * h), Some((2 * h, 2 * h)));
        assert_eq!(huge_range(h + 16, h), None);
        assert_eq!(huge_range(usize::MAX - 8, 3 * h), None);
    }

    /// A large block through every entry point holds what is written to it (the allocator
    /// forwards to the system's; the advice does not change contents), a zeroed one reads
    /// zeros, and a grown one keeps its old contents.
    #[test]
    fn large_blocks_hold_their_contents() {
        let a = HugePageAlloc;
        let n = THRESHOLD_BYTES + 12_345;
        let layout = Layout::from_size_align(n, 8).unwrap();
        // SAFETY: a non-zero layout; every pointer is checked, written within its block and
        // freed with the layout it was allocated with.
        unsafe {
            let z = a.alloc_zeroed(layout);
            assert!(!z.is_null());
            let zs = std::slice::from_raw_parts(z, n);
            assert!(zs.iter().step_by(4093).all(|&b| b == 0) && zs[n - 1] == 0);
            a.dealloc(z, layout);
            let p = a.alloc(layout);
            assert!(!p.is_null());
            for i in (0..n).step_by(4099) {
                *p.add(i) = (i % 251) as u8;
            }
            let q = a.realloc(p, layout, 2 * n);
            assert!(!q.is_null());
            for i in (0..n).step_by(4099) {
                assert_eq!(*q.add(i), (i % 251) as u8);
            }
            a.dealloc(q, Layout::from_size_align(2 * n, 8).unwrap());
        }
    }
}
