/* `capdem run`: set up from a config (or resume from a run file), step, and
 * write snapshots and the time series; report progress; stop with a
 * diagnostic when the run blows up. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <sys/stat.h>
#include "core/run.h"
#include "core/sim.h"
#include "core/observables.h"
#include "io/io_h5.h"
#include "io/io_h5_guard.h"
#include "protocols/protocol.h"
#include "rigid.h"
#include "mpm/mpm_run.h"
#include "mpi/mpi_decomp.h"

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct {
    int tty;            /* stderr is a terminal */
    double start, last; /* wall-clock seconds */
    long long step0;    /* step at start */
} progress_t;

static void progress(progress_t *pg, const cd_sim *sim, long long total, int final)
{
    double t = now_seconds();
    double interval = pg->tty ? 0.5 : 10.0; /* [s] between lines */
    if (!final && t - pg->last < interval) return;
    pg->last = t;
    long long done = sim->s.step - pg->step0;
    double rate = done > 0 ? (double)done / (t - pg->start) : 0; /* steps/s */
    double eta = rate > 0 ? (double)(total - sim->s.step) / rate : 0;
    fprintf(stderr, "%sstep %lld/%lld  t = %.6g s  %.3g particle-steps/s  ETA %.0f s%s", pg->tty ? "\r" : "",
            sim->s.step, total, sim->s.time, rate * (double)sim->s.n_particles, eta,
            pg->tty ? (final ? "\n" : "   ") : "\n");
    fflush(stderr);
}

/* A new run: every arm on the inner side of every plane wall, by at least
 * its radius: the placement (cd_sim_setup) fills the domain.type container, and domain.walls may cut
 * through it (or face away from it).  Refused here, naming the particle and
 * the wall, rather than as a huge overlap at the first step.  (Particles
 * cannot overlap each other at set-up: the lattice and random placements
 * keep their bounding spheres apart, init.exclusion: shape tests the arms.)
 * Checked here, not in cd_sim_setup, because programs that place particles
 * themselves after cd_sim_setup (tests) start from other positions. */
static int check_wall_placement(const cd_sim *sim, char *err, size_t errlen)
{
    const cd_config *c = &sim->cfg;
    const cd_state *s = &sim->s;
    size_t first_extra = s->n_walls - (size_t)c->n_extra_walls;
    for (size_t w = 0; w < s->n_walls; w++) {
        const cd_wall *W = &s->walls[w];
        if (W->type != CD_WALL_PLANE) continue;
        size_t crossing = 0, worst_q = 0;
        double worst = 0, worst_r = 0; /* [m] depth beyond the wall, arm radius */
        for (size_t q = 0; q < s->n_particles; q++)
            for (cd_int u = s->prim_first[q]; u < s->prim_first[q] + s->prim_count[q]; u++) {
                cd_vec3 e[2] = {cd_rigid_to_world(s->position[q], s->orientation[q], s->prim_a_body[u]),
                                cd_rigid_to_world(s->position[q], s->orientation[q], s->prim_b_body[u])};
                double r = s->prim_radius[u], depth = 0;
                for (int k = 0; k < 2; k++) {
                    double d = cd_v3_dot(W->normal, cd_v3_sub(e[k], W->point)); /* [m] signed distance */
                    if (r - d > depth) depth = r - d;
                }
                if (depth > 1e-9 * r) {
                    if (depth > worst) worst = depth, worst_q = q, worst_r = r;
                    crossing++;
                    break;
                }
            }
        if (!crossing) continue;
        char wall[96];
        if (w >= first_extra) snprintf(wall, sizeof wall, "domain.walls[%zu]", w - first_extra);
        else snprintf(wall, sizeof wall, "wall %zu of domain.type %s", w, c->domain);
        const cd_vec3 x = s->position[worst_q];
        snprintf(err, errlen,
                 "%s: %s (point [%g, %g, %g] m, normal [%g, %g, %g]) cuts through the start positions: "
                 "%zu particle%s reach%s across it, the deepest particle %zu (particles[%d], centre [%g, %g, %g] m) by "
                 "%g m (%.3g arm diameters) beyond the contact distance; every arm must start on the side the normal "
                 "points to, at least its radius %g m away: move the wall, turn its normal, or shrink the domain",
                 c->source_path, wall, W->point.x, W->point.y, W->point.z, W->normal.x, W->normal.y, W->normal.z,
                 crossing, crossing == 1 ? "" : "s", crossing == 1 ? "es" : "", worst_q, (int)s->shape[worst_q], x.x,
                 x.y, x.z, worst, worst / (2 * worst_r), worst_r);
        return -1;
    }
    return 0;
}

