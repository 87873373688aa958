//! The files of the `modes` command (and of anyone who wants them): `modes.csv` (one row per
//! track mode, `TRACK_HEADER`), `wheel_modes.csv` (`WHEEL_HEADER`), the mode shapes as
//! `.vtu` files for ParaView, and the summary of both substructures ([`ModesSummary`], the
//! command's `--json`).
//!
//! `family` is the snake_case name (longitudinal_compression, longitudinal_shear,
//! vertical_bending, lateral_bending, torsion, sleeper, local, other), `wavelength_m` is empty
//! when undefined (fewer than two zero crossings), `rail_x_*` and `amp_*` are relative to the
//! RMS rail displacement (dimensionless), `energy_*` strain-energy shares, `pinned_pinned` 0/1,
//! `rail_family` the family of the rail's own motion (differs from `family` for `sleeper`
//! modes, whose rail may e.g. carry a longitudinal-compression motion along with the
//! sleepers). Every file is written atomically.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::eigen::basis::ModalBasis;
use crate::eigen::classify::{
    wheel_band_modes, TrackModeClass, WheelBandModes, WheelModeClass, WHEEL_SUMMARY_BAND_HZ,
};
use crate::eigen::RESIDUAL_FLOOR_HZ;
use crate::fe::assembly::DofMap;
use crate::io::{write_text_csv, write_vtu, VtuField, VTK_HEXAHEDRON};
use crate::mesh::Mesh;
use crate::model::FMAX_HZ;
use crate::studies::StudiesError;

/// Columns of `modes.csv`.
pub(crate) const TRACK_HEADER: [&str; 21] = [
    "index",
    "frequency_hz",
    "family",
    "rail_x_head",
    "rail_x_web",
    "rail_x_foot",
    "wavelength_m",
    "energy_rail",
    "energy_sleepers",
    "energy_fastening",
    "energy_ballast",
    "relative_residual",
    "amp_compression",
    "amp_shear",
    "amp_vertical",
    "amp_lateral",
    "amp_torsion",
    "sleeper_kinetic_share",
    "section_fit",
    "pinned_pinned",
    "rail_family",
];

/// Columns of `wheel_modes.csv`.
pub(crate) const WHEEL_HEADER: [&str; 9] = [
    "index",
    "frequency_hz",
    "family",
    "rigid",
    "energy_wheel",
    "energy_suspension",
    "rim_radial",
    "rim_axial",
    "rim_circumferential",
];

/// Summary of one substructure.
#[derive(Debug, Serialize)]
pub struct SubSummary {
    /// Modes found below `fmax_hz`.
    pub count: usize,
    /// The upper frequency (Hz).
    pub fmax_hz: f64,
    /// The Sturm count of eigenvalues below `fmax_hz` (equal to `count` when none is missed).
    pub sturm_count: usize,
    /// The largest relative residual of the modes above [`RESIDUAL_FLOOR_HZ`] (1 Hz) (a rigid-body
    /// mode's relative residual is its eigenvalue's round-off over the measure's floor, up to
    /// about 1, and says nothing about its accuracy; `eigen` module doc).
    pub max_residual: f64,
    /// Wall time of the extraction or the cache read (s).
    pub seconds: f64,
    /// Whether the basis came from the cache.
    pub cached: bool,
    /// Modes per family name.
    pub families: BTreeMap<String, usize>,
}

/// JSON printed by `modes --json`: the track summary at top level, the wheel under `wheel`.
#[derive(Debug, Serialize)]
pub struct ModesSummary {
    /// The track.
    #[serde(flatten)]
    pub track: SubSummary,
    /// The wheel.
    pub wheel: SubSummary,
    /// The wheel's in-plane and out-of-plane modes in 0.5–2 kHz (to `--fmax` if lower).
    pub wheel_band: WheelBandModes,
    /// The modal cache directory.
    pub cache_dir: String,
}

/// The default number of mode shapes written as `.vtu` files per substructure.
pub const DEFAULT_VTU_MODES: usize = 50;

/// The modes command's default upper frequency (Hz): the default model's `run.fmax`.
pub const DEFAULT_FMAX_HZ: f64 = 5000.0;

/// Checks the upper frequency `fmax_hz` (Hz) of a modes run: [`FMAX_HZ`], as `run.fmax`.
pub fn check_fmax(fmax_hz: f64) -> Result<(), StudiesError> {
    if fmax_hz.is_finite() && (FMAX_HZ[0]..=FMAX_HZ[1]).contains(&fmax_hz) {
        return Ok(());
    }
    Err(StudiesError::OutOfRange {
        name: "--fmax",
        value: fmax_hz,
        lo: FMAX_HZ[0],
        hi: FMAX_HZ[1],
        unit: "Hz (as run.fmax)",
    })
}

impl ModesSummary {
    /// The summary of the track basis `tb` and the wheel basis `wb`, both below `fmax_hz`
    /// (Hz), read from or stored in the cache `cache_dir`.
    pub fn new(
        tb: &ModalBasis<TrackModeClass>,
        wb: &ModalBasis<WheelModeClass>,
        fmax_hz: f64,
        cache_dir: &Path,
    ) -> Self {
        ModesSummary {
            track: sub_summary(tb, tb.classes.iter().map(|c| c.family.name()), fmax_hz),
            wheel: sub_summary(wb, wb.classes.iter().map(|c| c.family.name()), fmax_hz),
            wheel_band: wheel_band_modes(
                &wb.frequencies_hz,
                &wb.classes,
                [
                    WHEEL_SUMMARY_BAND_HZ[0],
                    WHEEL_SUMMARY_BAND_HZ[1].min(fmax_hz),
                ],
            ),
            cache_dir: cache_dir.display().to_string(),
        }
    }
}

