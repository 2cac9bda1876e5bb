/* Fits of the analysis (host/analysis/analyze_fit.c) on synthetic samples with known
 * answers: the exponential tail, Mueth's form, the cascade model of Tran et al.
 * 2024, the jamming law of Nezamabadi et al. 2022, and P(f) through the whole forces
 * measure.  Random numbers come from capdem's seeded generator, so every
 * run sees the same samples. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "analysis/analyze.h"
#include "core/rng.h"

/* Exponential with rate k. */
static double draw_exp(cd_rng *r, double k) { return -log1p(-cd_rng_uniform(r)) / k; }

/* f - 1 ~ Exp(k) above 1, plus uniform samples below 1 that the fit must
 * ignore: the MLE recovers k within its interval. */
static void test_tail_mle_recovers_k(void **state)
{
    (void)state;
    const double k = 1.7;
    const size_t n = 20000;
    double *f = malloc(2 * n * sizeof(double));
    cd_rng r;
    cd_rng_seed(&r, 11);
    for (size_t i = 0; i < n; i++) f[i] = 1 + draw_exp(&r, k);
    for (size_t i = n; i < 2 * n; i++) f[i] = cd_rng_uniform(&r);
    cd_an_exp_fit fit;
    assert_int_equal(cd_an_fit_exp_tail_mle(f, 2 * n, 1.0, &fit), 0);
    assert_int_equal(fit.n, n);
    assert_true(fit.lo <= k && k <= fit.hi);
    /* the interval is about 2 x 1.96 k / sqrt(n) wide */
    double expect = 2 * 1.96 * k / sqrt((double)n);
    assert_true(fabs((fit.hi - fit.lo) / expect - 1) < 0.05);
    free(f);
}

/* The interval is exact (2 k S ~ chi^2(2n)): over 400 independent samples
 * of 500 it must cover the true k in 95% of them.  The binomial standard
 * deviation of the coverage is 0.011, so [0.91, 0.99] is about 4 sigma. */
static void test_tail_mle_coverage(void **state)
{
    (void)state;
    const double k = 1.3;
    const int reps = 400, n = 500;
    double f[500];
    cd_rng r;
    cd_rng_seed(&r, 12);
    int covered = 0;
    for (int t = 0; t < reps; t++) {
        for (int i = 0; i < n; i++) f[i] = 1 + draw_exp(&r, k);
        cd_an_exp_fit fit;
        assert_int_equal(cd_an_fit_exp_tail_mle(f, (size_t)n, 1.0, &fit), 0);
        covered += fit.lo <= k && k <= fit.hi;
    }
    double cov = (double)covered / reps;
    assert_true(cov > 0.91 && cov < 0.99);
}

/* Weighted least squares on log P: on a noise-free exponential histogram
 * (counts = the exact bin integrals) the slope is exact, because the bin
 * integral of e^{-k f} is e^{-k c} times a factor common to every bin. */
static void test_tail_wls_exact_histogram(void **state)
{
    (void)state;
    const double k = 1.4, w = 0.2, N = 1e6;
    double centre[50], counts[50];
    for (int b = 0; b < 50; b++) {
        centre[b] = (b + 0.5) * w;
        counts[b] = N * (exp(-k * b * w) - exp(-k * (b + 1) * w));
    }
    cd_an_exp_fit fit;
    assert_int_equal(cd_an_fit_exp_tail_wls(centre, counts, 50, w, N, 1.0, &fit), 0);
    assert_true(fabs(fit.k - k) < 1e-9);
    assert_true(fit.lo <= k && k <= fit.hi);
}

static double mueth_pdf(double f, double a, double b, double beta)
{
    return a * (1 - b * exp(-f * f)) * exp(-beta * f);
}

/* Mueth's form sampled by rejection (proposal Exp(beta), accepted with
 * probability 1 - b e^{-f^2}), normalised so that it is a density: the fit
 * of the histogram recovers a, b, beta within 1.5 half-widths of their 95%
 * intervals (~2.9 sigma: a fixed seed, and three parameters). */
