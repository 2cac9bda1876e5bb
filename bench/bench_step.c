/* Throughput of the time step on a settled packing.
 *
 *   capdem-bench [--case spheres|crosses2d|hexapods_a3|hexapods_a9] [--n 10000] [--threads T]
 *                [--settle-steps S] [--relax-steps X] [--gravity G] [--steps M] [--repeat R]
 *                [--backend omp|opencl|omp:2,omp:1,...] [--device cpu|gpu|auto] [--seed K]
 *                [--friction-limit elastic|total] [--save-settled F.h5] [--load-settled F.h5]
 *                [--tile KX,KZ] [--shuffle SEED] [--reorder cells|none]
 *                [--sphere-orientation integrate|fixed]
 *
 * A case (bench_cases.c) is a shape, a size distribution, a dimension and a
 * time step, with the default material (docs/references.md, Contact law).  N particles are deposited from a
 * lattice into a box of square cross-section (columns about 4x as tall as
 * wide), settled for S steps (default: the case's) under a strengthened
 * gravity (50 g, which shortens the fall without changing the contact law),
 * relaxed for X steps under G (default X 0, default G = 490.5 m/s^2: the
 * packing stays as dense as it settled; G = 9.81 unloads it, and a packing
 * settled under 50 g then springs up and loses most of its contacts), then M steps are timed R times
 * and one JSON line is printed per repeat: case, N, backend, device,
 * threads, steps, wall seconds (and the process's CPU seconds over the same
 * segment: less sensitive to other jobs on a shared machine), particle-steps/s, contact-updates/s (active
 * contacts x steps / s), contacts per particle and bytes per particle of the
 * state.  Only the stepping is timed: set-up, settling, sync and output are
 * not.
 *
 * --save-settled F writes the settled (and relaxed) packing to F, a run file
 * (docs/output.md) that `capdem analyze`, `capdem run --resume` and
 * bench/lammps/ read; --load-settled F starts from such a file instead of
 * settling (its config gives the case and N), so that an expensive settle is
 * done once and the timing later.  --repeat 0 with --save-settled only
 * settles.  --tile KX,KZ (with --load-settled) places KX x KZ copies of the
 * loaded packing side by side (bench_tile.c) and relaxes them for
 * --relax-steps before timing: a large packing without a tall settle.
 *
 * --shuffle SEED (with --load-settled) puts the loaded (and tiled)
 * particles in a random order, the memory order of a random placement or a
 * mixed flow, and drops their contact history (bench_tile.c): relax before
 * timing.
 *
 * --reorder overrides the case's neighbor.reorder (src/backend/omp/reorder.c: the
 * memory order of the omp backend; the same bits either way).
 *
 * --sphere-orientation fixed times the steps as physics.sphere_orientation:
 * fixed runs them (spheres keep their orientation, the work of LAMMPS's
 * and LIGGGHTS's nve/sphere; docs/motion.md); the settling integrates
 * every orientation either way.
 *
 * --backend takes a comma-separated list (an entry "omp:1" runs that round
 * with 1 thread, so thread counts are compared on one packing): the packing is settled on the
 * first backend, then each backend in turn starts from a copy of that state
 * (handed over through the host, as a resumed run) and is timed after 20
 * untimed steps (first list build, lazy kernel compilation), so that one
 * invocation compares backends on the same packing. */
#define _POSIX_C_SOURCE 200809L
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <omp.h>
#include "core/sim.h"
#include "../kernels/neighbor_items.h"
#include "io/io_h5.h"
#include "config/config.h"
#include "bench_cases.h"
#include "bench_tile.h"
#include "bench_traffic.h"

