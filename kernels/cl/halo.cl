/* What the MPI decomposition asks of a rank's OpenCL device (docs/mpi.md,
 * "GPUs"; src/backend/opencl/backend_cl_mpi.c): the ghost refresh packs
 * the rows its neighbours need into one buffer and unpacks the received
 * ghosts there, so that only the halo crosses to the host; a wall load
 * reads each primitive's F_n there.  The items are kernels/halo_items.h's,
 * which the host and the offload device run too. */
#include "../halo_items.h"

/* Row e of the sent halo: local particle list[e]'s ghost columns into
 * buf[e CD_HALO_REALS ...]. */
__kernel void cd_cl_halo_pack(
#include "col_params.h"
    cd_int n, __global const cd_int *list, __global cd_real *buf)
{
#include "col_bind.h"
    cd_int e = (cd_int)get_global_id(0);
    if (e < n) cd_item_ghost_io(c, list[e], buf + (cd_long)e * CD_HALO_REALS, 1);
}

/* Row e of the received halo into ghost list[e]'s columns. */
__kernel void cd_cl_halo_unpack(
#include "col_params.h"
    cd_int n, __global const cd_int *list, __global cd_real *buf)
{
#include "col_bind.h"
    cd_int e = (cd_int)get_global_id(0);
    if (e < n) cd_item_ghost_io(c, list[e], buf + (cd_long)e * CD_HALO_REALS, 0);
}

/* F_n [N] of primitive i on wall w into fn[i] (0 where it touches none),
 * from the step's wall-candidate entries. */
__kernel void cd_cl_wall_fn(
#include "col_params.h"
    cd_int n_prims, cd_int n_walls, cd_int w, __global const cd_int *wall_start, __global const cd_int *wall_rows,
    __global const cd_wall_entry *wall_out, __global cd_real *fn)
{
#include "col_bind.h"
    cd_int i = (cd_int)get_global_id(0);
    if (i < n_prims)
        fn[i] = cd_item_wall_fn(c, i, n_walls, w, (__global const cd_int *)0, wall_start, wall_rows, wall_out);
}
