/* The memory order changes no bit (src/backend/omp/reorder.c, docs/architecture.md
 * "Memory order"): a run with neighbor.reorder: cells (particles, primitives
 * and wall rows kept in the order of their grid cells, re-sorted at
 * rebuilds) and the same run with neighbor.reorder: none have the same
 * particle, pair-row and wall-row columns after every sync (the rows in
 * user order), the same observables summed where the steps run and the
 * same wall loads, while the columns are in memory order.  On OpenCL (no
 * reordering) both runs are the same run and the check is trivial. */
#include "test_util.h"
#include <omp.h>

/* 300 alpha-3 hexapods poured under 50 g into a box (six walls, so the
 * wall rows move in groups of six per primitive): a falling, then
 * settling pile that rebuilds its list often (about 1,000 times in 4,000
 * steps), with some 1,400 pair
 * rows and wall contacts.  Every sum of the observables is then one block
 * (kernels/observe_items.h), summed in user order.  Seconds on two
 * threads. */
static const char *pile = "run: {dt: 8.5e-6, steps: 0, seed: 7}\n"
                          "physics: {gravity: [0, -490.5, 0]}\n"
                          "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 300, polydispersity: 0.2}]\n"
                          "domain: {type: box, width: 0.06, thickness: 0.06, height: 0.3}\n"
                          "init: {placement: random, exclusion: shape, speed: 0.2}\n";

/* The same pile on frictional walls: the wall contacts' tangential springs
 * (history kept per wall candidate, carried over at each rebuild through
 * the reorder's map of old slots) decide the bits. */
static const char *pile_frictional_walls =
    "run: {dt: 8.5e-6, steps: 0, seed: 7}\n"
    "physics: {gravity: [0, -490.5, 0]}\n"
    "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0.2, friction: 0.5, wall_friction: 0.5}\n"
    "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 300, polydispersity: 0.2}]\n"
    "domain: {type: box, width: 0.06, thickness: 0.06, height: 0.3}\n"
    "init: {placement: random, exclusion: shape, speed: 0.2}\n";

/* Spheres and hexapods in one pile: some primitives have an arm and some
 * do not, so each primitive's arm index moves with it at a reorder and at
 * a sync (kernels/cols.h, src/backend/omp/reorder.c), where a pile of one
 * shape moves the arms themselves (hexapods) or has none (spheres). */
static const char *pile_mixed =
    "run: {dt: 8.5e-6, steps: 0, seed: 7}\n"
    "physics: {gravity: [0, -490.5, 0]}\n"
    "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 150, polydispersity: 0.2},\n"
    "            {shape: sphere, diameter: 0.005, count: 300, polydispersity: 0.2}]\n"
    "domain: {type: box, width: 0.06, thickness: 0.06, height: 0.3}\n"
    "init: {placement: random, exclusion: shape, speed: 0.2}\n";

/* Is column f one a pair row keeps while inactive?  (The point, force,
 * overlap and F_n of an inactive row are whatever its memory row last
 * held, in either order: nobody reads them, kernels/step_items.h.) */
static int kept_inactive(const cd_field_info *f)
{
    return !strcmp(f->name, "pair_prim_i") || !strcmp(f->name, "pair_prim_j") || !strcmp(f->name, "pair_active") ||
           !strcmp(f->name, "pair_shear");
}

/* Every column of group g (n rows) of a and b bit for bit (pair rows: the
 * columns an inactive row keeps, and every column of the active rows). */
static void assert_same_group(const cd_state *a, const cd_state *b, enum cd_field_group g, size_t n, long long step)
{
    for (size_t f = 0; f < cd_n_fields; f++) {
        if (cd_fields[f].group != g) continue;
        const char *pa = *(void *const *)((const char *)a + cd_fields[f].offset);
        const char *pb = *(void *const *)((const char *)b + cd_fields[f].offset);
        size_t e = cd_fields[f].elem_size;
        for (size_t r = 0; r < n; r++) {
            if (cd_group_pair_rows(g) && !a->pair_active[r] && !kept_inactive(&cd_fields[f])) continue;
            if (memcmp(pa + r * e, pb + r * e, e))
                fail_msg("step %lld: column %s, row %zu differs between reorder cells and none", step,
                         cd_fields[f].name, r);
        }
    }
}

