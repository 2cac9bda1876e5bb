/* Broad phase: the Verlet list of primitive pairs with a skin, built where
 * the step runs (host threads, or the offload device) by the passes of
 * kernels/neighbor_items.h -- the same items the OpenCL kernels call
 * (kernels/cl/neighbors.cl).  The list is rebuilt only when some primitive
 * end has moved more than half the skin since the last build (every point
 * of a segment moves at most as far as its farthest end, so no pair can
 * come into contact unseen), or a wall more than half the skin.  Contact
 * history is carried over by matching the sorted (primitive i, primitive j)
 * keys of the new list against the old one.  Between steps only two
 * integers come back to the host (the numbers of pair rows and of wall
 * candidates) and one overflow bound; the result is the same for every
 * thread count and device. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include "backend/omp/omp_loops.h"
#include "backend/omp/step_device.h"
#include "neighbor_items.h"
#include "step_items.h"

/* Candidate slots per primitive at the first build (a hexapod arm in a
 * dense packing with a skin of 0.1 d has about 10); they double whenever a
 * primitive overflows its slot. */
#define CD_NB_SLOT 32

void cd_neighbors_init(cd_neighbors *nb, double skin, int reorder)
{
    memset(nb, 0, sizeof(*nb));
    nb->skin = skin;
    nb->reorder = reorder;
    nb->force_rebuild = 1;
    nb->slot = CD_NB_SLOT;
    nb->walls_from_host = 1; /* no candidates yet: the host's wall rows hold the history */
}

void cd_neighbors_free(cd_neighbors *nb)
{
    cd_nb_lists *d = &nb->d;
    void *all[] = {d->wall_out,   d->gather_start, d->gather_rows, d->wall_start, d->wall_rows,  d->grid,
                   d->part_bound, d->partial,      d->part_cell,   d->cell_count, d->cell_start, d->cell_parts,
                   d->pair_count, d->pair_offset,  d->cand,        d->keys,       d->old_keys,   d->old_active,
                   d->old_shear,  d->count,        d->chunk_sum,   d->part_uid,   d->part_at,    d->prim_uid,
                   d->prim_at,    d->pair_at,      d->pair_ustart, d->part_src,   d->prim_src,   d->new_first,
                   d->sort_keys,  d->sort_vals,    d->hist,        d->move,       d->skin_flag,  d->ref_pose};
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++) cd_dev_free(all[k]);
    cd_dev_free(d->pair_visit);
    cd_dev_free(d->visit_starts);
    cd_dev_free(d->visit_scratch);
    free(nb->sweep_edge);
    memset(nb, 0, sizeof(*nb));
}

/* Allocates *p for n elements of elem bytes, contents discarded (0 or -1). */
static int realloc_dev(void **p, size_t n, size_t elem)
{
    cd_dev_free(*p);
    *p = cd_dev_alloc(n * elem);
    return *p ? 0 : -1;
}

/* The lists whose size is fixed by the particle, primitive and wall counts
 * (allocated at the first build), and room for rows pair rows. */
