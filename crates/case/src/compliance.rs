//! The keys of a contact surface's normal law: a prescribed pressure
//! (`law = "pressure"`, the default) takes `pressure` and `mu`; a
//! compliant foundation (`law = "compliance"`, METHOD.md §10) takes
//! `foundation`, `cn`, `mn` and `mu` or `ct`, `mt`. Each law refuses the
//! other's keys, so that a key that would change nothing is never silently
//! ignored.

use stickslip_contact::{Compliance, ContactError, ContactSurface};
use stickslip_fem::DofMap;
use stickslip_mesh::Mesh;

use crate::load::Num;
use crate::schema::{ContactLaw, ContactSection, History, InitialState, Mu};

/// The compliance law's keys, refused on a prescribed-pressure surface.
const COMPLIANCE_KEYS: [&str; 5] = ["foundation", "cn", "mn", "ct", "mt"];

/// Checks surface `c`'s law keys through `check(ok, key, message)`;
/// `key` gives a key's dotted path on this surface; `reported(k)`: key `k`
/// had a value, reported already as wrong and taken out, so it is not
/// missing (`mu = nan` was also "needs mu = ...").
pub(crate) fn check_law(
    c: &ContactSection,
    key: &dyn Fn(&str) -> String,
    reported: &dyn Fn(&str) -> bool,
    check: &mut dyn FnMut(bool, &str, String),
) {
    let given = |k: &str| match k {
        "foundation" => c.foundation.is_some(),
        "cn" => c.cn.is_some(),
        "mn" => c.mn.is_some(),
        "ct" => c.ct.is_some(),
        "mt" => c.mt.is_some(),
        _ => false,
    };
    if c.law == ContactLaw::Pressure {
        for k in COMPLIANCE_KEYS.into_iter().filter(|k| given(k)) {
            check(
                false,
                &key(k),
                format!(
                    "contact.{k} belongs to law = \"compliance\", but this surface has a prescribed \
                     pressure (law = \"pressure\", the default): remove {k}, or set law = \"compliance\" \
                     for a compliant foundation"
                ),
            );
        }
        for (k, v, what) in [
            ("pressure", c.pressure.is_some(), "the normal pressure F_n"),
            ("mu", c.mu.is_some(), "the Coulomb coefficient"),
        ] {
            check(
                v || reported(k),
                &key("group"),
                format!(
                    "contact (group {:?}) needs {k} = ..., {what}, for its prescribed-pressure law; \
                     or set law = \"compliance\" with a foundation",
                    c.group
                ),
            );
        }
        return;
    }
    check_compliance(c, key, reported, check);
}

fn check_compliance(
    c: &ContactSection,
    key: &dyn Fn(&str) -> String,
    reported: &dyn Fn(&str) -> bool,
    check: &mut dyn FnMut(bool, &str, String),
) {
    let law = key("law");
    for (k, given) in [
        ("pressure", c.pressure.is_some()),
        ("pressure_profile", c.pressure_profile.is_some()),
        ("pressure_history", c.pressure_history != History::Constant),
    ] {
        check(
            !given,
            &key(k),
            format!(
                "contact.{k} belongs to a prescribed pressure, but this surface has law = \
                 \"compliance\": the foundation computes the normal traction; remove {k}"
            ),
        );
    }
    match &c.foundation {
        None => check(
            reported("foundation"),
            &law,
            "law = \"compliance\" needs foundation = { point = [x, y], normal = [nx, ny] } (a \
             straight rigid foundation, its normal pointing towards the body)"
                .into(),
        ),
        Some(f) => {
            let [nx, ny] = f.normal;
            check(
                nx.hypot(ny) > 0.0,
                &key("foundation"),
                "contact.foundation.normal = [0, 0] has no direction; give the foundation's normal \
                 pointing towards the body, e.g. [0.0, 1.0] for a floor below it"
                    .into(),
            );
        }
    }
    match c.cn {
        None => check(
            reported("cn"),
            &law,
            "law = \"compliance\" needs cn = ..., the foundation's stiffness c_n > 0 (σ_n = c_n δ^mn)"
                .into(),
        ),
        Some(cn) => check(
            cn > 0.0,
            &key("cn"),
            format!("contact.cn = {} must be > 0: the foundation's stiffness, σ_n = cn δ^mn", Num(cn)),
        ),
    }
    for k in ["mn", "mt"] {
        let v = if k == "mn" { c.mn } else { c.mt };
        if let Some(m) = v {
            check(
                m >= 1.0,
                &key(k),
                format!(
                    "contact.{k} = {} must be >= 1: a power below 1 has an infinite stiffness at \
                     first touch; 1 is a linear spring",
                    Num(m)
                ),
            );
        }
    }
    // A moving compliant foundation and μ(w) against it are not built:
    // the keys would otherwise change nothing, silently.
    for (k, given, remedy) in [
        (
            "foundation_velocity",
            c.foundation_velocity != 0.0,
            "remove foundation_velocity",
        ),
        (
            "foundation_history",
            c.foundation_history != History::Constant,
            "remove foundation_history",
        ),
        (
            "mu",
            matches!(c.mu, Some(Mu::Speed { .. })),
            "give a constant mu",
        ),
    ] {
        check(
            !given,
            &key(k),
            format!(
                "contact.{k}: law = \"compliance\" takes a foundation at rest and a constant mu \
                 (a moving or speed-dependent friction runs with prescribed pressures); {remedy}, \
                 or use law = \"pressure\" with a pressure"
            ),
        );
    }
    match (c.mu.as_ref().map(Mu::at_rest), c.ct) {
        (Some(_), Some(_)) => check(
            false,
            &key("ct"),
            "contact: give mu (c_T = mu cn, mt = mn) or ct (with mt), not both".into(),
        ),
        (None, None) => check(
            reported("mu") || reported("ct"),
            &law,
            "law = \"compliance\" needs mu = ... (c_T = mu cn, mt = mn) or ct = ... (the friction \
             bound c_T δ^mt); mu = 0 for a frictionless foundation"
                .into(),
        ),
        (_, Some(ct)) => check(
            ct >= 0.0,
            &key("ct"),
            format!("contact.ct = {} must be >= 0: the friction bound is ct δ^mt", Num(ct)),
        ),
        (Some(_), None) => check(
            c.mt.is_none(),
            &key("mt"),
            "contact.mt goes with ct; with mu the friction bound is mu cn δ^mn (mt = mn): remove mt, \
             or give ct in place of mu"
                .into(),
        ),
    }
}

