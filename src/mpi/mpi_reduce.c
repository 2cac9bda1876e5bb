/* The run's global sums under MPI (docs/mpi.md, "Reductions"), with the
 * serial program's bits and without gathering the state: the observables
 * (kernels/observe_items.h: rows in blocks of CD_OBS_BLOCK, each block
 * summed in row order, the blocks merged by its fixed tree) and the wall loads
 * (kernels/step_items.h: CD_LOAD_CHUNK primitives a chunk, the same).
 *
 * A block (or chunk) b belongs to rank b % R.  Each rank sends the rows it
 * owns to the blocks' ranks, only the columns the sum reads and only the
 * rows that add something; a block's rank sums it with the serial block
 * function, in row order, from exactly the serial inputs; the blocks'
 * partial sums go to rank 0, which merges them in block order and sends
 * the total to every rank.  The pair rows' blocks are blocks of the serial
 * list's row numbers (inactive rows included), found by a prefix sum of
 * the rows of each primitive, itself distributed by blocks of primitives.
 * Every exchange moves each row once (no rank receives the whole state). */
#include <stdlib.h>
#include <string.h>
#include "mpi/mpi_halo.h"
#include "observe_items.h"
#include "step_items.h"

/* n items of `size` bytes to the ranks dest[k] (MPI_Alltoallv over all
 * ranks, after an MPI_Alltoall of the byte counts); what came into a new
 * *recv of *rlen bytes.  Counted in x->reduce_msgs, x->reduce_bytes.
 * 0, or -1 (out of memory). */
static int route(cd_mpi_ctx *x, const char *items, const int *dest, size_t n, size_t size, char **recv, size_t *rlen)
{
    int R = x->size, *cnt = calloc(4 * (size_t)R + 1, sizeof(int));
    char *send = malloc(n * size + 1);
    size_t *fill = calloc((size_t)R + 1, sizeof *fill);
    *recv = NULL;
    int rc = cnt && send && fill ? 0 : -1;
    if (!rc) {
        int *sc = cnt, *sd = cnt + R, *rcn = cnt + 2 * R, *rd = cnt + 3 * R;
        for (size_t k = 0; k < n; k++) sc[dest[k]] += (int)size;
        size_t at = 0;
        for (int r = 0; r < R; r++) {
            sd[r] = (int)at;
            fill[r] = at;
            at += (size_t)sc[r];
        }
        for (size_t k = 0; k < n; k++) { /* stable: in each rank's part the items keep their order */
            memcpy(send + fill[dest[k]], items + k * size, size);
            fill[dest[k]] += size;
        }
        MPI_Alltoall(sc, 1, MPI_INT, rcn, 1, MPI_INT, x->comm);
        size_t nr = 0;
        for (int r = 0; r < R; r++) {
            rd[r] = (int)nr;
            nr += (size_t)rcn[r];
            if (r != x->rank && sc[r] > 0) {
                x->reduce_msgs++;
                x->reduce_bytes += sc[r];
            }
        }
        *recv = malloc(nr + 1);
        *rlen = nr;
        if (!*recv) rc = -1;
        else MPI_Alltoallv(send, sc, sd, MPI_BYTE, *recv, rcn, rd, MPI_BYTE, x->comm);
    }
    free(cnt);
    free(send);
    free(fill);
    return rc;
}

/* qsort order of records that begin with their key (a long long). */
static int by_key(const void *pa, const void *pb)
{
    long long a, b;
    memcpy(&a, pa, sizeof a);
    memcpy(&b, pb, sizeof b);
    return a < b ? -1 : a > b;
}

/* ---- wall loads ------------------------------------------------------------ */

typedef struct {
    long long prim; /* global primitive */
    double fn;      /* [N] its normal force on the wall */
} prim_load;

typedef struct {
    long long chunk;
    double sum; /* [N] */
} chunk_sum;

/* Rank 0 merges n_blocks partials (block index, then `width` doubles)
 * gathered from every rank with merge(), and every rank gets the `width`
 * doubles of the total. */
