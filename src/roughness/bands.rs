//! One-third-octave wavelength bands (base ten), band spectra of roughness in dB re 1 µm, and
//! the ISO 3095:2013 limit spectrum.
//!
//! Band `n` has the exact centre wavelength `λ_n = 10^(−n/10)` m and the edges
//! `λ_n·10^(±1/20)`; it is named by its nominal wavelength (0.0315 m for `10^(−1.5)`), the
//! preferred numbers of the standards. A band level is `L = 10 lg(r²_rms / r₀²)` with
//! `r₀ = 1 µm` and `r²_rms` the mean square of the roughness within the band.

use std::path::Path;

use super::RoughnessError;

/// Reference roughness of the band levels, `r₀` (m): 1 µm.
pub(crate) const REFERENCE_ROUGHNESS_M: f64 = 1e-6;

/// The upper limit of the rail roughness of a reference track for vehicle noise tests
/// (ISO 3095:2013, 6.2.5 and Figure 2; the same levels are tabulated in EN 15610): nominal
/// band centre wavelength (m) and level (dB re 1 µm), 0.4 m to 3.15 mm.
pub(crate) const ISO3095_LIMIT_DB: [(f64, f64); 22] = [
    (0.4, 17.1),
    (0.315, 15.0),
    (0.25, 13.0),
    (0.2, 11.0),
    (0.16, 9.0),
    (0.125, 7.0),
    (0.1, 4.9),
    (0.08, 2.9),
    (0.063, 0.9),
    (0.05, -1.1),
    (0.04, -3.2),
    (0.0315, -5.0),
    (0.025, -5.6),
    (0.02, -6.2),
    (0.016, -6.8),
    (0.0125, -7.4),
    (0.01, -8.0),
    (0.008, -8.6),
    (0.0063, -9.2),
    (0.005, -9.8),
    (0.004, -10.4),
    (0.00315, -11.0),
];

/// The ISO 3095 limit (dB re 1 µm) of the band whose centre is `centre_m` (m, nominal or
/// exact); `None` outside 0.4 m … 3.15 mm.
pub fn iso3095_limit_db(centre_m: f64) -> Option<f64> {
    let n = band_index(centre_m)?;
    ISO3095_LIMIT_DB
        .iter()
        .find(|(l, _)| band_index(*l) == Some(n))
        .map(|&(_, v)| v)
}

/// One one-third-octave wavelength band.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Band {
    /// Band number `n`: exact centre `10^(−n/10)` m (10 = 0.1 m, 15 = 31.5 mm, 20 = 10 mm).
    pub index: i32,
}

impl Band {
    /// Exact centre wavelength (m).
    pub fn centre_m(&self) -> f64 {
        10f64.powf(-f64::from(self.index) / 10.0)
    }

    /// Nominal centre wavelength (m): the preferred number the standards print (31.5 mm for
    /// the exact 31.62 mm).
    pub fn nominal_m(&self) -> f64 {
        const MANTISSA: [f64; 10] = [1.0, 1.25, 1.6, 2.0, 2.5, 3.15, 4.0, 5.0, 6.3, 8.0];
        // λ = 10^(−n/10) = 10^(−d) · 10^(r/10) with r = 0…9
        let d = (f64::from(self.index) / 10.0).ceil() as i32;
        let r = (10 * d - self.index) as usize;
        MANTISSA[r % 10] * 10f64.powi(-d)
    }

    /// Longer edge (m): `centre · 10^(1/20)`.
    pub(crate) fn longest_m(&self) -> f64 {
        self.centre_m() * 10f64.powf(0.05)
    }

    /// Shorter edge (m): `centre · 10^(−1/20)`.
    pub(crate) fn shortest_m(&self) -> f64 {
        self.centre_m() * 10f64.powf(-0.05)
    }

    /// Wavenumber range `[1/longest, 1/shortest]` (1/m).
    pub fn wavenumbers(&self) -> [f64; 2] {
        [1.0 / self.longest_m(), 1.0 / self.shortest_m()]
    }

    /// Whether the wavelength `l` (m) lies in the band (shorter edge included).
    pub fn holds(&self, l: f64) -> bool {
        l >= self.shortest_m() && l < self.longest_m()
    }
}

