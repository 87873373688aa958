//! Line plots and heat maps, each written as `stem.svg` and `stem.png`.
//!
//! - [`line_plot`] / [`line_plot_log_y`]: one or more [`Series`] of `(x, y)` points. Non-finite
//!   points (and, on the log axis, `y ≤ 0`) are gaps: the line is broken there, so a `None`
//!   dominant wavelength written as `NaN` simply leaves a hole. Series of at most
//!   `MARKER_LIMIT` points also get a marker at every point (parameter studies).
//! - [`heat_map`]: a value `z(x_i, y_j)` on a rectilinear grid (cells centred on the grid
//!   values, edges half-way between neighbours), linear or logarithmic colour scale (a
//!   perceptually uniform blue–green–yellow map, `viridis`-like), a colour bar, and
//!   [`OverlayLine`]s in data coordinates (e.g. the eigenfrequency lines `λ = v / f_i` of a
//!   frequency-selection map). Cells with no data (non-finite, or `≤ 0` on a log scale) are
//!   light grey.
//!
//! The logarithmic axes are drawn as linear axes of `log10` of the value with tick labels
//! showing the value itself (`1.0e-3`), which keeps one drawing path for both scales.
//!
//! Files are rendered in memory (SVG) or into a temp file (PNG) and renamed into place.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

use super::ReportError;

/// The embedded font used for all PNG text (DejaVu Sans, Bitstream Vera licence).
pub(crate) const FONT_TTF: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");

/// Family name under which [`FONT_TTF`] is registered with plotters.
pub(crate) const FONT_FAMILY: &str = "sans-serif";

/// Series of at most this many points get markers.
pub(crate) const MARKER_LIMIT: usize = 60;

/// Size of a line plot (px) in the PNG and the SVG.
pub(crate) const LINE_PLOT_SIZE: (u32, u32) = (900, 600);

/// Size of a heat map (px) in the PNG and the SVG, the strip of its style legend included.
pub(crate) const HEAT_MAP_SIZE: (u32, u32) = (1000, 680);

/// One named curve of a line plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// Abscissae (plot unit).
    pub x: Vec<f64>,
    /// Ordinates (plot unit), one per abscissa.
    pub y: Vec<f64>,
}

impl Series {
    /// A series from a name and points.
    pub fn new(name: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            name: name.into(),
            x,
            y,
        }
    }
}

/// A polyline drawn over a heat map, in data coordinates (e.g. `λ = v / f_i`).
#[derive(Clone, Debug, PartialEq)]
pub struct OverlayLine {
    /// Label written next to the line and in the legend.
    pub name: String,
    /// Abscissae (plot unit).
    pub x: Vec<f64>,
    /// Ordinates (plot unit).
    pub y: Vec<f64>,
    /// How the line is drawn: one style per family of lines.
    pub style: LineStyle,
}

/// The drawing style of an [`OverlayLine`]. Labels of solid lines are placed first, then
/// those of dotted and dashed lines (a label too close to one already placed is left out).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LineStyle {
    /// White, 2 px: the primary family (e.g. the track's longitudinal-compression modes).
    #[default]
    Solid,
    /// White, 1 px, long dashes: a secondary family (e.g. the wheel's modes).
    Dashed,
    /// Light red, 2 px, short dashes: a third family (e.g. the coupled wheel–track modes).
    Dotted,
}

impl OverlayLine {
    /// A solid horizontal line at `y` from `x0` to `x1`.
    pub fn horizontal(name: impl Into<String>, y: f64, x0: f64, x1: f64) -> Self {
        Self {
            name: name.into(),
            x: vec![x0, x1],
            y: vec![y, y],
            style: LineStyle::Solid,
        }
    }
}

/// Smallest vertical distance (px) between two line labels drawn at the same end of the
/// plot; a label closer than this to one already drawn is left out (its line is still drawn).
const LABEL_MIN_GAP_PX: i32 = 18;

/// Horizontal distance (px) within which two label anchors count as "at the same end" (about
/// the width of a label such as `wheel 1043 Hz`).
const LABEL_SAME_END_PX: i32 = 80;

