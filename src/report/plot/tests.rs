use super::heat::{colour_map, column_bounds, MIN_COLUMNS};
use super::{
    edges, heat_map, least_covered, line_plot, line_plot_log_y, linear_labels, log_labels,
    render_line_plot_rgb, FontStyle, HeatMap, LineStyle, OverlayLine, PathBuf, RGBColor, Series,
    FONT_TTF, HEAT_MAP_SIZE, LINE_PLOT_SIZE, TICKS,
};

/// The ticks plotters would draw: multiples of a 1-2-5 step, at most `n` over the range.
fn ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let raw = (hi - lo) / n as f64;
    let e = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * e)
        .find(|&s| s >= raw)
        .unwrap();
    let k0 = (lo / step).ceil() as i64;
    let k1 = (hi / step).floor() as i64;
    (k0..=k1).map(|k| k as f64 * step).collect()
}

#[test]
fn neighbouring_tick_labels_differ() {
    // A normal force of 1e5 N varying by 2 %, a narrow log range, a wide one, a tiny span.
    for (lo, hi, log) in [
        (98_960.0, 101_060.0, false),
        (-3.02, -2.97, true),
        (-15.0, -4.0, true),
        (4.3, 5.3, false),
        (1.0e-4, 1.3e-4, false),
        (2.0e6, 2.2e6, false),
    ] {
        let f: Box<dyn Fn(&f64) -> String> = if log {
            Box::new(log_labels(lo, hi, TICKS))
        } else {
            Box::new(linear_labels(lo, hi, TICKS))
        };
        let t = ticks(lo, hi, TICKS);
        assert!(t.len() >= 2, "{lo}..{hi}");
        let labels: Vec<String> = t.iter().map(f).collect();
        for w in labels.windows(2) {
            assert_ne!(w[0], w[1], "{lo}..{hi}: {labels:?}");
        }
    }
    assert_eq!(
        linear_labels(98_960.0, 101_060.0, TICKS)(&99_200.0),
        "99200"
    );
    // A zero tick left as a round-off residue on a scientific axis prints as 0.
    assert_eq!(linear_labels(-4.5e-6, 0.0, TICKS)(&8.5e-22), "0");
    assert_ne!(linear_labels(-4.5e-6, 0.0, TICKS)(&-5.0e-7), "0");
}
fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("corrugation-plot-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Width and height from the PNG IHDR chunk (bytes 16..24, big endian).
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    (be(&bytes[16..20]), be(&bytes[20..24]))
}

#[test]
fn embedded_font_parses() {
    assert!(ab_glyph_check(FONT_TTF));
}

fn ab_glyph_check(bytes: &'static [u8]) -> bool {
    plotters::style::register_font("font-check", FontStyle::Normal, bytes).is_ok()
}

#[test]
fn line_plot_writes_svg_and_png_of_the_stated_size() {
    let d = tmpdir("line");
    let x: Vec<f64> = (0..200).map(|i| i as f64 * 0.01).collect();
    let y: Vec<f64> = x.iter().map(|x| (6.0 * x).sin()).collect();
    let mut y2 = y.iter().map(|v| v * 0.5).collect::<Vec<_>>();
    y2[50] = f64::NAN; // a gap
    let files = line_plot(
        &d.join("sine"),
        "Sine",
        "x (m)",
        "y (-)",
        &[Series::new("sin", x.clone(), y), Series::new("half", x, y2)],
    )
    .unwrap();
    let svg = std::fs::read_to_string(&files.svg).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("Sine") && svg.contains("x (m)"));
    let png = std::fs::read(&files.png).unwrap();
    assert_eq!(png_size(&png), LINE_PLOT_SIZE);
    assert!(png.len() > 10_000, "PNG has content: {} bytes", png.len());
    let names: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert_eq!(names.len(), 2, "no temp file left: {names:?}");
    std::fs::remove_dir_all(d).ok();
}

#[test]
fn log_plot_skips_non_positive_values() {
    let d = tmpdir("log");
    let x: Vec<f64> = (1..50).map(|i| i as f64).collect();
    let y: Vec<f64> = x
        .iter()
        .map(|x| if *x < 5.0 { 0.0 } else { 1e-6 * x * x })
        .collect();
    let f = line_plot_log_y(
        &d.join("psd"),
        "PSD",
        "λ (mm)",
        "PSD",
        &[Series::new("a", x, y)],
    )
    .unwrap();
    assert!(std::fs::read_to_string(&f.svg).unwrap().contains("1.0e-"));
    std::fs::remove_dir_all(d).ok();
}

