//! The UIC54 (54E1) rail profile as a closed polygon, and polygon section properties.
//!
//! The checked half profile `data/uic54-half-profile.csv` (mm; columns: lateral offset from
//! the centre line, height above the foot underside) runs from the foot centre along the foot
//! underside, foot edge, foot top, fishing face, R16 fillet, web, R22 fillet, head underside,
//! head side, and the R13 / R80 / R300 head-top arcs to the head centre. It is embedded with
//! `include_str!`, converted to the model frame (lateral → y, up → z, metres) and mirrored
//! about y = 0 to the full closed counter-clockwise polygon. The profile is upright (not
//! inclined); the 1/40 inclination is applied to the section mesh
//! ([`crate::mesh::section`]).
//!
//! Section properties of a simple polygon follow from Green's theorem (e.g. Bourke,
//! "Calculating the area and centroid of a polygon", 1988; Steger, "On the calculation of
//! arbitrary moments of polygons", 1996):
//! A = ½ Σ cᵢ, c_i = yᵢ z_{i+1} − y_{i+1} zᵢ; ∫y dA = ⅙ Σ (yᵢ + y_{i+1}) cᵢ;
//! ∫y² dA = 1/12 Σ (yᵢ² + yᵢ y_{i+1} + y_{i+1}²) cᵢ; likewise for z; second moments about the
//! centroidal axes by the parallel-axis theorem.
//!
//! Reference values: EN 13674-1 54E1 A = 69.77 cm², centroid 75.1 mm above the foot,
//! I = 2338 cm⁴ (vertical bending, about the horizontal axis) and 419.2 cm⁴ (lateral bending);
//! the simplified polygon gives 6947 mm², 75.6 mm, 2344 / 421 cm⁴ (CSV header).

use super::MeshError;

/// The embedded UIC54 half profile (mm, header comment line starting with `#`).
pub(crate) const UIC54_HALF_PROFILE_CSV: &str = include_str!("../../data/uic54-half-profile.csv");

/// Area, centroid and centroidal second moments of a plane section (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionProperties {
    /// Area A (m²).
    pub area_m2: f64,
    /// Centroid lateral coordinate y_c (m).
    pub centroid_y_m: f64,
    /// Centroid height z_c above the foot underside (m).
    pub centroid_z_m: f64,
    /// I_yy = ∫ (z − z_c)² dA (m⁴): about the horizontal centroidal axis, governs vertical
    /// bending.
    pub i_vertical_bending_m4: f64,
    /// I_zz = ∫ (y − y_c)² dA (m⁴): about the vertical centroidal axis, governs lateral
    /// bending.
    pub i_lateral_bending_m4: f64,
    /// Product of inertia ∫ (y − y_c)(z − z_c) dA (m⁴); zero for the upright symmetric section.
    pub i_product_m4: f64,
}

impl SectionProperties {
    /// Properties from the raw integrals A, ∫y, ∫z, ∫y², ∫z², ∫yz (SI units) about the origin.
    pub(crate) fn from_integrals(a: f64, sy: f64, sz: f64, syy: f64, szz: f64, syz: f64) -> Self {
        let yc = sy / a;
        let zc = sz / a;
        SectionProperties {
            area_m2: a,
            centroid_y_m: yc,
            centroid_z_m: zc,
            i_vertical_bending_m4: szz - a * zc * zc,
            i_lateral_bending_m4: syy - a * yc * yc,
            i_product_m4: syz - a * yc * zc,
        }
    }
}