/// A heat map: `z` is row-major over `x` then `y`: `z[i * y.len() + j]` is the value at
/// `(x[i], y[j])`. `x` and `y` must be strictly ascending.
#[derive(Clone, Debug)]
pub struct HeatMap<'a> {
    /// Plot title.
    pub title: &'a str,
    /// Label of the x axis (with unit).
    pub x_label: &'a str,
    /// Label of the y axis (with unit).
    pub y_label: &'a str,
    /// Label of the colour bar (with unit).
    pub colour_label: &'a str,
    /// Grid abscissae, ascending.
    pub x: &'a [f64],
    /// Grid ordinates, ascending.
    pub y: &'a [f64],
    /// Values, `x.len() * y.len()`, row-major over `x`.
    pub z: &'a [f64],
    /// Lines drawn over the map.
    pub lines: &'a [OverlayLine],
    /// Logarithmic colour scale (values `≤ 0` are shown as "no data").
    pub log_colour: bool,
    /// What each line style stands for, drawn as a legend in a strip beneath the figure
    /// (e.g. `(LineStyle::Dotted, "coupled wheel–track modes")`); empty: no legend.
    pub line_legend: &'a [(LineStyle, &'a str)],
}

/// The two files of one plot.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlotFiles {
    /// `stem.svg`.
    pub svg: PathBuf,
    /// `stem.png`.
    pub png: PathBuf,
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded font is a valid TTF (checked by the tests); ignore the impossible error.
        let _ = plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, FONT_TTF);
    });
}

/// Writes a line plot with a linear y axis to `stem.svg` and `stem.png`.
pub fn line_plot(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<PlotFiles, ReportError> {
    let spec = LineSpec {
        title,
        x_label,
        y_label,
        series,
        log_y: false,
    };
    write_both(stem, LINE_PLOT_SIZE, |root| draw_lines(root, &spec), title)
}

/// Writes a line plot with a logarithmic y axis (e.g. a PSD) to `stem.svg` and `stem.png`.
/// Points with `y ≤ 0` are gaps.
pub fn line_plot_log_y(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<PlotFiles, ReportError> {
    let spec = LineSpec {
        title,
        x_label,
        y_label,
        series,
        log_y: true,
    };
    write_both(stem, LINE_PLOT_SIZE, |root| draw_lines(root, &spec), title)
}

/// Writes a heat map to `stem.svg` and `stem.png`.
pub fn heat_map(stem: &Path, map: &HeatMap<'_>) -> Result<PlotFiles, ReportError> {
    check_heat_map(map)?;
    write_both(
        stem,
        HEAT_MAP_SIZE,
        |root| draw_heat_map(root, map),
        map.title,
    )
}

/// Renders a line plot into an RGB buffer (`w * h * 3` bytes) — for tests of the text
/// rendering and for callers that embed the pixels elsewhere.
pub fn render_line_plot_rgb(
    size: (u32, u32),
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<Vec<u8>, ReportError> {
    register_font();
    let spec = LineSpec {
        title,
        x_label,
        y_label,
        series,
        log_y: false,
    };
    check_series(&spec)?;
    let mut buf = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        draw_lines(&root, &spec)
            .and_then(|_| root.present().map_err(|e| e.to_string()))
            .map_err(|message| ReportError::Draw {
                path: PathBuf::from("<memory>"),
                message,
            })?;
    }
    Ok(buf)
}

struct LineSpec<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    series: &'a [Series],
    log_y: bool,
}

fn with_ext(stem: &Path, ext: &str) -> PathBuf {
    let mut name = stem.file_name().unwrap_or_default().to_os_string();
    name.push(".");
    name.push(ext);
    stem.with_file_name(name)
}

/// Draws with `draw` on an SVG string and on a PNG temp file, then renames both into place.
fn write_both<F>(
    stem: &Path,
    size: (u32, u32),
    draw: F,
    title: &str,
) -> Result<PlotFiles, ReportError>
where
    F: Fn(&dyn AreaRef) -> Result<(), String>,
{
    register_font();
    let svg = with_ext(stem, "svg");
    let png = with_ext(stem, "png");
    if stem.file_name().is_none() {
        return Err(ReportError::Data {
            title: title.into(),
            reason: format!("output stem `{}` has no file name", stem.display()),
        });
    }
    // SVG: in memory, then atomically to disk.
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        draw(&root)
            .and_then(|_| root.present().map_err(|e| e.to_string()))
            .map_err(|message| ReportError::Draw {
                path: svg.clone(),
                message,
            })?;
    }
    crate::io::write_text(&svg, &text).map_err(|source| ReportError::Io {
        path: svg.clone(),
        source,
    })?;
    // PNG: the encoder picks the format from the extension, so the temp name ends in .png.
    if let Some(d) = png.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).map_err(|source| ReportError::Io {
            path: png.clone(),
            source,
        })?;
    }
    let tmp = with_ext(stem, &format!("tmp{}.png", std::process::id()));
    let drawn = (|| {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        draw(&root)?;
        root.present().map_err(|e| e.to_string())
    })();
    if let Err(message) = drawn {
        let _ = std::fs::remove_file(&tmp);
        return Err(ReportError::Draw { path: png, message });
    }
    std::fs::rename(&tmp, &png).map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        ReportError::Io {
            path: png.clone(),
            source,
        }
    })?;
    Ok(PlotFiles { svg, png })
}

