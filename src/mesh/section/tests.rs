use super::{bilinear, dist, HashMap, RailProfile, SectionLocator, SectionMesh, SectionParams};
const EN_AREA_M2: f64 = 6977e-6;
const EN_ZC_M: f64 = 0.0751;
const EN_I_VERT_M4: f64 = 2338e-8;
const EN_I_LAT_M4: f64 = 419.2e-8;

fn row_lines() -> Vec<f64> {
    // Edges of four 20 mm strips centred at ±17.5 and ±52.5 mm.
    vec![0.0075, 0.0275, 0.0425, 0.0625]
}

#[test]
fn default_section_properties_match_en_and_polygon() {
    let params = SectionParams {
        foot_node_lines_m: row_lines(),
        ..Default::default()
    };
    let m = SectionMesh::uic54(&params).unwrap();
    let s = m.properties();
    let poly = RailProfile::uic54().unwrap().properties();
    eprintln!(
        "section: {} nodes, {} quads; A {:.1} mm2 (poly {:.1}, EN 6977), zc {:.2} mm, I {:.1} / {:.1} cm4",
        m.nodes.len(),
        m.quads.len(),
        s.area_m2 * 1e6,
        poly.area_m2 * 1e6,
        s.centroid_z_m * 1e3,
        s.i_vertical_bending_m4 * 1e8,
        s.i_lateral_bending_m4 * 1e8
    );
    assert!((s.area_m2 / EN_AREA_M2 - 1.0).abs() < 0.01);
    assert!((s.centroid_z_m - EN_ZC_M).abs() < 1e-3);
    assert!((s.i_vertical_bending_m4 / EN_I_VERT_M4 - 1.0).abs() < 0.03);
    assert!((s.i_lateral_bending_m4 / EN_I_LAT_M4 - 1.0).abs() < 0.03);
    assert!(s.centroid_y_m.abs() < 1e-12);
    // Against the polygon the mesh differs only by chords on the curved boundary.
    assert!((s.area_m2 / poly.area_m2 - 1.0).abs() < 0.003);
}

/// Writes an SVG picture of a section mesh (for eyeballing).
pub(crate) fn svg(m: &SectionMesh) -> String {
    let sc = 5000.0; // px per m
    let mut out = String::from(
        "<svg xmlns='http://www.w3.org/2000/svg' width='900' height='900' viewBox='-450 -850 900 900'>\n",
    );
    for q in &m.quads {
        let pts: Vec<String> = q
            .iter()
            .map(|&n| format!("{:.2},{:.2}", m.nodes[n][0] * sc, -m.nodes[n][1] * sc))
            .collect();
        out += &format!(
            "<polygon points='{}' fill='#cde' stroke='black' stroke-width='0.4'/>\n",
            pts.join(" ")
        );
    }
    for &n in m.running_surface.iter().chain(&m.foot_underside) {
        out += &format!(
            "<circle cx='{:.2}' cy='{:.2}' r='1.5' fill='red'/>\n",
            m.nodes[n][0] * sc,
            -m.nodes[n][1] * sc
        );
    }
    out + "</svg>\n"
}

/// Picture for eyeballing: `cargo test --lib mesh::section::tests::write_svg -- --ignored`
/// writes /tmp/uic54-section.svg.
#[test]
#[ignore]
fn write_svg() {
    let params = SectionParams {
        foot_node_lines_m: row_lines(),
        ..Default::default()
    };
    let m = SectionMesh::uic54(&params).unwrap();
    std::fs::write("/tmp/uic54-section.svg", svg(&m)).unwrap();
    let mut txt = String::new();
    for q in &m.quads {
        for &n in q {
            txt += &format!("{} {} ", m.nodes[n][0], m.nodes[n][1]);
        }
        txt += "\n";
    }
    std::fs::write("/tmp/uic54-section.txt", txt).unwrap();
}

