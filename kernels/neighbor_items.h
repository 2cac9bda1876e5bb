/* One work item of each pass of the Verlet-list build (docs/architecture.md,
 * "Neighbour list").  The build exists once: the OpenMP loops of
 * src/backend/omp/neighbors.c (host threads, or an offload device) and the OpenCL
 * kernels of kernels/cl/neighbors.cl call these items in the same passes:
 *
 *   1. bounds    per chunk of particles: bounding radii, box of centres
 *   2. grid      one item: merges the chunks' boxes, makes the grid
 *   3. bin       per particle: its cell, counted (integer atomic)
 *   4. scan      cell counts -> cell_start; cell_parts filled (atomic)
 *   5. collect   per particle (host threads, OpenCL) or per primitive (omp
 *                offload): the candidates of its primitives, each row
 *                sorted by j, into fixed slots (a second pass writes the
 *                rows in place when some primitive overflowed its slot)
 *   6. scan      row counts -> pair offsets; the number of rows goes back
 *   7. place     per primitive: slot -> rows (prim_i, prim_j) and keys
 *   8. carry     per row: history of the old row with the same key
 *   9. gather    per row: counted and filled into its two particles' lists
 *                (atomic), then per particle sorted ascending
 *  10. walls     per particle: wall candidates counted, scanned, filled
 *  11. visit     (mixtures only) per chunk of rows: the pair pass's
 *                visiting order, rows grouped by kind (counting sort)
 *
 * Integer atomics only fill counting sorts; whatever they leave out of
 * order is sorted again (rows by insertion in pass 5, gather lists in pass
 * 9), or feeds only a scan, so the list is the same on every run, backend
 * and thread count.  Device-safe: C11 and OpenCL C 1.2. */
#ifndef CD_NEIGHBOR_ITEMS_H
#define CD_NEIGHBOR_ITEMS_H
#include "cols.h"
#include "broadphase.h"
#include "reorder_items.h"

/* The cap of a row written in place (fill mode of pass 5). */
#define CD_BP_UNBOUNDED 0x7fffffff

CD_DEVICE_BEGIN

/* Rows to allocate for n rows of a list that the builds size (the pair
 * rows, their keys, gather entries and kept history; the wall
 * candidates): n and a 64th of it, so that a list at rest holds 1.6 %
 * spare rows instead of a quarter, and a growing list reallocates once per
 * 1.6 % of growth, not at every build (docs/performance.md, "Fewer bytes
 * per sphere").  Host code of both backends calls it. */
CD_INLINE cd_long cd_nb_room(cd_long n) { return n + n / 64 + 16; }

/* Pass 1, in three steps shaped for a GPU (one item per particle, then
 * a tree of boxes; a 256-particle chunk per item left a GPU a few hundred
 * threads, 4.8 ms at 1e5 hexapods on an H100):
 *   1a  bounding radius [m] of particle p into part_bound;
 *   1b  box of the centres of chunk g of CD_BOX_CHUNK particles and its
 *       largest bound, as 7 reals (lo xyz, hi xyz, rmax) at boxes + 7 g;
 *   1c  while more than CD_BOX_CHUNK boxes remain: the boxes of chunk g of
 *       them merged into one, a level up (the levels one after the other
 *       in one array of 7 cd_nb_box_scratch(n) reals).
 * Minimum and maximum are exact: the grid does not depend on the chunking. */
#define CD_BOX_CHUNK 64

/* Boxes of all levels of the tree over n particles; at least 1. */
CD_INLINE cd_long cd_nb_box_scratch(cd_long n)
{
    n = (n + CD_BOX_CHUNK - 1) / CD_BOX_CHUNK;
    cd_long s = n > 1 ? n : 1;
    while (n > CD_BOX_CHUNK) {
        n = (n + CD_BOX_CHUNK - 1) / CD_BOX_CHUNK;
        s += n;
    }
    return s;
}

/* Bounding radius of particle p about its centre [m] (cd_bp_particle_bound,
 * with end b of a ball without an arm its end a). */