static int gather_partials(cd_mpi_ctx *x, const char *mine, int bytes, size_t item, double *total, size_t width,
                           void (*merge)(const char *all, size_t n, double *total))
{
    int R = x->size, *cnt = x->rank == 0 ? calloc(2 * (size_t)R + 1, sizeof(int)) : NULL;
    char *all = NULL;
    int rc = x->rank == 0 && !cnt ? -1 : 0;
    MPI_Gather(&bytes, 1, MPI_INT, cnt, 1, MPI_INT, 0, x->comm);
    size_t n = 0;
    if (x->rank == 0 && cnt) {
        for (int r = 0; r < R; r++) {
            cnt[R + r] = (int)n;
            n += (size_t)cnt[r];
        }
        all = malloc(n + 1);
        if (!all) rc = -1;
    }
    if (x->rank != 0 && bytes > 0) {
        x->reduce_msgs++;
        x->reduce_bytes += bytes;
    }
    MPI_Gatherv(mine, bytes, MPI_BYTE, all, cnt, cnt ? cnt + R : NULL, MPI_BYTE, 0, x->comm);
    if (x->rank == 0 && all) merge(all, n / item, total);
    MPI_Bcast(total, (int)width, MPI_DOUBLE, 0, x->comm);
    free(cnt);
    free(all);
    return rc;
}

/* kernels/step_items.h, CD_LOAD_CHUNK: the chunks' sums in chunk order
 * from +0; a chunk without a nonzero row sums to +0, and adding +0 to a sum
 * that starts at +0 changes no bit, so only the chunks with rows come. */
static void merge_chunks(const char *all, size_t n, double *total)
{
    chunk_sum *c = (chunk_sum *)all;
    qsort(c, n, sizeof *c, by_key);
    double load = 0;
    for (size_t k = 0; k < n; k++) load += c[k].sum;
    *total = load;
}

double cd_mpi_wall_load(cd_mpi_ctx *x, int w, size_t n_prims_global)
{
    (void)n_prims_global;
    cd_state *s = &x->loc.s;
    size_t W = s->n_walls, n = 0;
    prim_load *mine = malloc((s->n_prims + 1) * sizeof *mine);
    int *dest = malloc((s->n_prims + 1) * sizeof *dest);
    if (!mine || !dest) MPI_Abort(x->comm, 1); /* the other ranks are about to wait in the exchange */
    for (size_t q = 0; q < s->n_particles; q++)
        for (cd_int i = s->prim_first[q]; x->owned[q] && i < s->prim_first[q] + s->prim_count[q]; i++)
            if (s->wallc_fn[(size_t)i * W + (size_t)w] != 0) {
                /* the rows left out hold exact zeros: adding one changes no sum that starts at +0 */
                mine[n] = (prim_load){x->gprim[i], s->wallc_fn[(size_t)i * W + (size_t)w]};
                dest[n++] = (int)((x->gprim[i] / CD_LOAD_CHUNK) % x->size);
            }
    char *got = NULL;
    size_t len = 0;
    if (route(x, (const char *)mine, dest, n, sizeof *mine, &got, &len)) MPI_Abort(x->comm, 1);
    /* this rank's chunks: each summed in primitive order */
    size_t m = len / sizeof(prim_load), nc = 0;
    prim_load *e = (prim_load *)got;
    qsort(e, m, sizeof *e, by_key);
    chunk_sum *sums = malloc((m + 1) * sizeof *sums);
    if (!sums) MPI_Abort(x->comm, 1);
    for (size_t k = 0; k < m;) {
        long long ch = e[k].prim / CD_LOAD_CHUNK;
        double acc = 0;
        for (; k < m && e[k].prim / CD_LOAD_CHUNK == ch; k++) acc += e[k].fn;
        sums[nc++] = (chunk_sum){ch, acc};
    }
    double load = 0;
    if (gather_partials(x, (const char *)sums, (int)(nc * sizeof *sums), sizeof *sums, &load, 1, merge_chunks))
        MPI_Abort(x->comm, 1);
    x->reduces++;
    free(mine);
    free(dest);
    free(got);
    free(sums);
    return load;
}

/* ---- observables ------------------------------------------------------------ */

/* What a block of each kind reads of a row (kernels/observe_items.h): a
 * particle's moving columns (its mass and inertia are the set-up's, on
 * every rank) and whether it touches; an active wall row; an active pair
 * row with its place in the serial list. */
typedef struct {
    long long gid;
    cd_vec3 position, velocity, angmom;
    cd_quat orientation;
    long long touch;
} obs_particle;

