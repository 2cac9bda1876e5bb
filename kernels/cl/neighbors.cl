/* The Verlet list built on an OpenCL device (docs/opencl.md, "Neighbour
 * list"): one kernel per pass of kernels/neighbor_items.h, each a thin
 * wrapper of the item the OpenMP build (src/backend/omp/neighbors.c) runs, so both
 * build the same list.  Integer atomics only fill counting sorts; what they
 * leave out of order is sorted again, so the result is the same on every
 * run. */
#include "../neighbor_items.h"
#include "../step_items.h"
#include "../cols.h"

/* Pass 1a: bounding radius of particle p. */
__kernel void cd_cl_bounds(
#include "col_params.h"
    cd_int n_particles, __global cd_real *part_bound)
{
#include "col_bind.h"
    cd_int p = (cd_int)get_global_id(0);
    if (p < n_particles) cd_nb_item_bound(c, p, part_bound);
}

/* The build's last pass: primitive i's ends become the skin test's
 * reference (cd_item_prim_refs). */
__kernel void cd_cl_prim_refs(
#include "col_params.h"
    cd_int n_prims)
{
#include "col_bind.h"
    cd_int i = (cd_int)get_global_id(0);
    if (i < n_prims) cd_item_prim_refs(c, i);
}

/* Pass 1b: box of the particles of chunk g. */
__kernel void cd_cl_box(
#include "col_params.h"
    cd_int n_particles, __global const cd_real *part_bound, __global cd_real *boxes)
{
#include "col_bind.h"
    cd_long g = (cd_long)get_global_id(0);
    if (g * CD_BOX_CHUNK < n_particles) cd_nb_item_box(c, g, n_particles, part_bound, boxes);
}

/* Pass 1c: the n boxes from box `at` merged by chunks into the level
 * above, from box `up_at` (one buffer). */
__kernel void cd_cl_box_up(__global const cd_real *boxes, cd_int at, cd_int n, __global cd_real *up, cd_int up_at)
{
    cd_long g = (cd_long)get_global_id(0);
    if (g * CD_BOX_CHUNK < n) cd_nb_item_box_up(boxes + 7 * (cd_long)at, n, g, up + 7 * (cd_long)up_at);
}

/* Pass 2 (one work-item): the last level's boxes, from box `at`, merged;
 * the grid. */
__kernel void cd_cl_grid(__global const cd_real *boxes, cd_int at, cd_int n_boxes, cd_real skin, cd_int n_particles,
                         __global cd_grid *grid)
{
    cd_nb_item_grid(boxes + 7 * (cd_long)at, n_boxes, skin, n_particles, grid);
}

/* Pass 3: cell of particle q, counted. */
__kernel void cd_cl_bin(
#include "col_params.h"
    cd_int n_particles, __global const cd_grid *grid, __global cd_int *part_cell, __global cd_int *cell_count,
    cd_int cell_cap)
{
#include "col_bind.h"
    cd_int q = (cd_int)get_global_id(0);
    if (q < n_particles) cd_nb_item_bin(c, q, grid, cell_cap, part_cell, cell_count);
}

/* Pass 4: particle q into its cell's slice (cursor starts as cell_start). */
__kernel void cd_cl_cell_fill(cd_int n_particles, __global const cd_int *part_cell, __global cd_int *cursor,
                              __global cd_int *cell_parts)
{
    cd_int q = (cd_int)get_global_id(0);
    if (q < n_particles) cd_nb_item_cell_fill(q, part_cell, cursor, cell_parts);
}

/* Pass 5, slot mode: the candidates of particle p's primitives into their
 * slots; a row longer than its slot raises flags[2], and the host then
 * runs cd_cl_pair_fill and enlarges the slots for the next build. */
__kernel void cd_cl_pair_collect(
#include "col_params.h"
    cd_int n_particles, __global const cd_grid *grid, __global const cd_int *cell_start,
    __global const cd_int *cell_parts, cd_real skin, __global const cd_real *part_bound, __global cd_int *pair_count,
    __global cd_prim_id *cand, cd_int slot, __global cd_int *flags)
{
#include "col_bind.h"
    cd_int p = (cd_int)get_global_id(0);
    if (p >= n_particles) return;
    cd_nb_item_collect(c, p, c.prim_first[p], c.prim_first[p] + c.prim_count[p], grid, cell_start, cell_parts,
                       part_bound, skin, cand, slot, (__global const cd_int *)0, pair_count, cd_order_identity());
    for (cd_int i = c.prim_first[p]; i < c.prim_first[p] + c.prim_count[p]; i++)
        if (pair_count[i] > slot) flags[2] = 1;
}

/* Pass 5, fill mode: the rows written in place (pair_prim_j at
 * pair_offset), after a slot overflowed; cd_cl_pair_place with slot 0
 * completes them. */
__kernel void cd_cl_pair_fill(
#include "col_params.h"
    cd_int n_particles, __global const cd_grid *grid, __global const cd_int *cell_start,
    __global const cd_int *cell_parts, cd_real skin, __global const cd_real *part_bound, __global cd_int *pair_count,
    __global const cd_int *pair_offset)
{
#include "col_bind.h"
    cd_int p = (cd_int)get_global_id(0);
    if (p < n_particles)
        cd_nb_item_collect(c, p, c.prim_first[p], c.prim_first[p] + c.prim_count[p], grid, cell_start, cell_parts,
                           part_bound, skin, c.pair_prim_j, 0, pair_offset, pair_count, cd_order_identity());
}

