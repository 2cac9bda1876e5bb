/* Protocols of SPEC section 6; see protocol.h and docs/protocols.md. */
#include <math.h>
#include <string.h>
#include "protocol.h"
#include "io_h5.h"

/* Slots of sim->s.control. */
enum {
    CTL_PHASE,       /* CD_PHASE_* */
    CTL_PHASE_TIME,  /* simulated time at which the phase began [s] */
    CTL_WALL,        /* index of the driven wall (piston or ball) */
    CTL_EEL_LAST,    /* elastic energy at the last relaxation check [J] */
    CTL_LOAD,        /* last normal load on the driven wall [N] */
    CTL_R_BASE,      /* bulk: ball radius of the base state [m] */
    CTL_P_BASE,      /* bulk: pressure of the base state [Pa] */
    CTL_STRAIN,      /* bulk: current volumetric strain -dV/V [1] */
    CTL_PROBE_STEP,  /* bulk: step at which the current probe began */
    CTL_N_PROBES,    /* bulk: probes done */
    CTL_P_SUM,       /* bulk: sum of pressure samples over the second half of a window [Pa] */
    CTL_P_COUNT,     /* bulk: number of those samples */
    CTL_BASE_STEP,   /* bulk: step of the base state every probe starts from (a snapshot holds it) */
    CTL_RATIO_MAX,   /* relax_sample > 0: largest kinetic / elastic energy sampled since the last check [1] */
    CTL_K_FIRST = 16 /* bulk: K of probe k in slot CTL_K_FIRST + k [Pa] */
};
#define CTL_MAX_PROBES (CD_CONTROL_SLOTS - CTL_K_FIRST)

static int phase_of(const cd_sim *sim) { return (int)sim->s.control[CTL_PHASE]; }

const char *cd_protocol_phase_name(int phase)
{
    static const char *const names[] = {"free", "settle", "compress", "hold", "compact", "base", "probe", "done"};
    return phase >= 0 && phase <= CD_PHASE_DONE ? names[phase] : "?";
}

int cd_protocol_check(const cd_config *c, char *err, size_t errlen)
{
    enum cd_protocol_kind p = c->protocol_kind;
    if (p == CD_PROTOCOL_DEPOSIT && c->domain_kind != CD_DOMAIN_BOX && c->domain_kind != CD_DOMAIN_CYLINDER) {
        snprintf(err, errlen, "%s: protocol.type = deposit_compress: expected domain.type box or cylinder, not %s",
                 c->source_path, c->domain);
        return -1;
    }
    if ((p == CD_PROTOCOL_RADIAL || p == CD_PROTOCOL_BULK) && c->domain_kind != CD_DOMAIN_BALL) {
        snprintf(err, errlen, "%s: protocol.type = %s: expected domain.type ball, not %s", c->source_path, c->protocol,
                 c->domain);
        return -1;
    }
    if (p == CD_PROTOCOL_DEPOSIT && !(c->gravity[0] != 0 || c->gravity[1] != 0 || c->gravity[2] != 0)) {
        snprintf(err, errlen, "%s: physics.gravity = [0, 0, 0]: deposit_compress needs gravity to deposit", c->source_path);
        return -1;
    }
    if (p == CD_PROTOCOL_BULK && c->strain_min > c->strain_max) {
        snprintf(err, errlen, "%s: protocol.strain_min = %g: expected at most protocol.strain_max = %g", c->source_path,
                 c->strain_min, c->strain_max);
        return -1;
    }
    return 0;
}

/* Pressure on the ball [Pa]: given, or p L / kn = pressure_ratio (seed 001). */
static double ball_pressure(const cd_sim *sim)
{
    if (sim->cfg.pressure > 0) return sim->cfg.pressure;
    double L = 0;
    for (int k = 0; k < sim->n_shapes; k++)
        if (sim->shapes[k].tip_length > L) L = sim->shapes[k].tip_length;
    return sim->cfg.pressure_ratio * sim->cfg.kn / L;
}

