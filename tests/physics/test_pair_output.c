/* The per-contact output columns (fields.def, PAIR_OUT) that the host
 * derives at sync (src/io/pair_output.c) from what the step keeps per pair
 * row: they must describe the forces the step applied.  On a settling pile
 * of hexapods in a cylinder (many contacts, friction, walls):
 *  - the normal is a unit vector and F_t lies in the tangent plane;
 *  - F_n n + F_t gives back the force the step stored for j;
 *  - the overlap of a contact, which no row keeps (derived at sync from the
 *    host's ends, and by the observables from the step's), is positive, and
 *    the largest overlap the observables find is the largest of these;
 *  - for every particle, gravity, its wall contacts and its pair rows' forces
 *    and derived torques add up to the force and torque the step's gather
 *    gave it. */
#include "test_util.h"
#include <math.h>

static const char *pile =
    "run: {dt: 8.0e-6, steps: 0, seed: 3}\n"
    "physics: {gravity: [0, -98.1, 0]}\n"
    "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0.2, friction: 0.5, wall_friction: 0.3}\n"
    "particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 60, polydispersity: 0.2}]\n"
    "domain: {type: cylinder, diameter: 0.08, height: 0.2}\n"
    "init: {placement: lattice, clearance: 1.0, speed: 0.5}\n";

static double vnorm(cd_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

static void test_derived_contact_columns_match_the_applied_forces(void **state)
{
    (void)state;
    static cd_sim sim;
    cd_config cfg;
    cdt_setup(&sim, &cfg, pile);
    assert_int_equal(cd_sim_initial_forces(&sim), 0);
    cdt_step(&sim, 15000); /* 0.12 s under 10 g: the lattice has fallen into a pile */
    const cd_state *s = &sim.s;
    size_t active = 0;
    for (size_t k = 0; k < s->n_pairs; k++) {
        if (!s->pair_active[k]) continue;
        active++;
        cd_vec3 n = s->pair_normal[k], ft = s->pair_ft[k], f = s->pair_force[k];
        double fn = s->pair_fn[k], scale = vnorm(f) + fabs(fn);
        /* One rounding per operation on numbers of size |F|: 1e-14 |F| is
         * a hundred roundings of margin. */
        assert_true(fabs(vnorm(n) - 1) < 1e-14);
        assert_true(fabs(cd_v3_dot(ft, n)) <= 1e-14 * scale);
        cd_vec3 back = cd_v3_axpy(ft, fn, n);
        assert_true(vnorm(cd_v3_sub(back, f)) <= 1e-14 * scale);
    }
    print_message("%zu active contacts among %zu pair rows\n", active, s->n_pairs);
    assert_true(active > 60); /* a pile, not a gas */

    /* The overlaps: derived at sync on the host (src/io/pair_output.c) and
     * by the observables on the step's columns (kernels/observe_items.h),
     * each by the narrow phase the step ran on the same ends: the largest
     * ratio overlap / diameter is the same number both ways (a maximum
     * does not depend on the order). */
    double most = 0, elastic = 0; /* [1], [J] */
    for (size_t k = 0; k < s->n_pairs; k++) {
        if (!s->pair_active[k]) continue;
        double ri = s->prim_radius[s->pair_prim_i[k]], rj = s->prim_radius[s->pair_prim_j[k]];
        assert_true(s->pair_overlap[k] > 0);
        double ratio = s->pair_overlap[k] / (2 * (ri < rj ? ri : rj));
        if (ratio > most) most = ratio;
        elastic +=
            cd_contact_elastic_energy(sim.p.law, cd_law_pair_radius(ri, rj), s->pair_overlap[k], s->pair_shear[k]);
    }
    for (size_t r = 0; r < s->n_prims * s->n_walls; r++) {
        if (!s->wallc_active[r]) continue;
        double ri = s->prim_radius[r / s->n_walls];
        double ratio = s->wallc_overlap[r] / (2 * ri);
        if (ratio > most) most = ratio;
        elastic += cd_contact_elastic_energy(sim.p.wall_law, ri, s->wallc_overlap[r], s->wallc_shear[r]);
    }
    cd_observables o;
    cd_sim_observe(&sim, &o);
    print_message("largest overlap / diameter %.6g, observables %.6g; elastic energy %.9g J, observables %.9g J\n",
                  most, o.max_overlap_ratio, elastic, o.elastic);
    assert_true(most > 0 && o.max_overlap_ratio == most);
    /* the same terms summed in another order (the observables' tree) */
    assert_true(elastic > 0 && fabs(o.elastic - elastic) <= 1e-12 * elastic);

    /* Per particle: the step's gather against the sum of the output columns
     * (the same terms; on the host backend in the same order, elsewhere the
     * torque's cross products are redone on the host: 1e-12 of the sum of
     * the terms' magnitudes allows for that). */
    double worst = 0;
    for (size_t q = 0; q < s->n_particles; q++) {
        cd_vec3 F = cd_v3_scale(sim.p.gravity, s->mass[q]), T = cd_v3_zero();
        double fscale = vnorm(F), tscale = 0;
        for (cd_int i = s->prim_first[q]; i < s->prim_first[q] + s->prim_count[q]; i++)
            for (size_t w = 0; w < s->n_walls; w++) {
                size_t row = (size_t)i * s->n_walls + w;
                if (!s->wallc_active[row]) continue;
                F = cd_v3_add(F, s->wallc_force[row]);
                T = cd_v3_add(T, s->wallc_torque[row]);
                fscale += vnorm(s->wallc_force[row]);
                tscale += vnorm(s->wallc_torque[row]);
            }
        for (size_t k = 0; k < s->n_pairs; k++) {
            if (!s->pair_active[k]) continue;
            int is_i = (size_t)s->prim_particle[s->pair_prim_i[k]] == q;
            int is_j = (size_t)s->prim_particle[s->pair_prim_j[k]] == q;
            if (!is_i && !is_j) continue;
            F = is_j ? cd_v3_add(F, s->pair_force[k]) : cd_v3_sub(F, s->pair_force[k]);
            cd_vec3 t = is_j ? s->pair_torque_j[k] : s->pair_torque_i[k];
            T = cd_v3_add(T, t);
            fscale += vnorm(s->pair_force[k]);
            tscale += vnorm(t);
        }
        double df = vnorm(cd_v3_sub(F, s->force[q])), dt = vnorm(cd_v3_sub(T, s->torque[q]));
        assert_true(df <= 1e-12 * fscale);
        assert_true(dt <= 1e-12 * tscale + 1e-300);
        if (tscale > 0 && dt / tscale > worst) worst = dt / tscale;
    }
    print_message("largest torque mismatch: %.3g of the terms' sum\n", worst);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_derived_contact_columns_match_the_applied_forces),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
