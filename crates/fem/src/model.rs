//! The assembled model: DOF map, K and consistent M on the free DOFs (one
//! sparsity pattern; M only where a run reads it), HRZ-lumped mass, and
//! the load of the prescribed displacements.

use nalgebra_sparse::CsrMatrix;
use stickslip_mesh::Mesh;

use crate::assembly::{assemble, Assembly};
use crate::dofs::{Dirichlet, DofMap};
use crate::error::FemError;
use crate::material::Material;
use crate::ordering::NodeDissection;
use crate::pattern::{pattern_of, shared_adjacency, SharedAdjacency};
use crate::setup_times::SetupTimes;
use stickslip_linalg::FillOrder;

/// Nodes from which the DOF map's bandwidth order and the factors'
/// dissection are made side by side: below, the dissection takes about
/// 2 ms or less, and a thread's start and join are a visible part of it
/// (docs/performance.md).
const BESIDE_MIN_NODES: usize = 10_000;

/// K, M (unless built without it) and lumped M of a mesh and material
/// under Dirichlet conditions, restricted to the free DOFs.
#[derive(Clone, Debug)]
pub struct Model {
    /// Full ↔ free DOF map with the prescribed values.
    pub dofs: DofMap,
    /// Stiffness K on free DOFs: symmetric, both triangles stored, columns sorted.
    pub stiffness: CsrMatrix<f64>,
    /// Consistent mass M with the same sparsity pattern as `stiffness`
    /// (explicit zeros where only K couples, e.g. x-y entries); `None` for
    /// a model built without it ([`Model::without_consistent_mass`]).
    pub mass: Option<CsrMatrix<f64>>,
    /// HRZ lumped mass per free DOF (METHOD.md §3).
    pub lumped_mass: Vec<f64>,
    /// −K_fc u_c on free DOFs: the load of the prescribed displacements.
    pub dirichlet_load: Vec<f64>,
    /// Area of the mesh (∫ dA by the element rule).
    pub area: f64,
    /// The ordering of the Cholesky factors of K, M and their sums (AMD
    /// or nested dissection, by the mesh: `ordering.rs`).
    pub fill_order: FillOrder,
    /// How long the DOF map, the pattern, the assembly and the ordering took.
    pub setup: SetupTimes,
}

impl Model {
    /// Builds the DOF map and assembles K, M, lumped M (element loops in
    /// parallel, results independent of the thread count).
    ///
    /// # Errors
    /// Those of [`DofMap::new`], and [`FemError::InvertedCell`].
    pub fn new(
        mesh: &Mesh,
        material: &Material,
        conditions: &[Dirichlet],
    ) -> Result<Model, FemError> {
        Model::on_mesh(mesh, material, conditions, true)
    }

    /// [`Model::new`] without the consistent mass (`mass` is `None`): the
    /// explicit and quasi-static schemes and Newmark with the lumped mass
    /// never read it, and at 500k DOFs
    /// its values and its copy of the pattern are a sixth of a run's
    /// memory (docs/performance.md).
    ///
    /// # Errors
    /// As [`Model::new`].
    pub fn without_consistent_mass(
        mesh: &Mesh,
        material: &Material,
        conditions: &[Dirichlet],
    ) -> Result<Model, FemError> {
        Model::on_mesh(mesh, material, conditions, false)
    }

    /// The DOF map, then [`Model::build`].
    fn on_mesh(
        mesh: &Mesh,
        material: &Material,
        conditions: &[Dirichlet],
        with_mass: bool,
    ) -> Result<Model, FemError> {
        let mut setup = SetupTimes::default();
        // The DOF map's bandwidth order and the pattern read one adjacency.
        let adjacency = SharedAdjacency::new();
        let dof_map = || DofMap::with_adjacency(mesh, conditions, &adjacency);
        // The bandwidth order and the dissection each run on one thread:
        // on large meshes they run side by side, the part "DOF map" the
        // wall time of both.
        let (dofs, dissection) = setup.time("DOF map", || {
            if mesh.nodes.len() >= BESIDE_MIN_NODES && crate::ordering::wanted(mesh.nodes.len()) {
                std::thread::scope(|s| {
                    let nodes = s.spawn(|| crate::ordering::dissection_nodes(mesh));
                    let dofs = dof_map();
                    (dofs, Some(nodes.join().expect("the dissection's thread")))
                })
            } else {
                (dof_map(), None)
            }
        });
        Model::build(
            mesh, material, dofs?, &adjacency, setup, with_mass, dissection,
        )
    }

