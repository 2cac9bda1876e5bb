/* Same backend, same input, same bits (docs/architecture.md, "Determinism and resume"): for two
 * runs, for 1 and 2 threads, across a forced neighbour rebuild, and for a
 * run checkpointed and resumed. */
#include "test_util.h"
#include <unistd.h>
#include <omp.h>
#include "core/run.h"
#include "io/io_h5.h"
#include <hdf5.h>
#include <math.h>

static const char *settling =
    "run: {name: det, dt: 1.0e-5, steps: 3000, seed: 11, snapshot_every: 1000, thermo_every: 100}\n"
    "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 60, polydispersity: 0.2}]\n"
    "domain: {type: cylinder, diameter: 0.1, height: 0.3}\n"
    "init: {placement: lattice, clearance: 1.0, speed: 1.0}\n";

/* Runs the settling case for n steps with the given thread count; returns
 * the number of contacts seen every 100 steps (to show there were some). */
static double run_case(int threads, long long n, cd_sim *sim, cd_config *cfg)
{
    omp_set_num_threads(threads);
    cdt_setup(sim, cfg, settling);
    assert_int_equal(cd_sim_initial_forces(sim), 0);
    double seen = 0;
    for (long long k = 0; k < n; k += 100) {
        cdt_step(sim, 100);
        cd_observables o;
        cd_sim_observe(sim, &o);
        seen += o.n_contacts;
    }
    return seen;
}

static void assert_same_particles(const cd_state *a, const cd_state *b)
{
    assert_int_equal(a->n_particles, b->n_particles);
    for (size_t f = 0; f < cd_n_fields; f++) {
        if (cd_fields[f].group != CD_GROUP_PARTICLE) continue;
        const void *pa = *(void *const *)((const char *)a + cd_fields[f].offset);
        const void *pb = *(void *const *)((const char *)b + cd_fields[f].offset);
        if (memcmp(pa, pb, a->n_particles * cd_fields[f].elem_size)) fail_msg("column %s differs", cd_fields[f].name);
    }
}

/* Frees the n runs of sims[] and their configs. */
static void free_runs(cd_sim *sims[], cd_config *cfgs[], int n)
{
    for (int k = 0; k < n; k++) {
        cd_sim_free(sims[k]);
        cd_config_free(cfgs[k]);
    }
}

static void test_same_bits_for_one_and_two_threads_and_twice(void **state)
{
    (void)state;
    static cd_sim a, b, c;
    cd_config ca, cb, cc;
    double contacts = run_case(1, 3000, &a, &ca);
    run_case(2, 3000, &b, &cb);
    run_case(2, 3000, &c, &cc);
    assert_true(contacts > 10); /* the particles did collide */
    assert_same_particles(&a.s, &b.s);
    assert_same_particles(&b.s, &c.s);
    free_runs((cd_sim *[]){&a, &b, &c}, (cd_config *[]){&ca, &cb, &cc}, 3);
}

/* The host threads' sweep marks the particles its ranges share (their
 * edges) for the thread count of the step's region, and marks them again
 * when that count changes between calls (src/backend/omp/step_omp.c, "The
 * sweep"): short calls of 2, 3, 1, 4 and 2 threads in turn have the bits
 * of one thread throughout. */
static void test_same_bits_when_the_thread_count_changes(void **state)
{
    (void)state;
    static cd_sim a, b;
    cd_config ca, cb;
    run_case(1, 2500, &a, &ca);
    omp_set_num_threads(2);
    cdt_setup(&b, &cb, settling);
    assert_int_equal(cd_sim_initial_forces(&b), 0);
    /* calls of 1 to 7 steps without a sync between them (a sync may
     * rebuild at the next call), most of them without a rebuild */
    const int threads[] = {2, 3, 1, 4, 2};
    char err[256];
    long long steps = 0, calls = 0, builds = b.nb.builds, without = 0;
    while (steps < 2500) {
        long long n = 1 + calls % 7 < 2500 - steps ? 1 + calls % 7 : 2500 - steps, before = b.nb.builds;
        omp_set_num_threads(threads[calls % 5]);
        if (cd_sim_step(&b, n, err, sizeof err)) fail_msg("step: %s", err);
        without += b.nb.builds == before;
        steps += n;
        calls++;
    }
    cdt_step(&b, 0);
    assert_true(b.nb.builds - builds >= 5 && without > calls / 2);
    assert_same_particles(&a.s, &b.s);
    free_runs((cd_sim *[]){&a, &b}, (cd_config *[]){&ca, &cb}, 2);
}

