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
2. Run case.toml (central difference; a rigid body motion left free would
   make the initial static solve singular, hence the wall: stickslip refuses
   such a case and says so).
3. Read block.h5 with h5py, and plot u_x of the pushed face's bottom corner
   and sigma_T / g along the base at a few times into OUT/block.png.

    python3 examples/02-sliding-block/run.py --out /tmp/block

The stickslip binary is $STICKSLIP_BIN, else `stickslip` on PATH, else
`cargo run` in this checkout.
"""

import argparse
import os
import shlex
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def stickslip():
    """The command that runs stickslip: $STICKSLIP_BIN, else `stickslip` on
    PATH, else `cargo run` in this checkout (whatever the current directory)."""
    exe = os.environ.get("STICKSLIP_BIN")
    if exe:
        return shlex.split(exe)
    if shutil.which("stickslip"):
        return ["stickslip"]
    manifest = os.path.join(HERE, "..", "..", "Cargo.toml")
    if shutil.which("cargo") and os.path.exists(manifest):
        return ["cargo", "run", "-q", "--manifest-path", manifest, "-p", "stickslip", "--"]
    sys.exit(
        "stickslip not found: build it (cargo build --release -p stickslip in the checkout) "
        "and put it on PATH, or set STICKSLIP_BIN to its path"
    )


def run_stickslip(args):
    """Runs stickslip; its own message says what went wrong, so no traceback."""
    cmd = stickslip() + args
    try:
        done = subprocess.run(cmd)
    except OSError as e:
        sys.exit(f"cannot start {cmd[0]}: {e}; set STICKSLIP_BIN to the stickslip binary")
    if done.returncode != 0:
        sys.exit(f"stickslip exited with {done.returncode} (its message is above)")


def mesh(geo, msh, order, params):
    """Meshes a .geo with the gmsh Python module, headless."""
    import gmsh

    argv = ["gmsh", "-nopopup"]
    for name, value in params.items():
        argv += ["-setnumber", name, str(value)]
    gmsh.initialize(argv, readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(geo)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        gmsh.write(msh)
    finally:
        gmsh.finalize()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="directory for the mesh, results and PNG")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    # 1. Mesh. The case refers to block.msh relative to itself, so the case
    #    is copied next to the mesh.
    mesh(os.path.join(HERE, "block.geo"), os.path.join(args.out, "block.msh"), 1, {"nx": 16, "ny": 8})
    case = os.path.join(args.out, "case.toml")
    with open(os.path.join(HERE, "case.toml")) as src, open(case, "w") as dst:
        dst.write(src.read())

    # 2. Run.
    h5 = os.path.join(args.out, "block.h5")
    run_stickslip(["run", case, "-o", h5, "--force", "--quiet"])

    # 3. Read.
    import h5py
    import numpy as np

    with h5py.File(h5, "r") as f:
        nodes = f["mesh/nodes"][:]
        t = f["time"][:]
        ux = f["displacement"][:, :, 0]
        contact = f["contact/nodes"][:]
        s = f["contact/s"][:]
        sigma = f["contact/friction_stress"][:]
        v_t = f["contact/slip_velocity"][:]
        state = f["contact/state"][:]
        assert bool(f.attrs["complete"]), "the run did not complete"
    g = 0.5 * 50.0  # mu * pressure, from case.toml
    corner = int(np.argmin(np.hypot(nodes[:, 0], nodes[:, 1])))  # (0, 0): pushed face, on the base

    ratio = np.abs(sigma).max() / g
    dissipation = (sigma * v_t).max()  # <= 0 at every node and step
    slipping = (state != 0).mean(axis=1)
    print(f"nodes {len(nodes)}, base nodes with friction {len(contact)}, output steps {len(t)}")
    print(f"final u_x of the pushed corner (0, 0): {ux[-1, corner]:.6f}")
    print(f"max |sigma_T| / g: {ratio:.6f}")
    print(f"max sigma_T * v_T: {dissipation:.3e}")
    print(f"largest fraction of the base slipping: {slipping.max():.3f} (at t = {t[slipping.argmax()]:.3f})")

    # 4. Plot.
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(2, 1, figsize=(6.5, 6))
    a.plot(t, ux[:, corner])
    a.set_xlabel("t")
    a.set_ylabel("u_x at the pushed corner (0, 0)")
    a.set_title("A block pushed towards a wall along a rough base")
    for k in np.linspace(1, len(t) - 1, 5).astype(int):
        b.plot(s, sigma[k] / g, marker=".", label=f"t = {t[k]:.2f}")
    b.axhline(1.0, color="gray", lw=0.5)
    b.axhline(-1.0, color="gray", lw=0.5)
    b.set_xlabel("x along the base")
    b.set_ylabel("sigma_T / g")
    b.legend(fontsize=8)
    fig.tight_layout()
    png = os.path.join(args.out, "block.png")
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")


if __name__ == "__main__":
    sys.exit(main())
