/* Fits of the analysis (docs/references.md, Analysis), all with GSL:
 *  - exponential tail of P(f) above f = 1: maximum likelihood on the
 *    samples with the exact chi-square interval (primary), and weighted
 *    least squares on log P of the histogram (as papers usually do);
 *  - Mueth's form a (1 - b e^{-f^2}) e^{-beta f}: weighted nonlinear least
 *    squares on the histogram;
 *  - cascade model of Tran et al. 2024 (eq. 12-13): maximum likelihood of gamma,
 *    profile-likelihood interval;
 *  - (Z - Z_c) ~ (Phi - Phi_c)^(1/2) above jamming (Nezamabadi et al. 2022, eq. 17):
 *    nonlinear least squares. */
#include "analysis/analyze.h"
#include <gsl/gsl_blas.h>
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_fit.h>
#include <gsl/gsl_min.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_roots.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- exponential tail -------------------------------------------------- */

/* Quantile p of chi^2 with nu degrees of freedom.  GSL's inverse does not
 * converge for very large nu (millions of contacts); there the
 * Wilson-Hilferty cube-root normal approximation is used, whose relative
 * error falls like 1/nu (below 1e-6 from nu = 1e5 on). */
static double chisq_quantile(double p, double nu)
{
    if (nu <= 1e5) return gsl_cdf_chisq_Pinv(p, nu);
    double z = gsl_cdf_ugaussian_Pinv(p), c = 2 / (9 * nu);
    double t = 1 - c + z * sqrt(c);
    return nu * t * t * t;
}

int cd_an_fit_exp_tail_mle(const double *f, size_t n, double fmin, cd_an_exp_fit *out)
{
    memset(out, 0, sizeof(*out));
    double S = 0; /* sum of the excesses f - fmin [1] */
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (f[i] > fmin) {
            S += f[i] - fmin;
            m++;
        }
    out->n = m;
    if (m < 2 || !(S > 0)) return -1;
    /* Given f > fmin, an exponential tail makes f - fmin exponential with
     * rate k, so 2 k S follows chi^2 with 2m degrees of freedom: the
     * interval is exact, not asymptotic. */
    out->k = (double)m / S;
    out->lo = chisq_quantile(0.025, 2.0 * (double)m) / (2 * S);
    out->hi = chisq_quantile(0.975, 2.0 * (double)m) / (2 * S);
    return 0;
}

int cd_an_fit_exp_tail_wls(const double *centre, const double *counts, int nb, double width, double total, double fmin,
                           cd_an_exp_fit *out)
{
    memset(out, 0, sizeof(*out));
    double *x = malloc((size_t)(nb > 0 ? nb : 1) * 3 * sizeof(double));
    if (!x) return -1;
    double *y = x + nb, *w = y + nb;
    size_t m = 0;
    for (int b = 0; b < nb; b++)
        if (centre[b] > fmin && counts[b] > 0) {
            x[m] = centre[b];
            y[m] = log(counts[b] / (total * width)); /* log of the density */
            w[m] = counts[b];                        /* 1 / var(log count) for Poisson counts */
            m++;
        }
    out->n = m;
    int rc = -1;
    if (m >= 3) {
        double c0, c1, cov00, cov01, cov11, chi2;
        gsl_fit_wlinear(x, 1, w, 1, y, 1, m, &c0, &c1, &cov00, &cov01, &cov11, &chi2);
        /* The weights are absolute (Poisson); a worse fit than they allow
         * (chi2 > dof: the tail is not quite exponential) widens the
         * interval, a better one does not shrink it. */
        double dof = (double)m - 2;
        double se = sqrt(cov11 * fmax(1.0, chi2 / dof));
        double t = gsl_cdf_tdist_Pinv(0.975, dof);
        out->k = -c1;
        out->lo = -c1 - t * se;
        out->hi = -c1 + t * se;
        rc = 0;
    }
    free(x);
    return rc;
}

/* ---- nonlinear least squares ------------------------------------------- */

typedef double (*nl_model)(double x, const double *p);

typedef struct {
    nl_model model;
    const double *x, *y;
} nl_data;

