/* One work item of each loop of the time step (docs/architecture.md, "A time
 * step"; SPEC sections 2-4).  The OpenMP loops of src/step_omp.c and the
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

CD_DEVICE_BEGIN

/* Half kick of particle q over h = dt/2 [s] (SPEC 4), then its angular
 * velocity from the new angular momentum. */
CD_INLINE void cd_item_kick(cd_cols c, cd_particle_id q, cd_real h)
{
    cd_vec3 v = c.velocity[q], L = c.angmom[q];
    cd_rigid_kick(&v, &L, c.force[q], c.torque[q], c.mass[q], h);
    c.velocity[q] = v;
    c.angmom[q] = L;
    c.angvel[q] = cd_rigid_angvel(c.orientation[q], L, c.inertia[q]);
}

/* Drift of particle q over dt [s]: position and free rotation (SPEC 4). */
CD_INLINE void cd_item_drift(cd_cols c, cd_particle_id q, cd_real dt)
{
    cd_vec3 x = c.position[q], w;
    cd_quat o = c.orientation[q];
    cd_rigid_drift_angvel(&x, &o, &w, c.velocity[q], c.angmom[q], c.inertia[q], dt);
    c.position[q] = x;
    c.orientation[q] = o;
    c.angvel[q] = w;
}

/* A wall after moving for dt [s] with its translational and radial
 * velocities. */
CD_INLINE cd_wall cd_wall_advanced(cd_wall w, cd_real dt)
{
    w.point = cd_v3_axpy(w.point, dt, w.velocity);
    w.radius += dt * w.radial_velocity;
    return w;
}

/* World axis ends of primitive i from its particle's pose. */
CD_INLINE void cd_item_prim_ends(cd_cols c, cd_prim_id i)
{
    cd_particle_id p = c.prim_particle[i];
    c.prim_a[i] = cd_rigid_to_world(c.position[p], c.orientation[p], c.prim_a_body[i]);
    c.prim_b[i] = cd_rigid_to_world(c.position[p], c.orientation[p], c.prim_b_body[i]);
}

/* Pair row k of the Verlet list: narrow phase and contact law with history
 * (SPEC 2-3).  law: particle-particle law, dt [s], sin_parallel [1],
 * parallel_blend 0/1 (material.parallel_blend). */
CD_INLINE void cd_item_pair_force(cd_cols c, cd_pair_id k, cd_law_params law, cd_real dt, cd_real sin_parallel,
                                  cd_int parallel_blend)
{
    cd_prim_id i = c.pair_prim_i[k], j = c.pair_prim_j[k];
    cd_particle_id pi = c.prim_particle[i], pj = c.prim_particle[j];
    cd_vec3 ai = c.prim_a[i], bi = c.prim_b[i], aj = c.prim_a[j], bj = c.prim_b[j];
    cd_real ri = c.prim_radius[i], rj = c.prim_radius[j];
    cd_contact_geom g;
    cd_real s, t;
    cd_segseg_closest(ai, bi, aj, bj, &s, &t);
    int apart = cd_segseg_clearly_apart(ai, bi, ri, aj, bj, rj, s, t);
    if (!apart) cd_segseg_contact_at(ai, bi, ri, aj, bj, rj, s, t, sin_parallel, parallel_blend, &g);
    if (apart || !(g.overlap > 0)) {
        /* Separated: the contact and its history end.  An inactive row is
         * read by nobody but its own next step and the history carry-over
         * (every reader checks pair_active), so it is written only when it
         * changes, to spare the bandwidth. */
        if (c.pair_active[k]) {
            c.pair_active[k] = 0;
            c.pair_shear[k] = cd_v3_zero();
            c.pair_fn[k] = 0;
            c.pair_overlap[k] = 0;
        }
        return;
    }
    cd_vec3 vi = cd_rigid_point_velocity(c.position[pi], c.velocity[pi], c.angvel[pi], g.point);
    cd_vec3 vj = cd_rigid_point_velocity(c.position[pj], c.velocity[pj], c.angvel[pj], g.point);
    cd_real m_eff = cd_law_effective_mass(c.mass[pi], c.mass[pj]);
    cd_vec3 shear = c.pair_shear[k];
    cd_contact_force f = cd_contact_law(law, m_eff, &g, cd_v3_sub(vj, vi), dt, &shear);
    c.pair_active[k] = 1;
    c.pair_shear[k] = shear;
    c.pair_point[k] = g.point;
    c.pair_normal[k] = g.normal;
    c.pair_overlap[k] = g.overlap;
    c.pair_fn[k] = f.fn;
    c.pair_ft[k] = f.ft;
    c.pair_torque_i[k] = cd_v3_cross(cd_v3_sub(g.point, c.position[pi]), cd_v3_neg(f.force_j));
    c.pair_torque_j[k] = cd_v3_cross(cd_v3_sub(g.point, c.position[pj]), f.force_j);
}

