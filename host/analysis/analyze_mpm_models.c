/* The compaction models of Nezamabadi et al. 2022 (the paper, section 4
 * and its appendix) beyond jamming, and their fits on an mpm packing run's
 * series (docs/mpm.md "Analysis"):
 *
 *   eq. (6)   sigma = M_eff / (1 + M_eff / (c1 K Z Phi)) (ln Phi + c2)
 *   eq. (7)   M_eff = G_eff (4 G_eff - E_eff) / (3 G_eff - E_eff)
 *   eqs. (8), (9)  E_eff = E (1 - p/p_c)^f_E, G_eff = G (1 - p/p_c)^f_G, p = 1 - Phi
 *   eq. (10)  sigma = (1 - f_p) sigma_e + f_p sigma_p
 *   eq. (11)  f_p = alpha ln(Phi / Phi_c)
 *   eq. (13)  sigma_p = sigma_y + M_p_eff / (1 + M_p_eff / (c1p K_p Z Phi)) (ln Phi + c2p)
 *   eqs. (14)-(16)  M_p_eff, E_p_eff, G_p_eff as (7)-(9) from E_p = E H / (E + H),
 *             G_p = E_p / (2 (1 + nu)), K_p from E_p and nu
 *
 * Stress compression positive (the paper writes eq. (6) with a minus sign
 * for its eps = ln(h/h_i) < 0 in compression).  K is the particle's 2D
 * bulk modulus lambda + mu (the paper's "K = lambda + mu in 2D"), G = mu. */
#include "analysis/analyze.h"
#include <gsl/gsl_blas.h>
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

double cd_an_mpm_m_eff(double E, double nu, double f_E, double f_G, double p_c, double phi)
{
    double x = 1 - (1 - phi) / p_c;     /* 1 - p / p_c [1] */
    if (!(x > 0) || !(E > 0)) return 0; /* at or below the critical porosity's packing: no stiffness */
    double G = E / (2 * (1 + nu));
    double Ee = E * pow(x, f_E), Ge = G * pow(x, f_G); /* [Pa] */
    return Ge * (4 * Ge - Ee) / (3 * Ge - Ee);
}

/* The bracket of eqs. (6) and (13): M / (1 + M / (c1 K Z Phi)) (ln Phi + c2) [Pa], K the 2D bulk
 * modulus lambda + mu of (E, nu). */
static double porous_stress(double E, double nu, const cd_an_mpm_model *m, double phi, double z)
{
    double M = cd_an_mpm_m_eff(E, nu, m->f_E, m->f_G, m->p_c, phi);
    if (M == 0) return 0;
    double K = E / (2 * (1 + nu) * (1 - 2 * nu)); /* lambda + mu [Pa] */
    return M / (1 + M / (m->c1 * K * z * phi)) * (log(phi) + m->c2);
}

double cd_an_mpm_sigma_elastic(const cd_an_mpm_model *m, double phi, double z)
{
    return porous_stress(m->E, m->nu, m, phi, z);
}

double cd_an_mpm_sigma_plastic(const cd_an_mpm_model *m, double phi, double z)
{
    double Ep = m->H > 0 ? m->E * m->H / (m->E + m->H) : 0; /* plastic tangent modulus [Pa] */
    double sp = m->sigma_y + porous_stress(Ep, m->nu, m, phi, z);
    double fp = m->alpha * log(phi / m->phi_c);
    return (1 - fp) * cd_an_mpm_sigma_elastic(m, phi, z) + fp * sp;
}

/* ---- eq. (6): f_E, f_G, c1 by nonlinear least squares ---------------- */

typedef struct {
    cd_an_mpm_model m;
    const double *phi, *z, *sigma;
} eq6_data;

static int eq6_residual(const gsl_vector *p, void *params, gsl_vector *f)
{
    const eq6_data *d = params;
    cd_an_mpm_model m = d->m;
    m.f_E = gsl_vector_get(p, 0);
    m.f_G = gsl_vector_get(p, 1);
    m.c1 = gsl_vector_get(p, 2);
    for (size_t i = 0; i < f->size; i++) {
        double r = cd_an_mpm_sigma_elastic(&m, d->phi[i], d->z[i]) - d->sigma[i];
        gsl_vector_set(f, i, isfinite(r) ? r : 1e300); /* a singular M_eff: far from any data */
    }
    return GSL_SUCCESS;
}

