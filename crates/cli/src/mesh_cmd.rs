//! `stickslip mesh FILE.msh [--json]`: what is in a mesh file, or what is
//! wrong with it (JSON keys in DESIGN.md).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use serde_json::json;
use stickslip_mesh::Mesh;

use stickslip_case::InputError;

/// Reads `path` and returns the report to print (a table, or one JSON object).
///
/// # Errors
/// The mesh reader's error (file, line or byte offset, what to do).
pub fn report(path: &Path, as_json: bool) -> Result<String, InputError> {
    let mesh = Mesh::from_file(path)?;
    Ok(if as_json {
        to_json(&mesh).to_string()
    } else {
        to_table(path, &mesh)
    })
}

/// The DESIGN.md object: format, version, binary, nodes, cells,
/// boundary_elements, groups, bbox, reoriented, unused_nodes.
pub fn to_json(mesh: &Mesh) -> serde_json::Value {
    // Gmsh lets groups of different dimensions share a name; an object
    // keeps one value a key, so later ones get their dimension (and, for a
    // hand-made same-dimension twin, their tag) in the key.
    let mut groups = serde_json::Map::new();
    for g in &mesh.groups {
        let value = json!({"dim": g.dim, "elements": g.elements, "nodes": g.nodes.len()});
        let key = [
            g.name.clone(),
            format!("{} (dim {})", g.name, g.dim),
            format!("{} (dim {} tag {})", g.name, g.dim, g.tag),
        ]
        .into_iter()
        .find(|k| !groups.contains_key(k))
        .unwrap_or_default();
        groups.insert(key, value);
    }
    let cells: BTreeMap<&str, usize> = [(mesh.kind.name(), mesh.n_cells())].into();
    json!({
        "format": "msh",
        "version": mesh.source.version,
        "binary": mesh.source.binary,
        "nodes": mesh.nodes.len(),
        "cells": cells,
        "boundary_elements": mesh.source.boundary_elements,
        "groups": groups,
        "bbox": mesh.bbox(),
        "reoriented": mesh.source.reoriented,
        "unused_nodes": mesh.source.unused_nodes,
        "warnings": warnings(mesh)
            .into_iter()
            .chain(empty_groups(mesh))
            .chain(twin_groups(mesh))
            .collect::<Vec<_>>(),
    })
}

/// What in the mesh runs but is likely not meant: nearly degenerate cells.
fn warnings(mesh: &Mesh) -> Vec<String> {
    stickslip_mesh::degenerate_cells(mesh, stickslip_mesh::DEGENERATE_RATIO)
        .map(|d| d.to_string())
        .into_iter()
        .collect()
}

/// A note for each physical group without elements: Gmsh keeps a group
/// whose entities are missing (`Physical Curve("load") = {7};` without a
/// curve 7) as a name alone, which a case cannot use (it would act on
/// nothing; `check` and `run` refuse it).
fn empty_groups(mesh: &Mesh) -> Vec<String> {
    mesh.groups
        .iter()
        .filter(|g| g.elements == 0)
        .map(|g| {
            format!(
                "group {:?} (dim {}) has no elements: {}; a case cannot use it",
                g.name,
                g.dim,
                g.empty_remedy()
            )
        })
        .collect()
}

/// A note for each name two physical groups of one dimension share (a
/// hand-made or merged file: Gmsh gives a name one group a dimension): a
/// case names a group by its name, so `check` and `run` refuse a case
/// that names this one.
fn twin_groups(mesh: &Mesh) -> Vec<String> {
    mesh.groups
        .iter()
        .enumerate()
        .filter_map(|(i, g)| {
            let first = mesh.groups[..i]
                .iter()
                .find(|h| h.name == g.name && h.dim == g.dim)?;
            Some(format!(
                "groups {} and {} (dim {}) are both named {:?}: a case names a group by its name, \
                 so `check` and `run` refuse a case that names it; rename one of them in the .geo",
                first.tag, g.tag, g.dim, g.name
            ))
        })
        .collect()
}

fn to_table(path: &Path, mesh: &Mesh) -> String {
    let mut s = String::new();
    let enc = if mesh.source.binary {
        "binary"
    } else {
        "ASCII"
    };
    let _ = writeln!(
        s,
        "{}: Gmsh MSH {} {enc}",
        path.display(),
        mesh.source.version
    );
    let _ = writeln!(s, "  nodes        {}", mesh.nodes.len());
    if mesh.source.unused_nodes > 0 {
        let _ = writeln!(
            s,
            "  unused nodes  {} dropped (in no cell: Gmsh's Mesh.SaveAll or geometry points)",
            mesh.source.unused_nodes
        );
    }
    let _ = writeln!(s, "  cells        {} {}", mesh.n_cells(), mesh.kind.name());
    let boundary: Vec<String> = mesh
        .source
        .boundary_elements
        .iter()
        .map(|(k, v)| format!("{v} {k}"))
        .collect();
    let boundary = if boundary.is_empty() {
        "none".to_string()
    } else {
        boundary.join(", ")
    };
    let _ = writeln!(s, "  boundary     {boundary}");
    let [[x0, y0], [x1, y1]] = mesh.bbox();
    let _ = writeln!(s, "  bbox         x in [{x0}, {x1}], y in [{y0}, {y1}]");
    let _ = writeln!(
        s,
        "  reoriented   {} cells (given clockwise, turned counter-clockwise)",
        mesh.source.reoriented
    );
    for w in warnings(mesh) {
        let _ = writeln!(s, "  warning: {w}");
    }
    if mesh.groups.is_empty() {
        let _ = writeln!(s, "  no physical groups: name the boundary parts in Gmsh (Physical Curve(\"contact\") = {{..}};)");
        return s;
    }
    let w = mesh
        .groups
        .iter()
        .map(|g| g.name.len())
        .max()
        .unwrap_or(0)
        .max(5);
    let _ = writeln!(s, "  physical groups:");
    let _ = writeln!(
        s,
        "    {:<w$}  {:>3}  {:>8}  {:>6}",
        "name", "dim", "elements", "nodes"
    );
    for g in &mesh.groups {
        let _ = writeln!(
            s,
            "    {:<w$}  {:>3}  {:>8}  {:>6}",
            g.name,
            g.dim,
            g.elements,
            g.nodes.len()
        );
    }
    for note in empty_groups(mesh).into_iter().chain(twin_groups(mesh)) {
        let _ = writeln!(s, "  note: {note}");
    }
    // Not an error (an interior line may be meant), but a traction or
    // contact surface there would act inside the body.
    for g in &mesh.groups {
        let k = mesh.interior_edges(g);
        if k > 0 {
            let _ = writeln!(
                s,
                "  note: group {:?} has {k} {} inside the body (shared by two cells); as a traction or contact surface it would act inside the body",
                g.name,
                if k == 1 { "edge" } else { "edges" }
            );
        }
    }
    s
}
