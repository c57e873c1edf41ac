"""The FEniCSx peer of `cargo xtask bench run`: a whole run of the paper's
scene in DOLFINx 0.11, written as a researcher would write it, so that the
whole process is timed as stickslip's is.

    python bench/fenicsx_run.py CASE.toml -o OUT.h5 [--set KEY=VALUE]...

It needs DOLFINx with real PETSc (the `dolfinx-solver-real` wheel, Python
≥ 3.12), meshio and h5py; `cargo xtask bench run` installs them into
a venv (target/bench/fenicsx) when they are missing. `import dolfinx_solver`
must come before `import dolfinx` (it loads the wheel's PETSc).

* The case and the mesh as a user has them (`peer_case.py`: the TOML with
  `--set`, the Gmsh file by meshio); the mesh made a DOLFINx mesh with
  Gmsh's node order permuted, its line groups facet tags.
* Consistent K and M (UFL, DOLFINx's default quadrature), the tractions
  and the contact pressure −F_n n as boundary integrals.
* Friction as a nodal term: g φ_ε(v·τ) (w·τ) on the contact facets with a
  Gauss–Lobatto rule (2 points on Q1 edges, 3 on Q2: the trapezoid and
  Simpson rules of METHOD.md §3), τ = (−n_y, n_x).
* Newmark (METHOD.md §4, the velocity the unknown): the step's residual in
  UFL, its Jacobian by `ufl.derivative`, solved by PETSc SNES (Newton,
  MUMPS). Plain Newton cycles between the slip directions on this problem;
  Remark 4.2 is the line search's pre-check: a node the Newton step would
  take from slipping one way to slipping the other has its step cut to
  v_T = 0 (stuck).
* Central difference: the row-sum lumped mass (HRZ's on rectangular cells,
  the committed and structured slabs; not on distorted ones, so the bench
  runs this peer on structured meshes only), K·r by PETSc, the friction
  in the nodal closed form t + c φ_ε(t) = p per node (numpy).
* Initial state (Remark 4.1): r₀ from K r₀ = R(0⁻), r̈₀ from M r̈₀ = R(0) −
  K r₀ with the scheme's mass (MUMPS).

The results file (h5py, per DOF node: `/mesh/nodes` the DOFs' locations)
is what `bench/peer_check.py` compares with stickslip's.
"""
import dolfinx_solver  # noqa: F401  (before dolfinx: the wheel's PETSc)

import basix.ufl
import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.io import gmsh as gmshio
from dolfinx.mesh import CellType, meshtags_from_entities
from mpi4py import MPI

import peer_case

args = peer_case.arguments("FEniCSx peer: one whole run of the paper's scene")
case = peer_case.load_case(args.case, args.sets)
sc = peer_case.Scene(case)
comm = MPI.COMM_WORLD
order = sc.order
nodes_per = 9 if order == 2 else 4
cells = sc.cells[:, gmshio.cell_perm_array(CellType.quadrilateral, nodes_per)]
coord = basix.ufl.element("Lagrange", "quadrilateral", order, shape=(2,))
mesh = dolfinx.mesh.create_mesh(comm, cells.astype(np.int64), ufl.Mesh(coord), sc.nodes)
fdim = 1
mesh.topology.create_connectivity(fdim, 2)
names = sorted(sc.lines)
edges = np.concatenate([sc.lines[k] for k in names])
values = np.concatenate([np.full(len(sc.lines[k]), i, dtype=np.int32) for i, k in enumerate(names)])
facet_perm = gmshio.cell_perm_array(CellType.interval, edges.shape[1])
local, vals = gmshio.distribute_entity_data(mesh, fdim, edges[:, facet_perm].astype(np.int64), values)
tags = meshtags_from_entities(mesh, fdim, dolfinx.graph.adjacencylist(local), vals.astype(np.int32))
tag = {k: i for i, k in enumerate(names)}
ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
ds_gll = ufl.Measure("ds", domain=mesh, subdomain_data=tags,
                     metadata={"quadrature_rule": "GLL", "quadrature_degree": 2 * order - 1})

