/* Contacts between a spherocylinder primitive and a wall (docs/references.md, Contacts,
 * "Walls").  Device-safe header: C11 and OpenCL C 1.2 (see segseg.h).
 *
 * CONVENTION.  A wall contact is a pair contact in which the PARTICLE is
 * body i and the WALL is body j (a body of radius 0 whose surface is the
 * wall surface):
 *   g->normal   unit n pointing FROM THE PARTICLE TOWARDS THE WALL, i.e. out
 *               of the domain at the contact (plane: n = -w->normal;
 *               cylinder / sphere: the outward radial direction).  The normal
 *               force on the particle is -F_n n, pushing it back into the
 *               domain.
 *   g->distance D = signed distance from the axis point x closest to the wall
 *               to the wall surface, measured along n [m]; positive while x
 *               is inside the domain, negative once the axis has crossed the
 *               wall.
 *   g->overlap  r - D [m] (the pair rule r_i + r_j - D with r_j = 0);
 *               contact when > 0.
 *   g->point    c = x + n (D + r)/2: on the line from x along n, half-way
 *               between the wall surface (x + n D) and the deepest point of
 *               the particle (x + n r), i.e. the middle of the overlap zone,
 *               inside the wall by overlap/2.  Its lever arm from the axis
 *               is r - overlap/2, as for a physical contact on the surface.
 *               (For two equal radii the pair rule (a + b)/2 is the same
 *               point, the middle of the overlap zone.)
 *   g->parallel 1 when the parallel rule placed the point (below).
 *
 * Closest axis point.  Each wall's distance function along the axis segment
 * is convex in the segment parameter (plane: linear; cylinder and sphere:
 * minus a convex radial distance), so its minimum is at an end point: x is
 * the end point a or b with the smaller distance (a on ties).
 *
 * Parallel rule.  With u the unit axis and n the normal at x, when
 * |dot(u, n)| < sin_parallel (the axis lies within the cut-off angle of the
 * wall's tangent plane at x) and the segment has non-zero length, the
 * contact point is taken at the segment's middle m instead of at x (with
 * blend, between the cut-off and twice it the two points, and on curved
 * walls the two normals, are mixed by cd_parallel_weight, so that they
 * move continuously with the angle):
 *   plane:            c = m - w->normal (d(m) + overlap/2), the foot of m on
 *                     the plane pushed overlap/2 into the wall; n unchanged.
 *   cylinder, sphere: c = foot(m) + e_m (R + overlap/2) with e_m the outward
 *                     radial unit vector through m (foot = axis point level
 *                     with m, or the centre), and n = e_m: on a curved wall
 *                     the normal is the wall normal at the contact point, so
 *                     that a short rod lying against the wall feels no
 *                     sideways push that flips with the rounding of which end
 *                     is deeper.  The difference from the end point's normal
 *                     is below the cut-off angle.
 *   D and overlap are unchanged (those of the deepest end point), so the
 *   force magnitude is continuous when the rule switches on or off.
 * A segment lying flat on a plane therefore gets one contact at its middle,
 * which does not jump between the two ends.
 *
 * Walls (geom_types.h): w->normal must be a unit vector. */
#ifndef CD_WALLS_H
#define CD_WALLS_H
#include "defs.h"
#include "vec3.h"
#include "geom_types.h"
#include "segseg.h"

/* Distance reported for an unknown wall type: never a contact [m]. */
#define CD_WALL_FAR CD_R(1e300)

CD_DEVICE_BEGIN

/* Weight [1] of the parallel rule for the segment a->b [m] against the
 * plane with unit normal nrm: cd_parallel_weight of the squared sine of
 * the angle between them, dot(b - a, nrm)^2 / |b - a|^2 (1 within the
 * cut-off angle, 0 beyond twice it); 0 for a zero-length segment
 * (docs/references.md, Contacts, parallel rule). */
CD_INLINE cd_real cd_wall_parallel_weight(cd_vec3 a, cd_vec3 b, cd_vec3 nrm, cd_real sin_parallel, cd_int blend)
{
    cd_vec3 ab = cd_v3_sub(b, a);
    cd_real l2 = cd_v3_dot(ab, ab);
    cd_real un = cd_v3_dot(ab, nrm);
    return l2 > CD_R(0) ? cd_parallel_weight(un * un, l2, sin_parallel, blend) : CD_R(0);
}