static int reserve(cd_neighbors *nb, const cd_state *s, size_t rows)
{
    cd_nb_lists *d = &nb->d;
    size_t N = s->n_particles, P = s->n_prims;
    if (!d->grid) {
        nb->cell_cap = 8 * N + 65; /* cd_grid_make: at most 8 N + 64 cells */
        /* the longest scan: the cells, the primitives or the radix sort's
         * histograms (src/backend/omp/reorder.c) */
        size_t longest = nb->cell_cap > P ? nb->cell_cap : P;
        if ((size_t)cd_reorder_hist_entries((cd_long)N) > longest)
            longest = (size_t)cd_reorder_hist_entries((cd_long)N);
        size_t chunks = (size_t)cd_scan_scratch((cd_long)longest);
        if (realloc_dev((void **)&d->grid, 1, sizeof(cd_grid)) ||
            realloc_dev((void **)&d->part_bound, N + 1, sizeof(cd_real)) ||
            realloc_dev((void **)&d->partial, 7 * (size_t)cd_nb_box_scratch((cd_long)N), sizeof(cd_real)) ||
            realloc_dev((void **)&d->part_cell, N + 1, sizeof(cd_int)) ||
            realloc_dev((void **)&d->cell_count, nb->cell_cap + 1, sizeof(cd_int)) ||
            realloc_dev((void **)&d->cell_start, nb->cell_cap + 1, sizeof(cd_int)) ||
            realloc_dev((void **)&d->cell_parts, N + 1, sizeof(cd_int)) ||
            realloc_dev((void **)&d->pair_count, P + 1, sizeof(cd_int)) ||
            realloc_dev((void **)&d->pair_offset, P + 1, sizeof(cd_int)) ||
            realloc_dev((void **)&d->cand, P * (size_t)nb->slot + 1, sizeof(cd_prim_id)) ||
            realloc_dev((void **)&d->count, N + 1, sizeof(cd_int)) ||
            realloc_dev((void **)&d->chunk_sum, chunks, sizeof(cd_int)) ||
            realloc_dev((void **)&d->gather_start, N + 1, sizeof(cd_int)) ||
            realloc_dev((void **)&d->wall_start, N + 1, sizeof(cd_int)))
            return -1;
        /* the poses the skin test bounds the ends' motion from (step_items.h) */
        if (CD_ENDS_FROM_POSE && realloc_dev((void **)&d->ref_pose, CD_REF_POSE * (N + 1), sizeof(cd_real))) return -1;
    }
    if (rows > nb->cap_rows || !d->keys) {
        size_t cap = (size_t)cd_nb_room((cd_long)rows);
        if (realloc_dev((void **)&d->keys, cap, sizeof(cd_ulong)) ||
            realloc_dev((void **)&d->gather_rows, 2 * cap, sizeof(cd_pair_id)))
            return -1;
        nb->cap_rows = cap;
    }
    return 0;
}

/* out[0] = 0, out[k+1] = out[k] + in[k] for k < n: the tree of chunks of
 * kernels/neighbor_items.h, 2 L + 1 loops for L levels above the input
 * (one loop up to 64 entries, three up to 4,096, five up to 262,144);
 * copy (or NULL): out[0 .. n] also into copy, in the loop that writes
 * them (the cursor of a counting fill; it may be in). */
static void scan_copy(const cd_int *in, cd_int n, cd_int *out, cd_int *scratch, cd_int *copy)
{
    cd_int *level[8]; /* levels above 0 in scratch: 64^7 > 2^31 entries */
    cd_long len[8];
    int L = 0;
    len[0] = n;
    cd_int *at = scratch;
    CD_WIDE_MIN
    while (len[L] > CD_SCAN_CHUNK) {
        const cd_int *src = L ? level[L] : in;
        cd_long n_src = len[L], m = (n_src + CD_SCAN_CHUNK - 1) / CD_SCAN_CHUNK;
        cd_int *sums = at;
        CD_STEP_FOR(m, CD_DEV(is_device_ptr(src, sums)))
        for (cd_long g = 0; g < m; g++) cd_scan_item_sum(src, n_src, g, sums);
        at += m + 1;
        L++;
        level[L] = sums;
        len[L] = m;
    }
    cd_int *top = L ? level[L] : out, *top_copy = L ? NULL : copy;
    const cd_int *top_in = L ? level[L] : in;
    cd_long n_top = len[L];
    CD_STEP_FOR(1, CD_DEV(is_device_ptr(top_in, top, top_copy)))
    for (int one = 0; one < 1; one++) {
        cd_scan_item_top(top_in, n_top, top);
        if (top_copy) cd_scan_item_copy(top, n_top, 0, top_copy);
    }
    for (int l = L - 1; l >= 0; l--) {
        const cd_int *src = l ? level[l] : in, *starts = level[l + 1];
        cd_int *dst = l ? level[l] : out, *dst_copy = l ? NULL : copy;
        cd_long n_src = len[l], m = len[l + 1];
        CD_STEP_FOR(m, CD_DEV(is_device_ptr(src, starts, dst, dst_copy)))
        for (cd_long g = 0; g < m; g++) {
            cd_scan_item_fill(src, n_src, g, starts, dst);
            if (dst_copy) cd_scan_item_copy(dst, n_src, g, dst_copy);
        }
    }
}

