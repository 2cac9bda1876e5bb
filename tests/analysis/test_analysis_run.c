/* End to end: the engine writes a real run file (50 hexapods dropped into a
 * cylinder), `capdem analyze` reads it back.  Checks the exit statuses for
 * bad input, that /analysis is written and replaced, that the JSON parses
 * and holds the documented keys, that the recomputed wall contact points
 * reproduce the torques the engine stored, and that the numbers obey the
 * identities that tie them together (sum of proportions, Z_c = sum c P_c,
 * valence = sum k P_k, normalised densities). */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include <cjson/cJSON.h>
#include <fcntl.h>
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "analysis/analyze.h"
#include "core/run.h"

#define RUN_FILE    "analysis_e2e.h5"
#define CONFIG_FILE "analysis_e2e.yaml"

/* Gravity of 1000 m/s^2 settles the particles into a heap within 2500
 * steps (0.02 s): a real contact network in a couple of seconds.  dt is
 * t_col/23 for these hexapods. */
static const char *config = "run:\n"
                            "  name: analysis-e2e\n"
                            "  seed: 5\n"
                            "  dt: 8.0e-6\n"
                            "  steps: 2500\n"
                            "  snapshot_every: 625\n"
                            "  thermo_every: 25\n"
                            "physics:\n"
                            "  gravity: [0, -1000, 0]\n"
                            "particles:\n"
                            "  - shape: hexapod\n"
                            "    aspect: 3\n"
                            "    diameter: 0.005\n"
                            "    count: 50\n"
                            "    polydispersity: 0.2\n"
                            "domain:\n"
                            "  type: cylinder\n"
                            "  diameter: 0.06\n"
                            "  height: 0.2\n"
                            "init:\n"
                            "  placement: lattice\n"
                            "  clearance: 1.0\n"
                            "  speed: 1.0\n";

static int setup(void **state)
{
    (void)state;
    FILE *f = fopen(CONFIG_FILE, "w");
    if (!f) return -1;
    fputs(config, f);
    fclose(f);
    cd_run_options opt = {.config_path = CONFIG_FILE, .output_path = RUN_FILE, .steps = -1, .quiet = 1, .overwrite = 1};
    return cd_run(&opt) == 0 ? 0 : -1;
}

static int analyze(int n, ...)
{
    char *argv[16];
    va_list ap;
    va_start(ap, n);
    for (int i = 0; i < n; i++) argv[i] = va_arg(ap, char *);
    va_end(ap);
    return cd_cmd_analyze(n, argv);
}

static void test_bad_input(void **state)
{
    (void)state;
    assert_int_equal(analyze(2, "no_such_run.h5", "--quiet"), 2);
    assert_int_equal(analyze(2, CONFIG_FILE, "--quiet"), 2); /* not HDF5 */
    assert_int_equal(analyze(4, RUN_FILE, "--snapshot", "99", "--quiet"), 2);
    assert_int_equal(analyze(3, RUN_FILE, "--frobnicate", "--quiet"), 2);
    assert_int_equal(analyze(4, RUN_FILE, "--measures", "forces,nonsense", "--quiet"), 2);
    assert_int_equal(analyze(0), 2);
    /* the first snapshot is the lattice before any collision: no contacts */
    cd_an_snapshot s;
    char err[1024];
    assert_int_equal(cd_an_read_snapshot(RUN_FILE, 0, &s, err, sizeof err), 0);
    assert_int_equal(s.nc, 0);
    cd_an_snapshot_free(&s);
    assert_int_equal(analyze(5, RUN_FILE, "--snapshot", "0", "--no-write", "--quiet"), 2);
    /* a requested measure the file cannot give: exit 2 */
    assert_int_equal(analyze(5, RUN_FILE, "--measures", "jamming", "--no-write", "--quiet"), 2);
    assert_int_equal(analyze(5, RUN_FILE, "--measures", "rdf", "--no-write", "--quiet"), 2); /* no core */
}

/* Number of links in /analysis/snapshot_<step> (or -1). */
static int analysis_links(long long step, double *mean_fn)
{
    hid_t f = H5Fopen(RUN_FILE, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) return -1;
    char p[128];
    snprintf(p, sizeof p, "/analysis/snapshot_%lld", step);
    int n = -1;
    if (H5Lexists(f, "/analysis", H5P_DEFAULT) > 0 && H5Lexists(f, p, H5P_DEFAULT) > 0) {
        hid_t g = H5Gopen2(f, p, H5P_DEFAULT);
        H5G_info_t info;
        H5Gget_info(g, &info);
        n = (int)info.nlinks;
        H5Gclose(g);
        snprintf(p, sizeof p, "/analysis/snapshot_%lld/normal_forces", step);
        hid_t a = H5Aopen_by_name(f, p, "mean_fn", H5P_DEFAULT, H5P_DEFAULT);
        if (a < 0 || H5Aread(a, H5T_NATIVE_DOUBLE, mean_fn) < 0) n = -1;
        if (a >= 0) H5Aclose(a);
    }
    H5Fclose(f);
    return n;
}

