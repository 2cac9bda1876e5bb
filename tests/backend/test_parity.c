/* The same case on the omp and the OpenCL backends (docs/opencl.md,
 * "Parity"): 500 hexapods settling in a cylinder under a strengthened
 * gravity, compared every 500 steps over 2000 steps, with the linear and the
 * Hertz-Mindlin law.  Both run the same
 * kernel headers (kernels/step_items.h, kernels/broadphase.h) with FMA
 * contraction off, so the contact sets must be identical and the particle
 * state must agree to 1e-10 relative; the test reports whether every bit
 * agrees (it did on PoCL 3.1 at the time of writing). */
#define _POSIX_C_SOURCE 200809L /* setenv */
#include "test_util.h"
#include <math.h>
#include "../kernels/step_items.h"

static const char *settling =
    "run: {name: parity, dt: 1.0e-5, steps: 2000, seed: 21}\n"
    "physics: {gravity: [0, -981, 0]}\n"
    "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 500, polydispersity: 0.2}]\n"
    "domain: {type: cylinder, diameter: 0.14, height: 0.33}\n"
    "init: {placement: lattice, clearance: 1.0, speed: 2.0}\n";

/* The same settling with the Hertz-Mindlin law (docs/contacts.md), over
 * 2000 steps. */
static const char *settling_hertz =
    "run: {name: parity_hertz, dt: 1.0e-5, steps: 2000, seed: 21}\n"
    "physics: {gravity: [0, -981, 0]}\n"
    "material: {law: hertz_mindlin, young_modulus: 1.0e8, poisson_ratio: 0.3, friction_limit: total}\n"
    "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 500, polydispersity: 0.2}]\n"
    "domain: {type: cylinder, diameter: 0.14, height: 0.33}\n"
    "init: {placement: lattice, clearance: 1.0, speed: 2.0}\n";

/* 1,500 hexapods (4,500 primitives) standing in a box, for the wall load. */
static const char *many = "run: {name: parity_load, dt: 1.0e-5, steps: 0, seed: 22}\n"
                          "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 1500}]\n"
                          "domain: {type: box, width: 0.3, height: 0.3, thickness: 0.3}\n"
                          "init: {placement: lattice, clearance: 1.0, speed: 0}\n";

/* The OpenCL backend is built, so an OpenCL platform is a dependency
 * (PoCL on a CPU): without one the parity checks fail rather than pass
 * unchecked. */
static const char *no_platform_msg =
    "no OpenCL platform found: install pocl-opencl-icd (.ci/install-deps) or build with -DCAPDEM_OPENCL=OFF";

/* Sets up a case on a backend; 1 when OpenCL has no platform here. */
static int start_yaml_on(cd_sim *sim, cd_config *cfg, const char *yaml, const char *backend)
{
    char err[2048];
    if (cd_config_parse(yaml, "parity.yaml", cfg, err, sizeof err)) fail_msg("config: %s", err);
    if (cd_sim_setup(sim, cfg, err, sizeof err)) fail_msg("setup: %s", err);
    if (cd_sim_use_backend(sim, backend, "auto", err, sizeof err)) fail_msg("%s", err);
    if (cd_sim_start(sim, 1, err, sizeof err)) {
        if (strstr(err, "no platform found")) return 1;
        fail_msg("start on %s: %s", backend, err);
    }
    return 0;
}

static int start_on(cd_sim *sim, cd_config *cfg, const char *backend)
{
    return start_yaml_on(sim, cfg, settling, backend);
}

/* Largest |a - b| / scale over the components of n vectors. */
static double max_diff(const cd_vec3 *a, const cd_vec3 *b, size_t n, double scale)
{
    double worst = 0;
    for (size_t q = 0; q < n; q++) {
        double d = fmax(fabs(a[q].x - b[q].x), fmax(fabs(a[q].y - b[q].y), fabs(a[q].z - b[q].z)));
        if (d / scale > worst) worst = d / scale;
    }
    return worst;
}

