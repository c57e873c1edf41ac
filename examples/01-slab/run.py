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

    # 1. Mesh (the case names slab.msh relative to itself: copy it alongside).
    mesh(os.path.join(HERE, "slab.geo"), os.path.join(args.out, "slab.msh"), 2, {"nx": 8, "ny": 2})
    case = os.path.join(args.out, "case.toml")
    with open(os.path.join(HERE, "case.toml")) as src, open(case, "w") as dst:
        dst.write(src.read())

    # 2. Run.
    h5 = os.path.join(args.out, "slab.h5")
    run_stickslip(["run", case, "-o", h5, "--force", "--quiet"])

    # 3. Read.
    import h5py
    import numpy as np

    with h5py.File(h5, "r") as f:
        nodes = f["mesh/nodes"][:]
        t = f["time"][:]
        contact = list(f["contact/nodes"][:])
        s = f["contact/s"][:]
        sigma = f["contact/friction_stress"][:]
        n81 = int(np.argmin(np.hypot(nodes[:, 0] - 8.0, nodes[:, 1])))  # the paper's node 81
        ux81 = f["displacement"][:, n81, 0]
        assert bool(f.attrs["complete"]), "the run did not complete"
    g = 0.3 * 300.0  # mu * F_n, from case.toml
    j81 = contact.index(n81)
    static = 0.3 * (1 + 0.3) * 300.0 / 1000.0 * 8.0  # nu (1 + nu) F_n / E * x at x = 8
    print(f"nodes {len(nodes)}, contact nodes with friction {len(contact)}, output steps {len(t)}")
    print(f"node 81 = mesh node {n81}; initial u_x {ux81[0]:.9f}, closed form {static:.9f}")
    print(f"node 81 final u_x at t = {t[-1]:g}: {ux81[-1]:.6f}")
    print(f"max |sigma_T| / g: {np.abs(sigma).max() / g:.6f}")

    # 4. Plot.
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b, c) = plt.subplots(3, 1, figsize=(6.5, 8))
    for k in np.searchsorted(t, [0.01, 0.05, 0.1, 0.2, 0.5]):
        k = min(k, len(t) - 1)
        a.plot(s, sigma[k] / g, marker=".", label=f"t = {t[k]:.2f}")
    a.set_xlabel("x along the bottom (s)")
    a.set_ylabel("sigma_T / g")
    a.set_title("Martins & Oden slab: friction stress on the bottom")
    a.legend(fontsize=8)
    b.plot(t, ux81)
    b.set_ylabel("u_x, node 81")
    c.plot(t, sigma[:, j81])
    c.axhline(g, color="gray", lw=0.5)
    c.set_ylabel("sigma_T, node 81")
    c.set_xlabel("t")
    fig.tight_layout()
    png = os.path.join(args.out, "slab.png")
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")


if __name__ == "__main__":
    sys.exit(main())
