/* The defined cases of capdem-bench (docs/performance.md, "Bench cases"):
 * shape, size distribution, dimension, time step and the box they settle in.
 * Material: the default material of docs/references.md, Contact law (rho 1000 kg/m^3, k_n 1e5 N/m, k_t 0.5 k_n,
 * eta_n = eta_t = 0.2, mu 0.5, frictionless walls). */
#ifndef CD_BENCH_CASES_H
#define CD_BENCH_CASES_H
#include <stddef.h>

typedef struct {
    const char *name;      /* spheres | crosses2d | hexapods_a3 | hexapods_a9 | mix_spheres_hexapods */
    const char *shape;     /* config particles[].shape */
    double aspect;         /* alpha (1 for spheres) */
    const char *shape2;    /* a mixture: the shape of the second half of the particles (NULL: one shape) */
    double aspect2;        /* its alpha */
    double diameter;       /* arm diameter d_p [m] */
    double polydispersity; /* p: sizes uniform in [1-p, 1+p] */
    int dimension;         /* 3, or 2 (motion in the x-y plane) */
    double dt;             /* time step [s], below t_col/20 of the lightest pair */
    long settle_steps;     /* default settling steps under 50 g */
} cd_bench_case;

/* The case called name, or NULL. */
const cd_bench_case *cd_bench_case_find(const char *name);

/* Comma-separated names of every case (for messages). */
const char *cd_bench_case_names(void);

/* Writes the run file of a case with n particles into yaml: lattice deposit
 * into a box (columns about 4x as tall as wide), settling gravity 50 g,
 * seed, friction limit (elastic | total).  Returns the length, or -1 if it
 * did not fit. */
int cd_bench_case_yaml(const cd_bench_case *c, long n, unsigned seed, const char *friction_limit, char *yaml,
                       size_t len);

#endif
