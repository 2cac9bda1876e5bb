#!/usr/bin/python3
"""capdem against LAMMPS (and LIGGGHTS for spheres) on the same work, same machine, same cores, same N.

    /usr/bin/python3 bench/lammps/compare.py [--build build] [--cases spheres:1000,hexapods_a3:1000:100]
        [--peers lammps,liggghts] [--threads 2] [--steps 1000] [--repeat 3] [--peer-warm 200]
        [--relax-steps 200] [--work build/bench-work] [--reuse] [--baseline OTHER_BUILD]
        [--sphere-orientation integrate[,fixed]] [--omp-wait-policy default|passive|active]

For each case:N[:PEER_STEPS][@KXxKZ], in one invocation (PEER_STEPS: the
length of the peers' timed segments, default --steps; shorter ones for the
hexapods keep the segments of a round about as long, so that they see the
same load; @KXxKZ: the settled packing of N particles tiled KX x KZ times,
capdem-bench --tile, relaxed by capdem (--relax-steps; default 20 ms spheres, 200 ms hexapods) and saved, and that one
packing timed by every code):
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
  LIGGGHTS     (spheres only, bench/liggghts/) reads capdem's settled (or
               tiled) packing with `gran model hooke/stiffness tangential
               history` and capdem's law (liggghts_law.py), steps --peer-warm
               untimed steps, then is timed like LAMMPS.
Every code uses capdem's automatic skin, 0.1 x the smallest diameter, and
rebuilds its list when a particle has moved half of it; the JSON lines give
the rebuilds of each timed segment (`*_neighbor_builds`).
capdem runs with --threads T (OpenMP), LAMMPS and LIGGGHTS with `mpirun -np T` (the
Debian package has no OPENMP package; MPI is its parallel mode here).  Only
the stepping is timed: capdem-bench's timed segment, LAMMPS's "Loop time of"
of each timed `run`.  Throughput counts particles (a hexapod is one particle
in both codes, 13 or 49 LAMMPS atoms).  Prints one JSON line per case and
a table; the ratio is capdem / LAMMPS of wall-clock throughput, taken per
pair of segments (median and range over pairs).  The JSON lines also give
the ratio of particle-steps per CPU second (capdem: the process's CPU time;
LAMMPS: loop time x "% CPU use" x ranks; LIGGGHTS: rank 0's CPU time
around the timed run, cpu_stamp.sh, x ranks), which other jobs on a shared
machine disturb much less; with 2 ranks LAMMPS's CPU time includes MPI's
busy waiting, so that ratio is clean with --threads 1 only.

--repeat 0 settles (tiles, converts) each case's packings and times
nothing: a long settle made ahead (while the machine is busy), and the
timing later with --reuse on the same --work folder.

--baseline OTHER_BUILD times that build's capdem-bench too, right after
capdem in every round on the same packing (a change measured against the
build before it, beside the peers; the table's last row per case).

--sphere-orientation integrate,fixed times capdem on a sphere case once per
value in every round: integrate (capdem's default: every sphere's
orientation is integrated, as it is output) and fixed
(physics.sphere_orientation: fixed: spheres keep their orientation, as
LAMMPS's and LIGGGHTS's nve/sphere, which have none); the first value gives
the `capdem_*` and `ratio_*` keys, the others `capdem_fixed_*` and
`ratio_fixed_*` keys and rows of their own.  Hexapods ignore it.

--omp-wait-policy: what capdem's idle OpenMP threads do at a barrier.
default leaves OMP_WAIT_POLICY unset (libgomp spins a while, then
sleeps: what a user gets), as the peers' MPI ranks poll while they wait
(mpi_yield_when_idle yields the core between polls but never sleeps);
passive (the setting until session 20) sleeps at once, which on a shared,
oversubscribed machine keeps a waiting thread from starving the one it
waits for, and on a quiet machine costs two threads about 1/8 of a sphere
step's time (docs/performance.md, "Session 20").

Installs LAMMPS (Debian package `lammps`) with apt-get if `lmp` is missing,
and LIGGGHTS (`liggghts`) if `liggghts` is missing and a sphere case asks for it.
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
sys.path.insert(0, os.path.join(HERE, "..", "liggghts"))
import liggghts_bench  # noqa: E402
import liggghts_law  # noqa: E402

MATERIAL = dict(kn=1e5, kt=5e4, eta_n=0.2, eta_t=0.2, mu=0.5)  # docs/references.md, Contact law; walls frictionless
SETTLE = {"spheres": 30000, "hexapods_a3": 15000, "hexapods_a9": 15000}
# A tiled packing has lost its tangential springs (bench_tile.c): it slips and
# springs back, and needs about 20 ms to find its contacts again (spheres: Z
# 4.46 settled, 3.5 after 0.6 ms, 4.50 after 20 ms; hexapods 7.54, 7.12, 7.48).
# Hexapod tiles relax 200 ms: before session 18's fix of --tile (its copies
# had other particles' arm lengths and flew apart) they still flowed after
# 20 ms; fixed, alpha-3 tiles of 1e4-1e5 came to rest (no list build in a
# 200-step probe) after 40-80 ms (bench/ladder.py's records); 200 ms leaves
# room for alpha 9 (docs/performance.md, "Session 18, cost against N").
RELAX = {"spheres": 10000, "hexapods_a3": 20000, "hexapods_a9": 20000}  # steps: 20 ms (dt 2e-6 s), 200 ms (1e-5 s)


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


def capdem_bench(args, extra, build=None):
    cmd = [os.path.join(build or args.build, "capdem-bench"), "--threads", str(args.threads)] + extra
    env = dict(os.environ)
    env.pop("OMP_WAIT_POLICY", None)
    if args.omp_wait_policy != "default":
        env["OMP_WAIT_POLICY"] = args.omp_wait_policy.upper()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode:
        raise SystemExit("compare: %s failed (%d): %s" % (" ".join(cmd), p.returncode, p.stderr))
    return [json.loads(l) for l in p.stdout.splitlines() if l.startswith("{")]


def run_lammps(args, data, meta, log, nsettle, nwarm, contacts=None, nsteps=None, nrepeat=None, write_data=None,
               law=None):
    """Runs in.capdem.lmp; returns [(loop seconds, steps, CPU seconds, list builds)] of the timed runs
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
    # ranks yield the core between polls while they wait: on a shared, oversubscribed machine a
    # spinning rank starves the one it waits for (capdem: --omp-wait-policy)
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
    builds = [int(b) for b in re.findall(r"Neighbor list builds = (\d+)", text)]  # one per run, as the loops
    timed = [(float(t), int(s), float(t) * float(pct) / 100 * int(np_), b) for (t, np_, s, _, pct), b in zip(loops, builds)
             if int(s) == var["nsteps"]][-var["nrepeat"]:] if var["nrepeat"] else []
    rows = re.findall(r"^\s+\d+\s+\d+\s+[0-9.eE+-]+\s+([0-9.eE+-]+)\s*$", text, re.M)
    return timed, (float(rows[-1]) if rows else None)


