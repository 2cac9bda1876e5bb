/* Broad phase of the Verlet list (docs/architecture.md; used by the passes
 * of kernels/neighbor_items.h, which every backend runs):
 * a uniform grid over the particles' centres with their bounding spheres,
 * the exact candidate test of two primitives, the pair key
 * and its binary search (history carry-over), and the skin criterion.
 * Written once so that both backends build the same list of pairs.
 * Device-safe: C11 and OpenCL C 1.2. */
#ifndef CD_BROADPHASE_H
#define CD_BROADPHASE_H
#include "defs.h"
#include "vec3.h"
#include "segseg.h"
#include "walls.h"

/* Uniform grid.  Plain struct of 8-byte members: same layout in C and in
 * OpenCL, so it can live in a device buffer. */
typedef struct {
    cd_real lo[3];  /* lower corner [m] */
    cd_real cell;   /* edge [m] */
    cd_long dim[3]; /* cells per axis */
} cd_grid;

CD_DEVICE_BEGIN

/* Centre of a primitive's bounding sphere [m]. */
CD_INLINE cd_vec3 cd_bp_centre(cd_vec3 a, cd_vec3 b) { return cd_v3_scale(cd_v3_add(a, b), CD_R(0.5)); }

/* Radius of a primitive's bounding sphere about cd_bp_centre [m]. */
CD_INLINE cd_real cd_bp_bound(cd_vec3 a, cd_vec3 b, cd_real r) { return CD_R(0.5) * cd_v3_norm(cd_v3_sub(b, a)) + r; }

/* Reach of a primitive (axis ends a, b, radius r [m]) from a particle's
 * centre x [m]: |centre - x| + its bound. */
CD_INLINE cd_real cd_bp_reach(cd_vec3 a, cd_vec3 b, cd_real r, cd_vec3 x)
{
    return cd_v3_norm(cd_v3_sub(cd_bp_centre(a, b), x)) + cd_bp_bound(a, b, r);
}

/* A particle's bounding radius from the largest reach r of its primitives
 * (cd_bp_reach), widened by 1e-9 of itself so that it holds every
 * primitive's sphere despite rounding (the particle test must never drop a
 * pair that the primitive test keeps). */
CD_INLINE cd_real cd_bp_widened(cd_real r) { return r * CD_R(1.000000001); }

/* Bounding radius of a particle about its centre of mass x [m]: the
 * largest reach of its primitives first .. first + count - 1, widened
 * (cd_bp_widened). */
CD_INLINE cd_real cd_bp_particle_bound(const CD_GLOBAL cd_vec3 *prim_a, const CD_GLOBAL cd_vec3 *prim_b,
                                       const CD_GLOBAL cd_real *prim_radius, cd_int first, cd_int count, cd_vec3 x)
{
    cd_real r = 0;
    for (cd_int i = first; i < first + count; i++) {
        cd_real reach = cd_bp_reach(prim_a[i], prim_b[i], prim_radius[i], x);
        if (reach > r) r = reach;
    }
    return cd_bp_widened(r);
}

/* Adds a particle (centre x [m], bounding radius bound [m]) to the running
 * box of centres lo/hi [m] and the largest bound rmax [m].  Minimum and
 * maximum are exact, so any order of additions (threads, work-groups)
 * gives the same box. */
CD_INLINE void cd_bp_bounds_add(cd_real *lo, cd_real *hi, cd_real *rmax, cd_vec3 x, cd_real bound)
{
    cd_real v[3];
    v[0] = x.x;
    v[1] = x.y;
    v[2] = x.z;
    for (int k = 0; k < 3; k++) {
        if (v[k] < lo[k]) lo[k] = v[k];
        if (v[k] > hi[k]) hi[k] = v[k];
    }
    if (bound > *rmax) *rmax = bound;
}

/* The grid for centres inside [lo, hi] [m], largest bounding radius rmax [m]
 * and skin [m]: cells of edge 2 rmax + skin (so that candidates lie in
 * neighbouring cells), enlarged until there are at most 8 n_prims + 64
 * cells, so that memory and the empty-cell scan stay linear in N. */
CD_INLINE void cd_grid_make(CD_NOESCAPE cd_grid *g, const cd_real *lo, const cd_real *hi, cd_real rmax, cd_real skin,
                            cd_long n_prims)
{
    g->cell = 2 * rmax + skin;
    for (;;) {
        cd_real cells = 1;
        for (int k = 0; k < 3; k++) {
            g->lo[k] = lo[k];
            g->dim[k] = (cd_long)floor((hi[k] - lo[k]) / g->cell) + 1;
            cells *= (cd_real)g->dim[k];
        }
        if (cells <= CD_R(8.0) * (cd_real)n_prims + 64) break;
        g->cell *= CD_R(1.26);
    }
}

