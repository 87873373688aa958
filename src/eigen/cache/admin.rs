//! Keeping the modal cache's size in hand: listing its entries and removing the least
//! recently used ones.
//!
//! A 5 kHz track basis of the default model is about 1 GB on disk, and every change of a
//! parameter that enters K or M adds an entry, so a cache that is never pruned grows without
//! bound. An entry's *last use* is the modification time of its `meta.json`, which
//! [`ModalCache::load`] refreshes on every hit (a read-only cache simply keeps the time of
//! the store; the time is no part of the content the manifest hashes). Removal renames the
//! entry to a hidden `.old-<key>-*` directory first and deletes that, so a concurrent reader
//! sees either the whole entry or a miss, never a partial one. Hidden
//! `.tmp-<key>-*`/`.old-<key>-*` directories are the leftovers of interrupted writes or
//! removals; they are never read and are removed by [`ModalCache::prune`] once older than a
//! day.
//!
//! Only what the cache owns is listed or removed: its entries and leftovers by the rule of
//! `cache/owned.rs` (a key-named directory with a `meta.json` or manifest holding nothing but
//! files the cache writes; a leftover named by the cache's own pattern). Any other file or
//! directory in the cache directory is left alone, whatever the limits.

use std::fs;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

use super::owned::{classify, Item};
use super::{io_err, CacheError, CacheMeta, ModalCache, META_FILE, TMP_COUNTER};

/// Age after which a hidden `.tmp-*`/`.old-*` leftover is removed by [`ModalCache::prune`]
/// (s): one day, far longer than any write of an entry takes.
pub(crate) const LEFTOVER_AGE_S: u64 = 86_400;

/// One entry of the cache, as listed by [`ModalCache::entries`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct CacheEntryInfo {
    /// The entry's key (hex), its directory's name.
    pub key: String,
    /// The entry's directory.
    pub dir: PathBuf,
    /// Bytes on disk of all the entry's files (B).
    pub bytes: u64,
    /// Whether `meta.json` is readable; a broken entry would be reported corrupt by a lookup
    /// and recomputed.
    pub readable: bool,
    /// Whether the manifest is present and sealed and `meta.json` matches it (the data
    /// files' hashes are checked by a lookup only). An entry that fails this, one written
    /// before manifests say, is recomputed on its next lookup.
    pub intact: bool,
    /// Number of DOFs of the basis (0 when the metadata is unreadable).
    pub n_dofs: usize,
    /// Number of modes (0 when the metadata is unreadable).
    pub n_modes: usize,
    /// Upper band edge (Hz; NaN when the metadata is unreadable).
    pub f_max_hz: f64,
    /// Time since the entry was last stored or loaded (s).
    pub idle_s: f64,
}

/// What [`ModalCache::prune`] removes. An entry goes when either limit asks for it; the
/// least recently used go first.
#[derive(Clone, Copy, Debug, Default)]
pub struct PrunePolicy {
    /// Keep the entries' total size at or below this (B); `None`: no size limit.
    pub max_bytes: Option<u64>,
    /// Remove entries not used for longer than this; `None`: no age limit.
    pub max_idle: Option<Duration>,
    /// Only report what would be removed.
    pub dry_run: bool,
}

/// What [`ModalCache::prune`] did (or, with `dry_run`, would do).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct PruneReport {
    /// Keys of the removed entries, least recently used first.
    pub removed: Vec<String>,
    /// Bytes freed by them (B).
    pub freed_bytes: u64,
    /// Bytes of the entries kept (B).
    pub kept_bytes: u64,
    /// Hidden leftovers of interrupted writes removed (older than `LEFTOVER_AGE_S`).
    pub leftovers_removed: usize,
}

