/* Observables of the state: energies, momentum, wall forces.  Sums run over
 * fixed blocks of rows, each block in order, then the blocks in order, so
 * the result does not depend on the number of threads. */
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include "sim.h"
#include "../kernels/rigid.h"

#define CD_SUM_BLOCK 4096
#define CD_OBS_SLOTS (10 + 3 * CD_MAX_WALLS)

enum { O_KT, O_KR, O_EL, O_PE, O_NC, O_NW, O_PX, O_PY, O_PZ, O_KC, O_WALL };

/* Adds the contributions of particle q into acc (slots as in the enum). */
/* Particles with at least one active contact (pair or wall), or NULL. */
static const unsigned char *touching;

static void particle_terms(const cd_sim *sim, size_t q, double *acc)
{
    const cd_state *s = &sim->s;
    cd_vec3 v = s->velocity[q];
    double kt = 0.5 * s->mass[q] * cd_v3_norm2(v), kr = cd_rigid_rot_energy(s->orientation[q], s->angmom[q], s->inertia[q]);
    acc[O_KT] += kt;
    acc[O_KR] += kr;
    if (touching && touching[q]) acc[O_KC] += kt + kr;
    acc[O_PE] -= s->mass[q] * cd_v3_dot(sim->p.gravity, s->position[q]);
    acc[O_PX] += s->mass[q] * v.x;
    acc[O_PY] += s->mass[q] * v.y;
    acc[O_PZ] += s->mass[q] * v.z;
}

static void pair_terms(const cd_sim *sim, size_t k, double *acc)
{
    const cd_state *s = &sim->s;
    if (!s->pair_active[k]) return;
    cd_real r_eff = cd_law_pair_radius(s->prim_radius[s->pair_prim_i[k]], s->prim_radius[s->pair_prim_j[k]]);
    acc[O_EL] += cd_contact_elastic_energy(sim->p.law, r_eff, s->pair_overlap[k], s->pair_shear[k]);
    acc[O_NC] += 1;
}

static void wall_terms(const cd_sim *sim, size_t row, double *acc)
{
    const cd_state *s = &sim->s;
    if (!s->wallc_active[row]) return;
    size_t w = row % s->n_walls;
    acc[O_EL] += cd_contact_elastic_energy(sim->p.wall_law, s->prim_radius[row / s->n_walls], s->wallc_overlap[row],
                                           s->wallc_shear[row]);
    acc[O_NW] += 1;
    /* The particle pushes the wall with the opposite of the wall's force. */
    acc[O_WALL + 3 * w + 0] -= s->wallc_force[row].x;
    acc[O_WALL + 3 * w + 1] -= s->wallc_force[row].y;
    acc[O_WALL + 3 * w + 2] -= s->wallc_force[row].z;
}

typedef void (*term_fn)(const cd_sim *, size_t, double *);

static void block_sum(const cd_sim *sim, size_t rows, term_fn fn, double *total)
{
    size_t nblocks = (rows + CD_SUM_BLOCK - 1) / CD_SUM_BLOCK;
    double partial[64][CD_OBS_SLOTS];
    /* Blocks are processed in batches of 64 to bound the stack use. */
    for (size_t b0 = 0; b0 < nblocks; b0 += 64) {
        size_t nb = nblocks - b0 < 64 ? nblocks - b0 : 64;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(nb * CD_SUM_BLOCK))
        for (size_t b = 0; b < nb; b++) {
            memset(partial[b], 0, sizeof(partial[b]));
            size_t end = (b0 + b + 1) * CD_SUM_BLOCK < rows ? (b0 + b + 1) * CD_SUM_BLOCK : rows;
            for (size_t r = (b0 + b) * CD_SUM_BLOCK; r < end; r++) fn(sim, r, partial[b]);
        }
        for (size_t b = 0; b < nb; b++)
            for (int k = 0; k < CD_OBS_SLOTS; k++) total[k] += partial[b][k];
    }
}

void cd_sim_observe(const cd_sim *sim, cd_observables *o)
{
    const cd_state *s = &sim->s;
    double acc[CD_OBS_SLOTS] = {0};
    /* Rattlers move freely in their cages (without gravity and friction
     * forever): relaxation criteria look at the particles that touch. */
    unsigned char *mark = calloc(s->n_particles + 1, 1);
    if (mark) {
        for (size_t k = 0; k < s->n_pairs; k++)
            if (s->pair_active[k]) mark[s->prim_particle[s->pair_prim_i[k]]] = mark[s->prim_particle[s->pair_prim_j[k]]] = 1;
        for (size_t r = 0; r < s->n_prims * s->n_walls; r++)
            if (s->wallc_active[r]) mark[s->prim_particle[r / s->n_walls]] = 1;
    }
    touching = mark;
    block_sum(sim, s->n_particles, particle_terms, acc);
    touching = NULL;
    free(mark);
    block_sum(sim, s->n_pairs, pair_terms, acc);
    block_sum(sim, s->n_prims * s->n_walls, wall_terms, acc);
    memset(o, 0, sizeof(*o));
    o->kinetic_translational = acc[O_KT];
    o->kinetic_rotational = acc[O_KR];
    o->kinetic_in_contact = acc[O_KC];
    o->elastic = acc[O_EL];
    o->potential = acc[O_PE];
    o->n_contacts = acc[O_NC];
    o->n_wall_contacts = acc[O_NW];
    o->momentum[0] = acc[O_PX];
    o->momentum[1] = acc[O_PY];
    o->momentum[2] = acc[O_PZ];
    for (size_t w = 0; w < s->n_walls; w++)
        for (int c = 0; c < 3; c++) o->wall_force[w][c] = acc[O_WALL + 3 * w + c];
    double worst = 0;
    for (size_t k = 0; k < s->n_pairs; k++)
        if (s->pair_active[k]) {
            double d = 2 * fmin(s->prim_radius[s->pair_prim_i[k]], s->prim_radius[s->pair_prim_j[k]]);
            if (s->pair_overlap[k] / d > worst) worst = s->pair_overlap[k] / d;
        }
    for (size_t r = 0; r < s->n_prims * s->n_walls; r++)
        if (s->wallc_active[r]) {
            double d = 2 * s->prim_radius[r / s->n_walls];
            if (s->wallc_overlap[r] / d > worst) worst = s->wallc_overlap[r] / d;
        }
    o->max_overlap_ratio = worst;
}
