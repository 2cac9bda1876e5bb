/* The Verlet list built on the device (docs/opencl.md, "Neighbour list"):
 * the same grid of particles, candidate test and sorted rows as src/neighbors.c
 * (kernels/broadphase.h), history carried by binary search of the new
 * (prim_i, prim_j) keys in the old sorted keys, and the per-particle gather
 * lists.  Integer atomics only fill counting sorts; every list that an
 * atomic fills out of order is sorted again (or, for the cell lists, only
 * feeds a scan that sorts its output), so the result is the same on every
 * run. */
#include "../broadphase.h"
#include "../step_items.h"
#include "../cols.h"

/* Bounding radius of each particle of the chunk [g chunk, (g+1) chunk)
 * into part_bound, and the box of their centres and largest bound: 7
 * reals per work-item. */
__kernel void cd_cl_bounds(
#include "col_params.h"
    cd_int n_particles, cd_int chunk, __global cd_real *partial, __global cd_real *part_bound)
{
#include "col_bind.h"
    cd_int g = (cd_int)get_global_id(0);
    cd_real lo[3], hi[3], rmax = 0;
    for (int k = 0; k < 3; k++) {
        lo[k] = (cd_real)INFINITY;
        hi[k] = -(cd_real)INFINITY;
    }
    cd_int end = (g + 1) * chunk < n_particles ? (g + 1) * chunk : n_particles;
    for (cd_int p = g * chunk; p < end; p++) {
        cd_real b = cd_bp_particle_bound(c.prim_a, c.prim_b, c.prim_radius, c.prim_first[p], c.prim_count[p],
                                         c.position[p]);
        part_bound[p] = b;
        cd_bp_bounds_add(lo, hi, &rmax, c.position[p], b);
    }
    for (int k = 0; k < 3; k++) {
        partial[7 * g + k] = lo[k];
        partial[7 * g + 3 + k] = hi[k];
    }
    partial[7 * g + 6] = rmax;
}

/* One work-item: merges the partial boxes (minimum and maximum are exact)
 * and makes the grid. */
__kernel void cd_cl_grid(__global const cd_real *partial, cd_int n_parts, cd_real skin, cd_int n_particles,
                         __global cd_grid *grid)
{
    cd_real lo[3], hi[3], rmax = 0;
    for (int k = 0; k < 3; k++) {
        lo[k] = (cd_real)INFINITY;
        hi[k] = -(cd_real)INFINITY;
    }
    for (cd_int g = 0; g < n_parts; g++) {
        for (int k = 0; k < 3; k++) {
            if (partial[7 * g + k] < lo[k]) lo[k] = partial[7 * g + k];
            if (partial[7 * g + 3 + k] > hi[k]) hi[k] = partial[7 * g + 3 + k];
        }
        if (partial[7 * g + 6] > rmax) rmax = partial[7 * g + 6];
    }
    cd_grid gr;
    cd_grid_make(&gr, lo, hi, rmax, skin, n_particles);
    grid[0] = gr;
}

/* Cell of particle q (its centre); counts the particles per cell.
 * cell_cap bounds the index even for a non-finite position (a run blowing
 * up before its check), so that no write leaves the buffers. */
__kernel void cd_cl_bin(
#include "col_params.h"
    cd_int n_particles, __global const cd_grid *grid, __global cd_int *part_cell, __global cd_int *cell_count,
    cd_int cell_cap)
{
#include "col_bind.h"
    cd_int q = (cd_int)get_global_id(0);
    if (q >= n_particles) return;
    cd_grid g = grid[0];
    cd_long idx = cd_grid_cell_of(&g, c.position[q]);
    cd_int cell = idx >= 0 && idx < cell_cap ? (cd_int)idx : 0;
    part_cell[q] = cell;
    atomic_inc(&cell_count[cell]);
}

/* Places particle q in its cell's slice of cell_parts (cursor starts as
 * cell_start).  The order inside a cell varies from run to run, but
 * cd_bp_scan_prim sorts each row, so the list does not. */
