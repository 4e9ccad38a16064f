//! Effects on the command line: `--effect NAME[:key=value,…]` parsed into entries, and an
//! entry written back in that form.

use super::{EffectSpec, EFFECT_KINDS};

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
    pub fn parse_cli(text: &str) -> Result<Self, String> {
        let (name, rest) = text.split_once(':').unwrap_or((text, ""));
        if !EFFECT_KINDS.contains(&name) {
            return Err(format!(
                "'{name}' is not a known effect; use one of {}",
                EFFECT_KINDS.join(", ")
            ));
        }
        let mut obj = serde_json::Map::new();
        obj.insert("type".into(), name.into());
        let mut free_given = false;
        for kv in rest.split(',').filter(|s| !s.is_empty()) {
            let (k, v) = kv
                .split_once('=')
                .ok_or_else(|| format!("'{kv}' in '{text}' is not key=value"))?;
            if obj.contains_key(k) {
                return Err(format!(
                    "'{k}' is given twice in '{text}'; give each parameter once"
                ));
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
            Some(k) => format!(
                "effect '{text}': '{k}' must be a number (for example {k}=0.02), got '{}'",
                obj[k].as_str().unwrap_or_default()
            ),
            None => format!("effect '{text}': {e}"),
        })?;
        if !free_given {
            spec.free_all();
        }
        spec.check()
            .map_err(|(f, r)| format!("effect '{text}': {f}: {r}"))?;
        Ok(spec)
    }

    /// Parse several `--effect` texts, refusing two that add the same effect (two sides
    /// of a held measurement effect compose, as in a model file).
    pub fn parse_cli_all(texts: &[String]) -> Result<Vec<Self>, String> {
        let specs = texts
            .iter()
            .map(|t| Self::parse_cli(t))
            .collect::<Result<Vec<_>, _>>()?;
        for (j, b) in specs.iter().enumerate() {
            if let Some(i) = (0..j).find(|&i| specs[i].overlaps(b) && !specs[i].composes_with(b)) {
                return Err(format!(
                    "'{}' and '{}' both add the effect '{}'; give it once",
                    texts[i],
                    texts[j],
                    b.label()
                ));
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
