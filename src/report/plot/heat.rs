//! The heat maps of [`super::heat_map`]: cells on a rectilinear grid (columns narrowed where
//! the abscissae are sparse), a logarithmic or linear colour scale with its bar, overlay lines
//! labelled at their right ends and a legend of their styles.

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{
    finite_range, linear_labels, log_labels, runs, HeatMap, LineStyle, FONT_FAMILY,
    LABEL_MIN_GAP_PX, LABEL_SAME_END_PX, TICKS,
};

/// A viridis-like colour map: `t` in `[0, 1]`.
pub(crate) fn colour_map(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * (STOPS.len() - 1) as f64;
    let i = (s.floor() as usize).min(STOPS.len() - 2);
    let f = s - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |u: f64, v: f64| (u + (v - u) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Decades shown below the maximum on a log colour scale.
pub(crate) const LOG_DECADES: f64 = 6.0;

/// A heat map's column (one abscissa) is at most the axis span over this wide, so that a few
/// speeds far apart are drawn as narrow columns with "no data" between them, not as wide
/// blocks claiming the speeds between (a dense grid's cells, narrower, touch as before).
pub(crate) const MIN_COLUMNS: f64 = 40.0;

/// The x-interval `[lo, hi]` of each column of the abscissae `v` (ascending): half-way to its
/// neighbours (half a spacing outside at the ends), narrowed to at most `s / (2 MIN_COLUMNS)`
/// either side of the value, `s` the span of the axis those bounds give; none for no
/// abscissae.
pub(crate) fn column_bounds(v: &[f64]) -> Vec<[f64; 2]> {
    if v.is_empty() {
        return Vec::new();
    }
    let e = edges(v);
    let span = v[v.len() - 1] - v[0];
    // The half-width cap h satisfies h = (span + 2h) / (2 MIN_COLUMNS).
    let cap = if span > 0.0 {
        span / (2.0 * MIN_COLUMNS - 2.0)
    } else {
        f64::INFINITY
    };
    v.iter()
        .enumerate()
        .map(|(i, &x)| [e[i].max(x - cap), e[i + 1].min(x + cap)])
        .collect()
}

/// Cell edges of a rectilinear grid: half-way between neighbours, half a spacing outside.
pub(super) fn edges(v: &[f64]) -> Vec<f64> {
    let n = v.len();
    if n == 1 {
        let h = if v[0] != 0.0 { 0.05 * v[0].abs() } else { 0.5 };
        return vec![v[0] - h, v[0] + h];
    }
    let mut e = Vec::with_capacity(n + 1);
    e.push(v[0] - 0.5 * (v[1] - v[0]));
    for w in v.windows(2) {
        e.push(0.5 * (w[0] + w[1]));
    }
    e.push(v[n - 1] + 0.5 * (v[n - 1] - v[n - 2]));
    e
}

/// Draws `map` on `root`: the cells and axes, the overlay lines with their labels, and the
/// colour bar on the right.
pub(super) fn heat_on<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    map: &HeatMap<'_>,
) -> Result<(), String> {
    let es = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(es)?;
    let (w, h) = root.dim_in_pixel();
    let rows = legend_rows(map);
    // The style legend in a strip beneath the whole figure, so that it covers no data.
    let (upper, strip) = if rows.is_empty() {
        (root.clone(), None)
    } else {
        let (u, s) = root.split_vertically(h.saturating_sub(LEGEND_STRIP_PX));
        (u, Some(s))
    };
    let (main, bar) = upper.split_horizontally(w.saturating_sub(130));
    let (mut c0, c1) =
        finite_range(map.z.iter().filter_map(|&z| colour_coordinate(map, z))).unwrap_or((0.0, 1.0));
    if map.log_colour {
        c0 = c0.max(c1 - LOG_DECADES);
    }
    let (xc, ye) = (column_bounds(map.x), edges(map.y));
    let xe = [xc[0][0], xc[xc.len() - 1][1]];
    let mut chart = heat_cells(&main, map, (&xc, &ye), (c0, c1))?;
    overlay_lines(&main, &mut chart, map, (&xe, &ye))?;
    if let Some(strip) = strip {
        line_legend(&strip, &rows)?;
    }
    colour_bar(&bar, map, (c0, c1))
}

/// Height (px) of the strip beneath a heat map that holds the legend of its line styles.
pub(crate) const LEGEND_STRIP_PX: u32 = 30;

/// The rows of the style legend: each style of `map.line_legend` that a line of the map uses.
fn legend_rows<'m>(map: &'m HeatMap<'_>) -> Vec<&'m (LineStyle, &'m str)> {
    map.line_legend
        .iter()
        .filter(|(st, _)| map.lines.iter().any(|l| l.style == *st))
        .collect()
}

/// The chart of a heat map's cells and lines (linear axes in data coordinates).
type HeatChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Where `z` lies on the colour scale of `map`: `log10 z` on a logarithmic scale, `z`
/// itself on a linear one; `None` for no data.
fn colour_coordinate(map: &HeatMap<'_>, z: f64) -> Option<f64> {
    if map.log_colour {
        (z > 0.0 && z.is_finite()).then(|| z.log10())
    } else {
        z.is_finite().then_some(z)
    }
}

/// The map's chart on `main` with the cells of the columns `xc` (x-intervals) between the
/// y-edges `ye`, coloured over the colour range `(c0, c1)` on a "no data" ground, and the axes.
fn heat_cells<'a, DB: DrawingBackend>(
    main: &'a DrawingArea<DB, Shift>,
    map: &HeatMap<'_>,
    (xc, ye): (&[[f64; 2]], &[f64]),
    (c0, c1): (f64, f64),
) -> Result<HeatChart<'a, DB>, String> {
    let es = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let (xa, xb) = (xc[0][0], xc[xc.len() - 1][1]);
    let (ya, yb) = (ye[0], ye[ye.len() - 1]);
    let mut chart = ChartBuilder::on(main)
        .caption(map.title, (FONT_FAMILY, 22))
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(xa..xb, ya..yb)
        .map_err(es)?;
    let ny = map.y.len();
    let nodata = RGBColor(225, 225, 225);
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(xa, ya), (xb, yb)],
            nodata.filled(),
        )))
        .map_err(es)?;
    chart
        .draw_series((0..map.x.len()).flat_map(|i| {
            (0..ny).map(move |j| {
                let colour = match colour_coordinate(map, map.z[i * ny + j]) {
                    Some(c) => colour_map((c - c0) / (c1 - c0)),
                    None => nodata,
                };
                Rectangle::new([(xc[i][0], ye[j]), (xc[i][1], ye[j + 1])], colour.filled())
            })
        }))
        .map_err(es)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(map.x_label)
        .y_desc(map.y_label)
        .label_style((FONT_FAMILY, 14))
        .axis_desc_style((FONT_FAMILY, 16))
        .x_label_formatter(&linear_labels(xa, xb, TICKS))
        .y_label_formatter(&linear_labels(ya, yb, TICKS))
        .draw()
        .map_err(es)?;
    Ok(chart)
}

