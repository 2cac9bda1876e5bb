/* Declares `cd_cols c` and points it at the column parameters of
 * col_params.h (no include guard: it expands at each use). */
cd_cols c;
#define CD_FIELD(group, ctype, h5type, ncomp, name, unit, meaning) CD_ON_DEVICE_##group(c.name = name;)
#include "../fields.def"
#undef CD_FIELD
c.prim_arm = prim_arm;
c.arm = arm;
c.inertia = inertia;
c.inertia_iso = inertia_iso;
c.force = force;
c.torque = torque;
