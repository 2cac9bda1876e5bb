/* `capdem analyze RUN.h5 [options]`: reads one snapshot, runs the measures
 * of docs/references.md, Analysis on it and on the run's time series, writes the results into the
 * run file (/analysis) and prints a summary or one JSON object.  Usage and
 * output keys: docs/analysis.md. */
#include "analysis/analyze.h"
#include "config/config.h"
#include "io/io_h5_guard.h"
#include "mpm/mpm_output.h" /* cd_mpm_is_run_file */
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef int (*measure_fn)(const cd_an_input *, cd_an_report *, char *, size_t);

/* The measures of the run's time series take the run file's path. */
static int compaction(const cd_an_input *in, cd_an_report *rep, char *msg, size_t len)
{
    return cd_an_compaction(in->s->path, in->s, in->g, in->opt, rep, msg, len);
}

static int jamming(const cd_an_input *in, cd_an_report *rep, char *msg, size_t len)
{
    return cd_an_jamming(in->s->path, in->opt, rep, msg, len);
}

/* Every measure, once, in the order they run and report: its --measures
 * name, its bit (analyze.h), whether it needs the snapshot's particle
 * contacts, and the function (docs/architecture.md, "How to add a
 * measure"); mpm, the measure of run files of solver mpm, has its own
 * reader (analyze_file, host/analysis/analyze_mpm.c). */
static const struct {
    const char *name;
    unsigned bit;
    int needs_contacts;
    measure_fn fn;
} measures[] = {
    {"forces", CD_AN_FORCES, 1, cd_an_forces},
    {"bonds", CD_AN_BONDS, 1, cd_an_bond_forces},
    {"stress", CD_AN_STRESS, 1, cd_an_stress},
    {"rdf", CD_AN_RDF, 0, cd_an_rdf},
    {"branch", CD_AN_BRANCH, 1, cd_an_branch},
    {"network", CD_AN_NETWORK, 1, cd_an_network},
    {"packing", CD_AN_PACKING, 0, cd_an_packing},
    {"modulus", CD_AN_MODULUS, 1, cd_an_modulus},
    {"compaction", CD_AN_COMPACTION, 0, compaction},
    {"jamming", CD_AN_JAMMING, 0, jamming},
    {"mpm", CD_AN_MPM, 0, NULL},
};
#define N_MEASURES (sizeof measures / sizeof measures[0])

/* The measures' names, comma-separated, into buf. */
static const char *measure_list(char *buf, size_t len)
{
    size_t at = 0;
    buf[0] = 0;
    for (size_t k = 0; k < N_MEASURES && at < len; k++)
        at += (size_t)snprintf(buf + at, len - at, "%s%s", k ? ", " : "", measures[k].name);
    return buf;
}

void cd_an_options_defaults(cd_an_options *o)
{
    memset(o, 0, sizeof(*o));
    o->snapshot = -1;
    o->measures = CD_AN_ALL;
    o->margin_side = o->margin_end = -1;
    o->mc_points = 1000000;
    o->write = 1;
}

unsigned cd_an_measure_bit(const char *name)
{
    for (size_t k = 0; k < N_MEASURES; k++)
        if (!strcmp(measures[k].name, name)) return measures[k].bit;
    return 0;
}

