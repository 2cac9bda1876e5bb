#!/usr/bin/python3
"""Rewrites a run file with chunks no larger than its data, for the seed
corpus of fuzz_runfile (tests/fuzz/make_seeds.sh): capdem's chunks are made
for long runs (a 6-particle run file is 3 MB, mostly empty chunks), and a
fuzzer mutates every byte of an input it is given.  Everything else is
kept: groups, datasets with their types, shapes, maximum shapes and
Fletcher-32 checksums, attributes.
usage: shrink_run.py IN.h5 OUT.h5 [LIBVER]  (LIBVER: earliest, the default, or latest:
the newer, smaller object headers and chunk indexes)"""
import os
import sys

import h5py

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "host"))  # capdem_h5
import capdem_h5  # noqa: E402

LIBVER = sys.argv[3] if len(sys.argv) > 3 else "earliest"


def copy_attrs(src, dst):
    for k, v in src.attrs.items():
        dst.attrs.create(k, v, dtype=src.attrs.get_id(k).dtype)


def copy(src, dst):
    copy_attrs(src, dst)
    for name, obj in src.items():
        if isinstance(obj, h5py.Group):
            copy(obj, dst.create_group(name))
        elif obj.chunks is None:
            d = dst.create_dataset(name, data=obj[()], dtype=obj.dtype)
            copy_attrs(obj, d)
        else:
            # one row per chunk along the growing axis, whole rows across
            chunks = tuple([1] + [max(1, n) for n in obj.shape[1:]])
            d = dst.create_dataset(name, shape=obj.shape, maxshape=obj.maxshape, dtype=obj.dtype, chunks=chunks,
                                   fletcher32=obj.fletcher32)
            if obj.size:
                d[...] = obj[...]
            copy_attrs(obj, d)


with capdem_h5.open_run(sys.argv[1]) as src, h5py.File(sys.argv[2], "w", libver=LIBVER) as dst:
    copy(src, dst)
