//! What the modal cache owns in its directory, and nothing else: the rule that keeps
//! [`ModalCache::prune`] and [`ModalCache::store`] away from anything a user put there.
//!
//! **The ownership rule.** Directly in the cache directory, the cache owns
//! * its *entries*: directories (not links to one) whose name is a key (64 lower-case hex
//!   digits, as [`CacheKey::hex`](super::CacheKey::hex) gives), that hold a `meta.json` or
//!   a `manifest.b3`, and that hold nothing but regular files the cache writes into an
//!   entry: `frequencies_hz.npy`,
//!   `modes.npy`, `meta.json`, `manifest.b3`, auxiliary files (a plain name whose content
//!   begins with the line `blake3 <64 hex digits>`, see [`ModalCache::store_aux`]) and the
//!   hidden temporary files of auxiliary writes (`.tmp-<name>-<pid>-<n>`);
//! * its *leftovers*: directories named `.tmp-<key>-<pid>-<n>` or `.old-<key>-<pid>-<n>` (an
//!   interrupted write or removal) that hold nothing but such files;
//! * its tag, the file `CACHEDIR.TAG`;
//! * the store of fe-patches ([`FE_PATCH_DIR`], `crate::passage::fe_patch`): a directory
//!   named `fe-patch` holding one or more patch directories (32 lower-case hex digits) and
//!   nothing else, each holding one or more of the files a patch is written as and nothing else (`kernel.npy`, `twins.npy`, `grid.txt`,
//!   `complete`, and the temporary files of their atomic writes, `<name>.tmp.<pid>`).
//!
//! Anything else — any other file, link or directory, a key-named directory holding a
//! subdirectory or a file of another kind — is not the cache's: it is never listed, never
//! replaced, never removed. A user's folder cannot pass for an entry unless it consists
//! solely of files the cache itself writes.
//!
//! **The tag.** The cache marks its directory with a `CACHEDIR.TAG` (the Cache Directory
//! Tagging signature, which backup tools honour by skipping the directory) when it stores an
//! entry into a directory that is untagged and holds nothing but entries and leftovers (a new
//! or empty directory, or a cache written before tags). A directory that holds anything else
//! is never tagged: a mistyped cache directory (a project folder) must not vanish from
//! backups. [`ModalCache::check_is_cache`] refuses such a directory for listing and pruning.

use std::fs;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

use super::manifest::is_hex64;
use super::{
    io_err, CacheError, ModalCache, AUX_HASH_TAG, FREQUENCIES_FILE, MANIFEST_FILE, META_FILE,
    MODES_FILE,
};

/// Name of the cache directory's tag file.
pub const TAG_FILE: &str = "CACHEDIR.TAG";

/// Name of the store of fe-patches in the cache directory (see the module doc).
pub const FE_PATCH_DIR: &str = "fe-patch";

/// The files of one fe-patch (see the module doc).
pub const FE_PATCH_FILES: [&str; 4] = ["kernel.npy", "twins.npy", "grid.txt", "complete"];

/// The Cache Directory Tagging signature: the first line of a valid [`TAG_FILE`].
pub(crate) const TAG_SIGNATURE: &str = "Signature: 8a477f597d28d172789f06886806bc55";

/// The whole tag file the cache writes.
const TAG_TEXT: &str = "Signature: 8a477f597d28d172789f06886806bc55\n\
# This file is a cache directory tag created by corrugation: this directory is its modal\n\
# cache (recomputable eigenmodes). See https://bford.info/cachedir/ about such tags.\n";

/// The files [`ModalCache::store`] writes into an entry.
const ENTRY_FILES: [&str; 4] = [FREQUENCIES_FILE, MODES_FILE, META_FILE, MANIFEST_FILE];

/// What an item directly in the cache directory is to the cache.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Item {
    /// The `CACHEDIR.TAG` file.
    Tag,
    /// An entry (see the module doc).
    Entry,
    /// A `.tmp-<key>-*`/`.old-<key>-*` leftover of an interrupted write or removal.
    Leftover,
    /// The store of fe-patches.
    FePatches,
    /// Not the cache's: never touched.
    Other,
}

