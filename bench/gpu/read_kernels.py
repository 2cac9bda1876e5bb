#!/usr/bin/env python3
"""What the compiler makes of the omp offload kernels, without a GPU.

    bench/gpu/read_kernels.py BUILD [--out DIR] [--sources a.c b.c ...] [--cl]

BUILD is a Clang 16 nvptx build tree (bench/gpu_bundle.sh's build-gpu/clang,
or any `CC=clang-16 cmake -DCAPDEM_OFFLOAD=nvptx` tree): its compile flags for
the engine (CMakeFiles/capdem_engine.dir/flags.make) are reused as they are.
Each source (default: the four files of src/backend/omp) is compiled again
with -save-temps and the openmp-opt remarks (-Rpass/-Rpass-analysis/
-Rpass-missed=openmp-opt: OMP110-OMP133), the device PTX it keeps (the one
the build hands to ptxas, device runtime linked and inlined) goes through
`ptxas -arch=sm_90 -O3 -v`, and each kernel gets one line:

  kernel   the name as ncu and LIBOMPTARGET_INFO print it, less the
           __omp_offloading_<dev>_<file>_ prefix: function_l<line>
  mode     SPMD or generic (the kernel's <name>_exec_mode: 2, 1, 3)
  regs     registers per thread (ptxas); occupancy on an H100 with the
           plugin's default 128 threads a team: 65,536 / (regs x 128) teams
           of an SM, at most 16 (64 warps)
  stack    stack frame [B] (local memory per thread) and spill stores/loads [B]
  u8       byte loads (ld.*.u8/s8) and byte stores: a struct copied from an
           address of unknown alignment (see docs/performance.md, "The omp
           offload kernels on sm_90")
  glob     ld.global (scalar and vector), of which .nc (read-only path)
  gen      generic loads (ld.u32 etc.: address space not known)
  vec      vector loads (ld.*.v2/v4)
  local    ld.local/st.local
  heap     calls of malloc / __kmpc_alloc_shared left in the kernel

--cl adds the same lines for the OpenCL kernels (kernels/cl/neighbors.cl,
step.cl) compiled by clang-16 for nvptx64 as plain kernels: a proxy of
NVIDIA's OpenCL compiler (not the same compiler; the same items, without the
OpenMP runtime and its argument passing).

Needs clang-16 and CUDA's ptxas (/usr/local/cuda/bin, or $CUDA_PATH/bin);
no GPU.  Prints a Markdown table; --out keeps the PTX, remarks and logs.
"""
import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from collections import Counter, defaultdict

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFAULT_SOURCES = ["src/backend/omp/step_omp.c", "src/backend/omp/neighbors.c", "src/backend/omp/reorder.c",
                   "src/backend/omp/observe.c"]
CL_SOURCES = ["kernels/cl/step.cl", "kernels/cl/neighbors.cl"]
# Stand-ins for the OpenCL built-ins the kernels call (no libclc here).
CL_PRELUDE = r"""
#define get_global_id(d) ((size_t)(__nvvm_read_ptx_sreg_ctaid_x() * __nvvm_read_ptx_sreg_ntid_x() + __nvvm_read_ptx_sreg_tid_x()))
#define get_local_id(d) ((size_t)__nvvm_read_ptx_sreg_tid_x())
#define get_local_size(d) ((size_t)__nvvm_read_ptx_sreg_ntid_x())
#define get_group_id(d) ((size_t)__nvvm_read_ptx_sreg_ctaid_x())
#define sqrt(x) __builtin_sqrt(x)
#define floor(x) __builtin_floor(x)
#define fabs(x) __builtin_fabs(x)
#define sin(x) __nv_sin(x)
#define cos(x) __nv_cos(x)
double __nv_sin(double);
double __nv_cos(double);
static inline int cd_prelude_atomic_inc(volatile __global int *p)
{
    int r;
    __asm__ volatile("atom.global.add.u32 %0, [%1], 1;" : "=r"(r) : "l"(p) : "memory");
    return r;
}
#define atomic_inc(p) cd_prelude_atomic_inc(p)
"""


def sh(cmd, cwd=None):
    return subprocess.run(cmd, cwd=cwd, shell=isinstance(cmd, str), capture_output=True, text=True)


def flags_of(build):
    fm = os.path.join(build, "CMakeFiles", "capdem_engine.dir", "flags.make")
    if not os.path.exists(fm):
        sys.exit(f"read_kernels.py: {fm} missing: BUILD must be a configured Clang nvptx build tree")
    vals = {}
    for line in open(fm):
        m = re.match(r"^(C_DEFINES|C_INCLUDES|C_FLAGS) = (.*)$", line)
        if m:
            vals[m.group(1)] = m.group(2)
    flags = " ".join(vals.get(k, "") for k in ("C_DEFINES", "C_INCLUDES", "C_FLAGS"))
    if "nvptx64" not in flags:
        sys.exit(f"read_kernels.py: {fm}: not an nvptx offload build (no -fopenmp-targets=nvptx64-...)")
    return flags