static void enter(cd_sim *sim, int phase, FILE *log)
{
    sim->s.control[CTL_PHASE] = phase;
    sim->s.control[CTL_PHASE_TIME] = sim->s.time;
    sim->s.control[CTL_EEL_LAST] = -1;
    sim->s.control[CTL_RATIO_MAX] = 0;
    if (log)
        fprintf(log, "\ncapdem: protocol phase %s at step %lld (t = %.6g s)\n", cd_protocol_phase_name(phase),
                sim->s.step, sim->s.time);
}

/* Removes the centre-of-mass velocity and the rigid rotation about the
 * ball centre from the initial velocities.  Inside a frictionless ball and
 * without gravity both are conserved: a packing that starts with some net
 * angular momentum keeps turning as a whole for ever, and its kinetic
 * energy never falls below the relaxation criterion. */
static void remove_net_motion(cd_sim *sim, cd_vec3 centre)
{
    cd_state *s = &sim->s;
    double M = 0, P[3] = {0, 0, 0}, L[3] = {0, 0, 0}, I[3][3] = {{0}};
    for (size_t q = 0; q < s->n_particles; q++) {
        double m = s->mass[q];
        M += m;
        P[0] += m * s->velocity[q].x; P[1] += m * s->velocity[q].y; P[2] += m * s->velocity[q].z;
    }
    cd_vec3 vcm = cd_v3(P[0] / M, P[1] / M, P[2] / M);
    for (size_t q = 0; q < s->n_particles; q++) {
        s->velocity[q] = cd_v3_sub(s->velocity[q], vcm);
        double m = s->mass[q];
        cd_vec3 r = cd_v3_sub(s->position[q], centre);
        cd_vec3 l = cd_v3_add(cd_v3_scale(cd_v3_cross(r, s->velocity[q]), m), s->angmom[q]);
        L[0] += l.x; L[1] += l.y; L[2] += l.z;
        double rr[3] = {r.x, r.y, r.z}, r2 = cd_v3_norm2(r);
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) I[a][b] += m * ((a == b ? r2 : 0) - rr[a] * rr[b]);
    }
    /* omega = I^-1 L by Cramer's rule (I is positive definite for more than
     * two particles not on a line) */
    double det = I[0][0] * (I[1][1] * I[2][2] - I[1][2] * I[2][1]) - I[0][1] * (I[1][0] * I[2][2] - I[1][2] * I[2][0]) +
                 I[0][2] * (I[1][0] * I[2][1] - I[1][1] * I[2][0]);
    if (!(fabs(det) > 0)) return;
    double w[3];
    for (int c = 0; c < 3; c++) {
        double A[3][3];
        memcpy(A, I, sizeof A);
        for (int a = 0; a < 3; a++) A[a][c] = L[a];
        w[c] = (A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0])) / det;
    }
    cd_vec3 omega = cd_v3(w[0], w[1], w[2]);
    for (size_t q = 0; q < s->n_particles; q++)
        s->velocity[q] = cd_v3_sub(s->velocity[q], cd_v3_cross(omega, cd_v3_sub(s->position[q], centre)));
}

/* Removes the rigid rotation about the cylinder axis (the y axis through
 * x = z = 0) from the initial velocities.  Frictionless cylinder walls,
 * floor and piston exert no torque about that axis, and neither does
 * gravity: the angular momentum about it is conserved, so a packing that
 * starts with some (random velocities of a finite sample do) turns for
 * ever, its kinetic energy never falls below the relaxation criterion. */
