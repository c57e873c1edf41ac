//! The case file: TOML in, a validated [`Case`] out (DESIGN.md "Case file").
//!
//! Loading goes in four steps, so that every message can name the file and
//! the line the user has to edit:
//! 1. parse the text with `toml_edit` (syntax errors, original lines);
//! 2. apply the `--set KEY=VALUE` overrides to that document, which keeps the
//!    rest of the text (and its comments) as written; the result is
//!    [`Case::source`], the case as run;
//! 3. check every key against the case schema ([`SCHEMA`]): unknown keys
//!    (with the nearest valid key suggested) and values of the wrong type are
//!    all collected, then removed so that step 4 can still look at the rest;
//! 4. deserialize with serde (`deny_unknown_fields`, spans kept on the values
//!    that are validated);
//! 5. validate every value, collecting all problems before reporting.
//!
//! Lines of the final text are mapped back to the user's file by a line diff;
//! a problem on a line that `--set` changed is reported against that `--set`.

use std::collections::BTreeMap;
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
    /// Where some keys are in the user's text: dotted key (`contact.group`,
    /// `dirichlet.0.group`, `time.dt`, ...) → `file:line:col` (or `--set ..`),
    /// for the problems only the mesh reveals (run.rs).
    pub locations: BTreeMap<String, String>,
}

impl Case {
    /// `file:line:col: ` of a dotted key for a message, or `file: ` when its
    /// place is not known.
    pub fn at(&self, key: &str) -> String {
        match self.locations.get(key) {
            Some(l) => format!("{l}: "),
            None => format!("{}: ", self.path.display()),
        }
    }
}

/// `[mesh]`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshSection {
    /// The `.msh` file, resolved against the case file's directory.
    pub file: PathBuf,
    /// `mesh.ladder`: meshes of the same geometry and group names, coarse to
    /// fine, resolved against the case file's directory (empty when the key
    /// is absent). Only `stickslip advise` reads it; a run uses `file`.
    pub ladder: Vec<PathBuf>,
    /// The ladder entries as written in the case file (for `advise --write`).
    pub ladder_text: Vec<String>,
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
    #[serde(deserialize_with = "table_points")]
    Table(Vec<[f64; 2]>),
}

