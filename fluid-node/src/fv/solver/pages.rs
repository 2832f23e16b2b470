//! The state and the sweep buffer on huge pages where the OS gives them.
//!
//! A y or z sweep reads and writes the state one run of a block's cells at a time (`block.rs`),
//! each run a plane apart (368 kB on 96³): on 4 kB pages every run is a page of its own, and on
//! 128³ (84 MB a buffer) the pages far outnumber what the TLB holds, so most runs wait on a page
//! walk. The buffers are allocated untouched, marked `MADV_HUGEPAGE` (Linux's transparent huge
//! pages in their `madvise` mode, this machine's setting) and only then written, so that their
//! first touch maps 2 MB pages. A hint: nothing changes where the OS declines it, and the values
//! are the same bits either way.

/// A buffer of `len` values equal to `src` (`None`: zeros), asked of the OS on huge pages.
pub(super) fn huge_vec(len: usize, src: Option<&[f64]>) -> Vec<f64> {
    let mut v: Vec<f64> = Vec::with_capacity(len);
    advise_huge(v.as_mut_ptr().cast(), len * size_of::<f64>());
    match src {
        Some(s) => v.extend_from_slice(&s[..len]),
        None => v.resize(len, 0.0),
    }
    v
}

#[cfg(target_os = "linux")]
fn advise_huge(ptr: *mut u8, bytes: usize) {
    const PAGE: usize = 4096;
    // Only large buffers: a small one shares its pages with other allocations.
    if bytes < (4 << 20) {
        return;
    }
    let start = (ptr as usize).next_multiple_of(PAGE);
    let end = (ptr as usize + bytes) / PAGE * PAGE;
    // SAFETY: the range lies inside the allocation `ptr .. ptr + bytes`, which the caller
    // owns; MADV_HUGEPAGE changes how its pages are mapped, never what they hold.
    // A refusal (EINVAL where transparent huge pages are off) leaves the buffer as it was.
    let _ = unsafe { libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE) };
}

#[cfg(not(target_os = "linux"))]
fn advise_huge(_ptr: *mut u8, _bytes: usize) {}
