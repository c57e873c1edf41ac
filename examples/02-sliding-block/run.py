"""Example 2: a block pushed along a rough base towards a wall.

Why
---
The paper's slab (example 1) is held by its support and slips only a
little. Here friction is the only thing that resists the load over most of
the base: a block of 2 x 1 sits on a rigid, rough floor (Coulomb, mu = 0.5,
pressure 50, so the friction bound is g = 25 per unit length, 50 over the
whole base) and is pushed on its left face by a traction of 60 that is
switched on at t = 0. The push (60) exceeds what the base can resist (50),
so near the pushed face the block slides towards the wall that holds its
right face; the compression wave runs to the wall and back, and the region
that slips grows and shrinks with it.

What to look for: the friction stress sigma_T never exceeds the bound g in
magnitude, and where a node slips, sigma_T opposes the slip velocity
(sigma_T * v_T <= 0: friction only dissipates). The pushed face ends up
displaced towards the wall (u_x > 0).

How
---
1. Mesh block.geo with the gmsh Python module (16 x 8 quad4 cells). The
   physical groups name what the case file refers to: base, wall, push.
2. Run case.toml (central difference; the wall holds the right face, so
   the block is pushed against it; without it the block would be held in x
   by friction alone, as in example 4).
3. Read block.h5 with h5py, and plot u_x of the pushed face's bottom corner
   and sigma_T / g along the base at a few times into OUT/block.png.

    python3 examples/02-sliding-block/run.py --out /tmp/block
"""

import os
import sys

# examples/common.py, whatever the current directory.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import common  # noqa: E402


def main():
    here, out = common.setup(__file__, __doc__)

    # 1. Mesh.
    common.mesh(here, out, "block", 1, nx=16, ny=8)

    # 2. Run. The case refers to block.msh relative to itself, so the case
    #    is copied next to the mesh.
    h5 = common.run_case(here, out, "block")

    # 3. Read.
    import numpy as np

    # The histories (time, contact/*) are at every step; the fields
    # (displacement) at frames, whose times are frames/time.
    nodes, t, u, tf, contact, s, sigma, v_t, state = common.read(
        h5, "mesh/nodes", "time", "displacement", "frames/time", "contact/nodes", "contact/s",
        "contact/friction_stress", "contact/slip_velocity", "contact/state",
    )
    ux = u[:, :, 0]
    g = 0.5 * 50.0  # mu * pressure, from case.toml
    corner = int(np.argmin(np.hypot(nodes[:, 0], nodes[:, 1])))  # (0, 0): pushed face, on the base

    ratio = np.abs(sigma).max() / g
    dissipation = (sigma * v_t).max()  # <= 0 at every node and step
    slipping = (state != 0).mean(axis=1)
    print(f"nodes {len(nodes)}, base nodes with friction {len(contact)}, output steps {len(t)}, frames {len(tf)}")
    print(f"final u_x of the pushed corner (0, 0): {ux[-1, corner]:.6f}")
    print(f"max |sigma_T| / g: {ratio:.6f}")
    print(f"max sigma_T * v_T: {dissipation:.3e}")
    print(f"largest fraction of the base slipping: {slipping.max():.3f} (at t = {t[slipping.argmax()]:.3f})")

    # 4. Plot.
    plt = common.pyplot()
    fig, (a, b) = plt.subplots(2, 1, figsize=(6.5, 6))
    a.plot(tf, ux[:, corner])
    a.set_xlabel("t")
    a.set_ylabel("u_x at the pushed corner (0, 0)")
    a.set_title("A block pushed towards a wall along a rough base")
    common.plot_along(b, s, sigma, g, t, np.linspace(1, len(t) - 1, 5).astype(int), "x along the base")
    b.axhline(1.0, color="gray", lw=0.5)
    b.axhline(-1.0, color="gray", lw=0.5)
    common.save(fig, out, "block.png")


if __name__ == "__main__":
    sys.exit(main())
