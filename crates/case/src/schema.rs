//! The case schema (DESIGN.md "Case file"), declared once: the types serde
//! fills are the types the rest of the code reads, and the key list that
//! the key-by-key check walks ([`Section::KEYS`]) is generated from the
//! same declarations by `section!` (below), each key's [`Kind`] taken
//! from its field's Rust type ([`Schema`]) unless the declaration gives
//! one (`=> Kind::Count`). docs/case-file.md is tested
//! against [`key_paths`].
//!
//! Values read as written (relative paths, defaults) are completed by
//! loading (`load.rs`): paths resolved against the case file's directory,
//! `output.file` defaulted from the case's name.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::Deserialize;

/// What a key's value must be.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    /// A string.
    Str,
    /// A string naming one of an enumeration's values; the value given is
    /// a valid one, put in place of a value of the wrong type so that the
    /// rest of the case can still be checked.
    Variant(&'static str),
    /// A number (integer or float).
    Num,
    /// A whole number >= 0.
    Int,
    /// A whole number >= 1 (a count of steps, frames, iterations), given
    /// in `section!` as `=> Kind::Count` (the Rust type is `usize` either
    /// way): what a negative value's message says; the value checks
    /// refuse 0 in their own words.
    Count,
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
    /// One table (`[name]`) or a list of them (`[[name]]`) with these keys.
    OneOrTables(&'static [(&'static str, Kind)]),
    /// Anything (checked by serde: `history`).
    Any,
}

/// The [`Kind`] of a field's Rust type: what its TOML value must be.
pub trait Schema {
    /// The kind.
    const KIND: Kind;
}

/// A table of the case file: its keys and their kinds, in declaration order.
pub trait Section {
    /// The keys.
    const KEYS: &'static [(&'static str, Kind)];
}

macro_rules! kind {
    ($kind:expr => $($t:ty),+) => {
        $(impl Schema for $t {
            const KIND: Kind = $kind;
        })+
    };
}
kind!(Kind::Str => String, PathBuf);
kind!(Kind::Num => f64);
kind!(Kind::Int => usize, u64);
kind!(Kind::Bool => bool);
kind!(Kind::Vec2 => [f64; 2]);
kind!(Kind::StrList => Vec<PathBuf>);

impl<T: Schema> Schema for Option<T> {
    const KIND: Kind = T::KIND;
}

impl<T: Section> Schema for Vec<T> {
    const KIND: Kind = Kind::Tables(T::KEYS);
}

/// The [`Kind`] of a key: its type's, or the one given.
macro_rules! kind_of {
    ($ty:ty) => {
        <$ty as Schema>::KIND
    };
    ($ty:ty, $kind:expr) => {
        $kind
    };
}