CD_INLINE void cd_nb_item_bound(cd_cols c, cd_particle_id p, CD_GLOBAL cd_real *part_bound)
{
    cd_real r = 0;
    cd_vec3 x = c.position[p];
    for (cd_prim_id i = c.prim_first[p]; i < c.prim_first[p] + c.prim_count[p]; i++) {
        cd_real reach = cd_bp_reach(c.prim_a[i], cd_prim_b(c, i), c.prim_radius[i], x);
        if (reach > r) r = reach;
    }
    part_bound[p] = cd_bp_widened(r);
}

CD_INLINE void cd_nb_box_clear(cd_real *lo, cd_real *hi, cd_real *rmax)
{
    for (int k = 0; k < 3; k++) {
        lo[k] = (cd_real)INFINITY;
        hi[k] = -(cd_real)INFINITY;
    }
    *rmax = 0;
}

CD_INLINE void cd_nb_box_store(const cd_real *lo, const cd_real *hi, cd_real rmax, CD_GLOBAL cd_real *box)
{
    for (int k = 0; k < 3; k++) {
        box[k] = lo[k];
        box[3 + k] = hi[k];
    }
    box[6] = rmax;
}

/* Boxes first .. end - 1 merged into lo, hi, rmax. */
CD_INLINE void cd_nb_box_merge(const CD_GLOBAL cd_real *boxes, cd_long first, cd_long end, cd_real *lo, cd_real *hi,
                               cd_real *rmax)
{
    for (cd_long g = first; g < end; g++) {
        for (int k = 0; k < 3; k++) {
            if (boxes[7 * g + k] < lo[k]) lo[k] = boxes[7 * g + k];
            if (boxes[7 * g + 3 + k] > hi[k]) hi[k] = boxes[7 * g + 3 + k];
        }
        if (boxes[7 * g + 6] > *rmax) *rmax = boxes[7 * g + 6];
    }
}

CD_INLINE void cd_nb_item_box(cd_cols c, cd_long g, cd_long n_particles, const CD_GLOBAL cd_real *part_bound,
                              CD_GLOBAL cd_real *boxes)
{
    cd_real lo[3], hi[3], rmax;
    cd_nb_box_clear(lo, hi, &rmax);
    cd_long end = (g + 1) * CD_BOX_CHUNK < n_particles ? (g + 1) * CD_BOX_CHUNK : n_particles;
    for (cd_long p = g * CD_BOX_CHUNK; p < end; p++) cd_bp_bounds_add(lo, hi, &rmax, c.position[p], part_bound[p]);
    cd_nb_box_store(lo, hi, rmax, boxes + 7 * g);
}

CD_INLINE void cd_nb_item_box_up(const CD_GLOBAL cd_real *boxes, cd_long n, cd_long g, CD_GLOBAL cd_real *up)
{
    cd_real lo[3], hi[3], rmax;
    cd_nb_box_clear(lo, hi, &rmax);
    cd_nb_box_merge(boxes, g * CD_BOX_CHUNK, (g + 1) * CD_BOX_CHUNK < n ? (g + 1) * CD_BOX_CHUNK : n, lo, hi, &rmax);
    cd_nb_box_store(lo, hi, rmax, up + 7 * g);
}

/* Pass 2 (one item): the last level's n_boxes boxes merged and the grid
 * made for skin [m]. */
CD_INLINE void cd_nb_item_grid(const CD_GLOBAL cd_real *boxes, cd_int n_boxes, cd_real skin, cd_int n_particles,
                               CD_GLOBAL cd_grid *grid)
{
    cd_real lo[3], hi[3], rmax;
    cd_nb_box_clear(lo, hi, &rmax);
    cd_nb_box_merge(boxes, 0, n_boxes, lo, hi, &rmax);
    cd_grid gr;
    /* Centres not finite, or spread over more than 1e12 cell sizes: the
     * run blew up, and a grid of them would overflow its integer
     * coordinates.  The grid is marked (dim[0] = -1: no cell, no pair) and
     * the build reports the blow-up. */
    int sane = 1;
    for (int k = 0; k < 3; k++)
        if (!(hi[k] - lo[k] <= CD_R(1e12) * (2 * rmax + skin))) sane = 0; /* NaN fails too */
    if (sane) {
        cd_grid_make(&gr, lo, hi, rmax, skin, n_particles);
    } else {
        for (int k = 0; k < 3; k++) {
            gr.lo[k] = 0;
            gr.dim[k] = k ? 1 : -1;
        }
        gr.cell = 1;
    }
    grid[0] = gr;
}

