/* Uniform cell lists for the neighbour searches of the analysis (G(r), the
 * Monte Carlo packing fraction): points sorted by cell with a counting
 * sort, O(N) to build, so that no search ever loops over all pairs. */
#include "analysis/analyze.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

void cd_an_cells_coord(const cd_an_cells *c, cd_vec3 x, int ijk[3])
{
    const double v[3] = {x.x, x.y, x.z};
    for (int k = 0; k < 3; k++) {
        if (k >= c->dim) {
            ijk[k] = 0;
            continue;
        }
        double t = floor((v[k] - c->lo[k]) / c->cs);
        ijk[k] = t < 0 ? 0 : t >= c->n[k] ? c->n[k] - 1 : (int)t;
    }
}

int cd_an_cells_build(cd_an_cells *c, const cd_vec3 *x, size_t n, double cs, int dim)
{
    memset(c, 0, sizeof(*c));
    c->dim = dim;
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (size_t i = 0; i < n; i++) {
        const double v[3] = {x[i].x, x[i].y, x[i].z};
        for (int k = 0; k < 3; k++) {
            if (v[k] < lo[k]) lo[k] = v[k];
            if (v[k] > hi[k]) hi[k] = v[k];
        }
    }
    if (n == 0)
        for (int k = 0; k < 3; k++) lo[k] = hi[k] = 0;
    /* A sparse cloud in a big box would need more cells than points: grow
     * the cells until there are at most about 2 per point (a search of
     * radius r <= cs is still correct with bigger cells, just slower). */
    double ext[3];
    for (int k = 0; k < 3; k++) ext[k] = hi[k] - lo[k];
    if (!(cs > 0)) cs = 1;
    for (;;) {
        double cells = 1;
        for (int k = 0; k < dim; k++) cells *= floor(ext[k] / cs) + 1;
        if (cells <= 2.0 * (double)n + 64) break;
        cs *= 1.25;
    }
    c->cs = cs;
    c->ncell = 1;
    for (int k = 0; k < 3; k++) {
        c->lo[k] = lo[k];
        c->n[k] = k < dim ? (int)floor(ext[k] / cs) + 1 : 1;
        c->ncell *= (size_t)c->n[k];
    }
    c->start = calloc(c->ncell + 1, sizeof(size_t));
    c->item = malloc((n ? n : 1) * sizeof(size_t));
    size_t *cell_of = malloc((n ? n : 1) * sizeof(size_t));
    if (!c->start || !c->item || !cell_of) {
        free(cell_of);
        cd_an_cells_free(c);
        return -1;
    }
    for (size_t i = 0; i < n; i++) {
        int ijk[3];
        cd_an_cells_coord(c, x[i], ijk);
        cell_of[i] = ((size_t)ijk[2] * (size_t)c->n[1] + (size_t)ijk[1]) * (size_t)c->n[0] + (size_t)ijk[0];
        c->start[cell_of[i] + 1]++;
    }
    for (size_t k = 0; k < c->ncell; k++) c->start[k + 1] += c->start[k];
    size_t *fill = malloc((c->ncell ? c->ncell : 1) * sizeof(size_t));
    if (!fill) {
        free(cell_of);
        cd_an_cells_free(c);
        return -1;
    }
    memcpy(fill, c->start, c->ncell * sizeof(size_t));
    for (size_t i = 0; i < n; i++) c->item[fill[cell_of[i]]++] = i;
    free(fill);
    free(cell_of);
    /* A copy of the points in cell order: searches then stream through
     * memory instead of jumping through the caller's order. */
    c->x = malloc((n ? n : 1) * sizeof(cd_vec3));
    if (!c->x) {
        cd_an_cells_free(c);
        return -1;
    }
    for (size_t t = 0; t < n; t++) c->x[t] = x[c->item[t]];
    return 0;
}

void cd_an_cells_row(const cd_an_cells *c, int kx0, int kx1, int ky, int kz, size_t *t0, size_t *t1)
{
    *t0 = *t1 = 0;
    if (ky < 0 || ky >= c->n[1] || kz < 0 || kz >= c->n[2]) return;
    if (kx0 < 0) kx0 = 0;
    if (kx1 >= c->n[0]) kx1 = c->n[0] - 1;
    if (kx1 < kx0) return;
    size_t base = ((size_t)kz * (size_t)c->n[1] + (size_t)ky) * (size_t)c->n[0];
    *t0 = c->start[base + (size_t)kx0];
    *t1 = c->start[base + (size_t)kx1 + 1];
}

void cd_an_cells_free(cd_an_cells *c)
{
    free(c->start);
    free(c->item);
    free(c->x);
    memset(c, 0, sizeof(*c));
}
