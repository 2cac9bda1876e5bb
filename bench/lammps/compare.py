#!/usr/bin/python3
"""capdem against LAMMPS on the same work, same machine, same cores, same N.

    /usr/bin/python3 bench/lammps/compare.py [--build build] [--cases spheres:1000,hexapods_a3:1000:100]
        [--threads 2] [--steps 1000] [--repeat 3] [--work build/bench-work] [--reuse]

For each case:N[:LAMMPS_STEPS], in one invocation (LAMMPS_STEPS: the
length of LAMMPS's timed segments, default --steps; shorter ones for the
hexapods keep the two segments of a pair about as long, so that they see the
same load):
  spheres      capdem-bench writes the initial lattice deposit (seed, N) and
               settles it under 50 g; LAMMPS reads the same initial state
               (capdem_to_lammps.py) and settles it for the same number of
               steps with the same law (lammps_law.py), walls, gravity and
               dt.  Each code then times `--steps` steps `--repeat` times on
               its own settled packing, still under 50 g.
  hexapods_aX  capdem-bench settles N hexapods; LAMMPS reads that settled
               packing as rigid clusters of glued spheres (fix rigid/small
               molecule, spheres <= d/2 apart along each arm), steps 500
               untimed steps to let the clusters find their contacts, then
               is timed the same way.  Settling the clusters from scratch in
               LAMMPS would cost ~10 x the timed segment and time nothing new.
capdem runs with --threads T (OpenMP), LAMMPS with `mpirun -np T` (the
Debian package has no OPENMP package; MPI is its parallel mode here).  Only
the stepping is timed: capdem-bench's timed segment, LAMMPS's "Loop time of"
of each timed `run`.  Throughput counts particles (a hexapod is one particle
in both codes, 13 or 49 LAMMPS atoms).  Prints one JSON line per case and
a table; the ratio is capdem / LAMMPS of wall-clock throughput, taken per
pair of segments (median and range over pairs).  The JSON lines also give
the ratio of particle-steps per CPU second (capdem: the process's CPU time;
LAMMPS: loop time x "% CPU use" x ranks), which other jobs on a shared
machine disturb much less; with 2 ranks LAMMPS's CPU time includes MPI's
busy waiting, so that ratio is clean with --threads 1 only.

Installs LAMMPS (Debian package `lammps`) with apt-get if `lmp` is missing.
"""
import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import lammps_law  # noqa: E402
import capdem_to_lammps  # noqa: E402

MATERIAL = dict(kn=1e5, kt=5e4, eta_n=0.2, eta_t=0.2, mu=0.5)  # SPEC 3; walls frictionless
SETTLE = {"spheres": 30000, "hexapods_a3": 15000, "hexapods_a9": 15000}


def ensure_lammps():
    if shutil.which("lmp"):
        return
    print("compare: lmp not found; installing Debian's lammps package", file=sys.stderr)
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    sudo = [] if os.geteuid() == 0 else ["sudo"]
    subprocess.run(sudo + ["apt-get", "update"], check=True, env=env)
    subprocess.run(sudo + ["apt-get", "install", "-y", "--no-install-recommends", "lammps", "openmpi-bin"], check=True, env=env)


def lammps_version():
    out = subprocess.run(["lmp", "-h"], capture_output=True, text=True).stdout
    m = re.search(r"Large-scale Atomic/Molecular Massively Parallel Simulator - (.*)", out)
    return m.group(1).strip() if m else "unknown"


def capdem_bench(args, extra):
    cmd = [os.path.join(args.build, "capdem-bench"), "--threads", str(args.threads)] + extra
    env = dict(os.environ, OMP_WAIT_POLICY="PASSIVE")
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode:
        raise SystemExit("compare: %s failed (%d): %s" % (" ".join(cmd), p.returncode, p.stderr))
    return [json.loads(l) for l in p.stdout.splitlines() if l.startswith("{")]


