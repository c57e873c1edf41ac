"""Example 4: a block launched along a rough floor slides to rest.

Why
---
Friction is often all that holds a part: here a block of 2 x 1 sits on a
rough floor (Coulomb, mu = 0.5, pressed by p = 10) and nothing else holds
it in x, only rollers on its top (u_y = 0), which resist the friction's
moment that would otherwise tip it over. It is launched at v0 = 1 along x
([initial] velocity). Rigidly, the friction force mu p W on the mass
rho W H decelerates it at a = mu p / (rho H) = 5: it stops after v0/a = 0.2,
having slid v0^2/(2a) = 0.1, and its position is x(t) = v0 t - a t^2/2
until then. The block is stiff (E = 1e5), so its mean position follows the
rigid closed form; once stopped it rings elastically about its rest.

What to look for: the mean position on the parabola and then flat, the
mean velocity on the straight line v0 - a t down to zero.

How
---
1. Mesh block.geo with the gmsh Python module (16 x 8 quad4 cells).
2. Run case.toml (central difference; the supports leave the translation
   in x free, which stickslip handles: the static preload under the
   pressure is balanced by the rollers).
3. Read block.h5 with h5py; the block's mean displacement and velocity
   (weighted as the lumped mass of the regular grid: a half at an edge, a
   quarter at a corner) against the rigid closed form into OUT/block.png.

    python3 examples/04-block-slides-to-rest/run.py --out /tmp/slide
"""

import os
import sys

# examples/common.py, whatever the current directory.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import common  # noqa: E402

V0 = 1.0  # [initial] velocity
A = 0.5 * 10.0 / (1.0 * 1.0)  # mu p / (rho H), from case.toml and block.geo


def main():
    here, out = common.setup(__file__, __doc__)

    # 1. Mesh.
    common.mesh(here, out, "block", 1, nx=16, ny=8)

    # 2. Run.
    h5 = common.run_case(here, out, "block")

    # 3. Read.
    import numpy as np

    nodes, t, u, v = common.read(h5, "mesh/nodes", "time", "displacement", "velocity")
    x, y = nodes[:, 0], nodes[:, 1]
    # The regular grid's lumped mass: a half at an edge, a quarter at a corner.
    w = np.where(np.isclose(x, x.min()) | np.isclose(x, x.max()), 0.5, 1.0)
    w = w * np.where(np.isclose(y, y.min()) | np.isclose(y, y.max()), 0.5, 1.0)
    w = w / w.sum()
    mean_u = (u[:, :, 0] * w).sum(axis=1)
    mean_v = (v[:, :, 0] * w).sum(axis=1)
    # The stop: where the line through the first times the mean velocity
    # falls to v0/2 and to v0/20 reaches zero (after it the stuck block
    # rings, its mean velocity a few percent of v0 about zero).
    t1 = t[np.argmax(mean_v <= 0.5 * V0)]
    t2 = t[np.argmax(mean_v <= 0.05 * V0)]
    stop = t2 + (t2 - t1) * 0.05 / 0.45
    rigid_stop, rigid_distance = V0 / A, V0 * V0 / (2 * A)
    distance = mean_u[-1] - mean_u[0]
    print(f"nodes {len(nodes)}, output steps {len(t)}")
    print(f"stop time: {stop:.6f} (rigid v0/a = {rigid_stop:.6f})")
    print(f"distance slid: {distance:.6f} (rigid v0^2/(2a) = {rigid_distance:.6f})")

    # 4. Plot.
    ts = np.minimum(t, rigid_stop)
    rigid_x = V0 * ts - 0.5 * A * ts * ts
    rigid_v = V0 - A * ts
    plt = common.pyplot()
    fig, (a, b) = plt.subplots(2, 1, figsize=(6.5, 6), sharex=True)
    a.plot(t, mean_u - mean_u[0], label="stickslip: mean u_x")
    a.plot(t, rigid_x, "--", label="rigid: v0 t - a t^2/2, then v0^2/(2a)")
    a.set_ylabel("mean position")
    a.set_title("A block launched along a rough floor slides to rest")
    a.legend(fontsize=8)
    b.plot(t, mean_v, label="stickslip: mean v_x")
    b.plot(t, rigid_v, "--", label="rigid: v0 - a t, then 0")
    b.set_xlabel("t")
    b.set_ylabel("mean velocity")
    b.legend(fontsize=8)
    common.save(fig, out, "block.png")


if __name__ == "__main__":
    sys.exit(main())
