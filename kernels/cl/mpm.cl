/* The material point method's step as OpenCL kernels (docs/mpm.md, "The
 * OpenCL backend"): one work-item per point, body, body-node or listed
 * common node, each a thin wrapper around the items of
 * kernels/mpm_step_items.h and kernels/mpm_contact.h that the omp loops of
 * src/mpm/mpm.c run too.  What the omp loops do in one item is parallel
 * here where the result is a count (the points' sort, one item per body;
 * the common nodes' lists, in six kernels); the sums in a fixed order (the
 * walls' forces, the mesh's kinetic energy) and the deepest overlap stay
 * one item (per wall) and run only at the steps the host reads them.  src/mpm/mpm_cl.c launches them without reading anything back
 * between steps.
 *
 * Every kernel takes the columns of kernels/cl/mpm_col_list.h first, then
 * the mesh, then the step's checks: flags (cd_int[8]: the failures LEFT,
 * OVERFLOW, CROWDED, BLEW_UP in the step's order, each the highest bad
 * index or -1, then the step each was first seen at, counted from the last
 * time the host looked, or CD_MPM_CL_NEVER), counts (cd_ulong[3]: body-nodes,
 * listed common nodes, contact keys) and j, this step's number counted
 * likewise.  A kernel at stage s of the step does nothing once a failure
 * was seen at an earlier step, or at this step by a kernel before it
 * (cd_mpm_cl_stopped): the state stays as the failing step left it, as
 * the omp loops leave it when they return, and the host finds out at its
 * next look (cd_mpm_cl_settle). */
#include "../mpm_step_items.h"
#include "../mpm_contact.h"
#include "mpm_col_list.h"

#define CD_MPM_CL_NEVER 0x7fffffff

#define CD_MPM_CL_PARAM(type, name, host, rows) __global type *name,
#define CD_MPM_CL_PARAMS                                                                                               \
    CD_MPM_CL_COLS(CD_MPM_CL_PARAM)                                                                                    \
    cd_int nx, cd_int ny, cd_int n_bodies, cd_real h, cd_real ox, cd_real oy, __global cd_int *flags,                  \
        __global cd_ulong *counts, cd_int j
#define CD_MPM_CL_SET(type, name, host, rows) c.name = name;
/* Declares `cd_mpm_cols c` over the column and mesh parameters. */
#define CD_MPM_CL_BIND                                                                                                 \
    cd_mpm_cols c;                                                                                                     \
    CD_MPM_CL_COLS(CD_MPM_CL_SET)                                                                                      \
    c.nx = nx;                                                                                                         \
    c.ny = ny;                                                                                                         \
    c.n_bodies = n_bodies;                                                                                             \
    c.h = h;                                                                                                           \
    c.ox = ox;                                                                                                         \
    c.oy = oy

/* 1 when a failure was seen at an earlier step, or at step j by one of the
 * stage checks before this kernel's (flag f < stage). */
CD_INLINE cd_int cd_mpm_cl_stopped(__global const cd_int *flags, cd_int j, cd_int stage)
{
    for (cd_int f = 0; f < 4; f++) {
        cd_int at = flags[4 + f];
        if (at < j || (f < stage && at == j)) return 1;
    }
    return 0;
}

/* Failure f at index i, seen at step j: the highest index and the first
 * step (integer atomics: the same answer in any order). */
CD_INLINE void cd_mpm_cl_fail(__global cd_int *flags, cd_int f, cd_int i, cd_int j)
{
    atomic_max(&flags[f], i);
    atomic_min(&flags[4 + f], j);
}

/* Stage 0.  Point p's stencil and wall forces; failure 0 (LEFT): the
 * highest point whose stencil left the mesh. */
__kernel void cd_mpm_cl_prepare(CD_MPM_CL_PARAMS, cd_ulong n, cd_mpm_item_walls walls)
{
    CD_MPM_CL_BIND;
    cd_ulong p = (cd_ulong)get_global_id(0);
    if (p >= n || cd_mpm_cl_stopped(flags, j, 0)) return;
    if (cd_mpm_item_prepare(c, p, walls)) cd_mpm_cl_fail(flags, 0, (cd_int)p, j);
}

/* Stage 1, observed steps only: wall w's force [N/m], summed in point
 * order (the omp loops' order, so the same bits), into f[2 w], f[2 w + 1]. */
__kernel void cd_mpm_cl_wall_force(CD_MPM_CL_PARAMS, cd_ulong n, cd_mpm_item_walls walls, __global cd_real *f)
{
    CD_MPM_CL_BIND;
    cd_int w = (cd_int)get_global_id(0);
    if (w < walls.n && !cd_mpm_cl_stopped(flags, j, 1)) cd_mpm_item_wall_force(c, n, walls, w, f);
}

