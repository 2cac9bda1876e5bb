/* Memory order (docs/architecture.md, "Memory order"; items in
 * kernels/reorder_items.h).  With neighbor.reorder: cells the omp backend
 * puts, at a neighbour-list rebuild, the particles in the order of the
 * grid cells of their centres, their primitives and wall rows with
 * them, so that the pair loop, the gather and the wall loop read particles
 * that are close in memory (the caches see a neighbourhood, not a random
 * sample of the state).  The maps between memory slots and user ids live
 * where the steps run, beside the neighbour lists.
 *
 * Nobody outside the backend sees the memory order: a sync puts the host
 * columns in user order (cd_reorder_to_user: rows copied back from an
 * offload device, or, on host threads, the columns themselves, which go
 * back to memory order before the next step, cd_reorder_to_memory), and
 * the sums of the step follow user ids (kernels/reorder_items.h), so the
 * trajectory has the same bits with either setting. */
#include <stdlib.h>
#include <string.h>
#include "backend/omp/omp_loops.h"
#include "backend/omp/step_device.h"
#include "reorder_items.h"

/* A rebuild reorders when more than 1/CD_REORDER_DRIFT of the particle
 * slots hold a key below their predecessor's. */
#define CD_REORDER_DRIFT 16

static int alloc_ints(cd_int **p, size_t n)
{
    cd_dev_free(*p);
    *p = cd_dev_alloc((n + 1) * sizeof(cd_int));
    return *p ? 0 : -1;
}

cd_order cd_sim_step_order(const cd_sim *sim)
{
    const cd_neighbors *nb = &sim->nb;
    if (!nb->ordered || nb->host_user) return cd_order_identity();
    cd_order o;
    o.part_uid = nb->d.part_uid;
    o.prim_uid = nb->d.prim_uid;
    o.part_at = nb->d.part_at;
    o.prim_at = nb->d.prim_at;
    o.pair_at = nb->d.pair_at;
    return o;
}

/* The host columns are in user order after every sync of an offload
 * device; where the steps run on them (cd_step_memory_is_host), they are
 * in the steps' order. */
cd_order cd_sim_host_order(const cd_sim *sim)
{
    return cd_step_memory_is_host() ? cd_sim_step_order(sim) : cd_order_identity();
}

void cd_reorder_forget(cd_sim *sim)
{
    cd_nb_lists *d = &sim->nb.d;
    cd_int **ints[] = {&d->part_uid, &d->part_at,  &d->prim_uid,  &d->prim_at,   &d->pair_at, &d->pair_ustart,
                       &d->part_src, &d->prim_src, &d->new_first, &d->sort_vals, &d->hist};
    for (size_t k = 0; k < sizeof ints / sizeof ints[0]; k++) {
        cd_dev_free(*ints[k]);
        *ints[k] = NULL;
    }
    cd_dev_free(d->sort_keys);
    cd_dev_free(d->move);
    d->sort_keys = NULL;
    d->move = NULL;
    sim->nb.ordered = 0;
    sim->nb.host_user = 0;
    sim->nb.pair_at_cap = 0;
}

/* Bytes of the largest column the reorder moves through its scratch
 * (particles, primitives, and the wall rows one wall at a time). */
static size_t largest_column(const cd_state *s)
{
    size_t most = 0;
    for (size_t f = 0; f < cd_n_fields; f++) {
        enum cd_field_group g = cd_fields[f].group;
        size_t rows = g == CD_GROUP_PARTICLE                      ? s->n_particles
                      : g == CD_GROUP_PRIM || g == CD_GROUP_WALLC ? s->n_prims
                                                                  : 0;
        if (rows * cd_fields[f].elem_size > most) most = rows * cd_fields[f].elem_size;
    }
    if (s->n_arms * sizeof(cd_arm) > most) most = s->n_arms * sizeof(cd_arm);
    return most;
}

/* move_host's move of a column whose rows are not whole cd_ints (a cd_flag,
 * kernels/defs.h): rows of e bytes through the scratch tmp, as
 * cd_reorder_item_move moves words. */
static void move_bytes(void *tmp, void *col, size_t rows, size_t e, const cd_int *map, int scatter)
{
    unsigned char *dst = tmp;
    const unsigned char *src = col;
    for (size_t g = 0; g < rows; g++)
        memcpy(dst + (scatter ? (size_t)map[g] : g) * e, src + (scatter ? g : (size_t)map[g]) * e, e);
    memcpy(col, tmp, rows * e);
}

