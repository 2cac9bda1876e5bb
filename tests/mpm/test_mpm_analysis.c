/* `capdem analyze` of mpm run files (host/analysis/analyze_mpm.c,
 * docs/mpm.md "Analysis") against known answers: the line fit on seeded
 * noisy samples; the boundary curvature of a fine polygon circle and of a
 * square; and a synthetic run file (3 square particles, series and
 * snapshots made from the paper's laws with known parameters: eq. (17)
 * Z = Z_c + A sqrt(Phi - Phi_c), eq. (5) sigma - sigma_c = M (eps -
 * eps_c), eq. (11) f_p = alpha ln(Phi / Phi_c)) through cd_an_mpm. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "analysis/analyze.h"
#include "core/rng.h"

static const double PI = 3.14159265358979323846;

/* y = 3 + 2.5e5 x + uniform noise of +-1e3, 400 seeded draws of 200
 * points: the slope's and the intercept's 95% intervals hold the truth in
 * 92-98 % of them (binomial: 95 % +- 3 x 1.1 %; measured 383 and 383 of
 * 400), and the slope's standard
 * error is the noise's sd (577 Pa) over sqrt(sum (x - mean)^2) within 15 %
 * on average (measured 0.996); exact data give the slope to round-off. */
static void test_fit_line(void **state)
{
    (void)state;
    enum { n = 200, draws = 400 };
    double x[n], y[n], sxx = 0;
    for (int i = 0; i < n; i++) x[i] = 0.001 * i;
    for (int i = 0; i < n; i++) sxx += pow(x[i] - 0.0995, 2);
    cd_rng r;
    cd_rng_seed(&r, 5);
    int cover = 0, cover0 = 0;
    double se = 0;
    cd_an_linfit f;
    for (int d = 0; d < draws; d++) {
        for (int i = 0; i < n; i++) y[i] = 3 + 2.5e5 * x[i] + 2e3 * (cd_rng_uniform(&r) - 0.5);
        assert_int_equal(cd_an_fit_line(x, y, n, &f), 0);
        cover += f.lo <= 2.5e5 && 2.5e5 <= f.hi;
        cover0 += f.intercept_lo <= 3 && 3 <= f.intercept_hi;
        se += f.se / draws;
    }
    assert_true(cover >= 0.92 * draws && cover <= 0.98 * draws);
    assert_true(cover0 >= 0.92 * draws && cover0 <= 0.98 * draws);
    assert_true(fabs(se / (577.35 / sqrt(sxx)) - 1) < 0.15);
    for (int i = 0; i < n; i++) y[i] = 3 + 2.5e5 * x[i];
    assert_int_equal(cd_an_fit_line(x, y, n, &f), 0);
    assert_true(fabs(f.slope / 2.5e5 - 1) < 1e-12 && f.se < 1e-6);
    assert_int_equal(cd_an_fit_line(x, y, 2, &f), -1);
}

/* A circle of 3600 vertices: 1/R to the vertex count's discreteness (a
 * window of R/2 holds 286 or 287 turns of 2 pi / 3600: within 0.4 %); a
 * square: the window holds one corner, (pi/2) / (2 scale), to round-off. */
static void test_curvature(void **state)
{
    (void)state;
    enum { m = 3600 };
    double *xy = malloc(2 * (m + 1) * sizeof(double)), R = 1.5e-3;
    for (int i = 0; i < m; i++) {
        xy[2 * i] = 0.01 + R * cos(2 * PI * i / m);
        xy[2 * i + 1] = -0.02 + R * sin(2 * PI * i / m);
    }
    xy[2 * m] = 0.01, xy[2 * m + 1] = -0.02; /* the centre: not on the hull */
    double k = cd_an_max_boundary_curvature(xy, m + 1, R / 4);
    assert_true(fabs(k * R - 1) < 0.004);
    /* an 11 x 11 grid filling the unit square, scale 0.1 */
    double sq[2 * 121];
    for (int i = 0; i < 121; i++) sq[2 * i] = (i % 11) / 10.0, sq[2 * i + 1] = (i / 11) / 10.0;
    k = cd_an_max_boundary_curvature(sq, 121, 0.1);
    assert_true(fabs(k - (PI / 2) / 0.2) < 1e-9);
    /* too short a perimeter for the scale */
    assert_true(isnan(cd_an_max_boundary_curvature(sq, 121, 1.1)));
    free(xy);
}

