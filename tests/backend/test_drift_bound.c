/* Host-versus-device maths drift, bounded (docs/offload.md, "Which maths
 * can differ").  The same settling case runs on two backends, A (omp) and
 * B (OpenCL); where their maths differ (a GPU's sqrt, division or
 * contraction against the host's; PoCL on a CPU agrees to the bit) the
 * trajectories part by round-off that the contacts amplify.  The test
 * asserts that the parting stays below a bound made of two measured
 * parts:
 *
 * - growth: a twin of A whose every coordinate starts one ulp of the
 *   position scale X away (exact: +ulp(X) is representable for |x| <= X)
 *   measures how the case amplifies a perturbation, S(m) = the largest
 *   coordinate difference after m steps (running maximum), so a
 *   perturbation e made at step j has grown to at most e S(m - j) / ulp(X)
 *   at step m (the twin's growth, taken as that of any round-off-sized
 *   perturbation: see the premise below);
 * - injection: per step, two maths whose every operation is within k ulp
 *   of each other make states that differ by at most k ulp of X.  The
 *   position update x + dt v is correctly rounded on every backend; the
 *   maths enters through the increments (forces, velocities, the rotation:
 *   sqrt and division are correctly rounded in IEEE 754, OpenCL C for
 *   doubles and CUDA; cd_sincos is our own polynomial; a compiler that
 *   contracted a*b+c would differ by an ulp of a product), and an increment
 *   is far below X (checked: dt |v| < 1e-2 X), so k ulp of an increment,
 *   even with an O(1) factor for a velocity perturbation growing faster
 *   than a position one, is below k ulp of X.  k = 16: the largest
 *   tolerance OpenCL C 1.2 allows a double built-in the kernels could
 *   reach (pow), over the 0.5-2 ulp of glibc, newlib and libdevice.
 *
 * Summed over the steps (linear in the perturbation while it stays at
 * round-off scale): D(n) <= k sum_{m<n} S(m), with S sampled every
 * `every` steps and held at the sample's end value over its interval.
 * Premise, asserted too: the twin stays below 1e-3 of a particle's size
 * over the steps run (the regime where the linear sum holds).
 *
 * The test can fail: a third run of B with gravity changed by 1e-6 (a
 * physical difference, not round-off) must break the bound.
 *
 * With CAPDEM_DRIFT_STEPS the number of steps changes (default 1000); the
 * GPU bundle runs it with omp on the host against OpenCL on the GPU
 * (docs/gpu_bundle.md). */
#include "test_util.h"
#include <float.h>
#include <math.h>

static const char *settling = "run: {name: drift, dt: 1.0e-5, steps: 100000, seed: 21}\n"
                              "physics: {gravity: [0, -981, 0]}\n"
                              "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 300, "
                              "polydispersity: 0.2}]\n"
                              "domain: {type: cylinder, diameter: 0.1, height: 0.3}\n"
                              "init: {placement: lattice, clearance: 1.0, speed: 2.0}\n";

#define ULP_BUDGET  16 /* k above */
#define EVERY       50 /* steps between samples */
#define MAX_SAMPLES 4096

/* 1 when the backend has no OpenCL platform here. */
static int start_on(cd_sim *sim, cd_config *cfg, const char *backend, double ulp_shift, double gravity_factor)
{
    char err[2048];
    if (cd_config_parse(settling, "drift.yaml", cfg, err, sizeof err)) fail_msg("config: %s", err);
    if (cd_sim_setup(sim, cfg, err, sizeof err)) fail_msg("setup: %s", err);
    if (cd_sim_use_backend(sim, backend, "auto", err, sizeof err)) fail_msg("%s", err);
    for (size_t q = 0; q < sim->s.n_particles; q++) {
        sim->s.position[q].x += ulp_shift;
        sim->s.position[q].y += ulp_shift;
        sim->s.position[q].z += ulp_shift;
    }
    sim->p.gravity = cd_v3_scale(sim->p.gravity, gravity_factor);
    if (cd_sim_start(sim, 1, err, sizeof err)) {
        if (strstr(err, "no platform found")) return 1;
        fail_msg("start on %s: %s", backend, err);
    }
    return 0;
}

