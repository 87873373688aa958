//! The AVX2 kernels of the contact step, in one place: the inner conjugate-gradient loops of
//! the tangential solver ([`cg`]), the tiled transposes of the FFT products ([`transpose`]),
//! and the vector operations of the strip products' dense sums ([`strip`], whose blocks are
//! `contact::column_sums`'). With `contact::avx512` and `contact::column_sums`, the only
//! `unsafe` code of the contact module besides the calls into them.
//!
//! Every kernel is an `unsafe fn` with `#[target_feature(enable = "avx2")]` (or inlined into
//! one): its callers check `is_x86_feature_detected!("avx2")` at run time first and fall back
//! to the plain loops otherwise. Each gives the bits of its plain loop (the same operations in
//! the same order, no fused multiply-add; moves only for the transposes), which the tests of
//! the callers check bit for bit on every remainder of the vector blocks
//! (`contact::influence::transpose`'s, `contact::tangential`'s and
//! `contact::influence::strip`'s tests). The kernel product
//! of the FFT convolutions needs no intrinsics and is dispatched by `pulp`, safely
//! (`contact::influence`).

pub(crate) mod cg;
pub(crate) mod strip;
pub(crate) mod transpose;
