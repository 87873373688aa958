//! The blocks of the section mesh (parent module documentation): the profile's outline cut
//! into the blocks' boundary pieces, and each block meshed into the node accumulator.

use super::{
    col_top_fix, dist, invalid, lerp, mirror, straight, tfi, vertex, Builder, Grid, Polyline,
    FILLET_SPLIT_FROM_WEB,
};
use crate::mesh::grading::{grade, FineZone, GradingSpec};
use crate::mesh::profile::RailProfile;
use crate::mesh::section::SectionParams;
use crate::mesh::MeshError;

/// The section parameters in their ranges.
pub(super) fn check_params(params: &SectionParams) -> Result<(), MeshError> {
    let h = params.size_m;
    let hr = params.running_surface_size_m;
    if !(h > 0.0 && h <= 0.05) {
        return Err(invalid("size_m", h, "must be in (0, 0.05] m"));
    }
    if !(hr > 0.0 && hr <= h) {
        return Err(invalid(
            "running_surface_size_m",
            hr,
            "must be in (0, size_m]",
        ));
    }
    let hw = params.running_surface_half_width_m;
    if !(0.0..0.035).contains(&hw) {
        return Err(invalid(
            "running_surface_half_width_m",
            hw,
            "must be in [0, 0.035) m",
        ));
    }
    let hd = params.running_surface_depth_m;
    if !(0.0..0.015).contains(&hd) {
        return Err(invalid(
            "running_surface_depth_m",
            hd,
            "must be in [0, 0.015) m",
        ));
    }
    let inc = params.inclination_rad;
    if !(-0.2..0.2).contains(&inc) {
        return Err(invalid("inclination_rad", inc, "must be |angle| < 0.2 rad"));
    }
    Ok(())
}

/// The required foot node lines (upright frame, m): mirrored onto `y ≥ 0`, sorted and
/// deduplicated; each within the foot half width `foot_half_w` (m).
pub(super) fn foot_lines(params: &SectionParams, foot_half_w: f64) -> Result<Vec<f64>, MeshError> {
    let mut lines: Vec<f64> = Vec::new();
    for &y in &params.foot_node_lines_m {
        if !y.is_finite() || y.abs() > foot_half_w {
            return Err(MeshError::BreakpointOutside {
                x: y,
                lo: -foot_half_w,
                hi: foot_half_w,
            });
        }
        lines.push(y.abs());
    }
    lines.sort_by(f64::total_cmp);
    lines.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    Ok(lines)
}

/// A graded 1D distribution on `[lo, hi]` (m) with the target `size` (m) holding the
/// breakpoints `bps` (m), growth ratio at most 1.5.
fn grade_with(lo: f64, hi: f64, size: f64, bps: Vec<f64>) -> Result<Vec<f64>, MeshError> {
    let mut spec = GradingSpec::new(lo, hi, size);
    spec.breakpoints_m = bps;
    spec.max_ratio = 1.5;
    grade(&spec)
}

/// The profile's key points and the pieces of its outline that bound the blocks (right
/// half, upright frame; letters as in the UIC54 drawing, M and N the fillet points 45° from
/// the web).
pub(super) struct Outline {
    /// Foot half width (m).
    pub(super) foot_half_w: f64,
    pc: [f64; 2],
    pd: [f64; 2],
    pe: [f64; 2],
    pub(super) pf: [f64; 2],
    pi: [f64; 2],
    pj: [f64; 2],
    pm: [f64; 2],
    pn: [f64; 2],
    /// E → M (lower part of the R16 fillet).
    fil16_lower: Polyline,
    /// M → N (web side with the fillets' upper and lower parts).
    web_side: Polyline,
    /// N → I (lower part of the R22 fillet and the head underside).
    head_under: Polyline,
    /// C → D → E (foot top, a graph over y).
    foot_top: Polyline,
    /// K → J (head top, from the centre).
    head_top: Polyline,
}

impl Outline {
    /// The outline of a UIC54-topology profile.
    pub(super) fn new(profile: &RailProfile) -> Result<Self, MeshError> {
        let half = &profile.half;
        let i_c = vertex(half, 70.0, 11.0)?;
        let i_d = vertex(half, 45.46, 13.669)?;
        let i_e = vertex(half, 18.532, 23.461)?;
        let i_f = vertex(half, 8.0, 38.498)?;
        let i_g = vertex(half, 8.0, 97.1)?;
        let i_h = vertex(half, 22.482, 117.775)?;
        let i_i = vertex(half, 35.0, 122.327)?;
        let i_j = vertex(half, 34.942, 146.127)?;
        let i_k = half.len() - 1;
        let pf = half[i_f];
        let fil16 = Polyline::new(half[i_e..=i_f].to_vec()); // E → F
        let s_m = fil16.len() * (1.0 - FILLET_SPLIT_FROM_WEB);
        let fil22 = Polyline::new(half[i_g..=i_h].to_vec()); // G → H
        let s_n = fil22.len() * FILLET_SPLIT_FROM_WEB;
        let web_side = fil16
            .sub(s_m, fil16.len())
            .join(&Polyline::new(vec![pf, half[i_g]]))
            .join(&fil22.sub(0.0, s_n)); // M → N
        let head_under = fil22
            .sub(s_n, fil22.len())
            .join(&Polyline::new(half[i_h..=i_i].to_vec())); // N → I
        Ok(Outline {
            foot_half_w: half[1][0],
            pc: half[i_c],
            pd: half[i_d],
            pe: half[i_e],
            pf,
            pi: half[i_i],
            pj: half[i_j],
            pm: fil16.at(s_m),
            pn: fil22.at(s_n),
            fil16_lower: fil16.sub(0.0, s_m),
            web_side,
            head_under,
            foot_top: Polyline::new(half[i_c..=i_e].to_vec()),
            head_top: Polyline::new(half[i_j..=i_k].to_vec()).reversed(),
        })
    }
}

