/* The pose of a particle and the world ends of its primitives, for the
 * time step's items (kernels/step_items.h) and the neighbour-list build:
 * the ends from the pose, where they are stored, the skin test against
 * the last build, and the reference pose it bounds the motion from.
 * Device-safe: C11 and OpenCL C 1.2. */
#ifndef CD_POSE_ITEMS_H
#define CD_POSE_ITEMS_H
#include "cols.h"
#include "rigid.h"
#include "broadphase.h"

CD_DEVICE_BEGIN

/* CD_ENDS_FROM_POSE 1 (the offload variants, whose step is bound by memory
 * traffic; docs/performance.md, "Ends from the pose"): the step does not
 * store the primitives' world ends.  The pair and wall passes compute them
 * where they use them, from the particle's pose and the body-frame ends
 * (cd_prim_world_ends: the same function on the same numbers, so the same
 * bits as the stored ones); the neighbour-list build stores them (it bins
 * and pairs them, and they become the reference ends of the run file), and
 * so does a sync; the skin test bounds the ends' motion from the pose at
 * the last build (cd_pose_moved) and computes them only when the bound
 * does not settle it, so it gives the per-end test's answer and the
 * rebuilds come at the same steps.  0 on host threads and in OpenCL,
 * where the stored ends cost fewer instructions. */
#ifndef CD_ENDS_FROM_POSE
#if defined(CAPDEM_OFFLOAD_TARGET) && CAPDEM_OFFLOAD_TARGET && !defined(__OPENCL_VERSION__)
#define CD_ENDS_FROM_POSE 1
#else
#define CD_ENDS_FROM_POSE 0
#endif
#endif

/* Reals per particle of the pose at the last neighbour-list build
 * (cd_item_ref_pose): centre [m] (3), orientation (4), reach [m] (the
 * largest distance of a body-frame end from the centre). */
#define CD_REF_POSE 8

/* World axis ends *a, *b of primitive i for its particle's pose (centre x
 * [m], orientation o).  A primitive without an arm (a sphere's ball, both
 * body-frame ends at the body origin) has both ends at x: the rotation of
 * a zero vector is a zero, and x plus a zero is x (but for the sign of a
 * zero coordinate of x), so the two rotations are skipped
 * (docs/performance.md, "The sphere step").  An arm through the body's
 * centre (b_body = -a_body, every arm of the named shapes: rods, crosses,
 * hexapods) is rotated once: the rotation (cd_q_rotate) of -v is minus
 * the rotation of v, operation by operation (negation commutes with
 * rounding to nearest), so x + -(R a) equals x + R b but for the sign of
 * a zero coordinate where x has a -0 (a zero coordinate of b_body may be
 * +0 where -a_body's is -0, which changes only the signs of zero terms);
 * docs/performance.md, "Session 17, hexapods".  (Written as one select
 * of R b, which GCC compiles to fewer instructions around a sphere's
 * early return than two stores on two paths.) */
CD_INLINE void cd_prim_ends_at(cd_cols c, cd_prim_id i, cd_vec3 x, cd_quat o, cd_vec3 *a, cd_vec3 *b)
{
    cd_int r = cd_prim_arm_of(c, i);
    if (r < 0) {
        *a = x;
        *b = x;
        return;
    }
    cd_vec3 ea = c.arm[r].a_body, eb = c.arm[r].b_body; /* [m] */
    cd_vec3 ra = cd_q_rotate(o, ea);
    cd_vec3 rb = eb.x == -ea.x && eb.y == -ea.y && eb.z == -ea.z ? cd_v3_neg(ra) : cd_q_rotate(o, eb);
    *a = cd_v3_add(x, ra);
    *b = cd_v3_add(x, rb);
}

/* Primitive i's world ends a, b into its columns (end b: its arm's, where
 * it has one; a ball's b is its a, cd_prim_b). */
CD_INLINE void cd_prim_ends_store(cd_cols c, cd_prim_id i, cd_vec3 a, cd_vec3 b)
{
    cd_int r = cd_prim_arm_of(c, i);
    c.prim_a[i] = a;
    if (r >= 0) c.arm[r].b = b;
}

/* World axis ends of primitive i from its particle's pose. */
CD_INLINE void cd_item_prim_ends(cd_cols c, cd_prim_id i)
{
    cd_particle_id p = c.prim_particle[i];
    cd_vec3 a, b;
    cd_prim_ends_at(c, i, c.position[p], c.orientation[p], &a, &b);
    cd_prim_ends_store(c, i, a, b);
}

/* Primitive i's ends become the reference of the skin test at a
 * neighbour-list build. */
CD_INLINE void cd_item_prim_refs(cd_cols c, cd_prim_id i)
{
    cd_int r = cd_prim_arm_of(c, i);
    c.prim_a_ref[i] = c.prim_a[i];
    if (r >= 0) c.arm[r].b_ref = c.arm[r].b;
}

/* The world ends of particle q's primitives for the pose x [m], o,
 * stored; with test = 1 also their skin test against the ends at the last
 * build (limit2 = (skin/2)^2 [m^2]): 1 when one moved more than half the
 * skin. */
CD_INLINE int cd_store_ends(cd_cols c, cd_particle_id q, cd_vec3 x, cd_quat o, int test, cd_real limit2)
{
    int moved = 0;
    cd_int first = c.prim_first[q], last = first + c.prim_count[q];
    for (cd_int i = first; i < last; i++) {
        cd_vec3 a, b;
        cd_prim_ends_at(c, i, x, o, &a, &b);
        cd_prim_ends_store(c, i, a, b);
        if (test) moved |= cd_bp_moved(a, c.prim_a_ref[i], b, cd_prim_b_ref(c, i), limit2);
    }
    return moved;
}