static void test_mueth_recovers_parameters(void **state)
{
    (void)state;
    const double b = 0.6, beta = 1.5;
    /* a from the normalisation: int e^{-f^2 - beta f} = sqrt(pi)/2 e^{beta^2/4} erfc(beta/2) */
    double a = 1 / (1 / beta - b * sqrt(CD_PI) / 2 * exp(beta * beta / 4) * erfc(beta / 2));
    const size_t n = 200000;
    double *f = malloc(n * sizeof(double));
    cd_rng r;
    cd_rng_seed(&r, 13);
    for (size_t i = 0; i < n;) {
        double x = draw_exp(&r, beta);
        if (cd_rng_uniform(&r) < 1 - b * exp(-x * x)) f[i++] = x;
    }
    double counts[50], centre[50];
    cd_an_histogram(f, n, 0, 0.2, 50, counts, NULL, NULL);
    for (int k = 0; k < 50; k++) centre[k] = (k + 0.5) * 0.2;
    cd_an_nlfit fit;
    assert_int_equal(cd_an_fit_mueth(centre, counts, 50, 0.2, (double)n, 1.0, &fit), 0);
    const double truth[3] = {a, b, beta};
    for (int k = 0; k < 3; k++) {
        /* the histogram is compared at bin centres; the bin average of P
         * differs by ~ w^2 P''/24, a bias below 0.3% here */
        double half = 0.5 * (fit.hi[k] - fit.lo[k]) + 0.003 * fabs(truth[k]);
        assert_true(fabs(fit.p[k] - truth[k]) < 1.5 * half);
    }
    /* noise-free: densities at the bin centres exactly */
    for (int k = 0; k < 50; k++) counts[k] = (double)n * 0.2 * mueth_pdf(centre[k], a, b, beta);
    assert_int_equal(cd_an_fit_mueth(centre, counts, 50, 0.2, (double)n, 1.0, &fit), 0);
    for (int k = 0; k < 3; k++) assert_true(fabs(fit.p[k] / truth[k] - 1) < 1e-6);
    free(f);
}

/* Tran et al. 2024, eq. 12-13: P_f integrates to 1 and has mean 1 for every gamma
 * (this is what fixes beta); P(0) = gamma ln((1 + gamma)/gamma). */
static void test_cascade_normalisation(void **state)
{
    (void)state;
    const double gammas[] = {0.05, 0.3, 1, 4};
    for (int g = 0; g < 4; g++) {
        double gm = gammas[g], beta = cd_an_cascade_beta(gm), s0 = 0, s1 = 0, h = 1e-3;
        /* Simpson on [0, 60 / beta]: the tail beyond is below e^-60 */
        int m = (int)(60 / beta / h) & ~1;
        for (int i = 0; i <= m; i++) {
            double x = i * h, w = (i == 0 || i == m) ? 1 : (i & 1) ? 4 : 2, p = cd_an_cascade_pdf(x, gm);
            s0 += w * p;
            s1 += w * x * p;
        }
        s0 *= h / 3;
        s1 *= h / 3;
        assert_true(fabs(s0 - 1) < 1e-6);
        assert_true(fabs(s1 - 1) < 1e-6);
        assert_true(fabs(cd_an_cascade_pdf(0, gm) - gm * log((1 + gm) / gm)) < 1e-12);
    }
}

/* Inverse of the cascade CDF F(f) = 1 - (1 + gamma) / (1 + gamma e^{beta f}). */
static double draw_cascade(cd_rng *r, double gamma)
{
    double u = cd_rng_uniform(r), beta = cd_an_cascade_beta(gamma);
    return log(((1 + gamma) / (1 - u) - 1) / gamma) / beta;
}

static void test_cascade_recovers_gamma(void **state)
{
    (void)state;
    const double gamma = 0.3;
    const size_t n = 20000;
    double *f = malloc(n * sizeof(double));
    cd_rng r;
    cd_rng_seed(&r, 14);
    for (size_t i = 0; i < n; i++) f[i] = draw_cascade(&r, gamma);
    cd_an_cascade_fit fit;
    assert_int_equal(cd_an_fit_cascade(f, n, &fit), 0);
    assert_true(fit.lo <= gamma && gamma <= fit.hi);
    assert_true(fit.hi / fit.lo < 1.3); /* informative at this size */
    assert_true(fit.beta_lo <= cd_an_cascade_beta(gamma) && cd_an_cascade_beta(gamma) <= fit.beta_hi);
    free(f);
}

/* The profile-likelihood interval is asymptotic; at 1000 samples its
 * coverage is close to 95%: 200 repetitions, binomial sd 0.015, accepted
 * in [0.89, 0.99]. */
static void test_cascade_coverage(void **state)
{
    (void)state;
    const double gamma = 1.5;
    const int reps = 200, n = 1000;
    double f[1000];
    cd_rng r;
    cd_rng_seed(&r, 15);
    int covered = 0;
    for (int t = 0; t < reps; t++) {
        for (int i = 0; i < n; i++) f[i] = draw_cascade(&r, gamma);
        cd_an_cascade_fit fit;
        assert_int_equal(cd_an_fit_cascade(f, (size_t)n, &fit), 0);
        covered += fit.lo <= gamma && gamma <= fit.hi;
    }
    double cov = (double)covered / reps;
    assert_true(cov > 0.89 && cov < 0.99);
}

