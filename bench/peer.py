"""The scipy peer of `cargo xtask bench step` (issue 7): the same time steps
as stickslip's, written the way a careful numpy/scipy user would, on the
very problem stickslip set up (read from the raw arrays its bench example
dumps into DIR: K and M in CSR, lumped mass, loads, contact nodes, the
initial state of Remark 4.1 and stickslip's state after `check_steps`).

* Central difference (β = 0, γ = ½, lumped mass): one `K @ r` per step,
  vectorized numpy passes, the nodal friction in closed form (METHOD.md §4,
  the equation t + c φ_ε(t) = p per node), the energy sums stickslip's step
  also forms.
* Newmark (β = ¼, γ = ½, consistent mass): `splu` of A₀ = (β/γ)Δt K +
  M/(γΔt) once per Δt (outside the timed steps), S = P A₀⁻¹ Pᵀ once; per
  step one solve, the stick/slip iteration of METHOD.md §5 with Remark 4.2
  on the contact nodes' tangential velocities (dense numpy), and a second
  solve for the correction (a dense n × n_c Z would not fit at 250k DOFs).
  A careful user cannot refactorize per stuck set and keep `splu` once per
  Δt, so the Woodbury/Schur form is the scipy way to the same iteration.

K, M and the lumped mass are the peer's own: scikit-fem assembles them on
the dumped mesh (`ElementQuad1`/`ElementQuad2`, 2×2 and 3×3 Gauss points as
stickslip's, plane-strain Lamé parameters), its DOFs are matched to
stickslip's free DOFs by their locations, and each matrix must agree with
stickslip's to 1e-10 of its largest entry before it is used (else exit 1;
`peer_k_check`, `peer_m_check`). The lumped mass is HRZ's (the diagonal of
the consistent mass scaled to the total mass), which on the bench's meshes
of identical rectangular cells is the global diagonal scaled per
component. The loads, the contact nodes and the initial state are read
from the dump.

Before timing, the state after `check_steps` steps is compared with
stickslip's (max |Δ| / max |ours|, must be ≤ 1e-8, else exit 1). Prints
`PEER peer_step=… peer_check=… check_steps=… check_slipping=ours/peer
peer_setup=… peer_rss=… peer_k_check=… peer_m_check=… peer_lumped_check=…
peer_assembly=…` (peer_setup includes the assembly). (the most nodes slipping at once during the check
steps, so that the friction branches are seen to be exercised).

    python3 bench/peer.py DIR [--steps N] [--repeats R]
"""
import argparse
import json
import os
import resource
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

ap = argparse.ArgumentParser()
ap.add_argument("dir")
ap.add_argument("--steps", type=int, default=20)
ap.add_argument("--repeats", type=int, default=3)
args = ap.parse_args()

t_setup = time.perf_counter()
d = args.dir
meta = json.load(open(os.path.join(d, "meta.json")))
n, nnz = meta["n"], meta["nnz"]


def f64(name):
    return np.fromfile(os.path.join(d, name), dtype="<f8")


def i64(name):
    return np.fromfile(os.path.join(d, name), dtype="<i8")


def ours(name):
    """stickslip's matrix on K's pattern (values from `name`)."""
    a = sp.csr_matrix((f64(name), i64("indices.i64"), i64("indptr.i64")), shape=(n, n))
    a.sort_indices()
    return a


