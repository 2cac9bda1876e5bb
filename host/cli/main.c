/* capdem command line: run, shape, recover, --version (analyze, export
 * and render live in their own files). */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "core/run.h"
#include "shapes/shapes.h"
#include "config/config.h"
#include "export/export.h"
#include "analysis/analyze.h"
#include "io/io_h5.h"
#include "io/io_h5_journal.h"
#include "mpi/mpi_decomp.h"
#include "capdem_commit.h" /* CAPDEM_COMMIT, generated at build time (src/git_commit.cmake) */
#ifdef _OPENMP
#include <omp.h>
#endif

static void usage(FILE *f)
{
    fprintf(f,
            "usage: capdem <command> [options]\n"
            "commands:\n"
            "  run CONFIG.yaml [--resume RUN.h5] [--output RUN.h5] [--overwrite] [--steps N] [--threads N]\n"
            "                  [--allow-change KEY]... [--quiet] [--backend omp|opencl] [--device cpu|gpu|auto]\n"
            "                  run a simulation; `capdem run --help` lists every config key\n"
            "  shape KIND [--aspect A] [--diameter D] [--density RHO] [--json]\n"
            "                  mass properties of a sphere, rod, cross or hexapod (SI units)\n"
            "  analyze RUN.h5 [--snapshot last|N] [--json]\n"
            "                  microstructure of a packing (docs/analysis.md)\n"
            "  export RUN.h5 [-o OUT.xmf]\n"
            "                  ParaView-ready XDMF description of a run (docs/visualization.md)\n"
            "  render RUN.h5 [--snapshot N] -o PIC.png [--mode arms|forces] [--view ELEV,AZIM]\n"
            "                [--color particle|height|shape|speed|plastic]   picture of a packing or of\n"
            "                material points (matplotlib)\n"
            "  recover RUN.h5  brings a run file left by a killed run to its last commit in place, so that\n"
            "                  programs other than capdem (h5py, h5dump) read it (docs/output.md, \"Crash safety\")\n"
            "  --version       version, build variant and OpenMP devices\n");
}

static int parse_double(const char *opt, const char *s, double *out)
{
    char err[256];
    if (cd_parse_cli_real(opt, s, -HUGE_VAL, HUGE_VAL, out, err, sizeof err)) {
        fprintf(stderr, "capdem: %s\n", err);
        return -1;
    }
    return 0;
}

static int cmd_shape(int argc, char **argv)
{
    if (argc < 1) {
        usage(stderr);
        return 2;
    }
    const char *kind = argv[0];
    double aspect = 1, diameter = 0.005, density = 1000; /* [1], [m], [kg/m^3] */
    int json = 0;
    for (int i = 1; i < argc; i++) {
        double *target = !strcmp(argv[i], "--aspect")     ? &aspect
                         : !strcmp(argv[i], "--diameter") ? &diameter
                         : !strcmp(argv[i], "--density")  ? &density
                                                          : NULL;
        if (target && i + 1 < argc) {
            if (parse_double(argv[i], argv[i + 1], target)) return 2;
            i++;
        } else if (!strcmp(argv[i], "--json")) {
            json = 1;
        } else {
            fprintf(stderr, "capdem shape: unknown or incomplete option '%s'\n", argv[i]);
            return 2;
        }
    }
    cd_shape s;
    char err[512];
    if (cd_shape_make_named(kind, aspect, diameter, density, &s, err, sizeof err)) {
        fprintf(stderr, "capdem shape: %s\n", err);
        return 2;
    }
    if (json) {
        cd_shape_print_json(&s, stdout);
    } else {
        printf("%s  aspect %g  diameter %g m  L %g m\n", s.kind, s.aspect, s.diameter, s.tip_length);
        printf("volume %.10g m^3  area %.10g m^2  sphericity %.6f\n", s.volume, s.area, s.sphericity);
        printf("mass %.10g kg  principal moments %.10g %.10g %.10g kg m^2\n", s.mass, s.principal[0], s.principal[1],
               s.principal[2]);
    }
    return 0;
}