typedef struct {
    long long row;     /* global primitive x walls + wall */
    cd_wall_entry out; /* the row's history and outputs (kernels/geom_types.h) */
} obs_wall;

typedef struct {
    long long row, gi, gj; /* the serial list's row; global primitives */
    cd_vec3 shear;
    double overlap;
    long long active;
} obs_pair;

typedef struct {
    long long prim, value, from; /* global primitive, rows or first row, the asking rank */
} prim_rows;

typedef struct {
    long long block; /* in merge order: particles, pairs, wall rows */
    double acc[CD_OBS_SLOTS];
} obs_partial;

/* This rank's partials, grown as blocks come. */
typedef struct {
    obs_partial *p;
    size_t n, cap;
} partials;

/* Room for one more partial, block `block`; its slots to fill, NULL when out of memory. */
static double *push(partials *v, long long block)
{
    if (v->n == v->cap) {
        size_t cap = v->cap ? 2 * v->cap : 16;
        obs_partial *p = realloc(v->p, cap * sizeof *p);
        if (!p) return NULL;
        v->p = p;
        v->cap = cap;
    }
    v->p[v->n].block = block;
    return v->p[v->n++].acc;
}

/* Every block has one rank, so the n partials are all the leaves: merged
 * by the serial program's tree (cd_obs_merge_serial). */
static void merge_blocks(const char *all, size_t n, double *total)
{
    obs_partial *p = (obs_partial *)all;
    qsort(p, n, sizeof *p, by_key);
    double *flat = malloc(((size_t)cd_obs_tree_blocks((cd_long)n) + 1) * CD_OBS_SLOTS * sizeof *flat);
    if (!flat) {
        for (int k = 0; k < CD_OBS_SLOTS; k++) total[k] = 0.0 / 0.0; /* (NaN: nothing known) */
        return;
    }
    for (size_t b = 0; b < n; b++) memcpy(flat + b * CD_OBS_SLOTS, p[b].acc, sizeof p[b].acc);
    cd_obs_merge_serial(flat, (cd_long)n, total);
    free(flat);
}

static int block_rank(const cd_mpi_ctx *x, long long row) { return (int)((row / CD_OBS_BLOCK) % x->size); }

/* The serial list's first row of each owned primitive with rows (first,
 * by global primitive, into *firsts, sorted; *n_firsts of them) and the
 * list's length (*K): the rows per primitive go to the ranks of the
 * primitives' blocks, which sum them in primitive order; the block totals
 * (one long long per block of primitives, each from its rank) are summed
 * over the ranks and prefixed on every rank; each first row goes back. */
static int serial_rows(cd_mpi_ctx *x, const long long *rows, prim_rows **firsts, size_t *n_firsts, long long *K,
                       size_t n_prims_global)
{
    cd_state *s = &x->loc.s;
    size_t n = 0, nb = (n_prims_global + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK;
    prim_rows *mine = malloc((s->n_prims + 1) * sizeof *mine);
    int *dest = malloc((s->n_prims + 1) * sizeof *dest);
    long long *tot = calloc(nb + 1, sizeof *tot), *start = calloc(nb + 1, sizeof *start);
    if (!mine || !dest || !tot || !start) return -1;
    for (size_t q = 0; q < s->n_particles; q++)
        for (cd_int i = s->prim_first[q]; x->owned[q] && i < s->prim_first[q] + s->prim_count[q]; i++)
            if (rows[i]) {
                mine[n] = (prim_rows){x->gprim[i], rows[i], x->rank};
                dest[n++] = block_rank(x, x->gprim[i]);
            }
    char *got = NULL, *back = NULL;
    size_t len = 0, blen = 0;
    int rc = route(x, (const char *)mine, dest, n, sizeof *mine, &got, &len);
    size_t m = len / sizeof(prim_rows);
    prim_rows *e = (prim_rows *)got;
    if (!rc) {
        qsort(e, m, sizeof *e, by_key);
        for (size_t k = 0; k < m; k++) tot[e[k].prim / CD_OBS_BLOCK] += e[k].value;
        /* each entry from one rank, the others' zeros: an integer sum, exact */
        MPI_Allreduce(tot, start, (int)nb, MPI_LONG_LONG, MPI_SUM, x->comm);
        long long run = 0;
        for (size_t b = 0; b < nb; b++) { /* exclusive prefix: the first row of each block of primitives */
            long long t = start[b];
            start[b] = run;
            run += t;
        }
        *K = run;
        long long at = -1, blk = -1;
        free(dest);
        dest = malloc((m + 1) * sizeof *dest);
        if (!dest) rc = -1;
        for (size_t k = 0; dest && k < m; k++) {
            if (e[k].prim / CD_OBS_BLOCK != blk) {
                blk = e[k].prim / CD_OBS_BLOCK;
                at = start[blk];
            }
            long long r = e[k].value;
            e[k].value = at;
            at += r;
            dest[k] = (int)e[k].from;
        }
        if (!rc) rc = route(x, got, dest, m, sizeof *e, &back, &blen);
    }
    if (!rc) {
        *firsts = (prim_rows *)back;
        *n_firsts = blen / sizeof(prim_rows);
        qsort(*firsts, *n_firsts, sizeof **firsts, by_key);
    } else free(back);
    free(mine);
    free(dest);
    free(tot);
    free(start);
    free(got);
    return rc;
}

/* The first row of global primitive gp in the serial list (firsts sorted). */
static long long first_row(const prim_rows *firsts, size_t n, long long gp)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (firsts[mid].prim < gp) lo = mid + 1;
        else hi = mid;
    }
    return lo < n && firsts[lo].prim == gp ? firsts[lo].value : -1;
}

