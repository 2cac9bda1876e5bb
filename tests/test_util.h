/* Helpers shared by the tests: cmocka, building a simulation from YAML text,
 * and placing bodies by hand. */
#ifndef CD_TEST_UTIL_H
#define CD_TEST_UTIL_H
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "core/sim.h"
#include "../kernels/rigid.h"

/* The backend under test: CAPDEM_TEST_BACKEND (CTest runs the physics and
 * regression tests once per backend), omp by default. */
static inline const char *cdt_backend(void)
{
    const char *b = getenv("CAPDEM_TEST_BACKEND");
    return b && *b ? b : "omp";
}

/* Builds a simulation from YAML text on the backend under test; fails the
 * test on error. */
static inline void cdt_setup(cd_sim *sim, cd_config *cfg, const char *yaml)
{
    char err[2048];
    if (cd_config_parse(yaml, "test.yaml", cfg, err, sizeof err)) fail_msg("config: %s", err);
    if (cd_sim_setup(sim, cfg, err, sizeof err)) fail_msg("setup: %s", err);
    if (cd_sim_use_backend(sim, cdt_backend(), getenv("CAPDEM_TEST_DEVICE"), err, sizeof err)) fail_msg("%s", err);
}

/* Puts particle q at pos with orientation qo, velocity v, angular velocity w. */
static inline void cdt_place(cd_sim *sim, size_t q, cd_vec3 pos, cd_quat qo, cd_vec3 v, cd_vec3 w)
{
    cd_state *s = &sim->s;
    s->position[q] = pos;
    s->orientation[q] = qo;
    s->velocity[q] = v;
    s->angmom[q] = cd_rigid_angmom(qo, w, s->inertia[q]);
}

/* Steps and brings the host copy of the state up to date. */
static inline void cdt_step(cd_sim *sim, long long n)
{
    char err[1024];
    if (cd_sim_step(sim, n, err, sizeof err)) fail_msg("step: %s", err);
    if (cd_sim_sync(sim, err, sizeof err)) fail_msg("sync: %s", err);
}

static inline double cdt_total_energy(const cd_sim *sim)
{
    cd_observables o;
    cd_sim_observe(sim, &o);
    return o.kinetic_translational + o.kinetic_rotational + o.elastic + o.potential;
}

#endif
