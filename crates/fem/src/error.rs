//! Typed errors of the fem crate. Each says what is wrong, where (group,
//! node, cell) and what to do; none of the user-input paths panics.

/// An error building or solving a finite element model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FemError {
    /// A material parameter outside its admissible range.
    #[error("invalid material: {parameter} = {value} {requirement}")]
    InvalidMaterial {
        /// "Young's modulus E", "Poisson's ratio nu" or "density rho".
        parameter: &'static str,
        /// The value given.
        value: f64,
        /// What it must be and what to do.
        requirement: &'static str,
    },
    /// A group name the mesh does not have.
    #[error("{purpose} names the physical group {name:?}, which the mesh does not have; it has: {}", available.join(", "))]
    UnknownGroup {
        /// The name asked for.
        name: String,
        /// What the group was wanted for ("a Dirichlet condition", "a traction", ...).
        purpose: String,
        /// The names the mesh has.
        available: Vec<String>,
    },
    /// A group of the wrong dimension for its use.
    #[error("{purpose} needs a group of boundary lines (dimension 1), but group {name:?} has dimension {dim}; name the boundary edges in Gmsh with a Physical Curve")]
    WrongGroupDimension {
        /// The group.
        name: String,
        /// What it was used for.
        purpose: String,
        /// Its dimension.
        dim: u8,
    },
    /// A boundary group whose edges do not form one open or closed chain.
    #[error("group {name:?} is not a single chain of boundary edges: {reason}; make the physical group one connected piece of the boundary (a traction may use one group per piece; the friction surface is one piece)")]
    NotAChain {
        /// The group.
        name: String,
        /// What breaks the chain.
        reason: String,
    },
    /// A Dirichlet component other than 0 (x) or 1 (y).
    #[error("the Dirichlet condition on group {group:?} names component {component}; use 0 for x or 1 for y")]
    InvalidComponent {
        /// The group.
        group: String,
        /// The component given.
        component: usize,
    },
    /// Two Dirichlet conditions giving the same DOF different values.
    #[error("node {node} at ({x}, {y}) gets u_{comp} = {first} from group {first_group:?} and u_{comp} = {second} from group {second_group:?}; give shared nodes one value")]
    ConflictingDirichlet {
        /// Node index.
        node: usize,
        /// Its x coordinate.
        x: f64,
        /// Its y coordinate.
        y: f64,
        /// "x" or "y".
        comp: &'static str,
        /// First value.
        first: f64,
        /// Group of the first value.
        first_group: String,
        /// Second value.
        second: f64,
        /// Group of the second value.
        second_group: String,
    },
    /// A Dirichlet value that is NaN or infinite.
    #[error("the Dirichlet condition on group {group:?} prescribes the non-finite value {value}; give a finite number")]
    NonFiniteDirichlet {
        /// The group.
        group: String,
        /// The value.
        value: f64,
    },
    /// A cell whose isoparametric map folds over (det J <= 0 at a quadrature point).
    #[error("cell {cell} (first node at ({x}, {y})) has a non-positive Jacobian determinant {det:e} at a quadrature point: the cell is inverted or its curved edges fold over; fix the mesh (move the mid-side nodes closer to the edge midpoints)")]
    InvertedCell {
        /// Cell index.
        cell: usize,
        /// x of the cell's first node.
        x: f64,
        /// y of the cell's first node.
        y: f64,
        /// The determinant found.
        det: f64,
    },
    /// The supports do not prevent a rigid-body motion: K is singular.
    #[error("the supports leave a rigid-body motion free: {motions}; add Dirichlet conditions that prevent it")]
    RigidBodyMotion {
        /// The free motions ("translation in x", "rotation about (0, 0)", ...).
        motions: String,
    },
    /// The sparse solver failed for another reason.
    #[error("sparse solver: {0}")]
    Solver(String),
}
