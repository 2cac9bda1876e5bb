/* The material point method's step as OpenCL kernels (docs/mpm.md, "The
 * OpenCL backend"): one work-item per point, body, body-node or listed
 * common node, each a thin wrapper around the items of
 * kernels/mpm_step_items.h, kernels/mpm_contact.h and kernels/mpm_checks.h
 * that the omp loops of src/mpm/mpm.c run too, loop for loop (the points'
 * sort one item per body, the common nodes' lists in six kernels; the sums
 * in a fixed order, the walls' forces and the mesh's kinetic energy, and
 * the deepest overlap one item (per wall), only at the steps the host
 * reads them).  src/mpm/mpm_cl.c launches them without reading anything
 * back between steps.
 *
 * Every kernel takes the columns of kernels/cl/mpm_col_list.h first, then
 * the mesh, then the step's checks (kernels/mpm_checks.h): flags, counts
 * and j, this step's number counted from the host's last look; a kernel
 * does nothing once an earlier stage failed (cd_mpm_stopped), and the host
 * finds out at its next look (cd_mpm_settle). */
#include "../mpm_checks.h"
#include "mpm_col_list.h"

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

/* Point p's stencil and wall forces; LEFT: the
 * highest point whose stencil left the mesh. */
__kernel void cd_mpm_cl_prepare(CD_MPM_CL_PARAMS, cd_ulong n, cd_mpm_item_walls walls)
{
    CD_MPM_CL_BIND;
    cd_ulong p = (cd_ulong)get_global_id(0);
    if (p < n) cd_mpm_checked_prepare(c, p, walls, flags, j);
}

/* Stage 1, observed steps only: wall w's force [N/m], summed in point
 * order (the omp loops' order, so the same bits), into f[2 w], f[2 w + 1]. */
__kernel void cd_mpm_cl_wall_force(CD_MPM_CL_PARAMS, cd_ulong n, cd_mpm_item_walls walls, __global cd_real *f)
{
    CD_MPM_CL_BIND;
    cd_int w = (cd_int)get_global_id(0);
    if (w < walls.n && !cd_mpm_stopped(flags, j, 1)) cd_mpm_item_wall_force(c, n, walls, w, f);
}

__kernel void cd_mpm_cl_window(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_bodies && !cd_mpm_stopped(flags, j, 1)) cd_mpm_item_window(c, k);
}

/* One item: the windows' offsets (300 integer additions at full size);
 * OVERFLOW when they need more than the cap rows the body-node buffers hold. */
__kernel void cd_mpm_cl_window_offsets(CD_MPM_CL_PARAMS, cd_ulong cap)
{
    CD_MPM_CL_BIND;
    if (get_global_id(0) == 0) cd_mpm_checked_window_offsets(c, counts, cap, flags, j);
}

__kernel void cd_mpm_cl_bnode_body(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_bodies && !cd_mpm_stopped(flags, j, 2)) cd_mpm_item_bnode_body(c, k);
}

/* Body k's points sorted by cell (stable counting sort, one item per body). */
__kernel void cd_mpm_cl_sort_body(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_bodies && !cd_mpm_stopped(flags, j, 2)) cd_mpm_item_sort_body(c, k);
}

/* The body-node kernels run over the buffers' rows; those past counts[CD_MPM_COUNT_BNODES] do nothing. */
__kernel void cd_mpm_cl_to_grid(CD_MPM_CL_PARAMS, cd_int normals)
{
    CD_MPM_CL_BIND;
    cd_ulong t = (cd_ulong)get_global_id(0);
    if (t < counts[CD_MPM_COUNT_BNODES] && !cd_mpm_stopped(flags, j, 2)) cd_mpm_item_to_grid(c, t, normals);
}

__kernel void cd_mpm_cl_node_update(CD_MPM_CL_PARAMS, cd_real dt)
{
    CD_MPM_CL_BIND;
    cd_ulong t = (cd_ulong)get_global_id(0);
    if (t < counts[CD_MPM_COUNT_BNODES] && !cd_mpm_stopped(flags, j, 2)) cd_mpm_item_node_update(c, t, dt);
}

/* The common nodes' body lists in six steps (kernels/mpm_step_items.h,
 * cd_mpm_item_cn_*: the lists of the omp loops' one-item sort, bit for
 * bit); the listed nodes' count into counts[CD_MPM_COUNT_LISTED]. */
__kernel void cd_mpm_cl_cn_rows(CD_MPM_CL_PARAMS, __global cd_int *row_n, __global cd_int *rows)
{
    CD_MPM_CL_BIND;
    cd_int row = (cd_int)get_global_id(0);
    if (row < ny && !cd_mpm_stopped(flags, j, 2)) cd_mpm_item_cn_rows(c, row, row_n, rows);
}

__kernel void cd_mpm_cl_cn_count(CD_MPM_CL_PARAMS, __global const cd_int *row_n, __global const cd_int *rows)
{
    CD_MPM_CL_BIND;
    cd_ulong g = (cd_ulong)get_global_id(0);
    if (g < (cd_ulong)nx * (cd_ulong)ny && !cd_mpm_stopped(flags, j, 2)) cd_mpm_item_cn_count(c, g, row_n, rows);
}

