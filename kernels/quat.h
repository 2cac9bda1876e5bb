/* Unit quaternions: orientation of a rigid body, body frame -> world frame. */
#ifndef CD_QUAT_H
#define CD_QUAT_H
#include "vec3.h"

CD_DEVICE_BEGIN

CD_INLINE cd_quat cd_q(cd_real w, cd_real x, cd_real y, cd_real z)
{
    cd_quat q;
    q.w = w;
    q.x = x;
    q.y = y;
    q.z = z;
    return q;
}
CD_INLINE cd_quat cd_q_identity(void) { return cd_q(1, 0, 0, 0); }

/* Hamilton product a*b: rotation b first, then a. */
CD_INLINE cd_quat cd_q_mul(cd_quat a, cd_quat b)
{
    return cd_q(a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
                a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w);
}

CD_INLINE cd_quat cd_q_normalize(cd_quat q)
{
    cd_real s = CD_R(1) / sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    return cd_q(q.w * s, q.x * s, q.y * s, q.z * s);
}

/* q / |q| for a q within round-off of unit length, without a sqrt: with
 * |q|^2 = 1 + e, (3 - |q|^2) / 2 = 1 - e/2 equals 1/sqrt(1 + e) up to
 * 3 e^2 / 8, far below round-off for |e| ~ 1e-16.  Keeps products of unit
 * quaternions from drifting off unit length over many steps. */
CD_INLINE cd_quat cd_q_renormalize(cd_quat q)
{
    cd_real s = CD_R(0.5) * (CD_R(3) - (q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z));
    return cd_q(q.w * s, q.x * s, q.y * s, q.z * s);
}

/* sin x and cos x [rad] from +, -, *, floor only: every backend rounds these
 * the same way (IEEE, contraction off), while libm's sin and cos differ
 * between glibc and an OpenCL library in the last bit now and then, which
 * a packing amplifies past the backend-parity bound (docs/motion.md).
 * x is reduced by k pi/2 in three parts (Cody-Waite, the constants of
 * fdlibm, exact products for |k| < 2^20), then Taylor polynomials on
 * |r| <= pi/4 whose first omitted terms are below 2e-18: about 1 ulp.
 * Rotation angles per step are small, where the reduction is skipped. */
CD_INLINE void cd_sincos(cd_real x, cd_real *sin_x, cd_real *cos_x)
{
    cd_real k = CD_R(0), r = x;
    int reduced = !(x >= CD_R(-0.78539816339744828) && x <= CD_R(0.78539816339744828));
    if (reduced) {
        k = floor(x * CD_R(0.63661977236758138) + CD_R(0.5));
        r = ((x - k * CD_R(1.57079632673412561417e+00)) - k * CD_R(6.07710050630396597660e-11)) -
            k * CD_R(2.02226624871116645580e-21);
    }
    cd_real z = r * r;
    cd_real ps = CD_R(-7.647163731819816e-13) + z * (CD_R(2.8114572543455206e-15) + z * CD_R(-8.22063524662433e-18));
    ps = CD_R(-1.9841269841269841e-04) +
         z * (CD_R(2.7557319223985893e-06) +
              z * (CD_R(-2.505210838544172e-08) + z * (CD_R(1.6059043836821613e-10) + z * ps)));
    cd_real sr = r + r * z * (CD_R(-0.16666666666666666) + z * (CD_R(8.3333333333333332e-03) + z * ps));
    cd_real pc = CD_R(-1.1470745597729725e-11) + z * (CD_R(4.779477332387385e-14) + z * CD_R(-1.5619206968586225e-16));
    pc = CD_R(-1.3888888888888889e-03) +
         z * (CD_R(2.4801587301587302e-05) +
              z * (CD_R(-2.755731922398589e-07) + z * (CD_R(2.08767569878681e-09) + z * pc)));
    cd_real cr = CD_R(1) + z * (CD_R(-0.5) + z * (CD_R(4.1666666666666664e-02) + z * pc));
    if (!reduced) { /* k = 0, quadrant 0 (the usual case: a step's angle) */
        *sin_x = sr;
        *cos_x = cr;
        return;
    }
    /* quadrant: k mod 4 (exact for |k| < 2^53; a non-finite x gives NaN) */
    cd_real m = k - CD_R(4) * floor(CD_R(0.25) * k);
    if (m == CD_R(0)) {
        *sin_x = sr;
        *cos_x = cr;
    } else if (m == CD_R(1)) {
        *sin_x = cr;
        *cos_x = -sr;
    } else if (m == CD_R(2)) {
        *sin_x = -sr;
        *cos_x = -cr;
    } else if (m == CD_R(3)) {
        *sin_x = -cr;
        *cos_x = sr;
    } else {
        *sin_x = x - x;
        *cos_x = x - x;
    } /* x not finite: NaN */
}

/* Rotation by angle [rad] about a unit axis. */
CD_INLINE cd_quat cd_q_from_axis_angle(cd_vec3 axis, cd_real angle)
{
    cd_real s = sin(CD_R(0.5) * angle);
    return cd_q(cos(CD_R(0.5) * angle), axis.x * s, axis.y * s, axis.z * s);
}

/* v rotated from body to world frame: q v q^-1. */
CD_INLINE cd_vec3 cd_q_rotate(cd_quat q, cd_vec3 v)
{
    cd_vec3 u = cd_v3(q.x, q.y, q.z);
    cd_vec3 t = cd_v3_scale(cd_v3_cross(u, v), CD_R(2));
    return cd_v3_add(cd_v3_axpy(v, q.w, t), cd_v3_cross(u, t));
}

/* v rotated from world to body frame: q^-1 v q. */
CD_INLINE cd_vec3 cd_q_rotate_inv(cd_quat q, cd_vec3 v) { return cd_q_rotate(cd_q(q.w, -q.x, -q.y, -q.z), v); }

CD_DEVICE_END
#endif