/// Declares a table of the case file: a struct that serde fills (unknown
/// keys refused), each field given with its TOML key (and, after `=>`, a
/// [`Kind`] other than its type's), and its [`Section::KEYS`]. Fields
/// after `derived` are no keys: loading fills them.
macro_rules! section {
    (
        $(#[$attr:meta])*
        pub struct $name:ident {
            $(
                $(#[$fattr:meta])*
                $key:literal $field:ident: $ty:ty $(=> $kind:expr)?,
            )*
        }
        $(derived {
            $(
                $(#[$dattr:meta])*
                $dfield:ident: $dty:ty,
            )*
        })?
    ) => {
        $(#[$attr])*
        #[derive(Clone, Debug, PartialEq, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            $(
                $(#[$fattr])*
                #[serde(rename = $key)]
                pub $field: $ty,
            )*
            $($(
                $(#[$dattr])*
                #[serde(skip)]
                pub $dfield: $dty,
            )*)?
        }

        impl Section for $name {
            const KEYS: &'static [(&'static str, Kind)] =
                &[$(($key, kind_of!($ty $(, $kind)?))),*];
        }

        impl Schema for $name {
            const KIND: Kind = Kind::Table(<$name as Section>::KEYS);
        }
    };
}

section! {
    /// A validated case: everything a run needs besides the mesh itself.
    pub struct Case {
        /// Free-text title.
        "title" title: Option<String>,
        /// The mesh.
        "mesh" mesh: MeshSection,
        /// Linear elastic material.
        "material" material: MaterialSection,
        /// Prescribed displacements, one entry per group.
        #[serde(default)]
        "dirichlet" dirichlet: Vec<DirichletSection>,
        /// Prescribed tractions, one entry per group.
        #[serde(default)]
        "traction" traction: Vec<TractionSection>,
        /// Constant body force per unit volume (bx, by), if any.
        "body_force" body_force: Option<[f64; 2]>,
        /// The frictional contact surfaces: `[contact]` (one) or
        /// `[[contact]]` (several); empty without friction.
        #[serde(default)]
        "contact" contact: Surfaces,
        /// The state at t = 0.
        #[serde(default)]
        "initial" initial: InitialSection,
        /// Time integration.
        "time" time: TimeSection,
        /// Results file.
        #[serde(default)]
        "output" output: OutputSection,
    }
    derived {
        /// The case file as given on the command line.
        path: PathBuf,
        /// The TOML text as run (after `--set`), stored in the results file.
        source: String,
        /// Where each key is in the user's text: dotted key (`contact.group`,
        /// `dirichlet.0.group`, `time.dt`, ...) → `file:line:col` (or
        /// `--set ..`), for the problems only the mesh reveals.
        locations: BTreeMap<String, String>,
    }
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

    /// The dotted key of contact surface `i`'s `key`: `contact.KEY` for a
    /// single `[contact]` table, `contact.I.KEY` in a list of `[[contact]]`.
    pub fn contact_key(&self, i: usize, key: &str) -> String {
        contact_key_in(self.locations.keys(), i, key)
    }
}

/// [`Case::contact_key`] among the dotted keys `keys` of a case's text.
pub(crate) fn contact_key_in<'a>(
    mut keys: impl Iterator<Item = &'a String>,
    i: usize,
    key: &str,
) -> String {
    let listed = format!("contact.{i}.");
    if keys.any(|k| k.starts_with(&listed)) {
        format!("{listed}{key}")
    } else {
        format!("contact.{key}")
    }
}

/// The contact surfaces of a case, in the order given: `[contact]` is
/// one, `[[contact]]` several, none without friction.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Surfaces(pub Vec<ContactSection>);

impl std::ops::Deref for Surfaces {
    type Target = Vec<ContactSection>;
    fn deref(&self) -> &Vec<ContactSection> {
        &self.0
    }
}

impl std::ops::DerefMut for Surfaces {
    fn deref_mut(&mut self) -> &mut Vec<ContactSection> {
        &mut self.0
    }
}

impl Schema for Surfaces {
    const KIND: Kind = Kind::OneOrTables(ContactSection::KEYS);
}

/// `[contact]` as one surface, `[[contact]]` as a list (serde's own errors
/// kept: a history or a key is reported as for any table).
impl<'de> Deserialize<'de> for Surfaces {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Surfaces, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Surfaces;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a [contact] table or [[contact]] tables")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<Surfaces, A::Error> {
                let one =
                    ContactSection::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(Surfaces(vec![one]))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Surfaces, A::Error> {
                Vec::deserialize(serde::de::value::SeqAccessDeserializer::new(seq)).map(Surfaces)
            }
        }
        d.deserialize_any(Visitor)
    }
}