static int nl_residual(const gsl_vector *p, void *params, gsl_vector *f)
{
    const nl_data *d = params;
    for (size_t i = 0; i < f->size; i++) gsl_vector_set(f, i, d->model(d->x[i], p->data) - d->y[i]);
    return GSL_SUCCESS;
}

/* Weighted least squares of y ~ model(x; p) from p (np parameters);
 * absolute: the weights are inverse variances (errors are then scaled up,
 * never down, by the reduced chi^2), otherwise relative (scaled by it). */
static int nl_fit(nl_model model, const double *x, const double *y, const double *wt, size_t n, int np,
                  const double *p0, int absolute, cd_an_nlfit *out)
{
    memset(out, 0, sizeof(*out));
    out->np = np;
    out->n = n;
    if (n <= (size_t)np) return -1;
    nl_data d = {model, x, y};
    gsl_multifit_nlinear_fdf fdf;
    memset(&fdf, 0, sizeof fdf);
    fdf.f = nl_residual;
    fdf.df = NULL; /* forward-difference Jacobian */
    fdf.n = n;
    fdf.p = (size_t)np;
    fdf.params = &d;
    gsl_multifit_nlinear_parameters fp = gsl_multifit_nlinear_default_parameters();
    gsl_multifit_nlinear_workspace *w = gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &fp, n, (size_t)np);
    gsl_matrix *cov = gsl_matrix_alloc((size_t)np, (size_t)np);
    if (!w || !cov) {
        if (w) gsl_multifit_nlinear_free(w);
        if (cov) gsl_matrix_free(cov);
        return -1;
    }
    double pstart[4];
    memcpy(pstart, p0, (size_t)np * sizeof(double));
    gsl_vector_view pv = gsl_vector_view_array(pstart, (size_t)np);
    gsl_vector_const_view wv = gsl_vector_const_view_array(wt, n);
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    int info = 0;
    int st = gsl_multifit_nlinear_winit(&pv.vector, &wv.vector, &fdf, w);
    /* ftol stops a fit that only dithers across a kink of the model (the
     * jamming law's sqrt(max(Phi - Phi_c, 0))) once the cost stalls. */
    if (st == GSL_SUCCESS) st = gsl_multifit_nlinear_driver(500, 1e-10, 1e-10, 1e-12, NULL, NULL, &info, w);
    int rc = -1;
    if (st == GSL_SUCCESS || st == GSL_EMAXITER) {
        gsl_vector *r = gsl_multifit_nlinear_residual(w);
        double chi2;
        gsl_blas_ddot(r, r, &chi2);
        gsl_multifit_nlinear_covar(gsl_multifit_nlinear_jac(w), 0.0, cov);
        out->chi2 = chi2;
        out->dof = (int)(n - (size_t)np);
        double s2 = chi2 / out->dof;
        if (absolute && s2 < 1) s2 = 1;
        double t = gsl_cdf_tdist_Pinv(0.975, out->dof);
        rc = st == GSL_SUCCESS ? 0 : -1;
        for (int k = 0; k < np; k++) {
            out->p[k] = gsl_vector_get(gsl_multifit_nlinear_position(w), (size_t)k);
            out->se[k] = sqrt(gsl_matrix_get(cov, (size_t)k, (size_t)k) * s2);
            out->lo[k] = out->p[k] - t * out->se[k];
            out->hi[k] = out->p[k] + t * out->se[k];
            if (!isfinite(out->p[k]) || !isfinite(out->se[k])) rc = -1;
        }
    }
    gsl_set_error_handler(old);
    gsl_matrix_free(cov);
    gsl_multifit_nlinear_free(w);
    return rc;
}

/* ---- Mueth ------------------------------------------------------------- */

static double mueth(double f, const double *p) { return p[0] * (1 - p[1] * exp(-f * f)) * exp(-p[2] * f); }

