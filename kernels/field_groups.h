/* Which groups of kernels/fields.def a device holds.  CD_ON_DEVICE_<group>(...)
 * expands to its arguments for the groups the time step reads or writes,
 * and to nothing for PAIR_OUT, the per-contact output columns that the host
 * derives at sync (src/io/pair_output.c).  The column lists of the backends
 * (cols.h, cl/col_params.h, cl/col_bind.h, the OpenCL column indices, the
 * offload mapping) expand fields.def through it, so a device never holds,
 * binds or copies an output-only column.  PAIR_OUT is the last group of
 * fields.def: the device columns are the first ones of cd_fields[].
 * Device-safe: C11 and OpenCL C 1.2 (variadic macros are C99). */
#ifndef CD_FIELD_GROUPS_H
#define CD_FIELD_GROUPS_H

#define CD_ON_DEVICE_PARTICLE(...) __VA_ARGS__
#define CD_ON_DEVICE_PRIM(...)     __VA_ARGS__
#define CD_ON_DEVICE_PAIR(...)     __VA_ARGS__
#define CD_ON_DEVICE_WALLC(...)    __VA_ARGS__
#define CD_ON_DEVICE_PAIR_OUT(...)

#endif