section! {
    /// `[mesh]`.
    pub struct MeshSection {
        /// The `.msh` file, resolved against the case file's directory.
        "file" file: PathBuf,
        /// Meshes of the same geometry and group names, coarse to fine,
        /// resolved against the case file's directory (empty when the key
        /// is absent). Only `stickslip advise` reads it; a run uses `file`.
        #[serde(default)]
        "ladder" ladder: Vec<PathBuf>,
    }
    derived {
        /// The ladder entries as written in the case file (for `advise --write`).
        ladder_text: Vec<String>,
    }
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

impl Schema for Hypothesis {
    const KIND: Kind = Kind::Variant("plane_strain");
}

section! {
    /// `[material]`.
    pub struct MaterialSection {
        /// Young's modulus.
        "E" e: f64,
        /// Poisson's ratio.
        "nu" nu: f64,
        /// Mass density.
        "rho" rho: f64,
        /// Plane strain (default) or plane stress.
        #[serde(default)]
        "hypothesis" hypothesis: Hypothesis,
        /// Rayleigh damping C = alpha M + beta K, if any.
        "damping" damping: Option<Damping>,
    }
}

section! {
    /// `material.damping`: Rayleigh damping C = αM + βK.
    #[derive(Copy)]
    pub struct Damping {
        /// α, mass-proportional (1/time; default 0).
        #[serde(default)]
        "alpha" alpha: f64,
        /// β, stiffness-proportional (time; default 0).
        #[serde(default)]
        "beta" beta: f64,
    }
}

section! {
    /// One `[[dirichlet]]` table: a component left out stays free.
    pub struct DirichletSection {
        /// Physical group name.
        "group" group: String,
        /// Prescribed u_x.
        "ux" ux: Option<f64>,
        /// Prescribed u_y.
        "uy" uy: Option<f64>,
    }
}

section! {
    /// One `[[traction]]` table: exactly one of `t` and `pressure` is set.
    pub struct TractionSection {
        /// Physical group name (a line group).
        "group" group: String,
        /// Traction vector (t_x, t_y).
        "t" t: Option<[f64; 2]>,
        /// Normal pressure (positive pushes into the body).
        "pressure" pressure: Option<f64>,
        /// Time factor multiplying the load.
        #[serde(default)]
        "history" history: History,
    }
}

/// Time factor of a load. TOML: `"constant"`, `"step"`,
/// `{ sin = { omega = .. } }` or `{ table = [[t0, f0], ..] }`; default `"step"`.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum History {
    /// 1 for all t, t < 0 included: part of the initial static state.
    Constant,
    /// Heaviside H(t) with H(0) = 1: on from t = 0, not in the static state.
    #[default]
    Step,
    /// sin(ω t).
    Sin {
        /// Angular frequency ω (rad per unit time).
        omega: f64,
    },
    /// Piecewise linear through (t_i, f_i), constant beyond the ends.
    Table(Vec<[f64; 2]>),
}

impl Schema for History {
    const KIND: Kind = Kind::Any;
}

/// A TOML value for a message: "the number 25", "a table".
fn described(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("the string {s:?}"),
        toml::Value::Integer(i) => format!("the number {i}"),
        toml::Value::Float(f) => format!("the number {f}"),
        toml::Value::Boolean(b) => b.to_string(),
        toml::Value::Datetime(_) => "a date".into(),
        toml::Value::Array(a) => format!("an array of {}", a.len()),
        toml::Value::Table(_) => "a table".into(),
    }
}

/// A TOML integer or float as f64 (`1000` and `1000.0` alike).
pub(crate) fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(f) => Some(*f),
        _ => None,
    }
}

