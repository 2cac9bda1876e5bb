/* The operations a backend provides.  A backend owns the state between
 * calls: the host columns of sim->s are current only after sync(). */
#ifndef CD_BACKEND_H
#define CD_BACKEND_H
#include <stddef.h>

struct cd_sim;

typedef struct cd_backend {
    const char *name; /* "omp" or "opencl" */
    /* Takes the host state (sim->s, set up or read from a checkpoint),
     * creates the device buffers and uploads it.  compute_forces: 1 to
     * build the neighbour list and compute the forces of this state (a new
     * run), 0 to keep the forces in sim->s (a resumed run). */
    int (*start)(struct cd_sim *sim, int compute_forces, char *err, size_t errlen);
    /* Advances n steps on the device. */
    int (*step)(struct cd_sim *sim, long long n, char *err, size_t errlen);
    /* Copies the device state into sim->s (output, checkpoints, analysis). */
    int (*sync)(struct cd_sim *sim, char *err, size_t errlen);
    /* Releases device resources. */
    void (*stop)(struct cd_sim *sim);
    /* Human-readable device description. */
    const char *(*device)(const struct cd_sim *sim);
    /* Optional (may be NULL): sum of the normal forces of all contacts on
     * wall w at the last force evaluation [N], without a full sync. */
    int (*wall_load)(struct cd_sim *sim, int w, double *load, char *err, size_t errlen);
    /* Optional (may be NULL): the observables of the current state summed
     * on the device, without a full sync: the CD_OBS_SLOTS merged slots of
     * kernels/observe_items.h into slots. */
    int (*observe)(struct cd_sim *sim, double *slots, char *err, size_t errlen);
} cd_backend;

extern const cd_backend cd_backend_omp;
#ifdef CAPDEM_HAVE_OPENCL
extern const cd_backend cd_backend_opencl;
#endif

/* Looks a backend up by name ("omp", "opencl"); NULL if unknown or not
 * built. */
const cd_backend *cd_backend_find(const char *name);

#endif
