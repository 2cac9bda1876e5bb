/* Throughput of the time step on a settled packing.
 *
 *   capdem-bench [--shape hexapod] [--aspect 3] [--n 10000] [--threads T]
 *                [--settle-steps S] [--steps M] [--repeat R]
 *                [--backend omp|opencl|omp,opencl] [--device cpu|gpu|auto]
 *
 * Deposits N particles from a lattice into a box of square cross-section
 * (10 particle sizes wide per 1000 particles), settles them for S steps
 * under a strengthened gravity (50 g, which shortens the fall without
 * changing the contact law), then times M steps R times and prints one
 * JSON line per repeat: case, N, backend, threads, steps, wall seconds,
 * particle-steps/s, contact-updates/s (active contacts x steps / s),
 * contacts per particle and bytes per particle of the state.
 *
 * --backend takes a comma-separated list: the packing is settled on the
 * first backend, then each backend in turn continues from the state the
 * previous one left (handed over through the host, as a resumed run) and is
 * timed after 20 untimed steps (first list build, lazy kernel compilation),
 * so that one invocation compares backends on the same packing. */
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
    long n = 10000, settle = 15000, steps = 500, repeat = 3;
    int threads = omp_get_max_threads();
    const char *backends = "omp", *device = "auto";
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--shape")) shape = argv[i + 1];
        else if (!strcmp(argv[i], "--aspect")) aspect = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "--n")) n = atol(argv[i + 1]);
        else if (!strcmp(argv[i], "--threads")) threads = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--settle-steps")) settle = atol(argv[i + 1]);
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
    double height = size * ((double)n / ((width / size) * (width / size)) + 2);
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
    char list[256], *save = NULL;
    snprintf(list, sizeof list, "%s", backends);
    double t_settle = 0;
    int first = 1;
    for (char *b = strtok_r(list, ",", &save); b; b = strtok_r(NULL, ",", &save), first = 0) {
        if (!first) {
            /* hand the state over through the host, as a resumed run does */
            if (cd_sim_sync(&sim, err, sizeof err)) { fprintf(stderr, "capdem-bench: %s\n", err); return 3; }
            sim.backend->stop(&sim);
        }
        if (cd_sim_use_backend(&sim, b, device, err, sizeof err) || cd_sim_start(&sim, first, err, sizeof err)) {
            fprintf(stderr, "capdem-bench: %s\n", err);
            return 2;
        }
        if (first) {
            double t0 = now();
            if (cd_sim_step(&sim, settle, err, sizeof err)) { fprintf(stderr, "capdem-bench: %s\n", err); return 3; }
            t_settle = now() - t0;
            sim.p.gravity = cd_v3(0, -9.81, 0);
        } else if (cd_sim_step(&sim, 20, err, sizeof err)) {
            fprintf(stderr, "capdem-bench: %s\n", err);
            return 3;
        }
        for (long r = 0; r < repeat; r++) {
            cd_observables o;
            if (cd_sim_sync(&sim, err, sizeof err)) { fprintf(stderr, "capdem-bench: %s\n", err); return 3; }
            cd_sim_observe(&sim, &o);
            double contacts = o.n_contacts + o.n_wall_contacts;
            double t = now();
            if (cd_sim_step(&sim, steps, err, sizeof err)) { fprintf(stderr, "capdem-bench: %s\n", err); return 3; }
            double wall = now() - t;
            printf("{\"case\": \"%s_a%g\", \"N\": %ld, \"backend\": \"%s\", \"device\": \"%s\", \"threads\": %d, "
                   "\"steps\": %ld, \"wall_s\": %.4f, \"particle_steps_per_s\": %.4g, \"contact_updates_per_s\": %.4g, "
                   "\"contacts_per_particle\": %.3f, \"pairs_in_list\": %zu, \"bytes_per_particle\": %.0f, "
                   "\"settle_wall_s\": %.2f, \"neighbor_builds\": %lld}\n",
                   shape, aspect, n, sim.backend->name, strcmp(b, "omp") ? sim.backend->device(&sim) : "host", threads,
                   steps, wall,
                   (double)n * steps / wall, contacts * steps / wall, 2 * o.n_contacts / (double)n, sim.s.n_pairs,
                   (double)state_bytes(&sim) / (double)n, t_settle, sim.nb.builds);
            fflush(stdout);
        }
    }
    cd_sim_free(&sim);
    cd_config_free(&cfg);
    return 0;
}
