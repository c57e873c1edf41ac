//! The case text with the chosen configuration, for `--write`.

use std::path::{Component, Path, PathBuf};

use anyhow::Context;

use stickslip_case::{self as case, Case, Method, PAPER_REDUCTION};

use super::candidates::Candidate;
use super::ladder::LadderMesh;

/// `path` relative to the directory `base` (both made absolute first).
fn relative_to(path: &Path, base: &Path) -> PathBuf {
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let (p, b) = (abs(path), abs(base));
    let pc: Vec<Component> = p.components().collect();
    let bc: Vec<Component> = b.components().collect();
    let common = pc.iter().zip(&bc).take_while(|(a, b)| a == b).count();
    if common == 0 {
        return p;
    }
    let mut out = PathBuf::new();
    for _ in common..bc.len() {
        out.push("..");
    }
    for c in &pc[common..] {
        out.push(c.as_os_str());
    }
    out
}

/// The case text with the chosen configuration, for `--write OUT.toml`:
/// the case as written (comments and layout kept, by toml_edit) with
/// `mesh.file`, `[time]` and `contact.eps` changed; paths are rewritten
/// relative to OUT's directory when it is not the case's.
///
/// # Errors
/// The case text does not parse (it did when it was loaded).
pub fn adjusted_case(
    case: &Case,
    c: &Candidate,
    ladder: &[LadderMesh],
    out: &Path,
    header: &str,
) -> anyhow::Result<String> {
    use toml_edit::{value, Array, InlineTable, Item, Value};
    let mut doc: toml_edit::DocumentMut = case
        .source
        .parse()
        .with_context(|| format!("{}: the case text no longer parses", case.path.display()))?;
    let case_dir = case.path.parent().unwrap_or(Path::new("")).to_path_buf();
    let out_dir = out.parent().unwrap_or(Path::new("")).to_path_buf();
    let same_dir = std::fs::canonicalize(if case_dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        &case_dir
    })
    .ok()
        == std::fs::canonicalize(if out_dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            &out_dir
        })
        .ok();
    let rel = |m: &LadderMesh| -> String {
        if same_dir {
            m.text.clone()
        } else {
            relative_to(
                &m.path,
                if out_dir.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    &out_dir
                },
            )
            .display()
            .to_string()
        }
    };
    let set = |t: &mut toml_edit::Table, k: &str, v: Value| match t.get_mut(k) {
        Some(Item::Value(old)) => {
            let decor = old.decor().clone();
            *old = v;
            *old.decor_mut() = decor;
        }
        _ => {
            t.insert(k, Item::Value(v));
        }
    };
    let mesh = doc["mesh"]
        .as_table_mut()
        .context("[mesh] is not a table")?;
    set(mesh, "file", Value::from(rel(&ladder[c.mesh_index])));
    if !same_dir {
        if let Some(Item::Value(Value::Array(a))) = mesh.get_mut("ladder") {
            let new: Array = ladder.iter().map(|m| Value::from(rel(m))).collect();
            for (slot, v) in a.iter_mut().zip(new.iter()) {
                let decor = slot.decor().clone();
                *slot = v.clone();
                *slot.decor_mut() = decor;
            }
        }
    }
    let time = doc["time"]
        .as_table_mut()
        .context("[time] is not a table")?;
    match c.method.newmark() {
        None => {
            set(time, "scheme", Value::from("central_difference"));
            time.remove("beta");
            time.remove("gamma");
        }
        Some((beta, gamma)) => {
            set(time, "scheme", Value::from("newmark"));
            set(time, "beta", Value::from(beta));
            set(time, "gamma", Value::from(gamma));
        }
    }
    set(time, "dt", Value::from(c.dt));
    time.remove("mass");
    time.remove("allow_unstable");
    if c.method == Method::TrapezoidalReduced {
        let r = case.time.stick_reduction.unwrap_or(PAPER_REDUCTION);
        let mut t = InlineTable::new();
        t.insert("dt", Value::from(r.dt));
        t.insert("steps", Value::from(r.steps as i64));
        time.remove("stick_reduction");
        time.insert("stick_reduction", value(t));
    } else {
        time.remove("stick_reduction");
    }
    // Every surface shares the one ε: [contact] or each [[contact]].
    let mut tables: Vec<&mut dyn toml_edit::TableLike> = match &mut doc["contact"] {
        Item::ArrayOfTables(a) => a
            .iter_mut()
            .map(|t| t as &mut dyn toml_edit::TableLike)
            .collect(),
        Item::None => Vec::new(),
        other => vec![other
            .as_table_like_mut()
            .context("[contact] is not a table")?],
    };
    for contact in tables.iter_mut() {
        match contact.get_mut("eps") {
            Some(Item::Value(old)) => {
                let decor = old.decor().clone();
                *old = Value::from(c.eps);
                *old.decor_mut() = decor;
            }
            _ => {
                contact.insert("eps", value(c.eps));
            }
        }
    }
    let mut text = String::new();
    for line in header.lines() {
        text.push_str("# ");
        text.push_str(line);
        text.push('\n');
    }
    text.push_str(&doc.to_string());
    // What we write must load as a case.
    case::load_str(out, &text, &[])
        .map_err(|e| anyhow::anyhow!("the adjusted case does not load: {}", e.0))?;
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths() {
        assert_eq!(
            relative_to(Path::new("/a/b/m.msh"), Path::new("/a/c")),
            PathBuf::from("../b/m.msh")
        );
    }
}
