/* The Cartesian grid of sub-domains of an MPI run (docs/mpi.md,
 * "Decomposition"): which rank owns a point, which ranks keep a ghost of
 * it.  Plain C without MPI.  The grid decides only who computes what: the
 * trajectories are the same bits for every grid (docs/mpi.md,
 * "Determinism"). */
#include <math.h>
#include <stdio.h>
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

int cd_decomp_ghost_ranks(const cd_decomp_grid *g, const double x[3], int skip, int *out)
{
    int from[3], to[3], n = 0;
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