    /// [`Model::new`] on a DOF map of `mesh` made already (e.g. one
    /// [`DofMap::renumbered`] into another node order).
    ///
    /// # Errors
    /// [`FemError::InvertedCell`].
    pub fn with_dofs(mesh: &Mesh, material: &Material, dofs: DofMap) -> Result<Model, FemError> {
        let adjacency = SharedAdjacency::new();
        Model::build(
            mesh,
            material,
            dofs,
            &adjacency,
            SetupTimes::default(),
            true,
            None,
        )
    }

    /// [`Model::with_dofs`], its parts' times added to `setup`, M only
    /// `with_mass`, the factors' ordering from `dissection` if made.
    fn build(
        mesh: &Mesh,
        material: &Material,
        dofs: DofMap,
        adjacency: &SharedAdjacency,
        mut setup: SetupTimes,
        with_mass: bool,
        dissection: Option<NodeDissection>,
    ) -> Result<Model, FemError> {
        let pattern = setup.time("pattern", || {
            pattern_of(shared_adjacency(mesh, adjacency), &dofs)
        });
        let started = std::time::Instant::now();
        let nnz = pattern.nnz();
        let mut k = vec![0.0; nnz];
        let mut m = if with_mass {
            vec![0.0; nnz]
        } else {
            Vec::new()
        };
        let mut lumped_nodal = vec![0.0; mesh.nodes.len()];
        let mut dirichlet_load = vec![0.0; dofs.n_free()];
        let area = assemble(
            mesh,
            material,
            &dofs,
            &pattern,
            Assembly {
                stiffness: &mut k,
                mass: with_mass.then_some(&mut m[..]),
                lumped_nodal: &mut lumped_nodal,
                dirichlet_load: &mut dirichlet_load,
            },
        )?;
        let lumped_mass = (0..dofs.n_free())
            .map(|f| lumped_nodal[dofs.full_of_free(f) / 2])
            .collect();
        let matrix = |pattern, values| {
            CsrMatrix::try_from_pattern_and_values(pattern, values)
                .expect("one value per pattern entry")
        };
        // Without M, K takes the pattern itself rather than a copy.
        let (stiffness, mass) = if with_mass {
            (matrix(pattern.clone(), k), Some(matrix(pattern, m)))
        } else {
            (matrix(pattern, k), None)
        };
        setup.add("assembly", started.elapsed().as_secs_f64());
        let fill_order = setup.time("ordering", || {
            crate::ordering::choose(mesh, &dofs, dissection)
        });
        Ok(Model {
            setup,
            fill_order,
            dofs,
            stiffness,
            mass,
            lumped_mass,
            dirichlet_load,
            area,
        })
    }

    /// `out.values = a·K + b·M`, in place. `out` must have K's pattern (e.g.
    /// a clone of `stiffness` or the result of [`Model::combined`]); nothing
    /// is allocated.
    ///
    /// # Panics
    /// If `out` does not have as many entries as K, or the model was built
    /// without M.
    pub fn combine(&self, a: f64, b: f64, out: &mut CsrMatrix<f64>) {
        let mass = self
            .mass
            .as_ref()
            .expect("combine: the model was built without the consistent mass");
        assert_eq!(
            out.nnz(),
            self.stiffness.nnz(),
            "combine: `out` must have the pattern of the stiffness matrix"
        );
        debug_assert!(out.pattern() == self.stiffness.pattern());
        for ((o, &k), &m) in out
            .values_mut()
            .iter_mut()
            .zip(self.stiffness.values())
            .zip(mass.values())
        {
            *o = a * k + b * m;
        }
    }

    /// A new matrix `a·K + b·M` (allocates; use [`Model::combine`] to refill
    /// it). Panics as [`Model::combine`].
    pub fn combined(&self, a: f64, b: f64) -> CsrMatrix<f64> {
        let mut out = self.stiffness.clone();
        self.combine(a, b, &mut out);
        out
    }
}
