#!/usr/bin/env python3
"""Run times of the full-size protocol presets, extrapolated from shortened runs.

    /usr/bin/python3 bench/preset_times.py BUILD --deposit-ref D.h5:CPU_S --radial-ref R.h5:CPU_S [--steps 3000]

D.h5 and R.h5 are complete runs of one deposit preset and one radial preset
(configs/protocols/; R.h5 named after its preset, for its twin), made with
--threads 1, and CPU_S the CPU seconds each took (/usr/bin/time).  The model, per preset
(docs/performance.md states it with the results):

    CPU seconds = N x (n_fall c_start + (n_settle - n_fall + n_after) c_dense)

  N         the preset's particle count (printed by its shortened run);
  n_settle  settling steps, t_settle / dt, exact (deposit only);
  n_fall    the first third of them: the lattice falls for sqrt(2h/g),
            a third of t_settle = 3 sqrt(2h/g), then rests on the floor;
  c_start   CPU seconds per particle-step of the preset's first --steps steps
            (one thread), measured here;
  c_dense   the reference run's: its CPU time solved for c_dense with its
            own c_start (a shortened run of the config it echoes) and step
            counts; carried to each preset by c_start / c_start(reference);
  n_after   steps after settling: the reference run's, the same for every
            deposit preset; for the radial presets, the reference's count
            times the ratio of the presets' CI twins' step counts (the
            twins' counts are read from their runs here too).

Every figure is CPU time of one thread: on the shared development machine
wall time says more about the other jobs than about capdem.  The bulk
preset (radial compaction, then 6 probe windows) is left out.  Prints one
JSON line per preset and a Markdown table.
"""
import argparse
import glob
import json
import math
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np

PHASE_DONE = 7


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(cmd, env=None):
    """Runs capdem; returns (stderr text, child CPU seconds)."""
    t0 = cpu_children()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit(f"preset_times: {' '.join(cmd)} failed ({p.returncode}):\n{p.stderr[-2000:]}")
    return p.stderr, cpu_children() - t0


def header(stderr):
    """N, dt [s] and the lattice height [m] (deposit) from a run's first lines."""
    n = int(re.search(r"capdem: (\d+) particles", stderr).group(1))
    dt = float(re.search(r"dt = ([0-9.eE+-]+) s", stderr).group(1))
    h = re.search(r"domain.height ([0-9.eE+-]+) m", stderr)
    return n, dt, float(h.group(1)) if h else None


def phases(path):
    """(steps, phases) of a run file's time series."""
    with h5py.File(path, "r") as f:
        return f["observables/phase/step"][:], f["observables/phase/value"][:]


def shortened(build, cfg, steps, work):
    """CPU seconds per particle-step over the first steps of a preset."""
    out = os.path.join(work, "short.h5")
    err, cpu = run([f"{build}/capdem", "run", cfg, "--steps", str(steps), "--threads", "1", "--quiet", "--output", out])
    n, dt, h = header(err)
    os.remove(out)
    return n, dt, h, cpu / (n * steps)


def reference(spec, build, steps, work):
    """A complete reference run 'FILE.h5:CPU_SECONDS': its step counts (from
    the time series), its own c_start (a shortened run of the config the
    file echoes) and the c_dense its CPU time implies:
    cpu = N (n_fall c_start + (n_done - n_fall) c_dense)."""
    path, cpu = spec.rsplit(":", 1)
    st, ph = phases(path)
    if not (ph == PHASE_DONE).any():
        sys.exit(f"preset_times: {path}: the protocol did not finish; a reference must be a complete run")
    done_at = int(st[np.argmax(ph == PHASE_DONE)])
    settle_end = int(st[np.argmax(ph > 1)]) if (ph == 1).any() else 0
    with h5py.File(path, "r") as f:
        text = f["parameters/config"][()]
    cfg = os.path.join(work, "reference.yaml")
    with open(cfg, "wb") as f:
        f.write(text if isinstance(text, bytes) else text.encode())
    n, dt, h, c_start = shortened(build, cfg, steps, work)
    n_fall = settle_end // 3
    c_dense = (float(cpu) / n - n_fall * c_start) / (done_at - n_fall)
    return dict(path=path, cpu=float(cpu), n=n, done_at=done_at, settle_end=settle_end, c_start=c_start,
                c_dense=c_dense, after=done_at - settle_end, name=os.path.basename(path)[:-3])


