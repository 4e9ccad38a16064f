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

/// A placed span label: span index, centre x (px), row.
struct SpanLabel {
    span: usize,
    cx: f64,
    row: usize,
}

impl LinePlot {
    /// An empty 640 × 360 plot.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            shaded: Vec::new(),
            width: 640.0,
            height: 360.0,
            x_range: None,
            y_range: None,
            bands: Vec::new(),
            top_axis: None,
            note: None,
        }
    }

    /// The plot as a standalone SVG document (`<svg xmlns=…>…</svg>`, newline-terminated).
    pub fn to_svg(&self) -> String {
        let mut out = String::new();
        self.render(&mut out, None);
        out
    }

    /// Finite points of a series.
    fn points(s: &Series) -> impl Iterator<Item = (f64, f64)> + '_ {
        s.x.iter()
            .zip(&s.y)
            .map(|(&x, &y)| (x, y))
            .filter(|(x, y)| x.is_finite() && y.is_finite())
    }

    /// Data extents (x from data and spans, y from data).
    fn extents(&self) -> ((f64, f64), (f64, f64)) {
        let mut xr = (f64::INFINITY, f64::NEG_INFINITY);
        let mut yr = (f64::INFINITY, f64::NEG_INFINITY);
        for s in &self.series {
            for (x, y) in Self::points(s) {
                xr = (xr.0.min(x), xr.1.max(x));
                yr = (yr.0.min(y), yr.1.max(y));
            }
        }
        for b in &self.bands {
            for ((&x, &a), &c) in b.x.iter().zip(&b.y0).zip(&b.y1) {
                if x.is_finite() && a.is_finite() && c.is_finite() {
                    xr = (xr.0.min(x), xr.1.max(x));
                    yr = (yr.0.min(a.min(c)), yr.1.max(a.max(c)));
                }
            }
        }
        for sp in &self.shaded {
            for v in [sp.x0, sp.x1] {
                if v.is_finite() {
                    xr = (xr.0.min(v), xr.1.max(v));
                }
            }
        }
        (xr, yr)
    }

    /// Write the SVG into `out`; `at` places it as a nested `<svg>` inside another.
    fn render(&self, out: &mut String, at: Option<(f64, f64)>) {
        let (w, h) = (self.width.max(160.0), self.height.max(120.0));
        let (xe, ye) = self.extents();

        // y axis: at most one tick per 35 px of the estimated plot height (the nice step
        // rounds up, so the ticks end up 35–90 px apart).
        let y_target = (((h - 110.0) / 35.0).floor() as usize).clamp(3, 10);
        let y_axis = match self.y_range {
            Some((a, b)) => {
                let (a, b) = widen(a, b);
                Axis::new(a, b, nice_step((b - a) / (y_target - 1) as f64))
            }
            None => {
                // 4 % margins keep curves off the frame (a bound or a zero baseline
                // would otherwise hide in it); ticks fall inside.
                let (a, b) = widen(ye.0, ye.1);
                let (a, b) = (a - 0.04 * (b - a), b + 0.04 * (b - a));
                Axis::new(a, b, nice_step((b - a) / (y_target - 1) as f64))
            }
        };
        let tick_w = y_axis
            .labels
            .iter()
            .map(|l| text_width(l, TICK_SIZE))
            .fold(0.0, f64::max);
        let y_label_band = if self.y_label.is_empty() {
            0.0
        } else {
            LABEL_SIZE + 8.0
        };
        let left = 8.0 + y_label_band + tick_w + 8.0;
        let right = 24.0;
        let pw = (w - left - right).max(40.0);

        // x axis: the most ticks whose labels keep a 12 px gap.
        let (xa, xb) = widen(
            self.x_range.map_or(xe.0, |r| r.0),
            self.x_range.map_or(xe.1, |r| r.1),
        );
        let x_axis = (2..=12)
            .rev()
            .map(|n| Axis::new(xa, xb, nice_step((xb - xa) / (n - 1) as f64)))
            .find(|ax| {
                let widths: f64 = ax
                    .labels
                    .iter()
                    .map(|l| text_width(l, TICK_SIZE) + 12.0)
                    .sum();
                widths <= pw
            })
            .unwrap_or_else(|| Axis::new(xa, xb, xb - xa));
        let sx = |x: f64| left + (x - x_axis.lo) / (x_axis.hi - x_axis.lo) * pw;

        // Legend rows below the x-axis label, wrapping at the plot width.
        let mut legend = Vec::new();
        let (mut lx, mut lrow) = (0.0, 0usize);
        // bands are listed after the series, as legend items `series.len() + band`
        let names: Vec<&str> = self
            .series
            .iter()
            .map(|s| s.name.as_str())
            .chain(self.bands.iter().map(|b| b.name.as_str()))
            .collect();
        for (i, name) in names.iter().enumerate().filter(|(_, n)| !n.is_empty()) {
            let item_w = LEGEND_SAMPLE + 6.0 + text_width(name, LEGEND_SIZE);
            if lx > 0.0 && lx + item_w > pw {
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
        let legend_rows = if legend.is_empty() { 0 } else { lrow + 1 };

        // Span labels: centred on their span, moved to a further row when they would
        // overlap a label already placed.
        let mut row_end = [f64::NEG_INFINITY; MAX_SPAN_ROWS];
        let mut span_labels = Vec::new();
        let mut order: Vec<usize> = (0..self.shaded.len())
            .filter(|&i| !self.shaded[i].label.is_empty())
            .collect();
        order.sort_by(|&a, &b| {
            self.shaded[a]
                .x0
                .total_cmp(&self.shaded[b].x0)
                .then(a.cmp(&b))
        });
        for i in order {
            let sp = &self.shaded[i];
            let (a, b) = (sp.x0.max(x_axis.lo), sp.x1.min(x_axis.hi));
            if !(a.is_finite() && b.is_finite()) || b < a {
                continue;
            }
            let tw = text_width(&sp.label, SPAN_SIZE);
            let cx = ((sx(a) + sx(b)) / 2.0).clamp(left + tw / 2.0, left + pw - tw / 2.0);
            let row = (0..MAX_SPAN_ROWS).find(|&r| cx - tw / 2.0 >= row_end[r] + 4.0);
            let (row, cx) = match row {
                Some(r) => (r, cx),
                None => {
                    let r = (0..MAX_SPAN_ROWS)
                        .min_by(|&p, &q| row_end[p].total_cmp(&row_end[q]))
                        .unwrap_or(0);
                    (r, cx.max(row_end[r] + 4.0 + tw / 2.0))
                }
            };
            row_end[row] = cx + tw / 2.0;
            span_labels.push(SpanLabel { span: i, cx, row });
        }
        let span_rows = span_labels.iter().map(|l| l.row + 1).max().unwrap_or(0);

        let title_band = if self.title.is_empty() {
            4.0
        } else {
            TITLE_SIZE + 14.0
        };
        let top_axis_band = if self.top_axis.is_some() {
            LABEL_SIZE + 6.0 + TICK_SIZE + 6.0
        } else {
            0.0
        };
        let top = title_band + span_rows as f64 * SPAN_ROW + top_axis_band + 6.0;
        let x_label_band = if self.x_label.is_empty() {
            0.0
        } else {
            LABEL_SIZE + 8.0
        };
        let legend_band = if legend_rows == 0 {
            0.0
        } else {
            legend_rows as f64 * LEGEND_ROW + 6.0
        };
        let bottom = 6.0 + TICK_SIZE + 6.0 + x_label_band + legend_band + 6.0;
        let ph = (h - top - bottom).max(40.0);
        let sy = |y: f64| top + ph - (y - y_axis.lo) / (y_axis.hi - y_axis.lo) * ph;

        // Header.
        svg_header(out, &self.title, w, h, at, left + pw / 2.0);

        // Shaded spans, alternately tinted, with their edges.
        for (i, sp) in self.shaded.iter().enumerate() {
            let (a, b) = (sp.x0.max(x_axis.lo), sp.x1.min(x_axis.hi));
            if !(a.is_finite() && b.is_finite()) || b < a {
                continue;
            }
            let (fill, opacity) = if i % 2 == 0 {
                ("#5b7fb0", "0.16")
            } else {
                ("#b0a05b", "0.14")
            };
            writeln!(
                out,
                r#"<rect x="{}" y="{}" width="{}" height="{}" fill="{fill}" fill-opacity="{opacity}"/>"#,
                px(sx(a)),
                px(top),
                px(sx(b) - sx(a)),
                px(ph)
            )
            .ok();
            for e in [a, b] {
                if e > x_axis.lo && e < x_axis.hi {
                    writeln!(
                        out,
                        r##"<line x1="{x}" y1="{}" x2="{x}" y2="{}" stroke="#7a869a" stroke-width="0.8" stroke-dasharray="3 3"/>"##,
                        px(top),
                        px(top + ph),
                        x = px(sx(e))
                    )
                    .ok();
                }
            }
        }
        for l in &span_labels {
            writeln!(
                out,
                r##"<text x="{}" y="{}" font-size="{SPAN_SIZE}" text-anchor="middle" fill="#3d4a5c">{}</text>"##,
                px(l.cx),
                px(title_band + (l.row as f64 + 1.0) * SPAN_ROW - 3.0),
                escape_xml(&self.shaded[l.span].label)
            )
            .ok();
        }

        // Grid, zero line, frame, ticks.
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
        for &t in &x_axis.ticks {
            writeln!(
                out,
                r##"<line x1="{x}" y1="{}" x2="{x}" y2="{}" stroke="#e3e3e3" stroke-width="0.8"/>"##,
                px(top),
                px(top + ph),
                x = px(sx(t))
            )
            .ok();
        }
        writeln!(
            out,
            r##"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="#333333" stroke-width="1"/>"##,
            px(left),
            px(top),
            px(pw),
            px(ph)
        )
        .ok();
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
        for (t, l) in x_axis.ticks.iter().zip(&x_axis.labels) {
            let x = sx(*t);
            writeln!(
                out,
                r##"<line x1="{x}" y1="{}" x2="{x}" y2="{}" stroke="#333333"/><text x="{x}" y="{}" font-size="{TICK_SIZE}" text-anchor="middle" fill="#333333">{l}</text>"##,
                px(top + ph),
                px(top + ph + 4.0),
                px(top + ph + 6.0 + TICK_SIZE),
                x = px(x)
            )
            .ok();
        }
        if !self.x_label.is_empty() {
            writeln!(
                out,
                r##"<text x="{}" y="{}" font-size="{LABEL_SIZE}" text-anchor="middle" fill="#222222">{}</text>"##,
                px(left + pw / 2.0),
                px(top + ph + 12.0 + TICK_SIZE + LABEL_SIZE + 2.0),
                escape_xml(&self.x_label)
            )
            .ok();
        }
        if !self.y_label.is_empty() {
            let (x, y) = (8.0 + LABEL_SIZE, top + ph / 2.0);
            writeln!(
                out,
                r##"<text x="{x}" y="{y}" font-size="{LABEL_SIZE}" text-anchor="middle" fill="#222222" transform="rotate(-90 {x} {y})">{}</text>"##,
                escape_xml(&self.y_label),
                x = px(x),
                y = px(y)
            )
            .ok();
        }

        if let Some(ta) = &self.top_axis {
            self.render_top_axis(
                out,
                ta,
                &sx,
                (x_axis.lo, x_axis.hi),
                top,
                title_band + span_rows as f64 * SPAN_ROW,
            );
        }

        // Bands, under the curves.
        let bx = (x_axis.lo, x_axis.hi, y_axis.lo, y_axis.hi);
        for (i, b) in self.bands.iter().enumerate() {
            let d = band_path(b, bx, &sx, &sy);
            if !d.is_empty() {
                writeln!(
                    out,
                    r#"<path d="{d}" fill="{}" fill-opacity="0.22" stroke="none"><title>{}</title></path>"#,
                    BAND_PALETTE[i % BAND_PALETTE.len()],
                    escape_xml(&b.name)
                )
                .ok();
            }
        }

        // Series.
        for (i, s) in self.series.iter().enumerate() {
            let colour = PALETTE[s.colour.unwrap_or(i) % PALETTE.len()];
            let d = match s.style {
                LineStyle::Markers => markers_path(s, bx, &sx, &sy),
                LineStyle::Solid | LineStyle::Dashed => line_path(s, bx, &sx, &sy),
            };
            if d.is_empty() {
                continue;
            }
            let name = escape_xml(&s.name);
            match s.style {
                LineStyle::Markers => writeln!(out, r#"<path d="{d}" fill="{colour}" stroke="none"><title>{name}</title></path>"#),
                LineStyle::Solid => writeln!(
                    out,
                    r#"<path d="{d}" fill="none" stroke="{colour}" stroke-width="1.6" stroke-linejoin="round" stroke-linecap="round"><title>{name}</title></path>"#
                ),
                LineStyle::Dashed => writeln!(
                    out,
                    r#"<path d="{d}" fill="none" stroke="{colour}" stroke-width="1.6" stroke-dasharray="6 4" stroke-linejoin="round" stroke-linecap="round"><title>{name}</title></path>"#
                ),
            }
            .ok();
        }

        // Legend.
        let legend_top = top + ph + 12.0 + TICK_SIZE + x_label_band + 4.0;
        for it in &legend {
            let x = left + it.x;
            let y = legend_top + it.row as f64 * LEGEND_ROW + LEGEND_ROW / 2.0;
            if it.series >= self.series.len() {
                let k = it.series - self.series.len();
                writeln!(
                    out,
                    r##"<rect x="{}" y="{}" width="{LEGEND_SAMPLE}" height="8" fill="{}" fill-opacity="0.35"/><text x="{}" y="{}" font-size="{LEGEND_SIZE}" fill="#222222">{}</text>"##,
                    px(x),
                    px(y - 4.0),
                    BAND_PALETTE[k % BAND_PALETTE.len()],
                    px(x + LEGEND_SAMPLE + 6.0),
                    px(y + LEGEND_SIZE * 0.35),
                    escape_xml(&self.bands[k].name)
                )
                .ok();
                continue;
            }
            let s = &self.series[it.series];
            let colour = PALETTE[s.colour.unwrap_or(it.series) % PALETTE.len()];
            match s.style {
                LineStyle::Markers => writeln!(
                    out,
                    r#"<circle cx="{}" cy="{}" r="{}" fill="{colour}"/>"#,
                    px(x + LEGEND_SAMPLE / 2.0),
                    px(y),
                    MARKER_RADIUS + 0.5
                ),
                LineStyle::Solid | LineStyle::Dashed => writeln!(
                    out,
                    r#"<line x1="{}" y1="{y}" x2="{}" y2="{y}" stroke="{colour}" stroke-width="2"{}/>"#,
                    px(x),
                    px(x + LEGEND_SAMPLE),
                    if s.style == LineStyle::Dashed { r#" stroke-dasharray="6 4""# } else { "" },
                    y = px(y)
                ),
            }
            .ok();
            writeln!(
                out,
                r##"<text x="{}" y="{}" font-size="{LEGEND_SIZE}" fill="#222222">{}</text>"##,
                px(x + LEGEND_SAMPLE + 6.0),
                px(y + LEGEND_SIZE * 0.35),
                escape_xml(&s.name)
            )
            .ok();
        }
        if let Some(note) = &self.note {
            let (cx, cy) = (left + pw / 2.0, top + ph / 2.0);
            let size = (pw / (text_width(note, 1.0) + 1.0)).clamp(10.0, 30.0);
            writeln!(
                out,
                r##"<text class="plot-note" x="{x}" y="{y}" font-size="{}" font-weight="bold" text-anchor="middle" fill="#c62828" fill-opacity="0.3" transform="rotate(-12 {x} {y})">{}</text>"##,
                px(size),
                escape_xml(note),
                x = px(cx),
                y = px(cy)
            )
            .ok();
        }
        if self.series.iter().all(|s| Self::points(s).next().is_none()) {
            writeln!(
                out,
                r##"<text x="{}" y="{}" font-size="{LABEL_SIZE}" text-anchor="middle" fill="#888888">no data</text>"##,
                px(left + pw / 2.0),
                px(top + ph / 2.0)
            )
            .ok();
        }
        out.push_str("</svg>\n");
    }
}

impl LinePlot {
    /// The second x axis along the top: per segment, nice ticks of its own scale placed
    /// through the segment's linear map; labels that would touch the previous are left out.
    fn render_top_axis(
        &self,
        out: &mut String,
        ta: &TopAxis,
        sx: &dyn Fn(f64) -> f64,
        (lo, hi): (f64, f64),
        top: f64,
        band_top: f64,
    ) {
        let mut labels: Vec<(f64, String)> = Vec::new();
        for &(x0, x1, t0, t1) in &ta.segments {
            if !(x0.is_finite() && x1.is_finite() && t0.is_finite() && t1.is_finite())
                || x1 <= x0
                || t1 == t0
            {
                continue;
            }
            let width = (sx(x1.min(hi)) - sx(x0.max(lo))).max(0.0);
            let target = ((width / 45.0).floor() as usize).clamp(3, 10);
            let (a, b) = (t0.min(t1), t0.max(t1));
            let step = nice_step((b - a) / (target - 1) as f64);
            let ticks = nice_ticks(a, b, target);
            for (t, l) in ticks.iter().zip(tick_labels(&ticks, step)) {
                let x = x0 + (t - t0) / (t1 - t0) * (x1 - x0);
                if x < lo || x > hi {
                    continue;
                }
                let px_x = sx(x);
                writeln!(
                    out,
                    r##"<line x1="{x}" y1="{}" x2="{x}" y2="{}" stroke="#333333"/>"##,
                    px(top - 4.0),
                    px(top),
                    x = px(px_x)
                )
                .ok();
                labels.push((px_x, l));
            }
        }
        // labels left to right, each kept clear of the one before
        labels.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut last_end = f64::NEG_INFINITY;
        for (px_x, l) in labels {
            let tw = text_width(&l, TICK_SIZE);
            if px_x - tw / 2.0 < last_end + 8.0 {
                continue;
            }
            last_end = px_x + tw / 2.0;
            writeln!(
                out,
                r##"<text x="{}" y="{}" font-size="{TICK_SIZE}" text-anchor="middle" fill="#555555">{l}</text>"##,
                px(px_x),
                px(top - 6.0)
            )
            .ok();
        }
        writeln!(
            out,
            r##"<text x="{}" y="{}" font-size="{LABEL_SIZE}" text-anchor="middle" fill="#444444">{}</text>"##,
            px((sx(lo) + sx(hi)) / 2.0),
            px(band_top + LABEL_SIZE),
            escape_xml(&ta.label)
        )
        .ok();
    }
}

/// Fill colours of bands.
const BAND_PALETTE: [&str; 3] = ["#D55E00", "#0072B2", "#009E73"];

/// Path data of a band: one closed polygon per run of finite points, along one edge and
/// back along the other, with values clamped to the axes.
fn band_path(
    b: &Band,
    bx: (f64, f64, f64, f64),
    sx: &dyn Fn(f64) -> f64,
    sy: &dyn Fn(f64) -> f64,
) -> String {
    let n = b.x.len().min(b.y0.len()).min(b.y1.len());
    let ok = |i: usize| {
        b.x[i].is_finite()
            && b.y0[i].is_finite()
            && b.y1[i].is_finite()
            && b.x[i] >= bx.0
            && b.x[i] <= bx.1
    };
    let cy = |y: f64| sy(y.clamp(bx.2, bx.3));
    let mut d = String::new();
    let mut i = 0;
    while i < n {
        if !ok(i) {
            i += 1;
            continue;
        }
        let start = i;
        while i < n && ok(i) {
            i += 1;
        }
        if i - start < 2 {
            continue;
        }
        for k in start..i {
            write!(
                d,
                "{}{} {}",
                if k == start { "M" } else { "L" },
                px(sx(b.x[k])),
                px(cy(b.y0[k]))
            )
            .ok();
        }
        for k in (start..i).rev() {
            write!(d, "L{} {}", px(sx(b.x[k])), px(cy(b.y1[k]))).ok();
        }
        d.push('Z');
    }
    d
}

/// Path data of a line series: segments between consecutive finite points, clipped to
/// the axes; a non-finite value lifts the pen. Isolated points become small dots.
fn line_path(
    s: &Series,
    bx: (f64, f64, f64, f64),
    sx: &dyn Fn(f64) -> f64,
    sy: &dyn Fn(f64) -> f64,
) -> String {
    let mut d = String::new();
    let mut pen: Option<String> = None; // last point written, formatted
    let n = s.x.len().min(s.y.len());
    let ok = |i: usize| s.x[i].is_finite() && s.y[i].is_finite();
    for i in 0..n {
        if !ok(i) {
            pen = None;
            continue;
        }
        let prev_ok = i > 0 && ok(i - 1);
        let next_ok = i + 1 < n && ok(i + 1);
        if !prev_ok && !next_ok {
            let (x, y) = (s.x[i], s.y[i]);
            if x >= bx.0 && x <= bx.1 && y >= bx.2 && y <= bx.3 {
                let (cx, cy) = (sx(x), sy(y));
                write!(d, "M{} {}h0", px(cx), px(cy)).ok();
            }
            continue;
        }
        if !prev_ok {
            continue;
        }
        let a = (s.x[i - 1], s.y[i - 1]);
        let b = (s.x[i], s.y[i]);
        match clip(a, b, bx) {
            None => pen = None,
            Some((a, b)) => {
                let pa = format!("{} {}", px(sx(a.0)), px(sy(a.1)));
                let pb = format!("{} {}", px(sx(b.0)), px(sy(b.1)));
                if pen.as_deref() != Some(pa.as_str()) {
                    write!(d, "M{pa}").ok();
                }
                if pb != pa || pen.as_deref() != Some(pa.as_str()) {
                    write!(d, "L{pb}").ok();
                }
                // After a clipped end the next segment starts elsewhere: it moves.
                pen = Some(pb);
            }
        }
    }
    d
}

/// Path data of a marker series: one small circle per finite point inside the axes.
fn markers_path(
    s: &Series,
    bx: (f64, f64, f64, f64),
    sx: &dyn Fn(f64) -> f64,
    sy: &dyn Fn(f64) -> f64,
) -> String {
    let r = MARKER_RADIUS;
    let mut d = String::new();
    for (x, y) in LinePlot::points(s) {
        if x >= bx.0 && x <= bx.1 && y >= bx.2 && y <= bx.3 {
            write!(
                d,
                "M{} {}a{r} {r} 0 1 0 {} 0a{r} {r} 0 1 0 {} 0",
                px(sx(x) - r),
                px(sy(y)),
                2.0 * r,
                -2.0 * r
            )
            .ok();
        }
    }
    d
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

/// One named set of bars in a [`BarChart`]: one value per category, all in one colour.
#[derive(Debug, Clone, PartialEq)]
pub struct BarSeries {
    /// Legend entry.
    pub name: String,
    /// Bar heights, one per category (y units); a non-finite value draws no bar.
    pub values: Vec<f64>,
    /// Text above each bar (e.g. the value in its own unit); missing or empty: none.
    /// A category without a bar still shows its label, at the baseline.
    pub labels: Vec<String>,
}

impl BarSeries {
    /// A series from its parts.
    pub fn new(name: impl Into<String>, values: Vec<f64>, labels: Vec<String>) -> Self {
        Self {
            name: name.into(),
            values,
            labels,
        }
    }
}

/// A grouped bar chart rendered to SVG: one group of bars per category, one bar per
/// series, bars from zero, an optional dashed reference line (e.g. 100 % = "as before").
///
/// Text is laid out as in [`LinePlot`]; the figure grows wider than [`BarChart::width`]
/// when the category or bar labels need the room, so labels never overlap. Bars beyond
/// a fixed `y_range` are clipped at the frame (their label still gives the value).
///
/// ```
/// use footfall::report::plot::{BarChart, BarSeries};
///
/// let mut c = BarChart::new("mean error, % of run A", "% of A");
/// c.categories = vec!["knee angle\n(°)".into(), "CoP\n(cm)".into()];
/// c.series.push(BarSeries::new("A", vec![100.0, 100.0], vec!["4.00 °".into(), "2.00 cm".into()]));
/// c.series.push(BarSeries::new("B", vec![75.0, 150.0], vec!["3.00 °".into(), "3.00 cm".into()]));
/// c.reference = Some((100.0, "A".into()));
/// let svg = c.to_svg();
/// assert!(svg.starts_with("<svg") && svg.contains("3.00 cm"));
/// assert_eq!(svg, c.to_svg()); // deterministic
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct BarChart {
    /// Title, drawn above the plot.
    pub title: String,
    /// y-axis label, with units.
    pub y_label: String,
    /// Category labels along the x axis; `\n` starts a further line.
    pub categories: Vec<String>,
    /// Bar series, drawn side by side within each category; colours as in [`LinePlot`].
    pub series: Vec<BarSeries>,
    /// A dashed horizontal line at this y value, labelled at its right end.
    pub reference: Option<(f64, String)>,
    /// Minimum width of the whole figure (px, default 640).
    pub width: f64,
    /// Height of the whole figure (px, default 380).
    pub height: f64,
    /// Fixed y range; `None`: from zero (or the lowest bar) to the highest bar or
    /// reference with a 4 % margin (default `None`).
    pub y_range: Option<(f64, f64)>,
}

impl BarChart {
    /// An empty 640 × 380 chart.
    pub fn new(title: impl Into<String>, y_label: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            y_label: y_label.into(),
            categories: Vec::new(),
            series: Vec::new(),
            reference: None,
            width: 640.0,
            height: 380.0,
            y_range: None,
        }
    }

    /// Value of series `s` in category `c` when it is drawn.
    fn value(&self, s: usize, c: usize) -> Option<f64> {
        self.series[s]
            .values
            .get(c)
            .copied()
            .filter(|v| v.is_finite())
    }

    /// Label of series `s` in category `c` ("" when none).
    fn label(&self, s: usize, c: usize) -> &str {
        self.series[s].labels.get(c).map_or("", String::as_str)
    }

    /// The chart as a standalone SVG document (`<svg xmlns=…>…</svg>`, newline-terminated).
    pub fn to_svg(&self) -> String {
        let n_cat = self.categories.len();
        let n_ser = self.series.len().max(1);
        let h = self.height.max(160.0);

        // y axis
        let mut yr = (0.0f64, f64::NEG_INFINITY);
        for s in 0..self.series.len() {
            for c in 0..n_cat {
                if let Some(v) = self.value(s, c) {
                    yr = (yr.0.min(v), yr.1.max(v));
                }
            }
        }
        if let Some((r, _)) = self.reference.as_ref().filter(|r| r.0.is_finite()) {
            yr = (yr.0.min(*r), yr.1.max(*r));
        }
        let y_target = (((h - 130.0) / 35.0).floor() as usize).clamp(3, 10);
        let (ya, yb) = match self.y_range {
            Some((a, b)) => widen(a, b),
            None => {
                let (a, b) = widen(yr.0, yr.1);
                let m = 0.04 * (b - a);
                (if a < 0.0 { a - m } else { a }, b + m)
            }
        };
        let y_axis = Axis::new(ya, yb, nice_step((yb - ya) / (y_target - 1) as f64));
        let tick_w = y_axis
            .labels
            .iter()
            .map(|l| text_width(l, TICK_SIZE))
            .fold(0.0, f64::max);
        let y_label_band = if self.y_label.is_empty() {
            0.0
        } else {
            LABEL_SIZE + 8.0
        };
        let left = 8.0 + y_label_band + tick_w + 8.0;
        let ref_w = self
            .reference
            .as_ref()
            .map_or(0.0, |r| text_width(&r.1, SPAN_SIZE) + 8.0);
        let right = ref_w.max(24.0);

        // x layout: each category gets a slot wide enough for its label lines and for
        // the labels of its bars side by side.
        let cat_lines: Vec<Vec<&str>> = self
            .categories
            .iter()
            .map(|c| c.split('\n').collect())
            .collect();
        let n_lines = cat_lines.iter().map(Vec::len).max().unwrap_or(0);
        let cat_w = cat_lines
            .iter()
            .flatten()
            .map(|l| text_width(l, TICK_SIZE))
            .fold(0.0, f64::max);
        let bar_label_w = (0..self.series.len())
            .flat_map(|s| (0..n_cat).map(move |c| (s, c)))
            .map(|(s, c)| text_width(self.label(s, c), SPAN_SIZE))
            .fold(0.0, f64::max);
        let slot_min = (cat_w + 14.0)
            .max((bar_label_w + 6.0) * n_ser as f64 / 0.8)
            .max(40.0);
        let pw = (self.width - left - right).max(slot_min * n_cat.max(1) as f64);
        let w = left + pw + right;
        let slot = pw / n_cat.max(1) as f64;
        let bar_w = slot * 0.8 / n_ser as f64;

        // legend rows below the category labels, wrapping at the plot width
        let mut legend = Vec::new();
        let (mut lx, mut lrow) = (0.0, 0usize);
        for (i, s) in self
            .series
            .iter()
            .enumerate()
            .filter(|(_, s)| !s.name.is_empty())
        {
            let item_w = 14.0 + 6.0 + text_width(&s.name, LEGEND_SIZE);
            if lx > 0.0 && lx + item_w > pw {
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
        let legend_rows = if legend.is_empty() { 0 } else { lrow + 1 };

        let title_band = if self.title.is_empty() {
            4.0
        } else {
            TITLE_SIZE + 14.0
        };
        let top = title_band + SPAN_SIZE + 8.0; // room for bar labels at the top
        let cat_band = n_lines as f64 * (TICK_SIZE + 3.0);
        let legend_band = if legend_rows == 0 {
            0.0
        } else {
            legend_rows as f64 * LEGEND_ROW + 6.0
        };
        let bottom = 8.0 + cat_band + legend_band + 8.0;
        let ph = (h - top - bottom).max(40.0);
        let sy = |y: f64| {
            top + ph - (y.clamp(y_axis.lo, y_axis.hi) - y_axis.lo) / (y_axis.hi - y_axis.lo) * ph
        };

        let mut out = String::new();
        svg_header(&mut out, &self.title, w, h, None, left + pw / 2.0);

        // grid, frame, y ticks and label
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
        if !self.y_label.is_empty() {
            let (x, y) = (8.0 + LABEL_SIZE, top + ph / 2.0);
            writeln!(
                out,
                r##"<text x="{x}" y="{y}" font-size="{LABEL_SIZE}" text-anchor="middle" fill="#222222" transform="rotate(-90 {x} {y})">{}</text>"##,
                escape_xml(&self.y_label),
                x = px(x),
                y = px(y)
            )
            .ok();
        }

        // the reference line behind the bars, labelled right of the frame
        if let Some((r, name)) = self
            .reference
            .as_ref()
            .filter(|r| r.0.is_finite() && r.0 >= y_axis.lo && r.0 <= y_axis.hi)
        {
            let y = sy(*r);
            writeln!(
                out,
                r##"<line x1="{}" y1="{y}" x2="{}" y2="{y}" stroke="#333333" stroke-width="1" stroke-dasharray="5 3"/>"##,
                px(left),
                px(left + pw),
                y = px(y)
            )
            .ok();
            if !name.is_empty() {
                writeln!(
                    out,
                    r##"<text x="{}" y="{}" font-size="{SPAN_SIZE}" text-anchor="start" fill="#333333">{}</text>"##,
                    px(left + pw + 3.0),
                    px(y + SPAN_SIZE * 0.35),
                    escape_xml(name)
                )
                .ok();
            }
        }

        // bars and their labels
        let base = sy(0.0);
        for (c, lines) in cat_lines.iter().enumerate() {
            let x0 = left + c as f64 * slot + 0.1 * slot;
            for (s, series) in self.series.iter().enumerate() {
                let x = x0 + s as f64 * bar_w;
                let label = self.label(s, c);
                let label_y = match self.value(s, c) {
                    Some(v) => {
                        let (y0, y1) = (sy(v).min(base), sy(v).max(base));
                        writeln!(
                            out,
                            r#"<rect x="{}" y="{}" width="{}" height="{}" fill="{}"><title>{}</title></rect>"#,
                            px(x + 1.0),
                            px(y0),
                            px((bar_w - 2.0).max(1.0)),
                            px(y1 - y0),
                            PALETTE[s % PALETTE.len()],
                            escape_xml(&format!("{}: {}", series.name, if label.is_empty() { format!("{v}") } else { label.to_string() }))
                        )
                        .ok();
                        y0
                    }
                    None => base,
                };
                if !label.is_empty() {
                    writeln!(
                        out,
                        r##"<text x="{}" y="{}" font-size="{SPAN_SIZE}" text-anchor="middle" fill="#222222">{}</text>"##,
                        px(x + bar_w / 2.0),
                        px(label_y - 3.0),
                        escape_xml(label)
                    )
                    .ok();
                }
            }
            for (k, line) in lines.iter().enumerate() {
                writeln!(
                    out,
                    r##"<text x="{}" y="{}" font-size="{TICK_SIZE}" text-anchor="middle" fill="#333333">{}</text>"##,
                    px(left + (c as f64 + 0.5) * slot),
                    px(top + ph + 6.0 + (k as f64 + 1.0) * (TICK_SIZE + 3.0) - 3.0),
                    escape_xml(line)
                )
                .ok();
            }
        }
        writeln!(
            out,
            r##"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="#333333" stroke-width="1"/>"##,
            px(left),
            px(top),
            px(pw),
            px(ph)
        )
        .ok();

        // legend
        let legend_top = top + ph + 8.0 + cat_band + 4.0;
        for it in &legend {
            let x = left + it.x;
            let y = legend_top + it.row as f64 * LEGEND_ROW + LEGEND_ROW / 2.0;
            writeln!(
                out,
                r#"<rect x="{}" y="{}" width="14" height="10" fill="{}"/>"#,
                px(x),
                px(y - 5.0),
                PALETTE[it.series % PALETTE.len()]
            )
            .ok();
            writeln!(
                out,
                r##"<text x="{}" y="{}" font-size="{LEGEND_SIZE}" fill="#222222">{}</text>"##,
                px(x + 20.0),
                px(y + LEGEND_SIZE * 0.35),
                escape_xml(&self.series[it.series].name)
            )
            .ok();
        }
        if n_cat == 0 {
            writeln!(
                out,
                r##"<text x="{}" y="{}" font-size="{LABEL_SIZE}" text-anchor="middle" fill="#888888">no data</text>"##,
                px(left + pw / 2.0),
                px(top + ph / 2.0)
            )
            .ok();
        }
        out.push_str("</svg>\n");
        out
    }
}
