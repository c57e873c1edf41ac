"""Peer figures for `cargo xtask bench fem`: scikit-fem's assembly of the
same Q2 (or Q1) slab stiffness K, and scipy's SuperLU (`splu`) on the very
matrix stickslip assembled (read from the raw arrays its bench example
dumps). Prints one `RESULT k=v ...` line.

    python3 bench/fem_peer.py --refine R [--q1] [--dump DIR] [--no-splu]
"""
import argparse
import resource
import time

import numpy as np
import scipy
import scipy.sparse as sp
import scipy.sparse.linalg as spla
import skfem
from skfem import Basis, ElementQuad1, ElementQuad2, ElementVector, MeshQuad, MeshQuad2, asm
from skfem.models.elasticity import lame_parameters, linear_elasticity

p = argparse.ArgumentParser()
p.add_argument("--refine", type=int, required=True)
p.add_argument("--q1", action="store_true")
p.add_argument("--dump")
p.add_argument("--no-splu", action="store_true")
a = p.parse_args()

nx, ny = (16, 4) if a.q1 else (8, 2)
m = MeshQuad.init_tensor(np.linspace(0, 8, nx * a.refine + 1), np.linspace(0, 1, ny * a.refine + 1))
if not a.q1:
    m = MeshQuad2.from_mesh(m)
elem = ElementVector(ElementQuad1() if a.q1 else ElementQuad2())
# Same rule as stickslip: 2x2 Gauss for Q1 (intorder 2), 3x3 for Q2 (intorder 4).
t = time.perf_counter()
basis = Basis(m, elem, intorder=2 if a.q1 else 4)
basis_s = time.perf_counter() - t
lam, mu = lame_parameters(1000.0, 0.3)  # plane strain Lame parameters
t = time.perf_counter()
K = asm(linear_elasticity(lam, mu), basis)
asm_s = time.perf_counter() - t

out = dict(skfem=skfem.__version__, scipy=scipy.__version__, skfem_dofs=K.shape[0], skfem_nnz=K.nnz,
           skfem_basis_s=f"{basis_s:.4f}", skfem_assembly_s=f"{asm_s:.4f}")
if a.dump and not a.no_splu:
    indptr = np.fromfile(f"{a.dump}/indptr.i64", dtype="<i8")
    indices = np.fromfile(f"{a.dump}/indices.i64", dtype="<i8")
    data = np.fromfile(f"{a.dump}/data.f64", dtype="<f8")
    rhs = np.fromfile(f"{a.dump}/rhs.f64", dtype="<f8")
    n = len(indptr) - 1
    A = sp.csc_matrix((data, indices, indptr), shape=(n, n))  # symmetric: CSR = CSC
    t = time.perf_counter()
    lu = spla.splu(A)  # SuperLU, default COLAMD ordering
    splu_s = time.perf_counter() - t
    t = time.perf_counter()
    x = lu.solve(rhs)
    solve_s = time.perf_counter() - t
    res = np.linalg.norm(A @ x - rhs) / np.linalg.norm(rhs)
    out.update(splu_factor_s=f"{splu_s:.4f}", splu_solve_s=f"{solve_s:.4f}", splu_lu_nnz=lu.L.nnz + lu.U.nnz,
               splu_residual=f"{res:.2e}")
out["peak_rss_mb"] = f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.1f}"
print("RESULT " + " ".join(f"{k}={v}" for k, v in out.items()))
