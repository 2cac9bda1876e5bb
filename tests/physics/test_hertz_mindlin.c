/* The Hertz-Mindlin law (material.law: hertz_mindlin, docs/contacts.md)
 * through the whole step: head-on collisions of two spheres and of a
 * sphere with a wall against Hertz's collision time and against the
 * restitution of the damped Hertz oscillator, and a ball sliding on a
 * floor against the Coulomb motion of a rigid ball. */
#include "test_util.h"
#include <math.h>

/* Soft spheres (E = 10 MPa) so that a collision lasts ~1000 steps. */
#define MATERIAL                                                                                                       \
    "material: {law: hertz_mindlin, density: 1000, young_modulus: 1.0e7, poisson_ratio: 0.3, "                         \
    "friction: 0.5, wall_friction: 0.5, friction_limit: total, damping_normal: %g}\n"

static const double E = 1.0e7, nu = 0.3, d = 0.005; /* [Pa], [1], [m] */

/* Hertz's duration of an undamped collision [s], written out here apart
 * from the kernel's constant: 2 x_max / v times the integral of
 * 1/sqrt(1 - u^(5/2)) over [0, 1] = (2/5) B(2/5, 1/2), with the largest
 * overlap x_max = (15 m v^2 / (16 E* sqrt(R)))^(2/5). */
static double hertz_time(double m_eff, double r_eff, double v)
{
    double e_star = E / (2 * (1 - nu * nu));
    double integral = 0.4 * tgamma(0.4) * tgamma(0.5) / tgamma(0.9);
    double x_max = pow(15 * m_eff * v * v / (16 * e_star * sqrt(r_eff)), 0.4);
    return 2 * integral * x_max / v;
}

/* Restitution of a damped contact from its dimensionless form, the force
 * clipped at zero.  Hertz (hertz = 1): with the law's dashpot
 * 2 sqrt(5/6) eta sqrt(S_n m), S_n = 2 E* a, the overlap obeys
 * x'' = -x^(3/2) - sqrt(5) eta x^(1/4) x' (time and length scaled so that
 * the elastic term has coefficient 1).  Linear (hertz = 0):
 * x'' = -x - 2 eta x'.  No scale is left but eta: e depends neither on the
 * speed nor on the mass or the stiffness.  Classical RK4 with 1e5 steps per
 * unit time; the impact speed is 1. */
