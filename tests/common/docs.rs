//! The shell blocks of the README and the command guide: their lines and the footfall
//! invocations in them, read by the front-door checks and run by `documented_commands`.

/// The Markdown files whose shell blocks are the product's documented commands.
pub const DOCUMENTED: [&str; 2] = ["README.md", "docs/commands.md"];

/// The shell lines of the ```sh blocks of a Markdown file, continuation lines joined.
pub fn sh_lines(markdown: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    let mut pending = String::new();
    for line in markdown.lines() {
        let t = line.trim();
        if t.starts_with("```") {
            inside = !inside && matches!(t.trim_start_matches('`'), "sh" | "bash" | "shell");
            continue;
        }
        if !inside || t.starts_with('#') || t.is_empty() {
            continue;
        }
        if let Some(head) = t.strip_suffix('\\') {
            pending.push_str(head.trim_end());
            pending.push(' ');
            continue;
        }
        pending.push_str(t);
        out.push(std::mem::take(&mut pending));
    }
    out
}

/// One invocation of footfall in a shell line: the subcommand and the options it uses.
#[derive(Debug)]
pub struct Invocation {
    pub line: String,
    pub subcommand: String,
    pub flags: Vec<String>,
}

/// Every footfall invocation in a shell line (`footfall …`, `target/release/footfall …`,
/// `cargo run --release -- …`), split at `&&`, `||`, `;` and `|`.
pub fn invocations(line: &str) -> Vec<Invocation> {
    let mut out = Vec::new();
    for part in line.split(['&', ';', '|']) {
        let words: Vec<&str> = part.split_whitespace().collect();
        let rest = match words.first() {
            Some(w) if w.ends_with("footfall") => &words[1..],
            Some(&"cargo") if words.get(1) == Some(&"run") => {
                match words.iter().position(|w| *w == "--") {
                    Some(k) => &words[k + 1..],
                    None => continue,
                }
            }
            _ => continue,
        };
        let Some(sub) = rest.iter().find(|w| !w.starts_with('-')) else {
            continue;
        };
        let flags = rest
            .iter()
            .filter(|w| w.starts_with("--"))
            .map(|w| w.split('=').next().unwrap().to_string())
            .collect();
        out.push(Invocation {
            line: line.to_string(),
            subcommand: sub.to_string(),
            flags,
        });
    }
    out
}
