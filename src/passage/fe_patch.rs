//! The influence operators of a passage's contact grid with `contact.influence = "fe-patch"`
//! (theory §6.9), for the reduced engine and the `contact` command (the explicit engine
//! refuses it, [`crate::explicit::ExplicitError::FePatch`]): the model's fe-patch on the grid
//! ([`crate::structure::contact_patch::of_model`]) as strip operators with the split as a
//! negative uniform compliance ([`StripInfluence::with_uniform`]).
//!
//! A patch is built once per model and grid (sparse factorisations of the two submodels' half
//! problems and of the two twins, a minute or more) and kept:
//! in memory for the process, and on disk in `fe-patch/<key>/` of the directory given to
//! [`use_cache_dir`] (the modal cache's; [`crate::dynamics::prepared::PreparedModel`] sets
//! it), written atomically with its completion marker last. The key is the hash of
//! everything the patch is built from (the two submodels' parameters — materials, grid,
//! meshes, rim — and the twins' Hertz semi-width), so a model change that does not touch
//! them keeps the entry. A grid that changes in a passage (lengthened over a corrugated rail,
//! widened when the patch reaches its edge) is another grid and another patch.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use crate::contact::influence::strip::StripInfluence;
use crate::contact::influence::Influence;
use crate::contact::transient::TransientConfig;
use crate::model::{ContactInfluence, Model};
use crate::progress::Progress;
use crate::structure::contact_patch::of_model::{
    model_patch, patch_dofs, patches, ModelPatch, PatchGrid, PASSAGE_REFINE,
};
use crate::structure::contact_patch::{StripKernel, MAX_PATCH_DOFS};

use super::PassageError;

/// Measured cost of a patch per free DOF on two cores: wall time (s) per DOF of both
/// submodels together, and peak memory (bytes) per DOF of the larger. The default model's
/// 32 × 24 grid (rail head 519,555 DOFs, tread 592,740; FE faces 0.31 mm), each submodel solved
/// as its two mirror half problems side by side, with huge pages advised for the factors (the
/// binary's allocator), took 71.1 s and peaked at 8.40 GB on a 2-core machine on which it had
/// taken 146.9 s and 9.69 GB as whole submodels (validation/contact_patch.md, P5;
/// docs/performance.md): 6.4e-5 s per DOF and 14.2 kB per DOF of the tread. The factor's fill
/// grows faster than the DOFs (a 37 × 24 patch of 672,660 DOFs needed about a fifth more per
/// DOF than the 32 × 24 one), hence 17 kB.
const SECONDS_PER_DOF: f64 = 7.0e-5;
const PEAK_BYTES_PER_DOF: f64 = 1.7e4;

/// The share of the machine's memory (`MemTotal`) a patch build may be estimated to need;
/// beyond it the build is refused before it starts.
const MEMORY_SHARE: f64 = 0.9;

/// The machine's memory (GB) from `/proc/meminfo`, where the system gives it.
fn machine_memory_gb() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0 / 1e9)
}

/// One key's patch: empty until built or read; locked while it is being built, so that a
/// second passage needing the same patch waits for it instead of building it again.
type Slot = Arc<Mutex<Option<Arc<ModelPatch>>>>;

/// The patches built or read in this process, by key (the map's lock is held only to find or
/// add a slot, never across a build).
static MEMO: Mutex<Option<HashMap<String, Slot>>> = Mutex::new(None);
/// Where patches are kept on disk (`None`: the default cache directory,
/// [`crate::eigen::cache::default_cache_dir`]).
static DIR: Mutex<Option<PathBuf>> = Mutex::new(None);

/// Keep fe-patches on disk under `dir/fe-patch/` from now on in this process.
pub fn use_cache_dir(dir: &Path) {
    *DIR.lock().unwrap_or_else(|e| e.into_inner()) = Some(dir.to_path_buf());
}