static void remove_axial_rotation(cd_sim *sim)
{
    cd_state *s = &sim->s;
    double L = 0, I = 0; /* [kg m^2/s], [kg m^2] */
    for (size_t q = 0; q < s->n_particles; q++) {
        cd_vec3 r = s->position[q], v = s->velocity[q];
        L += s->mass[q] * (r.z * v.x - r.x * v.z) + s->angmom[q].y;
        I += s->mass[q] * (r.x * r.x + r.z * r.z);
    }
    if (!(I > 0)) return;
    double w = L / I; /* [1/s] */
    for (size_t q = 0; q < s->n_particles; q++) {
        s->velocity[q].x -= w * s->position[q].z;
        s->velocity[q].z += w * s->position[q].x;
    }
}

void cd_protocol_begin(cd_sim *sim)
{
    enum cd_protocol_kind p = sim->cfg.protocol_kind;
    memset(sim->s.control, 0, sizeof sim->s.control);
    if (p == CD_PROTOCOL_DEPOSIT) {
        /* the piston is the last wall: the box's top wall, or the one added
         * over the cylinder */
        sim->s.control[CTL_WALL] = sim->cfg.domain_kind == CD_DOMAIN_BOX ? 1 : (double)(sim->s.n_walls - 1);
        if (sim->cfg.domain_kind == CD_DOMAIN_CYLINDER && sim->cfg.wall_friction == 0) remove_axial_rotation(sim);
        enter(sim, CD_PHASE_SETTLE, NULL);
    } else if (p == CD_PROTOCOL_RADIAL || p == CD_PROTOCOL_BULK) {
        sim->s.control[CTL_WALL] = 0;
        remove_net_motion(sim, sim->s.walls[0].point);
        enter(sim, CD_PHASE_COMPACT, NULL);
    } else {
        enter(sim, CD_PHASE_FREE, NULL);
    }
}

static double settle_time(const cd_sim *sim)
{
    if (sim->cfg.settle_time > 0) return sim->cfg.settle_time;
    const double *g = sim->cfg.gravity;
    double h = sim->cfg.domain_kind == CD_DOMAIN_BOX ? sim->cfg.box_height : sim->cfg.cyl_height; /* [m] */
    return 3 * sqrt(2 * h / sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]));
}

long long cd_protocol_steps_until_control(const cd_sim *sim)
{
    switch (phase_of(sim)) {
    case CD_PHASE_SETTLE: {
        double left = sim->s.control[CTL_PHASE_TIME] + settle_time(sim) - sim->s.time;
        long long n = (long long)ceil(left / sim->p.dt);
        return n > 1 ? n : 1;
    }
    case CD_PHASE_COMPRESS:
    case CD_PHASE_HOLD:
    case CD_PHASE_COMPACT: return 1; /* the driven wall responds to the load every step */
    case CD_PHASE_BASE: {
        long long n = sim->cfg.check_every - (sim->s.step % sim->cfg.check_every);
        long long m = sim->cfg.relax_sample > 0 ? sim->cfg.relax_sample - (sim->s.step % sim->cfg.relax_sample) : n;
        return n < m ? n : m;
    }
    case CD_PHASE_PROBE: {
        /* the pressure is averaged every step of the window's second half;
         * the ball is fixed, so nothing needs the load before that */
        long long elapsed = sim->s.step - (long long)sim->s.control[CTL_PROBE_STEP];
        long long half = (sim->cfg.probe_steps + 1) / 2;
        return elapsed < half ? half - elapsed : 1;
    }
    default: return 1LL << 40;
    }
}

/* Bulk probe: the pressure on the ball averaged over the second half of a
 * window of probe_steps steps that began at control[CTL_PROBE_STEP].  The
 * relaxed packing still vibrates a little; the average removes most of it.
 * Returns 1 when the window is complete (mean in *p). */
static int window_pressure(cd_sim *sim, double load, double *p)
{
    double *c = sim->s.control;
    double R = sim->s.walls[(int)c[CTL_WALL]].radius;
    double elapsed = (double)sim->s.step - c[CTL_PROBE_STEP], n = (double)sim->cfg.probe_steps;
    if (elapsed >= 0.5 * n) {
        c[CTL_P_SUM] += load / (4 * CD_PI * R * R);
        c[CTL_P_COUNT] += 1;
    }
    if (elapsed < n) return 0;
    *p = c[CTL_P_SUM] / c[CTL_P_COUNT];
    c[CTL_P_SUM] = c[CTL_P_COUNT] = 0;
    return 1;
}

