#!/usr/bin/env python3
"""Per-kernel table of Nsight Compute's CSV output (bench/gpu/kernel_profile.sh).

    ncu_table.py LABEL=FILE.csv [LABEL=FILE.csv ...]
    ncu_table.py --self-test

Each FILE is the output of `ncu --csv --metrics ...` of one capdem-bench run
(one backend, or one loop shape of the omp offload build).  Prints, per run,
every kernel with: launches, total and mean time, grid x block, registers
per thread, theoretical and achieved occupancy, local-memory load and store
instructions and bytes, global load instructions, DRAM bytes read and
written per launch; then the kernels of the same pass side by side (the omp
offload kernel and the OpenCL kernel that call the same item of
kernels/step_items.h or kernels/neighbor_items.h).
"""
import csv
import io
import re
import sys
from collections import defaultdict

# Metric name -> column, and how several launches combine.
METRICS = {
    "gpu__time_duration.sum": "time",
    "launch__registers_per_thread": "regs",
    "sm__maximum_warps_per_active_cycle_pct": "occ_theory",
    "sm__warps_active.avg.pct_of_peak_sustained_active": "occ",
    "smsp__sass_inst_executed_op_local_ld.sum": "local_ld",
    "smsp__sass_inst_executed_op_local_st.sum": "local_st",
    "l1tex__t_bytes_pipe_lsu_mem_local_op_ld.sum": "local_ld_B",
    "l1tex__t_bytes_pipe_lsu_mem_local_op_st.sum": "local_st_B",
    "smsp__sass_inst_executed_op_global_ld.sum": "global_ld",
    "dram__bytes_read.sum": "dram_rd",
    "dram__bytes_write.sum": "dram_wr",
}
UNIT = {"nsecond": 1e-3, "ns": 1e-3, "usecond": 1.0, "us": 1.0, "msecond": 1e3, "ms": 1e3, "second": 1e6, "s": 1e6,
        "byte": 1.0, "Kbyte": 1e3, "Mbyte": 1e6, "Gbyte": 1e9, "KB": 1e3, "MB": 1e6, "GB": 1e9}
# The same pass on the two backends: omp offload function (the kernel is
# __omp_offloading_<dev>_<file>_<function>_l<line>) -> OpenCL kernel.
PAIRS = [
    ("collect", "cd_cl_pair_collect", "candidates per particle/primitive (pass 5)"),
    ("pair_forces", "cd_cl_pair_forces", "pair rows"),
    ("wall_forces", "cd_cl_wall_forces", "wall candidates"),
    ("forces_and_advance", "cd_cl_gather_kick", "gather, kick, next advance"),
    ("advance_particles", "cd_cl_advance", "first advance of a call"),
    ("make_grid", "cd_cl_bounds", "bounds (pass 1a)"),
    ("bin_particles", "cd_cl_bin", "binning"),
    ("cd_neighbors_build", "cd_cl_pair_place", "place rows (pass 7)"),
    ("particle_lists", "cd_cl_gather_sort", "gather lists (pass 9)"),
]


def short(kernel):
    k = re.sub(r"\(.*$", "", kernel.strip())
    m = re.match(r"^__omp_offloading_[0-9a-f]+_[0-9a-f]+_(.*)$", k)
    return m.group(1) if m else k


def parse(text):
    """{kernel: {column: [values per launch]}, '_shape': {kernel: set of 'grid x block'}}"""
    rows = [l for l in text.splitlines() if l.startswith('"')]
    per = defaultdict(lambda: defaultdict(list))
    shapes = defaultdict(set)
    for r in csv.DictReader(io.StringIO("\n".join(rows))):
        name = r.get("Metric Name", "")
        if name not in METRICS:
            continue
        k = short(r.get("Kernel Name", "?"))
        try:
            v = float(r["Metric Value"].replace(",", ""))
        except ValueError:
            continue
        v *= UNIT.get(r.get("Metric Unit", ""), 1.0)
        per[k][METRICS[name]].append(v)
        g, b = r.get("Grid Size", ""), r.get("Block Size", "")
        if g or b:
            shapes[k].add(f"{g} x {b}".replace("(", "").replace(")", "").replace(", 1, 1", ""))
    return per, shapes


def mean(xs):
    return sum(xs) / len(xs) if xs else float("nan")


def fmt(x, f="{:.0f}"):
    return "-" if x != x else f.format(x)


