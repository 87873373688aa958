//! On-disk modal cache: a modal basis (frequencies, mode shapes, per-mode residuals and
//! caller-supplied classification data) stored under a content key.
//!
//! Layout of one entry `DIR/<key hex>/`:
//! * `frequencies_hz.npy` — f64, shape (m,), Hz;
//! * `modes.npy` — f64, shape (n, m), C order (row = DOF, column = mode; `numpy.load` gives the
//!   usual n × m array), M-orthonormal mode shapes;
//! * `meta.json` — [`CacheMeta`]: key, crate version, n, m, f_min/f_max, Sturm count,
//!   per-mode residuals, blake3 hashes of both .npy files, and the caller's
//!   `classification` (any `serde_json::Value`).
//!
//! **Atomicity.** An entry is written into a fresh temporary directory `DIR/.tmp-<key>-<pid>-<n>`
//! and renamed to its final name only when every file is complete and flushed (`rename(2)` of
//! a directory is atomic on POSIX file systems). An interrupted write leaves only a `.tmp-*`
//! directory that is never read. **Integrity.** On load, the blake3 hash of each .npy file is
//! checked against `meta.json` and shapes against the metadata, so a truncated or corrupted
//! entry is reported as [`CacheLookup::Corrupt`] (and can be recomputed and overwritten with
//! [`ModalCache::store`]), never trusted. Auxiliary files of an entry (derived data such as
//! the residual flexibility, [`ModalCache::store_aux`]) carry the blake3 hash of their content
//! on their first line, checked on load: a mismatch is a miss, recomputed.
//!
//! **Size.** [`ModalCache::entries`] lists the entries with their sizes and last use, and
//! [`ModalCache::prune`] removes the least recently used ones (`corrugation cache`); a hit
//! marks its entry used.
//!
//! The key ([`CacheKey`]) is a blake3 hash of labelled parts supplied by the caller (model
//! parameters, mesh, f_max, …) plus the crate version (`CARGO_PKG_VERSION`), so any change of
//! input or program version misses the cache.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use faer::Mat;
use npyz::WriterBuilder;

mod admin;
mod read;
pub use admin::{CacheEntryInfo, PrunePolicy, PruneReport, LEFTOVER_AGE_S};
use serde::{Deserialize, Serialize};

/// Errors of the modal cache.
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    /// File-system error (path and operation given).
    #[error("modal cache: {op} {path}: {source}")]
    Io {
        /// what was being done
        op: &'static str,
        /// the path
        path: PathBuf,
        /// the OS error
        source: std::io::Error,
    },
    /// `store` was handed frequencies and mode columns of different counts.
    #[error("modal cache: {frequencies} frequencies but {columns} mode columns to store")]
    ShapeMismatch {
        /// Number of frequencies.
        frequencies: usize,
        /// Number of mode columns.
        columns: usize,
    },
    /// The metadata could not be serialised.
    #[error("modal cache: meta.json could not be written")]
    Meta(#[from] serde_json::Error),
    /// An auxiliary file name that is not a plain file name.
    #[error("modal cache: auxiliary file name `{name}` must be a plain file name")]
    AuxName {
        /// The name given.
        name: String,
    },
    /// An auxiliary file for an entry that does not exist (derived data lives and dies with
    /// its modes).
    #[error("modal cache: no entry {} to store `{name}` in", dir.display())]
    NoEntry {
        /// The entry's directory.
        dir: PathBuf,
        /// The auxiliary file's name.
        name: String,
    },
}

