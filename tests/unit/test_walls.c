/* Unit tests of the wall contacts (kernels/walls.h, docs/references.md, Contacts "Walls")
 * against hand-computed overlaps, points and normals. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>

#include "walls.h"

#define SIN2DEG 0.034899496702500969 /* sin(2 degrees) */
#define DEG     (CD_PI / 180.0)

static double dist(cd_vec3 a, cd_vec3 b) { return cd_v3_norm(cd_v3_sub(a, b)); }

static cd_wall plane(cd_vec3 point, cd_vec3 normal)
{
    cd_wall w = {0};
    w.type = CD_WALL_PLANE;
    w.point = point;
    w.normal = normal;
    return w;
}
static cd_wall cylinder(cd_vec3 point, cd_vec3 axis, double R)
{
    cd_wall w = {0};
    w.type = CD_WALL_CYLINDER;
    w.point = point;
    w.normal = axis;
    w.radius = R;
    return w;
}
static cd_wall sphere(cd_vec3 centre, double R)
{
    cd_wall w = {0};
    w.type = CD_WALL_SPHERE;
    w.point = centre;
    w.radius = R;
    return w;
}

/* Floor z = 0; a tilted rod touches with its lower end a = (0,0,0.3):
 * D = 0.3, overlap 0.2, n = (0,0,-1) (particle -> wall), c = a + n (D+r)/2. */
static void test_plane_tilted_segment_touches_with_lower_end(void **state)
{
    cd_wall w = plane(cd_v3(0, 0, 0), cd_v3(0, 0, 1));
    cd_contact_geom g;
    (void)state;
    cd_wall_contact(&w, cd_v3(1, 0, 0.8), cd_v3(0, 0, 0.3), 0.5, SIN2DEG, &g);
    assert_true(fabs(g.distance - 0.3) < 1e-15);
    assert_true(fabs(g.overlap - 0.2) < 1e-15);
    assert_true(dist(g.normal, cd_v3(0, 0, -1)) == 0.0);
    assert_true(dist(g.point, cd_v3(0, 0, -0.1)) < 1e-15);
    assert_int_equal(g.parallel, 0);
    /* 5 degrees of tilt is above twice the cut-off: the end point either way */
    cd_wall_contact(&w, cd_v3(0, 0, 0.4), cd_v3(2 * cos(5 * DEG), 0, 0.4 + 2 * sin(5 * DEG)), 0.5, SIN2DEG, &g);
    assert_int_equal(g.parallel, 0);
    assert_true(dist(g.point, cd_v3(0, 0, -0.05)) < 1e-15);
    /* 3 degrees, above the cut-off: Conzelmann et al.'s rule takes the end point;
     * with material.parallel_blend (between the cut-off and twice it) the
     * end point's contact point (0, 0, -0.05) is mixed with the middle's, the
     * foot of the middle (cos 3, 0, 0) pushed overlap/2 = 0.05 into the
     * wall, with weight 2 - sin 3 / sin 2 */
    cd_wall_contact(&w, cd_v3(0, 0, 0.4), cd_v3(2 * cos(3 * DEG), 0, 0.4 + 2 * sin(3 * DEG)), 0.5, SIN2DEG, &g);
    assert_int_equal(g.parallel, 0);
    assert_true(dist(g.point, cd_v3(0, 0, -0.05)) < 1e-15);
    cd_wall_contact_rule(&w, cd_v3(0, 0, 0.4), cd_v3(2 * cos(3 * DEG), 0, 0.4 + 2 * sin(3 * DEG)), 0.5, SIN2DEG, 1, &g);
    double wpar = 2 - sin(3 * DEG) / SIN2DEG;
    assert_int_equal(g.parallel, 0);
    assert_true(dist(g.point, cd_v3(wpar * cos(3 * DEG), 0, -0.05)) < 1e-15);
    assert_true(fabs(g.overlap - 0.1) < 1e-15);
}

/* A rod lying flat (or within the cut-off) on the floor gets its contact at
 * its middle, at the depth of its lowest point: no jump between the ends. */
