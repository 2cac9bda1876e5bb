/* Force distributions (docs/references.md, Analysis).
 *
 * Normal contact forces f = F_n / <F_n> over every contact of the snapshot:
 * P(f) in 50 bins of 0.2 on [0, 10], normalised as a density over all the
 * contacts (the fraction beyond 10 is reported, not renormalised away), the
 * exponential tail above f = 1 and Mueth's form (Conzelmann et al., eq. 1-2).
 *
 * Bond forces (Tran et al. 2024, section 3.4): the vector sum of the contact forces, normal
 * and tangential, between two particles.  Their PDF is given normalised by
 * <F_n> (docs/references.md, Analysis), and normalised by their own mean <F_b> for the cascade
 * model, whose P_f has mean 1 by construction (Tran et al. 2024: "the force f is
 * assumed to be normalized by the mean force so that int f P_f df = 1");
 * fitting it to forces in units of <F_n>, whose mean is <F_b>/<F_n> ~ the
 * valence, would be inconsistent. */
#include "analysis/analyze.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PF_BINS  50
#define PF_WIDTH 0.2

/* Density histogram of x (n samples) as a curve (x, P, count) and the
 * raw counts in counts[PF_BINS]. */
static int density_curve(cd_an_group *g, const char *name, const char *xname, const double *x, size_t n, double *counts)
{
    size_t under, over;
    cd_an_histogram(x, n, 0, PF_WIDTH, PF_BINS, counts, &under, &over);
    char cols[96];
    snprintf(cols, sizeof cols, "%s,P,count", xname);
    double *c = cd_an_put_curve(g, name, PF_BINS, cols, "1,1,1");
    if (!c) return -1;
    for (int b = 0; b < PF_BINS; b++) {
        c[3 * b] = (b + 0.5) * PF_WIDTH;
        c[3 * b + 1] = counts[b] / ((double)n * PF_WIDTH);
        c[3 * b + 2] = counts[b];
    }
    char key[64];
    snprintf(key, sizeof key, "%s_fraction_above_10", name);
    cd_an_put(g, key, n ? (double)over / (double)n : 0, "1");
    return 0;
}

/* Model curve sampled on a fine grid for plotting and checking. */
static double *model_curve(cd_an_group *g, const char *name, int rows)
{
    return cd_an_put_curve(g, name, (size_t)rows, "f,P", "1,1");
}

