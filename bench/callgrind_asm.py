#!/usr/bin/python3
"""Per-instruction self cost of one function, from a callgrind file, on its disassembly.

    valgrind --tool=callgrind --branch-sim=yes --dump-instr=yes --callgrind-out-file=F.cg \\
        build/capdem-bench --load-settled P.h5 --gravity 490.5 --threads 1 --steps 300 --repeat 1
    bench/callgrind_asm.py F.cg build/capdem-bench pair_rows.isra.0 [MIN_IR] > pair_rows.txt

Prints `objdump -d -l` of FUNCTION with each executed instruction's count of
instructions (Ir), conditional branches (Bc) and mispredicted ones (Bcm,
callgrind's model), and the source line above each run of instructions;
instructions below MIN_IR executions are left out.  It shows what a loop
spends its instructions on: docs/performance.md, "Session 19, the arm-arm
row" (register copies against arithmetic).  Build with -g for the lines.
"""
import collections
import re
import subprocess
import sys


def self_costs(cg, func):
    """address -> [Ir, Bc, Bcm, ...] of FUNCTION's own instructions."""
    cost = collections.defaultdict(lambda: [0] * 8)
    names, cur, after_calls, pos = {}, None, False, [0, 0]
    for line in open(cg):
        line = line.rstrip("\n")
        m = re.match(r"^(c?fn)=\((\d+)\)(?: (.*))?$", line)
        if m:
            if m.group(3):
                names[m.group(2)] = m.group(3)
            if m.group(1) == "fn":
                cur = names.get(m.group(2))
            continue
        if line.startswith("calls="):  # the next line is the call's inclusive cost
            after_calls = True
            continue
        if not line or not (line[0].isdigit() or line[0] in "+-*"):
            continue
        toks = line.split()
        for k in (0, 1):  # positions: absolute, +/- relative, or * (the same)
            t = toks[k]
            if t != "*":
                pos[k] = pos[k] + int(t, 0) if t[0] in "+-" else int(t, 0)
        if after_calls:
            after_calls = False
            continue
        if cur == func:
            for k, v in enumerate(toks[2:]):
                cost[pos[0]][k] += int(v)
    return cost


def main():
    if len(sys.argv) < 4:
        raise SystemExit(__doc__)
    cg, binary, func = sys.argv[1:4]
    min_ir = int(sys.argv[4]) if len(sys.argv) > 4 else 1
    cost = self_costs(cg, func)
    dis = subprocess.run(["objdump", "-d", "-l", "--no-show-raw-insn", binary], capture_output=True, text=True).stdout
    inside, total, src = False, 0, None
    for line in dis.splitlines():
        if re.match(r"^[0-9a-f]+ <" + re.escape(func) + ">:", line):
            inside = True
            continue
        if not inside:
            continue
        if not line.strip():
            break
        m = re.match(r"\s*([0-9a-f]+):\s*(.*)", line)
        if not m:
            if line.startswith("/"):
                src = line
            continue
        c = cost.get(int(m.group(1), 16), [0] * 8)
        total += c[0]
        if c[0] >= min_ir:
            if src:
                print("        " + src)
                src = None
            print("%12d %10d %9d  %s: %s" % (c[0], c[1], c[2], m.group(1), m.group(2)))
    print("total Ir of %s: %d" % (func, total), file=sys.stderr)


if __name__ == "__main__":
    main()