V = fem.functionspace(mesh, ("Lagrange", order, (2,)))
w = ufl.TestFunction(V)
lam = sc.young * sc.poisson / ((1 + sc.poisson) * (1 - 2 * sc.poisson))  # plane strain
mu = sc.young / (2 * (1 + sc.poisson))
rho = sc.rho


def sigma(u):
    e = ufl.sym(ufl.grad(u))
    return 2 * mu * e + lam * ufl.tr(e) * ufl.Identity(2)


bcs = []
for d in case.get("dirichlet", []):
    facets = tags.find(tag[d["group"]])
    for c, key in enumerate(("ux", "uy")):
        if key in d:
            dofs = fem.locate_dofs_topological(V.sub(c), fdim, facets)
            bcs.append(fem.dirichletbc(0.0, dofs, V.sub(c)))
held = np.unique(np.concatenate([b.dof_indices()[0] for b in bcs]))
n_nodes = V.dofmap.index_map.size_local

# Loads: R(0⁻) (constant histories and the pressure) and R(t ≥ 0).
n = ufl.FacetNormal(mesh)
con = case["contact"]
pressure, g, eps = float(con["pressure"]), float(con["mu"]) * float(con["pressure"]), sc.eps
c_tag = tag[con["group"]]
before = ufl.dot(-pressure * n, w) * ds(c_tag)
after = before
for tr in case.get("traction", []):
    term = ufl.dot(fem.Constant(mesh, np.asarray(tr["t"], dtype=float)), w) * ds(tag[tr["group"]])
    after = after + term
    if tr.get("history", "constant") == "constant":
        before = before + term
tau = ufl.as_vector((-n[1], n[0]))

# Friction nodes: w_J g τ_J from the Gauss–Lobatto rule, per DOF node.
wgt = fem.assemble_vector(fem.form(g * ufl.dot(tau, w) * ds_gll(c_tag))).array.reshape(-1, 2)
wgt.reshape(-1)[held] = 0.0  # a held component carries no friction
wg_all = np.hypot(wgt[:, 0], wgt[:, 1])
contact = np.nonzero(wg_all > 1e-14 * wg_all.max())[0]
wg = wg_all[contact]
tx, ty = wgt[contact, 0] / wg, wgt[contact, 1] / wg
ix, iy = 2 * contact, 2 * contact + 1


def phi_np(x):
    return np.clip(x / eps, -1.0, 1.0)


def classify(x):
    return np.where(x > eps, 1, np.where(x < -eps, -1, 0))


def solve_linear(a, L, name):
    problem = dolfinx.fem.petsc.LinearProblem(
        a, L, bcs=bcs, petsc_options_prefix=name,
        petsc_options={"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"})
    return problem.solve()


u_trial = ufl.TrialFunction(V)
k_form = ufl.inner(sigma(u_trial), ufl.sym(ufl.grad(w))) * ufl.dx
m_form = rho * ufl.dot(u_trial, w) * ufl.dx
explicit = sc.scheme == "central_difference"
if not explicit and sc.scheme != "newmark":
    peer_case.refuse(f"time.scheme = {sc.scheme!r}: the peer knows central_difference and newmark")
beta, gamma = (0.0, 0.5) if explicit else (sc.beta, sc.gamma)
dt = sc.dt

# Remark 4.1.
r = solve_linear(k_form, before, "static_")
r_now = fem.Function(V)
r_now.x.array[:] = r.x.array
v = fem.Function(V)
residual0 = after - ufl.inner(sigma(r_now), ufl.sym(ufl.grad(w))) * ufl.dx
if explicit:
    K = dolfinx.fem.petsc.assemble_matrix(fem.form(k_form))
    K.assemble()
    lumped = fem.assemble_vector(fem.form(rho * ufl.dot(fem.Constant(mesh, (1.0, 1.0)), w) * ufl.dx)).array
    load = fem.assemble_vector(fem.form(after)).array
    a = fem.Function(V)
    a.x.array[:] = fem.assemble_vector(fem.form(residual0)).array / lumped
    a.x.array[held] = 0.0
else:
    a = solve_linear(m_form, residual0, "mass_")

out = peer_case.Results(args.output, sc, nodes=V.tabulate_dof_coordinates()[:n_nodes, :2], contact=contact)