__kernel void cd_cl_cell_fill(cd_int n_particles, __global const cd_int *part_cell, __global cd_int *cursor,
                              __global cd_int *cell_parts)
{
    cd_int q = (cd_int)get_global_id(0);
    if (q >= n_particles) return;
    cell_parts[atomic_inc(&cursor[part_cell[q]])] = q;
}

/* One pass over the candidates of primitive i: their number, and the
 * candidates themselves (ascending) in the fixed slot cand[i slot ..
 * (i+1) slot).  A primitive with more than `slot` candidates raises
 * flags[2]; the host then fills the rows with cd_cl_pair_fill instead (a
 * second scan) and enlarges the slots for the next build. */
__kernel void cd_cl_pair_collect(
#include "col_params.h"
    cd_int n_prims, __global const cd_grid *grid, __global const cd_int *cell_start,
    __global const cd_int *cell_parts, cd_real skin, __global const cd_real *part_bound, __global cd_int *pair_count,
    __global cd_prim_id *cand, cd_int slot, __global cd_int *flags)
{
#include "col_bind.h"
    cd_int i = (cd_int)get_global_id(0);
    if (i >= n_prims) return;
    cd_grid g = grid[0];
    cd_int n = cd_bp_scan_prim(c.prim_a, c.prim_b, c.prim_radius, c.prim_particle, c.position, c.prim_first,
                               c.prim_count, part_bound, &g, cell_start, cell_parts, i, skin, cand + (cd_long)i * slot,
                               slot);
    pair_count[i] = n;
    if (n > slot) flags[2] = 1;
}

/* Rows pair_offset[i] .. pair_offset[i+1] of the new list from primitive
 * i's slot: the list is sorted by (i, j) as on the host; the keys go to
 * keys. */
__kernel void cd_cl_pair_place(
#include "col_params.h"
    cd_int n_prims, __global const cd_int *pair_offset, __global const cd_prim_id *cand, cd_int slot,
    __global cd_ulong *keys)
{
#include "col_bind.h"
    cd_int i = (cd_int)get_global_id(0);
    if (i >= n_prims) return;
    cd_int first = pair_offset[i], n = pair_offset[i + 1] - first;
    for (cd_int m = 0; m < n; m++) {
        cd_prim_id j = cand[(cd_long)i * slot + m];
        c.pair_prim_i[first + m] = i;
        c.pair_prim_j[first + m] = j;
        keys[first + m] = cd_bp_pair_key(i, j);
    }
}

/* The same rows by a second scan, for a build in which some primitive
 * overflowed its slot. */
__kernel void cd_cl_pair_fill(
#include "col_params.h"
    cd_int n_prims, __global const cd_grid *grid, __global const cd_int *cell_start,
    __global const cd_int *cell_parts, cd_real skin, __global const cd_real *part_bound,
    __global const cd_int *pair_offset, __global cd_ulong *keys)
{
#include "col_bind.h"
    cd_int i = (cd_int)get_global_id(0);
    if (i >= n_prims) return;
    cd_grid g = grid[0];
    cd_int first = pair_offset[i];
    cd_int n = cd_bp_scan_prim(c.prim_a, c.prim_b, c.prim_radius, c.prim_particle, c.position, c.prim_first,
                               c.prim_count, part_bound, &g, cell_start, cell_parts, i, skin, c.pair_prim_j + first,
                               CD_BP_UNBOUNDED);
    for (cd_int k = first; k < first + n; k++) {
        c.pair_prim_i[k] = i;
        keys[k] = cd_bp_pair_key(i, c.pair_prim_j[k]);
    }
}

/* Keys of rows that came from the host (a new run or a checkpoint). */
__kernel void cd_cl_pair_keys(
#include "col_params.h"
    cd_int n_pairs, __global cd_ulong *keys)
{
#include "col_bind.h"
    cd_int k = (cd_int)get_global_id(0);
    if (k < n_pairs) keys[k] = cd_bp_pair_key(c.pair_prim_i[k], c.pair_prim_j[k]);
}