/// Each history form checked by hand, so that a message says what is wrong
/// with the form given (serde's derive said "invalid type: unit variant,
/// expected struct variant"); loading adds the forms a history takes.
impl<'de> Deserialize<'de> for History {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<History, D::Error> {
        use serde::de::Error;
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = History;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a history, text or a table of one key")
            }
            fn visit_bool<E: Error>(self, v: bool) -> Result<History, E> {
                Err(not_a_history(&v.to_string()))
            }
            fn visit_i64<E: Error>(self, v: i64) -> Result<History, E> {
                Err(not_a_history(&format!("the number {v}")))
            }
            fn visit_u64<E: Error>(self, v: u64) -> Result<History, E> {
                Err(not_a_history(&format!("the number {v}")))
            }
            fn visit_f64<E: Error>(self, v: f64) -> Result<History, E> {
                Err(not_a_history(&format!("the number {v}")))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, _: A) -> Result<History, A::Error> {
                Err(not_a_history(
                    "an array (a table's points go in { table = [...] })",
                ))
            }
            fn visit_str<E: Error>(self, v: &str) -> Result<History, E> {
                match v {
                    "constant" => Ok(History::Constant),
                    "step" => Ok(History::Step),
                    "sin" => Err(E::custom(
                        "\"sin\" alone lacks the angular frequency: a sine is a table, { sin = { omega = ... } }",
                    )),
                    "table" => Err(E::custom(
                        "\"table\" alone lacks the points: a table history is { table = [[t, f], ...] }",
                    )),
                    other => Err(E::custom(format!(
                        "unknown variant `{other}`: no history is called that"
                    ))),
                }
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<History, A::Error> {
                let Some(key) = map.next_key::<String>()? else {
                    return Err(A::Error::custom(
                        "an empty table is no history: a history table has one key, sin or table",
                    ));
                };
                let history = match key.as_str() {
                    "sin" => sin(&map.next_value::<toml::Value>()?),
                    "table" => rows(&map.next_value::<toml::Value>()?).map(History::Table),
                    "constant" | "step" => Err(format!(
                        "{key} is written as text, \"{key}\", not as a table"
                    )),
                    // How toml hands a date to a visitor.
                    k if k.starts_with("$__toml_private") => return Err(not_a_history("a date")),
                    other => Err(format!(
                        "a history table has no key `{other}`; its one key is sin or table"
                    )),
                }
                .map_err(A::Error::custom)?;
                if let Some(more) = map.next_key::<String>()? {
                    return Err(A::Error::custom(format!(
                        "a history table has one key, sin or table; this one has `{key}` and `{more}`"
                    )));
                }
                Ok(history)
            }
        }
        d.deserialize_any(Visitor)
    }
}

fn not_a_history<E: serde::de::Error>(found: &str) -> E {
    E::custom(format!(
        "a history is text or a table of one key, found {found}"
    ))
}

/// `{ sin = { omega = ω } }`: the value of `sin`.
fn sin(v: &toml::Value) -> Result<History, String> {
    let toml::Value::Table(t) = v else {
        let omega = number(v).map_or("...".into(), |w| w.to_string());
        return Err(format!(
            "sin takes a table of its angular frequency, found {}: write {{ sin = {{ omega = {omega} }} }}",
            described(v)
        ));
    };
    if let Some(k) = t.keys().find(|k| *k != "omega") {
        return Err(format!(
            "sin has no key `{k}`; its one key is omega, the angular frequency (sin(omega t))"
        ));
    }
    match t.get("omega") {
        None => {
            Err("sin lacks omega, the angular frequency: write { sin = { omega = ... } }".into())
        }
        Some(w) => match number(w) {
            Some(omega) => Ok(History::Sin { omega }),
            None => Err(format!(
                "sin's omega must be a number, found {}; write numbers without quotes",
                described(w)
            )),
        },
    }
}

/// `{ table = [[t, f], ...] }`: the rows of `table`, each two numbers.
fn rows(v: &toml::Value) -> Result<Vec<[f64; 2]>, String> {
    let toml::Value::Array(a) = v else {
        return Err(format!(
            "table takes a list of [t, f] points, found {}: write {{ table = [[0.0, 0.0], [0.1, 1.0]] }}",
            described(v)
        ));
    };
    a.iter()
        .enumerate()
        .map(|(i, r)| {
            let row = match r {
                toml::Value::Array(r) => r.iter().map(number).collect::<Option<Vec<f64>>>(),
                _ => None,
            };
            match row.as_deref() {
                Some(r) => two_numbers(i, r),
                None => Err(format!(
                    "table row {} is {}, not two numbers [t, f]; write the table as [[0.0, 0.0], [0.1, 1.0]]",
                    i + 1,
                    match r {
                        toml::Value::Array(_) => "an array holding something other than numbers".into(),
                        other => described(other),
                    }
                )),
            }
        })
        .collect()
}

