#!/usr/bin/python3
"""Byte-level comparison of two capdem run files (tests/mpi, docs/mpi.md).

usage: same_bytes.py A.h5 B.h5 [--exclude PATH]... [--ignore-attr PATH@NAME]...

Every dataset of A must be in B and the other way round, with the same
shape, the same stored type and the same bytes (numpy's tobytes of the
values as stored: so -0.0 against +0.0 or two different NaNs count as
differences, which h5diff's value comparison lets pass); every attribute
the same bytes too, except the ones named with --ignore-attr (e.g. the
building commit, /h5md/creator@commit, when the two files come from two
builds).  Paths under an --exclude PATH are left out.  Exit 0 when equal,
1 with the differences listed (at most 20), 2 on bad usage.
"""
import sys

import h5py
import numpy as np


def walk(f, skip):
    """{path: object} of every group and dataset under f but skipped paths."""
    found = {"/": f}

    def visit(name, obj):
        path = "/" + name
        if not any(path == s or path.startswith(s + "/") for s in skip):
            found[path] = obj

    f.visititems(visit)
    return found


def raw(value):
    arr = np.asarray(value)
    return arr.dtype.str, arr.shape, arr.tobytes()


def compare(a_path, b_path, skip, ignore):
    diffs = []
    with h5py.File(a_path, "r") as a, h5py.File(b_path, "r") as b:
        oa, ob = walk(a, skip), walk(b, skip)
        for path in sorted(set(oa) ^ set(ob)):
            diffs.append(f"{path}: only in {'A' if path in oa else 'B'}")
        for path in sorted(set(oa) & set(ob)):
            x, y = oa[path], ob[path]
            if isinstance(x, h5py.Dataset) != isinstance(y, h5py.Dataset):
                diffs.append(f"{path}: a dataset in one file only")
                continue
            if isinstance(x, h5py.Dataset):
                if x.id.get_type() != y.id.get_type() and x.dtype != y.dtype:
                    diffs.append(f"{path}: stored types differ")
                elif x.shape != y.shape:
                    diffs.append(f"{path}: shapes {x.shape} and {y.shape}")
                elif raw(x[()]) != raw(y[()]):
                    diffs.append(f"{path}: bytes differ")
            names = set(x.attrs) | set(y.attrs)
            for name in sorted(names):
                if f"{path}@{name}" in ignore:
                    continue
                if name not in x.attrs or name not in y.attrs:
                    diffs.append(f"{path}@{name}: in one file only")
                elif raw(x.attrs[name]) != raw(y.attrs[name]):
                    diffs.append(f"{path}@{name}: bytes differ")
    return diffs


def main(argv):
    files, skip, ignore = [], [], set()
    it = iter(argv)
    for arg in it:
        if arg in ("--exclude", "--ignore-attr"):
            value = next(it, None)
            if value is None:
                print(f"same_bytes.py: {arg} needs a value", file=sys.stderr)
                return 2
            (skip.append(value.rstrip("/")) if arg == "--exclude" else ignore.add(value))
        else:
            files.append(arg)
    if len(files) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    diffs = compare(files[0], files[1], skip, ignore)
    for d in diffs[:20]:
        print(d)
    if len(diffs) > 20:
        print(f"... {len(diffs) - 20} more")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