/* Plane wall (docs/references.md, Contacts, walls): w->point on the plane, w->normal unit, into the
 * domain.  Segment a-b [m], radius r [m]; fills *g as described at the top
 * of this file. */
CD_INLINE void cd_wall_plane_contact(const cd_wall *w, cd_vec3 a, cd_vec3 b, cd_real r, cd_real sin_parallel,
                                     cd_int blend, cd_contact_geom *g)
{
    cd_vec3 nw = w->normal;
    cd_real da = cd_v3_dot(cd_v3_sub(a, w->point), nw); /* signed distances [m] */
    cd_real db = cd_v3_dot(cd_v3_sub(b, w->point), nw);
    cd_vec3 x = da <= db ? a : b;
    cd_real D = da <= db ? da : db;
    cd_real delta = r - D;
    g->distance = D;
    g->overlap = delta;
    g->normal = cd_v3_neg(nw);
    g->point = cd_v3_axpy(x, -CD_R(0.5) * (D + r), nw);
    cd_real wpar = cd_wall_parallel_weight(a, b, nw, sin_parallel, blend);
    g->parallel = wpar == CD_R(1);
    if (wpar > CD_R(0)) {
        cd_vec3 m = cd_v3_scale(cd_v3_add(a, b), CD_R(0.5));
        cd_real dm = cd_v3_dot(cd_v3_sub(m, w->point), nw);
        cd_vec3 pm = cd_v3_axpy(m, -(dm + CD_R(0.5) * delta), nw);
        g->point = g->parallel ? pm : cd_v3_lerp(g->point, pm, wpar);
    }
}

/* Outward radial vector of x [m] from the wall's axis (cylinder, axis
 * through w->point along unit w->normal) or centre (sphere, w->point)
 * (docs/references.md, Contacts, walls). */
CD_INLINE cd_vec3 cd_wall_radial(const cd_wall *w, cd_vec3 x)
{
    cd_vec3 rel = cd_v3_sub(x, w->point);
    if (w->type == CD_WALL_CYLINDER) rel = cd_v3_axpy(rel, -cd_v3_dot(rel, w->normal), w->normal);
    return rel;
}

/* Inside of a cylinder (radius w->radius about the axis through w->point
 * along unit w->normal) or of a sphere (radius w->radius, centre w->point)
 * (docs/references.md, Contacts, walls).  Segment a-b [m], radius r [m]; fills *g as described at
 * the top of this file.  The radial distance rho is convex along the
 * segment, so its maximum is at an end point; D = R - rho_max,
 * overlap = r + rho_max - R.  A point on the axis / at the centre (rho = 0)
 * gets a deterministic normal: a perpendicular of the cylinder axis, or
 * (0, 0, -1) for the sphere. */
CD_INLINE void cd_wall_curved_contact(const cd_wall *w, cd_vec3 a, cd_vec3 b, cd_real r, cd_real sin_parallel,
                                      cd_int blend, cd_contact_geom *g)
{
    cd_vec3 ra = cd_wall_radial(w, a);
    cd_vec3 rb = cd_wall_radial(w, b);
    int use_a = cd_v3_dot(ra, ra) >= cd_v3_dot(rb, rb);
    cd_vec3 x = use_a ? a : b;
    cd_vec3 rx = use_a ? ra : rb;
    cd_vec3 n = w->type == CD_WALL_CYLINDER ? cd_segseg_any_perpendicular(w->normal) : cd_v3(0, 0, -1);
    cd_real rho = cd_segseg_normalize(rx, &n); /* [m] */
    cd_real R = w->radius;
    cd_real D = R - rho;
    cd_real delta = r - D;
    g->distance = D;
    g->overlap = delta;
    g->normal = n;
    g->parallel = 0;
    g->point = cd_v3_axpy(x, CD_R(0.5) * (D + r), n);
    cd_real wpar = cd_wall_parallel_weight(a, b, n, sin_parallel, blend);
    if (wpar > CD_R(0)) {
        cd_vec3 m = cd_v3_scale(cd_v3_add(a, b), CD_R(0.5));
        cd_vec3 rm = cd_wall_radial(w, m);
        cd_vec3 em = n;
        cd_real rhom = cd_segseg_normalize(rm, &em);
        if (rhom > CD_R(0)) {
            cd_vec3 foot = cd_v3_sub(m, rm);
            cd_vec3 pm = cd_v3_axpy(foot, R + CD_R(0.5) * delta, em);
            g->parallel = wpar == CD_R(1);
            if (g->parallel) {
                g->point = pm;
                g->normal = em;
            } else { /* between the cut-off and twice it: point and normal blended */
                cd_vec3 nb = n;
                g->point = cd_v3_lerp(g->point, pm, wpar);
                cd_segseg_normalize(cd_v3_lerp(n, em, wpar), &nb);
                g->normal = nb;
            }
        }
    }
}