/// Why a cache entry failed validation on load (it is then recomputed and stored again).
#[derive(Debug, thiserror::Error)]
pub enum CorruptEntry {
    /// A file of the entry could not be read.
    #[error(transparent)]
    Read(#[from] CacheError),
    /// `meta.json` is not valid metadata.
    #[error("meta.json")]
    Meta(#[source] serde_json::Error),
    /// `meta.json` names another key than its directory.
    #[error("meta.json key {found} ≠ directory {expected}")]
    KeyMismatch {
        /// The key in `meta.json`.
        found: String,
        /// The directory's name.
        expected: String,
    },
    /// A data file's blake3 hash differs from the one in `meta.json`.
    #[error("{file} hash mismatch (truncated or corrupted)")]
    HashMismatch {
        /// The file.
        file: &'static str,
    },
    /// A data file is not a readable `.npy` array.
    #[error("{file}")]
    Npy {
        /// The file.
        file: &'static str,
        /// The reader's error.
        #[source]
        source: std::io::Error,
    },
    /// A data file's shape or order disagrees with `meta.json`.
    #[error("{file}: shape {shape:?} does not match meta.json")]
    Shape {
        /// The file.
        file: &'static str,
        /// Its shape.
        shape: Vec<u64>,
    },
}

fn io_err<'a>(op: &'static str, path: &'a Path) -> impl FnOnce(std::io::Error) -> CacheError + 'a {
    move |source| CacheError::Io {
        op,
        path: path.to_path_buf(),
        source,
    }
}

/// Builder of a cache key: a blake3 hash over labelled parts. Each part is hashed as
/// `len(label) ‖ label ‖ tag ‖ len(bytes) ‖ bytes`, so parts cannot run into each other.
/// The crate version is always included.
#[derive(Clone)]
pub struct CacheKey {
    hasher: blake3::Hasher,
}

impl Default for CacheKey {
    fn default() -> Self {
        Self::new()
    }
}

impl CacheKey {
    /// New key seeded with the crate name and version.
    pub fn new() -> Self {
        let k = Self {
            hasher: blake3::Hasher::new(),
        };
        k.str("crate", env!("CARGO_PKG_NAME"))
            .str("version", env!("CARGO_PKG_VERSION"))
    }

    fn part(mut self, label: &str, tag: u8, bytes: &[u8]) -> Self {
        self.hasher.update(&(label.len() as u64).to_le_bytes());
        self.hasher.update(label.as_bytes());
        self.hasher.update(&[tag]);
        self.hasher.update(&(bytes.len() as u64).to_le_bytes());
        self.hasher.update(bytes);
        self
    }

    /// Adds raw bytes (e.g. a serialised mesh).
    pub fn bytes(self, label: &str, bytes: &[u8]) -> Self {
        self.part(label, 0, bytes)
    }

    /// Adds a string (e.g. the TOML model text).
    pub fn str(self, label: &str, s: &str) -> Self {
        self.part(label, 1, s.as_bytes())
    }

    /// Adds an f64 by its exact bit pattern (e.g. f_max in Hz).
    pub fn f64(self, label: &str, x: f64) -> Self {
        self.part(label, 2, &x.to_bits().to_le_bytes())
    }

    /// Adds a slice of f64 (e.g. nodal coordinates) by exact bit patterns.
    pub fn f64s(self, label: &str, xs: &[f64]) -> Self {
        let mut h = blake3::Hasher::new();
        for x in xs {
            h.update(&x.to_bits().to_le_bytes());
        }
        self.part(label, 3, h.finalize().as_bytes())
    }

    /// Adds an integer.
    pub fn u64(self, label: &str, x: u64) -> Self {
        self.part(label, 4, &x.to_le_bytes())
    }

    /// The key as 64 hex characters (the entry's directory name).
    pub fn hex(&self) -> String {
        self.hasher.finalize().to_hex().to_string()
    }
}

/// Metadata stored in `meta.json`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CacheMeta {
    /// Cache key (hex).
    pub key: String,
    /// Crate version that wrote the entry.
    pub crate_version: String,
    /// Number of DOFs n.
    pub n_dofs: usize,
    /// Number of modes m.
    pub n_modes: usize,
    /// Lower band edge (Hz).
    pub f_min_hz: f64,
    /// Upper band edge (Hz).
    pub f_max_hz: f64,
    /// Sturm count at f_max.
    pub sturm_count: usize,
    /// Per-mode relative residual (see `eigen` module doc).
    pub relative_residuals: Vec<f64>,
    /// M-orthonormality error of the basis.
    pub m_orthonormality_error: f64,
    /// blake3 of `frequencies_hz.npy` (hex).
    pub frequencies_blake3: String,
    /// blake3 of `modes.npy` (hex).
    pub modes_blake3: String,
    /// Caller data (mode classification etc.).
    pub classification: serde_json::Value,
}

/// A modal basis as stored in / loaded from the cache.
#[derive(Clone, Debug)]
pub struct CachedModes {
    /// Natural frequencies (Hz), ascending.
    pub frequencies_hz: Vec<f64>,
    /// Mode shapes n × m.
    pub modes: Mat<f64>,
    /// Metadata (includes the caller's classification value).
    pub meta: CacheMeta,
}

/// Result of a lookup.
#[derive(Debug)]
pub enum CacheLookup {
    /// Valid entry.
    Hit(Box<CachedModes>),
    /// No entry for this key.
    Miss,
    /// An entry exists but fails validation (reason given); recompute and store again.
    Corrupt(CorruptEntry),
}

/// The cache directory, and where the work of filling it (eigen-solves, classification,
/// warnings) is reported.
#[derive(Clone)]
pub struct ModalCache {
    dir: PathBuf,
    progress: std::sync::Arc<dyn crate::progress::Progress + Send>,
}

impl std::fmt::Debug for ModalCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ModalCache")
            .field("dir", &self.dir)
            .finish()
    }
}

