"""What the numbered examples share: their command line, finding and running
stickslip, meshing a .geo with the gmsh Python module, reading a finished
run's results with h5py, and the friction stress along the contact group
plotted with matplotlib.

Each example's run.py puts this folder on its import path first, so it runs
from any directory:

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

# The checkout: examples/ is one level below it.
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def setup(script, doc):
    """The example's folder (where `script`, its run.py, lies) and the --out
    directory of its command line, created; `doc` is the example's
    docstring, whose first line describes it in --help."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--out", required=True, help="directory for the mesh, results and PNG")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    return os.path.dirname(os.path.abspath(script)), args.out


def stickslip():
    """The command that runs stickslip: $STICKSLIP_BIN, else `stickslip` on
    PATH, else `cargo run` in this checkout (whatever the current directory)."""
    exe = os.environ.get("STICKSLIP_BIN")
    if exe:
        return shlex.split(exe)
    if shutil.which("stickslip"):
        return ["stickslip"]
    manifest = os.path.join(ROOT, "Cargo.toml")
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


def mesh(here, out, name, order, **params):
    """Meshes here/NAME.geo into out/NAME.msh with the gmsh Python module,
    headless: elements of the given order, the .geo's numbers `params` set
    as by `gmsh -setnumber`."""
    import gmsh

    argv = ["gmsh", "-nopopup"]
    for key, value in params.items():
        argv += ["-setnumber", key, str(value)]
    gmsh.initialize(argv, readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(os.path.join(here, name + ".geo"))
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        gmsh.write(os.path.join(out, name + ".msh"))
    finally:
        gmsh.finalize()


def run_case(here, out, name):
    """`stickslip run` of here/case.toml into out/NAME.h5; returns that path.
    The case names its mesh relative to itself, so it is copied into `out`,
    next to the mesh, first."""
    case = os.path.join(out, "case.toml")
    shutil.copyfile(os.path.join(here, "case.toml"), case)
    h5 = os.path.join(out, name + ".h5")
    run_stickslip(["run", case, "-o", h5, "--force", "--quiet"])
    return h5


def read(h5, *names):
    """The named datasets of a results file, whole, once the file says the
    run completed."""
    import h5py

    with h5py.File(h5, "r") as f:
        assert bool(f.attrs["complete"]), "the run did not complete"
        return [f[name][:] for name in names]


def pyplot():
    """matplotlib's pyplot on the Agg backend: the examples write PNGs and
    need no display."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_along(ax, s, sigma, g, t, steps, xlabel):
    """sigma_T / g along the contact group (arc length s) at the given output
    steps, one line each."""
    for k in steps:
        ax.plot(s, sigma[k] / g, marker=".", label=f"t = {t[k]:.2f}")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("sigma_T / g")
    ax.legend(fontsize=8)


def at_times(t, times):
    """The output steps at or just after the given times (the last step for
    times past the end)."""
    import numpy as np

    return [min(k, len(t) - 1) for k in np.searchsorted(t, times)]


def save(fig, out, name):
    """Writes the figure to out/name and says where."""
    fig.tight_layout()
    png = os.path.join(out, name)
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")