/* Large samples go through the binned likelihood (1e-3 wide bins): same
 * answer as the exact one to far below the statistical error. */
static void test_cascade_binned_matches(void **state)
{
    (void)state;
    const double gamma = 0.5;
    const size_t n = 300000;
    double *f = malloc(n * sizeof(double));
    cd_rng r;
    cd_rng_seed(&r, 16);
    for (size_t i = 0; i < n; i++) f[i] = draw_cascade(&r, gamma);
    cd_an_cascade_fit big, part;
    assert_int_equal(cd_an_fit_cascade(f, n, &big), 0);       /* binned */
    assert_int_equal(cd_an_fit_cascade(f, 200000, &part), 0); /* exact, 2/3 of the samples */
    assert_true(big.lo <= gamma && gamma <= big.hi);
    assert_true(fabs(big.gamma - part.gamma) < 0.5 * (part.hi - part.lo));
    free(f);
}

/* n states evenly spread over Phi in [0.55, 0.70]: Z = Z_c + A sqrt(Phi -
 * Phi_c) plus Gaussian noise of sd above jamming, loose (Z < 0.5) below. */
static void jamming_sample(cd_rng *r, double phic, double zc, double A, double sd, int n, double *phi, double *z)
{
    for (int i = 0; i < n; i++) {
        phi[i] = 0.55 + 0.15 * i / (n - 1);
        /* Box-Muller */
        double g = sqrt(-2 * log1p(-cd_rng_uniform(r))) * cos(2 * CD_PI * cd_rng_uniform(r));
        z[i] = phi[i] > phic ? zc + A * sqrt(phi[i] - phic) + sd * g : 0.5 * cd_rng_uniform(r);
    }
}

/* Z = Z_c + A sqrt(Phi - Phi_c) above jamming plus Gaussian noise, and
 * loose states below jamming with small Z: the fit finds the jammed branch
 * and recovers the three parameters within 1.5 half-widths of their 95%
 * intervals. */
static void test_jamming_fit(void **state)
{
    (void)state;
    const double phic = 0.62, zc = 4.0, A = 10.0, sd = 0.05;
    enum { n = 400 };
    double phi[n], z[n];
    cd_rng r;
    cd_rng_seed(&r, 17);
    jamming_sample(&r, phic, zc, A, sd, n, phi, z);
    cd_an_nlfit fit;
    assert_int_equal(cd_an_fit_jamming(phi, z, n, &fit), 0);
    const double truth[3] = {phic, zc, A};
    for (int k = 0; k < 3; k++) assert_true(fabs(fit.p[k] - truth[k]) < 0.75 * (fit.hi[k] - fit.lo[k]));
    /* the jammed states: (0.70 - 0.62) / 0.15 of the 400, about 213 */
    assert_true(fit.n > 205 && fit.n < 222);
}

/* Coverage of Mueth's intervals: P(f) histograms of 5,000 forces (a
 * packing of a few thousand particles) binned as the forces measure bins
 * them, 200 repetitions; the 95% intervals of b and beta must cover the
 * truth in 95% of them (binomial sd 0.015, accepted in [0.89, 0.99]).
 * Measured: b 196, beta 192 of 200 (with weights from the observed counts,
 * as the fit had them before: beta 173, 0.865). */
static void test_mueth_coverage(void **state)
{
    (void)state;
    const double b = 0.6, beta = 1.5;
    const int reps = 200;
    enum { n = 5000 };
    static double f[n];
    double counts[50], centre[50];
    for (int k = 0; k < 50; k++) centre[k] = (k + 0.5) * 0.2;
    cd_rng r;
    cd_rng_seed(&r, 19);
    int covered[3] = {0, 0, 0}, fitted = 0;
    for (int t = 0; t < reps; t++) {
        for (size_t i = 0; i < n;) {
            double x = draw_exp(&r, beta);
            if (cd_rng_uniform(&r) < 1 - b * exp(-x * x)) f[i++] = x;
        }
        cd_an_histogram(f, n, 0, 0.2, 50, counts, NULL, NULL);
        cd_an_nlfit fit;
        if (cd_an_fit_mueth(centre, counts, 50, 0.2, (double)n, 1.0, &fit)) continue;
        fitted++;
        covered[1] += fit.lo[1] <= b && b <= fit.hi[1];
        covered[2] += fit.lo[2] <= beta && beta <= fit.hi[2];
    }
    assert_int_equal(fitted, reps);
    for (int k = 1; k < 3; k++) assert_true(covered[k] > 0.89 * reps && covered[k] < 0.99 * reps);
}

