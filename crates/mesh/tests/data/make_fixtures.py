#!/usr/bin/env python3
"""Generates the .msh fixtures of the stickslip-mesh tests with Gmsh's Python
API (PyPI `gmsh`, tested with 4.15.2). Run once from this directory:

    python3 make_fixtures.py

The outputs are committed; the tests never call Gmsh. Every mesh is written
in the four encodings MSH 2.2 / 4.1 x ASCII / binary where the test needs it.
"""
import gmsh

ENC = [(2.2, 0, "v22_ascii"), (2.2, 1, "v22_bin"), (4.1, 0, "v41_ascii"), (4.1, 1, "v41_bin")]


def start(name):
    gmsh.clear()
    gmsh.model.add(name)
    for k, v in [("Mesh.SaveAll", 0), ("Mesh.SaveParametric", 0),
                 ("Mesh.SecondOrderIncomplete", 0), ("Mesh.Binary", 0)]:
        gmsh.option.setNumber(k, v)


def write(stem, encodings=ENC):
    for version, binary, suffix in encodings:
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.option.setNumber("Mesh.Binary", binary)
        gmsh.write(f"{stem}_{suffix}.msh")
    gmsh.option.setNumber("Mesh.Binary", 0)


def slab(order, incomplete=0):
    """A 4x2 transfinite quad mesh of a trapezoid (so cells are distorted),
    corners (0,0) (8,0) (8,1.5) (0,1). Groups: contact (1, bottom), unnamed 2
    (right), load (3, top), support (4, left), corner (5, point at origin),
    body (10, surface). Every element is in exactly one group, so Gmsh's 2.2
    element numbering equals its 4.1 numbering."""
    start("slab")
    g = gmsh.model.geo
    pts = [g.addPoint(x, y, 0) for x, y in [(0, 0), (8, 0), (8, 1.5), (0, 1)]]
    lines = [g.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)]
    surf = g.addPlaneSurface([g.addCurveLoop(lines)])
    for i, c in enumerate(lines):
        g.mesh.setTransfiniteCurve(c, 5 if i % 2 == 0 else 3)
    g.mesh.setTransfiniteSurface(surf)
    g.mesh.setRecombine(2, surf)
    g.synchronize()
    m = gmsh.model
    m.addPhysicalGroup(1, [lines[0]], 1, "contact")
    m.addPhysicalGroup(1, [lines[1]], 2)  # unnamed: the reader calls it "#2"
    m.addPhysicalGroup(1, [lines[2]], 3, "load")
    m.addPhysicalGroup(1, [lines[3]], 4, "support")
    m.addPhysicalGroup(0, [pts[0]], 5, "corner")
    m.addPhysicalGroup(2, [surf], 10, "body")
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", incomplete)
    m.mesh.generate(2)
    m.mesh.setOrder(order)


def hole(order, recombine=True):
    """A 4x2 plate with a circular hole (radius 0.5 at (2,1)), unstructured
    quads (Blossom recombination). Groups: outer (1: all four sides), hole
    (2: the circle), bottom (3) and contact (4) both on the bottom side (an
    element in two groups), body (10)."""
    start("hole")
    g = gmsh.model.geo
    h = 0.4
    pts = [g.addPoint(x, y, 0, h) for x, y in [(0, 0), (4, 0), (4, 2), (0, 2)]]
    sides = [g.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)]
    c = g.addPoint(2, 1, 0, h)
    q = [g.addPoint(2 + dx, 1 + dy, 0, h) for dx, dy in [(0.5, 0), (0, 0.5), (-0.5, 0), (0, -0.5)]]
    arcs = [g.addCircleArc(q[i], c, q[(i + 1) % 4]) for i in range(4)]
    surf = g.addPlaneSurface([g.addCurveLoop(sides), g.addCurveLoop(arcs)])
    if recombine:
        g.mesh.setRecombine(2, surf)
    g.synchronize()
    m = gmsh.model
    m.addPhysicalGroup(1, sides, 1, "outer")
    m.addPhysicalGroup(1, arcs, 2, "hole")
    m.addPhysicalGroup(1, [sides[0]], 3, "bottom")
    m.addPhysicalGroup(1, [sides[0]], 4, "contact")
    m.addPhysicalGroup(2, [surf], 10, "body")
    m.mesh.generate(2)
    m.mesh.setOrder(order)


gmsh.initialize(["-nopopup"])
gmsh.option.setNumber("General.Terminal", 0)

slab(1)
write("slab_q4")
slab(2)
write("slab_q9")

# Parametric node coordinates (u for curve nodes, u v for surface nodes).
gmsh.option.setNumber("Mesh.SaveParametric", 1)
write("slab_q9_param", [e for e in ENC if e[0] == 4.1])
gmsh.option.setNumber("Mesh.SaveParametric", 0)

# Non-contiguous node and element tags: tag t -> 3 t + 100 (nodes) and
# 5 t + 7 (elements); the mesh is otherwise slab_q4.
slab(1)
nt, _, _ = gmsh.model.mesh.getNodes()
gmsh.model.mesh.renumberNodes(list(nt), [3 * int(t) + 100 for t in nt])
et = [int(t) for ts in gmsh.model.mesh.getElements()[1] for t in ts]
gmsh.model.mesh.renumberElements(et, [5 * t + 7 for t in et])
write("slab_q4_gaps")

hole(1)
write("hole_q4")
hole(2)
write("hole_q9")

# Refused inputs: triangles, and incomplete quadratic quads (quad8).
hole(1, recombine=False)
write("hole_tri", [ENC[2]])
slab(2, incomplete=1)
write("slab_q8", [ENC[0]])

gmsh.finalize()