/// The PNG text is really drawn with the embedded font: the title band of a plot with a
/// title has dark pixels, the same band without the title has none.
#[test]
fn png_text_is_rendered_with_the_embedded_font() {
    let size = (400, 300);
    let s = [Series::new("", vec![0.0, 1.0], vec![0.0, 1.0])];
    let with = render_line_plot_rgb(size, "TITLE TEXT", "x", "y", &s).unwrap();
    let without = render_line_plot_rgb(size, "", "x", "y", &s).unwrap();
    let dark_in_title_band = |buf: &[u8]| {
        (0..30 * size.0 as usize)
            .filter(|&p| buf[3 * p] < 128 && buf[3 * p + 1] < 128 && buf[3 * p + 2] < 128)
            .count()
    };
    assert!(
        dark_in_title_band(&with) > 50,
        "{}",
        dark_in_title_band(&with)
    );
    assert_eq!(dark_in_title_band(&without), 0);
}

#[test]
fn heat_map_writes_both_files_and_checks_its_input() {
    let d = tmpdir("heat");
    let x: Vec<f64> = (0..20).map(|i| 50.0 + 5.0 * i as f64).collect();
    let y: Vec<f64> = (0..30).map(|j| 20.0 + 2.0 * j as f64).collect();
    let z: Vec<f64> = x
        .iter()
        .flat_map(|&a| {
            y.iter()
                .map(move |&b| (-(b - a / 3.0).powi(2) / 20.0).exp())
        })
        .collect();
    let lines = [
        OverlayLine::horizontal("f1", 40.0, 50.0, 145.0),
        OverlayLine {
            name: "curve".into(),
            x: x.clone(),
            y: x.iter().map(|a| a / 2.0).collect(),
            style: LineStyle::Dashed,
        },
    ];
    let mut map = HeatMap {
        title: "map",
        x_label: "v (km/h)",
        y_label: "λ (mm)",
        colour_label: "PSD",
        x: &x,
        y: &y,
        z: &z,
        lines: &lines,
        log_colour: true,
        line_legend: &[],
    };
    let f = heat_map(&d.join("map"), &map).unwrap();
    assert_eq!(png_size(&std::fs::read(&f.png).unwrap()), HEAT_MAP_SIZE);
    assert!(std::fs::read_to_string(&f.svg).unwrap().contains("curve"));
    let short = &z[..10];
    map.z = short;
    let e = heat_map(&d.join("bad"), &map).unwrap_err().to_string();
    assert!(e.contains("z has 10 values"), "{e}");
    assert!(!d.join("bad.png").exists());
    std::fs::remove_dir_all(d).ok();
}

#[test]
fn crowded_line_labels_are_thinned_and_dashed_lines_are_broken() {
    // Three horizontal lines: a solid one and a dashed one 0.5 units apart (about 4 px on
    // the 58-unit axis: their labels would overlap) and a dashed one far away.
    let d = tmpdir("heat_labels");
    let x: Vec<f64> = (0..20).map(|i| 50.0 + 5.0 * i as f64).collect();
    let y: Vec<f64> = (0..30).map(|j| 20.0 + 2.0 * j as f64).collect();
    let z = vec![1.0; x.len() * y.len()];
    let mut near = OverlayLine::horizontal("wheel_near", 40.5, 50.0, 145.0);
    near.style = LineStyle::Dashed;
    let mut far = OverlayLine::horizontal("wheel_far", 70.0, 50.0, 145.0);
    far.style = LineStyle::Dashed;
    // The dashed line comes first in the list: the solid line's label must still win.
    let lines = [
        near,
        OverlayLine::horizontal("LC_line", 40.0, 50.0, 145.0),
        far,
    ];
    let map = HeatMap {
        title: "labels",
        x_label: "v (km/h)",
        y_label: "f (Hz)",
        colour_label: "PSD",
        x: &x,
        y: &y,
        z: &z,
        lines: &lines,
        log_colour: false,
        line_legend: &[],
    };
    let f = heat_map(&d.join("map"), &map).unwrap();
    let svg = std::fs::read_to_string(&f.svg).unwrap();
    assert!(svg.contains("LC_line"));
    assert!(svg.contains("wheel_far"));
    assert!(!svg.contains("wheel_near"), "crowded label not left out");
    // A solid horizontal line is one polyline; a dashed one is many short ones (white
    // stroke, 1 px).
    let dashes = svg
        .split("<polyline")
        .skip(1)
        .filter(|rest| {
            let tag = &rest[..rest.find("/>").unwrap_or(rest.len())];
            tag.contains("#FFFFFF") && tag.contains("stroke-width=\"1\"")
        })
        .count();
    assert!(dashes >= 2 * 10, "dashed lines drawn as {dashes} segments");
    std::fs::remove_dir_all(d).ok();
}

