/* The observables of the state (energies, contact counts, momentum, wall
 * forces, largest overlap; their SUM and MAX rows of kernels/observables.def
 * give the slots) as fixed-order reductions, a fixed tree: rows in blocks
 * of CD_OBS_BLOCK, each block summed in row order into its own slots (the
 * leaves: particles, then pairs, then wall rows), then the leaves merged
 * in order CD_OBS_FANIN at a time, level by level, into the total (docs/
 * performance.md, "GPU-shaped reductions": 4,096-row blocks gave a GPU a
 * few dozen serial loops, 25 ms an observation at 1e5 hexapods).  Rows are
 * visited in user order (cd_order, kernels/reorder_items.h; the identity
 * when the memory order is the user's), so the sums do not depend on it.  src/backend/omp/observe.c
 * runs the items on host threads or, in the offload variant, on the device
 * (then only the merged slots come back), so the sums have the same bits
 * for every thread count and on every device.  Device-safe: C11 and
 * OpenCL C 1.2. */
#ifndef CD_OBSERVE_ITEMS_H
#define CD_OBSERVE_ITEMS_H
#include "cols.h"
#include "rigid.h"
#include "contact_law.h"
#include "reorder_items.h"
#include "step_items.h"

/* Rows a leaf: 64, so that a GPU has one thread a leaf and many leaves
 * (docs/performance.md, "GPU-shaped reductions").  A leaf's rows are a
 * function of global ids only: particles by id, wall rows by primitive x
 * walls + wall, and the pair rows of 64 primitives (their prim_i), however
 * many rows the list holds: the MPI reduction (src/mpi/mpi_reduce.c), whose
 * lists have other inactive rows than the serial one, sums the same rows
 * in the same leaves (docs/mpi.md, "Reductions"). */
#define CD_OBS_BLOCK 64
#define CD_OBS_FANIN 16

/* Components of an observable (kernels/observables.def) in the slots:
 * every wall of CD_MAX_WALLS has its place, used or not. */
#define CD_OBS_SLOTS_ONE   1
#define CD_OBS_SLOTS_VEC3  3
#define CD_OBS_SLOTS_WALL1 CD_MAX_WALLS
#define CD_OBS_SLOTS_WALL3 (3 * CD_MAX_WALLS)

/* The slots of a partial sum, from kernels/observables.def: CD_OBS_<id> is
 * the first slot of observable id.  The SUM observables come first, in the
 * table's order, merged by sum; from CD_OBS_SUMS on the MAX ones, merged by
 * maximum. */
#define CD_OBS_SLOT_(id, count) CD_OBS_##id, CD_OBS_LAST_##id = CD_OBS_##id + CD_OBS_SLOTS_##count - 1,
#define CD_OBS_NO_SLOT_(id, count)
#define CD_OBS_SUM_PASS_SUM      CD_OBS_SLOT_
#define CD_OBS_SUM_PASS_MAX      CD_OBS_NO_SLOT_
#define CD_OBS_SUM_PASS_WALLS    CD_OBS_NO_SLOT_
#define CD_OBS_SUM_PASS_PROTOCOL CD_OBS_NO_SLOT_
#define CD_OBS_MAX_PASS_SUM      CD_OBS_NO_SLOT_
#define CD_OBS_MAX_PASS_MAX      CD_OBS_SLOT_
#define CD_OBS_MAX_PASS_WALLS    CD_OBS_NO_SLOT_
#define CD_OBS_MAX_PASS_PROTOCOL CD_OBS_NO_SLOT_
enum cd_obs_slot {
#define CD_OBSERVABLE(id, name, unit, count, source, member, meaning) CD_OBS_SUM_PASS_##source(id, count)
#include "observables.def"
    CD_OBS_SUMS,
    CD_OBS_BEFORE_MAX_ = CD_OBS_SUMS - 1,
#define CD_OBSERVABLE(id, name, unit, count, source, member, meaning) CD_OBS_MAX_PASS_##source(id, count)
#include "observables.def"
    CD_OBS_SLOTS
};

