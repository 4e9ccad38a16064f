//! The report layer: SVG plots (well-formed, deterministic, NaN gaps, nice ticks), error
//! statistics against hand-computed values, tables in Markdown/CSV/HTML, CSV and `.sto`
//! time series (a `.sto` round trip), and `report.html` rendered by headless Chromium
//! (every plot present in the DOM, a non-empty PNG screenshot).
//!
//! The Chromium test needs Debian's `chromium` (`tools/setup` installs it) and fails,
//! rather than passes silently, when it is missing. Set `FOOTFALL_REPORT_OUT=DIR` to keep
//! the rendered `report.html` and `report.png` in DIR for a look.

use crate::common;

use footfall::data::{parse_storage, DataError};
use footfall::report::csv::TimeSeries;
use footfall::report::html::{Report, Section, Summary, Tone};
use footfall::report::plot::{
    grid, nice_step, nice_ticks, tick_labels, LinePlot, LineStyle, Series, Span,
};
use footfall::report::table::{error_table, ChannelErrors, ErrorStats, Table};
use footfall::report::ReportError;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

// ---------------------------------------------------------------------------------------
// A tiny well-formedness check for the XML we write (and for HTML with void elements).

/// Check that `doc` is well-formed: tags balanced and properly nested, attribute values
/// quoted, no bare `<` or `&` in text. `void` lists element names that never close (HTML).
fn check_well_formed(doc: &str, void: &[&str]) -> Result<(), String> {
    let b = doc.as_bytes();
    let mut stack: Vec<String> = Vec::new();
    let mut i = 0;
    let check_text = |text: &str, at: usize| -> Result<(), String> {
        let mut rest = text;
        while let Some(p) = rest.find('&') {
            let after = &rest[p + 1..];
            let end = after.find(';').ok_or(format!("bare & at byte {at}"))?;
            let ent = &after[..end];
            let ok = matches!(ent, "amp" | "lt" | "gt" | "quot" | "apos")
                || (ent.starts_with('#')
                    && ent.len() > 1
                    && ent[1..].chars().all(|c| c.is_ascii_digit()));
            if !ok {
                return Err(format!("bad entity &{ent}; near byte {at}"));
            }
            rest = &after[end + 1..];
        }
        Ok(())
    };
    while i < b.len() {
        if b[i] != b'<' {
            let next = doc[i..].find('<').map_or(b.len(), |p| i + p);
            check_text(&doc[i..next], i)?;
            if doc[i..next].contains('>') {
                return Err(format!("bare > in text at byte {i}"));
            }
            i = next;
            continue;
        }
        let rest = &doc[i..];
        if rest.starts_with("<!--") {
            i += rest.find("-->").ok_or("unclosed comment")? + 3;
            continue;
        }
        if rest.starts_with("<?") || rest.starts_with("<!") {
            i += rest.find('>').ok_or("unclosed declaration")? + 1;
            continue;
        }
        // A tag: find its end, respecting quotes.
        let mut j = 1;
        let mut quote: Option<u8> = None;
        while i + j < b.len() {
            let c = b[i + j];
            match quote {
                Some(q) if c == q => quote = None,
                Some(_) => {}
                None if c == b'"' || c == b'\'' => quote = Some(c),
                None if c == b'<' => return Err(format!("< inside a tag at byte {}", i + j)),
                None if c == b'>' => break,
                None => {}
            }
            j += 1;
        }
        if i + j >= b.len() {
            return Err(format!("unterminated tag at byte {i}"));
        }
        let inner = &doc[i + 1..i + j];
        i += j + 1;
        if let Some(name) = inner.strip_prefix('/') {
            let name = name.trim();
            match stack.pop() {
                Some(open) if open == name => {}
                Some(open) => return Err(format!("</{name}> closes <{open}>")),
                None => return Err(format!("</{name}> with nothing open")),
            }
            continue;
        }
        let self_closing = inner.ends_with('/');
        let inner = inner.trim_end_matches('/');
        let name: String = inner.chars().take_while(|c| !c.is_whitespace()).collect();
        if name.is_empty()
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == ':')
        {
            return Err(format!("bad tag name {name:?}"));
        }
        // Attributes: name="value" pairs.
        let mut attrs = inner[name.len()..].trim();
        while !attrs.is_empty() {
            let eq = attrs
                .find('=')
                .ok_or(format!("attribute without value in <{name}>"))?;
            let key = attrs[..eq].trim();
            if key.is_empty() || key.contains(char::is_whitespace) {
                return Err(format!("bad attribute {key:?} in <{name}>"));
            }
            let v = attrs[eq + 1..].trim_start();
            let q = v.chars().next().ok_or("missing value")?;
            if q != '"' && q != '\'' {
                return Err(format!("unquoted attribute {key} in <{name}>"));
            }
            let end = v[1..].find(q).ok_or("unclosed attribute")?;
            check_text(&v[1..1 + end], i)?;
            attrs = v[end + 2..].trim_start();
        }
        if !self_closing && !void.contains(&name.as_str()) {
            stack.push(name);
        }
    }
    match stack.last() {
        Some(open) => Err(format!("<{open}> never closed")),
        None => Ok(()),
    }
}