/// Section properties of a simple polygon given counter-clockwise (vertices (y, z) in m, not
/// repeated at the end). A clockwise polygon gives a negative area.
pub(crate) fn polygon_properties(poly: &[[f64; 2]]) -> SectionProperties {
    let n = poly.len();
    let (mut a, mut sy, mut sz, mut syy, mut szz, mut syz) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..n {
        let [y0, z0] = poly[i];
        let [y1, z1] = poly[(i + 1) % n];
        let c = y0 * z1 - y1 * z0;
        a += c;
        sy += (y0 + y1) * c;
        sz += (z0 + z1) * c;
        syy += (y0 * y0 + y0 * y1 + y1 * y1) * c;
        szz += (z0 * z0 + z0 * z1 + z1 * z1) * c;
        syz += (y0 * z1 + 2.0 * y0 * z0 + 2.0 * y1 * z1 + y1 * z0) * c;
    }
    SectionProperties::from_integrals(
        a / 2.0,
        sy / 6.0,
        sz / 6.0,
        syy / 12.0,
        szz / 12.0,
        syz / 24.0,
    )
}

/// Foot width of the embedded UIC54 profile (m), for checks that need it without parsing the
/// profile (the test `uic54_dimensions` holds it equal to [`RailProfile::foot_width_m`] of
/// [`RailProfile::uic54`]).
pub const UIC54_FOOT_WIDTH_M: f64 = 0.140;

/// The rail profile in the model frame (m): y lateral, z up, z = 0 at the foot underside.
#[derive(Debug, Clone, PartialEq)]
pub struct RailProfile {
    /// Half profile, y ≥ 0, from the foot centre (0, 0) round to the head centre (0, h).
    pub half: Vec<[f64; 2]>,
}

impl RailProfile {
    /// The embedded UIC54 (54E1) profile.
    pub fn uic54() -> Result<Self, MeshError> {
        Self::from_half_csv(UIC54_HALF_PROFILE_CSV)
    }

    /// Reads a half profile in the CSV format of `data/uic54-half-profile.csv`: lines
    /// `lateral_mm,up_mm`, `#` comments, from the foot centre to the head centre.
    pub(crate) fn from_half_csv(text: &str) -> Result<Self, MeshError> {
        let mut half = Vec::new();
        for (k, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let mut it = line.split(',').map(|s| s.trim().parse::<f64>());
            let (lat, up) = match (it.next(), it.next(), it.next()) {
                (Some(Ok(a)), Some(Ok(b)), None) if a.is_finite() && b.is_finite() => (a, b),
                _ => {
                    return Err(MeshError::ProfileParse {
                        line: k + 1,
                        reason: format!(
                            "expected two finite numbers `lateral_mm,up_mm`, got `{line}`"
                        ),
                    })
                }
            };
            if lat < 0.0 {
                return Err(MeshError::ProfileParse {
                    line: k + 1,
                    reason: "lateral coordinate of a half profile must be >= 0".into(),
                });
            }
            half.push([crate::units::mm_to_m(lat), crate::units::mm_to_m(up)]);
        }
        if half.len() < 3 {
            return Err(MeshError::ProfileParse {
                line: 0,
                reason: "fewer than 3 profile points".into(),
            });
        }
        let first = half[0];
        let last = half[half.len() - 1];
        if first[0] != 0.0 || last[0] != 0.0 || first[1] != 0.0 {
            return Err(MeshError::ProfileParse {
                line: 0,
                reason: "the half profile must start at the foot centre (0,0) and end on the centre line".into(),
            });
        }
        Ok(RailProfile { half })
    }

    /// The full closed polygon, counter-clockwise (starting at the foot centre, along the foot
    /// underside towards +y), vertices not repeated.
    pub fn polygon(&self) -> Vec<[f64; 2]> {
        // The half runs foot centre → +y foot edge → head centre: that is counter-clockwise.
        let mut p: Vec<[f64; 2]> = self.half.clone();
        // Mirror back from head centre to the foot centre, excluding the two centre points.
        for q in self.half[1..self.half.len() - 1].iter().rev() {
            p.push([-q[0], q[1]]);
        }
        p
    }

    /// Section properties of the full polygon.
    pub fn properties(&self) -> SectionProperties {
        polygon_properties(&self.polygon())
    }

    /// Rail height (m): the head centre above the foot underside.
    pub fn height_m(&self) -> f64 {
        self.half[self.half.len() - 1][1]
    }

