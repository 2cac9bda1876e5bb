/* Conservation laws of the step (docs/references.md, Contact law, Motion): energy without damping
 * or friction, linear and angular momentum in free collisions. */
#include "test_util.h"
#include <math.h>

/* Frictionless, undamped particles bouncing in a closed box without gravity.
 * Velocity Verlet is symplectic for the conservative part, so the energy
 * does not drift; it fluctuates while contacts are loaded by a relative
 * amount of order (omega dt)^2 / 8 of the contact energy, with
 * omega dt = pi dt / t_col.  At dt = t_col/50 that is 5e-4 (the bounds
 * below say how they follow from it and from the measured errors). */
/* Bounds: measured (2026-11-25, both backends, the same digits) max 1.1e-4
 * (hexapods) and 2.9e-4 (crosses), drift 1.7e-5 and 3.5e-6.  The bound on
 * the excursion is twice the amplitude (omega dt)^2/8 = 4.9e-4 that the
 * contacts' share of the energy could reach at most, 4x the largest
 * measured; the drift bound is 6x the largest measured: a first-order or
 * non-symplectic rotation update drifts by more than that within 1e5
 * steps. */
#define ENERGY_MAX   1e-3
#define ENERGY_DRIFT 1e-4
static void energy_in_box(const char *shape, int dimension)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "run: {dt: 1.0e-5, steps: 0, seed: 7}\n"
             "physics: {dimension: %d, gravity: [0, 0, 0]}\n"
             "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0, damping_tangential: 0, friction: 0}\n"
             "particles: [{shape: %s, aspect: 3, diameter: 0.005, count: 27, polydispersity: 0.2}]\n"
             "domain: {type: box, width: 0.12, height: 0.12, thickness: 0.08}\n"
             "init: {placement: lattice, clearance: 1.05, speed: 1.0}\n",
             dimension, shape);
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg, yaml);
    /* dt = t_col/50 of the lightest pair */
    sim.p.dt = sim.collision_time / 50;
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    double e0 = cdt_total_energy(&sim), worst = 0, first = 0, last = 0;
    long long contacts_seen = 0;
    /* sampled every 25 steps (a contact lasts 50: the peaks of a contact's
     * oscillation are met within a factor (cos(pi/4))^2); the means of the
     * first and the last tenth of the run give the drift */
    for (int block = 0; block < 4000; block++) {
        cdt_step(&sim, 25);
        double e = cdt_total_energy(&sim), rel = (e - e0) / e0;
        if (fabs(rel) > worst) worst = fabs(rel);
        if (block < 400) first += rel / 400;
        if (block >= 3600) last += rel / 400;
        cd_observables o;
        cd_sim_observe(&sim, &o);
        contacts_seen += (long long)(o.n_contacts + o.n_wall_contacts);
    }
    print_message("%s (%dD): relative energy error over 1e5 steps: max %.3g, drift (last - first tenth) %.3g, "
                  "%lld contacts seen\n",
                  shape, dimension, worst, last - first, contacts_seen);
    assert_true(contacts_seen > 400);
    assert_true(worst < ENERGY_MAX);
    assert_true(fabs(last - first) < ENERGY_DRIFT);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

static void test_energy_conserved_hexapods_in_box(void **state)
{
    (void)state;
    energy_in_box("hexapod", 3);
}
static void test_energy_conserved_crosses_2d(void **state)
{
    (void)state;
    energy_in_box("cross", 2);
}

/* Free collisions (no walls, no gravity, with friction and damping):
 * contact forces are equal and opposite and act at one point, so total
 * linear and angular momentum change only by round-off. */
static void test_momentum_conserved_in_free_collisions(void **state)
{
    (void)state;
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg,
              "run: {dt: 2.0e-6, steps: 0, seed: 3}\n"
              "physics: {gravity: [0, 0, 0]}\n"
              "particles: [{shape: hexapod, aspect: 4, diameter: 0.005, count: 27, polydispersity: 0.2}]\n"
              "domain: {type: none}\n"
              "init: {placement: lattice, clearance: 1.02, speed: 1.0}\n");
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    double P0[3], L0[3], scale_p = 0, scale_l = 0;
    cd_state *s = &sim.s;
    for (int pass = 0; pass < 2; pass++) {
        double P[3] = {0, 0, 0}, L[3] = {0, 0, 0};
        for (size_t q = 0; q < s->n_particles; q++) {
            cd_vec3 p = cd_v3_scale(s->velocity[q], s->mass[q]);
            cd_vec3 l = cd_v3_add(cd_v3_cross(s->position[q], p), s->angmom[q]);
            P[0] += p.x;
            P[1] += p.y;
            P[2] += p.z;
            L[0] += l.x;
            L[1] += l.y;
            L[2] += l.z;
            if (pass == 0) {
                scale_p += cd_v3_norm(p);
                scale_l += cd_v3_norm(l);
            }
        }
        if (pass == 0) {
            memcpy(P0, P, sizeof P);
            memcpy(L0, L, sizeof L);
            /* the lattice of hexapods flies apart at 1 m/s: count the
             * contacts on the way, so that a run without any collision
             * cannot pass for conservation */
            double contacts_seen = 0;
            for (int block = 0; block < 400; block++) {
                cdt_step(&sim, 50);
                cd_observables o;
                cd_sim_observe(&sim, &o);
                contacts_seen += o.n_contacts;
            }
            print_message("contacts seen (every 50 steps): %.0f\n", contacts_seen);
            assert_true(contacts_seen >= 10);
            assert_true(sim.nb.builds > 1);
        } else {
            for (int c = 0; c < 3; c++) {
                assert_true(fabs(P[c] - P0[c]) < 1e-12 * scale_p);
                assert_true(fabs(L[c] - L0[c]) < 1e-10 * scale_l);
            }
        }
    }
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_energy_conserved_hexapods_in_box),
        cmocka_unit_test(test_energy_conserved_crosses_2d),
        cmocka_unit_test(test_momentum_conserved_in_free_collisions),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