/* Pass 3: cell of particle q (its centre), counted in cell_count.  The
 * index is bounded by cell_cap even for a non-finite position (a run
 * blowing up before its check), so no write leaves the buffers. */
CD_INLINE void cd_nb_item_bin(cd_cols c, cd_particle_id q, const CD_GLOBAL cd_grid *grid, cd_int cell_cap,
                              CD_GLOBAL cd_int *part_cell, CD_GLOBAL cd_int *cell_count)
{
    cd_grid g = grid[0];
    cd_long idx = cd_grid_cell_of(&g, c.position[q]);
    cd_int cell = idx >= 0 && idx < cell_cap ? (cd_int)idx : 0;
    part_cell[q] = cell;
    cd_atomic_inc(&cell_count[cell]);
}

/* Pass 4: particle q into its cell's slice of cell_parts (cursor starts as
 * cell_start).  The order inside a cell may vary from run to run; pass 5
 * sorts every row, so the list does not. */
CD_INLINE void cd_nb_item_cell_fill(cd_particle_id q, const CD_GLOBAL cd_int *part_cell, CD_GLOBAL cd_int *cursor,
                                    CD_GLOBAL cd_int *cell_parts)
{
    cell_parts[cd_atomic_inc(&cursor[part_cell[q]])] = q;
}

/* Pass 5: the candidates (i, j) with i one of the primitives first ..
 * last - 1 of particle p and j a primitive of a particle q of a higher
 * user id (o.part_uid: the row's orientation, and so the narrow phase's
 * arithmetic, does not depend on the memory order): the particles in the
 * 27 cells around p's centre whose bounding spheres (part_bound [m]) come
 * within the skin [m] of p's, then each pair passing cd_bp_is_candidate.
 * Row i goes to out + i slot (slot mode, offset = 0: at most slot entries
 * written) or to out + offset[i] (fill mode: the row's exact place);
 * either way sorted by the user id of j (insertion), and count[i] = the
 * row's length, which in slot mode may exceed slot (then the row is
 * incomplete and the host runs fill mode).  A row's entries, its order and
 * its count do not depend on which other rows the item makes, nor on the
 * order in which it meets the candidates (their user ids differ): host
 * threads and OpenCL make all of a particle's rows in one item (first =
 * prim_first[p], last = first + prim_count[p]: one scan of the cells for
 * the arms of a hexapod), the omp offload build one row per item (first =
 * i, last = i + 1, p = prim_particle[i]: three times the threads,
 * src/backend/omp/neighbors.c). */