/// Bytes of the files under `d` (B). A file or directory removed while it is being summed
/// (a concurrent prune or store) counts as empty rather than failing the listing.
fn dir_bytes(d: &Path) -> Result<u64, CacheError> {
    let gone = |e: &std::io::Error| e.kind() == std::io::ErrorKind::NotFound;
    let rd = match fs::read_dir(d) {
        Ok(rd) => rd,
        Err(e) if gone(&e) => return Ok(0),
        Err(e) => return Err(io_err("read dir", d)(e)),
    };
    let mut total = 0;
    for e in rd {
        let e = e.map_err(io_err("read dir", d))?;
        let md = match e.metadata() {
            Ok(md) => md,
            Err(err) if gone(&err) => continue,
            Err(err) => return Err(io_err("stat", &e.path())(err)),
        };
        total += if md.is_dir() {
            dir_bytes(&e.path())?
        } else {
            md.len()
        };
    }
    Ok(total)
}

fn age_s(path: &Path, now: SystemTime) -> f64 {
    fs::metadata(path)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| now.duration_since(t).ok())
        .map_or(0.0, |d| d.as_secs_f64())
}

impl ModalCache {
    /// Every entry of the cache (see the ownership rule of `cache/owned.rs`), least recently
    /// used first. A cache directory that does not exist is empty; leftovers, the tag and
    /// anything that is not the cache's are not entries.
    pub fn entries(&self) -> Result<Vec<CacheEntryInfo>, CacheError> {
        let now = SystemTime::now();
        let mut out = Vec::new();
        let rd = match fs::read_dir(self.dir()) {
            Ok(rd) => rd,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(out),
            Err(e) => return Err(io_err("read dir", self.dir())(e)),
        };
        for e in rd {
            let e = e.map_err(io_err("read dir", self.dir()))?;
            if classify(&e) != Item::Entry {
                continue;
            }
            let name = e.file_name().to_string_lossy().into_owned();
            let dir = e.path();
            let meta_path = dir.join(META_FILE);
            let meta: Option<CacheMeta> = fs::read(&meta_path)
                .ok()
                .and_then(|b| serde_json::from_slice(&b).ok());
            let idle_s = age_s(if meta.is_some() { &meta_path } else { &dir }, now);
            let intact = Self::checked_meta(&dir, &name).is_ok();
            out.push(CacheEntryInfo {
                intact,
                key: name,
                bytes: dir_bytes(&dir)?,
                n_dofs: meta.as_ref().map_or(0, |m| m.n_dofs),
                n_modes: meta.as_ref().map_or(0, |m| m.n_modes),
                f_max_hz: meta.as_ref().map_or(f64::NAN, |m| m.f_max_hz),
                readable: meta.is_some(),
                dir,
                idle_s,
            });
        }
        out.sort_by(|a, b| b.idle_s.total_cmp(&a.idle_s).then(a.key.cmp(&b.key)));
        Ok(out)
    }

    /// Removes the least recently used entries until the policy holds, and leftovers older
    /// than `LEFTOVER_AGE_S`. Each entry is renamed aside before it is deleted. Only the
    /// entries of [`Self::entries`] and the cache's own leftovers are ever removed; nothing
    /// else in the directory is touched, whatever the limits.
    pub fn prune(&self, policy: PrunePolicy) -> Result<PruneReport, CacheError> {
        let entries = self.entries()?;
        let mut total: u64 = entries.iter().map(|e| e.bytes).sum();
        let mut report = PruneReport::default();
        for e in &entries {
            let too_big = policy.max_bytes.is_some_and(|m| total > m);
            let too_old = policy.max_idle.is_some_and(|d| e.idle_s > d.as_secs_f64());
            if !(too_big || too_old) {
                continue;
            }
            if !policy.dry_run {
                self.remove_dir(&e.dir, &e.key)?;
            }
            total -= e.bytes;
            report.freed_bytes += e.bytes;
            report.removed.push(e.key.clone());
        }
        report.kept_bytes = total;
        if !policy.dry_run {
            report.leftovers_removed = self.remove_leftovers()?;
        }
        Ok(report)
    }

