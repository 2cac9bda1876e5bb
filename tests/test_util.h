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

/* 24 alpha-3 hexapods settling on the floor of a cylinder with friction
 * (pair and wall contacts, tangential history, rebuilds): the config of
 * test_wall_out and test_force_summed. */
#define CDT_PILE_IN_CYLINDER                                                                                           \
    "run: {dt: 1.0e-5, steps: 0, seed: 3}\n"                                                                           \
    "physics: {gravity: [0, -98.1, 0]}\n"                                                                              \
    "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0.2, friction: 0.5, wall_friction: 0.4}\n"        \
    "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 24, polydispersity: 0.2}]\n"                      \
    "domain: {type: cylinder, diameter: 0.06, height: 0.12}\n"                                                         \
    "init: {placement: lattice, clearance: 1.0, speed: 0.3}\n"

/* What is wrong with visit (n entries) as the pair pass's visiting order
 * (kernels/neighbor_items.h, pass 11), kind[k] being the kind of row k
 * (0..2): NULL when it is a permutation of 0 .. n-1 that takes the rows
 * kind by kind (kinds ascending), with ascending = 1 each kind's rows in
 * ascending order (0: rows indexed in another order than the one the
 * order was made in, the user order of rows kept in a memory order);
 * else a message (static storage). */
static inline const char *cdt_visit_order_defect(const cd_int *visit, const cd_int *kind, size_t n, int ascending)
{
    static char msg[160];
    unsigned char *seen = calloc(n + 1, 1);
    if (!seen) return "out of memory";
    const char *bad = NULL;
    for (size_t v = 0; v < n && !bad; v++) {
        cd_int r = visit[v], prev = v ? visit[v - 1] : -1;
        if (r < 0 || (size_t)r >= n || seen[r]) {
            snprintf(msg, sizeof msg, "entry %zu: row %d out of range or seen twice: not a permutation", v, (int)r);
            bad = msg;
        } else if (v && (kind[r] < kind[prev] || (ascending && kind[r] == kind[prev] && r < prev))) {
            snprintf(msg, sizeof msg,
                     "entry %zu: row %d (kind %d) after row %d (kind %d): not grouped by kind in row order", v, (int)r,
                     (int)kind[r], (int)prev, (int)kind[prev]);
            bad = msg;
        }
        if (!bad) seen[r] = 1;
    }
    free(seen);
    return bad;
}

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
