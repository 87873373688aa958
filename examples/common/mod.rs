//! Helpers shared by the benchmarks (`examples/*_bench.rs`): CPU time, machine load, and a
//! digest of results, so that a speed-up is seen not to change the answer.

#![allow(dead_code)]

/// CPU time of this process, all threads (user + system, s) from `/proc/self/stat` (Linux,
/// 100 Hz clock ticks; `NaN` elsewhere): the machine is shared, so wall time alone says little.
pub fn cpu_seconds() -> f64 {
    corrugation::progress::cpu_seconds().unwrap_or(f64::NAN)
}

/// The machine's load: `/proc/loadavg`'s 1, 5 and 15 minute averages and the core count, as
/// one line (`"load 1.23 0.98 0.75 on 2 cores"`).
pub fn machine_load() -> String {
    let avg = std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    format!("load {avg} on {cores} cores")
}

/// Hex digest (first 16 hex digits of BLAKE3) of the bit patterns of `values`: equal digests
/// mean bitwise equal results.
pub fn bits_digest(values: &[f64]) -> String {
    let mut h = blake3::Hasher::new();
    for v in values {
        h.update(&v.to_bits().to_le_bytes());
    }
    h.finalize().to_hex()[..16].to_string()
}

/// The comparable figures of a passage summary, one line: mean F_N and F_L, band RMS of F_L,
/// F_N and the wear, dominant wavelength (9 significant digits, so that a change shows).
pub fn summary_line(s: &corrugation::dynamics::PassageSummary) -> String {
    format!(
        "mean F_N {:.9e} N, mean F_L {:.9e} N, band RMS F_L {:.9e} N, F_N {:.9e} N, wear {:.9e}, dominant wavelength {}",
        s.mean_fn_n,
        s.mean_fl_n,
        s.fl_band_rms_n,
        s.fn_band_rms_n,
        s.wear_band_rms,
        s.dominant_wavelength_mm
            .map_or("none".into(), |w| format!("{w:.9} mm"))
    )
}

/// The figures of a summary that a speed-up must keep, flattened (the digest input):
/// [`summary_line`]'s values and the wear PSD.
pub fn summary_values(s: &corrugation::dynamics::PassageSummary) -> Vec<f64> {
    let mut v = vec![
        s.speed_kmh,
        s.mean_fn_n,
        s.mean_fl_n,
        s.fl_band_rms_n,
        s.fn_band_rms_n,
        s.wear_band_rms,
        s.dominant_wavelength_mm.unwrap_or(f64::NAN),
    ];
    v.extend_from_slice(&s.wear_psd.psd);
    v
}