CD_INLINE_ALWAYS void cd_nb_item_collect(cd_cols c, cd_particle_id p, cd_prim_id first, cd_prim_id last,
                                         const CD_GLOBAL cd_grid *grid, const CD_GLOBAL cd_int *cell_start,
                                         const CD_GLOBAL cd_int *cell_parts, const CD_GLOBAL cd_real *part_bound,
                                         cd_real skin, CD_GLOBAL cd_prim_id *out, cd_int slot,
                                         const CD_GLOBAL cd_int *offset, CD_GLOBAL cd_int *count, cd_order o)
{
    cd_grid g = grid[0];
    cd_int cap = offset ? CD_BP_UNBOUNDED : slot;
    for (cd_int i = first; i < last; i++) count[i] = 0;
    cd_vec3 x = c.position[p];
    cd_real reach0 = part_bound[p] + skin; /* [m] */
    cd_long uid_p = cd_map(o.part_uid, p);
    cd_long cx = cd_grid_coord(&g, x.x, 0), cy = cd_grid_coord(&g, x.y, 1), cz = cd_grid_coord(&g, x.z, 2);
    for (cd_long z = cz - 1; z <= cz + 1; z++) {
        if (z < 0 || z >= g.dim[2]) continue;
        for (cd_long y = cy - 1; y <= cy + 1; y++) {
            if (y < 0 || y >= g.dim[1]) continue;
            for (cd_long xx = cx - 1; xx <= cx + 1; xx++) {
                if (xx < 0 || xx >= g.dim[0]) continue;
                cd_long cell = (z * g.dim[1] + y) * g.dim[0] + xx;
                for (cd_int k = cell_start[cell]; k < cell_start[cell + 1]; k++) {
                    cd_particle_id q = cell_parts[k];
                    if (cd_map(o.part_uid, q) <= uid_p) continue;
                    cd_real reach = reach0 + part_bound[q];
                    if (cd_v3_norm2(cd_v3_sub(c.position[q], x)) > reach * reach) continue;
                    for (cd_int i = first; i < last; i++) {
                        CD_GLOBAL cd_prim_id *row = out + (offset ? (cd_long)offset[i] : (cd_long)i * slot);
                        cd_vec3 ai = c.prim_a[i], bi = cd_prim_b(c, i);
                        cd_real ri = c.prim_radius[i];
                        for (cd_prim_id j = c.prim_first[q]; j < c.prim_first[q] + c.prim_count[q]; j++) {
                            if (!cd_bp_is_candidate(ai, bi, ri, c.prim_a[j], cd_prim_b(c, j), c.prim_radius[j], skin))
                                continue;
                            cd_int n = count[i];
                            if (n < cap) { /* insertion keeps the row sorted by the user id of j */
                                cd_int m = n;
                                cd_long uj = cd_map(o.prim_uid, j);
                                while (m > 0 && cd_map(o.prim_uid, row[m - 1]) > uj) {
                                    row[m] = row[m - 1];
                                    m--;
                                }
                                row[m] = j;
                            }
                            count[i] = n + 1;
                        }
                    }
                }
            }
        }
    }
}

/* Key of pair row k, ascending along the rows: the memory slot of prim_i,
 * then the user id of prim_j (the order of a primitive's rows, pass 5). */
CD_INLINE cd_ulong cd_nb_row_key(cd_cols c, cd_long k, cd_order o)
{
    return cd_bp_pair_key(c.pair_prim_i[k], (cd_prim_id)cd_map(o.prim_uid, c.pair_prim_j[k]));
}

/* Before the rows are replaced: the key and history of old row k, kept for
 * the carry-over (pass 8). */
CD_INLINE void cd_nb_item_keep(cd_cols c, cd_long k, cd_order o, CD_GLOBAL cd_ulong *old_keys,
                               CD_GLOBAL cd_flag *old_active, CD_GLOBAL cd_vec3 *old_shear)
{
    old_keys[k] = cd_nb_row_key(c, k, o);
    old_active[k] = c.pair_active[k];
    old_shear[k] = c.pair_shear[k];
}

/* Pass 7: the rows offset[i] .. offset[i+1] of primitive i from its slot
 * (slot > 0) or, after a fill-mode pass 5 (slot = 0), already in
 * pair_prim_j: prim_i set, and each row's key (cd_nb_row_key). */
CD_INLINE void cd_nb_item_place(cd_cols c, cd_prim_id i, const CD_GLOBAL cd_int *offset,
                                const CD_GLOBAL cd_prim_id *cand, cd_int slot, CD_GLOBAL cd_ulong *keys, cd_order o)
{
    cd_int first = offset[i], n = offset[i + 1] - first;
    for (cd_int m = 0; m < n; m++) {
        cd_prim_id j = slot > 0 ? cand[(cd_long)i * slot + m] : c.pair_prim_j[first + m];
        c.pair_prim_i[first + m] = i;
        c.pair_prim_j[first + m] = j;
        keys[first + m] = cd_bp_pair_key(i, (cd_prim_id)cd_map(o.prim_uid, j));
    }
}

