//! Classification of the wheel's modes: rigid, axial, radial or circumferential rim motion
//! from the rim's displacement shares and the strain energy of the wheel body (the track's
//! classification is in the parent module; docs/theory.md on mode classification).

use serde::{Deserialize, Serialize};

use super::{ClassifyError, RIGID_BODY_HZ};
use crate::fe::assembly::{spring_energy, strain_energy_per_part_many};
use crate::mesh::Part;
use crate::structure::WheelStructure;

/// Family of a wheel mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WheelFamily {
    /// Rigid-body motion (incl. bounce on the primary suspension).
    Rigid,
    /// Axial (umbrella / out-of-plane) rim motion.
    Axial,
    /// Radial (in-plane) rim motion.
    Radial,
    /// Anything else (circumferential, coupled).
    Other,
}

impl WheelFamily {
    /// All families, in output order.
    pub const ALL: [WheelFamily; 4] = [
        WheelFamily::Rigid,
        WheelFamily::Axial,
        WheelFamily::Radial,
        WheelFamily::Other,
    ];

    /// snake_case name.
    pub fn name(self) -> &'static str {
        match self {
            WheelFamily::Rigid => "rigid",
            WheelFamily::Axial => "axial",
            WheelFamily::Radial => "radial",
            WheelFamily::Other => "other",
        }
    }

    /// Index in [`WheelFamily::ALL`] (CSV code).
    pub fn code(self) -> usize {
        WheelFamily::ALL
            .iter()
            .position(|&f| f == self)
            .unwrap_or(0)
    }
}

/// Classification of one wheel mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WheelModeClass {
    /// Family.
    pub family: WheelFamily,
    /// Strain-energy share of the wheel elements (0 when there is no strain energy).
    pub energy_wheel: f64,
    /// Strain-energy share of the primary suspension.
    pub energy_suspension: f64,
    /// Rigid-body mode of the wheel (no elastic wheel deformation dominates).
    pub rigid: bool,
    /// Shares of Σ u² on the rim nodes: [radial, axial, circumferential].
    pub rim_shares: [f64; 3],
}

/// Classifies a wheel mode (free-DOF vector of `wheel`) at frequency `f_hz` (Hz).
pub fn classify_wheel_mode(
    wheel: &WheelStructure,
    u_free: &[f64],
    f_hz: f64,
) -> Result<WheelModeClass, ClassifyError> {
    Ok(classify_wheel_modes(wheel, &[u_free], &[f_hz])?.remove(0))
}

/// [`classify_wheel_mode`] of several modes (`f_hz[i]` is the frequency of `u_free[i]`):
/// the element strain energies of all of them in one pass over the elements (each element
/// stiffness built once).
pub(crate) fn classify_wheel_modes(
    wheel: &WheelStructure,
    u_free: &[&[f64]],
    f_hz: &[f64],
) -> Result<Vec<WheelModeClass>, ClassifyError> {
    if f_hz.len() != u_free.len() {
        return Err(ClassifyError::Count {
            modes: u_free.len(),
            frequencies: f_hz.len(),
        });
    }
    let mut full = Vec::with_capacity(u_free.len());
    for u in u_free {
        if u.len() != wheel.dofmap.n_free() {
            return Err(ClassifyError::Length {
                expected: wheel.dofmap.n_free(),
                got: u.len(),
            });
        }
        if u.iter().any(|v| !v.is_finite()) {
            return Err(ClassifyError::NonFinite);
        }
        full.push(wheel.dofmap.expand(u)?);
    }
    let refs: Vec<&[f64]> = full.iter().map(|u| u.as_slice()).collect();
    let energies = strain_energy_per_part_many(&wheel.mesh, &wheel.materials, &refs)?;
    full.iter()
        .zip(&energies)
        .zip(f_hz)
        .map(|((u, e), &f)| Ok(wheel_shape_class(wheel, u, e.get(Part::Wheel), f)))
        .collect()
}

