/* Every structure-of-arrays column of the state as one struct of pointers,
 * generated from kernels/fields.def.  The per-item functions of step_items.h
 * take it, so that the OpenMP loops (pointers into cd_state) and the OpenCL
 * kernels (pointers to __global buffers) run the same code: a column added
 * to fields.def reaches both backends without a second list.
 * Device-safe: C11 and OpenCL C 1.2 (a private struct may hold pointers to
 * __global memory; only kernel arguments may not). */
#ifndef CD_COLS_H
#define CD_COLS_H
#include "defs.h"
#include "geom_types.h"
#include "vec3.h"
#include "field_groups.h"

/* A column of ctype is a cd_col_<ctype>: a pointer known to be aligned as
 * its element (defs.h, CD_ALIGN_VALUE; the element types of fields.def and
 * cd_arm). */
typedef CD_GLOBAL cd_int *cd_col_cd_int CD_ALIGN_VALUE(cd_int);
typedef CD_GLOBAL cd_flag *cd_col_cd_flag CD_ALIGN_VALUE(cd_flag);
typedef CD_GLOBAL cd_real *cd_col_cd_real CD_ALIGN_VALUE(cd_real);
typedef CD_GLOBAL cd_vec3 *cd_col_cd_vec3 CD_ALIGN_VALUE(cd_vec3);
typedef CD_GLOBAL cd_quat *cd_col_cd_quat CD_ALIGN_VALUE(cd_quat);
typedef CD_GLOBAL cd_arm *cd_col_cd_arm CD_ALIGN_VALUE(cd_arm);
/* the wall candidates' entries, read by the gather (step_items.h) */
typedef const CD_GLOBAL cd_wall_entry *cd_wall_entries CD_ALIGN_VALUE(cd_wall_entry);

/* The device columns only (field_groups.h), then the primitives' arms
 * (geom_types.h, cd_arm): prim_arm[i] is primitive i's row of arm, or
 * negative for a ball at its particle's centre (a sphere; the value keeps
 * the signs of its zero body ends for the host, src/core/state.c), whose two axis ends are
 * both prim_a[i] (and both prim_a_ref[i] at the last build). */
typedef struct {
#define CD_FIELD(group, ctype, h5type, ncomp, name, unit, meaning) CD_ON_DEVICE_##group(cd_col_##ctype name;)
#include "fields.def"
#undef CD_FIELD
    cd_col_cd_int prim_arm;
    cd_col_cd_arm arm;
    /* The particles' principal moments of inertia [kg m^2] (the host's
     * column inertia, kernels/fields.def), as the step holds them: null
     * inertia where every particle is isotropic, and then one value a
     * particle in inertia_iso (16 B a sphere less; cd_inertia_of). */
    cd_col_cd_vec3 inertia;
    cd_col_cd_real inertia_iso;
    /* The particles' total force [N] and torque [N m] (the host's columns
     * of fields.def group PARTICLE_OUT) where the step holds them: on an
     * MPI rank (the ghosts' come from their owners between calls), and
     * from a start to its first advance (the host's values); null
     * otherwise, and then the first advance of a call sums them from the
     * rows (cd_item_advance) and the last step writes none (48 B a
     * particle less; docs/performance.md, "Session 18, force and torque
     * not held").  The test is the same for every item. */
    cd_col_cd_vec3 force;
    cd_col_cd_vec3 torque;
} cd_cols;

CD_DEVICE_BEGIN

/* Are both body-frame ends a, b the body origin (every component a zero
 * of either sign)?  Such a primitive has no arm.  One test of a sum of
 * magnitudes, which is zero only when every term is (a sum of non-negative
 * numbers does not underflow to zero). */
CD_INLINE int cd_ends_at_origin(cd_vec3 a, cd_vec3 b)
{
    return fabs(a.x) + fabs(a.y) + fabs(a.z) + fabs(b.x) + fabs(b.y) + fabs(b.z) == CD_R(0);
}

/* Primitive i's row of arm (negative: none).  A null prim_arm says that
 * every primitive has an arm, its own row (hexapods, crosses: the index
 * column is neither held nor read; the test is the same for every item,
 * so it does not diverge on a GPU). */
CD_INLINE cd_int cd_prim_arm_of(cd_cols c, cd_prim_id i) { return c.prim_arm ? c.prim_arm[i] : i; }

/* Principal moments of inertia of particle q [kg m^2]: its row of
 * inertia, or where that is null (every particle isotropic) its one value
 * three times, the three equal values the host's row holds (the same
 * bits).  The test is the same for every item (no divergence on a GPU). */
CD_INLINE cd_vec3 cd_inertia_of(cd_cols c, cd_particle_id q)
{
    if (c.inertia) return c.inertia[q];
    cd_real I = c.inertia_iso[q];
    return cd_v3(I, I, I);
}

/* World axis end b of primitive i [m]: its arm's, or prim_a[i] for a ball
 * without one (both ends at the particle's centre: the same value the
 * step wrote into both ends when every primitive had an arm). */
CD_INLINE cd_vec3 cd_prim_b(cd_cols c, cd_prim_id i)
{
    cd_int r = cd_prim_arm_of(c, i);
    return r < 0 ? c.prim_a[i] : c.arm[r].b;
}

/* End b of primitive i at the last neighbour-list build [m]. */
CD_INLINE cd_vec3 cd_prim_b_ref(cd_cols c, cd_prim_id i)
{
    cd_int r = cd_prim_arm_of(c, i);
    return r < 0 ? c.prim_a_ref[i] : c.arm[r].b_ref;
}

CD_DEVICE_END

#endif
