//! The crate's structure, read from the source text so that a change that breaks it fails
//! here. Its layers point downward only (the map in `src/lib.rs`): every `crate::…` path in
//! a top-level module's files names a module of a lower layer or of the bottom row. No file
//! imports from a file that imports from it, through any chain of files. Only the
//! command-line program prints, exits or handles signals. And no function is over 150
//! lines, no file over 800.

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

/// A source file's module path below the crate root: `src/a/b.rs` and `src/a/b/mod.rs`
/// are `["a", "b"]`; `src/lib.rs` and `src/main.rs` the root.
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap();
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().unwrap();
    let stem = last.trim_end_matches(".rs");
    if !matches!(stem, "mod" | "lib" | "main") {
        parts.push(stem.to_string());
    }
    parts
}

/// The file that holds module `path`, if any.
fn module_file(src: &Path, path: &[String]) -> Option<PathBuf> {
    if path.is_empty() {
        return Some(src.join("lib.rs"));
    }
    let base = path.iter().fold(src.to_path_buf(), |p, s| p.join(s));
    let file = base.with_extension("rs");
    let dir = base.join("mod.rs");
    [file, dir].into_iter().find(|p| p.is_file())
}

/// A file's code without comments and without its `#[cfg(test)]` module (the tests of a
/// file may reach anywhere).
fn code_of(text: &str) -> String {
    let text = text.split("#[cfg(test)]").next().unwrap();
    text.lines()
        .map(|l| l.split("//").next().unwrap())
        .collect::<Vec<_>>()
        .join("\n")
}

/// The paths a `use` tree names, braces expanded: `a::{b, c::{d, e}}` gives `a::b`,
/// `a::c::d`, `a::c::e`.
fn expand_use(tree: &str) -> Vec<String> {
    // an alias (`d as e`) names the path before it
    let tree: String = tree
        .replace(" as ", "@")
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    let Some(open) = tree.find('{') else {
        return vec![tree.split('@').next().unwrap().to_string()];
    };
    let prefix = &tree[..open];
    let inner = &tree[open + 1..tree.len() - 1];
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    parts
        .into_iter()
        .filter(|p| !p.is_empty())
        .flat_map(|p| expand_use(p).into_iter().map(|q| format!("{prefix}{q}")))
        .collect()
}

/// The paths starting `crate::`, `super::` or `self::` that the code of a file names, in
/// `use` declarations and inline.
fn named_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = String::new();
    let mut s = code;
    while let Some(i) = s.find("use ") {
        let boundary = i == 0 || !s[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_');
        rest.push_str(&s[..i]);
        let after = &s[i + 4..];
        let end = after.find(';').unwrap_or(after.len());
        if boundary {
            out.extend(expand_use(&after[..end]));
            s = &after[end..];
        } else {
            rest.push_str("use ");
            s = after;
        }
    }
    rest.push_str(s);
    for start in ["crate::", "super::", "self::"] {
        for (i, _) in rest.match_indices(start) {
            let before = rest[..i].chars().last();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$' || c == ':') {
                continue;
            }
            let path: String = rest[i..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
                .collect();
            out.push(path);
        }
    }
    out
}

/// The file a path named in the file of module `here` leads to: its longest prefix that is
/// a module with a file of its own.
fn target_file(src: &Path, here: &[String], path: &str) -> Option<PathBuf> {
    let mut segs = path.split("::").filter(|s| !s.is_empty());
    // in `a/b.rs` and in `a/b/mod.rs` alike, `self` is `a::b` and `super` is `a`
    let mut full: Vec<String> = match segs.next()? {
        "crate" => Vec::new(),
        "self" => here.to_vec(),
        "super" => here[..here.len().saturating_sub(1)].to_vec(),
        _ => return None,
    };
    for s in segs {
        match s {
            "super" => {
                full.pop();
            }
            "self" => {}
            s => full.push(s.to_string()),
        }
    }
    (0..=full.len())
        .rev()
        .find_map(|n| module_file(src, &full[..n]))
}

/// The library's files and, for each, the files it imports from: every file a named path
/// leads to, except its own and those of its own submodules (a module owns its children:
/// declaring, re-exporting and calling them is not an import).
fn file_imports(src: &Path) -> Vec<(PathBuf, BTreeSet<PathBuf>)> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.retain(|f| !f.ends_with("main.rs") && !f.starts_with(src.join("cli")));
    files.sort();
    files
        .iter()
        .map(|f| {
            let here = module_path(src, f);
            let code = code_of(&std::fs::read_to_string(f).unwrap());
            let targets = named_paths(&code)
                .iter()
                .filter_map(|p| target_file(src, &here, p))
                .filter(|t| {
                    let there = module_path(src, t);
                    !(there.len() >= here.len() && there[..here.len()] == here[..])
                })
                .collect();
            (f.clone(), targets)
        })
        .collect()
}

