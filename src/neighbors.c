/* Broad phase: cell lists over the bounding spheres of primitives feeding a
 * Verlet list of primitive pairs with a skin.  The list is rebuilt only when
 * some primitive end has moved more than half the skin since the last build
 * (every point of a segment moves at most as far as its farthest end, so no
 * pair can come into contact unseen).  Contact history is carried over by
 * matching the sorted (primitive i, primitive j) keys of the new list
 * against the old one.  Every result is independent of the thread count. */
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include "sim.h"
#include "../kernels/broadphase.h"

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
    free(nb->cell_start);
    free(nb->cell_prims);
    free(nb->prim_cell);
    free(nb->pair_count);
    memset(nb, 0, sizeof(*nb));
}

int cd_neighbors_needed(cd_sim *sim)
{
    if (sim->nb.force_rebuild) return 1;
    const cd_state *s = &sim->s;
    double limit2 = cd_bp_skin_limit2(sim->nb.skin); /* (skin/2)^2 [m^2] */
    int moved = 0;
#pragma omp parallel for schedule(static) reduction(|| : moved) if (CD_PARALLEL(s->n_prims))
    for (size_t i = 0; i < s->n_prims; i++)
        moved = moved || cd_bp_moved(s->prim_a[i], s->prim_a_ref[i], s->prim_b[i], s->prim_b_ref[i], limit2);
    return moved;
}

/* The grid of the primitives' bounding-sphere centres (kernels/broadphase.h). */
static void make_grid(const cd_state *s, double skin, cd_grid *g)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double rmax = 0;
    for (size_t i = 0; i < s->n_prims; i++) cd_bp_bounds_add(lo, hi, &rmax, s->prim_a[i], s->prim_b[i], s->prim_radius[i]);
    cd_grid_make(g, lo, hi, rmax, skin, (cd_long)s->n_prims);
}

/* Candidates j > i of primitive i, ascending, into out (if not NULL). */
static cd_int scan_prim(const cd_state *s, const cd_grid *g, const cd_int *cell_start, const cd_int *cell_prims,
                        size_t i, double skin, cd_prim_id *out)
{
    return cd_bp_scan_prim(s->prim_a, s->prim_b, s->prim_radius, s->prim_particle, g, cell_start, cell_prims,
                           (cd_prim_id)i, skin, out, CD_BP_UNBOUNDED);
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
    for (size_t k = 0; k < s->n_pairs; k++) {
        nb->gather_rows[fill[s->prim_particle[s->pair_prim_i[k]]]++] = (cd_pair_id)k;
        nb->gather_rows[fill[s->prim_particle[s->pair_prim_j[k]]]++] = (cd_pair_id)k;
    }
    return 0;
}

int cd_neighbors_build(cd_sim *sim)
{
    cd_state *s = &sim->s;
    cd_neighbors *nb = &sim->nb;
    size_t P = s->n_prims;
    double skin = nb->skin;
    cd_grid g;
    make_grid(s, skin, &g);
    size_t ncell = (size_t)(g.dim[0] * g.dim[1] * g.dim[2]);

    free(nb->cell_start);
    nb->cell_start = calloc(ncell + 1, sizeof(cd_int));
    if (!nb->prim_cell) {
        nb->prim_cell = malloc((P + 1) * sizeof(cd_int));
        nb->cell_prims = malloc((P + 1) * sizeof(cd_int));
        nb->pair_count = malloc((P + 2) * sizeof(cd_int));
    }
    if (!nb->cell_start || !nb->prim_cell || !nb->cell_prims || !nb->pair_count) return -1;

    /* Counting sort of primitives into cells, stable in primitive order. */
    for (size_t i = 0; i < P; i++) {
        nb->prim_cell[i] = (cd_int)cd_grid_cell_of(&g, cd_bp_centre(s->prim_a[i], s->prim_b[i]));
        nb->cell_start[nb->prim_cell[i] + 1]++;
    }
    for (size_t c = 0; c < ncell; c++) nb->cell_start[c + 1] += nb->cell_start[c];
    {
        cd_int *cursor = malloc((ncell + 1) * sizeof(cd_int));
        if (!cursor) return -1;
        memcpy(cursor, nb->cell_start, (ncell + 1) * sizeof(cd_int));
        for (size_t i = 0; i < P; i++) nb->cell_prims[cursor[nb->prim_cell[i]]++] = (cd_int)i;
        free(cursor);
    }

    /* Pass 1: count candidates per primitive; prefix sum gives row offsets. */
    cd_int *count = nb->pair_count;
#pragma omp parallel for schedule(dynamic, 256) if (CD_PARALLEL(P))
    for (size_t i = 0; i < P; i++) count[i + 1] = scan_prim(s, &g, nb->cell_start, nb->cell_prims, i, skin, NULL);
    count[0] = 0;
    for (size_t i = 0; i < P; i++) count[i + 1] += count[i];
    size_t n_new = (size_t)count[P];

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

    /* Pass 2: fill rows (sorted by i, then j) and carry history over. */
#pragma omp parallel for schedule(dynamic, 256) if (CD_PARALLEL(P))
    for (size_t i = 0; i < P; i++) {
        cd_int first = count[i];
        cd_int n = scan_prim(s, &g, nb->cell_start, nb->cell_prims, i, skin, s->pair_prim_j + first);
        for (cd_int k = first; k < first + n; k++) {
            s->pair_prim_i[k] = (cd_prim_id)i;
            long o = cd_bp_find_key(old_keys, (cd_long)n_old, cd_bp_pair_key((cd_prim_id)i, s->pair_prim_j[k]));
            s->pair_active[k] = o >= 0 ? old_active[o] : 0;
            s->pair_shear[k] = o >= 0 ? old_shear[o] : cd_v3_zero();
        }
    }
    free(old_keys);
    free(old_shear);
    free(old_active);

    if (build_gather(sim)) return -1;
    memcpy(s->prim_a_ref, s->prim_a, P * sizeof(cd_vec3));
    memcpy(s->prim_b_ref, s->prim_b, P * sizeof(cd_vec3));
    nb->force_rebuild = 0;
    nb->builds++;
    return 0;
}