/// A table's rows, each exactly two numbers (serde's [f64; 2] takes [t, f,
/// x] and drops x).
fn table_points<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<[f64; 2]>, D::Error> {
    let rows = Vec::<Vec<f64>>::deserialize(d)?;
    rows.iter()
        .enumerate()
        .map(|(i, r)| two_numbers(i, r).map_err(serde::de::Error::custom))
        .collect()
}

/// Table row `i` (from 0) as its two numbers.
fn two_numbers(i: usize, r: &[f64]) -> Result<[f64; 2], String> {
    match *r {
        [t, f] => Ok([t, f]),
        _ => Err(format!(
            "table row {} has {} numbers; each row is two: [t, f] in a history, [s, factor] in a profile",
            i + 1,
            r.len()
        )),
    }
}

impl History {
    /// The factor at time `t` (the builder hands the history to the time
    /// crate, which evaluates its own copy; this one documents and tests
    /// the schema).
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

fn default_remark_4_2() -> bool {
    true
}

fn default_max_iterations() -> usize {
    100
}

fn constant_history() -> History {
    History::Constant
}

/// The friction coefficient: `mu = 0.3`, the paper's constant law, or
/// `mu = { static = μs, kinetic = μk, speed = vs }`, μ(w) = μk + (μs − μk)
/// e^{−|w|/vs} on the slip speed (METHOD.md §9).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mu {
    /// μ for every slip speed.
    Constant(f64),
    /// μ falling from μs at rest to μk.
    Speed {
        /// μs.
        stat: f64,
        /// μk.
        kinetic: f64,
        /// vs.
        speed: f64,
    },
}

impl Mu {
    /// μ at rest: the constant μ, or μs (the friction bound's g = μ p).
    pub fn at_rest(&self) -> f64 {
        match *self {
            Mu::Constant(mu) | Mu::Speed { stat: mu, .. } => mu,
        }
    }
}

impl Schema for Mu {
    const KIND: Kind = Kind::Any;
}

const MU_FORMS: &str =
    "write mu = 0.3, or mu = { static = 0.5, kinetic = 0.3, speed = 1e-2 } for a coefficient that falls from static to kinetic with the slip speed";

