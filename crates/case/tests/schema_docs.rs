//! docs/case-file.md lists the keys the schema has, no more and no fewer:
//! every key of its TOML examples (the ```toml blocks and the indented
//! ones) is a key of the schema, and every key of the schema appears in one
//! of them. The schema's keys come from the types serde fills
//! (`stickslip_case::schema`), not from a list written beside them.

use std::collections::BTreeSet;

use stickslip_case::schema::{key_paths, Kind, ROOT};

/// The TOML examples of a Markdown page: fenced ```toml blocks and blocks
/// indented by four spaces.
fn examples(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut fenced: Option<String> = None;
    let mut indented: Option<String> = None;
    for line in text.lines() {
        if let Some(body) = fenced.as_mut() {
            if line.trim_start().starts_with("```") {
                out.push(fenced.take().unwrap_or_default());
            } else {
                body.push_str(line);
                body.push('\n');
            }
            continue;
        }
        if line.trim_start().starts_with("```toml") {
            fenced = Some(String::new());
            continue;
        }
        match (line.strip_prefix("    "), indented.as_mut()) {
            (Some(l), Some(body)) => {
                body.push_str(l);
                body.push('\n');
            }
            (Some(l), None) => indented = Some(format!("{l}\n")),
            (None, _) => {
                if let Some(body) = indented.take() {
                    out.push(body);
                }
            }
        }
    }
    out.extend(indented);
    out
}

/// The dotted keys of `table` (no list indices), read along the schema:
/// a key the schema does not have is listed as it is and not entered.
fn keys_of(table: &toml::Table, schema: &[(&str, Kind)], prefix: &str, out: &mut BTreeSet<String>) {
    for (key, value) in table {
        let name = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        let kind = schema.iter().find(|(k, _)| k == key).map(|(_, kind)| kind);
        match (kind, value) {
            (Some(Kind::Table(sub)), toml::Value::Table(t)) => keys_of(t, sub, &name, out),
            (Some(Kind::OneOrTables(sub)), toml::Value::Table(t)) => keys_of(t, sub, &name, out),
            (Some(Kind::Tables(sub) | Kind::OneOrTables(sub)), toml::Value::Array(a)) => {
                for t in a.iter().filter_map(toml::Value::as_table) {
                    keys_of(t, sub, &name, out);
                }
            }
            _ => {
                out.insert(name);
            }
        }
    }
}

#[test]
fn the_documented_keys_are_the_schema() {
    let page = stickslip_testkit::workspace_root().join("docs/case-file.md");
    let text = std::fs::read_to_string(&page).expect("docs/case-file.md");
    let mut documented = BTreeSet::new();
    let mut read = 0;
    for example in examples(&text) {
        // Indented blocks that are no TOML (shell commands) are not examples.
        if let Ok(t) = example.parse::<toml::Table>() {
            keys_of(&t, ROOT, "", &mut documented);
            read += 1;
        }
    }
    assert!(read >= 3, "expected the page's examples, read {read}");
    let schema: BTreeSet<String> = key_paths().into_iter().collect();
    let undocumented: Vec<&String> = schema.difference(&documented).collect();
    let unknown: Vec<&String> = documented.difference(&schema).collect();
    assert!(
        undocumented.is_empty(),
        "keys of the schema that no example of docs/case-file.md shows: {undocumented:?}"
    );
    assert!(
        unknown.is_empty(),
        "keys in docs/case-file.md that the schema does not have: {unknown:?}"
    );
}
