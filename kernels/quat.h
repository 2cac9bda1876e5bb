/* Unit quaternions: orientation of a rigid body, body frame -> world frame. */
#ifndef CD_QUAT_H
#define CD_QUAT_H
#include "vec3.h"

CD_DEVICE_BEGIN

CD_INLINE cd_quat cd_q(cd_real w, cd_real x, cd_real y, cd_real z) { cd_quat q; q.w = w; q.x = x; q.y = y; q.z = z; return q; }
CD_INLINE cd_quat cd_q_identity(void) { return cd_q(1, 0, 0, 0); }

/* Hamilton product a*b: rotation b first, then a. */
CD_INLINE cd_quat cd_q_mul(cd_quat a, cd_quat b)
{
    return cd_q(a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
                a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
                a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
                a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w);
}

CD_INLINE cd_quat cd_q_normalize(cd_quat q)
{
    cd_real s = CD_R(1) / sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    return cd_q(q.w * s, q.x * s, q.y * s, q.z * s);
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
CD_INLINE cd_vec3 cd_q_rotate_inv(cd_quat q, cd_vec3 v)
{
    return cd_q_rotate(cd_q(q.w, -q.x, -q.y, -q.z), v);
}

CD_DEVICE_END
#endif
