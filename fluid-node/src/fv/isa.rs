//! The instruction set the line kernel runs on, chosen at run time.
//!
//! The kernel (`line::advance_line` and everything it inlines: the cell and interface passes,
//! OSMP's `Ψ`, the face fluxes, the update) is one body of source compiled several times: for
//! the x86-64 baseline (SSE2), and under `#[target_feature]` for AVX2 and for AVX-512F (the
//! regular face loop is a function of its own in each copy, `line/strip.rs`: `face_loop_on`). The
//! loops of that body run over one array per quantity along the pencil (structure of arrays,
//! `osmp.rs`, `line.rs`), with selects instead of branches on the regular faces, so the
//! compiler vectorises them 2, 4 or 8 lanes wide. One binary runs on any x86-64 CPU:
//! [`Isa::best`] asks the CPU (`is_x86_feature_detected!`) once, and each worker's
//! [`LineScratch`](crate::fv::line::LineScratch) holds the ISA it runs
//! ([`FluidSolver::set_isa`](crate::fv::FluidSolver::set_isa) forces one, for the tests that
//! compare them).
//!
//! Every path gives the same bits. The source has no `mul_add` and no reassociation, and Rust
//! never contracts `a * b + c` into an FMA nor reorders a sum (LLVM does either only under
//! fast-math flags, which Rust does not set): each lane of a vector instruction does the IEEE
//! operation the scalar code names, in the same order (`+ − × ÷ √` are correctly rounded in
//! SSE2, AVX2 and AVX-512 alike, and `min`/`max` are written as the compare-and-select that
//! `minpd`/`maxpd` are). The AVX2 path enables `avx2` alone, not `fma`, so that even an FMA
//! the compiler might form could not exist. The tests `fv::tests_isa` run every path the CPU
//! has on the same states (a line with every kind of face; 3-D steps on one and two threads)
//! and compare the bits.
//!
//! On aarch64 the baseline is NEON (2 lanes of f64), which every aarch64 CPU has, so the
//! baseline path there is already the vector one; an SVE path would be one more
//! `#[target_feature(enable = "sve")]` copy chosen with `is_aarch64_feature_detected!("sve")`,
//! under the same rules (Rust does not contract FMAs on aarch64 either).

/// An instruction set the line kernel is compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// The target's baseline (SSE2 on x86-64, NEON on aarch64).
    Baseline,
    /// x86-64 with AVX2 (4 lanes of f64).
    Avx2,
    /// x86-64 with AVX-512F (8 lanes of f64).
    Avx512,
}

impl Isa {
    /// Every ISA this CPU can run, baseline first.
    pub fn available() -> Vec<Isa> {
        [Isa::Baseline, Isa::Avx2, Isa::Avx512]
            .into_iter()
            .filter(|isa| isa.supported())
            .collect()
    }

