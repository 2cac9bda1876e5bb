/* The time step on the host through OpenMP: every loop is one item per
 * primitive, pair or particle calling the shared kernel headers, and forces
 * reach particles by a gather in fixed order (no floating-point atomics), so
 * results are bitwise identical for any thread count. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "sim.h"
#include "../kernels/rigid.h"
#include "../kernels/segseg.h"
#include "../kernels/walls.h"

long cd_parallel_min_rows = 4096;

/* World endpoints of every primitive from its particle's pose. */
static void update_prims(cd_state *s)
{
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_prims))
    for (size_t i = 0; i < s->n_prims; i++) {
        cd_particle_id p = s->prim_particle[i];
        s->prim_a[i] = cd_rigid_to_world(s->position[p], s->orientation[p], s->prim_a_body[i]);
        s->prim_b[i] = cd_rigid_to_world(s->position[p], s->orientation[p], s->prim_b_body[i]);
    }
}

/* One work item per pair of the Verlet list: narrow phase + contact law. */
static void pair_forces(cd_state *s, const cd_step_params *p)
{
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_pairs))
    for (size_t k = 0; k < s->n_pairs; k++) {
        cd_prim_id i = s->pair_prim_i[k], j = s->pair_prim_j[k];
        cd_particle_id pi = s->prim_particle[i], pj = s->prim_particle[j];
        cd_contact_geom g;
        cd_segseg_contact(s->prim_a[i], s->prim_b[i], s->prim_radius[i], s->prim_a[j], s->prim_b[j],
                          s->prim_radius[j], p->sin_parallel, &g);
        if (!(g.overlap > 0)) {
            /* Separated: the contact and its history end. */
            s->pair_active[k] = 0;
            s->pair_shear[k] = cd_v3_zero();
            s->pair_fn[k] = 0;
            s->pair_overlap[k] = 0;
            continue;
        }
        cd_vec3 vi = cd_rigid_point_velocity(s->position[pi], s->velocity[pi], s->angvel[pi], g.point);
        cd_vec3 vj = cd_rigid_point_velocity(s->position[pj], s->velocity[pj], s->angvel[pj], g.point);
        cd_real m_eff = cd_law_effective_mass(s->mass[pi], s->mass[pj]);
        cd_vec3 shear = s->pair_shear[k];
        cd_contact_force f = cd_contact_law(p->law, m_eff, &g, cd_v3_sub(vj, vi), p->dt, &shear);
        s->pair_active[k] = 1;
        s->pair_shear[k] = shear;
        s->pair_point[k] = g.point;
        s->pair_normal[k] = g.normal;
        s->pair_overlap[k] = g.overlap;
        s->pair_fn[k] = f.fn;
        s->pair_ft[k] = f.ft;
        s->pair_torque_i[k] = cd_v3_cross(cd_v3_sub(g.point, s->position[pi]), cd_v3_neg(f.force_j));
        s->pair_torque_j[k] = cd_v3_cross(cd_v3_sub(g.point, s->position[pj]), f.force_j);
    }
}

/* One work item per primitive: its contacts with every wall. */
static void wall_forces(cd_state *s, const cd_step_params *p)
{
    size_t W = s->n_walls;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_prims))
    for (size_t i = 0; i < s->n_prims; i++) {
        cd_particle_id pi = s->prim_particle[i];
        for (size_t w = 0; w < W; w++) {
            size_t row = i * W + w;
            cd_contact_geom g;
            cd_wall_contact(&s->walls[w], s->prim_a[i], s->prim_b[i], s->prim_radius[i], p->sin_parallel, &g);
            if (!(g.overlap > 0)) {
                s->wallc_active[row] = 0;
                s->wallc_shear[row] = cd_v3_zero();
                s->wallc_overlap[row] = 0;
                continue;
            }
            cd_vec3 vi = cd_rigid_point_velocity(s->position[pi], s->velocity[pi], s->angvel[pi], g.point);
            cd_vec3 vw = cd_wall_velocity_at(&s->walls[w], g.point);
            cd_law_params law = p->wall_law;
            law.mu = s->walls[w].friction;
            cd_vec3 shear = s->wallc_shear[row];
            /* The particle is body i, the wall body j of infinite mass. */
            cd_contact_force f = cd_contact_law(law, s->mass[pi], &g, cd_v3_sub(vw, vi), p->dt, &shear);
            cd_vec3 fi = cd_v3_neg(f.force_j);
            s->wallc_active[row] = 1;
            s->wallc_shear[row] = shear;
            s->wallc_overlap[row] = g.overlap;
            s->wallc_force[row] = fi;
            s->wallc_torque[row] = cd_v3_cross(cd_v3_sub(g.point, s->position[pi]), fi);
        }
    }
}

