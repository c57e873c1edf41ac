//! The case file of stickslip, and the one path from a case to a model.
//!
//! * [`load`]: a case file (with `--set` overrides) read and validated into
//!   a [`Case`], every problem reported at once with its file and line, as
//!   an [`InputError`];
//! * the schema ([`schema`]): the types serde fills, the key list the
//!   key-by-key check walks generated from them;
//! * [`restart_changes`]: what a restart would change of a stored run;
//! * [`assemble`] and [`prepare`]: mesh, DOF map, model, loads, contact
//!   surface, settings and the integrator built from a case, the problems
//!   only the mesh reveals reported as [`InputError`]s too;
//! * [`Method`] and the pilot runner ([`pilot`]): a case run to t_end under
//!   one of the methods `stickslip advise` and the studies compare,
//!   recording chosen outputs, timed.
//!
//! Nothing here touches a terminal or a results file: the binary
//! (`stickslip`), `verify` and `study` use the same reader and builder.

#![forbid(unsafe_code)]

mod build;
mod compliance;
mod error;
mod keys;
mod load;
mod locate;
mod method;
pub mod pilot;
mod restart;
pub mod schema;
mod set;
mod surfaces;

pub use build::{assemble, assemble_for_run, prepare, settings, Prepared, Running, Scene};
pub use error::{listed, InputError, SHOWN};
pub use load::{load, load_str, parse_str};
pub use method::{Method, PAPER_REDUCTION};
pub use restart::restart_changes;
pub use schema::{
    Case, ContactSection, DirichletSection, Fields, History, Hypothesis, MassKind, MaterialSection,
    MeshSection, OutputSection, Profile, Scheme, StickReduction, Surfaces, TimeSection,
    TractionSection, DEFAULT_FRAMES,
};