/* After a failed step: whether the state blew up (a non-finite value, or a
 * particle moving more than half the thinnest arm per step), and then what
 * into cause.  A backend's own report of such a state may name a
 * consequence (an overflowing neighbour list) rather than the cause. */
static int blowup_cause(cd_sim *sim, char *cause, size_t len)
{
    char tmp[512];
    cd_sim_sync(sim, tmp, sizeof tmp); /* the device's state, where there is one */
    const cd_state *s = &sim->s;
    if (cd_sim_check_state(sim, cause, len)) return 1;
    double dmin = INFINITY, vmax = 0;
    size_t qmax = 0;
    for (size_t i = 0; i < s->n_prims; i++)
        if (2 * s->prim_radius[i] < dmin) dmin = 2 * s->prim_radius[i];
    for (size_t q = 0; q < s->n_particles; q++) {
        double v = sqrt(s->velocity[q].x * s->velocity[q].x + s->velocity[q].y * s->velocity[q].y +
                        s->velocity[q].z * s->velocity[q].z);
        if (v > vmax) vmax = v, qmax = q;
    }
    if (!(vmax * sim->p.dt > 0.5 * dmin)) return 0;
    snprintf(cause, len,
             "runaway velocity at step %lld (t = %.9g s): particle %zu moves at %.3g m/s, %.3g arm "
             "diameters per step (dt = %g s): the run blew up; reduce run.dt or check the material parameters",
             s->step, s->time, qmax, vmax, vmax * sim->p.dt / dmin, sim->p.dt);
    return 1;
}

/* After a failed write (message printed by the writer): what the file
 * keeps and how to go on. */
static void write_failed(const cd_run_options *opt, const cd_config *cfg, long long last_snap)
{
    if (last_snap < 0)
        fprintf(stderr, "capdem: the run stops before its first snapshot%s\n",
                opt->overwrite ? "; an existing file of that name is left as it was" : "");
    else if (access(cfg->output, F_OK) != 0) fprintf(stderr, "capdem: the run stops\n");
    else
        fprintf(stderr,
                "capdem: the run stops; %s keeps its complete snapshots, the last at step %lld: once the cause "
                "is removed (room made), `capdem run %s --resume %s` continues from there\n",
                cfg->output, last_snap, opt->config_path, cfg->output);
}

/* Under MPI (docs/mpi.md) every rank holds the output and writes the rows
 * of its particles (parallel HDF5; with mpi.output = rank0 rank 0 alone
 * holds it, out is NULL on the others), and every rank learns whether a
 * write failed, so that all stop together. */
static int write_thermo(cd_output *out, const cd_sim *sim, const cd_observables *o, double *row)
{
    if (out) cd_observable_row(sim, o, row);
    return cd_mpi_agree(out ? cd_output_thermo(out, sim->s.step, sim->s.time, row) : 0);
}

static int write_snapshot(cd_output *out, cd_sim *sim)
{
    int rc = out ? cd_mpi_write_snapshot(out, sim) : 0; /* each rank its rows, from its local state */
    if (rc == 1) rc = cd_output_snapshot(out, &sim->s);
    return cd_mpi_agree(rc);
}

/* The state where a snapshot reads it: the backend's copy back, or under
 * MPI with parallel output each rank's local state (no gather). */
static int sync_for_snapshot(cd_sim *sim, char *err, size_t errlen)
{
    int rc = cd_mpi_sync_output(sim, err, errlen);
    return rc == 1 ? cd_sim_sync(sim, err, errlen) : rc;
}

/* Whether paths a and b name the same file (device and inode; the same
 * name when neither exists). */
static int same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    int ea = stat(a, &sa), eb = stat(b, &sb);
    if (ea == 0 && eb == 0) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    return ea != 0 && eb != 0 && !strcmp(a, b);
}

/* --resume: the config given against the one stored in the run file, key
 * by key.  0, or 2 (refused, message printed). */
