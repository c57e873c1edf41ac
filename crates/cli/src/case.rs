//! The case file: TOML in, a validated [`Case`] out (DESIGN.md "Case file").
//!
//! Loading goes in four steps, so that every message can name the file and
//! the line the user has to edit:
//! 1. parse the text with `toml_edit` (syntax errors, original lines);
//! 2. apply the `--set KEY=VALUE` overrides to that document, which keeps the
//!    rest of the text (and its comments) as written; the result is
//!    [`Case::source`], the case as run;
//! 3. deserialize with serde (`deny_unknown_fields`, spans kept on the values
//!    that are validated);
//! 4. validate every value, collecting all problems before reporting.
//!
//! Lines of the final text are mapped back to the user's file by a line diff;
//! a problem on a line that `--set` changed is reported against that `--set`.

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;
use toml_edit::{Item, TableLike, Value};

use crate::error::InputError;

/// A validated case: everything a run needs besides the mesh itself.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// The case file as given on the command line.
    pub path: PathBuf,
    /// The TOML text as run (after `--set`), stored in the results file.
    pub source: String,
    /// Free-text title.
    pub title: Option<String>,
    /// The mesh.
    pub mesh: MeshSection,
    /// Linear elastic material.
    pub material: MaterialSection,
    /// Prescribed displacements, one entry per group.
    pub dirichlet: Vec<DirichletSection>,
    /// Prescribed tractions, one entry per group.
    pub traction: Vec<TractionSection>,
    /// Constant body force per unit volume (bx, by), if any.
    pub body_force: Option<[f64; 2]>,
    /// The frictional contact surface, if any.
    pub contact: Option<ContactSection>,
    /// Time integration.
    pub time: TimeSection,
    /// Results file.
    pub output: OutputSection,
}

/// `[mesh]`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshSection {
    /// The `.msh` file, resolved against the case file's directory.
    pub file: PathBuf,
}

/// Plane strain or plane stress.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Hypothesis {
    /// ε_zz = 0 (the paper's slab).
    #[default]
    PlaneStrain,
    /// σ_zz = 0.
    PlaneStress,
}

/// `[material]`.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSection {
    /// Young's modulus (TOML key `E`).
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
    /// Mass density.
    pub rho: f64,
    /// Plane strain (default) or plane stress.
    pub hypothesis: Hypothesis,
}

/// One `[[dirichlet]]` table: a component left out stays free.
#[derive(Clone, Debug, PartialEq)]
pub struct DirichletSection {
    /// Physical group name.
    pub group: String,
    /// Prescribed u_x.
    pub ux: Option<f64>,
    /// Prescribed u_y.
    pub uy: Option<f64>,
}

/// One `[[traction]]` table: exactly one of `t` and `pressure` is set.
#[derive(Clone, Debug, PartialEq)]
pub struct TractionSection {
    /// Physical group name (a line group).
    pub group: String,
    /// Traction vector (t_x, t_y).
    pub t: Option<[f64; 2]>,
    /// Normal pressure (positive pushes into the body).
    pub pressure: Option<f64>,
    /// Time factor multiplying the load.
    pub history: History,
}

/// Time factor of a load. TOML: `"constant"`, `"step"`,
/// `{ sin = { omega = .. } }` or `{ table = [[t0, f0], ..] }`; default `"step"`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum History {
    /// 1 for all t, t < 0 included: part of the initial static state.
    Constant,
    /// Heaviside H(t) with H(0) = 1: on from t = 0, not in the static state.
    Step,
    /// sin(ω t).
    Sin {
        /// Angular frequency ω (rad per unit time).
        omega: f64,
    },
    /// Piecewise linear through (t_i, f_i), constant beyond the ends.
    Table(Vec<[f64; 2]>),
}

impl History {
    /// The factor at time `t` (run.rs hands the history to the time crate,
    /// which evaluates its own copy; this one documents and tests the schema).
    #[cfg_attr(not(test), allow(dead_code))]
    pub fn value(&self, t: f64) -> f64 {
        match self {
            History::Constant => 1.0,
            History::Step => {
                if t >= 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
            History::Sin { omega } => (omega * t).sin(),
            History::Table(p) => {
                let (Some(first), Some(last)) = (p.first(), p.last()) else {
                    return 0.0;
                };
                if t <= first[0] {
                    return first[1];
                }
                if t >= last[0] {
                    return last[1];
                }
                // First point with t_i > t; validation guarantees increasing t_i.
                let i = p.partition_point(|q| q[0] <= t);
                let (a, b) = (p[i - 1], p[i]);
                a[1] + (b[1] - a[1]) * (t - a[0]) / (b[0] - a[0])
            }
        }
    }
}

/// `[contact]`: the regularized Coulomb friction surface (METHOD.md).
#[derive(Clone, Debug, PartialEq)]
pub struct ContactSection {
    /// Line group on which friction acts.
    pub group: String,
    /// Prescribed normal pressure F_n (friction bound g = μ F_n).
    pub pressure: f64,
    /// Coulomb coefficient μ.
    pub mu: f64,
    /// Regularization ε of the friction law.
    pub eps: f64,
    /// The paper's Remark 4.2 rule in the iteration (default true).
    pub remark_4_2: bool,
    /// Iteration cap per step (default 100).
    pub max_iterations: usize,
}

/// Time integration scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scheme {
    /// Explicit, lumped mass (β = 0, γ = ½).
    CentralDifference,
    /// Implicit Newmark (β, γ).
    Newmark,
}

