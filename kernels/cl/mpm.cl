/* The material point method's step as OpenCL kernels (docs/mpm.md, "The
 * OpenCL backend"): one work-item per point, body, body-node or listed
 * common node, each a thin wrapper around the items of
 * kernels/mpm_step_items.h and kernels/mpm_contact.h that the omp loops of
 * src/mpm/mpm.c run too; the serial parts (sorts, offsets, sums in a fixed
 * order) are one-item kernels, as there.  src/mpm/mpm_cl.c launches them.
 * Every kernel but cd_mpm_cl_max_over takes the columns of
 * kernels/cl/mpm_col_list.h first, then the mesh. */
#include "../mpm_step_items.h"
#include "../mpm_contact.h"
#include "mpm_col_list.h"

#define CD_MPM_CL_PARAM(type, name, host, rows) __global type *name,
#define CD_MPM_CL_PARAMS                                                                                               \
    CD_MPM_CL_COLS(CD_MPM_CL_PARAM) cd_int nx, cd_int ny, cd_int n_bodies, cd_real h, cd_real ox, cd_real oy
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

/* Point p's stencil and wall forces; flags[0]: the highest point whose
 * stencil left the mesh (an integer atomic: the same answer in any order). */
__kernel void cd_mpm_cl_prepare(CD_MPM_CL_PARAMS, cd_ulong n, cd_mpm_item_walls walls, __global cd_int *flags)
{
    CD_MPM_CL_BIND;
    cd_ulong p = (cd_ulong)get_global_id(0);
    if (p < n && cd_mpm_item_prepare(c, p, walls)) atomic_max(&flags[0], (cd_int)p);
}

/* Wall w's force [N/m], summed in point order, into f[2 w], f[2 w + 1]. */
__kernel void cd_mpm_cl_wall_force(CD_MPM_CL_PARAMS, cd_ulong n, cd_mpm_item_walls walls, __global cd_real *f)
{
    CD_MPM_CL_BIND;
    cd_int w = (cd_int)get_global_id(0);
    if (w < walls.n) cd_mpm_item_wall_force(c, n, walls, w, f);
}

__kernel void cd_mpm_cl_window(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_bodies) cd_mpm_item_window(c, k);
}

/* One item: the windows' offsets, the body-node count into *total. */
__kernel void cd_mpm_cl_window_offsets(CD_MPM_CL_PARAMS, __global cd_ulong *total)
{
    CD_MPM_CL_BIND;
    if (get_global_id(0) == 0) cd_mpm_item_window_offsets(c, total);
}

__kernel void cd_mpm_cl_bnode_body(CD_MPM_CL_PARAMS)
{
    CD_MPM_CL_BIND;
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_bodies) cd_mpm_item_bnode_body(c, k);
}

/* One item: the stable counting sort of the points by (body, cell). */
__kernel void cd_mpm_cl_sort_points(CD_MPM_CL_PARAMS, cd_ulong n, cd_ulong nbn)
{
    CD_MPM_CL_BIND;
    if (get_global_id(0) == 0) cd_mpm_item_sort_points(c, n, nbn);
}

__kernel void cd_mpm_cl_to_grid(CD_MPM_CL_PARAMS, cd_ulong nbn, cd_int normals)
{
    CD_MPM_CL_BIND;
    cd_ulong t = (cd_ulong)get_global_id(0);
    if (t < nbn) cd_mpm_item_to_grid(c, t, normals);
}

__kernel void cd_mpm_cl_node_update(CD_MPM_CL_PARAMS, cd_ulong nbn, cd_real dt)
{
    CD_MPM_CL_BIND;
    cd_ulong t = (cd_ulong)get_global_id(0);
    if (t < nbn) cd_mpm_item_node_update(c, t, dt);
}

/* One item: the common nodes' body lists; the listed nodes' count into *listed. */
__kernel void cd_mpm_cl_contact_nodes(CD_MPM_CL_PARAMS, cd_ulong nbn, __global cd_ulong *listed)
{
    CD_MPM_CL_BIND;
    if (get_global_id(0) == 0) cd_mpm_item_contact_nodes(c, nbn, listed);
}

