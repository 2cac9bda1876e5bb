/* Throughput of the time step on a settled packing.
 *
 *   capdem-bench [--shape hexapod] [--aspect 3] [--n 10000] [--threads T]
 *                [--settle-steps S] [--relax-steps X] [--gravity G] [--steps M] [--repeat R]
 *                [--backend omp|opencl|omp,opencl] [--device cpu|gpu|auto]
 *
 * Deposits N particles from a lattice into a box of square cross-section
 * (10 particle sizes wide per 1000 particles), settles them for S steps
 * under a strengthened gravity (50 g, which shortens the fall without
 * changing the contact law), lets the packing relax for X steps under G
 * (default 9.81 m/s^2, default X 0; G = 490.5 keeps the packing as dense as
 * it settled), then times M steps R times and prints one
 * JSON line per repeat: case, N, backend, threads, steps, wall seconds,
 * particle-steps/s, contact-updates/s (active contacts x steps / s),
 * contacts per particle and bytes per particle of the state.
 *
 * --backend takes a comma-separated list (an entry "omp:1" runs that round
 * with 1 thread, so thread counts are compared on one packing): the packing is settled on the
 * first backend, then each backend in turn starts from a copy of that state
 * (handed over through the host, as a resumed run) and is timed after 20
 * untimed steps (first list build, lazy kernel compilation), so that one
 * invocation compares backends on the same packing. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <omp.h>
#include "sim.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Copies every column and scalar of src into dst, whose columns are
 * allocated (its pair columns grow as needed). */
static int state_copy_into(cd_state *dst, const cd_state *src)
{
    if (cd_state_reserve_pairs(dst, src->n_pairs)) return -1;
    cd_state keep = *dst;
    *dst = *src; /* counts, walls, time, step and any other scalar */
    dst->cap_pairs = keep.cap_pairs;
    for (size_t f = 0; f < cd_n_fields; f++) {
        void **slot = cd_field_ptr(dst, &cd_fields[f]);
        *slot = *cd_field_ptr(&keep, &cd_fields[f]);
        size_t bytes = cd_state_rows(src, cd_fields[f].group) * cd_fields[f].elem_size;
        memcpy(*slot, *cd_field_ptr((cd_state *)src, &cd_fields[f]), bytes);
    }
    return 0;
}

static size_t state_bytes(const cd_sim *sim)
{
    size_t b = 0;
    for (size_t f = 0; f < cd_n_fields; f++) {
        size_t rows = cd_fields[f].group == CD_GROUP_PAIR ? sim->s.cap_pairs : cd_state_rows(&sim->s, cd_fields[f].group);
        b += rows * cd_fields[f].elem_size;
    }
    b += (sim->s.n_particles + 1) * sizeof(cd_int) + sim->nb.gather_cap * sizeof(cd_pair_id);
    return b;
}

