//! The AVX-512 kernels of the contact step, in one place: the vector operations of the strip
//! influence products' dense part ([`strip`]; the per-frequency sums over the source columns
//! of an FE contact patch's kernel, whose blocks are `contact::column_sums`').
//!
//! Every kernel is an `unsafe fn` with `#[target_feature(enable = "avx512f")]`: its caller
//! checks `is_x86_feature_detected!("avx512f")` at run time first and takes the AVX2 kernels or
//! the plain loops otherwise. Each gives the bits of its plain loop (the same operations in the
//! same order per element, no fused multiply-add), which the caller's tests check bit for bit
//! against the scalar reference loops on runs of one to four blocks, several lengths, and one
//! run across the components or one per component.

pub(crate) mod strip;
