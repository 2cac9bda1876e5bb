/* The loops of the OpenMP backend (src/backend/omp/step_omp.c, the time step;
 * src/backend/omp/neighbors.c, the Verlet-list build), and the memory they run on.
 * Two variants of every loop (docs/offload.md):
 * - host (CAPDEM_OFFLOAD=none): `omp parallel for schedule(static)` over
 *   host memory;
 * - offload (CAPDEM_OFFLOAD=nvptx|host, CAPDEM_OFFLOAD_TARGET=1): `omp
 *   target teams distribute parallel for` over device memory: the state's
 *   columns mapped once at start, the neighbour lists and the build's
 *   scratch allocated on the device (cd_dev_alloc), handed to the loops as
 *   device addresses inside one device-resident argument block
 *   (src/backend/omp/step_device.h, CD_ARGS).
 * A function with a CD_STEP_FOR loop declares CD_WIDE_MIN first. */
#ifndef CD_OMP_LOOPS_H
#define CD_OMP_LOOPS_H
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include "core/sim.h"
#ifdef _OPENMP
#include <omp.h>
#endif

#define CD_PRAGMA(...) _Pragma(#__VA_ARGS__)
#if defined(CAPDEM_OFFLOAD_TARGET) && CAPDEM_OFFLOAD_TARGET && defined(_OPENMP)
#define CD_OFFLOAD 1
/* One loop of the step on the offload device, or on the host when the
 * runtime finds none: then, as in the host variant, a loop of fewer than
 * cd_parallel_min_rows rows runs on one thread (waking threads for every
 * small loop made the small test cases 100 times slower).  The same holds
 * on LLVM's host offload devices (CAPDEM_OFFLOAD=host), whose teams are
 * host threads: there test_protocols took over 300 s instead of 47 s. */
static inline size_t cd_wide_min(void)
{
#if defined(CAPDEM_OFFLOAD_HOSTDEV) && CAPDEM_OFFLOAD_HOSTDEV
    return (size_t)cd_parallel_min_rows;
#elif defined(__clang__)
    /* Clang's GPU build: 0 also without a device (a machine without a GPU,
     * or OMP_TARGET_OFFLOAD=DISABLED: the target regions run on the host),
     * where LLVM 16's libomp aborts (kmp_runtime.cpp(1128), th_task_team)
     * once a process's host-run target regions mix a parallel inner region
     * and a serialized one (if (parallel : 0)); every one parallel, it
     * runs.  Found by bench/gpu_bundle.sh --no-gcc, whose settling runs
     * this build here (1,000 hexapods on two threads aborted at the first
     * neighbour-list build). */
    return 0;
#else
    static int devices = -1;
    if (devices < 0) devices = omp_get_num_devices();
    return devices > 0 ? 0 : (size_t)cd_parallel_min_rows;
#endif
}
/* (unused where a loop needs no test: CD_ONE_TEAM on host devices) */
#define CD_WIDE_MIN const size_t wide_min_ __attribute__((unused)) = cd_wide_min();
#if defined(CAPDEM_OFFLOAD_HOSTDEV) && CAPDEM_OFFLOAD_HOSTDEV
/* Host devices: teams of one thread each (host threads), one team for a
 * small loop.  No inner parallel: a serialized one (if (parallel : 0))
 * trips an assertion of libomp 14 (kmp_runtime.cpp(1122), th_task_team). */
#define CD_STEP_FOR(rows, ...)                                                                                         \
    CD_PRAGMA(omp target teams distribute num_teams((size_t)(rows) >= wide_min_ ? omp_get_max_threads() : 1)           \
                  __VA_ARGS__)
#else
#define CD_STEP_FOR(rows, ...)                                                                                         \
    CD_PRAGMA(omp target teams distribute parallel for if (parallel : (size_t)(rows) >= wide_min_) __VA_ARGS__)
#endif
/* A small step's loops in one launch (src/backend/omp/step_omp.c,
 * forces_and_advance): `CD_ONE_TEAM(rows, clauses)` opens a region of
 * one team whose threads share the loops marked `CD_TEAM_FOR(clauses)`,
 * with a barrier after each unless `nowait`.  On a GPU that is one launch
 * where separate loops were one each (about 8 us apiece, synchronous:
 * small systems are bound by it); on host devices the region is one
 * thread running the loops in turn, as its one-team loops did. */
#if defined(CAPDEM_OFFLOAD_HOSTDEV) && CAPDEM_OFFLOAD_HOSTDEV
#define CD_ONE_TEAM(rows, ...) CD_PRAGMA(omp target __VA_ARGS__)
#define CD_TEAM_FOR(...)
#else
#define CD_ONE_TEAM(rows, ...) CD_PRAGMA(omp target parallel if (parallel : (size_t)(rows) >= wide_min_) __VA_ARGS__)
#define CD_TEAM_FOR(...)       CD_PRAGMA(omp for schedule(static) __VA_ARGS__)
#endif
/* Clauses only the offload variant needs. */
#define CD_DEV(...) __VA_ARGS__

