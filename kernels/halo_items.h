/* What the MPI decomposition (docs/mpi.md) runs where a rank's local state
 * lives: one work item per ghost row of the halo, and per primitive of a
 * wall load.  Compiled as C (the host's refresh, src/mpi/mpi_halo.c; the
 * offload device's loops, src/mpi/mpi_device.c) and as OpenCL C
 * (kernels/cl/halo.cl), so that every backend packs, unpacks and reads the
 * same numbers in the same order.  No arithmetic: copies and one test. */
#ifndef CD_HALO_ITEMS_H
#define CD_HALO_ITEMS_H
#include "cols.h"
#include "step_items.h"

/* Reals per particle of the ghost refresh: position 3, orientation 4,
 * velocity 3, angmom 3, angvel 3, force 3, torque 3. */
#define CD_HALO_REALS 22

CD_DEVICE_BEGIN

/* The ghost columns of local particle q to (pack) or from the
 * CD_HALO_REALS reals at b, in the order above. */
CD_INLINE void cd_item_ghost_io(cd_cols c, cd_int q, CD_GLOBAL cd_real *b, int pack)
{
    CD_GLOBAL cd_real *cols[7] = {&c.position[q].x, &c.orientation[q].w, &c.velocity[q].x, &c.angmom[q].x,
                                  &c.angvel[q].x,   &c.force[q].x,       &c.torque[q].x};
    const int len[7] = {3, 4, 3, 3, 3, 3, 3};
    for (int k = 0; k < 7; k++) {
        for (int e = 0; e < len[k]; e++) {
            if (pack) b[e] = cols[k][e];
            else cols[k][e] = b[e];
        }
        b += len[k];
    }
}

/* F_n [N] of the primitive in step order u on wall w: what the serial
 * load adds for its row (cd_item_wall_load_chunk's test), 0 where it
 * touches none.  prim_at: the step's order (NULL: the user's). */
CD_INLINE cd_real cd_item_wall_fn(cd_cols c, cd_long u, cd_int n_walls, cd_int w, const CD_GLOBAL cd_int *prim_at,
                                  const CD_GLOBAL cd_int *wall_start, const CD_GLOBAL cd_int *wall_rows,
                                  const CD_GLOBAL cd_wall_entry *wall_out)
{
    cd_long e = cd_wall_out_place(c, (cd_long)cd_map(prim_at, u) * n_walls + w, n_walls, wall_start, wall_rows);
    return e >= 0 && wall_out[e].active ? wall_out[e].fn : 0;
}

CD_DEVICE_END
#endif