/// Boundary edges (used by exactly one quad); panics if an edge is used more than twice
/// or twice in the same direction (overlapping or inverted quads).
fn boundary_loop_area(m: &SectionMesh) -> (f64, usize) {
    let mut count: HashMap<(usize, usize), i32> = HashMap::new();
    for q in &m.quads {
        for k in 0..4 {
            *count.entry((q[k], q[(k + 1) % 4])).or_default() += 1;
        }
    }
    let mut next: HashMap<usize, usize> = HashMap::new();
    for (&(a, b), &c) in &count {
        assert_eq!(c, 1, "directed edge ({a},{b}) used {c} times");
        if !count.contains_key(&(b, a)) {
            assert!(
                next.insert(a, b).is_none(),
                "node {a} starts two boundary edges"
            );
        }
    }
    // Walk the loop.
    let start = *next.keys().next().unwrap();
    let (mut a, mut n, mut area) = (start, 0, 0.0);
    loop {
        let b = next[&a];
        let (p, q) = (m.nodes[a], m.nodes[b]);
        area += 0.5 * (p[0] * q[1] - q[0] * p[1]);
        n += 1;
        a = b;
        if a == start {
            break;
        }
    }
    assert_eq!(n, next.len(), "the boundary is not a single loop");
    (area, n)
}

#[test]
fn mesh_is_conforming_convex_and_tiles_the_section() {
    for params in [
        SectionParams::default(),
        SectionParams {
            foot_node_lines_m: row_lines(),
            ..Default::default()
        },
        SectionParams {
            size_m: 0.002,
            running_surface_size_m: 0.001,
            foot_node_lines_m: vec![0.0, 0.001, 0.03, -0.069],
            ..Default::default()
        },
        SectionParams {
            size_m: 0.012,
            running_surface_size_m: 0.006,
            inclination_rad: (1.0f64 / 40.0).atan(),
            ..Default::default()
        },
    ] {
        let m = SectionMesh::uic54(&params).unwrap();
        m.check_quads().unwrap();
        let (amin, amax, ratio) = m.quality();
        eprintln!(
            "h {:.1} mm, {} quads: angles {amin:.1}..{amax:.1} deg, edge ratio <= {ratio:.1}",
            params.size_m * 1e3,
            m.quads.len()
        );
        // The worst angles sit in the cap columns at the gauge corners (head side → R13
        // arc, a smooth boundary where the columns meet a near-vertical surface).
        assert!(amin > 8.0 && amax < 172.0 && ratio < 15.0);
        let quad_sum: f64 = (0..m.quads.len()).map(|q| m.quad_area(q)).sum();
        assert!((0..m.quads.len()).all(|q| m.quad_area(q) > 0.0));
        let (loop_area, _) = boundary_loop_area(&m);
        // A conforming, non-overlapping tiling: the quads add up to the area in the loop.
        assert!(
            (quad_sum / loop_area - 1.0).abs() < 1e-12,
            "{quad_sum} vs {loop_area}"
        );
        // Every boundary node lies on the profile polygon (rotated back).
        let poly = RailProfile::uic54().unwrap().polygon();
        let (c, s) = (params.inclination_rad.cos(), params.inclination_rad.sin());
        for &n in m.running_surface.iter().chain(&m.foot_underside) {
            let [y, z] = m.nodes[n];
            let p = [y * c + z * s, -y * s + z * c];
            let d = (0..poly.len())
                .map(|k| seg_dist(p, poly[k], poly[(k + 1) % poly.len()]))
                .fold(f64::INFINITY, f64::min);
            assert!(d < 1e-9, "boundary node {n} is {d} m off the profile");
        }
    }
}

fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dy, dz) = (b[0] - a[0], b[1] - a[1]);
    let t = (((p[0] - a[0]) * dy + (p[1] - a[1]) * dz) / (dy * dy + dz * dz)).clamp(0.0, 1.0);
    dist(p, [a[0] + t * dy, a[1] + t * dz])
}

