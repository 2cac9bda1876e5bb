/* Broad phase: cell lists over the bounding spheres of particles, then of
 * their primitives, feeding a Verlet list of primitive pairs with a skin.  The list is rebuilt only when
 * some primitive end has moved more than half the skin since the last build
 * (every point of a segment moves at most as far as its farthest end, so no
 * pair can come into contact unseen).  Contact history is carried over by
 * matching the sorted (primitive i, primitive j) keys of the new list
 * against the old one.  Every result is independent of the thread count. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include "sim.h"
#include "../kernels/broadphase.h"
#include "../kernels/step_items.h"

/* Particles per block of the build: each block fills its own row buffer,
 * and the buffers are copied into the list in block order, so the rows
 * come out in one fixed order whatever the threads. */
#define CD_NB_BLOCK 64

struct cd_nb_block {
    cd_prim_id *rows; /* candidate j of the block's primitives, row after row */
    size_t n, cap;
};


void cd_neighbors_init(cd_neighbors *nb, double skin)
{
    memset(nb, 0, sizeof(*nb));
    nb->skin = skin;
    nb->force_rebuild = 1;
}

void cd_neighbors_free(cd_neighbors *nb)
{
    free(nb->gather_start);
    free(nb->gather_rows);
    free(nb->wall_start);
    free(nb->wall_rows);
    free(nb->cell_start);
    free(nb->cell_parts);
    free(nb->part_cell);
    free(nb->part_bound);
    free(nb->pair_count);
    for (size_t b = 0; b < nb->n_blocks; b++) free(nb->blocks[b].rows);
    free(nb->blocks);
    memset(nb, 0, sizeof(*nb));
}

static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap && *p) return 0;
    size_t n = need + need / 2 + 16;
    void *q = realloc(*p, n * elem);
    if (!q) return -1;
    *p = q;
    *cap = n;
    return 0;
}

static int build_gather(cd_sim *sim)
{
    cd_state *s = &sim->s;
    cd_neighbors *nb = &sim->nb;
    size_t cap_dummy = 0;
    if (!nb->gather_start) {
        nb->gather_start = calloc(s->n_particles + 1, sizeof(cd_int));
        if (!nb->gather_start) return -1;
    }
    if (grow((void **)&nb->gather_rows, &nb->gather_cap, 2 * s->n_pairs + 1, sizeof(cd_pair_id))) return -1;
    (void)cap_dummy;
    memset(nb->gather_start, 0, (s->n_particles + 1) * sizeof(cd_int));
    for (size_t k = 0; k < s->n_pairs; k++) {
        nb->gather_start[s->prim_particle[s->pair_prim_i[k]] + 1]++;
        nb->gather_start[s->prim_particle[s->pair_prim_j[k]] + 1]++;
    }
    for (size_t p = 0; p < s->n_particles; p++) nb->gather_start[p + 1] += nb->gather_start[p];
    /* Filling in pair order keeps every particle's rows ascending. */
    cd_int *fill = nb->pair_count; /* reuse as cursor: sized n_prims+1 >= n_particles */
    memcpy(fill, nb->gather_start, s->n_particles * sizeof(cd_int));
    /* Entries 2 k + side (kernels/step_items.h, cd_item_gather). */
    for (size_t k = 0; k < s->n_pairs; k++) {
        nb->gather_rows[fill[s->prim_particle[s->pair_prim_i[k]]]++] = (cd_pair_id)(2 * k);
        nb->gather_rows[fill[s->prim_particle[s->pair_prim_j[k]]]++] = (cd_pair_id)(2 * k + 1);
    }
    return 0;
}

/* The wall candidates of every particle (cd_item_wall_candidates): a
 * counting pass, the offsets, a filling pass; then the walls become the
 * reference of the wall-motion test. */
