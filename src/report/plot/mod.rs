//! SVG line plots: axes with nice ticks, a legend, shaded and labelled phase spans, and
//! gaps where a value is NaN (never drawn as 0); and grouped bar charts ([`BarChart`])
//! on the same axes and palette.
//!
//! The output is deterministic: coordinates are rounded to 0.1 px and written in a fixed
//! order, so the same plot gives the same bytes. Text is laid out from an estimate of its
//! width (0.6 em per character, which bounds DejaVu Sans and Liberation Sans digits and
//! lower-case letters); tick counts are chosen so that tick labels never touch, and span
//! labels that would overlap are moved to further rows of the label band above the plot.
//!
//! # Example
//!
//! ```
//! use footfall::report::plot::{LinePlot, LineStyle, Series, Span};
//!
//! let mut p = LinePlot::new("normal GRF, right foot", "time (s)", "force (N)");
//! p.series.push(Series::new("model", vec![0.0, 0.1, 0.2], vec![0.0, 700.0, 650.0], LineStyle::Solid));
//! p.series.push(Series::new("measured", vec![0.0, 0.1, 0.2], vec![5.0, f64::NAN, 640.0], LineStyle::Markers));
//! p.shaded.push(Span::new(0.0, 0.1, "1e"));
//! let svg = p.to_svg();
//! assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
//! assert_eq!(svg, p.to_svg()); // deterministic
//! ```

mod bar;
mod line;

pub use bar::{BarChart, BarSeries};

use super::escape_xml;
use std::fmt::Write;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LineStyle {
    /// A continuous line (the usual choice for model results).
    #[default]
    Solid,
    /// A dashed line.
    Dashed,
    /// A dot at every sample, no line (the usual choice for measurements).
    Markers,
}

/// One named curve. Points where `x` or `y` is not finite are not drawn and break the
/// line; an isolated finite point of a line series is drawn as a dot. If `x` and `y`
/// differ in length, the extra values of the longer are ignored.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry (empty: not listed in the legend).
    pub name: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
    /// Drawing style.
    pub style: LineStyle,
    /// Palette index of its colour; `None`: the series' own index.
    pub colour: Option<usize>,
}

impl Series {
    /// A series from its parts.
    pub fn new(name: impl Into<String>, x: Vec<f64>, y: Vec<f64>, style: LineStyle) -> Self {
        Self {
            name: name.into(),
            x,
            y,
            style,
            colour: None,
        }
    }

    /// The same series drawn in palette colour `k` (so that related series share one).
    pub fn coloured(mut self, k: usize) -> Self {
        self.colour = Some(k);
        self
    }
}

/// A shaded interval of the x axis, such as a gait phase, with a label above the plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Span {
    /// Start (x units).
    pub x0: f64,
    /// End (x units).
    pub x1: f64,
    /// Label (may be empty).
    pub label: String,
}

impl Span {
    /// A span from its parts.
    pub fn new(x0: f64, x1: f64, label: impl Into<String>) -> Self {
        Self {
            x0,
            x1,
            label: label.into(),
        }
    }
}

/// A filled band between two curves over the same abscissae, such as the residual
/// between a model and its measurement. Points where any value is not finite break it.
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    /// Legend entry (empty: not listed in the legend).
    pub name: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// One edge.
    pub y0: Vec<f64>,
    /// The other edge.
    pub y1: Vec<f64>,
}

/// A second x axis along the top of the plot, piecewise linear in the first: each
/// segment maps `[x0, x1]` of the plot to `[t0, t1]` of its own scale (for example the
/// trial's clock over a percent-of-cycle axis, where each leg's half shows its own times).
#[derive(Debug, Clone, PartialEq)]
pub struct TopAxis {
    /// Label, with units.
    pub label: String,
    /// Segments `(x0, x1, t0, t1)`.
    pub segments: Vec<(f64, f64, f64, f64)>,
}

/// A line plot rendered to SVG.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    /// Title, drawn above the plot.
    pub title: String,
    /// x-axis label, with units.
    pub x_label: String,
    /// y-axis label, with units.
    pub y_label: String,
    /// Curves, drawn in order; colours follow the Okabe–Ito palette by index.
    pub series: Vec<Series>,
    /// Shaded spans (phases), alternately tinted, labelled above the plot area.
    pub shaded: Vec<Span>,
    /// Width of the whole figure (px, default 640).
    pub width: f64,
    /// Height of the whole figure (px, default 360).
    pub height: f64,
    /// Fixed x range; `None`: the range of the data and spans, exactly (default `None`).
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range; `None`: the data's range with 4 % margins (default `None`).
    pub y_range: Option<(f64, f64)>,
    /// Filled bands, drawn under the curves in a light tint.
    pub bands: Vec<Band>,
    /// A second x axis along the top (default `None`).
    pub top_axis: Option<TopAxis>,
    /// A caution written across the plot area, e.g. "not converged" (default `None`).
    pub note: Option<String>,
}