/* 1 when the loops run on the host's own columns: a runtime without an
 * offload device (libgomp's host fallback) runs the target regions in the
 * one memory, where mapping is the identity and a "device" column is the
 * host column.  The backend then keeps the host variant's memory-order
 * state (src/backend/omp/reorder.c): a sync puts the columns the steps run
 * on in user order, and the next step or build puts them back. */
static inline int cd_step_memory_is_host(void)
{
    static int devices = -1;
    if (devices < 0) devices = omp_get_num_devices();
    return devices == 0;
}

/* The device the loops run on: the default offload device, or the host
 * when the runtime finds none (the loops then fall back to it too). */
static inline int cd_dev_id(void)
{
    return omp_get_num_devices() > 0 ? omp_get_default_device() : omp_get_initial_device();
}
static inline void *cd_dev_alloc(size_t bytes) { return omp_target_alloc(bytes ? bytes : 1, cd_dev_id()); }
static inline void cd_dev_free(void *p)
{
    if (p) omp_target_free(p, cd_dev_id());
}
/* bytes from device address src to host address dst (0 on success) */
static inline int cd_dev_get(void *dst, const void *src, size_t bytes)
{
    return omp_target_memcpy(dst, (void *)src, bytes, 0, 0, omp_get_initial_device(), cd_dev_id());
}
/* bytes from host address src to device address dst (0 on success) */
static inline int cd_dev_put(void *dst, const void *src, size_t bytes)
{
    return omp_target_memcpy(dst, (void *)src, bytes, 0, 0, cd_dev_id(), omp_get_initial_device());
}
#else
#define CD_OFFLOAD 0
#define CD_WIDE_MIN
#define CD_STEP_FOR(rows, ...) CD_PRAGMA(omp parallel for schedule(static) if (CD_PARALLEL(rows)) __VA_ARGS__)
#define CD_DEV(...)
static inline int cd_step_memory_is_host(void) { return 1; }
static inline void *cd_dev_alloc(size_t bytes) { return malloc(bytes ? bytes : 1); }
static inline void cd_dev_free(void *p) { free(p); }
/* (no bytes: either address may be null, which memcpy does not allow) */
static inline int cd_dev_get(void *dst, const void *src, size_t bytes)
{
    if (bytes) memcpy(dst, src, bytes);
    return 0;
}
static inline int cd_dev_put(void *dst, const void *src, size_t bytes)
{
    if (bytes) memcpy(dst, src, bytes);
    return 0;
}
#endif
/* Host-only loops (set-up work on the host columns). */
#define CD_HOST_FOR(rows, ...) CD_PRAGMA(omp parallel for schedule(static) if (CD_PARALLEL(rows)) __VA_ARGS__)

/* The host threads' sweep (src/backend/omp/sweep.c): steps 5-8 of a step
 * and, with next = 1, steps 1-4 of the next one (returns its skin test),
 * for host threads; and what it needs of a neighbour-list build, made at
 * its end (0, or -1: out of memory, or rows out of memory order; nothing
 * in the offload variant). */
int cd_omp_sweep(cd_sim *sim, int next);
int cd_omp_sweep_lists(cd_sim *sim);
/* Does the sweep interleave rows and moves (the step's state above
 * cd_sweep_min_bytes; never in the offload variant)? */
int cd_omp_sweep_interleaves(const cd_sim *sim);

/* The columns the loops work on: device addresses in the offload variant
 * once the state is mapped, the host columns otherwise (src/backend/omp/step_omp.c). */
cd_cols cd_sim_step_cols(cd_sim *sim);
/* The offload variant: the state's columns mapped to the device again
 * after the host replaced them (the MPI migration, src/mpi/mpi_device.c,
 * with the backend stopped before), without start's refresh of the
 * derived columns, which are current.  0, or -1 with err set. */
int cd_sim_step_remap(cd_sim *sim, char *err, size_t errlen);

/* Copies of the loops' argument block to the device since the backend
 * started (src/backend/omp/step_device.c, cd_off_args): copies[0] of its
 * head (addresses, laws, order: the span that changed), copies[1] of its
 * walls, and their bytes (bytes may be NULL); all 0 on host threads,
 * where nothing is copied. */
void cd_sim_step_arg_copies(const cd_sim *sim, long long copies[2], long long bytes[2]);

/* The column of field f (cd_fields) the loops work on (src/backend/omp/step_omp.c). */
void *cd_sim_step_field(cd_sim *sim, size_t f);

/* out[0] = 0, out[k+1] = out[k] + in[k] for k < n, where the loops run
 * (src/backend/omp/neighbors.c); chunk_sum: the build's scratch. */
void cd_nb_scan(const cd_int *in, cd_int n, cd_int *out, cd_int *chunk_sum);

/* Room for n pair rows in the columns the loops work on: the host columns
 * grow (cd_state_reserve_pairs, contents kept); in the offload variant the
 * device copies are re-mapped at their new size, contents not kept (the
 * build keeps what it needs first).  0, or -1 out of memory. */
int cd_sim_reserve_step_pairs(cd_sim *sim, size_t n);

#endif
