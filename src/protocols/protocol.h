/* The procedures of docs/references.md, Protocols that a run file selects with
 * protocol.type: deposit and compress (Conzelmann et al.), radial compaction in a
 * pressure-driven ball and the bulk-modulus probe (Tran et al. 2024).  A protocol
 * moves the walls between steps and decides when the run is done; all its
 * state lives in sim->s.control, so it resumes from any snapshot. */
#ifndef CD_PROTOCOL_H
#define CD_PROTOCOL_H
#include <stdio.h>
#include "core/sim.h"

/* Phases (stored in control[CD_CTL_PHASE]). */
enum {
    CD_PHASE_FREE = 0, /* no protocol: plain dynamics for run.steps */
    CD_PHASE_SETTLE,   /* deposit: particles fall, piston parked at the top */
    CD_PHASE_COMPRESS, /* deposit: piston moves down at piston_speed */
    CD_PHASE_HOLD,     /* deposit: piston holds piston_force; relaxing */
    CD_PHASE_COMPACT,  /* ball: radius driven by the pressure; relaxing */
    CD_PHASE_BASE,     /* bulk: ball radius fixed, relaxing the base state */
    CD_PHASE_PROBE,    /* bulk: strained state relaxing */
    CD_PHASE_DONE
};

/* Checks that the protocol fits the domain (message names the keys). */
int cd_protocol_check(const cd_config *c, char *err, size_t errlen);

/* Prepares a new run (phase, driven wall, initial velocities: the net
 * motion in a ball and the rotation in a frictionless cylinder removed,
 * sums over every particle of the run in the serial order, also when
 * each MPI rank set up its own particles only).  0, or -1 (err: out of
 * memory, every rank alike). */
int cd_protocol_begin(cd_sim *sim, char *err, size_t errlen);

/* After a resume from path: a bulk probe in progress reads back its base
 * state (the snapshot of control slot CTL_BASE_STEP).  Returns 0, or -1
 * with a message. */
int cd_protocol_resume(cd_sim *sim, const char *path, char *err, size_t errlen);

/* Steps until the protocol must act again (>= 1). */
long long cd_protocol_steps_until_control(const cd_sim *sim);

/* Acts after the steps: wall dynamics, checks, phase changes.  Writes a
 * line to log on phase changes.  Returns 1 when the protocol is complete,
 * 0 to go on, -1 on error (message in err). */
int cd_protocol_control(cd_sim *sim, FILE *log, char *err, size_t errlen);

/* The PROTOCOL observables of kernels/observables.def (packing fraction,
 * coordination, phase, load on the driven wall, ball pressure):
 * values[CD_POBS_<id>] (src/core/observables.h). */
void cd_protocol_observables(const cd_sim *sim, const cd_observables *o, double *values);

/* Results of the bulk probe, appended as rows: strain, pressure change, K. */
const char *cd_protocol_phase_name(int phase);

#endif