int cd_an_mpm_fit_eq6(const double *phi, const double *z, const double *sigma, size_t n, cd_an_mpm_model *m,
                      cd_an_nlfit *out)
{
    memset(out, 0, sizeof(*out));
    out->np = 3;
    out->n = n;
    if (n <= 3) return -1;
    eq6_data d = {*m, phi, z, sigma};
    gsl_multifit_nlinear_fdf fdf;
    memset(&fdf, 0, sizeof fdf);
    fdf.f = eq6_residual;
    fdf.n = n;
    fdf.p = 3;
    fdf.params = &d;
    gsl_multifit_nlinear_parameters fp = gsl_multifit_nlinear_default_parameters();
    gsl_multifit_nlinear_workspace *w = gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &fp, n, 3);
    gsl_matrix *cov = gsl_matrix_alloc(3, 3);
    int rc = -1;
    if (w && cov) {
        double p0[3] = {m->f_E, m->f_G, m->c1};
        gsl_vector_view pv = gsl_vector_view_array(p0, 3);
        gsl_error_handler_t *old = gsl_set_error_handler_off();
        int info = 0;
        int st = gsl_multifit_nlinear_init(&pv.vector, &fdf, w);
        if (st == GSL_SUCCESS) st = gsl_multifit_nlinear_driver(500, 1e-12, 1e-12, 1e-14, NULL, NULL, &info, w);
        if (st == GSL_SUCCESS) {
            gsl_vector *r = gsl_multifit_nlinear_residual(w);
            gsl_blas_ddot(r, r, &out->chi2);
            gsl_multifit_nlinear_covar(gsl_multifit_nlinear_jac(w), 0.0, cov);
            out->dof = (int)(n - 3);
            double s2 = out->chi2 / out->dof, t = gsl_cdf_tdist_Pinv(0.975, out->dof);
            rc = 0;
            for (size_t k = 0; k < 3; k++) {
                out->p[k] = gsl_vector_get(gsl_multifit_nlinear_position(w), k);
                out->se[k] = sqrt(gsl_matrix_get(cov, k, k) * s2);
                out->lo[k] = out->p[k] - t * out->se[k];
                out->hi[k] = out->p[k] + t * out->se[k];
                if (!isfinite(out->p[k]) || !isfinite(out->se[k])) rc = -1;
            }
            if (!(out->chi2 < 1e290)) rc = -1; /* ended on a singular M_eff */
        }
        gsl_set_error_handler(old);
    }
    if (w) gsl_multifit_nlinear_free(w);
    if (cov) gsl_matrix_free(cov);
    if (rc == 0) {
        m->f_E = out->p[0];
        m->f_G = out->p[1];
        m->c1 = out->p[2];
    }
    return rc;
}

/* ---- eq. (10): alpha, linear least squares ----------------------------- */

int cd_an_mpm_fit_eq10(const double *phi, const double *z, const double *sigma, size_t n, cd_an_mpm_model *m,
                       double *alpha_lo, double *alpha_hi)
{
    /* sigma - sigma_e = alpha ln(Phi / Phi_c) (sigma_p - sigma_e): a line through the origin in alpha */
    cd_an_mpm_model one = *m;
    one.alpha = 1;
    double sxy = 0, sxx = 0;
    for (size_t i = 0; i < n; i++) {
        double se = cd_an_mpm_sigma_elastic(m, phi[i], z[i]);
        double u = cd_an_mpm_sigma_plastic(&one, phi[i], z[i]) - se; /* d sigma / d alpha [Pa] */
        sxy += u * (sigma[i] - se);
        sxx += u * u;
    }
    if (n < 2 || !(sxx > 0)) return -1;
    m->alpha = sxy / sxx;
    double ss = 0;
    for (size_t i = 0; i < n; i++) ss += pow(sigma[i] - cd_an_mpm_sigma_plastic(m, phi[i], z[i]), 2);
    double s = sqrt(ss / (double)(n - 1) / sxx), t = gsl_cdf_tdist_Pinv(0.975, (double)(n - 1));
    *alpha_lo = m->alpha - t * s;
    *alpha_hi = m->alpha + t * s;
    return 0;
}

/* ---- the report groups ------------------------------------------------- */

/* The paper's parameters (its section 4: f_E = f_Ep = 1.2, f_G = f_Gp = 0.2, p_c = 0.201,
 * c1 = c1p = 1, c2 = c2p = 0.23, alpha = 2.5) with the run's material. */
static cd_an_mpm_model paper_model(const cd_an_mpm_model *material)
{
    cd_an_mpm_model p = *material;
    p.f_E = 1.2;
    p.f_G = 0.2;
    p.p_c = 0.201;
    p.c1 = 1;
    p.c2 = 0.23;
    p.alpha = 2.5;
    p.phi_c = 0.8;
    return p;
}