/// Whether `dir` holds at least one fe-patch directory and nothing but fe-patch directories,
/// each holding at least one fe-patch file and nothing else (module doc): empty folders are
/// not taken for the cache's.
fn holds_only_fe_patches(dir: &Path) -> bool {
    let is_patch_file = |name: &str| {
        FE_PATCH_FILES.contains(&name)
            || FE_PATCH_FILES.iter().any(|f| {
                name.strip_prefix(f)
                    .and_then(|r| r.strip_prefix(".tmp."))
                    .is_some_and(|pid| !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()))
            })
    };
    let only = |d: &Path, ok: &dyn Fn(&fs::DirEntry) -> bool| {
        fs::read_dir(d).is_ok_and(|rd| {
            let items: Vec<_> = rd.collect();
            !items.is_empty() && items.into_iter().all(|e| e.is_ok_and(|e| ok(&e)))
        })
    };
    only(dir, &|e| {
        let name = e.file_name();
        let Some(name) = name.to_str() else {
            return false;
        };
        let hex32 =
            name.len() == 32 && name.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'));
        hex32
            && e.file_type().is_ok_and(|t| t.is_dir())
            && only(&e.path(), &|f| {
                f.file_type().is_ok_and(|t| t.is_file())
                    && f.file_name().to_str().is_some_and(is_patch_file)
            })
    })
}

/// Whether `s` is `-<digits>-<digits>`, the `-<pid>-<counter>` ending of the cache's
/// temporary names.
fn is_pid_counter(s: &str) -> bool {
    let digits = |d: &str| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit());
    s.strip_prefix('-')
        .and_then(|s| s.split_once('-'))
        .is_some_and(|(pid, n)| digits(pid) && digits(n))
}

/// Whether `name` is a leftover's: `.tmp-<key>-<pid>-<n>` or `.old-<key>-<pid>-<n>`.
pub(super) fn is_leftover_name(name: &str) -> bool {
    let Some(rest) = name
        .strip_prefix(".tmp-")
        .or_else(|| name.strip_prefix(".old-"))
    else {
        return false;
    };
    rest.split_at_checked(64)
        .is_some_and(|(key, tail)| is_hex64(key) && is_pid_counter(tail))
}

/// Whether `name` is the temporary name of an auxiliary write: `.tmp-<name>-<pid>-<n>`.
fn is_aux_temp_name(name: &str) -> bool {
    let Some(rest) = name.strip_prefix(".tmp-") else {
        return false;
    };
    let mut parts = rest.rsplitn(3, '-');
    let (n, pid, aux) = (parts.next(), parts.next(), parts.next());
    matches!((n, pid, aux), (Some(n), Some(pid), Some(aux))
        if !aux.is_empty() && is_pid_counter(&format!("-{pid}-{n}")))
}

/// Whether the file `path` (a plain name) begins as an auxiliary file: `blake3 <hex>\n`.
fn is_aux_file(path: &Path) -> bool {
    let head_len = AUX_HASH_TAG.len() + 65;
    let mut head = Vec::with_capacity(head_len);
    let read = fs::File::open(path).and_then(|f| f.take(head_len as u64).read_to_end(&mut head));
    if read.is_err() || head.len() != head_len || head[head_len - 1] != b'\n' {
        return false;
    }
    let hex = std::str::from_utf8(&head[AUX_HASH_TAG.len()..head_len - 1]);
    head.starts_with(AUX_HASH_TAG.as_bytes()) && hex.is_ok_and(is_hex64)
}

/// Whether `dir` holds nothing but regular files the cache writes into an entry (see the
/// module doc); an empty directory does. Anything unreadable counts as not the cache's.
pub(super) fn holds_only_cache_files(dir: &Path) -> bool {
    let Ok(mut rd) = fs::read_dir(dir) else {
        return false;
    };
    rd.all(|e| {
        let Ok(e) = e else { return false };
        let is_file = e.file_type().is_ok_and(|t| t.is_file());
        let name = e.file_name();
        let Some(name) = name.to_str().filter(|_| is_file) else {
            return false;
        };
        ENTRY_FILES.contains(&name)
            || is_aux_temp_name(name)
            || (!name.starts_with('.') && is_aux_file(&e.path()))
    })
}

/// What the item `e` of the cache directory is to the cache (links are never followed).
pub(super) fn classify(e: &fs::DirEntry) -> Item {
    let name = e.file_name();
    let Some(name) = name.to_str() else {
        return Item::Other;
    };
    let Ok(t) = e.file_type() else {
        return Item::Other;
    };
    let p = e.path();
    if name == TAG_FILE && t.is_file() {
        Item::Tag
    } else if !t.is_dir() {
        Item::Other
    } else if is_hex64(name)
        && (p.join(META_FILE).is_file() || p.join(MANIFEST_FILE).is_file())
        && holds_only_cache_files(&p)
    {
        Item::Entry
    } else if is_leftover_name(name) && holds_only_cache_files(&p) {
        Item::Leftover
    } else if name == FE_PATCH_DIR && holds_only_fe_patches(&p) {
        Item::FePatches
    } else {
        Item::Other
    }
}