void cd_nb_scan(const cd_int *in, cd_int n, cd_int *out, cd_int *scratch) { scan_copy(in, n, out, scratch, NULL); }

static void zero_ints(cd_int *dst, size_t n)
{
    CD_WIDE_MIN
    CD_STEP_FOR(n, CD_DEV(is_device_ptr(dst)))
    for (size_t k = 0; k < n; k++) dst[k] = 0;
}

/* Passes 1-2: bounds, the tree of boxes, and grid (2 + L loops for L
 * levels of boxes: 3 up to 4,096 particles, 4 up to 262,144), which comes
 * back into *grid_out (56 bytes; the reorder reads it too).  Returns 1 when the
 * grid says the run blew up (cd_nb_item_grid), -1 when it could not be
 * read, 0 otherwise. */
static int make_grid(cd_sim *sim, cd_grid *grid_out)
{
    cd_long N = (cd_long)sim->s.n_particles, n = (N + CD_BOX_CHUNK - 1) / CD_BOX_CHUNK;
    cd_real skin = sim->nb.skin, *boxes = sim->nb.d.partial; /* [m] */
    CD_WIDE_MIN
    CD_BUILD_ARGS(sim)
    /* (with CD_ENDS_FROM_POSE the world ends, which the steps do not
     * store, first: the build bins and pairs them) */
    CD_STEP_FOR(N, CD_BUILD_IN)
    for (cd_long p = 0; p < N; p++) {
        if (CD_ENDS_FROM_POSE) cd_item_particle_ends(CD_B.c, p);
        cd_nb_item_bound(CD_B.c, p, CD_B.d.part_bound);
    }
    CD_STEP_FOR(n, CD_BUILD_IN)
    for (cd_long q = 0; q < n; q++) cd_nb_item_box(CD_B.c, q, N, CD_B.d.part_bound, CD_B.d.partial);
    while (n > CD_BOX_CHUNK) {
        cd_long m = (n + CD_BOX_CHUNK - 1) / CD_BOX_CHUNK, n_in = n;
        cd_real *up = boxes + 7 * n;
        CD_STEP_FOR(m, CD_DEV(is_device_ptr(boxes, up)))
        for (cd_long q = 0; q < m; q++) cd_nb_item_box_up(boxes, n_in, q, up);
        boxes = up;
        n = m;
    }
    cd_int n_top = (cd_int)n;
    cd_grid *grid = sim->nb.d.grid;
    CD_STEP_FOR(1, CD_DEV(is_device_ptr(boxes, grid)))
    for (int one = 0; one < 1; one++) cd_nb_item_grid(boxes, n_top, skin, (cd_int)N, grid);
    if (cd_dev_get(grid_out, grid, sizeof *grid_out)) return -1;
    return grid_out->dim[0] < 0;
}

/* Passes 3-4: particles binned by cell (CSR); the scan's last loop turns
 * the counts into the fill's cursor. */
static void bin_particles(cd_sim *sim)
{
    cd_int N = (cd_int)sim->s.n_particles, cell_cap = (cd_int)sim->nb.cell_cap;
    cd_nb_lists *dl = &sim->nb.d;
    CD_WIDE_MIN
    CD_BUILD_ARGS(sim)
    zero_ints(dl->cell_count, (size_t)cell_cap);
    CD_STEP_FOR(N, CD_BUILD_IN)
    for (cd_int q = 0; q < N; q++)
        cd_nb_item_bin(CD_B.c, q, CD_B.d.grid, cell_cap, CD_B.d.part_cell, CD_B.d.cell_count);
    scan_copy(dl->cell_count, cell_cap, dl->cell_start, dl->chunk_sum, dl->cell_count);
    CD_STEP_FOR(N, CD_BUILD_IN)
    for (cd_int q = 0; q < N; q++) cd_nb_item_cell_fill(q, CD_B.d.part_cell, CD_B.d.cell_count, CD_B.d.cell_parts);
}