/* The sweep's interleaved rows and moves (every particle moved a span
 * after its block) give the bits of the loops over all rows that run
 * where the state fits the cache (src/backend/omp/sweep.c), at one and at
 * two threads. */
static void test_interleaved_sweep_equals_loops(void **state)
{
    (void)state;
    static cd_sim a, b, c;
    cd_config ca, cb, cc;
    long keep = cd_sweep_min_bytes;
    cd_sweep_min_bytes = -1; /* 60 hexapods, far below 16 MiB: the loops */
    run_case(1, 2500, &a, &ca);
    cd_sweep_min_bytes = 0; /* interleaved, in blocks of cd_sweep_block */
    run_case(1, 2500, &b, &cb);
    if (b.nb.sweep_span > 0) { /* host threads (OpenCL and offload devices do not sweep) */
        assert_true(a.nb.sweep_lag == a.s.n_particles);
        assert_true(b.nb.sweep_lag == b.nb.sweep_span && b.nb.sweep_lag < b.s.n_particles);
    }
    run_case(2, 2500, &c, &cc);
    cd_sweep_min_bytes = keep;
    assert_same_particles(&a.s, &b.s);
    assert_same_particles(&a.s, &c.s);
    free_runs((cd_sim *[]){&a, &b, &c}, (cd_config *[]){&ca, &cb, &cc}, 3);
}

/* The observables summed where the steps run (cd_sim_observe_step: on the
 * offload or OpenCL device, without a state copy) have the bits of those
 * summed on the host after a sync (cd_sim_observe): the same blocks in the
 * same order (kernels/observe_items.h).  Checked along a settling run,
 * with contacts and wall contacts. */
