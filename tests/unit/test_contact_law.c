/* One Hertz-Mindlin contact update (kernels/contact_law.h) against the
 * formulas of docs/contacts.md: Hertz's normal force, Mindlin's tangential
 * stiffness, the Coulomb cap and the stored elastic energy. */
#include "test_util.h"
#include <math.h>
#include "../kernels/contact_law.h"
#include "unit/segseg_rng.h"

static const double E = 7.0e10, nu = 0.22, R = 1.0e-3, m = 2.0e-5; /* glass: [Pa], [1], [m], [kg] */

static cd_law_params hertz(double mu)
{
    cd_law_params p;
    memset(&p, 0, sizeof p);
    p.law = CD_LAW_HERTZ_MINDLIN;
    p.e_eff = cd_law_contact_modulus(E, nu);
    p.g_eff = cd_law_contact_shear_modulus(E, nu);
    p.eta_n = 0.3;
    p.eta_t = 0.3;
    p.mu = mu;
    p.limit_total = 1;
    p.clip_normal = 1;
    return p;
}

/* Contact along y with overlap delta [m]. */
static cd_contact_geom geom(double delta)
{
    cd_contact_geom g;
    memset(&g, 0, sizeof g);
    g.normal = cd_v3(0, 1, 0);
    g.overlap = delta;
    return g;
}

/* The moduli of one material: E* = E / (2 (1 - nu^2)), G* = G / (2 (2 - nu))
 * with G = E / (2 (1 + nu)). */
static void test_contact_moduli(void **state)
{
    (void)state;
    double G = E / (2 * (1 + nu));
    assert_true(fabs(cd_law_contact_modulus(E, nu) / (1 / (2 * (1 - nu * nu) / E)) - 1) < 1e-15);
    assert_true(fabs(cd_law_contact_shear_modulus(E, nu) / (1 / (2 * (2 - nu) / G)) - 1) < 1e-15);
    assert_true(fabs(cd_law_pair_radius(2e-3, 2e-3) - 1e-3) < 1e-18);
}

/* At rest: F_n = (4/3) E* sqrt(R) delta^(3/2), no tangential force. */
static void test_hertz_normal_force_at_rest(void **state)
{
    (void)state;
    cd_law_params p = hertz(0.5);
    for (double delta = 1e-7; delta < 1e-4; delta *= 10) {
        cd_contact_geom g = geom(delta);
        cd_vec3 s = cd_v3_zero();
        cd_contact_force f = cd_contact_law(p, m, R, &g, cd_v3_zero(), 1e-7, &s);
        double expect = 4.0 / 3.0 * p.e_eff * sqrt(R) * pow(delta, 1.5);
        assert_true(fabs(f.fn / expect - 1) < 1e-13);
        assert_true(fabs(f.force_j.y - f.fn) < 1e-13 * f.fn && f.force_j.x == 0 && f.force_j.z == 0);
    }
}

/* Approaching at v_n: the dashpot adds 2 sqrt(5/6) eta_n sqrt(2 E* a m) |v_n|. */
static void test_hertz_dashpot(void **state)
{
    (void)state;
    cd_law_params p = hertz(0.5);
    double delta = 1e-5, vn = -0.1, a = sqrt(R * delta);
    cd_contact_geom g = geom(delta);
    cd_vec3 s = cd_v3_zero();
    cd_contact_force f = cd_contact_law(p, m, R, &g, cd_v3(0, vn, 0), 1e-7, &s);
    double elastic = 4.0 / 3.0 * p.e_eff * a * delta;
    double gamma = 2 * sqrt(5.0 / 6.0) * p.eta_n * sqrt(2 * p.e_eff * a * m);
    assert_true(fabs(f.fn / (elastic - gamma * vn) - 1) < 1e-13);
}

/* Mindlin: a spring delta_t in the tangent plane, no sliding, gives
 * F_t = -8 G* a delta_t; at another overlap the same spring gives a force
 * in proportion to a = sqrt(R delta) (no rescaling of the history). */
static void test_mindlin_tangential_stiffness(void **state)
{
    (void)state;
    cd_law_params p = hertz(0.5);
    double st = 1e-8; /* [m], far below the cap: 8 G* a st << mu F_n */
    double ft[2];
    for (int k = 0; k < 2; k++) {
        double delta = k ? 4e-6 : 1e-6;
        cd_contact_geom g = geom(delta);
        cd_vec3 s = cd_v3(st, 0, 0);
        cd_contact_force f = cd_contact_law(p, m, R, &g, cd_v3_zero(), 1e-7, &s);
        assert_int_equal(f.sliding, 0);
        double expect = -8 * p.g_eff * sqrt(R * delta) * st;
        assert_true(fabs(f.ft.x / expect - 1) < 1e-13);
        assert_true(s.x == st && s.y == 0 && s.z == 0);
        ft[k] = f.ft.x;
    }
    assert_true(fabs(ft[1] / ft[0] - 2) < 1e-13);
}

/* Beyond mu F_n the force is capped at mu F_n and the spring is shortened
 * to the length that gives that force: the next step at rest gives it
 * again, without sliding further. */
static void test_mindlin_coulomb_cap(void **state)
{
    (void)state;
    double mu = 0.4, delta = 1e-6;
    cd_law_params p = hertz(mu);
    cd_contact_geom g = geom(delta);
    cd_vec3 s = cd_v3(1e-4, 0, 2e-4);
    cd_contact_force f = cd_contact_law(p, m, R, &g, cd_v3_zero(), 1e-7, &s);
    assert_int_equal(f.sliding, 1);
    assert_true(fabs(cd_v3_norm(f.ft) / (mu * f.fn) - 1) < 1e-13);
    assert_true(fabs(f.ft.z / f.ft.x - 2) < 1e-12); /* opposite the spring */
    cd_contact_force again = cd_contact_law(p, m, R, &g, cd_v3_zero(), 1e-7, &s);
    assert_true(fabs(cd_v3_norm(again.ft) / (mu * again.fn) - 1) < 1e-12);
}

