/* Narrow phase between two spherocylinders (docs/references.md, Contacts).
 *
 * Device-safe: compiled as C11 (host, OpenMP declare target) and as
 * OpenCL C 1.2.  Only static inline functions, pointer parameters point to
 * private (local) variables, no recursion, no program-scope tables.
 *
 * A spherocylinder primitive is the set of points within radius r [m] of its
 * axis segment.  Segment i runs P(s) = p0 + s (p1 - p0), segment j runs
 * Q(t) = q0 + t (q1 - q0), with s, t in [0, 1] [1].  Either segment may have
 * zero length (a sphere).
 *
 * Conventions (see docs/contacts.md, "Contact geometry"):
 *   a = P(s), b = Q(t)  closest points of the two axes [m]
 *   D = |b - a|         distance of the axes [m]
 *   overlap = r_i + r_j - D [m], contact when > 0
 *   n = (b - a) / D     unit normal, FROM i TOWARDS j: the normal force on j
 *                       is +F_n n and the force on i is -F_n n
 *   c = (a + b) / 2     contact point [m], unless the parallel rule applies
 */
#ifndef CD_SEGSEG_H
#define CD_SEGSEG_H
#include "defs.h"
#include "vec3.h"
#include "geom_types.h"

/* Relative threshold on sin^2 of the angle between the two axes under which
 * cd_segseg_closest treats them as parallel [1].  The line-line solution is
 * evaluated with a cross product, whose relative error is about eps/sin;
 * below sin = 1e-14 the cross product is rounding noise.  The resulting
 * distance error is at most |d1| sin <= 1e-14 |d1| either way. */
#define CD_SEGSEG_PARALLEL_SIN2 CD_R(1e-28)
/* |v|^2 below this is rescaled before normalising (avoids underflow) [m^2]. */
#define CD_SEGSEG_TINY2 CD_R(1e-200)

CD_DEVICE_BEGIN

/* cd_segseg_closest for two axes of non-zero length (a = |d1|^2 > 0, e =
 * |d2|^2 > 0 [m^2]) with d1 = p1 - p0, d2 = q1 - q0, w = q0 - p0 [m] and
 * m = d1 x d2, m2 = |m|^2 [m^4] at hand (the pair pass has them already,
 * cd_pair_narrow): steps 1-3 of cd_segseg_closest. */
CD_INLINE void cd_segseg_closest_axes(cd_vec3 p0, cd_vec3 q0, cd_vec3 q1, cd_vec3 d1, cd_vec3 d2, cd_vec3 w, cd_real a,
                                      cd_real e, cd_vec3 m, cd_real m2, cd_real *s, cd_real *t)
{
    cd_real ss, tt;
    if (m2 > CD_SEGSEG_PARALLEL_SIN2 * a * e) {
        ss = cd_v3_dot(cd_v3_cross(w, d2), m) / m2;
    } else {
        cd_real u0 = cd_v3_dot(w, d1) / a;
        cd_real u1 = cd_v3_dot(cd_v3_sub(q1, p0), d1) / a;
        cd_real lo = u0 < u1 ? u0 : u1;
        cd_real hi = u0 < u1 ? u1 : u0;
        lo = lo > CD_R(0) ? lo : CD_R(0);
        hi = hi < CD_R(1) ? hi : CD_R(1);
        ss = CD_R(0.5) * (lo + hi);
    }
    ss = cd_clamp01(ss);
    tt = cd_v3_dot(cd_v3_sub(cd_v3_axpy(p0, ss, d1), q0), d2) / e;
    if (tt < CD_R(0)) {
        tt = CD_R(0);
        ss = cd_clamp01(cd_v3_dot(w, d1) / a);
    } else if (tt > CD_R(1)) {
        tt = CD_R(1);
        ss = cd_clamp01(cd_v3_dot(cd_v3_sub(q1, p0), d1) / a);
    }
    *s = ss;
    *t = tt;
}