int cd_an_forces(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen)
{
    const cd_an_snapshot *s = in->s;
    if (s->nc == 0 || !(in->mean_fn > 0)) {
        snprintf(err, errlen, "%s: snapshot %d (step %lld) has no contact with a normal force: no P(f)", s->path,
                 s->snapshot, s->step);
        return 2;
    }
    double *f = malloc(s->nc * sizeof(double));
    if (!f) {
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    for (size_t c = 0; c < s->nc; c++) f[c] = s->fn[c] / in->mean_fn;
    cd_an_group *g = cd_an_group_get(r, "normal_forces");
    cd_an_put(g, "n_contacts", (double)s->nc, "1");
    cd_an_put(g, "mean_fn", in->mean_fn, "N");
    double counts[PF_BINS], centre[PF_BINS];
    for (int b = 0; b < PF_BINS; b++) centre[b] = (b + 0.5) * PF_WIDTH;
    if (density_curve(g, "pdf", "f", f, s->nc, counts)) {
        free(f);
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    /* Tail: maximum likelihood on the samples is the primary estimate (no
     * binning choice, no bias from the log of small counts, exact
     * interval); the least-squares fit on log P is what papers plot. */
    cd_an_exp_fit mle, wls;
    int ok_mle = cd_an_fit_exp_tail_mle(f, s->nc, 1.0, &mle) == 0;
    int ok_wls = cd_an_fit_exp_tail_wls(centre, counts, PF_BINS, PF_WIDTH, (double)s->nc, 1.0, &wls) == 0;
    cd_an_put(g, "tail_n", (double)mle.n, "1");
    if (ok_mle) {
        cd_an_put(g, "k", mle.k, "1");
        cd_an_put(g, "k_lo", mle.lo, "1");
        cd_an_put(g, "k_hi", mle.hi, "1");
    } else {
        cd_an_put_text(g, "k_note", "fewer than 2 contacts with f > 1: no tail fit");
    }
    if (ok_wls) {
        cd_an_put(g, "k_wls", wls.k, "1");
        cd_an_put(g, "k_wls_lo", wls.lo, "1");
        cd_an_put(g, "k_wls_hi", wls.hi, "1");
        cd_an_put(g, "k_wls_bins", (double)wls.n, "1");
    }
    cd_an_nlfit mu;
    if (cd_an_fit_mueth(centre, counts, PF_BINS, PF_WIDTH, (double)s->nc, ok_mle ? mle.k : 1.4, &mu) == 0) {
        static const char *const names[3] = {"mueth_a", "mueth_b", "mueth_beta"};
        cd_an_put_fit(g, names, &mu);
        cd_an_put(g, "mueth_chi2_per_dof", mu.chi2 / mu.dof, "1");
        double *m = model_curve(g, "mueth_fit", 201);
        for (int i = 0; m && i <= 200; i++) {
            double x = 0.05 * i;
            m[2 * i] = x;
            m[2 * i + 1] = mu.p[0] * (1 - mu.p[1] * exp(-x * x)) * exp(-mu.p[2] * x);
        }
    } else {
        cd_an_put_text(g, "mueth_note", "Mueth's fit did not converge");
    }
    free(f);
    return 0;
}

int cd_an_bond_forces(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen)
{
    const cd_an_snapshot *s = in->s;
    const cd_an_bonds *b = in->b;
    if (b->n == 0 || !(in->mean_fn > 0)) {
        snprintf(err, errlen, "%s: snapshot %d (step %lld) has no bond with a force: no bond-force PDF", s->path,
                 s->snapshot, s->step);
        return 2;
    }
    double *f = malloc(2 * b->n * sizeof(double));
    if (!f) {
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    double *fb = f + b->n, sum = 0;
    for (size_t q = 0; q < b->n; q++) {
        double m = cd_v3_norm(b->force[q]); /* [N] */
        f[q] = m / in->mean_fn;
        sum += m;
    }
    double mean_fb = sum / (double)b->n; /* [N] */
    for (size_t q = 0; q < b->n; q++) fb[q] = mean_fb > 0 ? cd_v3_norm(b->force[q]) / mean_fb : 0;
    cd_an_group *g = cd_an_group_get(r, "bond_forces");
    cd_an_put(g, "n_bonds", (double)b->n, "1");
    cd_an_put(g, "mean_bond_force", mean_fb, "N");
    cd_an_put(g, "mean_bond_force_over_mean_fn", mean_fb / in->mean_fn, "1");
    double counts[PF_BINS];
    int rc = density_curve(g, "pdf", "f", f, b->n, counts);
    if (!rc) rc = density_curve(g, "pdf_mean1", "f_over_mean", fb, b->n, counts);
    if (rc) {
        free(f);
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    cd_an_cascade_fit cf;
    if (cd_an_fit_cascade(fb, b->n, &cf) == 0) {
        cd_an_put(g, "cascade_gamma", cf.gamma, "1");
        cd_an_put(g, "cascade_gamma_lo", cf.lo, "1");
        cd_an_put(g, "cascade_gamma_hi", cf.hi, "1");
        cd_an_put(g, "cascade_beta", cf.beta, "1");
        cd_an_put(g, "cascade_beta_lo", cf.beta_lo, "1");
        cd_an_put(g, "cascade_beta_hi", cf.beta_hi, "1");
        double *m = model_curve(g, "cascade_fit", 201);
        for (int i = 0; m && i <= 200; i++) {
            m[2 * i] = 0.05 * i;
            m[2 * i + 1] = cd_an_cascade_pdf(0.05 * i, cf.gamma);
        }
    } else {
        cd_an_put_text(g, "cascade_note", "fewer than 10 bonds: no cascade fit");
    }
    free(f);
    return 0;
}