/// The fe-patch grid of a passage's contact configuration `cfg`, its twins loaded with the
/// lateral weights of the static Hertz patch of semi-axis `hertz_b_m` (m; the model's at its
/// wheel load, `dynamics::setup::static_hertz`).
pub(crate) fn patch_grid(cfg: &TransientConfig, hertz_b_m: f64) -> PatchGrid {
    PatchGrid {
        nx: cfg.grid.nx,
        ny: cfg.grid.ny,
        dx_m: cfg.grid.dx(),
        dy_m: cfg.grid.dy(),
        hertz_half_width_m: hertz_b_m,
        refine: PASSAGE_REFINE,
    }
}

/// The estimated cost of building the patch of `grid`: wall time (s), peak memory (GB) and
/// the free DOFs of the larger submodel.
pub(crate) fn build_estimate(
    model: &Model,
    grid: &PatchGrid,
) -> Result<(f64, f64, usize), PassageError> {
    let (r, t) = patch_dofs(model, grid)?;
    let n = (r + t) as f64;
    let larger = r.max(t);
    Ok((
        n * SECONDS_PER_DOF,
        larger as f64 * PEAK_BYTES_PER_DOF / 1e9,
        larger,
    ))
}

/// The key of the patch of `model` on `grid`: a hash of what it is built from.
fn key(model: &Model, grid: &PatchGrid) -> String {
    let (rail, tread) = patches(model, grid);
    // the program version: a change to the meshers or the condensation makes a new entry
    let text = format!(
        "{}|{rail:?}|{tread:?}|{:?}",
        env!("CARGO_PKG_VERSION"),
        grid.hertz_half_width_m.to_bits()
    );
    blake3::hash(text.as_bytes()).to_hex()[..32].to_string()
}

/// The fe-patch of `model` on `grid`: from memory, from disk, or built (reported to
/// `progress` with its estimate first).
pub(crate) fn model_patch_cached(
    model: &Model,
    grid: &PatchGrid,
    progress: Option<&dyn Progress>,
) -> Result<Arc<ModelPatch>, PassageError> {
    let k = key(model, grid);
    let slot: Slot = MEMO
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .get_or_insert_with(HashMap::new)
        .entry(k.clone())
        .or_default()
        .clone();
    // Held across the build. The build runs on its own thread and thread pool (below), so
    // this thread blocks here without taking other rayon work (a sweep's next passage, which
    // might want this very slot).
    let mut slot = slot.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(p) = slot.as_ref() {
        return Ok(p.clone());
    }
    let dir = DIR
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .clone()
        .unwrap_or_else(crate::eigen::cache::default_cache_dir)
        .join(crate::eigen::cache::FE_PATCH_DIR)
        .join(&k);
    let dir = Some(dir);
    if let Some(p) = dir.as_deref().and_then(|d| read(d, grid)) {
        let p = Arc::new(p);
        *slot = Some(p.clone());
        return Ok(p);
    }
    let (seconds, gb, dofs) = build_estimate(model, grid)?;
    let reason = if dofs > MAX_PATCH_DOFS {
        Some(format!(
            "beyond the {MAX_PATCH_DOFS} DOFs of a patch submodel"
        ))
    } else {
        machine_memory_gb()
            .filter(|&m| gb > MEMORY_SHARE * m)
            .map(|m| format!("more than this machine's {m:.1} GB allows"))
    };
    if let Some(reason) = reason {
        return Err(PassageError::FePatchTooLarge {
            nx: grid.nx,
            ny: grid.ny,
            gb,
            dofs,
            seconds,
            reason,
        });
    }
    if let Some(pr) = progress {
        pr.warn(&format!(
            "building the fe-patch of the {} x {} contact grid (rail head and tread submodels): \
             about {:.0} s and {:.1} GB, once per model and grid",
            grid.nx, grid.ny, seconds, gb
        ));
        pr.stage("fe-patch influence coefficients", 1);
    }
    let p = Arc::new(build_apart(model, grid)?);
    if let Some(pr) = progress {
        pr.done(1);
        pr.finish();
    }
    if let Some(d) = dir.as_deref() {
        if let Err(e) = write(d, &p) {
            if let Some(pr) = progress {
                pr.warn(&format!("fe-patch not cached in {}: {e}", d.display()));
            }
        }
    }
    *slot = Some(p.clone());
    Ok(p)
}