const HTML_VOID: [&str; 4] = ["meta", "br", "hr", "img"];

#[test]
fn well_formedness_checker_catches_errors() {
    assert!(check_well_formed("<a x=\"1\"><b/>t &amp; u</a>", &[]).is_ok());
    assert!(check_well_formed("<a><b></a></b>", &[]).is_err());
    assert!(check_well_formed("<a>", &[]).is_err());
    assert!(check_well_formed("<a x=1></a>", &[]).is_err());
    assert!(check_well_formed("<a>x & y</a>", &[]).is_err());
    assert!(check_well_formed("<a>x < y</a>", &[]).is_err());
}

// ---------------------------------------------------------------------------------------
// Plots.

/// A gait-like figure: model (solid), measurement (markers, with gaps), a dashed bound,
/// four phases.
fn sample_plot(title: &str) -> LinePlot {
    let t: Vec<f64> = (0..=120).map(|i| i as f64 * 0.01).collect();
    let model: Vec<f64> = t
        .iter()
        .map(|t| 700.0 * (std::f64::consts::PI * t / 0.8).sin().max(0.0))
        .collect();
    let tm: Vec<f64> = (0..=72).map(|i| i as f64 / 60.0).collect();
    let meas: Vec<f64> = tm
        .iter()
        .enumerate()
        .map(|(i, t)| {
            if (20..24).contains(&i) {
                f64::NAN
            } else {
                690.0 * (std::f64::consts::PI * t / 0.8).sin().max(0.0) + 15.0
            }
        })
        .collect();
    let mut p = LinePlot::new(title, "time (s)", "normal force (N)");
    p.series
        .push(Series::new("model", t.clone(), model, LineStyle::Solid));
    p.series
        .push(Series::new("measured", tm, meas, LineStyle::Markers));
    p.series.push(Series::new(
        "bound",
        vec![0.0, 1.2],
        vec![800.0, 800.0],
        LineStyle::Dashed,
    ));
    p.shaded = vec![
        Span::new(0.0, 0.12, "1e heel"),
        Span::new(0.12, 0.5, "2e flat foot"),
        Span::new(0.5, 0.53, "3e toe"),
        Span::new(0.53, 0.8, "4e push-off"),
    ];
    p
}

/// The `d` attribute of the path whose tooltip is `name`.
fn series_path<'a>(svg: &'a str, name: &str) -> Option<&'a str> {
    let end = svg.find(&format!("><title>{name}</title></path>"))?;
    let start = svg[..end].rfind("<path d=\"")? + 9;
    let len = svg[start..].find('"')?;
    Some(&svg[start..start + len])
}

