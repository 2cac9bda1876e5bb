#!/usr/bin/python3
"""A/B: capdem-bench of two builds on the ladder beds, alternating; particle-steps per CPU s (1 thread) or wall s."""
import json, subprocess, sys, statistics, argparse
ap = argparse.ArgumentParser()
ap.add_argument("builds", nargs="+")
ap.add_argument("--beds", default="spheres_1000,spheres_1000_5x2,spheres_1000_10x10,hexapods_a3_1000,hexapods_a3_1000_5x2,hexapods_a3_1000_10x10")
ap.add_argument("--target", type=float, default=2e6)
ap.add_argument("--rounds", type=int, default=3)
ap.add_argument("--threads", type=int, default=1)
ap.add_argument("--extra", default="")
a = ap.parse_args()
W = "/work/bench-work18/ladder/ladder_%s.h5"
N = {"1000": 1000, "5x2": 10000, "6x5": 30000, "10x10": 100000}
for bed in a.beds.split(","):
    n = N[bed.split("_")[-1]] if not bed.endswith("_1000") else 1000
    steps = max(20, int(a.target / n))
    res = {b: [] for b in a.builds}
    for r in range(a.rounds):
        for b in a.builds:
            cmd = [b + "/capdem-bench", "--threads", str(a.threads), "--load-settled", W % bed, "--gravity", "490.5",
                   "--steps", str(steps), "--repeat", "1"] + a.extra.split()
            out = subprocess.run(cmd, capture_output=True, text=True).stdout
            j = json.loads(out.strip().splitlines()[-1])
            t = j["cpu_s"] if a.threads == 1 else j["wall_s"]
            res[b].append(j["N"] * j["steps"] / t)
    base = statistics.median(res[a.builds[0]])
    print(bed, " ".join("%s %.3e (x%.3f)" % (b.split("/")[-2], statistics.median(v), statistics.median(v) / base) for b, v in res.items()), flush=True)