/// A table's rows, each exactly [t, f] (serde's [f64; 2] took [t, f, x]
/// and dropped x).
fn table_points<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<[f64; 2]>, D::Error> {
    let rows = Vec::<Vec<f64>>::deserialize(d)?;
    rows.iter()
        .enumerate()
        .map(|(i, r)| match r[..] {
            [t, f] => Ok([t, f]),
            _ => Err(serde::de::Error::custom(format!(
                "table row {} has {} numbers; each row is [t, f]",
                i + 1,
                r.len()
            ))),
        })
        .collect()
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
    /// Flush the file (and rewrite the checkpoint) at least every this many
    /// steps (default 100).
    pub flush_every: usize,
    /// ... and at least every this many seconds (default 5).
    pub flush_seconds: f64,
    /// Deflate level of the growing datasets, 0 (none, the default) to 9
    /// (output.rs, `DEFLATE_LEVEL`: deflate costs more than the run).
    pub compression: u8,
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
    ladder: Option<Spanned<Vec<String>>>,
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
    flush_every: Option<Spanned<usize>>,
    flush_seconds: Option<Spanned<f64>>,
    compression: Option<Spanned<u64>>,
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
    // A device or FIFO would be read forever (`check /dev/zero` hung).
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
        return Err(InputError(format!(
            "{file}: not a regular file (a device, FIFO or socket); give the case's .toml file"
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| {
        InputError(format!(
            "{file}: cannot read the case file: {e}; check the path"
        ))
    })?;
    if bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]) {
        return Err(InputError(format!(
            "{file}: UTF-16 text (it starts with a UTF-16 byte-order mark); TOML files are UTF-8: \
             save it as UTF-8 in your editor (e.g. `iconv -f utf-16 -t utf-8`)"
        )));
    }
    let original = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let text = &e.as_bytes()[..at];
        let line = text.iter().filter(|&&b| b == b'\n').count() + 1;
        let col = text.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
        InputError(format!(
            "{file}:{line}:{col}: not UTF-8 text (byte {at}); TOML files are UTF-8: save it as \
             UTF-8 in your editor (e.g. `iconv -f latin1 -t utf-8`)"
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
    // Step 3: every key against the schema, all problems at once; keys that
    // are unknown or of the wrong type are then removed so that serde and
    // the value checks can still report on the rest.
    let loc = Locator::new(&file, original, &source, sets, false);
    let mut problems = Vec::new();
    let mut removals = Vec::new();
    let mut typed = Vec::new();
    match toml_edit::Document::parse(source.as_str()) {
        Ok(spanned) => check_table(
            spanned.as_table(),
            &mut Vec::new(),
            ROOT,
            &mut |span, msg| problems.push(format!("{}: {msg}", loc.at(span))),
            &mut removals,
            &mut typed,
        ),
        Err(e) => {
            // Only --set can make the text unparsable here (the original parsed).
            return Err(InputError(format!(
                "{}: the case after --set is not valid TOML: {}; check the --set values",
                file,
                e.message().trim_end()
            )));
        }
    }
    // Lines whose value was replaced: later problems there are artefacts.
    let quiet_lines: Vec<String> = typed
        .iter()
        .filter_map(|(_, _, span)| {
            let at = loc.at(span.clone());
            at.rsplit_once(':').map(|(l, _)| format!("{l}:"))
        })
        .filter(|l| !l.starts_with("--set"))
        .collect();
    let cleaned = if removals.is_empty() && typed.is_empty() {
        None
    } else {
        let mut doc: toml_edit::DocumentMut =
            source.parse().map_err(|e: toml_edit::TomlError| {
                InputError(format!("{file}: {}", e.message().trim_end()))
            })?;
        for r in &removals {
            remove_path(doc.as_table_mut(), r, None);
        }
        for (r, with, _) in &typed {
            remove_path(doc.as_table_mut(), r, with.as_ref());
            if with.is_none() {
                removals.push(r.clone());
            }
        }
        Some(doc.to_string())
    };
    let text = cleaned.as_deref().unwrap_or(&source);
    let loc_text = Locator::new(&file, original, text, sets, cleaned.is_some());

    match toml::from_str::<RawCase>(text) {
        Err(e) => {
            let msg = e.message().trim_end().to_string();
            // A required key removed above for its type is already reported.
            let removed_leaf = |m: &str| {
                removals.iter().any(|r| {
                    r.last()
                        .is_some_and(|k| m.contains(&format!("`{}`", seg_name(k))))
                })
            };
            if !(msg.starts_with("missing field") && removed_leaf(&msg)) {
                let hint = if msg.starts_with("unknown field") {
                    "; check the spelling (docs/case-file.md lists the keys)"
                } else if msg.starts_with("missing field") {
                    "; add it (docs/case-file.md lists the keys)"
                } else if msg.starts_with("wanted string or table")
                    || msg.starts_with("wanted exactly 1 element")
                {
                    // Only a traction's history is a string or a one-key table.
                    " (a traction's history); write history = \"step\", \
                     history = { sin = { omega = 25.13 } } or history = { table = [[0.0, 0.0], [0.1, 1.0]] }"
                } else if msg.contains("variant") {
                    "; use one of the values listed"
                } else if msg.starts_with("invalid type") || msg.starts_with("invalid length") {
                    "; numbers go without quotes, text in quotes, vectors as [x, y]"
                } else {
                    ""
                };
                problems.push(format!("{}: {msg}{hint}", loc_text.at(e.span())));
            }
        }
        Ok(raw) => {
            let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
            match convert(raw, path, &base, source.clone(), &loc_text) {
                Ok(case) if problems.is_empty() => return Ok(case),
                Ok(_) => {}
                Err(bad) => {
                    // A key given a placeholder (its type was wrong, which
                    // is reported): what the checks say of the placeholder
                    // is no problem of the user's, also where the value came
                    // from --set (no line of the file to quiet).
                    let placeholders: Vec<String> =
                        typed.iter().map(|(p, _, _)| dotted(p)).collect();
                    // ": key " also matches "[section]: key ".
                    let of_placeholder = |p: &str| {
                        placeholders.iter().any(|k| {
                            [" ", ":"]
                                .iter()
                                .any(|end| p.contains(&format!(": {k}{end}")))
                        })
                    };
                    problems.extend(bad.into_iter().filter(|p| {
                        !quiet_lines.iter().any(|l| p.starts_with(l.as_str())) && !of_placeholder(p)
                    }));
                }
            }
        }
    }
    Err(InputError(crate::error::listed(problems)))
}

/// [`load_str`] on text alone, named `case.toml` in the current directory
/// (for fuzzing and property tests: any text gives a case or an error).
///
/// # Errors
/// As [`load`].
pub fn parse_str(text: &str) -> Result<Case, InputError> {
    load_str(Path::new("case.toml"), text, &[])
}

// ---------------------------------------------------------------------------
// The schema: every key a case may have, and the type of its value.

/// What a key's value must be.
#[derive(Clone, Copy, Debug)]
enum Kind {
    /// A string.
    Str,
    /// A number (integer or float).
    Num,
    /// A whole number >= 0.
    Int,
    /// true or false.
    Bool,
    /// [x, y], two numbers.
    Vec2,
    /// A list of strings (`mesh.ladder`).
    StrList,
    /// A table with these keys.
    Table(&'static [(&'static str, Kind)]),
    /// A list of tables with these keys (`[[name]]`).
    Tables(&'static [(&'static str, Kind)]),
    /// Anything (checked by serde: `history`).
    Any,
}