def write(t):
    vt = tx * v.x.array[ix] + ty * v.x.array[iy]
    out.write(t, *(f.x.array[: 2 * n_nodes].reshape(-1, 2) for f in (r, v, a)), -g * phi_np(vt), classify(vt))


write(0.0)
records = set(sc.record_steps())

if explicit:
    ku = K.createVecLeft()
    mass = lumped
    dmass = mass / (gamma * dt)
    q = tx * tx / dmass[ix] + ty * ty / dmass[iy]
    c = wg * q
    for k in range(1, sc.steps + 1):
        R, Vv, A = r.x.array, v.x.array, a.x.array
        R += dt * Vv + (0.5 * dt * dt) * A
        K.mult(r.x.petsc_vec, ku)
        b = load - ku.array + mass * ((1.0 / (gamma * dt)) * Vv + (1.0 / gamma - 1.0) * A)
        v_new = b / dmass
        p = tx * v_new[ix] + ty * v_new[iy]
        stuck = p / (1.0 + c / eps)
        vt = np.where(np.abs(stuck) <= eps, stuck, p - c * np.sign(p))
        f = wg * phi_np(vt)
        v_new[ix] -= f * tx / dmass[ix]
        v_new[iy] -= f * ty / dmass[iy]
        v_new[held] = 0.0
        A[:] = (v_new - Vv) / (gamma * dt) - ((1.0 - gamma) / gamma) * A
        Vv[:] = v_new
        if k in records:
            write(k * dt)
else:
    # The step's unknown is the new velocity (METHOD.md §4).
    v_old, a_old, r_pred = fem.Function(V), fem.Function(V), fem.Function(V)
    r_new = r_pred + (beta / gamma) * dt * v
    a_new = (v - v_old) / (gamma * dt) - ((1.0 - gamma) / gamma) * a_old
    vt_u = ufl.dot(v, tau)
    phi = ufl.conditional(ufl.le(abs(vt_u), eps), vt_u / eps, ufl.sign(vt_u))
    F = (rho * ufl.dot(a_new, w) * ufl.dx + ufl.inner(sigma(r_new), ufl.sym(ufl.grad(w))) * ufl.dx
         + g * phi * ufl.dot(tau, w) * ds_gll(c_tag) - after)
    problem = dolfinx.fem.petsc.NonlinearProblem(
        F, v, bcs=bcs, petsc_options_prefix="newmark_",
        petsc_options={"snes_type": "newtonls", "snes_linesearch_type": "basic",
                       "snes_rtol": 1e-11, "snes_atol": 1e-10, "snes_stol": 1e-14, "snes_max_it": 100,
                       "ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"})
    snes = problem.solver

    def remark_4_2(x, y):
        """Newton proposes x − y; a node it takes from slipping one way to
        slipping the other is set stuck (v_T = 0) instead."""
        xs, ys = x.array_r, y.array
        now = classify(tx * xs[ix] + ty * xs[iy])
        vx, vy = xs[ix] - ys[ix], xs[iy] - ys[iy]
        then = classify(tx * vx + ty * vy)
        flip = now * then == -1
        if flip.any():
            vt = tx[flip] * vx[flip] + ty[flip] * vy[flip]
            ys[ix[flip]] += vt * tx[flip]
            ys[iy[flip]] += vt * ty[flip]

    snes.setLineSearchPreCheck(remark_4_2)
    for k in range(1, sc.steps + 1):
        v_old.x.array[:] = v.x.array
        a_old.x.array[:] = a.x.array
        r_pred.x.array[:] = r.x.array + dt * (1.0 - beta / gamma) * v.x.array \
            + 0.5 * dt * dt * (1.0 - 2.0 * beta / gamma) * a.x.array
        problem.solve()
        if snes.getConvergedReason() <= 0:
            peer_case.refuse(f"Newton did not converge at step {k} ({snes.getConvergedReason()})")
        v.x.scatter_forward()
        r.x.array[:] = r_pred.x.array + (beta / gamma) * dt * v.x.array
        a.x.array[:] = (v.x.array - v_old.x.array) / (gamma * dt) - ((1.0 - gamma) / gamma) * a_old.x.array
        if k in records:
            write(k * dt)
out.close()