    fn remove_dir(&self, dir: &Path, key: &str) -> Result<(), CacheError> {
        let aside = self.dir().join(format!(
            ".old-{key}-{}-{}",
            std::process::id(),
            TMP_COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
        ));
        fs::rename(dir, &aside).map_err(io_err("rename", dir))?;
        fs::remove_dir_all(&aside).map_err(io_err("remove", &aside))
    }

    fn remove_leftovers(&self) -> Result<usize, CacheError> {
        let now = SystemTime::now();
        let Ok(rd) = fs::read_dir(self.dir()) else {
            return Ok(0);
        };
        let mut n = 0;
        for e in rd.flatten() {
            let p = e.path();
            if classify(&e) == Item::Leftover && age_s(&p, now) > LEFTOVER_AGE_S as f64 {
                fs::remove_dir_all(&p).map_err(io_err("remove", &p))?;
                n += 1;
            }
        }
        Ok(n)
    }
}

/// Marks the entry `dir` as used now (its `meta.json`'s modification time). Failures are
/// ignored: a read-only cache keeps the time of the store.
pub(super) fn touch(dir: &Path) {
    if let Ok(f) = fs::File::options().append(true).open(dir.join(META_FILE)) {
        let _ = f.set_modified(SystemTime::now());
    }
}

#[cfg(test)]
mod tests {
    use super::{fs, CacheError, Duration, ModalCache, Path, PathBuf, PrunePolicy, SystemTime};
    use crate::eigen::cache::{CacheKey, FE_PATCH_DIR};
    use faer::Mat;

    fn cache(name: &str) -> (ModalCache, PathBuf) {
        let d = std::env::temp_dir().join(format!(
            "corrugation-cache-admin-{name}-{}",
            std::process::id()
        ));
        let _ = fs::remove_dir_all(&d);
        (ModalCache::new(&d), d)
    }

    /// Stores a basis of `n` DOFs and 3 modes (the cache's sample metadata) under `label`.
    fn store(c: &ModalCache, label: &str, n: usize) -> CacheKey {
        let key = CacheKey::new().str("entry", label);
        let (f, _, meta) = crate::eigen::cache::tests::sample();
        let m = Mat::<f64>::from_fn(n, f.len(), |i, j| (i + j) as f64);
        c.store(&key, &f, &m, meta).unwrap();
        key
    }

    fn set_age(c: &ModalCache, key: &CacheKey, age_s: u64) {
        let t = SystemTime::now() - Duration::from_secs(age_s);
        let f = fs::File::options()
            .append(true)
            .open(c.entry_dir(key).join("meta.json"))
            .unwrap();
        f.set_modified(t).unwrap();
    }

    #[test]
    fn entries_are_listed_least_recently_used_first_with_their_sizes() {
        let (c, d) = cache("list");
        assert!(
            c.entries().unwrap().is_empty(),
            "a missing directory is empty"
        );
        let a = store(&c, "a", 10);
        let b = store(&c, "b", 1000);
        set_age(&c, &a, 100);
        set_age(&c, &b, 3600);
        let e = c.entries().unwrap();
        assert_eq!(e.len(), 2);
        assert_eq!(e[0].key, b.hex(), "b was used longest ago");
        assert_eq!((e[0].n_dofs, e[0].n_modes, e[0].f_max_hz), (1000, 3, 100.0));
        assert!(e[0].readable && e[1].readable && e[0].intact && e[1].intact);
        // b's modes alone are 1000 × 3 f64 = 24,000 B of data.
        assert!(e[0].bytes > 24_000 && e[0].bytes < 28_000, "{}", e[0].bytes);
        assert!((e[0].idle_s - 3600.0).abs() < 60.0 && (e[1].idle_s - 100.0).abs() < 60.0);
        fs::remove_dir_all(d).ok();
    }

    #[test]
    fn a_load_marks_the_entry_used() {
        let (c, d) = cache("touch");
        let a = store(&c, "a", 10);
        set_age(&c, &a, 7200);
        assert!(c.entries().unwrap()[0].idle_s > 7000.0);
        assert!(matches!(
            c.load(&a),
            crate::eigen::cache::CacheLookup::Hit(_)
        ));
        assert!(c.entries().unwrap()[0].idle_s < 60.0);
        fs::remove_dir_all(d).ok();
    }

