//! What may change between the run stored in a results file and its
//! continuation (`run --restart`): the end time, the output settings, the
//! title, the ladder and the stick/slip iteration's budget; anything else
//! would continue another computation.

use std::collections::BTreeMap;

/// Keys a restart may change: the end time, the output settings, the
/// title, the ladder and `contact.max_iterations`.
fn restart_may_change(key: &str) -> bool {
    // mesh.ladder is read by `advise` only; a run never sees it.
    key == "title"
        || key == "time.t_end"
        || key == "mesh.ladder"
        || key == "output"
        || key.starts_with("output.")
        || is_max_iterations(key)
}

/// `contact.max_iterations` or `contact.N.max_iterations`: a budget, not
/// physics. The steps that converged did so within the old budget and are
/// the same under a larger one; a run stopped by it ("raise
/// contact.max_iterations") must be able to continue with more. The
/// checkpoint holds no budget: the restarted run takes the case's.
fn is_max_iterations(key: &str) -> bool {
    let Some(rest) = key.strip_prefix("contact.") else {
        return false;
    };
    match rest.split_once('.') {
        None => rest == "max_iterations",
        Some((i, leaf)) => leaf == "max_iterations" && i.parse::<usize>().is_ok(),
    }
}

/// Keys that did nothing under the stored run's `scheme`, which earlier
/// versions took and this one refuses there: the case must drop them to
/// be read at all, and dropping them changes nothing computed.
fn inert(key: &str, scheme: Option<&str>) -> bool {
    let under = |table: &str| key == table || key.starts_with(&format!("{table}."));
    if under("time.allow_unstable") {
        scheme.is_some_and(|s| s != "central_difference")
    } else if under("time.stick_reduction") {
        scheme == Some("quasi_static")
    } else {
        false
    }
}

fn flatten(prefix: &str, v: &toml::Value, out: &mut BTreeMap<String, toml::Value>) {
    let name = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match v {
        toml::Value::Table(t) => {
            for (k, v) in t {
                flatten(&name(k), v, out);
            }
        }
        toml::Value::Array(a) if a.iter().all(toml::Value::is_table) && !a.is_empty() => {
            for (i, v) in a.iter().enumerate() {
                flatten(&name(&i.to_string()), v, out);
            }
        }
        _ => {
            out.insert(prefix.to_string(), v.clone());
        }
    }
}

/// Numbers compare by value (`1000` equals `1000.0`); the rest as written.
fn same_value(a: &toml::Value, b: &toml::Value) -> bool {
    use crate::schema::number;
    match (number(a), number(b)) {
        (Some(x), Some(y)) => x.to_bits() == y.to_bits() || x == y,
        _ => match (a, b) {
            (toml::Value::Array(x), toml::Value::Array(y)) => {
                x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same_value(p, q))
            }
            _ => a == b,
        },
    }
}

/// The keys (dotted, as `--set` writes them) on which the case `new` differs
/// from the case `stored` in a results file, other than those a restart may
/// change (`time.t_end`, `output.*`, `title`, `mesh.ladder`,
/// `contact.max_iterations`), each as `key: stored X, now Y`.
/// A key given in one and left to its default in the other counts as a
/// change (write it the same way in both).
///
/// # Errors
/// The stored text is not TOML (a damaged file).
pub fn restart_changes(stored: &str, new: &str) -> Result<Vec<String>, String> {
    let parse = |s: &str| -> Result<BTreeMap<String, toml::Value>, String> {
        let v: toml::Table = toml::from_str(s).map_err(|e| e.message().trim_end().to_string())?;
        let mut out = BTreeMap::new();
        flatten("", &toml::Value::Table(v), &mut out);
        Ok(out)
    };
    let old = parse(stored).map_err(|e| format!("the case stored in the file is not TOML: {e}"))?;
    let new = parse(new)?;
    let mut keys: Vec<&String> = old.keys().chain(new.keys()).collect();
    keys.sort();
    keys.dedup();
    let show = |v: Option<&toml::Value>| v.map_or("(not given)".to_string(), |v| v.to_string());
    let scheme = old.get("time.scheme").and_then(toml::Value::as_str);
    Ok(keys
        .into_iter()
        .filter(|k| !restart_may_change(k) && !inert(k, scheme))
        .filter(|k| match (old.get(*k), new.get(*k)) {
            (Some(a), Some(b)) => !same_value(a, b),
            _ => true,
        })
        .map(|k| {
            format!(
                "{k}: {} in the stored run, {} now",
                show(old.get(k)),
                show(new.get(k))
            )
        })
        .collect())
}
