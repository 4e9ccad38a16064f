//! Drawing a [`LinePlot`]: axes, spans, bands, lines and markers, the legend and the
//! second x axis along the top.

use super::*;
use std::fmt::Write;

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
    pub(super) fn render(&self, out: &mut String, at: Option<(f64, f64)>) {
        let l = self.layout();
        svg_header(out, &self.title, l.w, l.h, at, l.left + l.pw / 2.0);
        self.draw_spans(out, &l);
        self.draw_axes(out, &l);
        self.draw_data(out, &l);
        self.draw_legend(out, &l);
        if let Some(note) = &self.note {
            let (cx, cy) = (l.left + l.pw / 2.0, l.top + l.ph / 2.0);
            let size = (l.pw / (text_width(note, 1.0) + 1.0)).clamp(10.0, 30.0);
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
            no_data(out, l.left, l.top, l.pw, l.ph);
        }
        out.push_str("</svg>\n");
    }

    /// The figure's layout: the axes, the margins, the span labels and the legend.
    fn layout(&self) -> Layout {
        let (w, h) = (self.width.max(160.0), self.height.max(120.0));
        let (xe, ye) = self.extents();
        let y_axis = self.y_axis(h, ye);
        let left = left_margin(&y_axis, &self.y_label);
        let right = 24.0;
        let pw = (w - left - right).max(40.0);
        let x_axis = self.x_axis(xe, pw);

        // Legend rows below the x-axis label, wrapping at the plot width.
        // bands are listed after the series, as legend items `series.len() + band`
        let names = self
            .series
            .iter()
            .map(|s| s.name.as_str())
            .chain(self.bands.iter().map(|b| b.name.as_str()));
        let (legend, legend_rows) = legend_layout(names, LEGEND_SAMPLE, pw);

        let span_labels = self.span_labels(&x_axis, left, pw);
        let span_rows = span_labels.iter().map(|l| l.row + 1).max().unwrap_or(0);

        let title_band = title_band(&self.title);
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
        let legend_band = legend_band(legend_rows);
        let bottom = 6.0 + TICK_SIZE + 6.0 + x_label_band + legend_band + 6.0;
        let ph = (h - top - bottom).max(40.0);
        Layout {
            w,
            h,
            left,
            pw,
            top,
            ph,
            x_axis,
            y_axis,
            title_band,
            span_rows,
            span_labels,
            legend,
            x_label_band,
        }
    }

    /// The y axis of a figure `h` px high over the data's y extent `ye`: at most one tick
    /// per 35 px of the estimated plot height (the nice step rounds up, so the ticks end
    /// up 35–90 px apart).
    fn y_axis(&self, h: f64, ye: (f64, f64)) -> Axis {
        let y_target = (((h - 110.0) / 35.0).floor() as usize).clamp(3, 10);
        match self.y_range {
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
        }
    }

    /// The x axis over the data's x extent `xe` on a plot `pw` px wide: the most ticks
    /// whose labels keep a 12 px gap.
    fn x_axis(&self, xe: (f64, f64), pw: f64) -> Axis {
        let (xa, xb) = widen(
            self.x_range.map_or(xe.0, |r| r.0),
            self.x_range.map_or(xe.1, |r| r.1),
        );
        (2..=12)
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
            .unwrap_or_else(|| Axis::new(xa, xb, xb - xa))
    }

    /// Span labels: centred on their span, moved to a further row when they would
    /// overlap a label already placed (the plot area starts at `left` and is `pw` px wide).
    fn span_labels(&self, x_axis: &Axis, left: f64, pw: f64) -> Vec<SpanLabel> {
        let sx = |x: f64| left + (x - x_axis.lo) / (x_axis.hi - x_axis.lo) * pw;
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
        span_labels
    }

    /// Shaded spans, alternately tinted, with their edges and labels.
    fn draw_spans(&self, out: &mut String, l: &Layout) {
        let (x_axis, top, ph) = (&l.x_axis, l.top, l.ph);
        let sx = |x: f64| l.sx(x);
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
        for sl in &l.span_labels {
            writeln!(
                out,
                r##"<text x="{}" y="{}" font-size="{SPAN_SIZE}" text-anchor="middle" fill="#3d4a5c">{}</text>"##,
                px(sl.cx),
                px(l.title_band + (sl.row as f64 + 1.0) * SPAN_ROW - 3.0),
                escape_xml(&self.shaded[sl.span].label)
            )
            .ok();
        }
    }

    /// Grid, frame, ticks, axis labels and the top axis.
    fn draw_axes(&self, out: &mut String, l: &Layout) {
        let (x_axis, left, pw, top, ph) = (&l.x_axis, l.left, l.pw, l.top, l.ph);
        let sx = |x: f64| l.sx(x);
        let sy = |y: f64| l.sy(y);
        y_grid(out, &l.y_axis, left, pw, sy);
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
        frame(out, left, top, pw, ph);
        y_ticks(out, &l.y_axis, left, sy);
        for (t, lab) in x_axis.ticks.iter().zip(&x_axis.labels) {
            let x = sx(*t);
            writeln!(
                out,
                r##"<line x1="{x}" y1="{}" x2="{x}" y2="{}" stroke="#333333"/><text x="{x}" y="{}" font-size="{TICK_SIZE}" text-anchor="middle" fill="#333333">{lab}</text>"##,
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
        y_label(out, &self.y_label, top, ph);

        if let Some(ta) = &self.top_axis {
            self.render_top_axis(
                out,
                ta,
                &sx,
                (x_axis.lo, x_axis.hi),
                top,
                l.title_band + l.span_rows as f64 * SPAN_ROW,
            );
        }
    }

    /// Bands, under the curves, then the series.
    fn draw_data(&self, out: &mut String, l: &Layout) {
        let sx = |x: f64| l.sx(x);
        let sy = |y: f64| l.sy(y);
        let bx = (l.x_axis.lo, l.x_axis.hi, l.y_axis.lo, l.y_axis.hi);
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
    }

    /// The legend below the x-axis label: a line, marker or band swatch and the name.
    fn draw_legend(&self, out: &mut String, l: &Layout) {
        let legend_top = l.top + l.ph + 12.0 + TICK_SIZE + l.x_label_band + 4.0;
        for it in &l.legend {
            let x = l.left + it.x;
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
    }
}

/// A line plot's layout (px): its size, the plot area and its axes, and the placed span
/// labels and legend.
struct Layout {
    /// Width and height of the figure.
    w: f64,
    h: f64,
    /// The plot area: left edge, width, top edge, height.
    left: f64,
    pw: f64,
    top: f64,
    ph: f64,
    x_axis: Axis,
    y_axis: Axis,
    /// Height of the title band.
    title_band: f64,
    /// Rows of span labels below the title.
    span_rows: usize,
    span_labels: Vec<SpanLabel>,
    legend: Vec<LegendItem>,
    /// Height of the x-axis label's band.
    x_label_band: f64,
}

impl Layout {
    /// The px x of data x.
    fn sx(&self, x: f64) -> f64 {
        self.left + (x - self.x_axis.lo) / (self.x_axis.hi - self.x_axis.lo) * self.pw
    }

    /// The px y of data y.
    fn sy(&self, y: f64) -> f64 {
        self.top + self.ph - (y - self.y_axis.lo) / (self.y_axis.hi - self.y_axis.lo) * self.ph
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
