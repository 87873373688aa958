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
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(io::ErrorKind::InvalidInput, "output path has no file name")
    })?;
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

/// The process id in the name of a temp file of [`write_atomic`] (`<name>.tmp.<pid>`) or of
/// the PNG writer of [`crate::report::plot`] (`<stem>.tmp<pid>.png`: the encoder picks the
/// format from the extension); `None` for any other name.
pub(crate) fn temp_file_pid(name: &str) -> Option<u32> {
    let digits = |s: &str| -> Option<u32> {
        (!s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
            .then(|| s.parse().ok())
            .flatten()
    };
    if let Some((stem, pid)) = name.rsplit_once(".tmp.") {
        if !stem.is_empty() {
            if let Some(p) = digits(pid) {
                return Some(p);
            }
        }
    }
    let (stem, pid) = name.strip_suffix(".png")?.rsplit_once(".tmp")?;
    if stem.is_empty() {
        return None;
    }
    digits(pid)
}

/// Removes the temp files `<name>.tmp.<pid>` of [`write_atomic`] and `<stem>.tmp<pid>.png` of
/// the PNG writer (`temp_file_pid`) in `dir` (not in its subdirectories) that a killed
/// process left: those of processes no longer running (on Linux, no `/proc/<pid>`; where
/// that cannot be told, none is removed). Returns how many were removed; a missing `dir` has
/// none.
pub fn remove_stale_temp_files(dir: &Path) -> io::Result<usize> {
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(0),
        Err(e) => return Err(e),
    };
    let can_tell = Path::new("/proc/self").exists();
    let mut removed = 0;
    for entry in entries {
        let entry = entry?;
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temp_file_pid) else {
            continue;
        };
        let dead =
            pid != std::process::id() && can_tell && !Path::new(&format!("/proc/{pid}")).exists();
        if dead && entry.file_type()?.is_file() {
            std::fs::remove_file(entry.path())?;
            removed += 1;
        }
    }
    Ok(removed)
}

/// Writes text atomically.
pub fn write_text(path: &Path, text: &str) -> io::Result<()> {
    write_atomic(path, |w| w.write_all(text.as_bytes()))
}

/// Writes a CSV file atomically: a header and rows of numbers (full precision).
pub fn write_csv(
    path: &Path,
    header: &[&str],
    rows: impl IntoIterator<Item = Vec<f64>>,
) -> io::Result<()> {
    write_atomic(path, |w| {
        let mut c = csv::Writer::from_writer(w);
        c.write_record(header)?;
        for row in rows {
            if row.len() != header.len() {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!(
                        "CSV row has {} values, header has {}",
                        row.len(),
                        header.len()
                    ),
                ));
            }
            c.write_record(row.iter().map(|v| format!("{v:e}")))?;
        }
        c.flush()
    })
}