/// Mass matrix kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MassKind {
    /// Consistent mass.
    Consistent,
    /// HRZ-lumped (diagonal) mass.
    Lumped,
}

/// Remark 4.3 step reduction after a slip-to-stick transition.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StickReduction {
    /// The reduced step.
    pub dt: f64,
    /// How many reduced steps follow each sticking event.
    pub steps: usize,
}

/// `[time]`.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeSection {
    /// Central difference or Newmark.
    pub scheme: Scheme,
    /// Newmark β (default 0.25; ignored for central difference).
    pub beta: f64,
    /// Newmark γ (default 0.5; ignored for central difference).
    pub gamma: f64,
    /// Mass override; `None` = the scheme's default (lumped for central
    /// difference, consistent for Newmark).
    pub mass: Option<MassKind>,
    /// Time step.
    pub dt: f64,
    /// End time.
    pub t_end: f64,
    /// Remark 4.3 step reduction, if asked for.
    pub stick_reduction: Option<StickReduction>,
    /// Run an explicit scheme above Δt_crit anyway.
    pub allow_unstable: bool,
}

/// `[output]`.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputSection {
    /// Results file, resolved against the case file's directory
    /// (default `<case stem>.h5` next to the case file).
    pub file: PathBuf,
    /// Write every `every`-th step (default 1).
    pub every: usize,
}