/* Pass 5's loop on an offload device: one item per primitive, unless
 * CAPDEM_COLLECT_PER_PARTICLE=1 asks for the per-particle item of host
 * threads (both make the same rows; the switch lets a GPU run time the
 * two shapes against each other: bench/gpu/kernel_profile.sh). */
static int collect_per_primitive(void)
{
    static int per_prim = -1;
    if (per_prim < 0) {
        const char *v = getenv("CAPDEM_COLLECT_PER_PARTICLE");
        per_prim = CD_OFFLOAD && !(v && strcmp(v, "1") == 0);
    }
    return per_prim;
}

/* Pass 5 in slot mode (slot > 0; returns the longest row, which may exceed
 * the slot) or in fill mode (slot = 0: rows written in place into
 * pair_prim_j at pair_offset).  Host threads: one item per particle (its
 * arms share one scan of the cells); offload: one item per primitive,
 * whose row alone the thread makes (docs/performance.md, "The omp offload
 * kernels on sm_90, read from the compiler"): the same rows. */
static cd_int collect(cd_sim *sim, cd_int slot)
{
    cd_int N = (cd_int)sim->s.n_particles, P = (cd_int)sim->s.n_prims, longest = 0;
    cd_real skin = sim->nb.skin; /* [m] */
    CD_WIDE_MIN
    CD_BUILD_ARGS(sim)
    if (collect_per_primitive()) {
        CD_STEP_FOR(P, CD_BUILD_IN reduction(max : longest) CD_DEV(map(tofrom : longest)))
        for (cd_int i = 0; i < P; i++) {
            /* slot mode: the slots, no offsets; fill mode: the rows in place */
            cd_nb_item_collect(CD_B.c, CD_B.c.prim_particle[i], i, i + 1, CD_B.d.grid, CD_B.d.cell_start,
                               CD_B.d.cell_parts, CD_B.d.part_bound, skin, slot > 0 ? CD_B.d.cand : CD_B.c.pair_prim_j,
                               slot, slot > 0 ? NULL : CD_B.d.pair_offset, CD_B.d.pair_count, CD_B.order);
            if (CD_B.d.pair_count[i] > longest) longest = CD_B.d.pair_count[i];
        }
        return longest;
    }
    CD_STEP_FOR(N, CD_BUILD_IN reduction(max : longest) CD_DEV(map(tofrom : longest)))
    for (cd_int p = 0; p < N; p++) {
        cd_nb_item_collect(CD_B.c, p, CD_B.c.prim_first[p], CD_B.c.prim_first[p] + CD_B.c.prim_count[p], CD_B.d.grid,
                           CD_B.d.cell_start, CD_B.d.cell_parts, CD_B.d.part_bound, skin,
                           slot > 0 ? CD_B.d.cand : CD_B.c.pair_prim_j, slot, slot > 0 ? NULL : CD_B.d.pair_offset,
                           CD_B.d.pair_count, CD_B.order);
        for (cd_int i = CD_B.c.prim_first[p]; i < CD_B.c.prim_first[p] + CD_B.c.prim_count[p]; i++)
            if (CD_B.d.pair_count[i] > longest) longest = CD_B.d.pair_count[i];
    }
    return longest;
}

/* The old rows' keys and history, before the rows are replaced (pass 8
 * reads them). */
