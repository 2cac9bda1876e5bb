"""Reading a capdem run file (docs/output.md) from Python: the one way the
Python tools (host/, bench/, tests/fuzz) open one.

    import capdem_h5
    with capdem_h5.open_run("run.h5") as f:
        n = capdem_h5.snapshot_count(f)
        x = capdem_h5.column(f, "position", n - 1)     # (N, 3), m
        fn = capdem_h5.column(f, "pair_fn", n - 1)     # the contacts of that snapshot
        walls = capdem_h5.walls(f, n - 1)              # compound rows, member "type" a WALL_* kind

Where every dataset is, how each column of kernels/fields.def is stored,
the members of the wall compound and the wall kinds come from the block
generated from the C tables (kernels/runfile.def, kernels/fields.def), which
tests/unit/test_runfile_layout.c checks against them; the functions after it
are written by hand.  A tool outside host/ adds host/ to sys.path first.
Needs h5py and numpy (Debian: python3-h5py python3-numpy).
"""
import os

import h5py
import numpy as np

# ---- BEGIN GENERATED from kernels/runfile.def, fields.def and observables.def by tests/unit/test_runfile_layout.c
# (build/tests/test_runfile_layout --write host/capdem_h5.py); edit the tables, not this block.
# groups and datasets that are not columns: key -> absolute path
PATH = {
    "particles": "/particles/all",
    "prims": "/particles/prims",
    "contacts": "/contacts",
    "wall_contacts": "/wall_contacts",
    "walls": "/walls",
    "observables": "/observables",
    "shapes": "/parameters/shapes",
    "h5md": "/h5md",
    "resumes": "/parameters/resumes",
    "analysis": "/analysis",
    "visualization": "/visualization",
    "snap_step": "/walls/step",
    "snap_time": "/walls/time",
    "walls_value": "/walls/value",
    "control_value": "/walls/control",
    "c_offset": "/contacts/offset",
    "c_particle_i": "/contacts/particle_i",
    "c_particle_j": "/contacts/particle_j",
    "w_offset": "/wall_contacts/offset",
    "w_index": "/wall_contacts/index",
    "config": "/parameters/config",
}
# link and attribute names: key -> name
NAME = {
    "commit": "n_snapshots",
    "unit": "unit",
    "wall_units": "units",
    "shape_count": "count",
    "shape_kind": "kind",
    "shape_arms": "arms",
    "step": "step",
    "time": "time",
    "value": "value",
    "analysis_snapshot": "snapshot_",
    "journal": "-journal",
}
# columns of fields.def: name -> (dataset, storage, group, components, unit); storage "fixed":
# (rows, c) once, "series": (snapshots, rows, c), "rows": the active rows of every snapshot
COLUMN = {
    "position": ("/particles/all/position/value", "series", "particle", 3, "m"),
    "velocity": ("/particles/all/velocity/value", "series", "particle", 3, "m/s"),
    "orientation": ("/particles/all/orientation/value", "series", "particle", 4, "1"),
    "angmom": ("/particles/all/angmom/value", "series", "particle", 3, "kg m^2/s"),
    "angvel": ("/particles/all/angvel/value", "series", "particle", 3, "rad/s"),
    "mass": ("/particles/all/mass", "fixed", "particle", 1, "kg"),
    "prim_first": ("/particles/all/prim_first", "fixed", "particle", 1, "1"),
    "prim_count": ("/particles/all/prim_count", "fixed", "particle", 1, "1"),
    "prim_particle": ("/particles/prims/prim_particle", "fixed", "prim", 1, "1"),
    "prim_radius": ("/particles/prims/prim_radius", "fixed", "prim", 1, "m"),
    "prim_a": ("/particles/prims/prim_a/value", "series", "prim", 3, "m"),
    "prim_a_ref": ("/particles/prims/prim_a_ref/value", "series", "prim", 3, "m"),
    "pair_prim_i": ("/contacts/pair_prim_i", "rows", "pair", 1, "1"),
    "pair_prim_j": ("/contacts/pair_prim_j", "rows", "pair", 1, "1"),
    "pair_active": ("/contacts/pair_active", "rows", "pair", 1, "1"),
    "pair_shear": ("/contacts/pair_shear", "rows", "pair", 3, "m"),
    "pair_point": ("/contacts/pair_point", "rows", "pair", 3, "m"),
    "pair_force": ("/contacts/pair_force", "rows", "pair", 3, "N"),
    "pair_fn": ("/contacts/pair_fn", "rows", "pair", 1, "N"),
    "force": ("/particles/all/force/value", "series", "particle", 3, "N"),
    "torque": ("/particles/all/torque/value", "series", "particle", 3, "N m"),
    "inertia": ("/particles/all/inertia", "fixed", "particle", 3, "kg m^2"),
    "scale": ("/particles/all/scale", "fixed", "particle", 1, "1"),
    "shape": ("/particles/all/shape", "fixed", "particle", 1, "1"),
    "prim_a_body": ("/particles/prims/prim_a_body", "fixed", "prim", 3, "m"),
    "prim_b_body": ("/particles/prims/prim_b_body", "fixed", "prim", 3, "m"),
    "prim_b": ("/particles/prims/prim_b/value", "series", "prim", 3, "m"),
    "prim_b_ref": ("/particles/prims/prim_b_ref/value", "series", "prim", 3, "m"),
    "wallc_active": ("/wall_contacts/wallc_active", "rows", "wallc", 1, "1"),
    "wallc_shear": ("/wall_contacts/wallc_shear", "rows", "wallc", 3, "m"),
    "wallc_force": ("/wall_contacts/wallc_force", "rows", "wallc", 3, "N"),
    "wallc_torque": ("/wall_contacts/wallc_torque", "rows", "wallc", 3, "N m"),
    "wallc_overlap": ("/wall_contacts/wallc_overlap", "rows", "wallc", 1, "m"),
    "wallc_fn": ("/wall_contacts/wallc_fn", "rows", "wallc", 1, "N"),
    "pair_normal": ("/contacts/pair_normal", "rows", "pair_out", 3, "1"),
    "pair_ft": ("/contacts/pair_ft", "rows", "pair_out", 3, "N"),
    "pair_torque_i": ("/contacts/pair_torque_i", "rows", "pair_out", 3, "N m"),
    "pair_torque_j": ("/contacts/pair_torque_j", "rows", "pair_out", 3, "N m"),
    "pair_overlap": ("/contacts/pair_overlap", "rows", "pair_out", 1, "m"),
}
# members of the compound /walls/value: (name, type, components, unit)
WALL_MEMBERS = (
    ("type", "int32", 1, "1"),
    ("point", "float64", 3, "m"),
    ("normal", "float64", 3, "1"),
    ("velocity", "float64", 3, "m/s"),
    ("radius", "float64", 1, "m"),
    ("radial_velocity", "float64", 1, "m/s"),
    ("friction", "float64", 1, "1"),
)
# wall kinds: the member type of /walls/value
WALL_PLANE = 0
WALL_CYLINDER = 1
WALL_SPHERE = 2
WALL_KIND_NAME = {
    0: "plane",
    1: "cylinder",
    2: "sphere",
}
# time series of a DEM run, /observables/<name>: name -> (unit, components per row, meaning);
# W: the number of walls
OBSERVABLES = {
    "kinetic_energy_translational": ("J", "1", "translational kinetic energy, sum of m v^2 / 2"),
    "kinetic_energy_rotational": ("J", "1", "rotational kinetic energy, sum of L . omega / 2"),
    "kinetic_energy_in_contact": ("J", "1", "kinetic energy of the particles that touch something (rattlers left out)"),
    "elastic_energy": ("J", "1", "energy stored in the normal and tangential springs of every contact"),
    "potential_energy": ("J", "1", "gravitational potential energy, -sum of m g . x"),
    "contacts": ("1", "1", "active particle-particle contacts (primitive pairs)"),
    "wall_contacts": ("1", "1", "active primitive-wall contacts"),
    "momentum": ("kg m/s", "3", "total linear momentum"),
    "wall_force": ("N", "3 W", "force of the particles on each wall"),
    "wall_position": ("m", "3 W", "reference point of each wall"),
    "wall_radius": ("m", "W", "radius of each wall (0 for a plane)"),
    "packing_fraction": ("1", "1", "solid volume over the container's (up to the piston, or the ball); 0 without a container"),
    "coordination": ("1", "1", "2 contacts / particles, rattlers included"),
    "phase": ("1", "1", "protocol phase (docs/protocols.md)"),
    "wall_load": ("N", "1", "load on the protocol's driven wall at the last control"),
    "pressure": ("Pa", "1", "ball: wall load over the ball's area; else 0"),
}
# ---- END GENERATED


