//! Matrix Market output (and input, for tests and tools) of symmetric sparse matrices.
//!
//! Format: NIST Matrix Market exchange format, `coordinate real symmetric` (Boisvert, Pozo &
//! Remington 1996, "The Matrix Market exchange formats: initial design", NISTIR 5935): a
//! header line, a size line `nrows ncols nnz`, then one `row col value` line per entry of
//! the *lower* triangle (row ≥ col), 1-based indices, values with 17 significant digits
//! (round-trips an f64 exactly). Files are written atomically: to `<file>.tmp`, flushed and
//! synced, then renamed over `<file>`.

use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;

use faer::sparse::{SparseColMat, Triplet};

use super::FeError;

fn io_err(path: &Path, e: std::io::Error) -> FeError {
    FeError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// Writes the lower triangle of a symmetric matrix (full or lower storage) as Matrix Market
/// `coordinate real symmetric`. The upper triangle is not read: the caller guarantees
/// symmetry (the assembled K, M, C are symmetric by construction).
pub fn write_symmetric(path: &Path, a: &SparseColMat<usize, f64>) -> Result<(), FeError> {
    if a.nrows() != a.ncols() {
        return Err(FeError::DimensionMismatch {
            what: "Matrix Market symmetric output: columns vs rows".into(),
            expected: a.nrows(),
            got: a.ncols(),
        });
    }
    let ar = a.as_ref();
    let n = a.ncols();
    // K, M and C share one pattern, so lumped M and C hold many explicit zeros: write only
    // the non-zero entries of the lower triangle.
    let lower = |j: usize| {
        ar.row_idx_of_col(j)
            .zip(ar.val_of_col(j))
            .filter(move |&(i, v)| i >= j && *v != 0.0)
    };
    let nnz_lower: usize = (0..n).map(|j| lower(j).count()).sum();
    crate::io::write_atomic(path, |w| {
        writeln!(w, "%%MatrixMarket matrix coordinate real symmetric")?;
        writeln!(
            w,
            "% written by corrugation::fe::mtx (lower triangle, 1-based, non-zeros)"
        )?;
        writeln!(w, "{n} {n} {nnz_lower}")?;
        for j in 0..n {
            for (i, v) in lower(j) {
                writeln!(w, "{} {} {:.16e}", i + 1, j + 1, v)?;
            }
        }
        Ok(())
    })
    .map_err(|e| io_err(path, e))
}

/// Reads a Matrix Market `coordinate real` file (`symmetric` or `general`) into full storage
/// (a symmetric file's lower triangle is mirrored).
pub fn read(path: &Path) -> Result<SparseColMat<usize, f64>, FeError> {
    let pstr = path.display().to_string();
    let perr = |line: usize, reason: String| FeError::MatrixMarketParse {
        path: pstr.clone(),
        line,
        reason,
    };
    let f = File::open(path).map_err(|e| io_err(path, e))?;
    let mut lines = BufReader::new(f).lines().enumerate();
    let (_, header) = lines.next().ok_or_else(|| perr(1, "empty file".into()))?;
    let header = header.map_err(|e| io_err(path, e))?.to_lowercase();
    let h: Vec<&str> = header.split_whitespace().collect();
    if h.len() < 5
        || h[0] != "%%matrixmarket"
        || h[1] != "matrix"
        || h[2] != "coordinate"
        || h[3] != "real"
    {
        return Err(perr(
            1,
            format!("unsupported header '{header}': need 'matrix coordinate real'"),
        ));
    }
    let symmetric = match h[4] {
        "symmetric" => true,
        "general" => false,
        s => return Err(perr(1, format!("unsupported symmetry '{s}'"))),
    };
    let mut size: Option<(usize, usize, usize)> = None;
    let mut trip = Vec::new();
    for (ln, line) in lines {
        let line = line.map_err(|e| io_err(path, e))?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('%') {
            continue;
        }
        let f: Vec<&str> = t.split_whitespace().collect();
        if f.len() != 3 {
            return Err(perr(ln + 1, format!("expected 3 fields, got {}", f.len())));
        }
        let pu = |s: &str| {
            s.parse::<usize>()
                .map_err(|e| perr(ln + 1, format!("'{s}': {e}")))
        };
        match size {
            None => {
                size = Some((pu(f[0])?, pu(f[1])?, pu(f[2])?));
                trip.reserve(2 * pu(f[2])?);
            }
            Some((nr, nc, _)) => {
                let (i, j) = (pu(f[0])?, pu(f[1])?);
                let v: f64 = f[2]
                    .parse()
                    .map_err(|e| perr(ln + 1, format!("'{}': {e}", f[2])))?;
                if i == 0 || j == 0 || i > nr || j > nc {
                    return Err(perr(
                        ln + 1,
                        format!("index ({i}, {j}) outside {nr} × {nc}"),
                    ));
                }
                trip.push(Triplet::new(i - 1, j - 1, v));
                if symmetric && i != j {
                    trip.push(Triplet::new(j - 1, i - 1, v));
                }
            }
        }
    }
    let (nr, nc, nnz) = size.ok_or_else(|| perr(2, "missing size line".into()))?;
    let expected = if symmetric {
        trip.iter().filter(|t| t.row >= t.col).count()
    } else {
        trip.len()
    };
    if expected != nnz {
        return Err(perr(
            2,
            format!("size line says {nnz} entries, file has {expected}"),
        ));
    }
    Ok(SparseColMat::try_new_from_triplets(nr, nc, &trip)?)
}

#[cfg(test)]
mod tests {
    use super::{read, write_symmetric, FeError};
    use crate::fe::block::block_mesh;
    use crate::fe::{assemble, AssemblyOptions, Direction, DofMap, Spring};
    use crate::mesh::Part;

    #[test]
    fn round_trip_is_bit_exact() {
        let mesh = block_mesh([2, 1, 1], [0.2, 0.1, 0.1], 0, Part::Rail);
        let springs = [Spring::node_to_ground(
            0,
            Direction::Z,
            1.234_567_890_123_456_7e8,
            0.0,
        )];
        let dm = DofMap::with_constraints(mesh.nodes.len(), &[0, 1]).unwrap();
        let fm = assemble(
            &mesh,
            &[crate::fe::material::IsotropicElastic::STEEL],
            &springs,
            &[],
            &dm,
            AssemblyOptions::default(),
        )
        .unwrap();
        let dir = std::env::temp_dir().join(format!("corrugation-mtx-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("k.mtx");
        write_symmetric(&path, &fm.k).unwrap();
        assert!(!dir.join("k.mtx.tmp").exists());
        let back = read(&path).unwrap();
        let (a, b) = (fm.k.to_dense(), back.to_dense());
        assert_eq!((a.nrows(), a.ncols()), (b.nrows(), b.ncols()));
        for i in 0..a.nrows() {
            for j in 0..a.ncols() {
                assert_eq!(a[(i, j)], b[(i, j)], "entry ({i}, {j})");
            }
        }
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("%%MatrixMarket matrix coordinate real symmetric\n"));
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(matches!(read(&path), Err(FeError::Io { .. })));
    }
}
