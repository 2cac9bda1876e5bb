/* physics.sphere_orientation: fixed (docs/motion.md, "Spheres that keep
 * their orientation"): a sphere's forces do not depend on its orientation,
 * so keeping it fixed must leave every other number of the run as it was,
 * bit for bit, while the other bodies, isotropic hexapods among them, turn
 * as before. */
#include "test_util.h"
#include <string.h>

/* Spheres, rods (anisotropic) and hexapods of three equal arms (isotropic,
 * like a sphere, but with arms: their orientation moves their arms) poured
 * with friction onto a floor, so that the spheres roll and spin. */
static const char *MIXTURE = "run: {dt: 2.0e-6, steps: 0, seed: 11}\n"
                             "physics: {gravity: [0, -9.81, 0], sphere_orientation: %s}\n"
                             "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, friction: 0.5, wall_friction: 0.3}\n"
                             "particles: [{shape: sphere, diameter: 0.004, count: 40, polydispersity: 0.2},\n"
                             "            {shape: rod, aspect: 3, diameter: 0.002, count: 20},\n"
                             "            {shape: hexapod, aspect: 3, diameter: 0.002, count: 20}]\n"
                             "domain: {type: box, width: 0.03, thickness: 0.03}\n"
                             "init: {placement: lattice, clearance: 1.05, speed: 1.0}\n";

static void run(cd_sim *sim, cd_config *cfg, const char *orientation, long long steps)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml, MIXTURE, orientation);
    cdt_setup(sim, cfg, yaml);
    assert_int_equal(cd_sim_initial_forces(sim), 0);
    cdt_step(sim, steps);
}

/* one primitive with both body-frame ends at the origin: a ball at the
 * centre, from the host's shape columns (the kernel reads the derived
 * prim_arm instead: cd_particle_is_sphere) */
static int is_sphere(const cd_state *s, size_t q)
{
    cd_int i = s->prim_first[q];
    return s->prim_count[q] == 1 && cd_ends_at_origin(s->prim_a_body[i], s->prim_b_body[i]);
}

static void test_fixed_spheres_change_nothing_but_their_orientation(void **state)
{
    (void)state;
    static cd_sim a, b, start;
    cd_config ca, cb, cs;
    run(&start, &cs, "fixed", 0);
    run(&a, &ca, "integrate", 10000);
    run(&b, &cb, "fixed", 10000);
    const cd_state *sa = &a.s, *sb = &b.s, *s0 = &start.s;
    size_t n = sa->n_particles;
    assert_int_equal(n, 80);
    assert_int_equal(sb->n_particles, n);
    /* every column of the particles but the orientation: the same bits */
    assert_memory_equal(sa->position, sb->position, n * sizeof *sa->position);
    assert_memory_equal(sa->velocity, sb->velocity, n * sizeof *sa->velocity);
    assert_memory_equal(sa->angmom, sb->angmom, n * sizeof *sa->angmom);
    assert_memory_equal(sa->angvel, sb->angvel, n * sizeof *sa->angvel);
    assert_memory_equal(sa->force, sb->force, n * sizeof *sa->force);
    assert_memory_equal(sa->torque, sb->torque, n * sizeof *sa->torque);
    int spheres = 0, spheres_turned = 0, others_turned = 0, hexapods_turned = 0;
    for (size_t q = 0; q < n; q++) {
        int turned = memcmp(&sa->orientation[q], &s0->orientation[q], sizeof(cd_quat)) != 0;
        if (is_sphere(sa, q)) {
            spheres++;
            spheres_turned += turned;
            /* fixed: the orientation it started with */
            assert_memory_equal(&sb->orientation[q], &s0->orientation[q], sizeof(cd_quat));
        } else {
            others_turned += turned;
            hexapods_turned += turned && sa->prim_count[q] == 3;
            /* the others turn as they did */
            assert_memory_equal(&sb->orientation[q], &sa->orientation[q], sizeof(cd_quat));
        }
    }
    print_message("%d spheres, %d of them turned when integrated; %d other bodies turned (%d hexapods)\n", spheres,
                  spheres_turned, others_turned, hexapods_turned);
    assert_int_equal(spheres, 40);
    /* the comparisons above see something: most spheres spin, and most of
     * the isotropic hexapods, which the option must not touch, turn too (40
     * of 40 and 20 of 20 when this was written) */
    assert_true(spheres_turned >= 20);
    assert_true(hexapods_turned >= 10);
    cd_sim_free(&a);
    cd_sim_free(&b);
    cd_sim_free(&start);
    cd_config_free(&ca);
    cd_config_free(&cb);
    cd_config_free(&cs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fixed_spheres_change_nothing_but_their_orientation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