/* Closest points of two segments (docs/references.md, Contacts, narrow phase).
 * Inputs: end points p0, p1 of segment i and q0, q1 of segment j [m].
 * Outputs: *s, *t in [0, 1] [1], parameters of a closest pair P(s), Q(t).
 *
 * The squared distance F(s,t) = |P(s) - Q(t)|^2 is a convex quadratic on the
 * unit square.  Algorithm (clamped line solution, exact for convex F):
 *   1. s0 = clamp(s*) where s* is the parameter on i of the closest points of
 *      the two infinite lines, s* = ((q0 - p0) x d2) . m / |m|^2, m = d1 x d2
 *      (cross-product form: no a*e - b^2 cancellation for nearly parallel
 *      axes).  For parallel axes every s is on the line minimum; s0 is then
 *      the middle of the part of [0,1] covered by j projected onto i, so that
 *      the closest pair of overlapping parallel segments is the middle of
 *      their overlap (symmetric under exchanging i and j).
 *   2. t = projection of P(s0) onto line j; if inside [0,1] done (P(s0) is
 *      the minimum of F over the strip s in [0,1], so it is the minimum over
 *      the square too).
 *   3. otherwise clamp t to the violated end (the minimum then lies on that
 *      edge, by convexity) and take s = clamp(projection of Q(t) onto i).
 * Zero-length segments reduce to a clamped point-segment projection; both
 * zero gives s = t = 0.  No tolerance other than the relative parallel test
 * (CD_SEGSEG_PARALLEL_SIN2 scaled by |d1|^2 |d2|^2); no NaN for finite
 * input whose squared lengths do not overflow (|coordinates| < 1e150). */
CD_INLINE void cd_segseg_closest(cd_vec3 p0, cd_vec3 p1, cd_vec3 q0, cd_vec3 q1, cd_real *s, cd_real *t)
{
    cd_vec3 d1 = cd_v3_sub(p1, p0);
    cd_vec3 d2 = cd_v3_sub(q1, q0);
    cd_vec3 w = cd_v3_sub(q0, p0); /* from p0 to q0 [m] */
    cd_real a = cd_v3_dot(d1, d1); /* |d1|^2 [m^2] */
    cd_real e = cd_v3_dot(d2, d2); /* |d2|^2 [m^2] */
    cd_real ss, tt;

    if (a <= CD_R(0) && e <= CD_R(0)) {
        ss = CD_R(0);
        tt = CD_R(0);
    } else if (a <= CD_R(0)) {
        /* i is a point: project p0 onto j. */
        ss = CD_R(0);
        tt = cd_clamp01(-cd_v3_dot(w, d2) / e);
    } else if (e <= CD_R(0)) {
        /* j is a point: project q0 onto i. */
        tt = CD_R(0);
        ss = cd_clamp01(cd_v3_dot(w, d1) / a);
    } else {
        cd_vec3 m = cd_v3_cross(d1, d2);
        cd_segseg_closest_axes(p0, q0, q1, d1, d2, w, a, e, m, cd_v3_dot(m, m), &ss, &tt);
    }
    *s = ss;
    *t = tt;
}

/* Length of v [same unit as v] and, when it is not zero, the unit vector
 * along v in *u [1].  Safe against underflow of |v|^2.  Returns 0 (and
 * leaves *u unchanged) for the zero vector.  (docs/references.md, Contacts: D and n.) */
CD_INLINE cd_real cd_segseg_normalize(cd_vec3 v, cd_vec3 *u)
{
    cd_real l2 = cd_v3_dot(v, v);
    if (l2 >= CD_SEGSEG_TINY2) {
        cd_real l = sqrt(l2);
        *u = cd_v3(v.x / l, v.y / l, v.z / l);
        return l;
    } else {
        cd_real ax = fabs(v.x), ay = fabs(v.y), az = fabs(v.z);
        cd_real mx = ax > ay ? ax : ay;
        cd_vec3 vs;
        cd_real l;
        mx = mx > az ? mx : az;
        if (mx == CD_R(0)) return CD_R(0);
        vs = cd_v3(v.x / mx, v.y / mx, v.z / mx);
        l = sqrt(cd_v3_dot(vs, vs));
        *u = cd_v3(vs.x / l, vs.y / l, vs.z / l);
        return mx * l;
    }
}

/* A deterministic unit vector perpendicular to the non-zero vector u [1]
 * (docs/references.md, Contacts: normal when the axes touch).  It depends on the line of u only,
 * not on its sign or length: u is first oriented so that its component of
 * largest magnitude is positive, then crossed with the coordinate axis of
 * smallest |u_k| (first index on ties).  u = 0 gives (0, 0, 1). */