/* The maps at the first build: identity, and the sort's scratch. */
static int begin(cd_sim *sim)
{
    cd_nb_lists *d = &sim->nb.d;
    size_t N = sim->s.n_particles, P = sim->s.n_prims, hist = (size_t)cd_reorder_hist_entries((cd_long)N);
    if (alloc_ints(&d->part_uid, N) || alloc_ints(&d->part_at, N) || alloc_ints(&d->prim_uid, P) ||
        alloc_ints(&d->prim_at, P) || alloc_ints(&d->pair_ustart, P + 1) || alloc_ints(&d->part_src, N) ||
        alloc_ints(&d->prim_src, P) || alloc_ints(&d->new_first, N + 1) || alloc_ints(&d->sort_vals, 2 * N) ||
        alloc_ints(&d->hist, 2 * hist + 1))
        return -1;
    d->sort_keys = cd_dev_alloc((2 * N + 1) * sizeof(cd_ulong));
    d->move = cd_dev_alloc(largest_column(&sim->s) + 8);
    if (!d->sort_keys || !d->move) return -1;
    cd_int *pu = d->part_uid, *pa = d->part_at, *iu = d->prim_uid, *ia = d->prim_at;
    CD_WIDE_MIN
    CD_STEP_FOR(N, CD_DEV(is_device_ptr(pu, pa)))
    for (size_t q = 0; q < N; q++) pu[q] = pa[q] = (cd_int)q;
    CD_STEP_FOR(P, CD_DEV(is_device_ptr(iu, ia)))
    for (size_t i = 0; i < P; i++) iu[i] = ia[i] = (cd_int)i;
    sim->nb.ordered = 1;
    return 0;
}

/* Moves groups of n 4-byte words, one every `stride` words from col
 * (where the steps run), by map (gather), through the scratch d->move. */
static void move_rows(cd_sim *sim, cd_int *col, size_t groups, size_t n, size_t stride, const cd_int *map)
{
    cd_int *tmp = sim->nb.d.move;
    cd_long nw = (cd_long)n, sw = (cd_long)stride;
    CD_WIDE_MIN
    CD_STEP_FOR(groups, CD_DEV(is_device_ptr(tmp, col, map)))
    for (size_t g = 0; g < groups; g++) cd_reorder_item_move(tmp, nw, col, sw, map, (cd_long)g, nw, 0);
    CD_STEP_FOR(groups, CD_DEV(is_device_ptr(tmp, col)))
    for (size_t g = 0; g < groups; g++)
        for (cd_long w = 0; w < nw; w++) col[(cd_long)g * sw + w] = tmp[(cd_long)g * nw + w];
}

/* The cell keys of the particles in d.sort_keys (values: their slots in
 * d.sort_vals), and how many slots hold a key below their predecessor's. */
static long particle_keys(cd_sim *sim)
{
    cd_int N = (cd_int)sim->s.n_particles;
    cd_ulong *keys = sim->nb.d.sort_keys;
    long descents = 0;
    CD_WIDE_MIN
    CD_BUILD_ARGS(sim)
    CD_STEP_FOR(N, CD_BUILD_IN)
    for (cd_int q = 0; q < N; q++) cd_reorder_item_key(CD_B.c, q, CD_B.d.grid, CD_B.d.sort_keys, CD_B.d.sort_vals);
    CD_STEP_FOR(N, reduction(+ : descents) CD_DEV(is_device_ptr(keys) map(tofrom : descents)))
    for (cd_int m = 1; m < N; m++) descents += cd_reorder_item_descent(keys, m);
    return descents;
}

/* Sorts the keys of particle_keys (radix, stable); returns the
 * sorted values (old memory slots in their new order). */