impl<'de> Deserialize<'de> for Mu {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Mu, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Mu;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(
                    f,
                    "a number or a table {{ static, kinetic, speed }}; {MU_FORMS}"
                )
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Mu, E> {
                Ok(Mu::Constant(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Mu, E> {
                Ok(Mu::Constant(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Mu, E> {
                Ok(Mu::Constant(v as f64))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Mu, A::Error> {
                use serde::de::Error;
                let mut got: [Option<f64>; 3] = [None; 3];
                let names = ["static", "kinetic", "speed"];
                while let Some(key) = map.next_key::<String>()? {
                    let Some(k) = names.iter().position(|n| *n == key) else {
                        return Err(A::Error::custom(format!(
                            "mu has no key `{key}`: its keys are static, kinetic and speed; {MU_FORMS}"
                        )));
                    };
                    got[k] = Some(
                        map.next_value::<f64>()
                            .map_err(|e| A::Error::custom(format!("mu.{key}: {e}; {MU_FORMS}")))?,
                    );
                }
                match got {
                    [Some(stat), Some(kinetic), Some(speed)] => Ok(Mu::Speed {
                        stat,
                        kinetic,
                        speed,
                    }),
                    _ => {
                        let missing: Vec<&str> = names
                            .iter()
                            .zip(got)
                            .filter(|(_, v)| v.is_none())
                            .map(|(n, _)| *n)
                            .collect();
                        Err(A::Error::custom(format!(
                            "mu lacks {}; {MU_FORMS}",
                            missing.join(" and ")
                        )))
                    }
                }
            }
        }
        d.deserialize_any(Visitor)
    }
}

section! {
    /// `pressure_profile = { table = [[s, factor], ..] }`: the pressure's
    /// factor along the surface, linear between rows.
    pub struct Profile {
        /// Rows [s, factor], s increasing from the surface's start.
        #[serde(deserialize_with = "table_points")]
        "table" table: Vec<[f64; 2]>,
    }
}

kind!(Kind::Any => Vec<[f64; 2]>);

section! {
    /// `[contact]`: the regularized Coulomb friction surface (METHOD.md).
    pub struct ContactSection {
        /// Line group on which friction acts.
        "group" group: String,
        /// Prescribed normal pressure F_n (friction bound g = μ F_n);
        /// required by the law `"pressure"`, refused by `"compliance"`.
        "pressure" pressure: Option<f64>,
        /// Coulomb coefficient μ, or μ falling with the slip speed; with
        /// `"compliance"` (constant only) c_T = μ c_n and m_T = m_n (or
        /// `ct`, `mt`).
        "mu" mu: Option<Mu>,
        /// Regularization ε of the friction law (each surface its own).
        "eps" eps: f64,
        /// Time factor of the pressure (the normal load and g = μ p);
        /// default `"constant"`, today's pressure present before t = 0.
        #[serde(default = "constant_history")]
        "pressure_history" pressure_history: History,
        /// Factor of the pressure along the surface's arc length s.
        "pressure_profile" pressure_profile: Option<Profile>,
        /// Speed V of the foundation along the surface's tangent τ (a
        /// conveyor belt): the law acts on the slip v_T − V (METHOD.md §9);
        /// default 0, a foundation at rest.
        #[serde(default)]
        "foundation_velocity" foundation_velocity: f64,
        /// Time factor of V, the forms of a traction's `history`; default
        /// `"constant"`.
        #[serde(default = "constant_history")]
        "foundation_history" foundation_history: History,
        /// The paper's Remark 4.2 rule in the iteration (default true).
        #[serde(default = "default_remark_4_2")]
        "remark_4_2" remark_4_2: bool,
        /// Iteration cap per step (default 100).
        #[serde(default = "default_max_iterations")]
        "max_iterations" max_iterations: usize => Kind::Count,
        /// The normal law: a prescribed pressure (default) or a compliant
        /// foundation (METHOD.md §10).
        #[serde(default)]
        "law" law: ContactLaw,
        /// The rigid foundation of `law = "compliance"`.
        "foundation" foundation: Option<FoundationLine>,
        /// c_n > 0: σ_n = c_n δ^{m_n}.
        "cn" cn: Option<f64>,
        /// m_n ≥ 1.
        "mn" mn: Option<f64>,
        /// c_T ≥ 0: the friction bound c_T δ^{m_T} (in place of μ).
        "ct" ct: Option<f64>,
        /// m_T ≥ 1 (with `ct`).
        "mt" mt: Option<f64>,
    }
}

impl ContactSection {
    /// μ at rest (0 where the surface gives none: a compliance surface
    /// with `ct`).
    pub fn mu_at_rest(&self) -> f64 {
        self.mu.as_ref().map_or(0.0, Mu::at_rest)
    }
}

/// The normal law of a contact surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactLaw {
    /// The paper's prescribed normal pressure.
    #[default]
    Pressure,
    /// Normal compliance against a rigid foundation.
    Compliance,
}

impl Schema for ContactLaw {
    const KIND: Kind = Kind::Variant("pressure");
}

section! {
    /// `foundation = { point = [x, y], normal = [nx, ny] }`: a straight
    /// rigid foundation.
    pub struct FoundationLine {
        /// A point of the line.
        "point" point: [f64; 2],
        /// Its normal, pointing towards the body (normalized on loading).
        "normal" normal: [f64; 2],
    }
}

/// Where a run starts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InitialState {
    /// Remark 4.1: the frictionless static equilibrium under the loads
    /// present before t = 0.
    #[default]
    Static,
    /// Undeformed (u = 0): every load acts from t = 0 on.
    Rest,
}

impl Schema for InitialState {
    const KIND: Kind = Kind::Variant("static");
}

section! {
    /// One `[[initial.velocities]]` table: the initial velocity of a group's
    /// nodes.
    pub struct GroupVelocity {
        /// Physical group name (any dimension).
        "group" group: String,
        /// (v_x, v_y) of every node of the group.
        "velocity" velocity: [f64; 2],
    }
}

section! {
    /// `[initial]`: the state at t = 0.
    #[derive(Default)]
    pub struct InitialSection {
        /// Static preload (default) or rest.
        #[serde(default)]
        "state" state: InitialState,
        /// A uniform initial velocity of every node (default zero).
        "velocity" velocity: Option<[f64; 2]>,
        /// Initial velocities per group, in place of `velocity` on the
        /// group's nodes (a later entry wins where groups share nodes).
        #[serde(default)]
        "velocities" velocities: Vec<GroupVelocity>,
    }
}

/// Time integration scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scheme {
    /// Explicit, lumped mass (β = 0, γ = ½).
    CentralDifference,
    /// Implicit Newmark (β, γ).
    Newmark,
    /// Load increments without inertia, friction on the increments' rate.
    QuasiStatic,
}

impl Schema for Scheme {
    const KIND: Kind = Kind::Variant("central_difference");
}

impl Scheme {
    /// The value `time.scheme` takes for it.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::CentralDifference => "central_difference",
            Scheme::Newmark => "newmark",
            Scheme::QuasiStatic => "quasi_static",
        }
    }
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

impl Schema for MassKind {
    const KIND: Kind = Kind::Variant("lumped");
}

section! {
    /// Remark 4.3 step reduction after a slip-to-stick transition.
    #[derive(Copy)]
    pub struct StickReduction {
        /// The reduced step.
        "dt" dt: f64,
        /// How many reduced steps follow each sticking event.
        "steps" steps: usize => Kind::Count,
    }
}

fn default_beta() -> f64 {
    0.25
}

fn default_gamma() -> f64 {
    0.5
}

section! {
    /// `[time]`.
    pub struct TimeSection {
        /// Central difference, Newmark, or quasi-static increments.
        "scheme" scheme: Scheme,
        /// Newmark β (default 0.25; refused for central difference).
        #[serde(default = "default_beta")]
        "beta" beta: f64,
        /// Newmark γ (default 0.5; refused for central difference).
        #[serde(default = "default_gamma")]
        "gamma" gamma: f64,
        /// Mass override; `None` = the scheme's default (lumped for central
        /// difference, consistent for Newmark).
        "mass" mass: Option<MassKind>,
        /// Time step.
        "dt" dt: f64,
        /// End time.
        "t_end" t_end: f64,
        /// Remark 4.3 step reduction, if asked for.
        "stick_reduction" stick_reduction: Option<StickReduction>,
        /// Run an explicit scheme above Δt_crit anyway.
        #[serde(default)]
        "allow_unstable" allow_unstable: bool,
    }
}

/// Frames of the full fields over [0, t_end] when the case names neither
/// `output.frames`, `output.interval` nor `output.every`: enough for a
/// film or a probe, and a file whose fields do not grow with the steps
/// (docs/results.md, "What is written, and why").
pub const DEFAULT_FRAMES: usize = 200;

fn default_flush_seconds() -> f64 {
    5.0
}

section! {
    /// `[output]`.
    pub struct OutputSection {
        /// Results file, resolved against the case file's directory
        /// (default `<case stem>.h5` next to the case file).
        #[serde(default)]
        "file" file: PathBuf,
        /// Full fields (u, v, a) at `frames` frames over [0, t_end]: the
        /// first steps at or after k·t_end/frames (default
        /// [`DEFAULT_FRAMES`] when neither `interval` nor `every` is given).
        "frames" frames: Option<usize> => Kind::Count,
        /// ... or at the first steps at or after k·interval.
        "interval" interval: Option<f64>,
        /// ... or at every `every`-th step.
        "every" every: Option<usize> => Kind::Count,
        /// Flush the file (and rewrite the checkpoint) at least every this
        /// many steps (default: none, by wall time only: a run's steps
        /// may take microseconds or minutes, its wall time is what a crash
        /// loses).
        "flush_every" flush_every: Option<usize> => Kind::Count,
        /// ... and at least every this many seconds of wall time (default
        /// 5), counted from the start of the run, its setup included.
        #[serde(default = "default_flush_seconds")]
        "flush_seconds" flush_seconds: f64,
        /// Deflate level of the growing datasets, 0 to 9 (`None`: the
        /// results writer's default); wider as read, so that a level out of
        /// range is reported with its value.
        "compression" compression: Option<u64>,
    }
}

impl Default for OutputSection {
    fn default() -> Self {
        OutputSection {
            file: PathBuf::new(),
            frames: None,
            interval: None,
            every: None,
            flush_every: None,
            flush_seconds: default_flush_seconds(),
            compression: None,
        }
    }
}

/// When a run writes the full fields (u, v, a): `output.frames`,
/// `output.interval` or `output.every`, at most one of them given (loading
/// refuses more), the initial state and the last step always.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fields {
    /// At the first steps at or after k·t_end/N, k = 1..N.
    Frames(usize),
    /// At the first steps at or after k·Δt_out.
    Interval(f64),
    /// At every N-th step.
    Every(usize),
}