CD_INLINE cd_vec3 cd_segseg_any_perpendicular(cd_vec3 u)
{
    cd_real ax = fabs(u.x), ay = fabs(u.y), az = fabs(u.z);
    cd_vec3 f, n;
    cd_real big;
    if (ax >= ay && ax >= az) big = u.x;
    else if (ay >= az) big = u.y;
    else big = u.z;
    if (big == CD_R(0)) return cd_v3(0, 0, 1);
    if (big < CD_R(0)) u = cd_v3_neg(u);
    /* u x e_k for the smallest |u_k| */
    if (ax <= ay && ax <= az) f = cd_v3(0, u.z, -u.y);
    else if (ay <= az) f = cd_v3(-u.z, 0, u.x);
    else f = cd_v3(u.y, -u.x, 0);
    n = cd_v3(0, 0, 1);
    cd_segseg_normalize(f, &n);
    return n;
}

/* Unit normal used when the axes touch, D = 0 (docs/references.md, Contacts; deep overlap) [1].
 * d1, d2: axis vectors of i and j [m]; wm = mid_j - mid_i, from the centre
 * of segment i to the centre of segment j [m].
 * Non-parallel non-degenerate axes: n = +-(d1 x d2)/|d1 x d2|, the common
 * perpendicular, with dot(n, wm) >= 0 (d1 x d2 itself when the dot product
 * is exactly 0, which it is in exact arithmetic when the axes intersect).
 * Parallel axes or a zero-length segment: the perpendicular f of the longer
 * axis from cd_segseg_any_perpendicular (two points: (0,0,1)), with
 * dot(n, wm) >= 0; if that dot product is exactly 0, n is flipped when the
 * first non-zero component of wm is negative; if wm = 0, when segment j is
 * the longer one.
 * Exchanging i and j flips n: d1 x d2 and wm change sign, f does not and
 * each tie-break does.  The only exception is two parallel (or zero-length)
 * segments with the same centre and the same length, where the geometry
 * offers no antisymmetric choice (for collinear ones the swap is the
 * identity). */
CD_INLINE cd_vec3 cd_segseg_touch_normal(cd_vec3 d1, cd_vec3 d2, cd_vec3 wm)
{
    cd_real a = cd_v3_dot(d1, d1);
    cd_real e = cd_v3_dot(d2, d2);
    cd_vec3 m = cd_v3_cross(d1, d2);
    cd_real m2 = cd_v3_dot(m, m);
    cd_vec3 n = cd_v3(0, 0, 1);
    cd_real sd;
    if (a > CD_R(0) && e > CD_R(0) && m2 > CD_SEGSEG_PARALLEL_SIN2 * a * e && cd_segseg_normalize(m, &n) > CD_R(0)) {
        /* common perpendicular; already antisymmetric, no tie-break */
        sd = cd_v3_dot(n, wm);
    } else {
        n = cd_segseg_any_perpendicular(a >= e ? d1 : d2);
        sd = cd_v3_dot(n, wm);
        if (sd == CD_R(0)) sd = wm.x != CD_R(0) ? wm.x : (wm.y != CD_R(0) ? wm.y : wm.z);
        if (sd == CD_R(0)) sd = a - e;
    }
    return sd < CD_R(0) ? cd_v3_neg(n) : n;
}

/* Weight [1] of the parallel rule's contact point for axes at an angle
 * whose squared sine is cross2 / norm2 (norm2 > 0; compared by products,
 * so that the common case, far from the cut-off, costs no division), with
 * the cut-off sin_parallel [1]
 * (docs/references.md, Contacts): 1 below the cut-off (the paper's parallel contact point), else
 * 0 (the closest points).  With blend (material.parallel_blend) the step
 * becomes a ramp: 0 only at or above twice the cut-off's sine, linear in
 * the sine between.  Without it the point jumps by up to half an arm's
 * length when the angle crosses the cut-off: a torque that is not the
 * gradient of any energy, which kept pairs of 2D crosses at the cut-off
 * spinning at 10-18 rad/s in a compressed packing, and the packing from
 * relaxing (docs/contacts.md).  sin_parallel <= 0: the rule is off. */
CD_INLINE cd_real cd_parallel_weight(cd_real cross2, cd_real norm2, cd_real sin_parallel, cd_int blend)
{
    cd_real sp2 = sin_parallel * sin_parallel;
    if (!(sin_parallel > CD_R(0)) || !(cross2 < (blend ? CD_R(4) : CD_R(1)) * sp2 * norm2)) return CD_R(0);
    if (cross2 < sp2 * norm2) return CD_R(1);
    return CD_R(2) - sqrt(cross2 / norm2) / sin_parallel;
}