static void usage(FILE *f)
{
    char names[256];
    fprintf(f,
            "usage: capdem analyze RUN.h5 [--snapshot last|N] [--json] [--measures LIST] [--no-write]\n"
            "                      [--margins SIDE,END] [--rdf-max R] [--rdf-bin DR] [--mc-points M]\n"
            "                      [--phi-series NAME] [--z-series NAME] [--phi-c PHI] [--quiet] [--timings]\n"
            "  --snapshot N     snapshot index (0 first, -1 or last: the last; default last)\n"
            "  --json           print one JSON object on stdout (keys: docs/analysis.md)\n"
            "  --measures LIST  comma-separated subset, each of which must succeed (else exit 2), of\n"
            "                   %s\n"
            "                   (default: all, skipping with a warning what the file cannot give)\n"
            "  --no-write       do not write /analysis into the run file\n"
            "  --margins S,E    core region: S L from side walls, E L from floor and top\n"
            "                   (default 10,10 in 2D and pseudo-2D, 3,10 in 3D, 3 for a ball)\n"
            "  --rdf-max R      G(r) up to R L (default: the smallest margin, at most 5 L)\n"
            "  --rdf-bin DR     G(r) bin width in L (default 0.02)\n"
            "  --mc-points M    Monte Carlo points for the core packing fraction (default 1e6)\n"
            "  --phi-series, --z-series  observables for the jamming fit\n"
            "  --phi-c PHI      mpm run files: Phi_c of the fits of eqs. (5) and (11) (default: eq. (17)'s)\n"
            "  --quiet          no summary and no warnings;  --timings  time of each phase on stderr\n"
            "exit status: 0 done, 2 bad input (missing file or data), 1 other failure\n",
            measure_list(names, sizeof names));
}

static void warn(const cd_an_options *opt, const char *msg)
{
    if (!opt->quiet) fprintf(stderr, "capdem analyze: warning: %s\n", msg);
}

