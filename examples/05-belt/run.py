"""Example 5: a pad on a conveyor belt sticks and slips.

Why
---
Static friction above kinetic friction makes a part on a moving belt stick
and slip in turn, the squeal of brakes and the chatter of machine slides.
Here an elastic pad of 2 x 1, clamped at its top, rests on a belt running
at V = 0.05 along +x, pressed by p = 10, with a friction coefficient that
falls from static 0.7 at rest to kinetic 0.3 as the pad slips
(mu = { static = 0.7, kinetic = 0.3, speed = 0.01 }: mu(w) = mk + (ms - mk)
exp(-|w|/vs) on the slip speed w = v_T - V). While its bottom sticks, the
belt carries it along at V and the pad's shear grows; when the shear
stress reaches mu_s p = 7 the bottom slips, friction falls towards
mu_k p = 3, and the pad springs back faster than the belt runs, sticks
again, and the cycle repeats.

What to look for: the sawtooth of the pad's bottom right corner against
time, rising at the belt's speed V while the whole bottom sticks (the
dashed slope), dropping quickly when it slips; and the count of stuck
nodes, all of them during the rise.

How
---
1. Mesh part.geo with the gmsh Python module (16 x 8 quad4 cells).
2. Run case.toml (central difference, whose nodal closed form takes the
   friction coefficient at the step's own slip speed; Newmark also runs a
   speed-dependent mu, at the previous step's slip: docs/case-file.md).
3. Read part.h5 with h5py: the corner's u_x and v_x and the contact
   states, into OUT/belt.png.

    python3 examples/05-belt/run.py --out /tmp/belt
"""

import os
import sys

# examples/common.py, whatever the current directory.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import common  # noqa: E402

V = 0.05  # foundation_velocity in case.toml


def main():
    here, out = common.setup(__file__, __doc__)

    # 1. Mesh.
    common.mesh(here, out, "part", 1, nx=16, ny=8)

    # 2. Run.
    h5 = common.run_case(here, out, "part")

    # 3. Read.
    import numpy as np

    nodes, t, u, v, state = common.read(
        h5, "mesh/nodes", "time", "displacement", "velocity", "contact/state"
    )
    corner = np.argmin(np.hypot(nodes[:, 0] - nodes[:, 0].max(), nodes[:, 1]))
    ux, vx = u[:, corner, 0], v[:, corner, 0]
    stuck = (state == 0).sum(axis=1)
    all_stuck = stuck == state.shape[1]
    # A cycle: one slip, a drop of the corner through the band of +-0.002
    # about its mean after the start (the chatter after a slip stays
    # within it).
    late = t > 0.5
    mid = ux[late].mean()
    slips, above = [], False
    for ti, x in zip(t[late], ux[late]):
        if x > mid + 0.002:
            above = True
        elif above and x < mid - 0.002:
            slips.append(ti)
            above = False
    periods = np.diff(slips)
    rise = vx[all_stuck].mean()
    print(f"nodes {len(nodes)}, output steps {len(t)}, contact nodes {state.shape[1]}")
    print(f"cycles: {len(slips)}")
    print(f"mean period: {periods.mean():.6f} (spread {periods.std():.6f})")
    print(f"rise speed while stuck: {rise:.6f} (belt V = {V})")
    print(f"sawtooth: u_x from {ux[t > 0.5].min():.6f} to {ux[t > 0.5].max():.6f}")

    # 4. Plot.
    plt = common.pyplot()
    fig, (a, b) = plt.subplots(2, 1, figsize=(6.5, 6), sharex=True)
    a.plot(t, ux, label="stickslip: u_x of the bottom right corner")
    t0 = t[all_stuck][0]
    a.plot([t0, t0 + 0.3], [ux[all_stuck][0], ux[all_stuck][0] + 0.3 * V], "--",
           label="slope V, the belt's speed")
    a.set_ylabel("u_x")
    a.set_title("A pad on a conveyor belt sticks and slips")
    a.legend(fontsize=8)
    b.plot(t, stuck, drawstyle="steps-post")
    b.set_xlabel("t")
    b.set_ylabel("stuck nodes")
    common.save(fig, out, "belt.png")


if __name__ == "__main__":
    sys.exit(main())