static cd_int *sort_particles(cd_sim *sim, const cd_grid *g)
{
    cd_nb_lists d = sim->nb.d;
    cd_int N = (cd_int)sim->s.n_particles, n_chunks = (N + CD_SORT_CHUNK - 1) / CD_SORT_CHUNK;
    cd_int entries = (cd_int)cd_reorder_hist_entries(N);
    cd_long cells = g->dim[0] * g->dim[1] * g->dim[2];
    int bits = 0;
    while (bits < 62 && ((cd_long)1 << bits) < cells) bits++;
    cd_ulong *kin = d.sort_keys, *kout = d.sort_keys + N;
    cd_int *vin = d.sort_vals, *vout = d.sort_vals + N, *hist = d.hist, *first = d.hist + entries;
    CD_WIDE_MIN
    for (int shift = 0; shift < bits; shift += CD_RADIX_BITS) {
        CD_STEP_FOR(n_chunks, CD_DEV(is_device_ptr(kin, hist)))
        for (cd_int b = 0; b < n_chunks; b++) cd_reorder_item_hist(kin, N, n_chunks, b, shift, hist);
        cd_nb_scan(hist, entries, first, d.chunk_sum);
        CD_STEP_FOR(n_chunks, CD_DEV(is_device_ptr(kin, vin, kout, vout, first)))
        for (cd_int b = 0; b < n_chunks; b++)
            cd_reorder_item_scatter(kin, vin, N, n_chunks, b, shift, first, kout, vout);
        cd_ulong *kt = kin;
        kin = kout;
        kout = kt;
        cd_int *vt = vin;
        vin = vout;
        vout = vt;
    }
    return vin;
}

/* Is field f moved with its rows?  The reference ends are not: the build
 * sets them at its end. */
static int moves(const cd_field_info *f)
{
    /* not the host-only columns: a device does not hold them, and on host
     * threads sync writes them anew (wallc_torque, the arms' columns) */
    return f->on_device && strcmp(f->name, "prim_a_ref");
}

/* Would the order slot_of at least halve the largest distance in memory
 * between a pair row's two particles, which the host threads' sweep waits
 * for where it interleaves (src/backend/omp/sweep.c)?  A tiled or
 * deposited bed's order can keep most rows short, as the test above
 * counts them, and still hold rows a whole layer of the bed apart (1e5
 * spheres tiled 10 x 10: 21,001 slots, 2,016 in the cells' order).  Not
 * where the sweep does not interleave: there the passes run as loops, for
 * which such a bed's order was as good (docs/performance.md, "Session 19,
 * the sweep"); never on an offload device, whose step does not sweep. */
static int halves_lag(cd_sim *sim, const cd_int *slot_of)
{
#if CD_OFFLOAD
    (void)sim;
    (void)slot_of;
    return 0;
#else
    if (!cd_omp_sweep_interleaves(sim)) return 0;
    cd_cols c = cd_sim_step_cols(sim);
    cd_ulong now = 0, then = 0;
    size_t K = sim->s.n_pairs;
#pragma omp parallel for schedule(static) if (K >= (size_t)cd_parallel_min_rows) reduction(max : now, then)
    for (size_t k = 0; k < K; k++) {
        cd_ulong d = cd_reorder_item_row_distance(c, (cd_long)k, NULL);
        cd_ulong e = cd_reorder_item_row_distance(c, (cd_long)k, slot_of);
        now = d > now ? d : now;
        then = e > then ? e : then;
    }
    return 2 * then <= now;
#endif
}