// ---------------------------------------------------------------------------
// What serde reads: the same shape, with spans on everything validated.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCase {
    title: Option<String>,
    mesh: RawMesh,
    material: RawMaterial,
    #[serde(default)]
    dirichlet: Vec<RawDirichlet>,
    #[serde(default)]
    traction: Vec<RawTraction>,
    body_force: Option<Spanned<[f64; 2]>>,
    contact: Option<RawContact>,
    time: RawTime,
    #[serde(default)]
    output: RawOutput,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    file: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    #[serde(rename = "E")]
    e: Spanned<f64>,
    nu: Spanned<f64>,
    rho: Spanned<f64>,
    #[serde(default)]
    hypothesis: Hypothesis,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDirichlet {
    group: Spanned<String>,
    ux: Option<f64>,
    uy: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTraction {
    group: Spanned<String>,
    t: Option<[f64; 2]>,
    pressure: Option<f64>,
    history: Option<Spanned<History>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawContact {
    group: Spanned<String>,
    pressure: Spanned<f64>,
    mu: Spanned<f64>,
    eps: Spanned<f64>,
    remark_4_2: Option<bool>,
    max_iterations: Option<Spanned<usize>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTime {
    scheme: Spanned<Scheme>,
    beta: Option<Spanned<f64>>,
    gamma: Option<Spanned<f64>>,
    mass: Option<Spanned<MassKind>>,
    dt: Spanned<f64>,
    t_end: Spanned<f64>,
    stick_reduction: Option<Spanned<RawStickReduction>>,
    allow_unstable: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStickReduction {
    dt: Spanned<f64>,
    steps: Spanned<usize>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    file: Option<Spanned<String>>,
    every: Option<Spanned<usize>>,
}

// ---------------------------------------------------------------------------

/// Reads, overrides (`--set KEY=VALUE`, VALUE parsed as TOML, else taken as a
/// string) and validates a case file.
///
/// # Errors
/// An [`InputError`] listing every problem found, each as
/// `file:line:col: what; what to do` (or `--set KEY=VALUE: ...`).
pub fn load(path: &Path, sets: &[String]) -> Result<Case, InputError> {
    let file = path.display().to_string();
    let original = std::fs::read_to_string(path).map_err(|e| {
        InputError(format!(
            "{file}: cannot read the case file: {e}; check the path"
        ))
    })?;
    load_str(path, &original, sets)
}

/// [`load`] on text already in memory (`path` names it and anchors relative paths).
///
/// # Errors
/// As [`load`].
pub fn load_str(path: &Path, original: &str, sets: &[String]) -> Result<Case, InputError> {
    let file = path.display().to_string();
    let mut doc: toml_edit::DocumentMut = original.parse().map_err(|e: toml_edit::TomlError| {
        let at = e.span().map(|s| line_col(original, s.start));
        InputError(format!(
            "{}: invalid TOML: {}; fix the syntax there",
            at.map_or(file.clone(), |(l, c)| format!("{file}:{l}:{c}")),
            e.message().trim_end()
        ))
    })?;
    for s in sets {
        apply_set(&mut doc, s).map_err(|m| InputError(format!("--set {s}: {m}")))?;
    }
    let source = if sets.is_empty() {
        original.to_string()
    } else {
        doc.to_string()
    };
    let loc = Locator::new(&file, original, &source, sets);

    let raw: RawCase = toml::from_str(&source).map_err(|e| {
        let msg = e.message().trim_end().to_string();
        let hint = if msg.starts_with("unknown field") {
            "; check the spelling (DESIGN.md \"Case file\" lists the keys)"
        } else if msg.starts_with("missing field") {
            "; add it (DESIGN.md \"Case file\" lists the keys)"
        } else if msg.contains("variant") {
            "; use one of the values listed"
        } else if msg.starts_with("invalid type") || msg.starts_with("invalid length") {
            "; numbers go without quotes, text in quotes, vectors as [x, y]"
        } else {
            ""
        };
        InputError(format!("{}: {msg}{hint}", loc.at(e.span())))
    })?;
    let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
    convert(raw, path, &base, source.clone(), &loc)
        .map_err(|problems| InputError(problems.join("\n")))
}

/// Builds the public [`Case`], or the list of every problem found.
fn convert(
    raw: RawCase,
    path: &Path,
    base: &Path,
    source: String,
    loc: &Locator,
) -> Result<Case, Vec<String>> {
    let mut bad = Vec::new();
    let mut check = |ok: bool, span: Range<usize>, msg: String| {
        if !ok {
            bad.push(format!("{}: {msg}", loc.at(Some(span))));
        }
    };

    // [mesh]
    let mesh_file = base.join(raw.mesh.file.get_ref());
    check(
        mesh_file.is_file(),
        raw.mesh.file.span(),
        format!(
            "mesh.file: {} does not exist (paths are relative to the case file's directory); \
             check the name, or make the mesh with Gmsh",
            mesh_file.display()
        ),
    );

    // [material]
    let m = &raw.material;
    let (e, nu, rho) = (*m.e.get_ref(), *m.nu.get_ref(), *m.rho.get_ref());
    check(
        e > 0.0,
        m.e.span(),
        format!("material.E = {e} must be > 0; give Young's modulus"),
    );
    check(
        rho > 0.0,
        m.rho.span(),
        format!("material.rho = {rho} must be > 0; give the mass density"),
    );
    check(
        nu > -1.0 && nu < 0.5,
        m.nu.span(),
        format!("material.nu = {nu} must lie in (-1, 0.5); 0.5 (incompressible) cannot be modelled with displacements only"),
    );

    // [[dirichlet]]
    for (i, d) in raw.dirichlet.iter().enumerate() {
        check(
            d.ux.is_some() || d.uy.is_some(),
            d.group.span(),
            format!(
                "dirichlet #{} (group {:?}) fixes neither ux nor uy; add ux = .. and/or uy = ..",
                i + 1,
                d.group.get_ref()
            ),
        );
        let finite = d.ux.is_none_or(f64::is_finite) && d.uy.is_none_or(f64::is_finite);
        check(
            finite,
            d.group.span(),
            format!("dirichlet #{}: ux/uy must be finite numbers", i + 1),
        );
    }

    // [[traction]]
    for (i, t) in raw.traction.iter().enumerate() {
        let what = format!("traction #{} (group {:?})", i + 1, t.group.get_ref());
        check(
            t.t.is_some() != t.pressure.is_some(),
            t.group.span(),
            format!(
                "{what} must give exactly one of t = [tx, ty] and pressure = p; it gives {}",
                if t.t.is_some() { "both" } else { "neither" }
            ),
        );
        let finite = t.t.is_none_or(|v| v.iter().all(|x| x.is_finite()))
            && t.pressure.is_none_or(f64::is_finite);
        check(
            finite,
            t.group.span(),
            format!("{what}: t and pressure must be finite numbers"),
        );
        if let Some(h) = &t.history {
            match h.get_ref() {
                History::Sin { omega } => check(
                    omega.is_finite(),
                    h.span(),
                    format!("{what}: history sin omega = {omega} must be a finite number"),
                ),
                History::Table(p) => {
                    let increasing = p.windows(2).all(|w| w[1][0] > w[0][0]);
                    let finite = p.iter().flatten().all(|x| x.is_finite());
                    check(
                        !p.is_empty() && increasing && finite,
                        h.span(),
                        format!("{what}: history table needs at least one [t, f] pair, finite values and strictly increasing times; e.g. {{ table = [[0.0, 0.0], [0.1, 1.0]] }}"),
                    );
                }
                History::Constant | History::Step => {}
            }
        }
    }

    if let Some(b) = &raw.body_force {
        check(
            b.get_ref().iter().all(|x| x.is_finite()),
            b.span(),
            "body_force must be finite numbers".into(),
        );
    }

    // [contact]
    if let Some(c) = &raw.contact {
        let (p, mu, eps) = (*c.pressure.get_ref(), *c.mu.get_ref(), *c.eps.get_ref());
        check(p >= 0.0, c.pressure.span(), format!("contact.pressure = {p} must be >= 0 (it presses the body onto the surface; g = mu * pressure)"));
        check(
            mu >= 0.0,
            c.mu.span(),
            format!("contact.mu = {mu} must be >= 0; use 0 for frictionless contact"),
        );
        check(eps > 0.0, c.eps.span(), format!("contact.eps = {eps} must be > 0 (the friction law's regularization; the paper uses 1e-4 to 1)"));
        if let Some(n) = &c.max_iterations {
            check(
                *n.get_ref() > 0,
                n.span(),
                "contact.max_iterations must be >= 1 (default 100)".into(),
            );
        }
    }

    // [time]
    let tm = &raw.time;
    let scheme = *tm.scheme.get_ref();
    let (dt, t_end) = (*tm.dt.get_ref(), *tm.t_end.get_ref());
    check(
        dt > 0.0 && dt.is_finite(),
        tm.dt.span(),
        format!("time.dt = {dt} must be > 0"),
    );
    check(
        t_end > 0.0 && t_end.is_finite(),
        tm.t_end.span(),
        format!("time.t_end = {t_end} must be > 0"),
    );
    let beta = tm.beta.as_ref().map_or(0.25, |b| *b.get_ref());
    let gamma = tm.gamma.as_ref().map_or(0.5, |g| *g.get_ref());
    if scheme == Scheme::Newmark {
        // Unconditional stability of Newmark's method: 2β ≥ γ ≥ ½ (Hughes, The
        // Finite Element Method, §9.1).
        let span = tm
            .gamma
            .as_ref()
            .or(tm.beta.as_ref())
            .map_or(tm.scheme.span(), |s| s.span());
        check(
            gamma >= 0.5 && 2.0 * beta >= gamma,
            span,
            format!("newmark with beta = {beta}, gamma = {gamma} is not unconditionally stable (needs 2*beta >= gamma >= 0.5); use e.g. beta = 0.25, gamma = 0.5 (trapezoidal) or beta = 0.3025, gamma = 0.6 (damped)"),
        );
    }
    if let (Scheme::CentralDifference, Some(m)) = (scheme, &tm.mass) {
        check(
            *m.get_ref() == MassKind::Lumped,
            m.span(),
            "central_difference needs mass = \"lumped\" (with a consistent mass it is no longer explicit); remove the key or use scheme = \"newmark\"".into(),
        );
    }
    let stick_reduction = tm.stick_reduction.as_ref().map(|sr| {
        let r = sr.get_ref();
        let rdt = *r.dt.get_ref();
        check(
            rdt > 0.0 && rdt <= dt,
            r.dt.span(),
            format!("time.stick_reduction.dt = {rdt} must be > 0 and <= time.dt = {dt}"),
        );
        check(
            *r.steps.get_ref() > 0,
            r.steps.span(),
            "time.stick_reduction.steps must be >= 1; remove stick_reduction to turn the reduction off".into(),
        );
        StickReduction { dt: rdt, steps: *r.steps.get_ref() }
    });

    // [output]
    let every = raw.output.every.as_ref().map_or(1, |e| *e.get_ref());
    if let Some(e) = &raw.output.every {
        check(
            every > 0,
            e.span(),
            "output.every must be >= 1 (1 writes every step)".into(),
        );
    }
    let out_file = match &raw.output.file {
        Some(f) => base.join(f.get_ref()),
        None => {
            let stem = path
                .file_stem()
                .map_or("results".into(), |s| s.to_string_lossy().into_owned());
            base.join(format!("{stem}.h5"))
        }
    };

    if !bad.is_empty() {
        return Err(bad);
    }
    Ok(Case {
        path: path.to_path_buf(),
        source,
        title: raw.title,
        mesh: MeshSection { file: mesh_file },
        material: MaterialSection {
            e,
            nu,
            rho,
            hypothesis: raw.material.hypothesis,
        },
        dirichlet: raw
            .dirichlet
            .into_iter()
            .map(|d| DirichletSection {
                group: d.group.into_inner(),
                ux: d.ux,
                uy: d.uy,
            })
            .collect(),
        traction: raw
            .traction
            .into_iter()
            .map(|t| TractionSection {
                group: t.group.into_inner(),
                t: t.t,
                pressure: t.pressure,
                history: t.history.map_or(History::Step, Spanned::into_inner),
            })
            .collect(),
        body_force: raw.body_force.map(Spanned::into_inner),
        contact: raw.contact.map(|c| ContactSection {
            group: c.group.into_inner(),
            pressure: c.pressure.into_inner(),
            mu: c.mu.into_inner(),
            eps: c.eps.into_inner(),
            remark_4_2: c.remark_4_2.unwrap_or(true),
            max_iterations: c.max_iterations.map_or(100, Spanned::into_inner),
        }),
        time: TimeSection {
            scheme,
            beta,
            gamma,
            mass: tm.mass.as_ref().map(|m| *m.get_ref()),
            dt,
            t_end,
            stick_reduction,
            allow_unstable: tm.allow_unstable.unwrap_or(false),
        },
        output: OutputSection {
            file: out_file,
            every,
        },
    })
}

// ---------------------------------------------------------------------------
// --set

/// Applies one `KEY=VALUE` to the document. Keys are dotted paths; a number
/// after an array of tables picks an entry (`dirichlet.0.uy=0`). A missing
/// leaf key is added (serde then rejects it if it is not a case key).
fn apply_set(doc: &mut toml_edit::DocumentMut, set: &str) -> Result<(), String> {
    let (key, val) = set
        .split_once('=')
        .ok_or_else(|| "expected KEY=VALUE, e.g. --set time.dt=5e-4".to_string())?;
    let key = key.trim();
    let segs: Vec<&str> = key.split('.').map(str::trim).collect();
    if segs.iter().any(|s| s.is_empty()) {
        return Err(format!(
            "{key:?} is not a dotted key path; write e.g. time.dt"
        ));
    }
    let val = val.trim();
    let mut value: Value = val.parse().unwrap_or_else(|_| Value::from(val));
    value.decor_mut().clear();
    set_in(doc.as_table_mut(), &segs, value, key)
}

fn set_in(t: &mut dyn TableLike, segs: &[&str], mut value: Value, key: &str) -> Result<(), String> {
    let (k, rest) = segs.split_first().expect("non-empty path");
    if rest.is_empty() {
        match t.get_mut(k) {
            Some(Item::Value(old)) => {
                // Keep the spacing and any trailing comment of the line.
                *value.decor_mut() = old.decor().clone();
                *old = value;
            }
            Some(Item::None) | None => {
                t.insert(k, Item::Value(value));
            }
            Some(_) => {
                return Err(format!(
                    "{key} is a table; set one of its keys, e.g. {key}.NAME=VALUE"
                ))
            }
        }
        return Ok(());
    }
    if t.get(k).is_none() {
        // A section the file does not have yet (e.g. --set contact.mu=0.3).
        t.insert(k, Item::Value(Value::InlineTable(Default::default())));
    }
    match t.get_mut(k).expect("just inserted") {
        Item::Table(tt) => set_in(tt, rest, value, key),
        Item::Value(Value::InlineTable(tt)) => set_in(tt, rest, value, key),
        Item::ArrayOfTables(a) => {
            let n = a.len();
            let (i, rest) = index(rest, k, n, key)?;
            set_in(a.get_mut(i).expect("index checked"), rest, value, key)
        }
        Item::Value(Value::Array(a)) => {
            let n = a.len();
            let (i, rest) = index(rest, k, n, key)?;
            match a.get_mut(i).expect("index checked") {
                Value::InlineTable(tt) => set_in(tt, rest, value, key),
                _ => Err(format!(
                    "{k}.{i} is a value, not a table; set {k} as a whole"
                )),
            }
        }
        _ => Err(format!("{k} holds a value, not a table; set {k} itself")),
    }
}

fn index<'a>(
    rest: &'a [&'a str],
    k: &str,
    n: usize,
    key: &str,
) -> Result<(usize, &'a [&'a str]), String> {
    let (i, rest) = rest.split_first().expect("caller checked");
    let i: usize = i.parse().map_err(|_| {
        format!("{k} is a list of {n} tables; pick one by number from 0, e.g. {k}.0.KEY=VALUE")
    })?;
    if i >= n {
        return Err(format!(
            "{k} has {n} entries (0..{}); {key} names entry {i}",
            n.saturating_sub(1)
        ));
    }
    if rest.is_empty() {
        return Err(format!(
            "{key} names a whole table; set one of its keys, e.g. {key}.NAME=VALUE"
        ));
    }
    Ok((i, rest))
}

// ---------------------------------------------------------------------------
// Locations

/// Turns byte spans in the final text into `file:line:col` of the user's file
/// (or `--set ...` for lines that `--set` changed).
struct Locator<'a> {
    file: &'a str,
    source: &'a str,
    sets: &'a [String],
    /// For each line of the final text (0-based), the line of the original
    /// file it is (0-based), or `None` if `--set` changed or added it.
    map: Vec<Option<usize>>,
}

