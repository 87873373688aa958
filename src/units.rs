//! Unit conversions at the input/output boundary.
//!
//! Everything inside the library is SI (m, s, kg, N, Pa, rad). Users think in km/h, mm and µm;
//! those conversions happen here and nowhere else, so a grep for `units::` finds every
//! boundary crossing.

/// Metres per millimetre.
pub const M_PER_MM: f64 = 1.0e-3;
/// Metres per micrometre.
pub const M_PER_UM: f64 = 1.0e-6;
/// Pascals per megapascal.
pub const PA_PER_MPA: f64 = 1.0e6;

/// Speed in km/h → m/s.
pub fn kmh_to_ms(kmh: f64) -> f64 {
    kmh / 3.6
}

/// Speed in m/s → km/h.
pub fn ms_to_kmh(ms: f64) -> f64 {
    ms * 3.6
}

/// Length in mm → m.
pub fn mm_to_m(mm: f64) -> f64 {
    mm * M_PER_MM
}

/// Length in m → mm.
pub fn m_to_mm(m: f64) -> f64 {
    m / M_PER_MM
}

/// Length in µm → m.
pub fn um_to_m(um: f64) -> f64 {
    um * M_PER_UM
}

/// Length in m → µm.
pub fn m_to_um(m: f64) -> f64 {
    m / M_PER_UM
}

/// Stress in Pa → MPa.
pub fn pa_to_mpa(pa: f64) -> f64 {
    pa / PA_PER_MPA
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_speed_is_38_89_m_per_s() {
        // docs/theory.md §1.2: 140 km/h = 38.89 m/s.
        assert!((kmh_to_ms(140.0) - 38.888_888_9).abs() < 1e-6);
        assert!((ms_to_kmh(kmh_to_ms(54.8)) - 54.8).abs() < 1e-12);
    }

    #[test]
    fn lengths_round_trip() {
        assert_eq!(mm_to_m(800.0), 0.8);
        assert!((m_to_um(um_to_m(160.0)) - 160.0).abs() < 1e-9);
        assert!((m_to_mm(0.46) - 460.0).abs() < 1e-9);
    }
}
