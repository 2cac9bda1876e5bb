/* The sub-domains of an MPI run (docs/mpi.md, "Decomposition"): a
 * Cartesian grid or a recursive coordinate bisection; which rank owns a
 * point, which ranks keep a ghost of it, which ranks are neighbours.
 * Plain C without MPI.  The grid decides only who computes what: the
 * trajectories are the same bits for every grid (docs/mpi.md,
 * "Determinism"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "mpi/mpi_decomp.h"

static const char axis_name[3] = {'x', 'y', 'z'};

/* Sub-domains along each axis at most: every one at least `range` [m] wide
 * (the inner ones; an axis of no extent takes one). */
static void most_per_axis(const double lo[3], const double hi[3], double range, long most[3])
{
    for (int a = 0; a < 3; a++) {
        double e = hi[a] - lo[a]; /* [m] */
        most[a] = range > 0 && e > 0 ? (long)floor(e / range) : 1;
        if (most[a] < 1) most[a] = 1;
    }
}

/* The grid of `ranks` sub-domains with the smallest total cut area,
 * leaving `keep` (the gravity axis, -1: none) whole when that is possible
 * (a settling pile fills the bottom of its box: cuts across gravity would
 * leave the upper sub-domains empty).  0, or -1 when no grid fits. */
static int auto_dims(int ranks, const long most[3], const double lo[3], const double hi[3], int dimension, int keep,
                     int dims[3])
{
    double best = INFINITY;
    int found = 0;
    for (int pass = 0; pass < 2 && !found; pass++) /* pass 0: keep the gravity axis whole */
        for (int px = 1; px <= ranks; px++)
            for (int py = 1; px * py <= ranks; py++) {
                if (ranks % (px * py)) continue;
                int p[3] = {px, py, ranks / (px * py)};
                if (dimension == 2 && p[2] != 1) continue;
                if (pass == 0 && keep >= 0 && p[keep] != 1) continue;
                int fits = 1;
                for (int a = 0; a < 3; a++) fits &= p[a] <= most[a];
                if (!fits) continue;
                double area = 0, e[3]; /* cut area [m^2]: (cuts along a) x (face of a) */
                for (int a = 0; a < 3; a++) e[a] = hi[a] - lo[a] > 0 ? hi[a] - lo[a] : 1;
                if (dimension == 2) e[2] = 1;
                for (int a = 0; a < 3; a++) area += (p[a] - 1) * e[(a + 1) % 3] * e[(a + 2) % 3];
                if (area < best) {
                    best = area;
                    for (int a = 0; a < 3; a++) dims[a] = p[a];
                    found = 1;
                }
            }
    return found ? 0 : -1;
}

int cd_decomp_choose(cd_decomp_grid *g, const cd_config *cfg, int ranks, const double lo[3], const double hi[3],
                     double range, double margin, char *err, size_t errlen)
{
    long most[3];
    most_per_axis(lo, hi, range, most);
    if (cfg->dimension == 2) most[2] = 1;
    const double *want = cfg->mpi_grid;
    int given = want[0] != 0 || want[1] != 0 || want[2] != 0;
    if (given) {
        long prod = 1;
        for (int a = 0; a < 3; a++) {
            if (!(want[a] >= 1 && want[a] <= 1e6 && want[a] == floor(want[a]))) {
                snprintf(err, errlen,
                         "%s: mpi.grid = [%g, %g, %g]: expected three integers >= 1 (sub-domains along x, "
                         "y, z), or [0, 0, 0] to let the ranks and the domain choose",
                         cfg->source_path, want[0], want[1], want[2]);
                return -1;
            }
            g->dims[a] = (int)want[a];
            prod *= g->dims[a];
        }
        if (prod != ranks) {
            snprintf(err, errlen,
                     "%s: mpi.grid = [%d, %d, %d] makes %ld sub-domains, but the run has %d MPI ranks: "
                     "expected a grid whose product is %d (or [0, 0, 0])",
                     cfg->source_path, g->dims[0], g->dims[1], g->dims[2], prod, ranks, ranks);
            return -1;
        }
        for (int a = 0; a < 3; a++)
            if (g->dims[a] > most[a]) {
                snprintf(err, errlen,
                         "%s: mpi.grid = [%d, %d, %d]: %d sub-domains along %c, but the particle centres "
                         "span %g m there and a sub-domain must be at least the interaction range %g m wide (largest "
                         "bounding diameter + skin): at most %ld along %c%s",
                         cfg->source_path, g->dims[0], g->dims[1], g->dims[2], g->dims[a], axis_name[a], hi[a] - lo[a],
                         range, most[a], axis_name[a], cfg->dimension == 2 && a == 2 ? " in 2D" : "");
                return -1;
            }
    } else {
        int keep = -1;
        double gmax = 0;
        for (int a = 0; a < 3; a++)
            if (fabs(cfg->gravity[a]) > gmax) gmax = fabs(cfg->gravity[a]), keep = a;
        if (auto_dims(ranks, most, lo, hi, cfg->dimension, keep, g->dims)) {
            snprintf(err, errlen,
                     "%s: %d MPI ranks: more than the domain can be split into: the particle centres span "
                     "[%g, %g, %g] m and a sub-domain must be at least the interaction range %g m wide (largest "
                     "bounding diameter + skin), so at most %ld x %ld x %ld sub-domains%s; run with fewer ranks",
                     cfg->source_path, ranks, hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], range, most[0], most[1],
                     most[2], cfg->dimension == 2 ? " (none along z in 2D)" : "");
            return -1;
        }
    }
    g->kind = CD_DECOMP_CARTESIAN;
    for (int a = 0; a < 3; a++) {
        g->lo[a] = lo[a];
        g->width[a] = hi[a] > lo[a] ? (hi[a] - lo[a]) / g->dims[a] : 1;
    }
    g->range = range;
    g->margin = margin;
    g->halo = range + margin;
    return 0;
}

