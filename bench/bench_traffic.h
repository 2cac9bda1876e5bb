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

/* Width of the groups of consecutive pair rows counted by cd_bench_row_kinds
 * (a warp of an NVIDIA GPU). */
enum { CD_BENCH_WARP = 32 };

/* The pair rows by the narrow phase their end points choose in
 * cd_item_pair_force (kernels/step_items.h; sim->s synced): kinds[0] two
 * points (sphere-sphere), kinds[1] a point and a segment, kinds[2] two
 * segments; and how many groups of CD_BENCH_WARP consecutive rows in the
 * order visit gives (the pair pass's visiting order, cd_neighbors_pair_visit;
 * NULL: the row order at hand) hold more than one kind (*mixed of *groups):
 * the groups whose items would diverge on a GPU (issue 21 item 5). */
void cd_bench_row_kinds(const cd_sim *sim, const cd_int *visit, double kinds[3], double *mixed, double *groups);

#endif
