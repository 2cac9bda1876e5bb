/* One work item of each loop of the time step (docs/architecture.md, "A time
 * step"; docs/references.md, Contacts, Contact law, Motion).  The OpenMP loops of src/backend/omp/step_omp.c and the
 * OpenCL kernels of kernels/cl/ are thin wrappers that call these for one
 * particle, primitive or pair, so both backends run the same arithmetic in
 * the same order and can agree bit for bit.  No item writes a row another
 * item writes, so no loop needs atomics.  Device-safe: C11 and OpenCL C 1.2.
 *
 * c: the state's columns (cols.h).  Walls are passed separately: on the
 * host they live inside cd_state, on a device in a small buffer. */
#ifndef CD_STEP_ITEMS_H
#define CD_STEP_ITEMS_H
#include "cols.h"
#include "rigid.h"
#include "segseg.h"
#include "walls.h"
#include "contact_law.h"
#include "broadphase.h"
#include "reorder_items.h"
#include "pose_items.h"

CD_DEVICE_BEGIN

/* A wall after moving for dt [s] with its translational and radial
 * velocities. */
CD_INLINE cd_wall cd_wall_advanced(cd_wall w, cd_real dt)
{
    w.point = cd_v3_axpy(w.point, dt, w.velocity);
    w.radius += dt * w.radial_velocity;
    return w;
}

/* cd_item_advance for particle q whose velocity v [m/s], angular momentum
 * L [kg m^2/s], force F [N], torque T [N m] and mass m [kg] the caller has
 * already read (or just computed): the state is read once and written
 * once, in locals between, which the compiler cannot do across the
 * columns' stores (any column may alias any other for it).  The kick's own
 * angular velocity is not formed: the drift's replaces it.  fixed_spheres
 * (physics.sphere_orientation: fixed): a sphere keeps its orientation. */
CD_INLINE_ALWAYS int cd_advance_from(cd_cols c, cd_particle_id q, cd_vec3 v, cd_vec3 L, cd_vec3 F, cd_vec3 T, cd_real m,
                                     cd_real dt, cd_real limit2, const CD_GLOBAL cd_real *ref_pose,
                                     cd_int fixed_spheres)
{
    cd_vec3 x = c.position[q], w;
    cd_quat o = c.orientation[q];
    cd_rigid_kick(&v, &L, F, T, m, CD_R(0.5) * dt);
    cd_rigid_drift_angvel(&x, &o, &w, v, L, cd_inertia_of(c, q), dt, fixed_spheres && cd_particle_is_sphere(c, q));
    c.velocity[q] = v;
    c.angmom[q] = L;
    c.position[q] = x;
    c.orientation[q] = o;
    c.angvel[q] = w;
#if CD_ENDS_FROM_POSE
    return cd_pose_moved(c, q, x, o, ref_pose, limit2);
#else
    (void)ref_pose;
    return cd_store_ends(c, q, x, o, 1, limit2);
#endif
}

/* Contact geometry of two primitives (axis ends ai, bi and aj, bj, radii
 * ri, rj [m]; docs/references.md, Contacts): closest points of the two
 * axes and, from them, the contact point, normal and overlap.  Fills g
 * always (the host's output pass, src/io/pair_output.c, needs the normal of
 * every active row, from the host's columns). */
CD_INLINE void cd_pair_geometry_of(cd_vec3 ai, cd_vec3 bi, cd_real ri, cd_vec3 aj, cd_vec3 bj, cd_real rj,
                                   cd_real sin_parallel, cd_int parallel_blend, cd_contact_geom *g)
{
    cd_real s, t;
    cd_segseg_closest(ai, bi, aj, bj, &s, &t);
    cd_segseg_contact_at(ai, bi, ri, aj, bj, rj, s, t, sin_parallel, parallel_blend, g);
}

/* Torque about a body's centre [m] of a force [N] acting at a point [m]. */
CD_INLINE cd_vec3 cd_contact_torque(cd_vec3 point, cd_vec3 centre, cd_vec3 force)
{
    return cd_v3_cross(cd_v3_sub(point, centre), force);
}

