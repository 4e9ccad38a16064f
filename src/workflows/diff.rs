//! `footfall diff RUN_A RUN_B`: per-channel tracking errors before (A) and after (B), as
//! a table on stdout and a run folder (`diff.md`, `diff.csv`, `diff.svg`, `report.html`,
//! `summary.json`). Reading and comparing the runs is [`crate::report::diff`].

#[allow(unused_imports)]
use super::{note, result_note, warn_note, Progress};
use crate::report::diff::{RunDiff, RunSummary, Verdict};
use crate::report::html::{Report, Section, Summary, Tone};
use crate::runfolder::RunFolder;
use anyhow::{bail, Context};
use std::path::{Path, PathBuf};

/// What `diff` does: the arguments of `footfall diff`.
#[derive(Debug, Clone)]
pub struct DiffRequest {
    /// Run A, the baseline ("before"): a run folder written by `track` or `predict`, or its summary.json.
    pub run_a: PathBuf,
    /// Run B, compared with A ("after").
    pub run_b: PathBuf,
    /// Output folder (default: runs/diff-NAME_A-vs-NAME_B, from the run folders' names).
    pub out: Option<PathBuf>,
    /// Replace the output folder if it exists.
    pub overwrite: bool,
    /// Changes of the mean error within this many per cent of A count as unchanged.
    pub threshold_pct: f64,
}

/// Refuse an output folder that would replace (with `--overwrite`) one of the inputs.
fn check_not_input(out: &Path, inputs: &[&Path]) -> anyhow::Result<()> {
    let Ok(out_c) = out.canonicalize() else {
        return Ok(());
    };
    for input in inputs {
        if let Ok(c) = input.canonicalize() {
            if c.starts_with(&out_c) {
                bail!(
                    "--out {}: this would replace the input run {}",
                    out.display(),
                    input.display()
                );
            }
        }
    }
    Ok(())
}

/// Run `diff` as `args` describes, reporting to `progress`.
pub fn run(args: &DiffRequest, progress: &dyn Progress) -> anyhow::Result<()> {
    let a = RunSummary::read(&args.run_a).context("run A")?;
    let b = RunSummary::read(&args.run_b).context("run B")?;
    let diff = RunDiff::new(&a, &b, args.threshold_pct);
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("runs").join(format!("diff-{}-vs-{}", a.name, b.name)));
    check_not_input(&out, &[&a.path, &b.path])?;

    let table = diff.table();
    let phase_table = diff.phase_table();
    let headline = diff.headline();
    let notes = diff.notes();
    let runs = format!("A: {}\nB: {}", a.describe(), b.describe());

    let mut md = format!(
        "# footfall diff\n\n{}\n\n{}\n{headline}.\n",
        runs.replace('\n', "  \n"),
        table.to_markdown()
    );
    for n in &notes {
        md.push_str(&format!("\n{n}\n"));
    }
    md.push('\n');
    md.push_str(&phase_table.to_markdown());

    let svg = diff.chart().to_svg();
    let (status, tone) = match (diff.count(Verdict::Better), diff.count(Verdict::Worse)) {
        (0, 0) => ("no change", Tone::Neutral),
        (_, 0) => ("B better", Tone::Good),
        (0, _) => ("B worse", Tone::Bad),
        _ => ("mixed", Tone::Warning),
    };
    let mut summary = Summary::new(
        status,
        tone,
        format!(
            "compared {} channels of two run summaries",
            diff.channels.len()
        ),
    );
    summary.extra = vec![
        ("verdict".into(), format!("{headline}.")),
        ("run A".into(), a.describe()),
        ("run B".into(), b.describe()),
    ];
    let mut paragraphs = vec![
        "Mean of |model − measurement| at the shooting nodes (both legs pooled), per channel in its own unit. Change = B − A; negative is an improvement.".to_string(),
        "Chart: both runs' mean errors as per cent of run A's, so that channels in different units share one axis (A is 100 % by construction); each bar is labelled with the mean in the channel's unit.".to_string(),
    ];
    paragraphs.extend(notes.iter().cloned());
    let report = Report {
        title: format!("footfall diff — {} vs {}", a.name, b.name),
        summary,
        sections: vec![
            Section {
                heading: "Mean error per channel".into(),
                paragraphs,
                tables: vec![table.clone()],
                svgs: vec![svg.clone()],
            },
            Section {
                heading: "By phase".into(),
                paragraphs: vec![],
                tables: vec![phase_table],
                svgs: vec![],
            },
        ],
    };
    let mut summary_json = serde_json::to_value(&diff)?;
    if let Some(obj) = summary_json.as_object_mut() {
        obj.insert("command".into(), "diff".into());
        let counts = [
            Verdict::Better,
            Verdict::Worse,
            Verdict::Unchanged,
            Verdict::OnlyInA,
            Verdict::OnlyInB,
        ]
        .iter()
        .map(|&v| (v.tag().to_string(), serde_json::Value::from(diff.count(v))))
        .collect::<serde_json::Map<_, _>>();
        obj.insert("counts".into(), counts.into());
    }

    let folder = RunFolder::create(&out, args.overwrite)?;
    folder.write("diff.md", md.as_bytes())?;
    folder.write("diff.csv", diff.csv_table().to_csv().as_bytes())?;
    folder.write("diff.svg", svg.as_bytes())?;
    folder.write("report.html", report.to_html().as_bytes())?;
    folder.write(
        "summary.json",
        serde_json::to_string_pretty(&summary_json)?.as_bytes(),
    )?;
    let path = folder.commit()?;

    {
        result_note!(progress, "{runs}\n\n{}\n{headline}.", table.to_markdown());
        for n in &notes {
            result_note!(progress, "{n}");
        }
        note!(progress, "report: {}", path.join("report.html").display());
    }
    Ok(())
}