impl<'a> Locator<'a> {
    fn new(file: &'a str, original: &str, source: &'a str, sets: &'a [String]) -> Self {
        let a: Vec<&str> = original.lines().collect();
        let b: Vec<&str> = source.lines().collect();
        let map = if sets.is_empty() || a.len() * b.len() > 16_000_000 {
            (0..b.len()).map(Some).collect()
        } else {
            diff_lines(&a, &b)
        };
        Locator {
            file,
            source,
            sets,
            map,
        }
    }

    fn at(&self, span: Option<Range<usize>>) -> String {
        let Some(span) = span else {
            return self.file.to_string();
        };
        let (line, col) = line_col(self.source, span.start);
        match self.map.get(line - 1).copied().flatten() {
            Some(orig) => format!("{}:{}:{col}", self.file, orig + 1),
            None => {
                // The line came from --set: name the override(s) on it.
                let text = self.source.lines().nth(line - 1).unwrap_or("");
                let on_line: Vec<&String> = self
                    .sets
                    .iter()
                    .filter(|s| {
                        let leaf = s
                            .split('=')
                            .next()
                            .unwrap_or("")
                            .rsplit('.')
                            .next()
                            .unwrap_or("")
                            .trim();
                        !leaf.is_empty() && text.contains(leaf)
                    })
                    .collect();
                let which: Vec<&String> = if on_line.is_empty() {
                    self.sets.iter().collect()
                } else {
                    on_line
                };
                let which: Vec<&str> = which.iter().map(|s| s.as_str()).collect();
                format!("--set {} (in {})", which.join(" --set "), self.file)
            }
        }
    }
}

