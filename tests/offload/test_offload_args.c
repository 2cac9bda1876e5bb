/* The step loops' arguments stay on the device (issue 20 item 1;
 * docs/offload.md, "Per-step copies"): in the offload variants the loops
 * take the device address of one argument block (columns, lists, laws,
 * walls), which goes out only when it changes.  Here, over steps without a
 * rebuild: no copy of the block's head at all, and one copy of the walls
 * per step while a wall moves (and one when its velocity is set), none
 * while they stand.  Before, every
 * launch copied its firstprivate structs (280-624 B) and the wall loop the
 * 832 B of the walls.  On host threads nothing is copied and the counts
 * stay 0 (the test then checks only that); it matters on
 * CAPDEM_OFFLOAD=host and on a GPU. */
#include "test_util.h"
#include "backend/omp/omp_loops.h"

/* 60 hexapods at rest in a box without gravity: no contact, no motion, no
 * rebuild after the first. */
static const char *resting = "run: {seed: 3, dt: 1.0e-5, steps: 0}\n"
                             "physics: {gravity: [0, 0, 0]}\n"
                             "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 60}]\n"
                             "domain: {type: box, width: 0.1, height: 0.1, thickness: 0.1}\n"
                             "init: {placement: lattice, clearance: 1.5, speed: 0}\n";

#if defined(CAPDEM_OFFLOAD_TARGET) && CAPDEM_OFFLOAD_TARGET
#define OFFLOADED 1
#else
#define OFFLOADED 0
#endif

static void test_arguments_copied_only_when_they_change(void **state)
{
    (void)state;
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg, resting);
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    long long c0[2], c1[2], c2[2];
    cdt_step(&sim, 2); /* the first steps allocate the skin flag: the head goes out again */
    cd_sim_step_arg_copies(&sim, c0, NULL);
    long long builds = sim.nb.builds;
    cdt_step(&sim, 100); /* standing walls */
    cd_sim_step_arg_copies(&sim, c1, NULL);
    assert_int_equal(sim.nb.builds, builds);
    assert_int_equal(c1[0] - c0[0], 0);
    assert_int_equal(c1[1] - c0[1], 0);
    /* a wall moving at 1 mm/s: 20 steps move it 0.2 um, far below half the skin */
    sim.s.walls[0].velocity = cd_v3_scale(sim.s.walls[0].normal, -1e-3);
    cdt_step(&sim, 20);
    cd_sim_step_arg_copies(&sim, c2, NULL);
    assert_int_equal(sim.nb.builds, builds);
    assert_int_equal(c2[0] - c1[0], 0);
    /* one copy for the new velocity (the call's first advance), then one
     * per step as the wall moves */
    assert_int_equal(c2[1] - c1[1], OFFLOADED ? 21 : 0);
    print_message("argument block copies (head, walls): %lld, %lld after start and 2 steps; +%lld, +%lld in 100 "
                  "steps with standing walls; +%lld, +%lld in 20 steps with a moving wall\n",
                  c0[0], c0[1], c1[0] - c0[0], c1[1] - c0[1], c2[0] - c1[0], c2[1] - c1[1]);
    if (OFFLOADED) assert_true(c0[0] > 0 && c0[1] > 0); /* the block did go out */
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

/* A build moves only the addresses of the wall-candidate lists (the new
 * ones and the previous build's swap places): the block's head goes out
 * once per build, as the span of words that changed (32 B), not whole
 * (hundreds of bytes) and not once per launch of the build. */
static void test_a_build_sends_the_changed_span_once(void **state)
{
    (void)state;
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg, resting);
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    cdt_step(&sim, 5);
    long long c0[2], b0[2], c1[2], b1[2];
    cd_sim_step_arg_copies(&sim, c0, b0);
    long long builds = sim.nb.builds;
    for (int k = 0; k < 10; k++) {
        sim.nb.force_rebuild = 1;
        cdt_step(&sim, 1);
    }
    cd_sim_step_arg_copies(&sim, c1, b1);
    assert_int_equal(sim.nb.builds - builds, 10);
    print_message("10 builds: +%lld copies of the head, %lld B\n", c1[0] - c0[0], b1[0] - b0[0]);
    assert_int_equal(c1[0] - c0[0], OFFLOADED ? 10 : 0);
    assert_true(b1[0] - b0[0] <= (OFFLOADED ? 10 * 64 : 0));
    assert_int_equal(c1[1] - c0[1], 0); /* standing walls */
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_arguments_copied_only_when_they_change),
                                       cmocka_unit_test(test_a_build_sends_the_changed_span_once)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