/* Sub-domain coordinate of x along axis a, clamped to the grid. */
static int cell_of(const cd_decomp_grid *g, double x, int a)
{
    double c = floor((x - g->lo[a]) / g->width[a]);
    if (!(c >= 0)) return 0; /* NaN too */
    return c >= g->dims[a] ? g->dims[a] - 1 : (int)c;
}

static int rank_of(const cd_decomp_grid *g, const int c[3]) { return (c[2] * g->dims[1] + c[1]) * g->dims[0] + c[0]; }

int cd_decomp_owner(const cd_decomp_grid *g, const double x[3])
{
    if (g->kind == CD_DECOMP_RCB) { /* down the tree; a NaN goes below every cut */
        int k = 0, r0 = 0, n = g->dims[0];
        while (n > 1) {
            int low = n / 2;
            if (!(x[g->rcb_axis[k]] >= g->rcb_cut[k])) k += 1, n = low;
            else k += 2 * low, r0 += low, n -= low;
        }
        return r0;
    }
    int c[3];
    for (int a = 0; a < 3; a++) c[a] = cell_of(g, x[a], a);
    return rank_of(g, c);
}

/* Distance [m] from x to the interval of sub-domain coordinate c along a
 * (the outer intervals open to infinity). */
static double gap(const cd_decomp_grid *g, double x, int a, int c)
{
    double lo = g->lo[a] + c * g->width[a], hi = g->lo[a] + (c + 1) * g->width[a];
    if (c > 0 && x < lo) return lo - x;
    if (c < g->dims[a] - 1 && x > hi) return x - hi;
    return 0;
}

/* Squared distance [m^2] from the point x to the box lo..hi. */
static double box_gap2(const double lo[3], const double hi[3], const double x[3])
{
    double d2 = 0;
    for (int a = 0; a < 3; a++) {
        double gap = x[a] < lo[a] ? lo[a] - x[a] : x[a] > hi[a] ? x[a] - hi[a] : 0;
        d2 += gap * gap;
    }
    return d2;
}

int cd_decomp_ghost_ranks(const cd_decomp_grid *g, const double x[3], int skip, int *out)
{
    int from[3], to[3], n = 0;
    if (g->kind == CD_DECOMP_RCB) { /* every box (a few hundred at most) */
        for (int r = 0; r < g->dims[0]; r++)
            if (r != skip && box_gap2(g->rcb_lo[r], g->rcb_hi[r], x) <= g->halo * g->halo) out[n++] = r;
        return n;
    }
    for (int a = 0; a < 3; a++) {
        from[a] = cell_of(g, x[a] - g->halo, a);
        to[a] = cell_of(g, x[a] + g->halo, a);
    }
    int c[3];
    for (c[2] = from[2]; c[2] <= to[2]; c[2]++)
        for (c[1] = from[1]; c[1] <= to[1]; c[1]++)
            for (c[0] = from[0]; c[0] <= to[0]; c[0]++) {
                double d2 = 0; /* [m^2] */
                for (int a = 0; a < 3; a++) d2 += gap(g, x[a], a, c[a]) * gap(g, x[a], a, c[a]);
                int r = rank_of(g, c);
                if (r != skip && d2 <= g->halo * g->halo) out[n++] = r;
            }
    return n; /* ascending: z slowest, x fastest, as rank_of numbers them */
}