/* Contact geometry of two spherocylinders (docs/references.md, Contacts): cd_segseg_contact, or
 * cd_segseg_contact_at when the closest-point parameters s, t [1] of
 * cd_segseg_closest are at hand.
 * Inputs: axis ends p0, p1 and radius ri of primitive i, q0, q1 and rj of
 * primitive j [m]; sin_parallel [1] = sine of the parallel cut-off angle
 * (default sin(2 degrees), docs/references.md, Contacts); <= 0 disables the parallel rule.
 * Output *g: distance D [m], overlap ri + rj - D [m], unit normal n from i to
 * j [1], contact point [m], parallel flag.
 *
 * Closest points a = P(s), b = Q(t) from cd_segseg_closest; D = |b - a|,
 * n = (b - a)/D, c = (a + b)/2.
 * D = 0 (axes touch): n from cd_segseg_touch_normal (deterministic unit).
 * Parallel rule: both segments of non-zero length, sin(angle) <
 * sin_parallel (2 sin_parallel with blend) and each segment's projection
 * onto the other's axis overlaps it.  Let
 * [lo_i, hi_i] = [0,1] intersected with the parameters on axis i of q0, q1
 * projected onto axis i, A = P((lo_i + hi_i)/2) the middle of that section
 * on axis i, and B the same on axis j.  Then c = (A + B)/2: the middle of the
 * overlapping section, half-way between the two axes (for exactly parallel
 * axes c = A + n D/2): the contact point below the cut-off (g->parallel = 1),
 * with blend mixed with the closest points' middle by cd_parallel_weight
 * between the cut-off and twice it, so that the point moves continuously
 * with the angle.  D, overlap and n stay those of the closest points so that the
 * force stays continuous. */
/* The closest points' part of cd_segseg_contact_at (everything but the
 * parallel rule). */
CD_INLINE void cd_segseg_contact_closest(cd_vec3 p0, cd_vec3 p1, cd_real ri, cd_vec3 q0, cd_vec3 q1, cd_real rj,
                                         cd_real s, cd_real t, cd_contact_geom *g)
{
    cd_real D;
    cd_vec3 a, b, n;
    cd_vec3 d1 = cd_v3_sub(p1, p0);
    cd_vec3 d2 = cd_v3_sub(q1, q0);

    a = cd_v3_axpy(p0, s, d1);
    b = cd_v3_axpy(q0, t, d2);
    n = cd_v3(0, 0, 1);
    D = cd_segseg_normalize(cd_v3_sub(b, a), &n);
    if (D == CD_R(0)) {
        cd_vec3 wm = cd_v3_scale(cd_v3_sub(cd_v3_add(q0, q1), cd_v3_add(p0, p1)), CD_R(0.5));
        n = cd_segseg_touch_normal(d1, d2, wm);
    }
    g->distance = D;
    g->overlap = ri + rj - D;
    g->normal = n;
    g->point = cd_v3_scale(cd_v3_add(a, b), CD_R(0.5));
    g->parallel = 0;
}

/* The parallel rule's part of cd_segseg_contact_at for two axes of
 * non-zero length (aa = |d1|^2, ee = |d2|^2 > 0 [m^2]) whose rule weight
 * wpar (cd_parallel_weight) is > 0: g->point moves to (or towards) the
 * middle of the overlapping section. */
CD_INLINE void cd_segseg_parallel_point(cd_vec3 p0, cd_vec3 p1, cd_vec3 q0, cd_vec3 q1, cd_vec3 d1, cd_vec3 d2,
                                        cd_real aa, cd_real ee, cd_real wpar, cd_contact_geom *g)
{
    /* section of axis i covered by j, and of axis j covered by i */
    cd_real u0 = cd_v3_dot(cd_v3_sub(q0, p0), d1) / aa;
    cd_real u1 = cd_v3_dot(cd_v3_sub(q1, p0), d1) / aa;
    cd_real v0 = cd_v3_dot(cd_v3_sub(p0, q0), d2) / ee;
    cd_real v1 = cd_v3_dot(cd_v3_sub(p1, q0), d2) / ee;
    cd_real loi = u0 < u1 ? u0 : u1, hii = u0 < u1 ? u1 : u0;
    cd_real loj = v0 < v1 ? v0 : v1, hij = v0 < v1 ? v1 : v0;
    loi = loi > CD_R(0) ? loi : CD_R(0);
    hii = hii < CD_R(1) ? hii : CD_R(1);
    loj = loj > CD_R(0) ? loj : CD_R(0);
    hij = hij < CD_R(1) ? hij : CD_R(1);
    if (loi <= hii && loj <= hij) {
        cd_vec3 A = cd_v3_axpy(p0, CD_R(0.5) * (loi + hii), d1);
        cd_vec3 B = cd_v3_axpy(q0, CD_R(0.5) * (loj + hij), d2);
        cd_vec3 mid = cd_v3_scale(cd_v3_add(A, B), CD_R(0.5));
        g->parallel = wpar == CD_R(1);
        g->point = g->parallel ? mid : cd_v3_lerp(g->point, mid, wpar);
    }
}