static int build_wall_lists(cd_sim *sim)
{
    cd_state *s = &sim->s;
    cd_neighbors *nb = &sim->nb;
    size_t N = s->n_particles, rows = s->n_prims * s->n_walls;
    if (rows > (size_t)INT32_MAX) {
        fprintf(stderr, "capdem: %zu primitive-wall rows exceed the wall lists' limit of %d\n", rows, INT32_MAX);
        return -1;
    }
    if (!nb->wall_start) nb->wall_start = calloc(N + 1, sizeof(cd_int));
    if (!nb->wall_rows) nb->wall_rows = malloc((rows + 1) * sizeof(cd_int));
    if (!nb->wall_start || !nb->wall_rows) return -1;
    cd_cols c = cd_sim_host_cols(s);
    const cd_wall *walls = s->walls;
    cd_int W = (cd_int)s->n_walls;
    cd_real skin = nb->skin;
    cd_int *start = nb->wall_start, *out = nb->wall_rows;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(N))
    for (size_t q = 0; q < N; q++) start[q + 1] = cd_item_wall_candidates(c, (cd_particle_id)q, walls, W, skin, NULL);
    start[0] = 0;
    for (size_t q = 0; q < N; q++) start[q + 1] += start[q];
#pragma omp parallel for schedule(static) if (CD_PARALLEL(N))
    for (size_t q = 0; q < N; q++) cd_item_wall_candidates(c, (cd_particle_id)q, walls, W, skin, out + start[q]);
    memcpy(nb->walls_ref, s->walls, sizeof nb->walls_ref);
    return 0;
}

/* Appends j to block b's rows (grows the buffer by half). */
static int block_push(struct cd_nb_block *b, cd_prim_id j)
{
    if (b->n == b->cap && grow((void **)&b->rows, &b->cap, b->n + 1, sizeof(cd_prim_id))) return -1;
    b->rows[b->n++] = j;
    return 0;
}

/* Bounding sphere of each particle about its centre of mass [m]
 * (cd_bp_particle_bound), the box of the centres and the largest bound. */
static double particle_bounds(const cd_state *s, double *bound, double lo[3], double hi[3])
{
    double rmax = 0;
    for (int k = 0; k < 3; k++) lo[k] = INFINITY, hi[k] = -INFINITY;
    for (size_t p = 0; p < s->n_particles; p++) {
        bound[p] = cd_bp_particle_bound(s->prim_a, s->prim_b, s->prim_radius, s->prim_first[p], s->prim_count[p],
                                        s->position[p]);
        cd_bp_bounds_add(lo, hi, &rmax, s->position[p], bound[p]);
    }
    return rmax;
}

/* Particles q > p whose bounding spheres come within the skin of p's, in
 * ascending order, into *list (grown as needed); returns how many.  (The
 * device's cd_bp_scan_prim makes the same scan once per primitive; here
 * the three arms of a hexapod share it.) */
static long particle_candidates(const cd_state *s, const cd_neighbors *nb, const cd_grid *g, size_t p,
                                cd_int **list, size_t *cap)
{
    cd_vec3 x = s->position[p];
    double reach0 = nb->part_bound[p] + nb->skin;
    cd_long cx = cd_grid_coord(g, x.x, 0), cy = cd_grid_coord(g, x.y, 1), cz = cd_grid_coord(g, x.z, 2);
    size_t n = 0;
    for (cd_long z = cz - 1; z <= cz + 1; z++) {
        if (z < 0 || z >= g->dim[2]) continue;
        for (cd_long y = cy - 1; y <= cy + 1; y++) {
            if (y < 0 || y >= g->dim[1]) continue;
            for (cd_long xx = cx - 1; xx <= cx + 1; xx++) {
                if (xx < 0 || xx >= g->dim[0]) continue;
                cd_long cell = (z * g->dim[1] + y) * g->dim[0] + xx;
                for (cd_int k = nb->cell_start[cell]; k < nb->cell_start[cell + 1]; k++) {
                    cd_int q = nb->cell_parts[k];
                    if ((size_t)q <= p) continue;
                    double reach = reach0 + nb->part_bound[q];
                    if (cd_v3_norm2(cd_v3_sub(s->position[q], x)) > reach * reach) continue;
                    if (n == *cap && grow((void **)list, cap, n + 1, sizeof(cd_int))) return -1;
                    cd_int m = (cd_int)n++; /* insertion keeps the list ascending */
                    while (m > 0 && (*list)[m - 1] > q) {
                        (*list)[m] = (*list)[m - 1];
                        m--;
                    }
                    (*list)[m] = q;
                }
            }
        }
    }
    return (long)n;
}

