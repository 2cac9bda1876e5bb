/* Deposit and compress (docs/references.md, Protocols, docs/protocols.md): the particles
 * settle under gravity in a box or cylinder, a piston comes down at
 * protocol.piston_speed until it carries protocol.piston_force, then holds
 * that load (or its position) until the packing has relaxed. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "protocols/protocol_internal.h"

static int check(const cd_config *c, char *err, size_t errlen)
{
    if (c->domain_kind != CD_DOMAIN_BOX && c->domain_kind != CD_DOMAIN_CYLINDER) {
        snprintf(err, errlen, "%s: protocol.type = deposit_compress: expected domain.type box or cylinder, not %s",
                 c->source_path, c->domain);
        return -1;
    }
    if (!(c->gravity[0] != 0 || c->gravity[1] != 0 || c->gravity[2] != 0)) {
        snprintf(err, errlen, "%s: physics.gravity = [0, 0, 0]: deposit_compress needs gravity to deposit",
                 c->source_path);
        return -1;
    }
    return 0;
}

/* Removes the rigid rotation about the cylinder axis (the y axis through
 * x = z = 0) from the initial velocities.  Frictionless cylinder walls,
 * floor and piston exert no torque about that axis, and neither does
 * gravity: the angular momentum about it is conserved, so a packing that
 * starts with some (random velocities of a finite sample do) turns for
 * ever, its kinetic energy never falls below the relaxation criterion. */
static int remove_axial_rotation(cd_sim *sim, char *err, size_t errlen)
{
    double *rows, w[2] = {0, 0}; /* the rotation [1/s], and 1 where it is defined */
    size_t n;
    if (cd_proto_motion_rows(sim, &rows, &n, err, errlen)) return -1;
    if (rows) {              /* the sums in particle order: the serial bits at any MPI rank count */
        double L = 0, I = 0; /* [kg m^2/s], [kg m^2] */
        for (size_t q = 0; q < n; q++) {
            const double *row = rows + q * CD_MOTION_WIDTH, m = row[CD_MOTION_MASS];
            const double *r = row + CD_MOTION_POSITION, *v = row + CD_MOTION_VELOCITY;
            L += m * (r[2] * v[0] - r[0] * v[2]) + row[CD_MOTION_ANGMOM + 1];
            I += m * (r[0] * r[0] + r[2] * r[2]);
        }
        if (I > 0) w[0] = L / I, w[1] = 1;
    }
    free(rows);
    cd_mpi_share(w, 2);
    cd_state *s = &sim->s;
    for (size_t q = 0; w[1] && q < s->n_particles; q++) {
        s->velocity[q].x -= w[0] * s->position[q].z;
        s->velocity[q].z += w[0] * s->position[q].x;
    }
    return 0;
}

/* Whether the begin removes the rotation about the cylinder axis (a
 * frictionless cylinder). */
static int removes_rotation(const cd_config *c)
{
    return c->domain_kind == CD_DOMAIN_CYLINDER && c->wall_friction == 0;
}

static int begin(cd_sim *sim, char *err, size_t errlen)
{
    /* the piston is the last wall: the box's top wall, or the one added
     * over the cylinder */
    sim->s.control[CTL_WALL] = sim->cfg.domain_kind == CD_DOMAIN_BOX ? 1 : (double)(sim->s.n_walls - 1);
    if (removes_rotation(&sim->cfg) && remove_axial_rotation(sim, err, errlen)) return -1;
    cd_proto_enter(sim, CD_PHASE_SETTLE, NULL);
    return 0;
}

static double settle_time(const cd_sim *sim)
{
    if (sim->cfg.settle_time > 0) return sim->cfg.settle_time;
    const double *g = sim->cfg.gravity;
    double h = sim->cfg.domain_kind == CD_DOMAIN_BOX ? sim->cfg.box_height : sim->cfg.cyl_height; /* [m] */
    return 3 * sqrt(2 * h / sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]));
}

static long long steps_until_control(const cd_sim *sim, int phase)
{
    if (phase == CD_PHASE_SETTLE) {
        double left = sim->s.control[CTL_PHASE_TIME] + settle_time(sim) - sim->s.time;
        long long n = (long long)ceil(left / sim->p.dt);
        return n > 1 ? n : 1;
    }
    return 1; /* compress, hold: the piston responds to the load every step */
}