int main(int argc, char **argv)
{
    const char *shape = "hexapod";
    double aspect = 3;
    long n = 10000, settle = 15000, relax = 0, steps = 500, repeat = 3;
    double gravity = 9.81; /* [m/s^2] after settling */
    int threads = omp_get_max_threads();
    const char *backends = "omp", *device = "auto";
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--shape")) shape = argv[i + 1];
        else if (!strcmp(argv[i], "--aspect")) aspect = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "--n")) n = atol(argv[i + 1]);
        else if (!strcmp(argv[i], "--threads")) threads = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--settle-steps")) settle = atol(argv[i + 1]);
        else if (!strcmp(argv[i], "--relax-steps")) relax = atol(argv[i + 1]);
        else if (!strcmp(argv[i], "--gravity")) gravity = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "--steps")) steps = atol(argv[i + 1]);
        else if (!strcmp(argv[i], "--repeat")) repeat = atol(argv[i + 1]);
        else if (!strcmp(argv[i], "--backend")) backends = argv[i + 1];
        else if (!strcmp(argv[i], "--device")) device = argv[i + 1];
        else { fprintf(stderr, "capdem-bench: unknown option %s\n", argv[i]); return 2; }
    }
    omp_set_num_threads(threads);
    double d = 0.005, L = aspect * d;                /* arm diameter, tip length [m] */
    double size = (strcmp(shape, "sphere") ? L : d) * 1.2 * 1.1; /* lattice spacing [m] */
    double width = size * ceil(cbrt((double)n / 4.0)); /* columns about 4x as tall as wide */
    /* the lattice keeps clear of the walls: a layer holds (width/size - 1)^2
     * sites, not (width/size)^2 */
    double per_layer = (width / size - 1) * (width / size - 1);
    double height = size * ((double)n / per_layer + 3);
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "run: {dt: 1.0e-5, steps: 0, seed: 5}\n"
             "physics: {gravity: [0, -490.5, 0]}\n"
             "particles: [{shape: %s, aspect: %g, diameter: %g, count: %ld, polydispersity: 0.2}]\n"
             "domain: {type: box, width: %g, thickness: %g, height: %g}\n"
             "init: {placement: lattice, clearance: 1.1, speed: 0.25}\n",
             shape, !strcmp(shape, "sphere") ? 1.0 : aspect, d, n, width, width, height * 1.01);
    cd_config cfg;
    char err[2048];
    static cd_sim sim;
    if (cd_config_parse(yaml, "bench", &cfg, err, sizeof err) || cd_sim_setup(&sim, &cfg, err, sizeof err)) {
        fprintf(stderr, "capdem-bench: %s\n", err);
        return 2;
    }
    char list[256], *save = NULL, *names[8];
    int n_backends = 0;
    snprintf(list, sizeof list, "%s", backends);
    int round_threads[8];
    for (char *b = strtok_r(list, ",", &save); b && n_backends < 8; b = strtok_r(NULL, ",", &save)) {
        /* "omp:1" runs that round with 1 thread: thread counts compared on
         * one packing in one invocation */
        char *colon = strchr(b, ':');
        round_threads[n_backends] = colon ? atoi(colon + 1) : threads;
        if (colon) *colon = 0;
        names[n_backends++] = b;
    }
    if (n_backends == 0) {
        fprintf(stderr, "capdem-bench: --backend: expected omp, opencl or a list of them\n");
        return 2;
    }
    if (cd_sim_use_backend(&sim, names[0], device, err, sizeof err) || cd_sim_start(&sim, 1, err, sizeof err)) {
        fprintf(stderr, "capdem-bench: %s\n", err);
        return 2;
    }
    double t0 = now();
    if (cd_sim_step(&sim, settle, err, sizeof err)) { fprintf(stderr, "capdem-bench: %s\n", err); return 3; }
    double t_settle = now() - t0;
    sim.p.gravity = cd_v3(0, -gravity, 0);
    if (relax > 0 && cd_sim_step(&sim, relax, err, sizeof err)) {
        fprintf(stderr, "capdem-bench: %s\n", err);
        return 3;
    }
    if (cd_sim_sync(&sim, err, sizeof err)) { fprintf(stderr, "capdem-bench: %s\n", err); return 3; }
    /* With several backends each starts from a copy of this state. */
    static cd_state settled;
    if (n_backends > 1 &&
        (cd_state_alloc(&settled, sim.s.n_particles, sim.s.n_prims, sim.s.n_walls, sim.s.n_pairs + 1) ||
         state_copy_into(&settled, &sim.s))) {
        fprintf(stderr, "capdem-bench: out of memory\n");
        return 3;
    }
    for (int k = 0; k < n_backends; k++) {
        omp_set_num_threads(round_threads[k]);
        sim.threads = round_threads[k];
        if (n_backends > 1) {
            /* hand the settled state over through the host, as a resumed run
             * does, and warm up (first list build, lazy kernel compilation) */
            sim.backend->stop(&sim);
            if (state_copy_into(&sim.s, &settled)) { fprintf(stderr, "capdem-bench: out of memory\n"); return 3; }
            if (cd_sim_use_backend(&sim, names[k], device, err, sizeof err) || cd_sim_start(&sim, 0, err, sizeof err) ||
                cd_sim_step(&sim, 20, err, sizeof err)) {
                fprintf(stderr, "capdem-bench: %s\n", err);
                return 2;
            }
        }
        for (long r = 0; r < repeat; r++) {
            cd_observables o;
            if (cd_sim_sync(&sim, err, sizeof err)) { fprintf(stderr, "capdem-bench: %s\n", err); return 3; }
            cd_sim_observe(&sim, &o);
            double contacts = o.n_contacts + o.n_wall_contacts;
            double t = now();
            if (cd_sim_step(&sim, steps, err, sizeof err)) { fprintf(stderr, "capdem-bench: %s\n", err); return 3; }
            double wall = now() - t;
            /* (a sync, untimed, for the pair count of the report) */
            if (cd_sim_sync(&sim, err, sizeof err)) { fprintf(stderr, "capdem-bench: %s\n", err); return 3; }
            printf("{\"case\": \"%s_a%g\", \"N\": %ld, \"backend\": \"%s\", \"device\": \"%s\", \"threads\": %d, "
                   "\"steps\": %ld, \"wall_s\": %.4f, \"particle_steps_per_s\": %.4g, \"contact_updates_per_s\": %.4g, "
                   "\"contacts_per_particle\": %.3f, \"pairs_in_list\": %zu, \"bytes_per_particle\": %.0f, "
                   "\"settle_wall_s\": %.2f, \"neighbor_builds\": %lld}\n",
                   shape, aspect, n, sim.backend->name, strcmp(names[k], "omp") ? sim.backend->device(&sim) : "host",
                   round_threads[k], steps, wall, (double)n * steps / wall, contacts * steps / wall, 2 * o.n_contacts / (double)n,
                   sim.s.n_pairs, (double)state_bytes(&sim) / (double)n, t_settle, sim.nb.builds);
            fflush(stdout);
        }
    }
    if (n_backends > 1) cd_state_free(&settled);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
    return 0;
}
