/* Radial compaction (docs/references.md, Protocols, docs/protocols.md): particles in a
 * ball whose radius is driven by the applied pressure, m_w R'' = sum f_i -
 * p 4 pi R^2, until the packing has relaxed.  The bulk probe
 * (protocol_bulk.c) starts with the same compaction. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "protocols/protocol_internal.h"

int cd_proto_ball_check(const cd_config *c, char *err, size_t errlen)
{
    if (c->domain_kind != CD_DOMAIN_BALL) {
        snprintf(err, errlen, "%s: protocol.type = %s: expected domain.type ball, not %s", c->source_path, c->protocol,
                 c->domain);
        return -1;
    }
    return 0;
}

/* Pressure on the ball [Pa]: given, or p L / kn = pressure_ratio (Tran et al. 2024). */
static double ball_pressure(const cd_sim *sim)
{
    if (sim->cfg.pressure > 0) return sim->cfg.pressure;
    double L = 0;
    for (int k = 0; k < sim->n_shapes; k++)
        if (sim->shapes[k].tip_length > L) L = sim->shapes[k].tip_length;
    return sim->cfg.pressure_ratio * sim->cfg.kn / L;
}

/* A row's vector at column k of cd_proto_motion_rows. */
static cd_vec3 row_vec(const double *row, int k) { return cd_v3(row[k], row[k + 1], row[k + 2]); }

/* The centre-of-mass velocity [m/s] (out[0..2]) and the rigid rotation
 * about centre [1/s] (out[3..5]; out[6] = 1 where it is defined) of the
 * motion of n particles (rows of cd_proto_motion_rows, global order).
 * The sums run in particle order: the bits of the serial program at any
 * rank count. */
static void net_motion(const double *rows, size_t n, cd_vec3 centre, double out[7])
{
    double M = 0, P[3] = {0, 0, 0}, L[3] = {0, 0, 0}, I[3][3] = {{0}};
    for (size_t q = 0; q < n; q++) {
        const double *row = rows + q * CD_MOTION_WIDTH;
        double m = row[CD_MOTION_MASS];
        M += m;
        P[0] += m * row[CD_MOTION_VELOCITY];
        P[1] += m * row[CD_MOTION_VELOCITY + 1];
        P[2] += m * row[CD_MOTION_VELOCITY + 2];
    }
    cd_vec3 vcm = cd_v3(P[0] / M, P[1] / M, P[2] / M);
    for (size_t q = 0; q < n; q++) {
        const double *row = rows + q * CD_MOTION_WIDTH;
        cd_vec3 v = cd_v3_sub(row_vec(row, CD_MOTION_VELOCITY), vcm);
        double m = row[CD_MOTION_MASS];
        cd_vec3 r = cd_v3_sub(row_vec(row, CD_MOTION_POSITION), centre);
        cd_vec3 l = cd_v3_add(cd_v3_scale(cd_v3_cross(r, v), m), row_vec(row, CD_MOTION_ANGMOM));
        L[0] += l.x;
        L[1] += l.y;
        L[2] += l.z;
        double rr[3] = {r.x, r.y, r.z}, r2 = cd_v3_norm2(r);
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) I[a][b] += m * ((a == b ? r2 : 0) - rr[a] * rr[b]);
    }
    out[0] = vcm.x;
    out[1] = vcm.y;
    out[2] = vcm.z;
    out[3] = out[4] = out[5] = out[6] = 0;
    /* omega = I^-1 L by Cramer's rule (I is positive definite for more than
     * two particles not on a line) */
    double det = I[0][0] * (I[1][1] * I[2][2] - I[1][2] * I[2][1]) - I[0][1] * (I[1][0] * I[2][2] - I[1][2] * I[2][0]) +
                 I[0][2] * (I[1][0] * I[2][1] - I[1][1] * I[2][0]);
    if (!(fabs(det) > 0)) return;
    for (int c = 0; c < 3; c++) {
        double A[3][3];
        memcpy(A, I, sizeof A);
        for (int a = 0; a < 3; a++) A[a][c] = L[a];
        out[3 + c] =
            (A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
             A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0])) /
            det;
    }
    out[6] = 1;
}

/* Removes the centre-of-mass velocity and the rigid rotation about the
 * ball centre from the initial velocities.  Inside a frictionless ball and
 * without gravity both are conserved: a packing that starts with some net
 * angular momentum keeps turning as a whole for ever, and its kinetic
 * energy never falls below the relaxation criterion.  Each particle is
 * changed where it is (every MPI rank its own rows and ghosts). */
static int remove_net_motion(cd_sim *sim, cd_vec3 centre, char *err, size_t errlen)
{
    double *rows, motion[7] = {0};
    size_t n;
    if (cd_proto_motion_rows(sim, &rows, &n, err, errlen)) return -1;
    if (rows) net_motion(rows, n, centre, motion);
    free(rows);
    cd_mpi_share(motion, 7);
    cd_state *s = &sim->s;
    cd_vec3 vcm = cd_v3(motion[0], motion[1], motion[2]), omega = cd_v3(motion[3], motion[4], motion[5]);
    for (size_t q = 0; q < s->n_particles; q++) {
        s->velocity[q] = cd_v3_sub(s->velocity[q], vcm);
        if (motion[6])
            s->velocity[q] = cd_v3_sub(s->velocity[q], cd_v3_cross(omega, cd_v3_sub(s->position[q], centre)));
    }
    return 0;
}

int cd_proto_ball_begin(cd_sim *sim, char *err, size_t errlen)
{
    sim->s.control[CTL_WALL] = 0;
    if (remove_net_motion(sim, sim->s.walls[0].point, err, errlen)) return -1;
    cd_proto_enter(sim, CD_PHASE_COMPACT, NULL);
    return 0;
}

int cd_proto_compact(cd_sim *sim, double load, char *err, size_t errlen, int *done)
{
    cd_state *s = &sim->s;
    int w = (int)s->control[CTL_WALL];
    /* m_w R'' = sum f_i - p 4 pi R^2, m_w the total particle mass */
    double R = s->walls[w].radius;
    double a = (load - ball_pressure(sim) * 4 * CD_PI * R * R) / sim->total_mass;
    s->walls[w].radial_velocity += a * sim->p.dt;
    return cd_proto_relaxed(sim, err, errlen, done);
}

static long long steps_until_control(const cd_sim *sim, int phase)
{
    (void)sim;
    (void)phase;
    return 1; /* the ball responds to the load every step */
}

static int control(cd_sim *sim, int phase, double load, FILE *log, char *err, size_t errlen)
{
    int done = 0;
    if (phase != CD_PHASE_COMPACT) return 0;
    if (cd_proto_compact(sim, load, err, errlen, &done)) return -1;
    if (done) cd_proto_enter(sim, CD_PHASE_DONE, log);
    return 0;
}

const cd_protocol_ops cd_protocol_radial = {cd_proto_ball_check, cd_proto_ball_begin, steps_until_control, control,
                                            NULL};