static int keep_history(cd_sim *sim)
{
    cd_neighbors *nb = &sim->nb;
    size_t n_old = sim->s.n_pairs;
    if (n_old > nb->cap_old || !nb->d.old_keys) {
        size_t cap = (size_t)cd_nb_room((cd_long)n_old);
        if (realloc_dev((void **)&nb->d.old_keys, cap, sizeof(cd_ulong)) ||
            realloc_dev((void **)&nb->d.old_active, cap, sizeof(cd_flag)) ||
            realloc_dev((void **)&nb->d.old_shear, cap, sizeof(cd_vec3)))
            return -1;
        nb->cap_old = cap;
    }
    CD_WIDE_MIN
    CD_BUILD_ARGS(sim)
    CD_STEP_FOR(n_old, CD_BUILD_IN)
    for (size_t k = 0; k < n_old; k++)
        cd_nb_item_keep(CD_B.c, (cd_long)k, CD_B.order, CD_B.d.old_keys, CD_B.d.old_active, CD_B.d.old_shear);
    return 0;
}

/* Room for n wall candidates (their rows and outputs), with a 64th to
 * spare (cd_nb_room): sized by the candidates, not by primitives x walls. */
static int reserve_wall_rows(cd_neighbors *nb, size_t n)
{
    if (n <= nb->cap_wall_rows && nb->d.wall_rows) return 0;
    size_t cap = (size_t)cd_nb_room((cd_long)n);
    if (realloc_dev((void **)&nb->d.wall_rows, cap, sizeof(cd_int)) ||
        realloc_dev((void **)&nb->d.wall_out, cap, sizeof(cd_wall_entry)))
        return -1;
    nb->cap_wall_rows = cap;
    return 0;
}

int cd_neighbors_wall_out_to_host(cd_sim *sim)
{
    cd_neighbors *nb = &sim->nb;
    size_t n = nb->n_wall_rows;
    if (!nb->wall_out_pending || !sim->s.n_walls) return 0;
    cd_int *rows = malloc((n + 1) * sizeof *rows);
    cd_wall_entry *out = malloc((n + 1) * sizeof *out);
    int rc = rows && out ? 0 : -1;
    if (!rc && n)
        rc = cd_dev_get(rows, nb->d.wall_rows, n * sizeof *rows) || cd_dev_get(out, nb->d.wall_out, n * sizeof *out);
    if (!rc) {
        cd_state_expand_wall_entries(&sim->s, rows, out, n);
        nb->wall_out_pending = 0;
    }
    free(rows);
    free(out);
    return rc ? -1 : 0;
}

/* Before the candidates are replaced: after a start the host's rows in
 * contact become the candidates of a build before (cd_state_wall_entries),
 * in the slots the step columns have before this build's reorder, whose
 * history the build carries over (particle_lists). */
static int keep_wall_history(cd_sim *sim)
{
    cd_neighbors *nb = &sim->nb;
    if (!nb->walls_from_host) return 0;
    size_t n = cd_state_wall_entries(&sim->s, NULL, NULL);
    cd_int *rows = malloc((n + 1) * sizeof *rows);
    cd_wall_entry *ent = malloc((n + 1) * sizeof *ent);
    int rc = rows && ent ? reserve_wall_rows(nb, n) : -1;
    if (!rc) {
        cd_state_wall_entries(&sim->s, rows, ent);
        rc = n ? cd_dev_put(nb->d.wall_rows, rows, n * sizeof *rows) || cd_dev_put(nb->d.wall_out, ent, n * sizeof *ent)
               : 0;
    }
    free(rows);
    free(ent);
    if (rc) return -1;
    nb->n_wall_rows = n;
    nb->walls_from_host = 0;
    return 0;
}

/* Passes 9 (gather lists: their counts came with the carry-over) and 10
 * (wall candidates; their number comes back, to size their lists; their
 * history carried over from the old ones, whose primitives had the slots
 * prim_src names: null, the same).  The gather lists are sorted and the
 * wall candidates counted in one launch (both per particle). */