/// [`model_patch`] on a thread of its own with a thread pool of its own (as many threads as
/// the global pool): its factorisations' parallel work never runs the caller's pending rayon
/// tasks, nor the caller theirs.
fn build_apart(model: &Model, grid: &PatchGrid) -> Result<ModelPatch, PassageError> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(rayon::current_num_threads())
        .build()
        .map_err(|_| PassageError::OutOfRange {
            name: "fe-patch build threads",
            value: rayon::current_num_threads() as f64,
            expected: "threads the system can start",
        })?;
    std::thread::scope(|s| {
        s.spawn(|| pool.install(|| model_patch(model, grid)))
            .join()
            .unwrap_or_else(|e| std::panic::resume_unwind(e))
    })
    .map_err(PassageError::from)
}

/// Builds (or reads) the fe-patch of the model's own contact configuration `cfg` (static
/// Hertz semi-axis `hertz_b_m`, m) before any passage, with `progress`; nothing for the
/// half-space. The passages then find it in memory.
pub fn prepare(
    model: &Model,
    cfg: &TransientConfig,
    hertz_b_m: f64,
    progress: Option<&dyn Progress>,
) -> Result<(), PassageError> {
    if model.contact.influence == ContactInfluence::HalfSpace {
        return Ok(());
    }
    model_patch_cached(model, &patch_grid(cfg, hertz_b_m), progress)?;
    Ok(())
}

/// What an fe-patch's operators stand beside.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Beside {
    /// A passage's global model (modes and series compliance): the split is applied
    /// (`influence_of`); the model's validation has made sure the residual flexibilities,
    /// which carry the share the split takes off, are on.
    GlobalModel,
    /// Nothing (the `contact` command): the refined submodels alone (`refined_influence`).
    Nothing,
}

/// The influence operators of a contact on `cfg`'s grid (its twins loaded as the static
/// Hertz patch of semi-axis `hertz_b_m`, m): `None` for the half-space (the contact builds its
/// own), the model's fe-patch otherwise, split or not as `beside` says.
pub fn influence_for(
    model: &Model,
    (cfg, hertz_b_m): (&TransientConfig, f64),
    beside: Beside,
    progress: Option<&dyn Progress>,
) -> Result<Option<Influence>, PassageError> {
    if model.contact.influence == ContactInfluence::HalfSpace {
        return Ok(None);
    }
    let p = model_patch_cached(model, &patch_grid(cfg, hertz_b_m), progress)?;
    Ok(Some(match beside {
        Beside::GlobalModel => influence_of(&p),
        Beside::Nothing => refined_influence(&p),
    }))
}

/// The strip operators of a model patch in a passage: the refined kernel, the twins'
/// diagonal as a negative uniform compliance (their couplings, zero for a patch centred on the
/// crown and the rolling circle to round-off, are left out with the kernel's
/// normal–tangential ones). Positive definite only beside the global model's compliance at
/// the contact (the passage's series compliance), from which the twins' share was split.
pub(crate) fn influence_of(p: &ModelPatch) -> Influence {
    let t = p.twins_m_per_n;
    match refined_influence(p) {
        Influence::Strip(op) => Influence::Strip(op.with_uniform([-t[0][0], -t[1][1], -t[2][2]])),
        other => other,
    }
}

/// The strip operators of the two refined submodels alone, without the split: the contact of
/// the rail head and the tread with no global model beside them (the `contact` command). Their
/// approach includes the submodels' own structural flexibility; the patch's pressure and
/// traction are those of the passage's fe-patch in steady rolling (a uniform compliance
/// changes neither under a prescribed load and creepage).
pub(crate) fn refined_influence(p: &ModelPatch) -> Influence {
    let k = &p.refined;
    let (nx, ny) = k.dims();
    Influence::Strip(StripInfluence::new(nx, ny, |o, j, jp| {
        k.get(o, j, jp).expect("offsets within the kernel")
    }))
}