int cd_an_fit_mueth(const double *centre, const double *counts, int nb, double width, double total, double beta_guess,
                    cd_an_nlfit *out)
{
    memset(out, 0, sizeof(*out));
    int last = -1;
    for (int b = 0; b < nb; b++)
        if (counts[b] > 0) last = b;
    if (last < 3 || !(total > 0)) return -1;
    size_t n = (size_t)last + 1;
    double *y = malloc(2 * n * sizeof(double));
    if (!y) return -1;
    double *w = y + n;
    double norm = total * width; /* counts -> density [1] */
    double an = 0, ad = 0;
    for (size_t b = 0; b < n; b++) {
        y[b] = counts[b] / norm;
        /* Poisson variance of the density; an empty bin still says the
         * density is below about one count. */
        double var = fmax(counts[b], 1.0) / (norm * norm);
        w[b] = 1 / var;
        if (centre[b] > 1 && counts[b] > 0) {
            an += counts[b] * y[b] * exp(beta_guess * centre[b]);
            ad += counts[b];
        }
    }
    double a0 = ad > 0 ? an / ad : 1;
    double b0 = 1 - y[0] / a0;
    if (b0 > 0.99) b0 = 0.99;
    if (b0 < -1) b0 = -1;
    double p0[3] = {a0, b0, beta_guess > 0 ? beta_guess : 1};
    int rc = nl_fit(mueth, centre, y, w, n, 3, p0, 1, out);
    /* Weights from the observed counts (Neyman's chi^2) pull the fit
     * towards bins that fell short, which biases beta: its 95% interval
     * covered the truth in 173 of 200 samples of 5,000 forces
     * (tests/analysis/test_analysis_fits.c).  Reweighting with the
     * model's expected counts until the parameters settle is Poisson
     * maximum likelihood for the histogram (the score equations of the
     * Poisson likelihood are the fixed point of these weights). */
    for (int it = 0; rc == 0 && it < 20; it++) {
        double before[3] = {out->p[0], out->p[1], out->p[2]};
        for (size_t k = 0; k < n; k++) {
            double mu = mueth(centre[k], out->p) * norm; /* expected count of bin k */
            w[k] = norm * norm / (mu > 0 ? mu : 1);      /* 1 / variance of the density [1] */
        }
        rc = nl_fit(mueth, centre, y, w, n, 3, before, 1, out);
        double change = 0;
        for (int k = 0; rc == 0 && k < 3; k++) change = fmax(change, fabs(out->p[k] - before[k]) / out->se[k]);
        if (change < 1e-3) break;
    }
    free(y);
    return rc;
}

/* ---- cascade model ----------------------------------------------------- */

/* beta = (1 + gamma) ln((1 + gamma) / gamma): the value that makes the
 * mean of P_f equal to 1 (Tran et al. 2024, eq. 13; checked: int_0^inf f P df =
 * (1 + gamma) ln((1 + gamma)/gamma) / beta). */
double cd_an_cascade_beta(double gamma) { return (1 + gamma) * log1p(1 / gamma); }

/* log(1 + e^u) without overflow. */
static double softplus(double u) { return u > 0 ? u + log1p(exp(-u)) : log1p(exp(u)); }

double cd_an_cascade_pdf(double f, double gamma)
{
    double beta = cd_an_cascade_beta(gamma);
    double u = log(gamma) + beta * f; /* log(gamma e^{beta f}) */
    return exp(log(beta) + log1p(gamma) + u - 2 * softplus(u));
}

typedef struct {
    const double *x, *wt; /* sample values (or bin means) and their multiplicities */
    size_t n;
} cascade_data;

/* Negative log-likelihood at t = ln gamma. */
static double cascade_nll(double t, void *params)
{
    const cascade_data *d = params;
    double gamma = exp(t), beta = cd_an_cascade_beta(gamma);
    double c = log(beta) + log1p(gamma), s = 0;
    for (size_t i = 0; i < d->n; i++) {
        double u = t + beta * d->x[i];
        s += d->wt[i] * (c + u - 2 * softplus(u));
    }
    return -s;
}

typedef struct {
    cascade_data *d;
    double level;
} cascade_level;

static double cascade_excess(double t, void *params)
{
    const cascade_level *l = params;
    return cascade_nll(t, l->d) - l->level;
}

/* Root of nll(t) = level between a and b (nll(a) - level and nll(b) -
 * level of opposite signs). */
