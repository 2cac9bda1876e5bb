/* Protocols of docs/references.md, Protocols (see protocol.h and docs/protocols.md): the
 * driver shared by all of them -- phases, the relaxation test, resume
 * checks, the protocol observables -- and the table of their operations
 * (protocol_internal.h), selected by protocol.type. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "protocols/protocol_internal.h"
#include "core/observables.h"

/* By cd_protocol_kind; none has no operations. */
static const cd_protocol_ops *const protocol_table[] = {
    [CD_PROTOCOL_NONE] = NULL,
    [CD_PROTOCOL_DEPOSIT] = &cd_protocol_deposit,
    [CD_PROTOCOL_RADIAL] = &cd_protocol_radial,
    [CD_PROTOCOL_BULK] = &cd_protocol_bulk,
};

static const cd_protocol_ops *ops_of(const cd_config *c) { return protocol_table[c->protocol_kind]; }

const char *cd_protocol_phase_name(int phase)
{
    static const char *const names[] = {"free", "settle", "compress", "hold", "compact", "base", "probe", "done"};
    return phase >= 0 && phase <= CD_PHASE_DONE ? names[phase] : "?";
}

int cd_protocol_check(const cd_config *c, char *err, size_t errlen)
{
    const cd_protocol_ops *ops = ops_of(c);
    return ops ? ops->check(c, err, errlen) : 0;
}

void cd_proto_enter(cd_sim *sim, int phase, FILE *log)
{
    sim->s.control[CTL_PHASE] = phase;
    sim->s.control[CTL_PHASE_TIME] = sim->s.time;
    sim->s.control[CTL_EEL_LAST] = -1;
    sim->s.control[CTL_RATIO_MAX] = 0;
    if (log)
        fprintf(log, "\ncapdem: protocol phase %s at step %lld (t = %.6g s)\n", cd_protocol_phase_name(phase),
                sim->s.step, sim->s.time);
}

int cd_protocol_begin(cd_sim *sim, char *err, size_t errlen)
{
    memset(sim->s.control, 0, sizeof sim->s.control);
    const cd_protocol_ops *ops = ops_of(&sim->cfg);
    if (ops) return ops->begin(sim, err, errlen);
    cd_proto_enter(sim, CD_PHASE_FREE, NULL);
    return 0;
}

/* One particle's row of cd_proto_motion_rows (local row q). */
static void pack_motion(const cd_sim *sim, size_t q, double *out)
{
    const cd_state *s = &sim->s;
    const cd_vec3 v[3] = {s->position[q], s->velocity[q], s->angmom[q]};
    out[CD_MOTION_MASS] = s->mass[q];
    for (int k = 0; k < 3; k++) {
        out[CD_MOTION_POSITION + 3 * k] = v[k].x;
        out[CD_MOTION_POSITION + 3 * k + 1] = v[k].y;
        out[CD_MOTION_POSITION + 3 * k + 2] = v[k].z;
    }
}

int cd_proto_motion_rows(const cd_sim *sim, double **rows, size_t *n, char *err, size_t errlen)
{
    int rc = cd_mpi_rows_in_order(sim, CD_MOTION_WIDTH, pack_motion, rows, n);
    if (rc < 0) snprintf(err, errlen, "out of memory for the particles' motion at the protocol's start");
    if (rc <= 0) return rc;
    /* the whole run is here: its rows, in order */
    *n = sim->s.n_particles;
    *rows = malloc((*n * CD_MOTION_WIDTH + 1) * sizeof **rows);
    if (!*rows) {
        snprintf(err, errlen, "out of memory for the motion of %zu particles at the protocol's start", *n);
        return -1;
    }
    for (size_t q = 0; q < *n; q++) pack_motion(sim, q, *rows + q * CD_MOTION_WIDTH);
    return 0;
}

long long cd_protocol_steps_until_control(const cd_sim *sim)
{
    int phase = cd_proto_phase(sim);
    const cd_protocol_ops *ops = ops_of(&sim->cfg);
    if (!ops || phase == CD_PHASE_FREE || phase == CD_PHASE_DONE) return 1LL << 40;
    return ops->steps_until_control(sim, phase);
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
int cd_proto_relaxed(cd_sim *sim, char *err, size_t errlen, int *done)
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
        snprintf(err, errlen,
                 "%s: dataset /walls/control holds phase %g, wall %g, probes %g: not a state the protocol "
                 "can be in (phases %d..%d, walls 0..%zu, probes 0..%d); the file is refused",
                 path, c[CTL_PHASE], c[CTL_WALL], c[CTL_N_PROBES], CD_PHASE_FREE, CD_PHASE_DONE,
                 sim->s.n_walls ? sim->s.n_walls - 1 : 0, CTL_MAX_PROBES);
        return -1;
    }
    const cd_protocol_ops *ops = ops_of(&sim->cfg);
    return ops && ops->resume ? ops->resume(sim, path, err, errlen) : 0;
}

int cd_protocol_control(cd_sim *sim, FILE *log, char *err, size_t errlen)
{
    cd_state *s = &sim->s;
    int phase = cd_proto_phase(sim), w = (int)s->control[CTL_WALL];
    double load = 0;
    const cd_protocol_ops *ops = ops_of(&sim->cfg);
    if (!ops || phase == CD_PHASE_FREE || phase == CD_PHASE_DONE) return phase == CD_PHASE_DONE;
    if (phase != CD_PHASE_SETTLE && cd_sim_wall_load(sim, w, &load, err, errlen)) return -1;
    s->control[CTL_LOAD] = load;
    if (ops->control(sim, phase, load, log, err, errlen)) return -1;
    return cd_proto_phase(sim) == CD_PHASE_DONE;
}

/* Container volume [m^3] (0 when there is none): up to the piston for the
 * deposit protocol, the ball for the ball protocols. */
static double container_volume(const cd_sim *sim)
{
    const cd_config *c = &sim->cfg;
    const cd_state *s = &sim->s;
    int w = (int)s->control[CTL_WALL];
    int deposit = c->protocol_kind == CD_PROTOCOL_DEPOSIT;
    if (c->domain_kind == CD_DOMAIN_BOX)
        return c->box_width * c->box_thickness * (deposit ? s->walls[w].point.y : c->box_height);
    if (c->domain_kind == CD_DOMAIN_CYLINDER)
        return CD_PI * 0.25 * c->cyl_diameter * c->cyl_diameter * (deposit ? s->walls[w].point.y : c->cyl_height);
    if (c->domain_kind == CD_DOMAIN_BALL) return 4.0 / 3.0 * CD_PI * pow(s->walls[0].radius, 3);
    return 0;
}

void cd_protocol_observables(const cd_sim *sim, const cd_observables *o, double *v)
{
    const cd_state *s = &sim->s;
    double V = container_volume(sim);
    v[CD_POBS_PHI] = V > 0 ? sim->solid_volume / V : 0;
    v[CD_POBS_Z] = s->n_particles ? 2 * o->n_contacts / (double)s->n_particles : 0;
    v[CD_POBS_PHASE] = s->control[CTL_PHASE];
    v[CD_POBS_LOAD] = s->control[CTL_LOAD];
    int w = (int)s->control[CTL_WALL];
    double R = s->n_walls ? s->walls[w].radius : 0;
    v[CD_POBS_PRESSURE] =
        sim->cfg.domain_kind == CD_DOMAIN_BALL && R > 0 ? s->control[CTL_LOAD] / (4 * CD_PI * R * R) : 0;
}