/// The band number of a centre wavelength (m), nominal or exact; `None` when it is not within
/// 2 % of a band centre.
fn band_index(centre_m: f64) -> Option<i32> {
    if !(centre_m.is_finite() && centre_m > 0.0) {
        return None;
    }
    let n = (-10.0 * centre_m.log10()).round();
    let exact = 10f64.powf(-n / 10.0);
    ((centre_m / exact - 1.0).abs() < 0.02).then_some(n as i32)
}

/// The bands whose centres lie in `[shortest_m, longest_m]` (m), longest wavelength first.
pub fn third_octave_bands(longest_m: f64, shortest_m: f64) -> Vec<Band> {
    let lo = (-10.0 * longest_m.log10() - 1e-9).ceil() as i32;
    let hi = (-10.0 * shortest_m.log10() + 1e-9).floor() as i32;
    (lo..=hi).map(|index| Band { index }).collect()
}

/// A roughness spectrum in one-third-octave wavelength bands.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BandSpectrum {
    /// The bands, longest wavelength first.
    pub bands: Vec<Band>,
    /// Level of each band (dB re 1 µm).
    pub level_db: Vec<f64>,
}

impl BandSpectrum {
    /// The level of the band centred at `centre_m` (m, nominal or exact), if the spectrum has it.
    pub fn level_at(&self, centre_m: f64) -> Option<f64> {
        let n = band_index(centre_m)?;
        self.bands
            .iter()
            .position(|b| b.index == n)
            .map(|i| self.level_db[i])
    }

    /// RMS roughness of each band (m): `r₀ · 10^(L/20)`.
    pub fn rms_m(&self) -> Vec<f64> {
        self.level_db
            .iter()
            .map(|l| REFERENCE_ROUGHNESS_M * 10f64.powf(l / 20.0))
            .collect()
    }

    /// Reads a band spectrum from CSV: a header, then one row per band with the centre
    /// wavelength and the level. The header names the wavelength's unit: `wavelength_mm` (mm)
    /// or `wavelength_m` (m), then `level_db` (dB re 1 µm). Centres must be one-third-octave
    /// band centres (nominal, e.g. 31.5 mm, or exact), each once.
    pub fn read_csv(path: &Path) -> Result<Self, RoughnessError> {
        Self::parse_csv(&super::read_text(path)?, &path.display().to_string())
    }

