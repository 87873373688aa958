//! Checks of the fastening's hold pattern: rigid and elastic regions, indices, the elastic
//! variant of the presets. Every error names the dotted key and what is allowed.

use super::{
    DirectionHold, Fastening, HoldPattern, Holds, ModelError, RigidRegion, MAX_HOLD_STIFFNESS,
    MIN_HOLD_STIFFNESS,
};

/// Largest damping per fastening of an elastic hold (N·s/m), as for the railpad dampers.
const MAX_HOLD_DAMPING: f64 = 1e12;

impl Fastening {
    /// Checks the values of the holds: each direction of a custom pattern, or the stiffness,
    /// damping and directions of a preset's elastic variant. (Which keys may appear together
    /// is checked when the table is read, `TryFrom<FasteningFile>`.)
    pub(super) fn validate_holds(&self, file: &str) -> Result<(), ModelError> {
        let key_err = |key: &str, message: String| ModelError::Key {
            file: file.into(),
            key: key.into(),
            message,
        };
        let (preset, e) = match &self.holds {
            Holds::Custom(p) => {
                for (d, h) in [("x", &p.x), ("y", &p.y), ("z", &p.z)] {
                    self.check_direction(file, &format!("fastening.custom.{d}"), h)?;
                }
                return Ok(());
            }
            Holds::Preset { elastic: None, .. } => return Ok(()),
            Holds::Preset {
                preset,
                elastic: Some(e),
            } => (*preset, e),
        };
        check_stiffness(
            file,
            "fastening.hold_stiffness",
            e.stiffness,
            "N/m per fastening",
        )?;
        check_damping(file, "fastening.hold_damping", e.damping, false)?;
        if e.directions.as_ref().is_some_and(|d| d.is_empty()) {
            return Err(key_err(
                "fastening.hold_directions",
                "give at least one of \"x\", \"y\", \"z\"".into(),
            ));
        }
        // A direction the preset does not hold cannot be made elastic (when the directions
        // are not given, those the preset holds are).
        let rigid = HoldPattern::preset(preset, self.rows, self.columns);
        for &a in e.directions.iter().flatten() {
            let h = [&rigid.x, &rigid.y, &rigid.z][a.index()];
            if h.region() == RigidRegion::None {
                return Err(key_err(
                    "fastening.hold_directions",
                    format!(
                        "{} holds nothing in {:?}: remove it from the list",
                        preset.model().name(),
                        a
                    ),
                ));
            }
        }
        Ok(())
    }

