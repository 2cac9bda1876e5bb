/* Material point method: frictionless contact of a material point with a
 * rigid plane wall by a penalty force (docs/mpm.md: where this departs from
 * the paper's Contact Dynamics).  Device-safe: C11 and OpenCL C.
 *
 * A point stands for the parallelogram F [-l/2, l/2]^2 (l its initial side
 * [m], F its deformation gradient), so its reach towards a wall of unit
 * normal n is (l/2) (|(F^T n)_x| + |(F^T n)_y|): exact for the affinely
 * deformed square.  Where the reach crosses the plane by delta > 0 [m] the
 * wall pushes along n with k delta, k [N/m per metre of thickness]. */
#ifndef CD_MPM_WALL_H
#define CD_MPM_WALL_H
#include "defs.h"

CD_DEVICE_BEGIN

/* Reach [m] of a point's parallelogram F [-l/2, l/2]^2 along the unit
 * vector (nx, ny): (l/2) (|(F^T n)_x| + |(F^T n)_y|); half_side is l/2. */
CD_INLINE cd_real cd_mpm_point_reach(cd_real half_side, cd_real f_xx, cd_real f_xy, cd_real f_yx, cd_real f_yy,
                                     cd_real nx, cd_real ny)
{
    cd_real ex = f_xx * nx + f_yx * ny; /* (F^T n)_x [1] */
    cd_real ey = f_xy * nx + f_yy * ny; /* (F^T n)_y [1] */
    return half_side * (fabs(ex) + fabs(ey));
}

/* Overlap delta [m] (<= 0: no contact) of a point at (x, y) [m] with the
 * wall through (wx, wy) [m] of unit normal (nx, ny) pointing into the
 * material; half_side is l/2 [m], f_* the point's deformation gradient. */
CD_INLINE cd_real cd_mpm_wall_overlap(cd_real x, cd_real y, cd_real half_side, cd_real f_xx, cd_real f_xy, cd_real f_yx,
                                      cd_real f_yy, cd_real wx, cd_real wy, cd_real nx, cd_real ny)
{
    cd_real gap = nx * (x - wx) + ny * (y - wy); /* centre's distance from the plane [m] */
    return cd_mpm_point_reach(half_side, f_xx, f_xy, f_yx, f_yy, nx, ny) - gap;
}

CD_DEVICE_END
#endif
