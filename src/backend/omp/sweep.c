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
#include "reorder_items.h"

size_t cd_sweep_block = 512;
long cd_sweep_min_bytes = -1;
long cd_sweep_prefetch_min_bytes = -1;

#if CD_OFFLOAD
int cd_omp_sweep_lists(cd_sim *sim)
{
    (void)sim;
    return 0;
}

int cd_omp_sweep_interleaves(const cd_sim *sim)
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
 * cd_sweep_block particles, with the wall candidates of the block, and
 * then gathers, kicks and advances every particle q with q + lag below the
 * block's end (lag: the largest distance in slots between a row's two
 * particles, cd_omp_sweep_lists): by then every row of q has been
 * computed, and no row computed later touches q, so none reads a moved q.  The rows a
 * gather reads were written about lag particles before, not a whole pass
 * before, so they are still in the cache, and so is the particles' state
 * that the rows and the gather read (docs/performance.md, "Session 19,
 * the sweep").  Threads: each sweeps a range of particles and its rows;
 * the particles with a row into another range (the range's edges) wait
 * for a barrier, after which each thread gathers, kicks and advances its
 * own: until then nobody moves a particle that another thread's row
 * reads.  Where the step's state fits the cache (cd_omp_sweep_interleaves
 * says no) the same three loops run one after the other over all rows,
 * each split evenly among the threads, as the step ran before the sweep:
 * the interleaving only costs there. */

/* Rows ahead of the one computed whose primitive j's data the rows'
 * loop asks the cache for (sweep_rows_prefetch). */
#define CD_PREFETCH_ROWS 16

/* Asks the cache for what pair row k reads of its primitive j and j's
 * particle and will not find there: a row's primitive i is its loop's
 * sequential stream, which the processor's own prefetcher follows, while
 * j's slot jumps by up to the span, so beyond the L2 its reads wait on
 * the L3 or memory (docs/performance.md, "Session 21, rows' reads asked
 * for ahead").  Reads pair_prim_j[k], prim_particle[j] and prim_arm[j];
 * a prefetch changes no value. */
CD_INLINE_ALWAYS void prefetch_row_j(cd_cols c, cd_pair_id k)
{
    cd_prim_id j = c.pair_prim_j[k];
    cd_particle_id pj = c.prim_particle[j];
    cd_int r = cd_prim_arm_of(c, j);
    __builtin_prefetch(&c.prim_a[j]);
    if (r >= 0) __builtin_prefetch(&c.arm[r].b);
    __builtin_prefetch(&c.position[pj]);
    __builtin_prefetch(&c.velocity[pj]);
    __builtin_prefetch(&c.angvel[pj]);
    __builtin_prefetch(&c.mass[pj]);
    __builtin_prefetch(&c.prim_radius[j]);
}

/* The sweep's three loops, each a function of its own with every item
 * inlined (noinline, flatten: GCC otherwise called the items, 1.15x the
 * instructions of the step), so that each compiles as it did as a loop
 * over all rows: inlined into one function with the others, a hexapod's
 * pair row lost about 5 % to register allocation (docs/performance.md,
 * "Session 19, the sweep").  The pair rows k0 .. k1 - 1 (in the visiting
 * order visit, null: the rows' order), without and with the prefetch of
 * the row CD_PREFETCH_ROWS ahead (a constant of each loop: where the state
 * fits a core's L2 the prefetch only costs, 0.97-0.98x on 1,000
 * hexapods): */
#define CD_SWEEP_ROWS(name, prefetch)                                                                                  \
    __attribute__((noinline, flatten)) static void name(cd_cols c, const cd_int *visit, size_t k0, size_t k1,          \
                                                        cd_law_params law, cd_real dt, cd_real sin_parallel,           \
                                                        cd_int blend, cd_int outputs)                                  \
    {                                                                                                                  \
        for (size_t k = k0; k < k1; k++) {                                                                             \
            if (prefetch && k + CD_PREFETCH_ROWS < k1)                                                                 \
                prefetch_row_j(c, (cd_pair_id)cd_map(visit, (cd_long)(k + CD_PREFETCH_ROWS)));                         \
            cd_item_pair_force(c, (cd_pair_id)cd_map(visit, (cd_long)k), law, dt, sin_parallel, blend, outputs);       \
        }                                                                                                              \
    }
CD_SWEEP_ROWS(sweep_rows_plain, 0)
CD_SWEEP_ROWS(sweep_rows_prefetch, 1)

static void sweep_rows(int prefetch, cd_cols c, const cd_int *visit, size_t k0, size_t k1, const cd_step_params *p,
                       cd_int outputs)
{
    if (prefetch) sweep_rows_prefetch(c, visit, k0, k1, p->law, p->dt, p->sin_parallel, p->parallel_blend, outputs);
    else sweep_rows_plain(c, visit, k0, k1, p->law, p->dt, p->sin_parallel, p->parallel_blend, outputs);
}

/* the wall candidates e0 .. e1 - 1: */
__attribute__((noinline, flatten)) static void sweep_walls(cd_cols c, const cd_int *rows, cd_wall_entry *out, cd_int e0,
                                                           cd_int e1, const cd_wall *walls, cd_int W, cd_law_params law,
                                                           cd_real dt, cd_real sin_parallel, cd_int blend)
{
    for (cd_int e = e0; e < e1; e++) cd_item_wall_row(c, rows[e], out + e, walls, W, law, dt, sin_parallel, blend);
}

/* the gathers, kicks and next advances of particles q0 .. q1 - 1 (only
 * those with edge[q] == want where edge is not null), with next = 1 and
 * with next = 0 (a call's last step): next a constant in each loop, so the
 * gather's store of the force at the last step, and its test, leave the
 * steps' loop (callgrind, 10,000 spheres: 11.6 instructions a
 * particle-step); likewise physics.sphere_orientation (fixed: spheres
 * keep theirs), whose test cost 9.9 instructions a sphere-step as an
 * argument (callgrind, 1,000 spheres). */
#define CD_SWEEP_MOVE(name, next, fixed_spheres)                                                                       \
    __attribute__((noinline, flatten)) static int name(cd_cols c, cd_nb_lists d, size_t q0, size_t q1,                 \
                                                       const unsigned char *edge, int want, cd_vec3 gravity,           \
                                                       cd_int dimension, cd_real dt, cd_real limit2)                   \
    {                                                                                                                  \
        int moved = 0;                                                                                                 \
        for (size_t q = q0; q < q1; q++)                                                                               \
            if (!edge || edge[q] == want)                                                                              \
                moved |= cd_item_gather_kick_advance(c, (cd_particle_id)q, d.gather_start, d.gather_rows,              \
                                                     d.wall_start, d.wall_out, gravity, dimension, dt, limit2,         \
                                                     d.ref_pose, fixed_spheres, next);                                 \
        return moved;                                                                                                  \
    }
CD_SWEEP_MOVE(sweep_move_next, 1, 0)
CD_SWEEP_MOVE(sweep_move_next_fixed, 1, 1)
CD_SWEEP_MOVE(sweep_move_last, 0, 0) /* (no advance: no orientation) */

static int sweep_moves(int next, cd_cols c, cd_nb_lists d, size_t q0, size_t q1, const unsigned char *edge, int want,
                       const cd_step_params *p, cd_real limit2)
{
    if (!next) return sweep_move_last(c, d, q0, q1, edge, want, p->gravity, p->dimension, p->dt, limit2);
    return p->fixed_spheres ? sweep_move_next_fixed(c, d, q0, q1, edge, want, p->gravity, p->dimension, p->dt, limit2)
                            : sweep_move_next(c, d, q0, q1, edge, want, p->gravity, p->dimension, p->dt, limit2);
}

/* The sweep of particles q0 .. q1 - 1 (of n) and of their pair rows (the
 * rows of their primitives, d.pair_offset: the build's offsets, which the
 * rows keep until the next build); edge (null: none) marks the particles
 * left for after the barrier. */
static int sweep_range(cd_cols c, const cd_nb_lists *d, size_t q0, size_t q1, size_t n, size_t n_pairs, size_t lag,
                       const unsigned char *edge, const cd_step_params *p, const cd_wall *walls, cd_int W,
                       cd_real limit2, int next, int prefetch)
{
    int moved = 0;
    size_t done = q0; /* the next particle to move */
    for (size_t x0 = q0; x0 < q1; x0 += cd_sweep_block) {
        size_t x1 = x0 + cd_sweep_block < q1 ? x0 + cd_sweep_block : q1;
        size_t k0 = (size_t)d->pair_offset[c.prim_first[x0]];
        size_t k1 = x1 < n ? (size_t)d->pair_offset[c.prim_first[x1]] : n_pairs;
        sweep_rows(prefetch, c, NULL, k0, k1, p, !next);
        sweep_walls(c, d->wall_rows, d->wall_out, d->wall_start[x0], d->wall_start[x1], walls, W, p->wall_law, p->dt,
                    p->sin_parallel, p->parallel_blend);
        size_t ready = x1 == q1 ? q1 : x1 > done + lag ? x1 - lag : done; /* rows up to x1 - 1 computed */
        if (ready > done) {
            moved |= sweep_moves(next, c, *d, done, ready, edge, 0, p, limit2);
            done = ready;
        }
    }
    return moved;
}

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

/* Bytes of the columns the step holds (kernels/fields.def, on_device),
 * pair rows included, and of its gather lists and wall candidates: what
 * its passes stream. */
static size_t step_bytes(const cd_sim *sim)
{
    size_t b = 0;
    for (size_t f = 0; f < cd_n_fields; f++)
        if (cd_fields[f].on_device) b += cd_state_rows(&sim->s, cd_fields[f].group) * cd_fields[f].elem_size;
    b += (sim->s.n_particles + 1) * sizeof(cd_int) + 2 * sim->s.n_pairs * sizeof(cd_pair_id);
    return b + sim->nb.n_wall_rows * (sizeof(cd_int) + sizeof(cd_wall_entry));
}

/* Below about half the last-level cache the passes' data stays in it
 * from one pass to the next, and interleaving them only costs (10,000
 * hexapods, 13 MB: 0.94x; docs/performance.md, "Session 19, the sweep"):
 * the lag is then the whole range, all rows first.  16 MiB: half the L3
 * of a core complex of the development machine's EPYC (the C library's
 * sysconf reports the whole chip's 320 MiB there). */
int cd_omp_sweep_interleaves(const cd_sim *sim)
{
    return step_bytes(sim) > (cd_sweep_min_bytes >= 0 ? (size_t)cd_sweep_min_bytes : (size_t)16 << 20);
}

/* Beyond 4 MiB (four times a core's 1 MiB L2 on the development machine's
 * EPYC) a row's primitive j is asked for ahead (prefetch_row_j): 10,000
 * hexapods (13 MB) 1.03-1.05x, 30,000 1.16-1.19x; below, 1,000 hexapods
 * (1.3 MB) 0.97-0.98x (docs/performance.md, "Session 21, rows' reads
 * asked for ahead"). */
static int sweep_prefetches(const cd_sim *sim)
{
    return step_bytes(sim) > (cd_sweep_prefetch_min_bytes >= 0 ? (size_t)cd_sweep_prefetch_min_bytes : (size_t)4 << 20);
}

/* What the host threads' sweep (above)
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
    const cd_int *pi = c.pair_prim_i, *part = c.prim_particle;
    cd_ulong lag = 0;
    long unsorted = 0;
#pragma omp parallel for schedule(static) if (R >= (size_t)cd_parallel_min_rows) reduction(max : lag) reduction(+ : unsorted)
    for (size_t k = 0; k < R; k++) {
        cd_ulong d = cd_reorder_item_row_distance(c, (cd_long)k, NULL);
        lag = d > lag ? d : lag;
        unsorted += k > 0 && part[pi[k - 1]] > part[pi[k]];
    }
    if (unsorted) {
        fprintf(stderr, "capdem: internal error: %ld pair rows out of memory order after a neighbour-list build\n",
                unsorted);
        return -1;
    }
    nb->sweep_lag = cd_omp_sweep_interleaves(sim) ? (size_t)lag : n;
    nb->sweep_prefetch = sweep_prefetches(sim);
    nb->sweep_span = (size_t)lag;
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
    int made = sim->nb.sweep_threads, used = 1, moved = 0, interleave = lag < n, prefetch = sim->nb.sweep_prefetch;
    /* not interleaved: the passes as loops over all rows, each split evenly
     * among the threads (a mixture's pair rows kind by kind), a barrier
     * before the moves, as the step ran before the sweep */
    const cd_int *visit = sim->nb.n_visit && sim->nb.n_visit == n_pairs ? d.pair_visit : NULL;
    size_t n_walls = W ? sim->nb.n_wall_rows : 0;
#pragma omp parallel if (CD_PARALLEL(most)) reduction(| : moved)
    {
#ifdef _OPENMP
        size_t T = (size_t)omp_get_num_threads(), t = (size_t)omp_get_thread_num();
#else
        size_t T = 1, t = 0;
#endif
        size_t q0 = n * t / T, q1 = n * (t + 1) / T;
        if (!interleave) {
            sweep_rows(prefetch, c, visit, n_pairs * t / T, n_pairs * (t + 1) / T, &p, !next);
            sweep_walls(c, d.wall_rows, d.wall_out, (cd_int)(n_walls * t / T), (cd_int)(n_walls * (t + 1) / T), walls,
                        W, p.wall_law, p.dt, p.sin_parallel, p.parallel_blend);
#pragma omp barrier
            moved |= sweep_moves(next, c, d, q0, q1, NULL, 0, &p, limit2);
        } else {
            if (T > 1 && (int)T != made) { /* the same test in every thread */
                mark_edges(c, d, q0, q1, edge);
#pragma omp barrier
            }
            moved |=
                sweep_range(c, &d, q0, q1, n, n_pairs, lag, T > 1 ? edge : NULL, &p, walls, W, limit2, next, prefetch);
            if (T > 1) {
#pragma omp barrier
                moved |= sweep_moves(next, c, d, q0, q1, edge, 1, &p, limit2);
            }
            if (t == 0) used = (int)T;
        }
    }
    if (interleave && used > 1) sim->nb.sweep_threads = used;
    sim->nb.wall_out_valid = sim->nb.wall_out_pending = 1;
    return moved;
}
#endif