/// 1-based line and column (in characters) of byte offset `pos`.
fn line_col(text: &str, pos: usize) -> (usize, usize) {
    let pos = pos.min(text.len());
    let before = &text[..text.floor_char_boundary_compat(pos)];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().unwrap_or("").chars().count() + 1;
    (line, col)
}

trait FloorCharBoundary {
    fn floor_char_boundary_compat(&self, i: usize) -> usize;
}
impl FloorCharBoundary for str {
    fn floor_char_boundary_compat(&self, mut i: usize) -> usize {
        while i > 0 && !self.is_char_boundary(i) {
            i -= 1;
        }
        i
    }
}

/// Longest-common-subsequence alignment of lines: for each line of `b`, the
/// index of the equal line of `a` it is matched with, if any.
fn diff_lines(a: &[&str], b: &[&str]) -> Vec<Option<usize>> {
    let (n, m) = (a.len(), b.len());
    // lcs[i][j] = LCS length of a[i..], b[j..].
    let mut lcs = vec![0u32; (n + 1) * (m + 1)];
    let w = m + 1;
    for i in (0..n).rev() {
        for j in (0..m).rev() {
            lcs[i * w + j] = if a[i] == b[j] {
                lcs[(i + 1) * w + j + 1] + 1
            } else {
                lcs[(i + 1) * w + j].max(lcs[i * w + j + 1])
            };
        }
    }
    let mut map = vec![None; m];
    let (mut i, mut j) = (0, 0);
    while i < n && j < m {
        if a[i] == b[j] {
            map[j] = Some(i);
            i += 1;
            j += 1;
        } else if lcs[(i + 1) * w + j] >= lcs[i * w + j + 1] {
            i += 1;
        } else {
            j += 1;
        }
    }
    map
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A directory with a mesh file placeholder, so mesh.file exists.
    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("stickslip-case-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join("m.msh"), "").unwrap();
        d
    }

    const GOOD: &str = r#"title = "slab"
[mesh]
file = "m.msh"
[material]
E = 1000
nu = 0.3
rho = 1.0
[[dirichlet]]
group = "support"
uy = 0.0
[[dirichlet]]
group = "left"
ux = 0.0
[[traction]]
group = "load"
t = [-150.0, 0.0]   # compressive
[contact]
group = "contact"
pressure = 300.0
mu = 0.3
eps = 1e-4
[time]
scheme = "central_difference"
dt = 1e-3
t_end = 0.5
"#;

    fn load_text(name: &str, text: &str, sets: &[&str]) -> Result<Case, InputError> {
        let d = scratch(name);
        let p = d.join("case.toml");
        std::fs::write(&p, text).unwrap();
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        load(&p, &sets)
    }

    /// The 1-based line of the first line of `text` containing `needle`:
    /// expected locations come from the test's own text, not the code.
    fn line_of(text: &str, needle: &str) -> usize {
        text.lines()
            .position(|l| l.contains(needle))
            .expect("needle in text")
            + 1
    }

    #[test]
    fn good_case_and_defaults() {
        let c = load_text("good", GOOD, &[]).unwrap();
        let dir = c.path.parent().unwrap().to_path_buf();
        assert_eq!(c.title.as_deref(), Some("slab"));
        assert_eq!(c.mesh.file, dir.join("m.msh"));
        assert_eq!(
            c.material,
            MaterialSection {
                e: 1000.0,
                nu: 0.3,
                rho: 1.0,
                hypothesis: Hypothesis::PlaneStrain
            }
        );
        assert_eq!(c.dirichlet.len(), 2);
        assert_eq!(
            c.dirichlet[1],
            DirichletSection {
                group: "left".into(),
                ux: Some(0.0),
                uy: None
            }
        );
        assert_eq!(c.traction[0].t, Some([-150.0, 0.0]));
        assert_eq!(
            c.traction[0].history,
            History::Step,
            "DESIGN.md: history defaults to step"
        );
        let k = c.contact.unwrap();
        assert!(k.remark_4_2);
        assert_eq!(k.max_iterations, 100);
        assert_eq!(c.time.scheme, Scheme::CentralDifference);
        assert_eq!((c.time.beta, c.time.gamma), (0.25, 0.5));
        assert_eq!(c.time.mass, None);
        assert!(!c.time.allow_unstable);
        assert_eq!(
            c.output.file,
            dir.join("case.h5"),
            "default output is <case stem>.h5 beside the case"
        );
        assert_eq!(c.output.every, 1);
        assert_eq!(c.source, GOOD);
    }

    #[test]
    fn unknown_key_names_file_line_and_key() {
        let text = GOOD.replace("eps = 1e-4", "eps = 1e-4\nepsilon = 2");
        let e = load_text("unknown", &text, &[]).unwrap_err().0;
        let l = line_of(&text, "epsilon");
        assert!(
            e.contains(&format!("case.toml:{l}:1: unknown field `epsilon`")),
            "{e}"
        );
    }

    #[test]
    fn syntax_error_has_line() {
        let text = GOOD.replace("mu = 0.3", "mu = = 0.3");
        let e = load_text("syntax", &text, &[]).unwrap_err().0;
        let l = line_of(&text, "mu = =");
        assert!(
            e.contains(&format!("case.toml:{l}:")) && e.contains("invalid TOML"),
            "{e}"
        );
    }

    #[test]
    fn all_value_problems_are_reported_together() {
        let text = GOOD
            .replace("E = 1000", "E = -1")
            .replace("nu = 0.3", "nu = 0.5")
            .replace("rho = 1.0", "rho = 0")
            .replace("mu = 0.3", "mu = -0.1")
            .replace("eps = 1e-4", "eps = 0.0")
            .replace("dt = 1e-3", "dt = -1e-3")
            .replace(
                "t_end = 0.5",
                "t_end = 0\nmass = \"consistent\"\nstick_reduction = { dt = 1e-2, steps = 3 }",
            )
            .replace("file = \"m.msh\"", "file = \"missing.msh\"")
            .replace("uy = 0.0", "")
            .replace(
                "t = [-150.0, 0.0]   # compressive",
                "t = [-150.0, 0.0]\npressure = 2.0",
            )
            + "[output]\nevery = 0\n";
        let e = load_text("many", &text, &[]).unwrap_err().0;
        let expect = [
            ("E = -1", "material.E"),
            ("nu = 0.5", "material.nu"),
            ("rho = 0", "material.rho"),
            ("mu = -0.1", "contact.mu"),
            ("eps = 0.0", "contact.eps"),
            ("dt = -1e-3", "time.dt"),
            ("t_end = 0", "time.t_end"),
            ("mass = ", "central_difference needs mass = \"lumped\""),
            ("stick_reduction", "time.stick_reduction.dt"),
            ("missing.msh", "does not exist"),
            ("group = \"support\"", "fixes neither ux nor uy"),
            ("group = \"load\"", "exactly one of t"),
            ("every = 0", "output.every"),
        ];
        for (needle, what) in expect {
            let l = line_of(&text, needle);
            assert!(
                e.lines()
                    .any(|m| m.contains(&format!("case.toml:{l}:")) && m.contains(what)),
                "no '{what}' at line {l} in:\n{e}"
            );
        }
        assert_eq!(
            e.lines().count(),
            expect.len(),
            "one line per problem:\n{e}"
        );
    }

    #[test]
    fn newmark_stability_condition() {
        // 2β ≥ γ ≥ ½ (textbook unconditional stability): (0.3025, 0.6) passes,
        // (0.25, 0.4) and (0.2, 0.5) fail.
        let nm = GOOD.replace("\"central_difference\"", "\"newmark\"");
        let ok = load_text("nm-ok", &nm, &["time.beta=0.3025", "time.gamma=0.6"]).unwrap();
        assert_eq!((ok.time.beta, ok.time.gamma), (0.3025, 0.6));
        for (b, g) in [(0.25, 0.4), (0.2, 0.5)] {
            let text = nm.replace("dt = 1e-3", &format!("dt = 1e-3\nbeta = {b}\ngamma = {g}"));
            let e = load_text("nm-bad", &text, &[]).unwrap_err().0;
            assert!(e.contains("not unconditionally stable"), "{e}");
            assert!(
                e.contains(&format!("case.toml:{}:", line_of(&text, "gamma ="))),
                "{e}"
            );
        }
    }

    #[test]
    fn set_replaces_inserts_and_keeps_lines() {
        let c = load_text(
            "set",
            GOOD,
            &[
                "time.dt=5e-4",
                "time.scheme=newmark",
                "contact.remark_4_2=false",
                "dirichlet.0.uy=0.5",
                "output.every=10",
            ],
        )
        .unwrap();
        assert_eq!(c.time.dt, 5e-4);
        assert_eq!(c.time.scheme, Scheme::Newmark);
        assert!(!c.contact.as_ref().unwrap().remark_4_2);
        assert_eq!(c.dirichlet[0].uy, Some(0.5));
        assert_eq!(c.output.every, 10);
        // The source is the case as run, and still carries the user's comment.
        let again = load_str(&c.path, &c.source, &[]).unwrap();
        assert_eq!(again.time, c.time);
        assert!(c.source.contains("# compressive"));
        // A problem on a line --set did not touch keeps its original line even
        // though --set inserted a line before it.
        let text = GOOD.replace("t_end = 0.5", "t_end = -0.5");
        let e = load_text("set-shift", &text, &["contact.remark_4_2=false"])
            .unwrap_err()
            .0;
        assert!(
            e.contains(&format!("case.toml:{}:", line_of(&text, "t_end"))),
            "{e}"
        );
    }

    #[test]
    fn set_problems_name_the_set() {
        let e = load_text("set-bad", GOOD, &["contact.eps=0"])
            .unwrap_err()
            .0;
        assert!(
            e.contains("--set contact.eps=0") && e.contains("contact.eps = 0 must be > 0"),
            "{e}"
        );
        let e = load_text("set-typo", GOOD, &["time.dtt=1"]).unwrap_err().0;
        assert!(
            e.contains("--set time.dtt=1") && e.contains("unknown field `dtt`"),
            "{e}"
        );
        let e = load_text("set-idx", GOOD, &["dirichlet.5.uy=0"])
            .unwrap_err()
            .0;
        assert!(e.contains("dirichlet has 2 entries"), "{e}");
        let e = load_text("set-noeq", GOOD, &["time.dt"]).unwrap_err().0;
        assert!(e.contains("expected KEY=VALUE"), "{e}");
    }

    #[test]
    fn history_forms_and_values() {
        let text = GOOD.replace(
            "t = [-150.0, 0.0]   # compressive",
            "t = [-150.0, 0.0]\nhistory = { table = [[0.0, 0.0], [0.1, 1.0], [0.3, 0.0]] }",
        );
        let h = load_text("hist", &text, &[]).unwrap().traction[0]
            .history
            .clone();
        // Piecewise linear through the given points, constant beyond the ends.
        for (t, f) in [
            (-1.0, 0.0),
            (0.0, 0.0),
            (0.05, 0.5),
            (0.1, 1.0),
            (0.2, 0.5),
            (0.3, 0.0),
            (9.0, 0.0),
        ] {
            assert!(
                (h.value(t) - f).abs() < 1e-15,
                "table({t}) = {} != {f}",
                h.value(t)
            );
        }
        let c = load_text(
            "hist-sin",
            GOOD,
            &["traction.0.history={ sin = { omega = 25.132741 } }"],
        )
        .unwrap();
        let h = &c.traction[0].history;
        assert_eq!(*h, History::Sin { omega: 25.132741 });
        assert!((h.value(1.0 / 16.0) - (25.132741f64 / 16.0).sin()).abs() < 1e-15);
        // H(t): H(0) = 1 (load on at t = 0), off before; constant is always on.
        assert_eq!(
            (History::Step.value(0.0), History::Step.value(-1e-12)),
            (1.0, 0.0)
        );
        assert_eq!(History::Constant.value(-1.0), 1.0);
        let bad = GOOD.replace(
            "t = [-150.0, 0.0]   # compressive",
            "t = [-150.0, 0.0]\nhistory = { table = [[0.2, 0.0], [0.1, 1.0]] }",
        );
        let e = load_text("hist-bad", &bad, &[]).unwrap_err().0;
        assert!(
            e.contains("strictly increasing")
                && e.contains(&format!("case.toml:{}:", line_of(&bad, "history"))),
            "{e}"
        );
        let e = load_text("hist-ramp", GOOD, &["traction.0.history=ramp"])
            .unwrap_err()
            .0;
        assert!(e.contains("unknown variant `ramp`"), "{e}");
    }

    #[test]
    fn diff_maps_unchanged_lines() {
        let a = ["a", "b", "c", "d"];
        let b = ["a", "b2", "b", "c", "x", "d"];
        assert_eq!(
            diff_lines(&a, &b),
            vec![Some(0), None, Some(1), Some(2), None, Some(3)]
        );
    }
}