/* Narrow phase of primitives i and j (radii ri, rj [m]) on the step's
 * columns: fills g and returns 1 when they are clearly apart (g then
 * unset); a contact is a row not apart with g.overlap > 0.  The pair pass
 * and the observables (kernels/observe_items.h: the overlap, which no row
 * keeps) take it, so both get the same bits from the same ends.  The
 * path is chosen per row: two balls without an arm (spheres:
 * cd_prim_arm_of < 0; where every primitive has an arm, prim_arm is null
 * and one test decides for every row) by their centres' distance only (no
 * end b read, no point test of the ends: 0.86x the instructions of a
 * sphere row; rows of one kind take one path, docs/performance.md, "Fewer
 * bytes per sphere"), the same call on the same values as the point test
 * below makes for them (a ball's two ends are its centre), so the same
 * bits. */
CD_INLINE_ALWAYS int cd_pair_narrow(cd_cols c, cd_prim_id i, cd_prim_id j, cd_real ri, cd_real rj, cd_real sin_parallel,
                                    cd_int parallel_blend, cd_contact_geom *g)
{
    int apart;
    if (c.prim_arm && c.prim_arm[i] < 0 && c.prim_arm[j] < 0) {
        apart = cd_segseg_point_contact(cd_ball_world_point(c, i), ri, cd_ball_world_point(c, j), rj, g);
    } else {
        cd_vec3 ai, bi, aj, bj;
        cd_prim_world_ends(c, i, &ai, &bi);
        cd_prim_world_ends(c, j, &aj, &bj);
        cd_vec3 d1 = cd_v3_sub(bi, ai), d2 = cd_v3_sub(bj, aj);
        cd_real a = cd_v3_dot(d1, d1), e = cd_v3_dot(d2, d2); /* [m^2] */
        if (a > CD_R(0) && e > CD_R(0)) {
            /* two arms (neither is a point: bi - ai is not zero) */
            return cd_segseg_axes_contact(ai, bi, ri, aj, bj, rj, d1, d2, a, e, sin_parallel, parallel_blend, g);
        }
        int point_i = cd_segseg_is_point(ai, bi), point_j = cd_segseg_is_point(aj, bj);
        if (point_i && point_j) {
            /* two points (balls with an arm of zero length): the same
             * geometry without the segment machinery */
            apart = cd_segseg_point_contact(ai, ri, aj, rj, g);
        } else if (point_i || point_j) {
            /* a sphere and an arm: the same, without the parallel rule */
            apart = cd_segseg_point_segment_contact(ai, bi, ri, aj, bj, rj, g);
        } else {
            cd_real s, t;
            cd_segseg_closest(ai, bi, aj, bj, &s, &t);
            apart = cd_segseg_clearly_apart(ai, bi, ri, aj, bj, rj, s, t);
            if (!apart) cd_segseg_contact_at(ai, bi, ri, aj, bj, rj, s, t, sin_parallel, parallel_blend, g);
        }
    }
    return apart;
}

/* Pair row k of the Verlet list: narrow phase and contact law with history
 * (docs/references.md, Contacts, Contact law).  law: particle-particle law, dt [s], sin_parallel [1],
 * parallel_blend 0/1 (material.parallel_blend).  An active row keeps what
 * the next step and the gather need: history, point, force on j; with
 * outputs = 1 also F_n, which only output reads, between calls of the
 * step: the step writes it at the last step of a call only (8 B per
 * contact-step less; docs/performance.md, "Argument blocks on the
 * device").  The overlap, the normal, F_t and the torques are derived
 * where they are read: the overlap by the observables from the same
 * narrow phase (cd_pair_narrow), all four on the host for output
 * (fields.def, PAIR_OUT; docs/performance.md, "Session 16, issue 21"). */