static double cascade_root(cascade_level *l, double a, double b)
{
    gsl_function F = {cascade_excess, l};
    gsl_root_fsolver *s = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    double r = 0.5 * (a + b);
    if (s && gsl_root_fsolver_set(s, &F, a, b) == GSL_SUCCESS) {
        for (int it = 0; it < 200; it++) {
            gsl_root_fsolver_iterate(s);
            r = gsl_root_fsolver_root(s);
            double lo = gsl_root_fsolver_x_lower(s), hi = gsl_root_fsolver_x_upper(s);
            if (gsl_root_test_interval(lo, hi, 1e-10, 0) == GSL_SUCCESS) break;
        }
    }
    if (s) gsl_root_fsolver_free(s);
    return r;
}

int cd_an_fit_cascade(const double *f, size_t n, cd_an_cascade_fit *out)
{
    memset(out, 0, sizeof(*out));
    out->n = n;
    if (n < 10) return -1;
    /* Large samples are binned (width 1e-3, each bin at its own sample
     * mean) so that every likelihood evaluation is O(bins): the binned
     * log-likelihood differs from the exact one by O(width^2) per sample. */
    const double bw = 1e-3;
    double fbig = 0; /* largest sample [1] */
    for (size_t i = 0; i < n; i++)
        if (f[i] > fbig) fbig = f[i];
    size_t nb = (size_t)(fbig / bw) + 1;
    int binned = n > 200000 && nb < n / 4;
    double *x = malloc((binned ? nb : n) * 2 * sizeof(double));
    if (!x) return -1;
    double *wt = x + (binned ? nb : n);
    cascade_data d = {x, wt, binned ? nb : n};
    if (binned) {
        memset(x, 0, 2 * nb * sizeof(double));
        for (size_t i = 0; i < n; i++) {
            size_t b = (size_t)(fbig > 0 ? f[i] / bw : 0);
            if (b >= nb) b = nb - 1;
            x[b] += f[i];
            wt[b] += 1;
        }
        size_t m = 0;
        for (size_t b = 0; b < nb; b++)
            if (wt[b] > 0) {
                x[m] = x[b] / wt[b];
                wt[m] = wt[b];
                m++;
            }
        /* compact: the weights follow the m means */
        memmove(x + m, wt, m * sizeof(double));
        wt = x + m;
        d.wt = wt;
        d.n = m;
    } else {
        for (size_t i = 0; i < n; i++) {
            x[i] = f[i];
            wt[i] = 1;
        }
    }
    /* gamma spans e^-20 (forces all near the mean) to e^20 (a pure
     * exponential): bracket the minimum on a grid, then Brent. */
    const double tlo = -20, thi = 20, dt = 0.5;
    int ng = (int)((thi - tlo) / dt) + 1, best = 0;
    double vbest = HUGE_VAL;
    for (int i = 0; i < ng; i++) {
        double v = cascade_nll(tlo + i * dt, &d);
        if (v < vbest) {
            vbest = v;
            best = i;
        }
    }
    double tmin = tlo + best * dt;
    if (best > 0 && best < ng - 1) {
        gsl_function F = {cascade_nll, &d};
        gsl_min_fminimizer *m = gsl_min_fminimizer_alloc(gsl_min_fminimizer_brent);
        gsl_error_handler_t *old = gsl_set_error_handler_off();
        if (m && gsl_min_fminimizer_set_with_values(m, &F, tmin, vbest, tmin - dt, cascade_nll(tmin - dt, &d),
                                                    tmin + dt, cascade_nll(tmin + dt, &d)) == GSL_SUCCESS) {
            for (int it = 0; it < 200; it++) {
                gsl_min_fminimizer_iterate(m);
                double a = gsl_min_fminimizer_x_lower(m), b = gsl_min_fminimizer_x_upper(m);
                if (gsl_min_test_interval(a, b, 1e-10, 0) == GSL_SUCCESS) break;
            }
            tmin = gsl_min_fminimizer_x_minimum(m);
            vbest = gsl_min_fminimizer_f_minimum(m);
        }
        gsl_set_error_handler(old);
        if (m) gsl_min_fminimizer_free(m);
    }
    /* 95% profile-likelihood interval: nll within chi^2_1(0.95)/2 of the
     * minimum; a side that never gets there is open (0 or infinity). */
    cascade_level lv = {&d, vbest + 0.5 * gsl_cdf_chisq_Pinv(0.95, 1)};
    double tl = -HUGE_VAL, th = HUGE_VAL;
    for (double t = tmin - dt; t >= tlo - 1e-9; t -= dt)
        if (cascade_nll(t, &d) > lv.level) {
            tl = cascade_root(&lv, t, fmin(t + dt, tmin));
            break;
        }
    for (double t = tmin + dt; t <= thi + 1e-9; t += dt)
        if (cascade_nll(t, &d) > lv.level) {
            th = cascade_root(&lv, fmax(t - dt, tmin), t);
            break;
        }
    free(x);
    out->gamma = exp(tmin);
    out->lo = isfinite(tl) ? exp(tl) : 0;
    out->hi = isfinite(th) ? exp(th) : HUGE_VAL;
    out->beta = cd_an_cascade_beta(out->gamma);
    /* beta decreases with gamma (d beta / d gamma = ln(1 + 1/gamma) - 1/gamma < 0) */
    out->beta_lo = isfinite(th) ? cd_an_cascade_beta(out->hi) : 1;
    out->beta_hi = out->lo > 0 ? cd_an_cascade_beta(out->lo) : HUGE_VAL;
    return 0;
}