/// Colour-blind-safe palette (Okabe & Ito 2008), yellow left out for contrast on white.
const PALETTE: [&str; 7] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000",
];
const FONT: &str = "DejaVu Sans, Liberation Sans, Arial, Helvetica, sans-serif";
const TITLE_SIZE: f64 = 14.0;
const LABEL_SIZE: f64 = 12.0;
const TICK_SIZE: f64 = 11.0;
const LEGEND_SIZE: f64 = 11.0;
const SPAN_SIZE: f64 = 10.0;
const SPAN_ROW: f64 = 13.0;
const MAX_SPAN_ROWS: usize = 3;
const LEGEND_ROW: f64 = 17.0;
const LEGEND_SAMPLE: f64 = 24.0;
const MARKER_RADIUS: f64 = 2.5;

/// Estimated width of `s` in px at font size `size`.
fn text_width(s: &str, size: f64) -> f64 {
    s.chars().count() as f64 * size * 0.6
}

/// A coordinate rounded to 0.1 px, never written as `-0.0`.
pub(crate) fn px(v: f64) -> String {
    let r = (v * 10.0).round() / 10.0;
    let r = if r == 0.0 { 0.0 } else { r };
    if r.fract() == 0.0 {
        format!("{r:.0}")
    } else {
        format!("{r:.1}")
    }
}

/// The smallest "nice" step (1, 2, 2.5 or 5 times a power of ten) that is at least `raw`.
pub fn nice_step(raw: f64) -> f64 {
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let e = raw.log10().floor();
    let p = 10f64.powf(e);
    let f = raw / p;
    let m = [1.0, 2.0, 2.5, 5.0, 10.0]
        .into_iter()
        .find(|&m| f <= m * (1.0 + 1e-9))
        .unwrap_or(10.0);
    m * p
}

/// Tick positions inside `[lo, hi]` at a nice step chosen so that there are at most
/// `target` ticks (and at least 2 when the interval is not degenerate). Values are exact
/// multiples of the step rounded to the step's decimals, with `0` as `+0.0`.
///
/// ```
/// use footfall::report::plot::nice_ticks;
/// assert_eq!(nice_ticks(0.0, 1.0, 5), vec![0.0, 0.25, 0.5, 0.75, 1.0]);
/// assert_eq!(nice_ticks(-3.0, 7.0, 6), vec![-2.0, 0.0, 2.0, 4.0, 6.0]);
/// ```
pub fn nice_ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi < lo {
        return Vec::new();
    }
    if hi == lo {
        return vec![lo];
    }
    let step = nice_step((hi - lo) / (target.max(2) - 1) as f64);
    ticks_at(lo, hi, step)
}

fn ticks_at(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    let i0 = (lo / step - 1e-9).ceil() as i64;
    let i1 = (hi / step + 1e-9).floor() as i64;
    // Round away the noise of i·step (1.2000000000000002 → 1.2).
    let k = 10f64.powi(decimals(step) as i32);
    (i0..=i1)
        .map(|i| {
            let v = (i as f64 * step * k).round() / k;
            if v == 0.0 {
                0.0
            } else {
                v
            }
        })
        .collect()
}

/// Number of decimals needed to write multiples of `step` exactly.
fn decimals(step: f64) -> usize {
    (0..=30)
        .find(|&d| {
            let s = step.abs() * 10f64.powi(d as i32);
            s >= 1.0 - 1e-9 && (s - s.round()).abs() < 1e-6 * s
        })
        .unwrap_or(30)
}

/// Tick labels for ticks at multiples of `step`: fixed-point, or a shared power of ten
/// when the largest tick is at least 1e5 or below 1e-3. Negative values use U+2212.
pub fn tick_labels(ticks: &[f64], step: f64) -> Vec<String> {
    let m = ticks.iter().fold(0.0f64, |a, t| a.max(t.abs()));
    let sci = m >= 1e5 || (m > 0.0 && m < 1e-3);
    let e = if sci { m.log10().floor() as i32 } else { 0 };
    let scale = 10f64.powi(e);
    let d = decimals(step / scale);
    ticks
        .iter()
        .map(|&t| {
            if t == 0.0 {
                return "0".to_string();
            }
            let s = format!("{:.*}", d, t / scale);
            let s = s.replacen('-', "\u{2212}", 1);
            if sci {
                format!("{s}e{e}")
            } else {
                s
            }
        })
        .collect()
}