CD_INLINE_ALWAYS void cd_item_pair_force(cd_cols c, cd_pair_id k, cd_law_params law, cd_real dt, cd_real sin_parallel,
                                         cd_int parallel_blend, cd_int outputs)
{
    cd_prim_id i = c.pair_prim_i[k], j = c.pair_prim_j[k];
    cd_particle_id pi = c.prim_particle[i], pj = c.prim_particle[j];
    cd_real ri = c.prim_radius[i], rj = c.prim_radius[j];
    cd_contact_geom g;
    int apart = cd_pair_narrow(c, i, j, ri, rj, sin_parallel, parallel_blend, &g);
    if (apart || !(g.overlap > 0)) {
        /* Separated: the contact and its history end.  An inactive row
         * holds a zero force (the gather adds it) and a finite point, and
         * is otherwise read by nobody but its own next step and the history
         * carry-over, so it is written only when it changes, to spare the
         * bandwidth. */
        if (c.pair_active[k]) {
            c.pair_active[k] = 0;
            c.pair_shear[k] = cd_v3_zero();
            c.pair_force[k] = cd_v3_zero();
            c.pair_fn[k] = 0;
        }
        return;
    }
    cd_vec3 vi = cd_rigid_point_velocity(c.position[pi], c.velocity[pi], c.angvel[pi], g.point);
    cd_vec3 vj = cd_rigid_point_velocity(c.position[pj], c.velocity[pj], c.angvel[pj], g.point);
    cd_real m_eff = cd_law_effective_mass(c.mass[pi], c.mass[pj]);
    cd_vec3 shear = c.pair_shear[k];
    cd_contact_force f = cd_contact_law(law, m_eff, cd_law_pair_radius(ri, rj), &g, cd_v3_sub(vj, vi), dt, &shear);
#if CD_ENDS_FROM_POSE
    if (!c.pair_active[k]) /* memory-bound variants: written when it changes (1 B a contact-step) */
#endif
        c.pair_active[k] = 1;
    c.pair_shear[k] = shear;
    c.pair_point[k] = g.point;
    c.pair_force[k] = f.force_j;
    if (outputs) c.pair_fn[k] = f.fn;
}

/* The place e of wall-contact row `row` (primitive i = row / n_walls)
 * among the wall candidates of i's particle (wall_rows[wall_start[q] ..
 * wall_start[q+1]), cd_item_wall_candidates), or -1 when it is none. */
CD_INLINE cd_long cd_wall_out_place(cd_cols c, cd_long row, cd_int n_walls, const CD_GLOBAL cd_int *wall_start,
                                    const CD_GLOBAL cd_int *wall_rows)
{
    cd_int q = c.prim_particle[row / n_walls];
    for (cd_int e = wall_start[q]; e < wall_start[q + 1]; e++)
        if (wall_rows[e] == row) return e;
    return -1;
}

/* Wall-contact row `row` = i n_walls + w: primitive i against wall w
 * (docs/references.md, Contacts (walls), Contact law).  The step runs it for the candidate rows of the last
 * neighbour-list build only (cd_item_wall_candidates).  wall_law: the
 * particle-wall law (its mu is replaced by the wall's friction).  *out:
 * the candidate's entry (cd_wall_entry): its history read and written,
 * its outputs written while in contact. */
CD_INLINE_ALWAYS void cd_item_wall_row(cd_cols c, cd_long row, CD_GLOBAL cd_wall_entry *out,
                                       const CD_GLOBAL cd_wall *walls, cd_int n_walls, cd_law_params wall_law,
                                       cd_real dt, cd_real sin_parallel, cd_int parallel_blend)
{
    cd_prim_id i = (cd_prim_id)(row / n_walls);
    cd_particle_id pi = c.prim_particle[i];
    cd_wall wall = walls[row % n_walls]; /* private copy: the wall functions take private pointers */
    cd_contact_geom g;
    cd_vec3 a, b;
    cd_prim_world_ends(c, i, &a, &b);
    int apart = cd_wall_clearly_apart(&wall, a, b, c.prim_radius[i]);
    if (!apart) cd_wall_contact_rule(&wall, a, b, c.prim_radius[i], sin_parallel, parallel_blend, &g);
    if (apart || !(g.overlap > 0)) {
        /* the contact and its history end; written only when it changes,
         * to spare the bandwidth (the outputs are read only while active) */
        if (out->active) {
            out->active = 0;
            out->shear = cd_v3_zero();
        }
        return;
    }
    cd_vec3 vi = cd_rigid_point_velocity(c.position[pi], c.velocity[pi], c.angvel[pi], g.point);
    cd_vec3 vw = cd_wall_velocity_at(&wall, g.point);
    cd_law_params law = wall_law;
    law.mu = wall.friction;
    cd_vec3 shear = out->shear;
    /* The particle is body i, the wall body j of infinite mass and radius. */
    cd_contact_force f = cd_contact_law(law, c.mass[pi], c.prim_radius[i], &g, cd_v3_sub(vw, vi), dt, &shear);
    cd_vec3 fi = cd_v3_neg(f.force_j);
    out->active = 1;
    out->shear = shear;
    out->force = fi;
    out->torque = cd_contact_torque(g.point, c.position[pi], fi);
    out->overlap = g.overlap;
    out->fn = f.fn;
}