static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Suggested default cache directory: `$XDG_CACHE_HOME/corrugation`, else
/// `$HOME/.cache/corrugation`, else `./.corrugation-cache`.
pub fn default_cache_dir() -> PathBuf {
    if let Some(x) = std::env::var_os("XDG_CACHE_HOME").filter(|s| !s.is_empty()) {
        return PathBuf::from(x).join("corrugation");
    }
    if let Some(h) = std::env::var_os("HOME").filter(|s| !s.is_empty()) {
        return PathBuf::from(h).join(".cache").join("corrugation");
    }
    PathBuf::from(".corrugation-cache")
}

fn write_npy_1d(path: &Path, data: &[f64]) -> Result<(), CacheError> {
    let f = fs::File::create(path).map_err(io_err("create", path))?;
    let mut bw = std::io::BufWriter::new(f);
    {
        let mut w = npyz::WriteOptions::<f64>::new()
            .default_dtype()
            .shape(&[data.len() as u64])
            .writer(&mut bw)
            .begin_nd()
            .map_err(io_err("write", path))?;
        w.extend(data.iter().copied())
            .map_err(io_err("write", path))?;
        w.finish().map_err(io_err("write", path))?;
    }
    finish_file(path, bw)
}

/// Streams an n × m matrix as a C-order .npy (row = DOF) without an in-memory copy.
fn write_npy_2d(path: &Path, m: &Mat<f64>) -> Result<(), CacheError> {
    let (n, c) = (m.nrows(), m.ncols());
    let f = fs::File::create(path).map_err(io_err("create", path))?;
    let mut bw = std::io::BufWriter::with_capacity(1 << 20, f);
    {
        let mut w = npyz::WriteOptions::<f64>::new()
            .default_dtype()
            .shape(&[n as u64, c as u64])
            .writer(&mut bw)
            .begin_nd()
            .map_err(io_err("write", path))?;
        for i in 0..n {
            w.extend((0..c).map(|j| m[(i, j)]))
                .map_err(io_err("write", path))?;
        }
        w.finish().map_err(io_err("write", path))?;
    }
    finish_file(path, bw)
}

fn finish_file(path: &Path, bw: std::io::BufWriter<fs::File>) -> Result<(), CacheError> {
    let f = bw.into_inner().map_err(|e| CacheError::Io {
        op: "flush",
        path: path.to_path_buf(),
        source: e.into_error(),
    })?;
    f.sync_all().map_err(io_err("sync", path))
}

/// First bytes of an auxiliary file: the tag, then the blake3 hex of the payload and `\n`.
const AUX_HASH_TAG: &str = "blake3 ";

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), CacheError> {
    let mut f = fs::File::create(path).map_err(io_err("create", path))?;
    f.write_all(bytes).map_err(io_err("write", path))?;
    f.sync_all().map_err(io_err("sync", path))?;
    Ok(())
}

