//! The body, moving: a stick figure of the model over the measured pose, the foot's
//! contact primitives drawn as they are (ellipses, circles, points), the ground, each
//! foot's ground force as an arrow from its centre of pressure, and the measured CoP
//! beside the model's. [`BodyAnimation::to_html`] gives an SVG animation with play,
//! pause and a scrubber for `report.html`; [`BodyAnimation::film_strip`] a static SVG of
//! the key instants (heel strike, mid-stance, toe-off) for print.
//!
//! The drawing keeps the geometry exact: primitives are SVG `<ellipse>`/`<circle>`
//! elements with the model's centres, semi-axes and angles (coordinates rounded to
//! 0.1 px), so a foot on the ground touches the drawn ground line at its drawn CoP.
//!
//! The animation's script reads the page address: `#frame=N` shows frame N (and
//! scrolls to it), `#play` starts playing, `solo` shows the animation alone (for a slide
//! or a screenshot, e.g. `report.html#frame=12,solo`); the figure's `data-frame`
//! attribute holds the frame shown.

use super::escape_xml;
use super::plot::px;
use crate::model::geometry::Shape;
use crate::model::GaitModel;
use std::fmt::Write;

/// World drawing of one contact primitive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outline {
    /// An ellipse: centre (m), semi-axes (m), world angle of the first axis (rad).
    Ellipse {
        /// Centre (m).
        centre: [f64; 2],
        /// Semi-axes (m).
        semi_axes: [f64; 2],
        /// World angle of the first semi-axis (rad, counter-clockwise).
        angle: f64,
    },
    /// A circle: centre and radius (m).
    Circle {
        /// Centre (m).
        centre: [f64; 2],
        /// Radius (m).
        radius: f64,
    },
    /// A point contact (m).
    Point {
        /// Position (m).
        at: [f64; 2],
    },
}

/// A pose to draw: polylines of the segments and the contact primitives per side.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Pose {
    /// Polylines (m): the trunk, then each leg hip → knee → ankle → primitive centres.
    pub lines: Vec<Vec<[f64; 2]>>,
    /// Contact primitives with their side (0 right, 1 left).
    pub outlines: Vec<(usize, Outline)>,
}

impl Pose {
    /// The model's pose at generalised positions `q` (m, rad), its contact primitives the
    /// shapes the free parameters `theta` give (an identified foot geometry).
    pub fn of_model(model: &GaitModel, q: &[f64], theta: &[f64]) -> Self {
        let tree = model.tree();
        let k = tree.kinematics(q, &vec![0.0; q.len()]);
        let body = |name: &str| tree.body_index(name);
        let origin = |b: usize| k.origin[b];
        let shapes: Vec<Shape> = (0..model.contacts.len())
            .map(|i| model.contact_shape(i, theta))
            .collect();
        let mut lines = Vec::new();
        if let Some(h) = body("hat") {
            // the trunk from the hip joint through the HAT frame's origin to twice its
            // centre of mass (about the top of the head)
            let com = tree.bodies()[h].com;
            let top = tree.point(&k, h, [1.9 * com[0], 1.9 * com[1]]);
            let mut trunk = vec![origin(h), top];
            if let Some(t) = body("thigh_r") {
                trunk.insert(0, origin(t));
            }
            lines.push(trunk);
        }
        for side in ["r", "l"] {
            let ids: Vec<usize> = ["thigh", "shank", "foot"]
                .iter()
                .filter_map(|s| body(&format!("{s}_{side}")))
                .collect();
            let mut leg: Vec<[f64; 2]> = ids.iter().map(|&b| origin(b)).collect();
            if let Some(&foot) = ids.last() {
                for (c, shape) in model.contacts.iter().zip(&shapes) {
                    if c.body == foot {
                        leg.push(tree.point(&k, foot, shape.centre()));
                        leg.push(origin(foot));
                    }
                }
            }
            lines.push(leg);
        }
        let outlines = model
            .contacts
            .iter()
            .zip(shapes)
            .map(|(c, shape)| {
                let side = usize::from(c.name.starts_with("l."));
                let centre = tree.point(&k, c.body, shape.centre());
                let o = match shape {
                    Shape::Ellipse {
                        angle, semi_axes, ..
                    } => Outline::Ellipse {
                        centre,
                        semi_axes,
                        angle: k.angle[c.body] + angle,
                    },
                    Shape::Circle { radius, .. } => Outline::Circle { centre, radius },
                    Shape::Point { .. } => Outline::Point { at: centre },
                };
                (side, o)
            })
            .collect();
        Self { lines, outlines }
    }

