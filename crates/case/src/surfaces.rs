//! The contact surfaces of a case (`[contact]` or `[[contact]]`): each
//! surface's normal load and friction nodes, its pressure varied along the
//! surface by `pressure_profile` and in time by `pressure_history`, all
//! joined into the one set of friction nodes the integrator takes
//! (friction couples no two nodes, METHOD.md §3).

use stickslip_contact::{ContactError, ContactSurface, Weakening};
use stickslip_fem::{boundary_quadrature, traction_load, traction_load_with, DofMap, Traction};
use stickslip_mesh::Mesh;
use stickslip_time::{History as TimeHistory, Load};

use crate::compliance::compliant_surface;
use crate::schema::{Case, ContactLaw, ContactSection, History, Mu};

/// What the contact surfaces add to a scene.
#[derive(Debug, Default)]
pub(crate) struct Surfaces {
    /// The friction nodes of all surfaces, `None` without any.
    pub contact: Option<ContactSurface>,
    /// Each surface's pressure as a load, in case order.
    pub loads: Vec<Load>,
    /// Each surface's pressure history, in case order.
    pub histories: Vec<TimeHistory>,
    /// Each surface's foundation history, in case order.
    pub foundation_histories: Vec<TimeHistory>,
}

/// Builds the surfaces of `case`, pushing every problem to `problems`.
/// `restrict` maps a full nodal vector to the free DOFs; `history` is the
/// time crate's copy of a history.
pub(crate) fn surfaces(
    case: &Case,
    mesh: &Mesh,
    dofs: &DofMap,
    restrict: &dyn Fn(&[f64]) -> Vec<f64>,
    history: fn(&History) -> TimeHistory,
    problems: &mut Vec<String>,
) -> Surfaces {
    let mut out = Surfaces::default();
    let mut built = Vec::new();
    let mut full = vec![0.0; 2 * mesh.nodes.len()];
    for (i, c) in case.contact.iter().enumerate() {
        let at = |key: &str| case.at(&case.contact_key(i, key));
        let before = problems.len();
        let profile = c
            .pressure_profile
            .as_ref()
            .map(|p| History::Table(p.table.clone()));
        // The quadrature's arc length s locates the profile (as /contact/s).
        let line = match boundary_quadrature(mesh, &c.group) {
            Ok(q) => q,
            Err(e) => {
                problems.push(format!(
                    "{}[contact]: contact group {:?}: {e}",
                    at("group"),
                    c.group
                ));
                continue;
            }
        };
        if c.law == ContactLaw::Compliance {
            // The foundation computes the normal traction: no pressure load.
            match compliant_surface(mesh, dofs, (c, case.initial.state), &at, problems) {
                Ok(s) if problems.len() == before => built.push((i, s)),
                Ok(_) => {}
                Err(e) => problems.push(format!("{}[contact]: {e}", at("group"))),
            }
            // One history of each kind a surface, so that each stays with
            // its part (a compliant foundation is at rest: constant).
            out.histories.push(history(&c.pressure_history));
            out.foundation_histories
                .push(history(&c.foundation_history));
            continue;
        }
        let length = line.last().map_or(0.0, |b| b.s);
        if let Some(p) = &c.pressure_profile {
            if let Some(last) = p.table.last().filter(|r| r[0] > length * (1.0 + 1e-12)) {
                problems.push(format!(
                    "{}[contact]: pressure_profile row s = {} runs past the end of surface {:?}, which is {length} \
                     long (s as in /contact/s, from the line's start); end the table at s <= {length}",
                    at("pressure_profile"),
                    crate::load::Num(last[0]),
                    c.group
                ));
            }
        }
        let pressure = c.pressure.unwrap_or(0.0);
        // The prescribed normal traction on Γ_C is a load like any other,
        // by default present before t = 0 (it makes the initial static
        // state, METHOD.md §3).
        full.iter_mut().for_each(|x| *x = 0.0);
        let load = match &profile {
            None => traction_load(mesh, &c.group, Traction::Pressure(pressure), &mut full),
            Some(f) => {
                let arc = ArcLength::new(mesh, &line);
                let p = pressure;
                let hint = std::cell::Cell::new(0);
                traction_load_with(
                    mesh,
                    &c.group,
                    |x, n| {
                        // p·1 is p: a uniform profile of 1 keeps the bits.
                        let q = p * f.value(arc.at(x, &hint));
                        [-q * n[0], -q * n[1]]
                    },
                    &mut full,
                )
            }
        };
        match load {
            Ok(()) => out.loads.push(Load {
                vector: restrict(&full),
                history: history(&c.pressure_history),
            }),
            Err(e) => problems.push(format!("{}[contact]: {e}", at("group"))),
        }
        match surface(mesh, dofs, c, profile.as_ref()) {
            // Every node's tangential DOF held: the friction the case asks
            // for could act nowhere, and a run without it is not the run
            // the case describes.
            Ok(s) if s.is_empty() => problems.push(format!(
                "{}[contact]: no node of group \"{}\" can slide: [[dirichlet]] conditions hold the tangential \
                 motion of all its {} nodes, so friction would act nowhere; remove the [[dirichlet]] on the \
                 contact surface's tangential direction, or remove [contact] for a run without friction",
                at("group"),
                c.group,
                s.excluded.len()
            )),
            Ok(s) if problems.len() == before => built.push((i, s)),
            Ok(_) => {}
            Err(e) => problems.push(format!("{}[contact]: {e}", at("group"))),
        }
        out.histories.push(history(&c.pressure_history));
        out.foundation_histories
            .push(history(&c.foundation_history));
    }
    if !problems.is_empty() || built.is_empty() {
        return out;
    }
    let last = built.last().map_or(0, |b| b.0);
    // Each built surface's foundation speed, kept only where one moves,
    // and its fall of μ with the slip speed (g = μs p times μ(|w|)/μs =
    // r + (1 − r) e^{−|w|/vs}).
    let speeds: Vec<f64> = built
        .iter()
        .map(|(i, _)| case.contact[*i].foundation_velocity)
        .collect();
    let weakening: Vec<Option<Weakening>> = built
        .iter()
        .map(|(i, _)| match case.contact[*i].mu {
            None | Some(Mu::Constant(_)) => None,
            Some(Mu::Speed {
                stat,
                kinetic,
                speed,
            }) => Some(Weakening {
                ratio: if stat > 0.0 { kinetic / stat } else { 1.0 },
                speed,
            }),
        })
        .collect();
    match ContactSurface::join(built.into_iter().map(|(_, s)| s).collect()) {
        Ok(mut s) => {
            let part = s.part_of_nodes();
            if speeds.iter().any(|&v| v != 0.0) {
                s.set_foundation(|j| speeds[part[j]]);
            }
            s.set_weakening(|j| weakening[part[j]]);
            out.contact = Some(s);
        }
        Err(ContactError::Overlap {
            node,
            first,
            second,
        }) => problems.push(format!(
            "{}[[contact]]: node {} at ({}, {}) carries friction on both surface {first:?} and surface {second:?}; \
             a node carries the friction of one surface only: make the groups disjoint (end one line a node \
             short of the other), or join them into one group with one normal law and mu",
            case.at(&case.contact_key(last, "group")),
            mesh.node_tags.get(node).copied().unwrap_or(node as u64),
            mesh.nodes[node][0],
            mesh.nodes[node][1]
        )),
        Err(e) => problems.push(format!(
            "{}[[contact]]: {e}",
            case.at(&case.contact_key(last, "group"))
        )),
    }
    out
}

