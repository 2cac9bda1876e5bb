/* Bodies on a floor come to rest (docs/references.md, Contacts, Motion). */
#include "test_util.h"
#include <math.h>

static const char *one_body_on_floor =
    "run: {dt: 5.0e-6, steps: 0}\n"
    "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0.2, friction: 0.5, wall_friction: 0.5}\n"
    "particles: [{shape: %s, aspect: 3, diameter: 0.005, count: 1}]\n"
    "domain: {type: none, walls: [{type: plane, point: [0, 0, 0], normal: [0, 1, 0]}]}\n"
    "init: {speed: 0}\n";

/* A hexapod dropped from 2 cm in a tilted orientation bounces, tips over and
 * stops: its kinetic energy falls below 1e-9 of the drop energy, and its
 * lowest point rests on the floor with the static overlap of a few contacts
 * (m g / (kn/2) = 1.3e-7 m for one contact, less when shared). */
static void test_hexapod_dropped_on_floor_comes_to_rest(void **state)
{
    (void)state;
    char yaml[1024];
    snprintf(yaml, sizeof yaml, one_body_on_floor, "hexapod");
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg, yaml);
    cd_quat tilt = cd_q_normalize(cd_q(0.9, 0.3, 0.2, 0.1));
    cdt_place(&sim, 0, cd_v3(0, 0.02, 0), tilt, cd_v3(0.05, 0, 0), cd_v3(0, 0, 3));
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    double drop_energy = sim.s.mass[0] * 9.81 * 0.02;
    cdt_step(&sim, 200000); /* 1 s */
    cd_observables o;
    cd_sim_observe(&sim, &o);
    double ke = o.kinetic_translational + o.kinetic_rotational;
    print_message("hexapod at rest: KE/E_drop = %.3g, wall contacts %g\n", ke / drop_energy, o.n_wall_contacts);
    assert_true(ke < 1e-9 * drop_energy);
    assert_true(o.n_wall_contacts >= 3); /* a stable stance */
    assert_true(o.max_overlap_ratio < 1e-4);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

/* A rod lying flat on the floor (its axis parallel to the floor, the
 * parallel-contact rule applies) stays put: no jitter, and the total energy
 * (kinetic + potential + elastic) never rises above its starting value, only
 * decays. */
static void test_rod_lying_flat_rests_without_jitter(void **state)
{
    (void)state;
    char yaml[1024];
    snprintf(yaml, sizeof yaml, one_body_on_floor, "rod");
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg, yaml);
    double r = 0.0025, overlap = sim.s.mass[0] * 9.81 / (0.5 * cfg.kn);
    cdt_place(&sim, 0, cd_v3(0, r - overlap, 0), cd_q_identity(), cd_v3_zero(), cd_v3_zero());
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    double e0 = cdt_total_energy(&sim), emax = e0;
    double scale = sim.s.mass[0] * 9.81 * r; /* [J] */
    for (int k = 0; k < 200; k++) {
        cdt_step(&sim, 1000);
        double e = cdt_total_energy(&sim);
        if (e > emax) emax = e;
    }
    cd_observables o;
    cd_sim_observe(&sim, &o);
    double ke = o.kinetic_translational + o.kinetic_rotational;
    print_message("rod flat: KE = %.3g J, energy rise %.3g of m g r\n", ke, (emax - e0) / scale);
    assert_true(ke < 1e-12 * scale);
    assert_true(emax - e0 < 1e-12 * scale);
    cd_vec3 x = sim.s.position[0];
    assert_true(fabs(x.x) < 1e-12 && fabs(x.z) < 1e-12);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hexapod_dropped_on_floor_comes_to_rest),
        cmocka_unit_test(test_rod_lying_flat_rests_without_jitter),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
