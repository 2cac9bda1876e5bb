/* OpenCL backend: the Verlet list rebuilt on the device (docs/opencl.md,
 * "Neighbour list"), pass by pass as kernels/neighbor_items.h lists them
 * and src/backend/omp/neighbors.c runs them: grid from the box of the particle centres,
 * particles binned by cell, candidates collected per particle into slots,
 * a prefix sum giving each primitive its rows, rows placed sorted by
 * (prim_i, prim_j), history found by binary search of each new key among
 * the old sorted keys, the per-particle gather and wall lists.  The only
 * transfers to the host are the numbers of pairs and of wall candidates
 * and the overflow flag, which size the buffers. */
#include <string.h>
#include "backend/opencl/backend_cl.h"
#include "broadphase.h"
#include "neighbor_items.h"

#define F CD_CL_N_COLS /* first kernel argument after the columns */

static int copy(cd_cl *cl, cl_mem src, cl_mem dst, size_t bytes)
{
    if (cl->status || bytes == 0) return cl->status ? -1 : 0;
    cl_int rc = clEnqueueCopyBuffer(cl->queue, src, dst, 0, 0, bytes, 0, NULL, NULL);
    return cd_cl_check(cl, rc, "copying a buffer") ? -1 : 0;
}

/* Particle bounds, grid and cell lists (CSR cell_start / cell_parts). */
static void bin_particles(cd_cl *cl, cd_int N, cd_real skin)
{
    cd_int cell_cap = (cd_int)cl->cell_cap, n = (N + CD_BOX_CHUNK - 1) / CD_BOX_CHUNK, at = 0;
    cd_cl_arg(cl, CD_CLK_BOUNDS, F, sizeof N, &N);
    cd_cl_arg(cl, CD_CLK_BOUNDS, F + 1, sizeof cl->part_bound, &cl->part_bound);
    cd_cl_run(cl, CD_CLK_BOUNDS, (size_t)N);
    cd_cl_arg(cl, CD_CLK_BOX, F, sizeof N, &N);
    cd_cl_arg(cl, CD_CLK_BOX, F + 1, sizeof cl->part_bound, &cl->part_bound);
    cd_cl_arg(cl, CD_CLK_BOX, F + 2, sizeof cl->partial, &cl->partial);
    cd_cl_run(cl, CD_CLK_BOX, (size_t)n);
    while (n > CD_BOX_CHUNK) { /* the tree of boxes (kernels/neighbor_items.h) */
        cd_int m = (n + CD_BOX_CHUNK - 1) / CD_BOX_CHUNK, up_at = at + n;
        cd_cl_arg(cl, CD_CLK_BOX_UP, 0, sizeof cl->partial, &cl->partial);
        cd_cl_arg(cl, CD_CLK_BOX_UP, 1, sizeof at, &at);
        cd_cl_arg(cl, CD_CLK_BOX_UP, 2, sizeof n, &n);
        cd_cl_arg(cl, CD_CLK_BOX_UP, 3, sizeof cl->partial, &cl->partial);
        cd_cl_arg(cl, CD_CLK_BOX_UP, 4, sizeof up_at, &up_at);
        cd_cl_run(cl, CD_CLK_BOX_UP, (size_t)m);
        at = up_at;
        n = m;
    }
    cd_cl_arg(cl, CD_CLK_GRID, 0, sizeof cl->partial, &cl->partial);
    cd_cl_arg(cl, CD_CLK_GRID, 1, sizeof at, &at);
    cd_cl_arg(cl, CD_CLK_GRID, 2, sizeof n, &n);
    cd_cl_arg(cl, CD_CLK_GRID, 3, sizeof skin, &skin);
    cd_cl_arg(cl, CD_CLK_GRID, 4, sizeof N, &N);
    cd_cl_arg(cl, CD_CLK_GRID, 5, sizeof cl->grid, &cl->grid);
    cd_cl_run(cl, CD_CLK_GRID, 1);

    /* The scan runs over every cell the grid may have: the empty tail
     * costs little and spares reading the grid back. */
    cd_cl_fill_int(cl, cl->cell_count, 0, 0, cl->cell_cap);
    cd_cl_arg(cl, CD_CLK_BIN, F, sizeof N, &N);
    cd_cl_arg(cl, CD_CLK_BIN, F + 1, sizeof cl->grid, &cl->grid);
    cd_cl_arg(cl, CD_CLK_BIN, F + 2, sizeof cl->part_cell, &cl->part_cell);
    cd_cl_arg(cl, CD_CLK_BIN, F + 3, sizeof cl->cell_count, &cl->cell_count);
    cd_cl_arg(cl, CD_CLK_BIN, F + 4, sizeof cell_cap, &cell_cap);
    cd_cl_run(cl, CD_CLK_BIN, (size_t)N);
    cd_cl_scan(cl, cl->cell_count, cl->cell_cap, cl->cell_start);
    copy(cl, cl->cell_start, cl->cell_cursor, cl->cell_cap * sizeof(cd_int));
    cd_cl_arg(cl, CD_CLK_CELL_FILL, 0, sizeof N, &N);
    cd_cl_arg(cl, CD_CLK_CELL_FILL, 1, sizeof cl->part_cell, &cl->part_cell);
    cd_cl_arg(cl, CD_CLK_CELL_FILL, 2, sizeof cl->cell_cursor, &cl->cell_cursor);
    cd_cl_arg(cl, CD_CLK_CELL_FILL, 3, sizeof cl->cell_parts, &cl->cell_parts);
    cd_cl_run(cl, CD_CLK_CELL_FILL, (size_t)N);
}