def assemble():
    """K, M and the lumped mass by scikit-fem, in stickslip's free-DOF order."""
    import skfem
    from scipy.spatial import cKDTree
    from skfem import (Basis, BilinearForm, ElementQuad1, ElementQuad2, ElementVector, MeshQuad,
                       MeshQuad2, asm)
    from skfem.helpers import dot
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    info = json.load(open(os.path.join(d, "mesh.json")))
    assert info["plane"] == "strain"
    nodes = f64("nodes.f64").reshape(-1, 2)
    corners = i64("cells.i64").reshape(-1, 4)
    free = i64("free.i64")
    used, local = np.unique(corners, return_inverse=True)
    mesh = MeshQuad(np.ascontiguousarray(nodes[used].T), np.ascontiguousarray(local.reshape(-1, 4).T))
    q2 = info["order"] == 2
    if q2:
        mesh = MeshQuad2.from_mesh(mesh)
    basis = Basis(mesh, ElementVector(ElementQuad2() if q2 else ElementQuad1()), intorder=4 if q2 else 2)
    lam, mu = lame_parameters(info["young"], info["poisson"])  # plane strain
    rho = info["density"]
    Kf = asm(linear_elasticity(lam, mu), basis).tocsr()
    Mf = asm(BilinearForm(lambda u, v, w: rho * dot(u, v)), basis).tocsr()
    # Each of scikit-fem's DOFs is stickslip's DOF 2·node + component of
    # the node at its location.
    extent = np.ptp(nodes, axis=0).max()
    tree = cKDTree(nodes)
    full = np.empty(basis.N, dtype=np.int64)
    lumped_full = np.empty(basis.N)
    diag = Mf.diagonal()
    for c, idx in enumerate(basis.split_indices()):
        dist, node = tree.query(basis.doflocs[:, idx].T)
        if dist.max() > 1e-9 * extent:
            sys.exit(f"peer: a scikit-fem DOF is {dist.max():.2e} from every node")
        full[idx] = 2 * node + c
        one = np.zeros(basis.N)
        one[idx] = 1.0
        lumped_full[idx] = diag[idx] * ((one @ (Mf @ one)) / diag[idx].sum())
    fr = free[full]
    keep = np.nonzero(fr >= 0)[0]
    if len(keep) != n or len(np.unique(fr[keep])) != n:
        sys.exit("peer: scikit-fem's DOFs do not match stickslip's free DOFs one to one")
    order = np.empty(n, dtype=np.int64)
    order[fr[keep]] = keep
    # scipy picks int32 indices when they fit, as a user's matrix would have.
    K = sp.csr_matrix(Kf[order][:, order])
    M = sp.csr_matrix(Mf[order][:, order])
    K.sort_indices()
    M.sort_indices()
    return K, M, lumped_full[order]


def agree(a, b):
    """max |a − b| / max |b| of two sparse matrices (0 when equal)."""
    return abs(a - b).max() / abs(b).max()


t_asm = time.perf_counter()
K, M, mass = assemble()
t_asm = time.perf_counter() - t_asm
k_check = agree(K, ours("k.f64"))
m_check = agree(M, ours("m.f64"))
lumped_check = np.abs(mass - f64("lumped.f64")).max() / np.abs(mass).max()
if max(k_check, m_check, lumped_check) > 1e-10:
    sys.exit(f"peer: scikit-fem's K, M, lumped M differ from stickslip's by {k_check:.2e}, "
             f"{m_check:.2e}, {lumped_check:.2e} (> 1e-10 of the largest entry)")
if meta["scheme"] != "newmark":
    del M
constant = f64("constant.f64")
loads = [f64(f"load{l}.f64") for l in range(len(meta["histories"]))]
histories = meta["histories"]
r, v, a = f64("r0.f64"), f64("v0.f64"), f64("a0.f64")
r_check, v_check = f64("r_check.f64"), f64("v_check.f64")
dt, beta, gamma, eps = meta["dt"], meta["beta"], meta["gamma"], meta["eps"]
assert len(mass) == n

# Contact nodes: free DOFs (−1 = fixed), tangent, w·g.
dx = np.array(meta["contact_dof_x"], dtype=np.int64)
dy = np.array(meta["contact_dof_y"], dtype=np.int64)
tx = np.array(meta["contact_tx"])
ty = np.array(meta["contact_ty"])
wg = np.array(meta["contact_wg"])
# A fixed component contributes nothing: zero tangent, any valid index.
tx = np.where(dx >= 0, tx, 0.0)
ty = np.where(dy >= 0, ty, 0.0)
ix = np.where(dx >= 0, dx, 0)
iy = np.where(dy >= 0, dy, 0)
n_c = len(wg)
mx, my = dx >= 0, dy >= 0
dxm, dym = dx[mx], dy[my]


def theta(h, t):
    # History::value for the bench's histories: constant and step are 1 at t ≥ 0.
    return 1.0


