/* Particle stresses (Conzelmann et al., eq. 8; docs/references.md, Analysis):
 *   sigma_p = (1/V_p) sum_c F_c (x) r_c,   (F (x) r)_ab = F_a r_b,
 * F_c the force on particle p at contact c (normal + tangential, wall
 * contacts included), r_c from the centre of p to the contact point, V_p
 * the particle volume (shape volume x scale^3).  Written as it stands, the
 * tensor is positive in tension: a compressed particle has I1 = trace < 0,
 * and i = I1 / <I1> is positive either way.  Principal stresses are the
 * eigenvalues of the symmetric part (the antisymmetric part is the net
 * torque / V, zero in equilibrium). */
#include "analysis/analyze.h"
#include "contact_law.h"
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_matrix.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

double cd_an_particle_volume(const cd_an_snapshot *s, size_t p)
{
    double sc = s->scale[p];
    return s->shapes[s->shape[p]].volume * sc * sc * sc;
}

/* sigma += F (x) r (9 entries, row-major) */
static void add_dyad(double *sigma, cd_vec3 F, cd_vec3 r)
{
    const double f[3] = {F.x, F.y, F.z}, v[3] = {r.x, r.y, r.z};
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) sigma[3 * a + b] += f[a] * v[b];
}

int cd_an_particle_stress(const cd_an_snapshot *s, double *sigma, int32_t *ncontacts)
{
    memset(sigma, 0, 9 * s->n * sizeof(double));
    memset(ncontacts, 0, s->n * sizeof(int32_t));
    for (size_t c = 0; c < s->nc; c++) {
        int i = s->ci[c], j = s->cj[c];
        cd_vec3 F = cd_contact_force_on_j(s->fn[c], s->normal[c], s->ft[c]); /* on j [N] */
        add_dyad(sigma + 9 * (size_t)j, F, cd_v3_sub(s->point[c], s->pos[j]));
        add_dyad(sigma + 9 * (size_t)i, cd_v3_neg(F), cd_v3_sub(s->point[c], s->pos[i]));
        ncontacts[i]++;
        ncontacts[j]++;
    }
    for (size_t c = 0; c < s->nw; c++) {
        int p = s->prim_particle[s->w_prim[c]];
        add_dyad(sigma + 9 * (size_t)p, s->w_force[c], cd_v3_sub(s->w_point[c], s->pos[p]));
        ncontacts[p]++;
    }
    for (size_t p = 0; p < s->n; p++) {
        double V = cd_an_particle_volume(s, p); /* [m^3] */
        for (int k = 0; k < 9; k++) sigma[9 * p + k] /= V;
    }
    return 0;
}

