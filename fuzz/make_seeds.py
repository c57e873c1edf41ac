"""Tiny Gmsh meshes for the msh fuzz corpus (binary and ASCII, 2.2 and 4.1):
small seeds let libFuzzer mutate every section quickly. Run with the Python
gmsh package: python3 make_seeds.py (writes seeds/msh/tiny_*.msh)."""
import gmsh

gmsh.initialize()
gmsh.option.setNumber("General.Verbosity", 0)
for order in (1, 2):
    gmsh.clear()
    gmsh.model.add("tiny")
    s = gmsh.model.occ.addRectangle(0, 0, 0, 2, 1)
    gmsh.model.occ.synchronize()
    for c in gmsh.model.getEntities(1):
        gmsh.model.mesh.setTransfiniteCurve(c[1], 2)
    gmsh.model.mesh.setTransfiniteSurface(s)
    gmsh.model.mesh.setRecombine(2, s)
    curves = [c[1] for c in gmsh.model.getEntities(1)]
    gmsh.model.addPhysicalGroup(1, curves[:1], name="contact")
    gmsh.model.addPhysicalGroup(1, curves[2:3], name="support")
    gmsh.model.addPhysicalGroup(2, [s], name="body")
    gmsh.model.mesh.generate(2)
    gmsh.model.mesh.setOrder(order)
    for version in (2.2, 4.1):
        for binary in (0, 1):
            gmsh.option.setNumber("Mesh.MshFileVersion", version)
            gmsh.option.setNumber("Mesh.Binary", binary)
            kind = "bin" if binary else "ascii"
            gmsh.write(f"seeds/msh/tiny_q{4 if order == 1 else 9}_v{str(version).replace('.', '')}_{kind}.msh")
gmsh.finalize()