/* Kinetic energy of the wall the protocol drives [J]: the piston or the
 * ball is a body too, and a packing is not at rest while it still swings. */
static double driven_wall_energy(const cd_sim *sim)
{
    const cd_wall *w = &sim->s.walls[(int)sim->s.control[CTL_WALL]];
    int deposit = sim->cfg.protocol_kind == CD_PROTOCOL_DEPOSIT;
    double m = deposit && sim->cfg.piston_mass > 0 ? sim->cfg.piston_mass : sim->total_mass;
    double v2 = deposit ? cd_v3_norm2(w->velocity) : w->radial_velocity * w->radial_velocity;
    return 0.5 * m * v2;
}

/* Relaxed: kinetic energy of the particles in contact below relax_ratio of
 * the elastic energy and the elastic energy steady since the last check
 * (checked every check_every steps).  Rattlers are left out: without gravity
 * and friction they can tumble in their cages indefinitely.  With
 * relax_sample > 0 the ratio is also sampled every relax_sample steps and a
 * check passes only if the largest sample since the previous check (the
 * check's own included) is below relax_ratio: a packing that still swings
 * as a whole has kinetic energy near zero twice a period, and a check that
 * falls there would otherwise pass it. */
static int relaxed(cd_sim *sim, char *err, size_t errlen, int *done)
{
    *done = 0;
    long long sample = sim->cfg.relax_sample;
    int at_check = sim->s.step % sim->cfg.check_every == 0;
    int at_sample = sample > 0 && sim->s.step % sample == 0;
    if (!at_check && !at_sample) return 0;
    cd_observables o; /* summed where the steps run: no state copy */
    if (cd_sim_observe_step(sim, &o, err, errlen)) return -1;
    double ke = o.kinetic_in_contact + driven_wall_energy(sim), eel = o.elastic, last = sim->s.control[CTL_EEL_LAST];
    double *worst = &sim->s.control[CTL_RATIO_MAX];
    if (sample > 0) *worst = fmax(*worst, eel > 0 ? ke / eel : INFINITY);
    if (!at_check) return 0;
    int quiet = sample > 0 ? *worst < sim->cfg.relax_ratio : ke < sim->cfg.relax_ratio * eel;
    *done = eel > 0 && quiet && last > 0 && fabs(eel - last) < sim->cfg.energy_tolerance * eel;
    sim->s.control[CTL_EEL_LAST] = eel;
    *worst = 0;
    return 0;
}

/* Deposit, protocol.piston_start = packing: moves the parked piston down
 * to one particle size (the largest bounding diameter, polydispersity
 * included) above the highest
 * point of any particle.  Seed 000 starts the piston at the top of the
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
 * container width, which seed 000 wants to be at least 2. */
static void report_fill(const cd_sim *sim, FILE *log)
{
    const cd_config *c = &sim->cfg;
    double width = c->domain_kind == CD_DOMAIN_BOX ? c->box_width : c->cyl_diameter; /* [m] */
    double h = sim->s.walls[(int)sim->s.control[CTL_WALL]].point.y;          /* [m] */
    if (!log) return;
    fprintf(log, "capdem: packing height %.6g m = %.3g x the %s\n", h, h / width, c->domain_kind == CD_DOMAIN_BOX ? "width" : "diameter");
    if (c->fill_ratio > 0 && h / width < c->fill_ratio)
        fprintf(log, "capdem: warning: below protocol.fill_ratio = %g: the packing is denser than protocol.fill_fraction = %g "
                "expected; set fill_fraction to the packing_fraction this run reached (time series)\n", c->fill_ratio, c->fill_fraction);
}

