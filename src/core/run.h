/* The `capdem run` command: set-up, stepping, output, progress, resume. */
#ifndef CD_RUN_H
#define CD_RUN_H

typedef struct {
    const char *config_path;         /* run file */
    const char *resume_path;         /* run file to continue from its last snapshot, or NULL */
    const char *output_path;         /* overrides run.output, or NULL */
    long long steps;                 /* overrides run.steps when >= 0 */
    int quiet;                       /* 1: no progress lines */
    const char *backend;             /* omp | opencl (NULL: omp) */
    const char *device;              /* cpu | gpu | auto (NULL: auto; OpenCL) */
    int overwrite;                   /* 1: an existing output is replaced once the new run's first snapshot is
                               * written (0: an existing output is refused); no effect on a resume */
    const char *const *allow_change; /* --resume: keys that may differ from the run file's config */
    int n_allow_change;
} cd_run_options;

/* Returns the process exit status: 0 success, 2 bad input, 3 the run blew
 * up (the output written so far stays readable), 1 other failures. */
int cd_run(const cd_run_options *opt);

#endif
