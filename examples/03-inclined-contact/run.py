"""Example 3: a wedge on an inclined rough face.

Why
---
Nothing in the friction model needs the contact line to be horizontal: at
every node of the contact group the tangent tau is the unit tangent of the
boundary walked with the body on its left, and the slip velocity and the
friction stress are components along that tau (DESIGN.md). Here the rough
face rises from (0, 0) to (4, 1), so tau = (4, 1) / sqrt(17) at every node of
it, about 14 degrees off the x axis, and a node's slip has both an x and a
y part. The wedge is held on top by rollers (u_y = 0) and at its left end in
x; a pressure of 200 acts on the inclined face (mu = 0.3, g = 60) and a
compressive traction of 100 is switched on at its right end at t = 0.

What to look for: the slip velocity stored in the file is exactly the
component of the node's velocity along the incline, v_T = tau . v; the
friction stress stays within the bound, |sigma_T| <= g, and opposes the slip
(sigma_T v_T <= 0).

How
---
1. Mesh wedge.geo with the gmsh Python module: 16 x 4 quad9 cells,
   transfinite on the trapezoid.
2. Run case.toml (central difference, dt = 5e-4, every 5th step written).
3. Read wedge.h5 with h5py; compare the stored v_T with tau . v from the
   velocity field; plot sigma_T / g along the incline at a few times and the
   mesh with the incline's tangent into OUT/wedge.png.

    python3 examples/03-inclined-contact/run.py --out /tmp/wedge
"""

import os
import sys

# examples/common.py, whatever the current directory.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import common  # noqa: E402


def main():
    here, out = common.setup(__file__, __doc__)

    # 1. Mesh.
    common.mesh(here, out, "wedge", 2)

    # 2. Run.
    h5 = common.run_case(here, out, "wedge")

    # 3. Read.
    import numpy as np

    # The histories (time, contact/*) are at every step; the fields
    # (velocity) at frames, frames/row[k] being frame k's step (its row of
    # time and contact/*).
    nodes, cells, t, vel, rows, contact, s, sigma, v_t = common.read(
        h5, "mesh/nodes", "mesh/cells", "time", "velocity", "frames/row", "contact/nodes", "contact/s",
        "contact/friction_stress", "contact/slip_velocity",
    )
    g = 0.3 * 200.0  # mu * pressure, from case.toml
    tau = np.array([4.0, 1.0]) / np.sqrt(17.0)  # the incline, walked with the body on its left
    along = vel[:, contact, :] @ tau  # tau . v at every contact node and frame
    print(f"nodes {len(nodes)}, contact nodes with friction {len(contact)}, output steps {len(t)}")
    print(f"incline: from ({nodes[contact[0]][0]:g}, {nodes[contact[0]][1]:g}) to "
          f"({nodes[contact[-1]][0]:g}, {nodes[contact[-1]][1]:g}), length {s[-1]:.6f} (sqrt 17 = {np.sqrt(17):.6f})")
    print(f"max |v_T - tau.v|: {np.abs(v_t[rows] - along).max():.3e} (max |v_T| {np.abs(v_t).max():.3e})")
    print(f"max |sigma_T| / g: {np.abs(sigma).max() / g:.6f}")
    print(f"max sigma_T * v_T: {(sigma * v_t).max():.3e}")

    # 4. Plot.
    plt = common.pyplot()
    from matplotlib.collections import PolyCollection

    fig, (a, b) = plt.subplots(2, 1, figsize=(6.5, 7.5))
    corners = nodes[cells[:, :4]]
    a.add_collection(PolyCollection(corners, facecolor="none", edgecolor="0.6", lw=0.5))
    a.plot(nodes[contact, 0], nodes[contact, 1], "r.-", label="contact group (rough face)")
    normal_in = np.array([-tau[1], tau[0]])  # into the body
    mid = nodes[contact[len(contact) // 2]] + 0.3 * normal_in
    a.annotate("", xy=mid + 0.8 * tau, xytext=mid, arrowprops=dict(arrowstyle="->", color="r", lw=1.5))
    a.text(*(mid + 0.4 * tau + 0.12 * normal_in), "tau", color="r")
    a.set_aspect("equal")
    a.autoscale()
    a.legend(loc="upper right", fontsize=8)
    a.set_title("A wedge on an inclined rough face")
    common.plot_along(b, s, sigma, g, t, common.at_times(t, [0.02, 0.1, 0.25, 0.5]), "s along the incline")
    common.save(fig, out, "wedge.png")


if __name__ == "__main__":
    sys.exit(main())
