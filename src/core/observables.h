/* The observables of kernels/observables.def as data for the host: their
 * names, units and meanings, and the time-series rows of a run (the
 * header given to the run file and one row of values), in the table's
 * order.  The sums themselves: kernels/observe_items.h. */
#ifndef CD_OBSERVABLES_H
#define CD_OBSERVABLES_H
#include <stddef.h>
#include "core/sim.h"
#include "io/io_h5.h"
#include "observe_items.h"

/* CD_OBSERVABLE_<id>: the row of observable id in the table. */
enum cd_observable_id {
#define CD_OBSERVABLE(id, ...) CD_OBSERVABLE_##id,
#include "observables.def"
    CD_OBSERVABLE_COUNT
};

/* CD_POBS_<id>: the place of a PROTOCOL observable in the values
 * cd_protocol_observables fills (src/protocols/protocol.h). */
#define CD_POBS_PROTOCOL_(id) CD_POBS_##id,
#define CD_POBS_OTHER_(id)
#define CD_POBS_SUM      CD_POBS_OTHER_
#define CD_POBS_MAX      CD_POBS_OTHER_
#define CD_POBS_WALLS    CD_POBS_OTHER_
#define CD_POBS_PROTOCOL CD_POBS_PROTOCOL_
enum cd_protocol_observable {
#define CD_OBSERVABLE(id, name, unit, count, source, member, meaning) CD_POBS_##source(id)
#include "observables.def"
    CD_POBS_COUNT
};

typedef enum { CD_OBS_FROM_SUM, CD_OBS_FROM_MAX, CD_OBS_FROM_WALLS, CD_OBS_FROM_PROTOCOL } cd_observable_source;

typedef struct {
    const char *id;      /* the table's id, e.g. "KT" */
    const char *name;    /* time series /observables/<name>; "" for none */
    const char *unit;    /* SI unit */
    const char *meaning; /* one line */
    int ncomp;           /* components per wall (per_wall) or in all */
    int per_wall;        /* 1: ncomp per wall */
    cd_observable_source source;
    size_t offset; /* of its member in cd_observables (SUM, MAX) or cd_wall (WALLS) */
    int index;     /* CD_POBS_<id> (PROTOCOL) */
} cd_observable_desc;

extern const cd_observable_desc cd_observable_table[CD_OBSERVABLE_COUNT];

/* Components of observable k in a row of a run with n_walls walls. */
int cd_observable_ncomp(int k, size_t n_walls);

/* The most values a time-series row holds (every observable with
 * CD_MAX_WALLS walls; kernels/observe_items.h's CD_OBS_SLOTS_<count>). */
enum {
    CD_OBS_ROW_MAX = 0
#define CD_OBSERVABLE(id, name, unit, count, source, member, meaning) +CD_OBS_SLOTS_##count
#include "observables.def"
};

/* The time series of a run: info[] (CD_OBSERVABLE_COUNT entries at most)
 * gets every named observable with at least one component, in the table's
 * order; returns their number. */
int cd_observable_series(const cd_sim *sim, cd_observable_info *info);

/* One time-series row in the order of cd_observable_series (at most
 * CD_OBS_ROW_MAX values). */
void cd_observable_row(const cd_sim *sim, const cd_observables *o, double *row);

#endif