int cd_reorder_build(cd_sim *sim, const cd_grid *g, int *moved)
{
    cd_state *s = &sim->s;
    *moved = 0;
    if (!sim->nb.reorder || s->n_particles < 2) return 0;
    if (!sim->nb.ordered && begin(sim)) return -1;
    cd_nb_lists d = sim->nb.d; /* host copies of device addresses (is_device_ptr) */
    cd_int N = (cd_int)s->n_particles, P = (cd_int)s->n_prims, W = (cd_int)s->n_walls;
    /* Sorting and moving the state costs a few passes over it: done only
     * when more than 1/CD_REORDER_DRIFT of the slots are out of cell
     * order (a settled packing keeps its order for many rebuilds). */
    int forced = sim->nb.reorder == CD_NB_REORDER_ALWAYS;
    if (particle_keys(sim) * CD_REORDER_DRIFT <= (long)N && !forced) return 0;
    /* No pair rows yet (a new run, a start from a file without contacts):
     * nothing tells whether the cells' order would beat the order at hand;
     * the next rebuild will. */
    if (s->n_pairs == 0 && !forced) return 0;
    cd_int *sorted = sort_particles(sim, g), *src = d.part_src, *slot_of = d.count;
    long changed = 0;
    CD_WIDE_MIN
    CD_STEP_FOR(N, reduction(+ : changed) CD_DEV(is_device_ptr(sorted, src, slot_of) map(tofrom : changed)))
    for (cd_int m = 0; m < N; m++) {
        src[m] = sorted[m];
        slot_of[sorted[m]] = m;
        changed += sorted[m] != m;
    }
    if (!changed) return 0;
    /* The cells' order only where it brings the pair rows' particles
     * closer in memory than the order at hand, by 1/8 of the summed bit
     * lengths of their distances: a deposit from a lattice keeps its
     * particles in a lattice order as good (docs/performance.md, "Memory
     * order"), and moving the state for nothing costs a few passes. */
    /* 8 x (bits in the cells' order) - 7 x (bits now), summed exactly in
     * one integer: one reduction variable (two made GCC 12's nvptx
     * offload pack them into a 16-byte atomic it cannot link) */
    long excess = 0;
    size_t K = s->n_pairs;
    CD_BUILD_ARGS(sim)
    CD_STEP_FOR(K, CD_BUILD_IN reduction(+ : excess) CD_DEV(is_device_ptr(slot_of) map(tofrom : excess)))
    for (size_t k = 0; k < K; k++)
        excess += 8L * cd_reorder_item_row_span(CD_B.c, (cd_long)k, slot_of) -
                  7L * cd_reorder_item_row_span(CD_B.c, (cd_long)k, NULL);
    if (excess >= 0 && !forced && !halves_lag(sim, slot_of)) return 0;

    /* the primitives follow their particles: new first primitives, and
     * the old slot of each new primitive (before prim_first moves) */
    CD_STEP_FOR(N, CD_BUILD_IN)
    for (cd_int m = 0; m < N; m++) CD_B.d.count[m] = CD_B.c.prim_count[CD_B.d.part_src[m]];
    cd_nb_scan(d.count, N, d.new_first, d.chunk_sum);
    CD_STEP_FOR(N, CD_BUILD_IN)
    for (cd_int m = 0; m < N; m++)
        cd_reorder_item_prim_src(m, CD_B.d.part_src, CD_B.d.new_first, CD_B.c.prim_first, CD_B.d.prim_src);

    const size_t word = sizeof(cd_int);
    for (size_t f = 0; f < cd_n_fields; f++) {
        enum cd_field_group grp = cd_fields[f].group;
        size_t words = cd_fields[f].elem_size / word;
        cd_int *col = cd_sim_step_field(sim, f);
        if (!moves(&cd_fields[f])) continue;
        if (grp == CD_GROUP_PARTICLE) move_rows(sim, col, (size_t)N, words, words, d.part_src);
        if (grp == CD_GROUP_PRIM) move_rows(sim, col, (size_t)P, words, words, d.prim_src);
        for (cd_int w = 0; grp == CD_GROUP_WALLC && w < W; w++) /* one wall's rows at a time */
            move_rows(sim, col + (size_t)w * words, (size_t)P, words, words * (size_t)W, d.prim_src);
    }
    /* the arms (kernels/cols.h): where every primitive has one (prim_arm
     * the identity since cd_state_arms_derive), the arms follow their
     * primitives; otherwise each primitive takes its arm's row along */
    cd_cols c = cd_sim_step_cols(sim); /* where the step's columns are (host copies of device addresses) */
    if (cd_state_arms_all(s))
        move_rows(sim, (cd_int *)c.arm, (size_t)P, sizeof(cd_arm) / word, sizeof(cd_arm) / word, d.prim_src);
    else move_rows(sim, c.prim_arm, (size_t)P, 1, 1, d.prim_src);
    /* the step's inertia (kernels/cols.h, cd_inertia_of) with its particles */
    size_t iw = (s->inertia_iso ? sizeof(cd_real) : sizeof(cd_vec3)) / word;
    cd_int *inertia = s->inertia_iso ? (cd_int *)c.inertia_iso : s->step_inertia ? (cd_int *)c.inertia : NULL;
    if (inertia) move_rows(sim, inertia, (size_t)N, iw, iw, d.part_src);
    move_rows(sim, (cd_int *)d.part_bound, (size_t)N, sizeof(cd_real) / word, sizeof(cd_real) / word, d.part_src);
    move_rows(sim, d.part_uid, (size_t)N, 1, 1, d.part_src);
    move_rows(sim, d.prim_uid, (size_t)P, 1, 1, d.prim_src);
    CD_STEP_FOR(N, CD_BUILD_IN)
    for (cd_int m = 0; m < N; m++) {
        cd_reorder_item_owner(CD_B.c, m, CD_B.d.new_first);
        CD_B.d.part_at[CD_B.d.part_uid[m]] = m;
    }
    CD_STEP_FOR(P, CD_BUILD_IN)
    for (cd_int i = 0; i < P; i++) CD_B.d.prim_at[CD_B.d.prim_uid[i]] = i;
    sim->nb.reorders++;
    *moved = 1;
    return 0;
}