/* Twice the candidate slots, after one overflowed (a primitive in contact
 * with unusually many others, e.g. a long rod among spheres); the buffer
 * is released only after the kernels that use it (in-order queue). */
static void grow_slots(cd_cl *cl, size_t P)
{
    if (cl->status) return;
    clReleaseMemObject(cl->cand);
    cl->slot *= 2;
    cl->cand = cd_cl_buffer(cl, P * (size_t)cl->slot * sizeof(cd_prim_id), "enlarging the candidate slots");
}

/* Arguments shared by the scans of the candidates (pass 5). */
static void scan_args(cd_cl *cl, enum cd_cl_kernel k, cd_int N, cd_real skin)
{
    cd_cl_arg(cl, k, F, sizeof N, &N);
    cd_cl_arg(cl, k, F + 1, sizeof cl->grid, &cl->grid);
    cd_cl_arg(cl, k, F + 2, sizeof cl->cell_start, &cl->cell_start);
    cd_cl_arg(cl, k, F + 3, sizeof cl->cell_parts, &cl->cell_parts);
    cd_cl_arg(cl, k, F + 4, sizeof skin, &skin);
    cd_cl_arg(cl, k, F + 5, sizeof cl->part_bound, &cl->part_bound);
}

/* Per-particle lists of pair rows in ascending order (CSR gather_start /
 * gather_rows), for the gather's fixed summation order. */
static void gather_lists(cd_cl *cl, cd_int N, cd_int n_pairs)
{
    cd_cl_fill_int(cl, cl->gather_count, 0, 0, (size_t)N);
    cd_cl_arg(cl, CD_CLK_GATHER_COUNT, F, sizeof n_pairs, &n_pairs);
    cd_cl_arg(cl, CD_CLK_GATHER_COUNT, F + 1, sizeof cl->gather_count, &cl->gather_count);
    cd_cl_run(cl, CD_CLK_GATHER_COUNT, (size_t)n_pairs);
    cd_cl_scan(cl, cl->gather_count, (size_t)N, cl->gather_start);
    copy(cl, cl->gather_start, cl->gather_cursor, (size_t)N * sizeof(cd_int));
    cd_cl_arg(cl, CD_CLK_GATHER_FILL, F, sizeof n_pairs, &n_pairs);
    cd_cl_arg(cl, CD_CLK_GATHER_FILL, F + 1, sizeof cl->gather_cursor, &cl->gather_cursor);
    cd_cl_arg(cl, CD_CLK_GATHER_FILL, F + 2, sizeof cl->gather_rows, &cl->gather_rows);
    cd_cl_run(cl, CD_CLK_GATHER_FILL, (size_t)n_pairs);
    cd_cl_arg(cl, CD_CLK_GATHER_SORT, 0, sizeof N, &N);
    cd_cl_arg(cl, CD_CLK_GATHER_SORT, 1, sizeof cl->gather_start, &cl->gather_start);
    cd_cl_arg(cl, CD_CLK_GATHER_SORT, 2, sizeof cl->gather_rows, &cl->gather_rows);
    cd_cl_run(cl, CD_CLK_GATHER_SORT, (size_t)N);
}

