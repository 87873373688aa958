//! On-disk modal cache: a modal basis (frequencies, mode shapes, per-mode residuals and
//! caller-supplied classification data) stored under a content key.
//!
//! Layout of one entry `DIR/<key hex>/` (the key's 64 hex digits, [`CacheKey::hex`]):
//! * `frequencies_hz.npy` — f64, shape (m,), Hz;
//! * `modes.npy` — f64, shape (n, m), C order (row = DOF, column = mode; `numpy.load` gives the
//!   usual n × m array), M-orthonormal mode shapes;
//! * `meta.json` — [`CacheMeta`]: key, crate version, n, m, f_min/f_max, Sturm count,
//!   per-mode residuals, blake3 hashes of both .npy files, and the caller's
//!   `classification` (any `serde_json::Value`);
//! * `manifest.b3` — the blake3 hash of each of the three files above, `meta.json` included,
//!   and a final line with the blake3 hash of the manifest's own preceding content (format in
//!   `cache/manifest.rs`), written last;
//! * auxiliary files ([`ModalCache::store_aux`], derived data such as the residual
//!   flexibility), each carrying the blake3 hash of its content on its first line.
//!
//! The cache directory itself carries a `CACHEDIR.TAG` (the Cache Directory Tagging
//! signature) once the cache has stored an entry in it.
//!
//! **Atomicity.** An entry is written into a fresh temporary directory `DIR/.tmp-<key>-<pid>-<n>`
//! and renamed to its final name only when every file, the manifest last, is complete and
//! flushed (`rename(2)` of a directory is atomic on POSIX file systems). An interrupted write
//! leaves only a `.tmp-*` directory that is never read. **Integrity.** On load, the manifest's
//! own hash is checked, then `meta.json` against the manifest, then the blake3 hash of each
//! .npy file against the manifest and `meta.json`, and the shapes against the metadata, so a
//! truncated, corrupted or edited entry (a mode family relabelled in `meta.json`, say) is
//! reported as [`CacheLookup::Corrupt`] (and recomputed and overwritten with
//! [`ModalCache::store`]), never trusted. An entry without a valid manifest is corrupt too:
//! **entries written before manifests (by earlier builds) are recomputed once**, on
//! their first lookup. Auxiliary files are checked against the hash on their first line: a
//! mismatch is a miss, recomputed.
//!
//! **Ownership.** The cache owns only its entries (key-named directories that hold a
//! `meta.json` or a manifest and nothing but files the cache writes), the hidden
//! `.tmp-<key>-*`/`.old-<key>-*` leftovers of interrupted writes and its tag: the exact rule
//! is in `cache/owned.rs` ([`ModalCache::survey`]). Nothing else in the directory — an output
//! folder, a user's file, a key-named folder holding a user's file — is ever listed, replaced
//! or removed, and an untagged directory holding such things is never tagged and is refused
//! by [`ModalCache::check_is_cache`] (`corrugation cache` without `--force`). An output
//! directory inside the cache is refused up front ([`ensure_outside_cache`]).
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
mod manifest;
mod owned;
mod read;
pub use admin::{CacheEntryInfo, PrunePolicy, PruneReport};
pub use owned::{
    ensure_outside_cache, quote_names, CacheSurvey, FE_PATCH_DIR, FE_PATCH_FILES, TAG_FILE,
};

/// An entry's frequencies (Hz), a 1-D `.npy` array.
pub(crate) const FREQUENCIES_FILE: &str = "frequencies_hz.npy";
/// An entry's mode shapes, a 2-D C-order `.npy` array (row = DOF).
pub(crate) const MODES_FILE: &str = "modes.npy";
/// An entry's metadata ([`CacheMeta`] as JSON).
pub(crate) const META_FILE: &str = "meta.json";
/// An entry's manifest: the blake3 hashes of its files, sealed by its own hash.
pub(crate) const MANIFEST_FILE: &str = "manifest.b3";
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
    /// Something that is not the cache's sits where an entry is to be stored (a link, or a
    /// key-named directory holding files the cache does not write); it is left alone.
    #[error(
        "modal cache: {} is in the way of an entry but is not one (it holds files the cache \
         does not write); move it out of the cache directory",
        dir.display()
    )]
    NotOurs {
        /// The entry's directory.
        dir: PathBuf,
    },
    /// The directory does not look like a modal cache: it exists, carries no `CACHEDIR.TAG`
    /// and holds other things than cache entries (a mistyped cache directory, say).
    #[error(
        "modal cache: {} does not look like a modal cache: it has no {} and holds {} that \
         {} not cache entries; nothing was listed or removed",
        dir.display(),
        owned::TAG_FILE,
        owned::quote_names(others),
        if others.len() == 1 { "is" } else { "are" }
    )]
    NotACache {
        /// The directory.
        dir: PathBuf,
        /// Names of the items in it that are not the cache's.
        others: Vec<String>,
    },
    /// An output directory that is the cache directory or lies inside it.
    #[error(
        "output directory {} is {}the modal cache's directory {}: that directory is for \
         cache entries only; choose an output directory outside it (or another cache \
         directory)",
        out.display(),
        if out_is_cache(out, cache) { "" } else { "inside " },
        cache.display()
    )]
    OutInCache {
        /// The output directory, as given.
        out: PathBuf,
        /// The cache directory, as given.
        cache: PathBuf,
    },
}