/// The summary of basis `b` below `fmax_hz` whose modes have the family names `families`.
fn sub_summary<'a, C>(
    b: &ModalBasis<C>,
    families: impl Iterator<Item = &'a str>,
    fmax_hz: f64,
) -> SubSummary {
    let mut counts = BTreeMap::new();
    for f in families {
        *counts.entry(f.to_string()).or_insert(0) += 1;
    }
    SubSummary {
        count: b.frequencies_hz.len(),
        fmax_hz,
        sturm_count: b.sturm_count,
        max_residual: b
            .residuals
            .iter()
            .zip(&b.frequencies_hz)
            .filter(|(_, &f)| f >= RESIDUAL_FLOOR_HZ)
            .map(|(&r, _)| r)
            .fold(0.0, f64::max),
        seconds: b.seconds,
        cached: b.cached,
        families: counts,
    }
}

/// Writes `modes.csv` and `wheel_modes.csv` into `out` (created if missing), atomically.
pub fn write_mode_tables(
    out: &Path,
    tb: &ModalBasis<TrackModeClass>,
    wb: &ModalBasis<WheelModeClass>,
) -> Result<(), StudiesError> {
    std::fs::create_dir_all(out).map_err(StudiesError::io(out))?;
    let path = out.join("modes.csv");
    write_text_csv(
        &path,
        &TRACK_HEADER,
        tb.classes.iter().enumerate().map(|(i, c)| {
            let mut r = vec![
                i.to_string(),
                num(tb.frequencies_hz[i]),
                c.family.name().to_string(),
                num(c.rail_x_head),
                num(c.rail_x_web),
                num(c.rail_x_foot),
                c.wavelength_m.map(num).unwrap_or_default(),
                num(c.energy.rail),
                num(c.energy.sleepers),
                num(c.energy.fastening),
                num(c.energy.ballast),
                tb.residuals.get(i).copied().map(num).unwrap_or_default(),
            ];
            r.extend(c.amplitudes.map(num));
            r.extend([
                num(c.sleeper_kinetic_share),
                num(c.section_fit),
                (c.pinned_pinned as u8).to_string(),
                c.rail_family.unwrap_or(c.family).name().to_string(),
            ]);
            r
        }),
    )
    .map_err(StudiesError::io(&path))?;
    let path = out.join("wheel_modes.csv");
    write_text_csv(
        &path,
        &WHEEL_HEADER,
        wb.classes.iter().enumerate().map(|(i, c)| {
            vec![
                i.to_string(),
                num(wb.frequencies_hz[i]),
                c.family.name().to_string(),
                (c.rigid as u8).to_string(),
                num(c.energy_wheel),
                num(c.energy_suspension),
                num(c.rim_shares[0]),
                num(c.rim_shares[1]),
                num(c.rim_shares[2]),
            ]
        }),
    )
    .map_err(StudiesError::io(&path))
}

fn num(x: f64) -> String {
    format!("{x:e}")
}

/// Writes `{name}_mode_NNNN.vtu` into `dir` for the first `limit` modes of `b` (mesh + point
/// field `displacement`: the mode shape, M-normalised, m/√kg; ParaView "Warp By Vector").
pub fn write_mode_vtus<C>(
    dir: &Path,
    name: &str,
    mesh: &Mesh,
    dofmap: &DofMap,
    b: &ModalBasis<C>,
    limit: usize,
) -> Result<(), StudiesError> {
    let cells: Vec<(u8, Vec<usize>)> = mesh
        .elements
        .iter()
        .map(|e| (VTK_HEXAHEDRON, e.nodes.to_vec()))
        .collect();
    for j in 0..b.frequencies_hz.len().min(limit) {
        let u = dofmap.expand(&b.modes.col(j).iter().copied().collect::<Vec<f64>>())?;
        let p = dir.join(format!("{name}_mode_{j:04}.vtu"));
        write_vtu(
            &p,
            &mesh.nodes,
            &cells,
            &[VtuField {
                name: "displacement",
                components: 3,
                data: &u,
            }],
            &[],
        )
        .map_err(StudiesError::io(&p))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{sub_summary, ModalBasis};
    /// The printed largest residual leaves out the rigid-body modes below 1 Hz, whose
    /// relative residual is round-off over the measure's floor (0.71 for a 0.84 Hz rotation
    /// of the bare wheelset, where the elastic modes' largest is 3.7e-6).
    #[test]
    fn the_largest_residual_is_the_elastic_modes() {
        let b = ModalBasis::<()> {
            frequencies_hz: vec![0.0, 0.84, 7.5, 610.0],
            modes: faer::Mat::zeros(1, 4),
            residuals: vec![1e-3, 0.71, 2e-6, 3.7e-6],
            sturm_count: 4,
            classes: vec![(); 4],
            cached: false,
            seconds: 0.0,
        };
        let s = sub_summary(
            &b,
            ["rigid", "rigid", "rigid", "radial"].into_iter(),
            5000.0,
        );
        assert_eq!(s.max_residual, 3.7e-6);
        assert_eq!(s.count, 4);
    }
}
