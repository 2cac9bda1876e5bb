/* The time step on the host through OpenMP: every loop is one item per
 * primitive, pair or particle calling the shared kernel headers, and forces
 * reach particles by a gather in fixed order (no floating-point atomics), so
 * results are bitwise identical for any thread count. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "sim.h"
#include "../kernels/step_items.h"

long cd_parallel_min_rows = 4096;

/* The state's columns for the per-item functions of kernels/step_items.h,
 * which the OpenCL kernels call too. */
static cd_cols cols_of(cd_state *s)
{
    cd_cols c;
#define CD_FIELD(group, ctype, h5type, ncomp, name, unit, meaning) c.name = s->name;
#include "fields.def"
#undef CD_FIELD
    return c;
}

/* World endpoints of every primitive from its particle's pose. */
static void update_prims(cd_state *s)
{
    cd_cols c = cols_of(s);
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_prims))
    for (size_t i = 0; i < s->n_prims; i++) cd_item_prim_ends(c, (cd_prim_id)i);
}

/* One work item per pair of the Verlet list: narrow phase + contact law. */
static void pair_forces(cd_state *s, const cd_step_params *p)
{
    cd_cols c = cols_of(s);
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_pairs))
    for (size_t k = 0; k < s->n_pairs; k++) cd_item_pair_force(c, (cd_pair_id)k, p->law, p->dt, p->sin_parallel);
}

/* One work item per primitive: its contacts with every wall. */
static void wall_forces(cd_state *s, const cd_step_params *p)
{
    cd_cols c = cols_of(s);
    cd_int W = (cd_int)s->n_walls;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_prims))
    for (size_t i = 0; i < s->n_prims; i++)
        cd_item_wall_forces(c, (cd_prim_id)i, s->walls, W, p->wall_law, p->dt, p->sin_parallel);
}

/* One work item per particle: gravity plus its contacts in fixed order. */
static void gather(cd_state *s, const cd_neighbors *nb, const cd_step_params *p)
{
    cd_cols c = cols_of(s);
    cd_int W = (cd_int)s->n_walls;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_particles))
    for (size_t q = 0; q < s->n_particles; q++)
        cd_item_gather(c, (cd_particle_id)q, nb->gather_start, nb->gather_rows, W, p->gravity, p->dimension);
}

static void kick(cd_state *s, const cd_step_params *p)
{
    cd_cols c = cols_of(s);
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_particles))
    for (size_t q = 0; q < s->n_particles; q++) cd_item_kick(c, (cd_particle_id)q, 0.5 * p->dt);
}

static void drift(cd_state *s, const cd_step_params *p)
{
    cd_cols c = cols_of(s);
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_particles))
    for (size_t q = 0; q < s->n_particles; q++) cd_item_drift(c, (cd_particle_id)q, p->dt);
    for (size_t w = 0; w < s->n_walls; w++) s->walls[w] = cd_wall_advanced(s->walls[w], p->dt);
}

/* Forces for the current positions (neighbour list up to date). */
static void compute_forces_host(cd_sim *sim)
{
    pair_forces(&sim->s, &sim->p);
    wall_forces(&sim->s, &sim->p);
    gather(&sim->s, &sim->nb, &sim->p);
}

void cd_sim_refresh(cd_sim *sim)
{
    cd_state *s = &sim->s;
    for (size_t q = 0; q < s->n_particles; q++) s->angvel[q] = cd_rigid_angvel(s->orientation[q], s->angmom[q], s->inertia[q]);
    update_prims(s);
    sim->nb.force_rebuild = 1;
}

/* A run that blew up must stop before it writes garbage. */
int cd_sim_check_state(const cd_sim *sim, char *err, size_t errlen)
{
    const cd_state *s = &sim->s;
    cd_cols c = cols_of((cd_state *)s); /* read only */
    long bad = -1;
#pragma omp parallel for schedule(static) reduction(max : bad) if (CD_PARALLEL(s->n_particles))
    for (size_t q = 0; q < s->n_particles; q++)
        if (cd_item_not_finite(c, (cd_particle_id)q)) bad = (long)q > bad ? (long)q : bad;
    if (bad >= 0) {
        snprintf(err, errlen, "non-finite position or velocity of particle %ld at step %lld (t = %.9g s): "
                 "the run blew up; reduce run.dt or check the material parameters", bad, s->step, s->time);
        return -1;
    }
    return 0;
}

static int omp_start(cd_sim *sim, int compute_forces, char *err, size_t errlen)
{
    cd_sim_refresh(sim);
    if (!compute_forces) return 0; /* the neighbour list is rebuilt at the first step */
    if (cd_neighbors_build(sim)) {
        snprintf(err, errlen, "out of memory while building the first neighbour list");
        return -1;
    }
    compute_forces_host(sim);
    return 0;
}

static int omp_step(cd_sim *sim, long long n, char *err, size_t errlen)
{
    cd_state *s = &sim->s;
    for (long long it = 0; it < n; it++) {
        kick(s, &sim->p);
        drift(s, &sim->p);
        update_prims(s);
        if (cd_neighbors_needed(sim) && cd_neighbors_build(sim)) {
            snprintf(err, errlen, "out of memory while building the neighbour list (%zu pairs)", s->n_pairs);
            return -1;
        }
        compute_forces_host(sim);
        kick(s, &sim->p);
        s->step++;
        s->time += sim->p.dt;
    }
    return cd_sim_check_state(sim, err, errlen);
}

static int omp_sync(cd_sim *sim, char *err, size_t errlen)
{
    (void)sim; (void)err; (void)errlen;
    return 0; /* the state lives in host memory */
}

static void omp_stop(cd_sim *sim) { (void)sim; }

static const char *omp_device(const cd_sim *sim)
{
    static char buf[64];
    snprintf(buf, sizeof buf, "host, %d OpenMP thread(s)", sim->threads);
    return buf;
}

const cd_backend cd_backend_omp = {"omp", omp_start, omp_step, omp_sync, omp_stop, omp_device, NULL};