static int cmd_run(int argc, char **argv)
{
    cd_run_options opt = {NULL, NULL, NULL, -1, 0, NULL, NULL, 0, NULL, 0};
    static const char *allow[64];
    char err[512];
    long long v;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        int has_value = i + 1 < argc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            printf(
                "usage: capdem run CONFIG.yaml [--resume RUN.h5] [--output RUN.h5] [--overwrite] [--steps N] "
                "[--threads N]\n"
                "                  [--allow-change KEY]... [--quiet] [--backend omp|opencl] [--device cpu|gpu|auto]\n\n"
                "  --output RUN.h5   run file (default run.output, else <run.name>.h5); an existing file is refused\n"
                "  --overwrite       replace an existing output, once the new run's first snapshot is written (the "
                "old\n"
                "                    file stays until then); never an input, never a file another process has open\n"
                "  --resume RUN.h5   continue RUN.h5 from its last complete snapshot, appending to it (--output, if\n"
                "                    given, must name the same file); the config must match the one stored in RUN.h5\n"
                "                    except for keys marked 'May change on --resume' below\n"
                "  --allow-change KEY  with --resume: accept a changed KEY (e.g. material.friction); repeatable\n"
                "  --steps N         run.steps: the step to reach, counted from step 0 of the run, also on a resume\n"
                "                    (a resume at step S continues to N; N < S is refused)\n"
                "  --threads N       OpenMP threads (1 to 4096)\n"
                "Exit status: 0 done, 2 bad input (nothing written), 3 the run blew up (the snapshots written so far\n"
                "stay readable), 1 other failures.\n\n"
                "Config keys (YAML; SI units):\n");
            cd_config_print_keys(stdout, 0);
            return 0;
        } else if (!strcmp(a, "--help-markdown")) { /* the key table of docs/config.md */
            cd_config_print_keys(stdout, 1);
            return 0;
        } else if (!strcmp(a, "--resume") && has_value) opt.resume_path = argv[++i];
        else if (!strcmp(a, "--output") && has_value) opt.output_path = argv[++i];
        else if (!strcmp(a, "--steps") && has_value) {
            if (cd_parse_cli_int(a, argv[++i], 0, LLONG_MAX, &v, err, sizeof err)) {
                fprintf(stderr, "capdem run: %s\n", err);
                return 2;
            }
            opt.steps = v;
        } else if (!strcmp(a, "--overwrite")) opt.overwrite = 1;
        else if (!strcmp(a, "--allow-change") && has_value) {
            if (opt.n_allow_change == (int)(sizeof allow / sizeof allow[0])) {
                fprintf(stderr, "capdem run: --allow-change given more than %d times\n",
                        (int)(sizeof allow / sizeof allow[0]));
                return 2;
            }
            allow[opt.n_allow_change++] = argv[++i];
            opt.allow_change = allow;
        } else if (!strcmp(a, "--quiet")) opt.quiet = 1;
        else if (!strcmp(a, "--backend") && has_value) opt.backend = argv[++i];
        else if (!strcmp(a, "--device") && has_value) opt.device = argv[++i];
        else if (!strcmp(a, "--threads") && has_value) {
            if (cd_parse_cli_int(a, argv[++i], 1, 4096, &v, err, sizeof err)) {
                fprintf(stderr, "capdem run: %s\n", err);
                return 2;
            }
#ifdef _OPENMP
            omp_set_num_threads((int)v);
#endif
        } else if (a[0] != '-' && !opt.config_path) opt.config_path = a;
        else {
            fprintf(stderr, "capdem run: unknown or incomplete option '%s'\n", a);
            return 2;
        }
    }
    if (!opt.config_path) {
        fprintf(stderr, "capdem run: missing CONFIG.yaml (see capdem run --help)\n");
        return 2;
    }
    return cd_run(&opt);
}

/* Exit status 1 when built for offload, no device is found and
 * OMP_TARGET_OFFLOAD=MANDATORY: a GPU machine's first check. */