class LayoutError(Exception):
    """The file lacks a dataset of the layout (not a capdem run file, or too old)."""


def open_run(path, locking=None):
    """The run file at path, open read-only: an h5py.File, to be used in a
    with block.  locking: h5py's file locking (None: HDF5's default; False
    reads a file a running capdem is writing).  A commit journal that is not
    empty beside the file (a capdem killed while committing, or a commit
    under way) means the file alone may not be a commit: LayoutError, naming
    `capdem recover` (docs/output.md, "Crash safety")."""
    journal = path + NAME["journal"]
    if os.path.exists(journal) and os.path.getsize(journal) > 0:
        raise LayoutError("%s: %s is not empty (a capdem killed while committing, or a commit under way): "
                          "run `capdem recover %s` first, or read it again" % (path, journal, path))
    if locking is None:
        return h5py.File(path, "r")
    return h5py.File(path, "r", locking=locking)


def dataset(f, key):
    """The dataset (or group) PATH[key]; LayoutError when the file lacks it."""
    path = PATH[key]
    if path not in f:
        raise LayoutError("%s: not a capdem run file (no %s)" % (f.filename, path))
    return f[path]


def snapshot_count(f):
    """Snapshots completely on disk, as the C readers count them
    (src/io/io_h5_layout.c, cdh5_committed): the commit record n_snapshots,
    bounded by the rows of the snapshot clock and offsets; 0 before the
    first snapshot."""
    if PATH["snap_step"] not in f:
        return 0
    n = min(len(dataset(f, "snap_step")), len(dataset(f, "snap_time")),
            max(len(dataset(f, "c_offset")) - 1, 0), max(len(dataset(f, "w_offset")) - 1, 0))
    if NAME["commit"] in f.attrs:
        c = int(f.attrs[NAME["commit"]])
        if 0 <= c < n:
            n = c
    return n


