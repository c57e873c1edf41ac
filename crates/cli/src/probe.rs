//! `stickslip probe OUT.h5 --at X,Y [--field ..] [--csv]`: the time history
//! of one field at the node nearest to a point, read from a results file.

use std::fmt::Write as _;
use std::path::Path;

use hdf5::File;
use ndarray::s;

use crate::error::InputError;

/// A field that can be probed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Field {
    /// Displacement u_x.
    Ux,
    /// Displacement u_y.
    Uy,
    /// Velocity v_x.
    Vx,
    /// Velocity v_y.
    Vy,
    /// Acceleration a_x.
    Ax,
    /// Acceleration a_y.
    Ay,
    /// Friction stress σ_T along τ (contact nodes only).
    #[value(name = "friction_stress")]
    FrictionStress,
}

impl Field {
    fn name(self) -> &'static str {
        match self {
            Field::Ux => "ux",
            Field::Uy => "uy",
            Field::Vx => "vx",
            Field::Vy => "vy",
            Field::Ax => "ax",
            Field::Ay => "ay",
            Field::FrictionStress => "friction_stress",
        }
    }
}

/// What `probe` prints: `info` says which node was used, `table` holds the
/// history (with `--csv` the info goes to stderr so stdout stays pure CSV).
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    /// Node index, its coordinates and distance to the point asked for.
    pub info: String,
    /// `t` and the field, one line per output step.
    pub table: String,
    /// The node used (0-based index into /mesh/nodes).
    pub node: usize,
    /// The times.
    pub t: Vec<f64>,
    /// The field's values.
    pub values: Vec<f64>,
}

/// Parses `X,Y`.
fn parse_point(at: &str) -> Result<[f64; 2], InputError> {
    let bad = || {
        InputError(format!(
            "--at {at:?}: expected two numbers X,Y, e.g. --at 8,0"
        ))
    };
    let (x, y) = at.split_once(',').ok_or_else(bad)?;
    let x: f64 = x.trim().parse().map_err(|_| bad())?;
    let y: f64 = y.trim().parse().map_err(|_| bad())?;
    if !(x.is_finite() && y.is_finite()) {
        return Err(bad());
    }
    Ok([x, y])
}

