"""The deformed mesh of a run, drawn with PyVista into a PNG, without a
display.

    cargo xtask demo                                  # writes target/demo/slab.h5
    stickslip views target/demo/slab.h5               # writes slab.xdmf for the viewers
    stickslip stress target/demo/slab.h5              # optional (writes slab.xdmf too): colour by von Mises
    python3 examples/warp_pyvista.py target/demo/slab.h5 --png slab.png [--time 0.25] [--scale 1]

PyVista reads `OUT.xdmf`, the file `stickslip views` (or `stickslip
stress`) writes beside OUT.h5 (keep OUT.h5, OUT.xdmf and OUT.views.h5
together), at the record nearest
`--time` (default: the last). Warp By Vector moves each node by its
displacement (times `--scale`), and the mesh is coloured by von Mises
where `stickslip stress` has run, else by |u|. The undeformed outline is
drawn too. Quadratic (Q2) cells are drawn by their corners.

    pip install pyvista
"""
import argparse
import pathlib

import numpy as np
import pyvista as pv

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("results", help="an HDF5 file written by `stickslip run`")
parser.add_argument("--png", required=True, help="the picture to write")
parser.add_argument("--time", type=float, help="the time to draw (default: the last record)")
parser.add_argument("--scale", type=float, default=1.0, help="displacement magnification (default 1)")
args = parser.parse_args()

xdmf = pathlib.Path(args.results).with_suffix(".xdmf")
if not xdmf.is_file():
    raise SystemExit(f"{xdmf} is missing: write it with `stickslip views {args.results}`")
reader = pv.get_reader(str(xdmf))
times = np.array(reader.time_values)
k = len(times) - 1 if args.time is None else int(np.argmin(np.abs(times - args.time)))
reader.set_active_time_value(times[k])
mesh = reader.read()

# Vectors carry z = 0, so the warped mesh stays in the plane.
warped = mesh.warp_by_vector("displacement", factor=args.scale)
if "von_mises" in mesh.point_data:
    field, label = "von_mises", "von Mises stress"
else:
    warped["|u|"] = np.linalg.norm(mesh.point_data["displacement"], axis=1)
    field, label = "|u|", "|displacement|"

plotter = pv.Plotter(off_screen=True, window_size=(1200, 500))
plotter.add_mesh(mesh.extract_feature_edges(), color="gray", line_width=1)
plotter.add_mesh(warped, scalars=field, show_edges=True, scalar_bar_args={"title": label})
plotter.view_xy()
plotter.add_text(f"t = {times[k]:g}, displacement x {args.scale:g}", font_size=10)
plotter.screenshot(args.png)

u = mesh.point_data["displacement"]
lo, hi = warped.points.min(axis=0), warped.points.max(axis=0)
print(f"record {k} of {len(times)}, t = {times[k]:.17g}")
print(f"max |u| = {np.linalg.norm(u, axis=1).max():.17g}")
print(f"warped x in [{lo[0]:.17g}, {hi[0]:.17g}], y in [{lo[1]:.17g}, {hi[1]:.17g}]")
print(f"coloured by {field}; wrote {args.png}")