/* Deposit, protocol.piston_start = packing: moves the parked piston down
 * to one particle size (the largest bounding diameter, polydispersity
 * included) above the highest
 * point of any particle.  Conzelmann et al. start the piston at the top of the
 * domain, but the domain is as high as the initial lattice, several times
 * the settled packing: the piston would cross metres of empty space at
 * 0.25 m/s (millions of steps) before touching anything.  Starting just
 * above the packing changes nothing the packing feels. */
static int lower_piston(cd_sim *sim, int w, char *err, size_t errlen)
{
    if (cd_sim_sync(sim, err, errlen)) return -1;
    const cd_state *s = &sim->s;
    double top = -INFINITY, size = 0; /* [m] */
    for (size_t i = 0; i < s->n_prims; i++) {
        double y = fmax(s->prim_a[i].y, s->prim_b[i].y) + s->prim_radius[i];
        if (y > top) top = y;
    }
    for (int k = 0; k < sim->n_shapes; k++)
        size = fmax(size, 2 * sim->shapes[k].bounding_radius * (1 + sim->cfg.species[k].polydispersity));
    double start = top + size;
    if (start < sim->s.walls[w].point.y) sim->s.walls[w].point.y = start;
    return 0;
}

/* Deposit: the compressed packing's height (the piston's) against the
 * container width, which Conzelmann et al. want to be at least 2. */
static void report_fill(const cd_sim *sim, FILE *log)
{
    const cd_config *c = &sim->cfg;
    double width = c->domain_kind == CD_DOMAIN_BOX ? c->box_width : c->cyl_diameter; /* [m] */
    double h = sim->s.walls[(int)sim->s.control[CTL_WALL]].point.y;                  /* [m] */
    if (!log) return;
    fprintf(log, "capdem: packing height %.6g m = %.3g x the %s\n", h, h / width,
            c->domain_kind == CD_DOMAIN_BOX ? "width" : "diameter");
    if (c->fill_ratio > 0 && h / width < c->fill_ratio)
        fprintf(
            log,
            "capdem: warning: below protocol.fill_ratio = %g: the packing is denser than protocol.fill_fraction = %g "
            "expected; set fill_fraction to the packing_fraction this run reached (time series)\n",
            c->fill_ratio, c->fill_fraction);
}

static int control(cd_sim *sim, int phase, double load, FILE *log, char *err, size_t errlen)
{
    cd_state *s = &sim->s;
    int w = (int)s->control[CTL_WALL], done = 0;
    double dt = sim->p.dt;
    switch (phase) {
    case CD_PHASE_SETTLE:
        if (s->time >= s->control[CTL_PHASE_TIME] + settle_time(sim) - 0.5 * dt) {
            if (!sim->cfg.piston_from_top && lower_piston(sim, w, err, errlen)) return -1;
            cd_proto_enter(sim, CD_PHASE_COMPRESS, log);
            s->walls[w].velocity = cd_v3_scale(s->walls[w].normal, sim->cfg.piston_speed);
        }
        break;
    case CD_PHASE_COMPRESS:
        if (load >= sim->cfg.piston_force) {
            cd_proto_enter(sim, CD_PHASE_HOLD, log);
            s->walls[w].velocity = cd_v3_zero();
        }
        break;
    case CD_PHASE_HOLD: {
        /* piston_hold load: m_p x'' = (load - F) along the outward direction;
         * position: the piston stays where it stopped */
        if (sim->cfg.piston_hold_position) {
            s->walls[w].velocity = cd_v3_zero();
        } else {
            double m = sim->cfg.piston_mass > 0 ? sim->cfg.piston_mass : sim->total_mass;
            double a = (load - sim->cfg.piston_force) / m; /* [m/s^2], positive outwards */
            s->walls[w].velocity = cd_v3_axpy(s->walls[w].velocity, -a * dt, s->walls[w].normal);
        }
        if (cd_proto_relaxed(sim, err, errlen, &done)) return -1;
        if (done) {
            cd_proto_enter(sim, CD_PHASE_DONE, log);
            report_fill(sim, log);
        }
        break;
    }
    default:
        break;
    }
    return 0;
}

const cd_protocol_ops cd_protocol_deposit = {check, begin, steps_until_control, control, NULL};