static int particle_lists(cd_sim *sim, const cd_int *prim_src)
{
    cd_state *s = &sim->s;
    cd_int N = (cd_int)s->n_particles, W = (cd_int)s->n_walls;
    size_t n_pairs = s->n_pairs;
    cd_real skin = sim->nb.skin; /* [m] */
    cd_nb_lists *dl = &sim->nb.d;
    CD_WIDE_MIN
    {
        CD_BUILD_ARGS(sim)
        scan_copy(dl->count, N, dl->gather_start, dl->chunk_sum, dl->count);
        CD_STEP_FOR(n_pairs, CD_BUILD_IN)
        for (size_t k = 0; k < n_pairs; k++)
            cd_nb_item_gather_fill(CD_B.c, (cd_long)k, CD_B.d.count, CD_B.d.gather_rows);
        CD_STEP_FOR(N, CD_BUILD_IN)
        for (cd_int q = 0; q < N; q++) {
            cd_nb_item_gather_sort(CD_B.c, CD_B.order, q, CD_B.d.gather_start, CD_B.d.gather_rows);
            CD_B.d.count[q] = cd_item_wall_candidates(CD_B.c, q, CD_B.walls, W, skin, 0);
        }
    }
    cd_nb_scan(dl->count, N, dl->wall_start, dl->chunk_sum);
    cd_int n_rows = 0;
    if (cd_dev_get(&n_rows, dl->wall_start + N, sizeof n_rows)) return -1;
    /* The candidates of the build before: only the carry-over below reads
     * them, then they are freed, so that the steps hold one set of
     * candidates, sized by this build's (the lists' addresses change once
     * a build, as when two sets swapped places). */
    cd_int *old_rows = dl->wall_rows;
    cd_wall_entry *old_out = dl->wall_out;
    cd_long n_old = (cd_long)sim->nb.n_wall_rows;
    dl->wall_rows = NULL;
    dl->wall_out = NULL;
    sim->nb.cap_wall_rows = 0;
    int rc = reserve_wall_rows(&sim->nb, (size_t)n_rows);
    if (!rc) {
        CD_BUILD_ARGS(sim) /* the candidate lists have moved */
        CD_STEP_FOR(N, CD_BUILD_IN)
        for (cd_int q = 0; q < N; q++)
            cd_item_wall_candidates(CD_B.c, q, CD_B.walls, W, skin, CD_B.d.wall_rows + CD_B.d.wall_start[q]);
        CD_STEP_FOR(n_rows, CD_BUILD_IN CD_DEV(is_device_ptr(prim_src, old_rows, old_out)))
        for (cd_int e = 0; e < n_rows; e++)
            cd_item_wall_carry(e, CD_B.d.wall_rows, CD_B.d.wall_out, old_rows, n_old, old_out, prim_src, W);
    }
    cd_dev_free(old_rows);
    cd_dev_free(old_out);
    if (rc) return -1;
    sim->nb.n_wall_rows = (size_t)n_rows;
    memcpy(sim->nb.walls_ref, s->walls, sizeof sim->nb.walls_ref);
    return 0;
}

/* Pass 11 (kernels/neighbor_items.h): the pair pass's visiting order,
 * rows grouped by kind, where the primitives are of both kinds; else none
 * (d.pair_visit null: the pair pass's direct loop, and no bytes held). */
