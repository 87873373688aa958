//! Joining the shard directories of a sweep into the unsharded result.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::run::{read_summary, same_speed};
use super::{assemble, speed_file, MapOptions, StudiesError, SweepMaps, SweepRecord, RUN_KEY_FILE};

/// Reads `sweep.json` of a sweep directory.
pub(crate) fn read_record(dir: &Path) -> Result<SweepRecord, StudiesError> {
    let p = dir.join("sweep.json");
    let text = std::fs::read_to_string(&p).map_err(StudiesError::io(&p))?;
    serde_json::from_str(&text).map_err(|e| StudiesError::BadFile {
        path: p,
        reason: format!("not a sweep record ({e}); rerun the sweep of this shard"),
    })
}

/// The shard plan file in `DIR/speeds`: which shard of which sweep the directory holds
/// ([`ShardPlan`]), written by [`write_shard_plan`] before the passages and checked by
/// [`merge`].
pub(crate) const SHARD_PLAN_FILE: &str = "shard.json";

/// Which shard of which sweep a sweep directory holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ShardPlan {
    /// Shard index `I` (0 … count−1).
    pub index: usize,
    /// Shard count `N`.
    pub count: usize,
    /// Every speed of the whole sweep (km/h), ascending.
    pub speeds_kmh: Vec<f64>,
}

/// Writes `dir/speeds/shard.json`: `dir` holds shard `shard` of the sweep of `all_speeds_kmh`.
pub fn write_shard_plan(
    dir: &Path,
    all_speeds_kmh: &[f64],
    shard: super::super::speeds::Shard,
) -> Result<(), StudiesError> {
    let p = dir.join("speeds").join(SHARD_PLAN_FILE);
    let plan = ShardPlan {
        index: shard.index,
        count: shard.count,
        speeds_kmh: all_speeds_kmh.to_vec(),
    };
    let text = serde_json::to_string_pretty(&plan).map_err(|source| StudiesError::Json {
        what: "shard plan",
        source,
    })?;
    if let Some(parent) = p.parent() {
        std::fs::create_dir_all(parent).map_err(StudiesError::io(parent))?;
    }
    crate::io::write_text(&p, &text).map_err(StudiesError::io(&p))
}

fn read_shard_plan(dir: &Path) -> Result<ShardPlan, StudiesError> {
    let p = dir.join("speeds").join(SHARD_PLAN_FILE);
    let text = std::fs::read_to_string(&p).map_err(StudiesError::io(&p))?;
    serde_json::from_str(&text).map_err(|e| StudiesError::BadFile {
        path: p,
        reason: format!("not a shard plan ({e}); rerun the sweep of this shard"),
    })
}

/// Checks that the shard directories form one complete sweep: the same sweep (speeds and
/// shard count) in each, every shard `0 … N−1` exactly once, and each finished with its
/// shard's speeds (from its `sweep.json`).
fn check_shards(dirs: &[PathBuf], records: &[SweepRecord]) -> Result<(), StudiesError> {
    let plans = dirs
        .iter()
        .map(|d| read_shard_plan(d))
        .collect::<Result<Vec<_>, _>>()?;
    let first = &plans[0];
    let count = first.count;
    let mut given: Vec<Option<&PathBuf>> = vec![None; count];
    for ((d, p), rec) in dirs.iter().zip(&plans).zip(records) {
        if p.count != count
            || p.speeds_kmh.len() != first.speeds_kmh.len()
            || p.speeds_kmh
                .iter()
                .zip(&first.speeds_kmh)
                .any(|(a, b)| !same_speed(*a, *b))
            || p.index >= count
        {
            return Err(StudiesError::ShardsOfDifferentSweeps {
                first: dirs[0].clone(),
                second: d.clone(),
            });
        }
        if let Some(prev) = given[p.index] {
            return Err(StudiesError::ShardTwice {
                index: p.index,
                count,
                first: prev.clone(),
                second: d.clone(),
            });
        }
        given[p.index] = Some(d);
        let want = super::super::speeds::Shard {
            index: p.index,
            count,
        }
        .select(&p.speeds_kmh);
        let same = want.len() == rec.speeds_kmh.len()
            && want
                .iter()
                .zip(&rec.speeds_kmh)
                .all(|(a, b)| same_speed(*a, *b));
        if !same {
            return Err(StudiesError::ShardUnfinished {
                dir: d.clone(),
                index: p.index,
                count,
                have: rec.speeds_kmh.len(),
                want: want.len(),
            });
        }
    }
    let missing: Vec<usize> = (0..count).filter(|&i| given[i].is_none()).collect();
    if !missing.is_empty() {
        return Err(StudiesError::ShardsMissing { count, missing });
    }
    Ok(())
}