def run_lammps(args, data, meta, log, nsettle, nwarm, contacts=None, nsteps=None, nrepeat=None, write_data=None,
               law=None):
    """Runs in.capdem.lmp; returns [(loop seconds, steps)] of the timed runs
    and the mean contacts per atom at the end (compute contact/atom).  law:
    LAMMPS constants (lammps_law.py); default those of MATERIAL."""
    c = law or lammps_law.lammps_constants(**MATERIAL)
    var = {
        "astyle": "hybrid sphere molecular" if meta["rigid"] else "sphere",
        "data": data, "rigid": int(meta["rigid"]),
        "model": lammps_law.pair_coeff_args(c), "wallmodel": lammps_law.pair_coeff_args(c, mu=0.0),
        "W": meta["width"], "H": meta["height"], "T": meta["thickness"], "dt": meta["dt"], "g": 490.5,
        "skin": 0.1 * meta["min_diameter"],  # capdem's automatic skin
        "commcut": meta["max_body_extent"] + 0.1 * meta["min_diameter"] + 1e-4,
        "nsettle": nsettle, "dumpc": int(contacts is not None), "contacts": contacts or "none",
        "writedata": int(write_data is not None), "settled": write_data or "none",
        "nwarm": nwarm, "nsteps": args.steps if nsteps is None else nsteps,
        "nrepeat": args.repeat if nrepeat is None else nrepeat,
    }
    # ranks yield the core while they wait (as capdem runs with OMP_WAIT_POLICY=PASSIVE): on a
    # shared, oversubscribed machine a spinning rank starves the one it waits for
    cmd = ["mpirun", "--allow-run-as-root", "--mca", "mpi_yield_when_idle", "1", "-np", str(args.threads), "lmp", "-in", os.path.join(HERE, "in.capdem.lmp"),
           "-log", log, "-screen", "none"]
    for k, v in var.items():
        cmd += ["-var", k, str(v)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode:
        raise SystemExit("compare: LAMMPS failed (%d), see %s: %s" % (p.returncode, log, p.stdout[-2000:] + p.stderr[-2000:]))
    text = open(log).read()
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms\s+"
                       r"(?:Performance:[^\n]*\n)?\s*([0-9.]+)% CPU use", text)
    # (loop wall seconds, steps, CPU seconds of all ranks = wall x CPU use x ranks)
    timed = [(float(t), int(s), float(t) * float(pct) / 100 * int(np_)) for t, np_, s, _, pct in loops
             if int(s) == var["nsteps"]][-var["nrepeat"]:] if var["nrepeat"] else []
    rows = re.findall(r"^\s+\d+\s+\d+\s+[0-9.eE+-]+\s+([0-9.eE+-]+)\s*$", text, re.M)
    return timed, (float(rows[-1]) if rows else None)