static int version_lines(void)
{
    printf("capdem %s (commit %s)\n", CAPDEM_VERSION, CAPDEM_COMMIT);
#if defined(__clang__)
    printf("omp backend: offload variant '%s', compiler clang %s", CAPDEM_OFFLOAD_VARIANT, __clang_version__);
#elif defined(__GNUC__)
    printf("omp backend: offload variant '%s', compiler gcc %s", CAPDEM_OFFLOAD_VARIANT, __VERSION__);
#else
    printf("omp backend: offload variant '%s'", CAPDEM_OFFLOAD_VARIANT);
#endif
#ifdef _OPENMP
    int devices = omp_get_num_devices();
    printf(", OpenMP %d, %d host thread(s), %d offload device(s)\n", _OPENMP, omp_get_max_threads(), devices);
    if (strcmp(CAPDEM_OFFLOAD_VARIANT, "none") && devices == 0) {
        const char *m = getenv("OMP_TARGET_OFFLOAD");
        if (m && (!strcmp(m, "MANDATORY") || !strcmp(m, "mandatory"))) {
            printf("built for %s offload but no offload device found, and OMP_TARGET_OFFLOAD=%s (docs/offload.md)\n",
                   CAPDEM_OFFLOAD_VARIANT, m);
            return 1;
        }
        printf("built for %s offload but no offload device found: running on the host (docs/offload.md)\n",
               CAPDEM_OFFLOAD_VARIANT);
    }
#else
    printf(", built without OpenMP\n");
#endif
    return 0;
}

/* Under an MPI launcher (an MPI build) rank 0 prints, with a line naming
 * each rank's device (docs/mpi.md, "GPUs"). */
static int print_version(void)
{
    if (cd_mpi_begin()) {
        fprintf(stderr, "capdem: MPI did not start\n");
        return 1;
    }
    int rc = cd_mpi_is_writer() ? version_lines() : 0;
    cd_mpi_version();
    return cd_mpi_end(rc);
}

/* `capdem recover RUN.h5`: replays the commit journal a killed writer left
 * beside the file (capdem itself reads through it without this). */
static int cmd_recover(int argc, char **argv)
{
    if (argc == 1 && (!strcmp(argv[0], "--help") || !strcmp(argv[0], "-h"))) {
        printf("usage: capdem recover RUN.h5\n");
        return 0;
    }
    if (argc != 1 || argv[0][0] == '-') {
        fprintf(stderr, "capdem recover: expected one run file (usage: capdem recover RUN.h5)\n");
        return 2;
    }
    if (access(argv[0], F_OK) != 0) {
        fprintf(stderr, "capdem recover: %s: no such run file\n", argv[0]);
        return 2;
    }
    char err[1024];
    int rc = cdh5_recover(argv[0], err, sizeof err);
    if (rc < 0) {
        fprintf(stderr, "capdem recover: %s\n", err);
        return 1;
    }
    printf("%s: %s\n", argv[0],
           rc ? "the commit a killed run had begun is now complete in the file"
              : "nothing to recover (the file holds its last commit)");
    return 0;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    const char *cmd = argv[1];
    /* Every file is closed explicitly, and run files are journaled: one a
     * command could not close (HDF5 failed to flush a corrupted file) keeps
     * its last commit.  HDF5's own clean-up at exit would try that close
     * again and can crash inside the library instead (fuzz_runfile). */
    cd_h5_no_atexit();
    if (!strcmp(cmd, "--version") || !strcmp(cmd, "version")) return print_version();
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(cmd, "run")) return cmd_run(argc - 2, argv + 2);
    if (!strcmp(cmd, "shape")) return cmd_shape(argc - 2, argv + 2);
    if (!strcmp(cmd, "recover")) return cmd_recover(argc - 2, argv + 2);
    if (!strcmp(cmd, "analyze")) return cd_cmd_analyze(argc - 2, argv + 2);
    if (!strcmp(cmd, "export")) return cd_cmd_export(argc - 2, argv + 2);
    if (!strcmp(cmd, "render")) return cd_cmd_render(argc - 2, argv + 2);
    fprintf(stderr, "capdem: unknown command '%s'\n", cmd);
    usage(stderr);
    return 2;
}