static void test_writes_and_replaces(void **state)
{
    (void)state;
    assert_int_equal(analyze(2, RUN_FILE, "--quiet"), 0);
    double fn1 = 0, fn2 = 0;
    int n1 = analysis_links(2500, &fn1);
    assert_true(n1 >= 8);
    assert_true(fn1 > 0);
    assert_int_equal(analyze(2, RUN_FILE, "--quiet"), 0);
    assert_int_equal(analysis_links(2500, &fn2), n1);
    assert_true(fn1 == fn2);
}

static double sum_column(const cd_an_curve *c, int col, int weight_by_first)
{
    double s = 0;
    for (size_t i = 0; i < c->rows; i++)
        s += c->data[i * (size_t)c->cols + (size_t)col] * (weight_by_first ? c->data[i * (size_t)c->cols] : 1);
    return s;
}

static void test_sane_numbers(void **state)
{
    (void)state;
    cd_an_options opt;
    cd_an_options_defaults(&opt);
    opt.quiet = 1;
    opt.margin_side = 0.5; /* a small heap: shrink the core so that G(r) and phi_core run */
    opt.margin_end = 0.5;
    opt.mc_points = 100000;
    cd_an_report rep;
    char err[2048];
    int rc = cd_analyze_file(RUN_FILE, &opt, &rep, err, sizeof err);
    if (rc) fail_msg("%s", err);
    double nc = cd_an_value(&rep, "sample", "n_contacts");
    assert_true(nc >= 20);
    assert_true(cd_an_value(&rep, "normal_forces", "mean_fn") > 0);

    /* connectivity identities */
    double Z = cd_an_value(&rep, "network", "Z"), Zc = cd_an_value(&rep, "network", "Z_c");
    double val = cd_an_value(&rep, "network", "valence");
    assert_true(Z >= 1 && Zc >= Z && val >= 1 && val <= 9); /* at most 9 contacts between two hexapods */
    assert_true(fabs(val - Zc / Z) < 1e-12);
    const cd_an_curve *pc = cd_an_curve_find(&rep, "network", "contacts_per_particle");
    const cd_an_curve *pb = cd_an_curve_find(&rep, "network", "neighbours_per_particle");
    const cd_an_curve *pk = cd_an_curve_find(&rep, "network", "valence");
    assert_true(fabs(sum_column(pc, 1, 0) - 1) < 1e-12 && fabs(sum_column(pc, 1, 1) - Zc) < 1e-12);
    assert_true(fabs(sum_column(pb, 1, 0) - 1) < 1e-12 && fabs(sum_column(pb, 1, 1) - Z) < 1e-12);
    assert_true(fabs(sum_column(pk, 1, 0) - 1) < 1e-12 && fabs(sum_column(pk, 1, 1) - val) < 1e-12);
    assert_true(pk->rows <= 9);

    /* densities integrate to 1 (minus what lies beyond the range) */
    const cd_an_curve *pf = cd_an_curve_find(&rep, "normal_forces", "pdf");
    assert_true(fabs(0.2 * sum_column(pf, 1, 0) + cd_an_value(&rep, "normal_forces", "pdf_fraction_above_10") - 1) <
                1e-12);
    const cd_an_curve *pl = cd_an_curve_find(&rep, "branch", "pdf");
    assert_true(fabs(0.02 * sum_column(pl, 1, 0) - 1) < 1e-12);
    /* two touching hexapods are closer than the sum of their bounding
     * radii: l < 1.2 L (largest scale 1.2, L = tip-to-tip length) */
    for (size_t i = 0; i < pl->rows; i++)
        if (pl->data[3 * i] > 1.21) assert_true(pl->data[3 * i + 1] == 0);
    double lambda = cd_an_value(&rep, "branch", "lambda");
    assert_true(lambda > 0 && lambda < 1);

    /* a heap under gravity is compressed */
    assert_true(cd_an_value(&rep, "stress", "mean_I1") < 0);
    assert_true(cd_an_value(&rep, "stress", "container_pressure") > 0);
    double phi = cd_an_value(&rep, "packing", "phi_container");
    assert_true(phi > 0.05 && phi < 0.74);
    double pcore = cd_an_value(&rep, "packing", "phi_core");
    assert_true(pcore > 0 && pcore < 0.74);
    assert_true(cd_an_value(&rep, "modulus", "K_t") > 0);
    assert_true(cd_an_value(&rep, "modulus", "k_contact") == 0.5e5);
    assert_true(cd_an_value(&rep, "rdf", "n_reference") >= 1);
    /* the time series: one row every 25 steps from step 0 to 2500 */
    assert_true(cd_an_value(&rep, "compaction", "rows") == 101);
    assert_non_null(cd_an_group_find(&rep, "skipped")); /* jamming: no (Phi, Z) series yet */
    cd_an_report_free(&rep);
}

/* The run file keeps the wall force and its torque but not its point; the
 * point recomputed from the geometry must reproduce the stored torque
 * (c - x) x F, and the pair points the stored pair torques. */