/* Per-particle wall candidates (CSR wall_start / wall_rows, ascending):
 * count, scan, fill; the number of rows comes back between scan and fill
 * (the size of their lists and of the wall kernel); their history carried
 * over from the old candidates (cd_item_wall_carry); and the walls become
 * the reference of the wall-motion test. */
static void wall_lists(cd_cl *cl, cd_sim *sim, cd_int N)
{
    cd_int W = (cd_int)sim->s.n_walls;
    cd_real skin = sim->nb.skin; /* [m] */
    cd_cl_keep_wall_rows(cl);    /* n_wall_rows 0: without walls the passes run too (wall_start all 0 for the gather) */
    for (int k = CD_CLK_WALL_CAND_COUNT; k <= CD_CLK_WALL_CAND_FILL; k++) {
        cd_cl_arg(cl, k, F, sizeof N, &N);
        cd_cl_arg(cl, k, F + 1, sizeof cl->walls, &cl->walls);
        cd_cl_arg(cl, k, F + 2, sizeof W, &W);
        cd_cl_arg(cl, k, F + 3, sizeof skin, &skin);
    }
    cd_cl_arg(cl, CD_CLK_WALL_CAND_COUNT, F + 4, sizeof cl->wall_count, &cl->wall_count);
    cd_cl_run(cl, CD_CLK_WALL_CAND_COUNT, (size_t)N);
    cd_cl_scan(cl, cl->wall_count, (size_t)N, cl->wall_start);
    /* their number sizes their lists (set_list_args binds them anew) */
    if (!cl->status)
        cd_cl_check(cl,
                    clEnqueueReadBuffer(cl->queue, cl->wall_start, CL_TRUE, (size_t)N * sizeof(cd_int),
                                        sizeof cl->n_wall_rows, &cl->n_wall_rows, 0, NULL, NULL),
                    "reading the number of wall candidates");
    if (cl->status || cd_cl_reserve_wall_rows(cl, (size_t)cl->n_wall_rows)) return;
    cd_cl_arg(cl, CD_CLK_WALL_CAND_FILL, F + 4, sizeof cl->wall_start, &cl->wall_start);
    cd_cl_arg(cl, CD_CLK_WALL_CAND_FILL, F + 5, sizeof cl->wall_rows, &cl->wall_rows);
    cd_cl_run(cl, CD_CLK_WALL_CAND_FILL, (size_t)N);
    cd_cl_arg(cl, CD_CLK_WALL_CARRY, 0, sizeof cl->n_wall_rows, &cl->n_wall_rows);
    cd_cl_arg(cl, CD_CLK_WALL_CARRY, 1, sizeof cl->wall_rows, &cl->wall_rows);
    cd_cl_arg(cl, CD_CLK_WALL_CARRY, 2, sizeof cl->wall_out, &cl->wall_out);
    cd_cl_arg(cl, CD_CLK_WALL_CARRY, 3, sizeof cl->old_wall_rows, &cl->old_wall_rows);
    cd_cl_arg(cl, CD_CLK_WALL_CARRY, 4, sizeof cl->n_old_wall_rows, &cl->n_old_wall_rows);
    cd_cl_arg(cl, CD_CLK_WALL_CARRY, 5, sizeof cl->old_wall_out, &cl->old_wall_out);
    cd_cl_arg(cl, CD_CLK_WALL_CARRY, 6, sizeof W, &W);
    cd_cl_run(cl, CD_CLK_WALL_CARRY, (size_t)cl->n_wall_rows);
    /* The old candidates have served the carry-over (released once the
     * queued carry has run): the steps hold the new ones only. */
    cd_cl_release_old_wall_rows(cl);
    memcpy(sim->nb.walls_ref, cl->host_walls, sizeof sim->nb.walls_ref);
}

/* A buffer of at least n entries of elem bytes in *buf (*cap entries):
 * made anew, contents dropped, when it is smaller (released after the
 * kernels queued before that use it: in-order queue). */
static void reserve_entries(cd_cl *cl, cl_mem *buf, size_t *cap, size_t n, size_t elem, const char *what)
{
    if (cl->status || (*buf && *cap >= n)) return;
    if (*buf) clReleaseMemObject(*buf);
    *cap = (size_t)cd_nb_room((cd_long)n);
    *buf = cd_cl_buffer(cl, *cap * elem, what);
}