def one_case(args, case, n, lammps_steps):
    """Settles once, then alternates capdem and LAMMPS timed segments
    (--repeat pairs): a load that drifts on the shared machine hits both
    codes of a pair alike, and each pair gives one ratio."""
    w = os.path.join(args.work, "%s_%d" % (case, n))
    settled = w + "_capdem.h5"
    common = ["--case", case, "--n", str(n), "--friction-limit", "total", "--gravity", "490.5", "--seed", str(args.seed)]
    if not (args.reuse and os.path.exists(settled)):
        capdem_bench(args, common + ["--settle-steps", str(SETTLE[case]), "--repeat", "0", "--save-settled", settled])
    if case == "spheres":
        # LAMMPS settles the same initial state itself and times its own packing
        init, data = w + "_init.h5", w + "_lammps_settled.data"
        if not (args.reuse and os.path.exists(data)):
            capdem_bench(args, common + ["--settle-steps", "0", "--repeat", "0", "--save-settled", init])
            meta = capdem_to_lammps.convert(capdem_to_lammps.read_run(init), w + "_init.data")
            run_lammps(args, w + "_init.data", meta, w + "_settle.lammps.log", SETTLE[case], 0, nrepeat=0,
                       write_data=data)
        meta = capdem_to_lammps.convert(capdem_to_lammps.read_run(init if os.path.exists(init) else settled), os.devnull)
        nwarm = 200  # write_data keeps no tangential history: let the springs build up again
    else:
        # LAMMPS times capdem's settled packing as glued-sphere clusters
        data = w + ".data"
        meta = capdem_to_lammps.convert(capdem_to_lammps.read_run(settled), data)
        nwarm = 200
    capdem, lammps, ratios, cpu_ratios, z_lammps = [], [], [], [], None
    for r in range(args.repeat):
        c = capdem_bench(args, ["--load-settled", settled, "--gravity", "490.5", "--steps", str(args.steps), "--repeat", "1"])[0]
        timed, z_lammps = run_lammps(args, data, meta, w + ".lammps.log", 0, nwarm, nsteps=lammps_steps, nrepeat=1)
        l_rate = n * timed[0][1] / timed[0][0]
        capdem.append(c)
        lammps.append(l_rate)
        ratios.append(c["particle_steps_per_s"] / l_rate)
        # per CPU second: n steps / cpu_s, both codes
        cpu_ratios.append((n * c["steps"] / c["cpu_s"]) / (n * timed[0][1] / timed[0][2]))
    c_rates = [c["particle_steps_per_s"] for c in capdem]
    return {
        "case": case, "N": n, "threads": args.threads, "steps": args.steps, "lammps_steps": lammps_steps,
        "pairs": args.repeat,
        "capdem_particle_steps_per_s": statistics.median(c_rates), "capdem_repeats": c_rates,
        "capdem_contacts_per_particle": capdem[-1]["contacts_per_particle"],
        "lammps_particle_steps_per_s": statistics.median(lammps), "lammps_repeats": lammps,
        "lammps_contacts_per_atom": z_lammps if case == "spheres" else None,
        "lammps_atoms": meta["atoms"], "lammps_atom_steps_per_s": statistics.median(lammps) * meta["spheres_per_particle"],
        "ratio_capdem_over_lammps": statistics.median(ratios), "ratios": ratios,
        "cpu_ratio_capdem_over_lammps": statistics.median(cpu_ratios), "cpu_ratios": cpu_ratios,
        "lammps_packing": "its own, settled from capdem's initial lattice" if case == "spheres" else "capdem's settled packing",
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--cases", default="spheres:1000,hexapods_a3:1000,hexapods_a9:1000")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--work", default="build/bench-work")
    ap.add_argument("--reuse", action="store_true", help="time capdem on a settled packing left by an earlier run")
    args = ap.parse_args()
    ensure_lammps()
    os.makedirs(args.work, exist_ok=True)
    version = lammps_version()
    rows = []
    for item in args.cases.split(","):
        case, n, *ls = item.split(":")
        if case not in SETTLE:
            raise SystemExit("compare: case %s: expected one of %s (crosses2d has no LAMMPS twin)" % (case, ", ".join(SETTLE)))
        r = one_case(args, case, int(float(n)), int(ls[0]) if ls else args.steps)
        r["lammps_version"] = version
        print(json.dumps(r), flush=True)
        rows.append(r)
    print("\n| case | N | threads | capdem p-steps/s | LAMMPS p-steps/s | capdem / LAMMPS wall (median, range) "
          "| capdem / LAMMPS per CPU s (median, range) |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print("| %s | %d | %d | %.3g | %.3g | %.2f (%.2f-%.2f) | %.2f (%.2f-%.2f) |" % (
            r["case"], r["N"], r["threads"], r["capdem_particle_steps_per_s"], r["lammps_particle_steps_per_s"],
            r["ratio_capdem_over_lammps"], min(r["ratios"]), max(r["ratios"]),
            r["cpu_ratio_capdem_over_lammps"], min(r["cpu_ratios"]), max(r["cpu_ratios"])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
