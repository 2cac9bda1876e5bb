/* Unit tests of the segment-segment narrow phase (kernels/segseg.h,
 * docs/references.md, Contacts); the OpenCL C 1.2 syntax check of the
 * geometry headers is tests/unit/test_geometry_opencl_c.c. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "segseg.h"
#include "walls.h"

#include "unit/segseg_rng.h"

/* dyadic numbers k/1024 in [-1, 1]: sums and small multiples are exact */
static double rng_dyadic(void) { return (double)((int)(rng_next() % 2049) - 1024) / 1024.0; }
static cd_vec3 rng_dyadic_vec(void) { return cd_v3(rng_dyadic(), rng_dyadic(), rng_dyadic()); }
static cd_vec3 rng_dyadic_nonzero_vec(void)
{
    cd_vec3 v;
    do v = rng_dyadic_vec();
    while (cd_v3_norm2(v) < 0.01);
    return v;
}

/* ---- reference distance ---------------------------------------------- */
/* For a fixed s the best t is the clamped projection of P(s) onto segment j,
 * so G(s) = min_t |P(s) - Q(t)|^2 is exact; G is convex, and a golden-section
 * search in long double (80-bit on x86) over s converges far below double
 * rounding.  Independent of the algorithm under test. */
typedef struct {
    long double x, y, z;
} lvec;
static lvec lv(cd_vec3 v)
{
    lvec r = {v.x, v.y, v.z};
    return r;
}
static long double ldot(lvec a, lvec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static lvec lsub(lvec a, lvec b)
{
    lvec r = {a.x - b.x, a.y - b.y, a.z - b.z};
    return r;
}
static lvec laxpy(lvec a, long double s, lvec b)
{
    lvec r = {a.x + s * b.x, a.y + s * b.y, a.z + s * b.z};
    return r;
}

static long double ref_G(lvec p0, lvec d1, lvec q0, lvec d2, long double s)
{
    lvec P = laxpy(p0, s, d1);
    long double e = ldot(d2, d2);
    long double t = 0;
    lvec diff;
    if (e > 0) {
        t = ldot(lsub(P, q0), d2) / e;
        t = t < 0 ? 0 : (t > 1 ? 1 : t);
    }
    diff = lsub(P, laxpy(q0, t, d2));
    return ldot(diff, diff);
}

static double ref_distance(cd_vec3 p0, cd_vec3 p1, cd_vec3 q0, cd_vec3 q1)
{
    lvec P0 = lv(p0), Q0 = lv(q0);
    lvec D1 = lsub(lv(p1), P0), D2 = lsub(lv(q1), Q0);
    const long double gr = 0.6180339887498948482045868343656381L;
    long double lo = 0, hi = 1;
    long double x1 = hi - gr * (hi - lo), x2 = lo + gr * (hi - lo);
    long double f1 = ref_G(P0, D1, Q0, D2, x1), f2 = ref_G(P0, D1, Q0, D2, x2);
    long double best = ref_G(P0, D1, Q0, D2, 0);
    long double g1 = ref_G(P0, D1, Q0, D2, 1);
    int it;
    if (g1 < best) best = g1;
    for (it = 0; it < 150; it++) {
        if (f1 <= f2) {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - gr * (hi - lo);
            f1 = ref_G(P0, D1, Q0, D2, x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + gr * (hi - lo);
            f2 = ref_G(P0, D1, Q0, D2, x2);
        }
        if (f1 < best) best = f1;
        if (f2 < best) best = f2;
    }
    return (double)sqrtl(best);
}

/* ---- random cases ------------------------------------------------------ */
enum {
    CASE_GENERIC,
    CASE_PARALLEL,
    CASE_NEAR_PARALLEL,
    CASE_NEAR_PARALLEL_CROSSING,
    CASE_OTHER_ANGLES,
    CASE_COLLINEAR_OVERLAP,
    CASE_COLLINEAR_DISJOINT,
    CASE_POINT_I,
    CASE_POINT_J,
    CASE_POINT_BOTH,
    CASE_CROSSING,
    CASE_SHORT_LONG,
    CASE_COUNT
};
static const char *case_name[CASE_COUNT] = {"generic",
                                            "exactly parallel",
                                            "nearly parallel 1e-9 rad",
                                            "nearly parallel crossing 1e-9 rad",
                                            "angles 1e-5..1e-15 rad",
                                            "collinear overlapping",
                                            "collinear disjoint",
                                            "zero-length i",
                                            "zero-length j",
                                            "zero-length both",
                                            "crossing (D = 0)",
                                            "length ratio 1e-7"};

/* rotate v by angle th about the unit axis k (Rodrigues, k perpendicular to v) */
static cd_vec3 rotate_perp(cd_vec3 v, cd_vec3 k, double th)
{
    return cd_v3_add(cd_v3_scale(v, cos(th)), cd_v3_scale(cd_v3_cross(k, v), sin(th)));
}
static cd_vec3 random_perp_unit(cd_vec3 v)
{
    cd_vec3 c;
    do c = cd_v3_cross(v, rng_vec(1.0));
    while (cd_v3_norm(c) < 1e-3);
    return cd_v3_scale(c, 1.0 / cd_v3_norm(c));
}
static double rng_ratio(void)
{
    static const double k[] = {-2.0, -1.0, -0.75, -0.5, -0.25, 0.25, 0.5, 0.75, 1.0, 2.0};
    return k[rng_next() % 10];
}

static void make_case(int kind, cd_vec3 *p0, cd_vec3 *p1, cd_vec3 *q0, cd_vec3 *q1)
{
    cd_vec3 d1, d2, X, k;
    double th;
    switch (kind) {
    case CASE_GENERIC:
        *p0 = rng_vec(1);
        *p1 = rng_vec(1);
        *q0 = rng_vec(1);
        *q1 = rng_vec(1);
        break;
    case CASE_PARALLEL:
        *p0 = rng_dyadic_vec();
        d1 = rng_dyadic_nonzero_vec();
        *p1 = cd_v3_add(*p0, d1);
        *q0 = rng_dyadic_vec();
        *q1 = cd_v3_add(*q0, cd_v3_scale(d1, rng_ratio()));
        break;
    case CASE_NEAR_PARALLEL:
    case CASE_NEAR_PARALLEL_CROSSING:
    case CASE_OTHER_ANGLES:
        *p0 = rng_vec(1);
        d1 = rng_vec(1);
        *p1 = cd_v3_add(*p0, d1);
        k = random_perp_unit(d1);
        th = 1e-9;
        if (kind == CASE_OTHER_ANGLES) th = pow(10.0, -5.0 - 10.0 * rng_u());
        d2 = cd_v3_scale(rotate_perp(d1, k, th), rng_ratio());
        if (kind == CASE_NEAR_PARALLEL_CROSSING) {
            X = cd_v3_axpy(*p0, rng_u(), d1);
            *q0 = cd_v3_axpy(X, -rng_u(), d2);
        } else {
            *q0 = cd_v3_add(*p0, rng_vec(0.5));
        }
        *q1 = cd_v3_add(*q0, d2);
        break;
    case CASE_COLLINEAR_OVERLAP:
    case CASE_COLLINEAR_DISJOINT: {
        double mu, kk;
        *p0 = rng_dyadic_vec();
        d1 = rng_dyadic_nonzero_vec();
        *p1 = cd_v3_add(*p0, d1);
        if (kind == CASE_COLLINEAR_OVERLAP) {
            mu = (double)(rng_next() % 9) / 8.0; /* q0 on segment i */
            kk = rng_ratio();
        } else {
            mu = 1.0 + (double)(1 + rng_next() % 8) / 8.0; /* beyond p1 ... */
            kk = 0.25 + (double)(rng_next() % 4) / 4.0;    /* ... pointing away */
            if (rng_next() & 1) {
                mu = -mu + 1.0;
                kk = -kk;
            } /* or before p0 */
        }
        *q0 = cd_v3_axpy(*p0, mu, d1);
        *q1 = cd_v3_axpy(*q0, kk, d1);
        break;
    }
    case CASE_POINT_I:
        *p0 = rng_vec(1);
        *p1 = *p0;
        *q0 = rng_vec(1);
        *q1 = rng_vec(1);
        break;
    case CASE_POINT_J:
        *p0 = rng_vec(1);
        *p1 = rng_vec(1);
        *q0 = rng_vec(1);
        *q1 = *q0;
        break;
    case CASE_POINT_BOTH:
        *p0 = rng_vec(1);
        *p1 = *p0;
        *q0 = rng_vec(1);
        *q1 = *q0;
        if (rng_next() % 4 == 0) *q0 = *q1 = *p0;
        break;
    case CASE_CROSSING: {
        /* exact intersection: X = p0 + s d1 = q0 + t d2 with dyadic s, t */
        double s = (double)(rng_next() % 9) / 8.0, t = (double)(rng_next() % 9) / 8.0;
        X = rng_dyadic_vec();
        d1 = rng_dyadic_nonzero_vec();
        d2 = rng_dyadic_nonzero_vec();
        *p0 = cd_v3_axpy(X, -s, d1);
        *p1 = cd_v3_add(*p0, d1);
        *q0 = cd_v3_axpy(X, -t, d2);
        *q1 = cd_v3_add(*q0, d2);
        break;
    }
    case CASE_SHORT_LONG:
        *p0 = rng_vec(1);
        *p1 = cd_v3_add(*p0, rng_vec(1e-7));
        *q0 = rng_vec(1);
        *q1 = rng_vec(1);
        if (rng_next() & 1) {
            cd_vec3 tmp0 = *p0, tmp1 = *p1;
            *p0 = *q0;
            *p1 = *q1;
            *q0 = tmp0;
            *q1 = tmp1;
        }
        break;
    default:
        break;
    }
}

static int finite_vec(cd_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }
static double len(cd_vec3 a, cd_vec3 b) { return cd_v3_norm(cd_v3_sub(b, a)); }

/* Same centre and same length: the D = 0 normal cannot be antisymmetric. */
static int same_segment(cd_vec3 p0, cd_vec3 p1, cd_vec3 q0, cd_vec3 q1)
{
    cd_vec3 mp = cd_v3_add(p0, p1), mq = cd_v3_add(q0, q1);
    return mp.x == mq.x && mp.y == mq.y && mp.z == mq.z &&
           cd_v3_norm2(cd_v3_sub(p1, p0)) == cd_v3_norm2(cd_v3_sub(q1, q0));
}

#define PAIRS_PER_CASE 2000

/* 24000 random pairs: distance of the returned pair vs the reference. */
static void test_closest_distance_matches_bruteforce_reference(void **state)
{
    int kind, i;
    double worst_all = 0;
    (void)state;
    rng_state = 12345;
    for (kind = 0; kind < CASE_COUNT; kind++) {
        double worst = 0;
        for (i = 0; i < PAIRS_PER_CASE; i++) {
            cd_vec3 p0, p1, q0, q1;
            double s = -1, t = -1, D, Dref, L, err;
            make_case(kind, &p0, &p1, &q0, &q1);
            cd_segseg_closest(p0, p1, q0, q1, &s, &t);
            assert_true(s >= 0.0 && s <= 1.0);
            assert_true(t >= 0.0 && t <= 1.0);
            D = len(cd_v3_lerp(p0, p1, s), cd_v3_lerp(q0, q1, t));
            Dref = ref_distance(p0, p1, q0, q1);
            L = fmax(len(p0, p1), len(q0, q1));
            if (L == 0) L = fmax(len(p0, q0), 1e-300);
            err = fabs(D - Dref) / L;
            if (!(err < 1e-12))
                print_error("case %s #%d: D = %.17g ref %.17g err %.3g\n", case_name[kind], i, D, Dref, err);
            assert_true(err < 1e-12);
            if (err > worst) worst = err;
        }
        print_message("  %-36s max |D - D_ref| / L = %.3g (%d pairs)\n", case_name[kind], worst, PAIRS_PER_CASE);
        if (worst > worst_all) worst_all = worst;
    }
    print_message("  all cases: max relative error %.3g over %d pairs\n", worst_all, CASE_COUNT * PAIRS_PER_CASE);
}

/* Every output of cd_segseg_contact is finite, n is a unit vector, and
 * n = (b - a)/D points from i to j whenever D > 0. */
static void test_contact_is_finite_with_unit_normal_from_i_to_j(void **state)
{
    int kind, i;
    (void)state;
    rng_state = 777;
    for (kind = 0; kind < CASE_COUNT; kind++) {
        for (i = 0; i < 500; i++) {
            cd_vec3 p0, p1, q0, q1, a, b;
            double s, t;
            cd_contact_geom g;
            make_case(kind, &p0, &p1, &q0, &q1);
            cd_segseg_contact(p0, p1, 0.1, q0, q1, 0.2, sin(2.0 * CD_PI / 180.0), &g);
            assert_true(finite_vec(g.point) && finite_vec(g.normal));
            assert_true(isfinite(g.distance) && isfinite(g.overlap));
            assert_true(fabs(cd_v3_norm(g.normal) - 1.0) < 1e-15);
            assert_true(fabs(g.overlap - (0.3 - g.distance)) < 1e-15);
            cd_segseg_closest(p0, p1, q0, q1, &s, &t);
            a = cd_v3_lerp(p0, p1, s);
            b = cd_v3_lerp(q0, q1, t);
            if (g.distance > 0) {
                /* projection of b - a on n is D: n points from a (on i) to b (on j) */
                assert_true(fabs(cd_v3_dot(cd_v3_sub(b, a), g.normal) - g.distance) < 1e-15);
            }
            if (!g.parallel) {
                cd_vec3 c = cd_v3_scale(cd_v3_add(a, b), 0.5);
                assert_true(len(c, g.point) < 1e-15);
            }
        }
    }
}

/* The force kernel's pre-test (cd_segseg_clearly_apart) may say "apart"
 * only where cd_segseg_contact_at finds no overlap, and it must say it for
 * every pair separated by more than its margin (1e-9 of the squared
 * reach), or it would spare nothing.  Radii are set around each pair's own
 * distance D: just touching (sum 1 + 1e-12 of D), just apart (1 - 1e-12,
 * inside the margin: either answer is right, the contact must still be
 * found separated) and clearly apart (1 - 1e-6). */
static void test_clearly_apart_never_hides_a_contact(void **state)
{
    int kind, i, spared = 0, clear = 0;
    double sp = sin(2.0 * CD_PI / 180.0);
    (void)state;
    rng_state = 9191;
    for (kind = 0; kind < CASE_COUNT; kind++) {
        for (i = 0; i < 500; i++) {
            cd_vec3 p0, p1, q0, q1;
            double s, t;
            cd_contact_geom g;
            make_case(kind, &p0, &p1, &q0, &q1);
            cd_segseg_closest(p0, p1, q0, q1, &s, &t);
            double D = len(cd_v3_lerp(p0, p1, s), cd_v3_lerp(q0, q1, t));
            if (!(D > 1e-9)) continue; /* touching axes: no radius makes them apart */
            const double factor[3] = {1 + 1e-12, 1 - 1e-12, 1 - 1e-6};
            for (int f = 0; f < 3; f++) {
                double ri = 0.3 * D * factor[f], rj = 0.7 * D * factor[f];
                int apart = cd_segseg_clearly_apart(p0, p1, ri, q0, q1, rj, s, t);
                cd_segseg_contact_at(p0, p1, ri, q0, q1, rj, s, t, sp, 0, &g);
                if (apart) {
                    spared++;
                    assert_true(g.overlap < 0);
                }
                if (f == 0) assert_false(apart);
                if (f == 2) {
                    clear++;
                    assert_true(apart);
                }
            }
            /* the split call gives the same geometry as the whole one */
            cd_contact_geom h;
            cd_segseg_contact(p0, p1, 0.1, q0, q1, 0.2, sp, &h);
            cd_segseg_contact_at(p0, p1, 0.1, q0, q1, 0.2, s, t, sp, 0, &g);
            assert_true(g.distance == h.distance && g.overlap == h.overlap && g.parallel == h.parallel);
            assert_memory_equal(&g.normal, &h.normal, sizeof g.normal);
            assert_memory_equal(&g.point, &h.point, sizeof g.point);
        }
    }
    assert_true(clear > 1000);
    print_message("  %d radius choices found apart (%d of them 1e-6 of D apart, all found)\n", spared, clear);
}

/* With material.parallel_blend the contact point moves continuously with
 * the angle between the axes (docs/contacts.md): a unit segment turned
 * about one end from 1.5 to 4.5
 * degrees against a parallel one 0.2 away (radii 0.15, overlapping).  Below
 * the 2-degree cut-off the point is the middle of the overlap section,
 * beyond 4 degrees the closest points' middle; in between it slides from
 * one to the other, 0.5 apart, by at most 4 x the steepest slope (0.5 over
 * sin 4 - sin 2, i.e. 14.3 per radian) between samples.  The rule without
 * the band jumped by 0.5 at 2 degrees. */
static void test_parallel_point_is_continuous_in_the_angle(void **state)
{
    double sp = sin(2.0 * CD_PI / 180.0), deg = CD_PI / 180.0, step = 3.0 * deg / 3000, worst = 0;
    cd_vec3 p0 = cd_v3(0, 0, 0), p1 = cd_v3(1, 0, 0), q0 = cd_v3(0, 0.2, 0), last = cd_v3(0, 0, 0);
    (void)state;
    for (int k = 0; k <= 3000; k++) {
        double th = 1.5 * deg + k * step;
        cd_vec3 q1 = cd_v3_add(q0, cd_v3(cos(th), sin(th), 0));
        cd_contact_geom g, h;
        double s, t;
        cd_segseg_closest(p0, p1, q0, q1, &s, &t);
        cd_segseg_contact_at(p0, p1, 0.15, q0, q1, 0.15, s, t, sp, 1, &g);
        cd_segseg_contact(p0, p1, 0.15, q0, q1, 0.15, sp, &h); /* the paper's rule: a step at 2 degrees */
        assert_int_equal(h.parallel, sin(th) < sp);
        assert_true(g.overlap > 0);
        if (sin(th) < sp * (1 - 1e-12)) {
            assert_int_equal(g.parallel, 1);
            assert_true(fabs(g.point.x - 0.5) < 0.005); /* middle of the overlap section (0.498 at 2 deg) */
        }
        if (sin(th) > 2 * sp * (1 + 1e-12)) { /* beyond 4.002 degrees */
            assert_int_equal(g.parallel, 0);
            assert_true(len(g.point, cd_v3(0, 0.1, 0)) < 1e-12); /* middle of the closest points */
        }
        if (k > 0 && len(g.point, last) > worst) worst = len(g.point, last);
        last = g.point;
    }
    print_message("  largest move of the point between samples %.3g (bound %.3g)\n", worst, 4 * 14.3 * step);
    assert_true(worst < 4 * 14.3 * step);
}

/* Exchanging i and j keeps D, the overlap and the contact point, and flips
 * the normal (random pairs of every kind, parallel rule on). */
static void test_swapping_i_and_j_flips_normal_keeps_distance_and_point(void **state)
{
    int kind, i;
    double sp = sin(2.0 * CD_PI / 180.0);
    (void)state;
    rng_state = 4242;
    for (kind = 0; kind < CASE_COUNT; kind++) {
        for (i = 0; i < 500; i++) {
            cd_vec3 p0, p1, q0, q1;
            cd_contact_geom g, h;
            make_case(kind, &p0, &p1, &q0, &q1);
            cd_segseg_contact(p0, p1, 0.1, q0, q1, 0.2, sp, &g);
            cd_segseg_contact(q0, q1, 0.2, p0, p1, 0.1, sp, &h);
            assert_true(fabs(g.distance - h.distance) < 1e-15);
            assert_true(fabs(g.overlap - h.overlap) < 1e-15);
            assert_int_equal(g.parallel, h.parallel);
            if (!(len(g.point, h.point) < 1e-14))
                print_error("%s #%d: points differ by %g\n", case_name[kind], i, len(g.point, h.point));
            assert_true(len(g.point, h.point) < 1e-14);
            /* near D = 0 the direction of b - a is rounding noise (and one
             * order may find D = 0 exactly, the other D = 1e-17); compare
             * normals where they are meaningful or both exactly defined */
            if (((g.distance > 1e-9 && h.distance > 1e-9) || (g.distance == 0.0 && h.distance == 0.0)) &&
                !same_segment(p0, p1, q0, q1)) {
                if (!(len(g.normal, cd_v3_neg(h.normal)) < 1e-9))
                    print_error("%s #%d: D %g n %g %g %g swapped %g %g %g\n", case_name[kind], i, g.distance,
                                g.normal.x, g.normal.y, g.normal.z, h.normal.x, h.normal.y, h.normal.z);
                assert_true(len(g.normal, cd_v3_neg(h.normal)) < 1e-9);
            }
        }
    }
}

/* Reversing the direction of either axis (p0 <-> p1) changes nothing. */
static void test_reversing_an_axis_changes_nothing(void **state)
{
    int kind, i;
    double sp = sin(2.0 * CD_PI / 180.0);
    (void)state;
    rng_state = 99;
    for (kind = 0; kind < CASE_COUNT; kind++) {
        for (i = 0; i < 300; i++) {
            cd_vec3 p0, p1, q0, q1;
            cd_contact_geom g, h;
            make_case(kind, &p0, &p1, &q0, &q1);
            cd_segseg_contact(p0, p1, 0.1, q0, q1, 0.2, sp, &g);
            cd_segseg_contact(p1, p0, 0.1, q1, q0, 0.2, sp, &h);
            assert_true(fabs(g.distance - h.distance) < 1e-15);
            assert_int_equal(g.parallel, h.parallel);
            assert_true(len(g.point, h.point) < 1e-14);
            if (g.distance > 1e-9) assert_true(len(g.normal, h.normal) < 1e-9);
        }
    }
}

/* Two segments tilted by just under / just over the 2 degree cut-off. */
static void test_parallel_rule_triggers_below_cutoff_only(void **state)
{
    double sp = sin(2.0 * CD_PI / 180.0);
    double below = 1.99 * CD_PI / 180.0, above = 2.01 * CD_PI / 180.0;
    cd_contact_geom g;
    (void)state;
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.5, cd_v3(0.5, 0, 0.8),
                      cd_v3(0.5 + 2 * cos(below), 2 * sin(below), 0.8), 0.5, sp, &g);
    assert_int_equal(g.parallel, 1);
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.5, cd_v3(0.5, 0, 0.8),
                      cd_v3(0.5 + 2 * cos(above), 2 * sin(above), 0.8), 0.5, sp, &g);
    assert_int_equal(g.parallel, 0);
    /* a tilt in the plane containing both axes (towards each other) */
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.5, cd_v3(0.5, 0, 0.8),
                      cd_v3(0.5 + 2 * cos(below), 0, 0.8 + 2 * sin(below)), 0.5, sp, &g);
    assert_int_equal(g.parallel, 1);
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.5, cd_v3(0.5, 0, 0.8),
                      cd_v3(0.5 + 2 * cos(above), 0, 0.8 + 2 * sin(above)), 0.5, sp, &g);
    assert_int_equal(g.parallel, 0);
    /* disabled with sin_parallel = 0, even for exactly parallel axes */
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.5, cd_v3(1, 0, 1), cd_v3(4, 0, 1), 0.6, 0.0, &g);
    assert_int_equal(g.parallel, 0);
    /* never for a zero-length segment */
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.5, cd_v3(1, 0, 1), cd_v3(1, 0, 1), 0.6, sp, &g);
    assert_int_equal(g.parallel, 0);
    /* parallel but end to end without overlapping section: ordinary contact */
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.5, cd_v3(2.5, 0, 0.1), cd_v3(4, 0, 0.1), 0.5, sp, &g);
    assert_int_equal(g.parallel, 0);
    assert_true(len(g.point, cd_v3(2.25, 0, 0.05)) < 1e-15);
}

