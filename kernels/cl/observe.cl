/* The observables summed on the device (kernels/observe_items.h): marks of
 * the particles in contact, the block sums of particles, pair rows and wall
 * rows (the leaves), and the fixed tree merging them level by level; only
 * the merged slots go back to the host.  The same items and order as src/backend/omp/observe.c. */
#include "../observe_items.h"

__kernel void cd_cl_obs_touch_pairs(
#include "col_params.h"
    cd_int n_pairs, __global cd_int *touch)
{
#include "col_bind.h"
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_pairs) cd_obs_item_touch_pair(c, k, touch);
}

/* One work-item per wall candidate of the last build. */
__kernel void cd_cl_obs_touch_walls(
#include "col_params.h"
    cd_long n_cand, cd_int n_walls, __global const cd_int *wall_rows, __global const cd_wall_entry *wall_out,
    __global cd_int *touch)
{
#include "col_bind.h"
    cd_long e = (cd_long)get_global_id(0);
    if (e < n_cand) cd_obs_item_touch_wall(c, e, n_walls, wall_rows, wall_out, touch);
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

/* n pair rows, their leaves by blocks of n_prims primitives; the
 * overlaps from the narrow phase (sin_parallel, parallel_blend: the pair
 * pass's). */
__kernel void cd_cl_obs_pairs(
#include "col_params.h"
    cd_long n, cd_law_params law, __global cd_real *part, cd_long first, cd_long n_prims, cd_real sin_parallel,
    cd_int parallel_blend)
{
#include "col_bind.h"
    cd_long b = (cd_long)get_global_id(0);
    if (b < cd_obs_pair_blocks(n_prims))
        cd_obs_block_pairs(c, b, n, law, part + (first + b) * CD_OBS_SLOTS, cd_order_identity(), 0, sin_parallel,
                           parallel_blend);
}

__kernel void cd_cl_obs_walls(
#include "col_params.h"
    cd_long n, cd_int n_walls, cd_law_params wall_law, __global cd_real *part, cd_long first,
    __global const cd_int *wall_start, __global const cd_int *wall_rows, __global const cd_wall_entry *wall_out)
{
#include "col_bind.h"
    cd_long b = (cd_long)get_global_id(0);
    if (b * CD_OBS_BLOCK < n)
        cd_obs_block_walls(c, b, n, n_walls, wall_law, part + (first + b) * CD_OBS_SLOTS, cd_order_identity(),
                           wall_start, wall_rows, wall_out);
}

/* One level of the tree: the n partial sums from block `at` of part merged
 * CD_OBS_FANIN at a time into out from block `out_at` (the level above in
 * part, or, for the last level of one item, the total). */
__kernel void cd_cl_obs_merge(__global const cd_real *part, cd_long at, cd_long n, __global cd_real *out,
                              cd_long out_at)
{
    cd_long g = (cd_long)get_global_id(0);
    if (g == 0 || g * CD_OBS_FANIN < n) cd_obs_item_merge(part + at * CD_OBS_SLOTS, n, g, out + out_at * CD_OBS_SLOTS);
}