#[test]
fn required_foot_lines_and_running_surface_size() {
    let params = SectionParams {
        foot_node_lines_m: row_lines(),
        ..Default::default()
    };
    let m = SectionMesh::uic54(&params).unwrap();
    for &y in &row_lines() {
        for y in [y, -y] {
            assert!(
                m.foot_underside_s_m.iter().any(|s| (s - y).abs() < 1e-12),
                "foot line {y} missing"
            );
        }
    }
    // Foot underside: ordered, from −70 to 70 mm, all at z = 0.
    assert!(m.foot_underside_s_m.windows(2).all(|w| w[1] > w[0]));
    assert!((m.foot_underside_s_m[0] + 0.070).abs() < 1e-12);
    assert!(m.foot_underside.iter().all(|&n| m.nodes[n][1] == 0.0));
    // Running surface ordered by y, from head side to head side, apex a node.
    let rs = &m.running_surface;
    assert!(rs.windows(2).all(|w| m.nodes[w[1]][0] > m.nodes[w[0]][0]));
    assert!(rs.iter().any(|&n| m.nodes[n] == [0.0, 0.159]));
    // Quads touching the running surface within the fine zone: all edges <= the fine size.
    let on_top: std::collections::HashSet<usize> = rs.iter().copied().collect();
    let mut checked = 0;
    let mut worst: f64 = 0.0;
    for q in &m.quads {
        let touching = q.iter().filter(|n| on_top.contains(n)).count();
        let central = q
            .iter()
            .all(|&n| m.nodes[n][0].abs() <= params.running_surface_half_width_m - 0.002);
        if touching >= 2 && central {
            checked += 1;
            for k in 0..4 {
                let e = dist(m.nodes[q[k]], m.nodes[q[(k + 1) % 4]]);
                worst = worst.max(e);
                assert!(
                    e <= params.running_surface_size_m * (1.0 + 1e-9),
                    "edge {e}"
                );
            }
        }
    }
    eprintln!(
        "{checked} running-surface quads, largest edge {:.3} mm",
        worst * 1e3
    );
    assert!(checked >= 14);
}

#[test]
fn refinement_converges_to_the_polygon() {
    // The mesh differs from the polygon by chord cuts on curved edges, O(h²) in area.
    let poly = RailProfile::uic54().unwrap().properties();
    let mut errs = Vec::new();
    for h in [0.008, 0.004, 0.002, 0.001] {
        let m = SectionMesh::uic54(&SectionParams {
            size_m: h,
            running_surface_size_m: h / 2.0,
            ..Default::default()
        })
        .unwrap();
        let s = m.properties();
        let e = [
            (s.area_m2 / poly.area_m2 - 1.0).abs(),
            (s.i_vertical_bending_m4 / poly.i_vertical_bending_m4 - 1.0).abs(),
            (s.i_lateral_bending_m4 / poly.i_lateral_bending_m4 - 1.0).abs(),
            (s.centroid_z_m - poly.centroid_z_m).abs(),
        ];
        eprintln!(
            "h {:.1} mm: {} quads, rel err A {:.2e}, Iv {:.2e}, Il {:.2e}, zc {:.2e} m",
            h * 1e3,
            m.quads.len(),
            e[0],
            e[1],
            e[2],
            e[3]
        );
        errs.push(e);
    }
    for k in 0..4 {
        assert!(
            errs[3][k] < errs[0][k] / 4.0 || errs[3][k] < 1e-6,
            "quantity {k} did not converge: {errs:?}"
        );
    }
    assert!(errs[3][0] < 2e-4 && errs[3][1] < 2e-4 && errs[3][2] < 2e-4);
}

#[test]
fn inclination_rotates_the_properties() {
    let upright = SectionMesh::uic54(&SectionParams::default())
        .unwrap()
        .properties();
    let th = (1.0f64 / 40.0).atan();
    let m = SectionMesh::uic54(&SectionParams {
        inclination_rad: th,
        ..Default::default()
    })
    .unwrap();
    let s = m.properties();
    // Rotation about the foot centre: centroid (0, zc) → (−zc sin θ, zc cos θ); second
    // moments by the tensor transformation of the principal values.
    let (c, sn) = (th.cos(), th.sin());
    assert!((s.area_m2 - upright.area_m2).abs() < 1e-15);
    assert!((s.centroid_y_m + upright.centroid_z_m * sn).abs() < 1e-12);
    assert!((s.centroid_z_m - upright.centroid_z_m * c).abs() < 1e-12);
    let (iv, il) = (upright.i_vertical_bending_m4, upright.i_lateral_bending_m4);
    assert!((s.i_vertical_bending_m4 - (iv * c * c + il * sn * sn)).abs() < 1e-12 * iv);
    assert!((s.i_lateral_bending_m4 - (il * c * c + iv * sn * sn)).abs() < 1e-12 * iv);
    assert!((s.i_product_m4.abs() - (iv - il) * c * sn).abs() < 1e-12 * iv);
    // The head tilts towards −y.
    let top = m.running_surface[m.running_surface.len() / 2];
    assert!(m.nodes[top][0] < -0.003);
}

