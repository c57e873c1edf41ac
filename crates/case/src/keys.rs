//! The key-by-key check of a case against the schema, before serde sees
//! it: unknown keys (with the nearest valid key, or the table a misplaced
//! key belongs in) and values of the wrong type, all reported at once with
//! their place; the offending keys are then taken out (or given a
//! placeholder of the right type) so that serde and the value checks can
//! still report on the rest.

use std::collections::BTreeMap;
use std::ops::Range;

use toml_edit::{Item, TableLike, Value};

use crate::schema::{sections, Kind, ROOT};

/// A key whose value had the wrong type: its path, the placeholder put in
/// its place (`None`: removed), and where it was.
pub(crate) type Retyped = (Vec<Seg>, Option<Value>, Option<Range<usize>>);

/// One step of a key path: a key or an index into a list of tables.
#[derive(Clone, Debug)]
pub(crate) enum Seg {
    Key(String),
    Index(usize),
}

pub(crate) fn seg_name(s: &Seg) -> String {
    match s {
        Seg::Key(k) => k.clone(),
        Seg::Index(i) => i.to_string(),
    }
}

/// `time.dt`, `dirichlet.0.uy` (the --set syntax).
pub(crate) fn dotted(path: &[Seg]) -> String {
    path.iter().map(seg_name).collect::<Vec<_>>().join(".")
}

/// Levenshtein distance (small strings only: keys).
fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for j in 0..b.len() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != b[j]))
                .min(row[j] + 1)
                .min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

/// The valid key nearest to `key`, if it is near enough to be a typo: at
/// most a third of the letters different (at least one), or one a prefix of
/// the other (`epsilon` → `eps`), ignoring case.
fn nearest<'a>(key: &str, valid: &[(&'a str, Kind)]) -> Option<&'a str> {
    let k = key.to_lowercase();
    valid
        .iter()
        .map(|(v, _)| {
            let vl = v.to_lowercase();
            let d = distance(&k, &vl);
            let prefix =
                k.len() >= 2 && vl.len() >= 2 && (k.starts_with(&vl) || vl.starts_with(&k));
            (if prefix { d.min(1) } else { d }, *v)
        })
        .filter(|(d, v)| *d <= (v.chars().count() / 3).max(1))
        .min_by_key(|(d, _)| *d)
        .map(|(_, v)| v)
}

/// Whether the key at `path`, removed as unknown, stood for `missing`, a
/// key serde then finds missing: `missing` is a key of the same table,
/// and its only one or the one nearest the removed key (a typo). Then the
/// unknown key's message, which names `missing`, says it all
/// (`pressure_profile = { sin = .. }` was also "missing field `table`").
pub(crate) fn stood_for(path: &[Seg], missing: &str) -> bool {
    let Some((Seg::Key(leaf), parent)) = path.split_last() else {
        return false;
    };
    let mut keys = ROOT;
    for seg in parent {
        let Seg::Key(k) = seg else { continue };
        match keys.iter().find(|(n, _)| n == k) {
            Some((_, Kind::Table(sub) | Kind::Tables(sub) | Kind::OneOrTables(sub))) => keys = sub,
            _ => return false,
        }
    }
    keys.iter().any(|(k, _)| *k == missing)
        && (keys.len() == 1 || nearest(leaf, keys) == Some(missing))
}

/// Describes a TOML value for a message.
fn found(item: &Item) -> String {
    match item {
        Item::Value(v) => found_value(v),
        Item::Table(_) => "a table".into(),
        Item::ArrayOfTables(_) => "a list of tables".into(),
        Item::None => "nothing".into(),
    }
}

fn found_value(v: &Value) -> String {
    match v {
        Value::String(s) => format!("the string {:?}", s.value()),
        Value::Integer(i) => format!("the integer {}", i.value()),
        Value::Float(f) => format!("the number {}", f.value()),
        Value::Boolean(b) => format!("{}", b.value()),
        Value::Datetime(_) => "a date".into(),
        Value::Array(a) => format!("an array of {}", a.len()),
        Value::InlineTable(_) => "a table".into(),
    }
}

