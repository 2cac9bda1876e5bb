/* The material point method step's checks, kept where the loops run so
 * that the host reads nothing between steps (docs/mpm.md, "Reading
 * nothing between steps"): the omp loops (src/mpm/mpm.c, host threads or
 * an offload device) and the OpenCL kernels (kernels/cl/mpm.cl) both
 * record failures here and run their counts and observed sums into it;
 * the host reads it only where the run reads the state (cd_mpm_settle).
 * Device-safe: C11 and OpenCL C.
 *
 *   flags[f]                the highest bad index of failure f, or -1;
 *   flags[CD_MPM_N_FAILS + f]  the step it was first seen at, counted from
 *                           the host's last look, or CD_MPM_NEVER;
 *   counts                  body-nodes, listed common nodes, contact keys;
 *   reals                   an observed step's sums: the walls' forces
 *                           [N/m], the deepest overlap [m], the mesh's
 *                           kinetic energy [J/m].
 * A loop at stage s of the step does nothing once a failure was seen at
 * an earlier step, or at this step by a check of an earlier stage
 * (cd_mpm_stopped): the state stays as the failing step left it, as when
 * the step returned at once. */
#ifndef CD_MPM_CHECKS_H
#define CD_MPM_CHECKS_H
#include "defs.h"
#include "mpm_step_items.h"
#include "mpm_contact.h"

/* Failures, in the step's order (also their stages). */
#define CD_MPM_FAIL_LEFT     0 /* a point's stencil left the mesh (stage 0) */
#define CD_MPM_FAIL_OVERFLOW 1 /* the body-nodes need more rows than their columns hold (stage 1) */
#define CD_MPM_FAIL_CROWDED  2 /* more bodies at a common node than the contact handles (stage 2) */
#define CD_MPM_FAIL_BLEW_UP  3 /* a point not finite or its volume gone (stage 3) */
#define CD_MPM_N_FAILS       4
#define CD_MPM_NEVER         0x7fffffff
#define CD_MPM_COUNT_BNODES  0
#define CD_MPM_COUNT_LISTED  1
#define CD_MPM_COUNT_KEYS    2
#define CD_MPM_N_COUNTS      3
#define CD_MPM_REAL_WALLS    0
#define CD_MPM_REAL_PEN      (2 * CD_MPM_ITEM_MAX_WALLS)
#define CD_MPM_REAL_KINETIC  (CD_MPM_REAL_PEN + 1)
#define CD_MPM_N_REALS       (CD_MPM_REAL_KINETIC + 1)

CD_DEVICE_BEGIN