static double max_norm(const cd_vec3 *a, size_t n)
{
    double m = 0;
    for (size_t q = 0; q < n; q++) m = fmax(m, cd_v3_norm(a[q]));
    return m;
}

/* Keys of the active contacts, in row order (the rows are sorted). */
static size_t active_keys(const cd_state *s, cd_ulong *out)
{
    size_t n = 0;
    for (size_t k = 0; k < s->n_pairs; k++)
        if (s->pair_active[k]) out[n++] = ((cd_ulong)(cd_uint)s->pair_prim_i[k] << 32) | (cd_uint)s->pair_prim_j[k];
    return n;
}

static int same_particle_bits(const cd_state *a, const cd_state *b)
{
    for (size_t f = 0; f < cd_n_fields; f++) {
        if (cd_fields[f].group != CD_GROUP_PARTICLE) continue;
        const void *pa = *(void *const *)((const char *)a + cd_fields[f].offset);
        const void *pb = *(void *const *)((const char *)b + cd_fields[f].offset);
        if (memcmp(pa, pb, a->n_particles * cd_fields[f].elem_size)) return 0;
    }
    return 1;
}

/* Runs yaml on both backends for chunks x 500 steps, comparing after each
 * chunk. */
static void settle_on_both(const char *yaml, int chunks)
{
    static cd_sim a, b;
    cd_config ca, cb;
    if (start_yaml_on(&a, &ca, yaml, "omp")) fail_msg("omp backend failed to start");
    if (start_yaml_on(&b, &cb, yaml, "opencl")) {
        cd_sim_free(&a);
        cd_config_free(&ca);
        fail_msg("%s", no_platform_msg);
    }
    size_t N = a.s.n_particles;
    double size = 3 * 0.005; /* hexapod tip-to-tip length [m]: position scale */
    cd_ulong *ka = NULL, *kb = NULL;
    size_t contacts = 0;
    int bitwise = 1;
    double worst_x = 0, worst_v = 0;
    for (int chunk = 0; chunk < chunks; chunk++) {
        cdt_step(&a, 500);
        cdt_step(&b, 500);
        /* identical contact sets */
        ka = realloc(ka, (a.s.n_pairs + 1) * sizeof *ka);
        kb = realloc(kb, (b.s.n_pairs + 1) * sizeof *kb);
        assert_non_null(ka);
        assert_non_null(kb);
        size_t na = active_keys(&a.s, ka), nb = active_keys(&b.s, kb);
        assert_int_equal(na, nb);
        assert_memory_equal(ka, kb, na * sizeof *ka);
        contacts = na;
        /* positions and velocities to 1e-10 relative */
        double vscale = fmax(max_norm(a.s.velocity, N), 1e-3); /* [m/s] */
        double dx = max_diff(a.s.position, b.s.position, N, size), dv = max_diff(a.s.velocity, b.s.velocity, N, vscale);
        worst_x = fmax(worst_x, dx);
        worst_v = fmax(worst_v, dv);
        assert_true(dx <= 1e-10);
        assert_true(dv <= 1e-10);
        bitwise = bitwise && same_particle_bits(&a.s, &b.s);
        assert_int_equal(a.s.step, b.s.step);
    }
    print_message("parity over %lld steps: %zu contacts, %lld / %lld list builds (omp / opencl), max difference "
                  "%.3g of the particle size in position, %.3g of the top speed in velocity; particle columns %s\n",
                  a.s.step, contacts, a.nb.builds, b.nb.builds, worst_x, worst_v,
                  bitwise ? "bitwise identical" : "NOT bitwise identical");
    assert_true(contacts > 200); /* a real packing, not a gas */
    free(ka);
    free(kb);
    cd_sim_free(&a);
    cd_sim_free(&b);
    cd_config_free(&ca);
    cd_config_free(&cb);
}

static void test_omp_and_opencl_agree_on_settling_hexapods(void **state)
{
    (void)state;
    settle_on_both(settling, 4);
}

/* The Hertz-Mindlin law is the same source on both backends too. */
static void test_omp_and_opencl_agree_with_hertz_mindlin(void **state)
{
    (void)state;
    settle_on_both(settling_hertz, 4);
}

