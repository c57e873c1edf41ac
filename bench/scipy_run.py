"""The numpy/scipy peer of `cargo xtask bench run`: a whole run of the
paper's scene as a careful numpy/scipy user would write it, so that the
whole process is timed as stickslip's is (start-up, imports, mesh,
assembly, initial state, steps, results file).

    python3 bench/scipy_run.py CASE.toml -o OUT.h5 [--set KEY=VALUE]...

It reads what a user has: the case file and the Gmsh mesh it names
(`peer_case.py`: meshio, the boundary reduced to nodes by nodal
quadrature, the results file by h5py). K and M are scikit-fem's
(`ElementQuad1`/`ElementQuad2`, 2×2 and 3×3 Gauss points as stickslip's,
plane-strain Lamé parameters), the lumped mass HRZ's, element by element
(METHOD.md §3). The scheme and its steps are those of `bench/peer.py`
(METHOD.md §4-5):

* Central difference (β = 0, γ = ½, lumped mass): one `K @ r` per step,
  vectorized numpy, the nodal friction in closed form (t + c φ_ε(t) = p
  per node).
* Newmark (β, γ, consistent mass): `splu` of A₀ = (β/γ)Δt K + M/(γΔt)
  once, S = P A₀⁻¹ Pᵀ on the friction nodes once; per step one solve,
  the stick/slip iteration of §5 with Remark 4.2 on the nodes (dense
  numpy), a second solve.
* The initial state of Remark 4.1: `splu` of K for r₀ under R(0⁻), r̈₀
  from M r̈₀ = R(0) − K r₀ with the scheme's mass.
* The energy ledger as stickslip writes it (docs/results.md, METHOD.md
  §6), at the records: `/energy/kinetic` ½ṙᵀMṙ (the scheme's mass),
  `strain` ½rᵀKr, `external_work` Σ ½(R_K + R_{K−1})·(r_K − r_{K−1})
  (R_0 = R(0)), `dissipated` Σ_J ½(f_J,K + f_J,K−1) τ_J·½Δt(ṙ_K + ṙ_{K−1})
  with f_J = w_J g φ_ε(v_TJ), `total` kinetic + strain − rᵀR(t).

It checks nothing itself: `cargo xtask bench run` compares its results
file with stickslip's (`bench/peer_check.py`, displacements to 1e-8)
before it times it, and crates/cli/tests/peer_agreement.rs compares the
paper's cases field by field (displacement, velocity, acceleration,
friction stress, states, energies) at round-off.
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree
from skfem import Basis, BilinearForm, ElementQuad1, ElementQuad2, ElementVector, MeshQuad, MeshQuad2, asm
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

import peer_case

args = peer_case.arguments("numpy/scipy peer: one whole run of the paper's scene")
case = peer_case.load_case(args.case, args.sets)
sc = peer_case.Scene(case)
nodes, n_nodes = sc.nodes, len(sc.nodes)


def assemble():
    """K, M, the HRZ lumped mass, in DOFs 2·node + component."""
    used, local = np.unique(sc.cells[:, :4], return_inverse=True)
    mesh = MeshQuad(np.ascontiguousarray(nodes[used].T), np.ascontiguousarray(local.reshape(-1, 4).T))
    q2 = sc.order == 2
    if q2:
        mesh = MeshQuad2.from_mesh(mesh)
    scalar = ElementQuad2() if q2 else ElementQuad1()
    intorder = 4 if q2 else 2
    basis = Basis(mesh, ElementVector(scalar), intorder=intorder)
    lam, mu = lame_parameters(sc.young, sc.poisson)  # plane strain
    rho = sc.rho
    K = asm(linear_elasticity(lam, mu), basis).tocsr()
    M = asm(BilinearForm(lambda u, v, w: rho * dot(u, v)), basis).tocsr()
    # HRZ per element: its consistent diagonal scaled to its mass.
    sb = Basis(mesh, scalar, intorder=intorder)
    diag = np.stack([rho * np.sum(sb.basis[i][0].value ** 2 * sb.dx, 1) for i in range(sb.Nbfun)])
    share = diag * (rho * sb.dx.sum(1)) / diag.sum(0)
    lumped_scalar = np.zeros(sb.N)
    np.add.at(lumped_scalar, sb.element_dofs.ravel(), share.ravel())
    # scikit-fem's DOFs to 2·node + component, by location.
    tree = cKDTree(nodes)
    to_node = np.empty(basis.N, dtype=np.int64)
    for c, idx in enumerate(basis.split_indices()):
        dist, node = tree.query(basis.doflocs[:, idx].T)
        if dist.max() > 1e-9 * np.ptp(nodes, axis=0).max():
            peer_case.refuse("a scikit-fem DOF is at no mesh node")
        to_node[idx] = 2 * node + c
    dist, node = tree.query(sb.doflocs.T)
    lumped = np.zeros(2 * n_nodes)
    lumped[2 * node] = lumped_scalar
    lumped[2 * node + 1] = lumped_scalar
    order = np.empty(basis.N, dtype=np.int64)
    order[to_node] = np.arange(basis.N)
    return K, M, lumped, order


Kfull, Mfull, lumped_full, order = assemble()
free = np.nonzero(~sc.fixed.ravel())[0]
n = len(free)
sk = order[free]  # scikit-fem's index of each free DOF
K = sp.csr_matrix(Kfull[sk][:, sk])
explicit = sc.scheme == "central_difference"
if not explicit and sc.scheme != "newmark":
    peer_case.refuse(f"time.scheme = {sc.scheme!r}: the peer knows central_difference and newmark")
M = None if explicit else sp.csr_matrix(Mfull[sk][:, sk])
mass = lumped_full[free]
del Kfull, Mfull
load_before = sc.load_before.ravel()[free]
load_after = sc.load_after.ravel()[free]
dt, eps = sc.dt, sc.eps
beta, gamma = (0.0, 0.5) if explicit else (sc.beta, sc.gamma)

# Friction nodes: their free DOFs (−1: held), tangent, w·g.
index = -np.ones(2 * n_nodes, dtype=np.int64)
index[free] = np.arange(n)
dx, dy = index[2 * sc.contact], index[2 * sc.contact + 1]
tx = np.where(dx >= 0, sc.tangent[:, 0], 0.0)
ty = np.where(dy >= 0, sc.tangent[:, 1], 0.0)
ix, iy = np.maximum(dx, 0), np.maximum(dy, 0)
mx, my = dx >= 0, dy >= 0
dxm, dym = dx[mx], dy[my]
wg = sc.wg
g = float(case["contact"]["mu"]) * float(case["contact"]["pressure"])
n_c = len(wg)


def phi(x):
    return np.clip(x / eps, -1.0, 1.0)


def classify(u):
    return np.where(u > eps, 1, np.where(u < -eps, -1, 0))


# Remark 4.1: r₀ static under R(0⁻), ṙ₀ = 0, M r̈₀ = R(0) − K r₀.
r = spla.splu(K.tocsc()).solve(load_before) if load_before.any() else np.zeros(n)
v = np.zeros(n)
rhs0 = load_after - K @ r
a = rhs0 / mass if explicit else spla.splu(M.tocsc()).solve(rhs0)


def cd_step(r, v, a, load):
    """One central-difference step with the closed-form nodal friction."""
    r_new = r + dt * v + (0.5 * dt * dt) * a
    kr = K @ r_new
    b = load - kr + mass * ((1.0 / (gamma * dt)) * v + (1.0 / gamma - 1.0) * a)
    dmass = mass * (1.0 / (gamma * dt))
    v_new = b / dmass
    # Per node: t + w g q φ_ε(t) = p, p = τᵀD⁻¹b, q = τᵀD⁻¹τ (closed form).
    p = tx * b[ix] / dmass[ix] + ty * b[iy] / dmass[iy]
    c = wg * (tx * tx / dmass[ix] + ty * ty / dmass[iy])
    stuck = p / (1.0 + c / eps)
    vt = np.where(np.abs(stuck) <= eps, stuck, p - c * np.sign(p))
    f = wg * phi(vt)
    v_new[dxm] = (b[dxm] - f[mx] * tx[mx]) / dmass[dxm]
    v_new[dym] = (b[dym] - f[my] * ty[my]) / dmass[dym]
    return r_new, v_new, kr


if not explicit:
    A0 = ((beta / gamma) * dt) * K + (1.0 / (gamma * dt)) * M
    lu = spla.splu(A0.tocsc())
    # Pᵀ: column J is τ_J on node J's free DOFs; S = P A₀⁻¹ Pᵀ (symmetrized).
    rows = np.concatenate([dx[mx], dy[my]])
    cols = np.concatenate([np.nonzero(mx)[0], np.nonzero(my)[0]])
    PT = sp.csc_matrix((np.concatenate([tx[mx], ty[my]]), (rows, cols)), shape=(n, n_c))
    S = np.empty((n_c, n_c))
    for j0 in range(0, n_c, 64):
        j1 = min(n_c, j0 + 64)
        S[:, j0:j1] = PT.T @ lu.solve(PT[:, j0:j1].toarray())
    S = 0.5 * (S + S.T)


def nodal_solve(p, classes):
    """f for the classes and u = p − S f (stuck nodes: f = (w g/ε) u)."""
    f = np.where(classes != 0, wg * classes, 0.0)
    st = np.nonzero(classes == 0)[0]
    if len(st):
        w = np.sqrt(wg[st] / eps)
        A = np.eye(len(st)) + (w[:, None] * S[np.ix_(st, st)]) * w[None, :]
        f[st] = w * np.linalg.solve(A, w * (p[st] - S[st] @ f))
    return f, p - S @ f


def newmark_step(r, v, a, load, classes):
    """One Newmark step: a solve, the §5 iteration on the nodes, a second solve."""
    r_new = r + (dt * (1.0 - beta / gamma)) * v + (0.5 * dt * dt * (1.0 - 2.0 * beta / gamma)) * a
    b = load - K @ r_new + M @ ((1.0 / (gamma * dt)) * v + (1.0 / gamma - 1.0) * a)
    v0 = lu.solve(b)
    p = tx * v0[ix] + ty * v0[iy]
    for _ in range(100):
        f, u = nodal_solve(p, classes)
        new = classify(u)
        new = np.where(classes * new == -1, 0, new)  # Remark 4.2
        if (new == classes).all():
            break
        classes = new
    else:
        peer_case.refuse("the stick/slip iteration did not converge")
    np.subtract.at(b, dxm, f[mx] * tx[mx])
    np.subtract.at(b, dym, f[my] * ty[my])
    v_new = lu.solve(b)
    return r_new + ((beta / gamma) * dt) * v_new, v_new, classes


out = peer_case.Results(args.output, sc)
full = np.zeros(2 * n_nodes)
ledger = {k: np.zeros(out.n_out) for k in ("kinetic", "strain", "external_work", "dissipated", "total")}
work = dissipated = 0.0


def write(t, r, v, a, kr):
    """One record: the fields, the contact's, the ledger (`kr` = K r)."""
    mv = mass * v if explicit else M @ v
    e = {"kinetic": 0.5 * (v @ mv), "strain": 0.5 * (r @ kr), "external_work": work, "dissipated": dissipated}
    e["total"] = e["kinetic"] + e["strain"] - r @ load_after
    for key, x in e.items():
        ledger[key][out.k] = x
    fields = []
    for x in (r, v, a):
        full[free] = x
        fields.append(full.reshape(-1, 2).copy())
    vt = tx * v[ix] + ty * v[iy]
    out.write(t, *fields, -g * phi(vt), classify(vt))