/* Integer atomics only (the same answer in any order; never a sum). */
#ifdef __OPENCL_VERSION__
#define cd_mpm_atomic_max(p, v) atomic_max(p, v)
#define cd_mpm_atomic_min(p, v) atomic_min(p, v)
#else
CD_INLINE void cd_mpm_atomic_max(cd_int *p, cd_int v)
{
    cd_int old = __atomic_load_n(p, __ATOMIC_RELAXED);
    while (old < v && !__atomic_compare_exchange_n(p, &old, v, 1, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {}
}
CD_INLINE void cd_mpm_atomic_min(cd_int *p, cd_int v)
{
    cd_int old = __atomic_load_n(p, __ATOMIC_RELAXED);
    while (old > v && !__atomic_compare_exchange_n(p, &old, v, 1, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {}
}
#endif

/* 1 when a failure was seen at an earlier step, or at step j by one of the
 * checks of a stage before this one (f < stage). */
CD_INLINE cd_int cd_mpm_stopped(CD_GLOBAL const cd_int *flags, cd_int j, cd_int stage)
{
    for (cd_int f = 0; f < CD_MPM_N_FAILS; f++) {
        cd_int at = flags[CD_MPM_N_FAILS + f];
        if (at < j || (f < stage && at == j)) return 1;
    }
    return 0;
}

/* Failure f at index i, seen at step j: the highest index and the first step. */
CD_INLINE void cd_mpm_fail(CD_GLOBAL cd_int *flags, cd_int f, cd_int i, cd_int j)
{
    cd_mpm_atomic_max(&flags[f], i);
    cd_mpm_atomic_min(&flags[CD_MPM_N_FAILS + f], j);
}

/* One item: the checks as before any step: no failure, never seen, nothing counted or summed. */
CD_INLINE void cd_mpm_checks_clear(CD_GLOBAL cd_int *flags, CD_GLOBAL cd_ulong *counts, CD_GLOBAL cd_real *reals)
{
    for (cd_int f = 0; f < CD_MPM_N_FAILS; f++) {
        flags[f] = -1;
        flags[CD_MPM_N_FAILS + f] = CD_MPM_NEVER;
    }
    for (cd_int i = 0; i < CD_MPM_N_COUNTS; i++) counts[i] = 0;
    for (cd_int i = 0; i < CD_MPM_N_REALS; i++) reals[i] = 0;
}

/* ---- the items of the step with their checks (stage, failure) */

/* Stage 0: point p's stencil and wall forces; LEFT. */
CD_INLINE void cd_mpm_checked_prepare(cd_mpm_cols c, cd_ulong p, cd_mpm_item_walls walls, CD_GLOBAL cd_int *flags,
                                      cd_int j)
{
    if (!cd_mpm_stopped(flags, j, 0) && cd_mpm_item_prepare(c, p, walls))
        cd_mpm_fail(flags, CD_MPM_FAIL_LEFT, (cd_int)p, j);
}

/* Stage 1, one item: the windows' offsets, the body-node count into
 * counts[CD_MPM_COUNT_BNODES]; OVERFLOW when it passes cap rows. */
CD_INLINE void cd_mpm_checked_window_offsets(cd_mpm_cols c, CD_GLOBAL cd_ulong *counts, cd_ulong cap,
                                             CD_GLOBAL cd_int *flags, cd_int j)
{
    if (cd_mpm_stopped(flags, j, 1)) return;
    cd_mpm_item_window_offsets(c, counts + CD_MPM_COUNT_BNODES);
    if (counts[CD_MPM_COUNT_BNODES] > cap) cd_mpm_fail(flags, CD_MPM_FAIL_OVERFLOW, 0, j);
}

/* Stage 2, listed common node ci (those past the count do nothing): CROWDED. */
CD_INLINE void cd_mpm_checked_crowded(cd_mpm_cols c, cd_ulong ci, CD_GLOBAL const cd_ulong *counts,
                                      CD_GLOBAL cd_int *flags, cd_int j)
{
    if (ci >= counts[CD_MPM_COUNT_LISTED] || cd_mpm_stopped(flags, j, 2)) return;
    if (cd_mpm_item_contact_crowded(c, ci)) cd_mpm_fail(flags, CD_MPM_FAIL_CROWDED, (cd_int)c.cn_list[ci], j);
}

/* Stage 3, listed common node ci: its contacts, and its deepest overlap
 * (0 if none) [m] into over[ci]. */
CD_INLINE void cd_mpm_checked_contact(cd_mpm_cols c, cd_ulong ci, cd_real gap_max, cd_real dt, CD_GLOBAL cd_real *over,
                                      CD_GLOBAL const cd_ulong *counts, CD_GLOBAL const cd_int *flags, cd_int j)
{
    if (ci >= counts[CD_MPM_COUNT_LISTED] || cd_mpm_stopped(flags, j, 3)) return;
    cd_real o = 0;
    cd_mpm_item_contact(c, ci, gap_max, dt, &o);
    over[ci] = o;
}

/* Stage 3, observed steps only, one item: the largest of the overlaps and
 * 0 [m] into reals[CD_MPM_REAL_PEN] (a maximum: the same in any order). */
CD_INLINE void cd_mpm_checked_max_over(CD_GLOBAL const cd_real *over, CD_GLOBAL const cd_ulong *counts,
                                       CD_GLOBAL cd_real *reals, CD_GLOBAL const cd_int *flags, cd_int j)
{
    if (cd_mpm_stopped(flags, j, 3)) return;
    cd_real m = 0;
    for (cd_ulong ci = 0; ci < counts[CD_MPM_COUNT_LISTED]; ci++)
        if (over[ci] > m) m = over[ci];
    reals[CD_MPM_REAL_PEN] = m;
}

/* Stage 3: point p's stress, deformation gradient and volume; BLEW_UP. */
CD_INLINE void cd_mpm_checked_stress(cd_mpm_cols c, cd_ulong p, cd_real dt, cd_mpm_material mat,
                                     CD_GLOBAL cd_int *flags, cd_int j)
{
    if (!cd_mpm_stopped(flags, j, 3) && cd_mpm_item_stress(c, p, dt, mat))
        cd_mpm_fail(flags, CD_MPM_FAIL_BLEW_UP, (cd_int)p, j);
}

CD_DEVICE_END
#endif