/// The legend of the line styles `rows` on `strip` (the strip beneath the map): one entry
/// per style, a short stroke in the style and its meaning, side by side on a dark box like the
/// line labels, starting under the plot area's left edge.
fn line_legend<DB: DrawingBackend>(
    strip: &DrawingArea<DB, Shift>,
    rows: &[&(LineStyle, &str)],
) -> Result<(), String> {
    let es = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let font = (FONT_FAMILY, 13).into_font().color(&WHITE);
    let widths: Vec<i32> = rows
        .iter()
        .map(|(_, t)| strip.estimate_text_size(t, &font).map(|(w, _)| w as i32))
        .collect::<Result<_, _>>()
        .map_err(es)?;
    let (stroke_w, pad, gap) = (30, 6, 18);
    let box_w: i32 = widths.iter().map(|w| stroke_w + w + 2 * pad).sum::<i32>()
        + gap * (rows.len() as i32 - 1)
        + 2 * pad;
    // Under the plot area: clear of the margin (15 px) and the y labels (70 px).
    let (x0, y0) = (15 + 70, 4);
    let y1 = LEGEND_STRIP_PX as i32 - 4;
    strip
        .draw(&Rectangle::new(
            [(x0, y0), (x0 + box_w, y1)],
            BLACK.mix(0.6).filled(),
        ))
        .map_err(es)?;
    let y = (y0 + y1) / 2;
    let mut x = x0 + pad;
    for ((st, text), w) in rows.iter().zip(&widths) {
        let (a, b) = ((x, y), (x + stroke_w, y));
        match st {
            LineStyle::Solid => strip.draw(&PathElement::new(vec![a, b], WHITE.stroke_width(2))),
            LineStyle::Dashed => strip.draw(&DashedPathElement::new(
                vec![a, b],
                6,
                5,
                WHITE.mix(0.85).stroke_width(1),
            )),
            LineStyle::Dotted => strip.draw(&DashedPathElement::new(
                vec![a, b],
                3,
                4,
                RGBColor(255, 120, 120).stroke_width(2),
            )),
        }
        .map_err(es)?;
        strip
            .draw(&Text::new(
                text.to_string(),
                (x + stroke_w + pad, y),
                font.clone().pos(Pos::new(HPos::Left, VPos::Center)),
            ))
            .map_err(es)?;
        x += stroke_w + w + 2 * pad + gap;
    }
    Ok(())
}

