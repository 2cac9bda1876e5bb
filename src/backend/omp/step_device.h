/* The omp backend's step arguments and, in the offload variant, the
 * state's residency on the device: the columns mapped once, their device
 * addresses, the pair columns re-mapped when they grow, and the argument
 * block every loop of a step reads (src/backend/omp/step_device.c; used by
 * src/backend/omp/step_omp.c). */
#ifndef CAPDEM_STEP_DEVICE_H
#define CAPDEM_STEP_DEVICE_H

#include "backend/omp/omp_loops.h"

/* What every loop of a step takes besides its row count: the columns, the
 * lists, the laws and the walls, as one block.  In the offload variant the
 * block is one global of the device image (cd_step_block, below): the
 * loops read it by name, so a launch copies and allocates nothing and, on
 * an NVIDIA GPU, the block sits in constant memory; a firstprivate struct
 * was one packed host-to-device copy per launch (280-624 B;
 * docs/offload.md, "Per-step copies").  The walls come last: they change
 * every step while a protocol moves one, the rest only when a build or a
 * re-map moves the buffers. */
typedef struct {
    cd_cols c;
    cd_nb_lists d;
    cd_order order; /* memory order maps where the loops run (cd_sim_step_order) */
    cd_law_params law, wall_law;
    cd_vec3 gravity;                  /* [m/s^2] */
    cd_real dt, sin_parallel, limit2; /* [s], [1], (skin/2)^2 [m^2] */
    cd_int blend, dimension, n_walls; /* material.parallel_blend, 2 or 3, walls in use */
    cd_int fixed_spheres;             /* physics.sphere_orientation: fixed (and walls 8-byte aligned) */
    cd_wall walls[CD_MAX_WALLS];      /* the first n_walls are in use */
} cd_step_args;

#if CD_OFFLOAD
/* The state's derived step rows mapped beside the columns (cd_off). */
#define CD_OFF_DERIVED 4
/* What the offload variant keeps in sim->backend_data. */
typedef struct {
    void **host;   /* per field of cd_fields: host address mapped (NULL: none) */
    size_t *bytes; /* per field: bytes mapped */
    /* the state's prim_arm, arm, step_inertia and inertia_iso, mapped
     * (kernels/cols.h; NULL: none) */
    void *arm_host[CD_OFF_DERIVED];
    size_t arm_bytes[CD_OFF_DERIVED]; /* their bytes mapped */
    /* the host's force and torque columns, mapped where the step holds
     * them (kernels/cols.h: an MPI rank; from a start to its first
     * advance), else NULL */
    void *force_host[2];
    size_t force_bytes;
    double *part; /* per-chunk partial sums of the wall load (mapped) */
    size_t part_n;
    cd_cols dev;              /* device addresses of the columns */
    long long args_copies[2]; /* copies of the block's head and of its walls since start */
    long long args_bytes[2];  /* their bytes */
} cd_off;

/* Maps every column of the host state to the device (once per run); 0 on
 * success, -1 with err set. */
int cd_off_acquire(cd_sim *sim, char *err, size_t errlen);
/* Unmaps everything and frees sim->backend_data. */
void cd_off_release(cd_sim *sim);
/* Copies bytes at host address p back from the device. */
void cd_off_from(void *p, size_t bytes);
/* Maps (map = 1: copied to the device) or unmaps the host's force and
 * torque columns, the step's while mapped (kernels/cols.h, cd_cols.force). */
void cd_off_force_map(cd_sim *sim, int map);
/* The mapped force and torque back into the host's columns. */
void cd_off_force_from(cd_sim *sim);
/* Device copies of the host's force and torque columns for the sums of a
 * sync, outside the step's columns (so the loops' argument block does
 * not change: docs/offload.md, "Per-step copies"): map = 1 maps them
 * (nothing copied) and gives their device addresses in *F, *T; map = 0
 * copies them back into the host's columns and unmaps them. */