__kernel void cd_mpm_cl_window(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_bodies && !cd_mpm_cl_stopped(flags, j, 1)) cd_mpm_item_window(c, k);
}

/* Stage 1, one item: the windows' offsets (300 integer additions at full
 * size), the body-node count into counts[0]; failure 1 (OVERFLOW) when
 * they need more than the cap rows the body-node buffers hold. */
__kernel void cd_mpm_cl_window_offsets(CD_MPM_CL_PARAMS, cd_ulong cap)
{
    CD_MPM_CL_BIND;
    if (get_global_id(0) != 0 || cd_mpm_cl_stopped(flags, j, 1)) return;
    cd_mpm_item_window_offsets(c, counts);
    if (counts[0] > cap) cd_mpm_cl_fail(flags, 1, 0, j);
}

__kernel void cd_mpm_cl_bnode_body(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_bodies && !cd_mpm_cl_stopped(flags, j, 2)) cd_mpm_item_bnode_body(c, k);
}

/* Body k's points sorted by cell (stable counting sort, one item per body). */
__kernel void cd_mpm_cl_sort_body(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_bodies && !cd_mpm_cl_stopped(flags, j, 2)) cd_mpm_item_sort_body(c, k);
}

/* The body-node kernels run over the buffers' rows; those past counts[0] do nothing. */
__kernel void cd_mpm_cl_to_grid(CD_MPM_CL_PARAMS, cd_int normals)
{
    CD_MPM_CL_BIND;
    cd_ulong t = (cd_ulong)get_global_id(0);
    if (t < counts[0] && !cd_mpm_cl_stopped(flags, j, 2)) cd_mpm_item_to_grid(c, t, normals);
}

__kernel void cd_mpm_cl_node_update(CD_MPM_CL_PARAMS, cd_real dt)
{
    CD_MPM_CL_BIND;
    cd_ulong t = (cd_ulong)get_global_id(0);
    if (t < counts[0] && !cd_mpm_cl_stopped(flags, j, 2)) cd_mpm_item_node_update(c, t, dt);
}

/* The common nodes' body lists in six steps (kernels/mpm_step_items.h,
 * cd_mpm_item_cn_*: the lists of the omp loops' one-item sort, bit for
 * bit); the listed nodes' count into counts[1]. */
__kernel void cd_mpm_cl_cn_rows(CD_MPM_CL_PARAMS, __global cd_int *row_n, __global cd_int *rows)
{
    CD_MPM_CL_BIND;
    cd_int row = (cd_int)get_global_id(0);
    if (row < ny && !cd_mpm_cl_stopped(flags, j, 2)) cd_mpm_item_cn_rows(c, row, row_n, rows);
}

__kernel void cd_mpm_cl_cn_count(CD_MPM_CL_PARAMS, __global const cd_int *row_n, __global const cd_int *rows)
{
    CD_MPM_CL_BIND;
    cd_ulong g = (cd_ulong)get_global_id(0);
    if (g < (cd_ulong)nx * (cd_ulong)ny && !cd_mpm_cl_stopped(flags, j, 2)) cd_mpm_item_cn_count(c, g, row_n, rows);
}

__kernel void cd_mpm_cl_cn_block_sums(CD_MPM_CL_PARAMS, __global cd_ulong *blocks, cd_ulong n_blocks)
{
    CD_MPM_CL_BIND;
    cd_ulong b = (cd_ulong)get_global_id(0);
    if (b < n_blocks && !cd_mpm_cl_stopped(flags, j, 2)) cd_mpm_item_cn_block_sums(c, b, blocks);
}

/* One item over the nn / CD_MPM_CN_BLOCK blocks' sums. */
__kernel void cd_mpm_cl_cn_block_scan(CD_MPM_CL_PARAMS, __global cd_ulong *blocks, cd_ulong n_blocks)
{
    if (get_global_id(0) == 0 && !cd_mpm_cl_stopped(flags, j, 2))
        cd_mpm_item_cn_block_scan(n_blocks, blocks, counts + 1);
}

__kernel void cd_mpm_cl_cn_block_starts(CD_MPM_CL_PARAMS, __global const cd_ulong *blocks, cd_ulong n_blocks)
{
    CD_MPM_CL_BIND;
    cd_ulong b = (cd_ulong)get_global_id(0);
    if (b < n_blocks && !cd_mpm_cl_stopped(flags, j, 2)) cd_mpm_item_cn_block_starts(c, b, blocks);
}