/// Writes a CSV file of text cells atomically: a header and rows (each as long as the
/// header).
pub fn write_text_csv<R, C>(path: &Path, header: &[&str], rows: R) -> io::Result<()>
where
    R: IntoIterator<Item = C>,
    C: IntoIterator,
    C::Item: AsRef<[u8]>,
{
    write_atomic(path, |w| {
        let mut c = csv::Writer::from_writer(w);
        c.write_record(header)?;
        for row in rows {
            c.write_record(row)?;
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
    use super::{temp_file_pid, write_csv, write_npy};
    fn tmpdir(tag: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("corrugation-io-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// Only the writers' own temp names carry a pid; anything else is left alone.
    #[test]
    fn temp_file_names() {
        assert_eq!(temp_file_pid("a.csv.tmp.123"), Some(123));
        assert_eq!(temp_file_pid("psd.tmp4567.png"), Some(4567));
        for other in [
            "a.csv",
            ".tmp.12",
            ".tmp12.png",
            "a.tmp.png",
            "a.tmp12x.png",
            "a.tmp.12x",
            "a.tmp12.svg",
            "notes.tmp",
            "a.tmp.-1",
        ] {
            assert_eq!(temp_file_pid(other), None, "{other}");
        }
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
        assert_eq!(
            std::fs::read_dir(&d).unwrap().count(),
            0,
            "no partial file left"
        );
        write_csv(&p, &["a_m", "b_n"], vec![vec![1.0, 2.0]]).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert_eq!(text, "a_m,b_n\n1e0,2e0\n");
        std::fs::remove_dir_all(d).ok();
    }
}

/// VTK cell type of an 8-node hexahedron.
pub const VTK_HEXAHEDRON: u8 = 12;
/// VTK cell type of a 2-node line (used to draw springs).
pub const VTK_LINE: u8 = 3;
/// VTK cell type of a vertex (used to draw point masses).
pub const VTK_VERTEX: u8 = 1;

/// A named field on points or cells of a VTU file: `components` values per entity.
#[derive(Debug, Clone, Copy)]
pub struct VtuField<'a> {
    /// Field name shown in ParaView.
    pub name: &'a str,
    /// Values per point/cell (1 = scalar, 3 = vector).
    pub components: usize,
    /// `components × count` values, entity-major.
    pub data: &'a [f64],
}

/// Writes an unstructured grid as an ASCII VTK XML `.vtu` file (ParaView), atomically.
/// `cells` are `(vtk_cell_type, node indices)`.
pub fn write_vtu(
    path: &Path,
    points: &[[f64; 3]],
    cells: &[(u8, Vec<usize>)],
    point_fields: &[VtuField],
    cell_fields: &[VtuField],
) -> io::Result<()> {
    let bad = |m: String| io::Error::new(io::ErrorKind::InvalidInput, m);
    for f in point_fields {
        if f.data.len() != f.components * points.len() {
            return Err(bad(format!(
                "point field {} has {} values for {} points",
                f.name,
                f.data.len(),
                points.len()
            )));
        }
    }
    for f in cell_fields {
        if f.data.len() != f.components * cells.len() {
            return Err(bad(format!(
                "cell field {} has {} values for {} cells",
                f.name,
                f.data.len(),
                cells.len()
            )));
        }
    }
    if let Some((_, c)) = cells
        .iter()
        .find(|(_, c)| c.iter().any(|&n| n >= points.len()))
    {
        return Err(bad(format!(
            "cell {c:?} refers to a node beyond {}",
            points.len()
        )));
    }
    write_atomic(path, |w| {
        writeln!(w, r#"<?xml version="1.0"?>"#)?;
        writeln!(
            w,
            r#"<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">"#
        )?;
        writeln!(w, "<UnstructuredGrid>")?;
        writeln!(
            w,
            r#"<Piece NumberOfPoints="{}" NumberOfCells="{}">"#,
            points.len(),
            cells.len()
        )?;
        writeln!(w, "<Points>")?;
        writeln!(
            w,
            r#"<DataArray type="Float64" NumberOfComponents="3" format="ascii">"#
        )?;
        for p in points {
            writeln!(w, "{:e} {:e} {:e}", p[0], p[1], p[2])?;
        }
        writeln!(w, "</DataArray>\n</Points>")?;
        writeln!(w, "<Cells>")?;
        writeln!(
            w,
            r#"<DataArray type="Int64" Name="connectivity" format="ascii">"#
        )?;
        for (_, c) in cells {
            let s: Vec<String> = c.iter().map(|n| n.to_string()).collect();
            writeln!(w, "{}", s.join(" "))?;
        }
        writeln!(w, "</DataArray>")?;
        writeln!(
            w,
            r#"<DataArray type="Int64" Name="offsets" format="ascii">"#
        )?;
        let mut off = 0usize;
        for (_, c) in cells {
            off += c.len();
            writeln!(w, "{off}")?;
        }
        writeln!(w, "</DataArray>")?;
        writeln!(w, r#"<DataArray type="UInt8" Name="types" format="ascii">"#)?;
        for (t, _) in cells {
            writeln!(w, "{t}")?;
        }
        writeln!(w, "</DataArray>\n</Cells>")?;
        for (tag, fields) in [("PointData", point_fields), ("CellData", cell_fields)] {
            writeln!(w, "<{tag}>")?;
            for f in fields {
                writeln!(
                    w,
                    r#"<DataArray type="Float64" Name="{}" NumberOfComponents="{}" format="ascii">"#,
                    f.name, f.components
                )?;
                for chunk in f.data.chunks(f.components.max(1)) {
                    let s: Vec<String> = chunk.iter().map(|v| format!("{v:e}")).collect();
                    writeln!(w, "{}", s.join(" "))?;
                }
                writeln!(w, "</DataArray>")?;
            }
            writeln!(w, "</{tag}>")?;
        }
        writeln!(w, "</Piece>\n</UnstructuredGrid>\n</VTKFile>")
    })
}

#[cfg(test)]
mod vtu_tests {
    use super::{write_vtu, VtuField, VTK_HEXAHEDRON};
    #[test]
    fn vtu_of_one_hexahedron_is_well_formed() {
        let d = std::env::temp_dir().join(format!("corrugation-vtu-{}", std::process::id()));
        let p = d.join("cube.vtu");
        let pts: Vec<[f64; 3]> = (0..8)
            .map(|i| {
                [
                    ((i & 1) ^ ((i >> 1) & 1)) as f64,
                    ((i >> 1) & 1) as f64,
                    (i >> 2) as f64,
                ]
            })
            .collect();
        let part = [0.0];
        let disp: Vec<f64> = (0..24).map(|i| i as f64).collect();
        write_vtu(
            &p,
            &pts,
            &[(VTK_HEXAHEDRON, (0..8).collect())],
            &[VtuField {
                name: "u",
                components: 3,
                data: &disp,
            }],
            &[VtuField {
                name: "part",
                components: 1,
                data: &part,
            }],
        )
        .unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.contains(r#"NumberOfPoints="8" NumberOfCells="1""#));
        assert!(text.contains("0 1 2 3 4 5 6 7\n"));
        assert!(text.trim_end().ends_with("</VTKFile>"));
        // A field of the wrong length is an error, not a corrupt file.
        assert!(write_vtu(
            &p,
            &pts,
            &[],
            &[VtuField {
                name: "u",
                components: 3,
                data: &part
            }],
            &[]
        )
        .is_err());
        std::fs::remove_dir_all(d).ok();
    }
}
