//! The reference study's own procedure for the longitudinal-compression frequency (docs/theory.md
//! §9.7): the nodal spectrum of rail-top points. One passage per point with the point's motion
//! recorded; the peaks of its longitudinal displacement's spectrum over the reference's short
//! record (contact from 0.1 m before to 0.2 m after the point) and over the whole solution zone,
//! each with its duration and frequency resolution, written to `nodal_spectrum.json` beside the
//! track's longitudinal-compression eigenfrequencies.

use std::path::Path;

use serde::Serialize;

use crate::dynamics::passage::PassageOptions;
use crate::dynamics::prepared::PreparedModel;
use crate::dynamics::RailProfile;
use crate::io::write_text;
use crate::spectral::nodal::{nodal_spectrum, short_window_m, NodalHistory, NodalSpectrum};
use crate::studies::{BoxError, StudiesError};

/// The nodal spectra of one rail-top point.
#[derive(Debug, Serialize)]
pub struct NodalPoint {
    /// `sleeper`, `mid_span` or `x<m>`.
    pub label: String,
    /// The spectra (short record, solution zone).
    pub spectra: Vec<NodalSpectrum>,
}

/// One passage per rail-top point at `at_m` (m along the rail; empty: the sleeper and the
/// mid-span nearest the solution-zone centre) with the point recorded, at `speed_m_per_s`
/// (m/s) over `profile`, and the spectra of its longitudinal displacement; written to
/// `nodal_spectrum.json` in `out` with the longitudinal-compression eigenfrequencies (Hz),
/// which are returned with the points.
pub fn nodal_outputs(
    prepared: &mut PreparedModel,
    speed_m_per_s: f64,
    profile: Option<&RailProfile>,
    at_m: &[f64],
    out: &Path,
) -> Result<(Vec<NodalPoint>, Vec<f64>), StudiesError> {
    prepared.engine.model().check_on_track("--nodal-at", at_m)?;
    let points: Vec<(String, f64)> = if at_m.is_empty() {
        let [mid, sl] = prepared.engine.midspan_and_sleeper_m();
        vec![("sleeper".into(), sl), ("mid_span".into(), mid)]
    } else {
        at_m.iter().map(|&x| (format!("x{x}"), x)).collect()
    };
    let zone = prepared.engine.zone_m();
    let band = [100.0, prepared.engine.model().run.fmax];
    let opts = PassageOptions {
        energy: false,
        rail_point_offset_m: Some(0.0),
        overlap: false,
    };
    let mut res = Vec::new();
    for (label, x) in points {
        let at = |source: BoxError| StudiesError::Nodal { x_m: x, source };
        prepared
            .engine
            .set_rail_point_at(x)
            .map_err(|e| at(Box::new(e)))?;
        let rec = prepared
            .engine
            .passage(speed_m_per_s, profile, &opts, None)
            .map_err(|e| at(Box::new(e)))?;
        let rp = rec
            .rail_point
            .as_ref()
            .ok_or_else(|| at("the passage did not record the rail point".into()))?;
        let ux: Vec<f64> = rp.displacement_m.iter().map(|u| u[0]).collect();
        let h = NodalHistory {
            point_x_m: rp.position_m[0],
            t_s: &rec.histories.t_s,
            x_contact_m: &rec.histories.x_m,
            ux_m: &ux,
        };
        let spectra = vec![
            nodal_spectrum(&h, "short", short_window_m(h.point_x_m), band, 6)
                .map_err(|e| at(Box::new(e)))?,
            nodal_spectrum(&h, "zone", zone, band, 6).map_err(|e| at(Box::new(e)))?,
        ];
        res.push(NodalPoint { label, spectra });
    }
    let lc = prepared.longitudinal_compression_hz();
    let json = serde_json::json!({
        "points": res,
        "longitudinal_compression_hz": lc,
    });
    let text = serde_json::to_string_pretty(&json).map_err(|source| StudiesError::Json {
        what: "nodal_spectrum.json",
        source,
    })?;
    let path = out.join("nodal_spectrum.json");
    write_text(&path, &text).map_err(StudiesError::io(&path))?;
    Ok((res, lc))
}
