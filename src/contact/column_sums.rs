//! The dense part of a strip product in vector registers (`contact::influence::strip`'s
//! `Dense`), for any instruction set: for one frequency, the field spectra `y_r = Σ_s S_rs x_s`
//! on a run of rows, as a sum of kernel columns scaled by the source spectra, in blocks of four
//! vectors of rows (three, two or one for the last rows) whose sums stay in registers over all
//! the sources: the kernel's columns are read once per block, so few blocks per run keep them
//! in the nearest cache. The vector operations are a [`Lanes`] implementation per instruction
//! set and precision: AVX2 in `contact::avx2::strip`, AVX-512 in `contact::avx512::strip`.
//! A kernel block whose spectra are real or imaginary only (a [`Part`]) skips the zero part's
//! products. Every route gives the bits of the plain loops (the same operations in the same
//! order per element, no fused multiply-add), which `contact::influence::strip`'s tests check.
//!
//! Safety of [`sums`]: the CPU must support the instruction set of the [`Lanes`]
//! implementation; every source `s` of the groups must have its column `s · cn` with
//! `s · cn + r1 + 4 · L ≤ spec.len()` (`L` the lanes of a vector; a last block reads less than
//! one vector past the run, into lanes it does not store; the bound keeps a margin),
//! `s < src.len()`, and `r1 + 4 · L ≤ acc.len()`: a last block stores whole vectors, less than
//! one past `r1`, so the rows there must be free (not read, or computed by a later run).

use crate::contact::influence::strip::Part;

/// The kernel's spectra of one frequency and the source spectra, real and imaginary parts
/// apart (`spec[s · cn + r]`, `src[s]`), and the field spectra's accumulators (`acc[r]`).
pub(crate) struct Sums<'a, T> {
    pub spec_re: &'a [T],
    pub spec_im: &'a [T],
    pub src_re: &'a [T],
    pub src_im: &'a [T],
    pub acc_re: &'a mut [T],
    pub acc_im: &'a mut [T],
    /// The length of a kernel column (`c · ny`).
    pub cn: usize,
    /// The field rows `r0..r1`.
    pub rows: (usize, usize),
}

/// A run of sources `s0..s1` whose kernel blocks have the non-zero [`Part`] `part`:
/// `(part, s0, s1)`.
pub(crate) type Group = (Part, usize, usize);