static void test_plane_flat_segment_contact_at_middle(void **state)
{
    cd_wall w = plane(cd_v3(0, 0, 0), cd_v3(0, 0, 1));
    cd_contact_geom g;
    double h = 2 * sin(1.0 * DEG);
    (void)state;
    cd_wall_contact(&w, cd_v3(0, 0, 0.4), cd_v3(2, 0, 0.4), 0.5, SIN2DEG, &g);
    assert_int_equal(g.parallel, 1);
    assert_true(fabs(g.overlap - 0.1) < 1e-15);
    assert_true(dist(g.normal, cd_v3(0, 0, -1)) == 0.0);
    assert_true(dist(g.point, cd_v3(1, 0, -0.05)) < 1e-15);
    /* tilted by 1 degree: middle, overlap of the lower end */
    cd_wall_contact(&w, cd_v3(0, 0, 0.4 + h), cd_v3(2 * cos(1.0 * DEG), 0, 0.4), 0.5, SIN2DEG, &g);
    assert_int_equal(g.parallel, 1);
    assert_true(fabs(g.overlap - 0.1) < 1e-15);
    assert_true(dist(g.point, cd_v3(cos(1.0 * DEG), 0, -0.05)) < 1e-15);
    /* the parallel rule off: the end point a (ties go to a) */
    cd_wall_contact(&w, cd_v3(0, 0, 0.4), cd_v3(2, 0, 0.4), 0.5, 0.0, &g);
    assert_int_equal(g.parallel, 0);
    assert_true(dist(g.point, cd_v3(0, 0, -0.05)) < 1e-15);
}

/* A sphere (zero-length axis) on a tilted plane through the origin with
 * normal (0, 0.6, 0.8): centre (1, 0.3, 0.4) is at distance 0.5. */
static void test_plane_sphere_on_tilted_plane(void **state)
{
    cd_wall w = plane(cd_v3(0, 0, 0), cd_v3(0, 0.6, 0.8));
    cd_contact_geom g;
    cd_vec3 x = cd_v3(1, 0.3, 0.4);
    (void)state;
    cd_wall_contact(&w, x, x, 0.7, SIN2DEG, &g);
    assert_int_equal(g.parallel, 0);
    assert_true(fabs(g.distance - 0.5) < 1e-15);
    assert_true(fabs(g.overlap - 0.2) < 1e-15);
    assert_true(dist(g.normal, cd_v3(0, -0.6, -0.8)) < 1e-15);
    assert_true(dist(g.point, cd_v3(1, -0.06, -0.08)) < 1e-15);
    /* away from the plane: negative overlap */
    cd_wall_contact(&w, cd_v3(0, 3, 4), cd_v3(0, 3, 4), 0.7, SIN2DEG, &g);
    assert_true(fabs(g.overlap - (0.7 - 5.0)) < 1e-15);
    /* centre behind the plane: negative distance, overlap > r */
    cd_wall_contact(&w, cd_v3(0, -0.06, -0.08), cd_v3(0, -0.06, -0.08), 0.7, SIN2DEG, &g);
    assert_true(fabs(g.distance + 0.1) < 1e-15);
    assert_true(fabs(g.overlap - 0.8) < 1e-15);
}