/// The map's overlay lines on `chart` (solid, then dotted, then dashed; clipped to the
/// edges `(xe, ye)`), each labelled at its last point unless a label already stands there,
/// the labels drawn last on dark boxes so that no line crosses them.
fn overlay_lines<DB: DrawingBackend>(
    main: &DrawingArea<DB, Shift>,
    chart: &mut HeatChart<'_, DB>,
    map: &HeatMap<'_>,
    (xe, ye): (&[f64], &[f64]),
) -> Result<(), String> {
    let es = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let (xa, xb, ya, yb) = (xe[0], xe[xe.len() - 1], ye[0], ye[ye.len() - 1]);
    let inside = |x: f64, y: f64| {
        x.is_finite() && y.is_finite() && (xa..=xb).contains(&x) && (ya..=yb).contains(&y)
    };
    // Pixel anchors of the labels drawn so far (solid lines first: their labels win).
    let mut labels: Vec<(i32, i32)> = Vec::new();
    let mut pending: Vec<(String, i32, i32)> = Vec::new();
    let ordered = [LineStyle::Solid, LineStyle::Dotted, LineStyle::Dashed]
        .into_iter()
        .flat_map(|st| map.lines.iter().filter(move |l| l.style == st));
    for l in ordered {
        let pts =
            l.x.iter()
                .zip(&l.y)
                .map(|(&x, &y)| inside(x, y).then_some((x, y)));
        let segs = runs(pts);
        for seg in &segs {
            match l.style {
                LineStyle::Dashed => chart
                    .draw_series(DashedLineSeries::new(
                        seg.clone(),
                        6,
                        5,
                        WHITE.mix(0.85).stroke_width(1),
                    ))
                    .map(|_| ()),
                LineStyle::Dotted => chart
                    .draw_series(DashedLineSeries::new(
                        seg.clone(),
                        3,
                        4,
                        RGBColor(255, 120, 120).stroke_width(2),
                    ))
                    .map(|_| ()),
                LineStyle::Solid => chart
                    .draw_series(LineSeries::new(seg.clone(), WHITE.stroke_width(2)))
                    .map(|_| ()),
            }
            .map_err(es)?;
        }
        if let Some(&(x, y)) = segs.last().and_then(|s| s.last()) {
            let (px, py) = chart.backend_coord(&(x, y));
            if labels.iter().any(|&(qx, qy)| {
                (qx - px).abs() < LABEL_SAME_END_PX && (qy - py).abs() < LABEL_MIN_GAP_PX
            }) {
                continue;
            }
            labels.push((px, py));
            pending.push((l.name.clone(), px, py));
        }
    }
    // Labels after all lines, each on a dark box, so that no later line crosses a label.
    for (name, px, py) in pending {
        let font = (FONT_FAMILY, 13)
            .into_font()
            .color(&WHITE)
            .pos(Pos::new(HPos::Right, VPos::Bottom));
        let (tw, th) = main.estimate_text_size(&name, &font).map_err(es)?;
        let (tw, th) = (tw as i32, th as i32);
        main.draw(&Rectangle::new(
            [(px - tw - 3, py - th - 2), (px + 1, py + 1)],
            BLACK.mix(0.6).filled(),
        ))
        .map_err(es)?;
        main.draw(&Text::new(name, (px, py), font)).map_err(es)?;
    }
    Ok(())
}

/// The colour bar over the colour range `(c0, c1)` on `bar`.
fn colour_bar<DB: DrawingBackend>(
    bar: &DrawingArea<DB, Shift>,
    map: &HeatMap<'_>,
    (c0, c1): (f64, f64),
) -> Result<(), String> {
    let es = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let mut cb = ChartBuilder::on(bar)
        .margin_top(50)
        .margin_bottom(65)
        .margin_right(10)
        .y_label_area_size(75)
        .build_cartesian_2d(0.0..1.0, c0..c1)
        .map_err(es)?;
    let steps = 100;
    cb.draw_series((0..steps).map(|k| {
        let a = c0 + (c1 - c0) * k as f64 / steps as f64;
        let b = c0 + (c1 - c0) * (k + 1) as f64 / steps as f64;
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            colour_map((k as f64 + 0.5) / steps as f64).filled(),
        )
    }))
    .map_err(es)?;
    let clab: Box<dyn Fn(&f64) -> String> = if map.log_colour {
        Box::new(log_labels(c0, c1, 6))
    } else {
        Box::new(linear_labels(c0, c1, 6))
    };
    cb.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(map.colour_label)
        .label_style((FONT_FAMILY, 12))
        .axis_desc_style((FONT_FAMILY, 13))
        .y_label_formatter(&*clab)
        .y_labels(6)
        .draw()
        .map_err(es)?;
    Ok(())
}