    fn extent(&self, lo: &mut [f64; 2], hi: &mut [f64; 2]) {
        let mut add = |p: [f64; 2], r: f64| {
            for i in 0..2 {
                lo[i] = lo[i].min(p[i] - r);
                hi[i] = hi[i].max(p[i] + r);
            }
        };
        for l in &self.lines {
            for &p in l {
                add(p, 0.0);
            }
        }
        for (_, o) in &self.outlines {
            match *o {
                Outline::Ellipse {
                    centre, semi_axes, ..
                } => add(centre, semi_axes[0].max(semi_axes[1])),
                Outline::Circle { centre, radius } => add(centre, radius),
                Outline::Point { at } => add(at, 0.0),
            }
        }
    }
}

/// One instant of the animation.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyFrame {
    /// Time (s).
    pub t: f64,
    /// Percent of the gait cycle (lead leg).
    pub percent: f64,
    /// The model.
    pub model: Pose,
    /// The measured pose (the data's coordinates on the same model).
    pub measured: Pose,
    /// Model CoP x per foot (m; `None` while the foot carries less than the threshold).
    pub cop_model: [Option<f64>; 2],
    /// Measured CoP x per foot (m).
    pub cop_measured: [Option<f64>; 2],
    /// Model ground force per foot `[fx, fy]` (N).
    pub grf_model: [[f64; 2]; 2],
    /// Measured ground force per foot (N; NaN where not measured).
    pub grf_measured: [[f64; 2]; 2],
}

/// A key instant to show in the film strip: frame index, name and the foot it concerns.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyFrame {
    /// Frame index.
    pub frame: usize,
    /// e.g. "heel strike".
    pub name: String,
    /// 0 right, 1 left.
    pub side: usize,
}

/// The animation: frames, the ground `n·p = h` and the key instants.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyAnimation {
    /// Frames in time order.
    pub frames: Vec<BodyFrame>,
    /// Ground height h (m).
    pub ground_height: f64,
    /// Ground unit normal n.
    pub ground_normal: [f64; 2],
    /// Key instants.
    pub keys: Vec<KeyFrame>,
}

/// Drawing scale (px per m).
const SCALE: f64 = 300.0;
/// Ground force arrow length per newton (m/N): body weight ≈ 0.3 m.
const FORCE_LENGTH: f64 = 4e-4;
const SIDE_COLOUR: [&str; 2] = ["#0072B2", "#D55E00"];
const SIDE_CLASS: [&str; 2] = ["side-r", "side-l"];

/// World → SVG coordinates over a view `[x0, x1] × [y0, y1]` (m).
#[derive(Clone, Copy)]
struct View {
    x0: f64,
    y1: f64,
    width: f64,
    height: f64,
}

impl View {
    fn p(&self, p: [f64; 2]) -> (f64, f64) {
        ((p[0] - self.x0) * SCALE, (self.y1 - p[1]) * SCALE)
    }
}

impl BodyAnimation {
    /// Key instants from the model's loads: the lead leg's heel strike (its first loaded
    /// frame), the middle of its single support, and the other leg's toe-off (its last
    /// loaded frame before it unloads). An instant the frames do not contain is left out.
    pub fn find_keys(&mut self, lead: usize) {
        let loaded = |f: &BodyFrame, s: usize| f.cop_model[s].is_some();
        let other = 1 - lead;
        let mut keys = Vec::new();
        if let Some(k) = self.frames.iter().position(|f| loaded(f, lead)) {
            keys.push(KeyFrame {
                frame: k,
                name: "heel strike".into(),
                side: lead,
            });
        }
        let single: Vec<usize> = (0..self.frames.len())
            .filter(|&k| loaded(&self.frames[k], lead) && !loaded(&self.frames[k], other))
            .collect();
        if !single.is_empty() {
            keys.push(KeyFrame {
                frame: single[single.len() / 2],
                name: "mid-stance".into(),
                side: lead,
            });
        }
        if let Some(k) = (0..self.frames.len().saturating_sub(1))
            .find(|&k| loaded(&self.frames[k], other) && !loaded(&self.frames[k + 1], other))
        {
            keys.push(KeyFrame {
                frame: k,
                name: "toe-off".into(),
                side: other,
            });
        }
        self.keys = keys;
    }