static int check_resume_config(const cd_run_options *opt, const cd_config *given)
{
    char err[2048], dpath[64];
    char *text = cd_h5_read_latest_config_text(opt->resume_path, dpath, sizeof dpath, err, sizeof err);
    if (!text) {
        fprintf(stderr, "capdem: --resume %s\n", err);
        return 2;
    }
    char where[CD_PATH_MAX + 96];
    snprintf(where, sizeof where, "%s:%s", opt->resume_path, dpath);
    cd_config stored;
    int rc = cd_config_parse(text, where, &stored, err, sizeof err);
    free(text);
    if (rc) {
        fprintf(stderr, "capdem: --resume %s: the config stored in the run file is not valid for this capdem: %s\n",
                opt->resume_path, err);
        return 2;
    }
    static char refused[16384], accepted[16384];
    int n = cd_config_resume_diff(&stored, given, opt->allow_change, opt->n_allow_change, refused, sizeof refused,
                                  accepted, sizeof accepted);
    cd_config_free(&stored);
    if (accepted[0] && !opt->quiet)
        fprintf(stderr, "capdem: --resume %s: %s changes keys that may change on a resume or were allowed:\n%s",
                opt->resume_path, opt->config_path, accepted);
    if (n == 0) return 0;
    fprintf(
        stderr,
        "capdem: --resume %s: %s changes %d key%s of the run's own config (%s in the run file) that "
        "set%s the physics or the set-up; a resume continues the same simulation, so this is refused:\n%s"
        "capdem: pass --allow-change KEY for each change that is meant (it applies from the resumed step on; masses, "
        "shapes and counts stay the file's), or start a new run\n",
        opt->resume_path, opt->config_path, n, n == 1 ? "" : "s", dpath, n == 1 ? "s" : "", refused);
    return 2;
}

/* Checks of the command line against the files, before anything is set up
 * or written: 0, or 2 (refused, message printed). */
static int check_files(const cd_run_options *opt, const cd_config *cfg, const cd_config *as_given)
{
    char err[2048], near[128];
    const char *inputs[1] = {opt->config_path};
    for (int i = 0; i < opt->n_allow_change; i++) {
        if (!opt->resume_path) {
            fprintf(stderr, "capdem: --allow-change %s: only a --resume compares configs\n", opt->allow_change[i]);
            return 2;
        }
        if (!cd_config_key_known(opt->allow_change[i], near, sizeof near)) {
            fprintf(stderr, "capdem: --allow-change %s: expected a config key (capdem run --help lists them)%s%s%s\n",
                    opt->allow_change[i], near[0] ? "; did you mean " : "", near, near[0] ? "?" : "");
            return 2;
        }
    }
    if (opt->resume_path) {
        if (opt->output_path && !same_file(opt->output_path, opt->resume_path)) {
            fprintf(stderr,
                    "capdem: --output %s with --resume %s: a resume appends to the file it resumes; copy %s "
                    "to %s first and resume that copy\n",
                    opt->output_path, opt->resume_path, opt->resume_path, opt->output_path);
            return 2;
        }
        if (cd_output_check_target(opt->resume_path, CD_OUTPUT_RESUME, inputs, 1, err, sizeof err)) {
            fprintf(stderr, "capdem: --resume %s\n", err);
            return 2;
        }
        return check_resume_config(opt, as_given);
    }
    if (cd_output_check_target(cfg->output, opt->overwrite ? CD_OUTPUT_REPLACE : CD_OUTPUT_NEW, inputs, 1, err,
                               sizeof err)) {
        fprintf(stderr, "capdem: output %s\n", err);
        return 2;
    }
    return 0;
}

static int run(const cd_run_options *opt);

int cd_run(const cd_run_options *opt)
{
    if (cd_mpi_begin()) {
        fprintf(stderr, "capdem: MPI could not start\n");
        return 1;
    }
    int status = run(opt);
    cdh5_guard_end(); /* (when a refusal returned before the resume's reopen) */
    return cd_mpi_end(status);
}