/* The pair pass's visiting order of sim's last build (sim synced): in a
 * pile of spheres and hexapods (mixed) a permutation of the rows grouped
 * by kind, in memory row order within a kind (kernels/neighbor_items.h, pass 11;
 * the kinds from the host's ends, as capdem-bench counts them); in a pile
 * of one shape none (the direct loop).  Returns the kind boundaries. */
static int check_visit_order(cd_sim *sim, int mixed)
{
    const cd_state *s = &sim->s;
    size_t n = s->n_pairs;
    cd_int *visit = calloc(n + 1, sizeof *visit), *kind = calloc(n + 1, sizeof *kind);
    assert_non_null(visit);
    assert_non_null(kind);
    size_t got = cd_neighbors_pair_visit(sim, visit);
    int boundaries = 0;
    if (!mixed) {
        assert_int_equal(got, 0);
    } else {
        assert_int_equal(got, n);
        for (size_t k = 0; k < n; k++) {
            cd_int i = s->pair_prim_i[k], j = s->pair_prim_j[k];
            kind[k] =
                2 - cd_segseg_is_point(s->prim_a[i], s->prim_b[i]) - cd_segseg_is_point(s->prim_a[j], s->prim_b[j]);
        }
        /* (in row order within a kind where the order was made in the
         * same row order: without a memory order) */
        const char *defect = cdt_visit_order_defect(visit, kind, n, !sim->nb.ordered);
        if (defect) fail_msg("step %lld: visiting order: %s", s->step, defect);
        for (size_t v = 1; v < n; v++) boundaries += kind[visit[v]] != kind[visit[v - 1]];
    }
    free(visit);
    free(kind);
    return boundaries;
}

/* Runs the pile (config text cfg) with reorder setting `reorder` in a and
 * none in b. */