/// The vector operations the sums need, in one precision on one instruction set.
///
/// # Safety
/// Every method requires the CPU to support the implementation's instruction set; `load` and
/// `store` require `L` readable or writable values at the pointer.
pub(crate) unsafe trait Lanes {
    /// The precision (`f32` or `f64`).
    type T: Copy + Default;
    /// The values in a vector.
    const L: usize;
    /// The vector.
    type V: Copy;
    unsafe fn zero() -> Self::V;
    unsafe fn splat(x: Self::T) -> Self::V;
    unsafe fn load(p: *const Self::T) -> Self::V;
    unsafe fn store(p: *mut Self::T, v: Self::V);
    unsafe fn add(a: Self::V, b: Self::V) -> Self::V;
    unsafe fn sub(a: Self::V, b: Self::V) -> Self::V;
    unsafe fn mul(a: Self::V, b: Self::V) -> Self::V;
    /// [`sums`] on these lanes, compiled for their instruction set (the entry point the
    /// dense part calls).
    ///
    /// # Safety
    /// The module's contract.
    unsafe fn run(a: Sums<'_, Self::T>, groups: &[Group]);
}

/// The sums of `B` vectors of rows (`yr`, `yi`) over the sources of one group, the products
/// of its [`Part`] only; `pr`, `pi` the kernel's spectra at the block's first row.
#[inline(always)]
unsafe fn group<W: Lanes, const B: usize>(
    a: &Sums<'_, W::T>,
    (part, s0, s1): Group,
    r: usize,
    (yr, yi): (&mut [W::V; B], &mut [W::V; B]),
) {
    let (l, cn) = (W::L, a.cn);
    if part == Part::Zero {
        return;
    }
    // SAFETY: the instruction set and the bounds are the caller's contract (module docs).
    unsafe {
        for s in s0..s1 {
            let (xr, xi) = (
                W::splat(*a.src_re.get_unchecked(s)),
                W::splat(*a.src_im.get_unchecked(s)),
            );
            let (pr, pi) = (
                a.spec_re.as_ptr().add(s * cn + r),
                a.spec_im.as_ptr().add(s * cn + r),
            );
            match part {
                Part::Complex => {
                    for v in 0..B {
                        let (ar, ai) = (W::load(pr.add(v * l)), W::load(pi.add(v * l)));
                        yr[v] = W::add(yr[v], W::sub(W::mul(ar, xr), W::mul(ai, xi)));
                        yi[v] = W::add(yi[v], W::add(W::mul(ar, xi), W::mul(ai, xr)));
                    }
                }
                Part::Real => {
                    for v in 0..B {
                        let ar = W::load(pr.add(v * l));
                        yr[v] = W::add(yr[v], W::mul(ar, xr));
                        yi[v] = W::add(yi[v], W::mul(ar, xi));
                    }
                }
                Part::Imaginary => {
                    for v in 0..B {
                        let ai = W::load(pi.add(v * l));
                        yr[v] = W::sub(yr[v], W::mul(ai, xi));
                        yi[v] = W::add(yi[v], W::mul(ai, xr));
                    }
                }
                Part::Zero => {}
            }
        }
    }
}

/// One block of `B` vectors of rows from row `r`: its sums over the groups' sources into
/// `acc`, whole vectors (past `r1` where the run ends inside the block's last vector).
#[inline(always)]
unsafe fn block<W: Lanes, const B: usize>(a: &mut Sums<'_, W::T>, groups: &[Group], r: usize) {
    let l = W::L;
    // SAFETY: the instruction set and the bounds are the caller's contract (module docs).
    unsafe {
        let mut yr = [W::zero(); B];
        let mut yi = [W::zero(); B];
        for g in groups {
            group::<W, B>(a, *g, r, (&mut yr, &mut yi));
        }
        // the whole block's vectors: past `r1` into rows of a later run or not read
        // (the contract's margin)
        for v in 0..B {
            W::store(a.acc_re.as_mut_ptr().add(r + v * l), yr[v]);
            W::store(a.acc_im.as_mut_ptr().add(r + v * l), yi[v]);
        }
    }
}

/// `acc[r] = Σ_s spec[s·cn + r] · src[s]` (complex, over the groups' sources in order, each
/// group's products those of its [`Part`]) for `r` in the run, as the plain loop: blocks of
/// four vectors, the last rows in the smallest block of three, two or one that holds them. To
/// be inlined into a function compiled for `W`'s instruction set (`#[target_feature]`).
///
/// # Safety
/// The module's contract.
#[inline(always)]
pub(crate) unsafe fn sums<W: Lanes>(mut a: Sums<'_, W::T>, groups: &[Group]) {
    let (l, (r0, r1)) = (W::L, a.rows);
    let mut r = r0;
    while r < r1 {
        // SAFETY: the module's contract.
        unsafe {
            let rest = r1 - r;
            if rest > 3 * l {
                block::<W, 4>(&mut a, groups, r);
                r += 4 * l;
            } else if rest > 2 * l {
                block::<W, 3>(&mut a, groups, r);
                r += 3 * l;
            } else if rest > l {
                block::<W, 2>(&mut a, groups, r);
                r += 2 * l;
            } else {
                block::<W, 1>(&mut a, groups, r);
                r += l;
            }
        }
    }
}

/// A [`Lanes`] implementation `$name` from an instruction set's intrinsics (`$feature` its
/// name as in `#[target_feature]`): precision `$t`, `$l` lanes, vector `$v`, and its zero,
/// splat, unaligned load and store, add, sub and mul; [`Lanes::run`] calls [`sums`] inside a
/// function compiled for `$feature`.
macro_rules! lanes {
    ($name:ident, $feature:literal, $t:ty, $l:literal, $v:ty,
     $zero:ident, $splat:ident, $load:ident, $store:ident, $add:ident, $sub:ident, $mul:ident) => {
        #[doc = concat!("`", stringify!($t), "` in ", $l, " lanes of `", stringify!($v), "` (", $feature, ").")]
        pub(crate) struct $name;

        impl $name {
            /// [`sums`](crate::contact::column_sums::sums) compiled for this instruction set.
            ///
            /// # Safety
            /// `contact::column_sums`' contract.
            #[target_feature(enable = $feature)]
            unsafe fn sums(
                a: $crate::contact::column_sums::Sums<'_, $t>,
                groups: &[$crate::contact::column_sums::Group],
            ) {
                // SAFETY: the caller's contract.
                unsafe { $crate::contact::column_sums::sums::<$name>(a, groups) }
            }
        }

        // SAFETY: every method is an intrinsic of `$feature`, which the trait's contract
        // requires; `load` and `store` touch `$l` values at the pointer, which it requires too.
        unsafe impl $crate::contact::column_sums::Lanes for $name {
            type T = $t;
            const L: usize = $l;
            type V = $v;
            #[inline(always)]
            unsafe fn zero() -> $v {
                // SAFETY: the trait's contract.
                unsafe { $zero() }
            }
            #[inline(always)]
            unsafe fn splat(x: $t) -> $v {
                // SAFETY: the trait's contract.
                unsafe { $splat(x) }
            }
            #[inline(always)]
            unsafe fn load(p: *const $t) -> $v {
                // SAFETY: the trait's contract (`$l` readable values at `p`).
                unsafe { $load(p) }
            }
            #[inline(always)]
            unsafe fn store(p: *mut $t, v: $v) {
                // SAFETY: the trait's contract (`$l` writable values at `p`).
                unsafe { $store(p, v) }
            }
            #[inline(always)]
            unsafe fn add(a: $v, b: $v) -> $v {
                // SAFETY: the trait's contract.
                unsafe { $add(a, b) }
            }
            #[inline(always)]
            unsafe fn sub(a: $v, b: $v) -> $v {
                // SAFETY: the trait's contract.
                unsafe { $sub(a, b) }
            }
            #[inline(always)]
            unsafe fn mul(a: $v, b: $v) -> $v {
                // SAFETY: the trait's contract.
                unsafe { $mul(a, b) }
            }
            unsafe fn run(
                a: $crate::contact::column_sums::Sums<'_, $t>,
                groups: &[$crate::contact::column_sums::Group],
            ) {
                // SAFETY: the trait's contract.
                unsafe { Self::sums(a, groups) }
            }
        }
    };
}
pub(crate) use lanes;
