/* Structure of the packing (docs/references.md, Analysis).
 *
 * G(r): reference particles are those in the core region (away from the
 * walls, analyze_geometry.c); every particle counts as a neighbour.  With
 * N_ref reference particles at number density rho = N_ref / V_core,
 *   G(r) = (pairs at distance in [r, r + dr]) / (N_ref rho dV(r)),
 * dV the exact shell volume (3D: 4/3 pi ((r+dr)^3 - r^3); 2D: pi ((r+dr)^2
 * - r^2) with the area density; pseudo-2D: the part of the shell inside a
 * slab of the centres' thickness, below), so that G -> 1 for an ideal gas.
 * Conzelmann et al. print 4 r^2 dr without the pi; capdem keeps it
 * (docs/references.md, Analysis).  r_max
 * does not exceed the smallest margin, so no shell around a reference
 * particle reaches a wall.  Pairs are found with a cell list (cells of
 * r_max / 4, only the cells within reach of the sphere), never all pairs.
 *
 * rho(r) = N(r) / N_inf (Tran et al. 2024, eq. 8): N(r) the mean number of centres
 * within r of a reference particle, N_inf = N(r_max).
 *
 * Branch vectors (Tran et al. 2024, section 3.2): centre-to-centre vectors of the bonds
 * (touching particle pairs); PDF of l / L and interlocking
 * lambda = 1 - <l> / L, L the tip-to-tip length of the largest shape. */
#include "analysis/analyze.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

/* Volume of the part of a ball of radius r around a point in a slab of
 * thickness T, averaged over points uniform across the slab, integrated:
 * the sphere of radius s has area 2 pi s h inside the slab, h = 2s - s^2/T
 * on average for s < T and T beyond, so this is int_0^r 2 pi s <h> ds. */
static double slab_ball(double r, double T)
{
    if (r <= T) return 2 * CD_PI * (2 * r * r * r / 3 - r * r * r * r / (4 * T));
    return 2 * CD_PI * (2 * T * T * T / 3 - T * T * T / 4) + CD_PI * T * (r * r - T * T);
}