def twin_steps(build, name, presets, work):
    """Steps the CI twin of a preset takes to finish its protocol."""
    out = os.path.join(work, "twin.h5")
    run([f"{build}/capdem", "run", os.path.join(presets, "ci", name + ".yaml"), "--quiet", "--output", out])
    st, ph = phases(out)
    os.remove(out)
    return int(st[np.argmax(ph == PHASE_DONE)])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("build")
    ap.add_argument("--deposit-ref", required=True)
    ap.add_argument("--radial-ref", required=True)
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--presets", default=os.path.join(os.path.dirname(__file__), "..", "configs", "protocols"))
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="preset_times.")
    try:
        refs = {"deposit": reference(a.deposit_ref, a.build, a.steps, work),
                "radial": reference(a.radial_ref, a.build, a.steps, work)}
        rows = []
        for cfg in sorted(glob.glob(os.path.join(a.presets, "*.yaml"))):
            name = os.path.basename(cfg)[:-5]
            if name.startswith("bulk"):
                continue  # radial compaction and then the probe windows: see docs/performance.md
            kind = "deposit" if name.startswith("deposit") else "radial"
            n, dt, h, c_start = shortened(a.build, cfg, a.steps, work)
            r = dict(preset=name, kind=kind, n=n, dt=dt, h=h, c_start=c_start)
            if kind == "deposit":
                r["n_settle"] = math.ceil(3 * math.sqrt(2 * h / 9.81) / dt)
                r["n_fall"] = r["n_settle"] // 3
            else:
                r["n_settle"] = r["n_fall"] = 0
                r["twin"] = twin_steps(a.build, "radial_spheres" if name.endswith("_a1") else name, a.presets, work)
            rows.append(r)
        for kind, ref in refs.items():
            if kind == "radial":
                twin = [r for r in rows if r["preset"] in ref["name"]]
                if not twin:
                    sys.exit(f"preset_times: {ref['path']}: name it after its preset (e.g. radial_hexapods_a3.h5)")
                ref["twin"] = twin[0]["twin"]
        out = []
        for r in rows:
            ref = refs[r["kind"]]
            c_dense = ref["c_dense"] * r["c_start"] / ref["c_start"]
            n_after = ref["after"] if r["kind"] == "deposit" else round(ref["after"] * r["twin"] / ref["twin"])
            measured = r["preset"] in ref["name"] and r["n"] == ref["n"]
            cpu = ref["cpu"] if measured else r["n"] * (r["n_fall"] * r["c_start"] + (r["n_settle"] - r["n_fall"] + n_after) * c_dense)
            o = dict(preset=r["preset"], N=r["n"], steps=r["n_settle"] + n_after, settle_steps=r["n_settle"],
                     us_per_particle_step_start=r["c_start"] * 1e6, us_per_particle_step_dense=c_dense * 1e6,
                     cpu_hours_one_thread=cpu / 3600, measured=measured)
            print(json.dumps(o))
            out.append(o)
        print("\n| preset | N | steps (settle + after) | CPU us per particle-step (start / dense) | hours, one thread |")
        print("|---|---|---|---|---|")
        for o in out:
            print(f"| {o['preset']} | {o['N']} | {o['settle_steps']:,} + {o['steps'] - o['settle_steps']:,} | "
                  f"{o['us_per_particle_step_start']:.2f} / {o['us_per_particle_step_dense']:.2f} | "
                  f"{o['cpu_hours_one_thread']:.2f}{' (measured)' if o['measured'] else ''} |")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