    /// Foot width (m): twice the largest lateral coordinate at the foot (z < height/2).
    pub fn foot_width_m(&self) -> f64 {
        let h = self.height_m();
        2.0 * self
            .half
            .iter()
            .filter(|p| p[1] < 0.5 * h)
            .map(|p| p[0])
            .fold(0.0, f64::max)
    }

    /// Head width (m): twice the largest lateral coordinate in the upper half.
    pub(crate) fn head_width_m(&self) -> f64 {
        let h = self.height_m();
        2.0 * self
            .half
            .iter()
            .filter(|p| p[1] >= 0.5 * h)
            .map(|p| p[0])
            .fold(0.0, f64::max)
    }

    /// Web thickness (m): twice the smallest lateral coordinate between foot and head.
    pub fn web_thickness_m(&self) -> f64 {
        let h = self.height_m();
        2.0 * self
            .half
            .iter()
            .filter(|p| p[1] > 0.2 * h && p[1] < 0.8 * h)
            .map(|p| p[0])
            .fold(f64::INFINITY, f64::min)
    }

    /// Index in [`Self::half`] of the start of the head top (running surface): the last vertex
    /// of the head side, i.e. the last point where the head is at (nearly, within 0.5 %) its
    /// full half width.
    pub(crate) fn head_top_start(&self) -> usize {
        let half_w = 0.5 * self.head_width_m();
        let mut idx = 0;
        for (i, p) in self.half.iter().enumerate() {
            if p[0] >= 0.995 * half_w {
                idx = i;
            }
        }
        idx
    }

    /// The head top (running surface) of the half profile, from the end of the head side to
    /// the head centre (m).
    pub(crate) fn head_top(&self) -> &[[f64; 2]] {
        &self.half[self.head_top_start()..]
    }

    /// The crown region of the running surface: the central arc of the head top.
    ///
    /// The crown radius is that of the circle tangent to the horizontal at the apex (0, h)
    /// through the head-top vertex nearest to y = 10 mm: R = (y² + d²)/(2d), d = h − z (the
    /// profile points are rounded to 1 µm, so three-point radii of the 1 mm spaced points are
    /// too noisy). The crown is the central run of vertices within 2 µm of that circle.
    pub fn crown(&self) -> Crown {
        let top = self.head_top();
        let h = self.height_m();
        let p_ref = top
            .iter()
            .copied()
            .min_by(|a, b| (a[0] - 0.010).abs().total_cmp(&(b[0] - 0.010).abs()))
            .unwrap_or([0.0, h]);
        let d = h - p_ref[1];
        let radius = if d > 0.0 {
            (p_ref[0] * p_ref[0] + d * d) / (2.0 * d)
        } else {
            f64::INFINITY
        };
        let mut half_width = 0.0;
        for p in top.iter().rev() {
            let z_circle = h - radius + (radius * radius - p[0] * p[0]).max(0.0).sqrt();
            if (p[1] - z_circle).abs() > 2e-6 {
                break;
            }
            half_width = p[0];
        }
        Crown {
            radius_m: radius,
            half_width_m: half_width,
        }
    }
}

/// The crown (central arc) of the rail head top.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crown {
    /// Crown radius (m) at the head centre (300 mm for 54E1).
    pub radius_m: f64,
    /// Lateral half width (m) of the region where the local radius is the crown radius.
    pub half_width_m: f64,
}