static int visit_order(cd_sim *sim)
{
    cd_state *s = &sim->s;
    cd_neighbors *nb = &sim->nb;
    cd_nb_lists *dl = &nb->d;
    size_t n = s->n_pairs;
    nb->n_visit = 0;
    if (!n || !cd_nb_prims_of_both_kinds(s->prim_a_body, s->prim_b_body, s->n_prims)) {
        cd_dev_free(dl->pair_visit);
        cd_dev_free(dl->visit_starts);
        cd_dev_free(dl->visit_scratch);
        dl->pair_visit = dl->visit_starts = dl->visit_scratch = NULL;
        nb->cap_visit = nb->cap_visit_starts = 0;
        return 0;
    }
    cd_long m = cd_nb_visit_chunks((cd_long)n), entries = CD_ROW_KINDS * m;
    if (n > nb->cap_visit || !dl->pair_visit) {
        size_t cap = (size_t)cd_nb_room((cd_long)n);
        if (realloc_dev((void **)&dl->pair_visit, cap, sizeof(cd_int))) return -1;
        nb->cap_visit = cap;
    }
    if ((size_t)entries + 1 > nb->cap_visit_starts || !dl->visit_starts) {
        size_t cap = (size_t)cd_nb_room(entries + 1);
        if (realloc_dev((void **)&dl->visit_starts, cap, sizeof(cd_int)) ||
            realloc_dev((void **)&dl->visit_scratch, (size_t)cd_scan_scratch((cd_long)cap), sizeof(cd_int)))
            return -1;
        nb->cap_visit_starts = cap;
    }
    cd_long rows = (cd_long)n;
    CD_WIDE_MIN
    {
        CD_BUILD_ARGS(sim)
        CD_STEP_FOR(m, CD_BUILD_IN)
        for (cd_long g = 0; g < m; g++) cd_nb_item_visit_count(CD_B.c, g, rows, CD_B.d.visit_starts);
    }
    cd_nb_scan(dl->visit_starts, (cd_int)entries, dl->visit_starts, dl->visit_scratch);
    {
        CD_BUILD_ARGS(sim)
        CD_STEP_FOR(m, CD_BUILD_IN)
        for (cd_long g = 0; g < m; g++) cd_nb_item_visit_fill(CD_B.c, g, rows, CD_B.d.visit_starts, CD_B.d.pair_visit);
    }
    nb->n_visit = n;
    return 0;
}

size_t cd_neighbors_pair_visit(const cd_sim *sim, cd_int *out)
{
    if (sim->nb.visit_get) return sim->nb.visit_get(sim, out);
    size_t n = sim->nb.n_visit;
    if (!n || n != sim->s.n_pairs) return 0;
    if (!out) return n;
    if (cd_dev_get(out, sim->nb.d.pair_visit, n * sizeof *out)) return 0;
    if (!sim->nb.ordered) return n;
    /* memory rows -> the host's rows after a sync (user order: pair_at
     * names the memory row of each) */
    cd_int *at = malloc(n * sizeof *at), *user = malloc(n * sizeof *user);
    int rc = at && user ? cd_dev_get(at, sim->nb.d.pair_at, n * sizeof *at) : -1;
    if (!rc) {
        for (size_t u = 0; u < n; u++) user[at[u]] = (cd_int)u;
        for (size_t v = 0; v < n; v++) out[v] = user[out[v]];
    }
    free(at);
    free(user);
    return rc ? 0 : n;
}

/* The candidate pairs (i, j), i < j, of primitives of different particles
 * whose axes come within r_i + r_j + skin, sorted by i then j, with their
 * history carried over; the gather and wall lists; the primitive ends
 * become the skin test's reference. */
