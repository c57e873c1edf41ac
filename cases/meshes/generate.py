#!/usr/bin/env python3
"""Regenerates the committed meshes in cases/meshes/ with Gmsh (PyPI `gmsh`).

    python3 cases/meshes/generate.py            # all committed meshes
    cargo xtask meshes                          # same, installs gmsh if missing

    python3 cases/meshes/generate.py --bench-out DIR --nx 1000 --ny 999
        # the ~1M-node Q1 slab of `cargo xtask bench mesh`, written to DIR
        # as MSH 4.1 ASCII and binary (not committed)
    python3 cases/meshes/generate.py --bench-out DIR --order 2 --nx 352 --ny 88
        # a Q2 slab as Gmsh numbers and places its nodes (not snapped)

Runs headless. The output is deterministic: one thread, fresh Gmsh state per
mesh, and on the transfinite slab every node is snapped to its exact grid
point (i * L / n, j * H / m), so rerunning gives the same bytes.
Prints one line per file written: name, nodes, cells, cell type.
"""

import argparse
import os
import sys

import gmsh

HERE = os.path.dirname(os.path.abspath(__file__))
CASES = os.path.dirname(HERE)
SLAB_GEO = os.path.join(CASES, "slab.geo")
HOLE_GEO = os.path.join(CASES, "hole.geo")

# Gmsh element types of the 2-D cells we accept (quad4, quad9).
QUAD_TYPES = {1: 3, 2: 10}


def committed_meshes():
    """(file name, .geo, order, parameters, MSH version) of every committed mesh."""
    out = []
    # The paper's mesh, 8 x 2 quad9 (85 nodes), also in MSH 2.2 for old readers.
    out.append(("slab-q2-8x2.msh", SLAB_GEO, 2, {"nx": 8, "ny": 2}, 4.1))
    out.append(("slab-q2-8x2-v22.msh", SLAB_GEO, 2, {"nx": 8, "ny": 2}, 2.2))
    # Q1 on the same 17 x 5 node grid.
    out.append(("slab-q1-16x4.msh", SLAB_GEO, 1, {"nx": 16, "ny": 4}, 4.1))
    # Refinement ladders (element size halved at each step).
    for nx, ny in [(16, 4), (32, 8), (64, 16)]:
        out.append((f"slab-q2-{nx}x{ny}.msh", SLAB_GEO, 2, {"nx": nx, "ny": ny}, 4.1))
    for nx, ny in [(32, 8), (64, 16), (128, 32)]:
        out.append((f"slab-q1-{nx}x{ny}.msh", SLAB_GEO, 1, {"nx": nx, "ny": ny}, 4.1))
    # Unstructured all-quad meshes: the slab, and a plate with a hole.
    for order in (1, 2):
        out.append((f"slab-unstructured-q{order}.msh", SLAB_GEO, order,
                    {"nx": 32, "ny": 4, "structured": 0}, 4.1))
    for order in (1, 2):
        out.append((f"hole-q{order}.msh", HOLE_GEO, order, {}, 4.1))
    return out


def snap_to_grid(params, order):
    """Moves every node of the transfinite slab onto its exact grid point.

    Gmsh's transfinite interpolation gives e.g. 1.999999999995288 for 2; the
    grid point is known exactly, so it is restored (i * L / n rounds once).
    """
    length, height = params.get("L", 8.0), params.get("H", 1.0)
    n = order * params["nx"]
    m = order * params["ny"]
    tags, coords, _ = gmsh.model.mesh.getNodes()
    for k, tag in enumerate(tags):
        x, y = coords[3 * k], coords[3 * k + 1]
        i = round(x * n / length)
        j = round(y * m / height)
        xs, ys = i * length / n, j * height / m
        # A node far from a grid point means the mesh is not the grid we think.
        if abs(xs - x) > 1e-9 * length or abs(ys - y) > 1e-9 * height:
            raise SystemExit(f"node {tag} at ({x!r}, {y!r}) is not on the {n}x{m} grid")
        gmsh.model.mesh.setNode(int(tag), [xs, ys, 0.0], [])


def make_mesh(geo, order, params, snap):
    """Fresh Gmsh state (options set by a previous .geo do not leak), then mesh."""
    argv = ["gmsh", "-nopopup"]
    for name, value in params.items():
        argv += ["-setnumber", name, str(value)]
    gmsh.initialize(argv, readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.open(geo)
    gmsh.model.mesh.generate(2)
    gmsh.model.mesh.setOrder(order)
    if snap:
        snap_to_grid(params, order)
    # Every 2-D cell must be a quad of the requested order.
    types, tags, _ = gmsh.model.mesh.getElements(2)
    counts = {int(t): len(ts) for t, ts in zip(types, tags)}
    if set(counts) != {QUAD_TYPES[order]}:
        names = {t: gmsh.model.mesh.getElementProperties(t)[0] for t in counts}
        raise SystemExit(f"{geo} order {order}: expected only Gmsh type {QUAD_TYPES[order]} cells, got {names} {counts}")
    # Nodes written = nodes of the cells (getNodes() would also count
    # geometry points that no cell uses, e.g. the hole's centre).
    nodes = len(set(int(n) for n in gmsh.model.mesh.getElements(2)[2][0]))
    return nodes, counts[QUAD_TYPES[order]]


def write(path, version, binary):
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", 1 if binary else 0)
    gmsh.write(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=HERE, help="output directory (default: cases/meshes)")
    ap.add_argument("--bench-out", help="write only the benchmark slab (Q1, MSH 4.1 ASCII + binary) here")
    ap.add_argument("--nx", type=int, default=1000, help="benchmark slab divisions along x")
    ap.add_argument("--ny", type=int, default=999, help="benchmark slab divisions along y")
    ap.add_argument("--order", type=int, default=1, choices=(1, 2), help="benchmark slab cell order (1: quad4, 2: quad9)")
    args = ap.parse_args()

    if args.bench_out:
        os.makedirs(args.bench_out, exist_ok=True)
        # Gmsh's own coordinates, not snapped: this is what a user's file looks like.
        nodes, cells = make_mesh(SLAB_GEO, args.order, {"nx": args.nx, "ny": args.ny}, snap=False)
        stem = f"slab-q{args.order}-{args.nx}x{args.ny}"
        kind = "quad4" if args.order == 1 else "quad9"
        for suffix, binary in (("ascii", False), ("bin", True)):
            path = os.path.join(args.bench_out, f"{stem}-{suffix}.msh")
            write(path, 4.1, binary)
            print(f"{path}  nodes {nodes}  cells {cells} {kind}  bytes {os.path.getsize(path)}")
        gmsh.finalize()
        return

    os.makedirs(args.out, exist_ok=True)
    for name, geo, order, params, version in committed_meshes():
        structured = geo == SLAB_GEO and params.get("structured", 1) == 1
        nodes, cells = make_mesh(geo, order, params, snap=structured)
        path = os.path.join(args.out, name)
        write(path, version, binary=False)
        gmsh.finalize()
        kind = "quad4" if order == 1 else "quad9"
        print(f"{os.path.relpath(path)}  MSH {version} ASCII  nodes {nodes}  cells {cells} {kind}")


if __name__ == "__main__":
    sys.exit(main())