/// Radius (m) of the circle through three points (infinite if collinear).
pub fn circumradius(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let ab = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    let bc = ((c[0] - b[0]).powi(2) + (c[1] - b[1]).powi(2)).sqrt();
    let ca = ((a[0] - c[0]).powi(2) + (a[1] - c[1]).powi(2)).sqrt();
    let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if cross == 0.0 {
        f64::INFINITY
    } else {
        ab * bc * ca / (2.0 * cross.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::{polygon_properties, MeshError, RailProfile, UIC54_FOOT_WIDTH_M};
    #[test]
    fn polygon_properties_of_a_rectangle_match_closed_form() {
        // b × h rectangle, corner at origin: A = bh, I = bh³/12, hb³/12.
        let (b, h) = (0.3, 0.5);
        let p = polygon_properties(&[[0.0, 0.0], [b, 0.0], [b, h], [0.0, h]]);
        assert!((p.area_m2 - b * h).abs() < 1e-15);
        assert!((p.centroid_y_m - b / 2.0).abs() < 1e-15);
        assert!((p.centroid_z_m - h / 2.0).abs() < 1e-15);
        assert!((p.i_vertical_bending_m4 - b * h.powi(3) / 12.0).abs() < 1e-15);
        assert!((p.i_lateral_bending_m4 - h * b.powi(3) / 12.0).abs() < 1e-15);
        assert!(p.i_product_m4.abs() < 1e-15);
        // Right triangle legs b (y) and h (z): I_product about centroid = −b²h²/72.
        let t = polygon_properties(&[[0.0, 0.0], [b, 0.0], [0.0, h]]);
        assert!((t.i_product_m4 + b * b * h * h / 72.0).abs() < 1e-15);
        assert!((t.i_vertical_bending_m4 - b * h.powi(3) / 36.0).abs() < 1e-15);
    }

    #[test]
    fn uic54_properties_match_csv_header_and_en() {
        let p = RailProfile::uic54().unwrap();
        let s = p.properties();
        let a_mm2 = s.area_m2 * 1e6;
        let zc_mm = s.centroid_z_m * 1e3;
        let iv_cm4 = s.i_vertical_bending_m4 * 1e8;
        let il_cm4 = s.i_lateral_bending_m4 * 1e8;
        eprintln!(
            "UIC54 polygon: A {a_mm2:.1} mm2, zc {zc_mm:.2} mm, I {iv_cm4:.1} / {il_cm4:.1} cm4"
        );
        // CSV header (rounded values): 6947 mm², 75.6 mm, 2344 / 421 cm⁴.
        assert!((a_mm2 - 6947.0).abs() < 1.0);
        assert!((zc_mm - 75.6).abs() < 0.05);
        assert!((iv_cm4 - 2344.0).abs() < 1.0);
        assert!((il_cm4 - 421.0).abs() < 1.0);
        // EN 13674-1: 6977 mm², 75.1 mm, 2338 / 419.2 cm⁴ (the simplified polygon is within 1 %).
        assert!((a_mm2 / 6977.0 - 1.0).abs() < 0.01);
        assert!((zc_mm - 75.1).abs() < 1.0);
        assert!((iv_cm4 / 2338.0 - 1.0).abs() < 0.01);
        assert!((il_cm4 / 419.2 - 1.0).abs() < 0.01);
        assert!(s.centroid_y_m.abs() < 1e-15 && s.i_product_m4.abs() < 1e-15);
    }

    #[test]
    fn uic54_dimensions() {
        let p = RailProfile::uic54().unwrap();
        assert!((p.height_m() - 0.159).abs() < 1e-12);
        assert!((p.foot_width_m() - 0.140).abs() < 1e-12);
        assert_eq!(p.foot_width_m(), UIC54_FOOT_WIDTH_M);
        assert!((p.head_width_m() - 0.070).abs() < 1e-12);
        assert!((p.web_thickness_m() - 0.016).abs() < 1e-12);
        let top = p.head_top();
        assert!(
            (top[0][0] - 0.034942).abs() < 1e-9,
            "head top starts at the head side end"
        );
        let c = p.crown();
        eprintln!(
            "crown R {:.1} mm, half width {:.2} mm",
            c.radius_m * 1e3,
            c.half_width_m * 1e3
        );
        assert!(
            (c.radius_m - 0.300).abs() < 0.003,
            "crown radius {}",
            c.radius_m
        );
        assert!(c.half_width_m > 0.0155 && c.half_width_m < 0.0175);
    }

    #[test]
    fn bad_csv_is_an_error() {
        assert!(matches!(
            RailProfile::from_half_csv("0,0\n1,x\n0,2\n"),
            Err(MeshError::ProfileParse { line: 2, .. })
        ));
        assert!(RailProfile::from_half_csv("0,0\n").is_err());
    }
}