/* Hand-made parallel contact: i on x in [0,2], j on x in [1,4] one unit
 * above; the overlapping section is x in [1,2], so c = (1.5, 0, 0.5). */
static void test_parallel_contact_point_is_middle_of_overlap(void **state)
{
    double sp = sin(2.0 * CD_PI / 180.0);
    cd_contact_geom g;
    (void)state;
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.5, cd_v3(1, 0, 1), cd_v3(4, 0, 1), 0.6, sp, &g);
    assert_int_equal(g.parallel, 1);
    assert_true(fabs(g.distance - 1.0) < 1e-15);
    assert_true(fabs(g.overlap - 0.1) < 1e-15);
    assert_true(len(g.normal, cd_v3(0, 0, 1)) < 1e-15);
    assert_true(len(g.point, cd_v3(1.5, 0, 0.5)) < 1e-15);
    /* j antiparallel and containing i: section = all of i, c at its middle */
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.5, cd_v3(3, 0.4, 0), cd_v3(-1, 0.4, 0), 0.5, sp, &g);
    assert_int_equal(g.parallel, 1);
    assert_true(len(g.point, cd_v3(1, 0.2, 0)) < 1e-15);
    assert_true(len(g.normal, cd_v3(0, 1, 0)) < 1e-15);
    /* the closest pair of exactly parallel overlapping segments is the
     * middle of the overlap too */
    {
        double s, t;
        cd_segseg_closest(cd_v3(0, 0, 0), cd_v3(2, 0, 0), cd_v3(1, 0, 1), cd_v3(4, 0, 1), &s, &t);
        assert_true(fabs(s - 0.75) < 1e-15);
        assert_true(fabs(t - 1.0 / 6.0) < 1e-15);
    }
}

