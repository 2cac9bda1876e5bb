/* The neighbour-list rebuild reads the state it bins (issue 20): the
 * Verlet list is rebuilt where the steps run (on the offload device in the
 * offload variants), binning particles into cells and bounding them about
 * their centres.  If the build read a stale copy of a column (as the host
 * round trip of an earlier version read a stale `position`), the list
 * still holds the same pairs -- the bounds only grow with the drift -- so
 * no other test sees it, but the cell grid coarsens until the build tends
 * to O(N^2).  Here every
 * particle's bounding radius as the last build computed it must equal the
 * one computed from the state of that build, bit for bit.  Runs on every
 * variant (the host variant passes trivially); it matters on
 * CAPDEM_OFFLOAD=host, where the device memory is separate. */
#include "test_util.h"
#include <math.h>
#include "../kernels/broadphase.h"

/* 300 alpha-3 hexapods of 5 mm dropped at 0.25 m/s from a lattice into a
 * cylinder: rebuilds every few tens of steps as they fall. */
static const char *drop =
    "run: {seed: 1, dt: 8.0e-6, steps: 0}\n"
    "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0.2, friction: 0.5, wall_friction: 0.0}\n"
    "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 300, polydispersity: 0.2}]\n"
    "domain: {type: cylinder, diameter: 0.15, height: 0.6}\n"
    "init: {placement: lattice, clearance: 1.5, speed: 0.25}\n";

static void test_rebuild_bounds_particles_about_current_centres(void **state)
{
    (void)state;
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg, drop);
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    const cd_state *s = &sim.s;
    double *bounds = malloc(s->n_particles * sizeof(double));
    assert_non_null(bounds);
    long long builds = sim.nb.builds;
    int checked = 0;
    double worst = 0; /* largest bound / true bound - 1 seen [1] */
    for (int k = 0; k < 2000 && checked < 10; k++) {
        cdt_step(&sim, 1); /* a build happens after the drift: the centres are those of the build */
        if (sim.nb.builds == builds) continue;
        builds = sim.nb.builds;
        checked++;
        assert_int_equal(cd_neighbors_part_bounds(&sim, bounds), 0);
        for (size_t p = 0; p < s->n_particles; p++) {
            double b = cd_bp_particle_bound(s->prim_a_ref, s->prim_b_ref, s->prim_radius, s->prim_first[p],
                                            s->prim_count[p], s->position[p]);
            if (bounds[p] / b - 1 > worst) worst = bounds[p] / b - 1;
            if (bounds[p] != b)
                fail_msg("build %lld at step %lld: particle %zu bounded by %.17g m about the centre the build "
                         "read, %.17g m about its current centre",
                         builds, s->step, p, bounds[p], b);
        }
    }
    print_message("%d rebuilds checked (largest bound excess %.3g)\n", checked, worst);
    assert_true(checked >= 3);
    free(bounds);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rebuild_bounds_particles_about_current_centres),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