/// The completion marker, written last; the files are the cache's
/// ([`crate::eigen::cache::FE_PATCH_FILES`]: what it recognises as its own).
const MARKER: &str = crate::eigen::cache::FE_PATCH_FILES[3];
const KERNEL_FILE: &str = crate::eigen::cache::FE_PATCH_FILES[0];
const TWINS_FILE: &str = crate::eigen::cache::FE_PATCH_FILES[1];
const GRID_FILE: &str = crate::eigen::cache::FE_PATCH_FILES[2];

/// Writes `p` into `dir`: the refined kernel `[2 nx, ny, ny, 3, 3]` (m/Pa), the twins
/// `[2, 3, 3]` (m/N; rail, wheel), the grid and DOFs, the marker last.
fn write(dir: &Path, p: &ModelPatch) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let k = &p.refined;
    let (nx, ny) = k.dims();
    let flat: Vec<f64> = k.values().iter().flatten().flatten().copied().collect();
    crate::io::write_npy(&dir.join(KERNEL_FILE), &[2 * nx, ny, ny, 3, 3], &flat)?;
    let twins: Vec<f64> = [p.rail_twin_m_per_n, p.wheel_twin_m_per_n]
        .iter()
        .flatten()
        .flatten()
        .copied()
        .collect();
    crate::io::write_npy(&dir.join(TWINS_FILE), &[2, 3, 3], &twins)?;
    let meta = format!(
        "{} {} {:e} {:e} {}\n",
        nx,
        ny,
        k.element_m(),
        k.element_y_m(),
        k.n_dofs()
    );
    crate::io::write_text(&dir.join(GRID_FILE), &meta)?;
    crate::io::write_text(&dir.join(MARKER), "")
}

/// Reads a complete entry written by [`write`] for `grid`; `None` if absent, incomplete or
/// not of this grid (it is then rebuilt and rewritten).
fn read(dir: &Path, grid: &PatchGrid) -> Option<ModelPatch> {
    if !dir.join(MARKER).is_file() {
        return None;
    }
    let meta = std::fs::read_to_string(dir.join(GRID_FILE)).ok()?;
    let f: Vec<&str> = meta.split_whitespace().collect();
    let (nx, ny): (usize, usize) = (f.first()?.parse().ok()?, f.get(1)?.parse().ok()?);
    let n_dofs: usize = f.get(4)?.parse().ok()?;
    if (nx, ny) != (grid.nx, grid.ny) {
        return None;
    }
    let load = |name: &str| -> Option<Vec<f64>> {
        let bytes = std::fs::read(dir.join(name)).ok()?;
        npyz::NpyFile::new(&bytes[..]).ok()?.into_vec().ok()
    };
    let flat = load(KERNEL_FILE)?;
    let values: Vec<[[f64; 3]; 3]> = flat
        .chunks_exact(9)
        .map(|c| std::array::from_fn(|a| std::array::from_fn(|b| c[3 * a + b])))
        .collect();
    let refined = StripKernel::from_values((nx, ny), (grid.dx_m, grid.dy_m), values, n_dofs)?;
    let t = load(TWINS_FILE)?;
    if t.len() != 18 || !t.iter().all(|v| v.is_finite()) {
        return None;
    }
    let m = |o: usize| -> [[f64; 3]; 3] {
        std::array::from_fn(|a| std::array::from_fn(|b| t[o + 3 * a + b]))
    };
    let (rail, wheel) = (m(0), m(9));
    Some(ModelPatch {
        refined,
        twins_m_per_n: std::array::from_fn(|a| std::array::from_fn(|b| rail[a][b] + wheel[a][b])),
        rail_twin_m_per_n: rail,
        wheel_twin_m_per_n: wheel,
    })
}

#[cfg(test)]
mod tests;
