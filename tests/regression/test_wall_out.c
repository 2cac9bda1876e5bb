/* The outputs of a wall contact (force, torque, overlap, F_n) live per wall
 * candidate of the last neighbour-list build while the steps run, and per
 * primitive and wall on the host after a sync (kernels/fields.def,
 * WALLC_OUT; docs/architecture.md).  Between syncs the wall loads and the
 * observables read them where the step keeps them; after a sync the host
 * reads its expanded rows.  Both must give the same bits, and the
 * expanded rows must hold zeros where a row is not in contact.  And the
 * candidates of a moving curved wall are complete between rebuilds. */
#include "test_util.h"
#include <math.h>

/* Hexapods settling in a cylinder on its floor: contacts with the floor
 * plane and the curved wall, a few rebuilds of the candidate lists. */
static const char *pile_in_cylinder = CDT_PILE_IN_CYLINDER;

/* The wall observables of o (contacts, elastic energy, each wall's force,
 * largest overlap) equal, bit for bit, to those of p. */
static void assert_same_wall_observables(const cd_observables *o, const cd_observables *p)
{
    assert_memory_equal(&o->n_wall_contacts, &p->n_wall_contacts, sizeof o->n_wall_contacts);
    assert_memory_equal(&o->elastic, &p->elastic, sizeof o->elastic);
    assert_memory_equal(o->wall_force, p->wall_force, sizeof o->wall_force);
    assert_memory_equal(&o->max_overlap_ratio, &p->max_overlap_ratio, sizeof o->max_overlap_ratio);
}

static void test_step_and_host_rows_agree(void **state)
{
    (void)state;
    static cd_sim sim;
    cd_config cfg;
    char err[1024];
    cdt_setup(&sim, &cfg, pile_in_cylinder);
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    long long builds0 = sim.nb.builds;
    double checked = 0;
    for (int round = 0; round < 6; round++) {
        /* steps without a sync: loads and observables from the step's lists */
        if (cd_sim_step(&sim, 1000, err, sizeof err)) fail_msg("step: %s", err);
        double load[CD_MAX_WALLS];
        for (int w = 0; w < (int)sim.s.n_walls; w++)
            if (cd_sim_wall_load(&sim, w, &load[w], err, sizeof err)) fail_msg("load: %s", err);
        cd_observables at_step, at_host;
        if (cd_sim_observe_step(&sim, &at_step, err, sizeof err)) fail_msg("observe: %s", err);
        /* the same from the host's rows after a sync */
        if (cd_sim_sync(&sim, err, sizeof err)) fail_msg("sync: %s", err);
        cd_sim_observe(&sim, &at_host);
        assert_same_wall_observables(&at_step, &at_host);
        for (int w = 0; w < (int)sim.s.n_walls; w++) {
            double host = cd_sim_wall_load_host(&sim, w);
            assert_memory_equal(&load[w], &host, sizeof host);
            checked += host;
        }
        /* rows not in contact hold zeros; rows in contact their overlap */
        const cd_state *s = &sim.s;
        for (size_t r = 0; r < s->n_prims * s->n_walls; r++) {
            if (s->wallc_active[r]) {
                assert_true(s->wallc_overlap[r] > 0 && s->wallc_fn[r] >= 0);
                continue;
            }
            cd_vec3 f = s->wallc_force[r], t = s->wallc_torque[r];
            assert_true(f.x == 0 && f.y == 0 && f.z == 0 && t.x == 0 && t.y == 0 && t.z == 0);
            assert_true(s->wallc_overlap[r] == 0 && s->wallc_fn[r] == 0);
        }
        print_message("round %d: %g wall contacts, loads %g N in all\n", round, at_host.n_wall_contacts, checked);
    }
    /* the case has wall contacts and rebuilds, or it checks nothing */
    assert_true(checked > 0);
    assert_true(sim.nb.builds > builds0 + 1);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

/* A cylinder wall moving sideways into the pile (docs/motion.md, wall
 * candidates): its motion alone asks for the rebuilds that keep the
 * candidates complete, so the bits are those of fresh candidates at every
 * step. */
static void test_moving_cylinder_same_bits_with_rebuild_every_step(void **state)
{
    (void)state;
    static cd_sim a, b;
    cd_config ca, cb;
    char err[1024];
    cdt_setup(&a, &ca, pile_in_cylinder);
    cdt_setup(&b, &cb, pile_in_cylinder);
    assert_int_equal(cd_sim_initial_forces(&a), 0);
    assert_int_equal(cd_sim_initial_forces(&b), 0);
    cdt_step(&a, 4000); /* 0.04 s: a pile against the floor and the side */
    cdt_step(&b, 4000);
    for (cd_sim *sim = &a; sim; sim = sim == &a ? &b : NULL) {
        for (size_t w = 0; w < sim->s.n_walls; w++)
            if (sim->s.walls[w].type == CD_WALL_CYLINDER) sim->s.walls[w].velocity = cd_v3(0.1, 0, 0); /* [m/s] */
        sim->backend->stop(sim); /* the host changed the walls: hand them over again */
        if (cd_sim_start(sim, 0, err, sizeof err)) fail_msg("%s", err);
    }
    long long builds0 = a.nb.builds;
    for (int it = 0; it < 20; it++) {
        cdt_step(&a, 100);
        for (int k = 0; k < 100; k++) {
            b.nb.force_rebuild = 1;
            cdt_step(&b, 1);
        }
    }
    int on_cylinder = 0; /* contacts with the moving wall at the end */
    for (size_t r = 0; r < a.s.n_prims * a.s.n_walls; r++)
        on_cylinder += a.s.wallc_active[r] && a.s.walls[r % a.s.n_walls].type == CD_WALL_CYLINDER;
    print_message("%lld rebuilds in 2000 steps (the cylinder moved 2 mm), %d contacts with it\n", a.nb.builds - builds0,
                  on_cylinder);
    assert_true(on_cylinder > 0);
    assert_true(a.nb.builds - builds0 > 2 && a.nb.builds - builds0 < 1000);
    size_t n = a.s.n_particles;
    assert_memory_equal(a.s.position, b.s.position, n * sizeof *a.s.position);
    assert_memory_equal(a.s.velocity, b.s.velocity, n * sizeof *a.s.velocity);
    assert_memory_equal(a.s.angmom, b.s.angmom, n * sizeof *a.s.angmom);
    assert_memory_equal(a.s.wallc_force, b.s.wallc_force, a.s.n_prims * a.s.n_walls * sizeof *a.s.wallc_force);
    cd_sim_free(&a);
    cd_sim_free(&b);
    cd_config_free(&ca);
    cd_config_free(&cb);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_step_and_host_rows_agree),
        cmocka_unit_test(test_moving_cylinder_same_bits_with_rebuild_every_step),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
