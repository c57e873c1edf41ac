//! The test kit: what the workspace's tests, examples and benchmarks
//! share, kept out of the libraries' public API. Its users take it as a
//! dev-dependency (`verify` and `study`, tools, as a dependency, for the
//! scenes their suites build in code).
//!
//! * [`grid`]: meshes built in code (a rectangle of Q1 or Q2 cells, the
//!   paper's slab as one) and edits of a mesh;
//! * [`scene`]: the slab's scenes (model, loads, contact surface) and the
//!   paper's slab on a committed mesh;
//! * [`wave`] and [`sdof`]: the two dynamic problems with a closed form,
//!   the 1-D wave (d'Alembert) and the single-DOF friction oscillator;
//! * [`strip`]: a thin strip on a rough base pulled at one end, the
//!   shear-lag problem of quasi-static friction and its 1-D closed form;
//! * [`impact`]: the bar-impact problem of Hughes et al. on a compliant
//!   wall, with the rigid wall's closed form, and [`settle`]: a block
//!   settling on a compliant floor under a pressure;
//! * [`block`] and [`damping`]: a block held only by friction (floating
//!   in x, rollers on its top) and Rayleigh damping's runs, with their
//!   closed forms;
//! * [`manufactured`]: the static manufactured solution of the fem
//!   convergence test and verify's rates suite;
//! * [`reference`](mod@reference): the plain sparse product and runs on
//!   a pool of a chosen number of threads, what the bit-for-bit tests
//!   compare against, and a vector for them to act on;
//! * [`paths`]: the workspace's folders, found from this crate's, and a
//!   scratch directory per test.
//!
//! A library's unit tests (`#[cfg(test)]` in its `src/`) cannot use the
//! kit when the kit depends on that library (they would see two copies of
//! its types): such tests live in the crate's `tests/` folder.

pub mod block;
pub mod case_text;
pub mod damping;
pub mod grid;
pub mod impact;
pub mod manufactured;
pub mod paths;
pub mod reference;
pub mod scene;
pub mod sdof;
pub mod settle;
pub mod solvers;
pub mod strip;
pub mod wave;
pub mod worst;

pub use grid::{add_point_group, map_nodes, rectangle, slab, structured_slab};
pub use paths::{meshes_dir, read_mesh, scratch, workspace_root};
pub use reference::{on_threads, plain_spmv, spread};
pub use scene::{paper_material, paper_slab, paper_supports, SceneError, Slab};
pub use worst::{max_or_nan, min_or_nan};