/* Pass 7: primitive i's rows from its slot (slot 0: from pair_prim_j) and
 * their keys. */
__kernel void cd_cl_pair_place(
#include "col_params.h"
    cd_int n_prims, __global const cd_int *pair_offset, __global const cd_prim_id *cand, cd_int slot,
    __global cd_ulong *keys)
{
#include "col_bind.h"
    cd_int i = (cd_int)get_global_id(0);
    if (i < n_prims) cd_nb_item_place(c, i, pair_offset, cand, slot, keys, cd_order_identity());
}

/* Keys of rows that came from the host (a new run or a checkpoint). */
__kernel void cd_cl_pair_keys(
#include "col_params.h"
    cd_int n_pairs, __global cd_ulong *keys)
{
#include "col_bind.h"
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_pairs) keys[k] = cd_nb_row_key(c, k, cd_order_identity());
}

/* Pass 8: history of new row k. */
__kernel void cd_cl_pair_carry(
#include "col_params.h"
    cd_int n_pairs, __global const cd_ulong *keys, __global const cd_ulong *old_keys, cd_int n_old,
    __global const cd_flag *old_active, __global const cd_vec3 *old_shear)
{
#include "col_bind.h"
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_pairs) cd_nb_item_carry(c, k, keys, old_keys, n_old, old_active, old_shear, (__global const cd_int *)0);
}

/* Pass 9: gather lists counted, filled (cursor starts as gather_start),
 * sorted. */
__kernel void cd_cl_gather_count(
#include "col_params.h"
    cd_int n_pairs, __global cd_int *count)
{
#include "col_bind.h"
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_pairs) cd_nb_item_gather_count(c, k, count);
}

__kernel void cd_cl_gather_fill(
#include "col_params.h"
    cd_int n_pairs, __global cd_int *cursor, __global cd_pair_id *gather_rows)
{
#include "col_bind.h"
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_pairs) cd_nb_item_gather_fill(c, k, cursor, gather_rows);
}

__kernel void cd_cl_gather_sort(cd_int n_particles, __global const cd_int *gather_start,
                                __global cd_pair_id *gather_rows)
{
    cd_int q = (cd_int)get_global_id(0);
    /* The OpenCL backend keeps the user's memory order (no reordering): the
     * entries sort by value, and the columns are not read. */
    cd_cols none;
    if (q < n_particles) cd_nb_item_gather_sort(none, cd_order_identity(), q, gather_start, gather_rows);
}

/* Pass 10: wall candidates of particle q counted, then (after the scan of
 * the counts into wall_start) filled. */
__kernel void cd_cl_wall_cand_count(
#include "col_params.h"
    cd_int n_particles, __global const cd_wall *walls, cd_int n_walls, cd_real skin, __global cd_int *count)
{
#include "col_bind.h"
    cd_int q = (cd_int)get_global_id(0);
    if (q < n_particles) count[q] = cd_item_wall_candidates(c, q, walls, n_walls, skin, (__global cd_int *)0);
}

__kernel void cd_cl_wall_cand_fill(
#include "col_params.h"
    cd_int n_particles, __global const cd_wall *walls, cd_int n_walls, cd_real skin, __global const cd_int *wall_start,
    __global cd_int *wall_rows)
{
#include "col_bind.h"
    cd_int q = (cd_int)get_global_id(0);
    if (q < n_particles) cd_item_wall_candidates(c, q, walls, n_walls, skin, wall_rows + wall_start[q]);
}

/* Pass 10, last: the history of wall candidate e from the old candidates
 * (no reordering here: prim_src null). */
__kernel void cd_cl_wall_carry(cd_int n_rows, __global const cd_int *wall_rows, __global cd_wall_entry *wall_out,
                               __global const cd_int *old_rows, cd_int n_old, __global const cd_wall_entry *old_out,
                               cd_int n_walls)
{
    cd_long e = (cd_long)get_global_id(0);
    if (e < n_rows)
        cd_item_wall_carry(e, wall_rows, wall_out, old_rows, n_old, old_out, (__global const cd_int *)0, n_walls);
}

/* Pass 11 (mixtures only): the pair pass's visiting order, rows grouped
 * by kind -- count per chunk of rows, then (after the scan of starts) fill. */
__kernel void cd_cl_visit_count(
#include "col_params.h"
    cd_int n_pairs, __global cd_int *starts)
{
#include "col_bind.h"
    cd_long g = (cd_long)get_global_id(0);
    if (g < cd_nb_visit_chunks(n_pairs)) cd_nb_item_visit_count(c, g, n_pairs, starts);
}

__kernel void cd_cl_visit_fill(
#include "col_params.h"
    cd_int n_pairs, __global const cd_int *starts, __global cd_int *visit)
{
#include "col_bind.h"
    cd_long g = (cd_long)get_global_id(0);
    if (g < cd_nb_visit_chunks(n_pairs)) cd_nb_item_visit_fill(c, g, n_pairs, starts, visit);
}