/// What an [x, y] vector holds instead: "an array of 3", or for an array
/// of two, which element is not a number ("an array of 2" alone
/// contradicted "a vector of two numbers").
fn found_vec2(item: &Item) -> String {
    let Item::Value(Value::Array(a)) = item else {
        return found(item);
    };
    match a.iter().position(|v| !is_number(v)) {
        Some(k) if a.len() == 2 => format!(
            "two values, the {} of them {}",
            if k == 0 { "first" } else { "second" },
            a.get(k).map_or(String::new(), found_value)
        ),
        _ => found(item),
    }
}

fn is_number(v: &Value) -> bool {
    matches!(v, Value::Integer(_) | Value::Float(_))
}

/// Magnitudes a case's numbers may have (or 0): beyond them products such
/// as E·h² or ρ·h²/Δt² overflow or underflow, and the run would fail with a
/// wrong diagnosis (E = 1e308: "a rigid-body motion left free"; ρ =
/// 1e-300: "use time.dt < 0").
const MODERATE: std::ops::RangeInclusive<f64> = 1e-100..=1e100;

/// A number of `v` that breaks the promise of docs/case-file.md: not
/// finite, or neither 0 nor of a magnitude in [`MODERATE`].
fn immoderate(v: &Value) -> Option<f64> {
    let x = match v {
        Value::Integer(i) => *i.value() as f64,
        Value::Float(f) => *f.value(),
        _ => return None,
    };
    (x != 0.0 && !(x.is_finite() && MODERATE.contains(&x.abs()))).then_some(x)
}

/// Every number inside `item`, at any depth (a history's table or
/// frequency).
fn nested_numbers<'a>(item: &'a Item, out: &mut Vec<&'a Value>) {
    fn in_value<'a>(v: &'a Value, out: &mut Vec<&'a Value>) {
        match v {
            Value::Array(a) => a.iter().for_each(|v| in_value(v, out)),
            Value::InlineTable(t) => t.iter().for_each(|(_, v)| in_value(v, out)),
            _ => out.push(v),
        }
    }
    match item {
        Item::Value(v) => in_value(v, out),
        Item::Table(t) => t.iter().for_each(|(_, i)| nested_numbers(i, out)),
        Item::ArrayOfTables(a) => a
            .iter()
            .flat_map(|t| t.iter())
            .for_each(|(_, i)| nested_numbers(i, out)),
        Item::None => {}
    }
}