/// Whether `dir` carries a valid tag (a `CACHEDIR.TAG` beginning with the signature).
fn is_tagged(dir: &Path) -> bool {
    let mut head = Vec::new();
    fs::File::open(dir.join(TAG_FILE))
        .and_then(|f| f.take(TAG_SIGNATURE.len() as u64).read_to_end(&mut head))
        .is_ok_and(|_| head == TAG_SIGNATURE.as_bytes())
}

/// What a directory given as the modal cache holds, as [`ModalCache::survey`] finds it.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct CacheSurvey {
    /// Whether the directory exists (a cache that was never written to does not).
    pub exists: bool,
    /// Whether it carries a valid `CACHEDIR.TAG`.
    pub tagged: bool,
    /// Number of entries (see the ownership rule of the module doc).
    pub entries: usize,
    /// Number of leftovers of interrupted writes or removals.
    pub leftovers: usize,
    /// Number of stored fe-patches and their size (bytes).
    pub fe_patches: usize,
    /// Bytes of the stored fe-patches.
    pub fe_patch_bytes: u64,
    /// Names of the items that are not the cache's (never touched), sorted.
    pub others: Vec<String>,
}

impl CacheSurvey {
    /// Whether the directory may be taken for a modal cache: it does not exist yet, carries
    /// the tag, or holds nothing but entries and leftovers (an empty directory, or a cache
    /// written before tags).
    pub(crate) fn looks_like_cache(&self) -> bool {
        !self.exists || self.tagged || self.others.is_empty()
    }
}

/// Most names of other items an error or a note quotes.
pub(crate) const OTHERS_QUOTED: usize = 5;

/// The first `OTHERS_QUOTED` of `names`, back-quoted and comma-separated, and how many more.
pub fn quote_names(names: &[String]) -> String {
    let mut s = names
        .iter()
        .take(OTHERS_QUOTED)
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > OTHERS_QUOTED {
        s.push_str(&format!(" and {} more", names.len() - OTHERS_QUOTED));
    }
    s
}

impl ModalCache {
    /// What the cache directory holds: its entries, leftovers, tag and the items that are not
    /// the cache's. A directory that does not exist is an empty survey.
    pub fn survey(&self) -> Result<CacheSurvey, CacheError> {
        let rd = match fs::read_dir(self.dir()) {
            Ok(rd) => rd,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(CacheSurvey::default()),
            Err(e) => return Err(io_err("read dir", self.dir())(e)),
        };
        let mut s = CacheSurvey {
            exists: true,
            tagged: is_tagged(self.dir()),
            ..CacheSurvey::default()
        };
        for e in rd {
            let e = e.map_err(io_err("read dir", self.dir()))?;
            match classify(&e) {
                Item::Tag => {}
                Item::Entry => s.entries += 1,
                Item::Leftover => s.leftovers += 1,
                Item::FePatches => {
                    for p in fs::read_dir(e.path()).into_iter().flatten().flatten() {
                        s.fe_patches += 1;
                        for f in fs::read_dir(p.path()).into_iter().flatten().flatten() {
                            s.fe_patch_bytes += f.metadata().map_or(0, |m| m.len());
                        }
                    }
                }
                Item::Other => s.others.push(e.file_name().to_string_lossy().into_owned()),
            }
        }
        s.others.sort();
        Ok(s)
    }

    /// The survey of the cache directory if it may be taken for a modal cache
    /// (`CacheSurvey::looks_like_cache`), else [`CacheError::NotACache`]: an existing,
    /// untagged directory holding other things than entries and leftovers is likely a
    /// mistyped cache directory.
    pub fn check_is_cache(&self) -> Result<CacheSurvey, CacheError> {
        let s = self.survey()?;
        if s.looks_like_cache() {
            Ok(s)
        } else {
            Err(CacheError::NotACache {
                dir: self.dir().to_path_buf(),
                others: s.others,
            })
        }
    }

    /// Writes the directory's `CACHEDIR.TAG` unless it carries one, provided the directory
    /// exists and holds nothing but entries and leftovers (see the module doc: an untagged
    /// directory holding anything else is never tagged). Returns whether the directory is
    /// tagged afterwards.
    pub fn tag_if_cache(&self) -> Result<bool, CacheError> {
        if is_tagged(self.dir()) {
            return Ok(true);
        }
        let s = self.survey()?;
        if !s.exists || !s.others.is_empty() {
            return Ok(false);
        }
        let p = self.dir().join(TAG_FILE);
        super::write_file(&p, TAG_TEXT.as_bytes())?;
        Ok(true)
    }
}

