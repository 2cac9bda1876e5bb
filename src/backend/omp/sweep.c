/* The host threads' time step after the first advance of a call: one
 * sweep over the particles in memory order (docs/performance.md, "Session
 * 19, the sweep"), and what it needs of each neighbour-list build.  The
 * offload variant runs the same items as launches over every row
 * (src/backend/omp/step_omp.c, forces_and_advance) and needs nothing here. */
#include <stdio.h>
#include <stdlib.h>
#include "backend/omp/omp_loops.h"
#include "step_items.h"
#include "broadphase.h"

#if CD_OFFLOAD
int cd_omp_sweep_lists(cd_sim *sim)
{
    (void)sim;
    return 0;
}
#else
/* ---- the sweep: host threads' steps 5-8 and the next 1-4 ------------------
 *
 * One pass over the particles in memory order does a step's pair rows,
 * wall rows, gathers, kicks and next advances: the items of the three
 * loops of an offload device, each row and particle computed by the same
 * item on the same values, so the same bits.  The rows ascend by the slot
 * of their first particle; the sweep computes them block by block of
 * CD_SWEEP_BLOCK particles, with the wall candidates of the block, and
 * then gathers, kicks and advances every particle q with q + lag below the
 * block's end (lag: the largest distance in slots between a row's two
 * particles, cd_omp_sweep_lists): by then every row of q has been computed, and
 * no row computed later touches q, so none reads a moved q.  The rows a
 * gather reads were written about lag particles before, not a whole pass
 * before, so they are still in the cache, and so is the particles' state
 * that the rows and the gather read (docs/performance.md, "Session 19,
 * the sweep").  Threads: each sweeps a range of particles and its rows;
 * the particles with a row into another range (the range's edges) wait
 * for a barrier, after which each thread gathers, kicks and advances its
 * own: until then nobody moves a particle that another thread's row
 * reads. */
#define CD_SWEEP_BLOCK 512

/* The sweep of particles q0 .. q1 - 1 (of n) and of their pair rows (the
 * rows of their primitives, d.pair_offset: the build's offsets, which the
 * rows keep until the next build); edge (null: none) marks the particles
 * left for sweep_edges.  next: a constant in each caller. */
CD_INLINE_ALWAYS int sweep_range(cd_cols c, cd_nb_lists d, size_t q0, size_t q1, size_t n, size_t n_pairs, size_t lag,
                                 const unsigned char *edge, cd_step_params p, const cd_wall *walls, cd_int W,
                                 cd_real limit2, int next)
{
    int moved = 0;
    size_t done = q0; /* the next particle to move */
    for (size_t x0 = q0; x0 < q1; x0 += CD_SWEEP_BLOCK) {
        size_t x1 = x0 + CD_SWEEP_BLOCK < q1 ? x0 + CD_SWEEP_BLOCK : q1;
        size_t k1 = x1 < n ? (size_t)d.pair_offset[c.prim_first[x1]] : n_pairs;
        for (size_t k = (size_t)d.pair_offset[c.prim_first[x0]]; k < k1; k++)
            cd_item_pair_force(c, (cd_pair_id)k, p.law, p.dt, p.sin_parallel, p.parallel_blend, !next);
        for (cd_int w = d.wall_start[x0]; w < d.wall_start[x1]; w++)
            cd_item_wall_row(c, d.wall_rows[w], d.wall_out + w, walls, W, p.wall_law, p.dt, p.sin_parallel,
                             p.parallel_blend);
        size_t ready = x1 == q1 ? q1 : x1 > done + lag ? x1 - lag : done; /* rows up to x1 - 1 computed */
        for (; done < ready; done++)
            if (!edge || !edge[done])
                moved |=
                    cd_item_gather_kick_advance(c, (cd_particle_id)done, d.gather_start, d.gather_rows, d.wall_start,
                                                d.wall_out, p.gravity, p.dimension, p.dt, limit2, d.ref_pose, next);
    }
    return moved;
}

/* The edges of q0 .. q1 - 1, after the barrier. */
CD_INLINE_ALWAYS int sweep_edges(cd_cols c, cd_nb_lists d, size_t q0, size_t q1, const unsigned char *edge,
                                 cd_step_params p, cd_real limit2, int next)
{
    int moved = 0;
    for (size_t q = q0; q < q1; q++)
        if (edge[q])
            moved |= cd_item_gather_kick_advance(c, (cd_particle_id)q, d.gather_start, d.gather_rows, d.wall_start,
                                                 d.wall_out, p.gravity, p.dimension, p.dt, limit2, d.ref_pose, next);
    return moved;
}

/* sweep_range (edges 0) or sweep_edges (1) with next = 1 and with next =
 * 0 (a call's last step): next a constant in each loop, so the gather's
 * store of the force at the last step, and its test, leave the steps'
 * loop (callgrind, 10,000 spheres: 11.6 instructions a particle-step).
 * noinline and flatten: every item inlined (GCC otherwise called them:
 * 1.15x the instructions of the step). */
