#!/usr/bin/python3
"""LIGGGHTS on a capdem sphere packing: the files it reads and one timed run.

    /usr/bin/python3 bench/liggghts/liggghts_bench.py RUN.h5 OUT   # writes OUT.data, OUT.material

convert() turns the last snapshot of a capdem run file (spheres only) into
a LIGGGHTS data file (atom_style granular; each sphere's type is its mass
bin, liggghts_law.py) and the law's property/global commands; run() runs
in.capdem.liggghts on it and returns the timed segments ("Loop time of"),
the neighbour-list builds of each and the mean contacts per sphere
(compute contact/atom) at the end.  bench/lammps/compare.py uses both.
"""
import json
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "lammps"))
import liggghts_law  # noqa: E402
import capdem_to_lammps  # noqa: E402


def convert(run, out_base, material=liggghts_law.MATERIAL):
    """Writes out_base.data and out_base.material; returns the metadata."""
    if any(run["prim_count"] != 1) or (abs(run["b"] - run["a"]).max() > 0):
        raise SystemExit("liggghts_bench: spheres only (LIGGGHTS has no spherocylinders)")
    first = run["prim_first"]
    spheres = [(2 * float(run["r"][first[p]]), float(run["mass"][p]), run["x"][p], run["v"][p], run["w"][p])
               for p in range(len(run["mass"]))]
    cfg = run["config"]
    W, T, H = (capdem_to_lammps.config_value(cfg, k) for k in ("width", "thickness", "height"))
    margin = 2 * max(s[0] for s in spheres)
    box = ((-margin, W + margin), (-margin, H + margin), (-margin, T + margin))
    meta = liggghts_law.write_inputs(spheres, box, out_base, material)
    meta.update(particles=len(spheres), width=W, height=H, thickness=T, dt=capdem_to_lammps.config_value(cfg, "dt"),
                min_diameter=min(s[0] for s in spheres), data=out_base + ".data", material=out_base + ".material")
    return meta


def run(meta, log, threads, nwarm=0, nsteps=0, nrepeat=0, gravity=490.5, contacts=None, yield_when_idle=True):
    """in.capdem.liggghts on meta's files; returns ([(loop s, steps, builds, CPU s
    of all ranks)] of the timed runs, mean contacts per sphere after the last
    run or None)."""
    var = {"data": meta["data"], "material": meta["material"], "walltype": meta["wall_type"],
           "W": meta["width"], "H": meta["height"], "T": meta["thickness"], "dt": meta["dt"], "g": gravity,
           "skin": 0.1 * meta["min_diameter"],  # capdem's automatic skin
           "dumpc": int(contacts is not None), "contacts": contacts or "none",
           "nwarm": nwarm, "nsteps": nsteps, "nrepeat": nrepeat,
           "stamp": os.path.join(HERE, "cpu_stamp.sh"), "stampfile": log + ".cpu"}
    if os.path.exists(var["stampfile"]):
        os.remove(var["stampfile"])
    text = liggghts_law.run_liggghts(var, log, ranks=threads, yield_when_idle=yield_when_idle)
    loops = [(float(t), int(s)) for t, s in re.findall(r"Loop time of ([0-9.eE+-]+) on \d+ procs for (\d+) steps", text)]
    builds = [int(b) for b in re.findall(r"Neighbor list builds = (\d+)", text)]
    # CPU seconds of each timed run: stamps alternate before / after; only rank 0
    # runs `shell`, so its time x ranks stands for all (as compare.py reads
    # LAMMPS's "% CPU use", also rank 0's)
    ticks = {}
    for line in open(var["stampfile"]) if nrepeat else []:
        pid, t = line.split()
        ticks.setdefault(pid, []).append(int(t))
    cpu = [threads / max(1, len(ticks)) * sum(v[2 * k + 1] - v[2 * k] for v in ticks.values()) / os.sysconf("SC_CLK_TCK")
           for k in range(nrepeat)]
    timed = [(t, s, b, c) for (t, s), b, c in zip(loops[-nrepeat:], builds[-nrepeat:], cpu)] if nrepeat else []
    rows = re.findall(r"^\s+\d+\s+\d+\s+([0-9.eE+-]+)\s*$", text, re.M)
    return timed, (float(rows[-1]) if rows else None)


def main():
    if len(sys.argv) != 3:
        raise SystemExit(__doc__.split("\n\n")[1])
    print(json.dumps(convert(capdem_to_lammps.read_run(sys.argv[1]), sys.argv[2])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
