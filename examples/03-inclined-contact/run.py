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

    # 1. Mesh.
    mesh(os.path.join(HERE, "wedge.geo"), os.path.join(args.out, "wedge.msh"), 2, {})
    case = os.path.join(args.out, "case.toml")
    with open(os.path.join(HERE, "case.toml")) as src, open(case, "w") as dst:
        dst.write(src.read())

    # 2. Run.
    h5 = os.path.join(args.out, "wedge.h5")
    run_stickslip(["run", case, "-o", h5, "--force", "--quiet"])

    # 3. Read.
    import h5py
    import numpy as np

    with h5py.File(h5, "r") as f:
        nodes = f["mesh/nodes"][:]
        cells = f["mesh/cells"][:]
        t = f["time"][:]
        vel = f["velocity"][:]
        contact = f["contact/nodes"][:]
        s = f["contact/s"][:]
        sigma = f["contact/friction_stress"][:]
        v_t = f["contact/slip_velocity"][:]
        assert bool(f.attrs["complete"]), "the run did not complete"
    g = 0.3 * 200.0  # mu * pressure, from case.toml
    tau = np.array([4.0, 1.0]) / np.sqrt(17.0)  # the incline, walked with the body on its left
    along = vel[:, contact, :] @ tau  # tau . v at every contact node and step
    print(f"nodes {len(nodes)}, contact nodes with friction {len(contact)}, output steps {len(t)}")
    print(f"incline: from ({nodes[contact[0]][0]:g}, {nodes[contact[0]][1]:g}) to "
          f"({nodes[contact[-1]][0]:g}, {nodes[contact[-1]][1]:g}), length {s[-1]:.6f} (sqrt 17 = {np.sqrt(17):.6f})")
    print(f"max |v_T - tau.v|: {np.abs(v_t - along).max():.3e} (max |v_T| {np.abs(v_t).max():.3e})")
    print(f"max |sigma_T| / g: {np.abs(sigma).max() / g:.6f}")
    print(f"max sigma_T * v_T: {(sigma * v_t).max():.3e}")

    # 4. Plot.
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
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
    for k in np.searchsorted(t, [0.02, 0.1, 0.25, 0.5]):
        k = min(k, len(t) - 1)
        b.plot(s, sigma[k] / g, marker=".", label=f"t = {t[k]:.2f}")
    b.set_xlabel("s along the incline")
    b.set_ylabel("sigma_T / g")
    b.legend(fontsize=8)
    fig.tight_layout()
    png = os.path.join(args.out, "wedge.png")
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")


if __name__ == "__main__":
    sys.exit(main())
