//! The crate's layers point downward only (the map in `src/lib.rs`): every `crate::…`
//! path in a top-level module's files names a module of a lower layer or of the bottom
//! row. Read from the source text, so a new upward `use` fails here.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The layers, top to bottom; modules in one layer may not use each other, except as
/// listed in `SAME_LAYER`.
const LAYERS: [&[&str]; 10] = [
    &["workflows"],
    &["report"],
    &["problems"],
    &["simulate", "phases"],
    &["ocp"],
    &["sqp"],
    &["integrate"],
    &["data", "controls"],
    &["model"],
    &["limits", "runfolder", "bundled", "interrupt"],
];

/// Uses within one layer that the map allows: `simulate` runs `phases`' sequences.
const SAME_LAYER: [(&str, &str); 1] = [("simulate", "phases")];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The top-level modules named by `crate::NAME` in the files of module `m`.
fn uses(src: &Path, m: &str) -> BTreeSet<String> {
    let mut files = Vec::new();
    let dir = src.join(m);
    if dir.is_dir() {
        rust_files(&dir, &mut files);
    }
    let file = src.join(format!("{m}.rs"));
    if file.is_file() {
        files.push(file);
    }
    assert!(!files.is_empty(), "no source for module {m}");
    let mut out = BTreeSet::new();
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        for (i, _) in text.match_indices("crate::") {
            // `footfall::crate::` cannot occur; skip `$crate::` in macros
            if text[..i].ends_with('$') {
                continue;
            }
            let name: String = text[i + 7..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() && name != m {
                out.insert(name);
            }
        }
    }
    out
}

fn layer_of(m: &str) -> usize {
    LAYERS
        .iter()
        .position(|l| l.contains(&m))
        .unwrap_or_else(|| panic!("module {m} is not in the layer map"))
}

/// The uses among `(module, used)` pairs that do not point down.
fn upward(pairs: &[(String, String)]) -> Vec<String> {
    let bottom = LAYERS.len() - 1;
    pairs
        .iter()
        .filter(|(m, used)| {
            let (lm, lu) = (layer_of(m), layer_of(used));
            !(lu > lm || lu == bottom || SAME_LAYER.contains(&(m.as_str(), used.as_str())))
        })
        .map(|(m, used)| format!("{m} uses {used}"))
        .collect()
}

#[test]
fn every_module_uses_only_modules_below_it() {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    let declared: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("pub mod "))
        .map(|l| l.trim_end_matches(';'))
        .collect();
    let mapped: BTreeSet<&str> = LAYERS.iter().flat_map(|l| l.iter().copied()).collect();
    assert_eq!(
        declared.iter().copied().collect::<BTreeSet<_>>(),
        mapped,
        "the layer map and lib.rs's modules differ"
    );
    let pairs: Vec<(String, String)> = declared
        .iter()
        .flat_map(|&m| uses(&src, m).into_iter().map(move |u| (m.to_string(), u)))
        .collect();
    // the reading sees the uses: workflows uses nearly everything
    assert!(
        pairs.iter().filter(|(m, _)| m == "workflows").count() >= 8,
        "{pairs:?}"
    );
    let bad = upward(&pairs);
    assert!(bad.is_empty(), "uses that do not point down: {bad:?}");
}

/// The check fails on an upward use (such as `problems` using `report`),
/// a use within a layer that the map does not allow, and passes the allowed ones.
#[test]
fn an_upward_use_is_caught() {
    let pair = |a: &str, b: &str| (a.to_string(), b.to_string());
    assert_eq!(
        upward(&[pair("problems", "report")]),
        ["problems uses report"]
    );
    assert_eq!(
        upward(&[pair("phases", "simulate")]),
        ["phases uses simulate"]
    );
    assert_eq!(
        upward(&[pair("model", "integrate")]),
        ["model uses integrate"]
    );
    assert!(upward(&[
        pair("simulate", "phases"),
        pair("model", "bundled"),
        pair("report", "sqp"),
        pair("workflows", "report"),
    ])
    .is_empty());
}