static void put(hid_t f, const char *name, hid_t type, int rank, const hsize_t *dims, const void *data)
{
    hid_t sp = H5Screate_simple(rank, dims, NULL);
    hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    hid_t d = H5Dcreate2(f, name, type, sp, lcpl, H5P_DEFAULT, H5P_DEFAULT);
    assert_true(d >= 0);
    assert_true(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0);
    H5Dclose(d);
    H5Pclose(lcpl);
    H5Sclose(sp);
}

/* The synthetic run: 3 particles of 10 x 10 square points (side l =
 * 0.1 mm, F = I): each a square of side a = 1 mm, whose kappa <d> at the
 * analysis' scale d/8 is (pi/2) / (d/4) x d = 2 pi.  Series (100 rows):
 * Phi from 0.75 to 0.95, strain 2 (Phi - 0.75), Z = 1 below Phi_c = 0.8
 * and 3 + 10 sqrt(Phi - 0.8) above; sigma = 1e5 (Phi / 0.8)^4 below and
 * sigma_c + 2e6 (strain - strain_c) above.  Snapshots at Phi = 0.8
 * e^(f_p / 2.5) with f_p = 0, 0.1, 0.2, 0.4 (the first 0, 30, 60, 120 of
 * the 300 equal points plastic): alpha = 2.5.  law 1 and 2: sigma above
 * Phi_c from eq. (6) (an elastic material, E = 10 MPa, nu = 0.45, f_E =
 * 1.0, f_G = 0.3, c1 = 0.7, p_c = 0.2, c2 = -ln 0.8) or eq. (10) (von Mises,
 * sigma_y = 0.4 MPa, H = 1 MPa, alpha = 2.5, the elastic part with the
 * paper's f_E = 1.2, f_G = 0.2, c1 = 1 and p_c = 0.2, c2 = -ln 0.8), the
 * material in the echoed config. */
enum { LAW_EQ5, LAW_EQ6, LAW_EQ10 };
static const cd_an_mpm_model law6 = {.E = 1e7, .nu = 0.45, .f_E = 1.0, .f_G = 0.3, .p_c = 0.2, .c1 = 0.7, .phi_c = 0.8};
static const cd_an_mpm_model law10 = {.E = 1e7,
                                      .nu = 0.45,
                                      .sigma_y = 4e5,
                                      .H = 1e6,
                                      .f_E = 1.2,
                                      .f_G = 0.2,
                                      .p_c = 0.2,
                                      .c1 = 1,
                                      .alpha = 2.5,
                                      .phi_c = 0.8};

