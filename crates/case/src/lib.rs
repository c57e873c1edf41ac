//! The case file of stickslip: its schema, reading and validation.
//!
//! * [`load`]: a case file (with `--set` overrides) read and validated into
//!   a [`Case`], every problem reported at once with its file and line, as
//!   an [`InputError`];
//! * the schema ([`schema`]): the types serde fills, the key list the
//!   key-by-key check walks generated from them;
//! * [`restart_changes`]: what a restart would change of a stored run.
//!
//! Nothing here touches a terminal or a results file.

mod error;
mod keys;
mod load;
mod locate;
mod restart;
pub mod schema;
mod set;

pub use error::{listed, InputError, SHOWN};
pub use load::{load, load_str, parse_str};
pub use restart::restart_changes;
pub use schema::{
    Case, ContactSection, DirichletSection, History, Hypothesis, MassKind, MaterialSection,
    MeshSection, OutputSection, Scheme, StickReduction, TimeSection, TractionSection,
};