/* Pass 8: history of new row k: the old row with the same key keeps its
 * activity and tangential spring [m]; a pair new to the list starts
 * without history.  Force and point start at zero in every row: the
 * gather adds every row's force, and a row that is not active must add a
 * zero (cd_item_pair_force keeps it so).  prim_src: the memory slot each primitive had when the
 * old rows were made (null: the same; src/backend/omp/reorder.c), so that the key is
 * looked up as the old rows wrote it. */
CD_INLINE void cd_nb_item_carry(cd_cols c, cd_long k, const CD_GLOBAL cd_ulong *keys,
                                const CD_GLOBAL cd_ulong *old_keys, cd_long n_old, const CD_GLOBAL cd_flag *old_active,
                                const CD_GLOBAL cd_vec3 *old_shear, const CD_GLOBAL cd_int *prim_src)
{
    cd_ulong key = keys[k];
    if (prim_src) key = cd_bp_pair_key(prim_src[key >> 32], (cd_prim_id)(key & 0xffffffffUL));
    cd_long o = cd_bp_find_key(old_keys, n_old, key);
    c.pair_active[k] = o >= 0 ? old_active[o] : 0;
    c.pair_shear[k] = o >= 0 ? old_shear[o] : cd_v3_zero();
    c.pair_force[k] = cd_v3_zero();
    c.pair_point[k] = cd_v3_zero();
}

/* Pass 9a: row k counts once in each of its two particles' lists. */
CD_INLINE void cd_nb_item_gather_count(cd_cols c, cd_long k, CD_GLOBAL cd_int *count)
{
    cd_atomic_inc(&count[c.prim_particle[c.pair_prim_i[k]]]);
    cd_atomic_inc(&count[c.prim_particle[c.pair_prim_j[k]]]);
}

/* Pass 9b: row k into its particles' slices as 2 k + side (side 1 for the
 * particle of primitive j: step_items.h, cd_item_gather); cursor starts as
 * gather_start. */
CD_INLINE void cd_nb_item_gather_fill(cd_cols c, cd_long k, CD_GLOBAL cd_int *cursor, CD_GLOBAL cd_pair_id *rows)
{
    rows[cd_atomic_inc(&cursor[c.prim_particle[c.pair_prim_i[k]]])] = (cd_pair_id)(2 * k);
    rows[cd_atomic_inc(&cursor[c.prim_particle[c.pair_prim_j[k]]])] = (cd_pair_id)(2 * k + 1);
}

/* User key of gather entry e (2 k + side): its row's primitives' user
 * ids, i then j.  Without reordering, rows ascend with their keys. */
CD_INLINE cd_ulong cd_nb_entry_key(cd_cols c, cd_order o, cd_pair_id e)
{
    if (!o.prim_uid) return (cd_ulong)(cd_uint)e;
    cd_pair_id k = e >> 1;
    return cd_bp_pair_key(o.prim_uid[c.pair_prim_i[k]], o.prim_uid[c.pair_prim_j[k]]);
}

/* Pass 9c: particle q's entries in ascending user key of their rows
 * (insertion: a few tens), the order in which the gather sums them: the
 * same order whatever the memory order. */
CD_INLINE void cd_nb_item_gather_sort(cd_cols c, cd_order o, cd_particle_id q, const CD_GLOBAL cd_int *start,
                                      CD_GLOBAL cd_pair_id *rows)
{
    cd_int first = start[q], last = start[q + 1];
    for (cd_int a = first + 1; a < last; a++) {
        cd_pair_id v = rows[a];
        cd_ulong kv = cd_nb_entry_key(c, o, v);
        cd_int b = a;
        while (b > first && cd_nb_entry_key(c, o, rows[b - 1]) > kv) {
            rows[b] = rows[b - 1];
            b--;
        }
        rows[b] = v;
    }
}