/* Bulk probe: puts the base state back (every column and the walls; the
 * step, time and protocol state go on), then scales the particle positions
 * about the ball centre and the ball radius to the volumetric strain
 * eps = -dV/V (eps = 0: the reference window, unstrained).  The state is
 * handed to the backend as a resumed run (forces kept, list rebuilt): the
 * strained packing feels the new positions from the next force
 * evaluation on.  Every window, the reference included, starts this way
 * from the same base state, so the reference and the strained runs differ
 * only by the strain: whatever the base state still does (creep,
 * vibration) is the same in both and cancels in p - p_ref. */
static int apply_strain(cd_sim *sim, double eps, char *err, size_t errlen)
{
    cd_state *s = &sim->s;
    double control[CD_CONTROL_SLOTS], time = s->time;
    long long step = s->step;
    memcpy(control, s->control, sizeof control);
    if (sim->backend) sim->backend->stop(sim);
    if (cd_state_copy(s, &sim->probe_base)) {
        snprintf(err, errlen, "out of memory restoring the base state of the bulk probe");
        return -1;
    }
    memcpy(s->control, control, sizeof control);
    s->time = time;
    s->step = step;
    int w = (int)s->control[CTL_WALL];
    if (eps > 0) {
        double r_new = s->control[CTL_R_BASE] * cbrt(1 - eps);
        double f = r_new / s->walls[w].radius;
        cd_vec3 c = s->walls[w].point;
        for (size_t q = 0; q < s->n_particles; q++) s->position[q] = cd_v3_axpy(c, f, cd_v3_sub(s->position[q], c));
        s->walls[w].radius = r_new;
    }
    s->control[CTL_STRAIN] = eps;
    s->control[CTL_PROBE_STEP] = (double)step;
    return cd_sim_start(sim, 0, err, errlen);
}

/* Bulk probe: keeps the relaxed base state (host copy) and asks the run
 * for a snapshot of it, from which a resumed run gets it back.  The base
 * state is put at rest first (every velocity and angular momentum zero):
 * the relaxation criterion leaves out the particles without contacts, and
 * these rattlers keep nearly all the kinetic energy of a "relaxed" packing
 * (CI twin, seeds 1-8: > 99 %, 0.8e-9 to 1.3e-8 J against ~1e-11 J in
 * the particles that touch something).
 * Bouncing in their cages they make the strained run diverge from the
 * reference run chaotically, whatever the strain, and add to p - p_ref an
 * offset of order 1e-4 Pa that does not scale with the strain (K wrong by
 * tens of per cent at 1e-9); the residual motion can also carry a marginal
 * packing over a barrier (a CI seed fell from 66.7 to 29 Pa in every
 * window, the reference included).  From rest the rattlers stay put and
 * the packing only relaxes its residual contact forces, the same in every
 * window. */
static int save_base(cd_sim *sim, char *err, size_t errlen)
{
    if (cd_sim_sync(sim, err, errlen)) return -1;
    for (size_t q = 0; q < sim->s.n_particles; q++)
        sim->s.velocity[q] = sim->s.angmom[q] = sim->s.angvel[q] = cd_v3_zero();
    sim->s.control[CTL_BASE_STEP] = (double)sim->s.step;
    if (cd_state_copy(&sim->probe_base, &sim->s)) {
        snprintf(err, errlen, "out of memory keeping the base state of the bulk probe");
        return -1;
    }
    sim->snapshot_request = 1;
    return 0;
}

/* Is v a whole number in lo..hi? (a NaN is not) */
static int whole_in(double v, double lo, double hi) { return v >= lo && v <= hi && v == floor(v); }

