//! Values inside their allowed ranges whose magnitude looks like a unit slip (a railpad
//! stiffness typed in kN/mm or MN/m, a wheel load in kN, a speed in m/h): the model runs, but
//! the user is told which key, what the model took it to mean, and what it probably meant.
//! The ranges themselves (hard errors) are in `validate.rs`; these are warnings only, since
//! each value can be meant (a study of a very soft pad, a light test vehicle).

use super::Model;

/// Below this stiffness (N/m) a railpad, hold or ballast spring is softer than any real one
/// (soft studded pads are about 1e7–1e8 N/m per fastening; ballast under a half sleeper
/// about 1e7–1e8 N/m): a value of 1300 is 1300 MN/m or kN/mm typed in the wrong unit.
pub(crate) const MIN_PLAUSIBLE_SPRING_N_M: f64 = 1e6;

/// Below this static wheel load (N) the load is under 100 kg: 100 is 100 kN typed in kN.
pub(crate) const MIN_PLAUSIBLE_WHEEL_LOAD_N: f64 = 1e3;

/// Above this speed (km/h) no train runs in service (a record run reaches about 575 km/h, the
/// model's limit is 500).
pub(crate) const MAX_PLAUSIBLE_SPEED_KMH: f64 = 400.0;

/// One value that looks like a unit slip.
#[derive(Debug, Clone, PartialEq)]
pub struct UnitSlip {
    /// Dotted key path, e.g. `fastening.vertical_stiffness`.
    pub key: String,
    /// The value as given (in the key's unit).
    pub value: f64,
    /// The unit the model reads the key in.
    pub unit: &'static str,
    /// Why it looks wrong and what was probably meant.
    pub hint: String,
}

impl std::fmt::Display for UnitSlip {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} = {} {}: {} (the model reads this key in {}; the run goes on with the value as given)",
            self.key, self.value, self.unit, self.hint, self.unit
        )
    }
}

/// Shortest wavelength of the analysis band (m): a rail mesh whose node planes in the solution
/// zone are this far apart or farther puts its element-passing ripple into the band.
pub(crate) const BAND_SHORTEST_WAVELENGTH_M: f64 = 0.02;

impl Model {
    /// A warning when the rail's node planes in the solution zone
    /// (`mesh.fine_element_length`) are at least `BAND_SHORTEST_WAVELENGTH_M` apart: the
    /// moving contact then excites the mesh at the element-passing wavelength inside the
    /// 20–80 mm band, and the band's F_L, F_N and wear are the mesh's, not the track's
    /// (both engines; on the small 80 mm test mesh they select 500 and 672 Hz and differ
    /// 8.6× in F_L band RMS). `None` for the default model (10 mm).
    pub fn mesh_in_band(&self) -> Option<String> {
        let e = self.mesh.fine_element_length;
        (e >= BAND_SHORTEST_WAVELENGTH_M).then(|| {
            format!(
                "mesh.fine_element_length = {e} m: the contact passes the rail's node planes every {:.0} mm, inside the 20–80 mm band, so the band's forces and wear show the mesh's ripple (and its harmonics), not the track; the two engines disagree there. Use at most 0.01 m for results (the default)",
                crate::units::m_to_mm(e)
            )
        })
    }

    /// The values of this (valid) model whose magnitudes look like unit slips: springs
    /// below `MIN_PLAUSIBLE_SPRING_N_M` (a zero stiffness is a deliberate "no spring" and
    /// not reported), a wheel load below `MIN_PLAUSIBLE_WHEEL_LOAD_N`, a speed above
    /// `MAX_PLAUSIBLE_SPEED_KMH`. Empty for the default model.
    pub fn unit_slips(&self) -> Vec<UnitSlip> {
        let mut out = Vec::new();
        let springs = [
            ("fastening", &self.fastening.springs, "a railpad"),
            ("ballast", &self.ballast, "ballast under a half sleeper"),
        ];
        for (scope, s, what) in springs {
            for (dir, k) in [
                ("vertical_stiffness", s.vertical_stiffness),
                ("lateral_stiffness", s.lateral_stiffness),
                ("longitudinal_stiffness", s.longitudinal_stiffness),
            ] {
                if k > 0.0 && k < MIN_PLAUSIBLE_SPRING_N_M {
                    out.push(UnitSlip {
                        key: format!("{scope}.{dir}"),
                        value: k,
                        unit: "N/m",
                        hint: format!(
                            "below {MIN_PLAUSIBLE_SPRING_N_M:e} N/m, softer than {what} is (1e7 to 5e9 N/m); \
                             {k} MN/m would be {:e} N/m",
                            k * 1e6
                        ),
                    });
                }
            }
        }
        let w = self.vehicle.wheel_load;
        if w < MIN_PLAUSIBLE_WHEEL_LOAD_N {
            out.push(UnitSlip {
                key: "vehicle.wheel_load".into(),
                value: w,
                unit: "N",
                hint: format!(
                    "below {MIN_PLAUSIBLE_WHEEL_LOAD_N:e} N (100 kg); {w} kN would be {:e} N",
                    w * 1e3
                ),
            });
        }
        let v = self.run.speed_kmh;
        if v > MAX_PLAUSIBLE_SPEED_KMH {
            out.push(UnitSlip {
                key: "run.speed_kmh".into(),
                value: v,
                unit: "km/h",
                hint: format!(
                    "above {MAX_PLAUSIBLE_SPEED_KMH} km/h, faster than any train in service \
                     ({MAX_PLAUSIBLE_SPEED_KMH} km/h is {:.0} m/s)",
                    crate::units::kmh_to_ms(MAX_PLAUSIBLE_SPEED_KMH)
                ),
            });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use crate::model::test_problems::small_model;
    use crate::model::Model;

    #[test]
    fn the_default_model_has_no_unit_slips() {
        assert!(Model::default_model().unit_slips().is_empty());
    }

    /// A railpad of 1300 (MN/m typed as N/m), a wheel load of 100 (kN) and 450 km/h are each
    /// reported once, naming the key and the unit; a zero pad stiffness (no spring) is not.
    #[test]
    fn slips_name_the_key_and_the_unit() {
        let m = small_model(&[
            "fastening.vertical_stiffness=1300",
            "vehicle.wheel_load=100",
            "run.speed_kmh=450",
        ])
        .unwrap();
        let s = m.unit_slips();
        let keys: Vec<&str> = s.iter().map(|u| u.key.as_str()).collect();
        assert_eq!(
            keys,
            [
                "fastening.vertical_stiffness",
                "vehicle.wheel_load",
                "run.speed_kmh"
            ]
        );
        let text = s[0].to_string();
        assert!(
            text.contains("fastening.vertical_stiffness = 1300 N/m"),
            "{text}"
        );
        assert!(text.contains("1.3e9 N/m"), "{text}");
        assert_eq!(s[1].unit, "N");
        assert_eq!(s[2].unit, "km/h");
        assert_eq!(
            small_model(&[])
                .unwrap()
                .fastening
                .springs
                .longitudinal_stiffness,
            0.0
        );
        assert!(small_model(&[]).unwrap().unit_slips().is_empty());
    }
}