/* History of new row k: the old row with the same key keeps its activity
 * and tangential spring; a pair new to the list starts without history. */
__kernel void cd_cl_pair_carry(
#include "col_params.h"
    cd_int n_pairs, __global const cd_ulong *keys, __global const cd_ulong *old_keys, cd_int n_old,
    __global const cd_int *old_active, __global const cd_vec3 *old_shear)
{
#include "col_bind.h"
    cd_int k = (cd_int)get_global_id(0);
    if (k >= n_pairs) return;
    cd_long o = cd_bp_find_key(old_keys, n_old, keys[k]);
    c.pair_active[k] = o >= 0 ? old_active[o] : 0;
    c.pair_shear[k] = o >= 0 ? old_shear[o] : cd_v3_zero();
}

/* Gather lists, pass 1: rows per particle (each row counts for both of its
 * particles). */
__kernel void cd_cl_gather_count(
#include "col_params.h"
    cd_int n_pairs, __global cd_int *count)
{
#include "col_bind.h"
    cd_int k = (cd_int)get_global_id(0);
    if (k >= n_pairs) return;
    atomic_inc(&count[c.prim_particle[c.pair_prim_i[k]]]);
    atomic_inc(&count[c.prim_particle[c.pair_prim_j[k]]]);
}

/* Pass 2: row k into the slices of its two particles as 2 k + side (side
 * 1 for the particle of primitive j: step_items.h, cd_item_gather; cursor
 * starts as gather_start); pass 3 restores ascending order. */
__kernel void cd_cl_gather_fill(
#include "col_params.h"
    cd_int n_pairs, __global cd_int *cursor, __global cd_pair_id *gather_rows)
{
#include "col_bind.h"
    cd_int k = (cd_int)get_global_id(0);
    if (k >= n_pairs) return;
    gather_rows[atomic_inc(&cursor[c.prim_particle[c.pair_prim_i[k]]])] = 2 * k;
    gather_rows[atomic_inc(&cursor[c.prim_particle[c.pair_prim_j[k]]])] = 2 * k + 1;
}

/* Pass 3: particle q's rows in ascending order (insertion sort: a few tens
 * of rows), the order in which the gather sums them on every backend. */
__kernel void cd_cl_gather_sort(cd_int n_particles, __global const cd_int *gather_start,
                                __global cd_pair_id *gather_rows)
{
    cd_int q = (cd_int)get_global_id(0);
    if (q >= n_particles) return;
    cd_int first = gather_start[q], last = gather_start[q + 1];
    for (cd_int a = first + 1; a < last; a++) {
        cd_pair_id v = gather_rows[a];
        cd_int b = a;
        while (b > first && gather_rows[b - 1] > v) {
            gather_rows[b] = gather_rows[b - 1];
            b--;
        }
        gather_rows[b] = v;
    }
}

/* Wall candidates, pass 1: how many rows particle q tests until the next
 * build (cd_item_wall_candidates, which also ends a stale row). */
__kernel void cd_cl_wall_cand_count(
#include "col_params.h"
    cd_int n_particles, __global const cd_wall *walls, cd_int n_walls, cd_real skin, __global cd_int *count)
{
#include "col_bind.h"
    cd_int q = (cd_int)get_global_id(0);
    if (q < n_particles) count[q] = cd_item_wall_candidates(c, q, walls, n_walls, skin, (__global cd_int *)0);
}

/* Pass 2, after the scan of the counts into wall_start: the rows, in
 * ascending order within each particle's slice. */
__kernel void cd_cl_wall_cand_fill(
#include "col_params.h"
    cd_int n_particles, __global const cd_wall *walls, cd_int n_walls, cd_real skin,
    __global const cd_int *wall_start, __global cd_int *wall_rows)
{
#include "col_bind.h"
    cd_int q = (cd_int)get_global_id(0);
    if (q < n_particles) cd_item_wall_candidates(c, q, walls, n_walls, skin, wall_rows + wall_start[q]);
}