void cd_decomp_box(const cd_decomp_grid *g, int r, double lo[3], double hi[3])
{
    if (g->kind == CD_DECOMP_RCB) {
        for (int a = 0; a < 3; a++) lo[a] = g->rcb_lo[r][a], hi[a] = g->rcb_hi[r][a];
        return;
    }
    int c[3] = {r % g->dims[0], r / g->dims[0] % g->dims[1], r / (g->dims[0] * g->dims[1])};
    for (int a = 0; a < 3; a++) {
        lo[a] = c[a] > 0 ? g->lo[a] + c[a] * g->width[a] : -INFINITY;
        hi[a] = c[a] < g->dims[a] - 1 ? g->lo[a] + (c[a] + 1) * g->width[a] : INFINITY;
    }
}

int cd_decomp_neighbors(const cd_decomp_grid *g, int rank, double reach, int *out)
{
    int n = 0, ranks = g->dims[0] * g->dims[1] * g->dims[2];
    double alo[3], ahi[3], blo[3], bhi[3];
    cd_decomp_box(g, rank, alo, ahi);
    for (int r = 0; r < ranks; r++) {
        if (r == rank) continue;
        cd_decomp_box(g, r, blo, bhi);
        double d2 = 0; /* [m^2] box to box; lo is never +inf nor hi -inf: no inf - inf */
        for (int a = 0; a < 3; a++) {
            double gap = fmax(0, fmax(blo[a] - ahi[a], alo[a] - bhi[a]));
            d2 += gap * gap;
        }
        if (d2 <= reach * reach) out[n++] = r;
    }
    return n;
}

/* ---- recursive coordinate bisection ---------------------------------------- */

typedef struct {
    double c;   /* [m] the coordinate along the cut axis */
    size_t idx; /* the particle: ties in index order, so every rank sorts alike */
} rcb_key;

static int cmp_rcb_key(const void *pa, const void *pb)
{
    const rcb_key *a = pa, *b = pb;
    if (a->c != b->c) return a->c < b->c ? -1 : 1;
    return a->idx < b->idx ? -1 : a->idx > b->idx;
}

/* Node k: ranks [r0, r0 + n) over the particles idx[0..m) in the box
 * lo..hi [m]; keys: scratch for m of them. */
static void rcb_split(cd_decomp_grid *g, int k, int r0, int n, size_t *idx, size_t m, const double *xyz, int dimension,
                      double lo[3], double hi[3], rcb_key *keys)
{
    if (n == 1) {
        g->rcb_axis[k] = -1;
        for (int a = 0; a < 3; a++) g->rcb_lo[r0][a] = lo[a], g->rcb_hi[r0][a] = hi[a];
        return;
    }
    /* the axis of the longest extent of these centres */
    int axis = 0;
    double best = -1;
    for (int a = 0; a < (dimension == 2 ? 2 : 3); a++) {
        double cmin = INFINITY, cmax = -INFINITY;
        for (size_t e = 0; e < m; e++) {
            double c = xyz[3 * idx[e] + (size_t)a];
            if (isfinite(c)) cmin = c < cmin ? c : cmin, cmax = c > cmax ? c : cmax;
        }
        if (cmax - cmin > best) best = cmax - cmin, axis = a;
    }
    for (size_t e = 0; e < m; e++) {
        double c = xyz[3 * idx[e] + (size_t)axis];
        keys[e] = (rcb_key){isfinite(c) ? c : -INFINITY, idx[e]};
    }
    qsort(keys, m, sizeof *keys, cmp_rcb_key);
    int low = n / 2;
    size_t m_low = m * (size_t)low / (size_t)n; /* the lower ranks' share of the particles */
    double cut;                                 /* [m] between the last particle below and the first above */
    if (m == 0) cut = isfinite(lo[axis]) && isfinite(hi[axis]) ? 0.5 * (lo[axis] + hi[axis]) : 0;
    else if (m_low == 0) cut = keys[0].c;
    else if (m_low == m) cut = nextafter(keys[m - 1].c, INFINITY);
    else cut = 0.5 * (keys[m_low - 1].c + keys[m_low].c);
    g->rcb_axis[k] = (signed char)axis;
    g->rcb_cut[k] = cut;
    /* the particles as the owner test splits them (below the cut: low) */
    size_t below = 0;
    for (size_t e = 0; e < m; e++) idx[e] = keys[e].idx;
    while (below < m && !(xyz[3 * idx[below] + (size_t)axis] >= cut)) below++;
    double mid_hi[3] = {hi[0], hi[1], hi[2]}, mid_lo[3] = {lo[0], lo[1], lo[2]};
    mid_hi[axis] = cut;
    mid_lo[axis] = cut;
    rcb_split(g, k + 1, r0, low, idx, below, xyz, dimension, lo, mid_hi, keys);
    rcb_split(g, k + 2 * low, r0 + low, n - low, idx + below, m - below, xyz, dimension, mid_lo, hi, keys);
}