/* Hand-made ordinary contacts: crossing above, end point to side, points. */
static void test_hand_computed_contacts(void **state)
{
    cd_contact_geom g;
    (void)state;
    /* perpendicular axes, j above i */
    cd_segseg_contact(cd_v3(-1, 0, 0), cd_v3(1, 0, 0), 0.3, cd_v3(0.25, -1, 0.5), cd_v3(0.25, 1, 0.5), 0.3, 0.0349, &g);
    assert_true(fabs(g.distance - 0.5) < 1e-15);
    assert_true(fabs(g.overlap - 0.1) < 1e-15);
    assert_true(len(g.normal, cd_v3(0, 0, 1)) < 1e-15);
    assert_true(len(g.point, cd_v3(0.25, 0, 0.25)) < 1e-15);
    assert_int_equal(g.parallel, 0);
    /* end point q0 of j beside the middle of i (a T) */
    cd_segseg_contact(cd_v3(-1, 0, 0), cd_v3(1, 0, 0), 0.3, cd_v3(0.5, 0.4, 0), cd_v3(0.5, 2, 0), 0.3, 0.0349, &g);
    assert_true(fabs(g.distance - 0.4) < 1e-15);
    assert_true(len(g.normal, cd_v3(0, 1, 0)) < 1e-15);
    assert_true(len(g.point, cd_v3(0.5, 0.2, 0)) < 1e-15);
    /* two spheres */
    cd_segseg_contact(cd_v3(1, 1, 1), cd_v3(1, 1, 1), 0.5, cd_v3(1.3, 1.4, 1), cd_v3(1.3, 1.4, 1), 0.5, 0.0349, &g);
    assert_true(fabs(g.distance - 0.5) < 1e-15);
    assert_true(len(g.normal, cd_v3(0.6, 0.8, 0)) < 1e-15);
    assert_true(len(g.point, cd_v3(1.15, 1.2, 1)) < 1e-15);
    /* sphere i against the end cap region of rod j */
    cd_segseg_contact(cd_v3(3, 0, 0), cd_v3(3, 0, 0), 0.5, cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.7, 0.0349, &g);
    assert_true(fabs(g.distance - 1.0) < 1e-15);
    assert_true(len(g.normal, cd_v3(-1, 0, 0)) < 1e-15);
    assert_true(len(g.point, cd_v3(2.5, 0, 0)) < 1e-15);
}