const MESH: &[(&str, Kind)] = &[("file", Kind::Str), ("ladder", Kind::StrList)];
const MATERIAL: &[(&str, Kind)] = &[
    ("E", Kind::Num),
    ("nu", Kind::Num),
    ("rho", Kind::Num),
    ("hypothesis", Kind::Str),
];
const DIRICHLET: &[(&str, Kind)] = &[("group", Kind::Str), ("ux", Kind::Num), ("uy", Kind::Num)];
const TRACTION: &[(&str, Kind)] = &[
    ("group", Kind::Str),
    ("t", Kind::Vec2),
    ("pressure", Kind::Num),
    ("history", Kind::Any),
];
const CONTACT: &[(&str, Kind)] = &[
    ("group", Kind::Str),
    ("pressure", Kind::Num),
    ("mu", Kind::Num),
    ("eps", Kind::Num),
    ("remark_4_2", Kind::Bool),
    ("max_iterations", Kind::Int),
];
const STICK_REDUCTION: &[(&str, Kind)] = &[("dt", Kind::Num), ("steps", Kind::Int)];
const TIME: &[(&str, Kind)] = &[
    ("scheme", Kind::Str),
    ("beta", Kind::Num),
    ("gamma", Kind::Num),
    ("mass", Kind::Str),
    ("dt", Kind::Num),
    ("t_end", Kind::Num),
    ("stick_reduction", Kind::Table(STICK_REDUCTION)),
    ("allow_unstable", Kind::Bool),
];
const OUTPUT: &[(&str, Kind)] = &[
    ("file", Kind::Str),
    ("every", Kind::Int),
    ("flush_every", Kind::Int),
    ("flush_seconds", Kind::Num),
    ("compression", Kind::Int),
];
/// The whole case file (DESIGN.md "Case file").
const ROOT: &[(&str, Kind)] = &[
    ("title", Kind::Str),
    ("mesh", Kind::Table(MESH)),
    ("material", Kind::Table(MATERIAL)),
    ("dirichlet", Kind::Tables(DIRICHLET)),
    ("traction", Kind::Tables(TRACTION)),
    ("body_force", Kind::Vec2),
    ("contact", Kind::Table(CONTACT)),
    ("time", Kind::Table(TIME)),
    ("output", Kind::Table(OUTPUT)),
];
/// Every table of the schema with its name, to say where a misplaced key belongs.
const SECTIONS: &[(&str, &[(&str, Kind)])] = &[
    ("mesh", MESH),
    ("material", MATERIAL),
    ("[dirichlet]", DIRICHLET),
    ("[traction]", TRACTION),
    ("contact", CONTACT),
    ("time", TIME),
    ("time.stick_reduction", STICK_REDUCTION),
    ("output", OUTPUT),
];

/// A key whose value had the wrong type: its path, the placeholder put in
/// its place (`None`: removed), and where it was.
type Retyped = (Vec<Seg>, Option<Value>, Option<Range<usize>>);

/// One step of a key path: a key or an index into a list of tables.
#[derive(Clone, Debug)]
enum Seg {
    Key(String),
    Index(usize),
}

fn seg_name(s: &Seg) -> String {
    match s {
        Seg::Key(k) => k.clone(),
        Seg::Index(i) => i.to_string(),
    }
}

/// `time.dt`, `dirichlet.0.uy` (the --set syntax).
fn dotted(path: &[Seg]) -> String {
    path.iter().map(seg_name).collect::<Vec<_>>().join(".")
}

/// Levenshtein distance (small strings only: keys).
fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for j in 0..b.len() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != b[j]))
                .min(row[j] + 1)
                .min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

/// The valid key nearest to `key`, if it is near enough to be a typo: at
/// most a third of the letters different (at least one), or one a prefix of
/// the other (`epsilon` → `eps`), ignoring case.
fn nearest<'a>(key: &str, valid: &[(&'a str, Kind)]) -> Option<&'a str> {
    let k = key.to_lowercase();
    valid
        .iter()
        .map(|(v, _)| {
            let vl = v.to_lowercase();
            let d = distance(&k, &vl);
            let prefix =
                k.len() >= 2 && vl.len() >= 2 && (k.starts_with(&vl) || vl.starts_with(&k));
            (if prefix { d.min(1) } else { d }, *v)
        })
        .filter(|(d, v)| *d <= (v.chars().count() / 3).max(1))
        .min_by_key(|(d, _)| *d)
        .map(|(_, v)| v)
}

/// Describes a TOML value for a message.
fn found(item: &Item) -> String {
    match item {
        Item::Value(Value::String(s)) => format!("the string {:?}", s.value()),
        Item::Value(Value::Integer(i)) => format!("the integer {}", i.value()),
        Item::Value(Value::Float(f)) => format!("the number {}", f.value()),
        Item::Value(Value::Boolean(b)) => format!("{}", b.value()),
        Item::Value(Value::Datetime(_)) => "a date".into(),
        Item::Value(Value::Array(a)) => format!("an array of {}", a.len()),
        Item::Value(Value::InlineTable(_)) | Item::Table(_) => "a table".into(),
        Item::ArrayOfTables(_) => "a list of tables".into(),
        Item::None => "nothing".into(),
    }
}