int cd_an_stress(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen)
{
    const cd_an_snapshot *s = in->s;
    const cd_an_geometry *geo = in->g;
    if (s->nc + s->nw == 0) {
        snprintf(err, errlen, "%s: snapshot %d (step %lld) has no contacts: no particle stress", s->path, s->snapshot,
                 s->step);
        return 2;
    }
    double *sigma = malloc(9 * (s->n ? s->n : 1) * sizeof(double));
    int32_t *ncon = malloc((s->n ? s->n : 1) * sizeof(int32_t));
    double *I1 = malloc((s->n ? s->n : 1) * sizeof(double));
    double *eig = malloc(3 * (s->n ? s->n : 1) * sizeof(double));
    if (!sigma || !ncon || !I1 || !eig) {
        free(sigma);
        free(ncon);
        free(I1);
        free(eig);
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    cd_an_particle_stress(s, sigma, ncon);
    size_t m = 0; /* particles with at least one contact */
    double packing[9] = {0}, core[9] = {0};
    long nfail = 0;
#pragma omp parallel reduction(+ : nfail)
    {
        gsl_eigen_symm_workspace *w = gsl_eigen_symm_alloc(3);
        gsl_matrix *A = gsl_matrix_alloc(3, 3);
        gsl_vector *ev = gsl_vector_alloc(3);
#pragma omp for schedule(static)
        for (size_t p = 0; p < s->n; p++) {
            const double *sg = sigma + 9 * p;
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++)
                    gsl_matrix_set(A, (size_t)a, (size_t)b, 0.5 * (sg[3 * a + b] + sg[3 * b + a]));
            if (!w || !A || !ev || gsl_eigen_symm(A, ev, w)) {
                nfail++;
                continue;
            }
            double e[3] = {gsl_vector_get(ev, 0), gsl_vector_get(ev, 1), gsl_vector_get(ev, 2)};
            /* sorted s1 >= s2 >= s3 */
            for (int a = 0; a < 2; a++)
                for (int b = a + 1; b < 3; b++)
                    if (e[b] > e[a]) {
                        double t = e[a];
                        e[a] = e[b];
                        e[b] = t;
                    }
            memcpy(eig + 3 * p, e, sizeof e);
        }
        if (ev) gsl_vector_free(ev);
        if (A) gsl_matrix_free(A);
        if (w) gsl_eigen_symm_free(w);
    }
    double sum_i1 = 0, sum_e[3] = {0, 0, 0};
    for (size_t p = 0; p < s->n; p++) {
        const double *sg = sigma + 9 * p;
        double V = cd_an_particle_volume(s, p);
        for (int k = 0; k < 9; k++) packing[k] += V * sg[k];
        if (geo->core_volume > 0 && cd_an_in_core(geo, s->pos[p]))
            for (int k = 0; k < 9; k++) core[k] += V * sg[k];
        if (ncon[p] == 0) continue;
        I1[m++] = sg[0] + sg[4] + sg[8];
        sum_i1 += sg[0] + sg[4] + sg[8];
        for (int k = 0; k < 3; k++) sum_e[k] += eig[3 * p + k];
    }
    double mean_i1 = sum_i1 / (double)m; /* [Pa] */
    cd_an_group *g = cd_an_group_get(r, "stress");
    cd_an_put(g, "n_particles", (double)m, "1");
    cd_an_put(g, "mean_I1", mean_i1, "Pa");
    cd_an_put(g, "mean_sigma_1", sum_e[0] / (double)m, "Pa");
    cd_an_put(g, "mean_sigma_2", sum_e[1] / (double)m, "Pa");
    cd_an_put(g, "mean_sigma_3", sum_e[2] / (double)m, "Pa");
    if (nfail) cd_an_put_text(g, "eigen_note", "%ld particle tensors could not be diagonalised", nfail);
    for (size_t q = 0; q < m; q++) I1[q] = mean_i1 != 0 ? I1[q] / mean_i1 : 0;
    double counts[50];
    size_t under, over;
    cd_an_histogram(I1, m, 0, 0.2, 50, counts, &under, &over);
    double *c = cd_an_put_curve(g, "pdf", 50, "i,P,count", "1,1,1");
    for (int b = 0; c && b < 50; b++) {
        c[3 * b] = (b + 0.5) * 0.2;
        c[3 * b + 1] = counts[b] / ((double)m * 0.2);
        c[3 * b + 2] = counts[b];
    }
    cd_an_put(g, "pdf_fraction_below_0", (double)under / (double)m, "1");
    cd_an_put(g, "pdf_fraction_above_10", (double)over / (double)m, "1");
    cd_an_exp_fit tail;
    if (cd_an_fit_exp_tail_mle(I1, m, 1.0, &tail) == 0) {
        cd_an_put(g, "tail_k", tail.k, "1");
        cd_an_put(g, "tail_k_lo", tail.lo, "1");
        cd_an_put(g, "tail_k_hi", tail.hi, "1");
    }
    /* Average stress of the packing, sum V_p sigma_p / V, over the
     * container and over the core region. */
    if (geo->volume > 0 && geo->dim == 3) {
        double *t = cd_an_put_curve(g, "container_stress", 3, "sigma_ax,sigma_ay,sigma_az", "Pa,Pa,Pa");
        for (int k = 0; t && k < 9; k++) t[k] = packing[k] / geo->volume;
        cd_an_put(g, "container_pressure", 0.0 - (packing[0] + packing[4] + packing[8]) / (3 * geo->volume), "Pa");
    }
    if (geo->core_volume > 0 && geo->dim == 3) {
        double *t = cd_an_put_curve(g, "core_stress", 3, "sigma_ax,sigma_ay,sigma_az", "Pa,Pa,Pa");
        for (int k = 0; t && k < 9; k++) t[k] = core[k] / geo->core_volume;
        cd_an_put(g, "core_pressure", 0.0 - (core[0] + core[4] + core[8]) / (3 * geo->core_volume), "Pa");
    }
    free(sigma);
    free(ncon);
    free(I1);
    free(eig);
    return 0;
}
