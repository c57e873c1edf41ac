"""Example 1: the paper's slab, from slab.geo to a friction-stress plot.

Why
---
Martins & Oden (1983, section 4.3) test their method on a slab 8 x 1
(E = 1000, nu = 0.3, rho = 1, plane strain) pressed against a rough support
by a pressure F_n = 300 on its bottom face (mu = 0.3, so the friction bound
is g = 90), held on top by rollers and at its left end in x, and loaded at
its right end by a compressive traction t_x = -150 H(t). Before t = 0 the
pressure alone squeezes the slab: with sigma_xx = 0 and eps_zz = 0 (plane
strain) the bottom face stretches uniformly, u_x = nu (1 + nu) F_n / E x =
0.117 x, so the paper's node 81 at (8, 0) starts at u_x = 0.936. The end
load then drives a compression wave along the slab; the bottom slips
backwards at the friction bound (sigma_T = g while slipping) and sticks
again as the wave dies out: Figs. 6 to 8 of the paper.

This example reproduces that chain the way a user would: Gmsh mesh, case
file, one command, h5py, matplotlib.

How
---
1. Mesh slab.geo (a copy of cases/slab.geo) with the gmsh Python module,
   8 x 2 quad9 cells (the paper's 85 nodes).
2. Run case.toml: central difference, dt = 1e-3 to t = 0.5, eps = 1e-4.
3. Read slab.h5 with h5py: the contact nodes along the bottom (in order,
   with their arc length s), the friction stress at every output step.
4. Plot sigma_T / g along the bottom at a few times, and u_x and sigma_T of
   node 81 over time, into OUT/slab.png.

    python3 examples/01-slab/run.py --out /tmp/slab
"""

import os
import sys

# examples/common.py, whatever the current directory.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import common  # noqa: E402


def main():
    here, out = common.setup(__file__, __doc__)

    # 1. Mesh.
    common.mesh(here, out, "slab", 2, nx=8, ny=2)

    # 2. Run (the case names slab.msh relative to itself: copied alongside).
    h5 = common.run_case(here, out, "slab")

    # 3. Read.
    import numpy as np

    # The histories (time, contact/*) are at every step; the fields
    # (displacement) at frames, whose times are frames/time.
    nodes, t, contact, s, sigma, u, tf = common.read(
        h5, "mesh/nodes", "time", "contact/nodes", "contact/s", "contact/friction_stress", "displacement",
        "frames/time",
    )
    n81 = int(np.argmin(np.hypot(nodes[:, 0] - 8.0, nodes[:, 1])))  # the paper's node 81
    ux81 = u[:, n81, 0]
    g = 0.3 * 300.0  # mu * F_n, from case.toml
    j81 = list(contact).index(n81)
    static = 0.3 * (1 + 0.3) * 300.0 / 1000.0 * 8.0  # nu (1 + nu) F_n / E * x at x = 8
    print(f"nodes {len(nodes)}, contact nodes with friction {len(contact)}, output steps {len(t)}, frames {len(tf)}")
    print(f"node 81 = mesh node {n81}; initial u_x {ux81[0]:.9f}, closed form {static:.9f}")
    print(f"node 81 final u_x at t = {tf[-1]:g}: {ux81[-1]:.6f}")
    print(f"max |sigma_T| / g: {np.abs(sigma).max() / g:.6f}")

    # 4. Plot.
    plt = common.pyplot()
    fig, (a, b, c) = plt.subplots(3, 1, figsize=(6.5, 8))
    a.set_title("Martins & Oden slab: friction stress on the bottom")
    common.plot_along(a, s, sigma, g, t, common.at_times(t, [0.01, 0.05, 0.1, 0.2, 0.5]), "x along the bottom (s)")
    b.plot(tf, ux81)
    b.set_ylabel("u_x, node 81")
    c.plot(t, sigma[:, j81])
    c.axhline(g, color="gray", lw=0.5)
    c.set_ylabel("sigma_T, node 81")
    c.set_xlabel("t")
    common.save(fig, out, "slab.png")


if __name__ == "__main__":
    sys.exit(main())