/* Cylinder of radius 2 about the vertical axis through (1,1,0). */
static void test_cylinder_wall_contacts(void **state)
{
    cd_wall w = cylinder(cd_v3(1, 1, 0), cd_v3(0, 0, 1), 2.0);
    cd_contact_geom g;
    double phi = 0.01;
    (void)state;
    /* radial rod: outer end at radius 1.8, D = 0.2, overlap 0.1 */
    cd_wall_contact(&w, cd_v3(1, 1, 0.5), cd_v3(2.8, 1, 0), 0.3, SIN2DEG, &g);
    assert_int_equal(g.parallel, 0);
    assert_true(fabs(g.distance - 0.2) < 1e-15);
    assert_true(fabs(g.overlap - 0.1) < 1e-15);
    assert_true(dist(g.normal, cd_v3(1, 0, 0)) < 1e-15);
    assert_true(dist(g.point, cd_v3(3.05, 1, 0)) < 1e-15);
    /* vertical rod against the wall at radius 1.9 (direction -y): parallel,
     * contact at mid height, overlap 0.1 */
    cd_wall_contact(&w, cd_v3(1, -0.9, 0), cd_v3(1, -0.9, 1), 0.2, SIN2DEG, &g);
    assert_int_equal(g.parallel, 1);
    assert_true(fabs(g.overlap - 0.1) < 1e-15);
    assert_true(dist(g.normal, cd_v3(0, -1, 0)) < 1e-15);
    assert_true(dist(g.point, cd_v3(1, -1.05, 0.5)) < 1e-15);
    /* short horizontal chord with ends at azimuth +-phi, radius 1.9: the
     * normal is the wall normal at the middle (+x), not an end's */
    cd_wall_contact(&w, cd_v3(1 + 1.9 * cos(phi), 1 + 1.9 * sin(phi), 0.2),
                    cd_v3(1 + 1.9 * cos(phi), 1 - 1.9 * sin(phi), 0.2), 0.2, SIN2DEG, &g);
    assert_int_equal(g.parallel, 1);
    assert_true(fabs(g.overlap - 0.1) < 1e-14);
    assert_true(dist(g.normal, cd_v3(1, 0, 0)) < 1e-15);
    assert_true(dist(g.point, cd_v3(1 + 2.05, 1, 0.2)) < 1e-14);
    /* sphere at (1, 2.5, 7): radius 1.5, D = 0.5, r 0.6 -> overlap 0.1 */
    cd_wall_contact(&w, cd_v3(1, 2.5, 7), cd_v3(1, 2.5, 7), 0.6, SIN2DEG, &g);
    assert_true(fabs(g.overlap - 0.1) < 1e-15);
    assert_true(dist(g.normal, cd_v3(0, 1, 0)) < 1e-15);
    assert_true(dist(g.point, cd_v3(1, 3.05, 7)) < 1e-15);
    /* a point on the axis: deterministic unit normal perpendicular to it */
    cd_wall_contact(&w, cd_v3(1, 1, 3), cd_v3(1, 1, 3), 2.5, SIN2DEG, &g);
    assert_true(fabs(g.overlap - 0.5) < 1e-15);
    assert_true(fabs(cd_v3_norm(g.normal) - 1.0) < 1e-15);
    assert_true(fabs(g.normal.z) < 1e-15);
}

/* Tilted cylinder axis (1,1,0)/sqrt2 through the origin, radius 1. */
static void test_cylinder_with_tilted_axis(void **state)
{
    double c = sqrt(0.5);
    cd_wall w = cylinder(cd_v3(0, 0, 0), cd_v3(c, c, 0), 1.0);
    cd_contact_geom g;
    (void)state;
    /* sphere at radial distance 0.9 along z, 5 units along the axis */
    cd_wall_contact(&w, cd_v3(5 * c, 5 * c, 0.9), cd_v3(5 * c, 5 * c, 0.9), 0.25, SIN2DEG, &g);
    assert_true(fabs(g.overlap - 0.15) < 1e-14);
    /* (c, c, 0) is a unit vector only to rounding: 1e-14 */
    assert_true(dist(g.normal, cd_v3(0, 0, 1)) < 1e-14);
    assert_true(dist(g.point, cd_v3(5 * c, 5 * c, 1.075)) < 1e-14);
}