    /// [`Self::read_csv`] on text; `name` names it in messages.
    pub fn parse_csv(text: &str, name: &str) -> Result<Self, RoughnessError> {
        let bad = |reason: String| RoughnessError::Format {
            path: name.to_string(),
            reason,
        };
        let (header, lines) = super::csv_lines(text, name, "wavelength_mm, level_db")?;
        let to_m: fn(f64) -> f64 = match header.first().map(String::as_str) {
            Some("wavelength_mm") => crate::units::mm_to_m,
            Some("wavelength_m") => |m| m,
            _ => {
                return Err(bad(format!(
                    "the header `{}` must start with `wavelength_mm` or `wavelength_m` (the band centre's unit), then `level_db` (dB re 1 µm)",
                    header.join(", ")
                )))
            }
        };
        if header.get(1).map(String::as_str) != Some("level_db") {
            return Err(bad(format!(
                "the second column of the header `{}` must be `level_db` (dB re 1 µm)",
                header.join(", ")
            )));
        }
        let (mut centres, mut levels) = (Vec::new(), Vec::new());
        for (i, line) in lines.into_iter().enumerate() {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            let num = |k: usize, what: &str| -> Result<f64, RoughnessError> {
                cells
                    .get(k)
                    .and_then(|c| c.parse::<f64>().ok())
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        bad(format!(
                            "data row {}: {what} `{}` is not a finite number",
                            i + 1,
                            cells.get(k).unwrap_or(&"")
                        ))
                    })
            };
            centres.push(to_m(num(0, "wavelength")?));
            levels.push(num(1, "level (dB)")?);
        }
        Self::from_levels(&centres, &levels, name)
    }

    /// A band spectrum from band centres `centres_m` (m; one-third-octave band centres,
    /// nominal or exact, each once) and their levels `levels_db` (dB re 1 µm, −80 to 80);
    /// `name` names the data in messages (row `i` is the `i+1`-th pair).
    pub fn from_levels(
        centres_m: &[f64],
        levels_db: &[f64],
        name: &str,
    ) -> Result<Self, RoughnessError> {
        let bad = |reason: String| RoughnessError::Format {
            path: name.to_string(),
            reason,
        };
        if centres_m.len() != levels_db.len() {
            return Err(bad(format!(
                "{} band centres but {} levels",
                centres_m.len(),
                levels_db.len()
            )));
        }
        let mut rows: Vec<(Band, f64)> = Vec::new();
        for (i, (&l, &level)) in centres_m.iter().zip(levels_db).enumerate() {
            let index = band_index(l).ok_or_else(|| {
                bad(format!(
                    "data row {}: wavelength {} m is not a one-third-octave band centre (10^(−n/10) m, e.g. 0.0315 or 0.04 m)",
                    i + 1,
                    l
                ))
            })?;
            if !(level.is_finite() && (-80.0..=80.0).contains(&level)) {
                return Err(bad(format!(
                    "data row {}: level {level} dB re 1 µm is out of range, allowed −80 to 80 dB (1e-4 to 1e4 µm rms)",
                    i + 1
                )));
            }
            if rows.iter().any(|(b, _)| b.index == index) {
                return Err(bad(format!(
                    "data row {}: the band of {} m is given twice",
                    i + 1,
                    l
                )));
            }
            rows.push((Band { index }, level));
        }
        if rows.is_empty() {
            return Err(bad("no bands: one row per band after the header".into()));
        }
        rows.sort_by_key(|(b, _)| b.index);
        Ok(Self {
            bands: rows.iter().map(|r| r.0).collect(),
            level_db: rows.iter().map(|r| r.1).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{iso3095_limit_db, third_octave_bands, BandSpectrum};
    /// Nominal centres are the standards' preferred numbers and band edges touch.
    #[test]
    fn nominal_centres_and_edges() {
        let b = third_octave_bands(0.1, 0.01);
        let nominal: Vec<f64> = b.iter().map(|b| b.nominal_m()).collect();
        let want = [
            0.1, 0.08, 0.063, 0.05, 0.04, 0.0315, 0.025, 0.02, 0.016, 0.0125, 0.01,
        ];
        assert_eq!(nominal.len(), want.len());
        for (a, w) in nominal.iter().zip(want) {
            assert!((a - w).abs() < 1e-12, "{a} {w}");
        }
        for w in b.windows(2) {
            assert!((w[0].shortest_m() - w[1].longest_m()).abs() < 1e-15);
        }
        // one-third octave: ten bands per decade
        assert!((b[0].centre_m() / b[10].centre_m() - 10.0).abs() < 1e-12);
    }

    #[test]
    fn the_limit_is_found_by_nominal_and_exact_centre() {
        assert_eq!(iso3095_limit_db(0.0315), Some(-5.0));
        assert_eq!(iso3095_limit_db(10f64.powf(-1.5)), Some(-5.0));
        assert_eq!(iso3095_limit_db(1.0), None);
        assert_eq!(iso3095_limit_db(0.033), None);
    }

    #[test]
    fn band_csv_reads_mm_and_refuses_non_centres_and_repeats() {
        let s =
            BandSpectrum::parse_csv("wavelength_mm, level_db\n40, -3\n31.5, -6\n", "t").unwrap();
        assert_eq!(s.level_at(0.0315), Some(-6.0));
        assert_eq!(s.bands[0].nominal_m(), 0.04);
        let e = BandSpectrum::parse_csv("wavelength_mm, level_db\n33, 1\n", "t").unwrap_err();
        assert!(
            e.to_string().contains("not a one-third-octave band centre"),
            "{e}"
        );
        let e =
            BandSpectrum::parse_csv("wavelength_mm, level_db\n40, 1\n40, 2\n", "t").unwrap_err();
        assert!(e.to_string().contains("twice"), "{e}");
        let e = BandSpectrum::parse_csv("lambda, level_db\n40, 1\n", "t").unwrap_err();
        assert!(e.to_string().contains("wavelength_mm"), "{e}");
    }
}