/// One axis after layout: its range and labelled ticks.
struct Axis {
    lo: f64,
    hi: f64,
    ticks: Vec<f64>,
    labels: Vec<String>,
}

impl Axis {
    fn new(lo: f64, hi: f64, step: f64) -> Self {
        let ticks = ticks_at(lo, hi, step);
        let labels = tick_labels(&ticks, step);
        Self {
            lo,
            hi,
            ticks,
            labels,
        }
    }
}

/// Widen a degenerate or empty range.
fn widen(lo: f64, hi: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) || hi < lo {
        (0.0, 1.0)
    } else if hi == lo {
        let d = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
        (lo - d, hi + d)
    } else {
        (lo, hi)
    }
}

/// Clip the segment `a`–`b` to the box (Liang–Barsky); `None` if it misses.
fn clip(
    a: (f64, f64),
    b: (f64, f64),
    bx: (f64, f64, f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    let (x0, x1, y0, y1) = bx;
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - x0),
        (dx, x1 - a.0),
        (-dy, a.1 - y0),
        (dy, y1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then_some((
        (a.0 + t0 * dx, a.1 + t0 * dy),
        (a.0 + t1 * dx, a.1 + t1 * dy),
    ))
}

/// A placed legend entry: series index, x offset within the row, row.
struct LegendItem {
    series: usize,
    x: f64,
    row: usize,
}

/// Left margin (px): gap, the y label's band, the widest y tick label, gap.
fn left_margin(y_axis: &Axis, y_label: &str) -> f64 {
    let tick_w = y_axis
        .labels
        .iter()
        .map(|l| text_width(l, TICK_SIZE))
        .fold(0.0, f64::max);
    let y_label_band = if y_label.is_empty() {
        0.0
    } else {
        LABEL_SIZE + 8.0
    };
    8.0 + y_label_band + tick_w + 8.0
}

/// Legend entries of the non-empty `names` (item `i` for the `i`-th name) in rows that wrap
/// at `width` px, each entry a `sample` px wide swatch and its name; the entries and the
/// number of rows.
fn legend_layout<'a>(
    names: impl Iterator<Item = &'a str>,
    sample: f64,
    width: f64,
) -> (Vec<LegendItem>, usize) {
    let mut legend = Vec::new();
    let (mut lx, mut lrow) = (0.0, 0usize);
    for (i, name) in names.enumerate().filter(|(_, n)| !n.is_empty()) {
        let item_w = sample + 6.0 + text_width(name, LEGEND_SIZE);
        if lx > 0.0 && lx + item_w > width {
            lx = 0.0;
            lrow += 1;
        }
        legend.push(LegendItem {
            series: i,
            x: lx,
            row: lrow,
        });
        lx += item_w + 18.0;
    }
    let rows = if legend.is_empty() { 0 } else { lrow + 1 };
    (legend, rows)
}

/// Height (px) of the title band above the plot.
fn title_band(title: &str) -> f64 {
    if title.is_empty() {
        4.0
    } else {
        TITLE_SIZE + 14.0
    }
}

/// Height (px) of `rows` legend rows below the plot.
fn legend_band(rows: usize) -> f64 {
    if rows == 0 {
        0.0
    } else {
        rows as f64 * LEGEND_ROW + 6.0
    }
}

/// Horizontal grid lines at the y ticks (the zero line darker), `sy` mapping a value to px.
fn y_grid(out: &mut String, y_axis: &Axis, left: f64, pw: f64, sy: impl Fn(f64) -> f64) {
    for &t in &y_axis.ticks {
        writeln!(
            out,
            r##"<line x1="{}" y1="{y}" x2="{}" y2="{y}" stroke="{}" stroke-width="{}"/>"##,
            px(left),
            px(left + pw),
            if t == 0.0 { "#9a9a9a" } else { "#e3e3e3" },
            if t == 0.0 { "1" } else { "0.8" },
            y = px(sy(t))
        )
        .ok();
    }
}