static int run(const cd_run_options *opt)
{
    char err[2048];
    cd_config cfg;
    cd_h5_no_atexit();
#ifdef SIGXFSZ
    /* a file size limit (ulimit -f) makes write() fail with EFBIG, reported
     * as an I/O error, instead of killing the run */
    signal(SIGXFSZ, SIG_IGN);
#endif
    if (cd_config_load(opt->config_path, &cfg, err, sizeof err)) {
        fprintf(stderr, "capdem: %s\n", err);
        return 2;
    }
    static cd_config as_given; /* the config as read (a shallow copy, not freed): what a resume compares */
    as_given = cfg;
    if (opt->steps >= 0) cfg.steps = opt->steps;
    if (opt->output_path) snprintf(cfg.output, sizeof cfg.output, "%s", opt->output_path);
    if (!cfg.output[0]) snprintf(cfg.output, sizeof cfg.output, "%s.h5", cfg.name);
    if (opt->resume_path) snprintf(cfg.output, sizeof cfg.output, "%s", opt->resume_path);
    /* from here to the reopen for writing a resume only reads its file */
    if (opt->resume_path) cdh5_guard_begin("run --resume", opt->resume_path);
    /* (under MPI rank 0 looks, before any rank writes) */
    if (cd_mpi_agree(cd_mpi_is_writer() ? check_files(opt, &cfg, &as_given) : 0)) {
        cd_config_free(&cfg);
        return 2;
    }
    if (cfg.solver == 1 && cd_mpi_decomposed()) {
        fprintf(stderr, "capdem: %s: solver = mpm runs on one MPI rank only (docs/mpi.md)\n", cfg.source_path);
        cd_config_free(&cfg);
        return 2;
    }
    if (cfg.solver == 1) { /* the material point method (docs/mpm.md) */
        int rc = cd_mpm_run(opt, &cfg);
        cd_config_free(&cfg);
        return rc;
    }

    static cd_sim sim;
    /* (under MPI a new run's ranks build their own particles only, and a
     * resume's none: each reads its own, src/mpi/mpi_setup.c) */
    if (cd_sim_setup_part(&sim, &cfg, opt->resume_path ? cd_mpi_setup_keep_none : cd_mpi_setup_keep, err, sizeof err)) {
        fprintf(stderr, "capdem: %s\n", err);
        cd_config_free(&cfg);
        return 2;
    }
    if (cd_sim_use_backend(&sim, opt->backend ? opt->backend : "omp", opt->device, err, sizeof err) ||
        cd_mpi_wrap(&sim, opt->backend ? opt->backend : "omp", err, sizeof err)) {
        fprintf(stderr, "capdem: %s\n", err);
        cd_sim_free(&sim);
        cd_config_free(&cfg);
        return 2;
    }
    cd_observable_info info[CD_OBSERVABLE_COUNT]; /* the time series, kernels/observables.def */
    int n_obs = cd_observable_series(&sim, info);
    double row[CD_OBS_ROW_MAX];
    cd_output *out = NULL;
    int status = 0, reopen_refused = 0;
    if (opt->resume_path) {
        /* (several MPI ranks cannot append to a serial writer's file: a
         * refusal of the input, on every rank before any reads) */
        if (cd_output_check_appendable(opt->resume_path, err, sizeof err)) {
            if (err[0]) fprintf(stderr, "capdem: %s\n", err);
            status = 2;
            goto done;
        }
        int part = 1;
        if (cd_h5_check_tails(opt->resume_path, err, sizeof err) ||
            (part = cd_mpi_read_snapshot(&sim, opt->resume_path, err, sizeof err)) < 0 ||
            (part == 1 && cd_h5_read_snapshot(opt->resume_path, -1, &sim.s, err, sizeof err))) {
            fprintf(stderr, "capdem: --resume %s: %s\n", opt->resume_path, err);
            status = 2;
            goto done;
        }
        /* On a resume the step count (--steps or run.steps) is the step to
         * reach, counted from the start of the run, not a number of steps
         * more: one behind the resumed step is refused. */
        if (cfg.steps < sim.s.step) {
            if (opt->steps >= 0)
                fprintf(stderr,
                        "capdem: --steps %lld: the run file %s is at step %lld already; on a resume --steps "
                        "is the step to reach, counted from the start of the run: expected an integer >= %lld\n",
                        cfg.steps, opt->resume_path, sim.s.step, sim.s.step);
            else
                fprintf(stderr,
                        "capdem: %s: run.steps = %lld, but the run file %s is at step %lld already; on a "
                        "resume it is the step to reach, counted from the start of the run: give --steps N with "
                        "N >= %lld\n",
                        opt->config_path, cfg.steps, opt->resume_path, sim.s.step, sim.s.step);
            status = 2;
            goto done;
        }
        if (cd_sim_start(&sim, 0, err, sizeof err)) {
            fprintf(stderr, "capdem: %s\n", err);
            status = 2;
            goto done;
        }
        int refused = cd_protocol_resume(&sim, opt->resume_path, err, sizeof err) != 0;
        if (refused) fprintf(stderr, "capdem: --resume %s\n", err);
        if (cd_mpi_agree(refused)) { /* (under MPI: every rank has read the file before rank 0 reopens it) */
            status = 2;
            goto done;
        }
        cdh5_guard_end();
        out = cd_mpi_opens_output()
                  ? cd_output_reopen(opt->resume_path, sim.s.step, info, n_obs, &reopen_refused, err, sizeof err)
                  : NULL;
        if (out && cd_output_note_resume(out, sim.s.step, &cfg)) { /* (the writer says why) */
            cd_output_close(out);
            out = NULL;
        }
        fprintf(stderr, "capdem: resuming %s at step %lld (t = %.9g s)\n", opt->resume_path, sim.s.step, sim.s.time);
    } else {
        /* (under MPI every rank checks the particles it set up: with
         * domain.walls, all of them, src/mpi/mpi_setup.c; all stop together) */
        int crossing = check_wall_placement(&sim, err, sizeof err) != 0;
        if (crossing) fprintf(stderr, "capdem: %s\n", err);
        if (cd_mpi_agree(crossing)) {
            status = 2;
            goto done;
        }
        if (cd_protocol_begin(&sim, err, sizeof err) || cd_sim_start(&sim, 1, err, sizeof err)) {
            fprintf(stderr, "capdem: %s\n", err);
            status = 2;
            goto done;
        }
        if (cd_mpi_opens_output())
            out = cd_output_create_mode(cfg.output, opt->overwrite ? CD_OUTPUT_REPLACE : CD_OUTPUT_NEW, &cfg,
                                        sim.shapes, sim.n_shapes, info, n_obs, err, sizeof err);
    }
    if (cd_mpi_agree(cd_mpi_opens_output() &&
                     !out)) { /* the writer printed why (cd_output_* report every failure on stderr) */
        /* a resumed file that cannot be appended to as it is (a dataset
         * the writer appends to damaged, other observables) is refused
         * like any bad input, nothing written to it; a failed write is 1 */
        status = cd_mpi_agree(reopen_refused) ? 2 : 1;
        goto done;
    }
    fprintf(stderr,
            "capdem: %zu particles, %zu primitives, %zu walls, dt = %g s (t_col/%.1f), backend %s on %s, output %s\n",
            sim.s.n_particles, sim.s.n_prims, sim.s.n_walls, sim.p.dt, sim.collision_time / sim.p.dt, sim.backend->name,
            sim.backend->device(&sim), cfg.output);
    if (cfg.fill_ratio > 0)
        fprintf(stderr, "capdem: protocol.fill_ratio %g at protocol.fill_fraction %g: %ld particles\n", cfg.fill_ratio,
                cfg.fill_fraction, sim.cfg.species[0].count);
    if ((cfg.domain_kind == CD_DOMAIN_BOX && cfg.box_height == 0) ||
        (cfg.domain_kind == CD_DOMAIN_CYLINDER && cfg.cyl_height == 0))
        fprintf(stderr, "capdem: domain.height %g m (the lowest that holds the init lattice)\n",
                cfg.domain_kind == CD_DOMAIN_BOX ? sim.cfg.box_height : sim.cfg.cyl_height);

    cd_observables o;
    long long last_snap = opt->resume_path ? sim.s.step : -1; /* step of the last snapshot committed */
    if (!opt->resume_path) {
        /* (under MPI the observables are reductions: no state gathered) */
        if (sync_for_snapshot(&sim, err, sizeof err) ||
            (cd_mpi_decomposed() && cd_sim_observe_step(&sim, &o, err, sizeof err))) {
            fprintf(stderr, "capdem: %s\n", err);
            status = 1;
            goto done;
        }
        if (!cd_mpi_decomposed()) cd_sim_observe(&sim, &o);
        if (write_thermo(out, &sim, &o, row) || write_snapshot(out, &sim)) {
            write_failed(opt, &cfg, -1);
            status = 1;
            goto done;
        }
        last_snap = sim.s.step;
    }
    progress_t pg = {isatty(STDERR_FILENO), now_seconds(), 0, sim.s.step};
    pg.last = pg.start;
    const long long batch_max = 200; /* steps between progress checks */
    int protocol_done = 0;
    while (sim.s.step < cfg.steps && !protocol_done) {
        long long to_thermo = cfg.thermo_every - sim.s.step % cfg.thermo_every;
        long long to_snap = cfg.snapshot_every - sim.s.step % cfg.snapshot_every;
        long long n = to_thermo < to_snap ? to_thermo : to_snap;
        if (n > cfg.steps - sim.s.step) n = cfg.steps - sim.s.step;
        if (n > batch_max) n = batch_max;
        long long to_control = cd_protocol_steps_until_control(&sim);
        if (n > to_control) n = to_control;
        if (cd_sim_step(&sim, n, err, sizeof err)) {
            /* a blown-up state is named as such, whatever the backend tripped over first */
            char cause[768];
            fprintf(stderr, "\ncapdem: run stopped: %s\n", blowup_cause(&sim, cause, sizeof cause) ? cause : err);
            fprintf(stderr, "capdem: %s keeps the snapshots written before step %lld\n", cfg.output, sim.s.step);
            status = 3;
            break;
        }
        protocol_done = cd_protocol_control(&sim, opt->quiet ? NULL : stderr, err, sizeof err);
        if (protocol_done < 0) {
            fprintf(stderr, "\ncapdem: protocol: %s\n", err);
            status = 1;
            break;
        }
        int thermo_due = sim.s.step % cfg.thermo_every == 0;
        int snap_due = sim.s.step % cfg.snapshot_every == 0 || sim.snapshot_request;
        sim.snapshot_request = 0;
        int last = sim.s.step == cfg.steps || protocol_done;
        if (thermo_due || snap_due || last) {
            /* A thermo line alone sums the observables where the steps run
             * (no state copy on an offload device); a snapshot brings the
             * state back first.  The same bits either way. */
            if ((snap_due || last) && sync_for_snapshot(&sim, err, sizeof err)) {
                fprintf(stderr, "\ncapdem: %s\n", err);
                status = 1;
                break;
            }
            if (cd_sim_observe_step(&sim, &o, err, sizeof err)) {
                fprintf(stderr, "\ncapdem: %s\n", err);
                status = 1;
                break;
            }
            /* Overlaps beyond run.max_overlap (default half the arm
             * diameter) are taken for a numerical failure (dt too large,
             * stiffness too low) or a load the stiffness cannot carry. */
            char cause[768];
            /* (under MPI the observables are reduced without the state: the
             * diagnosis reads the gathered one) */
            if (o.max_overlap_ratio > cfg.max_overlap && cd_mpi_decomposed() && cd_sim_sync(&sim, err, sizeof err)) {
                fprintf(stderr, "\ncapdem: %s\n", err);
                status = 1;
                break;
            }
            if (o.max_overlap_ratio > cfg.max_overlap && blowup_cause(&sim, cause, sizeof cause)) {
                /* the overlap is a symptom: name the blow-up */
                fprintf(stderr, "\ncapdem: run stopped: %s\n", cause);
                fprintf(stderr, "capdem: %s keeps the snapshots written before step %lld\n", cfg.output, sim.s.step);
                status = 3;
                break;
            }
            if (o.max_overlap_ratio > cfg.max_overlap) {
                fprintf(stderr,
                        "\ncapdem: run stopped at step %lld (t = %.9g s): an overlap reached %.3g of the arm diameter "
                        "(limit run.max_overlap = %.2g); the time step %g s, the stiffness or the load is unsuitable. "
                        "%s keeps the snapshots written so far\n",
                        sim.s.step, sim.s.time, o.max_overlap_ratio, cfg.max_overlap, sim.p.dt, cfg.output);
                status = 3;
                break;
            }
            if (write_thermo(out, &sim, &o, row)) {
                write_failed(opt, &cfg, last_snap);
                status = 1;
                break;
            }
        }
        if (snap_due || last) {
            if (write_snapshot(out, &sim)) {
                write_failed(opt, &cfg, last_snap);
                status = 1;
                break;
            }
            last_snap = sim.s.step;
        }
        if (!opt->quiet) progress(&pg, &sim, cfg.steps, 0);
    }
    if (!opt->quiet && status == 0) progress(&pg, &sim, cfg.steps, 1);
    if (status == 0 && cfg.protocol_kind != CD_PROTOCOL_NONE && !protocol_done)
        fprintf(stderr,
                "capdem: warning: run.steps = %lld reached in protocol phase '%s'; continue with "
                "`capdem run %s --resume %s --steps N`\n",
                cfg.steps, cd_protocol_phase_name((int)sim.s.control[0]), opt->config_path, cfg.output);
done:
    if (out && cd_output_close(out)) status = status ? status : 1;
    cd_sim_free(&sim);
    cd_config_free(&cfg);
    return status;
}