static void write_run(const char *path, int law)
{
    enum { R = 100, S = 4, n = 300 };
    const double l = 1e-4, W = 4e-3, area = n * l * l; /* [m], [m], [m^2/m] */
    hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    assert_true(f >= 0);
    hid_t st = H5Tcopy(H5T_C_S1);
    H5Tset_size(st, 4);
    hid_t as = H5Screate(H5S_SCALAR), a = H5Acreate2(f, "solver", st, as, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, st, "mpm");
    H5Aclose(a);
    long long ns = S;
    a = H5Acreate2(f, "n_snapshots", H5T_NATIVE_LLONG, as, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, H5T_NATIVE_LLONG, &ns);
    H5Aclose(a);
    H5Sclose(as);
    H5Tclose(st);
    static double step[R], phi[R], eps[R], z[R], sig[R], wall[R][8];
    const double pc = 0.8, ec = 2 * (pc - 0.75), sc = 1e5;
    for (int i = 0; i < R; i++) {
        step[i] = 20.0 * i;
        phi[i] = 0.75 + 0.2 * i / (R - 1);
        eps[i] = 2 * (phi[i] - 0.75);
        z[i] = phi[i] > pc ? 3 + 10 * sqrt(phi[i] - pc) : 1;
        cd_an_mpm_model m6 = law6, m10 = law10;
        m6.c2 = m10.c2 = -log(pc);
        sig[i] = phi[i] <= pc     ? sc * pow(phi[i] / pc, 4)
                 : law == LAW_EQ5 ? sc + 2e6 * (eps[i] - ec)
                 : law == LAW_EQ6 ? cd_an_mpm_sigma_elastic(&m6, phi[i], z[i])
                                  : cd_an_mpm_sigma_plastic(&m10, phi[i], z[i]);
        double h = area / (W * phi[i]);
        double w[8] = {0, 0, 0, h, 0, 0, W, 0}; /* bottom, top, left, right */
        memcpy(wall[i], w, sizeof w);
    }
    static int particle[n];
    static double sstep[S], stime[S], pos[S][n][2], vol[S][n], ep[S][n], F[S][n][4], swall[S][8];
    const int plastic[S] = {0, 30, 60, 120};
    for (int s = 0; s < S; s++) {
        double ph = pc * exp(plastic[s] / (double)n / 2.5), h = area / (W * ph);
        double w[8] = {0, 0, 0, h, 0, 0, W, 0};
        memcpy(swall[s], w, sizeof w);
        sstep[s] = 100.0 * s;
        stime[s] = 1e-4 * s;
        for (int p = 0; p < n; p++) {
            int b = p / 100, q = p % 100;
            particle[p] = b;
            pos[s][p][0] = 1.2e-3 * b + l * (q % 10 + 0.5);
            pos[s][p][1] = 1e-4 + l * (q / 10 + 0.5);
            vol[s][p] = l * l;
            ep[s][p] = p < plastic[s] ? 0.01 : 0;
            F[s][p][0] = F[s][p][3] = 1;
            F[s][p][1] = F[s][p][2] = 0;
        }
    }
    hsize_t dp[3] = {n, 1, 1}, dr[3] = {R, 4, 2}, dsn[3] = {S, n, 2}, ds4[3] = {S, n, 4}, dsw[3] = {S, 4, 2};
    put(f, "/mpm/points/particle", H5T_NATIVE_INT, 1, dp, particle);
    const struct {
        const char *name;
        int rank;
        const hsize_t *dims;
        const void *data;
    } cols[] = {{"series/step", 1, dr, step},
                {"series/packing_fraction", 1, dr, phi},
                {"series/strain", 1, dr, eps},
                {"series/coordination", 1, dr, z},
                {"series/stress", 1, dr, sig},
                {"series/wall_position", 3, dr, wall},
                {"snapshots/step", 1, dsn, sstep},
                {"snapshots/time", 1, dsn, stime},
                {"snapshots/position", 3, dsn, pos},
                {"snapshots/volume", 2, dsn, vol},
                {"snapshots/plastic_strain", 2, dsn, ep},
                {"snapshots/deformation_gradient", 3, ds4, F},
                {"snapshots/wall_position", 3, dsw, swall}};
    for (size_t k = 0; k < sizeof cols / sizeof cols[0]; k++) {
        char name[96];
        snprintf(name, sizeof name, "/mpm/%s", cols[k].name);
        put(f, name, H5T_NATIVE_DOUBLE, cols[k].rank, cols[k].dims, cols[k].data);
    }
    char config[1024];
    snprintf(config, sizeof config,
             "solver: mpm\nrun:\n  name: synthetic\n  dt: 1.0e-7\n  steps: 10\nmpm:\n  setup: packing\n"
             "  packing: none.h5\n  cells_per_diameter: 6\n  wall_speed: 2\n  material:\n    model: %s\n"
             "    density: 1000\n    young_modulus: 1.0e7\n    poisson_ratio: 0.45\n%s",
             law == LAW_EQ10 ? "von_mises" : "elastic",
             law == LAW_EQ10 ? "    yield_stress: 4.0e5\n    hardening: 1.0e6\n" : "");
    hid_t ct = H5Tcopy(H5T_C_S1);
    H5Tset_size(ct, strlen(config) + 1);
    hid_t cs = H5Screate(H5S_SCALAR), g = H5Gcreate2(f, "/parameters", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    hid_t cd = H5Dcreate2(f, "/parameters/config", ct, cs, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    assert_true(cd >= 0 && H5Dwrite(cd, ct, H5S_ALL, H5S_ALL, H5P_DEFAULT, config) >= 0);
    H5Dclose(cd);
    H5Gclose(g);
    H5Sclose(cs);
    H5Tclose(ct);
    H5Fclose(f);
}

static void test_synthetic_run(void **state)
{
    (void)state;
    const char *path = "test_mpm_analysis.h5";
    write_run(path, LAW_EQ5);
    cd_an_options opt;
    cd_an_options_defaults(&opt);
    cd_an_report rep;
    memset(&rep, 0, sizeof rep);
    char err[512] = "";
    int rc = cd_an_mpm(path, &opt, &rep, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(rep.snapshot, 3);
    assert_true(rep.step == 300 && fabs(rep.time - 3e-4) < 1e-18);
    /* the last series row and snapshot */
    assert_true(fabs(cd_an_value(&rep, "mpm", "phi") - 0.95) < 1e-12);
    assert_true(fabs(cd_an_value(&rep, "mpm", "z") - (3 + 10 * sqrt(0.15))) < 1e-12);
    double ph3 = 0.8 * exp(120.0 / 300 / 2.5);
    assert_true(fabs(cd_an_value(&rep, "mpm", "snapshot_phi") / ph3 - 1) < 1e-12);
    assert_true(fabs(cd_an_value(&rep, "mpm", "snapshot_strain") - log(ph3 / 0.75)) < 1e-12);
    assert_true(fabs(cd_an_value(&rep, "mpm", "f_p") - 0.4) < 1e-12);
    assert_true(fabs(cd_an_value(&rep, "mpm", "kappa_d") / (2 * PI) - 1) < 1e-9);
    /* the tables for the figures: the whole series, and each snapshot's applied stress, that of the
     * series row of its step (steps 0, 100, 200, 300: rows 0, 5, 10, 15) */
    const cd_an_curve *ser = cd_an_curve_find(&rep, "mpm", "series"), *sn = cd_an_curve_find(&rep, "mpm", "snapshots");
    assert_true(ser && ser->rows == 100 && ser->cols == 5 && !strcmp(ser->columns, "step,strain,phi,sigma,z"));
    assert_true(sn && sn->rows == 4 && sn->cols == 6 && !strcmp(sn->columns, "step,strain,phi,f_p,kappa_d,sigma"));
    assert_true(ser->data[5 * 99 + 2] == 0.95 && ser->data[5 * 99 + 3] > 0);
    for (int k = 0; k < 4; k++) assert_true(sn->data[6 * k + 5] == ser->data[5 * (5 * k) + 3]);
    /* eq. (17): exact data, the fit recovers them */
    assert_true(fabs(cd_an_value(&rep, "mpm_eq17", "phi_c") - 0.8) < 1e-5);
    assert_true(fabs(cd_an_value(&rep, "mpm_eq17", "z_c") - 3) < 1e-3);
    assert_true(fabs(cd_an_value(&rep, "mpm_eq17", "amplitude") - 10) < 1e-3);
    /* eq. (5): sigma_c, strain_c at the fitted Phi_c (interpolated between the two rows around it: the
     * kink of sigma between them costs at most one row's change of sigma, 3.6 kPa), M = 2 MPa */
    assert_true(fabs(cd_an_value(&rep, "mpm_eq5", "sigma_c") / 1e5 - 1) < 0.036);
    assert_true(fabs(cd_an_value(&rep, "mpm_eq5", "strain_c") - 0.1) < 1e-4);
    assert_true(fabs(cd_an_value(&rep, "mpm_eq5", "m_eff") / 2e6 - 1) < 1e-6);
    assert_true(cd_an_value(&rep, "mpm_eq5", "m_eff_lo") <= cd_an_value(&rep, "mpm_eq5", "m_eff"));
    /* eq. (11): alpha = 2.5 */
    assert_true(fabs(cd_an_value(&rep, "mpm_eq11", "alpha") / 2.5 - 1) < 1e-4);
    /* Phi_c given (--phi-c): eqs. (5) and (11) use it, sigma_c and strain_c exact at 0.8 */
    cd_an_report_free(&rep);
    memset(&rep, 0, sizeof rep);
    opt.phi_c = 0.8;
    assert_int_equal(cd_an_mpm(path, &opt, &rep, err, sizeof err), 0);
    assert_true(cd_an_value(&rep, "mpm_eq5", "phi_c") == 0.8);
    assert_true(fabs(cd_an_value(&rep, "mpm_eq5", "strain_c") - 0.1) < 1e-12);
    assert_true(fabs(cd_an_value(&rep, "mpm_eq5", "m_eff") / 2e6 - 1) < 1e-9);
    assert_true(fabs(cd_an_value(&rep, "mpm_eq11", "alpha") / 2.5 - 1) < 1e-9);
    /* and eq. (17) is a line in sqrt(Phi - 0.8): Z_c and A exact, their intervals around them */
    assert_true(fabs(cd_an_value(&rep, "mpm_eq17", "z_c") - 3) < 1e-9);
    assert_true(fabs(cd_an_value(&rep, "mpm_eq17", "amplitude") - 10) < 1e-9);
    assert_true(cd_an_value(&rep, "mpm_eq17", "z_c_lo") <= 3 + 1e-9 &&
                cd_an_value(&rep, "mpm_eq17", "z_c_hi") >= 3 - 1e-9);
    /* a snapshot out of range is refused (exit 2) */
    cd_an_report_free(&rep);
    memset(&rep, 0, sizeof rep);
    opt.snapshot = 7;
    assert_int_equal(cd_an_mpm(path, &opt, &rep, err, sizeof err), 2);
    assert_non_null(strstr(err, "snapshot 7"));
    cd_an_report_free(&rep);
    remove(path);
}

/* Eqs. (6)-(16) (host/analysis/analyze_mpm_models.c): known values of the
 * formulas, and the synthetic runs of law 1 and 2 give their parameters
 * back with Phi_c given (--phi-c 0.8). */
/* A text of a report group, "" when absent. */
static const char *text_of(const cd_an_report *r, const char *group, const char *name)
{
    const cd_an_group *g = cd_an_group_find(r, group);
    for (int k = 0; g && k < g->n_texts; k++)
        if (!strcmp(g->texts[k].name, name)) return g->texts[k].text;
    return "";
}

static void test_models(void **state)
{
    (void)state;
    /* eq. (7) at Phi = 1 (no porosity): the P-wave modulus lambda + 2 mu = 2 G (1 - nu) / (1 - 2 nu) */
    double G = 1e7 / 2.9, M1 = 2 * G * 0.55 / 0.1;
    assert_true(fabs(cd_an_mpm_m_eff(1e7, 0.45, 1.2, 0.2, 0.201, 1.0) / M1 - 1) < 1e-12);
    /* (1 - p/p_c)^f: at p = p_c / 2, E_eff = E / 2^f_E, G_eff = G / 2^f_G, eq. (7) of those */
    double Ee = 1e7 / pow(2, 1.2), Ge = G / pow(2, 0.2);
    assert_true(fabs(cd_an_mpm_m_eff(1e7, 0.45, 1.2, 0.2, 0.2, 0.9) / (Ge * (4 * Ge - Ee) / (3 * Ge - Ee)) - 1) <
                1e-12);
    assert_true(cd_an_mpm_m_eff(1e7, 0.45, 1.2, 0.2, 0.2, 0.79) == 0); /* below 1 - p_c: none */
    cd_an_mpm_model m = law10;
    m.c2 = -log(0.8);
    /* eq. (6) vanishes at Phi_c = exp(-c2); eq. (6) by hand at Phi = 0.9, Z = 4 (K = lambda + mu) */
    assert_true(fabs(cd_an_mpm_sigma_elastic(&m, 0.8, 4)) < 1e-6);
    double M = cd_an_mpm_m_eff(1e7, 0.45, 1.2, 0.2, 0.2, 0.9), K = 1e7 / (2 * 1.45 * 0.1);
    assert_true(fabs(cd_an_mpm_sigma_elastic(&m, 0.9, 4) / (M / (1 + M / (K * 4 * 0.9)) * log(0.9 / 0.8)) - 1) < 1e-12);
    /* eq. (10): alpha = 0 is the elastic law; H = 0 makes sigma_p = sigma_y */
    m.alpha = 0;
    assert_true(cd_an_mpm_sigma_plastic(&m, 0.9, 4) == cd_an_mpm_sigma_elastic(&m, 0.9, 4));
    m.alpha = 2.5;
    m.H = 0;
    double fp = 2.5 * log(0.9 / 0.8);
    assert_true(
        fabs(cd_an_mpm_sigma_plastic(&m, 0.9, 4) - ((1 - fp) * cd_an_mpm_sigma_elastic(&m, 0.9, 4) + fp * 4e5)) < 1e-6);

    const char *path = "test_mpm_models.h5";
    cd_an_options opt;
    cd_an_options_defaults(&opt);
    opt.phi_c = 0.8;
    cd_an_report rep;
    char err[512] = "";
    /* eq. (6): f_E, f_G, c1 back from exact data (from the paper's 1.2, 0.2, 1), their intervals hold them */
    write_run(path, LAW_EQ6);
    memset(&rep, 0, sizeof rep);
    assert_int_equal(cd_an_mpm(path, &opt, &rep, err, sizeof err), 0);
    const char *names[3] = {"f_e", "f_g", "c1"};
    const double truth[3] = {law6.f_E, law6.f_G, law6.c1};
    for (int k = 0; k < 3; k++) {
        char lo[16], hi[16];
        snprintf(lo, sizeof lo, "%s_lo", names[k]);
        snprintf(hi, sizeof hi, "%s_hi", names[k]);
        double v = cd_an_value(&rep, "mpm_eq6", names[k]);
        print_message("eq. (6): %s = %.9g (truth %g)\n", names[k], v, truth[k]);
        assert_true(fabs(v / truth[k] - 1) < 1e-6);
        assert_true(cd_an_value(&rep, "mpm_eq6", lo) <= truth[k] + 1e-6 &&
                    cd_an_value(&rep, "mpm_eq6", hi) >= truth[k] - 1e-6);
    }
    assert_true(fabs(cd_an_value(&rep, "mpm_eq6", "p_c") - 0.2) < 1e-12);
    assert_true(fabs(cd_an_value(&rep, "mpm_eq6", "c2") + log(0.8)) < 1e-12);
    assert_true(cd_an_value(&rep, "mpm_eq6", "rms_residual") < 1e-3);      /* Pa, of stresses up to ~1 MPa */
    assert_true(cd_an_value(&rep, "mpm_eq6", "rms_residual_paper") > 1e3); /* other parameters, other curve */
    assert_true(cd_an_value(&rep, "mpm_eq6", "n_points") == 75);           /* the rows with Phi > 0.8: 25..99 */
    assert_non_null(strstr(text_of(&rep, "mpm_eq10", "skipped"), "elastic material"));
    cd_an_report_free(&rep);
    /* eq. (10): alpha = 2.5 back (sigma is linear in it), the elastic part the paper's by default */
    write_run(path, LAW_EQ10);
    memset(&rep, 0, sizeof rep);
    assert_int_equal(cd_an_mpm(path, &opt, &rep, err, sizeof err), 0);
    print_message("eq. (10): alpha = %.12g\n", cd_an_value(&rep, "mpm_eq10", "alpha"));
    assert_true(fabs(cd_an_value(&rep, "mpm_eq10", "alpha") / 2.5 - 1) < 1e-9);
    assert_true(cd_an_value(&rep, "mpm_eq10", "rms_residual") < 1e-3);
    assert_true(cd_an_value(&rep, "mpm_eq10", "f_e") == 1.2 && cd_an_value(&rep, "mpm_eq10", "c1") == 1);
    assert_non_null(strstr(text_of(&rep, "mpm_eq6", "skipped"), "plastic material"));
    cd_an_report_free(&rep);
    /* another elastic part (--elastic-model): used, and then the data do not fit exactly */
    opt.elastic_model_set = 1;
    opt.elastic_model[0] = 1.0;
    opt.elastic_model[1] = 0.3;
    opt.elastic_model[2] = 0.7;
    memset(&rep, 0, sizeof rep);
    assert_int_equal(cd_an_mpm(path, &opt, &rep, err, sizeof err), 0);
    assert_true(cd_an_value(&rep, "mpm_eq10", "f_e") == 1.0 && cd_an_value(&rep, "mpm_eq10", "c1") == 0.7);
    assert_true(fabs(cd_an_value(&rep, "mpm_eq10", "alpha") / 2.5 - 1) > 1e-3);
    assert_true(cd_an_value(&rep, "mpm_eq10", "rms_residual") > 1);
    cd_an_report_free(&rep);
    remove(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fit_line),
        cmocka_unit_test(test_curvature),
        cmocka_unit_test(test_synthetic_run),
        cmocka_unit_test(test_models),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