fn is_number(v: &Value) -> bool {
    matches!(v, Value::Integer(_) | Value::Float(_))
}

/// Magnitudes a case's numbers may have (or 0): beyond them products such
/// as E·h² or ρ·h²/Δt² overflow or underflow, and the run failed with a
/// wrong diagnosis (E = 1e308: "a rigid-body motion left free"; ρ =
/// 1e-300: "use time.dt < 0").
const MODERATE: std::ops::RangeInclusive<f64> = 1e-100..=1e100;

/// Most steps a case may ask for: 1e12 steps of the paper's 85-node mesh
/// (about 1 µs each) take twelve days.
const MAX_STEPS: f64 = 1e12;

/// A finite number of `v` outside [`MODERATE`] (and not 0).
fn extreme(v: &Value) -> Option<f64> {
    let x = match v {
        Value::Integer(i) => *i.value() as f64,
        Value::Float(f) => *f.value(),
        _ => return None,
    };
    (x.is_finite() && x != 0.0 && !MODERATE.contains(&x.abs())).then_some(x)
}

/// Checks every key of `table` (at `path`) against `schema`: calls `report`
/// with the span and message of each problem and pushes the path of each
/// offending key to `removals`.
fn check_table(
    table: &dyn TableLike,
    path: &mut Vec<Seg>,
    schema: &'static [(&'static str, Kind)],
    report: &mut dyn FnMut(Option<Range<usize>>, String),
    removals: &mut Vec<Vec<Seg>>,
    typed: &mut Vec<Retyped>,
) {
    let section = if path.is_empty() {
        "the top level".to_string()
    } else {
        format!("[{}]", dotted(path))
    };
    for (key, item) in table.iter() {
        let key_span = table.key(key).and_then(|k| k.span());
        path.push(Seg::Key(key.to_string()));
        let Some((_, kind)) = schema.iter().find(|(k, _)| *k == key) else {
            let valid: Vec<&str> = schema.iter().map(|(k, _)| *k).collect();
            let hint = if let Some(n) = nearest(key, schema) {
                format!("did you mean `{n}`?")
            } else if let Some((sec, _)) = SECTIONS
                .iter()
                .find(|(_, keys)| keys.iter().any(|(k, _)| k.eq_ignore_ascii_case(key)))
            {
                format!("`{key}` belongs in [{sec}]; move it there")
            } else {
                format!("the keys here are: {}", valid.join(", "))
            };
            report(
                key_span.or_else(|| item.span()),
                format!("unknown field `{key}` in {section}; {hint}"),
            );
            removals.push(path.clone());
            path.pop();
            continue;
        };
        let name = dotted(path);
        let span = item.span().or_else(|| key_span.clone());
        let numbers: Vec<&Value> = match (kind, item) {
            (Kind::Num, Item::Value(v)) => vec![v],
            (Kind::Vec2, Item::Value(Value::Array(a))) => a.iter().collect(),
            _ => Vec::new(),
        };
        if let Some(x) = numbers.into_iter().find_map(extreme) {
            report(
                span.clone(),
                format!(
                    "{name} = {x:e} is beyond what the computation can carry (magnitudes from \
                     1e-100 to 1e100, or 0); choose units that keep the case's values moderate"
                ),
            );
        }
        let mut wrong = |want: &str, hint: &str| {
            report(
                span.clone(),
                format!("{name}: expected {want}, found {}; {hint}", found(item)),
            );
            // A placeholder of the right type keeps the key (and the table's
            // other checks) alive; problems on its line are not reported.
            typed.push((path.clone(), placeholder(key, kind), span.clone()));
        };
        match (kind, item) {
            (Kind::Any, _) => {}
            (Kind::Str, Item::Value(Value::String(_))) => {}
            (Kind::Str, _) => wrong("text", "put it in quotes, e.g. \"...\""),
            (Kind::Num, Item::Value(v)) if is_number(v) => {}
            (Kind::Num, _) => wrong("a number", "write numbers without quotes, e.g. 1e-3"),
            (Kind::Int, Item::Value(Value::Integer(i))) if *i.value() >= 0 => {}
            (Kind::Int, _) => wrong(
                "a whole number >= 0",
                "write it without quotes or decimal point, e.g. 10",
            ),
            (Kind::Bool, Item::Value(Value::Boolean(_))) => {}
            (Kind::Bool, _) => wrong("true or false", "write true or false without quotes"),
            (Kind::Vec2, Item::Value(Value::Array(a)))
                if a.len() == 2 && a.iter().all(is_number) => {}
            (Kind::Vec2, _) => wrong("a vector of two numbers", "write it as [x, y]"),
            (Kind::StrList, Item::Value(Value::Array(a)))
                if a.iter().all(|v| matches!(v, Value::String(_))) => {}
            (Kind::StrList, _) => wrong(
                "a list of mesh files",
                "write it as [\"meshes/coarse.msh\", \"meshes/fine.msh\"]",
            ),
            (Kind::Table(sub), Item::Table(t)) => {
                check_table(t, path, sub, report, removals, typed)
            }
            (Kind::Table(sub), Item::Value(Value::InlineTable(t))) => {
                check_table(t, path, sub, report, removals, typed)
            }
            (Kind::Table(_), _) => wrong(
                "a table",
                &format!("write it as [{name}] followed by its keys, or {{ key = value }}"),
            ),
            (Kind::Tables(sub), Item::ArrayOfTables(a)) => {
                for (i, t) in a.iter().enumerate() {
                    path.push(Seg::Index(i));
                    check_table(t, path, sub, report, removals, typed);
                    path.pop();
                }
            }
            (Kind::Tables(sub), Item::Value(Value::Array(a)))
                if a.iter().all(|v| matches!(v, Value::InlineTable(_))) =>
            {
                for (i, v) in a.iter().enumerate() {
                    if let Value::InlineTable(t) = v {
                        path.push(Seg::Index(i));
                        check_table(t, path, sub, report, removals, typed);
                        path.pop();
                    }
                }
            }
            (Kind::Tables(_), _) => wrong(
                "a list of tables",
                &format!("write one [[{name}]] section per entry"),
            ),
        }
        path.pop();
    }
}

