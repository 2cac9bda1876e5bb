/* Packing fraction, contact density and the effective-medium bulk modulus
 * (docs/references.md, Analysis; Tran et al. 2024, section 3.1, Fig. 3b and eq. 15).
 *
 * Container: sum of particle volumes (shape volume x scale^3) over the
 * container volume (box or cylinder up to the lid, piston or highest
 * particle point, whichever is lower; ball of the snapshot's radius).  In
 * 2D the area fraction: each particle's slice z = 0 of its body frame (the
 * plane of motion) over the box area.
 *
 * Core region: Monte Carlo.  M points uniform in the core region are tested
 * against the union of all capsules (cell list of the capsules keyed by
 * their midpoints), giving an unbiased estimate with binomial standard
 * error sqrt(Phi (1 - Phi) / M) -- overlaps between particles and the
 * particles cut by the core boundary are counted exactly, which assigning
 * each particle's volume to its centre does not do (that estimate is
 * reported beside it; its error is of order the boundary layer, L x core
 * surface / core volume, and it double counts contact overlaps).
 *
 * K_t = n_c k <l^2> / 9 (3D; Tran et al. 2024, eq. 15): n_c contacts per unit
 * volume, <l^2> the mean square branch length per contact, k the stiffness
 * of one contact, which in capdem is k_n / 2 (two particle springs in series,
 * docs/references.md, Contact law; Tran et al. 2024's k_n is the contact stiffness).  In 2D the affine
 * estimate reads n_c k <l^2> / 4 with n_c per unit area (a modulus in N/m). */
#include "analysis/analyze.h"
#include "core/rng.h"
#include <gsl/gsl_sort.h>
#include <gsl/gsl_statistics_double.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Inside the capsule (segment a-b, radius rad)? */
static int in_capsule(cd_vec3 p, cd_vec3 a, cd_vec3 b, double rad)
{
    cd_vec3 ab = cd_v3_sub(b, a), ap = cd_v3_sub(p, a);
    double l2 = cd_v3_norm2(ab);
    double t = l2 > 0 ? cd_clamp01(cd_v3_dot(ap, ab) / l2) : 0;
    return cd_v3_norm2(cd_v3_sub(ap, cd_v3_scale(ab, t))) < rad * rad;
}

/* Area of the slice z = 0 of a shape's body frame, on a 2048^2 grid;
 * *rel_err bounds the relative error by the boundary cells. */
static double shape_area2d(const cd_an_shape *sh, double *rel_err)
{
    const int n = 2048;
    double R = sh->bounding_radius, h = 2 * R / n; /* [m] */
    unsigned char *in = calloc((size_t)n * n, 1);
    if (!in) return 0;
    size_t inside = 0, boundary = 0;
    for (int iy = 0; iy < n; iy++)
        for (int ix = 0; ix < n; ix++) {
            cd_vec3 p = cd_v3(-R + (ix + 0.5) * h, -R + (iy + 0.5) * h, 0);
            for (int k = 0; k < sh->n_arms; k++) {
                const double *a = sh->arms[k];
                if (in_capsule(p, cd_v3(a[0], a[1], a[2]), cd_v3(a[3], a[4], a[5]), a[6])) {
                    in[(size_t)iy * n + ix] = 1;
                    inside++;
                    break;
                }
            }
        }
    for (int iy = 1; iy < n; iy++)
        for (int ix = 1; ix < n; ix++) {
            unsigned char v = in[(size_t)iy * n + ix];
            boundary += v != in[(size_t)iy * n + ix - 1] || v != in[(size_t)(iy - 1) * n + ix];
        }
    free(in);
    *rel_err = inside ? (double)boundary / (double)inside : 1;
    return (double)inside * h * h;
}

/* Uniform point in the core region (rejection from its bounding box). */
static cd_vec3 core_point(const cd_an_geometry *g, cd_rng *r)
{
    double ms = g->margin_side, me = g->margin_end;
    for (;;) {
        cd_vec3 p;
        if (g->kind == CD_AN_CYLINDER) {
            double rc = g->radius - ms;
            p = cd_v3(g->centre.x + cd_rng_range(r, -rc, rc), cd_rng_range(r, g->lo[1] + me, g->hi[1] - me),
                      g->centre.z + cd_rng_range(r, -rc, rc));
        } else if (g->kind == CD_AN_BALL) {
            double rc = g->radius - ms;
            p = cd_v3_add(g->centre,
                          cd_v3(cd_rng_range(r, -rc, rc), cd_rng_range(r, -rc, rc), cd_rng_range(r, -rc, rc)));
        } else {
            int thin = g->kind != CD_AN_BOX3D; /* 2D and pseudo-2D cores span the thickness */
            p = cd_v3(cd_rng_range(r, g->lo[0] + ms, g->hi[0] - ms), cd_rng_range(r, g->lo[1] + me, g->hi[1] - me),
                      thin ? cd_rng_range(r, g->lo[2], g->hi[2]) : cd_rng_range(r, g->lo[2] + ms, g->hi[2] - ms));
            if (g->kind == CD_AN_BOX2D) p.z = g->plane_z;
        }
        if (g->kind == CD_AN_BOX2D || g->kind == CD_AN_PSEUDO2D || cd_an_in_core(g, p)) return p;
    }
}