def load_at(t):
    out = constant.copy()
    for f, h in zip(loads, histories):
        th = theta(h, t)
        if th != 0.0:
            out += th * f
    return out


def phi(x):
    return np.clip(x / eps, -1.0, 1.0)


def classify(u):
    return np.where(u > eps, 1, np.where(u < -eps, -1, 0))


state = {"t": 0.0, "r": r, "v": v, "a": a, "load": load_at(0.0), "work": 0.0, "diss": 0.0}
state["forces"] = wg * phi(tx * v[ix] + ty * v[iy])


def cd_step(s):
    """One central-difference step with the closed-form nodal friction."""
    r, v, a = s["r"], s["v"], s["a"]
    t_new = s["t"] + dt
    load_new = load_at(t_new)
    r_new = r + dt * v + (0.5 * dt * dt) * a
    ku = K @ r_new
    strain = 0.5 * (r_new @ ku)
    scale = 1.0 / (gamma * dt)
    b = load_new - ku + mass * ((1.0 / (gamma * dt)) * v + (1.0 / gamma - 1.0) * a)
    dmass = mass * scale
    v_new = b / dmass
    # Per node: t + w g q φ_ε(t) = p, p = τᵀD⁻¹b, q = τᵀD⁻¹τ (closed form).
    p = tx * b[ix] / dmass[ix] + ty * b[iy] / dmass[iy]
    q = tx * tx / dmass[ix] + ty * ty / dmass[iy]
    c = wg * q
    stuck = p / (1.0 + c / eps)
    vt = np.where(np.abs(stuck) <= eps, stuck, p - c * np.sign(p))
    f = wg * phi(vt)
    v_new[dxm] = (b[dxm] - f[mx] * tx[mx]) / dmass[dxm]
    v_new[dym] = (b[dym] - f[my] * ty[my]) / dmass[dym]
    a_new = (v_new - v) / (gamma * dt) - ((1.0 - gamma) / gamma) * a
    work = 0.5 * ((load_new + s["load"]) @ (r_new - r))
    kinetic = 0.5 * (mass @ (v_new * v_new))
    load_dot = r_new @ load_new
    if not (np.isfinite(r_new).all() and np.isfinite(v_new).all()):
        sys.exit("peer: state not finite")
    forces = wg * phi(tx * v_new[ix] + ty * v_new[iy])
    inc = tx * (0.5 * dt * (v_new[ix] + v[ix])) + ty * (0.5 * dt * (v_new[iy] + v[iy]))
    s["diss"] += 0.5 * ((forces + s["forces"]) @ inc)
    s.update(t=t_new, r=r_new, v=v_new, a=a_new, load=load_new, forces=forces)
    s["work"] += work
    s["energy"] = (kinetic, strain, load_dot)


if meta["scheme"] == "newmark":
    A0 = ((beta / gamma) * dt) * K + (1.0 / (gamma * dt)) * M
    lu = spla.splu(A0.tocsc())
    # Pᵀ: column J is τ_J on node J's free DOFs; S = P A₀⁻¹ Pᵀ (symmetrized).
    rows = np.concatenate([dx[dx >= 0], dy[dy >= 0]])
    cols = np.concatenate([np.nonzero(dx >= 0)[0], np.nonzero(dy >= 0)[0]])
    vals = np.concatenate([tx[dx >= 0], ty[dy >= 0]])
    PT = sp.csc_matrix((vals, (rows, cols)), shape=(n, n_c))
    S = np.empty((n_c, n_c))
    for j0 in range(0, n_c, 64):
        j1 = min(n_c, j0 + 64)
        Zb = lu.solve(PT[:, j0:j1].toarray())
        S[:, j0:j1] = PT.T @ Zb
    S = 0.5 * (S + S.T)
    state["classes"] = classify(tx * v[ix] + ty * v[iy])
    max_iterations = 100