/// One surface's friction nodes, g_J = μ·|p|·profile(s_J).
fn surface(
    mesh: &Mesh,
    dofs: &DofMap,
    c: &ContactSection,
    profile: Option<&History>,
) -> Result<ContactSurface, ContactError> {
    let mut s = ContactSurface::from_group(
        mesh,
        dofs,
        &c.group,
        c.pressure.unwrap_or(0.0),
        c.mu_at_rest(),
        c.eps,
    )?;
    if let Some(f) = profile {
        let built: Vec<(f64, f64)> = s.nodes.iter().map(|n| (n.bound, n.s)).collect();
        s.set_bounds(|j| built[j].0 * f.value(built[j].1));
        // A profile is part of how the surface is built, not a change.
        s.revision = 0;
    }
    Ok(s)
}

/// The arc length s of a point on a line group: the nearest chord between
/// neighbouring nodes of its nodal quadrature, s linear along it (exact
/// on straight edges; on curved quadratic edges within the chord's sag).
struct ArcLength {
    points: Vec<([f64; 2], f64)>,
}

impl ArcLength {
    fn new(mesh: &Mesh, line: &[stickslip_fem::BoundaryNode]) -> ArcLength {
        ArcLength {
            points: line.iter().map(|b| (mesh.nodes[b.node], b.s)).collect(),
        }
    }

    /// s at `x`; `hint` is the chord found last (the loads visit a line's
    /// edges mostly in order), tried first.
    fn at(&self, x: [f64; 2], hint: &std::cell::Cell<usize>) -> f64 {
        let last = hint.get();
        let chords = self.points.len().saturating_sub(1);
        if chords == 0 {
            return 0.0;
        }
        let on = |k: usize| -> (f64, f64) {
            let ((a, sa), (b, sb)) = (self.points[k], self.points[k + 1]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let len2 = d[0] * d[0] + d[1] * d[1];
            let t = if len2 > 0.0 {
                (((x[0] - a[0]) * d[0] + (x[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (px, py) = (a[0] + t * d[0] - x[0], a[1] + t * d[1] - x[1]);
            (px * px + py * py, sa + t * (sb - sa))
        };
        // The hint's chord and its neighbours first: a point on one of
        // them (to rounding) is on the line there.
        let near = last.saturating_sub(1)..(last + 2).min(chords);
        let mut best = (f64::INFINITY, 0.0, 0);
        for k in near.chain(0..chords) {
            let (d2, s) = on(k);
            if d2 < best.0 {
                best = (d2, s, k);
            }
            let (a, b) = (self.points[k].0, self.points[k + 1].0);
            let scale = (b[0] - a[0]).abs() + (b[1] - a[1]).abs();
            if d2 <= (1e-9 * scale).powi(2) {
                break;
            }
        }
        hint.set(best.2);
        best.1
    }
}