/* Rows of the primitives of particles [p0, p1) into block b: for each
 * primitive i, the primitives j of the candidate particles (ascending, so
 * the row is sorted by j) that pass the primitive test cd_bp_is_candidate;
 * count[i + 1] = the row's length. */
static int fill_block(const cd_state *s, const cd_neighbors *nb, const cd_grid *g, size_t p0, size_t p1,
                      struct cd_nb_block *b, cd_int **list, size_t *cap)
{
    b->n = 0;
    for (size_t p = p0; p < p1; p++) {
        long nq = particle_candidates(s, nb, g, p, list, cap);
        if (nq < 0) return -1;
        for (cd_int i = s->prim_first[p]; i < s->prim_first[p] + s->prim_count[p]; i++) {
            size_t before = b->n;
            for (long k = 0; k < nq; k++) {
                cd_int q = (*list)[k];
                for (cd_int j = s->prim_first[q]; j < s->prim_first[q] + s->prim_count[q]; j++)
                    if (cd_bp_is_candidate(s->prim_a[i], s->prim_b[i], s->prim_radius[i], s->prim_a[j], s->prim_b[j],
                                           s->prim_radius[j], nb->skin) &&
                        block_push(b, (cd_prim_id)j))
                        return -1;
            }
            nb->pair_count[i + 1] = (cd_int)(b->n - before);
        }
    }
    return 0;
}

/* The candidate pairs (i, j), i < j, of primitives of different particles
 * whose axes come within r_i + r_j + skin, sorted by i then j.  The scan
 * runs over particles (a grid of particle centres, particle bounding
 * spheres first): the three arms of a hexapod share one centre, and a
 * scan over primitives met each neighbour nine times.  The pairs are the
 * same set as the primitive test alone gives (the particle sphere holds
 * its primitives' spheres), in the same order.  One pass: each block of
 * CD_NB_BLOCK particles writes its rows into its own buffer. */