/* Inside a sphere of radius 1 centred at (0,0,1). */
static void test_sphere_wall_contacts(void **state)
{
    cd_wall w = sphere(cd_v3(0, 0, 1), 1.0);
    cd_contact_geom g;
    double phi = 0.01;
    (void)state;
    /* radial rod, outer end at 0.9: D = 0.1, overlap 0.1 */
    cd_wall_contact(&w, cd_v3(0, 0, 1), cd_v3(0.9, 0, 1), 0.2, SIN2DEG, &g);
    assert_int_equal(g.parallel, 0);
    assert_true(fabs(g.distance - 0.1) < 1e-15);
    assert_true(fabs(g.overlap - 0.1) < 1e-15);
    assert_true(dist(g.normal, cd_v3(1, 0, 0)) < 1e-15);
    assert_true(dist(g.point, cd_v3(1.05, 0, 1)) < 1e-15);
    /* a sphere resting at the bottom */
    cd_wall_contact(&w, cd_v3(0, 0, 0.3), cd_v3(0, 0, 0.3), 0.4, SIN2DEG, &g);
    assert_true(fabs(g.overlap - 0.1) < 1e-15);
    assert_true(dist(g.normal, cd_v3(0, 0, -1)) < 1e-15);
    assert_true(dist(g.point, cd_v3(0, 0, -0.05)) < 1e-15);
    /* short chord lying against the bottom: contact below its middle */
    cd_wall_contact(&w, cd_v3(0.9 * sin(phi), 0, 1 - 0.9 * cos(phi)), cd_v3(-0.9 * sin(phi), 0, 1 - 0.9 * cos(phi)),
                    0.2, SIN2DEG, &g);
    assert_int_equal(g.parallel, 1);
    assert_true(fabs(g.overlap - 0.1) < 1e-14);
    assert_true(dist(g.normal, cd_v3(0, 0, -1)) < 1e-15);
    assert_true(dist(g.point, cd_v3(0, 0, -0.05)) < 1e-14);
    /* at the centre: deterministic normal (0,0,-1) */
    cd_wall_contact(&w, cd_v3(0, 0, 1), cd_v3(0, 0, 1), 1.5, SIN2DEG, &g);
    assert_true(fabs(g.overlap - 0.5) < 1e-15);
    assert_true(dist(g.normal, cd_v3(0, 0, -1)) == 0.0);
}

/* Surface velocity: planes and cylinders translate; the sphere adds its
 * radial velocity along the outward radial direction. */
static void test_moving_wall_velocity_at_contact(void **state)
{
    cd_wall p = plane(cd_v3(0, 0, 0), cd_v3(0, 0, 1));
    cd_wall c = cylinder(cd_v3(0, 0, 0), cd_v3(0, 0, 1), 1.0);
    cd_wall s = sphere(cd_v3(0, 0, 1), 1.0);
    cd_vec3 v;
    (void)state;
    p.velocity = cd_v3(0, 0, 0.1);
    v = cd_wall_velocity_at(&p, cd_v3(3, 4, 0));
    assert_true(dist(v, cd_v3(0, 0, 0.1)) == 0.0);
    c.velocity = cd_v3(0.2, 0, 0);
    v = cd_wall_velocity_at(&c, cd_v3(0, 1, 0));
    assert_true(dist(v, cd_v3(0.2, 0, 0)) == 0.0);
    s.velocity = cd_v3(0.1, 0, 0);
    s.radial_velocity = -0.5;
    v = cd_wall_velocity_at(&s, cd_v3(0, 0, 2.05));
    assert_true(dist(v, cd_v3(0.1, 0, -0.5)) < 1e-15);
    v = cd_wall_velocity_at(&s, cd_v3(0.6, 0.8, 1));
    assert_true(dist(v, cd_v3(0.1 - 0.3, -0.4, 0)) < 1e-15);
    v = cd_wall_velocity_at(&s, cd_v3(0, 0, 1));
    assert_true(dist(v, cd_v3(0.1, 0, 0)) == 0.0);
}

/* An unknown wall type never produces a contact. */
/* The force kernel's pre-test (cd_wall_clearly_apart) may say "apart" only
 * where cd_wall_contact finds no overlap, and must say it for primitives
 * well inside: 200,000 random rods and spheres (deterministic LCG) in and
 * around a plane, a tilted cylinder and a sphere, plus the exact touching
 * positions.  No tolerance: one disagreement would change forces. */