/// The cap block's result: the running-surface nodes, the right half's column bottoms on
/// the cap bottom line, the full width's column bottoms, and the right half's columns.
pub(super) struct Cap {
    pub(super) running: Vec<usize>,
    col_bot: Vec<[f64; 2]>,
    bots: Vec<[f64; 2]>,
    n_half: usize,
    /// Point S: the head side at the cap bottom line.
    ps: [f64; 2],
}

/// The blocks of a section mesh, meshed one after the other into the node accumulator.
pub(super) struct Blocks<'a> {
    pub(super) o: &'a Outline,
    pub(super) params: &'a SectionParams,
    /// Target element size (m).
    pub(super) h: f64,
    /// Web half thickness (m).
    pub(super) yc: f64,
    /// Required foot node lines (m, ≥ 0).
    pub(super) lines: &'a [f64],
    pub(super) b: Builder,
}

impl Blocks<'_> {
    /// The foot arms (right, and mirrored to the left): foot underside graded from the web
    /// to the foot edge through the required lines and the foot-top corners D and E.
    /// Returns the arm's straight left side (y_c, 0) → M.
    pub(super) fn foot_arms(&mut self) -> Result<Vec<[f64; 2]>, MeshError> {
        let (o, h, yc) = (self.o, self.h, self.yc);
        let (pc, pd, pe, pm) = (o.pc, o.pd, o.pe, o.pm);
        let foot_half_w = o.foot_half_w;
        let mut bps: Vec<f64> = self
            .lines
            .iter()
            .copied()
            .filter(|&y| y > yc && y < foot_half_w)
            .collect();
        for special in [pe[0], pd[0]] {
            if bps.iter().all(|&y| (y - special).abs() > 0.3 * h) {
                bps.push(special);
            }
        }
        let ys = grade_with(yc, foot_half_w, h, bps)?;
        let arm_bottom: Vec<[f64; 2]> = ys.iter().map(|&y| [y, 0.0]).collect();
        let arm_top: Vec<[f64; 2]> = ys
            .iter()
            .map(|&y| {
                if y >= pe[0] {
                    o.foot_top.at_y(y)
                } else {
                    let t = (pe[0] - y) / (pe[0] - yc);
                    o.fil16_lower.at(t * o.fil16_lower.len())
                }
            })
            .collect();
        let m_a = ((0.5 * (pc[1] + dist([yc, 0.0], pm)) / h).round() as usize).max(2);
        let arm_left = straight([yc, 0.0], pm, m_a);
        let arm_right = straight([foot_half_w, 0.0], pc, m_a);
        let arm = tfi(&arm_bottom, &arm_right, &arm_top, &arm_left);
        self.b.add(&arm, false);
        self.b.add(
            &Grid {
                pts: mirror(&arm.pts),
                ..arm
            },
            true,
        );
        Ok(arm_left)
    }

    /// The foot centre between the arms' left sides `arm_left`: its underside graded
    /// through the required lines. Returns its top M_L → M_R (the web's bottom) and the
    /// number of elements across it.
    pub(super) fn foot_centre(
        &mut self,
        arm_left: &[[f64; 2]],
    ) -> Result<(Vec<[f64; 2]>, usize), MeshError> {
        let (h, yc, pm) = (self.h, self.yc, self.o.pm);
        let bps: Vec<f64> = self
            .lines
            .iter()
            .copied()
            .filter(|&y| y > 0.0 && y < yc)
            .collect();
        let yh = grade_with(0.0, yc, h, bps)?;
        let mut centre_y: Vec<f64> = yh.iter().rev().map(|y| -y).collect();
        centre_y.extend_from_slice(&yh[1..]);
        let n_w = centre_y.len() - 1;
        let centre_bottom: Vec<[f64; 2]> = centre_y.iter().map(|&y| [y, 0.0]).collect();
        let pm_l = [-pm[0], pm[1]];
        let web_bottom = straight(pm_l, pm, n_w);
        self.b.add(
            &tfi(&centre_bottom, arm_left, &web_bottom, &mirror(arm_left)),
            false,
        );
        Ok((web_bottom, n_w))
    }

    /// The web from `web_bottom` to the line N_L → N_R of `n_w` elements, which it returns.
    pub(super) fn web(&mut self, web_bottom: &[[f64; 2]], n_w: usize) -> Vec<[f64; 2]> {
        let (o, h) = (self.o, self.h);
        let m_w = ((o.web_side.len() / h).ceil() as usize).max(2);
        let web_right = o.web_side.uniform(m_w);
        let pn_l = [-o.pn[0], o.pn[1]];
        let web_top = straight(pn_l, o.pn, n_w);
        self.b.add(
            &tfi(web_bottom, &web_right, &web_top, &mirror(&web_right)),
            false,
        );
        web_top
    }

    /// The cap: vertical columns under the running-surface nodes (graded along the head top,
    /// fine near the centre; at least half the web's `n_w` per half) with layers graded from
    /// the running surface down to the cap bottom line.
    pub(super) fn cap(&mut self, n_w: usize) -> Result<Cap, MeshError> {
        let (o, h, p) = (self.o, self.h, self.params);
        let (hr, hw, hd) = (
            p.running_surface_size_m,
            p.running_surface_half_width_m,
            p.running_surface_depth_m,
        );
        let (pi, pj, head_top) = (o.pi, o.pj, &o.head_top);
        let mut h_run = hr;
        let mut h_top = h;
        let s_top = loop {
            let mut spec = GradingSpec::new(0.0, head_top.len(), h_top);
            spec.zones.push(FineZone {
                start_m: 0.0,
                end_m: hw,
                size_m: h_run,
            });
            let s = grade(&spec)?;
            if s.len() > n_w / 2 + 2 {
                break s;
            }
            h_run *= 0.8;
            h_top *= 0.8;
        };
        let n_half = s_top.len() - 1;
        let zc = pi[1] + 0.6 * (pj[1] - pi[1]);
        let head_side = Polyline::new(vec![pi, pj]);
        let ps = head_side.at((zc - pi[1]) / (pj[1] - pi[1]) * head_side.len());
        // Right-half columns k = 0 (centre) … n_half (head side): top and bottom points.
        let col_top: Vec<[f64; 2]> = s_top.iter().map(|&s| head_top.at(s)).collect();
        let mut col_bot: Vec<[f64; 2]> = col_top.iter().map(|p| [p[0], zc]).collect();
        col_top_fix(&mut col_bot, ps);
        // Layer fractions from the centre column (depth graded from the running surface).
        let depth_c = col_top[0][1] - zc;
        let mut spec = GradingSpec::new(0.0, depth_c, h);
        spec.zones.push(FineZone {
            start_m: 0.0,
            end_m: hd,
            size_m: hr,
        });
        let depths = grade(&spec)?;
        let m_cap = depths.len() - 1;
        // Full-width columns from −J to +J.
        let mut tops: Vec<[f64; 2]> = mirror(&col_top[1..]);
        tops.reverse();
        tops.extend_from_slice(&col_top);
        let mut bots: Vec<[f64; 2]> = mirror(&col_bot[1..]);
        bots.reverse();
        bots.extend_from_slice(&col_bot);
        let ncol = tops.len();
        let mut cap = Grid {
            n: ncol - 1,
            m: m_cap,
            pts: vec![[0.0; 2]; ncol * (m_cap + 1)],
        };
        for j in 0..=m_cap {
            // j = 0 at the bottom: depth fraction from the top is 1 − …
            let f = depths[m_cap - j] / depth_c;
            for k in 0..ncol {
                cap.pts[j * ncol + k] = if j == 0 {
                    bots[k]
                } else if j == m_cap {
                    tops[k]
                } else {
                    lerp(tops[k], bots[k], f)
                };
            }
        }
        self.b.add(&cap, false);
        let running: Vec<usize> = tops.iter().map(|&p| self.b.node(p)).collect();
        Ok(Cap {
            running,
            col_bot,
            bots,
            n_half,
            ps,
        })
    }

    /// The head centre (from `web_top` to the cap bottom's middle `n_w` elements) and the
    /// head arms (head underside N → I to the rest of the cap bottom, mirrored).
    pub(super) fn head(&mut self, cap: &Cap, web_top: &[[f64; 2]], n_w: usize) {
        let (o, h) = (self.o, self.h);
        let (pn, pi, ps, n_half) = (o.pn, o.pi, cap.ps, cap.n_half);
        let i_t = n_w / 2;
        let pt = cap.col_bot[i_t];
        let m_h = ((0.5 * (dist(pn, pt) + dist(pi, ps)) / h).round() as usize).max(2);
        let head_if = straight(pn, pt, m_h); // N → T
        let centre_top: Vec<[f64; 2]> = cap.bots[n_half - i_t..=n_half + i_t].to_vec();
        self.b.add(
            &tfi(web_top, &head_if, &centre_top, &mirror(&head_if)),
            false,
        );
        let n_ha = n_half - i_t;
        let ha_bottom = o.head_under.uniform(n_ha);
        let ha_right = straight(pi, ps, m_h);
        let ha_top: Vec<[f64; 2]> = cap.col_bot[i_t..=n_half].to_vec();
        let ha = tfi(&ha_bottom, &ha_right, &ha_top, &head_if);
        self.b.add(&ha, false);
        self.b.add(
            &Grid {
                pts: mirror(&ha.pts),
                ..ha
            },
            true,
        );
    }
}