    #[test]
    fn prune_removes_the_least_recently_used_until_the_size_limit_holds() {
        let (c, d) = cache("size");
        let keys: Vec<_> = (0..3).map(|i| store(&c, &format!("{i}"), 1000)).collect();
        for (i, k) in keys.iter().enumerate() {
            set_age(&c, k, 1000 * (3 - i as u64)); // key 0 oldest
        }
        let each = c.entries().unwrap()[0].bytes;
        let policy = PrunePolicy {
            max_bytes: Some(2 * each),
            ..Default::default()
        };
        let dry = c
            .prune(PrunePolicy {
                dry_run: true,
                ..policy
            })
            .unwrap();
        assert_eq!(dry.removed, vec![keys[0].hex()]);
        assert_eq!(c.entries().unwrap().len(), 3, "a dry run removes nothing");
        let r = c.prune(policy).unwrap();
        assert_eq!(r.removed, vec![keys[0].hex()]);
        assert_eq!((r.freed_bytes, r.kept_bytes), (each, 2 * each));
        assert!(matches!(
            c.load(&keys[0]),
            crate::eigen::cache::CacheLookup::Miss
        ));
        assert!(matches!(
            c.load(&keys[2]),
            crate::eigen::cache::CacheLookup::Hit(_)
        ));
        fs::remove_dir_all(d).ok();
    }

    #[test]
    fn prune_by_age_removes_idle_entries_broken_ones_and_old_leftovers() {
        let (c, d) = cache("age");
        let old = store(&c, "old", 10);
        let new = store(&c, "new", 10);
        set_age(&c, &old, 10 * 86_400);
        // A broken entry (key name, unreadable meta.json, no manifest) and an interrupted
        // write's leftover, both old.
        let broken_key = CacheKey::new().str("entry", "broken").hex();
        let broken = d.join(&broken_key);
        fs::create_dir_all(&broken).unwrap();
        fs::write(broken.join("meta.json"), b"{\"key\": ").unwrap();
        let leftover = d.join(format!(".tmp-{broken_key}-1-1"));
        fs::create_dir_all(&leftover).unwrap();
        fs::write(leftover.join("modes.npy"), b"partial").unwrap();
        let t = SystemTime::now() - Duration::from_secs(3 * 86_400);
        for p in [&broken, &leftover] {
            fs::File::open(p).unwrap().set_modified(t).unwrap();
        }
        let listed = c.entries().unwrap();
        let b = listed.iter().find(|e| e.key == broken_key).unwrap();
        assert!(!b.readable && !b.intact);
        let r = c
            .prune(PrunePolicy {
                max_idle: Some(Duration::from_secs(86_400)),
                ..Default::default()
            })
            .unwrap();
        assert_eq!(r.removed.len(), 2, "{r:?}");
        assert!(r.removed.contains(&old.hex()) && r.removed.contains(&broken_key));
        assert_eq!(r.leftovers_removed, 1);
        assert!(!leftover.exists() && !broken.exists());
        assert!(matches!(
            c.load(&new),
            crate::eigen::cache::CacheLookup::Hit(_)
        ));
        fs::remove_dir_all(d).ok();
    }

