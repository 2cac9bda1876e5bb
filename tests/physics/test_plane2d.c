/* 2D mode (physics.dimension: 2) in a box: the particles move in the plane
 * z = thickness/2, so the box has no front and back walls.  A disc larger
 * than the slab (polydisperse discs of study 4 are up to 1.2 d_p in a slab
 * of d_p) resting on the floor touches the floor only: one wall contact,
 * the elastic energy of that one spring, a particle stress from its load. */
#include "test_util.h"
#include <math.h>

static void test_disc_thicker_than_the_slab_touches_only_the_floor(void **state)
{
    (void)state;
    const double d = 0.008, T = 0.005, kn = 1.0e5; /* [m], [m], [N/m] */
    const char *yaml = "run: {dt: 5.0e-6, steps: 0}\n"
                       "physics: {dimension: 2}\n"
                       "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0.2, friction: 0.5}\n"
                       "particles: [{shape: sphere, diameter: 0.008, count: 1}]\n"
                       "domain: {type: box, width: 0.05, height: 0.05, thickness: 0.005}\n"
                       "init: {speed: 0}\n";
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg, yaml);
    assert_int_equal(sim.s.n_walls, 4); /* floor, top, two sides */
    const double delta = 1e-5;          /* overlap with the floor [m] */
    cdt_place(&sim, 0, cd_v3(0.025, 0.5 * d - delta, 0.5 * T), cd_q_identity(), cd_v3_zero(), cd_v3_zero());
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    char err[256];
    assert_int_equal(cd_sim_sync(&sim, err, sizeof err), 0);
    cd_observables o;
    cd_sim_observe(&sim, &o);
    assert_true(o.n_wall_contacts == 1);
    /* the floor spring alone: the law's normal spring is kn/2 (docs/references.md, Contact law), so
     * 1/4 kn delta^2 = 2.5e-6 J; with front and back walls the disc (1.5 mm
     * into each) would add 0.11 J */
    double e = 0.25 * kn * delta * delta; /* [J] */
    assert_true(fabs(o.elastic - e) < 1e-12 * e);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_disc_thicker_than_the_slab_touches_only_the_floor),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
