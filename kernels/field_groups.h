/* Which groups of kernels/fields.def a device holds.  CD_ON_DEVICE_<group>(...)
 * expands to its arguments for the groups the time step reads or writes,
 * and to nothing for PARTICLE_OUT, the particles' force and torque, which
 * the step sums again where it reads them and holds only on an MPI rank
 * or from a start to its first advance (kernels/cols.h, cd_cols.force),
 * PARTICLE_HOST, the particles' columns no step reads
 * (scale, shape), PAIR_OUT, the per-contact output columns that the host
 * derives at sync (src/io/pair_output.c), PRIM_ARM, the primitives' arm
 * columns, which a device holds only for primitives with an arm (cd_arm,
 * kernels/cols.h), and WALLC and WALLC_OUT, the
 * wall-contact columns (history and outputs) the step keeps per wall
 * candidate (cd_wall_entry, expanded at sync).  The column lists of the backends
 * (cols.h, cl/col_params.h, cl/col_bind.h, the OpenCL column indices, the
 * offload mapping) expand fields.def through it, so a device never holds,
 * binds or copies a host-only column.  PARTICLE_OUT, PARTICLE_HOST, PRIM_ARM, WALLC,
 * WALLC_OUT and PAIR_OUT are the last groups of fields.def: the device columns are the first ones of
 * cd_fields[].
 * Device-safe: C11 and OpenCL C 1.2, whose compilers may refuse variadic
 * macros (NVIDIA's does: "variadic macros not supported in OpenCL"), so
 * each takes one argument; a list entry that needs a comma writes
 * CD_COMMA, expanded only after the argument is taken. */
#ifndef CD_FIELD_GROUPS_H
#define CD_FIELD_GROUPS_H

#define CD_COMMA                 ,
#define CD_ON_DEVICE_PARTICLE(x) x
#define CD_ON_DEVICE_PRIM(x)     x
#define CD_ON_DEVICE_PAIR(x)     x
#define CD_ON_DEVICE_PARTICLE_OUT(x)
#define CD_ON_DEVICE_PARTICLE_HOST(x)
#define CD_ON_DEVICE_PRIM_ARM(x)
#define CD_ON_DEVICE_WALLC(x)
#define CD_ON_DEVICE_WALLC_OUT(x)
#define CD_ON_DEVICE_PAIR_OUT(x)

#endif