    /// Whether this CPU runs `self`.
    pub fn supported(self) -> bool {
        match self {
            Isa::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => std::arch::is_x86_feature_detected!("avx512f"),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The widest ISA this CPU runs (asked once per process).
    pub fn best() -> Isa {
        static BEST: std::sync::OnceLock<Isa> = std::sync::OnceLock::new();
        *BEST.get_or_init(|| {
            Isa::available()
                .pop()
                .expect("the baseline is always available")
        })
    }
}

impl Default for Isa {
    /// [`Isa::best`].
    fn default() -> Isa {
        Isa::best()
    }
}

/// A hint to the CPU to bring the cache line of `p` into the nearest cache (never an access:
/// `p` need not be valid).
///
/// NOTE: `block.rs`'s scatter takes the same read hint. `prefetchw` (the line in the state a
/// store needs) gave the scatter 15–20 % more samples in two alternated profiles.
#[inline(always)]
pub(crate) fn prefetch_line(p: *const f64) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `prefetcht0` reads nothing and faults on no address.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p.cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// The f64 values of one cache line, aligned to it.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct CacheLine([f64; 8]);

/// A growable array of `f64` (a slice through `Deref`) whose entry `8 k − PAD` starts a 64-byte
/// cache line, for the line kernel's scratch arrays: a loop over entries from such an index
/// on reads and writes each vector of AVX-512 from one line, not two.
///
/// NOTE: a `Vec<f64>` is 16-byte aligned by the allocator, so a vector of 8 values at an
/// arbitrary entry straddled two lines 7 times in 8 (`line/strip.rs` states which entries its
/// loops start at, and the `PAD` of each array).
#[derive(Clone, Debug, Default)]
pub struct AlignedVec<const PAD: usize> {
    /// The storage: `PAD` values of padding, then the entries.
    lines: Vec<CacheLine>,
    /// Entries.
    len: usize,
}

impl<const PAD: usize> AlignedVec<PAD> {
    /// Resizes to `len` entries, new ones `value` (as `Vec::resize`; keeps the capacity).
    pub fn resize(&mut self, len: usize, value: f64) {
        let old = self.len;
        self.lines
            .resize((PAD + len).div_ceil(8), CacheLine::default());
        self.len = len;
        if len > old {
            self[old..].fill(value);
        }
    }
}

impl<const PAD: usize> std::ops::Deref for AlignedVec<PAD> {
    type Target = [f64];

    #[inline(always)]
    fn deref(&self) -> &[f64] {
        if self.len == 0 {
            return &[];
        }
        // SAFETY: `CacheLine` is `repr(C)` around `[f64; 8]` (64 bytes, no padding), so the
        // lines are `8 × lines.len() ≥ PAD + len` initialised values in a row.
        unsafe { std::slice::from_raw_parts(self.lines.as_ptr().cast::<f64>().add(PAD), self.len) }
    }
}

impl<const PAD: usize> std::ops::DerefMut for AlignedVec<PAD> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [f64] {
        if self.len == 0 {
            return &mut [];
        }
        // SAFETY: as in `deref`, through the unique borrow of the lines.
        unsafe {
            std::slice::from_raw_parts_mut(self.lines.as_mut_ptr().cast::<f64>().add(PAD), self.len)
        }
    }
}

/// An array of `8 LINES − 8` values of `f64` (a slice through `Deref`) held in place (no heap
/// pointer of its own) whose entry `8 k − PAD` starts a 64-byte cache line, as in
/// [`AlignedVec`]: the line kernel's strip arrays, all in one allocation.
///
/// NOTE: each strip array a `Vec` of its own (`AlignedVec`), every pass of a strip loaded the
/// array's pointer and length, checked its bounds, and checked its outputs against its inputs
/// for overlap at run time (~7,100 of ~58,600 instructions a 128-cell line of a 3-D step);
/// at fixed offsets from one base and of a length fixed at compile time the compiler does both
/// when it compiles: 17 % fewer kernel instructions (AVX2, callgrind, docs/performance.md, hQ).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct FixedVec<const PAD: usize, const LINES: usize>([CacheLine; LINES]);

impl<const PAD: usize, const LINES: usize> FixedVec<PAD, LINES> {
    /// Entries.
    pub const LEN: usize = 8 * LINES - 8;
}

impl<const PAD: usize, const LINES: usize> Default for FixedVec<PAD, LINES> {
    fn default() -> Self {
        const { assert!(PAD < 8 && LINES >= 1) };
        FixedVec([CacheLine::default(); LINES])
    }
}

impl<const PAD: usize, const LINES: usize> std::ops::Deref for FixedVec<PAD, LINES> {
    type Target = [f64];

    #[inline(always)]
    fn deref(&self) -> &[f64] {
        // SAFETY: `CacheLine` is `repr(C)` around `[f64; 8]` (64 bytes, no padding), so the
        // lines are `8 LINES ≥ PAD + LEN` initialised values in a row (`PAD < 8`).
        unsafe { std::slice::from_raw_parts(self.0.as_ptr().cast::<f64>().add(PAD), Self::LEN) }
    }
}

impl<const PAD: usize, const LINES: usize> std::ops::DerefMut for FixedVec<PAD, LINES> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [f64] {
        // SAFETY: as in `deref`, through the unique borrow of the lines.
        unsafe {
            std::slice::from_raw_parts_mut(self.0.as_mut_ptr().cast::<f64>().add(PAD), Self::LEN)
        }
    }
}