/* The visiting order of the last build, copied to out (nb.visit_get). */
static size_t visit_get(const cd_sim *sim, cd_int *out)
{
    cd_cl *cl = sim->backend_data;
    size_t n = cl ? cl->n_visit : 0;
    if (!n || n != cl->n_pairs || cl->status) return 0;
    if (!out) return n;
    cl_int rc = clEnqueueReadBuffer(cl->queue, cl->pair_visit, CL_TRUE, 0, n * sizeof *out, out, 0, NULL, NULL);
    return cd_cl_check(cl, rc, "reading the visiting order") ? 0 : n;
}

/* Pass 11 (kernels/neighbor_items.h): the pair pass's visiting order,
 * rows grouped by kind, where the primitives are of both kinds (the host's
 * body-frame ends say so); else none, and the pair kernel takes the rows
 * in order (its visit argument null; set_list_args). */
static void visit_order(cd_cl *cl, cd_sim *sim, cd_int n_pairs)
{
    const cd_state *s = &sim->s;
    sim->nb.visit_get = visit_get;
    cl->n_visit = 0;
    if (n_pairs <= 0 || !cd_nb_prims_of_both_kinds(s->prim_a_body, s->prim_b_body, s->n_prims)) return;
    cd_int m = (cd_int)cd_nb_visit_chunks(n_pairs), entries = CD_ROW_KINDS * m;
    reserve_entries(cl, &cl->pair_visit, &cl->cap_visit, (size_t)n_pairs, sizeof(cd_int),
                    "allocating the visiting order");
    reserve_entries(cl, &cl->visit_starts, &cl->cap_visit_starts, (size_t)entries + 1, sizeof(cd_int),
                    "allocating the visiting order");
    /* the scan's levels (block_sum is sized for the cells' scan, which is
     * usually the longer) */
    reserve_entries(cl, &cl->block_sum, &cl->block_sum_cap, (size_t)cd_scan_scratch(entries), sizeof(cd_int),
                    "allocating the scan");
    cd_cl_arg(cl, CD_CLK_VISIT_COUNT, F, sizeof n_pairs, &n_pairs);
    cd_cl_arg(cl, CD_CLK_VISIT_COUNT, F + 1, sizeof cl->visit_starts, &cl->visit_starts);
    cd_cl_run(cl, CD_CLK_VISIT_COUNT, (size_t)m);
    cd_cl_scan(cl, cl->visit_starts, (size_t)entries, cl->visit_starts);
    cd_cl_arg(cl, CD_CLK_VISIT_FILL, F, sizeof n_pairs, &n_pairs);
    cd_cl_arg(cl, CD_CLK_VISIT_FILL, F + 1, sizeof cl->visit_starts, &cl->visit_starts);
    cd_cl_arg(cl, CD_CLK_VISIT_FILL, F + 2, sizeof cl->pair_visit, &cl->pair_visit);
    cd_cl_run(cl, CD_CLK_VISIT_FILL, (size_t)m);
    if (!cl->status) cl->n_visit = (size_t)n_pairs;
}