int cd_neighbors_build(cd_sim *sim)
{
    cd_state *s = &sim->s;
    cd_neighbors *nb = &sim->nb;
    size_t P = s->n_prims, N = s->n_particles;
    size_t nblocks = (N + CD_NB_BLOCK - 1) / CD_NB_BLOCK;
    if (!nb->part_cell) {
        nb->part_cell = malloc((N + 1) * sizeof(cd_int));
        nb->cell_parts = malloc((N + 1) * sizeof(cd_int));
        nb->part_bound = malloc((N + 1) * sizeof(double));
        nb->pair_count = malloc((P + 2) * sizeof(cd_int));
    }
    if (nb->n_blocks != nblocks) { /* first build (the particle count is fixed) */
        for (size_t b = 0; b < nb->n_blocks; b++) free(nb->blocks[b].rows);
        free(nb->blocks);
        nb->blocks = calloc(nblocks + 1, sizeof(struct cd_nb_block));
        nb->n_blocks = nblocks;
    }
    if (!nb->part_cell || !nb->cell_parts || !nb->part_bound || !nb->pair_count || !nb->blocks) return -1;

    /* Grid of particle centres; counting sort into cells, stable in particle order. */
    double lo[3], hi[3];
    double rmax = particle_bounds(s, nb->part_bound, lo, hi);
    for (int k = 0; k < 3; k++)
        if (!(hi[k] - lo[k] <= 1e12 * (2 * rmax + nb->skin))) return CD_NB_BLOWUP; /* NaN fails too */
    cd_grid g;
    cd_grid_make(&g, lo, hi, rmax, nb->skin, (cd_long)N);
    size_t ncell = (size_t)(g.dim[0] * g.dim[1] * g.dim[2]);
    free(nb->cell_start);
    nb->cell_start = calloc(ncell + 1, sizeof(cd_int));
    cd_int *cursor = malloc((ncell + 1) * sizeof(cd_int));
    if (!nb->cell_start || !cursor) { free(cursor); return -1; }
    for (size_t p = 0; p < N; p++) {
        nb->part_cell[p] = (cd_int)cd_grid_cell_of(&g, s->position[p]);
        nb->cell_start[nb->part_cell[p] + 1]++;
    }
    for (size_t c = 0; c < ncell; c++) nb->cell_start[c + 1] += nb->cell_start[c];
    memcpy(cursor, nb->cell_start, (ncell + 1) * sizeof(cd_int));
    for (size_t p = 0; p < N; p++) nb->cell_parts[cursor[nb->part_cell[p]]++] = (cd_int)p;
    free(cursor);

    /* The rows, block by block. */
    int failed = 0;
#pragma omp parallel if (CD_PARALLEL(P)) reduction(|| : failed)
    {
        cd_int *list = NULL;
        size_t cap = 0;
#pragma omp for schedule(dynamic, 1)
        for (size_t b = 0; b < nblocks; b++) {
            size_t p1 = (b + 1) * CD_NB_BLOCK < N ? (b + 1) * CD_NB_BLOCK : N;
            if (!failed) failed = fill_block(s, nb, &g, b * CD_NB_BLOCK, p1, &nb->blocks[b], &list, &cap) != 0;
        }
        free(list);
    }
    if (failed) return -1;
    cd_int *count = nb->pair_count;
    count[0] = 0;
    for (size_t i = 0; i < P; i++) count[i + 1] += count[i];
    size_t n_new = (size_t)count[P];
    /* Gather entries are 2 k + 1 in a cd_int (cd_item_gather). */
    if (n_new > (size_t)(INT32_MAX - 1) / 2) {
        fprintf(stderr, "capdem: %zu pair rows exceed the neighbour list's limit of %d\n", n_new, (INT32_MAX - 1) / 2);
        return -1;
    }

    /* Keep the old keys and history for matching. */
    size_t n_old = s->n_pairs;
    cd_ulong *old_keys = malloc((n_old + 1) * sizeof(cd_ulong));
    cd_vec3 *old_shear = malloc((n_old + 1) * sizeof(cd_vec3));
    cd_int *old_active = malloc((n_old + 1) * sizeof(cd_int));
    if (!old_keys || !old_shear || !old_active) { free(old_keys); free(old_shear); free(old_active); return -1; }
    for (size_t k = 0; k < n_old; k++) old_keys[k] = cd_bp_pair_key(s->pair_prim_i[k], s->pair_prim_j[k]);
    memcpy(old_shear, s->pair_shear, n_old * sizeof(cd_vec3));
    memcpy(old_active, s->pair_active, n_old * sizeof(cd_int));

    if (cd_state_reserve_pairs(s, n_new + n_new / 4 + 16)) { free(old_keys); free(old_shear); free(old_active); return -1; }
    s->n_pairs = n_new;

    /* Copy each block's rows into place and carry the history over. */
#pragma omp parallel for schedule(dynamic, 1) if (CD_PARALLEL(P))
    for (size_t b = 0; b < nblocks; b++) {
        size_t p1 = (b + 1) * CD_NB_BLOCK < N ? (b + 1) * CD_NB_BLOCK : N;
        cd_int i0 = s->prim_first[b * CD_NB_BLOCK], i1 = s->prim_first[p1 - 1] + s->prim_count[p1 - 1];
        const cd_prim_id *rows = nb->blocks[b].rows;
        for (cd_int i = i0; i < i1; i++)
            for (cd_int k = count[i]; k < count[i + 1]; k++) {
                cd_prim_id j = rows[k - count[i0]];
                s->pair_prim_i[k] = (cd_prim_id)i;
                s->pair_prim_j[k] = j;
                long o = cd_bp_find_key(old_keys, (cd_long)n_old, cd_bp_pair_key((cd_prim_id)i, j));
                s->pair_active[k] = o >= 0 ? old_active[o] : 0;
                s->pair_shear[k] = o >= 0 ? old_shear[o] : cd_v3_zero();
            }
    }
    free(old_keys);
    free(old_shear);
    free(old_active);

    if (build_gather(sim) || build_wall_lists(sim)) return -1;
    memcpy(s->prim_a_ref, s->prim_a, P * sizeof(cd_vec3));
    memcpy(s->prim_b_ref, s->prim_b, P * sizeof(cd_vec3));
    nb->force_rebuild = 0;
    nb->builds++;
    return 0;
}