def nodal_solve(p, classes):
    """f for the classes and u = p − S f (stuck nodes: f = (w g/ε) u)."""
    f = np.where(classes != 0, wg * classes, 0.0)
    st = np.nonzero(classes == 0)[0]
    if len(st):
        w = np.sqrt(wg[st] / eps)
        rhs = w * (p[st] - S[st] @ f)
        A = np.eye(len(st)) + (w[:, None] * S[np.ix_(st, st)]) * w[None, :]
        f[st] = w * np.linalg.solve(A, rhs)
    return f, p - S @ f


def newmark_step(s):
    """One Newmark step: splu solve, §5 iteration on the nodes, second solve."""
    r, v, a = s["r"], s["v"], s["a"]
    t_new = s["t"] + dt
    load_new = load_at(t_new)
    c1 = dt * (1.0 - beta / gamma)
    c2 = 0.5 * dt * dt * (1.0 - 2.0 * beta / gamma)
    r_new = r + c1 * v + c2 * a
    b = load_new - K @ r_new + M @ ((1.0 / (gamma * dt)) * v + (1.0 / gamma - 1.0) * a)
    v0 = lu.solve(b)
    p = tx * v0[ix] + ty * v0[iy]
    classes = s["classes"].copy()
    for it in range(max_iterations):
        f, u = nodal_solve(p, classes)
        new = classify(u)
        new = np.where(classes * new == -1, 0, new)  # Remark 4.2
        if (new == classes).all():
            break
        classes = new
    else:
        sys.exit("peer: the stick/slip iteration did not converge")
    rhs = b.copy()
    np.subtract.at(rhs, dxm, f[mx] * tx[mx])
    np.subtract.at(rhs, dym, f[my] * ty[my])
    v_new = lu.solve(rhs)
    r_new += ((beta / gamma) * dt) * v_new
    if not (np.isfinite(r_new).all() and np.isfinite(v_new).all()):
        sys.exit("peer: state not finite")
    work = 0.5 * ((load_new + s["load"]) @ (r_new - r))
    forces = wg * phi(tx * v_new[ix] + ty * v_new[iy])
    inc = tx * (0.5 * dt * (v_new[ix] + v[ix])) + ty * (0.5 * dt * (v_new[iy] + v[iy]))
    s["diss"] += 0.5 * ((forces + s["forces"]) @ inc)
    a_new = (v_new - v) / (gamma * dt) - ((1.0 - gamma) / gamma) * a
    kinetic = 0.5 * (v_new @ (M @ v_new))
    strain = 0.5 * (r_new @ (K @ r_new))
    load_dot = r_new @ load_new
    s.update(t=t_new, r=r_new, v=v_new, a=a_new, load=load_new, forces=forces, classes=classes)
    s["work"] += work
    s["energy"] = (kinetic, strain, load_dot)


step = cd_step if meta["scheme"] == "cd" else newmark_step
setup = time.perf_counter() - t_setup

most = 0
for _ in range(meta["check_steps"]):
    step(state)
    vt = tx * state["v"][ix] + ty * state["v"][iy]
    most = max(most, int(np.count_nonzero(classify(vt))))


def rel(x, y):
    return float(np.max(np.abs(x - y)) / max(np.max(np.abs(y)), 1e-300))


check = max(rel(state["r"], r_check), rel(state["v"], v_check))
ours_slipping = json.load(open(os.path.join(d, "check.json")))["slipping"]

if not check <= 1e-8:
    print(f"PEER peer_check={check:.3e} peer=mismatch")
    sys.exit(f"peer: state after {meta['check_steps']} steps differs from stickslip's by {check:.3e} (> 1e-8)")

times = []
for _ in range(args.repeats):
    t = time.perf_counter()
    for _ in range(args.steps):
        step(state)
    times.append((time.perf_counter() - t) / args.steps)
times.sort()
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0
print(
    f"PEER peer_step={times[len(times) // 2]:.4e} peer_check={check:.3e} "
    f"check_steps={meta['check_steps']} check_slipping={ours_slipping}/{most} "
    f"peer_setup={setup:.3e} peer_steps={args.steps} peer_rss={rss:.0f} "
    f"peer_k_check={k_check:.1e} peer_m_check={m_check:.1e} peer_lumped_check={lumped_check:.1e} "
    f"peer_assembly={t_asm:.3e}"
)