CD_INLINE void cd_segseg_contact_at(cd_vec3 p0, cd_vec3 p1, cd_real ri, cd_vec3 q0, cd_vec3 q1, cd_real rj, cd_real s,
                                    cd_real t, cd_real sin_parallel, cd_int blend, cd_contact_geom *g)
{
    cd_vec3 d1 = cd_v3_sub(p1, p0);
    cd_vec3 d2 = cd_v3_sub(q1, q0);
    cd_segseg_contact_closest(p0, p1, ri, q0, q1, rj, s, t, g);
    if (sin_parallel > CD_R(0)) {
        cd_real aa = cd_v3_dot(d1, d1);
        cd_real ee = cd_v3_dot(d2, d2);
        cd_vec3 m = cd_v3_cross(d1, d2);
        cd_real wpar =
            aa > CD_R(0) && ee > CD_R(0) ? cd_parallel_weight(cd_v3_dot(m, m), aa * ee, sin_parallel, blend) : CD_R(0);
        if (wpar > CD_R(0)) cd_segseg_parallel_point(p0, p1, q0, q1, d1, d2, aa, ee, wpar, g);
    }
}

/* The narrow phase of two points (spheres: axes of zero length, p0 == p1
 * and q0 == q1): cd_segseg_closest, cd_segseg_clearly_apart and
 * cd_segseg_contact_at with the same operations on the same values, so the
 * same bits, less what vanishes for points: the closest points are the
 * points (s = t = 0) and the parallel rule never applies.  Returns 1 when
 * the spheres (centres p, q [m], radii ri, rj [m]) are clearly apart (g is
 * then not filled), 0 after filling g. */
CD_INLINE int cd_segseg_point_contact(cd_vec3 p, cd_real ri, cd_vec3 q, cd_real rj, cd_contact_geom *g)
{
    /* P(0) = p + 0 (p1 - p0): the general path's sum, which turns a -0
     * coordinate into +0, is kept for the same bits */
    cd_vec3 a = cd_v3_add(p, cd_v3_zero()), b = cd_v3_add(q, cd_v3_zero());
    cd_vec3 ab = cd_v3_sub(b, a);
    cd_real reach = ri + rj; /* [m] */
    if (cd_v3_dot(ab, ab) > reach * reach * CD_R(1.000000001)) return 1;
    cd_vec3 n = cd_v3(0, 0, 1);
    cd_real D = cd_segseg_normalize(ab, &n);
    if (D == CD_R(0)) {
        cd_vec3 wm = cd_v3_scale(cd_v3_sub(cd_v3_add(q, q), cd_v3_add(p, p)), CD_R(0.5));
        n = cd_segseg_touch_normal(cd_v3_sub(p, p), cd_v3_sub(q, q), wm);
    }
    g->distance = D;
    g->overlap = ri + rj - D;
    g->normal = n;
    g->point = cd_v3_scale(cd_v3_add(a, b), CD_R(0.5));
    g->parallel = 0;
    return 0;
}