/// Object-safe access to the two backends' drawing areas, so each plot is written once.
trait AreaRef {
    fn lines(&self, spec: &LineSpec<'_>) -> Result<(), String>;
    fn heat(&self, map: &HeatMap<'_>) -> Result<(), String>;
}

impl AreaRef for DrawingArea<SVGBackend<'_>, Shift> {
    fn lines(&self, spec: &LineSpec<'_>) -> Result<(), String> {
        lines_on(self, spec)
    }
    fn heat(&self, map: &HeatMap<'_>) -> Result<(), String> {
        heat_on(self, map)
    }
}

impl AreaRef for DrawingArea<BitMapBackend<'_>, Shift> {
    fn lines(&self, spec: &LineSpec<'_>) -> Result<(), String> {
        lines_on(self, spec)
    }
    fn heat(&self, map: &HeatMap<'_>) -> Result<(), String> {
        heat_on(self, map)
    }
}

fn draw_lines(root: &dyn AreaRef, spec: &LineSpec<'_>) -> Result<(), String> {
    root.lines(spec)
}

fn draw_heat_map(root: &dyn AreaRef, map: &HeatMap<'_>) -> Result<(), String> {
    root.heat(map)
}

fn check_series(spec: &LineSpec<'_>) -> Result<(), ReportError> {
    for s in spec.series {
        if s.x.len() != s.y.len() {
            return Err(ReportError::Data {
                title: spec.title.into(),
                reason: format!(
                    "series `{}` has {} x values but {} y values",
                    s.name,
                    s.x.len(),
                    s.y.len()
                ),
            });
        }
    }
    Ok(())
}

fn check_heat_map(map: &HeatMap<'_>) -> Result<(), ReportError> {
    let bad = |reason: String| ReportError::Data {
        title: map.title.into(),
        reason,
    };
    if map.x.is_empty() || map.y.is_empty() {
        return Err(bad("the grid is empty".into()));
    }
    if map.z.len() != map.x.len() * map.y.len() {
        return Err(bad(format!(
            "z has {} values, the grid {} × {}",
            map.z.len(),
            map.x.len(),
            map.y.len()
        )));
    }
    for (axis, v) in [("x", map.x), ("y", map.y)] {
        if v.iter().any(|a| !a.is_finite()) || v.windows(2).any(|w| w[1] <= w[0]) {
            return Err(bad(format!("{axis} must be finite and strictly ascending")));
        }
    }
    for l in map.lines {
        if l.x.len() != l.y.len() {
            return Err(bad(format!(
                "overlay line `{}`: x and y lengths differ",
                l.name
            )));
        }
    }
    Ok(())
}

/// `(min, max)` of the finite values, padded when degenerate; `None` when there is none.
fn finite_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return None;
    }
    if hi - lo <= 1e-12 * hi.abs().max(lo.abs()).max(1e-300) {
        let pad = if hi.abs() > 0.0 { 0.05 * hi.abs() } else { 1.0 };
        return Some((lo - pad, hi + pad));
    }
    Some((lo, hi))
}

/// Ticks per axis that plotters places by default (at most).
const TICKS: usize = 10;