/* Wall candidates of particle q at a neighbour-list build: the rows
 * i n_walls + w of its primitives i and the walls w a primitive is not
 * clearly apart from with its radius grown by the skin [m]
 * (cd_bp_wall_candidate), in ascending order.  Writes them from out[0]
 * unless out is null (the counting pass) and returns how many.  A row
 * left out can hold no contact (its history, impossible while the skin
 * criteria hold, is not carried over: cd_item_wall_carry). */
CD_INLINE cd_int cd_item_wall_candidates(cd_cols c, cd_particle_id q, const CD_GLOBAL cd_wall *walls, cd_int n_walls,
                                         cd_real skin, CD_GLOBAL cd_int *out)
{
    cd_int n = 0, first = c.prim_first[q], last = first + c.prim_count[q];
    for (cd_int i = first; i < last; i++)
        for (cd_int w = 0; w < n_walls; w++) {
            cd_long row = (cd_long)i * n_walls + w;
            cd_wall wall = walls[w];
            if (cd_bp_wall_candidate(&wall, c.prim_a[i], cd_prim_b(c, i), c.prim_radius[i], skin)) {
                if (out) out[n] = (cd_int)row;
                n++;
            }
        }
    return n;
}

/* CD_GATHER_SKIPS_INACTIVE 1: the gather reads each pair row's flag and
 * does not read the force and point of a row out of contact (48 B a side;
 * docs/performance.md, "Argument blocks on the device"): the offload
 * variants, whose step is bound by memory traffic.  0 on host threads and
 * in OpenCL (PoCL vectorises the branch-free loop), where the flag's
 * branch, mispredicted, costs more than the bytes.  The same bits either
 * way (cd_gather_sum). */
#ifndef CD_GATHER_SKIPS_INACTIVE
#if defined(CAPDEM_OFFLOAD_TARGET) && CAPDEM_OFFLOAD_TARGET && !defined(__OPENCL_VERSION__)
#define CD_GATHER_SKIPS_INACTIVE 1
#else
#define CD_GATHER_SKIPS_INACTIVE 0
#endif
#endif

/* History of new wall candidate e (row rows[e] = i n_walls + w) at a
 * build: the old candidate with the same row keeps its flag and spring
 * [m]; a row new to the lists starts without history.  The old rows
 * old_rows[0 .. n_old) ascend (each build writes them in particle order,
 * whose primitives' slots ascend; a start writes the host's rows in
 * order), so a binary search finds them.  prim_src: the memory slot each
 * primitive had when the old rows were made (null: the same;
 * src/backend/omp/reorder.c).  The outputs start at zero: the wall pass
 * writes them before anybody reads an active entry's. */
