/* The particles' force and torque are not held by the step between its
 * calls (kernels/cols.h, cd_cols.force): the first advance of a call sums
 * them again from the pair rows and wall entries, and sync sums them into
 * the host's columns the same way (docs/performance.md, "Session 18, force
 * and torque not held").  The trajectory must be the one a step that holds
 * them makes: that of an MPI rank (cd_sim_keeps_force), chosen here by a
 * rebuild hook that changes nothing.  Every column, bit for bit, after
 * calls of 1, 7 and 3,000 steps with a sync after each (a second sync
 * without a step between too), and across a start without forces (a
 * resume, a protocol's restart: the host's force and torque kick the first
 * advance); in the order of the particles as they are and, on host
 * threads, in the cells' order at every rebuild (the sync's sums go to
 * user order). */
#include "test_util.h"
#include <math.h>

/* Hexapods settling on the floor of a cylinder with friction: pair and
 * wall contacts, tangential history, rebuilds. */
static const char *pile_in_cylinder = CDT_PILE_IN_CYLINDER;

/* Polydisperse spheres dropped into a box: the sphere case's step. */
static const char *spheres_in_box =
    "run: {dt: 5.0e-6, steps: 0, seed: 5}\n"
    "physics: {gravity: [0, -98.1, 0]}\n"
    "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0.2, friction: 0.5, wall_friction: 0.4}\n"
    "particles: [{shape: sphere, diameter: 0.004, count: 60, polydispersity: 0.3}]\n"
    "domain: {type: box, width: 0.03, thickness: 0.03, height: 0.06}\n"
    "init: {placement: lattice, clearance: 1.0, speed: 0.3}\n";

/* A rebuild hook that keeps the step's answer: the step then holds the
 * force and torque between calls, as on an MPI rank. */
static int keep_answer(cd_sim *sim, int rebuild, char *err, size_t errlen)
{
    (void)sim;
    (void)err;
    (void)errlen;
    return rebuild;
}

/* Every column of a and b (the rows in use) equal bit for bit; F_n
 * (pair_fn) where a row is in contact: written by the last step of a call
 * only and never cleared by a build's carry-over, a row that has not been
 * in contact since holds what the column's memory held (no file, load or
 * observable reads it: the run file keeps the rows in contact). */
static void assert_same_columns(cd_sim *a, cd_sim *b, const char *when)
{
    assert_int_equal(a->s.n_pairs, b->s.n_pairs);
    for (size_t f = 0; f < cd_n_fields; f++) {
        size_t e = cd_fields[f].elem_size, rows = cd_state_rows(&a->s, cd_fields[f].group);
        const char *x = *cd_field_ptr(&a->s, &cd_fields[f]), *y = *cd_field_ptr(&b->s, &cd_fields[f]);
        int fn = !strcmp(cd_fields[f].name, "pair_fn");
        for (size_t r = 0; r < rows; r++)
            if ((!fn || a->s.pair_active[r]) && memcmp(x + r * e, y + r * e, e))
                fail_msg("%s: column %s differs (row %zu of %zu)", when, cd_fields[f].name, r, rows);
    }
}

static void sync_or_fail(cd_sim *sim)
{
    char err[1024];
    if (cd_sim_sync(sim, err, sizeof err)) fail_msg("sync: %s", err);
}

static void check_case(const char *yaml)
{
    /* held: the force and torque kept by the step; summed: this program's
     * way; cells: summed, the particles in the cells' order at every
     * rebuild (host threads) */
    static cd_sim held, summed, cells;
    cd_config cfg[3];
    cd_sim *sims[3] = {&held, &summed, &cells};
    char err[1024];
    for (int k = 0; k < 3; k++) {
        memset(sims[k], 0, sizeof *sims[k]);
        cdt_setup(sims[k], &cfg[k], yaml);
        sims[k]->nb.reorder = k == 2 ? CD_NB_REORDER_ALWAYS : 0; /* (an MPI rank's step: no reorder) */
    }
    held.rebuild_hook = keep_answer;
    assert_true(cd_sim_keeps_force(&held) && !cd_sim_keeps_force(&summed));
    for (int k = 0; k < 3; k++) assert_int_equal(cd_sim_initial_forces(sims[k]), 0);
    assert_same_columns(&held, &summed, "start");
    assert_same_columns(&held, &cells, "start (cells)");
    const long long calls[] = {1, 7, 3000, -1, 5, 3000, 1};
    double moved = 0;
    for (size_t c = 0; c < sizeof calls / sizeof calls[0]; c++) {
        char when[64];
        snprintf(when, sizeof when, "call %zu (%lld steps)", c, calls[c]);
        for (int k = 0; k < 3; k++) {
            if (calls[c] < 0) {
                /* a start without forces, as a resumed run's: the host's
                 * force and torque for the first advance */
                sims[k]->backend->stop(sims[k]);
                if (cd_sim_start(sims[k], 0, err, sizeof err)) fail_msg("start: %s", err);
                continue;
            }
            if (cd_sim_step(sims[k], calls[c], err, sizeof err)) fail_msg("step: %s", err);
            sync_or_fail(sims[k]);
            if (c == 1) sync_or_fail(sims[k]); /* a second sync, no step between */
        }
        assert_same_columns(&held, &summed, when);
        assert_same_columns(&held, &cells, when);
        for (size_t q = 0; q < held.s.n_particles; q++) moved += fabs(held.s.torque[q].x) + fabs(held.s.torque[q].z);
    }
    /* the case has forces and torques, or it checks nothing */
    assert_true(moved > 0);
    print_message("%zu particles, %zu pair rows, %lld builds, %lld reorders (cells)\n", held.s.n_particles,
                  held.s.n_pairs, summed.nb.builds, cells.nb.reorders);
    for (int k = 0; k < 3; k++) {
        cd_sim_free(sims[k]);
        cd_config_free(&cfg[k]);
    }
}

static void test_hexapods_in_cylinder(void **state)
{
    (void)state;
    check_case(pile_in_cylinder);
}

static void test_spheres_in_box(void **state)
{
    (void)state;
    check_case(spheres_in_box);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hexapods_in_cylinder),
        cmocka_unit_test(test_spheres_in_box),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