#[test]
fn svg_is_well_formed_and_deterministic() {
    let p = sample_plot("normal GRF <right> & \"left\"");
    let svg = p.to_svg();
    check_well_formed(&svg, &[]).unwrap();
    assert_eq!(svg, p.to_svg());
    assert_eq!(svg, p.clone().to_svg());
    assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
    assert!(svg.contains("normal GRF &lt;right&gt; &amp; &quot;left&quot;"));
    for label in [
        "1e heel",
        "2e flat foot",
        "3e toe",
        "4e push-off",
        "model",
        "measured",
        "time (s)",
        "normal force (N)",
    ] {
        assert!(svg.contains(&format!(">{label}<")), "{label} missing");
    }
    assert!(
        !svg.contains("NaN") && !svg.contains("inf"),
        "a non-finite number leaked into the SVG"
    );
    let g = grid(&[sample_plot("a"), sample_plot("b"), sample_plot("c")], 2);
    check_well_formed(&g, &[]).unwrap();
    assert_eq!(g.matches("<svg").count(), 4);
    assert!(g.contains("width=\"1280\" height=\"720\""));
}

#[test]
fn nan_breaks_lines_and_is_never_drawn_as_zero() {
    let x = vec![0.0, 1.0, 2.0, 3.0, 4.0];
    let mut p = LinePlot::new("gaps", "x", "y");
    p.series.push(Series::new(
        "a",
        x.clone(),
        vec![10.0, 11.0, f64::NAN, 13.0, 14.0],
        LineStyle::Solid,
    ));
    p.series.push(Series::new(
        "b",
        x.clone(),
        vec![10.0, f64::NAN, 12.0, f64::NAN, 14.0],
        LineStyle::Dashed,
    ));
    p.series.push(Series::new(
        "c",
        x.clone(),
        vec![10.0, f64::INFINITY, 12.0, 13.0, 14.0],
        LineStyle::Markers,
    ));
    let svg = p.to_svg();
    check_well_formed(&svg, &[]).unwrap();
    // Two pieces of one segment each.
    let a = series_path(&svg, "a").unwrap();
    assert_eq!(
        (a.matches('M').count(), a.matches('L').count()),
        (2, 2),
        "{a}"
    );
    // Three isolated points, drawn as dots, no segment.
    let b = series_path(&svg, "b").unwrap();
    assert_eq!(
        (
            b.matches('M').count(),
            b.matches('L').count(),
            b.matches("h0").count()
        ),
        (3, 0, 3),
        "{b}"
    );
    // Four markers (the infinite sample is left out).
    let c = series_path(&svg, "c").unwrap();
    assert_eq!(c.matches('M').count(), 4, "{c}");
    // The y axis spans the finite data only (10…14), so 0 is not even on it.
    assert!(
        !svg.contains("text-anchor=\"end\" fill=\"#333333\">0<"),
        "a zero y tick means NaN was taken as 0"
    );
    assert!(svg.contains("text-anchor=\"end\" fill=\"#333333\">10<"));

    let mut empty = LinePlot::new("nothing", "x", "y");
    empty.series.push(Series::new(
        "all NaN",
        vec![0.0, 1.0],
        vec![f64::NAN, f64::NAN],
        LineStyle::Solid,
    ));
    let svg = empty.to_svg();
    check_well_formed(&svg, &[]).unwrap();
    assert!(svg.contains(">no data<"));
    assert!(series_path(&svg, "all NaN").is_none());
}

#[test]
fn explicit_ranges_clip_lines() {
    let mut p = LinePlot::new("clip", "x", "y");
    p.series.push(Series::new(
        "a",
        vec![0.0, 2.0],
        vec![0.0, 2.0],
        LineStyle::Solid,
    ));
    p.x_range = Some((0.0, 1.0));
    p.y_range = Some((0.0, 1.0));
    let svg = p.to_svg();
    let d = series_path(&svg, "a").unwrap();
    // The segment ends at the frame's top-right corner, not beyond it.
    let frame = svg
        .split("<rect ")
        .find(|r| r.contains("fill=\"none\" stroke=\"#333333\""))
        .unwrap();
    let num = |key: &str| -> f64 {
        let s = &frame[frame.find(&format!("{key}=\"")).unwrap() + key.len() + 2..];
        s[..s.find('"').unwrap()].parse().unwrap()
    };
    let (x, y, w) = (num("x"), num("y"), num("width"));
    assert!(
        d.ends_with(&format!("L{} {}", x + w, y)),
        "{d} vs frame {x} {y} {w}"
    );
}