/// A value of the right kind for a key whose value has the wrong type (for
/// the enumerations, a valid variant), or `None` to remove the key (tables).
fn placeholder(key: &str, kind: &Kind) -> Option<Value> {
    Some(match (key, kind) {
        ("scheme", _) => Value::from("central_difference"),
        ("mass", _) => Value::from("lumped"),
        ("hypothesis", _) => Value::from("plane_strain"),
        (_, Kind::Str) => Value::from("placeholder"),
        (_, Kind::Num) => Value::from(1.0),
        (_, Kind::Int) => Value::from(1i64),
        (_, Kind::Bool) => Value::from(false),
        (_, Kind::Vec2) => Value::Array(toml_edit::Array::from_iter([0.0, 0.0])),
        (_, Kind::StrList) => Value::Array(toml_edit::Array::new()),
        _ => return None,
    })
}

/// Removes the key at `path` (as found by [`check_table`]) from a document,
/// or replaces its value by `with` keeping its line.
fn remove_path(table: &mut dyn TableLike, path: &[Seg], with: Option<&Value>) {
    let Some((Seg::Key(k), rest)) = path.split_first() else {
        return;
    };
    if rest.is_empty() {
        match (with, table.get_mut(k)) {
            (Some(v), Some(Item::Value(old))) => {
                let decor = old.decor().clone();
                *old = v.clone();
                *old.decor_mut() = decor;
            }
            _ => {
                table.remove(k);
            }
        }
        return;
    }
    match table.get_mut(k) {
        Some(Item::Table(t)) => remove_path(t, rest, with),
        Some(Item::Value(Value::InlineTable(t))) => remove_path(t, rest, with),
        Some(Item::ArrayOfTables(a)) => {
            if let Some((Seg::Index(i), rest)) = rest.split_first() {
                if let Some(t) = a.get_mut(*i) {
                    remove_path(t, rest, with);
                }
            }
        }
        Some(Item::Value(Value::Array(a))) => {
            if let Some((Seg::Index(i), rest)) = rest.split_first() {
                if let Some(Value::InlineTable(t)) = a.get_mut(*i) {
                    remove_path(t, rest, with);
                }
            }
        }
        _ => {}
    }
}

// ---------------------------------------------------------------------------
// Restart: what may change between the run stored in a file and its continuation.

/// Keys a restart may change: the end time, the output settings, the title.
fn restart_may_change(key: &str) -> bool {
    // mesh.ladder is read by `advise` only; a run never sees it.
    key == "title"
        || key == "time.t_end"
        || key == "mesh.ladder"
        || key == "output"
        || key.starts_with("output.")
}

fn flatten(prefix: &str, v: &toml::Value, out: &mut BTreeMap<String, toml::Value>) {
    let name = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match v {
        toml::Value::Table(t) => {
            for (k, v) in t {
                flatten(&name(k), v, out);
            }
        }
        toml::Value::Array(a) if a.iter().all(toml::Value::is_table) && !a.is_empty() => {
            for (i, v) in a.iter().enumerate() {
                flatten(&name(&i.to_string()), v, out);
            }
        }
        _ => {
            out.insert(prefix.to_string(), v.clone());
        }
    }
}

/// Numbers compare by value (`1000` equals `1000.0`); the rest as written.
fn same_value(a: &toml::Value, b: &toml::Value) -> bool {
    let num = |v: &toml::Value| match v {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(f) => Some(*f),
        _ => None,
    };
    match (num(a), num(b)) {
        (Some(x), Some(y)) => x.to_bits() == y.to_bits() || x == y,
        _ => match (a, b) {
            (toml::Value::Array(x), toml::Value::Array(y)) => {
                x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same_value(p, q))
            }
            _ => a == b,
        },
    }
}

