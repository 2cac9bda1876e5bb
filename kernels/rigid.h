/* Rigid-body motion of one particle (SPEC section 4): velocity Verlet for
 * the centre of mass, and for the rotation a symmetric splitting of the free
 * rigid body into exact rotations about the principal axes (x/2, y/2, z,
 * y/2, x/2), which is second order, time-reversible and keeps the quaternion
 * a unit quaternion up to round-off (renormalised each sub-rotation). */
#ifndef CD_RIGID_H
#define CD_RIGID_H
#include "quat.h"

CD_DEVICE_BEGIN

/* Half kick: v += F/m h, L += tau h.  h = dt/2 [s]. */
CD_INLINE void cd_rigid_kick(cd_vec3 *vel, cd_vec3 *angmom, cd_vec3 force, cd_vec3 torque, cd_real mass, cd_real h)
{
    *vel = cd_v3_axpy(*vel, h / mass, force);
    *angmom = cd_v3_axpy(*angmom, h, torque);
}

/* Component k (0,1,2) of a vector. */
CD_INLINE cd_real cd_v3_comp(cd_vec3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

/* Exact free rotation about principal body axis k for time h: the world
 * angular momentum L is constant, the body turns by (L_body,k / I_k) h. */
CD_INLINE cd_quat cd_rigid_rotate_axis(cd_quat q, cd_vec3 L, cd_vec3 inertia, int k, cd_real h)
{
    cd_vec3 Lb = cd_q_rotate_inv(q, L);
    cd_real phi = cd_v3_comp(Lb, k) / cd_v3_comp(inertia, k) * h; /* [rad] */
    if (phi == CD_R(0)) return q;
    cd_real c = cos(CD_R(0.5) * phi), s = sin(CD_R(0.5) * phi);
    cd_quat r = cd_q(c, k == 0 ? s : CD_R(0), k == 1 ? s : CD_R(0), k == 2 ? s : CD_R(0));
    return cd_q_normalize(cd_q_mul(q, r));
}

/* Drift: x += v dt and the free rotation of the orientation over dt. */
CD_INLINE void cd_rigid_drift(cd_vec3 *pos, cd_quat *q, cd_vec3 vel, cd_vec3 angmom, cd_vec3 inertia, cd_real dt)
{
    *pos = cd_v3_axpy(*pos, dt, vel);
    cd_real h = CD_R(0.5) * dt;
    cd_quat r = *q;
    r = cd_rigid_rotate_axis(r, angmom, inertia, 0, h);
    r = cd_rigid_rotate_axis(r, angmom, inertia, 1, h);
    r = cd_rigid_rotate_axis(r, angmom, inertia, 2, dt);
    r = cd_rigid_rotate_axis(r, angmom, inertia, 1, h);
    r = cd_rigid_rotate_axis(r, angmom, inertia, 0, h);
    *q = r;
}

/* Angular velocity in the world frame: omega = R I^-1 R^T L [rad/s]. */
CD_INLINE cd_vec3 cd_rigid_angvel(cd_quat q, cd_vec3 angmom, cd_vec3 inertia)
{
    cd_vec3 Lb = cd_q_rotate_inv(q, angmom);
    return cd_q_rotate(q, cd_v3(Lb.x / inertia.x, Lb.y / inertia.y, Lb.z / inertia.z));
}

/* Angular momentum from an angular velocity: L = R I R^T omega [kg m^2/s]. */
CD_INLINE cd_vec3 cd_rigid_angmom(cd_quat q, cd_vec3 angvel, cd_vec3 inertia)
{
    cd_vec3 wb = cd_q_rotate_inv(q, angvel);
    return cd_q_rotate(q, cd_v3(wb.x * inertia.x, wb.y * inertia.y, wb.z * inertia.z));
}

/* Rotational kinetic energy 1/2 L . omega [J]. */
CD_INLINE cd_real cd_rigid_rot_energy(cd_quat q, cd_vec3 angmom, cd_vec3 inertia)
{
    return CD_R(0.5) * cd_v3_dot(angmom, cd_rigid_angvel(q, angmom, inertia));
}

/* World position of a body-frame point. */
CD_INLINE cd_vec3 cd_rigid_to_world(cd_vec3 pos, cd_quat q, cd_vec3 body_point)
{
    return cd_v3_add(pos, cd_q_rotate(q, body_point));
}

/* Velocity of a world point attached to the body [m/s]. */
CD_INLINE cd_vec3 cd_rigid_point_velocity(cd_vec3 pos, cd_vec3 vel, cd_vec3 angvel, cd_vec3 point)
{
    return cd_v3_add(vel, cd_v3_cross(angvel, cd_v3_sub(point, pos)));
}

CD_DEVICE_END
#endif