int cd_decomp_make(cd_decomp_grid *g, const cd_config *cfg, int ranks, const double *xyz, size_t n, double range,
                   double margin, char *err, size_t errlen)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}; /* [m] */
    for (size_t q = 0; q < n; q++)
        for (int a = 0; a < 3; a++) {
            double c = xyz[3 * q + (size_t)a];
            if (isfinite(c)) lo[a] = c < lo[a] ? c : lo[a], hi[a] = c > hi[a] ? c : hi[a];
        }
    for (int a = 0; a < 3; a++)
        if (!(lo[a] <= hi[a])) lo[a] = hi[a] = 0;
    if (cfg->mpi_decomposition != CD_DECOMP_RCB)
        return cd_decomp_choose(g, cfg, ranks, lo, hi, range, margin, err, errlen);
    const double *want = cfg->mpi_grid;
    if (want[0] != 0 || want[1] != 0 || want[2] != 0) {
        snprintf(err, errlen,
                 "%s: mpi.grid = [%g, %g, %g] with mpi.decomposition = rcb: expected no mpi.grid (it sets the "
                 "cartesian grid; rcb cuts where the particles are)",
                 cfg->source_path, want[0], want[1], want[2]);
        return -1;
    }
    if (ranks > CD_RCB_MAX_RANKS || (size_t)ranks > n) {
        snprintf(err, errlen,
                 "%s: %d MPI ranks with mpi.decomposition = rcb: expected at most %d ranks and at most one per "
                 "particle (%zu particles); run with fewer ranks or mpi.decomposition: cartesian",
                 cfg->source_path, ranks, CD_RCB_MAX_RANKS, n);
        return -1;
    }
    size_t *idx = malloc((n + 1) * sizeof *idx);
    rcb_key *keys = malloc((n + 1) * sizeof *keys);
    if (!idx || !keys) {
        free(idx);
        free(keys);
        snprintf(err, errlen, "out of memory while cutting the domain for %d MPI ranks", ranks);
        return -1;
    }
    for (size_t q = 0; q < n; q++) idx[q] = q;
    g->kind = CD_DECOMP_RCB;
    g->dims[0] = ranks, g->dims[1] = g->dims[2] = 1;
    double all_lo[3] = {-INFINITY, -INFINITY, -INFINITY}, all_hi[3] = {INFINITY, INFINITY, INFINITY};
    rcb_split(g, 0, 0, ranks, idx, n, xyz, cfg->dimension, all_lo, all_hi, keys);
    free(idx);
    free(keys);
    g->range = range;
    g->margin = margin;
    g->halo = range + margin;
    /* as for the grid: a sub-domain at least the interaction range wide
     * where the centres' box bounds it */
    for (int r = 0; r < ranks; r++)
        for (int a = 0; a < 3; a++) {
            double w = fmin(g->rcb_hi[r][a], hi[a]) - fmax(g->rcb_lo[r][a], lo[a]); /* [m] */
            if ((isfinite(g->rcb_lo[r][a]) || isfinite(g->rcb_hi[r][a])) && w < range) {
                snprintf(err, errlen,
                         "%s: %d MPI ranks with mpi.decomposition = rcb: more than the domain can be split into: "
                         "the sub-domain of rank %d spans %g m along %c among the particle centres, and a "
                         "sub-domain must be at least the interaction range %g m wide (largest bounding "
                         "diameter + skin); run with fewer ranks",
                         cfg->source_path, ranks, r, w > 0 ? w : 0, axis_name[a], range);
                return -1;
            }
        }
    return 0;
}