int cd_protocol_resume(cd_sim *sim, const char *path, char *err, size_t errlen)
{
    /* The protocol state comes from the file: slots used as indices are
     * checked before they index anything (a crafted file is refused). */
    const double *c = sim->s.control;
    if (!whole_in(c[CTL_PHASE], CD_PHASE_FREE, CD_PHASE_DONE) ||
        !whole_in(c[CTL_WALL], 0, sim->s.n_walls ? (double)sim->s.n_walls - 1 : 0) ||
        !whole_in(c[CTL_N_PROBES], 0, CTL_MAX_PROBES)) {
        snprintf(err, errlen, "%s: dataset /walls/control holds phase %g, wall %g, probes %g: not a state the protocol "
                 "can be in (phases %d..%d, walls 0..%zu, probes 0..%d); the file is refused", path, c[CTL_PHASE],
                 c[CTL_WALL], c[CTL_N_PROBES], CD_PHASE_FREE, CD_PHASE_DONE, sim->s.n_walls ? sim->s.n_walls - 1 : 0,
                 CTL_MAX_PROBES);
        return -1;
    }
    if (phase_of(sim) != CD_PHASE_PROBE || sim->probe_base.position) return 0;
    long long base_step = (long long)sim->s.control[CTL_BASE_STEP];
    if (cd_state_copy(&sim->probe_base, &sim->s)) {
        snprintf(err, errlen, "out of memory reading the base state of the bulk probe");
        return -1;
    }
    for (int k = cd_h5_snapshot_count(path, err, errlen) - 1; k >= 0; k--) {
        if (cd_h5_read_snapshot(path, k, &sim->probe_base, err, errlen)) return -1;
        if (sim->probe_base.step == base_step) return 0;
        if (sim->probe_base.step < base_step) break;
    }
    snprintf(err, errlen, "%s: no snapshot of step %lld, the base state of the bulk probe; resume from an earlier checkpoint",
             path, base_step);
    return -1;
}

int cd_protocol_control(cd_sim *sim, FILE *log, char *err, size_t errlen)
{
    cd_state *s = &sim->s;
    int phase = phase_of(sim), w = (int)s->control[CTL_WALL], done = 0;
    double dt = sim->p.dt, load = 0;
    if (phase == CD_PHASE_FREE || phase == CD_PHASE_DONE) return phase == CD_PHASE_DONE;
    if (phase != CD_PHASE_SETTLE && cd_sim_wall_load(sim, w, &load, err, errlen)) return -1;
    s->control[CTL_LOAD] = load;
    switch (phase) {
    case CD_PHASE_SETTLE:
        if (s->time >= s->control[CTL_PHASE_TIME] + settle_time(sim) - 0.5 * dt) {
            if (!sim->cfg.piston_from_top && lower_piston(sim, w, err, errlen)) return -1;
            enter(sim, CD_PHASE_COMPRESS, log);
            s->walls[w].velocity = cd_v3_scale(s->walls[w].normal, sim->cfg.piston_speed);
        }
        break;
    case CD_PHASE_COMPRESS:
        if (load >= sim->cfg.piston_force) {
            enter(sim, CD_PHASE_HOLD, log);
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
        if (relaxed(sim, err, errlen, &done)) return -1;
        if (done) {
            enter(sim, CD_PHASE_DONE, log);
            report_fill(sim, log);
        }
        break;
    }
    case CD_PHASE_COMPACT: {
        /* m_w R'' = sum f_i - p 4 pi R^2, m_w the total particle mass */
        double R = s->walls[w].radius;
        double a = (load - ball_pressure(sim) * 4 * CD_PI * R * R) / sim->total_mass;
        s->walls[w].radial_velocity += a * dt;
        if (relaxed(sim, err, errlen, &done)) return -1;
        if (done) {
            if (sim->cfg.protocol_kind == CD_PROTOCOL_BULK) {
                enter(sim, CD_PHASE_BASE, log);
                s->walls[w].radial_velocity = 0;
                s->control[CTL_R_BASE] = s->walls[w].radius;
            } else {
                enter(sim, CD_PHASE_DONE, log);
            }
        }
        break;
    }
    case CD_PHASE_BASE:
        if (relaxed(sim, err, errlen, &done)) return -1;
        if (done) {
            if (save_base(sim, err, errlen)) return -1;
            enter(sim, CD_PHASE_PROBE, log);
            if (apply_strain(sim, 0, err, errlen)) return -1; /* the reference window first */
        }
        break;
    case CD_PHASE_PROBE: {
        double p;
        if (!window_pressure(sim, load, &p)) break;
        double eps = s->control[CTL_STRAIN], next;
        if (eps == 0) {
            s->control[CTL_P_BASE] = p;
            if (log) fprintf(log, "\ncapdem: bulk probe: reference window, p_ref %.9g Pa\n", p);
            next = sim->cfg.strain_min;
        } else {
            double dp = p - s->control[CTL_P_BASE];
            double K = dp / eps; /* K = -V dp / dV with dV/V = -eps [Pa] */
            int k = (int)s->control[CTL_N_PROBES];
            if (k < CTL_MAX_PROBES) s->control[CTL_K_FIRST + k] = K;
            s->control[CTL_N_PROBES] = k + 1;
            if (log) fprintf(log, "\ncapdem: bulk probe: strain %.3g  dp %.6g Pa  K %.6g Pa\n", eps, dp, K);
            next = eps * 10;
            if (next > sim->cfg.strain_max * (1 + 1e-9) || k + 1 >= CTL_MAX_PROBES) {
                enter(sim, CD_PHASE_DONE, log);
                break;
            }
        }
        if (apply_strain(sim, next, err, errlen)) return -1;
        break;
    }
    default: break;
    }
    return phase_of(sim) == CD_PHASE_DONE;
}