/* pair_at after a build: the rows in user order (kernels/reorder_items.h);
 * d.pair_count is free by then. */
int cd_reorder_pair_rows(cd_sim *sim)
{
    if (!sim->nb.ordered) return 0;
    cd_nb_lists *dl = &sim->nb.d;
    size_t cap = sim->nb.cap_rows;
    if (sim->nb.pair_at_cap < cap) {
        if (alloc_ints(&dl->pair_at, cap)) return -1;
        sim->nb.pair_at_cap = cap;
    }
    cd_int P = (cd_int)sim->s.n_prims;
    CD_WIDE_MIN
    CD_BUILD_ARGS(sim)
    CD_STEP_FOR(P, CD_BUILD_IN)
    for (cd_int u = 0; u < P; u++)
        CD_B.d.pair_count[u] = cd_reorder_item_pair_count(CD_B.d.prim_at, CD_B.d.pair_offset, u);
    cd_nb_scan(dl->pair_count, P, dl->pair_ustart, dl->chunk_sum);
    CD_STEP_FOR(P, CD_BUILD_IN)
    for (cd_int u = 0; u < P; u++)
        cd_reorder_item_pair_at(CD_B.d.prim_at, CD_B.d.pair_offset, CD_B.d.pair_ustart, u, CD_B.d.pair_at);
    return 0;
}

/* ---- the host columns in user order and back ---------------------------- */

/* A map where the steps run, as host memory (a copy in the offload
 * variant; free it with free_host_map). */
static cd_int *host_map(const cd_int *dev, size_t n)
{
#if CD_OFFLOAD
    cd_int *h = malloc((n + 1) * sizeof(cd_int));
    if (h && cd_dev_get(h, dev, n * sizeof(cd_int))) {
        free(h);
        return NULL;
    }
    return h;
#else
    (void)n;
    return (cd_int *)dev;
#endif
}

static void free_host_map(cd_int *h)
{
#if CD_OFFLOAD
    free(h);
#else
    (void)h;
#endif
}

/* Moves every step column of the host state (particles by part, primitives,
 * their arm indices and wall rows by prim, pair rows by pair, gather or scatter) through
 * scratch of `bytes`; the pair rows' primitive ids through prim_ids; then
 * each particle's primitive indices from the counts in the new order. */
