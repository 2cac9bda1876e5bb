/* A simulation's life cycle, independent of the backend that steps it. */
#include <stdio.h>
#include <string.h>
#include "core/sim.h"
#include "step_items.h"

int cd_sim_use_backend(cd_sim *sim, const char *name, const char *device, char *err, size_t errlen)
{
    const cd_backend *b = cd_backend_find(name);
    if (!b) {
        snprintf(err, errlen, "--backend %s: expected omp or opencl (this build has: omp%s)", name,
                 cd_backend_find("opencl") ? ", opencl" : "");
        return -1;
    }
    sim->backend = b;
    snprintf(sim->device_request, sizeof sim->device_request, "%s", device ? device : "auto");
    return 0;
}

int cd_sim_start(cd_sim *sim, int compute_forces, char *err, size_t errlen)
{
    if (!sim->backend) sim->backend = &cd_backend_omp;
    return sim->backend->start(sim, compute_forces, err, errlen);
}

int cd_sim_initial_forces(cd_sim *sim)
{
    char err[1024];
    if (cd_sim_start(sim, 1, err, sizeof err)) {
        fprintf(stderr, "capdem: %s\n", err);
        return -1;
    }
    return 0;
}

int cd_sim_step(cd_sim *sim, long long n, char *err, size_t errlen)
{
    if (!sim->backend) sim->backend = &cd_backend_omp;
    return sim->backend->step(sim, n, err, errlen);
}

int cd_sim_sync(cd_sim *sim, char *err, size_t errlen)
{
    if (sim->backend && sim->backend->sync(sim, err, errlen)) return -1;
    cd_sim_derive_pair_output(sim);
    return 0;
}

const cd_backend *cd_backend_find(const char *name)
{
    if (!strcmp(name, "omp")) return &cd_backend_omp;
#ifdef CAPDEM_HAVE_OPENCL
    if (!strcmp(name, "opencl")) return &cd_backend_opencl;
#endif
    return NULL;
}

double cd_sim_wall_load_host(cd_sim *sim, int w)
{
    /* the order of every backend (kernels/step_items.h, CD_LOAD_CHUNK:
     * chunk sums in user primitive order, added in chunk order), over the
     * host's rows, every row (one not in contact holds F_n = 0) */
    const cd_state *s = &sim->s;
    cd_long P = (cd_long)s->n_prims, W = (cd_long)s->n_walls;
    const cd_int *prim_at = cd_sim_host_order(sim).prim_at;
    double sum = 0;
    for (cd_long ch = 0; ch * CD_LOAD_CHUNK < P; ch++) {
        cd_long end = (ch + 1) * CD_LOAD_CHUNK < P ? (ch + 1) * CD_LOAD_CHUNK : P;
        double acc = 0;
        for (cd_long u = ch * CD_LOAD_CHUNK; u < end; u++) acc += s->wallc_fn[cd_map(prim_at, u) * W + w];
        sum += acc;
    }
    return sum;
}

int cd_sim_wall_load(cd_sim *sim, int w, double *load, char *err, size_t errlen)
{
    if (sim->backend && sim->backend->wall_load) return sim->backend->wall_load(sim, w, load, err, errlen);
    /* the backend's copy back only: the load reads no output-only column,
     * and protocols ask for it every step */
    if (sim->backend && sim->backend->sync(sim, err, errlen)) return -1;
    *load = cd_sim_wall_load_host(sim, w);
    return 0;
}