#[test]
fn colour_map_ends_and_edges() {
    assert_eq!(colour_map(0.0), RGBColor(68, 1, 84));
    assert_eq!(colour_map(1.0), RGBColor(253, 231, 37));
    assert_eq!(colour_map(f64::NAN), RGBColor(68, 1, 84));
    assert_eq!(edges(&[1.0, 2.0, 4.0]), vec![0.5, 1.5, 3.0, 5.0]);
}

/// A few abscissae far apart are narrow columns (at most 1/`MIN_COLUMNS` of the axis wide), a
/// dense grid keeps cells that touch half-way between neighbours.
#[test]
fn sparse_columns_are_narrow_and_dense_ones_touch() {
    let sparse = column_bounds(&[100.0, 140.0]);
    let span = sparse[1][1] - sparse[0][0];
    for (c, x) in sparse.iter().zip([100.0, 140.0]) {
        assert!(
            (c[1] - c[0] - 2.0 * span / (2.0 * MIN_COLUMNS)).abs() < 1e-9,
            "{c:?}"
        );
        assert!((0.5 * (c[0] + c[1]) - x).abs() < 1e-12);
    }
    let dense: Vec<f64> = (0..165).map(|i| 54.8 + i as f64).collect();
    let c = column_bounds(&dense);
    for w in c.windows(2) {
        assert!((w[0][1] - w[1][0]).abs() < 1e-9, "cells touch");
    }
    assert!((c[0][0] - 54.3).abs() < 1e-9 && (c[164][1] - 219.3).abs() < 1e-9);
    assert!(column_bounds(&[]).is_empty());
    let one = column_bounds(&[140.0]);
    assert!(one[0][0] < 140.0 && one[0][1] > 140.0);
}

/// The legend names each line style the map uses, and only those.
#[test]
fn the_line_legend_names_the_styles_in_use() {
    let d = tmpdir("heat_legend");
    let x = [100.0, 140.0];
    let y: Vec<f64> = (0..10).map(|j| 20.0 + 5.0 * j as f64).collect();
    let z = vec![1.0; x.len() * y.len()];
    let mut dotted = OverlayLine::horizontal("coupled 30", 30.0, 100.0, 140.0);
    dotted.style = LineStyle::Dotted;
    let lines = [OverlayLine::horizontal("LC 40", 40.0, 100.0, 140.0), dotted];
    let map = HeatMap {
        title: "legend",
        x_label: "v (km/h)",
        y_label: "f (Hz)",
        colour_label: "PSD",
        x: &x,
        y: &y,
        z: &z,
        lines: &lines,
        log_colour: false,
        line_legend: &[
            (LineStyle::Solid, "solid_meaning"),
            (LineStyle::Dashed, "dashed_meaning"),
            (LineStyle::Dotted, "dotted_meaning"),
        ],
    };
    let f = heat_map(&d.join("map"), &map).unwrap();
    let svg = std::fs::read_to_string(&f.svg).unwrap();
    assert!(svg.contains("solid_meaning") && svg.contains("dotted_meaning"));
    assert!(
        !svg.contains("dashed_meaning"),
        "a style no line uses is left out"
    );
    // The legend stands in the strip beneath the figure, outside the plot area.
    for name in ["solid_meaning", "dotted_meaning"] {
        let y = svg_text_y(&svg, name).unwrap_or_else(|| panic!("no y for {name}"));
        assert!(
            y >= (HEAT_MAP_SIZE.1 - super::heat::LEGEND_STRIP_PX) as f64,
            "{name} at y = {y} px, inside the plot area"
        );
    }
    std::fs::remove_dir_all(d).ok();
}

/// The `y` attribute (px) of the SVG text element whose content is `text`.
fn svg_text_y(svg: &str, text: &str) -> Option<f64> {
    let end = svg.find(text)?;
    let start = svg[..end].rfind("<text")?;
    let tag = &svg[start..end];
    let at = tag.find(" y=\"")? + 4;
    tag[at..].split('"').next()?.parse().ok()
}

/// The legend goes where the data is not: a rising diagonal leaves the upper left free; data
/// everywhere but the lower right sends it there; no data keeps the upper right.
#[test]
fn the_legend_avoids_the_data() {
    use plotters::chart::SeriesLabelPosition as P;
    let area = (100, 50, 800, 500);
    let b = (200, 80);
    let diagonal: Vec<(i32, i32)> = (0..=100).map(|k| (100 + 8 * k, 550 - 5 * k)).collect();
    assert!(matches!(least_covered(&diagonal, area, b), P::UpperLeft));
    let mut most: Vec<(i32, i32)> = Vec::new();
    for x in (100..900).step_by(10) {
        for y in (50..550).step_by(10) {
            if !(x > 680 && y > 450) {
                most.push((x, y));
            }
        }
    }
    assert!(matches!(least_covered(&most, area, b), P::LowerRight));
    assert!(matches!(least_covered(&[], area, b), P::UpperRight));
}