/* D = 0: the normal is still a deterministic unit vector: the common
 * perpendicular for crossing axes, perpendicular to the axis otherwise. */
static void test_touching_axes_give_deterministic_unit_normal(void **state)
{
    cd_contact_geom g, h;
    (void)state;
    /* crossing at the origin */
    cd_segseg_contact(cd_v3(-1, 0, 0), cd_v3(1, 0, 0), 0.3, cd_v3(0, -1, 0), cd_v3(0, 1, 0), 0.3, 0.0349, &g);
    assert_true(g.distance == 0.0);
    assert_true(fabs(g.overlap - 0.6) < 1e-15);
    assert_true(len(g.normal, cd_v3(0, 0, 1)) < 1e-15 || len(g.normal, cd_v3(0, 0, -1)) < 1e-15);
    assert_true(len(g.point, cd_v3(0, 0, 0)) == 0.0);
    /* centre of j above the crossing plane side: n points towards it */
    cd_segseg_contact(cd_v3(-1, 0, 0), cd_v3(1, 0, 0), 0.3, cd_v3(0, 0, 0), cd_v3(0, 1, 0.0), 0.3, 0.0349, &g);
    assert_true(g.distance == 0.0);
    assert_true(fabs(cd_v3_norm(g.normal) - 1.0) < 1e-15);
    assert_true(fabs(cd_v3_dot(g.normal, cd_v3(1, 0, 0))) < 1e-15);
    assert_true(fabs(cd_v3_dot(g.normal, cd_v3(0, 1, 0))) < 1e-15);
    /* collinear overlapping: n perpendicular to the axis, antisymmetric */
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.3, cd_v3(1, 0, 0), cd_v3(3, 0, 0), 0.3, 0.0349, &g);
    cd_segseg_contact(cd_v3(1, 0, 0), cd_v3(3, 0, 0), 0.3, cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.3, 0.0349, &h);
    assert_true(g.distance == 0.0);
    assert_int_equal(g.parallel, 1);
    assert_true(fabs(cd_v3_norm(g.normal) - 1.0) < 1e-15);
    assert_true(fabs(g.normal.x) < 1e-15);
    assert_true(len(g.normal, cd_v3_neg(h.normal)) < 1e-15);
    assert_true(len(g.point, cd_v3(1.5, 0, 0)) < 1e-15);
    /* sphere centre on the axis of a rod, and two coincident spheres */
    cd_segseg_contact(cd_v3(0.5, 0, 0), cd_v3(0.5, 0, 0), 0.3, cd_v3(0, 0, 0), cd_v3(2, 0, 0), 0.3, 0.0349, &g);
    assert_true(g.distance == 0.0);
    assert_true(fabs(cd_v3_norm(g.normal) - 1.0) < 1e-15 && fabs(g.normal.x) < 1e-15);
    cd_segseg_contact(cd_v3(1, 2, 3), cd_v3(1, 2, 3), 0.3, cd_v3(1, 2, 3), cd_v3(1, 2, 3), 0.3, 0.0349, &g);
    assert_true(g.distance == 0.0);
    assert_true(fabs(cd_v3_norm(g.normal) - 1.0) < 1e-15);
}