static double oscillator_restitution(int hertz, double eta)
{
    double x = 0, v = 1, h = 1e-5;
#define ACC(X, V)                                                                                                      \
    ((X) > 0 ? -fmax(0, hertz ? pow((X), 1.5) + sqrt(5.0) * eta * pow((X), 0.25) * (V) : (X) + 2 * eta * (V)) : 0)
    while (x >= 0) {
        double k1x = v, k1v = ACC(x, v);
        double k2x = v + 0.5 * h * k1v, k2v = ACC(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
        double k3x = v + 0.5 * h * k2v, k3v = ACC(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
        double k4x = v + h * k3v, k4v = ACC(x + h * k3x, v + h * k3v);
        x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
        v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    }
#undef ACC
    return -v;
}

/* The sqrt(5/6) of the Hertz dashpot makes one damping ratio give one
 * restitution in both laws (docs/contacts.md): the two oscillators agree
 * to 1e-5 (their RK4 error is ~1e-7; they differ by 1e-6 at most). */
static void test_same_restitution_as_the_linear_law(void **state)
{
    (void)state;
    for (double eta = 0.05; eta < 0.96; eta += 0.15) {
        double eh = oscillator_restitution(1, eta), el = oscillator_restitution(0, eta);
        print_message("eta_n %.2f: e = %.6f Hertz, %.6f linear\n", eta, eh, el);
        assert_true(fabs(eh - el) < 1e-5);
    }
}

typedef struct {
    double e, duration, t_hertz, energy_drift;
} collision_t;

/* Two spheres (wall = 0) or a sphere and a floor (wall = 1) meeting at
 * speed v0 [m/s] with time step dt [s], no gravity. */
static collision_t collide(int wall, double eta, double v0, double dt)
{
    static cd_sim sim;
    cd_config cfg;
    char yaml[1024];
    snprintf(yaml, sizeof yaml,
             "run: {dt: %g, steps: 0}\n"
             "physics: {gravity: [0, 0, 0]}\n" MATERIAL "particles: [{shape: sphere, diameter: %g, count: %d}]\n"
             "domain: {type: none%s}\n"
             "init: {speed: 0}\n",
             dt, eta, d, wall ? 1 : 2, wall ? ", walls: [{type: plane, point: [0, 0, 0], normal: [1, 0, 0]}]" : "");
    cdt_setup(&sim, &cfg, yaml);
    double gap = 1e-7; /* [m] */
    if (wall) {
        cdt_place(&sim, 0, cd_v3(0.5 * d + gap, 0, 0), cd_q_identity(), cd_v3(-v0, 0, 0), cd_v3_zero());
    } else {
        cdt_place(&sim, 0, cd_v3(-0.5 * (d + gap), 0, 0), cd_q_identity(), cd_v3(0.5 * v0, 0, 0), cd_v3_zero());
        cdt_place(&sim, 1, cd_v3(0.5 * (d + gap), 0, 0), cd_q_identity(), cd_v3(-0.5 * v0, 0, 0), cd_v3_zero());
    }
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    long long in_contact = 0, started = 0;
    collision_t c;
    double e0 = cdt_total_energy(&sim); /* [J] */
    c.energy_drift = 0;
    for (long long k = 0; k < 1000000; k++) {
        cdt_step(&sim, 1);
        int active = 0;
        for (size_t r = 0; r < sim.s.n_pairs; r++) active |= sim.s.pair_active[r];
        for (size_t r = 0; r < sim.s.n_prims * sim.s.n_walls; r++) active |= sim.s.wallc_active[r];
        if (active) {
            in_contact++;
            started = 1;
        } else if (started) break;
        c.energy_drift = fmax(c.energy_drift, fabs(cdt_total_energy(&sim) / e0 - 1));
    }
    double m = sim.s.mass[0];
    if (wall) {
        c.e = sim.s.velocity[0].x / v0;
        c.t_hertz = hertz_time(m, 0.5 * d, v0);
    } else {
        c.e = (sim.s.velocity[1].x - sim.s.velocity[0].x) / v0;
        c.t_hertz = hertz_time(0.5 * m, 0.25 * d, v0);
    }
    c.duration = (double)in_contact * dt;
    cd_sim_free(&sim);
    cd_config_free(&cfg);
    return c;
}

/* Undamped: the contact lasts Hertz's t_c, the spheres leave with their
 * impact speed, and kinetic plus elastic energy (src/backend/omp/observe.c, Hertz's
 * (8/15) E* sqrt(R) delta^(5/2)) stays the impact's kinetic energy within
 * Verlet's O((dt/t_c)^2) ~ 1e-5 error (1e-4 allowed).  dt = 4e-7 s is t_c/1000 (t_c = 0.41 ms at 0.5 m/s):
 * counting steps in contact misses at most one step at each end (2e-3),
 * Verlet's own error is O((dt/t_c)^2) ~ 1e-6, so 3e-3 holds the duration;
 * e = 1 to 1e-3 (the energy error of a contact that starts and ends between
 * two steps is of the order of one step's share, 1e-3). */
static void test_undamped_collision_lasts_hertz_time(void **state)
{
    (void)state;
    for (int wall = 0; wall <= 1; wall++) {
        collision_t c = collide(wall, 0, 0.5, 4e-7);
        print_message("%s, undamped: duration %.6g s, Hertz %.6g s (%+.2e), e = %.6f, energy drift %.2e\n",
                      wall ? "wall" : "pair", c.duration, c.t_hertz, c.duration / c.t_hertz - 1, c.e, c.energy_drift);
        assert_true(fabs(c.duration / c.t_hertz - 1) < 3e-3);
        assert_true(fabs(c.e - 1) < 1e-3);
        assert_true(c.energy_drift < 1e-4);
    }
}

/* t_c ~ v^(-1/5): ten times slower lasts 10^(1/5) = 1.585 times longer. */
static void test_collision_time_scales_with_impact_speed(void **state)
{
    (void)state;
    collision_t fast = collide(0, 0, 0.5, 4e-7), slow = collide(0, 0, 0.05, 4e-7);
    double ratio = slow.duration / fast.duration;
    print_message("duration ratio slow/fast %.5f, expected %.5f\n", ratio, pow(10, 0.2));
    assert_true(fabs(ratio / pow(10, 0.2) - 1) < 3e-3);
}

/* Damped: e is the restitution of the dimensionless oscillator for every
 * impact speed, pair or wall.  The same step error bound as above, 1e-3
 * of the speed per contact end, allows 3e-3. */
static void test_damped_restitution_matches_the_hertz_oscillator(void **state)
{
    (void)state;
    double eta = 0.2, e_ode = oscillator_restitution(1, eta);
    for (int wall = 0; wall <= 1; wall++)
        for (int s = 0; s < 2; s++) {
            double v0 = s ? 0.05 : 0.5;
            collision_t c = collide(wall, eta, v0, 4e-7);
            print_message("%s, eta_n %.2f, v0 %.2f m/s: e = %.6f, oscillator %.6f, linear law's formula %.6f\n",
                          wall ? "wall" : "pair", eta, v0, c.e, e_ode, exp(-CD_PI * eta / sqrt(1 - eta * eta)));
            assert_true(fabs(c.e - e_ode) < 3e-3);
            assert_true(c.duration > c.t_hertz); /* damping lengthens the contact */
        }
}

/* A ball resting on the floor under gravity and launched without spin
 * slides with deceleration mu g, |F_t| = mu F_n exactly while it slides,
 * until v = 5/7 v0 at t = 2 v0 / (7 mu g); then it rolls.  The Hertz
 * contact's normal oscillation makes F_n vary about m g; the tolerances
 * are those of the linear law's test (tests/physics/test_coulomb_sliding.c). */
static void test_sliding_ball_is_capped_at_mu_fn_then_rolls(void **state)
{
    (void)state;
    static cd_sim sim;
    cd_config cfg;
    char yaml[1024];
    snprintf(yaml, sizeof yaml,
             "run: {dt: 1.0e-6, steps: 0}\n"
             "physics: {gravity: [0, -9.81, 0]}\n" MATERIAL "particles: [{shape: sphere, diameter: %g, count: 1}]\n"
             "domain: {type: none, walls: [{type: plane, point: [0, 0, 0], normal: [0, 1, 0]}]}\n"
             "init: {speed: 0}\n",
             0.2, d);
    cdt_setup(&sim, &cfg, yaml);
    double g = 9.81, mu = 0.5, r = 0.5 * d, v0 = 0.2; /* [m/s^2], [1], [m], [m/s] */
    double e_star = E / (2 * (1 - nu * nu));
    double overlap = pow(sim.s.mass[0] * g / (4.0 / 3.0 * e_star * sqrt(r)), 2.0 / 3.0); /* static Hertz overlap [m] */
    cdt_place(&sim, 0, cd_v3(0, r - overlap, 0), cd_q_identity(), cd_v3(v0, 0, 0), cd_v3_zero());
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    double t_slide = 2 * v0 / (7 * mu * g);
    cdt_step(&sim, (long long)(0.5 * t_slide / sim.p.dt));
    cd_vec3 f = sim.s.wallc_force[0];
    assert_true(fabs(-f.x / f.y - mu) < 1e-9);
    double v_half = v0 - mu * g * (0.5 * t_slide);
    assert_true(fabs(sim.s.velocity[0].x - v_half) / v_half < 5e-3);
    cdt_step(&sim, (long long)(t_slide / sim.p.dt));
    double v = sim.s.velocity[0].x, w = sim.s.angvel[0].z;
    assert_true(fabs(v - 5.0 / 7.0 * v0) / v0 < 5e-3);
    assert_true(fabs(v + r * w) / v0 < 5e-3);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_undamped_collision_lasts_hertz_time),
        cmocka_unit_test(test_collision_time_scales_with_impact_speed),
        cmocka_unit_test(test_damped_restitution_matches_the_hertz_oscillator),
        cmocka_unit_test(test_same_restitution_as_the_linear_law),
        cmocka_unit_test(test_sliding_ball_is_capped_at_mu_fn_then_rolls),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