/* The prefix sums of passes 4, 6, 9 and 10 (and of the reorder's radix
 * sort): out[0] = 0, out[k+1] = out[k] + in[k] (out has n + 1 entries,
 * out[n] the total), as a tree of chunks of CD_SCAN_CHUNK entries, shaped
 * for a GPU as much as for host threads (docs/performance.md, "GPU-shaped
 * reductions"):
 *
 *   up      level l+1 holds the sums of the chunks of level l (level 0 is
 *           in), while level l has more than one chunk: cd_scan_item_sum;
 *   top     one item scans the last level (at most one chunk) in place,
 *           or in into out when n fits one chunk: cd_scan_item_top;
 *   down    each chunk of level l, from the top level down, rewrites its
 *           entries as prefix sums starting at its chunk's entry one level
 *           up; level 0 writes into out: cd_scan_item_fill.
 *
 * 2n additions in all, and short serial loops: a chunk of 64 entries is
 * one item, so 1e6 entries give 15,625 items at level 0 (1,024-entry chunks
 * gave a GPU under a thousand threads with long dependent loops).  Integer
 * arithmetic: exact, so the result does not depend on the chunking. The
 * levels above 0 live in one scratch array of cd_scan_scratch(n) entries,
 * level after level, each with one entry more for its total. */
#define CD_SCAN_CHUNK 64

/* Entries of the scratch of a scan of n entries (all levels above 0, and
 * their totals); at least 1. */
CD_INLINE cd_long cd_scan_scratch(cd_long n)
{
    cd_long s = 1;
    while (n > CD_SCAN_CHUNK) {
        n = (n + CD_SCAN_CHUNK - 1) / CD_SCAN_CHUNK;
        s += n + 1;
    }
    return s;
}

CD_INLINE cd_long cd_scan_chunk_end(cd_long g, cd_long n)
{
    return (g + 1) * CD_SCAN_CHUNK < n ? (g + 1) * CD_SCAN_CHUNK : n;
}

/* Up: sums[g] = the sum of chunk g of the n entries of in. */
CD_INLINE void cd_scan_item_sum(const CD_GLOBAL cd_int *in, cd_long n, cd_long g, CD_GLOBAL cd_int *sums)
{
    cd_int s = 0;
    for (cd_long i = g * CD_SCAN_CHUNK; i < cd_scan_chunk_end(g, n); i++) s += in[i];
    sums[g] = s;
}

/* Top (one item): out[k] = in[0] + ... + in[k-1] for k <= n; in and out
 * may be the same array (then it holds n + 1 entries). */
CD_INLINE void cd_scan_item_top(const CD_GLOBAL cd_int *in, cd_long n, CD_GLOBAL cd_int *out)
{
    cd_int run = 0;
    for (cd_long i = 0; i < n; i++) {
        cd_int t = in[i];
        out[i] = run;
        run += t;
    }
    out[n] = run;
}

/* Down: chunk g of the n entries of in as prefix sums into out, starting
 * at starts[g] (the scanned level above); the last chunk writes the total
 * out[n].  in and out may be the same array. */
CD_INLINE void cd_scan_item_fill(const CD_GLOBAL cd_int *in, cd_long n, cd_long g, const CD_GLOBAL cd_int *starts,
                                 CD_GLOBAL cd_int *out)
{
    cd_long end = cd_scan_chunk_end(g, n);
    cd_int run = starts[g];
    for (cd_long i = g * CD_SCAN_CHUNK; i < end; i++) {
        cd_int t = in[i];
        out[i] = run;
        run += t;
    }
    if (end == n) out[n] = run;
}

/* After chunk g of out is filled (cd_scan_item_fill, or the top item for
 * a single chunk): its entries, and the total after the last chunk, also
 * into copy, in the same item -- the cursor of a counting fill, which was
 * a launch of its own (copy may be the scan's input: the chunk has been
 * read). */
CD_INLINE void cd_scan_item_copy(const CD_GLOBAL cd_int *out, cd_long n, cd_long g, CD_GLOBAL cd_int *copy)
{
    cd_long end = cd_scan_chunk_end(g, n);
    for (cd_long i = g * CD_SCAN_CHUNK; i < end; i++) copy[i] = out[i];
    if (end == n) copy[n] = out[n];
}