/* ---- jamming ----------------------------------------------------------- */

static double jamming(double phi, const double *p) { return p[1] + p[2] * sqrt(fmax(phi - p[0], 0)); }

int cd_an_fit_jamming(const double *phi, const double *z, size_t n, cd_an_nlfit *out)
{
    memset(out, 0, sizeof(*out));
    double *x = malloc((n ? n : 1) * 3 * sizeof(double));
    if (!x) return -1;
    double *y = x + n, *w = y + n;
    double zmax = 0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(z[i]) && isfinite(phi[i]) && z[i] > zmax) zmax = z[i];
    /* First guess of the jammed states: coordination at least half its
     * largest value (below jamming Z collapses towards 0).  Then the
     * states above the fitted Phi_c, until the selection settles. */
    double cut = -HUGE_VAL;
    int rc = -1;
    double p[3] = {0, 0, 0};
    for (int iter = 0; iter < 10; iter++) {
        size_t m = 0;
        double pmin = HUGE_VAL, pmax = -HUGE_VAL, zmin = HUGE_VAL;
        for (size_t i = 0; i < n; i++) {
            if (!isfinite(z[i]) || !isfinite(phi[i]) || z[i] <= 0) continue;
            if (iter == 0 ? z[i] < 0.5 * zmax : phi[i] <= cut) continue;
            x[m] = phi[i];
            y[m] = z[i];
            w[m] = 1;
            m++;
            pmin = fmin(pmin, phi[i]);
            pmax = fmax(pmax, phi[i]);
            zmin = fmin(zmin, z[i]);
        }
        if (m < 5 || !(pmax > pmin)) {
            rc = -1;
            break;
        }
        if (iter == 0) {
            p[0] = pmin - 1e-3 * (pmax - pmin);
            p[1] = zmin;
            p[2] = (zmax - zmin) / sqrt(pmax - p[0]);
        }
        cd_an_nlfit fit;
        if (nl_fit(jamming, x, y, w, m, 3, p, 0, &fit)) {
            if (iter == 0) rc = -2; /* later: keep the fit of the previous selection */
            break;
        }
        /* A series that does not resolve the square root (all states at
         * one density, or Z not rising with Phi) drives Phi_c far outside
         * the data with A and Z_c compensating: refuse that rather than
         * report it. */
        if (!(fit.p[2] > 0) || fit.p[0] > pmax || fit.p[0] < pmin - (pmax - pmin)) {
            if (iter == 0) rc = -3;
            break;
        }
        *out = fit;
        rc = 0;
        memcpy(p, fit.p, sizeof p);
        if (iter > 0 && fit.p[0] == cut) break;
        if (iter > 0 && fabs(fit.p[0] - cut) < 1e-12) break;
        cut = fit.p[0];
    }
    free(x);
    return rc;
}