/* Tiny and huge coordinates: no NaN, no underflow of D. */
static void test_extreme_scales_stay_finite(void **state)
{
    cd_contact_geom g;
    (void)state;
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(1e-160, 0, 0), 0, cd_v3(0, 1e-170, 3e-170), cd_v3(1e-160, 1e-170, 3e-170),
                      0, 0.0349, &g);
    assert_true(finite_vec(g.normal) && finite_vec(g.point) && isfinite(g.distance));
    assert_true(fabs(g.distance / (sqrt(10.0) * 1e-170) - 1.0) < 1e-14);
    assert_true(fabs(cd_v3_norm(g.normal) - 1.0) < 1e-15);
    cd_segseg_contact(cd_v3(0, 0, 0), cd_v3(1e100, 0, 0), 0, cd_v3(0, 3e90, 4e90), cd_v3(1e100, 3e90, 4e90), 0, 0.0349,
                      &g);
    assert_true(fabs(g.distance / 5e90 - 1.0) < 1e-15);
    assert_true(len(g.normal, cd_v3(0, 0.6, 0.8)) < 1e-15);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closest_distance_matches_bruteforce_reference),
        cmocka_unit_test(test_contact_is_finite_with_unit_normal_from_i_to_j),
        cmocka_unit_test(test_swapping_i_and_j_flips_normal_keeps_distance_and_point),
        cmocka_unit_test(test_reversing_an_axis_changes_nothing),
        cmocka_unit_test(test_parallel_rule_triggers_below_cutoff_only),
        cmocka_unit_test(test_parallel_contact_point_is_middle_of_overlap),
        cmocka_unit_test(test_hand_computed_contacts),
        cmocka_unit_test(test_touching_axes_give_deterministic_unit_normal),
        cmocka_unit_test(test_extreme_scales_stay_finite),
        cmocka_unit_test(test_clearly_apart_never_hides_a_contact),
        cmocka_unit_test(test_parallel_point_is_continuous_in_the_angle),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