records = set(sc.record_steps())
vt = tx * v[ix] + ty * v[iy]
classes = classify(vt)
forces = wg * phi(vt)
write(0.0, r, v, a, K @ r)
for k in range(1, sc.steps + 1):
    if explicit:
        r_new, v_new, kr = cd_step(r, v, a, load_after)
    else:
        r_new, v_new, classes = newmark_step(r, v, a, load_after, classes)
        kr = None
    a = (v_new - v) / (gamma * dt) - ((1.0 - gamma) / gamma) * a
    # The ledger's increments: R(t) = R(0) from t = 0 on (step and constant
    # histories), friction's trapezoid on the nodes' tangential motion.
    work += load_after @ (r_new - r)
    vt_new = tx * v_new[ix] + ty * v_new[iy]
    forces_new = wg * phi(vt_new)
    dissipated += (0.5 * (forces_new + forces)) @ ((0.5 * dt) * (vt_new + vt))
    r, v, vt, forces = r_new, v_new, vt_new, forces_new
    if k in records:
        if not (np.isfinite(r).all() and np.isfinite(v).all()):
            peer_case.refuse(f"state not finite at step {k}")
        write(k * dt, r, v, a, K @ r if kr is None else kr)
for key, x in ledger.items():
    out.file[f"energy/{key}"] = x
out.close()