def table(label, per, shapes):
    out = [f"== {label}: per kernel, sorted by total time",
           "| kernel | launches | total ms | mean us | grid x block | regs | occupancy theory/achieved % "
           "| local ld/st instr per launch | local ld/st B per launch | global ld instr per launch | DRAM rd/wr MB per launch |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    tot = sum(sum(m.get("time", [])) for m in per.values())
    for k, m in sorted(per.items(), key=lambda kv: -sum(kv[1].get("time", []))):
        t = m.get("time", [])
        out.append(
            f"| {k} | {len(t)} | {sum(t) / 1e3:.3f} | {fmt(mean(t), '{:.1f}')} | {', '.join(sorted(shapes.get(k, [])))[:40]} "
            f"| {fmt(mean(m.get('regs', [])))} | {fmt(mean(m.get('occ_theory', [])), '{:.0f}')}/{fmt(mean(m.get('occ', [])), '{:.0f}')} "
            f"| {fmt(mean(m.get('local_ld', [])))}/{fmt(mean(m.get('local_st', [])))} "
            f"| {fmt(mean(m.get('local_ld_B', [])))}/{fmt(mean(m.get('local_st_B', [])))} "
            f"| {fmt(mean(m.get('global_ld', [])))} "
            f"| {fmt(mean(m.get('dram_rd', [])) / 1e6, '{:.2f}')}/{fmt(mean(m.get('dram_wr', [])) / 1e6, '{:.2f}')} |")
    out.append(f"total {tot / 1e3:.3f} ms in {sum(len(m.get('time', [])) for m in per.values())} launches")
    return out


def local_instr(m):
    """local loads + stores per launch (nan when neither was measured)"""
    parts = [mean(m[c]) for c in ("local_ld", "local_st") if m.get(c)]
    return sum(parts) if parts else float("nan")


def side_by_side(runs):
    out = ["== the same pass, side by side (mean us per launch; regs; achieved occupancy %; local ld+st instr per launch)",
           "| pass | " + " | ".join(label for label, _, _ in runs) + " |", "|---|" + "---|" * len(runs)]
    for omp_fn, cl_kernel, what in PAIRS:
        cells = []
        for label, per, _ in runs:
            ks = [k for k in per if k == cl_kernel or re.match(rf"^{re.escape(omp_fn)}_l\d+$", k)]
            if not ks:
                cells.append("-")
                continue
            # the longest launch of this pass (a function holds several loops)
            k = max(ks, key=lambda x: mean(per[x].get("time", [0])))
            m = per[k]
            cells.append(f"{k}: {fmt(mean(m.get('time', [])), '{:.1f}')} us, {fmt(mean(m.get('regs', [])))} regs, "
                         f"{fmt(mean(m.get('occ', [])), '{:.0f}')} %, "
                         f"{fmt(local_instr(m))} local")
        out.append(f"| {what} | " + " | ".join(cells) + " |")
    return out


def self_test():
    """A synthetic CSV in ncu's layout: the parser, units and both tables."""
    head = ('"ID","Process ID","Process Name","Host Name","Kernel Name","Context","Stream","Block Size","Grid Size",'
            '"Device","CC","Section Name","Metric Name","Metric Unit","Metric Value"')

    def row(i, k, metric, unit, v):
        return f'"{i}","1","capdem-bench","h","{k}","1","7","(128, 1, 1)","(782, 1, 1)","0","9.0","Command line profiler metrics","{metric}","{unit}","{v}"'
    omp = [head, "==PROF== Connected to process", row(0, "__omp_offloading_fe00_538372_collect_l222", "gpu__time_duration.sum", "msecond", "1.5"),
           row(0, "__omp_offloading_fe00_538372_collect_l222", "launch__registers_per_thread", "register/thread", "213"),
           row(0, "__omp_offloading_fe00_538372_collect_l222", "sm__warps_active.avg.pct_of_peak_sustained_active", "%", "11.9"),
           row(0, "__omp_offloading_fe00_538372_collect_l222", "smsp__sass_inst_executed_op_local_ld.sum", "inst", "1,024"),
           row(1, "__omp_offloading_fe00_538378_pair_forces_l114", "gpu__time_duration.sum", "usecond", "150"),
           row(2, "__omp_offloading_fe00_538378_pair_forces_l114", "gpu__time_duration.sum", "usecond", "170"),
           row(2, "__omp_offloading_fe00_538378_pair_forces_l114", "dram__bytes_read.sum", "Mbyte", "12.5")]
    cl = [head, row(0, "cd_cl_pair_collect", "gpu__time_duration.sum", "usecond", "400"),
          row(0, "cd_cl_pair_forces", "gpu__time_duration.sum", "usecond", "60"),
          row(0, "cd_cl_pair_forces", "launch__registers_per_thread", "register/thread", "105")]
    p1, s1 = parse("\n".join(omp))
    p2, s2 = parse("\n".join(cl))
    assert abs(sum(p1["collect_l222"]["time"]) - 1500.0) < 1e-9, p1["collect_l222"]
    assert p1["collect_l222"]["local_ld"] == [1024.0]
    assert len(p1["pair_forces_l114"]["time"]) == 2 and p1["pair_forces_l114"]["dram_rd"] == [12.5e6]
    assert s1["collect_l222"] == {"782 x 128"}, s1
    lines = table("omp", p1, s1) + table("opencl", p2, s2) + side_by_side([("omp", p1, s1), ("opencl", p2, s2)])
    text = "\n".join(lines)
    assert "| collect_l222 | 1 | 1.500 |" in text, text
    assert "collect_l222: 1500.0 us, 213 regs, 12 %, 1024 local" in text, text
    assert "cd_cl_pair_forces: 60.0 us, 105 regs" in text, text
    print(text)
    print("ncu_table.py self-test: ok")


def main():
    if sys.argv[1:] == ["--self-test"]:
        self_test()
        return
    if not sys.argv[1:]:
        sys.exit(__doc__)
    runs = []
    for a in sys.argv[1:]:
        label, _, path = a.partition("=")
        try:
            per, shapes = parse(open(path, errors="replace").read())
        except OSError as e:
            print(f"== {label}: {e}")
            continue
        if not per:
            print(f"== {label}: no kernel metrics in {path} (ncu failed? see its log)")
            continue
        runs.append((label, per, shapes))
        print("\n".join(table(label, per, shapes)))
        print()
    if len(runs) > 1:
        print("\n".join(side_by_side(runs)))


if __name__ == "__main__":
    main()