/// Tick labels of a linear axis over `[lo, hi]` with at most `n` ticks: as many decimals (or,
/// for |v| ≥ 1e6 or < 1e-3, significant digits) as the tick spacing needs, so that
/// neighbouring ticks never print the same label.
fn linear_labels(lo: f64, hi: f64, n: usize) -> impl Fn(&f64) -> String {
    let step = ((hi - lo).abs() / n.max(1) as f64).max(1e-300);
    let a = lo.abs().max(hi.abs());
    let sci = a != 0.0 && !(1e-3..1e6).contains(&a);
    let sig = ((a / step).log10().floor() as i64 + 2).clamp(2, 12) as usize;
    let dec = (-step.log10().floor() as i64).clamp(0, 12) as usize;
    move |v: &f64| {
        // A tick at zero computed as a round-off residue (e.g. 8.5e-22 on a 5e-7 step) is 0.
        if v.abs() < 1e-9 * step {
            return "0".into();
        }
        if sci {
            return format!("{:.*e}", sig - 1, v);
        }
        let s = format!("{v:.dec$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.')
        } else {
            s.as_str()
        };
        if s == "-0" {
            "0".into()
        } else {
            s.into()
        }
    }
}

/// Tick labels of a log axis drawn as `log10(value)` over `[lo, hi]` (decades) with at most
/// `n` ticks: the value in scientific notation with as many significant digits as
/// neighbouring ticks need to differ.
fn log_labels(lo: f64, hi: f64, n: usize) -> impl Fn(&f64) -> String {
    let step = ((hi - lo).abs() / n.max(1) as f64).max(1e-12);
    let rel = 10f64.powf(step) - 1.0;
    let sig = ((-rel.log10()).ceil() as i64 + 1).clamp(2, 8) as usize;
    move |v: &f64| format!("{:.*e}", sig - 1, 10f64.powf(*v))
}

fn palette(i: usize) -> RGBColor {
    const P: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(255, 127, 14),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(23, 190, 207),
    ];
    P[i % P.len()]
}

/// Splits a polyline into runs of drawable points.
fn runs(points: impl Iterator<Item = Option<(f64, f64)>>) -> Vec<Vec<(f64, f64)>> {
    let mut out = vec![Vec::new()];
    for p in points {
        match p {
            Some(p) => out.last_mut().expect("non-empty").push(p),
            None => {
                if !out.last().expect("non-empty").is_empty() {
                    out.push(Vec::new());
                }
            }
        }
    }
    out.retain(|r| !r.is_empty());
    out
}

