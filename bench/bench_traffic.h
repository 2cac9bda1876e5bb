/* Bytes moved per time step, kernel by kernel: see bench_traffic.c. */
#ifndef CD_BENCH_TRAFFIC_H
#define CD_BENCH_TRAFFIC_H
#include "core/sim.h"

enum { CD_TRAFFIC_KERNELS = 5 };

typedef struct {
    const char *kernel; /* the loop of src/backend/omp/step_omp.c (one OpenCL kernel) */
    double read, write; /* bytes per step [B] */
} cd_traffic;

/* The bytes each loop of one time step reads and writes, counted from the
 * code of kernels/step_items.h for the state's counts of particles,
 * primitives, pair rows, contacts and wall contacts (sim->s synced).
 * steps_per_call: the steps of one cd_sim_step call (the per-call loops
 * are amortised over them).
 * Fills out[CD_TRAFFIC_KERNELS]. */
void cd_bench_traffic(const cd_sim *sim, double steps_per_call, cd_traffic out[CD_TRAFFIC_KERNELS]);

#endif
