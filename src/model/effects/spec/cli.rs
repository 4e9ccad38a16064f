//! Effects on the command line: `--effect NAME[:key=value,…]` parsed into entries, and an
//! entry written back in that form.

use super::{EffectSpec, EFFECT_KINDS};
use crate::model::error::EffectError;

impl EffectSpec {
    /// The command-line form of the effect, `NAME:key=value,…,free=a+b`, that
    /// [`parse_cli`](Self::parse_cli) reads back as this entry: what a diagnosis tells
    /// the user to add with one line. `None` for an entry with a value the command line
    /// cannot carry (a list or an object).
    pub fn cli_text(&self) -> Option<String> {
        let v = serde_json::to_value(self).ok()?;
        let obj = v.as_object()?;
        let mut parts = Vec::new();
        // the values first, what is freed last, as people write it
        let free = obj.get("free").map(|f| ("free", f));
        for (k, x) in obj
            .iter()
            .filter(|(k, _)| *k != "free")
            .map(|(k, x)| (k.as_str(), x))
            .chain(free)
        {
            let text = match (k, x) {
                ("type", _) | (_, serde_json::Value::Null) => continue,
                ("free", serde_json::Value::Array(names)) => names
                    .iter()
                    .map(|n| n.as_str().map(String::from))
                    .collect::<Option<Vec<_>>>()?
                    .join("+"),
                (_, serde_json::Value::Number(n)) => n.as_f64()?.to_string(),
                (_, serde_json::Value::String(t)) => t.clone(),
                _ => return None,
            };
            parts.push(format!("{k}={text}"));
        }
        Some(format!("{}:{}", self.kind(), parts.join(",")))
    }

    /// Parse a command-line effect `NAME[:key=value,…]`, e.g. `ground_slope`,
    /// `passive_joint_stiffness:joint=knee`, `ground_slope:angle=0.03,free=`. Without a
    /// `free` key every parameter is freed ([`free_all`](Self::free_all)); `free=a+b`
    /// frees the listed ones, `free=` none.
    pub fn parse_cli(text: &str) -> Result<Self, EffectError> {
        let (name, rest) = text.split_once(':').unwrap_or((text, ""));
        if !EFFECT_KINDS.contains(&name) {
            return Err(EffectError::UnknownKind {
                name: name.to_string(),
            });
        }
        let mut obj = serde_json::Map::new();
        obj.insert("type".into(), name.into());
        let mut free_given = false;
        for kv in rest.split(',').filter(|s| !s.is_empty()) {
            let (k, v) = kv.split_once('=').ok_or_else(|| EffectError::NotKeyValue {
                item: kv.to_string(),
                text: text.to_string(),
            })?;
            if obj.contains_key(k) {
                return Err(EffectError::RepeatedKey {
                    key: k.to_string(),
                    text: text.to_string(),
                });
            }
            let value = if k == "free" {
                free_given = true;
                serde_json::Value::from(v.split('+').filter(|s| !s.is_empty()).collect::<Vec<_>>())
            } else if let Ok(x) = v.parse::<f64>() {
                serde_json::Value::from(x)
            } else {
                serde_json::Value::from(v)
            };
            obj.insert(k.into(), value);
        }
        let mut spec: EffectSpec = serde_json::from_value(serde_json::Value::Object(obj.clone()))
            .map_err(|e| match not_a_number(&obj, &e.to_string()) {
            Some(k) => EffectError::NotANumber {
                text: text.to_string(),
                key: k.to_string(),
                value: obj[k].as_str().unwrap_or_default().to_string(),
            },
            None => EffectError::Schema {
                text: text.to_string(),
                source: e,
            },
        })?;
        if !free_given {
            spec.free_all();
        }
        spec.check().map_err(|(field, reason)| EffectError::Entry {
            text: text.to_string(),
            source: Box::new(EffectError::Field { field, reason }),
        })?;
        Ok(spec)
    }

    /// Parse several `--effect` texts, refusing two that add the same effect (two sides
    /// of a held measurement effect compose, as in a model file).
    pub fn parse_cli_all(texts: &[String]) -> Result<Vec<Self>, EffectError> {
        let specs = texts
            .iter()
            .map(|t| Self::parse_cli(t))
            .collect::<Result<Vec<_>, _>>()?;
        for (j, b) in specs.iter().enumerate() {
            if let Some(i) = (0..j).find(|&i| specs[i].overlaps(b) && !specs[i].composes_with(b)) {
                return Err(EffectError::Twice {
                    first: texts[i].clone(),
                    second: texts[j].clone(),
                    effect: b.label(),
                });
            }
        }
        Ok(specs)
    }
}

/// The key of an effect's text whose value is not a number where serde's error `message`
/// says a number was expected (`invalid type: string "abc", expected f64`).
fn not_a_number<'a>(
    obj: &'a serde_json::Map<String, serde_json::Value>,
    message: &str,
) -> Option<&'a str> {
    if !message.contains("expected f64") {
        return None;
    }
    obj.iter()
        .filter(|(k, _)| k.as_str() != "type")
        .find(|(_, v)| {
            v.as_str()
                .is_some_and(|v| message.contains(&format!("string \"{v}\"")))
        })
        .map(|(k, _)| k.as_str())
}