/* Wall-clock seconds (for --timings). */
static double now(void)
{
    struct timespec t;
    timespec_get(&t, TIME_UTC);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Prints the wall-clock and CPU (all threads) time since the last lap. */
static void lap(const cd_an_options *opt, const char *what, double *t0)
{
    static double c0 = 0;
    double t = now(), c = (double)clock() / CLOCKS_PER_SEC;
    if (opt->timings) fprintf(stderr, "capdem analyze: %-12s %8.3f s wall %8.3f s cpu\n", what, t - *t0, c - c0);
    *t0 = t;
    c0 = c;
}

/* Runs one measure; a missing input is an error in strict mode, else a
 * warning recorded in the report's "skipped" group. */
static int run_measure(unsigned bit, int rc, const char *msg, const cd_an_options *opt, cd_an_report *rep)
{
    if (rc == 0) return 0;
    if (rc == 2 && !opt->strict) {
        warn(opt, msg);
        for (size_t k = 0; k < N_MEASURES; k++)
            if (measures[k].bit == bit) cd_an_put_text(cd_an_group_get(rep, "skipped"), measures[k].name, "%s", msg);
        return 0;
    }
    return rc;
}

static int analyze_file(const char *path, const cd_an_options *opt, cd_an_report *rep, char *err, size_t errlen)
{
    int mpm = cd_mpm_is_run_file(path);
    if (mpm && opt->measures != CD_AN_ALL && opt->measures != CD_AN_MPM) {
        snprintf(err, errlen, "%s: a run file of solver mpm: its only measure is mpm (--measures mpm)", path);
        return 2;
    }
    if (!mpm && (opt->measures & CD_AN_MPM)) {
        snprintf(err, errlen, "%s: measure mpm: not a run file of solver mpm", path);
        return 2;
    }
    if (mpm) return cd_an_mpm(path, opt, rep, err, errlen);
    cd_an_snapshot s;
    double t0 = now();
    int rc = cd_an_read_snapshot(path, opt->snapshot, &s, err, errlen);
    lap(opt, "read", &t0);
    if (rc) {
        cd_an_snapshot_free(&s);
        return rc;
    }
    rep->step = s.step;
    rep->time = s.time;
    rep->snapshot = s.snapshot;
    rep->n_snapshots = s.n_snapshots;
    if (!s.cfg_ok)
        warn(opt, "the config echoed in /parameters/config does not parse; the container is inferred from the walls "
                  "and K_t is skipped");
    unsigned contact_measures = 0;
    for (size_t k = 0; k < N_MEASURES; k++)
        if (measures[k].needs_contacts) contact_measures |= measures[k].bit;
    if ((opt->measures & contact_measures) && s.nc == 0) {
        snprintf(err, errlen,
                 "%s: snapshot %d (step %lld) has no particle contacts: P(f), bond forces, stresses, branch vectors, "
                 "connectivity and K_t need them (pick a later snapshot with --snapshot, or --measures rdf,packing)",
                 path, s.snapshot, s.step);
        cd_an_snapshot_free(&s);
        return 2;
    }
    cd_an_geometry g;
    cd_an_geometry_setup(&s, opt->margin_side, opt->margin_end, &g);
    cd_an_bonds b;
    rc = cd_an_bonds_build(&s, &b, err, errlen);
    lap(opt, "grouping", &t0);
    if (rc) {
        cd_an_snapshot_free(&s);
        return rc;
    }
    double sum = 0;
    for (size_t c = 0; c < s.nc; c++) sum += s.fn[c];
    cd_an_input in = {&s, &g, &b, opt, s.nc ? sum / (double)s.nc : 0};
    cd_an_group *info = cd_an_group_get(rep, "sample");
    cd_an_put(info, "n_particles", (double)s.n, "1");
    cd_an_put(info, "n_contacts", (double)s.nc, "1");
    cd_an_put(info, "n_wall_contacts", (double)s.nw, "1");
    cd_an_put(info, "L", g.L, "m");
    cd_an_put_text(info, "container", "%s", cd_an_kind_name(g.kind));
    if (g.note[0]) cd_an_put_text(info, "container_note", "%s", g.note);

    for (size_t k = 0; k < N_MEASURES && rc == 0; k++) {
        if (!(opt->measures & measures[k].bit) || !measures[k].fn) continue;
        char msg[1024] = "";
        rc = run_measure(measures[k].bit, measures[k].fn(&in, rep, msg, sizeof msg), msg, opt, rep);
        if (rc) snprintf(err, errlen, "%s", msg);
        lap(opt, measures[k].name, &t0);
    }
    cd_an_bonds_free(&b);
    cd_an_snapshot_free(&s);
    return rc;
}

int cd_analyze_file(const char *path, const cd_an_options *opt, cd_an_report *rep, char *err, size_t errlen)
{
    memset(rep, 0, sizeof(*rep));
    /* GSL's default handler aborts the process; every GSL result is
     * checked where it is used instead. */
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    cdh5_guard_begin("analyze", path); /* (analyze_file only reads the file) */
    int rc = analyze_file(path, opt, rep, err, errlen);
    cdh5_guard_end();
    gsl_set_error_handler(old);
    return rc;
}

/* Human-readable summary: every scalar and text, group by group. */
static void print_summary(const cd_an_report *rep, const char *path)
{
    printf("%s: snapshot %d (of 0..%d), step %lld, time %.6g s\n", path, rep->snapshot, rep->n_snapshots - 1, rep->step,
           rep->time);
    for (int k = 0; k < rep->n_groups; k++) {
        const cd_an_group *g = &rep->groups[k];
        printf("[%s]\n", g->name);
        for (int t = 0; t < g->n_texts; t++) printf("  %-30s %s\n", g->texts[t].name, g->texts[t].text);
        for (int s = 0; s < g->n_scalars; s++)
            printf("  %-30s %.6g %s\n", g->scalars[s].name, g->scalars[s].value,
                   strcmp(g->scalars[s].unit, "1") ? g->scalars[s].unit : "");
        for (int c = 0; c < g->n_curves; c++)
            printf("  %-30s table %zu x %d (%s)\n", g->curves[c].name, g->curves[c].rows, g->curves[c].cols,
                   g->curves[c].columns);
    }
}

static int parse_num(const char *opt, const char *s, double *out)
{
    char *end;
    *out = strtod(s, &end);
    if (end == s || *end || !isfinite(*out)) {
        fprintf(stderr, "capdem analyze: %s %s: expected a number\n", opt, s);
        return -1;
    }
    return 0;
}

int cd_cmd_analyze(int argc, char **argv)
{
    cd_an_options opt;
    cd_an_options_defaults(&opt);
    const char *path = NULL;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        int more = i + 1 < argc;
        double v;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--json")) {
            opt.json = 1;
        } else if (!strcmp(a, "--no-write")) {
            opt.write = 0;
        } else if (!strcmp(a, "--quiet")) {
            opt.quiet = 1;
        } else if (!strcmp(a, "--timings")) {
            opt.timings = 1;
        } else if (!strcmp(a, "--snapshot") && more) {
            const char *t = argv[++i];
            long long k = -1;
            char err[256];
            /* the strict parser of every command line (src/config/config_cli.c):
             * no 1e3, 2x or blanks; negative counts from the end */
            if (strcmp(t, "last") &&
                cd_parse_cli_int("--snapshot", t, -2147483647LL, 2147483647LL, &k, err, sizeof err)) {
                fprintf(stderr, "capdem analyze: %s (or last)\n", err);
                return 2;
            }
            opt.snapshot = (int)k;
        } else if (!strcmp(a, "--measures") && more) {
            char list[256];
            snprintf(list, sizeof list, "%s", argv[++i]);
            opt.measures = 0;
            opt.strict = 1;
            for (char *tok = strtok(list, ","); tok; tok = strtok(NULL, ",")) {
                unsigned bit = cd_an_measure_bit(tok);
                if (!bit) {
                    char names[256];
                    fprintf(stderr, "capdem analyze: --measures: unknown measure '%s' (%s)\n", tok,
                            measure_list(names, sizeof names));
                    return 2;
                }
                opt.measures |= bit;
            }
        } else if (!strcmp(a, "--margins") && more) {
            const char *t = argv[++i];
            char *end;
            opt.margin_side = strtod(t, &end);
            opt.margin_end = *end == ',' ? strtod(end + 1, &end) : opt.margin_side;
            if (*end || !(opt.margin_side >= 0) || !(opt.margin_end >= 0)) {
                fprintf(stderr, "capdem analyze: --margins %s: expected SIDE,END in units of L, >= 0\n", t);
                return 2;
            }
        } else if ((!strcmp(a, "--rdf-max") || !strcmp(a, "--rdf-bin") || !strcmp(a, "--mc-points")) && more) {
            if (parse_num(a, argv[++i], &v) || !(v > 0)) {
                fprintf(stderr, "capdem analyze: %s: expected a number > 0\n", a);
                return 2;
            }
            if (!strcmp(a, "--rdf-max")) opt.rdf_max = v;
            else if (!strcmp(a, "--rdf-bin")) opt.rdf_bin = v;
            else opt.mc_points = (long)v;
        } else if (!strcmp(a, "--phi-c") && more) {
            if (parse_num(a, argv[++i], &v) || !(v > 0 && v < 1)) {
                fprintf(stderr, "capdem analyze: --phi-c: expected a packing fraction in (0, 1)\n");
                return 2;
            }
            opt.phi_c = v;
        } else if (!strcmp(a, "--phi-series") && more) {
            opt.phi_series = argv[++i];
        } else if (!strcmp(a, "--z-series") && more) {
            opt.z_series = argv[++i];
        } else if (a[0] != '-' && !path) {
            path = a;
        } else {
            fprintf(stderr, "capdem analyze: unknown or incomplete option '%s'\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (!path) {
        fprintf(stderr, "capdem analyze: missing RUN.h5\n");
        usage(stderr);
        return 2;
    }
    cd_an_report rep;
    char err[2048] = "";
    int rc = cd_analyze_file(path, &opt, &rep, err, sizeof err);
    if (rc) {
        fprintf(stderr, "capdem analyze: %s\n", err[0] ? err : "failed");
        cd_an_report_free(&rep);
        return rc;
    }
    double t0 = now();
    if (opt.write && cd_an_write_h5(path, &rep, err, sizeof err)) {
        fprintf(stderr, "capdem analyze: %s\n", err);
        cd_an_report_free(&rep);
        return 1;
    }
    if (opt.write) lap(&opt, "write", &t0);
    if (opt.json) {
        if (cd_an_print_json(&rep, path, stdout)) rc = 1;
    } else if (!opt.quiet) {
        print_summary(&rep, path);
    }
    cd_an_report_free(&rep);
    return rc;
}