/// Reads the history of `field` at the node of `file` nearest to `at`.
///
/// # Errors
/// A bad point, a file that is not a stickslip results file, or
/// `friction_stress` asked at a node that is not on the contact surface.
pub fn probe(file: &Path, at: &str, field: Field, csv: bool) -> Result<Probe, InputError> {
    let p = parse_point(at)?;
    let name = file.display().to_string();
    let h5 = |what: &str, e: hdf5::Error| {
        InputError(format!(
            "{name}: {what}: {e}; give a results file written by `stickslip run`"
        ))
    };
    let f = File::open(file).map_err(|e| h5("cannot open it as HDF5", e))?;
    let nodes = f
        .dataset("mesh/nodes")
        .and_then(|d| d.read_2d::<f64>())
        .map_err(|e| h5("cannot read /mesh/nodes", e))?;
    if nodes.ncols() != 2 || nodes.nrows() == 0 {
        return Err(InputError(format!(
            "{name}: /mesh/nodes has shape {:?}, expected [n, 2] with n > 0",
            nodes.shape()
        )));
    }
    let dist = |i: usize| ((nodes[[i, 0]] - p[0]).powi(2) + (nodes[[i, 1]] - p[1]).powi(2)).sqrt();
    let node = (0..nodes.nrows())
        .min_by(|&a, &b| dist(a).total_cmp(&dist(b)))
        .expect("n > 0");
    let t = f
        .dataset("time")
        .and_then(|d| d.read_1d::<f64>())
        .map_err(|e| h5("cannot read /time", e))?
        .to_vec();

    let values: Vec<f64> = match field {
        Field::FrictionStress => {
            let contact = f
                .dataset("contact/nodes")
                .and_then(|d| d.read_1d::<i64>())
                .map_err(|e| h5("this file has no contact surface (/contact/nodes)", e))?;
            let Some(j) = contact.iter().position(|&c| c == node as i64) else {
                let nearest = contact
                    .iter()
                    .filter_map(|&c| usize::try_from(c).ok().filter(|&c| c < nodes.nrows()))
                    .min_by(|&a, &b| dist(a).total_cmp(&dist(b)));
                let hint = nearest.map_or(String::new(), |c| {
                    format!(
                        "; the nearest contact node is {c} at ({}, {}): use --at {},{}",
                        nodes[[c, 0]],
                        nodes[[c, 1]],
                        nodes[[c, 0]],
                        nodes[[c, 1]]
                    )
                });
                return Err(InputError(format!(
                    "{name}: node {node} at ({}, {}), nearest to ({}, {}), is not a contact node, so it has no friction stress{hint}",
                    nodes[[node, 0]], nodes[[node, 1]], p[0], p[1]
                )));
            };
            f.dataset("contact/friction_stress")
                .and_then(|d| d.read_slice_1d::<f64, _>(s![.., j]))
                .map_err(|e| h5("cannot read /contact/friction_stress", e))?
                .to_vec()
        }
        _ => {
            let (ds, comp) = match field {
                Field::Ux => ("displacement", 0),
                Field::Uy => ("displacement", 1),
                Field::Vx => ("velocity", 0),
                Field::Vy => ("velocity", 1),
                Field::Ax => ("acceleration", 0),
                _ => ("acceleration", 1),
            };
            f.dataset(ds)
                .and_then(|d| d.read_slice_1d::<f64, _>(s![.., node, comp]))
                .map_err(|e| h5(&format!("cannot read /{ds}"), e))?
                .to_vec()
        }
    };
    if values.len() != t.len() {
        return Err(InputError(format!(
            "{name}: /time has {} entries but {} has {}",
            t.len(),
            field.name(),
            values.len()
        )));
    }

    let complete = f
        .attr("complete")
        .and_then(|a| a.read_scalar::<bool>())
        .unwrap_or(false);
    let mut info = format!(
        "node {node} at ({}, {}), distance {:.3e} from ({}, {}); {} output steps",
        nodes[[node, 0]],
        nodes[[node, 1]],
        dist(node),
        p[0],
        p[1],
        t.len()
    );
    if !complete {
        info.push_str(" (the run did not complete)");
    }
    info.push('\n');
    let mut table = String::new();
    if csv {
        let _ = writeln!(table, "t,{}", field.name());
        for (t, v) in t.iter().zip(&values) {
            let _ = writeln!(table, "{t:e},{v:e}");
        }
    } else {
        let _ = writeln!(table, "{:>14}  {:>14}", "t", field.name());
        for (t, v) in t.iter().zip(&values) {
            let _ = writeln!(table, "{t:>14.6e}  {v:>14.6e}");
        }
    }
    Ok(Probe {
        info,
        table,
        node,
        t,
        values,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{Header, Record, ResultsWriter, Summary};

    /// Writes 4 steps for the two-cell mesh of output.rs's tests, with
    /// u_x(node i, step k) = 10 k + i, σ_T(contact j, step k) = k − j.
    fn write(path: &Path) {
        let mesh = crate::output::tests::tiny_mesh();
        let header = Header {
            case_source: "",
            mesh: &mesh,
            contact_nodes: &[0, 1, 2],
            contact_s: &[0.0, 1.0, 2.0],
        };
        let mut w = ResultsWriter::create(path, &header).unwrap();
        for k in 0..4 {
            let d: Vec<f64> = (0..12)
                .map(|i| {
                    if i % 2 == 0 {
                        10.0 * k as f64 + (i / 2) as f64
                    } else {
                        -1.0
                    }
                })
                .collect();
            let v: Vec<f64> = (0..12)
                .map(|i| if i % 2 == 1 { 0.5 * k as f64 } else { 0.0 })
                .collect();
            let fs: Vec<f64> = (0..3).map(|j| k as f64 - j as f64).collect();
            w.append(&Record {
                t: 0.25 * k as f64,
                displacement: &d,
                velocity: &v,
                acceleration: &d,
                friction_stress: &fs,
                slip_velocity: &[0.0; 3],
                state: &[0; 3],
                kinetic: 0.0,
                strain: 0.0,
                external_work: 0.0,
                dissipated: 0.0,
                total: 0.0,
                balance: 0.0,
                dt: 0.25,
                iterations: 1,
            })
            .unwrap();
        }
        w.finish(true, &Summary::default()).unwrap();
    }

    #[test]
    fn probe_nearest_node_and_fields() {
        let _guard = crate::output::tests::h5_lock();
        let path = std::env::temp_dir().join(format!("stickslip-probe-{}.h5", std::process::id()));
        write(&path);
        // (1.9, 0.2) is nearest to node 2 at (2, 0): distance sqrt(0.01 + 0.04).
        let p = probe(&path, "1.9,0.2", Field::Ux, false).unwrap();
        assert_eq!(p.node, 2);
        assert_eq!(p.t, vec![0.0, 0.25, 0.5, 0.75]);
        assert_eq!(p.values, vec![2.0, 12.0, 22.0, 32.0]);
        assert!(
            p.info.contains("node 2 at (2, 0), distance 2.236e-1"),
            "{}",
            p.info
        );
        assert_eq!(
            probe(&path, "2,0", Field::Vy, false).unwrap().values,
            vec![0.0, 0.5, 1.0, 1.5]
        );
        // Contact node 1 is index 1 along the surface: σ_T = k − 1.
        let fs = probe(&path, "1,0", Field::FrictionStress, true).unwrap();
        assert_eq!(fs.values, vec![-1.0, 0.0, 1.0, 2.0]);
        assert!(
            fs.table.starts_with("t,friction_stress\n0e0,-1e0\n"),
            "{}",
            fs.table
        );
        // Node 4 at (1, 1) is not on the contact line.
        let e = probe(&path, "1,1", Field::FrictionStress, false)
            .unwrap_err()
            .0;
        assert!(
            e.contains("node 4") && e.contains("not a contact node") && e.contains("--at 1,0"),
            "{e}"
        );
        assert!(probe(&path, "1;1", Field::Ux, false)
            .unwrap_err()
            .0
            .contains("expected two numbers"));
        std::fs::remove_file(&path).ok();
        let e = probe(&path, "0,0", Field::Ux, false).unwrap_err().0;
        assert!(e.contains("cannot open it as HDF5"), "{e}");
    }
}