/// The y ticks with their labels left of the frame.
fn y_ticks(out: &mut String, y_axis: &Axis, left: f64, sy: impl Fn(f64) -> f64) {
    for (t, l) in y_axis.ticks.iter().zip(&y_axis.labels) {
        let y = sy(*t);
        writeln!(
            out,
            r##"<line x1="{}" y1="{y}" x2="{}" y2="{y}" stroke="#333333"/><text x="{}" y="{}" font-size="{TICK_SIZE}" text-anchor="end" fill="#333333">{l}</text>"##,
            px(left - 4.0),
            px(left),
            px(left - 6.0),
            px(y + TICK_SIZE * 0.35),
            y = px(y)
        )
        .ok();
    }
}

/// The y label, rotated, centred on the plot's height.
fn y_label(out: &mut String, label: &str, top: f64, ph: f64) {
    if !label.is_empty() {
        let (x, y) = (8.0 + LABEL_SIZE, top + ph / 2.0);
        writeln!(
            out,
            r##"<text x="{x}" y="{y}" font-size="{LABEL_SIZE}" text-anchor="middle" fill="#222222" transform="rotate(-90 {x} {y})">{}</text>"##,
            escape_xml(label),
            x = px(x),
            y = px(y)
        )
        .ok();
    }
}

/// The plot's frame.
fn frame(out: &mut String, left: f64, top: f64, pw: f64, ph: f64) {
    writeln!(
        out,
        r##"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="#333333" stroke-width="1"/>"##,
        px(left),
        px(top),
        px(pw),
        px(ph)
    )
    .ok();
}

/// "no data" in the middle of an empty plot.
fn no_data(out: &mut String, left: f64, top: f64, pw: f64, ph: f64) {
    writeln!(
        out,
        r##"<text x="{}" y="{}" font-size="{LABEL_SIZE}" text-anchor="middle" fill="#888888">no data</text>"##,
        px(left + pw / 2.0),
        px(top + ph / 2.0)
    )
    .ok();
}

/// A placed span label: span index, centre x (px), row.
struct SpanLabel {
    span: usize,
    cx: f64,
    row: usize,
}

/// Opening of a plot's SVG: the `<svg>` element (standalone, or nested at `at` inside a
/// grid), its `<title>`, the white background and the bold title centred at `title_x`.
fn svg_header(out: &mut String, title: &str, w: f64, h: f64, at: Option<(f64, f64)>, title_x: f64) {
    let escaped = escape_xml(title);
    match at {
        None => writeln!(
            out,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" aria-label="{escaped}" font-family="{FONT}">"#,
            w = px(w),
            h = px(h)
        ),
        Some((x, y)) => writeln!(
            out,
            r#"<svg x="{x}" y="{y}" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" aria-label="{escaped}">"#,
            x = px(x),
            y = px(y),
            w = px(w),
            h = px(h)
        ),
    }
    .ok();
    writeln!(out, "<title>{escaped}</title>").ok();
    writeln!(
        out,
        r##"<rect width="{}" height="{}" fill="#ffffff"/>"##,
        px(w),
        px(h)
    )
    .ok();
    if !title.is_empty() {
        writeln!(
            out,
            r##"<text x="{}" y="{}" font-size="{TITLE_SIZE}" font-weight="bold" text-anchor="middle" fill="#222222">{escaped}</text>"##,
            px(title_x),
            px(8.0 + TITLE_SIZE)
        )
        .ok();
    }
}

/// Small multiples: the plots in one SVG, `columns` to a row (at least 1), each in a cell
/// as large as the largest plot, in order left to right, top to bottom.
pub fn grid(plots: &[LinePlot], columns: usize) -> String {
    let columns = columns.max(1).min(plots.len().max(1));
    let cw = plots.iter().map(|p| p.width.max(160.0)).fold(0.0, f64::max);
    let ch = plots
        .iter()
        .map(|p| p.height.max(120.0))
        .fold(0.0, f64::max);
    let rows = plots.len().div_ceil(columns);
    let (w, h) = (cw * columns as f64, ch * rows as f64);
    let label = plots
        .iter()
        .map(|p| p.title.as_str())
        .collect::<Vec<_>>()
        .join("; ");
    let label = escape_xml(&label);
    let mut out = String::new();
    writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" aria-label="{label}" font-family="{FONT}">"#,
        w = px(w),
        h = px(h)
    )
    .ok();
    writeln!(out, "<title>{label}</title>").ok();
    for (i, p) in plots.iter().enumerate() {
        let (r, c) = (i / columns, i % columns);
        p.render(&mut out, Some((c as f64 * cw, r as f64 * ch)));
    }
    out.push_str("</svg>\n");
    out
}