void cd_off_force_sums(cd_sim *sim, int map, cd_vec3 **F, cd_vec3 **T);
/* Brings the device's argument block (cd_step_block) up to date for this
 * state (`target update`: a copy the device refuses stops the run in the
 * OpenMP runtime, which has no error return for it). */
void cd_off_args_or_die(cd_sim *sim);

/* The loops' argument block: one global of the host program and of the
 * device image (declare target), sent by cd_off_args_or_die, read by the
 * loops by name.  Clang puts it in the GPU's constant memory
 * (omp_const_mem_alloc, src/backend/omp/step_device.c): loaded with
 * ld.const, which no store of the kernel can change, so that ptxas need
 * not hold the column addresses in registers for the whole kernel (pair
 * forces 197 -> 160 registers; docs/performance.md, "Session 16").  One block per process: a launch
 * fills it for the state it steps. */
#pragma omp declare target
extern cd_step_args cd_step_block;
#if defined(__clang__) && __clang_major__ >= 16
/* (every file that reads it must know where it lives) */
#pragma omp allocate(cd_step_block) allocator(omp_const_mem_alloc)
#endif
#pragma omp end declare target
#endif

/* The block for the state as it is now, padding zeroed (blocks are
 * compared byte by byte). */
void cd_step_args_fill(cd_sim *sim, cd_step_args *a);

/* Called by a neighbour-list build before it replaces the rows: a build
 * between calls of the step (tests do it) takes away the rows the next
 * call's first advance would sum the force and torque from, so these go
 * to the host's columns first, where that advance then reads them (user
 * order; kernels/cols.h).  Nothing inside a call (its first advance has
 * used them), on an MPI rank (its step holds them) or after a start
 * without forces (the host's are current). */
void cd_sim_force_before_build(cd_sim *sim);

/* A loop's arguments: `CD_ARGS(sim)` makes the block for the state as it
 * is now, `CD_ARGS_IN` hands it to a CD_STEP_FOR loop and `CD_A` names
 * it there (`CD_A.c`, `CD_A.dt`).  Offload: the device's global
 * block, brought up to date (a launch copies nothing unless the block
 * changed); host threads: a block on the stack, shared by the threads.
 *
 * The passes of the neighbour-list build and the reorder read only the
 * columns, lists, order and walls: `CD_BUILD_ARGS(sim)` and `CD_BUILD_IN`,
 * and the loops name them `CD_B.c`, `CD_B.d`, `CD_B.order`, `CD_B.walls`.
 * Offload: the device's block (`CD_B` is cd_step_block); host threads: a
 * private copy of those alone per thread (cd_build_view, firstprivate, as
 * the structs of these loops were), which the compiler knows no store of
 * the loop can change: read through a shared pointer, every store to a
 * list reloaded the column addresses (the build took 5 % more
 * instructions, callgrind). */
#if CD_OFFLOAD
#define CD_ARGS(sim) cd_off_args_or_die(sim);
#define CD_ARGS_IN
#define CD_A               cd_step_block
#define CD_BUILD_ARGS(sim) CD_ARGS(sim)
#define CD_BUILD_IN
#define CD_B cd_step_block
#else
#define CD_ARGS(sim)                                                                                                   \
    cd_step_args a_;                                                                                                   \
    cd_step_args_fill(sim, &a_);                                                                                       \
    const cd_step_args *a = &a_;
#define CD_ARGS_IN         firstprivate(a)
#define CD_A               (*a)
typedef struct {
    cd_cols c;
    cd_nb_lists d;
    cd_order order;
    const cd_wall *walls; /* the state's walls */
} cd_build_view;
/* The columns, lists, order and walls of the state (host threads). */
static inline cd_build_view cd_build_view_of(cd_sim *sim)
{
    cd_build_view v;
    v.c = cd_sim_step_cols(sim);
    v.d = sim->nb.d;
    v.order = cd_sim_step_order(sim);
    v.walls = sim->s.walls;
    return v;
}
#define CD_BUILD_ARGS(sim) cd_build_view b_ = cd_build_view_of(sim);
#define CD_BUILD_IN        firstprivate(b_)
#define CD_B               b_
#endif

#endif