/// Family of a wheel mode from its full displacement vector `u`, its element strain energy
/// `ew` (J) and its frequency `f_hz` (Hz).
fn wheel_shape_class(wheel: &WheelStructure, u: &[f64], ew: f64, f_hz: f64) -> WheelModeClass {
    let es = spring_energy(&wheel.springs, u);
    let tot = ew + es;
    let (energy_wheel, energy_suspension) = if tot > 0.0 {
        (ew / tot, es / tot)
    } else {
        (0.0, 0.0)
    };
    let r_rim = wheel.params.rim_inner_radius_m;
    let mut s = [0.0; 3];
    for (n, p) in wheel.mesh.nodes.iter().enumerate() {
        if n == wheel.sprung_node {
            continue;
        }
        let r = (p[0] * p[0] + p[2] * p[2]).sqrt();
        if r < r_rim - 1e-9 || r == 0.0 {
            continue;
        }
        let (ux, uy, uz) = (u[3 * n], u[3 * n + 1], u[3 * n + 2]);
        let ur = (p[0] * ux + p[2] * uz) / r;
        let ut = (p[2] * ux - p[0] * uz) / r;
        s[0] += ur * ur;
        s[1] += uy * uy;
        s[2] += ut * ut;
    }
    let st: f64 = s.iter().sum();
    let rim_shares = if st > 0.0 {
        [s[0] / st, s[1] / st, s[2] / st]
    } else {
        [0.0; 3]
    };
    let rigid = f_hz < RIGID_BODY_HZ || energy_wheel < 0.5;
    let family = if rigid {
        WheelFamily::Rigid
    } else if rim_shares[1] > 0.5 {
        WheelFamily::Axial
    } else if rim_shares[0] > 0.5 {
        WheelFamily::Radial
    } else {
        WheelFamily::Other
    };
    WheelModeClass {
        family,
        energy_wheel,
        energy_suspension,
        rigid,
        rim_shares,
    }
}

/// The band of [`wheel_band_modes`]'s summary in the `modes` command (Hz): where a wheel's
/// in-plane (radial) pair sets a wear floor in corrugation predictions (about 1060 Hz on the
/// default wheel) and its lower out-of-plane (axial) modes lie.
pub const WHEEL_SUMMARY_BAND_HZ: [f64; 2] = [500.0, 2000.0];

/// A wheel's elastic modes in a band, in-plane and out-of-plane: what moves when the wheel's
/// geometry keys change.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WheelBandModes {
    /// The band [lo, hi) (Hz).
    pub band_hz: [f64; 2],
    /// In-plane mode frequencies (Hz), ascending: the rim moves mostly in the wheel's plane
    /// (axial share of the rim's motion below one half: families [`WheelFamily::Radial`] and
    /// [`WheelFamily::Other`], the latter e.g. the rim translating in its plane on the web,
    /// half radial and half circumferential).
    pub in_plane_hz: Vec<f64>,
    /// Out-of-plane mode frequencies (Hz), ascending: axial rim motion
    /// ([`WheelFamily::Axial`]).
    pub out_of_plane_hz: Vec<f64>,
}

/// The elastic modes of `frequencies_hz` (Hz, with their `classes`) in `band_hz` = [lo, hi),
/// in-plane and out-of-plane (rigid-body modes left out).
pub fn wheel_band_modes(
    frequencies_hz: &[f64],
    classes: &[WheelModeClass],
    band_hz: [f64; 2],
) -> WheelBandModes {
    let mut s = WheelBandModes {
        band_hz,
        in_plane_hz: Vec::new(),
        out_of_plane_hz: Vec::new(),
    };
    for (&f, c) in frequencies_hz.iter().zip(classes) {
        if !(f >= band_hz[0] && f < band_hz[1]) {
            continue;
        }
        match c.family {
            WheelFamily::Radial | WheelFamily::Other => s.in_plane_hz.push(f),
            WheelFamily::Axial => s.out_of_plane_hz.push(f),
            WheelFamily::Rigid => {}
        }
    }
    s.in_plane_hz.sort_by(f64::total_cmp);
    s.out_of_plane_hz.sort_by(f64::total_cmp);
    s
}
