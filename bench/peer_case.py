"""What the whole-process peers of `cargo xtask bench run` share: the case
file and the mesh as a user of numpy would read them, and the results file
they write. No finite elements here (each peer assembles K and M its own
way); only what the case says about the boundary, reduced to nodes.

* The case: the TOML file (`tomllib`) with `--set KEY=VALUE` applied, as
  `stickslip run` takes them. The keys of the paper's scene only
  (`cases/martins-oden/*.toml`): `[mesh] file`, `[material] E nu rho`
  (plane strain), `[[dirichlet]] group ux|uy = 0`, `[[traction]] group t
  history = "step"|"constant"`, `[contact] group pressure mu eps`, `[time]
  scheme dt t_end (beta gamma)`, `[output] every`. Anything else is
  refused (exit 2), so that a peer never runs a different problem quietly.
* The mesh: the Gmsh file by meshio; cells turned counter-clockwise as
  stickslip does; line groups by their physical names.
* The boundary (METHOD.md §3): per node of a line group, the nodal
  quadrature weight w_J (trapezoid on 2-node edges, Simpson on 3-node
  edges, times |x'(ξ_J)|) and the unit tangent τ_J (the mean of the
  adjacent edges' tangents, body on the left). A constant traction's
  consistent load is w_J t on straight edges, which the slab's are; the
  contact pressure is the traction −F_n n with n = (τ_y, −τ_x). Friction
  nodes: the contact group's nodes whose tangential motion is not held
  by a Dirichlet condition, g = μ F_n.
* The results: an HDF5 file by h5py with stickslip's names for what the
  peers write (`/time`, `/mesh/nodes`, `/displacement`, `/velocity`,
  `/acceleration` [n_out, n_nodes, 2] per mesh node, `/contact/nodes`,
  `/contact/friction_stress`, `/contact/state`), the records at the steps
  stickslip writes (every `output.every` steps and the last).
"""
import argparse
import os
import sys
import tomllib

import h5py
import meshio
import numpy as np


def refuse(msg):
    print(f"peer: {msg}", file=sys.stderr)
    sys.exit(2)