/// Checks every key of `table` (at `path`) against `schema`: calls `report`
/// with the span and message of each problem and pushes the path of each
/// offending key to `removals`.
pub(crate) fn check_table(
    table: &dyn TableLike,
    path: &mut Vec<Seg>,
    schema: &'static [(&'static str, Kind)],
    report: &mut dyn FnMut(Option<Range<usize>>, String),
    removals: &mut Vec<Vec<Seg>>,
    typed: &mut Vec<Retyped>,
) {
    let section = if path.is_empty() {
        "the top level".to_string()
    } else {
        format!("[{}]", dotted(path))
    };
    for (key, item) in table.iter() {
        let key_span = table.key(key).and_then(|k| k.span());
        path.push(Seg::Key(key.to_string()));
        let Some((_, kind)) = schema.iter().find(|(k, _)| *k == key) else {
            let valid: Vec<&str> = schema.iter().map(|(k, _)| *k).collect();
            let hint = if let Some(n) = nearest(key, schema) {
                format!("did you mean `{n}`?")
            } else if let Some((sec, _)) = sections()
                .into_iter()
                .find(|(_, keys)| keys.iter().any(|(k, _)| k.eq_ignore_ascii_case(key)))
            {
                format!("`{key}` belongs in [{sec}]; move it there")
            } else {
                format!("the keys here are: {}", valid.join(", "))
            };
            report(
                key_span.or_else(|| item.span()),
                format!("unknown field `{key}` in {section}; {hint}"),
            );
            removals.push(path.clone());
            path.pop();
            continue;
        };
        let name = dotted(path);
        let span = item.span().or_else(|| key_span.clone());
        // The promise of docs/case-file.md on every number, in one place:
        // the value checks after serde need not repeat it key by key.
        let mut numbers: Vec<&Value> = Vec::new();
        match (kind, item) {
            (Kind::Num, Item::Value(v)) => numbers.push(v),
            (Kind::Vec2, Item::Value(Value::Array(a))) => numbers.extend(a.iter()),
            (Kind::Any, _) => nested_numbers(item, &mut numbers),
            _ => {}
        }
        if let Some(x) = numbers.into_iter().find_map(immoderate) {
            let is = if matches!(kind, Kind::Any) {
                format!("{name} holds {x:e}, which")
            } else {
                format!("{name} = {x:e}")
            };
            if x.is_finite() {
                report(
                    span.clone(),
                    format!(
                        "{is} is beyond what the computation can carry (magnitudes from \
                         1e-100 to 1e100, or 0); choose units that keep the case's values moderate"
                    ),
                );
            } else {
                report(
                    span.clone(),
                    format!(
                        "{is} is not a finite number; give a number (0, or of magnitude \
                         1e-100 to 1e100)"
                    ),
                );
                // As for a wrong type: the value checks would only repeat it.
                typed.push((path.clone(), placeholder(kind), span.clone()));
                path.pop();
                continue;
            }
        }
        let mut wrong = |want: &str, hint: &str| {
            let found = match kind {
                Kind::Vec2 => found_vec2(item),
                _ => found(item),
            };
            report(
                span.clone(),
                format!("{name}: expected {want}, found {found}; {hint}"),
            );
            // A placeholder of the right type keeps the key (and the table's
            // other checks) alive; problems on its line are not reported.
            typed.push((path.clone(), placeholder(kind), span.clone()));
        };
        match (kind, item) {
            (Kind::Any, _) => {}
            (Kind::Str | Kind::Variant(_), Item::Value(Value::String(_))) => {}
            (Kind::Str | Kind::Variant(_), _) => wrong("text", "put it in quotes, e.g. \"...\""),
            (Kind::Num, Item::Value(v)) if is_number(v) => {}
            (Kind::Num, _) => wrong("a number", "write numbers without quotes, e.g. 1e-3"),
            (Kind::Int | Kind::Count, Item::Value(Value::Integer(i))) if *i.value() >= 0 => {}
            // `--set` keeps what TOML cannot read as text: digits beyond
            // i64 are no quoted string.
            (Kind::Int | Kind::Count, Item::Value(Value::String(s)))
                if !s.value().is_empty()
                    && s.value().bytes().all(|b| b.is_ascii_digit())
                    && s.value().parse::<i64>().is_err() =>
            {
                wrong(
                    "a whole number",
                    "that one is beyond the largest a case takes (9223372036854775807); give a \
                     smaller one",
                )
            }
            (Kind::Int, _) => wrong(
                "a whole number >= 0",
                "write it without quotes or decimal point, e.g. 10",
            ),
            (Kind::Count, _) => wrong(
                "a whole number >= 1",
                "write it without quotes or decimal point, e.g. 10",
            ),
            (Kind::Bool, Item::Value(Value::Boolean(_))) => {}
            (Kind::Bool, _) => wrong("true or false", "write true or false without quotes"),
            (Kind::Vec2, Item::Value(Value::Array(a)))
                if a.len() == 2 && a.iter().all(is_number) => {}
            (Kind::Vec2, _) => wrong("a vector of two numbers", "write it as [x, y]"),
            (Kind::StrList, Item::Value(Value::Array(a)))
                if a.iter().all(|v| matches!(v, Value::String(_))) => {}
            (Kind::StrList, _) => wrong(
                "a list of mesh files",
                "write it as [\"meshes/coarse.msh\", \"meshes/fine.msh\"]",
            ),
            (Kind::Table(sub), Item::Table(t)) => {
                check_table(t, path, sub, report, removals, typed)
            }
            (Kind::Table(sub), Item::Value(Value::InlineTable(t))) => {
                check_table(t, path, sub, report, removals, typed)
            }
            (Kind::Table(_), _) => wrong(
                "a table",
                &format!("write it as [{name}] followed by its keys, or {{ key = value }}"),
            ),
            (Kind::OneOrTables(sub), Item::Table(t)) => {
                check_table(t, path, sub, report, removals, typed)
            }
            (Kind::OneOrTables(sub), Item::Value(Value::InlineTable(t))) => {
                check_table(t, path, sub, report, removals, typed)
            }
            (Kind::Tables(sub) | Kind::OneOrTables(sub), Item::ArrayOfTables(a)) => {
                for (i, t) in a.iter().enumerate() {
                    path.push(Seg::Index(i));
                    check_table(t, path, sub, report, removals, typed);
                    path.pop();
                }
            }
            (Kind::Tables(sub) | Kind::OneOrTables(sub), Item::Value(Value::Array(a)))
                if a.iter().all(|v| matches!(v, Value::InlineTable(_))) =>
            {
                for (i, v) in a.iter().enumerate() {
                    if let Value::InlineTable(t) = v {
                        path.push(Seg::Index(i));
                        check_table(t, path, sub, report, removals, typed);
                        path.pop();
                    }
                }
            }
            (Kind::OneOrTables(_), _) => wrong(
                "a table or a list of tables",
                &format!("write it as [{name}] followed by its keys, or one [[{name}]] section per entry"),
            ),
            (Kind::Tables(_), _) => wrong(
                "a list of tables",
                &format!("write one [[{name}]] section per entry"),
            ),
        }
        path.pop();
    }
}

