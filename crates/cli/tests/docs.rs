//! The documentation's case files are real: every ```toml block in
//! README.md and docs/*.md is a complete case that `stickslip check`
//! accepts (unknown keys are refused, every value validated), with its
//! mesh path, written relative to the repository root, made absolute.

use std::path::Path;

mod common;
use common::scratch;
use common::{check, root, succeeded};

/// (file, first line, text) of every ```toml block of a Markdown file.
fn toml_blocks(path: &Path) -> Vec<(String, usize, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut out = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        let fence = line.trim_start().starts_with("```");
        if let Some((start, body)) = current.take() {
            if fence {
                out.push((path.display().to_string(), start, body));
            } else {
                current = Some((start, body + line + "\n"));
            }
        } else if line.trim_start().starts_with("```toml") {
            current = Some((i + 2, String::new()));
        }
    }
    assert!(
        current.is_none(),
        "{}: a ```toml block is not closed",
        path.display()
    );
    out
}

#[test]
fn every_documented_case_passes_check() {
    let root = root();
    let mut files = vec![root.join("README.md")];
    for e in std::fs::read_dir(root.join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            files.push(p);
        }
    }
    let blocks: Vec<_> = files.iter().flat_map(|f| toml_blocks(f)).collect();
    assert!(
        blocks.len() >= 2,
        "expected the case-file reference's examples, found {} toml blocks",
        blocks.len()
    );
    let dir = scratch("docs");
    for (k, (file, line, body)) in blocks.iter().enumerate() {
        // [mesh] file is relative to the repository root in the docs.
        let mut doc: toml::Table = body
            .parse()
            .unwrap_or_else(|e| panic!("{file}:{line}: not TOML: {e}"));
        let mesh = doc
            .get_mut("mesh")
            .and_then(|m| m.as_table_mut())
            .unwrap_or_else(|| panic!("{file}:{line}: no [mesh] table"));
        let rel = mesh["file"].as_str().unwrap().to_string();
        let abs = root.join(&rel);
        assert!(abs.is_file(), "{file}:{line}: mesh {rel} does not exist");
        // Replace the value in the text itself, so comments and layout are
        // checked exactly as documented.
        let text = body.replacen(
            &format!("\"{rel}\""),
            &toml::Value::String(abs.display().to_string()).to_string(),
            1,
        );
        let case = dir.join(format!("doc-{k}.toml"));
        std::fs::write(&case, &text).unwrap();
        let what = format!("{file}:{line}: the documented case fails `stickslip check`");
        succeeded(&check(&case, &[]), &what);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The `cargo xtask SUB` commands the README and docs name are ones
/// xtask/src/main.rs dispatches.
#[test]
fn documented_xtask_commands_exist() {
    let root = root();
    let mut text = std::fs::read_to_string(root.join("README.md")).unwrap();
    for e in std::fs::read_dir(root.join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            text.push_str(&std::fs::read_to_string(p).unwrap());
        }
    }
    let xtask = std::fs::read_to_string(root.join("xtask/src/main.rs")).unwrap();
    for word in text.split("cargo xtask ").skip(1) {
        let sub: String = word
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
            .collect();
        assert!(
            xtask.contains(&format!("\"{sub}\"")),
            "the docs mention `cargo xtask {sub}`, which xtask/src/main.rs does not dispatch"
        );
    }
}