void cd_protocol_observable_info(const char **names, const char **units)
{
    static const char *const n[CD_PROTOCOL_OBSERVABLES] = {"packing_fraction", "coordination", "phase", "wall_load", "pressure"};
    static const char *const u[CD_PROTOCOL_OBSERVABLES] = {"1", "1", "1", "N", "Pa"};
    for (int k = 0; k < CD_PROTOCOL_OBSERVABLES; k++) { names[k] = n[k]; units[k] = u[k]; }
}

/* Container volume [m^3] (0 when there is none): up to the piston for the
 * deposit protocol, the ball for the ball protocols. */
static double container_volume(const cd_sim *sim)
{
    const cd_config *c = &sim->cfg;
    const cd_state *s = &sim->s;
    int w = (int)s->control[CTL_WALL];
    int deposit = c->protocol_kind == CD_PROTOCOL_DEPOSIT;
    if (c->domain_kind == CD_DOMAIN_BOX) return c->box_width * c->box_thickness * (deposit ? s->walls[w].point.y : c->box_height);
    if (c->domain_kind == CD_DOMAIN_CYLINDER)
        return CD_PI * 0.25 * c->cyl_diameter * c->cyl_diameter * (deposit ? s->walls[w].point.y : c->cyl_height);
    if (c->domain_kind == CD_DOMAIN_BALL) return 4.0 / 3.0 * CD_PI * pow(s->walls[0].radius, 3);
    return 0;
}

void cd_protocol_observables(const cd_sim *sim, const cd_observables *o, double *v)
{
    const cd_state *s = &sim->s;
    double V = container_volume(sim);
    v[0] = V > 0 ? sim->solid_volume / V : 0;
    v[1] = s->n_particles ? 2 * o->n_contacts / (double)s->n_particles : 0;
    v[2] = s->control[CTL_PHASE];
    v[3] = s->control[CTL_LOAD];
    int w = (int)s->control[CTL_WALL];
    double R = s->n_walls ? s->walls[w].radius : 0;
    v[4] = sim->cfg.domain_kind == CD_DOMAIN_BALL && R > 0 ? s->control[CTL_LOAD] / (4 * CD_PI * R * R) : 0;
}
