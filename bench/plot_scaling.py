#!/usr/bin/python3
"""Time per step against N, one panel per backend, from capdem-bench JSON lines.

    /usr/bin/python3 bench/plot_scaling.py results.jsonl [more.jsonl ...] -o docs/images/scaling.png

Every line of the inputs is one timed repeat (bench/scaling.sh,
capdem-bench --backend ...).  Points: the median over repeats of wall_s /
steps per (case, backend, threads, N); bars: the smallest and largest
repeat.  A dotted line of slope 1 (time proportional to N) through each
series' smallest N shows where the cost per particle-step changes.
"""
import argparse
import collections
import json
import statistics

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("inputs", nargs="+")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--title", default="capdem step time on a settled packing (2-core AMD EPYC)")
    a = ap.parse_args()
    series = collections.defaultdict(lambda: collections.defaultdict(list))
    for path in a.inputs:
        for line in open(path):
            if not line.startswith("{"):
                continue
            r = json.loads(line)
            if r["backend"] == "omp":
                label = "%s, %d thread%s" % (r["case"], r["threads"], "" if r["threads"] == 1 else "s")
            else:  # the OpenCL runtime chooses its own worker threads
                label = r["case"]
            series[r["backend"]][label].append((r["N"], r["wall_s"] / r["steps"]))
    backends = sorted(series)
    fig, axes = plt.subplots(1, len(backends), figsize=(5.5 * len(backends), 4.2), squeeze=False, sharey=True)
    for ax, backend in zip(axes[0], backends):
        for label, pts in sorted(series[backend].items()):
            by_n = collections.defaultdict(list)
            for n, t in pts:
                by_n[n].append(t)
            ns = sorted(by_n)
            med = [statistics.median(by_n[n]) for n in ns]
            lo = [m - min(by_n[n]) for n, m in zip(ns, med)]
            hi = [max(by_n[n]) - m for n, m in zip(ns, med)]
            line = ax.errorbar(ns, [1e3 * m for m in med], yerr=[[1e3 * x for x in lo], [1e3 * x for x in hi]],
                               marker="o", capsize=3, label=label)
            ax.plot(ns, [1e3 * med[0] * n / ns[0] for n in ns], ":", color=line[0].get_color(), lw=1)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("particles N")
        ax.set_title("backend %s" % backend + (" (PoCL, CPU)" if backend == "opencl" else " (host OpenMP)"))
        ax.grid(True, which="both", alpha=0.3)
        ax.yaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.legend(fontsize=8)
    axes[0][0].set_ylabel("wall time per step [ms]")
    fig.suptitle(a.title, fontsize=10)
    fig.tight_layout()
    fig.savefig(a.output, dpi=110)
    print("wrote", a.output)


if __name__ == "__main__":
    main()