/// `p` made absolute (from the current directory) with its existing part canonicalised
/// (links followed) and the rest, which does not exist yet, appended with `.` and `..`
/// resolved as `create_dir_all` would resolve them.
fn resolve(p: &Path) -> PathBuf {
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut r = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::Prefix(_) | Component::RootDir => r.push(c.as_os_str()),
            Component::CurDir => {}
            // `r` is canonical as far as it exists, so its parent is one `pop` away.
            Component::ParentDir => {
                r.pop();
            }
            Component::Normal(n) => {
                r.push(n);
                if let Ok(canonical) = fs::canonicalize(&r) {
                    r = canonical;
                }
            }
        }
    }
    r
}

/// Refuses an output directory `out` that is the cache directory `cache_dir` or lies inside
/// it ([`CacheError::OutInCache`]): the cache's directory is for its entries. Both paths
/// are resolved first (relative ones from the current directory, existing parts with their
/// links followed, `..` of parts still to be created as `create_dir_all` takes them), then
/// compared component by component. Nothing is created or changed.
pub fn ensure_outside_cache(out: &Path, cache_dir: &Path) -> Result<(), CacheError> {
    let (o, c) = (resolve(out), resolve(cache_dir));
    if o.starts_with(&c) {
        Err(CacheError::OutInCache {
            out: out.to_path_buf(),
            cache: cache_dir.to_path_buf(),
        })
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{ensure_outside_cache, fs, is_aux_temp_name, is_leftover_name, CacheError};
    #[test]
    fn names_of_leftovers_and_auxiliary_temporaries() {
        let key = "0123456789abcdef".repeat(4);
        assert!(is_leftover_name(&format!(".tmp-{key}-12-0")));
        assert!(is_leftover_name(&format!(".old-{key}-1-345")));
        for not in [
            format!(".tmp-{key}-12"),
            format!(".tmp-{key}-12-"),
            format!(".tmp-{key}-a-1"),
            format!(".new-{key}-1-1"),
            format!(".tmp-{}-1-1", &key[1..]),
            format!(".tmp-{}-1-1", key.to_uppercase()),
            ".tmp-notes-1-1".into(),
            format!("{key}-1-1"),
        ] {
            assert!(!is_leftover_name(&not), "{not}");
        }
        assert!(is_aux_temp_name(".tmp-residual-r3-b00ff-n1.json-77-2"));
        assert!(!is_aux_temp_name(".tmp--77-2"));
        assert!(!is_aux_temp_name(".tmp-notes"));
        assert!(!is_aux_temp_name("residual.json-77-2"));
    }

    #[test]
    fn an_output_directory_in_the_cache_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path();
        let cache = root.join("cache");
        fs::create_dir_all(cache.join("sub")).unwrap();
        fs::create_dir_all(root.join("elsewhere")).unwrap();
        std::os::unix::fs::symlink(&cache, root.join("link-to-cache")).unwrap();
        let refused = [
            cache.clone(),
            cache.join("out"),
            cache.join("new/deeper"),
            cache.join("sub/./../out"),
            cache.join("not-yet/../out"),
            root.join("elsewhere/../cache/out"),
            root.join("link-to-cache/out"),
        ];
        for out in &refused {
            match ensure_outside_cache(out, &cache) {
                Err(CacheError::OutInCache { out: o, cache: c }) => {
                    assert_eq!((&o, &c), (out, &cache));
                    let msg = CacheError::OutInCache { out: o, cache: c }.to_string();
                    assert!(msg.contains(&*out.to_string_lossy()), "{msg}");
                    assert!(msg.contains(&*cache.to_string_lossy()), "{msg}");
                }
                other => panic!("{} accepted: {other:?}", out.display()),
            }
        }
        // A cache given through the link, or not created yet, is the same directory.
        assert!(ensure_outside_cache(&cache.join("out"), &root.join("link-to-cache")).is_err());
        let future = root.join("future-cache");
        assert!(ensure_outside_cache(&future.join("out"), &future).is_err());
        for out in [
            root.to_path_buf(),
            root.join("cache2"),
            root.join("cache-out"),
            root.join("elsewhere/out"),
            cache.join("../out"),
        ] {
            assert!(
                ensure_outside_cache(&out, &cache).is_ok(),
                "{} refused",
                out.display()
            );
        }
    }
}