fn hash_file(path: &Path) -> Result<(String, Vec<u8>), CacheError> {
    let bytes = fs::read(path).map_err(io_err("read", path))?;
    Ok((blake3::hash(&bytes).to_hex().to_string(), bytes))
}

/// The C-ordered array `file` of the entry `d`, checked against its blake3 hash and shape.
fn read_checked(
    d: &Path,
    file: &'static str,
    blake3_hex: &str,
    shape: &[u64],
) -> Result<Vec<f64>, CorruptEntry> {
    let (h, bytes) = hash_file(&d.join(file))?;
    if h != blake3_hex {
        return Err(CorruptEntry::HashMismatch { file });
    }
    let npy_err = |source| CorruptEntry::Npy { file, source };
    let npy = npyz::NpyFile::new(&bytes[..]).map_err(npy_err)?;
    if npy.shape() != shape || npy.order() != npyz::Order::C {
        return Err(CorruptEntry::Shape {
            file,
            shape: npy.shape().to_vec(),
        });
    }
    npy.into_vec().map_err(npy_err)
}

impl ModalCache {
    /// A cache rooted at `dir` (created on first store); its work is reported to nobody
    /// ([`crate::progress::Silent`]).
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self {
            dir: dir.into(),
            progress: std::sync::Arc::new(crate::progress::Silent),
        }
    }

    /// This cache, reporting the work of filling it (the stages "track modes", "classifying
    /// track modes", …, and warnings) to `progress`.
    pub fn with_progress(
        mut self,
        progress: std::sync::Arc<dyn crate::progress::Progress + Send>,
    ) -> Self {
        self.progress = progress;
        self
    }

    /// Where the work of filling this cache is reported.
    pub fn progress(&self) -> &dyn crate::progress::Progress {
        &*self.progress
    }

    /// The cache's root directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Directory of the entry for `key`.
    pub fn entry_dir(&self, key: &CacheKey) -> PathBuf {
        self.dir.join(key.hex())
    }

    /// Stores a modal basis under `key` atomically (temp dir + rename); replaces an existing
    /// (e.g. corrupt) entry. `meta.key`, `meta.crate_version`, the hashes and the sizes are
    /// filled in here.
    pub fn store(
        &self,
        key: &CacheKey,
        frequencies_hz: &[f64],
        modes: &Mat<f64>,
        mut meta: CacheMeta,
    ) -> Result<PathBuf, CacheError> {
        if modes.ncols() != frequencies_hz.len() {
            return Err(CacheError::ShapeMismatch {
                frequencies: frequencies_hz.len(),
                columns: modes.ncols(),
            });
        }
        fs::create_dir_all(&self.dir).map_err(io_err("create dir", &self.dir))?;
        let hex = key.hex();
        let tmp = self.dir.join(format!(
            ".tmp-{hex}-{}-{}",
            std::process::id(),
            TMP_COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = fs::remove_dir_all(&tmp);
        fs::create_dir(&tmp).map_err(io_err("create dir", &tmp))?;
        let result = (|| {
            let fp = tmp.join("frequencies_hz.npy");
            let mp = tmp.join("modes.npy");
            write_npy_1d(&fp, frequencies_hz)?;
            write_npy_2d(&mp, modes)?;
            meta.key = hex.clone();
            meta.crate_version = env!("CARGO_PKG_VERSION").to_string();
            meta.n_dofs = modes.nrows();
            meta.n_modes = modes.ncols();
            meta.frequencies_blake3 = hash_file(&fp)?.0;
            meta.modes_blake3 = hash_file(&mp)?.0;
            let jp = tmp.join("meta.json");
            let json = serde_json::to_vec_pretty(&meta)?;
            write_file(&jp, &json)?;
            let final_dir = self.dir.join(&hex);
            if final_dir.exists() {
                // Move the old entry aside first (rename onto a non-empty dir fails).
                let old = self.dir.join(format!(
                    ".old-{hex}-{}-{}",
                    std::process::id(),
                    TMP_COUNTER.fetch_add(1, Ordering::Relaxed)
                ));
                fs::rename(&final_dir, &old).map_err(io_err("rename", &final_dir))?;
                let _ = fs::remove_dir_all(&old);
            }
            fs::rename(&tmp, &final_dir).map_err(io_err("rename", &tmp))?;
            Ok(final_dir)
        })();
        if result.is_err() {
            let _ = fs::remove_dir_all(&tmp);
        }
        result
    }

    /// Stores an auxiliary file `name` (derived data of the basis, e.g. the residual
    /// flexibility) inside the existing entry of `key`, atomically (temp file + rename).
    /// Fails when the entry does not exist: derived data lives and dies with its modes.
    /// The file is a line `blake3 <hex of bytes>` and then `bytes`; [`Self::load_aux`]
    /// checks the hash.
    pub fn store_aux(&self, key: &CacheKey, name: &str, bytes: &[u8]) -> Result<(), CacheError> {
        if name.is_empty() || name.contains(['/', '\\']) || name.starts_with('.') {
            return Err(CacheError::AuxName { name: name.into() });
        }
        let d = self.entry_dir(key);
        if !d.is_dir() {
            return Err(CacheError::NoEntry {
                dir: d,
                name: name.into(),
            });
        }
        let tmp = d.join(format!(
            ".tmp-{name}-{}-{}",
            std::process::id(),
            TMP_COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        let mut content = format!("{AUX_HASH_TAG}{}\n", blake3::hash(bytes).to_hex()).into_bytes();
        content.extend_from_slice(bytes);
        let result = write_file(&tmp, &content).and_then(|_| {
            let fin = d.join(name);
            fs::rename(&tmp, &fin).map_err(io_err("rename", &tmp))
        });
        if result.is_err() {
            let _ = fs::remove_file(&tmp);
        }
        result
    }

    /// The auxiliary file `name` of the entry of `key`, if present and its blake3 hash
    /// matches the one stored with it (the caller validates its content). A truncated,
    /// corrupted or hash-less file is `None`, like a missing one: recomputed, never trusted.
    pub fn load_aux(&self, key: &CacheKey, name: &str) -> Option<Vec<u8>> {
        let content = fs::read(self.entry_dir(key).join(name)).ok()?;
        let rest = content.strip_prefix(AUX_HASH_TAG.as_bytes())?;
        let nl = rest.iter().position(|&b| b == b'\n')?;
        let (hex, payload) = (&rest[..nl], &rest[nl + 1..]);
        (hex == blake3::hash(payload).to_hex().as_bytes()).then(|| payload.to_vec())
    }

    /// Looks up `key`; validates hashes, shapes and metadata. A hit marks the entry used
    /// (for [`Self::prune`]).
    pub fn load(&self, key: &CacheKey) -> CacheLookup {
        let hex = key.hex();
        let d = self.dir.join(&hex);
        if !d.is_dir() {
            return CacheLookup::Miss;
        }
        match Self::load_dir(&d, &hex) {
            Ok(c) => {
                admin::touch(&d);
                CacheLookup::Hit(Box::new(c))
            }
            Err(reason) => CacheLookup::Corrupt(reason),
        }
    }

    fn load_dir(d: &Path, hex: &str) -> Result<CachedModes, CorruptEntry> {
        let meta_path = d.join("meta.json");
        let meta_bytes = fs::read(&meta_path).map_err(io_err("read", &meta_path))?;
        let meta: CacheMeta = serde_json::from_slice(&meta_bytes).map_err(CorruptEntry::Meta)?;
        if meta.key != hex {
            return Err(CorruptEntry::KeyMismatch {
                found: meta.key,
                expected: hex.into(),
            });
        }
        let freqs: Vec<f64> = read_checked(
            d,
            "frequencies_hz.npy",
            &meta.frequencies_blake3,
            &[meta.n_modes as u64],
        )?;
        let (n, m) = (meta.n_dofs, meta.n_modes);
        if freqs.len() != m {
            return Err(CorruptEntry::Shape {
                file: "frequencies_hz.npy",
                shape: vec![freqs.len() as u64],
            });
        }
        let modes = read::read_modes(d, "modes.npy", &meta.modes_blake3, n, m)?;
        Ok(CachedModes {
            frequencies_hz: freqs,
            modes,
            meta,
        })
    }
}

impl CacheMeta {
    /// Metadata from a solver result plus the caller's classification value (the hashes,
    /// key and sizes are filled in by [`ModalCache::store`]).
    pub fn from_solution(
        sol: &super::EigenSolution,
        f_min_hz: f64,
        f_max_hz: f64,
        classification: serde_json::Value,
    ) -> Self {
        Self {
            key: String::new(),
            crate_version: String::new(),
            n_dofs: sol.modes.nrows(),
            n_modes: sol.modes.ncols(),
            f_min_hz,
            f_max_hz,
            sturm_count: sol.sturm_count,
            relative_residuals: sol.relative_residuals.clone(),
            m_orthonormality_error: sol.m_orthonormality_error,
            frequencies_blake3: String::new(),
            modes_blake3: String::new(),
            classification,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmpdir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!(
            "corrugation-cache-test-{name}-{}",
            std::process::id()
        ));
        let _ = fs::remove_dir_all(&d);
        d
    }

    pub(super) fn sample() -> (Vec<f64>, Mat<f64>, CacheMeta) {
        let f = vec![0.0, 12.5, 1.0 / 3.0];
        let m = Mat::<f64>::from_fn(5, 3, |i, j| (i as f64 + 1.0) * 0.1 - j as f64 / 7.0);
        let meta = CacheMeta {
            key: String::new(),
            crate_version: String::new(),
            n_dofs: 0,
            n_modes: 0,
            f_min_hz: 0.0,
            f_max_hz: 100.0,
            sturm_count: 3,
            relative_residuals: vec![1e-12, 2e-12, 3e-12],
            m_orthonormality_error: 1e-14,
            frequencies_blake3: String::new(),
            modes_blake3: String::new(),
            classification: serde_json::json!({"kinds": ["rigid", "bending", "compression"]}),
        };
        (f, m, meta)
    }

    #[test]
    fn auxiliary_files_are_checked_against_their_hash() {
        let dir = tmpdir("aux");
        let cache = ModalCache::new(&dir);
        let key = CacheKey::new().str("model", "aux");
        let (f, m, meta) = sample();
        cache.store(&key, &f, &m, meta).unwrap();
        let payload = br#"{"residual": [1.5e-10, 2.5e-10]}"#;
        cache.store_aux(&key, "r.json", payload).unwrap();
        assert_eq!(
            cache.load_aux(&key, "r.json").as_deref(),
            Some(&payload[..])
        );
        let path = cache.entry_dir(&key).join("r.json");
        let good = fs::read(&path).unwrap();
        // One changed digit of a value (still valid JSON), a truncation, a file without the
        // hash line: none is returned.
        let mut flipped = good.clone();
        let i = flipped.len() - 4; // the 1 of 2.5e-10: 2.5e-20
        flipped[i] = if flipped[i] == b'1' { b'2' } else { b'1' };
        for bad in [flipped, good[..good.len() - 3].to_vec(), payload.to_vec()] {
            fs::write(&path, &bad).unwrap();
            assert_eq!(cache.load_aux(&key, "r.json"), None);
        }
        fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn round_trip_is_bit_exact() {
        let dir = tmpdir("rt");
        let cache = ModalCache::new(&dir);
        let key = CacheKey::new().str("model", "a").f64("f_max", 100.0);
        let (f, m, meta) = sample();
        cache.store(&key, &f, &m, meta.clone()).unwrap();
        match cache.load(&key) {
            CacheLookup::Hit(c) => {
                assert_eq!(c.frequencies_hz, f);
                assert_eq!(c.modes, m);
                assert_eq!(c.meta.classification, meta.classification);
                assert_eq!(c.meta.relative_residuals, meta.relative_residuals);
                assert_eq!(c.meta.n_dofs, 5);
            }
            other => panic!("expected hit, got {other:?}"),
        }
        // No temp directories left behind.
        let leftovers = fs::read_dir(&dir)
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .file_name()
                    .to_string_lossy()
                    .starts_with('.')
            })
            .count();
        assert_eq!(leftovers, 0);
        let _ = fs::remove_dir_all(&dir);
    }

    /// A matrix of several read chunks (and a partial last block of rows) comes back bit
    /// for bit, in its column-major layout.
    #[test]
    fn a_matrix_of_several_chunks_round_trips() {
        let dir = tmpdir("chunks");
        let cache = ModalCache::new(&dir);
        let key = CacheKey::new().str("model", "chunks");
        let (n, m) = (3001, 400); // 8 MiB chunks of 2621 rows: two chunks
        let modes = Mat::<f64>::from_fn(n, m, |i, j| (i as f64 * 1e-3 - j as f64).sin() / 7.0);
        let f: Vec<f64> = (0..m).map(|j| j as f64 * 1.5).collect();
        let (_, _, meta) = sample();
        cache.store(&key, &f, &modes, meta).unwrap();
        match cache.load(&key) {
            CacheLookup::Hit(c) => {
                assert_eq!(c.modes, modes);
                assert_eq!(c.frequencies_hz, f);
            }
            other => panic!("expected hit, got {other:?}"),
        }
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn changed_key_misses() {
        let dir = tmpdir("miss");
        let cache = ModalCache::new(&dir);
        let (f, m, meta) = sample();
        let key = CacheKey::new().str("model", "a").f64("f_max", 100.0);
        cache.store(&key, &f, &m, meta).unwrap();
        for other in [
            CacheKey::new().str("model", "b").f64("f_max", 100.0),
            CacheKey::new()
                .str("model", "a")
                .f64("f_max", 100.000_000_1),
            // Same bytes, different labelling: must not collide.
            CacheKey::new().str("mode", "la").f64("f_max", 100.0),
        ] {
            assert_ne!(other.hex(), key.hex());
            assert!(matches!(cache.load(&other), CacheLookup::Miss));
        }
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn truncated_or_corrupted_entry_is_detected_and_replaced() {
        let dir = tmpdir("trunc");
        let cache = ModalCache::new(&dir);
        let (f, m, meta) = sample();
        let key = CacheKey::new().str("model", "t");
        let entry = cache.store(&key, &f, &m, meta.clone()).unwrap();
        // Truncate modes.npy.
        let p = entry.join("modes.npy");
        let bytes = fs::read(&p).unwrap();
        fs::write(&p, &bytes[..bytes.len() - 8]).unwrap();
        assert!(matches!(cache.load(&key), CacheLookup::Corrupt(_)));
        // Recompute-and-store replaces the corrupt entry.
        cache.store(&key, &f, &m, meta.clone()).unwrap();
        assert!(matches!(cache.load(&key), CacheLookup::Hit(_)));
        // Flip one byte of the frequencies (same length).
        let p = entry.join("frequencies_hz.npy");
        let mut bytes = fs::read(&p).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 0x55;
        fs::write(&p, &bytes).unwrap();
        assert!(matches!(cache.load(&key), CacheLookup::Corrupt(_)));
        // Missing meta.json (e.g. a hand-copied partial entry).
        cache.store(&key, &f, &m, meta).unwrap();
        fs::remove_file(entry.join("meta.json")).unwrap();
        assert!(matches!(cache.load(&key), CacheLookup::Corrupt(_)));
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn interrupted_write_is_invisible() {
        // A leftover temp dir (simulated crash before rename) is not an entry.
        let dir = tmpdir("crash");
        let cache = ModalCache::new(&dir);
        let key = CacheKey::new().str("model", "c");
        let tmp = dir.join(format!(".tmp-{}-1-0", key.hex()));
        fs::create_dir_all(&tmp).unwrap();
        fs::write(tmp.join("modes.npy"), b"partial").unwrap();
        assert!(matches!(cache.load(&key), CacheLookup::Miss));
        let _ = fs::remove_dir_all(&dir);
    }
}