CD_INLINE void cd_item_wall_carry(cd_long e, const CD_GLOBAL cd_int *rows, CD_GLOBAL cd_wall_entry *ent,
                                  const CD_GLOBAL cd_int *old_rows, cd_long n_old,
                                  const CD_GLOBAL cd_wall_entry *old_ent, const CD_GLOBAL cd_int *prim_src,
                                  cd_int n_walls)
{
    cd_int row = rows[e];
    if (prim_src) row = prim_src[row / n_walls] * n_walls + row % n_walls;
    cd_long lo = 0, hi = n_old; /* the first old row >= row is in [lo, hi] */
    while (lo < hi) {
        cd_long mid = lo + (hi - lo) / 2;
        if (old_rows[mid] < row) lo = mid + 1;
        else hi = mid;
    }
    cd_wall_entry x;
    x.force = cd_v3_zero();
    x.torque = cd_v3_zero();
    x.overlap = 0;
    x.fn = 0;
    x.shear = cd_v3_zero();
    x.active = 0;
    x.pad_ = 0;
    if (lo < n_old && old_rows[lo] == row) {
        x.shear = old_ent[lo].shear;
        x.active = old_ent[lo].active;
    }
    ent[e] = x;
}

/* Total force *F_out [N] and torque *T_out [N m] of particle q (mass m
 * [kg], centre x [m]): gravity [m/s^2] times its mass,
 * then its wall contacts (its candidates' entries wall_out[wall_start[q]
 * .. wall_start[q+1]), ascending by row, i.e. primitive by primitive and
 * wall by wall), then its pair rows in
 * ascending row order, so the sum has one fixed order on every backend.
 * gather_rows[gather_start[q] .. gather_start[q+1]) hold 2 k + side for
 * pair row k: side 1 when q owns the row's primitive j (it gets +F_j), 0
 * when it owns primitive i (it gets -F_j), so the gather reads only the
 * row's force and point.  dimension 2 keeps the motion in the x-y plane. */
CD_INLINE void cd_gather_sum(cd_cols c, cd_particle_id q, cd_real m, cd_vec3 x, const CD_GLOBAL cd_int *gather_start,
                             const CD_GLOBAL cd_pair_id *gather_rows, const CD_GLOBAL cd_int *wall_start,
                             cd_wall_entries wall_out, cd_vec3 gravity, cd_int dimension, cd_vec3 *F_out,
                             cd_vec3 *T_out)
{
    cd_vec3 F = cd_v3_scale(gravity, m);
    cd_vec3 T = cd_v3_zero();
    /* the factor of a side, read from a table: one load where the integer
     * 2 side - 1 took three instructions and a conversion (the same +-1) */
    const cd_real side_sign[2] = {CD_R(-1), CD_R(1)};
    for (cd_int r = wall_start[q]; r < wall_start[q + 1]; r++) {
        if (!wall_out[r].active) continue;
        F = cd_v3_add(F, wall_out[r].force);
        T = cd_v3_add(T, wall_out[r].torque);
    }
    for (cd_int r = gather_start[q]; r < gather_start[q + 1]; r++) {
        cd_pair_id e = gather_rows[r], k = e >> 1;
#if CD_GATHER_SKIPS_INACTIVE
        if (!c.pair_active[k]) {
            /* The zero force an inactive row holds, +0 for side 1 and -0
             * for side 0, changes F only where a component is -0 (+0 + -0
             * and -0 + +0 are +0): adding a +0 for side 1 does that
             * without reading the row; its zero torque never changes T
             * (below).  So the same bits as the sum over every row. */
            if (e & 1) F = cd_v3_add(F, cd_v3_zero());
            continue;
        }
#endif
        /* Every row, without a branch: an inactive row adds a zero force
         * (cd_nb_item_carry, cd_item_pair_force) and a zero torque, which
         * leave F and T as they are (F + 0 is F, but for a sum that is -0,
         * which only a gravity component written as -0 starts; T starts at
         * +0 and never becomes -0).  +F_j or -F_j by a factor +-1 (exact:
         * F + (-f) is F - f).  Branches on the row's activity and side
         * follow no pattern: they were mispredicted about three times per
         * particle-step (callgrind --branch-sim, 10,000 spheres). */
        cd_vec3 f = cd_v3_scale(c.pair_force[k], side_sign[e & 1]);
        F = cd_v3_add(F, f);
        T = cd_v3_add(T, cd_contact_torque(c.pair_point[k], x, f));
    }
    if (dimension == 2) {
        /* Crosses in the x-y plane: no out-of-plane force or tilt. */
        F.z = 0;
        T.x = 0;
        T.y = 0;
    }
    *F_out = F;
    *T_out = T;
}

