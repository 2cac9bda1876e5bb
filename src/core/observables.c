/* The observables of kernels/observables.def as data for the host, and
 * the time-series rows `capdem run` writes (src/core/run.c). */
#include <string.h>
#include "core/observables.h"
#include "protocols/protocol.h"

#define CD_OBS_NCOMP_ONE            1, 0
#define CD_OBS_NCOMP_VEC3           3, 0
#define CD_OBS_NCOMP_WALL1          1, 1
#define CD_OBS_NCOMP_WALL3          3, 1
#define CD_OBS_OFFSET_SUM(member)   offsetof(cd_observables, member), 0
#define CD_OBS_OFFSET_MAX(member)   offsetof(cd_observables, member), 0
#define CD_OBS_OFFSET_WALLS(member) offsetof(cd_wall, member), 0
#define CD_OBS_OFFSET_PROTOCOL(member)
/* offset and index: "offset, 0" for members, "0, CD_POBS_<id>" for the protocol's */
#define CD_OBS_INDEX_SUM(id)
#define CD_OBS_INDEX_MAX(id)
#define CD_OBS_INDEX_WALLS(id)
#define CD_OBS_INDEX_PROTOCOL(id) 0, CD_POBS_##id

const cd_observable_desc cd_observable_table[CD_OBSERVABLE_COUNT] = {
#define CD_OBSERVABLE(id, name, unit, count, source, member, meaning)                                                  \
    {#id,                                                                                                              \
     name,                                                                                                             \
     unit,                                                                                                             \
     meaning,                                                                                                          \
     CD_OBS_NCOMP_##count,                                                                                             \
     CD_OBS_FROM_##source,                                                                                             \
     CD_OBS_OFFSET_##source(member) CD_OBS_INDEX_##source(id)},
#include "observables.def"
};

int cd_observable_ncomp(int k, size_t n_walls)
{
    const cd_observable_desc *d = &cd_observable_table[k];
    return d->per_wall ? d->ncomp * (int)n_walls : d->ncomp;
}

int cd_observable_series(const cd_sim *sim, cd_observable_info *info)
{
    int n = 0;
    for (int k = 0; k < CD_OBSERVABLE_COUNT; k++) {
        const cd_observable_desc *d = &cd_observable_table[k];
        int ncomp = cd_observable_ncomp(k, sim->s.n_walls);
        if (*d->name && ncomp > 0) info[n++] = (cd_observable_info){d->name, d->unit, ncomp};
    }
    return n;
}

void cd_observable_row(const cd_sim *sim, const cd_observables *o, double *row)
{
    double protocol[CD_POBS_COUNT];
    cd_protocol_observables(sim, o, protocol);
    int n = 0;
    for (int k = 0; k < CD_OBSERVABLE_COUNT; k++) {
        const cd_observable_desc *d = &cd_observable_table[k];
        if (!*d->name) continue;
        if (d->source == CD_OBS_FROM_PROTOCOL) {
            row[n++] = protocol[d->index];
        } else if (d->source == CD_OBS_FROM_WALLS) {
            for (size_t w = 0; w < sim->s.n_walls; w++) {
                memcpy(row + n, (const char *)&sim->s.walls[w] + d->offset, (size_t)d->ncomp * sizeof(double));
                n += d->ncomp;
            }
        } else {
            int c = cd_observable_ncomp(k, sim->s.n_walls);
            memcpy(row + n, (const char *)o + d->offset, (size_t)c * sizeof(double));
            n += c;
        }
    }
}