CD_DEVICE_BEGIN

/* Particles with an active contact, marked by counting their contacts
 * (integer atomics: a count, never a floating-point sum). */
CD_INLINE void cd_obs_item_touch_pair(cd_cols c, cd_long k, CD_GLOBAL cd_int *touch)
{
    if (!c.pair_active[k]) return;
    cd_atomic_inc(&touch[c.prim_particle[c.pair_prim_i[k]]]);
    cd_atomic_inc(&touch[c.prim_particle[c.pair_prim_j[k]]]);
}

/* Wall candidate e (row wall_rows[e], entry wall_out[e]: kernels/step_items.h). */
CD_INLINE void cd_obs_item_touch_wall(cd_cols c, cd_long e, cd_int n_walls, const CD_GLOBAL cd_int *wall_rows,
                                      const CD_GLOBAL cd_wall_entry *wall_out, CD_GLOBAL cd_int *touch)
{
    if (wall_out[e].active) cd_atomic_inc(&touch[c.prim_particle[wall_rows[e] / n_walls]]);
}

/* Partial sums of the tree over n leaves: the leaves and the levels above
 * them but the last (the total). */
CD_INLINE cd_long cd_obs_tree_blocks(cd_long n)
{
    cd_long s = n;
    while (n > CD_OBS_FANIN) {
        n = (n + CD_OBS_FANIN - 1) / CD_OBS_FANIN;
        s += n;
    }
    return s;
}

CD_INLINE void cd_obs_clear(CD_GLOBAL cd_real *acc)
{
    for (int k = 0; k < CD_OBS_SLOTS; k++) acc[k] = 0;
}

CD_INLINE cd_long cd_obs_block_end(cd_long b, cd_long n)
{
    return (b + 1) * CD_OBS_BLOCK < n ? (b + 1) * CD_OBS_BLOCK : n;
}

/* The leaves sum into scalars (registers on a GPU; a private array of
 * the slots was kept in device heap by Clang's offload, remark OMP112),
 * written out once; per slot the additions are those of a sum into the
 * slots, in row order. */

/* Block b of the particles: kinetic and potential energy in gravity
 * [m/s^2], momentum. */
CD_INLINE void cd_obs_block_particles(cd_cols c, cd_long b, cd_long n, cd_vec3 gravity, const CD_GLOBAL cd_int *touch,
                                      CD_GLOBAL cd_real *acc, cd_order o)
{
    cd_real sum_kt = 0, sum_kr = 0, sum_kc = 0, sum_pe = 0; /* [J] */
    cd_vec3 sum_p = cd_v3_zero();                           /* [kg m/s] */
    for (cd_long u = b * CD_OBS_BLOCK; u < cd_obs_block_end(b, n); u++) {
        cd_long q = cd_map(o.part_at, u);
        cd_vec3 v = c.velocity[q];
        cd_real m = c.mass[q];
        cd_real kt = CD_R(0.5) * m * cd_v3_norm2(v),
                kr = cd_rigid_rot_energy(c.orientation[q], c.angmom[q], cd_inertia_of(c, q));
        sum_kt += kt;
        sum_kr += kr;
        if (touch[q]) sum_kc += kt + kr;
        sum_pe -= m * cd_v3_dot(gravity, c.position[q]);
        sum_p.x += m * v.x;
        sum_p.y += m * v.y;
        sum_p.z += m * v.z;
    }
    cd_obs_clear(acc);
    acc[CD_OBS_KT] = sum_kt;
    acc[CD_OBS_KR] = sum_kr;
    acc[CD_OBS_KC] = sum_kc;
    acc[CD_OBS_PE] = sum_pe;
    acc[CD_OBS_PX] = sum_p.x;
    acc[CD_OBS_PX + 1] = sum_p.y;
    acc[CD_OBS_PX + 2] = sum_p.z;
}

