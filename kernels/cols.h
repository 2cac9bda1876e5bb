/* Every structure-of-arrays column of the state as one struct of pointers,
 * generated from kernels/fields.def.  The per-item functions of step_items.h
 * take it, so that the OpenMP loops (pointers into cd_state) and the OpenCL
 * kernels (pointers to __global buffers) run the same code: a column added
 * to fields.def reaches both backends without a second list.
 * Device-safe: C11 and OpenCL C 1.2 (a private struct may hold pointers to
 * __global memory; only kernel arguments may not). */
#ifndef CD_COLS_H
#define CD_COLS_H
#include "defs.h"
#include "geom_types.h"
#include "field_groups.h"

/* The device columns only (field_groups.h). */
typedef struct {
#define CD_FIELD(group, ctype, h5type, ncomp, name, unit, meaning) CD_ON_DEVICE_##group(CD_GLOBAL ctype *name;)
#include "fields.def"
#undef CD_FIELD
} cd_cols;

#endif
