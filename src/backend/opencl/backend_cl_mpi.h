/* What the MPI decomposition (docs/mpi.md, "GPUs"; src/mpi/mpi_device.c)
 * asks of the OpenCL backend, where a rank's local state lives on its
 * OpenCL device: the ghost refresh's halo packed and unpacked there, only
 * its rows crossing to the host; the local state reloaded after a
 * migration rebuilt it on the host; a wall load's F_n per primitive and
 * an observation's columns read from there; the device of the rank's
 * node-local rank.  No OpenCL type here: the MPI files include it in a
 * build with OpenCL. */
#ifndef CD_BACKEND_CL_MPI_H
#define CD_BACKEND_CL_MPI_H
#include <stddef.h>
#include "core/sim.h"

/* Is sim's state on an OpenCL device (the backend started)? */
int cd_cl_mpi_started(const cd_sim *sim);
/* The next open takes the n-th of the eligible devices (the rank's
 * node-local rank, modulo their count); 0 by default. */
void cd_cl_use_nth_device(int n);
/* The device sim took: its name, its place among the eligible devices
 * (index, count) into the arguments. */
void cd_cl_device_slot(const cd_sim *sim, char *name, size_t len, int *index, int *count);
/* The ghost refresh's lists of local particles (send: ns rows packed,
 * recv: nr rows unpacked), onto the device after a migration re-planned
 * them.  0, or -1 (the backend's failure recorded). */
int cd_cl_halo_lists(cd_sim *sim, const int *send, int ns, const int *recv, int nr);
/* The ns sent rows packed on the device into out (CD_HALO_REALS reals a
 * row), or the nr received rows of in unpacked there into the ghosts'
 * columns.  0, or -1. */
int cd_cl_halo_pack(cd_sim *sim, double *out);
int cd_cl_halo_unpack(cd_sim *sim, const double *in);
/* F_n [N] on wall w of every local primitive into fn (n_prims doubles),
 * from the step's wall-candidate entries on the device: 0; 1 when the
 * host's columns are the current ones (no forces since the start: the
 * caller reads them); -1 with err set. */
int cd_cl_wall_fn(cd_sim *sim, int w, double *fn, char *err, size_t errlen);
/* The columns an MPI observation reads (src/mpi/mpi_reduce.c: the
 * particles' pose, velocity and angular momentum, the primitives' ends,
 * the pair rows' primitives, flag and spring) and the wall rows in
 * contact, from the device to the host instead of every column.  0, or
 * -1 with err set. */
int cd_cl_observe_cols(cd_sim *sim, char *err, size_t errlen);
/* After a migration rebuilt sim's state on the host (its particle,
 * primitive and pair counts changed): the device's buffers made anew for
 * it and filled from it, as a start does, but in the middle of a step:
 * the walls as the device moved them, no forces, the list rebuilt next
 * (backend_cl.c).  0, or -1 with err set. */
int cd_cl_reload(cd_sim *sim, char *err, size_t errlen);

#endif
