/* `capdem run` for solver: mpm (docs/mpm.md): set-up, stepping, snapshots,
 * time series and progress, with the exit codes of the DEM runs (0 done,
 * 2 bad input, 3 the run blew up, 1 other failures). */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include "mpm/mpm_run.h"
#include "mpm/mpm.h"
#include "mpm/mpm_output.h"
#include "io/io_h5_guard.h"

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The diametral set-up's nominal measures: strain (D - gap) / D [1] and
 * stress F / D [Pa] from the mean of the two walls' forces [N/m]. */
static void nominal(const cd_mpm *m, const cd_config *c, double *eps, double *sig)
{
    double gap = m->walls[1].py - m->walls[0].py;
    *eps = (c->mpm_diameter - gap) / c->mpm_diameter;
    *sig = 0.5 * (m->walls[1].fy - m->walls[0].fy) / c->mpm_diameter;
}

static void progress(const cd_mpm *m, const cd_config *c, double t0, long long step0, int tty, int final)
{
    double t = now_seconds(), eps, sig;
    long long done = m->step - step0;
    double rate = done > 0 && t > t0 ? (double)done / (t - t0) : 0; /* steps/s */
    double eta = rate > 0 ? (double)(c->steps - m->step) / rate : 0;
    char what[128];
    if (m->n_walls == 4) {
        double phi, z;
        cd_mpm_packing_measures(m, &phi, &sig, &eps, &z);
        snprintf(what, sizeof what, "phi %.4f  sigma %.4g Pa  eps %.4f  Z %.2f", phi, sig, eps, z);
    } else {
        nominal(m, c, &eps, &sig);
        snprintf(what, sizeof what, "eps_yy %.4f  sigma_yy %.4g Pa", eps, sig);
    }
    fprintf(stderr, "%sstep %lld/%lld  t = %.6g s  %s  %.3g point-steps/s  ETA %.0f s%s", tty ? "\r" : "", m->step,
            c->steps, m->time, what, rate * (double)m->n, eta, tty ? (final ? "\n" : "   ") : "\n");
    fflush(stderr);
}

int cd_mpm_run(const cd_run_options *opt, cd_config *cfg)
{
    char err[1024];
    int opencl = opt->backend && !strcmp(opt->backend, "opencl");
    if (opt->backend && strcmp(opt->backend, "omp") && !opencl) {
        fprintf(stderr, "capdem: --backend %s: expected omp or opencl\n", opt->backend);
        return 2;
    }
    static cd_mpm m;
    if (cd_mpm_setup(&m, cfg, err, sizeof err)) {
        fprintf(stderr, "capdem: %s\n", err);
        return 2;
    }
    if (opencl && cd_mpm_cl_open(&m, opt->device, err, sizeof err)) { /* as the DEM runs: exit 2 */
        fprintf(stderr, "capdem: %s\n", err);
        cd_mpm_free(&m);
        return 2;
    }
    cd_mpm_output *out;
    if (opt->resume_path) { /* as the DEM runs: the last committed snapshot, and run.steps is the step to reach */
        if (cd_mpm_read_snapshot(opt->resume_path, &m, err, sizeof err)) {
            fprintf(stderr, "capdem: --resume %s\n", err);
            cd_mpm_free(&m);
            return 2;
        }
        if (cfg->steps < m.step) {
            fprintf(stderr,
                    "capdem: %s: run.steps (or --steps) = %lld, but the run file %s is at step %lld already; on a "
                    "resume it is the step to reach, counted from the start of the run: expected an integer >= %lld\n",
                    cfg->source_path, cfg->steps, opt->resume_path, m.step, m.step);
            cd_mpm_free(&m);
            return 2;
        }
        cdh5_guard_end(); /* (armed by cd_run while the file is only read) */
        out = cd_mpm_output_reopen(opt->resume_path, cfg, &m, err, sizeof err);
    } else {
        out = cd_mpm_output_create(cfg->output, opt->overwrite, cfg, &m, err, sizeof err);
    }
    if (!out) {
        fprintf(stderr, "capdem: %s\n", err);
        cd_mpm_free(&m);
        return 1;
    }
    if (opt->resume_path)
        fprintf(stderr, "capdem: resuming %s at step %lld (t = %.9g s)\n", opt->resume_path, m.step, m.time);
    fprintf(stderr,
            "capdem: mpm: %zu material points, mesh %d x %d nodes (h = %g m), dt = %g s (stability limit / %.1f), "
            "backend %s on %s, output %s\n",
            m.n, m.nx, m.ny, m.h, m.dt, cd_mpm_dt_limit(&m) / m.dt, opencl ? "opencl" : "omp",
            opencl ? cd_mpm_cl_device(&m) : "host", cfg->output);
    int status = 0;
    /* the walls' forces of step 0 come from the first step's contact pass */
    if (!opt->resume_path && (cd_mpm_output_series(out, &m, cd_mpm_kinetic_energy(&m), err, sizeof err) ||
                              cd_mpm_output_snapshot(out, &m, err, sizeof err))) {
        fprintf(stderr, "capdem: %s\n", err);
        status = 1;
    }
    int tty = isatty(STDERR_FILENO);
    double t0 = now_seconds(), last = t0;
    long long step0 = m.step;
    while (status == 0 && m.step < cfg->steps) {
        /* what the run reads after this step, decided before it: the OpenCL
         * backend computes the output-only sums at these steps only */
        long long next = m.step + 1;
        int last_step = next == cfg->steps;
        double t = now_seconds();
        int show = !opt->quiet && t - last >= (tty ? 0.5 : 10.0);
        int row = next % cfg->thermo_every == 0 || last_step;
        int snap = next % cfg->snapshot_every == 0 || last_step;
        m.observe = row || snap || show;
        int back = 0; /* the OpenCL backend went back to an earlier step (cd_mpm_settle) */
        if (cd_mpm_step(&m, err, sizeof err) || (m.observe && (back = cd_mpm_settle(&m, err, sizeof err)) < 0)) {
            fprintf(stderr, "\ncapdem: run stopped: %s\ncapdem: %s keeps the snapshots written before step %lld\n", err,
                    cfg->output, m.step);
            status = 3;
            break;
        }
        if (back) continue;
        /* the contact count Z, read by the series row and the progress line only */
        if ((row || show) && cd_mpm_contact_count(&m, err, sizeof err)) {
            fprintf(stderr, "\ncapdem: %s\n", err);
            status = 1;
        }
        if (status == 0 && row && cd_mpm_output_series(out, &m, cd_mpm_kinetic_energy(&m), err, sizeof err)) {
            fprintf(stderr, "\ncapdem: %s\n", err);
            status = 1;
        }
        if (status == 0 && snap && cd_mpm_output_snapshot(out, &m, err, sizeof err)) {
            fprintf(stderr, "\ncapdem: %s\n", err);
            status = 1;
        }
        if (show) {
            last = t;
            progress(&m, cfg, t0, step0, tty, 0);
        }
    }
    if (!opt->quiet && status == 0) progress(&m, cfg, t0, step0, tty, 1);
    if (cd_mpm_output_close(out) && status == 0) status = 1;
    cd_mpm_free(&m);
    return status;
}