static void test_device_observables_equal_host_ones(void **state)
{
    (void)state;
    static cd_sim sim;
    cd_config cfg;
    char err[512];
    /* 70 hexapods dropped under 50 g into the bottom of a ball: a pile of
     * about 200 contacts and 68 wall contacts within 4000 steps */
    cdt_setup(&sim, &cfg,
              "run: {dt: 8.5e-6, steps: 0, seed: 3}\n"
              "physics: {gravity: [0, -490.5, 0]}\n"
              "particles: [{shape: hexapod, aspect: 2, diameter: 0.005, count: 70}]\n"
              "domain: {type: ball, radius: 0.03}\n"
              "init: {placement: random, exclusion: shape, speed: 0.1}\n");
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    double contacts = 0, wall_contacts = 0;
    for (int k = 0; k < 6; k++) {
        if (cd_sim_step(&sim, 1000, err, sizeof err)) fail_msg("step: %s", err);
        cd_observables dev, host;
        memset(&dev, 0x5a, sizeof dev);
        if (cd_sim_observe_step(&sim, &dev, err, sizeof err)) fail_msg("observe: %s", err);
        if (cd_sim_sync(&sim, err, sizeof err)) fail_msg("sync: %s", err);
        cd_sim_observe(&sim, &host);
        if (memcmp(&dev, &host, sizeof dev))
            fail_msg("step %lld: observables on the device differ from the host's (elastic %.17g vs %.17g J, "
                     "kinetic %.17g vs %.17g J, contacts %g vs %g)",
                     sim.s.step, dev.elastic, host.elastic, dev.kinetic_translational, host.kinetic_translational,
                     dev.n_contacts, host.n_contacts);
        contacts += host.n_contacts;
        wall_contacts += host.n_wall_contacts;
    }
    print_message("%s: %g contacts and %g wall contacts summed bit for bit\n", cdt_backend(), contacts, wall_contacts);
    assert_true(contacts > 500 && wall_contacts > 200);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

/* A candidate row longer than its slot sends the omp build through its
 * second pass (rows written in place, then the slots double): the list,
 * and so the trajectory, are those of slots that never overflow.  (OpenCL
 * has its own slots: test_parity's slot-overflow case.) */
static void test_slot_overflow_changes_nothing(void **state)
{
    (void)state;
    if (strcmp(cdt_backend(), "omp")) skip();
    static cd_sim a, b;
    cd_config ca, cb;
    cdt_setup(&a, &ca, settling);
    cdt_setup(&b, &cb, settling);
    b.nb.slot = 1; /* every row of more than one candidate overflows */
    assert_int_equal(cd_sim_initial_forces(&a), 0);
    assert_int_equal(cd_sim_initial_forces(&b), 0);
    cdt_step(&a, 3000);
    cdt_step(&b, 3000);
    print_message("slots grew from 1 to %d; %zu pair rows\n", (int)b.nb.slot, b.s.n_pairs);
    assert_true(b.nb.slot > 1 && b.s.n_pairs > 0);
    assert_same_particles(&a.s, &b.s);
    free_runs((cd_sim *[]){&a, &b}, (cd_config *[]){&ca, &cb}, 2);
}

/* Rebuilding the Verlet list every step instead of when the skin is used up
 * changes nothing: the history is carried by key and the forces are
 * gathered in key order. */
static void test_history_survives_forced_rebuilds(void **state)
{
    (void)state;
    static cd_sim a, b;
    cd_config ca, cb;
    omp_set_num_threads(2);
    cdt_setup(&a, &ca, settling);
    cdt_setup(&b, &cb, settling);
    assert_int_equal(cd_sim_initial_forces(&a), 0);
    assert_int_equal(cd_sim_initial_forces(&b), 0);
    cdt_step(&a, 2000);
    cdt_step(&b, 2000);
    /* step on until some contact has a loaded tangential spring */
    long k = -1;
    for (int tries = 0; tries < 1000 && k < 0; tries++) {
        for (size_t r = 0; r < b.s.n_pairs && k < 0; r++)
            if (b.s.pair_active[r] && cd_v3_norm(b.s.pair_shear[r]) > 0) k = (long)r;
        if (k < 0) {
            cdt_step(&a, 1);
            cdt_step(&b, 1);
        }
    }
    assert_true(k >= 0);
    cd_prim_id pi = b.s.pair_prim_i[k], pj = b.s.pair_prim_j[k];
    cd_vec3 shear = b.s.pair_shear[k];
    /* cd_neighbors_build is the omp backend's list (built on the host or
     * the offload device); OpenCL builds its own on its device, and the
     * forced rebuilds below exercise its carry-over. */
    if (!strcmp(cdt_backend(), "omp")) {
        b.nb.force_rebuild = 1;
        assert_int_equal(cd_neighbors_build(&b), 0);
        char err[256]; /* the list is built where the steps run: bring it to the host */
        assert_int_equal(cd_sim_sync(&b, err, sizeof err), 0);
        long found = -1;
        for (size_t r = 0; r < b.s.n_pairs; r++)
            if (b.s.pair_prim_i[r] == pi && b.s.pair_prim_j[r] == pj) found = (long)r;
        assert_true(found >= 0);
        assert_memory_equal(&b.s.pair_shear[found], &shear, sizeof shear);
    }
    long long before = b.nb.builds;
    for (int it = 0; it < 500; it++) {
        b.nb.force_rebuild = 1;
        cdt_step(&b, 1);
    }
    cdt_step(&a, 500);
    assert_true(b.nb.builds >= before + 500);
    assert_same_particles(&a.s, &b.s);
    free_runs((cd_sim *[]){&a, &b}, (cd_config *[]){&ca, &cb}, 2);
}

/* Writes the settling case to cfgpath, runs it to the end into full and
 * to `part_steps` steps into part (new files, or rerun into them). */
static void run_full_and_part(const char *cfgpath, const char *full, const char *part, long long part_steps)
{
    FILE *f = fopen(cfgpath, "w");
    assert_non_null(f);
    fputs(settling, f);
    fclose(f);
    cd_run_options o1 = {
        .config_path = cfgpath, .output_path = full, .steps = -1, .quiet = 1, .overwrite = 1, .backend = cdt_backend()};
    assert_int_equal(cd_run(&o1), 0);
    cd_run_options o2 = {.config_path = cfgpath,
                         .output_path = part,
                         .steps = part_steps,
                         .quiet = 1,
                         .overwrite = 1,
                         .backend = cdt_backend()};
    assert_int_equal(cd_run(&o2), 0);
}

/* A run stopped after 1000 steps and resumed from its file to 3000 steps
 * ends with the same bits as a run of 3000 steps in one go. */
static void test_resumed_run_equals_uninterrupted(void **state)
{
    (void)state;
    char cfgpath[] = "det_resume.yaml", full[] = "det_full.h5", part[] = "det_part.h5";
    run_full_and_part(cfgpath, full, part, 1000);
    cd_run_options o3 = {
        .config_path = cfgpath, .resume_path = part, .steps = -1, .quiet = 1, .backend = cdt_backend()};
    assert_int_equal(cd_run(&o3), 0);

    static cd_sim a, b;
    cd_config ca, cb;
    char err[1024];
    cdt_setup(&a, &ca, settling);
    cdt_setup(&b, &cb, settling);
    if (cd_h5_read_snapshot(full, -1, &a.s, err, sizeof err)) fail_msg("%s", err);
    if (cd_h5_read_snapshot(part, -1, &b.s, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(a.s.step, 3000);
    assert_int_equal(b.s.step, 3000);
    assert_same_particles(&a.s, &b.s);
    assert_int_equal(a.s.n_pairs, b.s.n_pairs);
    assert_memory_equal(a.s.pair_shear, b.s.pair_shear, a.s.n_pairs * sizeof(cd_vec3));
    assert_int_equal(cd_h5_snapshot_count(full, err, sizeof err), cd_h5_snapshot_count(part, err, sizeof err));
    cd_sim_free(&a);
    cd_sim_free(&b);
    cd_config_free(&ca);
    cd_config_free(&cb);
    unlink(cfgpath);
    unlink(full);
    unlink(part);
}

/* A run file written before /contacts/pair_force existed (simulated by
 * deleting that column) resumes to the same bits as an uninterrupted run:
 * the reader rebuilds the force on j as F_n n + F_t, reopening adds the
 * column for every stored row, and the resumed steps append to it. */
static void test_resumed_file_without_pair_force_equals_uninterrupted(void **state)
{
    (void)state;
    char cfgpath[] = "det_legacy.yaml", full[] = "det_legacy_full.h5", part[] = "det_legacy_part.h5";
    run_full_and_part(cfgpath, full, part, 2000);
    hid_t file = H5Fopen(part, H5F_ACC_RDWR, H5P_DEFAULT);
    assert_true(file >= 0);
    assert_true(H5Ldelete(file, "/contacts/pair_force", H5P_DEFAULT) >= 0);
    H5Fclose(file);

    static cd_sim a, b;
    cd_config ca, cb;
    char err[1024];
    cdt_setup(&a, &ca, settling);
    cdt_setup(&b, &cb, settling);
    /* Step 2000 read back: the rebuilt force is the stored one up to the
     * rounding of F_t = F_j - F_n n and of F_n n + F_t (a few 1e-16 |F|). */
    if (cd_h5_read_snapshot(full, 2, &a.s, err, sizeof err)) fail_msg("%s", err);
    if (cd_h5_read_snapshot(part, 2, &b.s, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(b.s.step, 2000);
    assert_int_equal(a.s.n_pairs, b.s.n_pairs);
    assert_true(a.s.n_pairs > 0);
    for (size_t k = 0; k < a.s.n_pairs; k++) {
        cd_vec3 d = cd_v3_sub(a.s.pair_force[k], b.s.pair_force[k]);
        assert_true(sqrt(cd_v3_norm2(d)) <= 1e-14 * (sqrt(cd_v3_norm2(a.s.pair_force[k])) + 1e-300));
    }
    cd_run_options o3 = {
        .config_path = cfgpath, .resume_path = part, .steps = -1, .quiet = 1, .backend = cdt_backend()};
    assert_int_equal(cd_run(&o3), 0);
    if (cd_h5_read_snapshot(full, -1, &a.s, err, sizeof err)) fail_msg("%s", err);
    if (cd_h5_read_snapshot(part, -1, &b.s, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(b.s.step, 3000);
    assert_same_particles(&a.s, &b.s);
    assert_int_equal(a.s.n_pairs, b.s.n_pairs);
    assert_memory_equal(a.s.pair_force, b.s.pair_force, a.s.n_pairs * sizeof(cd_vec3));
    cd_sim_free(&a);
    cd_sim_free(&b);
    cd_config_free(&ca);
    cd_config_free(&cb);
    unlink(cfgpath);
    unlink(full);
    unlink(part);
}

/* Wall candidates (docs/motion.md): a wall that moves into the packing is
 * tested only against the primitives listed at the last build, and its own
 * motion triggers the rebuilds.  Pressed by a plane (a piston) brought down
 * to 1 mm above it and closing in at 0.1 m/s, and by the ball around it
 * shrinking at 0.05 m/s, a settled pile gives the same bits
 * as with a rebuild (hence fresh candidates) at every step. */
static const char *pile_in_ball =
    "run: {dt: 1.0e-5, steps: 0, seed: 5}\n"
    "physics: {gravity: [0, -98.1, 0]}\n"
    "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0.2, friction: 0.5, wall_friction: 0.3}\n"
    "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 40, polydispersity: 0.2}]\n"
    "domain: {type: ball, radius: 0.05, walls: [{type: plane, point: [0, 0.045, 0], normal: [0, -1, 0]}]}\n"
    "init: {placement: lattice, clearance: 1.0, speed: 0.2}\n";

/* Active wall-contact rows of the plane wall (wall 1: the ball is wall 0). */
static double piston_contacts(const cd_sim *sim)
{
    double n = 0;
    for (size_t i = 0; i < sim->s.n_prims; i++) n += sim->s.wallc_active[i * sim->s.n_walls + 1] != 0;
    return n;
}

static void test_moving_walls_same_bits_with_rebuild_every_step(void **state)
{
    (void)state;
    static cd_sim a, b;
    cd_config ca, cb;
    cdt_setup(&a, &ca, pile_in_ball);
    cdt_setup(&b, &cb, pile_in_ball);
    assert_int_equal(cd_sim_initial_forces(&a), 0);
    assert_int_equal(cd_sim_initial_forces(&b), 0);
    cdt_step(&a, 6000); /* 0.06 s under 10 g: a pile at the bottom of the ball */
    cdt_step(&b, 6000);
    assert_int_equal(a.s.n_walls, 2);
    assert_int_equal(a.s.walls[0].type, CD_WALL_SPHERE);
    assert_int_equal(a.s.walls[1].type, CD_WALL_PLANE);
    char err[256];
    double top = -1; /* highest point of the pile [m] */
    for (size_t i = 0; i < a.s.n_prims; i++) {
        double y = fmax(a.s.prim_a[i].y, a.s.prim_b[i].y) + a.s.prim_radius[i];
        if (y > top) top = y;
    }
    for (cd_sim *sim = &a; sim; sim = sim == &a ? &b : NULL) {
        for (size_t w = 0; w < 2; w++) {
            cd_wall *wl = &sim->s.walls[w];
            if (wl->type == CD_WALL_SPHERE) {
                wl->radial_velocity = -0.05; /* [m/s] */
            } else {
                wl->point.y = top + 1e-3;
                wl->velocity = cd_v3(0, -0.1, 0);
            }
        }
        /* the host changed the walls: hand them to the backend again */
        sim->backend->stop(sim);
        if (cd_sim_start(sim, 0, err, sizeof err)) fail_msg("%s", err);
    }
    long long builds0 = a.nb.builds;
    double wall_contacts = 0;
    for (int it = 0; it < 40; it++) {
        cdt_step(&a, 100);
        for (int k = 0; k < 100; k++) {
            b.nb.force_rebuild = 1;
            cdt_step(&b, 1);
        }
        cd_observables o;
        cd_sim_observe(&a, &o);
        wall_contacts += o.n_wall_contacts;
    }
    print_message("%lld rebuilds in 4000 steps (walls moved 4 and 2 mm), %.0f wall contacts seen, %.0f with the piston "
                  "at the end\n",
                  a.nb.builds - builds0, wall_contacts, piston_contacts(&a));
    assert_true(wall_contacts > 100);
    assert_true(piston_contacts(&a) > 0);
    assert_true(a.nb.builds - builds0 > 4); /* the walls' motion alone asks for one every skin/2 */
    assert_true(a.nb.builds - builds0 < 4000);
    assert_same_particles(&a.s, &b.s);
    free_runs((cd_sim *[]){&a, &b}, (cd_config *[]){&ca, &cb}, 2);
}

/* Between syncs the wall contacts' flag and tangential spring live in the
 * step's wall candidates (cd_wall_entry), not in the host's rows: a backend
 * stopped and started again (a resumed run, a state put back) turns the
 * host's rows back into candidates at its first build.  A settled pile on
 * frictional walls (loaded springs) restarted that way keeps the bits of
 * the same pile stepped on without a restart. */
static void test_wall_history_survives_a_restart(void **state)
{
    (void)state;
    static cd_sim a, b;
    cd_config ca, cb;
    char err[256];
    cdt_setup(&a, &ca, pile_in_ball);
    cdt_setup(&b, &cb, pile_in_ball);
    assert_int_equal(cd_sim_initial_forces(&a), 0);
    assert_int_equal(cd_sim_initial_forces(&b), 0);
    cdt_step(&a, 6000);
    cdt_step(&b, 6000);
    if (cd_sim_sync(&b, err, sizeof err)) fail_msg("%s", err);
    double springs = 0; /* wall contacts with a loaded tangential spring */
    for (size_t r = 0; r < b.s.n_prims * b.s.n_walls; r++)
        springs += b.s.wallc_active[r] && cd_v3_norm(b.s.wallc_shear[r]) > 0;
    print_message("%.0f wall contacts with a loaded spring at the restart\n", springs);
    assert_true(springs > 0);
    b.backend->stop(&b);
    if (cd_sim_start(&b, 0, err, sizeof err)) fail_msg("%s", err);
    cdt_step(&a, 2000);
    cdt_step(&b, 2000);
    assert_same_particles(&a.s, &b.s);
    free_runs((cd_sim *[]){&a, &b}, (cd_config *[]){&ca, &cb}, 2);
}

int main(void)
{
    /* Parallelise every loop, however small, so that 2 threads really split
     * the work of this small case. */
    cd_parallel_min_rows = 0;
    /* and interleave the host threads' sweep (src/backend/omp/sweep.c) in
     * blocks of 8 particles whatever the state's size */
    cd_sweep_block = 8;
    cd_sweep_min_bytes = 0;
    /* its rows' loop asking for primitive j's data ahead, whatever the size
     * (a prefetch changes no value; under the sanitizers its reads are checked) */
    cd_sweep_prefetch_min_bytes = 0;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_bits_for_one_and_two_threads_and_twice),
        cmocka_unit_test(test_same_bits_when_the_thread_count_changes),
        cmocka_unit_test(test_interleaved_sweep_equals_loops),
        cmocka_unit_test(test_history_survives_forced_rebuilds),
        cmocka_unit_test(test_slot_overflow_changes_nothing),
        cmocka_unit_test(test_device_observables_equal_host_ones),
        cmocka_unit_test(test_resumed_run_equals_uninterrupted),
        cmocka_unit_test(test_resumed_file_without_pair_force_equals_uninterrupted),
        cmocka_unit_test(test_moving_walls_same_bits_with_rebuild_every_step),
        cmocka_unit_test(test_wall_history_survives_a_restart),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