/* Monte Carlo solid fraction of the core; returns the fraction, -1 on
 * failure.  The points are drawn in blocks of 4096, each block with its own
 * random stream (the result does not depend on the number of threads), and
 * tested in cell order, against capsules also stored in cell order, so
 * that neighbouring points reuse the same cached capsules. */
static double core_fraction_mc(const cd_an_snapshot *s, const cd_an_geometry *g, long M)
{
    size_t P = s->n_prims;
    cd_vec3 *mid = malloc((P ? P : 1) * sizeof(cd_vec3));
    cd_vec3 *pts = malloc((size_t)(M > 0 ? M : 1) * sizeof(cd_vec3));
    if (!mid || !pts) {
        free(mid);
        free(pts);
        return -1;
    }
    double reach = 0; /* largest half-length + radius [m] */
    for (size_t q = 0; q < P; q++) {
        mid[q] = cd_v3_scale(cd_v3_add(s->prim_a[q], s->prim_b[q]), 0.5);
        double h = 0.5 * cd_v3_norm(cd_v3_sub(s->prim_b[q], s->prim_a[q])) + s->prim_radius[q];
        if (h > reach) reach = h;
    }
    const long block = 4096;
    long nblocks = (M + block - 1) / block;
#pragma omp parallel for schedule(static)
    for (long k = 0; k < nblocks; k++) {
        cd_rng r;
        cd_rng_seed(&r, 0x5eedULL + (uint64_t)k);
        long end = (k + 1) * block < M ? (k + 1) * block : M;
        for (long m = k * block; m < end; m++) pts[m] = core_point(g, &r);
    }
    cd_an_cells cells, pc;
    int bad = cd_an_cells_build(&cells, mid, P, reach, g->dim);
    free(mid);
    if (!bad && cd_an_cells_build(&pc, pts, (size_t)M, reach, g->dim)) {
        cd_an_cells_free(&cells);
        bad = 1;
    }
    free(pts);
    if (bad) return -1;
    /* capsules in cell order: ends a, b and radius */
    double *cap = malloc((P ? P : 1) * 7 * sizeof(double));
    if (!cap) {
        cd_an_cells_free(&cells);
        cd_an_cells_free(&pc);
        return -1;
    }
    for (size_t t = 0; t < P; t++) {
        size_t q = cells.item[t];
        double *c = cap + 7 * t;
        c[0] = s->prim_a[q].x, c[1] = s->prim_a[q].y, c[2] = s->prim_a[q].z;
        c[3] = s->prim_b[q].x, c[4] = s->prim_b[q].y, c[5] = s->prim_b[q].z;
        c[6] = s->prim_radius[q];
    }
    long hits = 0;
#pragma omp parallel for schedule(static) reduction(+ : hits)
    for (long m = 0; m < M; m++) {
        cd_vec3 p = pc.x[m];
        int c[3];
        cd_an_cells_coord(&cells, p, c);
        int hit = 0;
        int zlo = g->dim == 3 ? c[2] - 1 : 0, zhi = g->dim == 3 ? c[2] + 1 : 0;
        for (int kz = zlo; kz <= zhi && !hit; kz++)
            for (int ky = c[1] - 1; ky <= c[1] + 1 && !hit; ky++) {
                size_t t0, t1;
                cd_an_cells_row(&cells, c[0] - 1, c[0] + 1, ky, kz, &t0, &t1);
                for (size_t t = t0; t < t1 && !hit; t++) {
                    const double *q = cap + 7 * t;
                    hit = in_capsule(p, cd_v3(q[0], q[1], q[2]), cd_v3(q[3], q[4], q[5]), q[6]);
                }
            }
        hits += hit;
    }
    free(cap);
    cd_an_cells_free(&cells);
    cd_an_cells_free(&pc);
    return (double)hits / (double)M;
}

/* Distance used for the contact-density profile: from the axis
 * (cylinder), the centre (ball), the floor (box). */
static double profile_coord(const cd_an_geometry *g, cd_vec3 x)
{
    if (g->kind == CD_AN_CYLINDER) return hypot(x.x - g->centre.x, x.z - g->centre.z);
    if (g->kind == CD_AN_BALL) return cd_v3_norm(cd_v3_sub(x, g->centre));
    return x.y - g->lo[1];
}

