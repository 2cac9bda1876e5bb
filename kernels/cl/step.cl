/* The time step as OpenCL kernels (docs/opencl.md): one work-item per
 * particle, primitive or pair, each a thin wrapper around the per-item
 * functions of kernels/step_items.h that the OpenMP loops of src/backend/omp/step_omp.c
 * call too.  Kernels that touch the state take the columns of
 * kernels/fields.def first (col_params.h), in table order. */
#include "../step_items.h"
#include "../broadphase.h"

/* Steps 1-4: first half kick, drift, world ends of the particle's
 * primitives and their skin test (cd_item_advance); any particle with a
 * primitive past half the skin raises flags[0] (every writer writes 1, so
 * the race is harmless); item w < n_walls also moves wall w.  The kick's
 * force and torque: the columns where bound (not null: a start's, an MPI
 * rank's), else summed from the rows with the gather's arguments
 * (gather_start .. dimension, as cd_cl_gather_kick takes them). */
__kernel void cd_cl_advance(
#include "col_params.h"
    __global cd_wall *walls, cd_int n_walls, cd_int n_particles, cd_real dt, cd_real limit2, __global cd_int *flags,
    __global const cd_int *gather_start, __global const cd_pair_id *gather_rows, __global const cd_int *wall_start,
    __global const cd_wall_entry *wall_out, cd_vec3 gravity, cd_int dimension, cd_int fixed_spheres)
{
#include "col_bind.h"
    cd_int q = (cd_int)get_global_id(0);
    if (q < n_particles && cd_item_advance(c, q, gather_start, gather_rows, wall_start, wall_out, gravity, dimension, 0,
                                           dt, limit2, 0, fixed_spheres))
        flags[0] = 1;
    if (q < n_walls) walls[q] = cd_wall_advanced(walls[q], dt);
}

/* Step 5: narrow phase and contact law of pair row k (outputs: 1 at the
 * last step of a call, when the rows' F_n is written too); item v takes
 * row visit[v] where a mixture has a visiting order (rows grouped by kind,
 * kernels/neighbor_items.h pass 11: one narrow phase a warp), row v where
 * visit is null (one kind of row).  The same bits either way. */
__kernel void cd_cl_pair_forces(
#include "col_params.h"
    cd_int n_pairs, cd_law_params law, cd_real dt, cd_real sin_parallel, cd_int parallel_blend, cd_int outputs,
    __global const cd_int *visit)
{
#include "col_bind.h"
    cd_int v = (cd_int)get_global_id(0);
    if (v < n_pairs)
        cd_item_pair_force(c, (cd_pair_id)cd_map(visit, v), law, dt, sin_parallel, parallel_blend, outputs);
}

/* Step 6: wall candidate e of the last build (its wall-contact row; its
 * outputs in wall_out[e]). */
__kernel void cd_cl_wall_forces(
#include "col_params.h"
    cd_int n_rows, __global const cd_int *wall_rows, __global const cd_wall *walls, cd_int n_walls,
    cd_law_params wall_law, cd_real dt, cd_real sin_parallel, cd_int parallel_blend, __global cd_wall_entry *wall_out)
{
#include "col_bind.h"
    cd_int e = (cd_int)get_global_id(0);
    if (e < n_rows)
        cd_item_wall_row(c, wall_rows[e], wall_out + e, walls, n_walls, wall_law, dt, sin_parallel, parallel_blend);
}

/* Steps 7-8: gather of particle q in fixed order, then by mode: 0 nothing
 * more (the forces of a new run); 1 the second half kick (the last step of
 * a call); 2 the kick and the next step's steps 1-4 in the same item
 * (cd_item_gather_kick_advance, as the omp backend runs it: the particle's
 * state read once, docs/performance.md, "Argument blocks on the device"),
 * raising flags[0] as cd_cl_advance does, and item w < n_walls moves wall
 * w (no item of this kernel reads the walls). */
__kernel void cd_cl_gather_kick(
#include "col_params.h"
    cd_int n_particles, __global const cd_int *gather_start, __global const cd_pair_id *gather_rows,
    __global const cd_int *wall_start, cd_vec3 gravity, cd_int dimension, cd_int mode, cd_real dt,
    __global const cd_wall_entry *wall_out, cd_real limit2, __global cd_wall *walls, cd_int n_walls,
    __global cd_int *flags, cd_int fixed_spheres)
{
#include "col_bind.h"
    cd_int q = (cd_int)get_global_id(0);
    if (mode == 2 && q < n_walls) walls[q] = cd_wall_advanced(walls[q], dt);
    if (q >= n_particles) return;
    if (mode == 0) {
        cd_item_gather(c, q, gather_start, gather_rows, wall_start, wall_out, gravity, dimension);
        return;
    }
    if (cd_item_gather_kick_advance(c, q, gather_start, gather_rows, wall_start, wall_out, gravity, dimension, dt,
                                    limit2, 0, fixed_spheres, mode == 2))
        flags[0] = 1;
}

/* Blow-up check: the highest particle index with a non-finite state goes
 * to flags[1] (integer atomic: the result is the same for any order). */
__kernel void cd_cl_check_finite(
#include "col_params.h"
    cd_int n_particles, __global cd_int *flags)
{
#include "col_bind.h"
    cd_int q = (cd_int)get_global_id(0);
    if (q < n_particles && cd_item_not_finite(c, q)) atomic_max(&flags[1], q);
}

/* Sum of the normal forces of wall w's contacts [N], pass 1: one
 * work-item per chunk of primitives (cd_item_wall_load_chunk), from the
 * outputs of the wall candidates. */
__kernel void cd_cl_wall_load(
#include "col_params.h"
    cd_int n_prims, cd_int n_walls, cd_int w, __global cd_real *part, cd_int n_chunks,
    __global const cd_int *wall_start, __global const cd_int *wall_rows, __global const cd_wall_entry *wall_out)
{
#include "col_bind.h"
    cd_int ch = (cd_int)get_global_id(0);
    if (ch < n_chunks)
        part[ch] = cd_item_wall_load_chunk(c, ch, n_prims, n_walls, w, (__global const cd_int *)0, wall_start,
                                           wall_rows, wall_out);
}

/* Pass 2, one work-item: the chunks' sums in chunk order, as every backend
 * adds them (the same bits). */
__kernel void cd_cl_wall_load_sum(__global const cd_real *part, cd_int n_chunks, __global cd_real *out)
{
    cd_real sum = 0;
    for (cd_int ch = 0; ch < n_chunks; ch++) sum += part[ch];
    out[0] = sum;
}
