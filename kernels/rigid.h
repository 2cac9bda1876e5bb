/* Rigid-body motion of one particle (docs/references.md, Motion; docs/motion.md):
 * velocity Verlet for the centre of mass; for the rotation, an isotropic
 * body (three equal moments as stored) turns exactly about the fixed axis of
 * L (one sin/cos), an anisotropic one by the symmetric splitting x/2, y/2,
 * z, y/2, x/2 of the free rigid body into rational (Cayley) rotations about
 * its principal axes: second order, time-reversible, symplectic, no
 * trigonometry and one normalisation per step. */
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

/* Are the three principal moments equal as stored (spheres, hexapods of
 * three equal arms)?  An exact comparison of the stored column: both
 * backends read the same bits, so they take the same branch, and a body
 * whose moments differ by round-off only takes the anisotropic path, which
 * is correct for it too (docs/motion.md). */
CD_INLINE int cd_rigid_isotropic(cd_vec3 inertia) { return inertia.x == inertia.y && inertia.y == inertia.z; }

/* Exact free rotation of an isotropic body (moment I) over dt: the world
 * angular velocity L/I is constant, so the body turns about the fixed axis
 * of L by |L| dt / I.  One sqrt, one sin/cos pair (cd_sincos, the same
 * bits on every backend); the result is brought back to unit length
 * without a second sqrt (cd_q_renormalize). */
CD_INLINE cd_quat cd_rigid_rotate_isotropic(cd_quat q, cd_vec3 L, cd_real I, cd_real dt)
{
    cd_real l2 = cd_v3_norm2(L);
    if (!(l2 > CD_R(0))) return q;
    cd_real l = sqrt(l2);
    cd_real th = CD_R(0.5) * dt * l / I; /* half the angle [rad] */
    cd_real c, s;
    cd_sincos(th, &s, &c);
    s /= l;
    return cd_q_renormalize(cd_q_mul(cd_q(c, s * L.x, s * L.y, s * L.z), q));
}

/* Sub-rotation of the splitting about principal body axis k for a time h,
 * without trigonometry: with tau = h L_body,k / (2 I_k) = a L_body,k, the
 * body turns about its axis k by 2 atan(tau) (an odd function of L_body,k
 * alone, equal to h L_body,k / I_k up to O(h^3)), i.e. q -> q (1, tau e_k),
 * a unit quaternion times sqrt(1 + tau^2) (normalised once per step by the
 * caller).  Lb, the world L in the body frame, turns the other way by the
 * same angle, through its rational cosine and sine (1 - tau^2, 2 tau) /
 * (1 + tau^2).  docs/motion.md gives why this is the exact flow of a
 * modified rotor Hamiltonian, hence symplectic and reversible. */
CD_INLINE void cd_rigid_cayley_axis(cd_quat *q, cd_vec3 *Lb, int k, cd_real a)
{
    cd_vec3 v = *Lb;
    cd_quat r = *q;
    cd_real tau, li, lj; /* (i, j, k) cyclic */
    if (k == 0) {
        tau = a * v.x;
        li = v.y;
        lj = v.z;
    } else if (k == 1) {
        tau = a * v.y;
        li = v.z;
        lj = v.x;
    } else {
        tau = a * v.z;
        li = v.x;
        lj = v.y;
    }
    if (tau == CD_R(0)) return; /* the identity (2D: the x and y sub-rotations) */
    cd_real t2 = tau * tau, den = CD_R(1) / (CD_R(1) + t2);
    cd_real c = (CD_R(1) - t2) * den, s = CD_R(2) * tau * den;
    cd_real ni = c * li + s * lj, nj = c * lj - s * li;
    /* r (1, tau e_k) */
    if (k == 0) {
        *Lb = cd_v3(v.x, ni, nj);
        *q = cd_q(r.w - tau * r.x, r.x + tau * r.w, r.y + tau * r.z, r.z - tau * r.y);
    } else if (k == 1) {
        *Lb = cd_v3(nj, v.y, ni);
        *q = cd_q(r.w - tau * r.y, r.x - tau * r.z, r.y + tau * r.w, r.z + tau * r.x);
    } else {
        *Lb = cd_v3(ni, nj, v.z);
        *q = cd_q(r.w - tau * r.z, r.x + tau * r.y, r.y - tau * r.x, r.z + tau * r.w);
    }
}

/* Free rotation of an anisotropic body over dt: the symmetric splitting
 * x dt/2, y dt/2, z dt, y dt/2, x dt/2 into rational sub-rotations, one
 * normalisation at the end.  Returns the new orientation; *Lb_out is the
 * world L in the new body frame (for the angular velocity). */
CD_INLINE cd_quat cd_rigid_rotate_anisotropic(cd_quat q, cd_vec3 L, cd_vec3 inertia, cd_real dt, cd_vec3 *Lb_out)
{
    cd_vec3 Lb = cd_q_rotate_inv(q, L);
    cd_real ax = CD_R(0.25) * dt / inertia.x, ay = CD_R(0.25) * dt / inertia.y, az = CD_R(0.5) * dt / inertia.z;
    cd_quat r = q;
    cd_rigid_cayley_axis(&r, &Lb, 0, ax);
    cd_rigid_cayley_axis(&r, &Lb, 1, ay);
    cd_rigid_cayley_axis(&r, &Lb, 2, az);
    cd_rigid_cayley_axis(&r, &Lb, 1, ay);
    cd_rigid_cayley_axis(&r, &Lb, 0, ax);
    *Lb_out = Lb;
    return cd_q_normalize(r);
}

/* Drift: x += v dt and the free rotation of the orientation over dt; also
 * the angular velocity at the new orientation [rad/s].  keep = 1 leaves
 * the orientation of an isotropic body as it is (a sphere, whose geometry
 * does not depend on it: physics.sphere_orientation: fixed, docs/motion.md);
 * its position and angular velocity are those of keep = 0, bit for bit. */
CD_INLINE void cd_rigid_drift_angvel(cd_vec3 *pos, cd_quat *q, cd_vec3 *angvel, cd_vec3 vel, cd_vec3 angmom,
                                     cd_vec3 inertia, cd_real dt, int keep)
{
    *pos = cd_v3_axpy(*pos, dt, vel);
    if (cd_rigid_isotropic(inertia)) {
        if (!keep) *q = cd_rigid_rotate_isotropic(*q, angmom, inertia.x, dt);
        *angvel = cd_v3_scale(angmom, CD_R(1) / inertia.x);
    } else {
        cd_vec3 Lb;
        *q = cd_rigid_rotate_anisotropic(*q, angmom, inertia, dt, &Lb);
        *angvel = cd_q_rotate(*q, cd_v3(Lb.x / inertia.x, Lb.y / inertia.y, Lb.z / inertia.z));
    }
}

/* Drift without the angular velocity. */
CD_INLINE void cd_rigid_drift(cd_vec3 *pos, cd_quat *q, cd_vec3 vel, cd_vec3 angmom, cd_vec3 inertia, cd_real dt)
{
    cd_vec3 w;
    cd_rigid_drift_angvel(pos, q, &w, vel, angmom, inertia, dt, 0);
}

/* Angular velocity in the world frame: omega = R I^-1 R^T L [rad/s];
 * L / I for an isotropic body. */
CD_INLINE cd_vec3 cd_rigid_angvel(cd_quat q, cd_vec3 angmom, cd_vec3 inertia)
{
    if (cd_rigid_isotropic(inertia)) return cd_v3_scale(angmom, CD_R(1) / inertia.x);
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