impl OutputSection {
    /// When the full fields are written.
    pub fn fields(&self) -> Fields {
        match (self.every, self.interval, self.frames) {
            (Some(n), _, _) => Fields::Every(n.max(1)),
            (None, Some(dt), _) => Fields::Interval(dt),
            (None, None, n) => Fields::Frames(n.unwrap_or(DEFAULT_FRAMES).max(1)),
        }
    }

    /// The deflate level asked for, if any (validated to 0..=9 when the
    /// case was loaded).
    pub fn deflate_level(&self) -> Option<u8> {
        self.compression.map(|c| c.min(9) as u8)
    }
}

/// The keys of the whole case file.
pub const ROOT: &[(&str, Kind)] = <Case as Section>::KEYS;

/// Visits every key of `keys` and below, depth first in declaration
/// order, with its dotted path (no list indices) and kind.
fn walk(keys: &'static [(&'static str, Kind)], prefix: &str, visit: &mut dyn FnMut(&str, &Kind)) {
    for (key, kind) in keys {
        let name = if prefix.is_empty() {
            key.to_string()
        } else {
            format!("{prefix}.{key}")
        };
        visit(&name, kind);
        if let Kind::Table(sub) | Kind::Tables(sub) | Kind::OneOrTables(sub) = kind {
            walk(sub, &name, visit);
        }
    }
}

/// Every table of the schema with its name, in the order of the schema
/// (`mesh`, `[dirichlet]` for a list of tables, `time.stick_reduction`),
/// to say where a misplaced key belongs.
pub fn sections() -> Vec<(String, &'static [(&'static str, Kind)])> {
    let mut out = Vec::new();
    walk(ROOT, "", &mut |name, kind| match kind {
        Kind::Table(sub) => out.push((name.to_string(), *sub)),
        Kind::Tables(sub) => out.push((format!("[{name}]"), *sub)),
        // Named as its single table, `[contact]`, which stays valid.
        Kind::OneOrTables(sub) => out.push((name.to_string(), *sub)),
        _ => {}
    });
    out
}

/// Every key a case may have, as a dotted path without list indices
/// (`time.stick_reduction.dt`, `dirichlet.group`); tables are listed by
/// their keys only.
pub fn key_paths() -> Vec<String> {
    let mut out = Vec::new();
    walk(ROOT, "", &mut |name, kind| {
        if !matches!(
            kind,
            Kind::Table(_) | Kind::Tables(_) | Kind::OneOrTables(_)
        ) {
            out.push(name.to_string());
        }
    });
    out
}
