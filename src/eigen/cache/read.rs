//! Reading an entry's mode shapes: one pass over `modes.npy` that hashes the file and moves
//! its little-endian `f64` values straight into the column-major matrix, in chunks of rows,
//! the hashing of a chunk and the reading of the next one running beside the chunk's
//! transposition (two threads). No intermediate copy of the whole array: the memory is the
//! matrix plus two chunks. The values are the file's bit patterns, as a `.npy` reader's.

use std::fs;
use std::io::Read;
use std::path::Path;

use faer::Mat;

use super::{io_err, CorruptEntry};

/// Bytes of one chunk of rows (rounded down to whole rows, at least one row).
const CHUNK_BYTES: usize = 8 << 20;

/// Rows transposed together: their values of consecutive columns share cache lines.
const ROW_BLOCK: usize = 32;

/// A reader that hashes every byte passed through it.
struct Hashing<R> {
    inner: R,
    hasher: blake3::Hasher,
}

impl<R: Read> Read for Hashing<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }
}

/// The n × m matrix of the C-ordered (row = DOF) little-endian `f64` array `file` of the
/// entry `d`, checked against its blake3 hash (hex, of the whole file) and its shape.
pub(super) fn read_modes(
    d: &Path,
    file: &'static str,
    blake3_hex: &str,
    n: usize,
    m: usize,
) -> Result<Mat<f64>, CorruptEntry> {
    let path = d.join(file);
    let f = fs::File::open(&path).map_err(io_err("open", &path))?;
    let bytes = f.metadata().map_err(io_err("stat", &path))?.len();
    let mut r = Hashing {
        inner: std::io::BufReader::with_capacity(1 << 16, f),
        hasher: blake3::Hasher::new(),
    };
    let npy_err = |source| CorruptEntry::Npy { file, source };
    let header = npyz::NpyHeader::from_reader(&mut r).map_err(npy_err)?;
    let f8 = matches!(header.dtype(), npyz::DType::Plain(t) if t.to_string() == "<f8");
    // A file too short for its shape is refused before the matrix is allocated.
    let values = (n as u64).saturating_mul(m as u64);
    let short = bytes < values.saturating_mul(8);
    if header.shape() != [n as u64, m as u64] || header.order() != npyz::Order::C || !f8 || short {
        return Err(CorruptEntry::Shape {
            file,
            shape: header.shape().to_vec(),
        });
    }
    let mut mat = Mat::<f64>::zeros(n, m);
    if m > 0 {
        read_rows(&mut r, &mut mat, &path)?;
    }
    // Whatever follows the array is hashed too: the hash is the whole file's.
    std::io::copy(&mut r, &mut std::io::sink()).map_err(io_err("read", &path))?;
    if r.hasher.finalize().to_hex().as_str() != blake3_hex {
        return Err(CorruptEntry::HashMismatch { file });
    }
    Ok(mat)
}

/// Reads the array's rows into `mat` chunk by chunk (the reader is at the first value).
fn read_rows<R: Read + Send>(
    r: &mut Hashing<R>,
    mat: &mut Mat<f64>,
    path: &Path,
) -> Result<(), super::CacheError> {
    let (n, m) = (mat.nrows(), mat.ncols());
    let row_bytes = 8 * m;
    let rows_per_chunk = (CHUNK_BYTES / row_bytes).max(1);
    let mut cur = vec![0u8; rows_per_chunk.min(n) * row_bytes];
    let mut next = cur.clone();
    let len = |r0: usize| (n - r0).min(rows_per_chunk) * row_bytes;
    let first = len(0);
    r.inner
        .read_exact(&mut cur[..first])
        .map_err(io_err("read", path))?;
    let mut r0 = 0;
    while r0 < n {
        let l = len(r0);
        let r1 = r0 + rows_per_chunk.min(n - r0);
        let l_next = if r1 < n { len(r1) } else { 0 };
        let (read, ()) = rayon::join(
            || {
                r.hasher.update(&cur[..l]);
                r.inner.read_exact(&mut next[..l_next])
            },
            || transpose_rows(&cur[..l], r0, mat),
        );
        read.map_err(io_err("read", path))?;
        std::mem::swap(&mut cur, &mut next);
        r0 = r1;
    }
    Ok(())
}

/// Writes the rows `r0..` held C-ordered as little-endian `f64` in `bytes` into `mat`.
fn transpose_rows(bytes: &[u8], r0: usize, mat: &mut Mat<f64>) {
    let m = mat.ncols();
    let rows = bytes.len() / (8 * m);
    for b0 in (0..rows).step_by(ROW_BLOCK) {
        let b1 = (b0 + ROW_BLOCK).min(rows);
        for j in 0..m {
            let col = &mut mat.col_as_slice_mut(j)[r0 + b0..r0 + b1];
            for (i, x) in (b0..b1).zip(col) {
                let at = 8 * (i * m + j);
                let v: [u8; 8] = bytes[at..at + 8].try_into().expect("8 bytes");
                *x = f64::from_le_bytes(v);
            }
        }
    }
}
