#!/usr/bin/env bash
# Nsight Compute on the omp offload build and the OpenCL backend, side by
# side, per kernel: time, grid x block, registers, theoretical and achieved
# occupancy, local-memory loads and stores, global load instructions, DRAM
# bytes (docs/performance.md, "The omp offload kernels on sm_90, read from
# the compiler": what the compiler showed without a GPU, for a GPU run to
# confirm).  Part `kernels` of run_on_gpu.sh calls it with the bundle's
# paths; it runs on its own where the environment is set (LD_LIBRARY_PATH,
# an OpenCL ICD).
#
#   kernel_profile.sh [--dry-run] BENCH PACKING DIR
#
# BENCH: capdem-bench of the Clang 16 offload build; PACKING: a settled
# packing (hexapods_a3_n1000.h5), tiled CAPDEM_KERNELS_TILE (default 10,10:
# 1e5 hexapods); DIR: where the CSV files and logs go.  Three runs, each
# capdem-bench --relax-steps 0 --steps 8 (start, the first neighbour-list
# build, 8 steps), the first CAPDEM_KERNELS_LAUNCHES (160) launches profiled:
#   omp           the omp offload build as it is (pass 5 per primitive)
#   omp_particle  the same with CAPDEM_COLLECT_PER_PARTICLE=1 (pass 5 per
#                 particle, as host threads and OpenCL run it)
#   opencl        --backend opencl (NVIDIA's OpenCL goes through the same
#                 driver; whether ncu sees its kernels is for this run to
#                 say: the table then says "no kernel metrics")
# each under CAPDEM_KERNELS_CAP_S (35) seconds: about 110 s of device time
# in all at most.  A run whose metric list ncu refuses is run again with
# time, registers and achieved occupancy only.  Then bench/gpu/ncu_table.py
# prints the tables (stdout).
#
# --dry-run: checks the arguments and the tools, prints the ncu commands and
# runs ncu_table.py's self-test (the parser and tables on a synthetic CSV):
# what can be checked without a GPU (bench/gpu/check_bundle.sh runs it).
set -u -o pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
DRY=0
if [ "${1:-}" = --dry-run ]; then DRY=1; shift; fi
[ $# = 3 ] || { echo "usage: kernel_profile.sh [--dry-run] BENCH PACKING DIR" >&2; exit 2; }
BENCH=$1 PACK=$2 DIR=$3
[ -x "$BENCH" ] || { echo "kernel_profile.sh: $BENCH is not an executable capdem-bench" >&2; exit 2; }
[ -r "$PACK" ] || { echo "kernel_profile.sh: cannot read the packing $PACK" >&2; exit 2; }
TABLE=$HERE/ncu_table.py
[ -r "$TABLE" ] || { echo "kernel_profile.sh: $TABLE missing (it travels with this script)" >&2; exit 2; }
mkdir -p "$DIR"
TILE=${CAPDEM_KERNELS_TILE:-10,10}
CAP=${CAPDEM_KERNELS_CAP_S:-35}
LAUNCHES=${CAPDEM_KERNELS_LAUNCHES:-160}
NCU=${NCU:-$(command -v ncu || ls /usr/local/cuda/bin/ncu 2>/dev/null | head -1)}
FULL=gpu__time_duration.sum,launch__registers_per_thread,sm__maximum_warps_per_active_cycle_pct,sm__warps_active.avg.pct_of_peak_sustained_active,smsp__sass_inst_executed_op_local_ld.sum,smsp__sass_inst_executed_op_local_st.sum,l1tex__t_bytes_pipe_lsu_mem_local_op_ld.sum,l1tex__t_bytes_pipe_lsu_mem_local_op_st.sum,smsp__sass_inst_executed_op_global_ld.sum,dram__bytes_read.sum,dram__bytes_write.sum
BASIC=gpu__time_duration.sum,launch__registers_per_thread,sm__warps_active.avg.pct_of_peak_sustained_active
ARGS=(--load-settled "$PACK" --tile "$TILE" --relax-steps 0 --steps 8 --repeat 1 --device gpu)
RUNS=("omp||--backend omp" "omp_particle|CAPDEM_COLLECT_PER_PARTICLE=1|--backend omp" "opencl||--backend opencl")

profile() { # label env backend-args metrics -> DIR/ncu_<label>.csv
    local label=$1 envs=$2 be=$3 metrics=$4
    # shellcheck disable=SC2086
    timeout -k 5 "$CAP" env $envs "$NCU" --csv --launch-count "$LAUNCHES" --metrics "$metrics" \
        "$BENCH" "${ARGS[@]}" $be >"$DIR/ncu_$label.csv" 2>"$DIR/ncu_$label.err"
}

if [ $DRY = 1 ]; then
    echo "kernel_profile.sh --dry-run: bench $BENCH, packing $PACK, tile $TILE, ncu ${NCU:-(not found here)}"
    for r in "${RUNS[@]}"; do
        IFS='|' read -r label envs be <<<"$r"
        echo "  $label: timeout $CAP env $envs ncu --csv --launch-count $LAUNCHES --metrics $FULL $BENCH ${ARGS[*]} $be"
    done
    python3 "$TABLE" --self-test >"$DIR/ncu_table_selftest.txt" || { cat "$DIR/ncu_table_selftest.txt"; exit 1; }
    tail -1 "$DIR/ncu_table_selftest.txt"
    exit 0
fi

[ -n "$NCU" ] || { echo "kernel_profile.sh: no ncu on PATH or in /usr/local/cuda/bin" >&2; exit 1; }
rc=0
labels=()
for r in "${RUNS[@]}"; do
    IFS='|' read -r label envs be <<<"$r"
    s=$SECONDS
    profile "$label" "$envs" "$be" "$FULL"
    st=$?
    if [ $st != 0 ] && grep -qi 'metric' "$DIR/ncu_$label.err" && [ $((SECONDS - s)) -lt $((CAP / 2)) ]; then
        echo "kernel_profile.sh: $label: ncu refused the metric list, again with $BASIC"
        profile "$label" "$envs" "$be" "$BASIC"
        st=$?
    fi
    echo "kernel_profile.sh: $label: rc $st in $((SECONDS - s)) s; $(grep -c '^"' "$DIR/ncu_$label.csv") metric lines; $(tail -2 "$DIR/ncu_$label.err" | tr '\n' ' ' | cut -c1-200)"
    [ $st = 0 ] || rc=1
    labels+=("$label=$DIR/ncu_$label.csv")
done
echo
python3 "$TABLE" "${labels[@]}" || rc=1
exit $rc