/* Coverage of the jamming law's intervals: the set-up of
 * test_jamming_fit, 200 repetitions; each of Phi_c, Z_c and A covered in
 * [0.89, 0.99] of them.  Measured: Phi_c 182, Z_c 192, A 196 of 200 (the
 * kink of sqrt(max(Phi - Phi_c, 0)) makes Phi_c's linearised interval a
 * little short). */
static void test_jamming_coverage(void **state)
{
    (void)state;
    const double phic = 0.62, zc = 4.0, A = 10.0, sd = 0.05, truth[3] = {phic, zc, A};
    const int reps = 200;
    enum { n = 400 };
    double phi[n], z[n];
    cd_rng r;
    cd_rng_seed(&r, 20);
    int covered[3] = {0, 0, 0};
    for (int t = 0; t < reps; t++) {
        jamming_sample(&r, phic, zc, A, sd, n, phi, z);
        cd_an_nlfit fit;
        assert_int_equal(cd_an_fit_jamming(phi, z, n, &fit), 0);
        for (int k = 0; k < 3; k++) covered[k] += fit.lo[k] <= truth[k] && truth[k] <= fit.hi[k];
    }
    for (int k = 0; k < 3; k++) assert_true(covered[k] > 0.89 * reps && covered[k] < 0.99 * reps);
}

/* P(f) through the forces measure: a density whose tail above f = 1 is
 * exactly exp(-k f) with k = sqrt(2), uniform below 1, which has mean 1 (the
 * only k for which this shape is normalised by its mean: k/(k+1) (1/2 + 1/k
 * + 1/k^2) = 1).  The analysis divides by the sample mean, off by ~0.3% at
 * this size, which moves k by far less than its interval. */
static void test_forces_measure(void **state)
{
    (void)state;
    const size_t nc = 100000;
    const double k = sqrt(2.0), F0 = 3.0; /* [N] */
    cd_an_snapshot s;
    memset(&s, 0, sizeof s);
    assert_int_equal(cd_an_snapshot_alloc(&s, 2, 2, nc, 0, 0), 0);
    snprintf(s.path, sizeof s.path, "synthetic");
    cd_rng r;
    cd_rng_seed(&r, 18);
    for (size_t c = 0; c < nc; c++) {
        double u = cd_rng_uniform(&r);
        double f = u < k / (k + 1) * 1 ? cd_rng_uniform(&r) : 1 + draw_exp(&r, k);
        s.fn[c] = F0 * f;
        s.ci[c] = 0;
        s.cj[c] = 1;
        s.normal[c] = cd_v3(1, 0, 0);
    }
    double sum = 0;
    for (size_t c = 0; c < nc; c++) sum += s.fn[c];
    cd_an_options opt;
    cd_an_options_defaults(&opt);
    cd_an_geometry g;
    memset(&g, 0, sizeof g);
    cd_an_bonds b;
    memset(&b, 0, sizeof b);
    cd_an_input in = {&s, &g, &b, &opt, sum / nc};
    cd_an_report rep;
    memset(&rep, 0, sizeof rep);
    char err[512];
    assert_int_equal(cd_an_forces(&in, &rep, err, sizeof err), 0);
    double kk = cd_an_value(&rep, "normal_forces", "k");
    double lo = cd_an_value(&rep, "normal_forces", "k_lo"), hi = cd_an_value(&rep, "normal_forces", "k_hi");
    assert_true(lo <= k && k <= hi);
    assert_true(fabs(kk - k) < 0.03);
    const cd_an_curve *pdf = cd_an_curve_find(&rep, "normal_forces", "pdf");
    assert_non_null(pdf);
    assert_int_equal(pdf->rows, 50);
    double integral = 0;
    for (size_t i = 0; i < pdf->rows; i++) integral += 0.2 * pdf->data[3 * i + 1];
    assert_true(fabs(integral + cd_an_value(&rep, "normal_forces", "pdf_fraction_above_10") - 1) < 1e-12);
    /* below f = 1 the density is flat at k/(k+1) / <f> */
    assert_true(fabs(pdf->data[3 * 2 + 1] / (k / (k + 1)) - 1) < 0.05);
    cd_an_report_free(&rep);
    cd_an_snapshot_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tail_mle_recovers_k),
        cmocka_unit_test(test_tail_mle_coverage),
        cmocka_unit_test(test_tail_wls_exact_histogram),
        cmocka_unit_test(test_mueth_recovers_parameters),
        cmocka_unit_test(test_mueth_coverage),
        cmocka_unit_test(test_jamming_coverage),
        cmocka_unit_test(test_cascade_normalisation),
        cmocka_unit_test(test_cascade_recovers_gamma),
        cmocka_unit_test(test_cascade_coverage),
        cmocka_unit_test(test_cascade_binned_matches),
        cmocka_unit_test(test_jamming_fit),
        cmocka_unit_test(test_forces_measure),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