/* The stored energy is the work of the normal force, (8/15) E* sqrt(R)
 * delta^(5/2), plus 4 G* a delta_t^2 of the spring. */
static void test_hertz_elastic_energy(void **state)
{
    (void)state;
    cd_law_params p = hertz(0.5);
    double delta = 2e-6, st = 3e-8, a = sqrt(R * delta);
    double u = cd_contact_elastic_energy(p, R, delta, cd_v3(0, 0, st));
    double expect = 8.0 / 15.0 * p.e_eff * sqrt(R) * pow(delta, 2.5) + 4 * p.g_eff * a * st * st;
    assert_true(fabs(u / expect - 1) < 1e-13);
}

/* The law forms v_t and the spring's projection onto the tangent plane as
 * differences, v - n (v . n) (session 19; before: v + (-(v . n)) n, one
 * negation more).  The same bits, because x + (-y) is x - y and (-a) b is
 * -(a b) in IEEE arithmetic (rounding to nearest is symmetric) and a b is
 * b a: checked here on random vectors and factors, with signed zeros,
 * subnormals, huge and tiny magnitudes and exact cancellations. */
static double special_or(double x, int k)
{
    static const double sp[] = {0.0, -0.0, 4.9e-324, -2.2e-308, 1e-300, -1e300, 1.0, -1.0};
    return k < 8 ? sp[k] : x;
}

static void test_difference_form_same_bits(void **state)
{
    (void)state;
    rng_state = 1919;
    for (int i = 0; i < 1000000; i++) {
        int k = (int)(rng_next() % 64);
        cd_vec3 v = rng_vec(pow(10.0, 20 * rng_sym())), n = rng_vec(1.0);
        double d = special_or(pow(10.0, 20 * rng_sym()) * rng_sym(), k);
        if (i % 3 == 0) v.x = special_or(v.x, (int)(rng_next() % 16));
        if (i % 5 == 0) n.y = special_or(n.y, (int)(rng_next() % 16));
        if (i % 7 == 0) d = cd_v3_dot(v, n); /* the law's own factor */
        cd_vec3 got = cd_v3_sub(v, cd_v3_scale(n, d)), want = cd_v3_axpy(v, -d, n);
        assert_memory_equal(&got, &want, sizeof got);
    }
}

/* The Coulomb test without the square root (cd_law_clearly_below, session
 * 20): wherever it says "clearly below", the law's former comparison
 * sqrt(x2) > limit is false, so the law takes the same branch with the
 * same bits.  Checked on limits over 1e-160 .. 1e160 (both sides of the
 * 1e-150 cut) and x2 within a few ulps of limit^2 on either side, where a
 * rounding could tip it, and far from it, where the shortcut must engage
 * (x2 below 0.99 limit^2: a test that always took the root would pass the
 * first check and save nothing); NaN and infinite x2 or limits never take
 * the shortcut wrongly. */
static void test_coulomb_shortcut_agrees_with_sqrt(void **state)
{
    (void)state;
    rng_state = 2020;
    long engaged = 0, far = 0;
    for (int i = 0; i < 1000000; i++) {
        double limit = pow(10.0, 160 * rng_sym()) * (1 + rng_sym() * 0.5);
        double x2 = limit * limit;
        int near = i % 2;
        if (near) {
            for (int k = (int)(rng_next() % 17) - 8; k != 0; k += k > 0 ? -1 : 1)
                x2 = nextafter(x2, k > 0 ? INFINITY : 0.0);
        } else {
            x2 *= 1.5 * (rng_sym() + 1) / 2; /* 0 .. 1.5 limit^2 */
        }
        int clear = cd_law_clearly_below(x2, limit);
        if (clear) assert_false(sqrt(x2) > limit);
        engaged += clear;
        if (!near && x2 < 0.99 * limit * limit && limit > 1e-140 && limit < 1e150) {
            far++;
            assert_true(clear);
        }
    }
    assert_true(far > 100000);
    assert_false(cd_law_clearly_below(NAN, 1.0));
    assert_false(cd_law_clearly_below(1.0, NAN));
    assert_false(cd_law_clearly_below(INFINITY, INFINITY));
    assert_true(cd_law_clearly_below(1e300, INFINITY)); /* sqrt(1e300) > inf is false too */
    assert_false(cd_law_clearly_below(0.0, 0.0));       /* a zero limit: the root decides */
    print_message("shortcut taken in %ld of 1e6 cases (%ld far below the limit)\n", engaged, far);
}

/* The kernels receive the parameters by value (kernels/cl/step.cl): the
 * struct has no padding the OpenCL compiler could lay out differently. */
static void test_params_layout(void **state)
{
    (void)state;
    assert_int_equal(sizeof(cd_law_params), 7 * sizeof(cd_real) + 4 * sizeof(cd_int));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_contact_moduli),
        cmocka_unit_test(test_hertz_normal_force_at_rest),
        cmocka_unit_test(test_hertz_dashpot),
        cmocka_unit_test(test_mindlin_tangential_stiffness),
        cmocka_unit_test(test_mindlin_coulomb_cap),
        cmocka_unit_test(test_hertz_elastic_energy),
        cmocka_unit_test(test_params_layout),
        cmocka_unit_test(test_difference_form_same_bits),
        cmocka_unit_test(test_coulomb_shortcut_agrees_with_sqrt),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