    fn ground_y(&self, x: f64) -> f64 {
        let n = self.ground_normal;
        (self.ground_height - n[0] * x) / n[1]
    }

    /// The view around `frames` (all when `None`), with a margin.
    fn view(&self, only: Option<usize>) -> View {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let pick: Vec<&BodyFrame> = match only {
            Some(k) => vec![&self.frames[k]],
            None => self.frames.iter().collect(),
        };
        for f in pick {
            f.model.extent(&mut lo, &mut hi);
            f.measured.extent(&mut lo, &mut hi);
        }
        if !(lo[0].is_finite() && hi[0].is_finite()) {
            lo = [0.0, 0.0];
            hi = [1.0, 1.0];
        }
        let (gx0, gx1) = (self.ground_y(lo[0] - 0.15), self.ground_y(hi[0] + 0.15));
        let x0 = lo[0] - 0.15;
        let x1 = hi[0] + 0.15;
        let y0 = lo[1].min(gx0).min(gx1) - 0.05;
        let y1 = hi[1] + 0.05;
        View {
            x0,
            y1,
            width: (x1 - x0) * SCALE,
            height: (y1 - y0) * SCALE,
        }
    }

    fn ground_svg(&self, v: &View, out: &mut String) {
        let xa = v.x0;
        let xb = v.x0 + v.width / SCALE;
        let (a, b) = (v.p([xa, self.ground_y(xa)]), v.p([xb, self.ground_y(xb)]));
        writeln!(
            out,
            r##"<line class="ground" x1="{}" y1="{}" x2="{}" y2="{}" stroke="#5d4037" stroke-width="1.5"/>"##,
            px(a.0),
            px(a.1),
            px(b.0),
            px(b.1)
        )
        .ok();
    }

