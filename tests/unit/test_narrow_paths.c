/* The specialised narrow phases of the pair kernel (kernels/segseg.h):
 * sphere-sphere (cd_segseg_point_contact), sphere-arm
 * (cd_segseg_point_segment_contact) and arm-arm (cd_segseg_axes_contact)
 * give the bits of the general segment-segment path on random pairs, so
 * choosing one per row changes no trajectory; an arm through its body's
 * centre rotated once (cd_prim_ends_at) gives the ends of two rotations. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "segseg.h"
#include "quat.h"
#include "unit/segseg_rng.h"

/* The general path of the pair kernel (closest points, pre-test, contact
 * with the blended parallel rule) into *want (zeroed first); returns the
 * pre-test's "apart". */
static int general_contact(cd_vec3 p0, cd_vec3 p1, double ri, cd_vec3 q0, cd_vec3 q1, double rj, double sp,
                           cd_contact_geom *want)
{
    double s, t;
    memset(want, 0, sizeof *want);
    cd_segseg_closest(p0, p1, q0, q1, &s, &t);
    int apart = cd_segseg_clearly_apart(p0, p1, ri, q0, q1, rj, s, t);
    if (!apart) cd_segseg_contact_at(p0, p1, ri, q0, q1, rj, s, t, sp, 1, want);
    return apart;
}

static void assert_same_geometry(const cd_contact_geom *got, const cd_contact_geom *want)
{
    assert_memory_equal(&got->normal, &want->normal, sizeof got->normal);
    assert_memory_equal(&got->point, &want->point, sizeof got->point);
    assert_memory_equal(&got->distance, &want->distance, sizeof got->distance);
    assert_memory_equal(&got->overlap, &want->overlap, sizeof got->overlap);
    assert_int_equal(got->parallel, want->parallel);
}

/* Two spheres (axes of zero length): the point path of the pair kernel
 * (cd_segseg_point_contact) gives the bits of the general one
 * (cd_segseg_closest, cd_segseg_clearly_apart, cd_segseg_contact_at) for
 * random pairs apart, touching and overlapping, coincident centres (the
 * touch normal) and centres with -0 coordinates. */
static void test_point_contact_equals_general_path(void **state)
{
    (void)state;
    double sp = sin(2.0 * CD_PI / 180.0);
    int overlapping = 0;
    rng_state = 4242;
    for (int i = 0; i < 20000; i++) {
        cd_vec3 p = rng_vec(0.01), q = cd_v3_add(p, rng_vec(0.006));
        if (i % 97 == 0) q = p;                      /* coincident centres */
        if (i % 89 == 0) p = cd_v3(-0.0, p.y, -0.0); /* signed zeros */
        double ri = 0.001 + 0.002 * rng_u(), rj = 0.001 + 0.002 * rng_u();
        cd_contact_geom want, got;
        memset(&got, 0, sizeof got);
        int apart = general_contact(p, p, ri, q, q, rj, sp, &want);
        assert_int_equal(cd_segseg_point_contact(p, ri, q, rj, &got), apart);
        if (apart) continue;
        overlapping += want.overlap > 0;
        assert_same_geometry(&got, &want);
    }
    assert_true(overlapping > 1000);
}

/* A sphere and an arm (one axis of zero length): the point-segment path
 * of the pair kernel (cd_segseg_point_segment_contact) gives the bits of
 * the general one, with the sphere as i or as j, for random pairs apart,
 * touching and overlapping, the sphere's centre on the axis (the touch
 * normal) and beyond either end. */
static void test_point_segment_contact_equals_general_path(void **state)
{
    (void)state;
    double sp = sin(2.0 * CD_PI / 180.0);
    int overlapping = 0, ends = 0;
    rng_state = 777;
    for (int k = 0; k < 40000; k++) {
        cd_vec3 p = rng_vec(0.01), q0 = cd_v3_add(p, rng_vec(0.006)), q1 = cd_v3_add(q0, rng_vec(0.008));
        if (k % 101 == 0) p = cd_v3_lerp(q0, q1, 0.25); /* on the axis */
        double ri = 0.001 + 0.002 * rng_u(), rj = 0.001 + 0.002 * rng_u();
        int sphere_j = k % 2; /* the sphere as primitive j every other pair */
        cd_vec3 a0 = sphere_j ? q0 : p, a1 = sphere_j ? q1 : p, b0 = sphere_j ? p : q0, b1 = sphere_j ? p : q1;
        double ra = sphere_j ? rj : ri, rb = sphere_j ? ri : rj;
        cd_contact_geom want, got;
        memset(&got, 0, sizeof got);
        int apart = general_contact(a0, a1, ra, b0, b1, rb, sp, &want);
        assert_int_equal(cd_segseg_point_segment_contact(a0, a1, ra, b0, b1, rb, &got), apart);
        if (apart) continue;
        overlapping += want.overlap > 0;
        /* the sphere's projection beyond an end of the arm (clamped) */
        cd_vec3 d = cd_v3_sub(q1, q0);
        double u = cd_v3_dot(cd_v3_sub(p, q0), d) / cd_v3_dot(d, d);
        ends += u < 0 || u > 1;
        assert_same_geometry(&got, &want);
    }
    assert_true(overlapping > 1000 && ends > 100);
}