/* Primitive i against every wall (SPEC 2, walls; SPEC 3): rows
 * i n_walls .. i n_walls + n_walls - 1 of the wall-contact columns.
 * wall_law: particle-wall law (its mu is replaced by each wall's friction). */
CD_INLINE void cd_item_wall_forces(cd_cols c, cd_prim_id i, const CD_GLOBAL cd_wall *walls, cd_int n_walls,
                                   cd_law_params wall_law, cd_real dt, cd_real sin_parallel,
                                   cd_int parallel_blend)
{
    cd_particle_id pi = c.prim_particle[i];
    for (cd_int w = 0; w < n_walls; w++) {
        cd_long row = (cd_long)i * n_walls + w;
        cd_wall wall = walls[w]; /* private copy: the wall functions take private pointers */
        cd_contact_geom g;
        int apart = cd_wall_clearly_apart(&wall, c.prim_a[i], c.prim_b[i], c.prim_radius[i]);
        if (!apart)
            cd_wall_contact_rule(&wall, c.prim_a[i], c.prim_b[i], c.prim_radius[i], sin_parallel, parallel_blend, &g);
        if (apart || !(g.overlap > 0)) {
            /* An inactive row holds zeros (the load sums read every row);
             * it is written only when it changes, to spare the bandwidth. */
            if (c.wallc_active[row]) {
                c.wallc_active[row] = 0;
                c.wallc_shear[row] = cd_v3_zero();
                c.wallc_overlap[row] = 0;
                c.wallc_fn[row] = 0;
            }
            continue;
        }
        cd_vec3 vi = cd_rigid_point_velocity(c.position[pi], c.velocity[pi], c.angvel[pi], g.point);
        cd_vec3 vw = cd_wall_velocity_at(&wall, g.point);
        cd_law_params law = wall_law;
        law.mu = wall.friction;
        cd_vec3 shear = c.wallc_shear[row];
        /* The particle is body i, the wall body j of infinite mass. */
        cd_contact_force f = cd_contact_law(law, c.mass[pi], &g, cd_v3_sub(vw, vi), dt, &shear);
        cd_vec3 fi = cd_v3_neg(f.force_j);
        c.wallc_active[row] = 1;
        c.wallc_shear[row] = shear;
        c.wallc_overlap[row] = g.overlap;
        c.wallc_fn[row] = f.fn;
        c.wallc_force[row] = fi;
        c.wallc_torque[row] = cd_v3_cross(cd_v3_sub(g.point, c.position[pi]), fi);
    }
}

/* Total force and torque of particle q: gravity [m/s^2] times its mass,
 * then its wall contacts primitive by primitive, then its pair rows
 * gather_rows[gather_start[q] .. gather_start[q+1]) in ascending row order,
 * so the sum has one fixed order on every backend.  dimension 2 keeps the
 * motion in the x-y plane. */
CD_INLINE void cd_item_gather(cd_cols c, cd_particle_id q, const CD_GLOBAL cd_int *gather_start,
                              const CD_GLOBAL cd_pair_id *gather_rows, cd_int n_walls, cd_vec3 gravity,
                              cd_int dimension)
{
    cd_vec3 F = cd_v3_scale(gravity, c.mass[q]);
    cd_vec3 T = cd_v3_zero();
    cd_int first = c.prim_first[q], last = first + c.prim_count[q];
    for (cd_int i = first; i < last; i++)
        for (cd_int w = 0; w < n_walls; w++) {
            cd_long row = (cd_long)i * n_walls + w;
            if (!c.wallc_active[row]) continue;
            F = cd_v3_add(F, c.wallc_force[row]);
            T = cd_v3_add(T, c.wallc_torque[row]);
        }
    for (cd_int r = gather_start[q]; r < gather_start[q + 1]; r++) {
        cd_pair_id k = gather_rows[r];
        if (!c.pair_active[k]) continue;
        cd_vec3 fj = cd_v3_axpy(c.pair_ft[k], c.pair_fn[k], c.pair_normal[k]);
        if (c.prim_particle[c.pair_prim_i[k]] == q) {
            F = cd_v3_sub(F, fj);
            T = cd_v3_add(T, c.pair_torque_i[k]);
        } else {
            F = cd_v3_add(F, fj);
            T = cd_v3_add(T, c.pair_torque_j[k]);
        }
    }
    if (dimension == 2) {
        /* Crosses in the x-y plane: no out-of-plane force or tilt. */
        F.z = 0;
        T.x = 0;
        T.y = 0;
    }
    c.force[q] = F;
    c.torque[q] = T;
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