def has_column(f, name):
    """Does the file hold column `name` of fields.def?"""
    return name in COLUMN and COLUMN[name][0] in f


def column_dataset(f, name):
    """The dataset that holds column `name` (shape: see COLUMN)."""
    path = COLUMN[name][0]
    if path not in f:
        raise LayoutError("%s: no column %s (%s)" % (f.filename, name, path))
    return f[path]


def rows(f, k, wall=False):
    """(first, end) rows of snapshot k in the concatenated contact rows
    (wall=True: the wall-contact rows)."""
    off = dataset(f, "w_offset" if wall else "c_offset")
    a, b = (int(v) for v in off[k:k + 2])
    return a, b


def column(f, name, k=None):
    """Column `name` of fields.def at snapshot k (negative: from the end of
    the committed snapshots) as a numpy array: a fixed column whole (k
    unused), a time series' row of snapshot k, the contact (or wall-contact)
    rows of snapshot k."""
    path, storage, group = COLUMN[name][:3]
    d = column_dataset(f, name)
    if storage == "fixed":
        return np.asarray(d[()])
    if k is None:
        raise ValueError("column %s is stored per snapshot: give a snapshot" % name)
    if k < 0:
        k += snapshot_count(f)
    if storage == "series":
        return np.asarray(d[k])
    a, b = rows(f, k, wall=group == "wallc")
    return np.asarray(d[a:b])


def snapshot_rows(f, key, k):
    """The contact rows of snapshot k of a dataset that is not a column
    (PATH["c_particle_i"], PATH["c_particle_j"], PATH["w_index"])."""
    a, b = rows(f, k, wall=key.startswith("w_"))
    return np.asarray(dataset(f, key)[a:b])


def step(f, k):
    """Step of snapshot k."""
    return int(dataset(f, "snap_step")[k])


def time(f, k):
    """Time of snapshot k, s."""
    return float(dataset(f, "snap_time")[k])


def walls(f, k):
    """The walls of snapshot k (a numpy record array, WALL_MEMBERS), or None
    when the file has none."""
    if PATH["walls_value"] not in f:
        return None
    return dataset(f, "walls_value")[k]


def config_text(f):
    """The config the run started with, verbatim."""
    text = dataset(f, "config")[()]
    return text.decode() if isinstance(text, bytes) else str(text)


def observable(f, name):
    """(step, time, value) arrays of the time series /observables/<name>
    (a DEM run's: the keys of OBSERVABLES)."""
    g = dataset(f, "observables")
    if name not in g:
        known = "" if name in OBSERVABLES else " (not one of the OBSERVABLES of kernels/observables.def either)"
        raise LayoutError("%s: no observable %s%s" % (f.filename, name, known))
    s = g[name]
    return s[NAME["step"]][:], s[NAME["time"]][:], s[NAME["value"]][:]


def analysis(f):
    """The /analysis group `capdem analyze` writes (docs/analysis.md), or None."""
    return f[PATH["analysis"]] if PATH["analysis"] in f else None