/// Refuses an output directory that is, lies inside or contains one of `dirs` (compared as
/// canonical paths; a part of `out` that does not exist yet is taken as written).
fn check_out_apart(dirs: &[PathBuf], out: &Path) -> Result<(), StudiesError> {
    let o = canonical_lenient(out);
    for d in dirs {
        let c = canonical_lenient(d);
        let relation = if o == c {
            "is"
        } else if o.starts_with(&c) {
            "lies inside"
        } else if c.starts_with(&o) {
            "contains"
        } else {
            continue;
        };
        return Err(StudiesError::OutputOverlapsShard {
            out: out.to_path_buf(),
            shard: d.clone(),
            relation,
        });
    }
    Ok(())
}

/// `p` made absolute with its longest existing ancestor canonicalised (symbolic links and
/// `..` resolved) and the rest appended as written.
fn canonical_lenient(p: &Path) -> PathBuf {
    let abs = if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir().unwrap_or_default().join(p)
    };
    let mut rest = Vec::new();
    let mut head = abs.as_path();
    loop {
        if let Ok(c) = head.canonicalize() {
            return rest
                .iter()
                .rev()
                .fold(c, |acc: PathBuf, part| acc.join(part));
        }
        match (head.parent(), head.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                head = parent;
            }
            _ => return abs,
        }
    }
}

/// Refuses a merge input that is not a sweep's output directory (no `speeds/run.key` or no
/// `sweep.json`), naming what it lacks.
fn check_is_sweep(dir: &Path) -> Result<(), StudiesError> {
    let missing = if !dir.is_dir() {
        Some("such directory".to_string())
    } else if !dir.join("speeds").join(RUN_KEY_FILE).is_file() {
        Some(format!("speeds/{RUN_KEY_FILE}"))
    } else if !dir.join("sweep.json").is_file() {
        Some("sweep.json".to_string())
    } else {
        None
    };
    match missing {
        Some(missing) => Err(StudiesError::NotASweep {
            dir: dir.to_path_buf(),
            missing,
        }),
        None => Ok(()),
    }
}

