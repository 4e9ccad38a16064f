//! The gait report as a researcher opens it, rendered by headless Chromium: a plot for
//! every channel of the cost (velocities included), percent of the gait cycle on the x
//! axis, the phase legend, the body animation (its controls, a frame advancing when
//! played, screenshots of the key instants with the foot touching the ground at its
//! CoP, checked from the drawn geometry), and two runs side by side.
//!
//! The run is the bundled trial's converged ellipse-foot track (`tests/data/hidden/base`)
//! re-written by the tracking workflow without iterating (as `track --max-iter 0`), and
//! its double-circle twin for the comparison.
//! Set `FOOTFALL_REPORT_OUT=DIR` to keep the screenshots.

use crate::common;

use common::chromium;
use footfall::runfolder::RunFolder;
use footfall::workflows::track::{track, TrackRequest};
use footfall::workflows::Quiet;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn footfall(args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_footfall"))
        .current_dir(root())
        .args(args)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "footfall {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The run folder of a kept solution, re-written by the tracking workflow without
/// iterating (`track --init FROM --max-iter 0`), as it is: the report is the subject here,
/// so no check points are added (the ellipse's kept solution lets the ground pull a foot
/// between two nodes, which its report shows).
fn rewrite(from: &Path, foot: &str, out: &Path) {
    let mut req = TrackRequest::new(foot);
    req.init = Some(from.to_path_buf());
    req.check_points = false;
    req.sqp.max_iter = 0;
    let folder = RunFolder::create(out, false).unwrap();
    let run = track(&req, folder, &Quiet).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(run.converged, "{}", run.result.status);
}

const TIMEOUT: Duration = Duration::from_secs(90);

fn dom(page: &Path, hash: &str, virtual_ms: u32) -> String {
    String::from_utf8(chromium(
        &[
            format!("--virtual-time-budget={virtual_ms}"),
            "--dump-dom".into(),
            format!("file://{}{hash}", page.display()),
        ],
        TIMEOUT,
    ))
    .unwrap()
}

/// The value of attribute `name` in the tag `tag` (its text from `<` to `>`).
fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    Some(tag[i..i + tag[i..].find('"')?].to_string())
}

fn num(tag: &str, name: &str) -> f64 {
    attr(tag, name)
        .unwrap_or_else(|| panic!("no {name} in {tag}"))
        .parse()
        .unwrap()
}

/// Every tag `<name …>` in `text`.
fn tags<'a>(text: &'a str, name: &str) -> Vec<&'a str> {
    let open = format!("<{name} ");
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find(&open) {
        let end = rest[i..].find('>').unwrap() + i + 1;
        out.push(&rest[i..end]);
        rest = &rest[end..];
    }
    out
}

/// The body of the element that starts with the tag at `start` (a `<g>`, to its `</g>`).
fn group(text: &str, start: usize) -> &str {
    let end = text[start..].find("</g>").unwrap() + start;
    &text[start..end]
}

/// Signed distance (px, positive below the line, SVG y pointing down) of the lowest point
/// of the drawn primitive `tag` from the ground line, and that point's x.
fn lowest_point(tag: &str, ground: &str) -> (f64, f64) {
    let (gx1, gy1, gx2, gy2) = (
        num(ground, "x1"),
        num(ground, "y1"),
        num(ground, "x2"),
        num(ground, "y2"),
    );
    let ground_y = |x: f64| gy1 + (gy2 - gy1) * (x - gx1) / (gx2 - gx1);
    let (cx, cy) = (num(tag, "cx"), num(tag, "cy"));
    let (rx, ry, a) = if tag.starts_with("<ellipse") {
        let t = attr(tag, "transform").unwrap();
        let deg: f64 = t["rotate(".len()..]
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        (num(tag, "rx"), num(tag, "ry"), deg.to_radians())
    } else {
        (num(tag, "r"), num(tag, "r"), 0.0)
    };
    let mut best = (f64::NEG_INFINITY, 0.0);
    for k in 0..20_000 {
        let t = k as f64 / 20_000.0 * std::f64::consts::TAU;
        let (u, v) = (rx * t.cos(), ry * t.sin());
        let (x, y) = (
            cx + u * a.cos() - v * a.sin(),
            cy + u * a.sin() + v * a.cos(),
        );
        let d = y - ground_y(x);
        if d > best.0 {
            best = (d, x);
        }
    }
    best
}