int cd_an_rdf(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen)
{
    const cd_an_snapshot *s = in->s;
    const cd_an_geometry *g = in->g;
    if (g->kind == CD_AN_FREE || !(g->core_volume > 0)) {
        snprintf(err, errlen, "%s: no G(r): %s", s->path, g->note[0] ? g->note : "no core region");
        return 2;
    }
    double L = g->L;
    double rmax = fmin(g->margin_side, 5 * L); /* [m] */
    if (g->kind != CD_AN_BALL) rmax = fmin(rmax, g->margin_end);
    if (in->opt->rdf_max > 0) rmax = in->opt->rdf_max * L;
    double dr = (in->opt->rdf_bin > 0 ? in->opt->rdf_bin : 0.02) * L; /* [m] */
    int nb = (int)ceil(rmax / dr - 1e-9);
    if (nb < 1 || nb > 1000000) {
        snprintf(err, errlen, "%s: G(r): %d bins for r_max %g L and bin %g L", s->path, nb, rmax / L, dr / L);
        return 2;
    }
    rmax = nb * dr;
    int dim = g->dim;
    size_t *ref = malloc((s->n ? s->n : 1) * sizeof(size_t));
    if (!ref) {
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    size_t nref = 0;
    double zs = 0, zz = 0;
    for (size_t p = 0; p < s->n; p++) {
        if (cd_an_in_core(g, s->pos[p])) ref[nref++] = p;
        zs += s->pos[p].z;
        zz += s->pos[p].z * s->pos[p].z;
    }
    if (nref == 0) {
        free(ref);
        if (g->kind == CD_AN_BALL)
            snprintf(err, errlen,
                     "%s: no G(r): no particle centre lies in the core region (%.3g L from the ball); "
                     "set --margins",
                     s->path, g->margin_side / L);
        else
            snprintf(err, errlen,
                     "%s: no G(r): no particle centre lies in the core region (%.3g L from the side "
                     "walls, %.3g L from floor and top); set --margins",
                     s->path, g->margin_side / L, g->margin_end / L);
        return 2;
    }
    /* Pseudo-2D: the centres fill a slab; its thickness from the spread of
     * their z (a uniform layer of thickness T has standard deviation
     * T / sqrt(12)). */
    double slab = 0;
    double vref = g->core_volume; /* [m^3], 2D [m^2] */
    if (g->kind == CD_AN_PSEUDO2D) {
        double mz = zs / (double)s->n, var = fmax(zz / (double)s->n - mz * mz, 0);
        slab = fmax(sqrt(12 * var), 1e-6 * L);
        vref = g->core_volume / (g->hi[2] - g->lo[2]) * slab;
    }
    double dens = (double)nref / vref; /* [1/m^3], 2D [1/m^2] */

    cd_an_cells cells;
    if (cd_an_cells_build(&cells, s->pos, s->n, 0.25 * rmax, dim)) {
        free(ref);
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    double *hist = calloc((size_t)nb, sizeof(double));
    int R = (int)ceil(rmax / cells.cs);
    double r2max = rmax * rmax, inv_dr = 1 / dr;
    const cd_vec3 *X = cells.x;      /* positions in cell order */
    const size_t *item = cells.item; /* local copies: the histogram stores cannot alias them */
#pragma omp parallel
    {
        uint64_t *h = calloc((size_t)nb, sizeof(uint64_t));
#pragma omp for schedule(dynamic, 256)
        for (size_t a = 0; a < nref; a++) {
            if (!h) continue;
            size_t i = ref[a];
            cd_vec3 xi = s->pos[i];
            int c[3];
            cd_an_cells_coord(&cells, xi, c);
            int zlo = dim == 3 ? c[2] - R : 0, zhi = dim == 3 ? c[2] + R : 0;
            for (int kz = zlo; kz <= zhi; kz++) {
                /* distance from xi to the nearest point of the slab of
                 * cells kz (0 inside it) [m] */
                double gz = 0;
                if (dim == 3) {
                    double z0 = cells.lo[2] + kz * cells.cs;
                    gz = xi.z < z0 ? z0 - xi.z : xi.z > z0 + cells.cs ? xi.z - z0 - cells.cs : 0;
                }
                for (int ky = c[1] - R; ky <= c[1] + R; ky++) {
                    double y0 = cells.lo[1] + ky * cells.cs;
                    double gy = xi.y < y0 ? y0 - xi.y : xi.y > y0 + cells.cs ? xi.y - y0 - cells.cs : 0;
                    double rest = r2max - gy * gy - gz * gz;
                    if (rest <= 0) continue;
                    /* only the cells of this row within reach along x;
                     * the row's cells are one contiguous range */
                    double hx = sqrt(rest);
                    int kx0 = (int)floor((xi.x - hx - cells.lo[0]) / cells.cs);
                    int kx1 = (int)floor((xi.x + hx - cells.lo[0]) / cells.cs);
                    size_t t0, t1;
                    cd_an_cells_row(&cells, kx0, kx1, ky, kz, &t0, &t1);
                    for (size_t t = t0; t < t1; t++) {
                        double dx = X[t].x - xi.x, dy = X[t].y - xi.y;
                        double dz = dim == 3 ? X[t].z - xi.z : 0;
                        double d2 = dx * dx + dy * dy + dz * dz;
                        if (d2 >= r2max || item[t] == i) continue;
                        int bin = (int)(sqrt(d2) * inv_dr);
                        if (bin < nb) h[bin]++;
                    }
                }
            }
        }
#pragma omp critical
        for (int b = 0; h && b < nb; b++) hist[b] += (double)h[b];
        free(h);
    }
    cd_an_cells_free(&cells);

    cd_an_group *grp = cd_an_group_get(r, "rdf");
    cd_an_put(grp, "n_reference", (double)nref, "1");
    cd_an_put(grp, "number_density", dens, dim == 2 ? "1/m^2" : "1/m^3");
    cd_an_put(grp, "L", L, "m");
    cd_an_put(grp, "r_max_over_L", rmax / L, "1");
    cd_an_put(grp, "bin_over_L", dr / L, "1");
    if (slab > 0) cd_an_put(grp, "slab_thickness", slab, "m");
    double *c = cd_an_put_curve(grp, "rdf", (size_t)nb, "r_over_L,G,N,rho", "1,1,1,1");
    if (!c) {
        free(hist);
        free(ref);
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    double cum = 0, ninf = 0;
    for (int b = 0; b < nb; b++) ninf += hist[b];
    ninf /= (double)nref;
    for (int b = 0; b < nb; b++) {
        double r1 = b * dr, r2 = (b + 1) * dr, shell; /* [m] */
        if (dim == 2) shell = CD_PI * (r2 * r2 - r1 * r1);
        else if (slab > 0) shell = slab_ball(r2, slab) - slab_ball(r1, slab);
        else shell = 4.0 / 3.0 * CD_PI * (r2 * r2 * r2 - r1 * r1 * r1);
        cum += hist[b] / (double)nref;
        c[4 * b] = (b + 0.5) * dr / L;
        c[4 * b + 1] = hist[b] / ((double)nref * dens * shell);
        c[4 * b + 2] = cum;
        c[4 * b + 3] = ninf > 0 ? cum / ninf : 0;
    }
    free(hist);
    free(ref);
    return 0;
}

int cd_an_branch(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen)
{
    const cd_an_snapshot *s = in->s;
    const cd_an_bonds *b = in->b;
    if (b->n == 0) {
        snprintf(err, errlen, "%s: snapshot %d (step %lld) has no contacts: no branch vectors", s->path, s->snapshot,
                 s->step);
        return 2;
    }
    double L = in->g->L;
    double *x = malloc(b->n * sizeof(double));
    if (!x) {
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    double sl = 0, sl2 = 0, spair = 0; /* [m], [m^2], [1] */
    for (size_t q = 0; q < b->n; q++) {
        int i = b->i[q], j = b->j[q];
        double l = cd_v3_norm(cd_v3_sub(s->pos[j], s->pos[i]));
        /* per-pair length scale: mean tip-to-tip length of the two
         * particles with their polydisperse scale */
        double Lij =
            0.5 * (s->shapes[s->shape[i]].tip_length * s->scale[i] + s->shapes[s->shape[j]].tip_length * s->scale[j]);
        x[q] = l / L;
        sl += l;
        sl2 += l * l;
        spair += l / Lij;
    }
    double nb = (double)b->n;
    cd_an_group *g = cd_an_group_get(r, "branch");
    cd_an_put(g, "n_bonds", nb, "1");
    cd_an_put(g, "L", L, "m");
    cd_an_put(g, "mean_l", sl / nb, "m");
    cd_an_put(g, "mean_l2", sl2 / nb, "m^2");
    cd_an_put(g, "lambda", 1 - sl / nb / L, "1");
    cd_an_put(g, "lambda_pair", 1 - spair / nb, "1");
    const int bins = 100;
    const double w = 0.02;
    double counts[100];
    size_t over;
    cd_an_histogram(x, b->n, 0, w, bins, counts, NULL, &over);
    double *c = cd_an_put_curve(g, "pdf", (size_t)bins, "l_over_L,P,count", "1,1,1");
    for (int k = 0; c && k < bins; k++) {
        c[3 * k] = (k + 0.5) * w;
        c[3 * k + 1] = counts[k] / (nb * w);
        c[3 * k + 2] = counts[k];
    }
    cd_an_put(g, "pdf_fraction_above_2", (double)over / nb, "1");
    free(x);
    return 0;
}
