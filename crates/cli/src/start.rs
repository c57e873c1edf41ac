//! Where a run starts: a new results file holding the case, the mesh and
//! the initial state, or a stored run continued from its checkpoint
//! (`run --restart`), checked against the case and the mesh and restored
//! into the integrator.

use std::path::Path;

use anyhow::Context;
use stickslip_case::{self as case, Case};
use stickslip_fem::{DofMap, NodeOrder};
use stickslip_mesh::Mesh;
use stickslip_time::Integrator;

use crate::output::{self, Header, ResultsWriter};
use crate::run::{input, record, setup_warnings, FullState};

/// The results file a run writes to, opened, and what it carries over.
pub(crate) struct Opened {
    pub(crate) writer: ResultsWriter,
    /// Wall time of the runs before (a restart's).
    pub(crate) wall_before: f64,
    /// Largest |energy balance| so far.
    pub(crate) max_balance: f64,
    /// Times of the records written.
    pub(crate) times: Vec<f64>,
    /// Kinetic + strain energy at t = 0, for the blow-up test.
    pub(crate) initial_mechanical: f64,
}

/// A fresh run's file: created with the case, the mesh and the contact
/// nodes, its first record the initial state; the setup warnings said.
pub(crate) fn fresh(
    case: &Case,
    out: &Path,
    mesh: &Mesh,
    dofs: &DofMap,
    integrator: &Integrator,
    full: &mut FullState,
) -> anyhow::Result<Opened> {
    let (contact_nodes, contact_s): (Vec<usize>, Vec<f64>) = integrator
        .contact()
        .map(|c| c.nodes.iter().map(|n| (n.node, n.s)).unzip())
        .unwrap_or_default();
    let contact_lines: Vec<[usize; 2]> = integrator
        .contact()
        .into_iter()
        .flat_map(|c| &c.parts)
        .flat_map(|p| crate::views::contact_lines(mesh, &p.group, &contact_nodes))
        .collect();
    let (contact_surface, contact_groups): (Vec<usize>, Vec<String>) = integrator
        .contact()
        .map(|c| {
            (
                c.part_of_nodes(),
                c.parts.iter().map(|p| p.group.clone()).collect(),
            )
        })
        .unwrap_or_default();
    let header = Header {
        case_source: &case.source,
        mesh,
        contact_nodes: &contact_nodes,
        contact_s: &contact_s,
        contact_lines: &contact_lines,
        contact_surface: &contact_surface,
        contact_groups: &contact_groups,
    };
    let mut writer = ResultsWriter::create_with(
        out,
        &header,
        case.output.deflate_level().unwrap_or(output::DEFLATE_LEVEL),
    )
    .with_context(|| format!("cannot create the results file {}", out.display()))?;
    // The initial state is frame 0.
    writer.append(&record(integrator, dofs, full, (0.0, 0), true))?;
    // Kept in the file and printed with --quiet too: quiet silences
    // progress, not what the user should know.
    let warnings = setup_warnings(case, mesh, dofs, &full.u, integrator);
    for w in &warnings {
        say!("{}: warning: {w}", case.path.display());
    }
    writer.set_warnings(&warnings)?;
    let e0 = integrator.energy();
    Ok(Opened {
        writer,
        wall_before: 0.0,
        max_balance: 0.0,
        times: vec![integrator.time()],
        initial_mechanical: e0.kinetic + e0.strain,
    })
}

