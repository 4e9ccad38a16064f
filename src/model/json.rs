//! Reading the project's JSON files (models, feet, phase sequences) with errors that name
//! the file, the field and the position.
//!
//! serde_json gives the line and column of a problem and `serde_path_to_error` the path of
//! the field being read. Inside an internally tagged enum (`body`, `actuators`, `effects[i]`,
//! `shape`, phases) serde buffers the object and reports only the enum's path and the end
//! of the object; the path is then narrowed below the enum by looking for the key or value
//! that serde's message names, and serde_json itself is walked to that field for its line.

use super::error::ModelError;
use serde::de::{
    DeserializeOwned, DeserializeSeed, Error as _, IgnoredAny, MapAccess, SeqAccess, Visitor,
};
use std::path::Path;

/// Read and parse a JSON file, mapping errors to [`ModelError`] with line and column.
pub fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T, ModelError> {
    let text = std::fs::read_to_string(path).map_err(|source| ModelError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_json(&text, path)
}

/// Parse JSON text that came from `path`.
///
/// The error names the dotted path of the offending field (`body.segments.thigh.mass`,
/// `primitives[0].shape.type`), serde's description of what is wrong and what it expected,
/// and the line and column of the field.
///
/// A leading byte-order mark is skipped, as spreadsheet programs write one.
pub fn parse_json<T: DeserializeOwned>(text: &str, path: &Path) -> Result<T, ModelError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut de = serde_json::Deserializer::from_str(text);
    let (e, mut field) = match serde_path_to_error::deserialize::<_, T>(&mut de) {
        Ok(v) => match de.end() {
            Ok(()) => return Ok(v),
            Err(e) => (e, Vec::new()),
        },
        Err(e) => {
            let field = e
                .path()
                .iter()
                .filter_map(|s| match s {
                    serde_path_to_error::Segment::Map { key } => Some(PathSeg::Key(key.clone())),
                    serde_path_to_error::Segment::Seq { index } => Some(PathSeg::Index(*index)),
                    _ => None,
                })
                .collect();
            (e.into_inner(), field)
        }
    };
    let what = e.to_string();
    let what = match what.rfind(" at line ") {
        Some(k) if e.line() > 0 => what[..k].to_string(),
        _ => what,
    };
    let (mut line, mut column) = (e.line(), e.column());
    let syntax = matches!(
        e.classify(),
        serde_json::error::Category::Syntax | serde_json::error::Category::Eof
    );
    if !syntax {
        let root = serde_json::from_str::<serde_json::Value>(text).ok();
        // the value normally lies at or below serde's path; else look further up
        let found = root.as_ref().and_then(|root| {
            (0..=field.len())
                .rev()
                .find_map(|depth| Some((depth, locate(root, &field[..depth], &what)?)))
        });
        if let Some((depth, sub)) = found {
            field.truncate(depth);
            field.extend(sub);
            // serde's position inside a tagged enum is the end of the buffered object;
            // point at the field (or, for a missing one, at the object lacking it).
            let pos = position_of(text, &field).or_else(|| {
                field
                    .split_last()
                    .and_then(|(_, parent)| position_of(text, parent))
            });
            if let Some(pos) = pos {
                (line, column) = pos;
            }
        } else if let Some(name) = what
            .strip_prefix("missing field `")
            .and_then(|r| r.split('`').next())
        {
            field.push(PathSeg::Key(name.to_string()));
        }
    }
    let field = format_path(&field);
    let message = if syntax {
        if field.is_empty() {
            format!("invalid JSON: {what}")
        } else {
            format!("invalid JSON: {what} (near field '{field}')")
        }
    } else if let Some(held) = not_an_object(text) {
        held
    } else if field.is_empty() {
        what
    } else {
        format!("field '{field}': {what}")
    };
    Err(ModelError::Json {
        path: path.to_path_buf(),
        message,
        line,
        column,
    })
}

/// What a document that is valid JSON but no object holds, e.g. `the file holds null,
/// not a JSON object { … } of fields`; None for an object.
fn not_an_object(text: &str) -> Option<String> {
    use serde_json::Value;
    let held = match serde_json::from_str::<Value>(text).ok()? {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => return None,
    };
    Some(format!(
        "the file holds {held}, not a JSON object {{ … }} of fields"
    ))
}

/// One step of a path into a JSON document.
#[derive(Debug, Clone, PartialEq)]
enum PathSeg {
    Key(String),
    Index(usize),
}

fn format_path(p: &[PathSeg]) -> String {
    let mut out = String::new();
    for s in p {
        match s {
            PathSeg::Key(k) => {
                if !out.is_empty() {
                    out.push('.');
                }
                out.push_str(k);
            }
            PathSeg::Index(i) => out.push_str(&format!("[{i}]")),
        }
    }
    out
}

/// The message of the error by which [`Probe`] stops at its target.
const PROBE_FOUND: &str = "probe reached its target";

/// Line and column (1-based) of the value at `target` in `text` (for an object member,
/// right after its key), as serde_json reports them when a [`Probe`] walking the document
/// stops there; `None` for the root or a path that does not occur.
fn position_of(text: &str, target: &[PathSeg]) -> Option<(usize, usize)> {
    if target.is_empty() {
        return None;
    }
    let mut de = serde_json::Deserializer::from_str(text);
    match Probe(target).deserialize(&mut de) {
        Err(e) if e.to_string().starts_with(PROBE_FOUND) => Some((e.line(), e.column())),
        _ => None,
    }
}