#[test]
fn nice_ticks_and_labels() {
    assert_eq!(nice_step(0.23), 0.25);
    assert_eq!(nice_step(0.3), 0.5);
    assert_eq!(nice_step(1.0), 1.0);
    assert_eq!(nice_step(7.0), 10.0);
    assert_eq!(nice_step(1.1e-5), 2e-5);
    assert_eq!(nice_ticks(0.0, 1.0, 5), vec![0.0, 0.25, 0.5, 0.75, 1.0]);
    assert_eq!(
        nice_ticks(0.0, 1.2, 7),
        vec![0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2]
    );
    assert_eq!(nice_ticks(-3.0, 7.0, 6), vec![-2.0, 0.0, 2.0, 4.0, 6.0]);
    assert_eq!(nice_ticks(0.6182, 1.4086, 6), vec![0.8, 1.0, 1.2, 1.4]);
    assert_eq!(nice_ticks(2.0, 2.0, 5), vec![2.0]);
    assert!(nice_ticks(f64::NAN, 1.0, 5).is_empty());
    for (lo, hi) in [
        (0.0, 1.0),
        (-1e-6, 3e-6),
        (12.0, 7000.0),
        (-0.3, -0.1),
        (0.6182, 1.4086),
    ] {
        for target in 2..10 {
            let t = nice_ticks(lo, hi, target);
            assert!(t.len() <= target.max(2), "{lo} {hi} {target}: {t:?}");
            assert!(t.iter().all(|&v| v >= lo - 1e-12 && v <= hi + 1e-12));
            assert!(t.windows(2).all(|w| w[1] > w[0]));
        }
    }
    assert_eq!(
        tick_labels(&[0.0, 0.2, 0.6000000000000001, 1.2000000000000002], 0.2),
        ["0", "0.2", "0.6", "1.2"]
    );
    assert_eq!(
        tick_labels(&[-250.0, 0.0, 250.0], 250.0),
        ["\u{2212}250", "0", "250"]
    );
    assert_eq!(
        tick_labels(&[0.0, 2.5e-6, 5e-6], 2.5e-6),
        ["0", "2.5e-6", "5.0e-6"]
    );
    assert_eq!(tick_labels(&[0.0, 5e5, 1e6], 5e5), ["0", "0.5e6", "1.0e6"]);
}

