//! Output files: atomic writes (temp file + rename), CSV and `.npy`.
//!
//! Every result file is written to `name.tmp.<pid>` in the same directory and renamed into
//! place only after it is complete and flushed, so an interrupted run never leaves a
//! half-written file that looks complete. `.npy` files load with `numpy.load`; CSV files have
//! a header row whose column names carry units (`x_m`, `fn_n`, ...).

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

use npyz::WriterBuilder;

/// Writes a file atomically: `fill` writes the content into a buffered temp file, which is
/// flushed, synced and renamed over `path`. On error the temp file is removed.
pub fn write_atomic<F>(path: &Path, fill: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(d) = dir {
        std::fs::create_dir_all(d)?;
    }
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "output path has no file name"))?;
    let tmp = path.with_file_name(format!(
        "{}.tmp.{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let mut w = BufWriter::new(File::create(&tmp)?);
        fill(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Writes text atomically.
pub fn write_text(path: &Path, text: &str) -> io::Result<()> {
    write_atomic(path, |w| w.write_all(text.as_bytes()))
}

/// Writes a CSV file atomically: a header and rows of numbers (full precision).
pub fn write_csv(path: &Path, header: &[&str], rows: impl IntoIterator<Item = Vec<f64>>) -> io::Result<()> {
    write_atomic(path, |w| {
        let mut c = csv::Writer::from_writer(w);
        c.write_record(header)?;
        for row in rows {
            if row.len() != header.len() {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!("CSV row has {} values, header has {}", row.len(), header.len()),
                ));
            }
            c.write_record(row.iter().map(|v| format!("{v:e}")))?;
        }
        c.flush()
    })
}

/// Writes an n-d `f64` array (C order, `data.len()` = product of `shape`) as `.npy`, atomically.
pub fn write_npy(path: &Path, shape: &[usize], data: &[f64]) -> io::Result<()> {
    let n: usize = shape.iter().product();
    if n != data.len() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("npy shape {shape:?} holds {n} values, got {}", data.len()),
        ));
    }
    let shape: Vec<u64> = shape.iter().map(|&s| s as u64).collect();
    write_atomic(path, |w| {
        let mut npy = npyz::WriteOptions::<f64>::new()
            .default_dtype()
            .shape(&shape)
            .writer(w)
            .begin_nd()?;
        npy.extend(data.iter().copied())?;
        npy.finish()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmpdir(tag: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("corrugation-io-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn npy_round_trips_through_npyz_reader() {
        let d = tmpdir("npy");
        let p = d.join("a.npy");
        let data: Vec<f64> = (0..6).map(|i| i as f64 * 0.5).collect();
        write_npy(&p, &[2, 3], &data).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        let arr = npyz::NpyFile::new(&bytes[..]).unwrap();
        assert_eq!(arr.shape(), &[2, 3]);
        assert_eq!(arr.into_vec::<f64>().unwrap(), data);
        assert!(write_npy(&p, &[4], &data).is_err());
        std::fs::remove_dir_all(d).ok();
    }

    #[test]
    fn failed_write_leaves_neither_file_nor_temp() {
        let d = tmpdir("atomic");
        let p = d.join("out.csv");
        let r = write_csv(&p, &["a_m", "b_n"], vec![vec![1.0, 2.0], vec![3.0]]);
        assert!(r.is_err());
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0, "no partial file left");
        write_csv(&p, &["a_m", "b_n"], vec![vec![1.0, 2.0]]).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert_eq!(text, "a_m,b_n\n1e0,2e0\n");
        std::fs::remove_dir_all(d).ok();
    }
}