def one_case(args, case, n, lammps_steps, tile=(1, 1)):
    """Settles once, then alternates capdem and its peers' timed segments
    (--repeat rounds: capdem, LAMMPS, LIGGGHTS, capdem, ...): a load that
    drifts on the shared machine hits every code of a round alike, and each
    round gives one ratio per peer.  With tile (KX, KZ) != (1, 1) the settled
    packing of n particles is tiled (capdem-bench --tile), relaxed for
    --relax-steps and saved, and every code times that one packing."""
    w = os.path.join(args.work, "%s_%d" % (case, n))
    settled = w + "_capdem.h5"
    common = ["--case", case, "--n", str(n), "--friction-limit", "total", "--gravity", "490.5", "--seed", str(args.seed)]
    if not (args.reuse and os.path.exists(settled)):
        capdem_bench(args, common + ["--settle-steps", str(SETTLE[case]), "--repeat", "0", "--save-settled", settled])
    tiled = tile != (1, 1)
    if tiled:
        w += "_tile%dx%d" % tile
        if not (args.reuse and os.path.exists(w + "_capdem.h5")):
            capdem_bench(args, ["--load-settled", settled, "--tile", "%d,%d" % tile, "--relax-steps",
                                str(RELAX[case] if args.relax_steps is None else args.relax_steps),
                                "--repeat", "0", "--save-settled", w + "_capdem.h5"])
        settled = w + "_capdem.h5"
    if case == "spheres" and not tiled:
        # LAMMPS settles the same initial state itself and times its own packing
        init, data = w + "_init.h5", w + "_lammps_settled.data"
        if not (args.reuse and os.path.exists(data)):
            capdem_bench(args, common + ["--settle-steps", "0", "--repeat", "0", "--save-settled", init])
            meta = capdem_to_lammps.convert(capdem_to_lammps.read_run(init), w + "_init.data")
            run_lammps(args, w + "_init.data", meta, w + "_settle.lammps.log", SETTLE[case], 0, nrepeat=0,
                       write_data=data)
        meta = capdem_to_lammps.convert(capdem_to_lammps.read_run(init if os.path.exists(init) else settled), os.devnull)
    else:
        # LAMMPS times capdem's settled packing (as glued-sphere clusters for hexapods)
        data = w + ".data"
        meta = capdem_to_lammps.convert(capdem_to_lammps.read_run(settled), data)
    nwarm = args.peer_warm  # a data file keeps no tangential history: let the springs build up again
    peers = [p for p in args.peers.split(",") if p and (p == "lammps" or case == "spheres")]
    lig_meta = liggghts_bench.convert(capdem_to_lammps.read_run(settled), w + "_liggghts") if "liggghts" in peers else None
    if args.repeat == 0:  # prepared only, for a later --reuse
        return {"case": case, "settled_N": n, "tile": "%dx%d" % tile, "prepared": settled}
    base_rates, base_ratios, base_cpu = [], [], []
    capdem, rates, ratios, builds, cpu_ratios, lig_cpu, z = [], {p: [] for p in peers}, {p: [] for p in peers}, {p: [] for p in peers}, [], [], {}
    # the other sphere orientations: [(value, capdem rows)]
    orient = args.sphere_orientation.split(",") if case == "spheres" else ["integrate"]
    others = [(o, []) for o in orient[1:]]
    timed_args = ["--load-settled", settled, "--gravity", "490.5", "--steps", str(args.steps), "--repeat", "1"]
    for r in range(args.repeat):
        c = capdem_bench(args, timed_args + (["--sphere-orientation", orient[0]] if orient[0] != "integrate" else []))[0]
        capdem.append(c)
        for o, rows in others:
            rows.append(capdem_bench(args, timed_args + ["--sphere-orientation", o])[0])
        if args.baseline:
            # another capdem build, timed in the same round on the same packing (capdem now / baseline)
            b0 = capdem_bench(args, ["--load-settled", settled, "--gravity", "490.5", "--steps", str(args.steps),
                                     "--repeat", "1"], build=args.baseline)[0]
            base_rates.append(b0["particle_steps_per_s"])
            base_ratios.append(c["particle_steps_per_s"] / b0["particle_steps_per_s"])
            base_cpu.append(b0["cpu_s"] / c["cpu_s"])
        for peer in peers:
            if peer == "lammps":
                timed, z[peer] = run_lammps(args, data, meta, w + ".lammps.log", 0, nwarm, nsteps=lammps_steps, nrepeat=1)
                # per CPU second: n steps / cpu_s, both codes
                cpu_ratios.append((n * c["steps"] / c["cpu_s"]) / (n * timed[0][1] / timed[0][2]))
                b = timed[0][3]
            else:
                timed, z[peer] = liggghts_bench.run(lig_meta, w + ".liggghts.log", args.threads, nwarm, lammps_steps, 1)
                b = timed[0][2]
                lig_cpu.append((n * c["steps"] / c["cpu_s"]) / (n * timed[0][1] / timed[0][3]))
            rate = c["N"] * timed[0][1] / timed[0][0]
            rates[peer].append(rate)
            ratios[peer].append(c["particle_steps_per_s"] / rate)
            builds[peer].append(b)
    c_rates = [c["particle_steps_per_s"] for c in capdem]
    out = {
        "case": case, "N": capdem[-1]["N"], "settled_N": n, "tile": "%dx%d" % tile, "threads": args.threads,
        "steps": args.steps, "lammps_steps": lammps_steps, "pairs": args.repeat,
        "skin_m": 0.1 * meta["min_diameter"],
        "capdem_particle_steps_per_s": statistics.median(c_rates), "capdem_repeats": c_rates,
        "capdem_contacts_per_particle": capdem[-1]["contacts_per_particle"],
        "capdem_neighbor_builds": [c["neighbor_builds_timed"] for c in capdem],
        "packing": ("LAMMPS: its own, settled from capdem's initial lattice; LIGGGHTS: capdem's" if case == "spheres" and not tiled
                    else "capdem's settled packing" + (", tiled and relaxed" if tiled else "")),
    }
    if orient[0] != "integrate":
        out["capdem_sphere_orientation"] = orient[0]
    for o, rows in others:
        o_rates = [x["particle_steps_per_s"] for x in rows]
        out.update({"capdem_%s_particle_steps_per_s" % o: statistics.median(o_rates), "capdem_%s_repeats" % o: o_rates,
                    "capdem_%s_neighbor_builds" % o: [x["neighbor_builds_timed"] for x in rows]})
        for peer in peers:
            q = [x / p_ for x, p_ in zip(o_rates, rates[peer])]
            out.update({"ratio_capdem_%s_over_%s" % (o, peer): statistics.median(q), "ratios_%s_%s" % (o, peer): q})
    if args.baseline:
        out.update(baseline_build=args.baseline, baseline_particle_steps_per_s=statistics.median(base_rates),
                   baseline_repeats=base_rates, ratio_capdem_over_baseline=statistics.median(base_ratios),
                   ratios_baseline=base_ratios, cpu_ratio_capdem_over_baseline=statistics.median(base_cpu),
                   cpu_ratios_baseline=base_cpu)
    for peer in peers:
        out.update({
            peer + "_particle_steps_per_s": statistics.median(rates[peer]), peer + "_repeats": rates[peer],
            peer + "_neighbor_builds": builds[peer], peer + "_contacts_per_atom": z[peer] if case == "spheres" else None,
            "ratio_capdem_over_" + peer: statistics.median(ratios[peer]), "ratios_" + peer: ratios[peer],
        })
    if "lammps" in peers:
        out.update({
            "ratios": ratios["lammps"], "ratio_capdem_over_lammps": statistics.median(ratios["lammps"]),
            "lammps_atoms": meta["atoms"], "lammps_atom_steps_per_s": statistics.median(rates["lammps"]) * meta["spheres_per_particle"],
            "cpu_ratio_capdem_over_lammps": statistics.median(cpu_ratios), "cpu_ratios": cpu_ratios,
        })
    if "liggghts" in peers:
        out["liggghts_damping_rel_error_bound"] = lig_meta["damping_rel_error_bound"]
        out.update(cpu_ratio_capdem_over_liggghts=statistics.median(lig_cpu), cpu_ratios_liggghts=lig_cpu)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--cases", default="spheres:1000,hexapods_a3:1000,hexapods_a9:1000",
                    help="case:N[:PEER_STEPS][@KXxKZ], comma-separated")
    ap.add_argument("--peers", default="lammps,liggghts", help="lammps, liggghts (spheres only) or both")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3,
                    help="rounds; 0 settles, tiles and converts the packings only (time them later with --reuse)")
    ap.add_argument("--relax-steps", type=int, default=None,
                    help="steps a tiled packing relaxes (capdem) before timing (default: RELAX, 20 ms spheres, 200 ms hexapods)")
    ap.add_argument("--peer-warm", type=int, default=200, help="untimed steps of a peer before each timed segment")
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--baseline", default=None,
                    help="another build folder whose capdem-bench is timed after capdem in every round (same packing)")
    ap.add_argument("--work", default="build/bench-work")
    ap.add_argument("--reuse", action="store_true", help="time capdem on a settled packing left by an earlier run")
    ap.add_argument("--sphere-orientation", default="integrate",
                    help="integrate, fixed or both (integrate,fixed): capdem's physics.sphere_orientation on sphere "
                         "cases, each timed in every round")
    ap.add_argument("--omp-wait-policy", default="default", choices=("default", "passive", "active"),
                    help="OMP_WAIT_POLICY of capdem's runs (default: unset, libgomp's own)")
    args = ap.parse_args()
    if any(o not in ("integrate", "fixed") for o in args.sphere_orientation.split(",")):
        raise SystemExit("compare: --sphere-orientation %s: expected integrate, fixed or integrate,fixed"
                         % args.sphere_orientation)
    cases = []
    for item in args.cases.split(","):
        spec, _, tile = item.partition("@")
        case, n, *ls = spec.split(":")
        if case not in SETTLE:
            raise SystemExit("compare: case %s: expected one of %s (crosses2d has no LAMMPS twin)" % (case, ", ".join(SETTLE)))
        try:
            kx, kz = (int(k) for k in tile.split("x")) if tile else (1, 1)
        except ValueError:
            raise SystemExit("compare: case %s: @%s: expected @KXxKZ, e.g. @5x2" % (item, tile))
        cases.append((case, int(float(n)), int(ls[0]) if ls else args.steps, (kx, kz)))
    ensure_lammps()
    versions = {"lammps_version": lammps_version()}
    if "liggghts" in args.peers and any(c[0] == "spheres" for c in cases):
        liggghts_law.ensure_liggghts()
        versions["liggghts_version"] = liggghts_law.liggghts_version()
    os.makedirs(args.work, exist_ok=True)
    rows = []
    for case, n, peer_steps, tile in cases:
        r = one_case(args, case, n, peer_steps, tile)
        r.update(versions)
        print(json.dumps(r), flush=True)
        rows.append(r)
    print("\n| case | N | threads | capdem p-steps/s | peer | peer p-steps/s | capdem / peer wall (median, range) "
          "| capdem / peer per CPU s (median, range) | list builds capdem / peer (per segment) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        for peer in ("lammps", "liggghts"):
            if "ratios_" + peer not in r:
                continue
            q = r["ratios_" + peer]
            qc = r["cpu_ratios" + ("" if peer == "lammps" else "_" + peer)]
            print("| %s | %d | %d | %.3g | %s | %.3g | %.2f (%.2f-%.2f) | %.2f (%.2f-%.2f) | %s / %s |" % (
                r["case"], r["N"], r["threads"], r["capdem_particle_steps_per_s"], peer, r[peer + "_particle_steps_per_s"],
                r["ratio_capdem_over_" + peer], min(q), max(q), r["cpu_ratio_capdem_over_" + peer], min(qc), max(qc),
                r["capdem_neighbor_builds"], r[peer + "_neighbor_builds"]))
        for o in args.sphere_orientation.split(",")[1:]:
            for peer in ("lammps", "liggghts"):
                if "ratios_%s_%s" % (o, peer) not in r:
                    continue
                q = r["ratios_%s_%s" % (o, peer)]
                print("| %s | %d | %d | %.3g (sphere_orientation %s) | %s | %.3g | %.2f (%.2f-%.2f) | | %s / %s |" % (
                    r["case"], r["N"], r["threads"], r["capdem_%s_particle_steps_per_s" % o], o, peer,
                    r[peer + "_particle_steps_per_s"], r["ratio_capdem_%s_over_%s" % (o, peer)], min(q), max(q),
                    r["capdem_%s_neighbor_builds" % o], r[peer + "_neighbor_builds"]))
        if "ratios_baseline" in r:
            q, qc = r["ratios_baseline"], r["cpu_ratios_baseline"]
            print("| %s | %d | %d | %.3g | capdem %s | %.3g | %.2f (%.2f-%.2f) | %.2f (%.2f-%.2f) | |" % (
                r["case"], r["N"], r["threads"], r["capdem_particle_steps_per_s"], r["baseline_build"],
                r["baseline_particle_steps_per_s"], r["ratio_capdem_over_baseline"], min(q), max(q),
                r["cpu_ratio_capdem_over_baseline"], min(qc), max(qc)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