/// Joins shard directories (each a finished `sweep` of some speeds, with its `sweep.json`)
/// into `out`: the speed files are copied byte for byte, then [`assemble`]d over the union of
/// the speeds — the same files as the unsharded sweep. The shards must have the same map
/// options; a speed present in two shards must have identical files.
///
/// `out` must lie apart from every shard (not one, not inside one, not containing one).
/// Every input is read and checked (each speed file parsed in its shard, so a bad file is
/// named where it is) before anything is written; the merged files are then written to a
/// staging directory beside `out` and moved into it with `speeds/run.key`, the mark of a
/// finished sweep directory, last. A merge that fails leaves `out` as it was.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<(SweepRecord, SweepMaps), StudiesError> {
    if dirs.is_empty() {
        return Err(StudiesError::NoShards);
    }
    check_out_apart(dirs, out)?;
    for d in dirs {
        check_is_sweep(d)?;
    }
    let mut key: Option<(String, &PathBuf)> = None;
    for d in dirs {
        let p = d.join("speeds").join(RUN_KEY_FILE);
        let k = std::fs::read_to_string(&p).map_err(StudiesError::io(&p))?;
        match &key {
            None => key = Some((k, d)),
            Some((k0, first)) if *k0 != k => {
                return Err(StudiesError::ShardsOfDifferentModels {
                    first: (*first).clone(),
                    second: d.clone(),
                    file: RUN_KEY_FILE,
                })
            }
            Some(_) => {}
        }
    }
    let (key, _) = key.expect("at least one shard");
    let kp = out.join("speeds").join(RUN_KEY_FILE);
    if let Ok(k) = std::fs::read_to_string(&kp) {
        if k != key {
            return Err(StudiesError::OutputOfAnotherModel {
                out: out.to_path_buf(),
            });
        }
    }
    let mut opts: Option<(MapOptions, &PathBuf)> = None;
    let mut files: Vec<(f64, Vec<u8>, PathBuf)> = Vec::new();
    let records = dirs
        .iter()
        .map(|d| read_record(d))
        .collect::<Result<Vec<_>, _>>()?;
    for (d, rec) in dirs.iter().zip(&records) {
        match &opts {
            None => opts = Some((rec.map.clone(), d)),
            Some((o, first)) if !o.same_as(&rec.map) => {
                return Err(StudiesError::ShardsWithDifferentMaps {
                    first: (*first).clone(),
                    second: d.clone(),
                })
            }
            Some(_) => {}
        }
        for &v in &rec.speeds_kmh {
            let p = speed_file(d, v);
            let s = read_summary(&p)?;
            if !same_speed(s.speed_kmh, v) {
                return Err(StudiesError::BadFile {
                    path: p,
                    reason: format!("holds {} km/h, expected {v} km/h", s.speed_kmh),
                });
            }
            let bytes = std::fs::read(&p).map_err(StudiesError::io(&p))?;
            files.push((v, bytes, p));
        }
    }
    check_shards(dirs, &records)?;
    files.sort_by(|a, b| a.0.total_cmp(&b.0));
    files.dedup_by(|b, a| same_speed(a.0, b.0) && a.1 == b.1);
    if let Some(w) = files.windows(2).find(|w| same_speed(w[0].0, w[1].0)) {
        return Err(StudiesError::SpeedConflict {
            speed_kmh: w[0].0,
            first: w[0].2.clone(),
            second: w[1].2.clone(),
        });
    }
    let (o, _) = opts.expect("at least one shard");
    let stage = staging_dir(out);
    let _ = std::fs::remove_dir_all(&stage);
    let staged = (|| {
        for (v, bytes, _) in &files {
            let p = speed_file(&stage, *v);
            crate::io::write_atomic(&p, |w| w.write_all(bytes)).map_err(StudiesError::io(&p))?;
        }
        let speeds: Vec<f64> = files.iter().map(|f| f.0).collect();
        write_shard_plan(&stage, &speeds, super::super::speeds::Shard::ALL)?;
        let done = assemble(&stage, &speeds, &o)?;
        install(&stage, out, &key)?;
        Ok(done)
    })();
    let _ = std::fs::remove_dir_all(&stage);
    staged
}

/// The staging directory of a merge into `out`: a hidden sibling of it.
fn staging_dir(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "merge".into());
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    parent.join(format!(".{name}.merging.{}", std::process::id()))
}

/// Moves the merged files from `stage` into `out`, with `speeds/run.key` (`key`) last: a
/// missing or empty `out` is replaced by `stage` in one rename; into the directory of an
/// earlier merge of the same sweep (same run key) the files are moved one by one, replacing
/// its files.
fn install(stage: &Path, out: &Path, key: &str) -> Result<(), StudiesError> {
    let kp = out.join("speeds").join(RUN_KEY_FILE);
    let empty = std::fs::read_dir(out).map(|mut d| d.next().is_none());
    match empty {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(StudiesError::Io {
                path: out.to_path_buf(),
                source: e,
            })
        }
        Err(_) | Ok(true) => {
            let sk = stage.join("speeds").join(RUN_KEY_FILE);
            crate::io::write_text(&sk, key).map_err(StudiesError::io(&sk))?;
            if empty.is_ok() {
                std::fs::remove_dir(out).map_err(StudiesError::io(out))?;
            }
            return std::fs::rename(stage, out).map_err(StudiesError::io(out));
        }
        Ok(false) => {}
    }
    for sub in ["speeds", ""] {
        let (from, to) = (stage.join(sub), out.join(sub));
        std::fs::create_dir_all(&to).map_err(StudiesError::io(&to))?;
        for e in std::fs::read_dir(&from).map_err(StudiesError::io(&from))? {
            let e = e.map_err(StudiesError::io(&from))?;
            if sub.is_empty() && e.file_name() == "speeds" {
                continue;
            }
            let dest = to.join(e.file_name());
            if dest.is_dir() {
                std::fs::remove_dir_all(&dest).map_err(StudiesError::io(&dest))?;
            }
            std::fs::rename(e.path(), &dest).map_err(StudiesError::io(&dest))?;
        }
    }
    crate::io::write_text(&kp, key).map_err(StudiesError::io(&kp))
}
