/* The Verlet list of the backend under test (omp: src/backend/omp/neighbors.c;
 * OpenCL, as test_neighbors_opencl: kernels/cl/neighbors.cl) against brute
 * force: every pair (i < j) of primitives of different particles whose
 * axes come within r_i + r_j + skin, in (i, j) order, and nothing else.
 * The brute force measures the axes' distance with a method of its own
 * (seg_distance below), not with the code under test.  The list
 * is built over particles first (particle bounding spheres, then the
 * primitive test), so this checks that the particle stage drops no pair
 * and keeps the order, for each shape kind, polydisperse mixtures, thin
 * stars packed far beyond the bounding-sphere density, and 2D. */
#include "test_util.h"
#include <math.h>
#include "../kernels/broadphase.h"

static double lcg_unit(uint64_t *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*x >> 11) / 9007199254740992.0; /* [0, 1) */
}

/* Distance between segments [p0, p1] and [q0, q1] [m], written here
 * independently of kernels/segseg.h: the minimum over the interior
 * stationary point (when the axes are not parallel and it lies inside the
 * unit square) and over the four edges s = 0, s = 1, t = 0, t = 1, each a
 * point-segment distance by clamped projection. */
static double point_seg2(cd_vec3 x, cd_vec3 a, cd_vec3 b)
{
    cd_vec3 d = cd_v3_sub(b, a);
    double L2 = cd_v3_dot(d, d), u = L2 > 0 ? cd_v3_dot(cd_v3_sub(x, a), d) / L2 : 0;
    u = u < 0 ? 0 : (u > 1 ? 1 : u);
    cd_vec3 c = cd_v3_sub(x, cd_v3_axpy(a, u, d));
    return cd_v3_dot(c, c);
}
static double seg_distance(cd_vec3 p0, cd_vec3 p1, cd_vec3 q0, cd_vec3 q1)
{
    double m = fmin(fmin(point_seg2(p0, q0, q1), point_seg2(p1, q0, q1)),
                    fmin(point_seg2(q0, p0, p1), point_seg2(q1, p0, p1)));
    cd_vec3 u = cd_v3_sub(p1, p0), v = cd_v3_sub(q1, q0), w = cd_v3_sub(p0, q0);
    double a = cd_v3_dot(u, u), b = cd_v3_dot(u, v), c = cd_v3_dot(v, v), d = cd_v3_dot(u, w), e = cd_v3_dot(v, w);
    double den = a * c - b * b;
    if (den > 1e-12 * a * c) {
        double s = (b * e - c * d) / den, t = (a * e - b * d) / den;
        if (s > 0 && s < 1 && t > 0 && t < 1) {
            cd_vec3 g = cd_v3_sub(cd_v3_axpy(p0, s, u), cd_v3_axpy(q0, t, v));
            m = fmin(m, cd_v3_dot(g, g));
        }
    }
    return sqrt(m);
}

/* Scatters the particles over a cube of edge box [m] (2D: the x-y square,
 * rotations about z) with random orientations, overlaps allowed, then
 * rebuilds the list and compares it with the brute-force one.  Returns the
 * number of pairs (to show there were some). */