/// Whether `out` and `cache` resolve to the same directory (for the message of
/// [`CacheError::OutInCache`]).
fn out_is_cache(out: &Path, cache: &Path) -> bool {
    ensure_outside_cache(cache, out).is_err()
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
    /// The entry has no `manifest.b3`: it was written before manifests, or is an incomplete
    /// copy.
    #[error("no manifest.b3 (an entry written by an earlier build, or an incomplete copy)")]
    NoManifest,
    /// `manifest.b3` is not a valid, sealed manifest.
    #[error("manifest.b3: {reason}")]
    Manifest {
        /// Why it is refused.
        reason: &'static str,
    },
    /// `meta.json` names another hash for a data file than the manifest.
    #[error("meta.json's hash of {file} differs from the manifest's")]
    ManifestDisagrees {
        /// The data file.
        file: &'static str,
    },
    /// `meta.json` names another key than its directory.
    #[error("meta.json key {found} ≠ directory {expected}")]
    KeyMismatch {
        /// The key in `meta.json`.
        found: String,
        /// The directory's name.
        expected: String,
    },
    /// A file's blake3 hash differs from the one the manifest (or `meta.json`) lists.
    #[error("{file} hash mismatch (truncated, corrupted or edited)")]
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
    pub(crate) fn entry_dir(&self, key: &CacheKey) -> PathBuf {
        self.dir.join(key.hex())
    }

    /// Whether an entry for `key` has been written with a manifest (a cheap check for
    /// planning: [`Self::load`] still validates it, and an entry written before manifests is
    /// recomputed).
    pub fn has_entry(&self, key: &CacheKey) -> bool {
        self.entry_dir(key).join(MANIFEST_FILE).is_file()
    }

    /// Stores a modal basis under `key` atomically (temp dir + rename, the manifest written
    /// last); replaces an existing (e.g. corrupt) entry, provided it holds nothing but files
    /// the cache writes (else [`CacheError::NotOurs`], and it is left alone). Tags the cache
    /// directory (`CACHEDIR.TAG`) if it holds nothing but entries and leftovers.
    /// `meta.key`, `meta.crate_version`, the hashes and the sizes are filled in here.
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
        self.tag_if_cache()?;
        let hex = key.hex();
        let final_dir = self.dir.join(&hex);
        Self::check_replaceable(&final_dir)?;
        let tmp = self.dir.join(format!(
            ".tmp-{hex}-{}-{}",
            std::process::id(),
            TMP_COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = fs::remove_dir_all(&tmp);
        fs::create_dir(&tmp).map_err(io_err("create dir", &tmp))?;
        let result = (|| {
            let fp = tmp.join(FREQUENCIES_FILE);
            let mp = tmp.join(MODES_FILE);
            write_npy_1d(&fp, frequencies_hz)?;
            write_npy_2d(&mp, modes)?;
            meta.key = hex.clone();
            meta.crate_version = env!("CARGO_PKG_VERSION").to_string();
            meta.n_dofs = modes.nrows();
            meta.n_modes = modes.ncols();
            meta.frequencies_blake3 = hash_file(&fp)?.0;
            meta.modes_blake3 = hash_file(&mp)?.0;
            let json = serde_json::to_vec_pretty(&meta)?;
            write_file(&tmp.join(META_FILE), &json)?;
            let listed = manifest::Listed {
                frequencies: meta.frequencies_blake3.clone(),
                modes: meta.modes_blake3.clone(),
                meta: blake3::hash(&json).to_hex().to_string(),
            };
            write_file(
                &tmp.join(MANIFEST_FILE),
                manifest::render(&listed).as_bytes(),
            )?;
            // Checked again just before the swap: something may have appeared meanwhile.
            Self::check_replaceable(&final_dir)?;
            if fs::symlink_metadata(&final_dir).is_ok() {
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

    /// Refuses ([`CacheError::NotOurs`]) an existing `dir` where an entry is to be stored
    /// unless it is a directory (not a link) holding nothing but files the cache writes.
    fn check_replaceable(dir: &Path) -> Result<(), CacheError> {
        match fs::symlink_metadata(dir) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
            Err(e) => Err(io_err("stat", dir)(e)),
            Ok(md) if md.is_dir() && owned::holds_only_cache_files(dir) => Ok(()),
            Ok(_) => Err(CacheError::NotOurs {
                dir: dir.to_path_buf(),
            }),
        }
    }

    /// Stores an auxiliary file `name` (derived data of the basis, e.g. the residual
    /// flexibility) inside the existing entry of `key`, atomically (temp file + rename).
    /// Fails when the entry does not exist: derived data lives and dies with its modes.
    /// The file is a line `blake3 <hex of bytes>` and then `bytes`; [`Self::load_aux`]
    /// checks the hash. The name is a plain file name, not hidden and none of the entry's own
    /// files (`meta.json`, …).
    pub fn store_aux(&self, key: &CacheKey, name: &str, bytes: &[u8]) -> Result<(), CacheError> {
        let own = [FREQUENCIES_FILE, MODES_FILE, META_FILE, MANIFEST_FILE].contains(&name);
        if name.is_empty() || name.contains(['/', '\\']) || name.starts_with('.') || own {
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

    /// Looks up `key`; validates the manifest, the hashes of `meta.json` and of the data
    /// files, the shapes and the metadata. A hit marks the entry used (for [`Self::prune`]).
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

    /// The metadata of the entry `d` (named `hex`), checked through its manifest: the
    /// manifest's seal, `meta.json`'s hash, the key, and the data files' hashes in
    /// `meta.json` against the manifest's (the data files themselves are not read).
    fn checked_meta(d: &Path, hex: &str) -> Result<CacheMeta, CorruptEntry> {
        let manifest_path = d.join(MANIFEST_FILE);
        let manifest_bytes = match fs::read(&manifest_path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Err(CorruptEntry::NoManifest)
            }
            Err(e) => return Err(io_err("read", &manifest_path)(e).into()),
        };
        let listed =
            manifest::parse(&manifest_bytes).map_err(|reason| CorruptEntry::Manifest { reason })?;
        let meta_path = d.join(META_FILE);
        let meta_bytes = fs::read(&meta_path).map_err(io_err("read", &meta_path))?;
        if blake3::hash(&meta_bytes).to_hex().as_str() != listed.meta {
            return Err(CorruptEntry::HashMismatch { file: META_FILE });
        }
        let meta: CacheMeta = serde_json::from_slice(&meta_bytes).map_err(CorruptEntry::Meta)?;
        if meta.key != hex {
            return Err(CorruptEntry::KeyMismatch {
                found: meta.key,
                expected: hex.into(),
            });
        }
        if meta.frequencies_blake3 != listed.frequencies {
            return Err(CorruptEntry::ManifestDisagrees {
                file: FREQUENCIES_FILE,
            });
        }
        if meta.modes_blake3 != listed.modes {
            return Err(CorruptEntry::ManifestDisagrees { file: MODES_FILE });
        }
        Ok(meta)
    }

    fn load_dir(d: &Path, hex: &str) -> Result<CachedModes, CorruptEntry> {
        let meta = Self::checked_meta(d, hex)?;
        let freqs: Vec<f64> = read_checked(
            d,
            FREQUENCIES_FILE,
            &meta.frequencies_blake3,
            &[meta.n_modes as u64],
        )?;
        let (n, m) = (meta.n_dofs, meta.n_modes);
        if freqs.len() != m {
            return Err(CorruptEntry::Shape {
                file: FREQUENCIES_FILE,
                shape: vec![freqs.len() as u64],
            });
        }
        let modes = read::read_modes(d, MODES_FILE, &meta.modes_blake3, n, m)?;
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
    pub(crate) fn from_solution(
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
    use super::{
        fs, manifest, CacheError, CacheKey, CacheLookup, CacheMeta, CorruptEntry, Mat, ModalCache,
        PathBuf, FREQUENCIES_FILE, MANIFEST_FILE, META_FILE, MODES_FILE, TAG_FILE,
    };
    use crate::eigen::cache::owned::TAG_SIGNATURE;
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

    /// `meta.json` is checked through the manifest: a relabelled mode family, a changed mode
    /// count or an edited residual — each still valid JSON naming the right key and hashes —
    /// is corrupt, and a store replaces the entry.
    #[test]
    fn an_edited_meta_json_is_corrupt() {
        let dir = tmpdir("meta-edit");
        let cache = ModalCache::new(&dir);
        let (f, m, meta) = sample();
        let key = CacheKey::new().str("model", "meta-edit");
        let entry = cache.store(&key, &f, &m, meta.clone()).unwrap();
        let path = entry.join(META_FILE);
        let good = fs::read_to_string(&path).unwrap();
        let edits = [
            good.replace("\"bending\"", "\"torsion\""),
            good.replace("\"n_modes\": 3", "\"n_modes\": 2"),
            good.replace("1e-12", "1e-11"),
        ];
        for edited in edits {
            assert_ne!(edited, good);
            fs::write(&path, &edited).unwrap();
            match cache.load(&key) {
                CacheLookup::Corrupt(CorruptEntry::HashMismatch { file: META_FILE }) => {}
                other => panic!("edited meta.json: {other:?}"),
            }
        }
        cache.store(&key, &f, &m, meta).unwrap();
        assert!(matches!(cache.load(&key), CacheLookup::Hit(_)));
        let _ = fs::remove_dir_all(&dir);
    }

    /// An entry without a manifest (one written before manifests) or with a broken one is
    /// corrupt, never trusted, and is replaced by the next store.
    #[test]
    fn an_entry_without_a_valid_manifest_is_corrupt_and_replaced() {
        let dir = tmpdir("manifest");
        let cache = ModalCache::new(&dir);
        let (f, m, meta) = sample();
        let key = CacheKey::new().str("model", "manifest");
        let entry = cache.store(&key, &f, &m, meta.clone()).unwrap();
        let path = entry.join(MANIFEST_FILE);
        let good = fs::read_to_string(&path).unwrap();
        assert!(cache.has_entry(&key));
        fs::remove_file(&path).unwrap();
        assert!(!cache.has_entry(&key));
        assert!(matches!(
            cache.load(&key),
            CacheLookup::Corrupt(CorruptEntry::NoManifest)
        ));
        // The legacy entry is still the cache's: listed (not intact), and replaceable.
        let listed = cache.entries().unwrap();
        assert_eq!(listed.len(), 1);
        assert!(listed[0].readable && !listed[0].intact);
        cache.store(&key, &f, &m, meta.clone()).unwrap();
        assert!(matches!(cache.load(&key), CacheLookup::Hit(_)));
        // One changed digit of a listed hash (seal not updated), and a resealed manifest
        // whose modes hash disagrees with meta.json's.
        let first_hash_digit = good.find('\n').unwrap() + 1;
        let mut edited = good.clone().into_bytes();
        edited[first_hash_digit] = if edited[first_hash_digit] == b'0' {
            b'1'
        } else {
            b'0'
        };
        fs::write(&path, &edited).unwrap();
        assert!(matches!(
            cache.load(&key),
            CacheLookup::Corrupt(CorruptEntry::Manifest { .. })
        ));
        let listed = manifest::parse(good.as_bytes()).unwrap();
        let other_modes = manifest::Listed {
            modes: "0".repeat(64),
            ..listed
        };
        fs::write(&path, manifest::render(&other_modes)).unwrap();
        assert!(matches!(
            cache.load(&key),
            CacheLookup::Corrupt(CorruptEntry::ManifestDisagrees { file: MODES_FILE })
        ));
        let _ = fs::remove_dir_all(&dir);
    }

    /// The first store tags the directory it creates; an auxiliary file may not take the
    /// name of one of the entry's own files.
    #[test]
    fn the_first_store_tags_the_directory_and_aux_names_stay_clear_of_the_entry() {
        let dir = tmpdir("tag");
        let cache = ModalCache::new(&dir);
        let (f, m, meta) = sample();
        let key = CacheKey::new().str("model", "tag");
        cache.store(&key, &f, &m, meta).unwrap();
        let tag = fs::read_to_string(dir.join(TAG_FILE)).unwrap();
        assert!(tag.starts_with(&format!("{TAG_SIGNATURE}\n#")), "{tag}");
        for name in [META_FILE, MANIFEST_FILE, MODES_FILE, FREQUENCIES_FILE] {
            assert!(matches!(
                cache.store_aux(&key, name, b"x"),
                Err(CacheError::AuxName { .. })
            ));
        }
        cache.store_aux(&key, "derived.json", b"[1]").unwrap();
        let s = cache.survey().unwrap();
        assert!(s.tagged && s.entries == 1 && s.others.is_empty(), "{s:?}");
        assert!(matches!(cache.load(&key), CacheLookup::Hit(_)));
        let _ = fs::remove_dir_all(&dir);
    }
}