/// A value of the right kind for a key whose value has the wrong type (for
/// the enumerations, a valid variant), or `None` to remove the key (tables).
fn placeholder(kind: &Kind) -> Option<Value> {
    Some(match kind {
        Kind::Variant(valid) => Value::from(*valid),
        Kind::Str => Value::from("placeholder"),
        Kind::Num => Value::from(1.0),
        Kind::Int | Kind::Count => Value::from(1i64),
        Kind::Bool => Value::from(false),
        Kind::Vec2 => Value::Array(toml_edit::Array::from_iter([0.0, 0.0])),
        Kind::StrList => Value::Array(toml_edit::Array::new()),
        Kind::Table(_) | Kind::Tables(_) | Kind::OneOrTables(_) | Kind::Any => return None,
    })
}

/// Removes the key at `path` (as found by [`check_table`]) from a document,
/// or replaces its value by `with` keeping its line.
pub(crate) fn remove_path(table: &mut dyn TableLike, path: &[Seg], with: Option<&Value>) {
    let Some((Seg::Key(k), rest)) = path.split_first() else {
        return;
    };
    if rest.is_empty() {
        match (with, table.get_mut(k)) {
            (Some(v), Some(Item::Value(old))) => {
                let decor = old.decor().clone();
                *old = v.clone();
                *old.decor_mut() = decor;
            }
            _ => {
                table.remove(k);
            }
        }
        return;
    }
    match table.get_mut(k) {
        Some(Item::Table(t)) => remove_path(t, rest, with),
        Some(Item::Value(Value::InlineTable(t))) => remove_path(t, rest, with),
        Some(Item::ArrayOfTables(a)) => {
            if let Some((Seg::Index(i), rest)) = rest.split_first() {
                if let Some(t) = a.get_mut(*i) {
                    remove_path(t, rest, with);
                }
            }
        }
        Some(Item::Value(Value::Array(a))) => {
            if let Some((Seg::Index(i), rest)) = rest.split_first() {
                if let Some(Value::InlineTable(t)) = a.get_mut(*i) {
                    remove_path(t, rest, with);
                }
            }
        }
        _ => {}
    }
}

/// The span of every value of `table` and below, by dotted key (`time.dt`,
/// `dirichlet.0.group`, `time.stick_reduction`): where the value checks
/// point their messages.
pub(crate) fn value_spans(
    table: &dyn TableLike,
    prefix: &str,
    out: &mut BTreeMap<String, Range<usize>>,
) {
    for (key, item) in table.iter() {
        let name = if prefix.is_empty() {
            key.to_string()
        } else {
            format!("{prefix}.{key}")
        };
        if let Some(span) = item
            .span()
            .or_else(|| table.key(key).and_then(|k| k.span()))
        {
            out.insert(name.clone(), span);
        }
        match item {
            Item::Table(t) => value_spans(t, &name, out),
            Item::Value(Value::InlineTable(t)) => value_spans(t, &name, out),
            Item::ArrayOfTables(a) => {
                for (i, t) in a.iter().enumerate() {
                    value_spans(t, &format!("{name}.{i}"), out);
                }
            }
            Item::Value(Value::Array(a)) => {
                for (i, v) in a.iter().enumerate() {
                    if let Value::InlineTable(t) = v {
                        value_spans(t, &format!("{name}.{i}"), out);
                    }
                }
            }
            _ => {}
        }
    }
}