    /// Things a user put into the cache directory: a folder (an `--out` directory), a file,
    /// a link, a hidden folder, a key-named folder holding a user's file or a subfolder, a
    /// key-named folder of user files without metadata, and a folder named like a leftover
    /// that holds a subfolder. All of them old.
    fn user_items(d: &Path) -> Vec<PathBuf> {
        let t = SystemTime::now() - Duration::from_secs(400 * 86_400);
        let k = |s: &str| CacheKey::new().str("user", s).hex();
        let out = d.join("out");
        fs::create_dir_all(out.join("plots")).unwrap();
        fs::write(out.join("forces.csv"), b"t,f\n0,1\n").unwrap();
        fs::write(d.join("notes.txt"), b"my notes").unwrap();
        std::os::unix::fs::symlink(&out, d.join("link")).unwrap();
        fs::create_dir_all(d.join(".git")).unwrap();
        fs::write(d.join(".git/HEAD"), b"ref").unwrap();
        let with_file = d.join(k("file"));
        fs::create_dir_all(&with_file).unwrap();
        fs::write(with_file.join("meta.json"), b"{}").unwrap();
        fs::write(with_file.join("thesis.tex"), b"\\section{}").unwrap();
        let with_dir = d.join(k("dir"));
        fs::create_dir_all(with_dir.join("data")).unwrap();
        fs::write(with_dir.join("manifest.b3"), b"mine").unwrap();
        let no_meta = d.join(k("no-meta"));
        fs::create_dir_all(&no_meta).unwrap();
        fs::write(no_meta.join("modes.npy"), b"my array").unwrap();
        let leftover_like = d.join(format!(".old-{}-1-1", k("old")));
        fs::create_dir_all(leftover_like.join("keep")).unwrap();
        let items = vec![
            out.join("forces.csv"),
            out.join("plots"),
            d.join("notes.txt"),
            d.join("link"),
            d.join(".git/HEAD"),
            with_file.join("thesis.tex"),
            with_dir.join("data"),
            no_meta.join("modes.npy"),
            leftover_like.join("keep"),
        ];
        for p in [&out, &with_file, &with_dir, &no_meta, &leftover_like] {
            fs::File::open(p).unwrap().set_modified(t).unwrap();
        }
        items
    }

    /// `prune` with a size limit of 0 and an age limit of 0 removes every entry and leftover
    /// and nothing else: a user's folders and files in the cache directory survive, and are
    /// not listed as entries.
    #[test]
    fn user_folders_and_files_in_the_cache_survive_any_prune() {
        let (c, d) = cache("user");
        let a = store(&c, "a", 10);
        let b = store(&c, "b", 10);
        let items = user_items(&d);
        let leftover = d.join(format!(".old-{}-9-9", a.hex()));
        fs::create_dir_all(&leftover).unwrap();
        let t = SystemTime::now() - Duration::from_secs(3 * 86_400);
        fs::File::open(&leftover).unwrap().set_modified(t).unwrap();
        let keys: Vec<String> = c.entries().unwrap().into_iter().map(|e| e.key).collect();
        assert_eq!(keys.len(), 2, "{keys:?}");
        assert!(keys.contains(&a.hex()) && keys.contains(&b.hex()));
        let s = c.survey().unwrap();
        assert_eq!((s.entries, s.leftovers, s.others.len()), (2, 1, 8), "{s:?}");
        let r = c
            .prune(PrunePolicy {
                max_bytes: Some(0),
                max_idle: Some(Duration::ZERO),
                dry_run: false,
            })
            .unwrap();
        assert_eq!(r.removed.len(), 2, "{r:?}");
        assert_eq!((r.leftovers_removed, r.kept_bytes), (1, 0));
        assert!(!leftover.exists());
        for p in &items {
            assert!(
                fs::symlink_metadata(p).is_ok(),
                "{} was removed",
                p.display()
            );
        }
        assert!(c.entries().unwrap().is_empty());
        assert!(d.join(crate::eigen::cache::TAG_FILE).is_file());
        fs::remove_dir_all(d).ok();
    }

    /// A key-named folder that is not the cache's is not replaced by a store either.
    #[test]
    fn a_store_does_not_replace_a_folder_that_is_not_an_entry() {
        let (c, d) = cache("replace");
        let key = CacheKey::new().str("entry", "taken");
        let dir = c.entry_dir(&key);
        fs::create_dir_all(&dir).unwrap();
        fs::write(dir.join("thesis.tex"), b"mine").unwrap();
        let (f, m, meta) = crate::eigen::cache::tests::sample();
        let err = c.store(&key, &f, &m, meta).unwrap_err();
        assert!(matches!(err, CacheError::NotOurs { .. }), "{err}");
        assert!(err.to_string().contains(&*dir.to_string_lossy()), "{err}");
        assert_eq!(fs::read(dir.join("thesis.tex")).unwrap(), b"mine");
        fs::remove_dir_all(d).ok();
    }