/* Cell coordinate of x along axis, clamped to the grid. */
CD_INLINE cd_long cd_grid_coord(CD_NOESCAPE const cd_grid *g, cd_real x, int axis)
{
    cd_long c = (cd_long)floor((x - g->lo[axis]) / g->cell);
    return c < 0 ? 0 : (c >= g->dim[axis] ? g->dim[axis] - 1 : c);
}

/* Cell index of point p [m] (x fastest). */
CD_INLINE cd_long cd_grid_cell_of(CD_NOESCAPE const cd_grid *g, cd_vec3 p)
{
    return (cd_grid_coord(g, p.z, 2) * g->dim[1] + cd_grid_coord(g, p.y, 1)) * g->dim[0] + cd_grid_coord(g, p.x, 0);
}

/* Candidate test of primitives (ai, bi, ri) and (aj, bj, rj) [m]: bounding
 * spheres first, then the exact distance of the axes against
 * ri + rj + skin [m]. */
CD_INLINE int cd_bp_is_candidate(cd_vec3 ai, cd_vec3 bi, cd_real ri, cd_vec3 aj, cd_vec3 bj, cd_real rj, cd_real skin)
{
    cd_real reach = ri + rj + skin;
    cd_real rb = cd_bp_bound(ai, bi, ri) + cd_bp_bound(aj, bj, rj) + skin;
    if (cd_v3_norm2(cd_v3_sub(cd_bp_centre(ai, bi), cd_bp_centre(aj, bj))) > rb * rb) return 0;
    cd_real u, w;
    cd_segseg_closest(ai, bi, aj, bj, &u, &w);
    cd_vec3 d = cd_v3_sub(cd_v3_lerp(aj, bj, w), cd_v3_lerp(ai, bi, u));
    return cd_v3_norm2(d) <= reach * reach;
}

/* Key of a primitive pair, ordered by i then j. */
CD_INLINE cd_ulong cd_bp_pair_key(cd_prim_id i, cd_prim_id j) { return ((cd_ulong)(cd_uint)i << 32) | (cd_uint)j; }

/* Index of key in the ascending keys[0 .. n), or -1. */
CD_INLINE cd_long cd_bp_find_key(const CD_GLOBAL cd_ulong *keys, cd_long n, cd_ulong key)
{
    cd_long lo = 0, hi = n;
    while (lo < hi) {
        cd_long mid = lo + (hi - lo) / 2;
        if (keys[mid] < key) lo = mid + 1;
        else hi = mid;
    }
    return (lo < n && keys[lo] == key) ? lo : -1;
}

/* Skin criterion: has either axis end moved more than half the skin since
 * the last build?  Every point of a segment moves at most as far as its
 * farthest end, so no pair can come into contact unseen before that.
 * limit2 = (skin/2)^2 [m^2] from cd_bp_skin_limit2. */
CD_INLINE cd_real cd_bp_skin_limit2(cd_real skin) { return CD_R(0.25) * skin * skin; }
CD_INLINE int cd_bp_moved(cd_vec3 a, cd_vec3 a_ref, cd_vec3 b, cd_vec3 b_ref, cd_real limit2)
{
    return cd_v3_norm2(cd_v3_sub(a, a_ref)) > limit2 || cd_v3_norm2(cd_v3_sub(b, b_ref)) > limit2;
}

/* Wall candidates.  A primitive (axis ends a, b, radius r [m]) is tested
 * against wall w in the steps until the next build only if, at the build,
 * it is not clearly apart from the wall with its radius grown by the whole
 * skin [m]: until the next build its ends move at most half the skin (the
 * skin criterion above) and the wall at most half the skin (cd_bp_wall_moved
 * below), so a primitive left out stays clearly apart (walls.h) and its
 * row stays inactive. */
CD_INLINE int cd_bp_wall_candidate(const cd_wall *w, cd_vec3 a, cd_vec3 b, cd_real r, cd_real skin)
{
    return !cd_wall_clearly_apart(w, a, b, r + skin);
}

/* How far wall w has moved since its state ref at the last build, as the
 * wall-candidate test needs it [m]: the displacement of its point bounds
 * how far a plane moved along its normal and how far an axis or centre
 * moved; a radius change counts twice, which covers the clearance of
 * 1e-5 of the radius that the curved test of cd_wall_clearly_apart keeps.
 * A rebuild is due when it exceeds half the skin. */
CD_INLINE cd_real cd_bp_wall_moved(cd_wall w, cd_wall ref)
{
    cd_real dr = w.radius - ref.radius;
    return cd_v3_norm(cd_v3_sub(w.point, ref.point)) + CD_R(2) * (dr < CD_R(0) ? -dr : dr);
}

CD_DEVICE_END
#endif