def arguments(description):
    """`CASE -o OUT [--set K=V]...`, as `stickslip run` takes them."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("case")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--set", action="append", default=[], dest="sets")
    ap.add_argument("--quiet", action="store_true")
    ap.add_argument("--force", action="store_true")
    return ap.parse_args()


def load_case(path, sets):
    """The case as a dict, `--set` applied; `mesh.file` made absolute."""
    with open(path, "rb") as f:
        case = tomllib.load(f)
    base = os.path.dirname(os.path.abspath(path))
    case["mesh"]["file"] = os.path.join(base, case["mesh"]["file"])
    for kv in sets:
        key, _, raw = kv.partition("=")
        try:
            value = tomllib.loads(f"v = {raw}")["v"]
        except tomllib.TOMLDecodeError:
            value = raw
        *path_, last = key.split(".")
        table = case
        for k in path_:
            table = table.setdefault(k, {})
        table[last] = value
    known = {
        "mesh": {"file", "ladder"},
        "material": {"E", "nu", "rho", "hypothesis"},
        "dirichlet": {"group", "ux", "uy"},
        "traction": {"group", "t", "history"},
        "contact": {"group", "pressure", "mu", "eps"},
        "time": {"scheme", "dt", "t_end", "beta", "gamma", "allow_unstable"},
        "output": {"file", "every"},
    }
    for k, v in case.items():
        if k == "title":
            continue
        if k not in known:
            refuse(f"the peer does not know [{k}]")
        for table in v if isinstance(v, list) else [v]:
            for key in table:
                if key not in known[k]:
                    refuse(f"the peer does not know {k}.{key}")
    if case["material"].get("hypothesis", "plane_strain") != "plane_strain":
        refuse("the peer knows plane strain only")
    return case


class Scene:
    """The mesh and the case's boundary, per node (see the module doc)."""

    def __init__(self, case):
        m = meshio.read(case["mesh"]["file"])
        self.nodes = np.ascontiguousarray(m.points[:, :2])
        kinds = [b.type for b in m.cells if b.type.startswith("quad")]
        if len(set(kinds)) != 1 or kinds[0] not in ("quad", "quad9"):
            refuse("the peer needs one kind of cells, quad4 or quad9")
        cells = np.concatenate([b.data for b in m.cells if b.type == kinds[0]])
        self.order = 2 if kinds[0] == "quad9" else 1
        # Counter-clockwise cells (stickslip turns clockwise ones around).
        p = self.nodes[cells[:, :4]]
        area = np.sum(p[:, :, 0] * np.roll(p[:, :, 1], -1, 1) - np.roll(p[:, :, 0], -1, 1) * p[:, :, 1], 1)
        flip = area < 0
        turned = [0, 3, 2, 1] + ([7, 6, 5, 4, 8] if self.order == 2 else [])
        cells[flip] = cells[flip][:, turned]
        # Nodes of no cell (Gmsh's Mesh.SaveAll) are dropped, as stickslip does.
        used, cells = np.unique(cells, return_inverse=True)
        renumber = np.full(len(self.nodes), -1)
        renumber[used] = np.arange(len(used))
        self.nodes = self.nodes[used]
        self.cells = cells.reshape(-1, 9 if self.order == 2 else 4)
        # Line groups by name: their edges, nodes (end, end[, mid]).
        self.lines = {}
        for name, blocks in m.cell_sets.items():
            if name.startswith("gmsh:"):
                continue
            edges = [m.cells[i].data[sel] for i, sel in enumerate(blocks)
                     if sel is not None and len(sel) and m.cells[i].type.startswith("line")]
            if edges:
                self.lines[name] = renumber[np.concatenate(edges)]
        n = len(self.nodes)
        self.fixed = np.zeros((n, 2), dtype=bool)
        for d in case.get("dirichlet", []):
            nodes = np.unique(self.group(d["group"]))
            for c, key in enumerate(("ux", "uy")):
                if key in d:
                    if d[key] != 0.0:
                        refuse(f"[[dirichlet]] {key} = {d[key]}: the peer knows held components only")
                    self.fixed[nodes, c] = True
        # Loads on nodes: before t = 0 (R(0⁻)) and from t = 0 on.
        self.load_before = np.zeros((n, 2))
        self.load_after = np.zeros((n, 2))
        for tr in case.get("traction", []):
            w, _, _ = self.weights(tr["group"])
            history = tr.get("history", "constant")
            if history not in ("step", "constant"):
                refuse(f"[[traction]] history = {history!r}: the peer knows step and constant")
            f = w[:, None] * np.asarray(tr["t"], dtype=float)[None, :]
            self.load_after += f
            if history == "constant":
                self.load_before += f
        c = case["contact"]
        w, tau, normal_load = self.weights(c["group"])
        pressure = float(c["pressure"])
        self.load_before += pressure * normal_load
        self.load_after += pressure * normal_load
        held = np.where(np.abs(tau) > 1e-12, self.fixed, True).all(1)
        self.contact = np.nonzero((w > 0) & ~held)[0]
        self.tangent = tau[self.contact]
        self.wg = w[self.contact] * float(c["mu"]) * pressure
        self.eps = float(c["eps"])
        t = case["time"]
        self.dt, t_end = float(t["dt"]), float(t["t_end"])
        steps = t_end / self.dt
        self.steps = int(round(steps))
        if abs(steps - self.steps) > 1e-9 * max(steps, 1.0):
            refuse("t_end is not a whole number of steps; the peer takes whole steps only")
        self.every = int(case.get("output", {}).get("every", 1))
        self.scheme = t["scheme"]
        self.beta = float(t.get("beta", 0.25))
        self.gamma = float(t.get("gamma", 0.5))
        mat = case["material"]
        self.young, self.poisson, self.rho = float(mat["E"]), float(mat["nu"]), float(mat["rho"])

    def group(self, name):
        if name not in self.lines:
            refuse(f"the mesh has no line group {name!r}")
        return self.lines[name]

    def weights(self, name):
        """Per node: w_J, the unit tangent τ_J, and Σ_e w_eJ (−n_e) (the
        nodal load of a unit pressure), over the group's edges oriented
        with the body on their left."""
        edges = self.group(name).copy()
        n = len(self.nodes)
        # Orient: the cell having the edge's ends lies on its left.
        corner = self.cells[:, :4]
        a, b = edges[:, 0], edges[:, 1]
        key = np.minimum(a, b) * n + np.maximum(a, b)
        ca, cb = corner, np.roll(corner, -1, 1)
        ckey = (np.minimum(ca, cb) * n + np.maximum(ca, cb)).ravel()
        sort = np.argsort(ckey)
        pos = np.searchsorted(ckey[sort], key)
        cell = sort[np.minimum(pos, len(ckey) - 1)] // 4
        if not (ckey[sort][np.minimum(pos, len(ckey) - 1)] == key).all():
            refuse(f"an edge of group {name!r} is no side of a cell")
        centre = self.nodes[corner[cell]].mean(1)
        pa, pb = self.nodes[a], self.nodes[b]
        d = pb - pa
        left = d[:, 0] * (centre[:, 1] - pa[:, 1]) - d[:, 1] * (centre[:, 0] - pa[:, 0])
        swap = left < 0
        edges[swap, 0], edges[swap, 1] = b[swap], a[swap]
        x = self.nodes[edges]
        if edges.shape[1] == 3:
            # Simpson on ξ = −1, 1, 0 (ends, then middle) times |x'(ξ_J)|.
            xa, xb, xm = x[:, 0], x[:, 1], x[:, 2]
            dxs = [-1.5 * xa - 0.5 * xb + 2 * xm, 0.5 * xa + 1.5 * xb - 2 * xm, 0.5 * (xb - xa)]
            we = np.stack([np.hypot(*dx.T) * r for dx, r in zip(dxs, (1 / 3, 1 / 3, 4 / 3))], 1)
            te = np.stack([dx / np.hypot(*dx.T)[:, None] for dx in dxs], 1)
        else:
            d = x[:, 1] - x[:, 0]
            length = np.hypot(*d.T)
            we = np.stack([length / 2, length / 2], 1)
            te = np.repeat((d / length[:, None])[:, None, :], 2, 1)
        w = np.zeros(n)
        tau = np.zeros((n, 2))
        load = np.zeros((n, 2))
        np.add.at(w, edges.ravel(), we.ravel())
        np.add.at(tau, edges.ravel(), te.reshape(-1, 2))
        # −n = (−τ_y, τ_x): a pressure pushes into the body.
        inward = np.stack([-te[..., 1], te[..., 0]], -1)
        np.add.at(load, edges.ravel(), (we[..., None] * inward).reshape(-1, 2))
        norm = np.hypot(*tau.T)
        tau[norm > 0] /= norm[norm > 0, None]
        return w, tau, load

    def record_steps(self):
        """The steps stickslip writes: 0, every, 2·every, … and the last."""
        steps = list(range(0, self.steps + 1, self.every))
        if steps[-1] != self.steps:
            steps.append(self.steps)
        return steps