/* Leaves of the pair rows: one per CD_OBS_BLOCK primitives (n_prims). */
CD_INLINE cd_long cd_obs_pair_blocks(cd_long n_prims) { return (n_prims + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK; }

/* The first of the n pair rows in user order whose primitive i has a user
 * id >= p (n if none): the rows are in key order (user id of i, then of
 * j: the list build, kernels/neighbor_items.h, and the file's rows), so a
 * binary search. */
CD_INLINE cd_long cd_obs_pair_first(cd_cols c, cd_long n, cd_long p, cd_order o)
{
    cd_long lo = 0, hi = n;
    while (lo < hi) {
        cd_long mid = lo + (hi - lo) / 2;
        if (cd_map(o.prim_uid, c.pair_prim_i[cd_map(o.pair_at, mid)]) < p) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* Overlap [m] of active pair row k: overlap[k] where the rows come with
 * it (the MPI leaves' gathered rows, src/mpi/mpi_reduce.c), else from the
 * narrow phase of the step on the columns' ends (cd_pair_narrow: the value
 * the pair pass computed from the same ends; no row keeps it, fields.def). */
CD_INLINE cd_real cd_obs_pair_overlap(cd_cols c, cd_long k, const CD_GLOBAL cd_real *overlap, cd_real sin_parallel,
                                      cd_int parallel_blend)
{
    if (overlap) return overlap[k];
    cd_prim_id i = c.pair_prim_i[k], j = c.pair_prim_j[k];
    cd_contact_geom g;
    return cd_pair_narrow(c, i, j, c.prim_radius[i], c.prim_radius[j], sin_parallel, parallel_blend, &g) ? CD_R(0)
                                                                                                         : g.overlap;
}

/* Block b of the pair rows (n of them), the rows of primitives i = b
 * CD_OBS_BLOCK .. (b + 1) CD_OBS_BLOCK - 1 (user ids): elastic energy,
 * contacts, largest overlap.  Inactive rows add nothing, so the sums do not
 * depend on how many a list holds.  overlap, sin_parallel [1],
 * parallel_blend: cd_obs_pair_overlap. */
CD_INLINE void cd_obs_block_pairs(cd_cols c, cd_long b, cd_long n, cd_law_params law, CD_GLOBAL cd_real *acc,
                                  cd_order o, const CD_GLOBAL cd_real *overlap, cd_real sin_parallel,
                                  cd_int parallel_blend)
{
    cd_real el = 0, contacts = 0, most = 0; /* [J], count, overlap / diameter */
    cd_long end = cd_obs_pair_first(c, n, (b + 1) * CD_OBS_BLOCK, o);
    for (cd_long u = cd_obs_pair_first(c, n, b * CD_OBS_BLOCK, o); u < end; u++) {
        cd_long k = cd_map(o.pair_at, u);
        if (!c.pair_active[k]) continue;
        cd_real ri = c.prim_radius[c.pair_prim_i[k]], rj = c.prim_radius[c.pair_prim_j[k]];
        cd_real delta = cd_obs_pair_overlap(c, k, overlap, sin_parallel, parallel_blend); /* [m] */
        el += cd_contact_elastic_energy(law, cd_law_pair_radius(ri, rj), delta, c.pair_shear[k]);
        contacts += 1;
        cd_real ratio = delta / (2 * (ri < rj ? ri : rj));
        if (ratio > most) most = ratio;
    }
    cd_obs_clear(acc);
    acc[CD_OBS_EL] = el;
    acc[CD_OBS_NC] = contacts;
    acc[CD_OBS_MAXOV] = most;
}

/* Block b of the primitive-wall rows (n_walls per primitive): elastic
 * energy, contacts, the particles' force on each wall [N] (summed in
 * place: its slot depends on the row), largest overlap.  The history and
 * outputs of the rows: wall_out per wall candidate (cd_wall_out_place; a
 * row that is none is not in contact). */
CD_INLINE void cd_obs_block_walls(cd_cols c, cd_long b, cd_long n, cd_int n_walls, cd_law_params wall_law,
                                  CD_GLOBAL cd_real *acc, cd_order o, const CD_GLOBAL cd_int *wall_start,
                                  const CD_GLOBAL cd_int *wall_rows, const CD_GLOBAL cd_wall_entry *wall_out)
{
    cd_real el = 0, contacts = 0, most = 0; /* [J], count, overlap / diameter */
    cd_obs_clear(acc);
    for (cd_long u = b * CD_OBS_BLOCK; u < cd_obs_block_end(b, n); u++) {
        cd_long w = u % n_walls, i = cd_map(o.prim_at, u / n_walls), r = i * n_walls + w;
        cd_long e = cd_wall_out_place(c, r, n_walls, wall_start, wall_rows);
        if (e < 0 || !wall_out[e].active) continue;
        cd_wall_entry out = wall_out[e];
        el += cd_contact_elastic_energy(wall_law, c.prim_radius[i], out.overlap, out.shear);
        contacts += 1;
        /* The particle pushes the wall with the opposite of the wall's force. */
        acc[CD_OBS_WALL + 3 * w + 0] -= out.force.x;
        acc[CD_OBS_WALL + 3 * w + 1] -= out.force.y;
        acc[CD_OBS_WALL + 3 * w + 2] -= out.force.z;
        cd_real ratio = out.overlap / (2 * c.prim_radius[i]);
        if (ratio > most) most = ratio;
    }
    acc[CD_OBS_EL] = el;
    acc[CD_OBS_NW] = contacts;
    acc[CD_OBS_MAXOV] = most;
}

/* Item g of a level of the tree: partial sums g FANIN .. (g + 1) FANIN - 1
 * of the n at partial merged in order into out + g CD_OBS_SLOTS: the SUM
 * slots added, the MAX slots by maximum.  The last level has one item,
 * whose out is the total. */
CD_INLINE void cd_obs_item_merge(const CD_GLOBAL cd_real *partial, cd_long n, cd_long g, CD_GLOBAL cd_real *out)
{
    CD_GLOBAL cd_real *total = out + g * CD_OBS_SLOTS;
    cd_obs_clear(total);
    cd_long end = (g + 1) * CD_OBS_FANIN < n ? (g + 1) * CD_OBS_FANIN : n;
    for (cd_long b = g * CD_OBS_FANIN; b < end; b++) {
        const CD_GLOBAL cd_real *p = partial + b * CD_OBS_SLOTS;
        for (int k = 0; k < CD_OBS_SUMS; k++) total[k] += p[k];
        for (int k = CD_OBS_SUMS; k < CD_OBS_SLOTS; k++)
            if (p[k] > total[k]) total[k] = p[k];
    }
}

/* The whole tree on one thread (MPI: rank 0 merging the leaves summed on
 * every rank, src/mpi/mpi_reduce.c): the levels of cd_obs_item_merge in
 * the order src/backend/omp/observe.c runs them, so the same bits; part
 * has room for cd_obs_tree_blocks(n) partials, the leaves first. */
CD_INLINE void cd_obs_merge_serial(CD_GLOBAL cd_real *part, cd_long n, CD_GLOBAL cd_real *total)
{
    for (CD_GLOBAL cd_real *in = part;;) {
        cd_long m = n > CD_OBS_FANIN ? (n + CD_OBS_FANIN - 1) / CD_OBS_FANIN : 1;
        CD_GLOBAL cd_real *out = m == 1 ? total : in + n * CD_OBS_SLOTS;
        for (cd_long g = 0; g < m; g++) cd_obs_item_merge(in, n, g, out);
        if (m == 1) return;
        in = out;
        n = m;
    }
}

CD_DEVICE_END
#endif
