//! The case's `mesh.ladder`: each mesh prepared once and checked (it fits
//! the case, it is the same body, the probe can be placed on it).

use std::path::PathBuf;

use stickslip_case::{prepare, Case, Method};

use super::input;
use super::pilots::probe_of;
use super::quantity::Quantity;

/// One mesh of the ladder, as the case sees it.
#[derive(Clone, Debug)]
pub struct LadderMesh {
    /// Resolved path.
    pub path: PathBuf,
    /// As written in the case.
    pub text: String,
    /// Element order.
    pub order: u8,
    /// Cells.
    pub cells: usize,
    /// Free DOFs.
    pub dofs: usize,
    /// Stored entries of K.
    pub nnz: usize,
    /// Contact nodes.
    pub contact_nodes: usize,
    /// Central difference's critical step (lumped mass).
    pub dt_crit: f64,
    /// Position of the probed node (None for the energy).
    pub node_at: Option<[f64; 2]>,
}

/// Reads the ladder of `case`: each mesh prepared once (groups checked,
/// order, DOFs, Δt_crit, probe position).
///
/// # Errors
/// No ladder, a mesh the case does not fit, a probe that cannot be placed.
pub fn read_ladder(
    case: &Case,
    q: Quantity,
    at: Option<[f64; 2]>,
) -> anyhow::Result<Vec<LadderMesh>> {
    if case.mesh.ladder.len() < 2 {
        return Err(input(format!(
            "{}mesh.ladder: advise needs at least two meshes of one element order to estimate the \
             discretization error in h; add e.g. ladder = [\"coarse.msh\", \"medium.msh\", \"fine.msh\"] \
             to [mesh] (same geometry and group names, coarse to fine)",
            case.at(if case.mesh.ladder.is_empty() { "mesh.file" } else { "mesh.ladder" })
        )));
    }
    let mut out = Vec::new();
    // The first mesh's extent, which every other must share: a ladder is
    // one geometry refined (10% slack per side: a coarse mesh of a curved
    // boundary falls short of it).
    let mut first: Option<(String, [[f64; 2]; 2])> = None;
    for (path, text) in case.mesh.ladder.iter().zip(&case.mesh.ladder_text) {
        if !path.is_file() {
            return Err(input(format!(
                "{}mesh.ladder entry {text:?}: {} does not exist (paths are relative to the case file's directory); \
                 check the name, or make the mesh with Gmsh",
                case.at("mesh.ladder"),
                path.display()
            )));
        }
        // A Newmark set-up never refuses a Δt; the static solve checks the supports.
        let mut c = Method::Trapezoidal.configure(case, path, case.time.t_end / 50.0, eps_of(case));
        // The mesh read here is the entry's, not mesh.file's: a problem
        // with it is placed at mesh.ladder, said once.
        if let Some(at) = case.locations.get("mesh.ladder") {
            c.locations.insert("mesh.file".into(), at.clone());
        }
        let p = prepare(&c).map_err(|e| {
            let at = case.at("mesh.ladder");
            input(format!(
                "{at}mesh.ladder entry {text:?}: {}",
                e.0.strip_prefix(&at).unwrap_or(&e.0)
            ))
        })?;
        let b = p.mesh.bbox();
        let size = (b[1][0] - b[0][0]).max(b[1][1] - b[0][1]);
        let show = |b: [[f64; 2]; 2]| {
            format!(
                "x in [{}, {}], y in [{}, {}]",
                b[0][0], b[1][0], b[0][1], b[1][1]
            )
        };
        match &first {
            None => {
                if let Some(p) = at {
                    if crate::probe::off_the_body(b, p) {
                        return Err(input(format!(
                            "--at {},{}: the point lies outside the mesh ({}); give a point on the body",
                            p[0],
                            p[1],
                            show(b)
                        )));
                    }
                }
                first = Some((text.clone(), b));
            }
            Some((t0, b0)) => {
                let apart = (0..2)
                    .flat_map(|i| (0..2).map(move |k| (b[i][k] - b0[i][k]).abs()))
                    .fold(0.0_f64, f64::max);
                if apart > 0.1 * size {
                    return Err(input(format!(
                        "{}mesh.ladder entry {text:?} spans {} but {t0:?} spans {}: a ladder is one \
                         geometry meshed finer and finer; give meshes of the same body",
                        case.at("mesh.ladder"),
                        show(b),
                        show(*b0)
                    )));
                }
            }
        }
        let (_, node_at) = probe_of(&c, &p, q, at)?;
        let dt_crit =
            stickslip_time::stability::critical_step(&p.model.stiffness, &p.model.lumped_mass);
        out.push(LadderMesh {
            path: path.clone(),
            text: text.clone(),
            order: match p.mesh.kind {
                stickslip_mesh::CellKind::Quad4 => 1,
                stickslip_mesh::CellKind::Quad9 => 2,
            },
            cells: p.mesh.n_cells(),
            dofs: p.model.dofs.n_free(),
            nnz: p.model.stiffness.nnz(),
            contact_nodes: p.integrator.contact().map_or(0, |c| c.len()),
            dt_crit,
            node_at,
        });
    }
    Ok(out)
}

/// The case's ε (NaN without a [contact] section).
pub(super) fn eps_of(case: &Case) -> f64 {
    case.contact.first().map_or(f64::NAN, |c| c.eps)
}