/* cd_gather_sum for particle q (a memory slot), stored in the rows
 * cd_map(uid, q) of force [N] and torque [N m]: the sync's force and
 * torque in user order (uid: each slot's user id; null where memory order
 * is user order), the sums the first advance of the next call makes. */
CD_INLINE void cd_item_gather_to(cd_cols c, cd_particle_id q, const CD_GLOBAL cd_int *gather_start,
                                 const CD_GLOBAL cd_pair_id *gather_rows, const CD_GLOBAL cd_int *wall_start,
                                 const CD_GLOBAL cd_wall_entry *wall_out, cd_vec3 gravity, cd_int dimension,
                                 const CD_GLOBAL cd_int *uid, CD_GLOBAL cd_vec3 *force, CD_GLOBAL cd_vec3 *torque)
{
    cd_vec3 F, T;
    cd_gather_sum(c, q, c.mass[q], c.position[q], gather_start, gather_rows, wall_start, wall_out, gravity, dimension,
                  &F, &T);
    cd_long r = cd_map(uid, q);
    force[r] = F;
    torque[r] = T;
}

/* cd_gather_sum for particle q, stored as its force and torque where the
 * step holds them (c.force, c.torque: not null; a start's forces). */
CD_INLINE void cd_item_gather(cd_cols c, cd_particle_id q, const CD_GLOBAL cd_int *gather_start,
                              const CD_GLOBAL cd_pair_id *gather_rows, const CD_GLOBAL cd_int *wall_start,
                              const CD_GLOBAL cd_wall_entry *wall_out, cd_vec3 gravity, cd_int dimension)
{
    cd_item_gather_to(c, q, gather_start, gather_rows, wall_start, wall_out, gravity, dimension,
                      (const CD_GLOBAL cd_int *)0, c.force, c.torque);
}

/* Steps 1-4 of particle q in one pass over its data: the first half kick
 * over dt/2, the drift over dt [s], the world ends of its primitives, and
 * the skin test of those ends (limit2 = (skin/2)^2 [m^2], broadphase.h;
 * ref_pose: the poses at the last build when CD_ENDS_FROM_POSE, which
 * stores no ends here, else unused).
 * Returns 1 when one of its primitives moved more than half the skin since
 * the last neighbour-list build.  The same arithmetic as the four items
 * one after the other: fused because each reads what the one before wrote
 * (docs/performance.md, "Bytes per step").
 * The kick's force and torque: where the step holds them (c.force not
 * null), particle q's rows cd_map(uid, q) of c.force, c.torque (an MPI
 * rank's, uid null; the host's, in user order: uid each memory slot's user
 * id, after a start or a build between calls); else summed again from the
 * pair rows and wall entries of the last force evaluation with the
 * gather's arguments (cd_gather_sum: the sum the last step's gather made,
 * the same rows in the same order at the same positions, so the same bits;
 * docs/performance.md, "Session 18, force and torque not held"). */
CD_INLINE int cd_item_advance(cd_cols c, cd_particle_id q, const CD_GLOBAL cd_int *gather_start,
                              const CD_GLOBAL cd_pair_id *gather_rows, const CD_GLOBAL cd_int *wall_start,
                              const CD_GLOBAL cd_wall_entry *wall_out, cd_vec3 gravity, cd_int dimension,
                              const CD_GLOBAL cd_int *uid, cd_real dt, cd_real limit2,
                              const CD_GLOBAL cd_real *ref_pose, cd_int fixed_spheres)
{
    cd_real m = c.mass[q];
    cd_vec3 F, T;
    if (c.force) {
        cd_long r = cd_map(uid, q);
        F = c.force[r];
        T = c.torque[r];
    } else {
        cd_gather_sum(c, q, m, c.position[q], gather_start, gather_rows, wall_start, wall_out, gravity, dimension, &F,
                      &T);
    }
    return cd_advance_from(c, q, c.velocity[q], c.angmom[q], F, T, m, dt, limit2, ref_pose, fixed_spheres);
}