int cd_cl_neighbors_build(cd_cl *cl, cd_sim *sim)
{
    const cd_state *s = &sim->s;
    cd_int P = (cd_int)s->n_prims, N = (cd_int)s->n_particles;
    cd_real skin = sim->nb.skin; /* [m] */
    cd_int n_new = 0, overflow = 0;
    if (P > 0) {
        bin_particles(cl, N, skin);
        /* the skin flag (these ends become the references) and the overflow */
        cd_cl_fill_int(cl, cl->flags, 0, 0, 1);
        cd_cl_fill_int(cl, cl->flags, 0, 2, 1);
        scan_args(cl, CD_CLK_PAIR_COLLECT, N, skin);
        cd_cl_arg(cl, CD_CLK_PAIR_COLLECT, F + 6, sizeof cl->pair_count, &cl->pair_count);
        cd_cl_arg(cl, CD_CLK_PAIR_COLLECT, F + 7, sizeof cl->cand, &cl->cand);
        cd_cl_arg(cl, CD_CLK_PAIR_COLLECT, F + 8, sizeof cl->slot, &cl->slot);
        cd_cl_arg(cl, CD_CLK_PAIR_COLLECT, F + 9, sizeof cl->flags, &cl->flags);
        cd_cl_run(cl, CD_CLK_PAIR_COLLECT, (size_t)N);
        cd_cl_scan(cl, cl->pair_count, (size_t)P, cl->pair_offset);
        /* the one wait of a rebuild: how many pairs (to size the buffers),
         * and whether a slot overflowed */
        if (!cl->status)
            cd_cl_check(cl,
                        clEnqueueReadBuffer(cl->queue, cl->pair_offset, CL_FALSE, (size_t)P * sizeof(cd_int),
                                            sizeof n_new, &n_new, 0, NULL, NULL),
                        "reading the number of pairs");
        if (!cl->status)
            cd_cl_check(cl,
                        clEnqueueReadBuffer(cl->queue, cl->flags, CL_TRUE, 2 * sizeof(cd_int), sizeof overflow,
                                            &overflow, 0, NULL, NULL),
                        "reading the number of pairs");
    }
    if (cl->status) return -1;

    /* The new list goes into the spare history set; the old set stays for
     * the carry-over, then becomes the spare. */
    int old = cl->cur, nxt = 1 - cl->cur;
    cd_int n_old = (cd_int)cl->n_pairs;
    if (cd_cl_reserve_pairs(cl, (size_t)n_new, nxt)) return -1;
    cl->cur = nxt;
    if (cd_cl_bind_cols(cl)) return -1;
    if (n_new > 0) {
        cd_int slot = cl->slot;
        if (overflow) { /* rows written in place, then completed by the place pass */
            scan_args(cl, CD_CLK_PAIR_FILL, N, skin);
            cd_cl_arg(cl, CD_CLK_PAIR_FILL, F + 6, sizeof cl->pair_count, &cl->pair_count);
            cd_cl_arg(cl, CD_CLK_PAIR_FILL, F + 7, sizeof cl->pair_offset, &cl->pair_offset);
            cd_cl_run(cl, CD_CLK_PAIR_FILL, (size_t)N);
            slot = 0;
        }
        cd_cl_arg(cl, CD_CLK_PAIR_PLACE, F, sizeof P, &P);
        cd_cl_arg(cl, CD_CLK_PAIR_PLACE, F + 1, sizeof cl->pair_offset, &cl->pair_offset);
        cd_cl_arg(cl, CD_CLK_PAIR_PLACE, F + 2, sizeof cl->cand, &cl->cand);
        cd_cl_arg(cl, CD_CLK_PAIR_PLACE, F + 3, sizeof slot, &slot);
        cd_cl_arg(cl, CD_CLK_PAIR_PLACE, F + 4, sizeof cl->hist[nxt].keys, &cl->hist[nxt].keys);
        cd_cl_run(cl, CD_CLK_PAIR_PLACE, (size_t)P);
        if (overflow) grow_slots(cl, (size_t)P);
    }
    if (n_new > 0) {
        cd_cl_arg(cl, CD_CLK_PAIR_CARRY, F, sizeof n_new, &n_new);
        cd_cl_arg(cl, CD_CLK_PAIR_CARRY, F + 1, sizeof cl->hist[nxt].keys, &cl->hist[nxt].keys);
        cd_cl_arg(cl, CD_CLK_PAIR_CARRY, F + 2, sizeof cl->hist[old].keys, &cl->hist[old].keys);
        cd_cl_arg(cl, CD_CLK_PAIR_CARRY, F + 3, sizeof n_old, &n_old);
        cd_cl_arg(cl, CD_CLK_PAIR_CARRY, F + 4, sizeof cl->hist[old].active, &cl->hist[old].active);
        cd_cl_arg(cl, CD_CLK_PAIR_CARRY, F + 5, sizeof cl->hist[old].shear, &cl->hist[old].shear);
        cd_cl_run(cl, CD_CLK_PAIR_CARRY, (size_t)n_new);
    }
    gather_lists(cl, N, n_new);
    wall_lists(cl, sim, N);
    visit_order(cl, sim, n_new);

    /* Reference ends for the skin criterion (its flag was cleared above). */
    cd_cl_arg(cl, CD_CLK_PRIM_REFS, F, sizeof P, &P);
    cd_cl_run(cl, CD_CLK_PRIM_REFS, (size_t)P);
    if (cl->status) return -1;
    cl->n_pairs = (size_t)n_new;
    sim->nb.force_rebuild = 0;
    sim->nb.builds++;
    return 0;
}
