//! `--set KEY=VALUE`: one case value overridden by its dotted path, in
//! the document as written (toml_edit keeps the rest of the text and its
//! comments), so that the case as run can be stored and read again.

use toml_edit::{Item, TableLike, Value};

/// Applies one `KEY=VALUE` to the document. Keys are dotted paths; a number
/// after an array of tables picks an entry (`dirichlet.0.uy=0`), after a
/// list of values the entry itself (`mesh.ladder.0=a.msh`). A missing
/// leaf key is added (serde then rejects it if it is not a case key).
pub(crate) fn apply_set(doc: &mut toml_edit::DocumentMut, set: &str) -> Result<(), String> {
    let (key, val) = set
        .split_once('=')
        .ok_or_else(|| "expected KEY=VALUE, e.g. --set time.dt=5e-4".to_string())?;
    let key = key.trim();
    let segs: Vec<&str> = key.split('.').map(str::trim).collect();
    if segs.iter().any(|s| s.is_empty()) {
        return Err(format!(
            "{key:?} is not a dotted key path; write e.g. time.dt"
        ));
    }
    let val = val.trim();
    let mut value: Value = val.parse().unwrap_or_else(|_| Value::from(val));
    value.decor_mut().clear();
    set_in(doc.as_table_mut(), &segs, value, key)?;
    // One rule says when the fields are written, and a file may give only
    // one (loading refuses two): the one set on the command line replaces
    // the file's, so that `--set output.frames=50` runs a case that says
    // `every = 1`.
    if let Some(rule) = field_rule(set) {
        if let Some(output) = doc.get_mut("output").and_then(Item::as_table_like_mut) {
            for other in FIELD_RULES.iter().filter(|&&r| r != rule) {
                output.remove(other);
            }
        }
    }
    Ok(())
}

/// The `[output]` keys that say when the fields are written.
const FIELD_RULES: [&str; 3] = ["frames", "interval", "every"];

/// The rule for the fields a `--set` gives (`"frames"` for
/// `output.frames=10`), if it gives one.
pub(crate) fn field_rule(set: &str) -> Option<&'static str> {
    let (key, _) = set.split_once('=')?;
    let segs: Vec<&str> = key.split('.').map(str::trim).collect();
    match segs[..] {
        ["output", rule] => FIELD_RULES.into_iter().find(|r| *r == rule),
        _ => None,
    }
}

fn set_in(t: &mut dyn TableLike, segs: &[&str], mut value: Value, key: &str) -> Result<(), String> {
    let (k, rest) = segs.split_first().expect("non-empty path");
    if rest.is_empty() {
        match t.get_mut(k) {
            Some(Item::Value(old)) => {
                // Keep the spacing and any trailing comment of the line.
                *value.decor_mut() = old.decor().clone();
                *old = value;
            }
            Some(Item::None) | None => {
                t.insert(k, Item::Value(value));
            }
            Some(Item::ArrayOfTables(a)) => {
                return Err(format!(
                    "{key} is a list of {} tables ([[{key}]]), which --set cannot replace as a \
                     whole; set a key of one entry by its number, e.g. {key}.0.KEY=VALUE, or edit \
                     the list in the case file",
                    a.len()
                ))
            }
            Some(_) => {
                return Err(format!(
                    "{key} is a table; set one of its keys, e.g. {key}.NAME=VALUE"
                ))
            }
        }
        return Ok(());
    }
    if t.get(k).is_none() {
        // A section the file does not have yet (e.g. --set contact.mu=0.3).
        t.insert(k, Item::Value(Value::InlineTable(Default::default())));
    }
    match t.get_mut(k).expect("just inserted") {
        Item::Table(tt) => set_in(tt, rest, value, key),
        Item::Value(Value::InlineTable(tt)) => set_in(tt, rest, value, key),
        Item::ArrayOfTables(a) => {
            let n = a.len();
            let (i, rest) = index(rest, k, n, key)?;
            set_in(a.get_mut(i).expect("index checked"), rest, value, key)
        }
        Item::Value(Value::Array(a)) => {
            let n = a.len();
            let (i, tail) = entry(rest, k, n, key)?;
            match a.get_mut(i).expect("index checked") {
                Value::InlineTable(_) if tail.is_empty() => Err(whole_table(key)),
                Value::InlineTable(tt) => set_in(tt, tail, value, key),
                // An entry of a list of values (mesh.ladder.0=FILE).
                _ if tail.is_empty() => {
                    a.replace(i, value);
                    Ok(())
                }
                _ => Err(format!(
                    "{key}: entry {i} of {k} is a value, not a table; set the entry itself, \
                     without the keys after .{i}"
                )),
            }
        }
        _ => Err(format!("{k} holds a value, not a table; set {k} itself")),
    }
}

fn index<'a>(
    rest: &'a [&'a str],
    k: &str,
    n: usize,
    key: &str,
) -> Result<(usize, &'a [&'a str]), String> {
    let (i, rest) = entry(rest, k, n, key)?;
    if rest.is_empty() {
        return Err(whole_table(key));
    }
    Ok((i, rest))
}

/// "`key` names a whole table": --set sets one key of a table.
fn whole_table(key: &str) -> String {
    format!("{key} names a whole table; set one of its keys, e.g. {key}.NAME=VALUE")
}

/// The entry of a list of `n` that `rest` starts with, and the keys after
/// it.
fn entry<'a>(
    rest: &'a [&'a str],
    k: &str,
    n: usize,
    key: &str,
) -> Result<(usize, &'a [&'a str]), String> {
    let (i, rest) = rest.split_first().expect("caller checked");
    let i: usize = i.parse().map_err(|_| {
        format!("{k} is a list of {n} tables; pick one by number from 0, e.g. {k}.0.KEY=VALUE")
    })?;
    if i >= n {
        return Err(format!(
            "{k} has {n} entries (0..{}); {key} names entry {i}",
            n.saturating_sub(1)
        ));
    }
    Ok((i, rest))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An entry of a list of values is set by its number (mesh.ladder.0 =
    /// FILE was refused as "a whole table", and the advice that followed,
    /// mesh.ladder.0.NAME=VALUE, as "a value, not a table").
    #[test]
    fn an_entry_of_a_list_of_values_is_set_by_number() {
        let mut doc: toml_edit::DocumentMut =
            "[mesh]\nladder = [\"a.msh\", \"b.msh\"]\n".parse().unwrap();
        apply_set(&mut doc, "mesh.ladder.1=c.msh").unwrap();
        assert_eq!(doc["mesh"]["ladder"][1].as_str(), Some("c.msh"));
        assert_eq!(doc["mesh"]["ladder"][0].as_str(), Some("a.msh"));
        let e = apply_set(&mut doc, "mesh.ladder.2=d.msh").unwrap_err();
        assert!(e.contains("has 2 entries"), "{e}");
        let e = apply_set(&mut doc, "mesh.ladder.0.x=1").unwrap_err();
        assert!(e.contains("is a value, not a table"), "{e}");
    }
}