/// A restart's file: its checkpoint read and checked against the case
/// and the mesh, restored into `integrator` (in this run's node order and
/// with the stored run's solver), the file opened to append.
pub(crate) fn resume(
    case: &Case,
    out: &Path,
    quiet: bool,
    mesh: &Mesh,
    dofs: &DofMap,
    integrator: &mut Integrator,
) -> anyhow::Result<Opened> {
    let stored = output::read_checkpoint(out)
        .map_err(|e| input(format!("--restart {}: {e:#}", out.display())))?;
    let changes = case::restart_changes(&stored.case_source, &case.source)
        .map_err(|e| input(format!("--restart {}: {e}", out.display())))?;
    if !changes.is_empty() {
        return Err(input(format!(
            "{}: --restart {}: the case changes what the stored run computed:\n  {}\n\
             a restart may change only time.t_end, output.*, title, mesh.ladder and contact.max_iterations; undo those changes, or start a new run with -o NEW.h5",
            case.path.display(),
            out.display(),
            changes.join("\n  ")
        )));
    }
    if let Some(change) = output::stored_mesh_change(out, mesh)
        .map_err(|e| input(format!("--restart {}: {e:#}", out.display())))?
    {
        return Err(input(format!(
            "{}: --restart {}: {} has changed since the run began ({change}); restart with \
             the mesh the run began on, or start a new run with -o NEW.h5",
            case.path.display(),
            out.display(),
            case.mesh.file.display()
        )));
    }
    let cp = &stored.checkpoint;
    if case.time.t_end < cp.t {
        return Err(input(format!(
            "{}time.t_end = {} is before the checkpoint's t = {} in {}; give a t_end >= {}",
            case.at("time.t_end"),
            case.time.t_end,
            cp.t,
            out.display(),
            cp.t
        )));
    }
    // A state stored in another node order (a file of a version
    // before the node orders, or STICKSLIP_DOF_ORDER changed) is read
    // into this run's numbering.
    let remapped;
    let n_free = dofs.n_free();
    let lengths_fit = [&cp.displacement, &cp.velocity, &cp.acceleration]
        .iter()
        .all(|x| x.len() == n_free);
    // (Other lengths: `restore` says what is wrong.)
    let cp = if stored.extra.node_order != dofs.node_order().code() && lengths_fit {
        let theirs = NodeOrder::from_code(stored.extra.node_order)
            .and_then(|order| dofs.renumbered(mesh, order))
            .ok_or_else(|| {
                input(format!(
                    "--restart {}: its state's node_order {} does not apply to {} (a newer version's order, or a structured grid's on a mesh that is none); restart with the version and the mesh the run started from",
                    out.display(),
                    stored.extra.node_order,
                    case.mesh.file.display()
                ))
            })?;
        let to_ours = |x: &[f64]| dofs.from_numbering(&theirs, x);
        remapped = stickslip_time::Checkpoint {
            displacement: to_ours(&cp.displacement),
            velocity: to_ours(&cp.velocity),
            acceleration: to_ours(&cp.acceleration),
            ..cp.clone()
        };
        &remapped
    } else {
        cp
    };
    integrator
        .restore(cp)
        .map_err(|e| input(format!("--restart {}: {e}", out.display())))?;
    // A restart to the checkpoint's own time takes no step: it ends on
    // the checkpoint's state, whose fields need that state's row, which
    // output.every = n may have left out.
    let row_there = stored.times.last().map(|t| t.to_bits()) == Some(cp.t.to_bits());
    if integrator.done() && !row_there {
        return Err(input(format!(
            "{}time.t_end = {} ends the run at the checkpoint's t = {} in {}, a step without a \
             row of its own (output.every), so its last step would have no fields; give a \
             t_end > {}",
            case.at("time.t_end"),
            case.time.t_end,
            cp.t,
            out.display(),
            cp.t
        )));
    }
    let n_c = integrator.contact().map_or(0, |c| c.len());
    // As a new run's records: the rest of the run must fit on the disk
    // with the room the run keeps, or it would stop part way (or HDF5
    // fail mid-write on a full disk). The records in proportion to the
    // time left: an estimate, as the new run's.
    let share = ((case.time.t_end - cp.t) / case.time.t_end).clamp(0.0, 1.0);
    let size = crate::run::output_size(case, mesh.nodes.len(), n_c, n_free).share(share);
    // A restart to the checkpoint's own time adds no step (`conclude`
    // checks the room where it adds a frame).
    if let Some(free) = size
        .short_of_room(out, false)
        .filter(|_| !integrator.done())
    {
        use crate::run::human_bytes;
        return Err(input(format!(
            "{}: --restart {}: the rest of the run (t = {} to {}) would add about {} frames and \
             {} rows ({}) and keeps {} free beside them while it writes, but the disk has {} \
             free; shorten time.t_end, write fewer frames (output.frames, output.interval, \
             output.every: a restart may change them), or make room",
            case.path.display(),
            out.display(),
            cp.t,
            case.time.t_end,
            size.frames,
            size.rows,
            human_bytes(size.bytes),
            human_bytes(size.kept),
            human_bytes(free as f64)
        )));
    }
    ResultsWriter::check_appendable(out)?;
    // Only now that the restart is accepted: a refused one leaves every
    // file as it was. Before the results change, so that no companion
    // outlives the records it lists.
    crate::run::forget_companions(out, quiet);
    let mut writer = ResultsWriter::open_append(
        out,
        (stored.extra.rows, stored.extra.frames),
        mesh.nodes.len(),
        n_c,
    )?;
    writer.set_case(&case.source)?;
    if !quiet {
        say!(
            "restart: continuing {} from step {}, t = {} ({} records and {} frames kept)",
            out.display(),
            cp.steps,
            cp.t,
            stored.extra.rows,
            stored.extra.frames
        );
    }
    Ok(Opened {
        writer,
        wall_before: stored.extra.wall_time_s,
        max_balance: stored.extra.max_balance,
        times: stored.times,
        initial_mechanical: stored.checkpoint.initial_mechanical,
    })
}