int cd_neighbors_build(cd_sim *sim)
{
    cd_state *s = &sim->s;
    cd_neighbors *nb = &sim->nb;
    cd_int P = (cd_int)s->n_prims, N = (cd_int)s->n_particles;
    /* a build between calls: the force and torque the rows hold to the host
     * first (step_omp.c); host threads after a sync: the columns back in
     * the lists' order */
    cd_sim_force_before_build(sim);
    if (cd_reorder_to_memory(sim) || reserve(nb, s, s->n_pairs)) return -1;
    /* the old rows' history aside, keyed in the order they were made in */
    if (keep_history(sim) || keep_wall_history(sim)) return -1;
    cd_grid grid;
    int bad = make_grid(sim, &grid);
    if (bad) return bad > 0 ? CD_NB_BLOWUP : -1;
    int moved = 0;
    if (cd_reorder_build(sim, &grid, &moved)) return -1;
    bin_particles(sim);
    cd_int longest = collect(sim, nb->slot);
    cd_nb_scan(nb->d.pair_count, P, nb->d.pair_offset, nb->d.chunk_sum);
    cd_int n_new = 0;
    if (cd_dev_get(&n_new, nb->d.pair_offset + P, sizeof n_new)) return -1;
    /* Gather entries are 2 k + 1 in a cd_int (cd_item_gather); a negative
     * total is a count that overflowed cd_int. */
    if (n_new < 0 || (size_t)n_new > (size_t)(INT32_MAX - 1) / 2) {
        fprintf(stderr, "capdem: the pair rows exceed the neighbour list's limit of %d\n", (INT32_MAX - 1) / 2);
        return -1;
    }

    /* Replace the rows: room for the new rows. */
    size_t n_old = s->n_pairs;
    size_t room = (size_t)n_new <= s->cap_pairs ? s->cap_pairs : (size_t)cd_nb_room(n_new);
    if (cd_sim_reserve_step_pairs(sim, room) || reserve(nb, s, (size_t)n_new)) return -1;
    s->n_pairs = (size_t)n_new;
    cd_int slot = nb->slot;
    if (longest > nb->slot) { /* some row is incomplete in its slot: write the rows in place */
        collect(sim, 0);
        slot = 0;
        while (nb->slot < longest) nb->slot *= 2;
        if (realloc_dev((void **)&nb->d.cand, (size_t)P * (size_t)nb->slot + 1, sizeof(cd_prim_id))) return -1;
    }
    const cd_int *prim_src = moved ? nb->d.prim_src : NULL; /* the slots the old rows' keys name */
    cd_int most = P > N ? P : N;
    CD_WIDE_MIN
    {
        CD_BUILD_ARGS(sim)
        /* Pass 7, with in the same launch: the primitive ends become the
         * skin test's reference (nothing later in the build moves them;
         * with CD_ENDS_FROM_POSE the particles' poses too), the particles'
         * gather counts are cleared for the next launch, and the skin flag
         * (offload: set by the step that asked for this build) is cleared;
         * three launches and a copy before. */
        CD_STEP_FOR(most, CD_BUILD_IN)
        for (cd_int i = 0; i < most; i++) {
            if (i < P) {
                cd_nb_item_place(CD_B.c, i, CD_B.d.pair_offset, CD_B.d.cand, slot, CD_B.d.keys, CD_B.order);
                cd_item_prim_refs(CD_B.c, i);
            }
            if (i < N) CD_B.d.count[i] = 0;
            if (i < N && CD_B.d.ref_pose) cd_item_ref_pose(CD_B.c, i, CD_B.d.ref_pose);
            if (i == 0 && CD_B.d.skin_flag) CD_B.d.skin_flag[0] = 0;
        }
        /* Passes 8 and 9a: each new row's history, and its count in its
         * two particles' gather lists. */
        CD_STEP_FOR(n_new, CD_BUILD_IN CD_DEV(is_device_ptr(prim_src)))
        for (cd_int k = 0; k < n_new; k++) {
            cd_nb_item_carry(CD_B.c, k, CD_B.d.keys, CD_B.d.old_keys, (cd_long)n_old, CD_B.d.old_active,
                             CD_B.d.old_shear, prim_src);
            cd_nb_item_gather_count(CD_B.c, k, CD_B.d.count);
        }
    }
    if (particle_lists(sim, prim_src) || cd_reorder_pair_rows(sim) || visit_order(sim)) return -1;
    nb->force_rebuild = 0;
    nb->builds++;
    if (cd_omp_sweep_lists(sim)) return -1;
    return 0;
}

int cd_neighbors_part_bounds(const cd_sim *sim, double *out)
{
    size_t N = sim->s.n_particles;
    if (!sim->nb.d.part_bound || cd_dev_get(out, sim->nb.d.part_bound, N * sizeof(double))) return -1;
    if (!sim->nb.ordered) return 0;
    /* the build's rows are in memory order: out in user order */
    double *mem = malloc((N + 1) * sizeof(double));
    cd_int *at = malloc((N + 1) * sizeof(cd_int));
    int rc = mem && at ? cd_dev_get(at, sim->nb.d.part_at, N * sizeof(cd_int)) : -1;
    if (!rc) {
        memcpy(mem, out, N * sizeof(double));
        for (size_t u = 0; u < N; u++) out[u] = mem[at[u]];
    }
    free(mem);
    free(at);
    return rc;
}
