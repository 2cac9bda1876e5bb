/* Coulomb friction (docs/references.md, Contact law) on a sphere and a floor, against the
 * closed-form motion of a rigid ball. */
#include "test_util.h"
#include <math.h>

static const char *ball_on_floor =
    "run: {dt: 1.0e-6, steps: 0}\n"
    "physics: {gravity: [0, -9.81, 0]}\n"
    "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0.2, friction: 0.5, wall_friction: 0.5}\n"
    "particles: [{shape: sphere, diameter: 0.005, count: 1}]\n"
    "domain: {type: none, walls: [{type: plane, point: [0, 0, 0], normal: [0, 1, 0]}]}\n"
    "init: {speed: 0}\n";

static const double g = 9.81, mu = 0.5, r = 0.0025; /* [m/s^2], [1], [m] */

/* Sphere resting on the floor at its static overlap m g / (kn/2). */
static void rest_on_floor(cd_sim *sim, cd_vec3 v, cd_vec3 w)
{
    double overlap = sim->s.mass[0] * g / (0.5 * sim->cfg.kn);
    cdt_place(sim, 0, cd_v3(0, r - overlap, 0), cd_q_identity(), v, w);
    assert_int_equal(cd_sim_initial_forces(sim), 0);
}

/* A ball launched without spin slides with deceleration mu g and a friction
 * force mu F_n until v = r omega, which happens at v = 5/7 v0 after
 * t = 2 v0 / (7 mu g); it then rolls on at constant speed. */
static void test_sliding_ball_decelerates_at_mu_g_then_rolls(void **state)
{
    (void)state;
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg, ball_on_floor);
    double v0 = 0.2; /* [m/s] */
    rest_on_floor(&sim, cd_v3(v0, 0, 0), cd_v3_zero());
    double t_slide = 2 * v0 / (7 * mu * g);
    /* Half-way through the sliding phase: friction is mu F_n and opposes v. */
    cdt_step(&sim, (long long)(0.5 * t_slide / sim.p.dt));
    cd_vec3 f = sim.s.wallc_force[0];
    double fn = f.y, ft = -f.x;
    /* The normal force oscillates about m g at the contact's damped
     * frequency; the ratio ft/fn is exact while sliding. */
    assert_true(fabs(ft / fn - mu) < 1e-9);
    double v_half = v0 - mu * g * (0.5 * t_slide);
    assert_true(fabs(sim.s.velocity[0].x - v_half) / v_half < 5e-3);
    /* Well after the slip has ended: rolling at 5/7 v0. */
    cdt_step(&sim, (long long)(t_slide / sim.p.dt));
    double v = sim.s.velocity[0].x, w = sim.s.angvel[0].z;
    assert_true(fabs(v - 5.0 / 7.0 * v0) / v0 < 5e-3);
    assert_true(fabs(v + r * w) / v0 < 5e-3); /* rolling: contact point at rest */
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

/* On an incline with tan(theta) < 7/2 mu the tangential spring holds the
 * contact point: the ball rolls without slipping with a = 5/7 g sin(theta).
 * Above that it slides with a = g (sin theta - mu cos theta). */
static double incline_acceleration(double theta)
{
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg, ball_on_floor);
    sim.p.gravity = cd_v3(g * sin(theta), -g * cos(theta), 0);
    double overlap = sim.s.mass[0] * g * cos(theta) / (0.5 * cfg.kn);
    cdt_place(&sim, 0, cd_v3(0, r - overlap, 0), cd_q_identity(), cd_v3_zero(), cd_v3_zero());
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    cdt_step(&sim, 20000); /* let the tangential spring load up */
    double t0 = sim.s.time, v0 = sim.s.velocity[0].x;
    cdt_step(&sim, 50000);
    double a = (sim.s.velocity[0].x - v0) / (sim.s.time - t0);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
    return a;
}

static void test_tangential_spring_holds_below_threshold(void **state)
{
    (void)state;
    double theta = atan(1.0); /* tan = 1 < 7/2 mu = 1.75 */
    double a = incline_acceleration(theta);
    assert_true(fabs(a - 5.0 / 7.0 * g * sin(theta)) / (g * sin(theta)) < 5e-3);
}

static void test_ball_slides_above_threshold(void **state)
{
    (void)state;
    double theta = atan(2.5); /* tan = 2.5 > 7/2 mu */
    double a = incline_acceleration(theta);
    double expect = g * (sin(theta) - mu * cos(theta));
    assert_true(fabs(a - expect) / expect < 5e-3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sliding_ball_decelerates_at_mu_g_then_rolls),
        cmocka_unit_test(test_tangential_spring_holds_below_threshold),
        cmocka_unit_test(test_ball_slides_above_threshold),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