def short(name):
    return re.sub(r"^__omp_offloading_[0-9a-f]+_[0-9a-f]+_", "", name)


def entries(ptx):
    """{entry name: its PTX text} (each entry's body up to the closing brace)."""
    out, name, body = {}, None, []
    for line in ptx.splitlines():
        m = re.match(r"^\.(?:visible|weak)?\s*\.entry\s+([\w$.]+)\(", line) or re.match(r"^\.(?:visible |weak )?\.entry ([\w$.]+)", line)
        if m:
            name, body = m.group(1), []
        if name is not None:
            body.append(line)
            if line.startswith("}"):
                out[name] = "\n".join(body)
                name = None
    return out


def count_ops(body):
    c = Counter()
    for m in re.finditer(r"^\s+(?:@%p\d+\s+)?((?:ld|st|call|atom)[\w.]*)\s+(.*)$", body, re.M):
        op = m.group(1)
        parts = op.split(".")
        if parts[0] == "call":
            callee = re.search(r"\b(malloc|__kmpc_alloc_shared|free)\b", body[m.end():m.end() + 200])
            if callee:
                c["heap"] += 1
            continue
        if parts[0] not in ("ld", "st"):
            continue
        space = "gen"
        for s in ("global", "local", "shared", "param", "const"):
            if s in parts:
                space = s
        if parts[0] == "ld":
            if space in ("param", "shared", "const"):
                continue
            if any(p in ("u8", "s8", "b8") for p in parts):
                c["ld_u8"] += 1
            if any(p in ("v2", "v4") for p in parts):
                c["ld_vec"] += 1
            if space == "global":
                c["ld_global"] += 1
                if "nc" in parts:
                    c["ld_nc"] += 1
            elif space == "gen":
                c["ld_gen"] += 1
            elif space == "local":
                c["local"] += 1
        else:
            if space in ("param", "shared"):
                continue
            if any(p in ("u8", "s8", "b8") for p in parts):
                c["st_u8"] += 1
            if space == "local":
                c["local"] += 1
    return c