void cd_an_mpm_models(cd_an_report *r, const cd_an_mpm_model *material, int plastic, const double *elastic, double pc,
                      const double *phi, const double *z, const double *sigma, const double *strain, size_t rows)
{
    cd_an_group *g6 = cd_an_group_get(r, "mpm_eq6"), *g10 = cd_an_group_get(r, "mpm_eq10");
    if (!(pc > 0)) {
        const char *why = "no Phi_c: eq. (17) did not fit (give it with --phi-c)";
        cd_an_put_text(g6, "skipped", "%s", why);
        cd_an_put_text(g10, "skipped", "%s", why);
        return;
    }
    /* the rows beyond jamming with contacts: Z > 0 enters eq. (6)'s denominator */
    size_t *use = malloc((rows ? rows : 1) * sizeof(size_t));
    double *buf = malloc(3 * (rows ? rows : 1) * sizeof(double));
    if (!use || !buf) {
        free(use);
        free(buf);
        cd_an_put_text(g6, "skipped", "out of memory");
        cd_an_put_text(g10, "skipped", "out of memory");
        return;
    }
    double *x = buf, *y = buf + rows, *s = buf + 2 * rows;
    size_t n = 0;
    for (size_t i = 0; i < rows; i++)
        if (phi[i] > pc && z[i] > 0 && isfinite(sigma[i])) {
            use[n] = i;
            x[n] = phi[i];
            y[n] = z[i];
            s[n++] = sigma[i];
        }
    /* p_c and c2 from the jamming point, as the paper's 0.201 ~ 1 - Phi_c and 0.23 ~ -ln Phi_c */
    cd_an_mpm_model m = *material, paper = paper_model(material);
    m.p_c = 1 - pc;
    m.c2 = -log(pc);
    m.phi_c = pc;
    m.f_E = elastic ? elastic[0] : paper.f_E;
    m.f_G = elastic ? elastic[1] : paper.f_G;
    m.c1 = elastic ? elastic[2] : paper.c1;
    cd_an_group *g = plastic ? g10 : g6;
    cd_an_put_text(plastic ? g6 : g10, "skipped", "%s",
                   plastic ? "a plastic material: the mixture of eq. (10), mpm_eq10"
                           : "an elastic material: eq. (6), mpm_eq6");
    int fit;
    double alo = NAN, ahi = NAN;
    cd_an_nlfit nf;
    if (!plastic) fit = cd_an_mpm_fit_eq6(x, y, s, n, &m, &nf);
    else fit = cd_an_mpm_fit_eq10(x, y, s, n, &m, &alo, &ahi);
    if (n < 4) {
        cd_an_put_text(g, "skipped", "fewer than 4 rows with Z > 0 beyond Phi_c = %.4g", pc);
        free(use);
        free(buf);
        return;
    }
    cd_an_put(g, "phi_c", pc, "1");
    cd_an_put(g, "p_c", m.p_c, "1");
    cd_an_put(g, "c2", m.c2, "1");
    if (plastic) {
        cd_an_put_text(g, "elastic_from", "%s", elastic ? "--elastic-model" : "the paper");
        cd_an_put(g, "f_e", m.f_E, "1");
        cd_an_put(g, "f_g", m.f_G, "1");
        cd_an_put(g, "c1", m.c1, "1");
    }
    /* a fit that does not converge (the rows too close to Phi_c to tell f_E from f_G and c1) still
     * leaves the paper's curve against the series */
    if (fit) cd_an_put_text(g, "fit", "no convergence (or a singular M_eff): sigma_fit is NaN");
    else if (!plastic) {
        static const char *const names[3] = {"f_e", "f_g", "c1"};
        cd_an_put_fit(g, names, &nf);
    } else {
        cd_an_put(g, "alpha", m.alpha, "1");
        cd_an_put(g, "alpha_lo", alo, "1");
        cd_an_put(g, "alpha_hi", ahi, "1");
    }
    cd_an_put(g, "n_points", (double)n, "1");
    /* the model against the series: the fitted parameters and the paper's */
    double *c = cd_an_put_curve(g, "curve", n, "row,phi,z,strain,sigma,sigma_fit,sigma_paper", "1,1,1,1,Pa,Pa,Pa");
    double ss = 0, sp = 0;
    for (size_t k = 0; k < n; k++) {
        double f = fit       ? NAN
                   : plastic ? cd_an_mpm_sigma_plastic(&m, x[k], y[k])
                             : cd_an_mpm_sigma_elastic(&m, x[k], y[k]);
        double q = plastic ? cd_an_mpm_sigma_plastic(&paper, x[k], y[k]) : cd_an_mpm_sigma_elastic(&paper, x[k], y[k]);
        ss += (f - s[k]) * (f - s[k]);
        sp += (q - s[k]) * (q - s[k]);
        if (c) {
            double row[7] = {(double)use[k], x[k], y[k], strain[use[k]], s[k], f, q};
            memcpy(c + 7 * k, row, sizeof row);
        }
    }
    if (!fit) cd_an_put(g, "rms_residual", sqrt(ss / (double)n), "Pa");
    cd_an_put(g, "rms_residual_paper", sqrt(sp / (double)n), "Pa");
    free(use);
    free(buf);
}