static void test_contact_points_match_torques(void **state)
{
    (void)state;
    cd_an_snapshot s;
    char err[1024];
    assert_int_equal(cd_an_read_snapshot(RUN_FILE, -1, &s, err, sizeof err), 0);
    assert_true(s.nw > 0 && s.nc > 0);
    long long off[2];
    hid_t f = H5Fopen(RUN_FILE, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f >= 0);
    const char *what[2] = {"/wall_contacts", "/contacts"};
    for (int kind = 0; kind < 2; kind++) {
        char p[128];
        snprintf(p, sizeof p, "%s/offset", what[kind]);
        hid_t d = H5Dopen2(f, p, H5P_DEFAULT), sp = H5Dget_space(d);
        hsize_t start = (hsize_t)s.snapshot, count = 2;
        H5Sselect_hyperslab(sp, H5S_SELECT_SET, &start, NULL, &count, NULL);
        hid_t ms = H5Screate_simple(1, &count, NULL);
        assert_true(H5Dread(d, H5T_NATIVE_INT64, ms, sp, H5P_DEFAULT, off) >= 0);
        H5Sclose(ms);
        H5Sclose(sp);
        H5Dclose(d);
        size_t n = (size_t)(off[1] - off[0]);
        assert_int_equal(n, kind ? s.nc : s.nw);
        double *tq = malloc(3 * n * sizeof(double));
        snprintf(p, sizeof p, "%s", kind ? "/contacts/pair_torque_j" : "/wall_contacts/wallc_torque");
        d = H5Dopen2(f, p, H5P_DEFAULT);
        sp = H5Dget_space(d);
        hsize_t st2[2] = {(hsize_t)off[0], 0}, ct2[2] = {n, 3};
        H5Sselect_hyperslab(sp, H5S_SELECT_SET, st2, NULL, ct2, NULL);
        ms = H5Screate_simple(2, ct2, NULL);
        assert_true(H5Dread(d, H5T_NATIVE_DOUBLE, ms, sp, H5P_DEFAULT, tq) >= 0);
        H5Sclose(ms);
        H5Sclose(sp);
        H5Dclose(d);
        for (size_t c = 0; c < n; c++) {
            cd_vec3 F, r;
            if (kind) {
                F = cd_v3_axpy(s.ft[c], s.fn[c], s.normal[c]);
                r = cd_v3_sub(s.point[c], s.pos[s.cj[c]]);
            } else {
                F = s.w_force[c];
                r = cd_v3_sub(s.w_point[c], s.pos[s.prim_particle[s.w_prim[c]]]);
            }
            cd_vec3 t = cd_v3_cross(r, F);
            double scale = cd_v3_norm(r) * cd_v3_norm(F) + 1e-300;
            double dev = cd_v3_norm(cd_v3_sub(t, cd_v3(tq[3 * c], tq[3 * c + 1], tq[3 * c + 2])));
            if (dev > 1e-9 * scale) fail_msg("%s row %zu: torque differs by %g of %g", what[kind], c, dev, scale);
        }
        free(tq);
    }
    H5Fclose(f);
    cd_an_snapshot_free(&s);
}

/* --json prints one object with the documented keys (stdout redirected to
 * a file for the test). */
static void test_json(void **state)
{
    (void)state;
    fflush(stdout);
    int saved = dup(1);
    int fd = open("analysis_e2e.json", O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(saved >= 0 && fd >= 0);
    dup2(fd, 1);
    close(fd);
    int rc = analyze(4, RUN_FILE, "--json", "--no-write", "--quiet");
    fflush(stdout);
    dup2(saved, 1);
    close(saved);
    assert_int_equal(rc, 0);
    FILE *f = fopen("analysis_e2e.json", "r");
    assert_non_null(f);
    static char text[1 << 22];
    size_t len = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[len] = 0;
    cJSON *root = cJSON_Parse(text);
    assert_non_null(root);
    assert_true(cJSON_GetObjectItem(root, "step")->valuedouble == 2500);
    const char *groups[] = {"sample",  "normal_forces", "bond_forces", "stress",    "branch",
                            "network", "packing",       "modulus",     "compaction"};
    for (size_t k = 0; k < sizeof groups / sizeof groups[0]; k++) {
        cJSON *g = cJSON_GetObjectItem(root, groups[k]);
        if (!g) fail_msg("JSON lacks %s", groups[k]);
        assert_non_null(cJSON_GetObjectItem(g, "units"));
    }
    cJSON *net = cJSON_GetObjectItem(root, "network");
    assert_true(cJSON_IsNumber(cJSON_GetObjectItem(net, "Z_c")));
    assert_string_equal(cJSON_GetObjectItem(cJSON_GetObjectItem(net, "units"), "Z_c")->valuestring, "1");
    cJSON *curve =
        cJSON_GetObjectItem(cJSON_GetObjectItem(cJSON_GetObjectItem(root, "normal_forces"), "curves"), "pdf");
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(curve, "data")), 50);
    cJSON_Delete(root);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_input),    cmocka_unit_test(test_writes_and_replaces),
        cmocka_unit_test(test_sane_numbers), cmocka_unit_test(test_contact_points_match_torques),
        cmocka_unit_test(test_json),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
