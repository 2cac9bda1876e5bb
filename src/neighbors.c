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
#include "../kernels/segseg.h"

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
    double limit2 = 0.25 * sim->nb.skin * sim->nb.skin; /* (skin/2)^2 [m^2] */
    int moved = 0;
#pragma omp parallel for schedule(static) reduction(|| : moved) if (CD_PARALLEL(s->n_prims))
    for (size_t i = 0; i < s->n_prims; i++) {
        double da = cd_v3_norm2(cd_v3_sub(s->prim_a[i], s->prim_a_ref[i]));
        double db = cd_v3_norm2(cd_v3_sub(s->prim_b[i], s->prim_b_ref[i]));
        moved = moved || da > limit2 || db > limit2;
    }
    return moved;
}

/* Uniform grid over the primitives' bounding-sphere centres. */
typedef struct {
    double lo[3];      /* lower corner [m] */
    double cell;       /* edge [m] */
    long dim[3];       /* cells per axis */
} grid_t;

static cd_vec3 prim_centre(const cd_state *s, size_t i) { return cd_v3_scale(cd_v3_add(s->prim_a[i], s->prim_b[i]), 0.5); }
static double prim_bound(const cd_state *s, size_t i)
{
    return 0.5 * cd_v3_norm(cd_v3_sub(s->prim_b[i], s->prim_a[i])) + s->prim_radius[i];
}

static long cell_coord(const grid_t *g, double x, int axis)
{
    long c = (long)floor((x - g->lo[axis]) / g->cell);
    return c < 0 ? 0 : (c >= g->dim[axis] ? g->dim[axis] - 1 : c);
}

static long cell_of(const grid_t *g, cd_vec3 p)
{
    return (cell_coord(g, p.z, 2) * g->dim[1] + cell_coord(g, p.y, 1)) * g->dim[0] + cell_coord(g, p.x, 0);
}

static void make_grid(const cd_state *s, double skin, grid_t *g)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double rmax = 0;
    for (size_t i = 0; i < s->n_prims; i++) {
        cd_vec3 c = prim_centre(s, i);
        double v[3] = {c.x, c.y, c.z};
        for (int k = 0; k < 3; k++) {
            if (v[k] < lo[k]) lo[k] = v[k];
            if (v[k] > hi[k]) hi[k] = v[k];
        }
        double r = prim_bound(s, i);
        if (r > rmax) rmax = r;
    }
    g->cell = 2 * rmax + skin;
    /* Keep the number of cells of the order of the number of primitives so
     * that memory and the empty-cell scan stay linear in N. */
    for (;;) {
        double cells = 1;
        for (int k = 0; k < 3; k++) {
            g->lo[k] = lo[k];
            g->dim[k] = (long)floor((hi[k] - lo[k]) / g->cell) + 1;
            cells *= (double)g->dim[k];
        }
        if (cells <= 8.0 * (double)s->n_prims + 64) break;
        g->cell *= 1.26;
    }
}

/* Candidate test: bounding spheres, then the exact axis distance. */
static int is_candidate(const cd_state *s, size_t i, size_t j, double skin)
{
    double reach = s->prim_radius[i] + s->prim_radius[j] + skin;
    double rb = prim_bound(s, i) + prim_bound(s, j) + skin;
    if (cd_v3_norm2(cd_v3_sub(prim_centre(s, i), prim_centre(s, j))) > rb * rb) return 0;
    cd_real u, w;
    cd_segseg_closest(s->prim_a[i], s->prim_b[i], s->prim_a[j], s->prim_b[j], &u, &w);
    cd_vec3 d = cd_v3_sub(cd_v3_lerp(s->prim_a[j], s->prim_b[j], w), cd_v3_lerp(s->prim_a[i], s->prim_b[i], u));
    return cd_v3_norm2(d) <= reach * reach;
}

/* Visits the candidates j > i of primitive i; writes them to out (if not
 * NULL) in ascending order and returns how many there are. */
static cd_int scan_prim(const cd_state *s, const grid_t *g, const cd_int *cell_start, const cd_int *cell_prims,
                        size_t i, double skin, cd_prim_id *out)
{
    cd_vec3 c = prim_centre(s, i);
    long cx = cell_coord(g, c.x, 0), cy = cell_coord(g, c.y, 1), cz = cell_coord(g, c.z, 2);
    cd_int n = 0;
    for (long z = cz - 1; z <= cz + 1; z++) {
        if (z < 0 || z >= g->dim[2]) continue;
        for (long y = cy - 1; y <= cy + 1; y++) {
            if (y < 0 || y >= g->dim[1]) continue;
            for (long x = cx - 1; x <= cx + 1; x++) {
                if (x < 0 || x >= g->dim[0]) continue;
                long cell = (z * g->dim[1] + y) * g->dim[0] + x;
                for (cd_int k = cell_start[cell]; k < cell_start[cell + 1]; k++) {
                    size_t j = (size_t)cell_prims[k];
                    if (j <= i || s->prim_particle[j] == s->prim_particle[i]) continue;
                    if (!is_candidate(s, i, j, skin)) continue;
                    if (out) {
                        /* insertion keeps the row sorted by j */
                        cd_int m = n;
                        while (m > 0 && out[m - 1] > (cd_prim_id)j) { out[m] = out[m - 1]; m--; }
                        out[m] = (cd_prim_id)j;
                    }
                    n++;
                }
            }
        }
    }
    return n;
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

/* Key of a primitive pair, ordered by i then j. */
static cd_ulong pair_key(cd_prim_id i, cd_prim_id j) { return ((cd_ulong)(cd_uint)i << 32) | (cd_uint)j; }

/* Index of key in the sorted old keys, or -1. */
static long find_key(const cd_ulong *keys, size_t n, cd_ulong key)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (keys[mid] < key) lo = mid + 1; else hi = mid;
    }
    return (lo < n && keys[lo] == key) ? (long)lo : -1;
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
    grid_t g;
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
        nb->prim_cell[i] = (cd_int)cell_of(&g, prim_centre(s, i));
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
    for (size_t k = 0; k < n_old; k++) old_keys[k] = pair_key(s->pair_prim_i[k], s->pair_prim_j[k]);
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
            long o = find_key(old_keys, n_old, pair_key((cd_prim_id)i, s->pair_prim_j[k]));
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
