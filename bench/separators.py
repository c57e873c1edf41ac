"""The fill of stickslip's nested dissection against METIS's, on a mesh.

    cargo run --release -p stickslip-fem --example dissection_nodes -- MESH ND.txt
    python3 bench/separators.py MESH ND.txt

Reads the mesh (meshio; quadrilateral cells, corners only: the Q1 node
graph, every two nodes of a cell coupled as in K) and stickslip's node
order (one node a line by its coordinates, matched to the mesh's nodes
exactly), orders the same graph by METIS's nested dissection (pymetis),
and prints for each order the exact symbolic fill of the node graph's
Cholesky factor: nnz(L) with the diagonal (Σ c_j, c_j the column counts),
the flop measure Σ c_j², the sizes of the separators at the top of
the elimination tree (single-child chains from the root, level by level),
their mean size at each of the first 14 levels, and Σ c_j² split by the
size of each column's subtree (where in the tree the flops lie).
A DOF-level factor has about 4 Σ c_j values (faer's supernodal layout
stores more: its relaxed supernodes' zeros).

It also prints the fewest nodes on a path of cell sides from the bottom
of the mesh to its top within bands of growing width around the median
x: a separator across the slab can be no smaller, and the band shows how
far from a straight cut the short separators lie.

Needs numpy, meshio and pymetis (pip install pymetis). Not part of the
test suite: a measurement for docs/performance.md.
"""

import sys
from collections import deque

import meshio
import numpy as np
import pymetis


def graph(path):
    m = meshio.read(path)
    quads = np.vstack([c.data[:, :4] for c in m.cells if c.type.startswith("quad")])
    used = np.unique(quads)
    remap = -np.ones(m.points.shape[0], dtype=np.int64)
    remap[used] = np.arange(len(used))
    q = remap[quads]
    n = len(used)
    pairs = np.vstack([np.stack([q[:, a], q[:, b]], 1) for a in range(4) for b in range(4) if a != b])
    pairs = np.unique(pairs, axis=0)
    xadj = np.zeros(n + 1, dtype=np.int64)
    np.add.at(xadj, pairs[:, 0] + 1, 1)
    return m.points[used, :2], q, np.cumsum(xadj), pairs[:, 1]


def columns(order, xadj, adj):
    """Column counts and elimination tree of the graph eliminated in `order`."""
    n = len(order)
    pos = np.empty(n, dtype=np.int64)
    pos[order] = np.arange(n)
    xa, ad, ps, od = xadj.tolist(), adj.tolist(), pos.tolist(), order.tolist()
    parent, ancestor, mark, count = [-1] * n, [-1] * n, [-1] * n, [1] * n
    for i in range(n):  # Liu's elimination tree, with path compression
        v = od[i]
        for e in range(xa[v], xa[v + 1]):
            j = ps[ad[e]]
            while j != -1 and j < i:
                up = ancestor[j]
                ancestor[j] = i
                if up == -1:
                    parent[j] = i
                j = up
    for i in range(n):  # row i's structure: its row subtree
        v = od[i]
        mark[i] = i
        for e in range(xa[v], xa[v + 1]):
            j = ps[ad[e]]
            if j < i:
                while mark[j] != i:
                    mark[j] = i
                    count[j] += 1
                    j = parent[j]
    return np.array(count, dtype=np.float64), parent


def subtree_sizes(parent):
    """Nodes in each column's elimination subtree (children come before
    their parent)."""
    size = np.ones(len(parent))
    for j, p in enumerate(parent):
        if p != -1:
            size[p] += size[j]
    return size


def levels(parent, count):
    """Per level of the tree, from the root, (separator size, subtree size)
    of each separator: a single-child chain from the level's roots."""
    children = [[] for _ in parent]
    roots = []
    for j, p in enumerate(parent):
        (children[p] if p != -1 else roots).append(j)
    size = subtree_sizes(parent)
    frontier, out = roots, []
    for _ in range(count):
        if not frontier:
            break
        level, below = [], []
        for r in frontier:
            s, v = 1, r
            while len(children[v]) == 1:
                v = children[v][0]
                s += 1
            level.append((s, size[r]))
            below.extend(children[v])
        out.append(level)
        frontier = below
    return out


def separators(parent, count=5):
    return [sorted((s for s, _ in level), reverse=True)[:8] for level in levels(parent, count)]


def separator_means(parent, count=14):
    """Per level: separators, their mean size, their subtrees' mean size."""
    return [
        (len(level), float(np.mean([s for s, _ in level])), float(np.mean([t for _, t in level])))
        for level in levels(parent, count)
    ]


def flops_by_subtree(c, parent, bounds=(64, 256, 1024, 4096, 16384, 65536)):
    """Σ c_j² of the columns whose elimination subtree has a number of
    nodes in each range: where in the tree an order's flops lie."""
    size = subtree_sizes(parent)
    edges = (0,) + tuple(bounds) + (np.inf,)
    return [((lo, hi), float((c[(size >= lo) & (size < hi)] ** 2).sum())) for lo, hi in zip(edges[:-1], edges[1:])]


def shortest_crossing(points, q, fractions):
    n = len(points)
    sides = np.unique(np.sort(np.vstack([np.stack([q[:, a], q[:, (a + 1) % 4]], 1) for a in range(4)]), 1), axis=0)
    near = [[] for _ in range(n)]
    for a, b in sides:
        near[a].append(b)
        near[b].append(a)
    x, y = points[:, 0], points[:, 1]
    mid, length = np.median(x), x.max() - x.min()
    for f in fractions:
        band = np.abs(x - mid) < f * length
        dist = np.full(n, -1)
        queue = deque()
        for s in np.flatnonzero(band & (y <= y.min())):
            dist[s] = 1
            queue.append(s)
        found = None
        while queue:
            v = queue.popleft()
            if y[v] >= y.max():
                found = dist[v]
                break
            for u in near[v]:
                if band[u] and dist[u] < 0:
                    dist[u] = dist[v] + 1
                    queue.append(u)
        print(f"  band ±{f:.4f} of the length: {found} nodes")


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: separators.py MESH ND_ORDER.txt")
    points, q, xadj, adj = graph(sys.argv[1])
    n = len(points)
    at = {(float(a), float(b)): i for i, (a, b) in enumerate(points)}
    xy = np.loadtxt(sys.argv[2], ndmin=2)
    ours = np.array([at[(float(a), float(b))] for a, b in xy], dtype=np.int64)
    if len(ours) != n or len(np.unique(ours)) != n:
        sys.exit("the order file does not list every node of the mesh once")
    metis, _ = pymetis.nested_dissection(pymetis.CSRAdjacency(xadj, adj))
    print(f"{sys.argv[1]}: {n} nodes")
    for name, order in [("stickslip", ours), ("METIS", np.asarray(metis, dtype=np.int64))]:
        c, parent = columns(order, xadj, adj)
        print(f"{name}: nnz(L) {int(c.sum())}, sum c^2 {(c * c).sum():.3e}")
        for level, sizes in enumerate(separators(parent)):
            print(f"  separators at level {level}: {sizes}")
        for level, (count, sep, sub) in enumerate(separator_means(parent)):
            print(f"  level {level}: {count} separators, mean {sep:.1f} nodes, mean subtree {sub:.0f}")
        for (lo, hi), flops in flops_by_subtree(c, parent):
            print(f"  sum c^2 of columns with subtrees of [{lo}, {hi}) nodes: {flops:.3e}")
    print("fewest nodes on a path of cell sides from bottom to top, near the median x:")
    shortest_crossing(points, q, [1e-3, 4e-3, 2e-2, 5e-2])


if __name__ == "__main__":
    main()