/* cd_segseg_closest as it was before session 17 split out its
 * segment-segment part (cd_segseg_closest_axes), kept here verbatim as the
 * reference of the bits. */
static void reference_closest(cd_vec3 p0, cd_vec3 p1, cd_vec3 q0, cd_vec3 q1, double *s, double *t)
{
    cd_vec3 d1 = cd_v3_sub(p1, p0), d2 = cd_v3_sub(q1, q0), w = cd_v3_sub(q0, p0);
    double a = cd_v3_dot(d1, d1), e = cd_v3_dot(d2, d2), ss, tt;
    if (a <= 0 && e <= 0) {
        ss = 0;
        tt = 0;
    } else if (a <= 0) {
        ss = 0;
        tt = cd_clamp01(-cd_v3_dot(w, d2) / e);
    } else if (e <= 0) {
        tt = 0;
        ss = cd_clamp01(cd_v3_dot(w, d1) / a);
    } else {
        cd_vec3 m = cd_v3_cross(d1, d2);
        double m2 = cd_v3_dot(m, m);
        if (m2 > CD_SEGSEG_PARALLEL_SIN2 * a * e) {
            ss = cd_v3_dot(cd_v3_cross(w, d2), m) / m2;
        } else {
            double u0 = cd_v3_dot(w, d1) / a, u1 = cd_v3_dot(cd_v3_sub(q1, p0), d1) / a;
            double lo = u0 < u1 ? u0 : u1, hi = u0 < u1 ? u1 : u0;
            lo = lo > 0 ? lo : 0;
            hi = hi < 1 ? hi : 1;
            ss = 0.5 * (lo + hi);
        }
        ss = cd_clamp01(ss);
        tt = cd_v3_dot(cd_v3_sub(cd_v3_axpy(p0, ss, d1), q0), d2) / e;
        if (tt < 0) {
            tt = 0;
            ss = cd_clamp01(cd_v3_dot(w, d1) / a);
        } else if (tt > 1) {
            tt = 1;
            ss = cd_clamp01(cd_v3_dot(cd_v3_sub(q1, p0), d1) / a);
        }
    }
    *s = ss;
    *t = tt;
}

/* Two arms (axes of non-zero length): cd_segseg_closest gives the bits of
 * the reference, and the arm-arm path of the pair kernel
 * (cd_segseg_axes_contact: the cross product and squared lengths formed
 * once) the bits of the general path on the reference's closest points,
 * for random pairs apart, touching and overlapping, crossing axes (the
 * touch normal), nearly parallel ones (the blended parallel rule: inside
 * the cut-off, on the ramp and exactly parallel) and closest points at
 * the ends and inside. */
