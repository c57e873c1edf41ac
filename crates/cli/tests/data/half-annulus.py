"""Writes half-annulus-q2.msh: a Q2 half-annulus (radii 1 and 2) meshed
with Gmsh's defaults and its quads recombined (Blossom, Gmsh's default
recombination), which leaves one nearly degenerate cell at the outer arc
(det J at a node 8.4e-4 of its largest in the cell, Gmsh 4.15.2). For
crates/cli/tests/warnings.rs: python3 half-annulus.py half-annulus-q2.msh
"""
import sys

import gmsh

lc, alg, out = 0.6, 1, sys.argv[1]
gmsh.initialize(); gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("half-annulus")
g = gmsh.model.geo
c = g.addPoint(0, 0, 0)
p = [g.addPoint(x, y, 0, lc) for x, y in [(1, 0), (2, 0), (0, 2), (-2, 0), (-1, 0), (0, 1)]]
bottom_r = g.addLine(p[0], p[1])
outer = [g.addCircleArc(p[1], c, p[2]), g.addCircleArc(p[2], c, p[3])]
bottom_l = g.addLine(p[3], p[4])
inner = [g.addCircleArc(p[4], c, p[5]), g.addCircleArc(p[5], c, p[0])]
loop = g.addCurveLoop([bottom_r] + outer + [bottom_l] + inner)
s = g.addPlaneSurface([loop])
g.synchronize()
gmsh.model.addPhysicalGroup(2, [s], name="body")
gmsh.model.addPhysicalGroup(1, inner, name="contact")
gmsh.model.addPhysicalGroup(1, [bottom_r, bottom_l], name="support")
gmsh.option.setNumber("Mesh.RecombineAll", 1)
gmsh.option.setNumber("Mesh.RecombinationAlgorithm", alg)
gmsh.model.mesh.generate(2)
gmsh.model.mesh.setOrder(2)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.write(out)
gmsh.finalize()