/* Pass 11, only where the primitives are of both kinds (points: balls,
 * arms of zero length; segments: arms), so that rows of several kinds
 * exist: the order in which the pair pass visits the rows, grouped by
 * kind (cd_nb_row_kind: the three narrow phases of cd_pair_narrow), each
 * group in ascending row order, so that a GPU warp (32 consecutive items)
 * runs one narrow phase but at the two group boundaries.  The rows stay
 * in key order (the carry-over's binary search, the gather lists, the
 * reorder's user order and the MPI leaves read them so); only the pair
 * pass reads the order, and a row's result does not depend on when it is
 * computed (it reads the particles and writes its own row only), so the
 * bits are those of the direct loop (docs/contacts.md, "Rows visited by
 * kind").  A counting sort without atomics, the same on every backend:
 *
 *   count   per chunk g of CD_SCAN_CHUNK rows: its rows of each kind t
 *           into starts[t n_chunks + g] (kind-major: one scan then gives
 *           every (kind, chunk) its first place);
 *   scan    starts in place (cd_scan_item_*; 3 n_chunks entries);
 *   fill    per chunk g: its rows, in row order, to the places of their
 *           kind from starts[t n_chunks + g] on. */
#define CD_ROW_KINDS 3

/* Kind of pair row k: 0 two points, 1 a point and a segment, 2 two
 * segments (rows.pair_rows_by_kind of capdem-bench). */
CD_INLINE cd_int cd_nb_row_kind(cd_cols c, cd_long k)
{
    cd_prim_id i = c.pair_prim_i[k], j = c.pair_prim_j[k];
    return 2 - cd_segseg_is_point(c.prim_a[i], cd_prim_b(c, i)) - cd_segseg_is_point(c.prim_a[j], cd_prim_b(c, j));
}

/* Chunks of the visiting order's counting sort over n rows. */
CD_INLINE cd_long cd_nb_visit_chunks(cd_long n) { return (n + CD_SCAN_CHUNK - 1) / CD_SCAN_CHUNK; }

/* Count: the rows of each kind in chunk g of the n rows. */
CD_INLINE void cd_nb_item_visit_count(cd_cols c, cd_long g, cd_long n, CD_GLOBAL cd_int *starts)
{
    cd_int count[CD_ROW_KINDS] = {0, 0, 0};
    for (cd_long k = g * CD_SCAN_CHUNK; k < cd_scan_chunk_end(g, n); k++) count[cd_nb_row_kind(c, k)]++;
    cd_long m = cd_nb_visit_chunks(n);
    for (int t = 0; t < CD_ROW_KINDS; t++) starts[t * m + g] = count[t];
}

/* Fill: chunk g's rows into their kinds' places (starts scanned). */
CD_INLINE void cd_nb_item_visit_fill(cd_cols c, cd_long g, cd_long n, const CD_GLOBAL cd_int *starts,
                                     CD_GLOBAL cd_int *visit)
{
    cd_long m = cd_nb_visit_chunks(n);
    cd_int at[CD_ROW_KINDS];
    for (int t = 0; t < CD_ROW_KINDS; t++) at[t] = starts[t * m + g];
    for (cd_long k = g * CD_SCAN_CHUNK; k < cd_scan_chunk_end(g, n); k++) visit[at[cd_nb_row_kind(c, k)]++] = (cd_int)k;
}

CD_DEVICE_END

#ifndef __OPENCL_VERSION__
/* Host (both backends): are the n primitives of both kinds, points (both
 * body-frame ends the same) and segments?  Then a build makes the visiting
 * order (pass 11); a packing of one shape keeps the direct loop. */
static inline int cd_nb_prims_of_both_kinds(const cd_vec3 *a_body, const cd_vec3 *b_body, size_t n)
{
    int seen = 0; /* bit 0: a point, bit 1: a segment */
    for (size_t i = 0; i < n && seen != 3; i++) seen |= cd_segseg_is_point(a_body[i], b_body[i]) ? 1 : 2;
    return seen == 3;
}
#endif
#endif