/* Largest coordinate difference [m]. */
static double max_coord_diff(const cd_state *a, const cd_state *b)
{
    double d = 0;
    for (size_t q = 0; q < a->n_particles; q++) {
        cd_vec3 x = a->position[q], y = b->position[q];
        d = fmax(d, fmax(fabs(x.x - y.x), fmax(fabs(x.y - y.y), fabs(x.z - y.z))));
    }
    return d;
}

static double max_coord(const cd_state *s)
{
    double m = 0;
    for (size_t q = 0; q < s->n_particles; q++)
        m = fmax(m, fmax(fabs(s->position[q].x), fmax(fabs(s->position[q].y), fabs(s->position[q].z))));
    return m;
}

static double max_speed(const cd_state *s)
{
    double m = 0;
    for (size_t q = 0; q < s->n_particles; q++) m = fmax(m, cd_v3_norm(s->velocity[q]));
    return m;
}

static void test_drift_within_bound(void **state)
{
    (void)state;
    const char *env = getenv("CAPDEM_DRIFT_STEPS");
    long steps = env && atol(env) > 0 ? atol(env) : 1000;
    if (steps / EVERY > MAX_SAMPLES) steps = (long)EVERY * MAX_SAMPLES;
    static cd_sim a, t, b, p;
    cd_config ca, ct, cb, cp;
    if (start_on(&a, &ca, "omp", 0, 1)) fail_msg("omp backend failed to start");
    double X = max_coord(&a.s), ulp_X = nextafter(X, INFINITY) - X; /* position scale [m], its ulp */
    if (start_on(&t, &ct, "omp", ulp_X, 1)) fail_msg("omp backend failed to start");
    if (start_on(&b, &cb, "opencl", 0, 1) || start_on(&p, &cp, "opencl", 0, 1 + 1e-6))
        fail_msg("no OpenCL platform found: install pocl-opencl-icd or build with -DCAPDEM_OPENCL=OFF");
    double size = 3 * 0.005; /* hexapod tip to tip [m] */
    double S_run = max_coord_diff(&a.s, &t.s), sum_S = 0, worst_ratio = 0, D = 0, P = 0, bound = 0;
    double increment = 0;        /* largest dt |v| / X seen */
    assert_true(S_run == ulp_X); /* the twin starts exactly one ulp of X away */
    for (long n = EVERY; n <= steps; n += EVERY) {
        cdt_step(&a, EVERY);
        cdt_step(&t, EVERY);
        cdt_step(&b, EVERY);
        cdt_step(&p, EVERY);
        /* the interval's steps, each held at its end value (S grows) */
        S_run = fmax(S_run, max_coord_diff(&a.s, &t.s));
        sum_S += EVERY * S_run;
        bound = ULP_BUDGET * sum_S;
        D = max_coord_diff(&a.s, &b.s);
        P = max_coord_diff(&a.s, &p.s);
        increment = fmax(increment, a.p.dt * max_speed(&a.s) / X);
        worst_ratio = fmax(worst_ratio, D / bound);
        if (D > bound)
            fail_msg("step %ld: omp and opencl differ by %.3g m, above the bound %.3g m (twin %.3g m)", n, D, bound,
                     S_run);
    }
    cd_observables o;
    cd_sim_observe(&a, &o);
    print_message("drift over %ld steps (X = %.3g m, ulp %.3g m): twin (1 ulp of X at start) %.3g m, growth %.3g; "
                  "bound k sum S = %.3g m (%.3g of a particle's size); omp against opencl %.3g m (%.3g of the "
                  "bound at worst); planted (gravity x (1 + 1e-6)) %.3g m; %ld contacts, largest dt|v|/X %.3g\n",
                  steps, X, ulp_X, S_run, S_run / ulp_X, bound, bound / size, D, worst_ratio, P, (long)o.n_contacts,
                  increment);
    /* the premises of the bound */
    assert_true(increment < 1e-2);
    assert_true(S_run < 1e-3 * size);
    assert_true(o.n_contacts > 50); /* colliding bodies (82 at 1,000 steps), not a gas */
    /* the test can fail: a physical difference breaks the bound */
    assert_true(P > bound);
    cd_sim_free(&a);
    cd_sim_free(&t);
    cd_sim_free(&b);
    cd_sim_free(&p);
    cd_config_free(&ca);
    cd_config_free(&ct);
    cd_config_free(&cb);
    cd_config_free(&cp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_drift_within_bound)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
