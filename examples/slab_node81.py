"""The paper's slab, read back with h5py: node 81's horizontal displacement
and friction stress (Martins & Oden 1983, Figs. 6 and 8).

    cargo xtask demo                      # writes target/demo/slab.h5
    python3 examples/slab_node81.py target/demo/slab.h5 [--png node81.png]

Node 81 in the paper's numbering is the bottom-right corner (8, 0)
(BENCHMARK.md); Gmsh numbers nodes its own way, so we find it by coordinate.
"""
import argparse

import h5py
import numpy as np

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("results", help="an HDF5 file written by `stickslip run`")
parser.add_argument("--png", help="also plot to this PNG (needs matplotlib)")
args = parser.parse_args()

with h5py.File(args.results, "r") as f:
    nodes = f["mesh/nodes"][:]
    n81 = int(np.argmin(np.hypot(nodes[:, 0] - 8.0, nodes[:, 1] - 0.0)))
    t = f["time"][:]                           # every step: time, energy/*, contact/*
    ux = f["displacement"][:, n81, 0]          # at frames; total displacement, includes the static state
    # Frame k is the step of row rows[k] of time (files before the frames:
    # a frame every row).
    rows = f["frames/row"][:] if "frames" in f else np.arange(len(t))
    contact = list(f["contact/nodes"][:])
    stress = f["contact/friction_stress"][:, contact.index(n81)]
    state = f["contact/state"][:, contact.index(n81)]
    energy = f["energy/total"][:]
    complete = bool(f.attrs["complete"])

x, y = (float(v) for v in nodes[n81])
print(f"node 81 = mesh node {n81} at ({x:g}, {y:g}); run complete: {complete}")
print(f"{'t':>8} {'u_x':>10} {'sigma_T':>9} {'state':>6} {'E_total':>10}")
for k in np.linspace(0, len(rows) - 1, 11).astype(int):
    r = rows[k]
    print(f"{t[r]:8.3f} {ux[k]:10.5f} {stress[r]:9.3f} {state[r]:6d} {energy[r]:10.3f}")

if args.png:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(2, 1, sharex=True, figsize=(6, 5))
    a.plot(t[rows], ux)
    a.set_ylabel("u_x at node 81")
    b.plot(t, stress)
    b.set_ylabel("friction stress at node 81")
    b.set_xlabel("t")
    fig.tight_layout()
    fig.savefig(args.png, dpi=120)
    print(f"wrote {args.png}")