/* cd_gather_sum, then the second half kick over dt/2 (cd_rigid_kick and
 * the angular velocity) and, with next = 1, the next step's
 * cd_item_advance (returns its skin test), all on particle q's state read
 * once (cd_advance_from): the same arithmetic in the same order as the
 * three items one after the other.  The force and torque go into their
 * columns at the call's last step only (next = 0), and only where the step
 * holds them (c.force not null: an MPI rank, whose ghosts' come from their
 * owners): within a call only this item's advance reads them, from its
 * locals, and the next call's first advance and sync sum them again
 * (docs/performance.md, "Session 16, issue 21" and "Session 18, force and
 * torque not held"). */
CD_INLINE_ALWAYS int cd_item_gather_kick_advance(cd_cols c, cd_particle_id q, const CD_GLOBAL cd_int *gather_start,
                                                 const CD_GLOBAL cd_pair_id *gather_rows,
                                                 const CD_GLOBAL cd_int *wall_start,
                                                 const CD_GLOBAL cd_wall_entry *wall_out, cd_vec3 gravity,
                                                 cd_int dimension, cd_real dt, cd_real limit2,
                                                 const CD_GLOBAL cd_real *ref_pose, cd_int fixed_spheres, int next)
{
    cd_real m = c.mass[q];
    cd_vec3 F, T, v = c.velocity[q], L = c.angmom[q];
    cd_gather_sum(c, q, m, c.position[q], gather_start, gather_rows, wall_start, wall_out, gravity, dimension, &F, &T);
    if (!next && c.force) {
        c.force[q] = F;
        c.torque[q] = T;
    }
    cd_rigid_kick(&v, &L, F, T, m, CD_R(0.5) * dt);
    if (next) return cd_advance_from(c, q, v, L, F, T, m, dt, limit2, ref_pose, fixed_spheres);
    c.velocity[q] = v;
    c.angmom[q] = L;
    c.angvel[q] = cd_rigid_angvel(c.orientation[q], L, cd_inertia_of(c, q));
    return 0;
}

/* Primitives per chunk of a wall-load sum: the load of a wall is the sum,
 * in chunk order, of per-chunk sums in primitive order, on every backend
 * (the chunks in parallel on a device), so every backend gets the same
 * bits; with fewer primitives than a chunk it is the plain sum in
 * primitive order. */
#define CD_LOAD_CHUNK 4096

/* Sum of the normal forces F_n [N] that the primitives of chunk ch exert
 * on wall w, in user primitive order (prim_at: user id -> memory slot,
 * null for the identity; kernels/reorder_items.h): the rows in contact,
 * whose entries wall_out holds per wall candidate (cd_wall_out_place; the
 * rows not in contact have F_n = +0, which leaves a sum as it is). */
CD_INLINE cd_real cd_item_wall_load_chunk(cd_cols c, cd_long ch, cd_long n_prims, cd_int n_walls, cd_int w,
                                          const CD_GLOBAL cd_int *prim_at, const CD_GLOBAL cd_int *wall_start,
                                          const CD_GLOBAL cd_int *wall_rows, const CD_GLOBAL cd_wall_entry *wall_out)
{
    cd_long end = (ch + 1) * CD_LOAD_CHUNK < n_prims ? (ch + 1) * CD_LOAD_CHUNK : n_prims;
    cd_real acc = 0;
    for (cd_long u = ch * CD_LOAD_CHUNK; u < end; u++) {
        cd_long row = cd_map(prim_at, u) * n_walls + w;
        cd_long e = cd_wall_out_place(c, row, n_walls, wall_start, wall_rows);
        if (e >= 0 && wall_out[e].active) acc += wall_out[e].fn;
    }
    return acc;
}

/* Has particle q a non-finite position, velocity or angular momentum (a
 * blown-up run)? */
CD_INLINE int cd_item_not_finite(cd_cols c, cd_particle_id q)
{
    cd_vec3 x = c.position[q], v = c.velocity[q], L = c.angmom[q];
    return !isfinite(x.x + x.y + x.z + v.x + v.y + v.z + L.x + L.y + L.z);
}

CD_DEVICE_END
#endif