/* One work item per particle: gravity plus its contacts in fixed order. */
static void gather(cd_state *s, const cd_neighbors *nb, const cd_step_params *p)
{
    size_t W = s->n_walls;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_particles))
    for (size_t q = 0; q < s->n_particles; q++) {
        cd_vec3 F = cd_v3_scale(p->gravity, s->mass[q]);
        cd_vec3 T = cd_v3_zero();
        cd_int first = s->prim_first[q], last = first + s->prim_count[q];
        for (cd_int i = first; i < last; i++)
            for (size_t w = 0; w < W; w++) {
                size_t row = (size_t)i * W + w;
                if (!s->wallc_active[row]) continue;
                F = cd_v3_add(F, s->wallc_force[row]);
                T = cd_v3_add(T, s->wallc_torque[row]);
            }
        for (cd_int r = nb->gather_start[q]; r < nb->gather_start[q + 1]; r++) {
            cd_pair_id k = nb->gather_rows[r];
            if (!s->pair_active[k]) continue;
            cd_vec3 fj = cd_v3_axpy(s->pair_ft[k], s->pair_fn[k], s->pair_normal[k]);
            if ((size_t)s->prim_particle[s->pair_prim_i[k]] == q) {
                F = cd_v3_sub(F, fj);
                T = cd_v3_add(T, s->pair_torque_i[k]);
            } else {
                F = cd_v3_add(F, fj);
                T = cd_v3_add(T, s->pair_torque_j[k]);
            }
        }
        if (p->dimension == 2) {
            /* Crosses in the x-y plane: no out-of-plane force or tilt. */
            F.z = 0;
            T.x = 0;
            T.y = 0;
        }
        s->force[q] = F;
        s->torque[q] = T;
    }
}

static void kick(cd_state *s, const cd_step_params *p)
{
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_particles))
    for (size_t q = 0; q < s->n_particles; q++) {
        cd_rigid_kick(&s->velocity[q], &s->angmom[q], s->force[q], s->torque[q], s->mass[q], 0.5 * p->dt);
        s->angvel[q] = cd_rigid_angvel(s->orientation[q], s->angmom[q], s->inertia[q]);
    }
}

static void drift(cd_state *s, const cd_step_params *p)
{
#pragma omp parallel for schedule(static) if (CD_PARALLEL(s->n_particles))
    for (size_t q = 0; q < s->n_particles; q++) {
        cd_rigid_drift(&s->position[q], &s->orientation[q], s->velocity[q], s->angmom[q], s->inertia[q], p->dt);
        s->angvel[q] = cd_rigid_angvel(s->orientation[q], s->angmom[q], s->inertia[q]);
    }
    for (size_t w = 0; w < s->n_walls; w++) {
        s->walls[w].point = cd_v3_axpy(s->walls[w].point, p->dt, s->walls[w].velocity);
        s->walls[w].radius += p->dt * s->walls[w].radial_velocity;
    }
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
    long bad = -1;
#pragma omp parallel for schedule(static) reduction(max : bad) if (CD_PARALLEL(s->n_particles))
    for (size_t q = 0; q < s->n_particles; q++) {
        cd_vec3 x = s->position[q], v = s->velocity[q], L = s->angmom[q];
        if (!isfinite(x.x + x.y + x.z + v.x + v.y + v.z + L.x + L.y + L.z)) bad = (long)q > bad ? (long)q : bad;
    }
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

const cd_backend cd_backend_omp = {"omp", omp_start, omp_step, omp_sync, omp_stop, omp_device};