static void check_reorder(int reorder, const char *cfg)
{
    static cd_sim a, b;
    cd_config ca, cb;
    char err[512];
    omp_set_num_threads(2);
    cdt_setup(&a, &ca, cfg);
    cdt_setup(&b, &cb, cfg);
    assert_int_equal(a.nb.reorder, 1); /* the default */
    a.nb.reorder = reorder;
    b.nb.reorder = 0;
    assert_int_equal(cd_sim_initial_forces(&a), 0);
    assert_int_equal(cd_sim_initial_forces(&b), 0);
    double contacts = 0, wall_contacts = 0, springs = 0; /* springs: wall contacts with a loaded spring */
    /* kind boundaries of the visiting orders seen (a mixture) */
    int boundaries = 0;
    for (int k = 0; k < 16; k++) {
        cd_sim *sims[2] = {&a, &b};
        cd_observables o[2];
        double load[2];
        for (int s = 0; s < 2; s++) {
            /* no sync: the sums run over the columns in memory order */
            if (cd_sim_step(sims[s], 250, err, sizeof err)) fail_msg("step: %s", err);
            if (cd_sim_observe_step(sims[s], &o[s], err, sizeof err)) fail_msg("observe: %s", err);
            if (cd_sim_wall_load(sims[s], 0, &load[s], err, sizeof err)) fail_msg("wall load: %s", err);
        }
        if (memcmp(&o[0], &o[1], sizeof o[0]))
            fail_msg("step %lld: observables differ (elastic %.17g vs %.17g J, kinetic %.17g vs %.17g J)", a.s.step,
                     o[0].elastic, o[1].elastic, o[0].kinetic_translational, o[1].kinetic_translational);
        if (memcmp(&load[0], &load[1], sizeof load[0]))
            fail_msg("step %lld: wall load %.17g vs %.17g N", a.s.step, load[0], load[1]);
        /* every third round the host writes a velocity between sync and
         * step, as a protocol does: it must reach the run in both orders */
        for (int s = 0; s < 2; s++) {
            if (cd_sim_sync(sims[s], err, sizeof err)) fail_msg("sync: %s", err);
            if (k % 3 == 2) sims[s]->s.velocity[7] = cd_v3(0, 0.1, 0);
        }
        assert_int_equal(a.s.n_pairs, b.s.n_pairs);
        for (int s = 0; s < 2; s++) boundaries += check_visit_order(sims[s], cfg == pile_mixed);
        assert_same_group(&a.s, &b.s, CD_GROUP_PARTICLE, a.s.n_particles, a.s.step);
        assert_same_group(&a.s, &b.s, CD_GROUP_PRIM, a.s.n_prims, a.s.step);
        assert_same_group(&a.s, &b.s, CD_GROUP_PAIR, a.s.n_pairs, a.s.step);
        assert_same_group(&a.s, &b.s, CD_GROUP_PAIR_OUT, a.s.n_pairs, a.s.step);
        assert_same_group(&a.s, &b.s, CD_GROUP_WALLC, a.s.n_prims * a.s.n_walls, a.s.step);
        contacts += o[0].n_contacts;
        wall_contacts += o[0].n_wall_contacts;
        for (size_t r = 0; r < a.s.n_prims * a.s.n_walls; r++)
            springs += a.s.wallc_active[r] && cd_v3_norm(a.s.wallc_shear[r]) > 0;
    }
    /* the user's order after a sync: each particle owns its primitives in
     * order, and pair rows are sorted by (prim_i, prim_j), i < j */
    for (size_t q = 0, first = 0; q < a.s.n_particles; first += (size_t)a.s.prim_count[q], q++)
        assert_int_equal(a.s.prim_first[q], (cd_int)first);
    for (size_t k = 1; k < a.s.n_pairs; k++)
        assert_true(cd_bp_pair_key(a.s.pair_prim_i[k - 1], a.s.pair_prim_j[k - 1]) <
                    cd_bp_pair_key(a.s.pair_prim_i[k], a.s.pair_prim_j[k]));
    print_message("%s: %lld rebuilds, %lld of them reordered; %zu pair rows, %g contacts and %g wall contacts seen, "
                  "%g with a loaded spring\n",
                  cdt_backend(), a.nb.builds, a.nb.reorders, a.s.n_pairs, contacts, wall_contacts, springs);
    assert_true(contacts > 1000 && wall_contacts > 300);
    if (cfg == pile_frictional_walls) assert_true(springs > 300);
    assert_int_equal(b.nb.reorders, 0);
    if (cfg == pile_mixed) assert_true(a.s.n_arms > 0 && a.s.n_arms < a.s.n_prims);
    /* the mixed pile's rows are of more than one kind most of the time */
    if (cfg == pile_mixed) assert_true(boundaries >= 16);
    /* the particles did move in memory: once for the default (the random
     * placement's order, then the cells', which the pile keeps), at
     * every rebuild that changes the cells' order when forced */
    if (!strcmp(cdt_backend(), "omp")) assert_true(a.nb.reorders >= (reorder == CD_NB_REORDER_ALWAYS ? 50 : 1));
    cd_sim_free(&a);
    cd_sim_free(&b);
    cd_config_free(&ca);
    cd_config_free(&cb);
}

static void test_reorder_changes_no_bit(void **state)
{
    (void)state;
    check_reorder(1, pile);
}

/* The same with a reorder at every rebuild that changes the order (not
 * only where the cells' order shortens the rows' memory distances): many moves,
 * history carried across each. */
static void test_reorder_at_every_rebuild_changes_no_bit(void **state)
{
    (void)state;
    check_reorder(CD_NB_REORDER_ALWAYS, pile);
}

/* The same on frictional walls. */
static void test_reorder_with_frictional_walls_changes_no_bit(void **state)
{
    (void)state;
    check_reorder(CD_NB_REORDER_ALWAYS, pile_frictional_walls);
}

/* The same with spheres among the hexapods (primitives with and without
 * an arm). */
static void test_reorder_of_spheres_and_hexapods_changes_no_bit(void **state)
{
    (void)state;
    check_reorder(CD_NB_REORDER_ALWAYS, pile_mixed);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reorder_changes_no_bit),
        cmocka_unit_test(test_reorder_at_every_rebuild_changes_no_bit),
        cmocka_unit_test(test_reorder_with_frictional_walls_changes_no_bit),
        cmocka_unit_test(test_reorder_of_spheres_and_hexapods_changes_no_bit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