    fn pose_svg(v: &View, pose: &Pose, model: bool, out: &mut String) {
        let class = if model { "model" } else { "measured" };
        for l in &pose.lines {
            let pts: Vec<String> = l
                .iter()
                .map(|&p| v.p(p))
                .map(|(x, y)| format!("{},{}", px(x), px(y)))
                .collect();
            if model {
                writeln!(out, r##"<polyline class="model-body" points="{}" fill="none" stroke="#1d232b" stroke-width="3" stroke-linejoin="round" stroke-linecap="round"/>"##, pts.join(" ")).ok();
            } else {
                writeln!(out, r##"<polyline class="measured-body" points="{}" fill="none" stroke="#8a94a3" stroke-width="2" stroke-dasharray="5 3" stroke-linejoin="round"/>"##, pts.join(" ")).ok();
            }
        }
        for (side, o) in &pose.outlines {
            let stroke = if model { SIDE_COLOUR[*side] } else { "#8a94a3" };
            let common = format!(
                r#"class="{class}-primitive {}" fill="none" stroke="{stroke}" stroke-width="{}""#,
                SIDE_CLASS[*side],
                if model { 1.6 } else { 1.0 }
            );
            match *o {
                Outline::Ellipse {
                    centre,
                    semi_axes,
                    angle,
                } => {
                    let (cx, cy) = v.p(centre);
                    let deg = -angle.to_degrees();
                    writeln!(
                        out,
                        r#"<ellipse {common} cx="{}" cy="{}" rx="{}" ry="{}" transform="rotate({} {} {})"/>"#,
                        px(cx),
                        px(cy),
                        px(semi_axes[0] * SCALE),
                        px(semi_axes[1] * SCALE),
                        (deg * 1e4).round() / 1e4,
                        px(cx),
                        px(cy)
                    )
                    .ok();
                }
                Outline::Circle { centre, radius } => {
                    let (cx, cy) = v.p(centre);
                    writeln!(
                        out,
                        r#"<circle {common} cx="{}" cy="{}" r="{}"/>"#,
                        px(cx),
                        px(cy),
                        px(radius * SCALE)
                    )
                    .ok();
                }
                Outline::Point { at } => {
                    let (cx, cy) = v.p(at);
                    writeln!(
                        out,
                        r#"<circle {common} cx="{}" cy="{}" r="2"/>"#,
                        px(cx),
                        px(cy)
                    )
                    .ok();
                }
            }
        }
    }

    fn frame_svg(&self, v: &View, f: &BodyFrame, out: &mut String) {
        Self::pose_svg(v, &f.measured, false, out);
        Self::pose_svg(v, &f.model, true, out);
        for s in 0..2 {
            for (model, cop, grf) in [
                (false, f.cop_measured[s], f.grf_measured[s]),
                (true, f.cop_model[s], f.grf_model[s]),
            ] {
                let Some(x) = cop.filter(|x| x.is_finite()) else {
                    continue;
                };
                let at = [x, self.ground_y(x)];
                let (cx, cy) = v.p(at);
                let kind = if model { "model" } else { "measured" };
                if grf.iter().all(|g| g.is_finite()) {
                    let (ex, ey) =
                        v.p([at[0] + grf[0] * FORCE_LENGTH, at[1] + grf[1] * FORCE_LENGTH]);
                    writeln!(
                        out,
                        r#"<line class="grf-{kind} {}" x1="{}" y1="{}" x2="{}" y2="{}" stroke="{}" stroke-width="{}"{}/>"#,
                        SIDE_CLASS[s],
                        px(cx),
                        px(cy),
                        px(ex),
                        px(ey),
                        if model { SIDE_COLOUR[s] } else { "#8a94a3" },
                        if model { 2.5 } else { 1.5 },
                        if model { "" } else { r#" stroke-dasharray="4 3""# }
                    )
                    .ok();
                }
                if model {
                    writeln!(
                        out,
                        r#"<circle class="cop-model {}" cx="{}" cy="{}" r="3.5" fill="{}"/>"#,
                        SIDE_CLASS[s],
                        px(cx),
                        px(cy),
                        SIDE_COLOUR[s]
                    )
                    .ok();
                } else {
                    writeln!(out, r##"<circle class="cop-measured {}" cx="{}" cy="{}" r="4.5" fill="none" stroke="#5b6573" stroke-width="1.2"/>"##, SIDE_CLASS[s], px(cx), px(cy)).ok();
                }
            }
        }
    }

    fn label(&self, k: usize) -> String {
        let f = &self.frames[k];
        let key = self
            .keys
            .iter()
            .find(|kf| kf.frame == k)
            .map(|kf| format!(" — {} ({})", kf.name, ["right", "left"][kf.side]))
            .unwrap_or_default();
        format!("{:.3} s, {:.1} % of the cycle{key}", f.t, f.percent)
    }

    /// The animation as an HTML fragment: an SVG with one group per frame, play/pause,
    /// a scrubber, the frame's time, and the script that drives them.
    pub fn to_html(&self) -> String {
        let mut out = String::new();
        if self.frames.is_empty() {
            return out;
        }
        let v = self.view(None);
        writeln!(
            out,
            r#"<div class="anim" id="body-animation" data-frame="0" data-frames="{}">"#,
            self.frames.len()
        )
        .ok();
        writeln!(
            out,
            r#"<div class="anim-controls"><button type="button" class="anim-play">Play</button> <input type="range" class="anim-scrub" min="0" max="{}" value="0" step="1" aria-label="frame"> <span class="anim-label">{}</span></div>"#,
            self.frames.len() - 1,
            escape_xml(&self.label(0))
        )
        .ok();
        writeln!(
            out,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" aria-label="the model over the measured pose">"#,
            w = px(v.width),
            h = px(v.height)
        )
        .ok();
        writeln!(
            out,
            r##"<rect width="{}" height="{}" fill="#ffffff"/>"##,
            px(v.width),
            px(v.height)
        )
        .ok();
        self.ground_svg(&v, &mut out);
        for (k, f) in self.frames.iter().enumerate() {
            let key = self.keys.iter().find(|kf| kf.frame == k);
            writeln!(
                out,
                r#"<g class="frame{}" data-index="{k}" data-t="{}" data-percent="{:.2}" data-label="{}"{}>"#,
                if k == 0 { " on" } else { "" },
                f.t,
                f.percent,
                escape_xml(&self.label(k)),
                key.map_or(String::new(), |kf| format!(r#" data-key="{}" data-side="{}""#, kf.name, kf.side))
            )
            .ok();
            self.frame_svg(&v, f, &mut out);
            out.push_str("</g>\n");
        }
        out.push_str("</svg>\n</div>\n");
        out.push_str(SCRIPT);
        out
    }

    /// The key instants side by side as one static SVG, each with its caption.
    pub fn film_strip(&self) -> String {
        let panels: Vec<(View, &KeyFrame)> = self
            .keys
            .iter()
            .map(|kf| (self.view(Some(kf.frame)), kf))
            .collect();
        let height = panels.iter().map(|(v, _)| v.height).fold(0.0, f64::max) + 28.0;
        let width: f64 = panels.iter().map(|(v, _)| v.width).sum::<f64>().max(1.0);
        let mut out = String::new();
        writeln!(
            out,
            r#"<svg xmlns="http://www.w3.org/2000/svg" class="film-strip" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" aria-label="key instants of the gait" font-family="DejaVu Sans, Liberation Sans, Arial, Helvetica, sans-serif">"#,
            w = px(width),
            h = px(height)
        )
        .ok();
        writeln!(
            out,
            r##"<rect width="{}" height="{}" fill="#ffffff"/>"##,
            px(width),
            px(height)
        )
        .ok();
        let mut x = 0.0;
        for (v, kf) in &panels {
            let f = &self.frames[kf.frame];
            writeln!(
                out,
                r#"<svg x="{}" y="28" width="{}" height="{}" viewBox="0 0 {} {}"><g class="panel" data-index="{}" data-key="{}" data-side="{}">"#,
                px(x),
                px(v.width),
                px(v.height),
                px(v.width),
                px(v.height),
                kf.frame,
                kf.name,
                kf.side
            )
            .ok();
            self.ground_svg(v, &mut out);
            self.frame_svg(v, f, &mut out);
            out.push_str("</g></svg>\n");
            writeln!(
                out,
                r##"<text x="{}" y="18" font-size="13" text-anchor="middle" fill="#222222">{} ({}), {:.0} %</text>"##,
                px(x + v.width / 2.0),
                kf.name,
                ["right", "left"][kf.side],
                f.percent
            )
            .ok();
            x += v.width;
        }
        out.push_str("</svg>\n");
        out
    }
}

/// Plays, pauses and scrubs every `.anim` figure; `#frame=N` and `#play` in the address
/// choose the start.
const SCRIPT: &str = r#"<script>
(function () {
  document.querySelectorAll('.anim').forEach(function (a) {
    var frames = a.querySelectorAll('.frame'), scrub = a.querySelector('.anim-scrub');
    var button = a.querySelector('.anim-play'), label = a.querySelector('.anim-label'), timer = null;
    function show(k) {
      k = ((k % frames.length) + frames.length) % frames.length;
      frames.forEach(function (f, i) { f.classList.toggle('on', i === k); });
      scrub.value = k; a.dataset.frame = k; label.textContent = frames[k].dataset.label;
    }
    function play() {
      if (timer) return;
      button.textContent = 'Pause'; a.dataset.playing = '1';
      timer = setInterval(function () { show(+a.dataset.frame + 1); }, 40);
    }
    function pause() { clearInterval(timer); timer = null; button.textContent = 'Play'; a.dataset.playing = '0'; }
    button.addEventListener('click', function () { if (timer) pause(); else play(); });
    scrub.addEventListener('input', function () { pause(); show(+scrub.value); });
    var m = /frame=(\d+)/.exec(location.hash);
    show(m ? +m[1] : 0);
    if (/solo/.test(location.hash)) document.body.replaceChildren(a);
    else if (m) a.scrollIntoView();
    if (/play/.test(location.hash)) play();
  });
})();
</script>
"#;
