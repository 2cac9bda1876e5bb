#!/usr/bin/env python3
"""Run times of the full-size protocol presets, extrapolated from shortened runs.

    /usr/bin/python3 bench/preset_times.py BUILD --deposit-ref D.h5:CPU_S [--radial-ref R.h5:CPU_S] [--steps 3000]

D.h5 is a complete run of a deposit preset and R.h5 a run (complete or not)
of a radial preset (configs/protocols/; R.h5 named after its preset), made
with --threads 1, and CPU_S the CPU seconds each took (/usr/bin/time, or
/proc/PID/stat for a run still going).  Model, per deposit preset
(docs/performance.md states it with the results):

    CPU seconds = N x (n_fall c_start + (n_settle - n_fall + n_after) c_dense)

  N         the preset's particle count (printed by its shortened run);
  n_settle  settling steps, t_settle / dt, exact;
  n_fall    the first third of them: the lattice falls for sqrt(2h/g),
            a third of t_settle = 3 sqrt(2h/g), then rests on the floor;
  c_start   CPU seconds per particle-step over the preset's first --steps
            steps (one thread), measured here;
  c_dense   the reference's: its CPU time solved for c_dense with its own
            c_start (a shortened run of the config it echoes) and step
            counts, carried to each preset by c_start / c_start(reference);
  n_after   steps after settling (compress, hold): the reference's.

Radial presets are dense from the first few thousand steps on: their cost
is N x steps x c_dense, with c_dense = the radial reference's CPU time over
its particle-steps (carried by c_start as above), and the steps those of
the reference when it finished, times the ratio of the presets' CI twins'
step counts (run here too).  For a reference still running, the steps are
unknown: the table gives hours per million steps and the steps reached so
far as a lower bound.

Every figure is CPU time of one thread: on the shared development machine
wall time says more about the other jobs than about capdem.  The bulk
preset is left out.  Prints one JSON line per preset and a Markdown table.
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

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "host"))  # capdem_h5
import capdem_h5  # noqa: E402

PHASE_DONE = 7


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(cmd):
    """Runs capdem; returns (stderr text, child CPU seconds)."""
    t0 = cpu_children()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"preset_times: {' '.join(cmd)} failed ({p.returncode}):\n{p.stderr[-2000:]}")
    return p.stderr, cpu_children() - t0


def phases(path):
    """(steps, phases) of a run file's time series."""
    with capdem_h5.open_run(path) as f:
        st, _, value = capdem_h5.observable(f, "phase")
        return st, value


def shortened(build, cfg, steps, work):
    """N, dt [s], lattice height [m] (deposit) and CPU seconds per
    particle-step over the first steps of a config."""
    out = os.path.join(work, "short.h5")
    err, cpu = run([f"{build}/capdem", "run", cfg, "--steps", str(steps), "--threads", "1", "--quiet", "--output", out])
    os.remove(out)
    n = int(re.search(r"capdem: (\d+) particles", err).group(1))
    dt = float(re.search(r"dt = ([0-9.eE+-]+) s", err).group(1))
    h = re.search(r"domain.height ([0-9.eE+-]+) m", err)
    return n, dt, float(h.group(1)) if h else None, cpu / (n * steps)


def reference(spec, build, steps, work, kind):
    """A reference run 'FILE.h5:CPU_SECONDS' -> its counts and c_dense."""
    path, cpu = spec.rsplit(":", 1)
    cpu = float(cpu)
    st, ph = phases(path)
    done = bool((ph == PHASE_DONE).any())
    last = int(st[np.argmax(ph == PHASE_DONE)]) if done else int(st[-1])
    if kind == "deposit" and not done:
        sys.exit(f"preset_times: {path}: the deposit reference must be a complete run")
    settle_end = int(st[np.argmax(ph > 1)]) if kind == "deposit" else 0
    with capdem_h5.open_run(path) as f:
        text = capdem_h5.config_text(f)
    cfg = os.path.join(work, "reference.yaml")
    with open(cfg, "wb") as f:
        f.write(text.encode())
    n, _, _, c_start = shortened(build, cfg, steps, work)
    n_fall = settle_end // 3
    c_dense = (cpu / n - n_fall * c_start) / (last - n_fall)
    return dict(path=path, name=os.path.basename(path)[:-3], cpu=cpu, n=n, done=done, last=last,
                after=last - settle_end, c_start=c_start, c_dense=c_dense)


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
    ap.add_argument("--radial-ref")
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--presets", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "configs", "protocols"))
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="preset_times.")
    try:
        refs = {"deposit": reference(a.deposit_ref, a.build, a.steps, work, "deposit")}
        if a.radial_ref:
            refs["radial"] = reference(a.radial_ref, a.build, a.steps, work, "radial")
        out = []
        for cfg in sorted(glob.glob(os.path.join(a.presets, "*.yaml"))):
            name = os.path.basename(cfg)[:-5]
            kind = "deposit" if name.startswith("deposit") else "radial" if name.startswith("radial") else None
            if kind not in refs:
                continue
            ref = refs[kind]
            n, dt, h, c_start = shortened(a.build, cfg, a.steps, work)
            c_dense = ref["c_dense"] * c_start / ref["c_start"]
            o = dict(preset=name, N=n, us_per_particle_step_start=c_start * 1e6, us_per_particle_step_dense=c_dense * 1e6)
            if kind == "deposit":
                n_settle = math.ceil(3 * math.sqrt(2 * h / 9.81) / dt)
                n_fall = n_settle // 3
                cpu = n * (n_fall * c_start + (n_settle - n_fall + ref["after"]) * c_dense)
                o.update(settle_steps=n_settle, steps=n_settle + ref["after"])
            else:
                if "twin" not in ref:
                    ref["twin"] = twin_steps(a.build, ref["name"], a.presets, work)
                twin = twin_steps(a.build, "radial_spheres" if name.endswith("_a1") else name, a.presets, work)
                steps = round(ref["last"] * twin / ref["twin"])
                cpu = n * steps * c_dense
                o.update(settle_steps=0, steps=steps, steps_known=ref["done"],
                         cpu_hours_per_million_steps=n * 1e6 * c_dense / 3600)
            o["measured"] = name == ref["name"] and n == ref["n"] and ref["done"]
            o["cpu_hours_one_thread"] = (ref["cpu"] if o["measured"] else cpu) / 3600
            print(json.dumps(o))
            out.append(o)
        print("\n| preset | N | steps | CPU us per particle-step (start / dense) | CPU hours, one thread |")
        print("|---|---|---|---|---|")
        for o in out:
            steps = f"{o['settle_steps']:,} + {o['steps'] - o['settle_steps']:,}" if o["settle_steps"] else f"{o['steps']:,}"
            hours = f"{o['cpu_hours_one_thread']:.2f}"
            if o.get("steps_known") is False:
                steps = f"> {o['steps']:,}"
                hours = f"> {hours} ({o['cpu_hours_per_million_steps']:.2f} per 1e6 steps)"
            print(f"| {o['preset']} | {o['N']} | {steps} | {o['us_per_particle_step_start']:.2f} / "
                  f"{o['us_per_particle_step_dense']:.2f} | {hours}{' (measured)' if o['measured'] else ''} |")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