static size_t check_against_brute_force(cd_sim *sim, double box, int dim2, uint64_t seed)
{
    cd_state *s = &sim->s;
    uint64_t x = seed;
    for (size_t q = 0; q < s->n_particles; q++) {
        cd_vec3 pos = cd_v3(box * lcg_unit(&x), box * lcg_unit(&x), dim2 ? 0 : box * lcg_unit(&x));
        cd_vec3 axis = dim2 ? cd_v3(0, 0, 1) : cd_v3(lcg_unit(&x) - 0.5, lcg_unit(&x) - 0.5, lcg_unit(&x) - 0.5);
        cd_quat qo = cd_q_from_axis_angle(cd_v3_scale(axis, 1 / cd_v3_norm(axis)), 2 * CD_PI * lcg_unit(&x));
        cdt_place(sim, q, pos, qo, cd_v3_zero(), cd_v3_zero());
    }
    /* (Re)start the backend: it builds its list (on the host for omp, on
     * the device for OpenCL) and computes the forces; sync brings it back. */
    char err[1024];
    sim->nb.force_rebuild = 1;
    if (cd_sim_start(sim, 1, err, sizeof err)) fail_msg("start: %s", err);
    if (cd_sim_sync(sim, err, sizeof err)) fail_msg("sync: %s", err);
    /* Pairs within 1e-9 of the reach either way may fall on either side by
     * rounding (the two distance methods differ by a few 1e-16 of it):
     * the list may or may not hold them. */
    size_t k = 0, borderline = 0;
    for (size_t i = 0; i < s->n_prims; i++)
        for (size_t j = i + 1; j < s->n_prims; j++) {
            if (s->prim_particle[i] == s->prim_particle[j]) continue;
            double reach = s->prim_radius[i] + s->prim_radius[j] + sim->nb.skin;
            double D = seg_distance(s->prim_a[i], s->prim_b[i], s->prim_a[j], s->prim_b[j]);
            int listed = k < s->n_pairs && (size_t)s->pair_prim_i[k] == i && (size_t)s->pair_prim_j[k] == j;
            if (fabs(D - reach) <= 1e-9 * reach) {
                borderline++;
                k += listed;
                continue;
            }
            if (D > reach) {
                if (listed)
                    fail_msg("row %zu (%zu, %zu) is listed, its axes %.9g m apart, reach %.9g m", k, i, j, D, reach);
                continue;
            }
            if (!listed)
                fail_msg("pair (%zu, %zu) (axes %.9g m apart, reach %.9g m) missing: row %zu is (%d, %d)", i, j, D,
                         reach, k, k < s->n_pairs ? (int)s->pair_prim_i[k] : -1,
                         k < s->n_pairs ? (int)s->pair_prim_j[k] : -1);
            k++;
        }
    assert_int_equal(k, s->n_pairs);
    if (borderline) print_message("%zu pairs within 1e-9 of the reach\n", borderline);
    return k;
}

static void run(const char *yaml, double box, int dim2, size_t min_pairs)
{
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg, yaml);
    for (uint64_t seed = 1; seed <= 3; seed++) {
        size_t n = check_against_brute_force(&sim, box, dim2, seed);
        print_message("%zu particles, %zu primitives: %zu pairs\n", sim.s.n_particles, sim.s.n_prims, n);
        assert_true(n >= min_pairs);
    }
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

/* 400 stars of alpha 11 (prims 5.5 cm long) in a 12 cm cube: every star
 * meets dozens of others, most pairs of particles only through some of
 * their nine arm pairs. */
static void test_thin_stars_dense(void **state)
{
    (void)state;
    run("particles: [{shape: hexapod, aspect: 11, diameter: 0.005, count: 400, polydispersity: 0.2}]\n"
        "domain: {type: box, width: 1, thickness: 1, height: 1}\n"
        "neighbor: {skin: 0.0025}\n",
        0.12, 0, 5000);
}

/* Every shape kind at once, different sizes, with the automatic skin. */
static void test_mixed_shapes(void **state)
{
    (void)state;
    run("particles: [{shape: sphere, diameter: 0.004, count: 150},\n"
        "            {shape: rod, aspect: 6, diameter: 0.003, count: 100, polydispersity: 0.3},\n"
        "            {shape: cross, aspect: 3, diameter: 0.005, count: 100},\n"
        "            {shape: hexapod, aspect: 2, diameter: 0.006, count: 100}]\n"
        "domain: {type: box, width: 1, thickness: 1, height: 1}\n",
        0.08, 0, 1000);
}

/* 2D crosses (all centres in the plane z = 0). */
static void test_crosses_2d(void **state)
{
    (void)state;
    run("physics: {dimension: 2}\n"
        "particles: [{shape: cross, aspect: 6, diameter: 0.005, count: 300, polydispersity: 0.15}]\n"
        "domain: {type: box, width: 1, thickness: 0.03, height: 1}\n"
        "neighbor: {skin: 0.001}\n",
        0.3, 1, 500);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_thin_stars_dense),
        cmocka_unit_test(test_mixed_shapes),
        cmocka_unit_test(test_crosses_2d),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
