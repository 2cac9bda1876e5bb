/* What the protocols share (src/protocols/protocol.c) and the operations each
 * protocol provides (src/protocols/protocol_deposit.c, protocol_ball.c,
 * protocol_bulk.c): a new protocol is a new operations table, a row of
 * the table in protocol.c, a config choice and its docs. */
#ifndef CD_PROTOCOL_INTERNAL_H
#define CD_PROTOCOL_INTERNAL_H
#include <stdio.h>
#include "protocols/protocol.h"
#include "mpi/mpi_decomp.h"

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

static inline int cd_proto_phase(const cd_sim *sim) { return (int)sim->s.control[CTL_PHASE]; }

/* Enters phase (its start time, a new relaxation test), said on log. */
void cd_proto_enter(cd_sim *sim, int phase, FILE *log);
/* Relaxation test of the phases that relax (protocol.c); *done = 1 once
 * relaxed. */
int cd_proto_relaxed(cd_sim *sim, char *err, size_t errlen, int *done);

/* The operations of one protocol. */
typedef struct {
    /* config checks that need more than one key (the schema did the rest) */
    int (*check)(const cd_config *c, char *err, size_t errlen);
    /* control slots, driven wall and initial velocities of a new run; 0,
     * or -1 (err: out of memory, every MPI rank alike) */
    int (*begin)(cd_sim *sim, char *err, size_t errlen);
    /* steps until control must run again in this phase */
    long long (*steps_until_control)(const cd_sim *sim, int phase);
    /* one control call in this phase, load [N] the driven wall's normal
     * load (0 in the deposit's settling, which does not read it) */
    int (*control)(cd_sim *sim, int phase, double load, FILE *log, char *err, size_t errlen);
    /* after a resume read the control slots (may be NULL) */
    int (*resume)(cd_sim *sim, const char *path, char *err, size_t errlen);
} cd_protocol_ops;

extern const cd_protocol_ops cd_protocol_deposit, cd_protocol_radial, cd_protocol_bulk;

/* The ball's compaction, which the bulk probe starts with
 * (protocol_ball.c). */
int cd_proto_ball_check(const cd_config *c, char *err, size_t errlen);
int cd_proto_ball_begin(cd_sim *sim, char *err, size_t errlen);

/* The motion of every particle of the run, for the sums of a begin that
 * must not depend on how the particles are spread over MPI ranks: each
 * particle's CD_MOTION_WIDTH values (mass [kg], position [m], velocity
 * [m/s], angular momentum [kg m^2/s]) in global id order into a new *rows
 * (the caller frees it), *n particles, where the sums are made: the one
 * process, or rank 0 when each rank set up its own particles (the other
 * ranks: *rows NULL, they take the result from cd_mpi_share).  0, or -1
 * (err: out of memory, every rank alike). */
enum { CD_MOTION_MASS, CD_MOTION_POSITION, CD_MOTION_VELOCITY = 4, CD_MOTION_ANGMOM = 7, CD_MOTION_WIDTH = 10 };
int cd_proto_motion_rows(const cd_sim *sim, double **rows, size_t *n, char *err, size_t errlen);
int cd_proto_compact(cd_sim *sim, double load, char *err, size_t errlen, int *done);

#endif
