/* G(r) and the container geometry (host/analysis/analyze_structure.c,
 * analyze_geometry.c) on synthetic point sets with known answers: ideal
 * gases in 3D, 2D and pseudo-2D boxes (G = 1 within the statistical error)
 * and perfect lattices (peaks exactly at the lattice distances, with the
 * right number of neighbours in each shell). */
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

/* A snapshot of n point-like spheres (one zero-length primitive of radius
 * rad each, tip length L = 1 m) in the box [0,W] x [0,H] x [0,T]: six plane
 * walls in 3D, four in 2D (no front and back, as capdem's 2D box; the slab
 * is domain.thickness); dimension 2 or 3.  Positions are set by the caller. */
static void box_snapshot(cd_an_snapshot *s, size_t n, double W, double H, double T, int dim, double rad)
{
    int n_walls = dim == 2 ? 4 : 6;
    memset(s, 0, sizeof(*s));
    assert_int_equal(cd_an_snapshot_alloc(s, n, n, 0, 0, n_walls), 0);
    snprintf(s->path, sizeof s->path, "synthetic");
    cd_config_defaults(&s->cfg);
    s->cfg_ok = 1;
    snprintf(s->cfg.domain, sizeof s->cfg.domain, "box");
    s->cfg.domain_kind = CD_DOMAIN_BOX;
    s->cfg.dimension = dim;
    s->cfg.box_thickness = T;
    s->n_shapes = 1;
    s->shapes = calloc(1, sizeof(cd_an_shape));
    snprintf(s->shapes[0].kind, sizeof s->shapes[0].kind, "sphere");
    s->shapes[0].volume = 4.0 / 3.0 * CD_PI * rad * rad * rad;
    s->shapes[0].tip_length = 1.0;
    s->shapes[0].bounding_radius = rad;
    s->shapes[0].n_arms = 1;
    s->shapes[0].arms[0][6] = rad;
    const double pt[6][3] = {{0, 0, 0}, {0, H, 0}, {0, 0, 0}, {W, 0, 0}, {0, 0, 0}, {0, 0, T}};
    const double nm[6][3] = {{0, 1, 0}, {0, -1, 0}, {1, 0, 0}, {-1, 0, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int w = 0; w < n_walls; w++) {
        s->walls[w].type = CD_WALL_PLANE;
        s->walls[w].point = cd_v3(pt[w][0], pt[w][1], pt[w][2]);
        s->walls[w].normal = cd_v3(nm[w][0], nm[w][1], nm[w][2]);
    }
    for (size_t p = 0; p < n; p++) {
        s->scale[p] = 1;
        s->prim_particle[p] = (int32_t)p;
        s->prim_radius[p] = rad;
    }
}

/* Primitives follow the particle centres (the container top is the
 * highest particle point). */
static void sync_prims(cd_an_snapshot *s)
{
    for (size_t p = 0; p < s->n; p++) s->prim_a[p] = s->prim_b[p] = s->pos[p];
}

/* Runs G(r) with the given margins, r_max and bin (units of L = 1 m). */
static void run_rdf(cd_an_snapshot *s, double ms, double me, double rmax, double bin, cd_an_report *rep,
                    cd_an_geometry *g)
{
    cd_an_options opt;
    cd_an_options_defaults(&opt);
    opt.rdf_max = rmax;
    opt.rdf_bin = bin;
    cd_an_geometry_setup(s, ms, me, g);
    cd_an_bonds b;
    memset(&b, 0, sizeof b);
    cd_an_input in = {s, g, &b, &opt, 0};
    memset(rep, 0, sizeof(*rep));
    char err[512];
    int rc = cd_an_rdf(&in, rep, err, sizeof err);
    if (rc) fail_msg("rdf: %s", err);
}

/* Ideal gas: |G - 1| must stay within 4.5 standard errors in every bin.
 * Each bin's count is Poisson-like with the pairs between two reference
 * particles counted twice (variance up to 2 x mean), and the density used
 * to normalise, N_ref / V_core, has relative error 1/sqrt(N_ref) common to
 * every bin. */
static void check_ideal(const cd_an_report *rep, double rmin)
{
    const cd_an_curve *c = cd_an_curve_find(rep, "rdf", "rdf");
    assert_non_null(c);
    double nref = cd_an_value(rep, "rdf", "n_reference");
    double worst = 0;
    for (size_t i = 0; i < c->rows; i++) {
        double r = c->data[4 * i], G = c->data[4 * i + 1];
        if (r < rmin) continue;
        /* expected pair count of the bin: G = count / expected */
        double dN = c->data[4 * i + 2] - (i ? c->data[4 * (i - 1) + 2] : 0); /* per reference particle */
        double expected = dN * nref / (G > 0 ? G : 1);
        double se = sqrt(2 / expected + 1 / nref);
        double z = fabs(G - 1) / se;
        if (z > worst) worst = z;
    }
    print_message("ideal gas: worst bin |G - 1| = %.2f standard errors\n", worst);
    if (worst > 4.5) fail_msg("ideal gas: worst bin |G - 1| = %.2f standard errors", worst);
}

static void test_rdf_ideal_gas_3d(void **state)
{
    (void)state;
    const size_t n = 40000;
    cd_an_snapshot s;
    box_snapshot(&s, n, 20, 20, 20, 3, 1e-3);
    cd_rng r;
    cd_rng_seed(&r, 21);
    for (size_t p = 0; p < n; p++)
        s.pos[p] = cd_v3(20 * cd_rng_uniform(&r), 20 * cd_rng_uniform(&r), 20 * cd_rng_uniform(&r));
    sync_prims(&s);
    cd_an_report rep;
    cd_an_geometry g;
    run_rdf(&s, 3, 3, 3, 0.1, &rep, &g);
    assert_int_equal(g.kind, CD_AN_BOX3D);
    check_ideal(&rep, 0.5);
    /* rho(r) = N(r)/N(r_max) ends at 1 and grows like r^3 */
    const cd_an_curve *c = cd_an_curve_find(&rep, "rdf", "rdf");
    assert_true(fabs(c->data[4 * (c->rows - 1) + 3] - 1) < 1e-12);
    assert_true(fabs(c->data[4 * 14 + 3] / pow(1.5 / 3.0, 3) - 1) < 0.03);
    cd_an_report_free(&rep);
    cd_an_snapshot_free(&s);
}

static void test_rdf_ideal_gas_2d(void **state)
{
    (void)state;
    const size_t n = 20000;
    cd_an_snapshot s;
    box_snapshot(&s, n, 100, 100, 1, 2, 1e-3);
    cd_rng r;
    cd_rng_seed(&r, 22);
    for (size_t p = 0; p < n; p++) s.pos[p] = cd_v3(100 * cd_rng_uniform(&r), 100 * cd_rng_uniform(&r), 0.5);
    sync_prims(&s);
    cd_an_report rep;
    cd_an_geometry g;
    run_rdf(&s, -1, -1, 5, 0.1, &rep, &g); /* default margins: 10 L */
    assert_int_equal(g.kind, CD_AN_BOX2D);
    assert_true(fabs(g.margin_side - 10) < 1e-12);
    check_ideal(&rep, 0.5);
    cd_an_report_free(&rep);
    cd_an_snapshot_free(&s);
}

/* Pseudo-2D: a slab 2 L thick; the shell volume inside the slab makes G
 * flat also below r = T, where neither the 2D nor the 3D formula holds. */
static void test_rdf_ideal_gas_pseudo2d(void **state)
{
    (void)state;
    const size_t n = 40000;
    cd_an_snapshot s;
    box_snapshot(&s, n, 100, 100, 2, 3, 1e-3);
    cd_rng r;
    cd_rng_seed(&r, 23);
    for (size_t p = 0; p < n; p++)
        s.pos[p] = cd_v3(100 * cd_rng_uniform(&r), 100 * cd_rng_uniform(&r), 2 * cd_rng_uniform(&r));
    sync_prims(&s);
    cd_an_report rep;
    cd_an_geometry g;
    run_rdf(&s, -1, -1, 5, 0.1, &rep, &g);
    assert_int_equal(g.kind, CD_AN_PSEUDO2D);
    /* the slab thickness estimated from the spread of z: 2 within 1% */
    assert_true(fabs(cd_an_value(&rep, "rdf", "slab_thickness") / 2 - 1) < 0.01);
    check_ideal(&rep, 0.3);
    cd_an_report_free(&rep);
    cd_an_snapshot_free(&s);
}

/* Neighbour shells of a perfect lattice: distance and count.  Every
 * reference particle has the same neighbours, so N(r) (the mean count
 * within r) must step by exactly each shell's count in the bin of its
 * distance and stay flat elsewhere. */
static void check_shells(const cd_an_report *rep, const double *dist, const int *count, int nshell)
{
    const cd_an_curve *c = cd_an_curve_find(rep, "rdf", "rdf");
    assert_non_null(c);
    double dr = cd_an_value(rep, "rdf", "bin_over_L");
    for (size_t i = 0; i < c->rows; i++) {
        double step = c->data[4 * i + 2] - (i ? c->data[4 * (i - 1) + 2] : 0);
        int expect = 0;
        for (int k = 0; k < nshell; k++) {
            /* the lattice distances are chosen away from bin edges */
            double t = dist[k] / dr;
            assert_true(t - floor(t) > 0.01 && t - floor(t) < 0.99);
            if ((size_t)floor(t) == i) {
                expect = count[k];
                /* the peak's bin centre is within half a bin of the distance */
                assert_true(fabs(c->data[4 * i] - dist[k]) <= 0.5 * dr + 1e-12);
            }
        }
        if (fabs(step - expect) > 1e-9)
            fail_msg("bin %zu (r = %g L): %g neighbours, expected %d", i, c->data[4 * i], step, expect);
        assert_true((c->data[4 * i + 1] > 0) == (expect > 0));
    }
}

static void test_rdf_cubic_lattice(void **state)
{
    (void)state;
    const int m = 24;
    cd_an_snapshot s;
    box_snapshot(&s, (size_t)m * m * m, m, m, m, 3, 0.01);
    size_t p = 0;
    for (int k = 0; k < m; k++)
        for (int j = 0; j < m; j++)
            for (int i = 0; i < m; i++) s.pos[p++] = cd_v3(i + 0.5, j + 0.5, k + 0.5);
    sync_prims(&s);
    cd_an_report rep;
    cd_an_geometry g;
    run_rdf(&s, 3, 3, 2.9, 0.03, &rep, &g);
    const double d[] = {1, sqrt(2), sqrt(3), 2, sqrt(5), sqrt(6), sqrt(8)};
    const int cnt[] = {6, 12, 8, 6, 24, 24, 12};
    check_shells(&rep, d, cnt, 7);
    cd_an_report_free(&rep);
    cd_an_snapshot_free(&s);
}

static void test_rdf_hexagonal_lattice_2d(void **state)
{
    (void)state;
    const int m = 40;
    const double h = sqrt(3) / 2; /* row spacing [L] */
    cd_an_snapshot s;
    box_snapshot(&s, (size_t)m * m, m + 0.5, m * h, 1, 2, 0.01); /* x of the sites: 0.5 .. m */
    size_t p = 0;
    for (int j = 0; j < m; j++)
        for (int i = 0; i < m; i++) s.pos[p++] = cd_v3(0.5 + i + 0.5 * (j & 1), (j + 0.5) * h, 0.5);
    sync_prims(&s);
    cd_an_report rep;
    cd_an_geometry g;
    run_rdf(&s, 3, 3, 2.9, 0.03, &rep, &g);
    assert_int_equal(g.kind, CD_AN_BOX2D);
    const double d[] = {1, sqrt(3), 2, sqrt(7)};
    const int cnt[] = {6, 6, 6, 12};
    check_shells(&rep, d, cnt, 4);
    cd_an_report_free(&rep);
    cd_an_snapshot_free(&s);
}

/* Container and core of a cylinder and a ball; no core when the packing is
 * too small, and G(r) then refuses with a message (exit 2 upstream). */
static void test_geometry_cylinder_ball(void **state)
{
    (void)state;
    cd_an_snapshot s;
    box_snapshot(&s, 2, 1, 1, 1, 3, 0.1);
    snprintf(s.cfg.domain, sizeof s.cfg.domain, "cylinder");
    s.cfg.domain_kind = CD_DOMAIN_CYLINDER;
    memset(s.walls, 0, 6 * sizeof(cd_wall));
    s.n_walls = 2;
    s.walls[0].type = CD_WALL_CYLINDER;
    s.walls[0].normal = cd_v3(0, 1, 0);
    s.walls[0].radius = 10;
    s.walls[1].type = CD_WALL_PLANE;
    s.walls[1].normal = cd_v3(0, 1, 0);
    s.pos[0] = cd_v3(0, 0.1, 0);
    s.pos[1] = cd_v3(1, 29.9, 0);
    sync_prims(&s);
    cd_an_geometry g;
    cd_an_geometry_setup(&s, -1, -1, &g);
    assert_int_equal(g.kind, CD_AN_CYLINDER);
    /* open top: the container ends at the highest particle point, 30 */
    assert_true(fabs(g.hi[1] - 30) < 1e-12);
    assert_true(fabs(g.volume - CD_PI * 100 * 30) < 1e-9);
    assert_true(fabs(g.core_volume - CD_PI * 49 * 10) < 1e-9); /* radius 10 - 3, height 30 - 20 */
    assert_true(cd_an_in_core(&g, cd_v3(6.9, 15, 0)) && !cd_an_in_core(&g, cd_v3(7.1, 15, 0)));
    assert_true(!cd_an_in_core(&g, cd_v3(0, 9.9, 0)));
    /* a piston below the top particle caps the container */
    s.n_walls = 3;
    s.walls[2].type = CD_WALL_PLANE;
    s.walls[2].normal = cd_v3(0, -1, 0);
    s.walls[2].point = cd_v3(0, 25, 0);
    cd_an_geometry_setup(&s, -1, -1, &g);
    assert_true(fabs(g.hi[1] - 25) < 1e-12);
    /* too short for the 10 L end margins: no core, G(r) refuses */
    s.walls[2].point = cd_v3(0, 15, 0);
    cd_an_report rep;
    memset(&rep, 0, sizeof rep);
    cd_an_options opt;
    cd_an_options_defaults(&opt);
    cd_an_geometry_setup(&s, -1, -1, &g);
    cd_an_bonds b;
    memset(&b, 0, sizeof b);
    cd_an_input in = {&s, &g, &b, &opt, 0};
    char err[512];
    assert_int_equal(cd_an_rdf(&in, &rep, err, sizeof err), 2);
    assert_non_null(strstr(err, "core"));
    /* ball */
    snprintf(s.cfg.domain, sizeof s.cfg.domain, "ball");
    s.cfg.domain_kind = CD_DOMAIN_BALL;
    s.n_walls = 1;
    s.walls[0].type = CD_WALL_SPHERE;
    s.walls[0].point = cd_v3(1, 2, 3);
    s.walls[0].radius = 5;
    cd_an_geometry_setup(&s, -1, -1, &g);
    assert_int_equal(g.kind, CD_AN_BALL);
    assert_true(fabs(g.volume - 4.0 / 3.0 * CD_PI * 125) < 1e-9);
    assert_true(fabs(g.core_volume - 4.0 / 3.0 * CD_PI * 8) < 1e-9);
    assert_true(cd_an_in_core(&g, cd_v3(1, 2, 4.9)) && !cd_an_in_core(&g, cd_v3(1, 2, 5.1)));
    cd_an_report_free(&rep);
    cd_an_snapshot_free(&s);
}

/* Packing fraction of a known arrangement: spheres of radius 0.25 L on a
 * cubic lattice of spacing 1 L in a 16^3 box.  The container ends at the
 * highest particle point (15.75), so the container value is N V / (16 x 16
 * x 15.75) exactly.  The core (3 L margins: x, z in [3, 13], y in [3,
 * 12.75]) holds exactly 10^3 whole spheres and cuts none, so its true
 * solid fraction is 1000 V / V_core: the centre estimate gives it exactly
 * and the Monte Carlo one within 4 of its own standard errors. */
static void test_packing_lattice(void **state)
{
    (void)state;
    const int m = 16;
    const double rad = 0.25;
    cd_an_snapshot s;
    box_snapshot(&s, (size_t)m * m * m, m, m, m, 3, rad);
    size_t p = 0;
    for (int k = 0; k < m; k++)
        for (int j = 0; j < m; j++)
            for (int i = 0; i < m; i++) s.pos[p++] = cd_v3(i + 0.5, j + 0.5, k + 0.5);
    sync_prims(&s);
    cd_an_options opt;
    cd_an_options_defaults(&opt);
    opt.mc_points = 200000;
    cd_an_geometry g;
    cd_an_geometry_setup(&s, 3, 3, &g);
    cd_an_bonds b;
    memset(&b, 0, sizeof b);
    cd_an_input in = {&s, &g, &b, &opt, 0};
    cd_an_report rep;
    memset(&rep, 0, sizeof rep);
    char err[512];
    assert_int_equal(cd_an_packing(&in, &rep, err, sizeof err), 0);
    double V = 4.0 / 3.0 * CD_PI * rad * rad * rad;
    assert_true(fabs(cd_an_value(&rep, "packing", "phi_container") - m * m * m * V / (16 * 16 * 15.75)) < 1e-12);
    double vcore = cd_an_value(&rep, "packing", "core_volume");
    assert_true(fabs(vcore - 10 * 9.75 * 10) < 1e-9);
    double truth = 1000 * V / vcore;
    assert_true(fabs(cd_an_value(&rep, "packing", "phi_core_centres") - truth) < 1e-12);
    double mc = cd_an_value(&rep, "packing", "phi_core"), se = cd_an_value(&rep, "packing", "phi_core_error");
    assert_true(fabs(mc - truth) < 4 * se);
    cd_an_report_free(&rep);
    cd_an_snapshot_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rdf_ideal_gas_3d),         cmocka_unit_test(test_rdf_ideal_gas_2d),
        cmocka_unit_test(test_rdf_ideal_gas_pseudo2d),   cmocka_unit_test(test_rdf_cubic_lattice),
        cmocka_unit_test(test_rdf_hexagonal_lattice_2d), cmocka_unit_test(test_geometry_cylinder_ball),
        cmocka_unit_test(test_packing_lattice),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