/* Candidate slots of one entry overflow at the first builds: the device
 * falls back to a second scan and doubles the slots, and the list, hence
 * the trajectory, stays the same. */
static void test_candidate_slot_overflow_changes_nothing(void **state)
{
    (void)state;
    static cd_sim a, b;
    cd_config ca, cb;
    if (start_on(&a, &ca, "omp")) fail_msg("omp backend failed to start");
    setenv("CAPDEM_OPENCL_SLOTS", "1", 1);
    int no_platform = start_on(&b, &cb, "opencl");
    unsetenv("CAPDEM_OPENCL_SLOTS");
    if (no_platform) {
        cd_sim_free(&a);
        cd_config_free(&ca);
        fail_msg("%s", no_platform_msg);
    }
    cdt_step(&a, 1000);
    cdt_step(&b, 1000);
    assert_int_equal(a.s.n_pairs, b.s.n_pairs);
    assert_memory_equal(a.s.pair_prim_j, b.s.pair_prim_j, a.s.n_pairs * sizeof(cd_prim_id));
    assert_memory_equal(a.s.position, b.s.position, a.s.n_particles * sizeof(cd_vec3));
    cd_sim_free(&a);
    cd_sim_free(&b);
    cd_config_free(&ca);
    cd_config_free(&cb);
}

/* A wall load over more primitives than one chunk (CD_LOAD_CHUNK): the
 * OpenCL backend's parallel chunk sums, added in chunk order, give the
 * bits of the host's sum (sim.c), which adds the chunks the same way; the
 * plain sum in primitive order differs from it by rounding only. */
static void test_wall_load_same_bits_on_both_backends(void **state)
{
    (void)state;
    static cd_sim a, b;
    cd_config ca, cb;
    if (start_yaml_on(&a, &ca, many, "omp")) fail_msg("omp backend failed to start");
    assert_true(a.s.n_prims > CD_LOAD_CHUNK); /* 1,500 hexapods, 4,500 primitives: two chunks */
    uint64_t x = 12345;
    for (size_t r = 0; r < a.s.n_prims * a.s.n_walls; r++) {
        x = x * 6364136223846793005ULL + 1442695040888963407ULL;
        a.s.wallc_fn[r] = (double)(x >> 11) * 0x1.0p-53 * 10; /* [N], 0..10 */
    }
    char err[1024];
    if (cd_sim_start(&a, 0, err, sizeof err)) fail_msg("%s", err);
    int no_platform = start_yaml_on(&b, &cb, many, "opencl");
    if (no_platform) {
        cd_sim_free(&a);
        cd_config_free(&ca);
        fail_msg("%s", no_platform_msg);
    }
    b.backend->stop(&b);
    if (cd_state_copy(&b.s, &a.s)) fail_msg("copy");
    if (cd_sim_start(&b, 0, err, sizeof err)) fail_msg("%s", err);
    for (int w = 0; w < (int)a.s.n_walls; w++) {
        double la, lb, plain = 0;
        if (cd_sim_wall_load(&a, w, &la, err, sizeof err) || cd_sim_wall_load(&b, w, &lb, err, sizeof err))
            fail_msg("%s", err);
        for (size_t i = 0; i < a.s.n_prims; i++) plain += a.s.wallc_fn[i * a.s.n_walls + (size_t)w];
        print_message("wall %d: %.17g N (plain sum %+.3g)\n", w, la, lb - plain);
        assert_memory_equal(&la, &lb, sizeof la);
        assert_true(fabs(la - plain) <= 1e-12 * plain);
    }
    cd_sim_free(&a);
    cd_sim_free(&b);
    cd_config_free(&ca);
    cd_config_free(&cb);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_omp_and_opencl_agree_on_settling_hexapods),
        cmocka_unit_test(test_omp_and_opencl_agree_with_hertz_mindlin),
        cmocka_unit_test(test_candidate_slot_overflow_changes_nothing),
        cmocka_unit_test(test_wall_load_same_bits_on_both_backends),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