/// Surface `c` of `law = "compliance"` on its foundation, its keys checked
/// already. A node that starts inside the foundation by more than a
/// rounding of the mesh's size is, for a start at `rest`, a problem pushed
/// to `problems` (it would be released with a jolt of c_n δ₀^{m_n}); one
/// within rounding starts touching it. The static start keeps such an
/// interference: its preload (the frictionless static problem with the
/// foundation, convex) settles it into equilibrium before t = 0.
pub(crate) fn compliant_surface(
    mesh: &Mesh,
    dofs: &DofMap,
    (c, start): (&ContactSection, InitialState),
    at: &dyn Fn(&str) -> String,
    problems: &mut Vec<String>,
) -> Result<ContactSurface, ContactError> {
    let f = c
        .foundation
        .as_ref()
        .expect("checked: law = \"compliance\" has a foundation");
    let length = f.normal[0].hypot(f.normal[1]);
    let normal = [f.normal[0] / length, f.normal[1] / length];
    let cn = c.cn.expect("checked: law = \"compliance\" has cn");
    let mn = c.mn.unwrap_or(1.0);
    let (ct, mt) = match c.ct {
        Some(ct) => (ct, c.mt.unwrap_or(mn)),
        None => (c.mu_at_rest() * cn, mn),
    };
    let law = Compliance { cn, mn, ct, mt };
    let mut s = ContactSurface::on_foundation(mesh, dofs, &c.group, (f.point, normal), law, c.eps)?;
    let size = mesh
        .nodes
        .iter()
        .flat_map(|x| x.iter())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    let tolerance = 1e-9 * size.max(f.point[0].abs()).max(f.point[1].abs());
    // The node of a message, and how many others the same problem has:
    // one message a problem, not one a node.
    let node_at = |node: usize| {
        let x = mesh.nodes[node];
        let tag = mesh.node_tags.get(node).copied().unwrap_or(node as u64);
        format!("node {tag} at ({}, {})", x[0], x[1])
    };
    let others = |n: usize| match n {
        0 => String::new(),
        1 => " (and 1 other node of it)".to_string(),
        n => format!(" (and {n} other nodes of it)"),
    };
    // The approach is read from a node's free components (a held one does
    // not move); one held at a value other than 0 along the normal would
    // move the node into or off the foundation unseen.
    let held: Vec<(usize, &str, f64)> = s
        .compliance
        .iter()
        .flat_map(|k| {
            let node = s.nodes[k.index].node;
            ["ux", "uy"]
                .into_iter()
                .enumerate()
                .filter_map(move |(a, axis)| {
                    let v = dofs.prescribed(node, a).filter(|&v| v != 0.0)?;
                    (normal[a].abs() > 1e-12).then_some((node, axis, v))
                })
        })
        .collect();
    if let Some(&(node, axis, v)) = held.first() {
        problems.push(format!(
            "{}[contact]: {} of group {:?}{} has {axis} = {v} from a [[dirichlet]] condition, \
             along the foundation's normal: the compliance law measures the approach by the free \
             components only, so it would not see that motion; hold the nodes at 0 along the \
             normal, or prescribe the motion on another group",
            at("foundation"),
            node_at(node),
            c.group,
            others(held.len() - 1),
        ));
    }
    let mut inside = Vec::new();
    for k in &mut s.compliance {
        if k.gap >= -tolerance {
            k.gap = k.gap.max(0.0);
        } else if start == InitialState::Rest {
            inside.push((s.nodes[k.index].node, -k.gap));
        }
    }
    // The deepest, the first of equals.
    let deepest = inside
        .iter()
        .fold(None, |best: Option<&(usize, f64)>, x| match best {
            Some(b) if b.1 >= x.1 => Some(b),
            _ => Some(x),
        });
    if let Some(&(node, depth)) = deepest {
        problems.push(format!(
            "{}[contact]: {} of group {:?}{} starts {depth:e} inside the foundation (the deepest; \
             a start at rest would release it with the foundation's full push); start the part \
             off or touching the foundation (move foundation.point, or the mesh), or start from \
             the static state ([initial] state = \"static\"), which settles the interference",
            at("foundation"),
            node_at(node),
            c.group,
            others(inside.len() - 1),
        ));
    }
    Ok(s)
}