/* Is the segment with ends a, b a point (an arm of zero length: a sphere)? */
CD_INLINE int cd_segseg_is_point(cd_vec3 a, cd_vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/* cd_segseg_contact_at at the closest points of cd_segseg_closest, with
 * the paper's parallel rule (no blend). */
CD_INLINE void cd_segseg_contact(cd_vec3 p0, cd_vec3 p1, cd_real ri, cd_vec3 q0, cd_vec3 q1, cd_real rj,
                                 cd_real sin_parallel, cd_contact_geom *g)
{
    cd_real s, t;
    cd_segseg_closest(p0, p1, q0, q1, &s, &t);
    cd_segseg_contact_at(p0, p1, ri, q0, q1, rj, s, t, sin_parallel, 0, g);
}

/* Square-root-free pre-test of the force kernel: 1 when the spherocylinders
 * (axis ends p0, p1, q0, q1 [m], radii ri, rj [m]) are apart at their
 * closest points P(s), Q(t) of cd_segseg_closest by more than 1e-9 of
 * ri + rj in squared distance, i.e. |Q(t) - P(s)|^2 > (ri + rj)^2 (1 + 1e-9).
 * Then cd_segseg_contact_at gives overlap < 0 (its D, a square root of the
 * same sum, is within a few 1e-16 of it), so skipping it changes no result;
 * it spares the square root, the divisions and the parallel rule of the
 * separated rows, most rows of a Verlet list with a skin. */
CD_INLINE int cd_segseg_clearly_apart(cd_vec3 p0, cd_vec3 p1, cd_real ri, cd_vec3 q0, cd_vec3 q1, cd_real rj, cd_real s,
                                      cd_real t)
{
    cd_vec3 a = cd_v3_axpy(p0, s, cd_v3_sub(p1, p0));
    cd_vec3 b = cd_v3_axpy(q0, t, cd_v3_sub(q1, q0));
    cd_vec3 ab = cd_v3_sub(b, a);
    cd_real reach = ri + rj; /* [m] */
    return cd_v3_dot(ab, ab) > reach * reach * CD_R(1.000000001);
}

/* The narrow phase of two arms (axes of non-zero length: a = |p1 - p0|^2
 * > 0 and e = |q1 - q0|^2 > 0 [m^2], with d1 = p1 - p0 and d2 = q1 - q0
 * [m] at hand): cd_segseg_closest's branch for two segments,
 * cd_segseg_clearly_apart and cd_segseg_contact_at with the same
 * operations on the same values, so the same bits; the axes' cross
 * product and the squared lengths are formed once for the closest points
 * and the parallel rule.  Returns 1 when the two are clearly apart (g is
 * then not filled), 0 after filling g. */
CD_INLINE int cd_segseg_axes_contact(cd_vec3 p0, cd_vec3 p1, cd_real ri, cd_vec3 q0, cd_vec3 q1, cd_real rj, cd_vec3 d1,
                                     cd_vec3 d2, cd_real a, cd_real e, cd_real sin_parallel, cd_int blend,
                                     cd_contact_geom *g)
{
    cd_vec3 m = cd_v3_cross(d1, d2);
    cd_real m2 = cd_v3_dot(m, m), s, t; /* [m^4], [1], [1] */
    cd_segseg_closest_axes(p0, q0, q1, d1, d2, cd_v3_sub(q0, p0), a, e, m, m2, &s, &t);
    if (cd_segseg_clearly_apart(p0, p1, ri, q0, q1, rj, s, t)) return 1;
    cd_segseg_contact_closest(p0, p1, ri, q0, q1, rj, s, t, g);
    if (sin_parallel > CD_R(0)) {
        cd_real wpar = cd_parallel_weight(m2, a * e, sin_parallel, blend);
        if (wpar > CD_R(0)) cd_segseg_parallel_point(p0, p1, q0, q1, d1, d2, a, e, wpar, g);
    }
    return 0;
}

/* The narrow phase of a point and a segment (a sphere and an arm: p0 ==
 * p1, or q0 == q1, not both): cd_segseg_closest's branch for a point,
 * cd_segseg_clearly_apart and cd_segseg_contact_at with the same operations
 * on the same values, so the same bits, less the parallel rule, which
 * needs two axes of non-zero length (its weight is 0 for a point).
 * Returns 1 when the two are clearly apart (g is then not filled), 0
 * after filling g. */
CD_INLINE int cd_segseg_point_segment_contact(cd_vec3 p0, cd_vec3 p1, cd_real ri, cd_vec3 q0, cd_vec3 q1, cd_real rj,
                                              cd_contact_geom *g)
{
    cd_vec3 d1 = cd_v3_sub(p1, p0), d2 = cd_v3_sub(q1, q0), w = cd_v3_sub(q0, p0);
    cd_real a = cd_v3_dot(d1, d1), e = cd_v3_dot(d2, d2), s = CD_R(0), t = CD_R(0);
    if (a <= CD_R(0)) /* i is the point: p0 projected onto j */
        t = cd_clamp01(-cd_v3_dot(w, d2) / e);
    else /* j is the point: q0 projected onto i */ s = cd_clamp01(cd_v3_dot(w, d1) / a);
    if (cd_segseg_clearly_apart(p0, p1, ri, q0, q1, rj, s, t)) return 1;
    cd_segseg_contact_closest(p0, p1, ri, q0, q1, rj, s, t, g);
    return 0;
}

CD_DEVICE_END
#endif