    /// One direction of a custom pattern under `key` (`fastening.custom.x`, …).
    fn check_direction(&self, file: &str, key: &str, h: &DirectionHold) -> Result<(), ModelError> {
        let key_err = |k: String, message: String| ModelError::Key {
            file: file.into(),
            key: k,
            message,
        };
        if h.node_lines && !h.region().has_node_lines() {
            return Err(key_err(
                format!("{key}.node_lines"),
                "node lines are held for the regions \"columns\" and \"rows\" only".into(),
            ));
        }
        // The stiffness keys of the region held elastically (per fastening, or per line on
        // node lines), and those of the other kind, which are refused.
        let lines = h.on_node_lines();
        let (k_key, c_key, k_given, c_given) = if lines {
            (
                "line_stiffness",
                "line_damping",
                h.line_stiffness,
                h.line_damping,
            )
        } else {
            ("stiffness", "damping", h.stiffness, h.damping)
        };
        let (other_k, other_c, other_given) = if lines {
            ("stiffness", "damping", [h.stiffness, h.damping])
        } else {
            (
                "line_stiffness",
                "line_damping",
                [h.line_stiffness, h.line_damping],
            )
        };
        if let Some((k, _)) = [other_k, other_c]
            .into_iter()
            .zip(other_given)
            .find(|(_, v)| v.is_some())
        {
            let why = if lines {
                "a hold on node lines takes line_stiffness and line_damping (N/m and N s/m per held line)"
            } else {
                "only allowed with an elastic hold on node lines (elastic = \"columns\" or \"rows\" with node_lines = true)"
            };
            return Err(key_err(format!("{key}.{k}"), why.into()));
        }
        if let Some(e) = h.elastic {
            if h.rigid != RigidRegion::None {
                return Err(key_err(
                    key.into(),
                    "give either rigid or elastic, not both".into(),
                ));
            }
            if e == RigidRegion::None {
                return Err(key_err(
                    format!("{key}.elastic"),
                    "an elastic hold needs a region: \"columns\", \"rows\", \"continuous\" or \"grid_points\" (for no hold write rigid = \"none\")".into(),
                ));
            }
            let unit = if lines {
                "N/m per held line"
            } else {
                "N/m per fastening"
            };
            let Some(k) = k_given else {
                return Err(key_err(
                    format!("{key}.{k_key}"),
                    format!("an elastic hold needs {k_key} ({unit})"),
                ));
            };
            check_stiffness(file, &format!("{key}.{k_key}"), k, unit)?;
            check_damping(file, &format!("{key}.{c_key}"), c_given, lines)?;
        } else if k_given.is_some() || c_given.is_some() {
            let k = if k_given.is_some() { k_key } else { c_key };
            return Err(key_err(
                format!("{key}.{k}"),
                "only allowed with an elastic hold (elastic = \"columns\" etc. instead of rigid)"
                    .into(),
            ));
        }
        let n = match h.region() {
            RigidRegion::Columns => self.columns,
            RigidRegion::Rows => self.rows,
            RigidRegion::None | RigidRegion::Continuous | RigidRegion::GridPoints => 0,
        };
        let ikey = format!("{key}.indices");
        if n == 0 && !h.indices.is_empty() {
            return Err(key_err(
                ikey,
                "indices are only allowed with the regions \"columns\" or \"rows\"".into(),
            ));
        }
        if n > 0 && h.indices.is_empty() {
            return Err(key_err(ikey, "give at least one column/row index".into()));
        }
        if let Some(&i) = h.indices.iter().find(|&&i| i >= n.max(1)) {
            return Err(ModelError::OutOfRange {
                file: file.into(),
                key: ikey,
                value: i.to_string(),
                allowed: format!("0..={}", n.saturating_sub(1)),
            });
        }
        let mut sorted = h.indices.clone();
        sorted.sort_unstable();
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            return Err(key_err(ikey, "indices must be distinct".into()));
        }
        Ok(())
    }
}

fn check_stiffness(file: &str, key: &str, k: f64, unit: &str) -> Result<(), ModelError> {
    if !(k.is_finite() && (MIN_HOLD_STIFFNESS..=MAX_HOLD_STIFFNESS).contains(&k)) {
        return Err(ModelError::OutOfRange {
            file: file.into(),
            key: key.into(),
            value: k.to_string(),
            allowed: format!(
                "{MIN_HOLD_STIFFNESS:e} to {MAX_HOLD_STIFFNESS:e} {unit} (an elastic hold stands for a fastening clip, 1e6 to 1e9 N/m; far below, the rail held by it alone in a direction is nearly free; a rigid hold: rigid = …)"
            ),
        });
    }
    Ok(())
}

/// Damping of an elastic hold under `key`: per held line (`per_line`) or per fastening.
fn check_damping(file: &str, key: &str, c: Option<f64>, per_line: bool) -> Result<(), ModelError> {
    let unit = if per_line {
        "N s/m per held line"
    } else {
        "N s/m per fastening"
    };
    match c {
        Some(c) if !(c.is_finite() && (0.0..=MAX_HOLD_DAMPING).contains(&c)) => {
            Err(ModelError::OutOfRange {
                file: file.into(),
                key: key.into(),
                value: c.to_string(),
                allowed: format!("0 to {MAX_HOLD_DAMPING:e} {unit}"),
            })
        }
        _ => Ok(()),
    }
}