/* The world ends of particle q's primitives from its pose, stored (the
 * build and a sync when CD_ENDS_FROM_POSE). */
CD_INLINE void cd_item_particle_ends(cd_cols c, cd_particle_id q)
{
    cd_store_ends(c, q, c.position[q], c.orientation[q], 0, 0);
}

/* World ends of primitive i as the step's passes use them: stored by the
 * last advance, or (CD_ENDS_FROM_POSE) computed from the pose. */
CD_INLINE void cd_prim_world_ends(cd_cols c, cd_prim_id i, cd_vec3 *a, cd_vec3 *b)
{
#if CD_ENDS_FROM_POSE
    cd_particle_id p = c.prim_particle[i];
    cd_prim_ends_at(c, i, c.position[p], c.orientation[p], a, b);
#else
    *a = c.prim_a[i];
    *b = cd_prim_b(c, i);
#endif
}

/* World point of primitive i when it has no arm (cd_prim_arm_of < 0: a
 * ball at its particle's centre, both ends the same point): its stored
 * end a, or (CD_ENDS_FROM_POSE) its particle's centre, the value
 * cd_prim_world_ends gives both ends [m]. */
CD_INLINE cd_vec3 cd_ball_world_point(cd_cols c, cd_prim_id i)
{
#if CD_ENDS_FROM_POSE
    return c.position[c.prim_particle[i]];
#else
    return c.prim_a[i];
#endif
}

/* Is particle q a sphere: one primitive, a ball at its centre (no arm,
 * cd_prim_arm_of < 0)?  Its geometry does not depend on its orientation. */
CD_INLINE int cd_particle_is_sphere(cd_cols c, cd_particle_id q)
{
    return c.prim_count[q] == 1 && cd_prim_arm_of(c, c.prim_first[q]) < 0;
}

/* At a build: particle q's pose and reach into ref_pose (CD_REF_POSE
 * reals a particle), for cd_pose_moved. */
CD_INLINE void cd_item_ref_pose(cd_cols c, cd_particle_id q, CD_GLOBAL cd_real *ref_pose)
{
    CD_GLOBAL cd_real *r = ref_pose + (cd_long)CD_REF_POSE * q;
    cd_vec3 x = c.position[q];
    cd_quat o = c.orientation[q];
    cd_real reach = 0; /* [m] */
    cd_int first = c.prim_first[q], last = first + c.prim_count[q];
    for (cd_int i = first; i < last; i++) {
        cd_int arm = cd_prim_arm_of(c, i);
        if (arm < 0) continue; /* a ball at the centre: its ends move with x only */
        cd_real ra = cd_v3_norm(c.arm[arm].a_body), rb = cd_v3_norm(c.arm[arm].b_body);
        reach = ra > reach ? ra : reach;
        reach = rb > reach ? rb : reach;
    }
    r[0] = x.x;
    r[1] = x.y;
    r[2] = x.z;
    r[3] = o.w;
    r[4] = o.x;
    r[5] = o.y;
    r[6] = o.z;
    r[7] = reach;
}

/* The skin test of particle q (now at centre x, orientation o) against
 * its pose at the last build (ref_pose; NULL before the first build: 1).
 * An end at body-frame offset e moved by (x - x_ref) + (R(o) - R(o_ref)) e,
 * and |R(o) - R(o_ref)| = 2 sin(theta/2) <= 2 |o -+ o_ref| for unit
 * quaternions (theta: the angle between the two orientations; o and -o
 * are one rotation), so no end moved more than |x - x_ref| + 2 min|o -+
 * o_ref| reach.  When that bound, grown by far more than the roundings of
 * the ends (1e-9 relative, 1e-12 of the coordinates' size), is within
 * half the skin (limit2 = (skin/2)^2 [m^2]), no end moved beyond it: 0,
 * without reading the primitives.  Otherwise the ends now and at the build
 * are computed (as the advance and the build computed them: the same
 * bits) and tested one by one, as the stored ends were. */
CD_INLINE int cd_pose_moved(cd_cols c, cd_particle_id q, cd_vec3 x, cd_quat o, const CD_GLOBAL cd_real *ref_pose,
                            cd_real limit2)
{
    if (!ref_pose) return 1;
    const CD_GLOBAL cd_real *r = ref_pose + (cd_long)CD_REF_POSE * q;
    cd_vec3 xr = cd_v3(r[0], r[1], r[2]);
    cd_quat orf = cd_q(r[3], r[4], r[5], r[6]);
    cd_real reach = r[7];
    cd_real dw = o.w - orf.w, dx = o.x - orf.x, dy = o.y - orf.y, dz = o.z - orf.z;
    cd_real sw = o.w + orf.w, sx = o.x + orf.x, sy = o.y + orf.y, sz = o.z + orf.z;
    cd_real dm = dw * dw + dx * dx + dy * dy + dz * dz, dp = sw * sw + sx * sx + sy * sy + sz * sz;
    cd_real bound = cd_v3_norm(cd_v3_sub(x, xr)) + CD_R(2) * sqrt(dm < dp ? dm : dp) * reach;
    bound = bound * CD_R(1.000000001) + CD_R(1e-12) * (fabs(x.x) + fabs(x.y) + fabs(x.z) + reach);
    if (bound * bound <= limit2) return 0;
    int moved = 0;
    cd_int first = c.prim_first[q], last = first + c.prim_count[q];
    for (cd_int i = first; i < last; i++) {
        cd_vec3 a, b, ar, br;
        cd_prim_ends_at(c, i, x, o, &a, &b);
        cd_prim_ends_at(c, i, xr, orf, &ar, &br);
        moved |= cd_bp_moved(a, ar, b, br, limit2);
    }
    return moved;
}

CD_DEVICE_END
#endif
