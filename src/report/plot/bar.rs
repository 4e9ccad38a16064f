//! Grouped bar charts on the line plots' axes, palette and legend layout.

use super::*;
use std::fmt::Write;

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
        let l = self.layout();
        let sy = |y: f64| l.sy(y);
        let mut out = String::new();
        svg_header(&mut out, &self.title, l.w, l.h, None, l.left + l.pw / 2.0);

        // grid, frame, y ticks and label
        y_grid(&mut out, &l.y_axis, l.left, l.pw, sy);
        y_ticks(&mut out, &l.y_axis, l.left, sy);
        y_label(&mut out, &self.y_label, l.top, l.ph);

        self.draw_reference(&mut out, &l);
        self.draw_bars(&mut out, &l);
        frame(&mut out, l.left, l.top, l.pw, l.ph);
        self.draw_legend(&mut out, &l);
        if self.categories.is_empty() {
            no_data(&mut out, l.left, l.top, l.pw, l.ph);
        }
        out.push_str("</svg>\n");
        out
    }

    /// The y axis of a chart `h` px high: the given range, or from zero (or the lowest
    /// bar) to the highest bar or reference with a 4 % margin.
    fn y_axis(&self, h: f64) -> Axis {
        let n_cat = self.categories.len();
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
        Axis::new(ya, yb, nice_step((yb - ya) / (y_target - 1) as f64))
    }

    /// The chart's layout: each category gets a slot wide enough for its label lines and
    /// for the labels of its bars side by side; the legend rows below the category
    /// labels wrap at the plot width.
    fn layout(&self) -> BarLayout<'_> {
        let n_cat = self.categories.len();
        let n_ser = self.series.len().max(1);
        let h = self.height.max(160.0);
        let y_axis = self.y_axis(h);
        let left = left_margin(&y_axis, &self.y_label);
        let ref_w = self
            .reference
            .as_ref()
            .map_or(0.0, |r| text_width(&r.1, SPAN_SIZE) + 8.0);
        let right = ref_w.max(24.0);

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

        let names = self.series.iter().map(|s| s.name.as_str());
        let (legend, legend_rows) = legend_layout(names, 14.0, pw);

        let title_band = title_band(&self.title);
        let top = title_band + SPAN_SIZE + 8.0; // room for bar labels at the top
        let cat_band = n_lines as f64 * (TICK_SIZE + 3.0);
        let legend_band = legend_band(legend_rows);
        let bottom = 8.0 + cat_band + legend_band + 8.0;
        let ph = (h - top - bottom).max(40.0);
        BarLayout {
            w,
            h,
            left,
            pw,
            top,
            ph,
            y_axis,
            cat_lines,
            cat_band,
            slot,
            bar_w,
            legend,
        }
    }

    /// The reference line behind the bars, labelled right of the frame.
    fn draw_reference(&self, out: &mut String, l: &BarLayout<'_>) {
        let (left, pw) = (l.left, l.pw);
        if let Some((r, name)) = self
            .reference
            .as_ref()
            .filter(|r| r.0.is_finite() && r.0 >= l.y_axis.lo && r.0 <= l.y_axis.hi)
        {
            let y = l.sy(*r);
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
    }

    /// The bars and their labels, and the category labels below the frame.
    fn draw_bars(&self, out: &mut String, l: &BarLayout<'_>) {
        let (left, slot, bar_w) = (l.left, l.slot, l.bar_w);
        let base = l.sy(0.0);
        for (c, lines) in l.cat_lines.iter().enumerate() {
            let x0 = left + c as f64 * slot + 0.1 * slot;
            for (s, series) in self.series.iter().enumerate() {
                let x = x0 + s as f64 * bar_w;
                let label = self.label(s, c);
                let label_y = match self.value(s, c) {
                    Some(v) => {
                        let (y0, y1) = (l.sy(v).min(base), l.sy(v).max(base));
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
                    px(l.top + l.ph + 6.0 + (k as f64 + 1.0) * (TICK_SIZE + 3.0) - 3.0),
                    escape_xml(line)
                )
                .ok();
            }
        }
    }

    /// The legend below the category labels: a swatch and the series' name.
    fn draw_legend(&self, out: &mut String, l: &BarLayout<'_>) {
        let legend_top = l.top + l.ph + 8.0 + l.cat_band + 4.0;
        for it in &l.legend {
            let x = l.left + it.x;
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
    }
}

/// A bar chart's layout (px): its size, the plot area and y axis, the category slots
/// and the legend.
struct BarLayout<'a> {
    /// Width and height of the figure.
    w: f64,
    h: f64,
    /// The plot area: left edge, width, top edge, height.
    left: f64,
    pw: f64,
    top: f64,
    ph: f64,
    y_axis: Axis,
    /// Each category's label lines.
    cat_lines: Vec<Vec<&'a str>>,
    /// Height of the category labels' band.
    cat_band: f64,
    /// Width of a category's slot and of one bar.
    slot: f64,
    bar_w: f64,
    legend: Vec<LegendItem>,
}

impl BarLayout<'_> {
    /// The px y of value y, clamped to the axis.
    fn sy(&self, y: f64) -> f64 {
        let y_axis = &self.y_axis;
        self.top + self.ph
            - (y.clamp(y_axis.lo, y_axis.hi) - y_axis.lo) / (y_axis.hi - y_axis.lo) * self.ph
    }
}