#[test]
fn the_report_shows_what_the_cost_sees_and_the_body_moving() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("ellipse");
    let twin = tmp.path().join("double_circle");
    let base = root().join("tests/data/hidden/base");
    rewrite(&base, "ellipse", &run);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    let page = run.join("report.html");
    let size = std::fs::metadata(&page).unwrap().len();
    assert!(size < 2_000_000, "report.html is {size} bytes");
    eprintln!("report.html: {:.0} kB", size as f64 / 1e3);

    // played for 2 s of virtual time from `#play`, the animation has advanced
    let d = dom(&page, "#play", 2000);
    let anim = tags(&d, "div")
        .into_iter()
        .find(|t| t.contains("id=\"body-animation\""))
        .expect("the animation is in the DOM");
    let frames: usize = attr(anim, "data-frames").unwrap().parse().unwrap();
    let shown: usize = attr(anim, "data-frame").unwrap().parse().unwrap();
    assert!(frames > 40, "{frames} frames");
    assert!(shown > 5, "played, the animation shows frame {shown}");
    assert!(d.contains("class=\"anim-play\"") && d.contains(">Pause</button>"));
    assert!(tags(&d, "input")
        .iter()
        .any(|t| t.contains("class=\"anim-scrub\"") && t.contains("type=\"range\"")));

    // a plot for every channel of the cost: the angle and the velocity of every tracked
    // coordinate, both ground forces, the CoP, the actuators' excitations and activations
    let titles: Vec<String> = tags(&d, "svg")
        .iter()
        .filter_map(|t| attr(t, "aria-label"))
        .collect();
    let has = |t: &str| titles.iter().any(|x| x == t);
    let channels = summary["cost_breakdown"]["channels"].as_array().unwrap();
    assert!(channels.len() >= 10, "{channels:?}");
    let angles: Vec<&str> = channels
        .iter()
        .filter_map(|c| c.as_str())
        .filter(|c| c.contains('_'))
        .collect();
    for c in channels.iter().map(|c| c.as_str().unwrap()) {
        let wanted: Vec<String> = match c {
            "velocities" => angles.iter().map(|a| velocity_title(a)).collect(),
            "excitations" => vec![
                "hip excitations".into(),
                "knee excitations".into(),
                "ankle excitations".into(),
            ],
            "activations" => vec![
                "hip activations".into(),
                "knee activations".into(),
                "ankle activations".into(),
            ],
            "normal GRF" | "tangential GRF" | "CoP" => vec![c.to_string()],
            a => vec![angle_title(a)],
        };
        for w in wanted {
            assert!(
                has(&w),
                "cost channel {c}: no plot titled {w:?} in {titles:?}"
            );
        }
    }
    for joint in ["hip", "knee", "ankle"] {
        assert!(has(&format!("{joint} torques")), "{titles:?}");
    }
    // gait conventions: percent of the cycle, the trial's clock on top, left and right
    // overlaid, the residual band
    assert!(d.contains(">% of gait cycle (each leg from its heel strike)</text>"));
    assert!(
        d.contains(">trial time (s) of each leg's part</text>")
            || d.contains(">trial time (s) of each leg&#39;s part</text>")
    );
    assert!(
        d.contains("<title>right, measured</title>") && d.contains("<title>left, measured</title>")
    );
    assert!(d.contains("<title>residual</title>"));
    // the phase legend names every phase, its contacts and what begins and ends it
    let legend_at = d.find("Phases of ellipse_walk").expect("phase legend");
    let legend = &d[legend_at..legend_at + d[legend_at..].find("</table>").unwrap()];
    for text in [
        "1e*",
        "2e",
        "3e",
        "4e*",
        "r.sole, l.sole",
        "r.sole lifts off",
        "impact 4e*: r.sole lands",
        "instantaneous",
    ] {
        assert!(
            legend.contains(text),
            "{text:?} not in the phase legend: {legend}"
        );
    }

    // the key instants: shown alone with `#frame=K,solo`, the foot of the instant touches
    // the ground line at its drawn CoP, within drawing precision (coordinates rounded to
    // 0.1 px at 300 px per metre)
    let html = std::fs::read_to_string(&page).unwrap();
    let keys: Vec<(usize, String, usize)> = tags(&html, "g")
        .iter()
        .filter(|t| t.contains("class=\"frame") && t.contains("data-key="))
        .map(|t| {
            (
                attr(t, "data-index").unwrap().parse().unwrap(),
                attr(t, "data-key").unwrap(),
                attr(t, "data-side").unwrap().parse().unwrap(),
            )
        })
        .collect();
    let mut names: Vec<&str> = keys.iter().map(|k| k.1.as_str()).collect();
    names.sort();
    assert_eq!(
        names,
        ["heel strike", "mid-stance", "toe-off"],
        "key instants"
    );
    let keep = std::env::var_os("FOOTFALL_REPORT_OUT").map(PathBuf::from);
    for (k, name, side) in &keys {
        let hash = format!("#frame={k},solo");
        let d = dom(&page, &hash, 200);
        let at = d
            .find(&format!("class=\"frame on\" data-index=\"{k}\""))
            .unwrap_or_else(|| panic!("{name}: frame {k} is not the one shown"));
        let frame = group(&d, at);
        let ground = tags(&d, "line")
            .into_iter()
            .find(|t| t.contains("class=\"ground\""))
            .unwrap();
        let class = ["side-r", "side-l"][*side];
        let cop = tags(frame, "circle")
            .into_iter()
            .find(|t| t.contains(&format!("class=\"cop-model {class}\"")))
            .unwrap_or_else(|| panic!("{name}: no model CoP of the {class} foot"));
        let prims: Vec<&str> = tags(frame, "ellipse")
            .into_iter()
            .chain(tags(frame, "circle"))
            .filter(|t| t.contains(&format!("class=\"model-primitive {class}\"")))
            .collect();
        assert!(!prims.is_empty(), "{name}: no primitive of the foot drawn");
        let (gap, x) = prims
            .iter()
            .map(|p| lowest_point(p, ground))
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap();
        let cop_x = num(cop, "cx");
        eprintln!("{name}: foot {gap:+.3} px from the ground, touching at x = {x:.2} px, CoP at {cop_x:.2} px");
        assert!(
            gap.abs() < 0.3,
            "{name}: the foot is {gap:.2} px off the ground"
        );
        assert!(
            (x - cop_x).abs() < 0.5,
            "{name}: the foot touches at x = {x:.2} px, its CoP is at {cop_x:.2} px"
        );

        let png = tmp.path().join(format!("{}.png", name.replace(' ', "_")));
        chromium(
            &[
                format!("--screenshot={}", png.display()),
                "--window-size=900,900".into(),
                format!("file://{}{hash}", page.display()),
            ],
            TIMEOUT,
        );
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        assert!(
            bytes.len() > 10_000,
            "{name}: screenshot of {} bytes",
            bytes.len()
        );
        if let Some(dir) = &keep {
            std::fs::create_dir_all(dir).unwrap();
            std::fs::copy(&png, dir.join(png.file_name().unwrap())).unwrap();
        }
    }
    // the film strip of the same instants is written for print and the README
    let strip = std::fs::read_to_string(run.join("film_strip.svg")).unwrap();
    assert_eq!(strip.matches("class=\"panel\"").count(), 3);

    // two runs side by side: both runs' curves on each plot, errors next to each other
    rewrite(
        &root().join("tests/data/hidden/double_circle_base"),
        "double-circle",
        &twin,
    );
    let both = tmp.path().join("both");
    footfall(&[
        "report",
        run.to_str().unwrap(),
        twin.to_str().unwrap(),
        "--out",
        both.to_str().unwrap(),
    ]);
    let d = dom(&both.join("report.html"), "", 100);
    for plot in ["knee angle", "knee angular velocity", "normal GRF", "CoP"] {
        let at = d
            .find(&format!("aria-label=\"{plot}\""))
            .unwrap_or_else(|| panic!("no {plot} plot side by side"));
        let svg = &d[at..at + d[at..].find("</svg>").unwrap()];
        // a run whose verdict is not "converged" is labelled with it (the ellipse's kept
        // solution: "converged, physically invalid")
        for name in ["ellipse", "double_circle"] {
            assert!(
                svg.contains(&format!(">{name}</text>")) || svg.contains(&format!(">{name} (")),
                "{plot}: no curve of {name}"
            );
        }
        assert!(
            svg.contains(">measured (ellipse)</text>"),
            "{plot}: no measurement"
        );
    }
    let table_at = d.find("Errors at the shooting nodes").unwrap();
    let table = &d[table_at..table_at + d[table_at..].find("</table>").unwrap()];
    assert!(
        table.contains(">ellipse<")
            && table.contains(">double_circle<")
            && table.contains("knee angle")
    );
}

/// The plot title of an angle channel of the cost (`hip_r` → `hip angle`).
fn angle_title(c: &str) -> String {
    match c.split('_').next().unwrap() {
        j @ ("hip" | "knee" | "ankle") => format!("{j} angle"),
        _ => c.replace('_', " "),
    }
}

/// The plot title of the velocity of an angle channel.
fn velocity_title(c: &str) -> String {
    match c.split('_').next().unwrap() {
        j @ ("hip" | "knee" | "ankle") => format!("{j} angular velocity"),
        _ => format!("{} velocity", c.replace('_', " ")),
    }
}