__kernel void cd_mpm_cl_cn_entries(CD_MPM_CL_PARAMS, __global const cd_int *row_n, __global const cd_int *rows)
{
    CD_MPM_CL_BIND;
    cd_ulong g = (cd_ulong)get_global_id(0);
    if (g < (cd_ulong)nx * (cd_ulong)ny && !cd_mpm_cl_stopped(flags, j, 2)) cd_mpm_item_cn_entries(c, g, row_n, rows);
}

/* Stage 2 (the listed-node kernels run over a bound; those past counts[1]
 * do nothing).  Failure 2 (CROWDED): the highest common node where too
 * many bodies meet. */
__kernel void cd_mpm_cl_contact_crowded(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_ulong ci = (cd_ulong)get_global_id(0);
    if (ci >= counts[1] || cd_mpm_cl_stopped(flags, j, 2)) return;
    if (cd_mpm_item_contact_crowded(c, ci)) cd_mpm_cl_fail(flags, 2, (cd_int)c.cn_list[ci], j);
}

/* Stage 3.  Listed common node ci's contacts; its deepest overlap (0 if
 * none) [m] into over[ci], for cd_mpm_cl_max_over. */
__kernel void cd_mpm_cl_contact(CD_MPM_CL_PARAMS, cd_real gap_max, cd_real dt, __global cd_real *over)
{
    CD_MPM_CL_BIND;
    cd_ulong ci = (cd_ulong)get_global_id(0);
    if (ci >= counts[1] || cd_mpm_cl_stopped(flags, j, 3)) return;
    cd_real o = 0;
    cd_mpm_item_contact(c, ci, gap_max, dt, &o);
    over[ci] = o;
}

/* Observed steps only, one item: the largest of the overlaps and 0 [m]
 * into out[at] (a maximum: the same bits in any order). */
__kernel void cd_mpm_cl_max_over(CD_MPM_CL_PARAMS, __global const cd_real *over, __global cd_real *out, cd_ulong at)
{
    if (get_global_id(0) != 0 || cd_mpm_cl_stopped(flags, j, 3)) return;
    cd_real m = 0;
    for (cd_ulong ci = 0; ci < counts[1]; ci++)
        if (over[ci] > m) m = over[ci];
    out[at] = m;
}

__kernel void cd_mpm_cl_point_update(CD_MPM_CL_PARAMS, cd_ulong n, cd_real dt, cd_real pic)
{
    CD_MPM_CL_BIND;
    cd_ulong p = (cd_ulong)get_global_id(0);
    if (p < n && !cd_mpm_cl_stopped(flags, j, 3)) cd_mpm_item_point_update(c, p, dt, pic);
}

__kernel void cd_mpm_cl_remap(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_ulong t = (cd_ulong)get_global_id(0);
    if (t < counts[0] && !cd_mpm_cl_stopped(flags, j, 3)) cd_mpm_item_remap(c, t);
}

/* Observed steps only, one item: the mesh's kinetic energy [J/m], summed in
 * body-node order (the omp loop's order), into out[at]. */
__kernel void cd_mpm_cl_mesh_kinetic(CD_MPM_CL_PARAMS, __global cd_real *out, cd_ulong at)
{
    CD_MPM_CL_BIND;
    if (get_global_id(0) == 0 && !cd_mpm_cl_stopped(flags, j, 3)) cd_mpm_item_mesh_kinetic(c, counts[0], out + at);
}

/* Point p's stress, deformation gradient and volume; failure 3 (BLEW_UP):
 * the highest point that is not finite or lost its volume. */
__kernel void cd_mpm_cl_stress(CD_MPM_CL_PARAMS, cd_ulong n, cd_real dt, cd_mpm_material mat)
{
    CD_MPM_CL_BIND;
    cd_ulong p = (cd_ulong)get_global_id(0);
    if (p >= n || cd_mpm_cl_stopped(flags, j, 3)) return;
    if (cd_mpm_item_stress(c, p, dt, mat)) cd_mpm_cl_fail(flags, 3, (cd_int)p, j);
}

/* Where the host looks (no failure seen), one item: the keys of the body
 * pairs in contact (into keys unless it is NULL) and their number into
 * counts[2] (src/mpm/mpm_contact.c counts them). */
__kernel void cd_mpm_cl_pair_keys(CD_MPM_CL_PARAMS, __global cd_long *keys)
{
    CD_MPM_CL_BIND;
    if (get_global_id(0) == 0) cd_mpm_item_pair_keys(c, counts[1], keys, counts + 2);
}

#undef CD_MPM_CL_PARAM
#undef CD_MPM_CL_PARAMS
#undef CD_MPM_CL_SET
#undef CD_MPM_CL_BIND
