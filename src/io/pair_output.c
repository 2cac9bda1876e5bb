/* The per-contact output columns (fields.def, group PAIR_OUT), derived on
 * the host from what the step keeps per pair row.  The step writes only
 * the history, contact point, force on j and F_n of a row (the bytes the
 * next step needs, and F_n); the unit normal, overlap, tangential force and
 * the two torques, which output and analysis read, are rebuilt here when
 * the state is synced to the host:
 *   normal,
 *   overlap : the same contact geometry the step computed (kernels/
 *             step_items.h, cd_pair_geometry_of: the narrow phase's general
 *             path, which gives its point paths' bits (test_narrow_paths),
 *             on the same primitive ends from the host's columns);
 *   F_t     : F_j - F_n n, the law's tangential force up to one rounding
 *             of F_n n (relative 1e-16 of F_n);
 *   torques : the expressions the gather sums (cd_contact_torque), so the
 *             per-contact torques add up to each particle's torque. */
#include "core/sim.h"
#include "step_items.h"

void cd_sim_derive_pair_output(cd_sim *sim)
{
    cd_state *s = &sim->s;
    cd_real sin_parallel = sim->p.sin_parallel;
    cd_int blend = sim->p.parallel_blend;
    size_t n = s->n_pairs;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(n))
    for (size_t r = 0; r < n; r++) {
        cd_pair_id k = (cd_pair_id)r;
        if (!s->pair_active[k]) {
            s->pair_normal[k] = s->pair_ft[k] = s->pair_torque_i[k] = s->pair_torque_j[k] = cd_v3_zero();
            s->pair_overlap[k] = 0;
            continue;
        }
        /* from the host's columns (synced; the arms of a backend's step
         * may be elsewhere, or of another state: an MPI gather's) */
        cd_prim_id i = s->pair_prim_i[k], j = s->pair_prim_j[k];
        cd_contact_geom g;
        cd_pair_geometry_of(s->prim_a[i], s->prim_b[i], s->prim_radius[i], s->prim_a[j], s->prim_b[j],
                            s->prim_radius[j], sin_parallel, blend, &g);
        cd_vec3 f = s->pair_force[k], point = s->pair_point[k];
        s->pair_normal[k] = g.normal;
        s->pair_overlap[k] = g.overlap;
        s->pair_ft[k] = cd_contact_tangential(f, s->pair_fn[k], g.normal);
        s->pair_torque_i[k] = cd_contact_torque(point, s->position[s->prim_particle[s->pair_prim_i[k]]], cd_v3_neg(f));
        s->pair_torque_j[k] = cd_contact_torque(point, s->position[s->prim_particle[s->pair_prim_j[k]]], f);
    }
}
