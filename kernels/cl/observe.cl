/* The observables summed on the device (kernels/observe_items.h): marks of
 * the particles in contact, the block sums of particles, pair rows and wall
 * rows, and their merge in order by one work-item; only the merged slots
 * go back to the host.  The same items and order as src/backend/omp/observe.c. */
#include "../observe_items.h"

__kernel void cd_cl_obs_touch_pairs(
#include "col_params.h"
    cd_int n_pairs, __global cd_int *touch)
{
#include "col_bind.h"
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_pairs) cd_obs_item_touch_pair(c, k, touch);
}

__kernel void cd_cl_obs_touch_walls(
#include "col_params.h"
    cd_long n_rows, cd_int n_walls, __global cd_int *touch)
{
#include "col_bind.h"
    cd_long r = (cd_long)get_global_id(0);
    if (r < n_rows) cd_obs_item_touch_wall(c, r, n_walls, touch);
}

/* One work-item per block; part: CD_OBS_SLOTS reals per block, this
 * kind's blocks from block `first` on (particles, then pairs, then walls). */
__kernel void cd_cl_obs_particles(
#include "col_params.h"
    cd_long n, cd_vec3 gravity, __global const cd_int *touch, __global cd_real *part, cd_long first)
{
#include "col_bind.h"
    cd_long b = (cd_long)get_global_id(0);
    if (b * CD_OBS_BLOCK < n)
        cd_obs_block_particles(c, b, n, gravity, touch, part + (first + b) * CD_OBS_SLOTS, cd_order_identity());
}

__kernel void cd_cl_obs_pairs(
#include "col_params.h"
    cd_long n, cd_law_params law, __global cd_real *part, cd_long first)
{
#include "col_bind.h"
    cd_long b = (cd_long)get_global_id(0);
    if (b * CD_OBS_BLOCK < n) cd_obs_block_pairs(c, b, n, law, part + (first + b) * CD_OBS_SLOTS, cd_order_identity());
}

__kernel void cd_cl_obs_walls(
#include "col_params.h"
    cd_long n, cd_int n_walls, cd_law_params wall_law, __global cd_real *part, cd_long first,
    __global const cd_int *wall_start, __global const cd_int *wall_rows, __global const cd_wall_out *wall_out)
{
#include "col_bind.h"
    cd_long b = (cd_long)get_global_id(0);
    if (b * CD_OBS_BLOCK < n)
        cd_obs_block_walls(c, b, n, n_walls, wall_law, part + (first + b) * CD_OBS_SLOTS, cd_order_identity(),
                           wall_start, wall_rows, wall_out);
}

__kernel void cd_cl_obs_merge(__global const cd_real *part, cd_long n_blocks, __global cd_real *total)
{
    cd_obs_merge(part, n_blocks, total);
}
