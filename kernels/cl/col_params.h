/* Kernel parameters: one __global pointer per device column of
 * kernels/fields.def (kernels/field_groups.h), in
 * table order, then prim_arm, arm, inertia, inertia_iso, force and torque, each followed by a comma.  Included at the start of the
 * parameter list of every kernel that reads or writes the state, so that
 * the host binds columns by their index in cd_fields[] (no include guard:
 * it expands at each use). */
#include "../field_groups.h"
#define CD_FIELD(group, ctype, h5type, ncomp, name, unit, meaning) CD_ON_DEVICE_##group(__global ctype *name CD_COMMA)
#include "../fields.def"
#undef CD_FIELD
/* then the primitives' arms, the step's inertia, and the force and torque
 * where the step holds them (null otherwise; kernels/cols.h) */
__global cd_int *prim_arm, __global cd_arm *arm, __global cd_vec3 *inertia, __global cd_real *inertia_iso,
    __global cd_vec3 *force, __global cd_vec3 *torque,
