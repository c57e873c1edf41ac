"""Does a peer's results file agree with stickslip's? `cargo xtask bench run`
asks before it times the peer.

    python3 bench/peer_check.py OURS.h5 PEER.h5 [--tol 1e-8]

The peer's nodes are matched to stickslip's `/mesh/nodes` by location (to
1e-9 of the mesh's extent), its records to stickslip's by `/time` (to 1e-9
of a step). Over every record both files hold, the last record of each
included, max |u_peer − u_ours| / max |u_ours| of `/displacement` must be
at most the tolerance. Prints `PEERCHECK records=N max_rel=X` and exits 0
when it is, 1 (saying why) when it is not or the files cannot be matched.
"""
import argparse
import sys

import h5py
import numpy as np
from scipy.spatial import cKDTree

ap = argparse.ArgumentParser()
ap.add_argument("ours")
ap.add_argument("peer")
ap.add_argument("--tol", type=float, default=1e-8)
args = ap.parse_args()


def fail(msg):
    print(f"PEERCHECK failed: {msg}")
    sys.exit(1)


with h5py.File(args.ours, "r") as a, h5py.File(args.peer, "r") as b:
    nodes = a["mesh/nodes"][:]
    dist, node = cKDTree(b["mesh/nodes"][:]).query(nodes)
    if dist.max() > 1e-9 * np.ptp(nodes, axis=0).max():
        fail(f"a node of {args.ours} is {dist.max():.2e} from every node of {args.peer}")
    ta, tb = a["time"][:], b["time"][:]
    if len(ta) < 2 or len(tb) < 2:
        fail("fewer than two records")
    step = np.diff(ta).min() if len(ta) > 1 else 1.0
    j = np.searchsorted(tb, ta)
    pairs = [(i, k) for i, k in enumerate(j)
             for k in (k - 1, k) if 0 <= k < len(tb) and abs(tb[k] - ta[i]) <= 1e-9 * step]
    if not pairs or pairs[-1] != (len(ta) - 1, len(tb) - 1):
        fail(f"the last records differ in time ({ta[-1]:.12g} and {tb[-1]:.12g}) or none match")
    ua = a["displacement"]
    ub = b["displacement"]
    scale = worst = 0.0
    for i, k in pairs:
        x = ua[i]
        scale = max(scale, np.abs(x).max())
        worst = max(worst, np.abs(ub[k][node] - x).max())
    rel = worst / max(scale, 1e-300)
    print(f"PEERCHECK records={len(pairs)} max_rel={rel:.3e}")
    if not rel <= args.tol:
        fail(f"the displacements differ by {rel:.3e} of the largest (> {args.tol:g})")