#define CD_SWEEP_FN(name, next)                                                                                        \
    __attribute__((noinline, flatten)) static int name(                                                                \
        cd_cols c, cd_nb_lists d, size_t q0, size_t q1, size_t n, size_t n_pairs, size_t lag,                          \
        const unsigned char *edge, cd_step_params p, const cd_wall *walls, cd_int W, cd_real limit2, int edges)        \
    {                                                                                                                  \
        return edges ? sweep_edges(c, d, q0, q1, edge, p, limit2, next)                                                \
                     : sweep_range(c, d, q0, q1, n, n_pairs, lag, edge, p, walls, W, limit2, next);                    \
    }
CD_SWEEP_FN(sweep_next, 1)
CD_SWEEP_FN(sweep_last, 0)

/* Marks the edges of the range q0 .. q1 - 1: the particles with a pair
 * row whose other particle is outside it. */
static void mark_edges(cd_cols c, cd_nb_lists d, size_t q0, size_t q1, unsigned char *edge)
{
    for (size_t q = q0; q < q1; q++) {
        unsigned char out = 0;
        for (cd_int r = d.gather_start[q]; r < d.gather_start[q + 1]; r++) {
            cd_pair_id e = d.gather_rows[r], k = e >> 1;
            size_t o = (size_t)c.prim_particle[e & 1 ? c.pair_prim_i[k] : c.pair_prim_j[k]];
            out |= o < q0 || o >= q1;
        }
        edge[q] = out;
    }
}

/* What the host threads' sweep (src/backend/omp/step_omp.c, "The sweep")
 * needs of new rows: its lag, the largest distance in memory slots between
 * the two particles of a row (a particle's rows are all computed once the
 * sweep's rows have passed its slot plus the lag), and room for the edges
 * of its threads' ranges, made again at the next step.  The rows must
 * ascend by the memory slot of their first particle (they ascend by the
 * slot of primitive i, pass 7, and a particle's primitives are
 * consecutive): checked here, since the sweep walks them so. */
int cd_omp_sweep_lists(cd_sim *sim)
{
    cd_neighbors *nb = &sim->nb;
    size_t n = sim->s.n_particles, R = sim->s.n_pairs;
    if (nb->sweep_edge_cap < n || !nb->sweep_edge) {
        unsigned char *edge = realloc(nb->sweep_edge, n + 1);
        if (!edge) return -1;
        nb->sweep_edge = edge;
        nb->sweep_edge_cap = n;
    }
    nb->sweep_threads = 0;
    cd_cols c = cd_sim_step_cols(sim);
    const cd_int *pi = c.pair_prim_i, *pj = c.pair_prim_j, *part = c.prim_particle;
    long lag = 0, unsorted = 0;
#pragma omp parallel for schedule(static) if (R >= (size_t)cd_parallel_min_rows) reduction(max : lag) reduction(+ : unsorted)
    for (size_t k = 0; k < R; k++) {
        long a = part[pi[k]], b = part[pj[k]];
        long d = a > b ? a - b : b - a;
        lag = d > lag ? d : lag;
        unsorted += k > 0 && part[pi[k - 1]] > a;
    }
    if (unsorted) {
        fprintf(stderr, "capdem: internal error: %ld pair rows out of memory order after a neighbour-list build\n",
                unsorted);
        return -1;
    }
    nb->sweep_lag = (size_t)lag;
    return 0;
}

int cd_omp_sweep(cd_sim *sim, int next)
{
    cd_cols c = cd_sim_step_cols(sim);
    cd_nb_lists d = sim->nb.d;
    cd_step_params p = sim->p;
    cd_real limit2 = cd_bp_skin_limit2(sim->nb.skin);
    cd_int W = (cd_int)sim->s.n_walls;
    const cd_wall *walls = sim->s.walls;
    size_t n = sim->s.n_particles, most = sim->s.n_pairs > n ? sim->s.n_pairs : n;
    unsigned char *edge = sim->nb.sweep_edge; /* n of them (each build makes room) */
    size_t lag = sim->nb.sweep_lag, n_pairs = sim->s.n_pairs;
    int made = sim->nb.sweep_threads, used = 1, moved = 0;
#pragma omp parallel if (CD_PARALLEL(most)) reduction(| : moved)
    {
#ifdef _OPENMP
        int T = omp_get_num_threads(), t = omp_get_thread_num();
#else
        int T = 1, t = 0;
#endif
        size_t q0 = n * (size_t)t / (size_t)T, q1 = n * (size_t)(t + 1) / (size_t)T;
        if (T > 1 && T != made) { /* the same test in every thread */
            mark_edges(c, d, q0, q1, edge);
#pragma omp barrier
        }
        const unsigned char *ed = T > 1 ? edge : NULL;
        moved |= next ? sweep_next(c, d, q0, q1, n, n_pairs, lag, ed, p, walls, W, limit2, 0)
                      : sweep_last(c, d, q0, q1, n, n_pairs, lag, ed, p, walls, W, limit2, 0);
        if (T > 1) {
#pragma omp barrier
            moved |= next ? sweep_next(c, d, q0, q1, n, n_pairs, lag, ed, p, walls, W, limit2, 1)
                          : sweep_last(c, d, q0, q1, n, n_pairs, lag, ed, p, walls, W, limit2, 1);
        }
        if (t == 0) used = T;
    }
    if (used > 1) sim->nb.sweep_threads = used;
    sim->nb.wall_out_valid = sim->nb.wall_out_pending = 1;
    return moved;
}

#endif