int cd_an_packing(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen)
{
    const cd_an_snapshot *s = in->s;
    const cd_an_geometry *g = in->g;
    if (g->kind == CD_AN_FREE || !(g->volume > 0)) {
        snprintf(err, errlen, "%s: no packing fraction: %s", s->path, g->note[0] ? g->note : "no container");
        return 2;
    }
    cd_an_group *grp = cd_an_group_get(r, "packing");
    cd_an_put_text(grp, "container", "%s", cd_an_kind_name(g->kind));
    int two_d = g->dim == 2;
    double *meas = malloc(s->n_shapes * sizeof(double)); /* volume (area in 2D) per shape at scale 1 */
    if (!meas) {
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    double area_err = 0;
    for (int k = 0; k < s->n_shapes; k++) {
        double e = 0;
        meas[k] = two_d ? shape_area2d(&s->shapes[k], &e) : s->shapes[k].volume;
        if (e > area_err) area_err = e;
    }
    double total = 0, core_sum = 0; /* [m^3], 2D [m^2] */
    for (size_t p = 0; p < s->n; p++) {
        double sc = s->scale[p], v = meas[s->shape[p]] * sc * sc * (two_d ? 1 : sc);
        total += v;
        if (g->core_volume > 0 && cd_an_in_core(g, s->pos[p])) core_sum += v;
    }
    free(meas);
    const char *vu = two_d ? "m^2" : "m^3";
    cd_an_put(grp, "container_volume", g->volume, vu);
    cd_an_put(grp, "container_height", g->kind == CD_AN_BALL ? 2 * g->radius : g->hi[1] - g->lo[1], "m");
    cd_an_put(grp, "solid_volume", total, vu);
    cd_an_put(grp, "phi_container", total / g->volume, "1");
    if (two_d) {
        cd_an_put(grp, "area2d_rel_error", area_err, "1");
        /* the volume fraction of the box slab, as the time series of the
         * protocols give it in 2D */
        double vs = 0;
        for (size_t p = 0; p < s->n; p++) vs += cd_an_particle_volume(s, p);
        cd_an_put(grp, "phi_container_slab", vs / (g->volume * (g->hi[2] - g->lo[2])), "1");
    }
    if (g->core_volume > 0) {
        cd_an_put(grp, "core_volume", g->core_volume, vu);
        cd_an_put(grp, "phi_core_centres", core_sum / g->core_volume, "1");
        long M = in->opt->mc_points > 0 ? in->opt->mc_points : 1000000;
        double phi = core_fraction_mc(s, g, M);
        if (phi >= 0) {
            cd_an_put(grp, "phi_core", phi, "1");
            cd_an_put(grp, "phi_core_error", sqrt(phi * (1 - phi) / (double)M), "1");
            cd_an_put(grp, "mc_points", (double)M, "1");
        }
    } else {
        cd_an_put_text(grp, "core_note", "%s", g->note);
    }

    /* Contact density against distance from the axis / centre / floor, in
     * bins of L/4; the volume of a bin is the shell (ball), annulus x
     * height (cylinder) or slab (box) that it covers. */
    double L = g->L, w = 0.25 * L; /* [m] */
    double extent = g->kind == CD_AN_CYLINDER || g->kind == CD_AN_BALL ? g->radius : g->hi[1] - g->lo[1];
    int nb = (int)ceil(extent / w);
    if (nb < 1) nb = 1;
    if (nb > 100000) nb = 100000;
    double *cnt = calloc((size_t)nb, sizeof(double));
    if (!cnt) {
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    for (size_t c = 0; c < s->nc; c++) {
        cd_vec3 x = s->point[c];
        if (g->kind == CD_AN_CYLINDER && (x.y < g->lo[1] || x.y > g->hi[1])) continue;
        double d = profile_coord(g, x);
        int b = (int)floor(d / w);
        if (b >= 0 && b < nb) cnt[b] += 1;
    }
    double *c = cd_an_put_curve(grp, "contact_density", (size_t)nb, "r,n_c,count", two_d ? "m,1/m^2,1" : "m,1/m^3,1");
    for (int b = 0; c && b < nb; b++) {
        double r1 = b * w, r2 = fmin((b + 1) * w, extent), vol; /* [m] */
        if (g->kind == CD_AN_BALL) vol = 4.0 / 3.0 * CD_PI * (r2 * r2 * r2 - r1 * r1 * r1);
        else if (g->kind == CD_AN_CYLINDER) vol = CD_PI * (r2 * r2 - r1 * r1) * (g->hi[1] - g->lo[1]);
        else vol = (r2 - r1) * (g->hi[0] - g->lo[0]) * (two_d ? 1 : g->hi[2] - g->lo[2]);
        c[3 * b] = 0.5 * (r1 + r2);
        c[3 * b + 1] = vol > 0 ? cnt[b] / vol : 0;
        c[3 * b + 2] = cnt[b];
    }
    cd_an_put_text(grp, "contact_density_axis", "%s",
                   g->kind == CD_AN_CYLINDER ? "distance from the cylinder axis"
                   : g->kind == CD_AN_BALL   ? "distance from the ball centre"
                                             : "height above the floor");
    cd_an_put(grp, "contact_density_mean", (double)s->nc / g->volume, two_d ? "1/m^2" : "1/m^3");
    free(cnt);
    return 0;
}

int cd_an_modulus(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen)
{
    const cd_an_snapshot *s = in->s;
    const cd_an_geometry *g = in->g;
    const cd_an_bonds *b = in->b;
    if (!s->cfg_ok) {
        snprintf(err, errlen, "%s: no K_t: the config echoed in /parameters/config does not parse, so k_n is unknown",
                 s->path);
        return 2;
    }
    if (b->n == 0 || g->kind == CD_AN_FREE || !(g->volume > 0)) {
        snprintf(err, errlen, "%s: no K_t: %s", s->path,
                 b->n == 0    ? "the snapshot has no contacts"
                 : g->note[0] ? g->note
                              : "no container volume");
        return 2;
    }
    double sl2 = 0, sl2_core = 0; /* sums of l^2 over contacts [m^2] */
    size_t ncore = 0;
    for (size_t q = 0; q < b->n; q++) {
        double l2 = cd_v3_norm2(cd_v3_sub(s->pos[b->j[q]], s->pos[b->i[q]]));
        sl2 += b->k[q] * l2;
        if (g->core_volume > 0)
            for (int a = 0; a < b->k[q]; a++)
                if (cd_an_in_core(g, s->point[b->order[b->first[q] + (size_t)a]])) {
                    sl2_core += l2;
                    ncore++;
                }
    }
    double kc = 0.5 * s->cfg.kn;     /* contact stiffness [N/m] */
    double d2 = g->dim == 2 ? 4 : 9; /* dimension squared */
    const char *unit = g->dim == 2 ? "N/m" : "Pa";
    double nc = (double)s->nc / g->volume; /* [1/m^3], 2D [1/m^2] */
    cd_an_group *grp = cd_an_group_get(r, "modulus");
    cd_an_put(grp, "k_contact", kc, "N/m");
    cd_an_put(grp, "contact_density", nc, g->dim == 2 ? "1/m^2" : "1/m^3");
    cd_an_put(grp, "mean_l2_per_contact", sl2 / (double)s->nc, "m^2");
    cd_an_put(grp, "K_t", nc * kc * (sl2 / (double)s->nc) / d2, unit);
    if (ncore > 0) {
        double ncc = (double)ncore / g->core_volume;
        cd_an_put(grp, "core_contact_density", ncc, g->dim == 2 ? "1/m^2" : "1/m^3");
        cd_an_put(grp, "K_t_core", ncc * kc * (sl2_core / (double)ncore) / d2, unit);
    }
    /* The measured K of a bulk-modulus run, beside K_t (docs/references.md, Analysis): the
     * protocol keeps K of each probe in /walls/control slots 16.. and the
     * number of probes in slot 9; probe k has strain strain_min 10^k
     * (docs/protocols.md).  All probes are the linear response (K agrees
     * within 1 % from 1e-9 to 1e-6); the smallest strains carry the most
     * noise of the base state, so K_measured is the median of the probes. */
    int probes = s->n_control >= 32 && s->cfg.protocol_kind == CD_PROTOCOL_BULK ? (int)s->control[9] : 0;
    if (probes > 16) probes = 16;
    if (probes > 0) {
        double *c = cd_an_put_curve(grp, "probes", (size_t)probes, "strain,K", "1,Pa");
        for (int k = 0; c && k < probes; k++) {
            c[2 * k] = s->cfg.strain_min * pow(10, k);
            c[2 * k + 1] = s->control[16 + k];
        }
        double sorted[16];
        memcpy(sorted, s->control + 16, (size_t)probes * sizeof(double));
        gsl_sort(sorted, 1, (size_t)probes);
        double K = gsl_stats_median_from_sorted_data(sorted, 1, (size_t)probes); /* [Pa] */
        cd_an_put(grp, "K_measured", K, "Pa");
        cd_an_put(grp, "K_t_over_K", nc * kc * (sl2 / (double)s->nc) / d2 / K, "1");
    }
    return 0;
}
