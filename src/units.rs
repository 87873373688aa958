//! Unit conversions at the input/output boundary.
//!
//! Everything inside the library is SI (m, s, kg, N, Pa, rad). Users think in km/h, mm and µm;
//! those conversions happen here and nowhere else, so a grep for `units::` finds every
//! boundary crossing.

/// Metres per millimetre.
pub const M_PER_MM: f64 = 1.0e-3;
/// Metres per micrometre.
pub(crate) const M_PER_UM: f64 = 1.0e-6;
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

/// A train speed, built from the value the user gave (km/h at the input boundary, m/s inside
/// the library) and carrying that value unchanged: [`Speed::kmh`] of a speed built with
/// [`Speed::from_kmh`] is exactly the number given (60 km/h reads 60, not the
/// 60.00000000000001 of a round trip through m/s), and [`Speed::m_per_s`] of one built with
/// [`Speed::from_m_per_s`] is exactly its m/s. The other unit is converted once, here.
///
/// Valid range: finite and positive; the model and the sweeps accept 40 to 500 km/h
/// (`crate::model::SPEED_KMH`) and check it where the speed is read.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Speed {
    /// Speed (km/h).
    kmh: f64,
    /// Speed (m/s).
    m_per_s: f64,
}

impl Speed {
    /// The speed `kmh` (km/h); [`Speed::kmh`] returns `kmh` exactly.
    pub fn from_kmh(kmh: f64) -> Self {
        Speed {
            kmh,
            m_per_s: kmh_to_ms(kmh),
        }
    }

    /// The speed `m_per_s` (m/s); [`Speed::m_per_s`] returns `m_per_s` exactly.
    pub fn from_m_per_s(m_per_s: f64) -> Self {
        Speed {
            kmh: ms_to_kmh(m_per_s),
            m_per_s,
        }
    }

    /// The speed in m/s, for the physics.
    pub fn m_per_s(self) -> f64 {
        self.m_per_s
    }

    /// The speed in km/h, for reports and file names.
    pub fn kmh(self) -> f64 {
        self.kmh
    }
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

/// Newtons per kilonewton.
pub(crate) const N_PER_KN: f64 = 1.0e3;

/// Force in N → kN (for printed tables).
pub fn n_to_kn(n: f64) -> f64 {
    n / N_PER_KN
}

/// Time in s → ms (for printed tables).
pub fn s_to_ms(s: f64) -> f64 {
    s * 1.0e3
}

/// Bytes per GB (decimal, as disk sizes are quoted).
pub(crate) const BYTES_PER_GB: f64 = 1.0e9;
/// Seconds per day.
pub(crate) const S_PER_DAY: f64 = 86_400.0;

/// Size in B → GB (10⁹ B).
pub fn bytes_to_gb(bytes: u64) -> f64 {
    bytes as f64 / BYTES_PER_GB
}

/// Size in GB (10⁹ B) → B, rounded down; `gb` ≥ 0.
pub fn gb_to_bytes(gb: f64) -> u64 {
    (gb * BYTES_PER_GB) as u64
}

/// Duration in days → s.
pub fn days_to_s(days: f64) -> f64 {
    days * S_PER_DAY
}

/// Duration in s → days.
pub fn s_to_days(s: f64) -> f64 {
    s / S_PER_DAY
}

#[cfg(test)]
mod tests {
    use super::{kmh_to_ms, m_to_mm, m_to_um, mm_to_m, ms_to_kmh, um_to_m, Speed};
    #[test]
    fn reference_speed_is_38_89_m_per_s() {
        // docs/theory.md §1.2: 140 km/h = 38.89 m/s.
        assert!((kmh_to_ms(140.0) - 38.888_888_9).abs() < 1e-6);
        assert!((ms_to_kmh(kmh_to_ms(54.8)) - 54.8).abs() < 1e-12);
    }

    #[test]
    fn speed_from_kmh_keeps_the_kmh_exactly_and_converts_to_m_per_s() {
        // 60 km/h through m/s and back is 60.00000000000001; the Speed keeps the given value.
        assert_ne!(ms_to_kmh(kmh_to_ms(60.0)), 60.0);
        for kmh in [54.8, 60.0, 100.0, 140.0, 219.0] {
            assert_eq!(Speed::from_kmh(kmh).kmh(), kmh);
        }
        // Closed form: 140 km/h = 140 000 m / 3600 s = 38.888… m/s.
        let v = Speed::from_kmh(140.0).m_per_s();
        assert!((v - 140_000.0 / 3600.0).abs() < 1e-12, "{v}");
        assert!((v - 38.888_888_888_888_9).abs() < 1e-12, "{v}");
    }

    #[test]
    fn speed_from_m_per_s_keeps_the_m_per_s_exactly() {
        let s = Speed::from_m_per_s(38.9);
        assert_eq!(s.m_per_s(), 38.9);
        // Closed form: 38.9 m/s × 3600 s/h / 1000 m/km = 140.04 km/h.
        assert!((s.kmh() - 140.04).abs() < 1e-12, "{}", s.kmh());
    }

    #[test]
    fn lengths_round_trip() {
        assert_eq!(mm_to_m(800.0), 0.8);
        assert!((m_to_um(um_to_m(160.0)) - 160.0).abs() < 1e-9);
        assert!((m_to_mm(0.46) - 460.0).abs() < 1e-9);
    }
}
