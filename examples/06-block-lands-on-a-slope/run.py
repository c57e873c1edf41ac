"""Example 6: a block dropped onto a rough slope bounces, slides and sticks.

Why
---
With a prescribed pressure (the paper's law) a part cannot land, bounce or
lift off: the normal traction is an input. With the normal-compliance law
(law = "compliance", Oden and Martins 1985) the slope is a rigid
foundation that pushes back c_n delta where the block has moved into it,
and bounds the friction by mu c_n delta: contact opens and closes by
itself. Here a block of 1 x 0.5 (rho = 1, E = 1e4) is dropped at rest from
D = 0.05 above a slope of 20 degrees with mu = 0.6 > tan 20 deg = 0.364
under gravity g = 9.81, with a mass-proportional drag (alpha = 20) that
lets the bouncing die out: the compliant contact itself is elastic, and
with a light drag (alpha = 4) the block keeps hopping down the slope,
friction turning its slide into rocking.

It falls, lands, bounces on the slope while sliding down it, and once the
bouncing has died down the friction holds it: at rest, the slope carries
the block's weight m g = 4.905 (per unit thickness) as a normal force
m g cos 20 = 4.609 and a friction force m g sin 20 = 1.678, their ratio
tan 20 = 0.364 below mu (while the regularized law lets a stuck node
creep at a speed below eps, the drag alpha m v takes its small share). The
first touch comes when the block has fallen D along the slope's normal
under g cos 20 and the drag, D = (a/alpha)(t - (1 - exp(-alpha t))/alpha),
a = g cos 20: t = 0.1563.

As run (8 x 4 cells, dt = 2e-4, rows every 2e-3): first touch at 0.158
(the first row after 0.1563), 4 touchdowns, 0.035 slid down the slope,
a final speed of 6e-4 (below eps), a final normal force of 4.6091 and a
friction force of 1.6716 (m g sin 20 less the drag's 0.006).

What to look for: the height above the slope falling to the touch, the
bounces (the normal force on and off), the slide down the slope slowing,
then the position flat and the two forces at their static values.

How
---
1. Mesh block.geo with the gmsh Python module (8 x 4 quad4 cells).
2. Run case.toml (central difference from rest; the block is free: only
   the slope, a compliant foundation, holds it).
3. Read block.h5 with h5py: the block's mean displacement along the slope
   and across it (weighted as the lumped mass of the regular grid), and
   the contact forces, the normal and friction tractions
   (/contact/normal_stress, /contact/friction_stress) summed with the
   bottom's trapezoid weights, into OUT/slope.png.

    python3 examples/06-block-lands-on-a-slope/run.py --out /tmp/slope
"""

import math
import os
import sys

# examples/common.py, whatever the current directory.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import common  # noqa: E402

ANGLE = math.radians(20.0)  # block.geo's A, case.toml's foundation normal
MASS = 1.0 * 0.5 * 1.0  # W H rho
G = 9.81  # case.toml's body force


def main():
    here, out = common.setup(__file__, __doc__)

    # 1. Mesh.
    common.mesh(here, out, "block", 1, nx=8, ny=4)

    # 2. Run.
    h5 = common.run_case(here, out, "block")

    # 3. Read.
    import numpy as np

    nodes, t, u, s, normal, friction = common.read(
        h5,
        "mesh/nodes",
        "time",
        "displacement",
        "contact/s",
        "contact/normal_stress",
        "contact/friction_stress",
    )
    along = np.array([math.cos(ANGLE), -math.sin(ANGLE)])  # downhill
    across = np.array([math.sin(ANGLE), math.cos(ANGLE)])  # the slope's normal
    # The block's own coordinates (along and across it) for the lumped
    # mass of its regular grid: a half at an edge, a quarter at a corner.
    a, c = nodes[:, :2] @ along, nodes[:, :2] @ across
    w = np.where(np.isclose(a, a.min()) | np.isclose(a, a.max()), 0.5, 1.0)
    w = w * np.where(np.isclose(c, c.min()) | np.isclose(c, c.max()), 0.5, 1.0)
    w = w / w.sum()
    mean = (u * w[None, :, None]).sum(axis=1)
    slide = mean @ along
    height = 0.05 + mean @ across  # the bottom's gap D + u.n, rigidly
    # The bottom's nodal weights: trapezoids along its arc length.
    order = np.argsort(s)
    ss = s[order]
    tw = np.zeros_like(ss)
    tw[1:] += 0.5 * np.diff(ss)
    tw[:-1] += 0.5 * np.diff(ss)
    weights = np.empty_like(tw)
    weights[order] = tw
    n_force = normal @ weights
    f_force = friction @ weights
    touching = n_force > 0.0
    first = t[np.argmax(touching)]
    # Contact phases: each run of rows with a normal force.
    bounces = int(np.sum(touching[1:] & ~touching[:-1]))
    mean_v = np.gradient(slide, t)
    print(f"nodes {len(nodes)}, output steps {len(t)}")
    print(f"first touch: {first:.4f}")
    print(f"touchdowns: {bounces}")
    print(f"slid along the slope: {slide[-1]:.4f}")
    print(f"final speed along the slope: {abs(mean_v[-1]):.2e}")
    print(f"final normal force: {n_force[-1]:.4f} (m g cos A = {MASS * G * math.cos(ANGLE):.4f})")
    print(f"final friction force: {abs(f_force[-1]):.4f} (m g sin A = {MASS * G * math.sin(ANGLE):.4f})")

    # 4. Plot.
    plt = common.pyplot()
    fig, (p, q) = plt.subplots(2, 1, figsize=(6.5, 6), sharex=True)
    p.plot(t, slide, label="mean displacement down the slope")
    p.plot(t, height, label="mean height of the bottom above the slope")
    p.set_ylabel("position")
    p.set_title("A block dropped onto a rough slope bounces, slides and sticks")
    p.legend(fontsize=8)
    q.plot(t, n_force, label="normal force (sum of w c_n delta)")
    q.plot(t, np.abs(f_force), label="friction force (|sum of w sigma_T|)")
    q.axhline(MASS * G * math.cos(ANGLE), ls="--", c="gray", lw=0.8, label="m g cos A, m g sin A")
    q.axhline(MASS * G * math.sin(ANGLE), ls="--", c="gray", lw=0.8)
    q.set_xlabel("t")
    q.set_ylabel("force (per unit thickness)")
    q.legend(fontsize=8)
    common.save(fig, out, "slope.png")


if __name__ == "__main__":
    sys.exit(main())