static double clock_s(clockid_t which)
{
    struct timespec t;
    clock_gettime(which, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}
static double now(void) { return clock_s(CLOCK_MONOTONIC); }

static size_t state_bytes(const cd_sim *sim)
{
    size_t b = 0;
    for (size_t f = 0; f < cd_n_fields; f++) {
        if (!cd_fields[f].on_device) continue; /* host-only output columns */
        size_t rows =
            cd_fields[f].group == CD_GROUP_PAIR ? sim->s.cap_pairs : cd_state_rows(&sim->s, cd_fields[f].group);
        b += rows * cd_fields[f].elem_size;
    }
    /* the primitives' arm indices and arms (kernels/cols.h) */
    b += (cd_state_arms_all(&sim->s) ? 0 : sim->s.n_prims * sizeof(cd_int)) + sim->s.n_arms * sizeof(cd_arm);
    /* the step's inertia (kernels/cols.h, cd_inertia_of): one value a
     * particle where every particle is isotropic, else three */
    b += sim->s.n_particles * (sim->s.inertia_iso ? sizeof(cd_real) : sizeof(cd_vec3));
    b += (sim->s.n_particles + 1) * sizeof(cd_int) + 2 * sim->nb.cap_rows * sizeof(cd_pair_id);
    /* the wall candidates: CSR starts, rows and their entries (cd_wall_entry:
     * history and outputs); the build before's, which only a build's
     * carry-over reads, are freed after it (neighbors.c, particle_lists) */
    b += (sim->s.n_particles + 1) * sizeof(cd_int) + sim->nb.cap_wall_rows * (sizeof(cd_int) + sizeof(cd_wall_entry));
    /* a mixture: the pair pass's visiting order (a row index a row, with
     * the spare rows) and its counting sort's starts (kernels/neighbor_items.h,
     * pass 11) */
    if (cd_neighbors_pair_visit(sim, NULL)) {
        cd_long rows = (cd_long)sim->s.n_pairs;
        b += (size_t)(cd_nb_room(rows) + cd_nb_room(CD_ROW_KINDS * cd_nb_visit_chunks(rows) + 1)) * sizeof(cd_int);
    }
    return b;
}

static int fail(const char *what, int status)
{
    fprintf(stderr, "capdem-bench: %s\n", what);
    return status;
}

/* Writes the synced state of sim to path as a one-snapshot run file. */
static int save_settled(const char *path, cd_sim *sim, const cd_config *cfg, char *err, size_t len)
{
    cd_output *o = cd_output_create(path, cfg, sim->shapes, sim->n_shapes, NULL, 0, err, len);
    if (!o) return -1;
    int rc = cd_output_snapshot(o, &sim->s);
    if (rc) snprintf(err, len, "%s: %s", path, cd_output_error(o));
    return cd_output_close(o) || rc ? -1 : 0;
}

int main(int argc, char **argv)
{
    const char *case_name = "hexapods_a3", *friction_limit = "elastic";
    const char *save_path = NULL, *load_path = NULL, *reorder = NULL, *sphere_orientation = "integrate";
    int tile_x = 1, tile_z = 1;
    long shuffle = -1;
    long n = 10000, settle = -1, relax = 0, steps = 500, repeat = 3;
    unsigned seed = 5;
    double gravity = 490.5; /* [m/s^2] after settling: the settling load */
    int threads = omp_get_max_threads();
    const char *backends = "omp", *device = "auto";
    char perr[512];
    long long v;
    /* every number strictly (cd_parse_cli_int/real: whole argument, in range), exit 2 otherwise */
#define INT_OPT(name, lo, hi, dst)                                                                                     \
    if (!strcmp(argv[i], name)) {                                                                                      \
        if (cd_parse_cli_int(argv[i], argv[i + 1], lo, hi, &v, perr, sizeof perr)) return fail(perr, 2);               \
        dst = v;                                                                                                       \
        continue;                                                                                                      \
    }
#define STRING_OPT(name, dst)                                                                                          \
    if (!strcmp(argv[i], name)) {                                                                                      \
        dst = argv[i + 1];                                                                                             \
        continue;                                                                                                      \
    }
    for (int i = 1; i < argc; i += 2) { /* each option ends its turn with continue */
        if (i + 1 >= argc) {
            fprintf(stderr, "capdem-bench: %s needs a value\n", argv[i]);
            return 2;
        }
        STRING_OPT("--case", case_name)
        INT_OPT("--n", 1, 2147483647LL, n)
        INT_OPT("--threads", 1, 4096, threads)
        INT_OPT("--settle-steps", 0, LLONG_MAX, settle)
        INT_OPT("--relax-steps", 0, LLONG_MAX, relax)
        INT_OPT("--steps", 1, LLONG_MAX, steps)
        INT_OPT("--repeat", 0, LLONG_MAX, repeat)
        INT_OPT("--seed", 0, 4294967295LL, seed)
        INT_OPT("--shuffle", 0, 4294967295LL, shuffle)
        STRING_OPT("--backend", backends)
        STRING_OPT("--device", device)
        STRING_OPT("--friction-limit", friction_limit)
        STRING_OPT("--sphere-orientation", sphere_orientation)
        STRING_OPT("--save-settled", save_path)
        STRING_OPT("--load-settled", load_path)
        if (!strcmp(argv[i], "--gravity")) {
            if (cd_parse_cli_real(argv[i], argv[i + 1], 0, HUGE_VAL, &gravity, perr, sizeof perr)) return fail(perr, 2);
            continue;
        }
        if (!strcmp(argv[i], "--reorder")) {
            reorder = argv[i + 1];
            if (strcmp(reorder, "cells") && strcmp(reorder, "none")) {
                fprintf(stderr, "capdem-bench: --reorder %s: expected cells or none\n", reorder);
                return 2;
            }
            continue;
        }
        if (!strcmp(argv[i], "--tile")) {
            char kx[32], *comma = strchr(argv[i + 1], ',');
            long long tx, tz;
            snprintf(kx, sizeof kx, "%.*s", comma ? (int)(comma - argv[i + 1]) : 0, argv[i + 1]);
            if (!comma || cd_parse_cli_int("--tile KX", kx, 1, 1024, &tx, perr, sizeof perr) ||
                cd_parse_cli_int("--tile KZ", comma + 1, 1, 1024, &tz, perr, sizeof perr)) {
                fprintf(stderr,
                        "capdem-bench: --tile %s: expected KX,KZ (copies along x and z, each an integer in "
                        "[1, 1024])%s%s\n",
                        argv[i + 1], comma ? ": " : "", comma ? perr : "");
                return 2;
            }
            tile_x = (int)tx;
            tile_z = (int)tz;
            continue;
        }
        fprintf(stderr, "capdem-bench: unknown option %s\n", argv[i]);
        return 2;
    }
#undef STRING_OPT
#undef INT_OPT
    if (strcmp(sphere_orientation, "integrate") && strcmp(sphere_orientation, "fixed")) {
        fprintf(stderr, "capdem-bench: --sphere-orientation %s: expected integrate or fixed\n", sphere_orientation);
        return 2;
    }
    /* the backend list is checked before anything is set up */
    char list[256], *save = NULL, *names[8];
    int n_backends = 0;
    snprintf(list, sizeof list, "%s", backends);
    int round_threads[8];
    for (char *b = strtok_r(list, ",", &save); b && n_backends < 8; b = strtok_r(NULL, ",", &save)) {
        /* "omp:1" runs that round with 1 thread: thread counts compared on
         * one packing in one invocation */
        char *colon = strchr(b, ':');
        round_threads[n_backends] = threads;
        if (colon) {
            if (cd_parse_cli_int("--backend NAME:THREADS", colon + 1, 1, 4096, &v, perr, sizeof perr))
                return fail(perr, 2);
            round_threads[n_backends] = (int)v;
            *colon = 0;
        }
        names[n_backends++] = b;
    }
    if (n_backends == 0) {
        fprintf(stderr, "capdem-bench: --backend: expected omp, opencl or a list of them\n");
        return 2;
    }
    if (shuffle >= 0 && !load_path) return fail("--shuffle: needs --load-settled", 2);
    omp_set_num_threads(threads);
    char yaml[2048], err[2048];
    cd_config cfg;
    static cd_sim sim;
    if (load_path) {
        /* the case and N come from the config echoed in the file */
        char *text = cd_h5_read_config_text(load_path, err, sizeof err);
        if (!text) return fail(err, 2);
        int rc = cd_config_parse(text, load_path, &cfg, err, sizeof err);
        free(text);
        if (rc || cd_sim_setup(&sim, &cfg, err, sizeof err) ||
            cd_h5_read_snapshot(load_path, -1, &sim.s, err, sizeof err))
            return fail(err, 2);
        if (tile_x * tile_z > 1) {
            static cd_sim big;
            static char tiled[4096];
            cd_config big_cfg;
            double w = sim.cfg.box_width, t = sim.cfg.box_thickness;
            if (cd_bench_tile_config(cfg.source_text, tile_x, tile_z, tiled, sizeof tiled))
                return fail("--tile: the loaded file is not a capdem-bench case", 2);
            if (cd_config_parse(tiled, load_path, &big_cfg, err, sizeof err) ||
                cd_sim_setup(&big, &big_cfg, err, sizeof err))
                return fail(err, 2);
            if (cd_bench_tile_state(&big.s, &sim.s, tile_x, tile_z, w, t))
                return fail("--tile: counts do not match, or out of memory", 2);
            cd_sim_free(&sim);
            cd_config_free(&cfg);
            sim = big; /* the tiled simulation replaces the loaded one */
            cfg = big_cfg;
        }
        if (shuffle >= 0 && cd_bench_shuffle_state(&sim.s, (unsigned)shuffle))
            return fail("--shuffle: out of memory", 3);
        n = (long)sim.s.n_particles;
        const char *tag = strstr(cfg.source_text, "# case: ");
        if (tag && sscanf(tag + 8, "%63s", yaml) == 1) case_name = yaml;
    } else {
        const cd_bench_case *bc = cd_bench_case_find(case_name);
        if (!bc) {
            fprintf(stderr, "capdem-bench: --case %s: expected one of %s\n", case_name, cd_bench_case_names());
            return 2;
        }
        if (settle < 0) settle = bc->settle_steps;
        int k = snprintf(yaml, sizeof yaml, "# case: %s\n", bc->name);
        if (cd_bench_case_yaml(bc, n, seed, friction_limit, yaml + k, sizeof yaml - (size_t)k) < 0)
            return fail("case config too long", 2);
        if (cd_config_parse(yaml, "bench", &cfg, err, sizeof err) || cd_sim_setup(&sim, &cfg, err, sizeof err))
            return fail(err, 2);
    }
    const char *case_label = case_name;
    if (reorder) sim.nb.reorder = !strcmp(reorder, "cells");
    if (cd_sim_use_backend(&sim, names[0], device, err, sizeof err) ||
        cd_sim_start(&sim, load_path && tile_x * tile_z == 1 && shuffle < 0 ? 0 : 1, err, sizeof err))
        return fail(err, 2);
    double t0 = now();
    if (!load_path && cd_sim_step(&sim, settle, err, sizeof err)) return fail(err, 3);
    double t_settle = now() - t0;
    sim.p.gravity = cd_v3(0, -gravity, 0);
    /* the timed steps' (settling integrates every orientation, as the
     * packings saved before the option were made) */
    sim.p.fixed_spheres = !strcmp(sphere_orientation, "fixed");
    if (relax > 0 && cd_sim_step(&sim, relax, err, sizeof err)) return fail(err, 3);
    if (cd_sim_sync(&sim, err, sizeof err)) return fail(err, 3);
    if (save_path && save_settled(save_path, &sim, &cfg, err, sizeof err)) return fail(err, 1);
    if (repeat == 0) n_backends = 0;
    /* With several backends each starts from a copy of this state. */
    static cd_state settled; /* zeroed: cd_state_copy allocates it */
    if (n_backends > 1 && cd_state_copy(&settled, &sim.s)) {
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
            if (cd_state_copy(&sim.s, &settled)) {
                fprintf(stderr, "capdem-bench: out of memory\n");
                return 3;
            }
            if (cd_sim_use_backend(&sim, names[k], device, err, sizeof err) || cd_sim_start(&sim, 0, err, sizeof err) ||
                cd_sim_step(&sim, 20, err, sizeof err)) {
                fprintf(stderr, "capdem-bench: %s\n", err);
                return 2;
            }
        } else if (load_path && cd_sim_step(&sim, 20, err, sizeof err)) {
            return fail(err, 3); /* warm-up of a loaded packing: first list build */
        }
        /* one more build, now that the contact rows exist: the omp
         * backend's memory order is chosen from them (src/backend/omp/reorder.c), and
         * a loaded packing would otherwise time its first choice */
        sim.nb.force_rebuild = 1;
        if (cd_sim_step(&sim, 1, err, sizeof err)) return fail(err, 3);
        for (long r = 0; r < repeat; r++) {
            cd_observables o; /* summed where the steps run: no sync, which would leave the columns in user order */
            if (cd_sim_observe_step(&sim, &o, err, sizeof err)) {
                fprintf(stderr, "capdem-bench: %s\n", err);
                return 3;
            }
            double contacts = o.n_contacts + o.n_wall_contacts;
            long long builds0 = sim.nb.builds; /* rebuilds of the timed segment alone */
            double t = now(), c = clock_s(CLOCK_PROCESS_CPUTIME_ID);
            if (cd_sim_step(&sim, steps, err, sizeof err)) {
                fprintf(stderr, "capdem-bench: %s\n", err);
                return 3;
            }
            double wall = now() - t, cpu = clock_s(CLOCK_PROCESS_CPUTIME_ID) - c;
            /* (a sync, untimed, for the pair count of the report) */
            if (cd_sim_sync(&sim, err, sizeof err)) {
                fprintf(stderr, "capdem-bench: %s\n", err);
                return 3;
            }
            cd_observables after; /* the counts the traffic model uses */
            cd_sim_observe(&sim, &after);
            cd_traffic tr[CD_TRAFFIC_KERNELS];
            cd_bench_traffic(&sim, (double)steps, tr);
            /* the warps of 32 rows in row order, and in the pair pass's
             * visiting order (a mixture's rows grouped by kind; else the
             * same) */
            double kinds[3], mixed, warps, mixed_visited = 0, warps_visited = 0;
            cd_bench_row_kinds(&sim, NULL, kinds, &mixed, &warps);
            cd_int *visit = malloc((sim.s.n_pairs + 1) * sizeof *visit);
            if (!visit) return fail("out of memory", 3);
            size_t n_visit = cd_neighbors_pair_visit(&sim, visit);
            cd_bench_row_kinds(&sim, n_visit ? visit : NULL, kinds, &mixed_visited, &warps_visited);
            free(visit);
            double moved = 0;
            char kernels[768];
            int at = 0;
            for (int kk = 0; kk < CD_TRAFFIC_KERNELS; kk++) {
                moved += tr[kk].read + tr[kk].write;
                at += snprintf(kernels + at, sizeof kernels - (size_t)at, "%s\"%s\": [%.0f, %.0f]", kk ? ", " : "",
                               tr[kk].kernel, tr[kk].read / (double)n, tr[kk].write / (double)n);
            }
            printf("{\"case\": \"%s\", \"N\": %ld, \"backend\": \"%s\", \"device\": \"%s\", \"threads\": %d, "
                   "\"steps\": %ld, \"wall_s\": %.6g, \"cpu_s\": %.6g, \"particle_steps_per_s\": %.4g, "
                   "\"contact_updates_per_s\": %.4g, "
                   "\"contacts_per_particle\": %.3f, \"pairs_in_list\": %zu, \"bytes_per_particle\": %.0f, "
                   "\"settle_wall_s\": %.2f, \"neighbor_builds\": %lld, \"neighbor_builds_timed\": %lld, \"dt\": %g, "
                   "\"reorder\": \"%s\", \"reorders\": %lld, \"sphere_orientation\": \"%s\", "
                   "\"bytes_moved_per_particle_step\": %.0f, \"kernel_bytes_read_written\": {%s}, "
                   "\"rows\": {\"prims\": %zu, \"arms\": %zu, \"pair_rows\": %zu, \"contacts\": %.0f, "
                   "\"walls\": %zu, \"wall_contacts\": %.0f, \"pair_rows_by_kind\": [%.0f, %.0f, %.0f], "
                   "\"mixed_warps\": [%.0f, %.0f], \"mixed_warps_visited\": [%.0f, %.0f], \"visit_order\": %s, "
                   "\"sweep_span\": %zu, \"sweep_lag\": %zu, \"sweep_prefetch\": %s}}\n",
                   case_label, n, sim.backend->name, sim.backend->device(&sim), round_threads[k], steps, wall, cpu,
                   (double)n * steps / wall, contacts * steps / wall, 2 * o.n_contacts / (double)n, sim.s.n_pairs,
                   (double)state_bytes(&sim) / (double)n, t_settle, sim.nb.builds, sim.nb.builds - builds0, sim.p.dt,
                   sim.nb.reorder && !strcmp(sim.backend->name, "omp") ? "cells" : "none", sim.nb.reorders,
                   sphere_orientation, moved / (double)n, kernels, sim.s.n_prims, sim.s.n_arms, sim.s.n_pairs,
                   after.n_contacts, sim.s.n_walls, after.n_wall_contacts, kinds[0], kinds[1], kinds[2], mixed, warps,
                   mixed_visited, warps_visited, n_visit ? "true" : "false", sim.nb.sweep_span, sim.nb.sweep_lag,
                   sim.nb.sweep_prefetch ? "true" : "false");
            fflush(stdout);
        }
    }
    if (n_backends > 1) cd_state_free(&settled);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
    return 0;
}