/* Is the primitive (axis ends a, b [m], radius r [m]) certainly clear of
 * wall *w?  A test without square roots or divisions that lets the force
 * kernel skip cd_wall_contact for the many primitives far from every wall
 * (most of them: 47 % of a step's time went to the full test in a tall
 * cylinder).  It answers 1 only when cd_wall_contact would report
 * overlap <= 0: exactly so for the plane (the same comparison), with a
 * margin of 1e-5 R [m] for the curved walls, far above the rounding of
 * r - (R - rho), so the two never disagree. */
CD_INLINE int cd_wall_clearly_apart(const cd_wall *w, cd_vec3 a, cd_vec3 b, cd_real r)
{
    if (w->type == CD_WALL_PLANE) {
        cd_real da = cd_v3_dot(cd_v3_sub(a, w->point), w->normal); /* [m] */
        cd_real db = cd_v3_dot(cd_v3_sub(b, w->point), w->normal);
        return (da <= db ? da : db) >= r;
    }
    if (w->type == CD_WALL_CYLINDER || w->type == CD_WALL_SPHERE) {
        cd_vec3 ra = cd_wall_radial(w, a), rb = cd_wall_radial(w, b);
        cd_real ra2 = cd_v3_dot(ra, ra), rb2 = cd_v3_dot(rb, rb); /* [m^2] */
        cd_real q = w->radius - r - CD_R(1e-5) * w->radius;       /* [m] */
        return q > CD_R(0) && (ra2 >= rb2 ? ra2 : rb2) < q * q;
    }
    return 1; /* unknown type: cd_wall_contact reports CD_WALL_FAR */
}

/* Contact geometry of a spherocylinder primitive (axis ends a, b [m],
 * radius r [m]) with wall *w (docs/references.md, Contacts, walls).  sin_parallel [1]: sine of the
 * parallel cut-off angle, <= 0 disables the parallel rule; blend 1: its
 * continuous form (cd_parallel_weight).  The particle is body i, the wall
 * body j: g->normal points from the particle towards the wall (see the top
 * of this file). */
CD_INLINE void cd_wall_contact_rule(const cd_wall *w, cd_vec3 a, cd_vec3 b, cd_real r, cd_real sin_parallel,
                                    cd_int blend, cd_contact_geom *g)
{
    if (w->type == CD_WALL_PLANE) {
        cd_wall_plane_contact(w, a, b, r, sin_parallel, blend, g);
    } else if (w->type == CD_WALL_CYLINDER || w->type == CD_WALL_SPHERE) {
        cd_wall_curved_contact(w, a, b, r, sin_parallel, blend, g);
    } else {
        g->distance = CD_WALL_FAR;
        g->overlap = r - CD_WALL_FAR;
        g->normal = cd_v3(0, 0, -1);
        g->point = a;
        g->parallel = 0;
    }
}

/* cd_wall_contact_rule with the paper's parallel rule (no blend). */
CD_INLINE void cd_wall_contact(const cd_wall *w, cd_vec3 a, cd_vec3 b, cd_real r, cd_real sin_parallel,
                               cd_contact_geom *g)
{
    cd_wall_contact_rule(w, a, b, r, sin_parallel, 0, g);
}

/* Velocity of the wall's surface material at a contact point [m/s]
 * (docs/references.md, Contacts, walls: moving planes, sphere of variable radius).  Plane and
 * cylinder: the wall's translational velocity w->velocity.  Sphere:
 * w->velocity + w->radial_velocity e, e the outward radial unit vector at
 * the point (just w->velocity at the centre). */
CD_INLINE cd_vec3 cd_wall_velocity_at(const cd_wall *w, cd_vec3 point)
{
    cd_vec3 v = w->velocity;
    if (w->type == CD_WALL_SPHERE) {
        cd_vec3 e = cd_v3_zero();
        if (cd_segseg_normalize(cd_v3_sub(point, w->point), &e) > CD_R(0)) v = cd_v3_axpy(v, w->radial_velocity, e);
    }
    return v;
}

CD_DEVICE_END
#endif