#[test]
fn x_tick_labels_do_not_crowd_a_narrow_plot() {
    let mut p = sample_plot("narrow");
    p.width = 260.0;
    p.x_range = Some((0.6182, 1.4086));
    let svg = p.to_svg();
    // Tick labels sit on the baseline just below the frame: gather them.
    let frame_bottom = {
        let frame = svg
            .split("<rect ")
            .find(|r| r.contains("fill=\"none\" stroke=\"#333333\""))
            .unwrap();
        let num = |key: &str| -> f64 {
            let s = &frame[frame.find(&format!(" {key}=\"")).unwrap() + key.len() + 3..];
            s[..s.find('"').unwrap()].parse().unwrap()
        };
        num("y") + num("height")
    };
    let mut xs = Vec::new();
    for piece in svg.split("<text x=\"").skip(1) {
        let x: f64 = piece[..piece.find('"').unwrap()].parse().unwrap();
        let y: f64 = {
            let s = &piece[piece.find("y=\"").unwrap() + 3..];
            s[..s.find('"').unwrap()].parse().unwrap()
        };
        let text = &piece[piece.find('>').unwrap() + 1..piece.find("</text>").unwrap()];
        if (y - (frame_bottom + 17.0)).abs() < 0.11 {
            xs.push((x, text.chars().count() as f64 * 11.0 * 0.6));
        }
    }
    assert!(xs.len() >= 2, "{xs:?}");
    for w in xs.windows(2) {
        assert!(
            w[1].0 - w[1].1 / 2.0 - (w[0].0 + w[0].1 / 2.0) >= 8.0,
            "crowded tick labels {xs:?}"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Statistics and tables.

#[test]
fn error_stats_match_hand_computed_values() {
    // |e| = 1, 2, 3 (NaN ignored): mean 2, population sd sqrt(2/3), max 3.
    let s = ErrorStats::from_errors(&[1.0, -2.0, f64::NAN, 3.0]);
    assert_eq!(s.n, 3);
    assert_eq!(s.mean, 2.0);
    assert!((s.sd - (2.0f64 / 3.0).sqrt()).abs() < 1e-15);
    assert_eq!(s.max, 3.0);
    assert_eq!(s.cell(2), "2.00 ± 0.82 (max 3.00)");
    // Model − measurement, NaN in either side skipped, shorter length used.
    let p = ErrorStats::from_pair(&[0.1, 0.2, f64::NAN, 0.5, 9.0], &[0.0, 0.4, 0.3, f64::NAN]);
    assert_eq!(p.n, 2);
    assert!(
        (p.mean - 0.15).abs() < 1e-15 && (p.sd - 0.05).abs() < 1e-15 && (p.max - 0.2).abs() < 1e-15
    );
    let deg = ErrorStats::from_errors(&[std::f64::consts::PI]).scaled(180.0 / std::f64::consts::PI);
    assert!((deg.mean - 180.0).abs() < 1e-12 && deg.sd == 0.0);
    let none = ErrorStats::from_errors(&[f64::NAN]);
    assert_eq!(none.n, 0);
    assert!(none.mean.is_nan());
    assert_eq!(none.cell(1), "—");
}

#[test]
fn markdown_csv_and_html_tables() {
    let t = Table {
        title: "Peaks".into(),
        headers: vec!["foot".into(), "peak (N)".into(), "note".into()],
        rows: vec![
            vec!["right".into(), "1219.0".into(), "a|b".into()],
            vec!["left".into(), "595.6".into()],
        ],
    };
    assert_eq!(
        t.to_markdown(),
        "**Peaks**\n\n\
         | foot  | peak (N) | note |\n\
         |-------|----------|------|\n\
         | right | 1219.0   | a\\|b |\n\
         | left  | 595.6    |      |\n"
    );
    let t2 = Table {
        rows: vec![vec!["x, y".into(), "say \"hi\"".into(), "ok".into()]],
        ..t.clone()
    };
    assert_eq!(
        t2.to_csv(),
        "foot,peak (N),note\n\"x, y\",\"say \"\"hi\"\"\",ok\n"
    );
    let html = Table {
        rows: vec![vec!["<b>".into(), "1 & 2".into()]],
        ..t
    }
    .to_html();
    check_well_formed(&html, &[]).unwrap();
    assert!(html.contains("<caption>Peaks</caption>"));
    assert!(html.contains("<th scope=\"row\">&lt;b&gt;</th><td>1 &amp; 2</td><td></td>"));
}

#[test]
fn table_3_like_error_table() {
    let runs = vec!["ellipse".to_string(), "double circle".to_string()];
    let knee = ErrorStats::from_errors(&[0.01, 0.03]).scaled(180.0 / std::f64::consts::PI);
    let cop = ErrorStats::from_errors(&[0.01, 0.02, 0.03]).scaled(100.0);
    let t = error_table(
        "Tracking errors",
        &runs,
        &[
            ChannelErrors {
                name: "knee angle".into(),
                unit: "°".into(),
                decimals: 2,
                runs: vec![Some(knee), None],
            },
            ChannelErrors {
                name: "CoP".into(),
                unit: "cm".into(),
                decimals: 1,
                runs: vec![Some(cop), Some(cop)],
            },
        ],
    );
    assert_eq!(t.headers, ["error", "ellipse", "double circle"]);
    assert_eq!(t.rows[0], ["knee angle (°)", "1.15 ± 0.57 (max 1.72)", "—"]);
    assert_eq!(
        t.rows[1],
        ["CoP (cm)", "2.0 ± 0.8 (max 3.0)", "2.0 ± 0.8 (max 3.0)"]
    );
    let md = t.to_markdown();
    assert!(
        md.contains("| knee angle (°) | 1.15 ± 0.57 (max 1.72) | —                   |"),
        "{md}"
    );
}

// ---------------------------------------------------------------------------------------
// Time series.

#[test]
fn time_series_csv() {
    let mut ts = TimeSeries::new(vec![0.0, 0.001, 0.001]).unwrap();
    ts.push("knee_r", vec![-0.25, 1.0 / 3.0, f64::NAN]).unwrap();
    ts.push("cop_x_r", vec![f64::INFINITY, 0.1, 0.2]).unwrap();
    ts.push_text("phase", vec!["1e".into(), "2e, flat".into(), "3e".into()])
        .unwrap();
    assert_eq!(ts.names(), ["time", "knee_r", "cop_x_r", "phase"]);
    assert_eq!(
        ts.to_csv(),
        "time,knee_r,cop_x_r,phase\n\
         0.000000000e0,-2.500000000e-1,,1e\n\
         1.000000000e-3,3.333333333e-1,1.000000000e-1,\"2e, flat\"\n\
         1.000000000e-3,,2.000000000e-1,3e\n"
    );
}

#[test]
fn time_series_rejects_bad_input() {
    assert!(matches!(
        TimeSeries::new(vec![0.0, f64::NAN]),
        Err(ReportError::BadTime { row: 1, .. })
    ));
    assert!(matches!(
        TimeSeries::new(vec![0.1, 0.0]),
        Err(ReportError::BadTime { row: 1, .. })
    ));
    let mut ts = TimeSeries::new(vec![0.0, 1.0]).unwrap();
    assert!(matches!(
        ts.push("a", vec![1.0]),
        Err(ReportError::LengthMismatch {
            expected: 2,
            found: 1,
            ..
        })
    ));
    assert!(matches!(
        ts.push("time", vec![1.0, 2.0]),
        Err(ReportError::DuplicateColumn(_))
    ));
    assert!(matches!(
        ts.push("knee r", vec![1.0, 2.0]),
        Err(ReportError::BadColumnName { .. })
    ));
    assert!(matches!(
        ts.push("", vec![1.0, 2.0]),
        Err(ReportError::BadColumnName { .. })
    ));
    let msg = ts.push("a", vec![1.0]).unwrap_err().to_string();
    assert!(
        msg.contains("\"a\"") && msg.contains("1 values") && msg.contains("expected 2"),
        "{msg}"
    );
}

#[test]
fn sto_round_trip() {
    let time: Vec<f64> = (0..5).map(|i| 0.6182 + i as f64 * 1e-3).collect();
    let knee: Vec<f64> = time.iter().map(|t| -(t * 7.0).sin() / 3.0).collect();
    let grf = vec![0.0, 612.25, f64::NAN, 1e-12, -3.5e4];
    let mut ts = TimeSeries::new(time.clone()).unwrap();
    ts.push("knee_angle_r", knee.clone()).unwrap();
    ts.push_text("phase", vec!["1e".into(); 5]).unwrap();
    ts.push("grf_y_r", grf.clone()).unwrap();
    let text = ts.to_sto("footfall\ttracking");
    let head: Vec<&str> = text.lines().take(7).collect();
    assert_eq!(
        head,
        [
            "footfall tracking",
            "version=1",
            "nRows=5",
            "nColumns=3",
            "inDegrees=no",
            "endheader",
            "time\tknee_angle_r\tgrf_y_r"
        ]
    );
    // read back by the crate's one .sto reader, as a user reads the run's kinematics.sto
    let path = Path::new("kinematics.sto");
    let sto = parse_storage(&text, path).unwrap();
    assert_eq!(sto.name, "footfall tracking");
    assert!(!sto.in_degrees && sto.angle_unit_stated);
    assert_eq!(sto.columns, ["time", "knee_angle_r", "grf_y_r"]);
    assert_eq!(sto.len(), 5);
    let close = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .all(|(x, y)| (x.is_nan() && y.is_nan()) || (x - y).abs() <= 1e-9 * y.abs().max(1e-300))
    };
    assert!(close(sto.column("time").unwrap(), &time));
    assert!(close(sto.column("knee_angle_r").unwrap(), &knee));
    assert!(close(sto.column("grf_y_r").unwrap(), &grf));
    assert!(sto.column("phase").is_none());

    // A header that disagrees with the data, and a short row, are refused with the line.
    let bad = text.replace("nRows=5", "nRows=6");
    assert!(matches!(
        parse_storage(&bad, path),
        Err(DataError::Format { .. })
    ));
    let short = format!("{}1.0\t2.0\n", text);
    let e = parse_storage(&short, path).unwrap_err().to_string();
    assert!(e.contains("line 13"), "{e}");
    assert!(parse_storage("name\nversion=1\n", path).is_err());
}

// ---------------------------------------------------------------------------------------
// The HTML report and Chromium.

/// Angle-like and drift-like figures that exercise negative values, power-of-ten tick
/// labels and crowded phase labels (the seven double-circle phases in a narrow plot).
fn varied_plot(title: &str, kind: usize) -> LinePlot {
    let t: Vec<f64> = (0..=400).map(|i| 0.6182 + i as f64 * 0.002).collect();
    let tm: Vec<f64> = (0..=48).map(|i| 0.6182 + i as f64 / 60.0).collect();
    let f = |t: f64| match kind {
        0 => -180.0 * (9.0 * t).sin() + 40.0 * (23.0 * t).cos(),
        1 => 25.0 * (7.0 * t).sin() - 5.0,
        2 => -35.0 - 30.0 * (8.0 * t).cos(),
        3 => 10.0 * (3.0 * t).cos() - 5.0,
        _ => 3e-9 * (40.0 * t).sin() * (t - 0.6182),
    };
    let (y_label, names) = match kind {
        0 => ("tangential force (N)", ["model", "force plate"]),
        4 => (
            "drift φ (m)",
            [
                "position drift, right heel",
                "velocity drift × 1 s, right heel",
            ],
        ),
        _ => ("angle (°)", ["model", "measured (60 Hz)"]),
    };
    let mut p = LinePlot::new(title, "time (s)", y_label);
    p.series.push(Series::new(
        names[0],
        t.clone(),
        t.iter().map(|&t| f(t)).collect(),
        LineStyle::Solid,
    ));
    let meas: Vec<f64> = tm
        .iter()
        .enumerate()
        .map(|(i, &t)| {
            if i % 17 == 5 {
                f64::NAN
            } else {
                f(t) * 1.05 + 1e-10 * (i as f64).sin()
            }
        })
        .collect();
    let style = if kind == 4 {
        LineStyle::Dashed
    } else {
        LineStyle::Markers
    };
    p.series.push(Series::new(names[1], tm, meas, style));
    let edges = [0.6182, 0.66, 0.70, 0.72, 0.95, 1.05, 1.16, 1.4086];
    let labels = [
        "1c* heel strike",
        "2c heel",
        "3c both",
        "4c forefoot roll",
        "5c toe",
        "6c",
        "7c* swing",
    ];
    p.shaded = labels
        .iter()
        .enumerate()
        .map(|(i, l)| Span::new(edges[i], edges[i + 1], *l))
        .collect();
    if (1..=3).contains(&kind) {
        p.width = 420.0;
        p.height = 300.0;
    }
    p
}

fn sample_report() -> (Report, Vec<String>) {
    let titles: Vec<String> = vec![
        "Normal GRF, right foot".into(),
        "Tangential GRF, right foot".into(),
        "Knee angle, right".into(),
        "Hip angle, right".into(),
        "Ankle angle, right".into(),
        "Constraint drift".into(),
    ];
    let plots: Vec<LinePlot> = titles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            if i == 0 {
                sample_plot(t)
            } else {
                varied_plot(t, i - 1)
            }
        })
        .collect();
    let knee =
        ErrorStats::from_errors(&[0.01, 0.03, f64::NAN]).scaled(180.0 / std::f64::consts::PI);
    let table = error_table(
        "Tracking errors (layout of Millard & Mombaur 2019, Table 3)",
        &["ellipse".to_string(), "double circle".to_string()],
        &[ChannelErrors {
            name: "knee angle".into(),
            unit: "°".into(),
            decimals: 2,
            runs: vec![Some(knee), Some(knee)],
        }],
    );
    let mut summary = Summary::new(
        "converged",
        Tone::Good,
        "KKT residual 3.1e-7 below tol 1e-6",
    );
    summary.iterations = Some(23);
    summary.time_s = Some(187.4);
    summary.extra.push(("objective".into(), "1.2585".into()));
    let report = Report {
        title: "footfall tracking — ellipse foot & subject01".into(),
        summary,
        sections: vec![
            Section {
                heading: "Ground reaction forces".into(),
                paragraphs: vec![
                    "Model (line) against the force plate (dots); phases shaded. <not HTML>".into(),
                ],
                tables: vec![table],
                svgs: [&plots[0], &plots[1], &plots[5]]
                    .iter()
                    .map(|p| p.to_svg())
                    .collect(),
            },
            Section {
                heading: "Kinematics".into(),
                paragraphs: vec![],
                tables: vec![],
                svgs: vec![grid(&plots[2..5], 2)],
            },
        ],
    };
    (report, titles)
}