#[test]
fn locate_finds_points() {
    let m = SectionMesh::uic54(&SectionParams::default()).unwrap();
    for (y, z) in [(0.0, 0.15), (0.05, 0.005), (-0.003, 0.08), (0.03, 0.13)] {
        let (q, nat) = m.locate(y, z).unwrap();
        let p = m.quads[q].map(|n| m.nodes[n]);
        let (yy, zz, _) = bilinear(&p, nat[0], nat[1]);
        assert!((yy - y).abs() < 1e-12 && (zz - z).abs() < 1e-12);
    }
    assert!(m.locate(0.05, 0.1).is_none());
    // The bucket locator agrees with the brute-force search on a grid of points.
    let loc = SectionLocator::new(&m);
    let mut found = 0;
    for a in 0..60 {
        for b in 0..60 {
            let (y, z) = (
                -0.075 + 0.15 * a as f64 / 59.0,
                -0.001 + 0.162 * b as f64 / 59.0,
            );
            let brute = m.locate(y, z);
            let fast = loc.locate(&m, y, z);
            assert_eq!(brute.is_some(), fast.is_some(), "({y}, {z})");
            if let (Some((_, n1)), Some((q2, n2))) = (brute, fast) {
                found += 1;
                // A point on a shared edge may be found in either quad: compare positions.
                let p = m.quads[q2].map(|n| m.nodes[n]);
                let (yy, zz, _) = bilinear(&p, n2[0], n2[1]);
                assert!(
                    (yy - y).abs() < 1e-12 && (zz - z).abs() < 1e-12 && n1[0].abs() <= 1.0 + 1e-9
                );
            }
        }
    }
    assert!(found > 500);
}

#[test]
fn bad_params_are_errors() {
    let bad = |p: SectionParams| SectionMesh::uic54(&p).is_err();
    assert!(bad(SectionParams {
        size_m: 0.0,
        ..Default::default()
    }));
    assert!(bad(SectionParams {
        running_surface_size_m: 0.01,
        ..Default::default()
    }));
    assert!(bad(SectionParams {
        foot_node_lines_m: vec![0.08],
        ..Default::default()
    }));
    assert!(bad(SectionParams {
        inclination_rad: f64::NAN,
        ..Default::default()
    }));
}

/// The shortest element edge (m) among the quads whose nodes all lie below `z_max` (m).
fn shortest_edge_below(m: &SectionMesh, z_max: f64) -> f64 {
    m.quads
        .iter()
        .filter(|q| q.iter().all(|&n| m.nodes[n][1] < z_max))
        .flat_map(|q| (0..4).map(|k| dist(m.nodes[q[k]], m.nodes[q[(k + 1) % 4]])))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn a_foot_line_beyond_a_quarter_element_from_the_web_leaves_no_sliver() {
    // Node lines at the centres of four 35 mm spring rows (±17.5, ±52.5 mm) with 20 mm
    // elements: 17.5 mm lies 9.5 mm from the web face (8 mm), within h/2 but beyond h/4. Snapped
    // to the line, the web's foot boundary left 1.11 mm elements in the foot arm (the explicit
    // step's limit on such a track); unsnapped, the line is a node line of the foot arm and no
    // foot element is much thinner than the gap to the web.
    let lines = vec![0.0175, 0.0525];
    let params = SectionParams {
        size_m: 0.02,
        foot_node_lines_m: lines.clone(),
        ..Default::default()
    };
    let m = SectionMesh::uic54(&params).unwrap();
    for &y in &lines {
        for y in [y, -y] {
            assert!(
                m.foot_underside_s_m.iter().any(|s| (s - y).abs() < 1e-12),
                "foot line {y} missing"
            );
        }
    }
    let shortest = shortest_edge_below(&m, 0.04);
    assert!(
        shortest > 0.004,
        "shortest foot edge {:.2} mm",
        shortest * 1e3
    );
    // a line within h/4 of the web face still takes the web's boundary (no thin element there)
    let near = SectionParams {
        foot_node_lines_m: vec![0.0115],
        ..params
    };
    let m = SectionMesh::uic54(&near).unwrap();
    let shortest = shortest_edge_below(&m, 0.04);
    assert!(
        shortest > 0.003,
        "shortest foot edge {:.2} mm",
        shortest * 1e3
    );
}