__kernel void cd_mpm_cl_cn_block_sums(CD_MPM_CL_PARAMS, __global cd_ulong *blocks, cd_ulong n_blocks)
{
    CD_MPM_CL_BIND;
    cd_ulong b = (cd_ulong)get_global_id(0);
    if (b < n_blocks && !cd_mpm_stopped(flags, j, 2)) cd_mpm_item_cn_block_sums(c, b, blocks);
}

/* One item over the nn / CD_MPM_CN_BLOCK blocks' sums. */
__kernel void cd_mpm_cl_cn_block_scan(CD_MPM_CL_PARAMS, __global cd_ulong *blocks, cd_ulong n_blocks)
{
    if (get_global_id(0) == 0 && !cd_mpm_stopped(flags, j, 2))
        cd_mpm_item_cn_block_scan(n_blocks, blocks, counts + CD_MPM_COUNT_LISTED);
}

__kernel void cd_mpm_cl_cn_block_starts(CD_MPM_CL_PARAMS, __global const cd_ulong *blocks, cd_ulong n_blocks)
{
    CD_MPM_CL_BIND;
    cd_ulong b = (cd_ulong)get_global_id(0);
    if (b < n_blocks && !cd_mpm_stopped(flags, j, 2)) cd_mpm_item_cn_block_starts(c, b, blocks);
}

__kernel void cd_mpm_cl_cn_entries(CD_MPM_CL_PARAMS, __global const cd_int *row_n, __global const cd_int *rows)
{
    CD_MPM_CL_BIND;
    cd_ulong g = (cd_ulong)get_global_id(0);
    if (g < (cd_ulong)nx * (cd_ulong)ny && !cd_mpm_stopped(flags, j, 2)) cd_mpm_item_cn_entries(c, g, row_n, rows);
}

/* The listed-node kernels run over a bound; those past the count do nothing. */
__kernel void cd_mpm_cl_contact_crowded(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_mpm_checked_crowded(c, (cd_ulong)get_global_id(0), counts, flags, j);
}

__kernel void cd_mpm_cl_contact(CD_MPM_CL_PARAMS, cd_real gap_max, cd_real dt, __global cd_real *over)
{
    CD_MPM_CL_BIND;
    cd_mpm_checked_contact(c, (cd_ulong)get_global_id(0), gap_max, dt, over, counts, flags, j);
}

/* Observed steps only, one item. */
__kernel void cd_mpm_cl_max_over(CD_MPM_CL_PARAMS, __global const cd_real *over, __global cd_real *reals)
{
    if (get_global_id(0) == 0) cd_mpm_checked_max_over(over, counts, reals, flags, j);
}

__kernel void cd_mpm_cl_point_update(CD_MPM_CL_PARAMS, cd_ulong n, cd_real dt, cd_real pic)
{
    CD_MPM_CL_BIND;
    cd_ulong p = (cd_ulong)get_global_id(0);
    if (p < n && !cd_mpm_stopped(flags, j, 3)) cd_mpm_item_point_update(c, p, dt, pic);
}

__kernel void cd_mpm_cl_remap(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_ulong t = (cd_ulong)get_global_id(0);
    if (t < counts[CD_MPM_COUNT_BNODES] && !cd_mpm_stopped(flags, j, 3)) cd_mpm_item_remap(c, t);
}

/* Observed steps only, one item: the mesh's kinetic energy [J/m], summed in
 * body-node order (the omp loop's order), into out[at]. */
__kernel void cd_mpm_cl_mesh_kinetic(CD_MPM_CL_PARAMS, __global cd_real *out, cd_ulong at)
{
    CD_MPM_CL_BIND;
    if (get_global_id(0) == 0 && !cd_mpm_stopped(flags, j, 3))
        cd_mpm_item_mesh_kinetic(c, counts[CD_MPM_COUNT_BNODES], out + at);
}

__kernel void cd_mpm_cl_stress(CD_MPM_CL_PARAMS, cd_ulong n, cd_real dt, cd_mpm_material mat)
{
    CD_MPM_CL_BIND;
    cd_ulong p = (cd_ulong)get_global_id(0);
    if (p < n) cd_mpm_checked_stress(c, p, dt, mat, flags, j);
}

/* Where the host looks (no failure seen), one item: the keys of the body
 * pairs in contact (into keys unless it is NULL) and their number into
 * counts[2] (src/mpm/mpm_contact.c counts them). */
__kernel void cd_mpm_cl_pair_keys(CD_MPM_CL_PARAMS, __global cd_long *keys)
{
    CD_MPM_CL_BIND;
    if (get_global_id(0) == 0) cd_mpm_item_pair_keys(c, counts[CD_MPM_COUNT_LISTED], keys, counts + CD_MPM_COUNT_KEYS);
}

#undef CD_MPM_CL_PARAM
#undef CD_MPM_CL_PARAMS
#undef CD_MPM_CL_SET
#undef CD_MPM_CL_BIND
