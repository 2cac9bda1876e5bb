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
 * the total to every rank.  The observables' leaves are functions of
 * global ids only (the pair rows' of their primitive i), dealt to the
 * ranks by groups of CD_OBS_FANIN^k leaves, so that each rank makes the
 * tree's first k levels of merges of its groups and rank 0 the rest.  Every exchange
 * moves each row once (no rank receives the whole state), and a leaf's
 * rank keeps the rows of its leaves only (no column of the whole run). */
#include <stdlib.h>
#include <string.h>
#include "mpi/mpi_halo.h"
#include "observe_items.h"
#include "step_items.h"

/* n items of `size` bytes to the ranks dest[k] (MPI_Alltoallv over all
 * ranks, after an MPI_Alltoall of the byte counts); what came into a new
 * *recv of *rlen bytes.  Counted in x->reduce_msgs, x->reduce_bytes.
 * items and dest (malloc'd by the caller) are let go once packed in rank
 * order, before the receive buffer is allocated: a rank holds two copies
 * of its rows at a time, not three.  0, or -1 (out of memory). */
static int route(cd_mpi_ctx *x, void *items_in, int *dest, size_t n, size_t size, char **recv, size_t *rlen)
{
    const char *items = items_in;
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
        free(items_in);
        free(dest);
        items_in = NULL;
        dest = NULL;
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
    free(items_in);
    free(dest);
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

double cd_mpi_wall_load(cd_mpi_ctx *x, int w, const double *fn)
{
    cd_state *s = &x->loc.s;
    size_t W = s->n_walls, n = 0;
    prim_load *mine = malloc((s->n_prims + 1) * sizeof *mine);
    int *dest = malloc((s->n_prims + 1) * sizeof *dest);
    if (!mine || !dest) MPI_Abort(x->comm, 1); /* the other ranks are about to wait in the exchange */
    for (size_t q = 0; q < s->n_particles; q++)
        for (cd_int i = s->prim_first[q]; x->owned[q] && i < s->prim_first[q] + s->prim_count[q]; i++)
            if ((fn ? fn[i] : s->wallc_fn[(size_t)i * W + (size_t)w]) != 0) {
                /* the rows left out hold exact zeros: adding one changes no sum that starts at +0 */
                mine[n] = (prim_load){x->gprim[i], fn ? fn[i] : s->wallc_fn[(size_t)i * W + (size_t)w]};
                dest[n++] = (int)((x->gprim[i] / CD_LOAD_CHUNK) % x->size);
            }
    char *got = NULL;
    size_t len = 0;
    if (route(x, mine, dest, n, sizeof *mine, &got, &len)) MPI_Abort(x->comm, 1);
    /* (route let mine and dest go) */
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
    free(got);
    free(sums);
    return load;
}

/* ---- observables ------------------------------------------------------------ */

/* What a leaf of each kind reads of a row (kernels/observe_items.h): a
 * particle's moving columns, its mass and inertia, and whether it
 * touches; an active wall row with its primitive's radius; an active pair
 * row with its global primitives and their radii.  A leaf's rank holds
 * these rows only (no column of the whole run): each leaf is summed on
 * columns of its own rows, in a frame of row numbers where the serial leaf
 * function visits exactly its rows, in its order ("Reductions",
 * docs/mpi.md). */
typedef struct {
    long long gid;
    cd_vec3 position, velocity, angmom, inertia;
    cd_quat orientation;
    double mass; /* [kg] */
    long long touch;
} obs_particle;

typedef struct {
    long long row;     /* global primitive x walls + wall */
    cd_wall_entry out; /* the row's history and outputs (kernels/geom_types.h) */
    double radius;     /* [m] the primitive's */
} obs_wall;

typedef struct {
    long long key, gi, gj; /* gi x (global primitives) + gj: the serial list's order; global primitives */
    cd_vec3 shear;
    double overlap, ri, rj; /* [m] */
    long long active;
} obs_pair;

typedef struct {
    long long index; /* leaf (merge order: particles, pairs, wall rows), or group of CD_OBS_FANIN leaves */
    double acc[CD_OBS_SLOTS];
} obs_partial;

/* This rank's partials, grown as leaves come. */
typedef struct {
    obs_partial *p;
    size_t n, cap;
} partials;

/* The leaves of the whole tree: the first leaf of each kind, and all; the
 * tree's levels that the ranks merge themselves (levels, the first merge
 * counted as 1) and the leaves under one item of the last of them (span =
 * CD_OBS_FANIN^levels), which go to one rank. */
typedef struct {
    long long particles, pairs, walls, n;
    int levels;
    long long span;
} leaf_plan;

/* Items of the tree's level j over n leaves (level 0: the leaves; the
 * last level has one item, the total). */
static long long level_items(long long n, int j)
{
    for (int k = 0; k < j && n > 1; k++) n = n > CD_OBS_FANIN ? (n + CD_OBS_FANIN - 1) / CD_OBS_FANIN : 1;
    return n;
}

/* As many levels merged on the ranks as leave at least 4 items of the last
 * of them per rank (at least the first merge, at most the whole tree): rank
 * 0 then merges n / 16^levels partials, not one per leaf (1e8 hexapods:
 * 3e7 leaves on 64 ranks, about 450 partials of 4 levels). */
static void plan_levels(leaf_plan *lp, int ranks)
{
    const char *force = getenv("CAPDEM_MPI_MERGE_LEVELS"); /* that many levels where the tree has them, for the test */
    int forced = force ? atoi(force) : 0;
    lp->levels = 1;
    lp->span = CD_OBS_FANIN;
    while (forced > lp->levels && level_items(lp->n, lp->levels) > 1) {
        lp->levels++;
        lp->span *= CD_OBS_FANIN;
    }
    if (forced > 0) return;
    while (level_items(lp->n, lp->levels) > 1 &&
           (lp->n + lp->span * CD_OBS_FANIN - 1) / (lp->span * CD_OBS_FANIN) >= 4LL * ranks) {
        lp->levels++;
        lp->span *= CD_OBS_FANIN;
    }
}

/* Room for one more partial, number `index`; its slots to fill, NULL when out of memory. */
static double *push(partials *v, long long index)
{
    if (v->n == v->cap) {
        size_t cap = v->cap ? 2 * v->cap : 16;
        obs_partial *p = realloc(v->p, cap * sizeof *p);
        if (!p) return NULL;
        v->p = p;
        v->cap = cap;
    }
    v->p[v->n].index = index;
    return v->p[v->n++].acc;
}

/* Leaf L belongs to the rank of its group of lp.span leaves (an item of
 * the last level the ranks merge), groups dealt round the ranks: a rank
 * merges its groups itself, and rank 0 gets one partial a group. */
static int leaf_rank(const cd_mpi_ctx *x, const leaf_plan *lp, long long leaf)
{
    return (int)((leaf / lp->span) % x->size);
}

/* Rank 0, the items of the ranks' last level (n of them) gathered from
 * every rank: the rest of the serial program's tree (cd_obs_merge_serial
 * from the next level on); when the ranks' levels were the whole tree, the
 * one item is the total. */
static void merge_groups(const char *all, size_t n, double *total)
{
    obs_partial *p = (obs_partial *)all;
    qsort(p, n, sizeof *p, by_key);
    if (n == 1) {
        memcpy(total, p[0].acc, sizeof p[0].acc);
        return;
    }
    double *flat = malloc(((size_t)cd_obs_tree_blocks((cd_long)n) + 1) * CD_OBS_SLOTS * sizeof *flat);
    if (!flat) {
        for (int k = 0; k < CD_OBS_SLOTS; k++) total[k] = 0.0 / 0.0; /* (NaN: nothing known) */
        return;
    }
    for (size_t g = 0; g < n; g++) memcpy(flat + g * CD_OBS_SLOTS, p[g].acc, sizeof p[g].acc);
    cd_obs_merge_serial(flat, (cd_long)n, total);
    free(flat);
}

/* The particle leaves of this rank: each on columns of its own rows
 * (rows b CD_OBS_BLOCK .. of the run, put at 0 ..), which the serial leaf
 * function sums as leaf 0 of a state of that many particles: the same
 * rows in the same order, so the same bits. */
static int particle_leaves(cd_mpi_ctx *x, const cd_sim *g, const cd_int *touch_loc, leaf_plan lp, partials *out)
{
    cd_state *s = &x->loc.s;
    size_t n = 0, N = g->s.n_particles;
    obs_particle *mine = malloc((s->n_particles + 1) * sizeof *mine);
    int *dest = malloc((s->n_particles + 1) * sizeof *dest);
    if (!mine || !dest) return -1;
    for (size_t q = 0; q < s->n_particles; q++)
        if (x->owned[q]) {
            mine[n] = (obs_particle){x->gid[q],     s->position[q],    s->velocity[q], s->angmom[q],
                                     s->inertia[q], s->orientation[q], s->mass[q],     touch_loc[q] != 0};
            dest[n++] = leaf_rank(x, &lp, lp.particles + x->gid[q] / CD_OBS_BLOCK);
        }
    char *got = NULL;
    size_t len = 0;
    int rc = route(x, mine, dest, n, sizeof *mine, &got, &len);
    /* (route let mine and dest go) */
    size_t m = len / sizeof(obs_particle);
    obs_particle *e = (obs_particle *)got;
    if (!rc) qsort(e, m, sizeof *e, by_key); /* each leaf's rows together, ascending */
    cd_vec3 position[CD_OBS_BLOCK], velocity[CD_OBS_BLOCK], angmom[CD_OBS_BLOCK], inertia[CD_OBS_BLOCK];
    cd_quat orientation[CD_OBS_BLOCK];
    cd_real mass[CD_OBS_BLOCK];
    cd_int touch[CD_OBS_BLOCK];
    cd_cols c;
    memset(&c, 0, sizeof c);
    c.position = position;
    c.velocity = velocity;
    c.angmom = angmom;
    c.inertia = inertia;
    c.orientation = orientation;
    c.mass = mass;
    size_t k = 0;
    for (cd_long b = 0; !rc && b < lp.pairs - lp.particles; b++) {
        if (leaf_rank(x, &lp, lp.particles + b) != x->rank) continue;
        cd_long rows = cd_obs_block_end(b, (cd_long)N) - b * CD_OBS_BLOCK;
        for (cd_long u = 0; u < rows; u++, k++) {
            if (k >= m || e[k].gid != b * CD_OBS_BLOCK + u) { /* (every particle has one owner: cannot happen) */
                rc = -1;
                break;
            }
            position[u] = e[k].position;
            velocity[u] = e[k].velocity;
            angmom[u] = e[k].angmom;
            inertia[u] = e[k].inertia;
            orientation[u] = e[k].orientation;
            mass[u] = e[k].mass;
            touch[u] = (cd_int)e[k].touch;
        }
        double *acc = rc ? NULL : push(out, lp.particles + b);
        if (!acc) rc = -1;
        else cd_obs_block_particles(c, 0, rows, g->p.gravity, touch, acc, cd_order_identity());
    }
    free(got);
    return rc;
}

/* Greatest common divisor of a, b > 0. */
static long long gcd(long long a, long long b)
{
    while (b) {
        long long t = a % b;
        a = b;
        b = t;
    }
    return a;
}

/* The wall-row leaves of this rank.  Leaf b is rows b CD_OBS_BLOCK .. of
 * the primitive x wall rows (W a primitive), and the serial leaf function
 * takes a row's wall from the row number (row % W): so each leaf is
 * summed in a frame whose rows are the run's less a shift that is a
 * multiple of both CD_OBS_BLOCK and W, as leaf b' = b mod (W / gcd(64, W))
 * of it: the same rows, walls and order, on columns of at most 64 / gcd +
 * 1 primitives (their radius; each its own particle, with its rows in
 * contact as the step's candidate entries, cd_wall_out_place). */
static int wall_leaves(cd_mpi_ctx *x, const cd_sim *g, leaf_plan lp, partials *out)
{
    cd_state *s = &x->loc.s;
    size_t W = s->n_walls, n = 0;
    long long rows = (long long)(g->s.n_prims * W);
    obs_wall *mine = malloc((s->n_prims * W + 1) * sizeof *mine);
    int *dest = malloc((s->n_prims * W + 1) * sizeof *dest);
    if (!mine || !dest) return -1;
    for (size_t q = 0; q < s->n_particles; q++)
        for (cd_int i = s->prim_first[q]; x->owned[q] && i < s->prim_first[q] + s->prim_count[q]; i++)
            for (size_t w = 0; w < W; w++) {
                size_t r = (size_t)i * W + w;
                if (!s->wallc_active[r]) continue; /* (an inactive row adds nothing) */
                long long row = x->gprim[i] * (long long)W + (long long)w;
                mine[n] = (obs_wall){row, cd_state_wall_entry(s, r), s->prim_radius[i]};
                dest[n++] = leaf_rank(x, &lp, lp.walls + row / CD_OBS_BLOCK);
            }
    char *got = NULL;
    size_t len = 0;
    int rc = route(x, mine, dest, n, sizeof *mine, &got, &len);
    /* (route let mine and dest go) */
    size_t m = len / sizeof(obs_wall);
    obs_wall *e = (obs_wall *)got;
    if (!rc) qsort(e, m, sizeof *e, by_key); /* rows ascending: each leaf's together */
    enum { PRIMS = CD_OBS_BLOCK + 2 };       /* a frame's primitives: at most 64 / gcd(64, W) + 1 */
    cd_int prim_particle[PRIMS], start[PRIMS + 1], wrows[CD_OBS_BLOCK];
    cd_real radius[PRIMS];
    cd_wall_entry outs[CD_OBS_BLOCK];
    cd_cols c;
    memset(&c, 0, sizeof c);
    c.prim_particle = prim_particle;
    c.prim_radius = radius;
    for (int i = 0; i < PRIMS; i++) prim_particle[i] = i;
    long long period = W ? (long long)W / gcd(CD_OBS_BLOCK, (long long)W) : 1; /* leaves */
    size_t k = 0;
    for (cd_long b = 0; !rc && b < lp.n - lp.walls; b++) {
        if (leaf_rank(x, &lp, lp.walls + b) != x->rank) continue;
        long long bf = b % period, shift = (b - bf) * CD_OBS_BLOCK; /* frame's leaf; rows before it */
        long long end = cd_obs_block_end(b, rows);
        memset(start, 0, sizeof start);
        memset(radius, 0, sizeof radius);
        cd_int ne = 0;
        for (; k < m && e[k].row < end; k++, ne++) { /* the leaf's rows, ascending */
            long long r = e[k].row - shift, i = r / (long long)W;
            wrows[ne] = (cd_int)r;
            outs[ne] = e[k].out;
            radius[i] = e[k].radius;
            start[i + 1]++;
        }
        for (int i = 0; i < PRIMS; i++) start[i + 1] += start[i];
        double *acc = push(out, lp.walls + b);
        if (!acc) rc = -1;
        else
            cd_obs_block_walls(c, bf, (cd_long)(rows - shift), (cd_int)W, g->p.wall_law, acc, cd_order_identity(),
                               start, wrows, outs);
    }
    free(got);
    return rc;
}

/* The pair-row leaves of this rank: the active rows, each sent by the
 * owner of its particle i to the rank of its primitive i's leaf, put in
 * the serial list's order (by global primitive i, then j: the order of the
 * rows of the serial list, inactive rows aside, which add nothing).  The
 * serial leaf function finds a leaf's rows by their primitive i, so each
 * leaf is summed as leaf 0 of its own rows: primitive i numbered from the
 * leaf's first (0 .. 63), primitive j of row k as 64 + k, each with the
 * radius the owner sent. */
static int pair_leaves(cd_mpi_ctx *x, const cd_sim *g, leaf_plan lp, partials *out)
{
    cd_state *s = &x->loc.s;
    long long P = (long long)g->s.n_prims;
    size_t n = 0;
    obs_pair *mine = malloc((s->n_pairs + 1) * sizeof *mine);
    int *dest = malloc((s->n_pairs + 1) * sizeof *dest);
    if (!mine || !dest) return -1;
    /* each row's overlap from the local step's ends, as the serial leaf
     * derives it (kernels/observe_items.h, cd_obs_pair_overlap); from the
     * host's columns where the arms were never derived (as at sync) */
    cd_cols lc = cd_sim_host_cols(s);
    const double *host_overlap = NULL;
    if (!s->prim_arm) {
        cd_sim_derive_pair_output(&x->loc);
        host_overlap = s->pair_overlap;
    }
    for (size_t k = 0; k < s->n_pairs; k++) {
        cd_int i = s->pair_prim_i[k], j = s->pair_prim_j[k];
        if (!s->pair_active[k] || !x->owned[s->prim_particle[i]]) continue;
        long long gi = x->gprim[i], gj = x->gprim[j];
        double overlap =
            cd_obs_pair_overlap(lc, (cd_long)k, host_overlap, x->loc.p.sin_parallel, x->loc.p.parallel_blend);
        mine[n] = (obs_pair){gi * P + gj,      gi, gj, s->pair_shear[k], overlap, s->prim_radius[i], s->prim_radius[j],
                             s->pair_active[k]};
        dest[n++] = leaf_rank(x, &lp, lp.pairs + gi / CD_OBS_BLOCK);
    }
    char *got = NULL;
    size_t len = 0;
    int rc = route(x, mine, dest, n, sizeof *mine, &got, &len);
    /* (route let mine and dest go) */
    size_t m = len / sizeof(obs_pair);
    obs_pair *e = (obs_pair *)got;
    cd_flag *active = malloc((m + 1) * sizeof *active);
    cd_int *pi = malloc((m + 1) * sizeof *pi), *pj = malloc((m + 1) * sizeof *pj);
    double *overlap = malloc((m + 1) * sizeof *overlap), *radius = malloc((m + CD_OBS_BLOCK + 1) * sizeof *radius);
    cd_vec3 *shear = malloc((m + 1) * sizeof *shear);
    if (!active || !pi || !pj || !overlap || !shear || !radius) rc = -1;
    if (!rc) qsort(e, m, sizeof *e, by_key);
    cd_cols c;
    memset(&c, 0, sizeof c);
    c.pair_active = active;
    c.pair_prim_i = pi;
    c.pair_prim_j = pj;
    c.pair_shear = shear;
    c.prim_radius = radius;
    size_t k = 0;
    for (cd_long b = 0; !rc && b < lp.walls - lp.pairs; b++) {
        if (leaf_rank(x, &lp, lp.pairs + b) != x->rank) continue;
        cd_long nb = 0; /* the leaf's rows */
        for (; k < m && e[k].gi < (b + 1) * CD_OBS_BLOCK; k++, nb++) {
            active[nb] = (cd_flag)e[k].active;
            pi[nb] = (cd_int)(e[k].gi - b * CD_OBS_BLOCK);
            pj[nb] = (cd_int)(CD_OBS_BLOCK + nb);
            overlap[nb] = e[k].overlap;
            shear[nb] = e[k].shear;
            radius[pi[nb]] = e[k].ri;
            radius[pj[nb]] = e[k].rj;
        }
        double *acc = push(out, lp.pairs + b);
        if (!acc) rc = -1;
        else cd_obs_block_pairs(c, 0, nb, g->p.law, acc, cd_order_identity(), overlap, 0, 0);
    }
    free(got);
    free(active);
    free(pi);
    free(pj);
    free(overlap);
    free(shear);
    free(radius);
    return rc;
}

/* This rank's groups of leaves merged, level by level up to lp.levels:
 * each item by cd_obs_item_merge over its own children (at most
 * CD_OBS_FANIN, all this rank's), the additions of the serial program's
 * tree.  The rank's items of level lp.levels into *groups. */
static int merge_own_groups(const partials *leaves, leaf_plan lp, partials *groups)
{
    partials in = *leaves, out = {NULL, 0, 0};
    int rc = 0;
    for (int j = 1; !rc && j <= lp.levels; j++) {
        long long n_in = level_items(lp.n, j - 1);
        out.n = 0;
        for (size_t k = 0; !rc && k < in.n;) { /* items in ascending order */
            long long item = in.p[k].index / CD_OBS_FANIN;
            size_t first = k;
            double buf[CD_OBS_FANIN * CD_OBS_SLOTS];
            for (; k < in.n && in.p[k].index / CD_OBS_FANIN == item; k++)
                memcpy(buf + (k - first) * CD_OBS_SLOTS, in.p[k].acc, sizeof in.p[k].acc);
            long long children = n_in - item * CD_OBS_FANIN < CD_OBS_FANIN ? n_in - item * CD_OBS_FANIN : CD_OBS_FANIN;
            double *acc = (long long)(k - first) == children ? push(&out, item) : NULL; /* (every child here) */
            if (!acc) rc = -1;
            else cd_obs_item_merge(buf, children, 0, acc);
        }
        if (in.p != leaves->p) free(in.p);
        in = out;
        out = (partials){NULL, 0, 0};
    }
    if (rc && in.p != leaves->p) free(in.p);
    if (!rc) *groups = in;
    return rc;
}

int cd_mpi_observe_slots(cd_mpi_ctx *x, const cd_sim *global, double *total)
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
    /* the leaves: a function of the global counts only (kernels/observe_items.h) */
    leaf_plan lp;
    lp.particles = 0;
    lp.pairs = ((long long)gs->n_particles + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK;
    lp.walls = lp.pairs + cd_obs_pair_blocks((cd_long)gs->n_prims);
    lp.n = lp.walls + ((long long)(gs->n_prims * gs->n_walls) + CD_OBS_BLOCK - 1) / CD_OBS_BLOCK;
    plan_levels(&lp, x->size);
    partials leaves = {NULL, 0, 0}, groups = {NULL, 0, 0};
    /* (a rank out of memory stops all: the others wait in the exchanges) */
    if (particle_leaves(x, global, touch, lp, &leaves) || pair_leaves(x, global, lp, &leaves) ||
        wall_leaves(x, global, lp, &leaves) || merge_own_groups(&leaves, lp, &groups) ||
        gather_partials(x, (const char *)groups.p, (int)(groups.n * sizeof *groups.p), sizeof *groups.p, total,
                        CD_OBS_SLOTS, merge_groups))
        MPI_Abort(x->comm, 1);
    x->reduces++;
    free(touch);
    free(leaves.p);
    free(groups.p);
    return 0;
}
