//! Transposes of complex blocks between the row-major grids and the transposed spectral layout
//! of [`super::Fft2`]: `dst[j · ds + i] = src[i · ss + j]` for `i < rows`, `j < cols`.
//!
//! Pure data movement, so every build gives the same bits. On a CPU with AVX2 (checked at
//! run time) the block is moved in tiles held in 256-bit registers: 4 × 4 elements of
//! `Complex<f32>` (8 bytes each) or 2 × 2 of `Complex<f64>` (16 bytes), instead of one
//! strided element at a time (the scalar form was about a tenth of a passage's time loop,
//! docs/log/performance.md §5.16); the edges that do not fill a tile are moved one by one.

use rustfft::num_complex::Complex;
use rustfft::FftNum;

/// `dst[j · ds + i] = src[i · ss + j]` for `i < rows`, `j < cols` (`ss`, `ds`: the row
/// strides of `src` and `dst`, in elements). Panics if a slice is too short.
pub(super) fn transpose<T: FftNum>(
    src: &[Complex<T>],
    ss: usize,
    dst: &mut [Complex<T>],
    ds: usize,
    (rows, cols): (usize, usize),
) {
    if rows == 0 || cols == 0 {
        return;
    }
    assert!(src.len() >= (rows - 1) * ss + cols && dst.len() >= (cols - 1) * ds + rows);
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        let words = std::mem::size_of::<Complex<T>>() / 8;
        let (ps, pd) = (src.as_ptr().cast::<f64>(), dst.as_mut_ptr().cast::<f64>());
        // SAFETY: AVX2 is present (checked above); the tiles lie inside the block, whose
        // bounds the assertion above checks; `Complex<T>` is two `T` (repr C), so an element
        // of 8 bytes is moved as one f64 lane and one of 16 bytes as two, bits untouched
        // (loads, shuffles and stores only).
        let tiled = unsafe {
            match words {
                1 => Some(crate::contact::avx2::transpose::tiles::<1>(
                    ps, ss, pd, ds, rows, cols,
                )),
                2 => Some(crate::contact::avx2::transpose::tiles::<2>(
                    ps, ss, pd, ds, rows, cols,
                )),
                _ => None,
            }
        };
        if let Some((rt, ct)) = tiled {
            // the edges the tiles leave: the columns right of them, then the rows below
            edges(src, ss, dst, ds, (0, rt), (ct, cols));
            edges(src, ss, dst, ds, (rt, rows), (0, cols));
            return;
        }
    }
    edges(src, ss, dst, ds, (0, rows), (0, cols));
}

/// The plain element-by-element transpose of rows `i0..i1`, columns `j0..j1`.
fn edges<T: FftNum>(
    src: &[Complex<T>],
    ss: usize,
    dst: &mut [Complex<T>],
    ds: usize,
    (i0, i1): (usize, usize),
    (j0, j1): (usize, usize),
) {
    for j in j0..j1 {
        for i in i0..i1 {
            dst[j * ds + i] = src[i * ss + j];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{edges, transpose, Complex, FftNum};
    fn check<T: FftNum + From<f32>>(rows: usize, cols: usize, ss: usize, ds: usize) {
        let src: Vec<Complex<T>> = (0..rows * ss)
            .map(|k| Complex::new(T::from(k as f32), T::from(-(k as f32) - 0.5)))
            .collect();
        let fill = Complex::new(T::from(7.25), T::from(-7.25));
        let mut dst = vec![fill; cols * ds];
        let mut want = dst.clone();
        transpose(&src, ss, &mut dst, ds, (rows, cols));
        edges(&src, ss, &mut want, ds, (0, rows), (0, cols));
        assert_eq!(dst, want, "{rows} x {cols}, strides {ss}, {ds}");
    }

    #[test]
    fn tiled_transpose_moves_every_element_as_the_plain_one() {
        // every remainder of the tiles (rows and columns mod 4 and mod 2), strides wider
        // than the block; the elements outside the block stay untouched
        for rows in [1, 2, 3, 4, 5, 8, 11, 24] {
            for cols in [1, 3, 4, 6, 7, 36] {
                for (ss, ds) in [(cols, rows), (cols + 5, rows + 3)] {
                    check::<f32>(rows, cols, ss, ds);
                    check::<f64>(rows, cols, ss, ds);
                }
            }
        }
    }
}