/// Walks a JSON document along a path, skipping everything else, and fails with
/// [`PROBE_FOUND`] on reaching its end (serde_json then attaches the position).
struct Probe<'a>(&'a [PathSeg]);

/// Fails with [`PROBE_FOUND`] before reading the value it is asked for.
struct Here;

impl<'de> DeserializeSeed<'de> for Here {
    type Value = ();
    fn deserialize<D: serde::Deserializer<'de>>(self, _: D) -> Result<(), D::Error> {
        Err(D::Error::custom(PROBE_FOUND))
    }
}

impl<'de> DeserializeSeed<'de> for Probe<'_> {
    type Value = ();
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Probe<'_> {
    type Value = ();
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("an object or array on the path")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let Some((PathSeg::Key(want), rest)) = self.0.split_first() else {
            return Err(A::Error::custom("not on the path"));
        };
        while let Some(key) = map.next_key::<String>()? {
            if key == *want {
                if rest.is_empty() {
                    return Err(A::Error::custom(PROBE_FOUND));
                }
                return map.next_value_seed(Probe(rest));
            }
            map.next_value::<IgnoredAny>()?;
        }
        Err(A::Error::custom("not on the path"))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let Some((PathSeg::Index(want), rest)) = self.0.split_first() else {
            return Err(A::Error::custom("not on the path"));
        };
        for _ in 0..*want {
            seq.next_element::<IgnoredAny>()?;
        }
        if rest.is_empty() {
            seq.next_element_seed(Here)?;
        } else {
            seq.next_element_seed(Probe(rest))?;
        }
        Err(A::Error::custom("not on the path"))
    }
}

/// Narrow serde's message down to a path below `at` in `root`: the key an `unknown field`
/// names, the object a `missing field` is missing from, or the value an `invalid type`,
/// `invalid value`, `unknown variant` or `invalid length` quotes. `None` when nothing fits.
fn locate(root: &serde_json::Value, at: &[PathSeg], what: &str) -> Option<Vec<PathSeg>> {
    use serde_json::Value;
    let mut base = root;
    for s in at {
        base = match (s, base) {
            (PathSeg::Key(k), Value::Object(m)) => m.get(k)?,
            (PathSeg::Index(i), Value::Array(a)) => a.get(*i)?,
            _ => return None,
        };
    }
    let quoted = |open: &str, close: char| -> Option<String> {
        let k = what.find(open)? + open.len();
        let rest = &what[k..];
        Some(rest[..rest.find(close)?].to_string())
    };
    // Every value below `base` with its relative path, in document order.
    fn walk<'a>(v: &'a Value, path: &mut Vec<PathSeg>, out: &mut Vec<(Vec<PathSeg>, &'a Value)>) {
        out.push((path.clone(), v));
        match v {
            Value::Object(m) => {
                for (k, x) in m {
                    path.push(PathSeg::Key(k.clone()));
                    walk(x, path, out);
                    path.pop();
                }
            }
            Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    path.push(PathSeg::Index(i));
                    walk(x, path, out);
                    path.pop();
                }
            }
            _ => {}
        }
    }
    let mut all = Vec::new();
    walk(base, &mut Vec::new(), &mut all);
    let first =
        |pred: &dyn Fn(&Value) -> bool| all.iter().find(|(_, v)| pred(v)).map(|(p, _)| p.clone());
    if let Some(name) = quoted("unknown field `", '`') {
        let mut p = first(&|v| v.as_object().is_some_and(|m| m.contains_key(&name)))?;
        p.push(PathSeg::Key(name));
        return Some(p);
    }
    if let Some(name) = quoted("missing field `", '`') {
        if !base.is_object() {
            return None;
        }
        // The object below `base` lacking `name` that looks most like the objects of the
        // document having it (shares the most keys with one); without such, `base` itself.
        let mut everything = Vec::new();
        walk(root, &mut Vec::new(), &mut everything);
        let having: Vec<&serde_json::Map<String, Value>> = everything
            .iter()
            .filter_map(|(_, v)| v.as_object())
            .filter(|m| m.contains_key(&name))
            .collect();
        let mut best: Option<(usize, Vec<PathSeg>)> = None;
        for (p, v) in &all {
            let Some(m) = v.as_object() else { continue };
            if m.contains_key(&name) {
                continue;
            }
            let score = having
                .iter()
                .map(|h| m.keys().filter(|k| h.contains_key(*k)).count())
                .max()
                .unwrap_or(0);
            if best.as_ref().is_none_or(|(s, _)| score > *s) {
                best = Some((score, p.clone()));
            }
        }
        let mut p = match best {
            Some((s, p)) if s > 0 => p,
            _ => Vec::new(),
        };
        p.push(PathSeg::Key(name));
        return Some(p);
    }
    if let Some(s) = quoted("unknown variant `", '`').or_else(|| quoted("string \"", '"')) {
        return first(&|v| v.as_str() == Some(s.as_str()));
    }
    if let Some(n) = quoted("integer `", '`').or_else(|| quoted("floating point `", '`')) {
        let n: f64 = n.parse().ok()?;
        return first(&|v| v.as_f64() == Some(n));
    }
    if let Some(b) = quoted("boolean `", '`') {
        return first(&|v| v.as_bool().map(|x| x.to_string()) == Some(b.clone()));
    }
    if what.contains("invalid type: null") {
        return first(&|v| v.is_null());
    }
    if let Some(n) = quoted("invalid length ", ',') {
        let n: usize = n.parse().ok()?;
        return first(&|v| v.as_array().is_some_and(|a| a.len() == n));
    }
    None
}