/// The keys (dotted, as `--set` writes them) on which the case `new` differs
/// from the case `stored` in a results file, other than those a restart may
/// change (`time.t_end`, `output.*`, `title`), each as `key: stored X, now Y`.
/// A key given in one and left to its default in the other counts as a
/// change (write it the same way in both).
///
/// # Errors
/// The stored text is not TOML (a damaged file).
pub fn restart_changes(stored: &str, new: &str) -> Result<Vec<String>, String> {
    let parse = |s: &str| -> Result<BTreeMap<String, toml::Value>, String> {
        let v: toml::Table = toml::from_str(s).map_err(|e| e.message().trim_end().to_string())?;
        let mut out = BTreeMap::new();
        flatten("", &toml::Value::Table(v), &mut out);
        Ok(out)
    };
    let old = parse(stored).map_err(|e| format!("the case stored in the file is not TOML: {e}"))?;
    let new = parse(new)?;
    let mut keys: Vec<&String> = old.keys().chain(new.keys()).collect();
    keys.sort();
    keys.dedup();
    let show = |v: Option<&toml::Value>| v.map_or("(not given)".to_string(), |v| v.to_string());
    Ok(keys
        .into_iter()
        .filter(|k| !restart_may_change(k))
        .filter(|k| match (old.get(*k), new.get(*k)) {
            (Some(a), Some(b)) => !same_value(a, b),
            _ => true,
        })
        .map(|k| {
            format!(
                "{k}: {} in the stored run, {} now",
                show(old.get(k)),
                show(new.get(k))
            )
        })
        .collect())
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
    let mut locations = BTreeMap::new();
    let mut locate = |key: String, span: Range<usize>| {
        locations.insert(key, loc.at(Some(span)));
    };
    locate("mesh.file".into(), raw.mesh.file.span());
    if let Some(l) = &raw.mesh.ladder {
        locate("mesh.ladder".into(), l.span());
    }
    locate("material.E".into(), raw.material.e.span());
    for (i, d) in raw.dirichlet.iter().enumerate() {
        locate(format!("dirichlet.{i}.group"), d.group.span());
    }
    for (i, t) in raw.traction.iter().enumerate() {
        locate(format!("traction.{i}.group"), t.group.span());
    }
    if let Some(c) = &raw.contact {
        locate("contact.group".into(), c.group.span());
    }
    locate("time.scheme".into(), raw.time.scheme.span());
    locate("time.dt".into(), raw.time.dt.span());
    locate("time.t_end".into(), raw.time.t_end.span());
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
        if mesh_file.is_dir() {
            format!(
                "mesh.file: {} is a directory; give the .msh file in it",
                mesh_file.display()
            )
        } else if mesh_file.exists() {
            format!(
                "mesh.file: {} is not a regular file (a device, FIFO or socket); give the .msh file",
                mesh_file.display()
            )
        } else {
            format!(
                "mesh.file: {} does not exist (paths are relative to the case file's directory); \
                 check the name, or make the mesh with Gmsh",
                mesh_file.display()
            )
        },
    );

    // mesh.ladder: at least one entry. Whether its files exist is checked
    // by `advise`, which reads them; a run does not, and must not fail on them.
    let mut ladder = Vec::new();
    let mut ladder_text = Vec::new();
    if let Some(l) = &raw.mesh.ladder {
        check(
            !l.get_ref().is_empty(),
            l.span(),
            "mesh.ladder is empty; list the meshes coarse to fine, e.g. [\"a.msh\", \"b.msh\"], or remove the key".into(),
        );
        for f in l.get_ref() {
            ladder.push(base.join(f));
            ladder_text.push(f.clone());
        }
    }

    // [material]
    let m = &raw.material;
    let (e, nu, rho) = (*m.e.get_ref(), *m.nu.get_ref(), *m.rho.get_ref());
    check(
        e > 0.0 && e.is_finite(),
        m.e.span(),
        format!("material.E = {e} must be a finite number > 0; give Young's modulus"),
    );
    check(
        rho > 0.0 && rho.is_finite(),
        m.rho.span(),
        format!("material.rho = {rho} must be a finite number > 0; give the mass density"),
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
                "dirichlet.{} (group {:?}) fixes neither ux nor uy; add ux = .. and/or uy = ..",
                i,
                d.group.get_ref()
            ),
        );
        let finite = d.ux.is_none_or(f64::is_finite) && d.uy.is_none_or(f64::is_finite);
        check(
            finite,
            d.group.span(),
            format!(
                "dirichlet.{i} (group {:?}): {}: give finite numbers",
                d.group.get_ref(),
                [("ux", d.ux), ("uy", d.uy)]
                    .iter()
                    .filter_map(|(k, v)| v.map(|v| format!("{k} = {v}")))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        );
    }

    // A component of a group prescribed twice: even with equal values it is
    // a copy-paste slip the user should see (different values would also
    // contradict each other).
    let mut seen: BTreeMap<(&str, usize), usize> = BTreeMap::new();
    for (i, d) in raw.dirichlet.iter().enumerate() {
        for (comp, given) in [(0, d.ux.is_some()), (1, d.uy.is_some())] {
            if !given {
                continue;
            }
            if let Some(first) = seen.insert((d.group.get_ref().as_str(), comp), i) {
                let c = if comp == 0 { "ux" } else { "uy" };
                check(
                    false,
                    d.group.span(),
                    format!(
                        "dirichlet.{} (group {:?}) sets {c} again, already set by dirichlet.{} ({}); give each component of a group once",
                        i,
                        d.group.get_ref(),
                        first,
                        loc.at(Some(raw.dirichlet[first].group.span()))
                    ),
                );
            }
        }
    }

    // [[traction]]
    for (i, t) in raw.traction.iter().enumerate() {
        let what = format!("traction.{i} (group {:?})", t.group.get_ref());
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
        check(p >= 0.0 && p.is_finite(), c.pressure.span(), format!("contact.pressure = {p} must be >= 0 and finite (it presses the body onto the surface; g = mu * pressure)"));
        check(
            mu >= 0.0 && mu.is_finite(),
            c.mu.span(),
            format!("contact.mu = {mu} must be >= 0 and finite; use 0 for frictionless contact"),
        );
        check(eps > 0.0 && eps.is_finite(), c.eps.span(), format!("contact.eps = {eps} must be > 0 and finite (the friction law's regularization; the paper uses 1e-4 to 1)"));
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
        format!("time.dt = {dt} must be a finite number > 0"),
    );
    check(
        t_end > 0.0 && t_end.is_finite(),
        tm.t_end.span(),
        format!("time.t_end = {t_end} must be a finite number > 0"),
    );
    // A run that cannot end (1e300 steps passed `check` and ran on).
    // Blamed on t_end, or on dt where only dt came from --set.
    let steps = t_end / dt;
    let blamed = if loc.set_by_override(&tm.dt.span()) && !loc.set_by_override(&tm.t_end.span()) {
        tm.dt.span()
    } else {
        tm.t_end.span()
    };
    check(
        steps.is_nan() || steps <= MAX_STEPS,
        blamed,
        format!(
            "time.t_end / time.dt = {t_end:e} / {dt:e} = {steps:.3e} steps, more than {MAX_STEPS:e}: \
             a run that would not end in years; check the two values (their units, a missing minus \
             sign in an exponent)"
        ),
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
    if scheme == Scheme::CentralDifference {
        // Newmark's parameters on an explicit run would be ignored
        // silently: say so (a Newmark case switched by --set keeps them).
        for (key, v) in [("beta", &tm.beta), ("gamma", &tm.gamma)] {
            if let Some(v) = v {
                check(
                    false,
                    v.span(),
                    format!(
                        "time.{key} is a Newmark parameter; scheme = \"central_difference\" has none: \
                         remove it, or use scheme = \"newmark\""
                    ),
                );
            }
        }
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
    let flush_every = raw
        .output
        .flush_every
        .as_ref()
        .map_or(100, |e| *e.get_ref());
    if let Some(e) = &raw.output.flush_every {
        check(
            flush_every > 0,
            e.span(),
            "output.flush_every must be >= 1 (steps between flushes of the results file; default 100)".into(),
        );
    }
    let flush_seconds = raw
        .output
        .flush_seconds
        .as_ref()
        .map_or(5.0, |e| *e.get_ref());
    if let Some(e) = &raw.output.flush_seconds {
        check(
            flush_seconds > 0.0 && !flush_seconds.is_nan(),
            e.span(),
            format!("output.flush_seconds = {flush_seconds} must be > 0 (seconds between flushes; default 5)"),
        );
    }
    let compression = raw
        .output
        .compression
        .as_ref()
        .map_or(u64::from(crate::output::DEFLATE_LEVEL), |e| *e.get_ref());
    if let Some(e) = &raw.output.compression {
        check(
            compression <= 9,
            e.span(),
            format!("output.compression = {compression} must be 0 (none) to 9 (deflate level; default 0)"),
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
        mesh: MeshSection {
            file: mesh_file,
            ladder,
            ladder_text,
        },
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
            flush_every,
            flush_seconds,
            compression: compression.min(9) as u8,
        },
        locations,
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
    /// `changed`: the text differs from the user's file other than by
    /// `sets` (keys removed after a schema problem), so lines are aligned by
    /// a diff even without `--set`.
    fn new(
        file: &'a str,
        original: &str,
        source: &'a str,
        sets: &'a [String],
        changed: bool,
    ) -> Self {
        let a: Vec<&str> = original.lines().collect();
        let b: Vec<&str> = source.lines().collect();
        let map = if (sets.is_empty() && !changed) || a.len().saturating_mul(b.len()) > 16_000_000 {
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

    /// Whether the line of `span` was changed or added by `--set`.
    fn set_by_override(&self, span: &Range<usize>) -> bool {
        let (line, _) = line_col(self.source, span.start);
        self.map.get(line - 1).copied().flatten().is_none()
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
                // No override on the line (a key missing from a file
                // with no such line, e.g. an empty one): the file.
                if on_line.is_empty() {
                    return self.file.to_string();
                }
                let which: Vec<&str> = on_line.iter().map(|s| s.as_str()).collect();
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
    fn mesh_ladder_is_read_resolved_and_checked() {
        let text = GOOD.replace(
            "file = \"m.msh\"",
            "file = \"m.msh\"\nladder = [\"m.msh\", \"m.msh\"]  # coarse to fine",
        );
        let c = load_text("ladder", &text, &[]).unwrap();
        let dir = c.path.parent().unwrap().to_path_buf();
        assert_eq!(c.mesh.ladder, vec![dir.join("m.msh"), dir.join("m.msh")]);
        assert_eq!(c.mesh.ladder_text, vec!["m.msh", "m.msh"]);
        assert!(load_text("ladder-none", GOOD, &[])
            .unwrap()
            .mesh
            .ladder
            .is_empty());
        // A missing file does not stop a run (advise checks the files); an
        // empty list and a wrong type are refused, named at their line.
        let missing = text.replace("[\"m.msh\", \"m.msh\"]", "[\"m.msh\", \"nope.msh\"]");
        assert!(load_text("ladder-missing", &missing, &[]).is_ok());
        let line = line_of(&missing, "ladder");
        let empty = text.replace("[\"m.msh\", \"m.msh\"]", "[]");
        let e = load_text("ladder-empty", &empty, &[]).unwrap_err().0;
        assert!(e.contains("mesh.ladder is empty"), "{e}");
        let wrong = text.replace("[\"m.msh\", \"m.msh\"]", "\"m.msh\"");
        let e = load_text("ladder-type", &wrong, &[]).unwrap_err().0;
        assert!(
            e.contains("mesh.ladder: expected a list of mesh files"),
            "{e}"
        );
        assert!(e.contains(&format!("case.toml:{line}:")), "{e}");
        // A typo is caught by the unknown-key machinery with a suggestion.
        let typo = text.replace("ladder =", "ladders =");
        let e = load_text("ladder-typo", &typo, &[]).unwrap_err().0;
        assert!(e.contains("did you mean `ladder`?"), "{e}");
        // A restart may add or change the ladder: advise reads it, a run does not.
        assert!(restart_changes(GOOD, &text).unwrap().is_empty());
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
    fn table_rows_cd_parameters_and_an_empty_file_are_reported_where_they_are() {
        let with = |rows: &str| {
            GOOD.replace(
                "t = [-150.0, 0.0]   # compressive",
                &format!("t = [-150.0, 0.0]\nhistory = {{ table = {rows} }}"),
            )
        };
        assert!(load_text("rows-ok", &with("[[0.0, 0.0], [0.1, 1.0]]"), &[]).is_ok());
        // serde's [f64; 2] took a third number and dropped it.
        let text = with("[[0.0, 0.0], [0.1, 1.0, 99.0]]");
        let e = load_text("rows-3", &text, &[]).unwrap_err().0;
        assert!(e.contains("table row 2 has 3 numbers"), "{e}");
        assert!(
            e.contains(&format!("case.toml:{}:", line_of(&text, "history ="))),
            "{e}"
        );
        // Newmark's parameters on a central-difference run were ignored.
        let text = GOOD.replace("dt = 1e-3", "dt = 1e-3\nbeta = 0.3");
        let e = load_text("cd-beta", &text, &[]).unwrap_err().0;
        assert!(e.contains("time.beta is a Newmark parameter"), "{e}");
        assert!(
            e.contains(&format!("case.toml:{}:", line_of(&text, "beta ="))),
            "{e}"
        );
        // No --set to blame in an empty file.
        let e = load_text("empty", "", &[]).unwrap_err().0;
        assert!(e.contains("case.toml: missing field `mesh`"), "{e}");
        assert!(!e.contains("--set"), "{e}");
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

    /// Too many steps is blamed on the value that came from --set: a tiny
    /// dt given by --set named t_end's line of the file.
    #[test]
    fn endless_runs_blame_the_set_value() {
        let e = load_text("set-dt", GOOD, &["time.dt=1e-14"]).unwrap_err().0;
        assert!(
            e.contains("--set time.dt=1e-14") && e.contains("more than 1e12"),
            "{e}"
        );
        let e = load_text("set-t-end", GOOD, &["time.t_end=1e20"])
            .unwrap_err()
            .0;
        assert!(
            e.contains("--set time.t_end=1e20") && e.contains("more than 1e12"),
            "{e}"
        );
        // Neither set: t_end's line of the file.
        let text = GOOD.replace("t_end = 0.5", "t_end = 1e20");
        let e = load_text("file-t-end", &text, &[]).unwrap_err().0;
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