    /// A directory with other things than entries and no tag is not taken for a cache (nor
    /// tagged); an empty or missing one, a tagged one and one of entries only are.
    #[test]
    fn a_folder_of_other_things_is_not_taken_for_a_cache() {
        let (c, d) = cache("survey");
        assert!(c.check_is_cache().is_ok(), "a missing directory");
        fs::create_dir_all(&d).unwrap();
        assert!(c.check_is_cache().is_ok(), "an empty directory");
        fs::create_dir_all(d.join("src")).unwrap();
        fs::write(d.join("Cargo.toml"), b"[package]").unwrap();
        let err = c.check_is_cache().unwrap_err();
        let msg = err.to_string();
        assert!(matches!(err, CacheError::NotACache { .. }), "{msg}");
        for s in [&*d.to_string_lossy(), "CACHEDIR.TAG", "`Cargo.toml`, `src`"] {
            assert!(msg.contains(s), "{msg} lacks {s}");
        }
        assert!(!c.tag_if_cache().unwrap());
        // A store into it works but does not tag the user's folder.
        let key = store(&c, "a", 10);
        assert!(!d.join(crate::eigen::cache::TAG_FILE).exists());
        assert!(c.check_is_cache().is_err());
        fs::remove_dir_all(d.join("src")).unwrap();
        fs::remove_file(d.join("Cargo.toml")).unwrap();
        // A legacy cache (entries only, no tag) is accepted and tagged.
        let s = c.check_is_cache().unwrap();
        assert_eq!((s.tagged, s.entries), (false, 1));
        assert!(c.tag_if_cache().unwrap());
        fs::write(d.join("notes.txt"), b"x").unwrap();
        let s = c.check_is_cache().unwrap();
        assert!(s.tagged && s.others == ["notes.txt"], "{s:?}");
        assert!(matches!(
            c.load(&key),
            crate::eigen::cache::CacheLookup::Hit(_)
        ));
        fs::remove_dir_all(d).ok();
    }

    /// The store of fe-patches is the cache's: counted, not an "other" item, and it does not
    /// keep an untagged directory from being tagged; with a foreign file inside it, it is
    /// another item, left alone.
    #[test]
    fn the_fe_patch_store_is_the_caches_own() {
        let (c, d) = cache("fe-patch");
        let p = d
            .join(FE_PATCH_DIR)
            .join("0123456789abcdef0123456789abcdef");
        fs::create_dir_all(&p).unwrap();
        for f in crate::eigen::cache::FE_PATCH_FILES {
            fs::write(p.join(f), b"x").unwrap();
        }
        fs::write(p.join("kernel.npy.tmp.123"), b"xy").unwrap();
        let s = c.survey().unwrap();
        assert!(
            s.others.is_empty() && (s.fe_patches, s.fe_patch_bytes) == (1, 6),
            "{s:?}"
        );
        assert!(
            c.tag_if_cache().unwrap(),
            "an fe-patch store keeps a cache taggable"
        );
        fs::write(p.join("notes.txt"), b"x").unwrap();
        let s = c.survey().unwrap();
        assert_eq!(
            (s.others.clone(), s.fe_patches),
            (vec![FE_PATCH_DIR.to_string()], 0)
        );
        // an empty store is not taken for the cache's
        fs::remove_dir_all(d.join(FE_PATCH_DIR)).unwrap();
        fs::create_dir_all(d.join(FE_PATCH_DIR)).unwrap();
        assert_eq!(c.survey().unwrap().others, vec![FE_PATCH_DIR.to_string()]);
        fs::remove_dir_all(d).ok();
    }
}