/// The import circles among files: each strongly connected set of more than one file
/// (Tarjan's algorithm), as sorted lists of paths below `src`.
fn circles(src: &Path, graph: &[(PathBuf, BTreeSet<PathBuf>)]) -> Vec<Vec<String>> {
    let index: std::collections::BTreeMap<&PathBuf, usize> =
        graph.iter().enumerate().map(|(i, (f, _))| (f, i)).collect();
    let edges: Vec<Vec<usize>> = graph
        .iter()
        .map(|(_, ts)| ts.iter().filter_map(|t| index.get(t).copied()).collect())
        .collect();
    struct Tarjan<'e> {
        edges: &'e [Vec<usize>],
        next: usize,
        num: Vec<Option<usize>>,
        low: Vec<usize>,
        stack: Vec<usize>,
        on_stack: Vec<bool>,
        sets: Vec<Vec<usize>>,
    }
    impl Tarjan<'_> {
        fn visit(&mut self, v: usize) {
            self.num[v] = Some(self.next);
            self.low[v] = self.next;
            self.next += 1;
            self.stack.push(v);
            self.on_stack[v] = true;
            for i in 0..self.edges[v].len() {
                let w = self.edges[v][i];
                match self.num[w] {
                    None => {
                        self.visit(w);
                        self.low[v] = self.low[v].min(self.low[w]);
                    }
                    Some(n) if self.on_stack[w] => self.low[v] = self.low[v].min(n),
                    Some(_) => {}
                }
            }
            if Some(self.low[v]) == self.num[v] {
                let mut set = Vec::new();
                while let Some(w) = self.stack.pop() {
                    self.on_stack[w] = false;
                    set.push(w);
                    if w == v {
                        break;
                    }
                }
                self.sets.push(set);
            }
        }
    }
    let n = graph.len();
    let mut t = Tarjan {
        edges: &edges,
        next: 0,
        num: vec![None; n],
        low: vec![0; n],
        stack: Vec::new(),
        on_stack: vec![false; n],
        sets: Vec::new(),
    };
    for v in 0..n {
        if t.num[v].is_none() {
            t.visit(v);
        }
    }
    let mut out: Vec<Vec<String>> = t
        .sets
        .into_iter()
        .filter(|s| s.len() > 1)
        .map(|s| {
            let mut names: Vec<String> = s
                .iter()
                .map(|&i| graph[i].0.strip_prefix(src).unwrap().display().to_string())
                .collect();
            names.sort();
            names
        })
        .collect();
    out.sort();
    out
}

#[test]
fn no_file_imports_from_a_file_that_imports_from_it() {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = file_imports(&src);
    // the reading sees imports between files: the SQP driver imports the QP's types
    let driver = graph
        .iter()
        .find(|(f, _)| f.ends_with("sqp/driver.rs"))
        .unwrap();
    assert!(!driver.1.is_empty(), "{driver:?}");
    let found = circles(&src, &graph);
    assert!(found.is_empty(), "import circles between files: {found:?}");
}

/// Paths are resolved as the compiler does: `super` from a file is its parent module,
/// a use tree's braces expand, and a parent's use of its own child is not an import.
#[test]
fn file_imports_are_read_as_the_compiler_resolves_them() {
    assert_eq!(
        expand_use("super::{a, b::{c, d as e}}"),
        ["super::a", "super::b::c", "super::b::d"]
    );
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let here = module_path(&src, &src.join("sqp/driver.rs"));
    assert_eq!(here, ["sqp", "driver"]);
    assert_eq!(
        target_file(&src, &here, "super::qp::QpSolver"),
        Some(src.join("sqp/qp/mod.rs"))
    );
    assert_eq!(
        target_file(&src, &here, "crate::model::GaitModel"),
        Some(src.join("model/mod.rs"))
    );
    let a = PathBuf::from("a.rs");
    let b = PathBuf::from("b.rs");
    let c = PathBuf::from("c.rs");
    let graph = vec![
        (a.clone(), BTreeSet::from([b.clone()])),
        (b.clone(), BTreeSet::from([c.clone()])),
        (c.clone(), BTreeSet::from([a.clone()])),
    ];
    assert_eq!(circles(Path::new(""), &graph), [["a.rs", "b.rs", "c.rs"]]);
    assert!(circles(Path::new(""), &graph[..2]).is_empty());
}

/// Only the command-line program prints to the terminal, exits the process or installs a
/// signal handler; the library reports through its observers and returns statuses.
#[test]
fn only_the_command_line_prints_exits_or_handles_signals() {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let forbidden = [
        "println!",
        "eprintln!",
        "print!(",
        "eprint!(",
        "process::exit",
        "ctrlc::",
        "signal_hook",
        "dbg!(",
    ];
    let mut found = Vec::new();
    for f in files {
        if f.ends_with("main.rs") || f.starts_with(src.join("cli")) {
            continue;
        }
        let code = code_of(&std::fs::read_to_string(&f).unwrap());
        for word in forbidden {
            if code.contains(word) {
                found.push(format!(
                    "{}: {word}",
                    f.strip_prefix(&src).unwrap().display()
                ));
            }
        }
    }
    assert!(
        found.is_empty(),
        "the library prints, exits or handles signals: {found:?}"
    );
}