fn lines_on<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    spec: &LineSpec<'_>,
) -> Result<(), String> {
    let es = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(es)?;
    let ty = |y: f64| {
        if spec.log_y {
            if y > 0.0 {
                Some(y.log10())
            } else {
                None
            }
        } else {
            Some(y)
        }
    };
    let point = |x: f64, y: f64| {
        let y = ty(y)?;
        (x.is_finite() && y.is_finite()).then_some((x, y))
    };
    let all = || {
        spec.series
            .iter()
            .flat_map(|s| s.x.iter().zip(&s.y).filter_map(|(&x, &y)| point(x, y)))
    };
    let (x0, x1) = finite_range(all().map(|p| p.0)).unwrap_or((0.0, 1.0));
    let (y0, y1) = finite_range(all().map(|p| p.1)).unwrap_or((0.0, 1.0));
    let ypad = 0.04 * (y1 - y0);
    let mut chart = ChartBuilder::on(root)
        .caption(spec.title, (FONT_FAMILY, 22))
        .margin(15)
        // room for the last x label, centred on the axis's right end
        .margin_right(35)
        .x_label_area_size(50)
        .y_label_area_size(85)
        .build_cartesian_2d(x0..x1, (y0 - ypad)..(y1 + ypad))
        .map_err(es)?;
    let (ylo, yhi) = (y0 - ypad, y1 + ypad);
    let ylab: Box<dyn Fn(&f64) -> String> = if spec.log_y {
        Box::new(log_labels(ylo, yhi, TICKS))
    } else {
        Box::new(linear_labels(ylo, yhi, TICKS))
    };
    let xlab = linear_labels(x0, x1, TICKS);
    chart
        .configure_mesh()
        .x_desc(spec.x_label)
        .y_desc(spec.y_label)
        .label_style((FONT_FAMILY, 14))
        .axis_desc_style((FONT_FAMILY, 16))
        .x_label_formatter(&xlab)
        .y_label_formatter(&*ylab)
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(es)?;
    let mut any_legend = false;
    for (i, s) in spec.series.iter().enumerate() {
        let colour = palette(i);
        let pts = s.x.iter().zip(&s.y).map(|(&x, &y)| point(x, y));
        let mut first = true;
        for run in runs(pts) {
            let ann = chart
                .draw_series(LineSeries::new(run.clone(), colour.stroke_width(2)))
                .map_err(es)?;
            if first && !s.name.is_empty() {
                ann.label(s.name.clone()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                });
                any_legend = true;
                first = false;
            }
            if s.x.len() <= MARKER_LIMIT {
                chart
                    .draw_series(run.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                    .map_err(es)?;
            }
        }
    }
    if any_legend {
        let position = legend_position(root, &chart, spec, &point).map_err(es)?;
        chart
            .configure_series_labels()
            .position(position)
            .label_font((FONT_FAMILY, 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(es)?;
    }
    Ok(())
}

/// Where the legend of a line plot covers the least data: of the legend's eight places around
/// the plot area's edges, the one whose box (sized as plotters sizes it: the labels' text, a
/// 30 px sample, 10 px margins) holds the fewest points of the series and of eight points
/// along each of their segments; the upper right on a tie.
fn legend_position<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    spec: &LineSpec<'_>,
    point: &dyn Fn(f64, f64) -> Option<(f64, f64)>,
) -> Result<SeriesLabelPosition, DrawingAreaErrorKind<DB::ErrorType>> {
    let font: TextStyle = (FONT_FAMILY, 14).into_font().into();
    let (mut tw, mut th) = (0, 0);
    for s in spec.series.iter().filter(|s| !s.name.is_empty()) {
        let (w, h) = root.estimate_text_size(&s.name, &font)?;
        tw = tw.max(w as i32);
        th += (1.25 * h as f64).ceil() as i32;
    }
    let (bw, bh) = (tw + 30 + 20, th + 20);
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    // Pixel points of the data: every point and eight along each segment.
    let mut px = Vec::new();
    for s in spec.series {
        let pts: Vec<Option<(f64, f64)>> =
            s.x.iter().zip(&s.y).map(|(&x, &y)| point(x, y)).collect();
        for w in pts.windows(2) {
            if let (Some(a), Some(b)) = (w[0], w[1]) {
                for k in 0..8 {
                    let t = k as f64 / 8.0;
                    px.push(chart.backend_coord(&(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))));
                }
            }
        }
        if let Some(Some(p)) = pts.last() {
            px.push(chart.backend_coord(p));
        }
    }
    Ok(least_covered(
        &px,
        (xr.start, yr.start, xr.end - xr.start, yr.end - yr.start),
        (bw, bh),
    ))
}

/// Of a legend box `(bw, bh)` (px) at its eight places in the plot area `(x, y, w, h)` (px, as
/// plotters places it, 5 px from the edges), the place covering the fewest of the pixel
/// points `px`; the upper right on a tie.
pub(crate) fn least_covered(
    px: &[(i32, i32)],
    (ax, ay, aw, ah): (i32, i32, i32, i32),
    (bw, bh): (i32, i32),
) -> SeriesLabelPosition {
    use SeriesLabelPosition::{
        LowerLeft, LowerMiddle, LowerRight, MiddleLeft, MiddleRight, UpperLeft, UpperMiddle,
        UpperRight,
    };
    let place = |p: &SeriesLabelPosition| -> (i32, i32) {
        let x = match p {
            UpperLeft | MiddleLeft | LowerLeft => 5,
            UpperMiddle | LowerMiddle => (aw - bw) / 2,
            _ => aw - bw - 5,
        };
        let y = match p {
            UpperLeft | UpperMiddle | UpperRight => 5,
            MiddleLeft | MiddleRight => (ah - bh) / 2,
            _ => ah - bh - 5,
        };
        (ax + x, ay + y)
    };
    let covered = |p: &SeriesLabelPosition| {
        let (x0, y0) = place(p);
        px.iter()
            .filter(|&&(x, y)| x >= x0 && x <= x0 + bw && y >= y0 && y <= y0 + bh)
            .count()
    };
    let candidates = [
        UpperRight,
        UpperLeft,
        LowerRight,
        LowerLeft,
        MiddleRight,
        MiddleLeft,
        UpperMiddle,
        LowerMiddle,
    ];
    let mut best = (UpperRight, usize::MAX);
    for p in candidates {
        let c = covered(&p);
        if c < best.1 {
            best = (p, c);
        }
    }
    best.0
}

mod heat;

#[cfg(test)]
use heat::edges;
use heat::heat_on;

#[cfg(test)]
mod tests;