/* flags[1]: the highest common node where too many bodies meet. */
__kernel void cd_mpm_cl_contact_crowded(CD_MPM_CL_PARAMS, cd_ulong n_cn, __global cd_int *flags)
{
    CD_MPM_CL_BIND;
    cd_ulong ci = (cd_ulong)get_global_id(0);
    if (ci < n_cn && cd_mpm_item_contact_crowded(c, ci)) atomic_max(&flags[1], (cd_int)c.cn_list[ci]);
}

/* Listed common node ci's contacts; its deepest overlap (0 if none) [m]
 * into over[ci], for cd_mpm_cl_max_over. */
__kernel void cd_mpm_cl_contact(CD_MPM_CL_PARAMS, cd_ulong n_cn, cd_real gap_max, cd_real dt, __global cd_real *over)
{
    CD_MPM_CL_BIND;
    cd_ulong ci = (cd_ulong)get_global_id(0);
    if (ci >= n_cn) return;
    cd_real o = 0;
    cd_mpm_item_contact(c, ci, gap_max, dt, &o);
    over[ci] = o;
}

/* One item: the largest of the n_cn overlaps and 0 [m] into out[at] (a
 * maximum: the same bits in any order). */
__kernel void cd_mpm_cl_max_over(cd_ulong n_cn, __global const cd_real *over, __global cd_real *out, cd_ulong at)
{
    if (get_global_id(0) != 0) return;
    cd_real m = 0;
    for (cd_ulong ci = 0; ci < n_cn; ci++)
        if (over[ci] > m) m = over[ci];
    out[at] = m;
}

__kernel void cd_mpm_cl_point_update(CD_MPM_CL_PARAMS, cd_ulong n, cd_real dt, cd_real pic)
{
    CD_MPM_CL_BIND;
    cd_ulong p = (cd_ulong)get_global_id(0);
    if (p < n) cd_mpm_item_point_update(c, p, dt, pic);
}

__kernel void cd_mpm_cl_remap(CD_MPM_CL_PARAMS, cd_ulong nbn)
{
    CD_MPM_CL_BIND;
    cd_ulong t = (cd_ulong)get_global_id(0);
    if (t < nbn) cd_mpm_item_remap(c, t);
}

/* One item: the mesh's kinetic energy [J/m], summed in body-node order, into out[at]. */
__kernel void cd_mpm_cl_mesh_kinetic(CD_MPM_CL_PARAMS, cd_ulong nbn, __global cd_real *out, cd_ulong at)
{
    CD_MPM_CL_BIND;
    if (get_global_id(0) == 0) cd_mpm_item_mesh_kinetic(c, nbn, out + at);
}

/* Point p's stress, deformation gradient and volume; flags[2]: the highest
 * point that is not finite or lost its volume. */
__kernel void cd_mpm_cl_stress(CD_MPM_CL_PARAMS, cd_ulong n, cd_real dt, cd_mpm_material mat, __global cd_int *flags)
{
    CD_MPM_CL_BIND;
    cd_ulong p = (cd_ulong)get_global_id(0);
    if (p < n && cd_mpm_item_stress(c, p, dt, mat)) atomic_max(&flags[2], (cd_int)p);
}

/* One item: the keys of the body pairs in contact (into keys unless it is
 * NULL) and their number into *count (src/mpm/mpm_contact.c counts them). */
__kernel void cd_mpm_cl_pair_keys(CD_MPM_CL_PARAMS, cd_ulong n_cn, __global cd_long *keys, __global cd_ulong *count)
{
    CD_MPM_CL_BIND;
    if (get_global_id(0) == 0) cd_mpm_item_pair_keys(c, n_cn, keys, count);
}

#undef CD_MPM_CL_PARAM
#undef CD_MPM_CL_PARAMS
#undef CD_MPM_CL_SET
#undef CD_MPM_CL_BIND