/// The functions of a file's text with their lengths in lines, from the `fn` line to its
/// closing brace (comments and blank lines included): `(name, first line, lines)`.
fn function_lengths(text: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let code = line.split("//").next().unwrap().trim_start();
        let Some(at) = code.find("fn ") else {
            continue;
        };
        let before = &code[..at];
        let words_ok = before.split_whitespace().all(|w| {
            matches!(w, "pub" | "const" | "async" | "unsafe" | "extern" | "\"C\"")
                || w.starts_with("pub(")
        });
        if !words_ok {
            continue;
        }
        let name: String = code[at + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if name.is_empty() {
            continue;
        }
        let (mut depth, mut opened) = (0i64, false);
        for (j, l) in lines.iter().enumerate().skip(i) {
            let code = l.split("//").next().unwrap();
            for c in code.chars() {
                match c {
                    '{' => {
                        depth += 1;
                        opened = true;
                    }
                    '}' => depth -= 1,
                    _ => {}
                }
            }
            if opened && depth <= 0 {
                out.push((name.clone(), i + 1, j - i + 1));
                break;
            }
            if !opened && code.trim_end().ends_with(';') {
                break;
            }
        }
    }
    out
}

/// Functions fit on a screen and files hold one concept: no function in `src/` is over
/// 150 lines, no file over 800.
#[test]
fn no_function_is_over_150_lines_and_no_file_over_800() {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut long = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let name = f.strip_prefix(&src).unwrap().display().to_string();
        let lines = text.lines().count();
        if lines > 800 {
            long.push(format!("{name}: {lines} lines"));
        }
        for (func, at, n) in function_lengths(&text) {
            if n > 150 {
                long.push(format!("{name}:{at} fn {func}: {n} lines"));
            }
        }
    }
    // the reading sees the functions: the SQP's driver has some
    let driver = std::fs::read_to_string(src.join("sqp/driver.rs")).unwrap();
    assert!(function_lengths(&driver).len() >= 5);
    assert!(long.is_empty(), "too long: {long:#?}");
}

/// A function's length runs from its `fn` line to its closing brace, nested blocks and
/// comments included; a declaration without a body is no function.
#[test]
fn function_lengths_are_counted_to_the_closing_brace() {
    let text = "pub(crate) fn a(x: u8) -> u8 {\n    if x > 0 {\n        1 // }\n    } else {\n        0\n    }\n}\ntrait T {\n    fn b(&self);\n}\nunsafe extern \"C\" fn c() {}\n";
    assert_eq!(
        function_lengths(text),
        [("a".to_string(), 1, 7), ("c".to_string(), 11, 1)]
    );
}

/// The error types of every `Result<T, E>` written in `code`, as written (`E` trimmed).
fn result_error_types(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("Result<") {
        let args = &rest[at + "Result<".len()..];
        let (mut depth, mut comma) = (0i64, None);
        let (mut end, mut previous) = (args.len(), ' ');
        for (i, c) in args.char_indices() {
            let arrow = previous == '-';
            previous = c;
            match c {
                '>' if arrow => {}
                '<' | '(' | '[' => depth += 1,
                '>' if depth == 0 => {
                    end = i;
                    break;
                }
                '>' | ')' | ']' => depth -= 1,
                ',' if depth == 0 => comma = Some(i),
                _ => {}
            }
        }
        if let Some(c) = comma {
            out.push(
                args[c + 1..end]
                    .split_whitespace()
                    .collect::<Vec<_>>()
                    .join(" "),
            );
        }
        rest = &args[..];
    }
    out
}

/// The library's errors are typed: no `Result` in `src/` (outside the command line and
/// the files' tests) carries its error as a bare `String`, so that a caller can tell one
/// failure from another and the command line decides how to say it.
#[test]
fn no_library_result_carries_a_string_error() {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut found = Vec::new();
    for f in &files {
        if f.ends_with("main.rs") || f.starts_with(src.join("cli")) {
            continue;
        }
        let code = code_of(&std::fs::read_to_string(f).unwrap());
        let strings = result_error_types(&code)
            .into_iter()
            .filter(|e| e == "String" || e == "std::string::String")
            .count();
        if strings > 0 {
            let name = f.strip_prefix(&src).unwrap().display();
            found.push(format!("{name}: {strings}"));
        }
    }
    assert!(
        found.is_empty(),
        "Result<_, String> in the library: {found:#?}"
    );
}

/// The reading of `Result`'s error type sees through nested generics and tuples, and
/// counts a `Result` with its error type left to an alias as none.
#[test]
fn result_error_types_are_read_at_the_top_level_of_the_arguments() {
    let code = "fn a() -> Result<Vec<(String, f64)>, String> {}\n\
                fn b() -> anyhow::Result<Result<HashMap<u8, String>, io::Error>> {}\n\
                fn c() -> io::Result<()> {}\n\
                type D = Result<Box<dyn Fn(u8) -> Vec<u8>>, String>;";
    assert_eq!(
        result_error_types(code),
        ["String", "io::Error", "String"].map(String::from)
    );
}