class Results:
    """The peer's results file, written record by record (module doc)."""

    def __init__(self, path, scene, nodes=None, contact=None):
        """`nodes`, `contact`: the peer's own nodes (coordinates) and
        friction nodes (indices into them) where they are not the mesh's."""
        self.file = h5py.File(path, "w")
        self.file.attrs["program"] = os.path.basename(sys.argv[0])
        self.n_out = len(scene.record_steps())
        nodes = scene.nodes if nodes is None else nodes
        contact = scene.contact if contact is None else contact
        self.file["mesh/nodes"] = nodes
        self.file["contact/nodes"] = contact
        f, n, c = self.file, len(nodes), len(contact)
        self.time = f.create_dataset("time", (self.n_out,), dtype="f8")
        self.fields = [f.create_dataset(k, (self.n_out, n, 2), dtype="f8") for k in ("displacement", "velocity", "acceleration")]
        self.stress = f.create_dataset("contact/friction_stress", (self.n_out, c), dtype="f8")
        self.state = f.create_dataset("contact/state", (self.n_out, c), dtype="i1")
        self.k = 0

    def write(self, t, u, v, a, stress, state):
        """One record: u, v, a as [n_nodes, 2]; the contact fields."""
        self.time[self.k] = t
        for d, x in zip(self.fields, (u, v, a)):
            d[self.k] = x
        self.stress[self.k] = stress
        self.state[self.k] = state
        self.k += 1

    def close(self):
        self.file.attrs["complete"] = self.k == self.n_out
        self.file.close()