#[test]
fn report_html_is_self_contained() {
    let (report, titles) = sample_report();
    let html = report.to_html();
    assert_eq!(html, report.to_html());
    check_well_formed(&html, &HTML_VOID).unwrap();
    for t in &titles {
        assert!(html.contains(&format!(">{t}</text>")), "{t}");
    }
    assert!(html.contains("<div class=\"summary good\""));
    assert!(html.contains("<dt>iterations</dt><dd>23</dd>"));
    assert!(html.contains("<dt>time</dt><dd>3 min 07 s</dd>"));
    assert!(html.contains("&lt;not HTML&gt;"));
    assert!(html.contains("ellipse foot &amp; subject01"));
    for external in ["<script", "<link", "src=", "href=\"http", "url(", "@import"] {
        assert!(!html.contains(external), "{external} in report.html");
    }
    let dir = tempfile::tempdir().unwrap();
    let path = report.write(dir.path()).unwrap();
    assert_eq!(std::fs::read_to_string(path).unwrap(), html);
}

use common::chromium;

#[test]
fn chromium_renders_the_report() {
    let (report, titles) = sample_report();
    let dir = tempfile::tempdir().unwrap();
    let path: PathBuf = report.write(dir.path()).unwrap();
    let url = format!("file://{}", path.display());
    let timeout = Duration::from_secs(90);

    let t0 = Instant::now();
    let dom = String::from_utf8(chromium(&["--dump-dom".into(), url.clone()], timeout))
        .expect("UTF-8 DOM");
    let t_dom = t0.elapsed();
    // 3 standalone plots + 1 grid holding 3 nested plots.
    assert_eq!(dom.matches("<svg").count(), 7, "SVG elements in the DOM");
    for t in &titles {
        assert!(
            dom.contains(&format!(">{t}</text>")),
            "plot title {t:?} not in the rendered DOM"
        );
        assert!(
            dom.contains(&format!("<title>{t}</title>")),
            "SVG <title> {t:?} not in the rendered DOM"
        );
    }
    assert!(dom.contains("KKT residual 3.1e-7 below tol 1e-6"));

    let png = dir.path().join("report.png");
    let t1 = Instant::now();
    chromium(
        &[
            format!("--screenshot={}", png.display()),
            "--window-size=1200,2400".into(),
            url,
        ],
        timeout,
    );
    let t_png = t1.elapsed();
    let bytes = std::fs::read(&png).expect("screenshot written");
    assert!(
        bytes.len() > 10_000,
        "screenshot only {} bytes",
        bytes.len()
    );
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
    eprintln!(
        "chromium: dump-dom {:.2} s, screenshot {:.2} s",
        t_dom.as_secs_f64(),
        t_png.as_secs_f64()
    );

    if let Some(keep) = std::env::var_os("FOOTFALL_REPORT_OUT") {
        let keep = PathBuf::from(keep);
        std::fs::create_dir_all(&keep).unwrap();
        std::fs::copy(&path, keep.join("report.html")).unwrap();
        std::fs::copy(&png, keep.join("report.png")).unwrap();
    }
}