static int move_host(cd_state *s, const cd_int *part, const cd_int *prim, const cd_int *pair, int pair_scatter,
                     const cd_int *prim_ids)
{
    size_t bytes = largest_column(s) * (s->n_walls > 1 ? s->n_walls : 1);
    if (s->n_pairs * sizeof(cd_vec3) > bytes) bytes = s->n_pairs * sizeof(cd_vec3);
    cd_int *tmp = malloc(bytes + 8);
    if (!tmp) return -1;
    for (size_t f = 0; f < cd_n_fields; f++) {
        enum cd_field_group grp = cd_fields[f].group;
        if (grp == CD_GROUP_PAIR_OUT) continue;
        /* the particles' host-only columns (fields.def, PARTICLE_HOST):
         * no step moves them, so they are in user order always */
        if (grp == CD_GROUP_PARTICLE && !cd_fields[f].on_device) continue;
        const cd_int *map = grp == CD_GROUP_PARTICLE ? part : grp == CD_GROUP_PAIR ? pair : prim;
        size_t rows = cd_state_rows(s, grp), stride = grp == CD_GROUP_WALLC ? s->n_walls : 1;
        cd_long n = (cd_long)(stride * cd_fields[f].elem_size / sizeof(cd_int));
        size_t groups = stride ? rows / stride : 0;
        int scatter = grp == CD_GROUP_PAIR && pair_scatter;
        cd_int *col = *cd_field_ptr(s, &cd_fields[f]);
        if (!groups) continue;
        if (cd_fields[f].elem_size % sizeof(cd_int)) { /* a byte a row (cd_flag: pair_active) */
            move_bytes(tmp, col, groups, stride * cd_fields[f].elem_size, map, scatter);
            continue;
        }
        CD_HOST_FOR(groups, firstprivate(tmp, col, map))
        for (size_t g = 0; g < groups; g++) cd_reorder_item_move(tmp, n, col, n, map, (cd_long)g, n, scatter);
        memcpy(col, tmp, rows * cd_fields[f].elem_size);
    }
    /* the arms as at the reorder's build (cd_reorder_build): where every
     * primitive has one (prim_arm the identity), the arms with their
     * primitives; otherwise each primitive's arm index with it */
    int all = cd_state_arms_all(s);
    cd_int *col = all ? (cd_int *)s->arm : s->prim_arm;
    cd_long nw = all ? (cd_long)(sizeof(cd_arm) / sizeof(cd_int)) : 1;
    size_t P = col ? s->n_prims : 0;
    CD_HOST_FOR(P, firstprivate(tmp, col, prim, nw))
    for (size_t i = 0; i < P; i++) cd_reorder_item_move(tmp, nw, col, nw, prim, (cd_long)i, nw, 0);
    if (P) memcpy(col, tmp, P * (size_t)nw * sizeof(cd_int));
    /* the step's inertia with its particles, as at the reorder's build */
    cd_int *icol = s->inertia_iso ? (cd_int *)s->inertia_iso : (cd_int *)s->step_inertia;
    cd_long iw = (cd_long)((s->inertia_iso ? sizeof(cd_real) : sizeof(cd_vec3)) / sizeof(cd_int));
    size_t N = icol ? s->n_particles : 0;
    CD_HOST_FOR(N, firstprivate(tmp, icol, part, iw))
    for (size_t q = 0; q < N; q++) cd_reorder_item_move(tmp, iw, icol, iw, part, (cd_long)q, iw, 0);
    if (N) memcpy(icol, tmp, N * (size_t)iw * sizeof(cd_int));
    free(tmp);
    size_t K = s->n_pairs;
    CD_HOST_FOR(K, firstprivate(s, prim_ids))
    for (size_t k = 0; k < K; k++) {
        s->pair_prim_i[k] = prim_ids[s->pair_prim_i[k]];
        s->pair_prim_j[k] = prim_ids[s->pair_prim_j[k]];
    }
    cd_int first = 0;
    for (size_t q = 0; q < s->n_particles; q++) {
        s->prim_first[q] = first;
        for (cd_int t = 0; t < s->prim_count[q]; t++) s->prim_particle[first + t] = (cd_int)q;
        first += s->prim_count[q];
    }
    return 0;
}

int cd_reorder_to_user(cd_sim *sim)
{
    cd_neighbors *nb = &sim->nb;
    if (!nb->ordered || nb->host_user) return 0;
    cd_state *s = &sim->s;
    cd_int *part_at = host_map(nb->d.part_at, s->n_particles), *prim_at = host_map(nb->d.prim_at, s->n_prims),
           *pair_at = host_map(nb->d.pair_at, s->n_pairs), *prim_uid = host_map(nb->d.prim_uid, s->n_prims);
    int rc = part_at && prim_at && pair_at && prim_uid ? move_host(s, part_at, prim_at, pair_at, 0, prim_uid) : -1;
    free_host_map(part_at);
    free_host_map(prim_at);
    free_host_map(pair_at);
    free_host_map(prim_uid);
    /* host memory (host threads, or an offload build's host fallback):
     * these are the step's columns, now in user order until the next step;
     * an offload device keeps its own in memory order */
    if (!rc && cd_step_memory_is_host()) nb->host_user = 1;
    return rc;
}

int cd_reorder_to_memory(cd_sim *sim)
{
    cd_neighbors *nb = &sim->nb;
    if (!nb->ordered || !nb->host_user) return 0;
    /* host memory only (host_user): the maps are host memory too */
    if (move_host(&sim->s, nb->d.part_uid, nb->d.prim_uid, nb->d.pair_at, 1, nb->d.prim_at)) return -1;
    nb->host_user = 0;
    return 0;
}