static void test_arm_pair_contact_equals_general_path(void **state)
{
    (void)state;
    double sp = sin(2.0 * CD_PI / 180.0);
    int overlapping = 0, parallel = 0, ramp = 0, inside = 0, ends = 0;
    rng_state = 31337;
    for (int k = 0; k < 60000; k++) {
        cd_vec3 p0 = rng_vec(0.01), p1 = cd_v3_add(p0, rng_vec(0.008));
        cd_vec3 q0 = cd_v3_add(p0, rng_vec(0.008)), q1 = cd_v3_add(q0, rng_vec(0.008));
        cd_vec3 d1 = cd_v3_sub(p1, p0);
        if (k % 5 == 1) q1 = cd_v3_add(q0, cd_v3_scale(d1, -0.7)); /* exactly parallel (antiparallel) */
        if (k % 5 == 2) {                                          /* nearly parallel: up to 4 sp */
            cd_vec3 n = cd_v3_cross(d1, rng_vec(1.0));
            double dn = sqrt(cd_v3_dot(n, n)), l1 = sqrt(cd_v3_dot(d1, d1));
            q1 = cd_v3_add(q0, cd_v3_add(cd_v3_scale(d1, 0.9), cd_v3_scale(n, 4.0 * sp * rng_u() * 0.9 * l1 / dn)));
        }
        if (k % 97 == 0) { /* crossing axes: the closest points coincide */
            cd_vec3 mid = cd_v3_lerp(p0, p1, 0.4);
            q0 = cd_v3_sub(mid, cd_v3_scale(cd_v3_sub(q1, q0), 0.5));
            q1 = cd_v3_add(q0, cd_v3_scale(cd_v3_sub(mid, q0), 2.0));
        }
        double ri = 0.001 + 0.002 * rng_u(), rj = 0.001 + 0.002 * rng_u();
        double s, t, rs, rt;
        cd_segseg_closest(p0, p1, q0, q1, &s, &t);
        reference_closest(p0, p1, q0, q1, &rs, &rt);
        assert_memory_equal(&s, &rs, sizeof s);
        assert_memory_equal(&t, &rt, sizeof t);
        cd_contact_geom want, got;
        memset(&want, 0, sizeof want);
        memset(&got, 0, sizeof got);
        int apart = cd_segseg_clearly_apart(p0, p1, ri, q0, q1, rj, rs, rt);
        if (!apart) cd_segseg_contact_at(p0, p1, ri, q0, q1, rj, rs, rt, sp, 1, &want);
        cd_vec3 d2 = cd_v3_sub(q1, q0);
        double a = cd_v3_dot(d1, d1), e = cd_v3_dot(d2, d2);
        assert_int_equal(cd_segseg_axes_contact(p0, p1, ri, q0, q1, rj, d1, d2, a, e, sp, 1, &got), apart);
        if (apart) continue;
        overlapping += want.overlap > 0;
        parallel += want.parallel;
        cd_vec3 m = cd_v3_cross(d1, d2);
        double w = cd_parallel_weight(cd_v3_dot(m, m), a * e, sp, 1);
        ramp += w > 0 && w < 1;
        inside += rs > 0 && rs < 1 && rt > 0 && rt < 1;
        ends += !(rs > 0 && rs < 1 && rt > 0 && rt < 1);
        assert_same_geometry(&got, &want);
    }
    assert_true(overlapping > 1000 && parallel > 100 && ramp > 100 && inside > 100 && ends > 1000);
}

/* An arm through its body's centre (b_body = -a_body, the zero
 * coordinates +0 in both, as src/shapes/shapes.c makes them): its end b
 * from the one rotation of a (x + -(R a), cd_prim_ends_at) has the bits of
 * the rotation of b (x + R b), for random orientations, centres (with +0
 * coordinates among them) and arms along a body axis or in any direction. */
static void test_symmetric_arm_one_rotation(void **state)
{
    (void)state;
    rng_state = 2718;
    for (int k = 0; k < 100000; k++) {
        cd_quat o = cd_q_normalize(cd_q(rng_sym(), rng_sym(), rng_sym(), rng_sym()));
        if (k % 7 == 0) o = cd_q_normalize(cd_q(rng_sym(), 0.0, 0.0, rng_sym())); /* about z (2D) */
        cd_vec3 x = rng_vec(0.1);
        if (k % 11 == 0) x.z = 0.0;
        double h = 0.01 * rng_u(), ea[3] = {0, 0, 0}, eb[3] = {0, 0, 0};
        ea[k % 3] = -h;
        eb[k % 3] = h;
        cd_vec3 a_body = cd_v3(ea[0], ea[1], ea[2]), b_body = cd_v3(eb[0], eb[1], eb[2]);
        if (k % 4 == 3) {
            a_body = rng_vec(0.01);
            b_body = cd_v3_neg(a_body);
        }
        cd_vec3 want = cd_v3_add(x, cd_q_rotate(o, b_body));
        cd_vec3 got = cd_v3_add(x, cd_v3_neg(cd_q_rotate(o, a_body)));
        assert_memory_equal(&got, &want, sizeof got);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_point_contact_equals_general_path),
        cmocka_unit_test(test_point_segment_contact_equals_general_path),
        cmocka_unit_test(test_arm_pair_contact_equals_general_path),
        cmocka_unit_test(test_symmetric_arm_one_rotation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