static double lcg_unit(uint64_t *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*x >> 11) / 9007199254740992.0; /* [0, 1) */
}
static void test_clearly_apart_never_hides_a_contact(void **state)
{
    double c = sqrt(0.5);
    cd_wall walls[3] = {plane(cd_v3(0, 0, 0.1), cd_v3(0, c, c)), cylinder(cd_v3(0, 0, 0), cd_v3(c, 0, c), 1.0),
                        sphere(cd_v3(0.2, 0, 0), 1.0)};
    uint64_t x = 12345;
    long apart = 0, contacts = 0;
    (void)state;
    for (int k = 0; k < 200000; k++) {
        cd_wall *w = &walls[k % 3];
        cd_vec3 a = cd_v3(2.4 * lcg_unit(&x) - 1.2, 2.4 * lcg_unit(&x) - 1.2, 2.4 * lcg_unit(&x) - 1.2);
        cd_vec3 d = cd_v3(lcg_unit(&x) - 0.5, lcg_unit(&x) - 0.5, lcg_unit(&x) - 0.5);
        cd_vec3 b = (k / 3) % 2 ? cd_v3_add(a, cd_v3_scale(d, 0.6)) : a; /* rod or sphere */
        double r = 0.2 * lcg_unit(&x);
        cd_contact_geom g;
        cd_wall_contact(w, a, b, r, SIN2DEG, &g);
        if (cd_wall_clearly_apart(w, a, b, r)) {
            apart++;
            assert_false(g.overlap > 0);
        }
        contacts += g.overlap > 0;
    }
    assert_true(apart > 50000 && contacts > 20000); /* both branches exercised */
    /* touching exactly (overlap 0) and just overlapping, radius-0.3 spheres */
    cd_wall cyl = cylinder(cd_v3(0, 0, 0), cd_v3(0, 0, 1), 2.0);
    cd_contact_geom g;
    assert_true(cd_wall_clearly_apart(&cyl, cd_v3(1.6, 0, 0), cd_v3(1.6, 0, 0), 0.3));
    cd_wall_contact(&cyl, cd_v3(1.7, 0, 0), cd_v3(1.7, 0, 0), 0.3, SIN2DEG, &g);
    assert_false(cd_wall_clearly_apart(&cyl, cd_v3(1.7, 0, 0), cd_v3(1.7, 0, 0), 0.3));
    assert_false(g.overlap > 1e-15);
    cd_wall floor = plane(cd_v3(0, 0, 0), cd_v3(0, 0, 1));
    assert_true(cd_wall_clearly_apart(&floor, cd_v3(0, 0, 0.3), cd_v3(1, 0, 0.5), 0.3));
    assert_false(cd_wall_clearly_apart(&floor, cd_v3(0, 0, 0.3), cd_v3(1, 0, 0.5), 0.3 + 1e-12));
}

static void test_unknown_wall_type_gives_no_contact(void **state)
{
    cd_wall w = plane(cd_v3(0, 0, 0), cd_v3(0, 0, 1));
    cd_contact_geom g;
    (void)state;
    w.type = 17;
    cd_wall_contact(&w, cd_v3(0, 0, 0), cd_v3(1, 0, 0), 0.5, SIN2DEG, &g);
    assert_true(g.overlap < 0);
    assert_true(fabs(cd_v3_norm(g.normal) - 1.0) < 1e-15);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plane_tilted_segment_touches_with_lower_end),
        cmocka_unit_test(test_plane_flat_segment_contact_at_middle),
        cmocka_unit_test(test_plane_sphere_on_tilted_plane),
        cmocka_unit_test(test_cylinder_wall_contacts),
        cmocka_unit_test(test_cylinder_with_tilted_axis),
        cmocka_unit_test(test_sphere_wall_contacts),
        cmocka_unit_test(test_moving_wall_velocity_at_contact),
        cmocka_unit_test(test_clearly_apart_never_hides_a_contact),
        cmocka_unit_test(test_unknown_wall_type_gives_no_contact),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