/* The particle blocks of this rank, summed on the global state's columns
 * (their rows written from the owners' records; mass and inertia are the
 * set-up's) with the touch flags of the owners. */
static int particle_blocks(cd_mpi_ctx *x, cd_sim *g, const cd_int *touch_loc, partials *out)
{
    cd_state *s = &x->loc.s, *gs = &g->s;
    size_t n = 0, N = gs->n_particles;
    obs_particle *mine = malloc((s->n_particles + 1) * sizeof *mine);
    int *dest = malloc((s->n_particles + 1) * sizeof *dest);
    cd_int *touch = calloc(N + 1, sizeof *touch);
    if (!mine || !dest || !touch) return -1;
    for (size_t q = 0; q < s->n_particles; q++)
        if (x->owned[q]) {
            mine[n] = (obs_particle){x->gid[q],    s->position[q],    s->velocity[q],
                                     s->angmom[q], s->orientation[q], touch_loc[q] != 0};
            dest[n++] = block_rank(x, x->gid[q]);
        }
    char *got = NULL;
    size_t len = 0;
    int rc = route(x, (const char *)mine, dest, n, sizeof *mine, &got, &len);
    for (size_t k = 0; !rc && k < len / sizeof(obs_particle); k++) {
        obs_particle r;
        memcpy(&r, got + k * sizeof r, sizeof r);
        gs->position[r.gid] = r.position;
        gs->velocity[r.gid] = r.velocity;
        gs->angmom[r.gid] = r.angmom;
        gs->orientation[r.gid] = r.orientation;
        touch[r.gid] = (cd_int)r.touch;
    }
    cd_cols c = cd_sim_host_cols(gs);
    cd_long nb = ((cd_long)N + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK;
    for (cd_long b = x->rank; !rc && b < nb; b += x->size) {
        double *acc = push(out, b);
        if (!acc) rc = -1;
        else cd_obs_block_particles(c, b, (cd_long)N, g->p.gravity, touch, acc, cd_order_identity());
    }
    free(mine);
    free(dest);
    free(touch);
    free(got);
    return rc;
}

/* The wall-row blocks of this rank (first block first_block in merge
 * order), summed on the global state's wall columns (this rank's blocks
 * cleared, then the active rows written from the owners' records) with
 * the rows' outputs in the form of the step's candidate lists
 * (kernels/step_items.h, cd_wall_out_place): per particle its rows in
 * contact, ascending. */
static int wall_blocks(cd_mpi_ctx *x, cd_sim *g, long long first_block, partials *out)
{
    cd_state *s = &x->loc.s, *gs = &g->s;
    size_t W = s->n_walls, n = 0, rows = gs->n_prims * W, N = gs->n_particles;
    obs_wall *mine = malloc((s->n_prims * W + 1) * sizeof *mine);
    int *dest = malloc((s->n_prims * W + 1) * sizeof *dest);
    if (!mine || !dest) return -1;
    for (size_t q = 0; q < s->n_particles; q++)
        for (cd_int i = s->prim_first[q]; x->owned[q] && i < s->prim_first[q] + s->prim_count[q]; i++)
            for (size_t w = 0; w < W; w++) {
                size_t r = (size_t)i * W + w;
                if (!s->wallc_active[r]) continue; /* (an inactive row adds nothing) */
                long long row = x->gprim[i] * (long long)W + (long long)w;
                cd_wall_entry o = cd_state_wall_entry(s, r);
                mine[n] = (obs_wall){row, o};
                dest[n++] = block_rank(x, row);
            }
    char *got = NULL;
    size_t len = 0, m = 0;
    int rc = route(x, (const char *)mine, dest, n, sizeof *mine, &got, &len);
    m = len / sizeof(obs_wall);
    obs_wall *e = (obs_wall *)got;
    cd_int *start = calloc(N + 2, sizeof *start), *wrows = malloc((m + 1) * sizeof *wrows);
    cd_wall_entry *outs = malloc((m + 1) * sizeof *outs);
    if (!start || !wrows || !outs) rc = -1;
    cd_long nb = ((cd_long)rows + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK;
    for (cd_long b = x->rank; !rc && b < nb; b += x->size)
        for (cd_long r = b * CD_OBS_BLOCK; r < cd_obs_block_end(b, (cd_long)rows); r++) gs->wallc_active[r] = 0;
    if (!rc) qsort(e, m, sizeof *e, by_key); /* rows ascending: particles ascending */
    for (size_t k = 0; !rc && k < m; k++) {
        gs->wallc_active[e[k].row] = e[k].out.active;
        gs->wallc_shear[e[k].row] = e[k].out.shear;
        start[gs->prim_particle[e[k].row / (long long)W] + 1]++;
        wrows[k] = (cd_int)e[k].row;
        outs[k] = e[k].out;
    }
    for (size_t q = 0; !rc && q < N; q++) start[q + 1] += start[q];
    cd_cols c = cd_sim_host_cols(gs);
    for (cd_long b = x->rank; !rc && b < nb; b += x->size) {
        double *acc = push(out, first_block + b);
        if (!acc) rc = -1;
        else
            cd_obs_block_walls(c, b, (cd_long)rows, (cd_int)W, g->p.wall_law, acc, cd_order_identity(), start, wrows,
                               outs);
    }
    free(mine);
    free(dest);
    free(got);
    free(start);
    free(wrows);
    free(outs);
    return rc;
}

/* The pair-row blocks of this rank (first block first_block in merge
 * order): the active rows of the serial list, each sent by the owner of
 * its particle i, into a block's own columns (the rows of the block at
 * 0..), summed by the serial block function; prim_radius is the set-up's. */
static int pair_blocks(cd_mpi_ctx *x, cd_sim *g, long long first_block, partials *out, long long *n_blocks)
{
    cd_state *s = &x->loc.s;
    size_t P = s->n_prims, n = 0, n_firsts = 0;
    long long *row0 = malloc((P + 1) * sizeof *row0), *rows = calloc(P + 1, sizeof *rows), K = 0;
    prim_rows *firsts = NULL;
    if (!row0 || !rows) return -1;
    /* the rows of each primitive: contiguous, the list being in key order */
    for (size_t k = s->n_pairs; k-- > 0;) {
        row0[s->pair_prim_i[k]] = (long long)k;
        rows[s->pair_prim_i[k]]++;
    }
    int rc = serial_rows(x, rows, &firsts, &n_firsts, &K, g->s.n_prims);
    obs_pair *mine = malloc((s->n_pairs + 1) * sizeof *mine);
    int *dest = malloc((s->n_pairs + 1) * sizeof *dest);
    if (!mine || !dest) rc = -1;
    for (size_t k = 0; !rc && k < s->n_pairs; k++) {
        cd_int i = s->pair_prim_i[k];
        if (!s->pair_active[k] || !x->owned[s->prim_particle[i]]) continue;
        long long row = first_row(firsts, n_firsts, x->gprim[i]) + ((long long)k - row0[i]);
        mine[n] = (obs_pair){
            row, x->gprim[i], x->gprim[s->pair_prim_j[k]], s->pair_shear[k], s->pair_overlap[k], s->pair_active[k]};
        dest[n++] = block_rank(x, row);
    }
    char *got = NULL;
    size_t len = 0;
    if (!rc) rc = route(x, (const char *)mine, dest, n, sizeof *mine, &got, &len);
    cd_long nb = (K + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK;
    *n_blocks = nb;
    /* one block's columns, rows from 0 */
    cd_int *active = malloc(CD_OBS_BLOCK * sizeof *active), *pi = malloc(CD_OBS_BLOCK * sizeof *pi),
           *pj = malloc(CD_OBS_BLOCK * sizeof *pj);
    double *overlap = malloc(CD_OBS_BLOCK * sizeof *overlap);
    cd_vec3 *shear = malloc(CD_OBS_BLOCK * sizeof *shear);
    if (!active || !pi || !pj || !overlap || !shear) rc = -1;
    size_t m = len / sizeof(obs_pair);
    for (cd_long b = x->rank; !rc && b < nb; b += x->size) {
        cd_long b0 = b * CD_OBS_BLOCK, len_b = cd_obs_block_end(b, K) - b0;
        memset(active, 0, CD_OBS_BLOCK * sizeof *active);
        for (size_t k = 0; k < m; k++) {
            obs_pair r;
            memcpy(&r, got + k * sizeof r, sizeof r);
            if (r.row < b0 || r.row >= b0 + len_b) continue;
            size_t at = (size_t)(r.row - b0);
            active[at] = (cd_int)r.active;
            pi[at] = (cd_int)r.gi;
            pj[at] = (cd_int)r.gj;
            overlap[at] = r.overlap;
            shear[at] = r.shear;
        }
        cd_cols c;
        memset(&c, 0, sizeof c);
        c.pair_active = active;
        c.pair_prim_i = pi;
        c.pair_prim_j = pj;
        c.pair_overlap = overlap;
        c.pair_shear = shear;
        c.prim_radius = g->s.prim_radius;
        double *acc = push(out, first_block + b);
        if (!acc) rc = -1;
        else cd_obs_block_pairs(c, 0, len_b, g->p.law, acc, cd_order_identity());
    }
    free(row0);
    free(rows);
    free(firsts);
    free(mine);
    free(dest);
    free(got);
    free(active);
    free(pi);
    free(pj);
    free(overlap);
    free(shear);
    return rc;
}

int cd_mpi_observe_slots(cd_mpi_ctx *x, cd_sim *global, double *total)
{
    cd_state *s = &x->loc.s;
    const cd_state *gs = &global->s;
    /* Rattlers: which owned particles touch (every row of an owned particle
     * is local), counted as the serial program counts them */
    cd_int *touch = calloc(s->n_particles + 1, sizeof *touch);
    if (!touch) MPI_Abort(x->comm, 1);
    cd_cols lc = cd_sim_host_cols(s);
    for (size_t k = 0; k < s->n_pairs; k++) cd_obs_item_touch_pair(lc, (cd_long)k, touch);
    /* the wall rows in contact as the step's candidate entries (kernels/observe_items.h) */
    size_t n_wall = cd_state_wall_entries(s, NULL, NULL);
    cd_int *wrows = malloc((n_wall + 1) * sizeof *wrows);
    cd_wall_entry *went = malloc((n_wall + 1) * sizeof *went);
    if (!wrows || !went) MPI_Abort(x->comm, 1);
    cd_state_wall_entries(s, wrows, went);
    for (size_t e = 0; e < n_wall; e++) cd_obs_item_touch_wall(lc, (cd_long)e, (cd_int)s->n_walls, wrows, went, touch);
    free(wrows);
    free(went);
    cd_long nbp = ((cd_long)gs->n_particles + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK;
    partials part = {NULL, 0, 0};
    long long nbk = 0;
    /* (a rank out of memory stops all: the others wait in the exchanges) */
    if (particle_blocks(x, global, touch, &part) || pair_blocks(x, global, nbp, &part, &nbk) ||
        wall_blocks(x, global, nbp + nbk, &part) ||
        gather_partials(x, (const char *)part.p, (int)(part.n * sizeof *part.p), sizeof *part.p, total, CD_OBS_SLOTS,
                        merge_blocks))
        MPI_Abort(x->comm, 1);
    x->reduces++;
    free(touch);
    free(part.p);
    return 0;
}
