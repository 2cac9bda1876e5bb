/* Material point method: where the line through a node along a contact
 * normal crosses a material point (src/mpm/mpm_contact.c, docs/mpm.md
 * "Contact").  Device-safe: C11 and OpenCL C.
 *
 * A point stands for the parallelogram x_p + F [-l/2, l/2]^2 (l its initial
 * side [m], F its deformation gradient), as for the walls
 * (kernels/mpm_wall.h).  The line x_i + s n (s [m]) crosses it where the
 * reference coordinates xi(s) = F^-1 (x_i - x_p) + s F^-1 n lie in the
 * square: two slabs, one per reference direction.  The chord of the line
 * in the point, not the point's projection on n: the chords of points that
 * do not overlap do not overlap either, so two bodies in touch, not
 * overlapping, show no overlap. */
#ifndef CD_MPM_CONTACT_H
#define CD_MPM_CONTACT_H
#include "defs.h"

CD_DEVICE_BEGIN

/* The chord [*s_lo, *s_hi] [m] of the line through the node at distance
 * (dx, dy) = x_i - x_p [m] from the point, along the unit vector (nx, ny),
 * in the point's parallelogram of half-side half_side [m] and deformation
 * gradient f_*; returns 0 when the line misses it. */
CD_INLINE cd_int cd_mpm_point_chord(cd_real half_side, cd_real f_xx, cd_real f_xy, cd_real f_yx, cd_real f_yy,
                                    cd_real dx, cd_real dy, cd_real nx, cd_real ny, cd_real *s_lo, cd_real *s_hi)
{
    cd_real det = f_xx * f_yy - f_xy * f_yx;                                         /* det F > 0 [1] */
    cd_real a0 = (f_yy * dx - f_xy * dy) / det, a1 = (-f_yx * dx + f_xx * dy) / det; /* F^-1 (x_i - x_p) [m] */
    cd_real d0 = (f_yy * nx - f_xy * ny) / det, d1 = (-f_yx * nx + f_xx * ny) / det; /* F^-1 n [1] */
    cd_real lo = -CD_R(1e300), hi = CD_R(1e300);
    cd_real a[2] = {a0, a1}, d[2] = {d0, d1};
    for (cd_int k = 0; k < 2; k++) {
        if (d[k] == CD_R(0)) {
            if (fabs(a[k]) > half_side) return 0;
            continue;
        }
        cd_real t1 = (-half_side - a[k]) / d[k], t2 = (half_side - a[k]) / d[k];
        lo = fmax(lo, fmin(t1, t2));
        hi = fmin(hi, fmax(t1, t2));
    }
    *s_lo = lo;
    *s_hi = hi;
    return lo <= hi;
}

CD_DEVICE_END
#endif