def ptxas_info(ptxas, s_file, log, relocatable=False):
    """{entry: (regs, stack, spill_st, spill_ld)} from ptxas -v (-c: code
    that calls functions defined elsewhere, e.g. libdevice's sin)."""
    r = sh([ptxas, "-arch=sm_90", "-O3", "-v"] + (["-c"] if relocatable else []) + [s_file, "-o", os.devnull])
    open(log, "w").write(r.stderr)
    if r.returncode:
        sys.exit(f"read_kernels.py: ptxas failed on {s_file}:\n{r.stderr[-2000:]}")
    info, cur = {}, None
    for line in r.stderr.splitlines():
        m = re.search(r"Function properties for ([\w$.]+)", line)
        if m:
            cur = m.group(1)
            info.setdefault(cur, [0, 0, 0, 0])
            continue
        m = re.search(r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads", line)
        if m and cur:
            info[cur][1:4] = [int(x) for x in m.groups()]
        m = re.search(r"Used (\d+) registers", line)
        if m and cur:
            info[cur][0] = int(m.group(1))
    return info


def remarks_of(text):
    """Counter of (code, file:line) of the openmp-opt remarks."""
    rem = Counter()
    for m in re.finditer(r"^(?:remark: )?(\S+?):(\d+):\d+: (?:remark: )?.*?\[(OMP\d+)\]", text, re.M):
        rem[(m.group(3), os.path.relpath(m.group(1), ROOT) if m.group(1).startswith("/") else m.group(1),
             int(m.group(2)))] += 1
    return rem


def occupancy(regs, threads=128):
    if not regs:
        return "-"
    per_reg = 65536 // (max(regs, 24) * threads)
    teams = min(per_reg, 16)
    return f"{teams * threads // 32}"


def row(name, mode, info, ops):
    regs, stack, sst, sld = info
    return (f"| {name} | {mode} | {regs} | {occupancy(regs)} | {stack} / {sst} / {sld} | {ops['ld_u8']} / {ops['st_u8']} "
            f"| {ops['ld_global']} ({ops['ld_nc']} nc) | {ops['ld_gen']} | {ops['ld_vec']} | {ops['local']} | {ops['heap']} |")


HEADER = ("| kernel | mode | regs | warps/SM | stack / spill st / ld [B] | u8 ld / st | ld.global | generic ld "
          "| vector ld | local ld+st | heap calls |\n|---|---|---|---|---|---|---|---|---|---|---|")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("build")
    ap.add_argument("--out", help="keep PTX, remarks and ptxas logs here")
    ap.add_argument("--sources", nargs="*", default=DEFAULT_SOURCES)
    ap.add_argument("--cl", action="store_true", help="also the OpenCL kernels compiled for nvptx64 (proxy)")
    ap.add_argument("--only", help="regular expression: kernels to print")
    ap.add_argument("--dry-run", action="store_true", help="print the commands, compile nothing")
    args = ap.parse_args()
    cuda = os.environ.get("CUDA_PATH", "/usr/local/cuda")
    ptxas = shutil.which("ptxas") or os.path.join(cuda, "bin", "ptxas")
    clang = shutil.which("clang-16") or "clang-16"
    build = os.path.abspath(args.build)
    flags = flags_of(build)
    if args.dry_run:
        out = os.path.abspath(args.out or "OUT")
    else:
        out = os.path.abspath(args.out) if args.out else tempfile.mkdtemp(prefix="read_kernels.")
        os.makedirs(out, exist_ok=True)
    only = re.compile(args.only) if args.only else None
    rems = Counter()
    print(HEADER)
    for src in args.sources:
        path = os.path.join(ROOT, src)
        base = os.path.splitext(os.path.basename(src))[0]
        cmd = (f"{clang} {flags} -c {shlex.quote(path)} -o {base}.o -save-temps "
               f"-Rpass=openmp-opt -Rpass-analysis=openmp-opt -Rpass-missed=openmp-opt")
        if args.dry_run:
            print(f"(cd {out} && {cmd})\n(cd {out} && {ptxas} -arch=sm_90 -O3 -v {base}-openmp-nvptx64-nvidia-cuda-sm_90.s)")
            continue
        r = sh(cmd, cwd=out)
        open(os.path.join(out, base + ".remarks"), "w").write(r.stderr)
        if r.returncode:
            sys.exit(f"read_kernels.py: compiling {src} failed:\n{r.stderr[-3000:]}")
        rems.update(remarks_of(r.stderr))
        s_file = os.path.join(out, f"{base}-openmp-nvptx64-nvidia-cuda-sm_90.s")
        ptx = open(s_file).read()
        info = ptxas_info(ptxas, s_file, os.path.join(out, base + ".ptxas.log"))
        modes = {m.group(1): {"1": "generic", "2": "SPMD", "3": "generic-SPMD"}.get(m.group(2), m.group(2))
                 for m in re.finditer(r"\.u8 ([\w$.]+)_exec_mode = (\d+);", ptx)}
        for name, body in entries(ptx).items():
            if only and not only.search(short(name)):
                continue
            print(row(short(name), modes.get(name, "?"), info.get(name, [0, 0, 0, 0]), count_ops(body)))
    if args.cl and not args.dry_run:
        pre = os.path.join(out, "cl_prelude.h")
        open(pre, "w").write(CL_PRELUDE)
        for src in CL_SOURCES:
            base = os.path.splitext(os.path.basename(src))[0] + "_cl"
            s_file = os.path.join(out, base + ".ptx")
            r = sh([clang, "-x", "cl", "-cl-std=CL1.2", "-D__OPENCL_VERSION__=120", "-target", "nvptx64-nvidia-cuda",
                    "-march=sm_90", "-Xclang", "-finclude-default-header", "-include", pre, "-O3",
                    "-I" + os.path.join(ROOT, "kernels"), "-S", os.path.join(ROOT, src), "-o", s_file])
            if r.returncode:
                sys.exit(f"read_kernels.py: compiling {src} as OpenCL C failed:\n{r.stderr[-3000:]}")
            ptx = open(s_file).read()
            info = ptxas_info(ptxas, s_file, os.path.join(out, base + ".ptxas.log"), ".extern" in ptx)
            for name, body in entries(ptx).items():
                if only and not only.search(name):
                    continue
                print(row("(OpenCL) " + name, "kernel", info.get(name, [0, 0, 0, 0]), count_ops(body)))
    if rems:
        print("\nopenmp-opt remarks (code, place, count):")
        by = defaultdict(list)
        for (code, f, line), n in sorted(rems.items()):
            by[code].append(f"{f}:{line}" + (f" x{n}" if n > 1 else ""))
        for code, places in sorted(by.items()):
            print(f"  {code} ({len(places)}): " + ", ".join(places))
    if args.out:
        print(f"\n(PTX, remarks and ptxas logs in {out})")
    elif not args.dry_run:
        shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
