/* Contacts, bonds and particle stresses on hand-built snapshots whose
 * answers are worked out by hand: Z, Z_c, valence, P_c, P_b, P_k, bond
 * forces and F_k with several contacts per pair (host/analysis/analyze_network.c),
 * branch vectors and interlocking (analyze_structure.c), the particle
 * stress tensor and its invariants (analyze_stress.c). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "analysis/analyze.h"

/* n particles of one shape (volume V, tip length L) and nc contacts, no
 * walls; positions and contacts are set by the caller. */
static void bare_snapshot(cd_an_snapshot *s, size_t n, size_t nc, size_t nw, double V, double L)
{
    memset(s, 0, sizeof(*s));
    assert_int_equal(cd_an_snapshot_alloc(s, n, n, nc, nw, 1), 0);
    snprintf(s->path, sizeof s->path, "hand-built");
    cd_config_defaults(&s->cfg);
    s->cfg_ok = 1;
    s->n_shapes = 1;
    s->shapes = calloc(1, sizeof(cd_an_shape));
    s->shapes[0].volume = V;
    s->shapes[0].tip_length = L;
    for (size_t p = 0; p < n; p++) {
        s->scale[p] = 1;
        s->prim_particle[p] = (int32_t)p;
    }
}

static void contact(cd_an_snapshot *s, size_t c, int i, int j, double fn, cd_vec3 n, cd_vec3 ft, cd_vec3 point)
{
    s->ci[c] = i;
    s->cj[c] = j;
    s->fn[c] = fn;
    s->normal[c] = n;
    s->ft[c] = ft;
    s->point[c] = point;
}

/* Seven particles: bonds (0,1) with 3 contacts, (0,2) with 2, (1,2) and
 * (3,4) with 1; particle 5 has no contact (a rattler) and particle 6 only
 * touches a wall, which makes no neighbour.  The rows are shuffled and the
 * pair order flips, as in a real pair list.  By hand:
 *   N_c = 7, N_b = 4, N_p* = 5: Z_c = 14/5, Z = 8/5, valence = 7/4;
 *   contacts per particle 5, 4, 3, 1, 1: P_c(1) = 2/5, P_c(3) = P_c(4) =
 *   P_c(5) = 1/5; neighbours 2, 2, 2, 1, 1: P_b(1) = 2/5, P_b(2) = 3/5;
 *   P_k(1) = 2/4, P_k(2) = P_k(3) = 1/4.
 * Bond (0,1): force on 1 = (1,0,0) + (0,-2,0) + (1,0,1) = (2,-2,1), |F| = 3;
 * bond (0,2): force on 2 = (0,0,3) + (0,0,1) = (0,0,4), |F| = 4. */
static void build_network(cd_an_snapshot *s)
{
    bare_snapshot(s, 7, 7, 1, 1e-6, 1.0);
    const cd_vec3 ex = cd_v3(1, 0, 0), ey = cd_v3(0, 1, 0), ez = cd_v3(0, 0, 1), o = cd_v3(0, 0, 0);
    s->pos[0] = cd_v3(0, 0, 0);
    s->pos[1] = cd_v3(0.6, 0, 0);
    s->pos[2] = cd_v3(0, 0, 0.8);
    s->pos[3] = cd_v3(5, 5, 5);
    s->pos[4] = cd_v3(5, 5, 5.5);
    s->pos[5] = cd_v3(9, 9, 9);
    s->pos[6] = cd_v3(-9, -9, -9);
    contact(s, 0, 2, 0, 3, cd_v3(0, 0, -1), o, cd_v3(0, 0, 0.4));       /* (0,2): on 0 = (0,0,-3) */
    contact(s, 1, 0, 1, 1, ex, o, cd_v3(0.3, 0, 0));                    /* (0,1) */
    contact(s, 2, 3, 4, 2, ez, o, cd_v3(5, 5, 5.25));                   /* (3,4) */
    contact(s, 3, 1, 0, 2, ey, o, cd_v3(0.3, 0.1, 0));                  /* (0,1): on 0 = (0,2,0) */
    contact(s, 4, 1, 2, 1, cd_v3(-0.6, 0, 0.8), o, cd_v3(0.3, 0, 0.4)); /* (1,2) */
    contact(s, 5, 0, 1, 1, ex, ez, cd_v3(0.3, 0, 0.1));                 /* (0,1) */
    contact(s, 6, 0, 2, 1, ez, o, cd_v3(0, 0.1, 0.4));                  /* (0,2): on 2 = (0,0,1) */
    s->w_prim[0] = 6;
    s->w_wall[0] = 0;
    s->w_force[0] = cd_v3(0, 1, 0);
    s->w_point[0] = cd_v3(-9, -9.5, -9);
}

static void test_network_by_hand(void **state)
{
    (void)state;
    cd_an_snapshot s;
    build_network(&s);
    cd_an_bonds b;
    char err[512];
    assert_int_equal(cd_an_bonds_build(&s, &b, err, sizeof err), 0);
    assert_int_equal(b.n, 4);
    double mean_fn = (3 + 1 + 2 + 2 + 1 + 1 + 1) / 7.0;
    cd_an_geometry g;
    memset(&g, 0, sizeof g);
    g.dim = 3;
    g.L = 1.0;
    cd_an_options opt;
    cd_an_options_defaults(&opt);
    cd_an_input in = {&s, &g, &b, &opt, mean_fn};
    cd_an_report rep;
    memset(&rep, 0, sizeof rep);
    assert_int_equal(cd_an_network(&in, &rep, err, sizeof err), 0);
    const double eps = 1e-12;
    assert_true(fabs(cd_an_value(&rep, "network", "n_particles_in_contact") - 5) < eps);
    assert_true(fabs(cd_an_value(&rep, "network", "n_rattlers") - 2) < eps);
    assert_true(fabs(cd_an_value(&rep, "network", "Z_c") - 14.0 / 5) < eps);
    assert_true(fabs(cd_an_value(&rep, "network", "Z") - 8.0 / 5) < eps);
    assert_true(fabs(cd_an_value(&rep, "network", "valence") - 7.0 / 4) < eps);
    const cd_an_curve *pc = cd_an_curve_find(&rep, "network", "contacts_per_particle");
    const double pc_hand[5] = {0.4, 0, 0.2, 0.2, 0.2};
    assert_int_equal(pc->rows, 5);
    for (int c = 0; c < 5; c++) {
        assert_true(fabs(pc->data[2 * c] - (c + 1)) < eps);
        assert_true(fabs(pc->data[2 * c + 1] - pc_hand[c]) < eps);
    }
    const cd_an_curve *pb = cd_an_curve_find(&rep, "network", "neighbours_per_particle");
    assert_int_equal(pb->rows, 2);
    assert_true(fabs(pb->data[1] - 0.4) < eps && fabs(pb->data[3] - 0.6) < eps);
    const cd_an_curve *pk = cd_an_curve_find(&rep, "network", "valence");
    assert_int_equal(pk->rows, 3);
    const double pk_hand[3] = {0.5, 0.25, 0.25};
    /* F_k: k = 1 bonds (1,2) |F| = 1 and (3,4) |F| = 2; k = 2: 4; k = 3: 3 */
    const double fk_hand[3] = {1.5 / mean_fn, 4 / mean_fn, 3 / mean_fn};
    double sum_kpk = 0;
    for (int k = 0; k < 3; k++) {
        assert_true(fabs(pk->data[4 * k + 1] - pk_hand[k]) < eps);
        assert_true(fabs(pk->data[4 * k + 2] - fk_hand[k]) < eps);
        sum_kpk += (k + 1) * pk->data[4 * k + 1];
    }
    assert_true(fabs(sum_kpk - 7.0 / 4) < eps); /* valence = sum k P_k */

    /* branch vectors: lengths 0.6 (0,1), 0.8 (0,2), 1.0 (1,2), 0.5 (3,4) */
    assert_int_equal(cd_an_branch(&in, &rep, err, sizeof err), 0);
    assert_true(fabs(cd_an_value(&rep, "branch", "mean_l") - 2.9 / 4) < eps);
    assert_true(fabs(cd_an_value(&rep, "branch", "lambda") - (1 - 2.9 / 4)) < eps);
    assert_true(fabs(cd_an_value(&rep, "branch", "mean_l2") - (0.36 + 0.64 + 1 + 0.25) / 4) < eps);

    /* bond forces: |F| = 3, 4, 1, 2 over <F_n>; mean bond force 2.5 N */
    assert_int_equal(cd_an_bond_forces(&in, &rep, err, sizeof err), 0);
    assert_true(fabs(cd_an_value(&rep, "bond_forces", "mean_bond_force") - 2.5) < eps);
    cd_an_report_free(&rep);
    cd_an_bonds_free(&b);

    /* a contact of a particle with itself is bad input */
    s.cj[2] = 3;
    assert_int_equal(cd_an_bonds_build(&s, &b, err, sizeof err), 2);
    assert_non_null(strstr(err, "contact row 2"));
    cd_an_snapshot_free(&s);
}

/* Particle 0 (volume V) between particles 1 (at +2R x) and 2 (at -2R x),
 * touching each at distance R along x, with normal force F and tangential
 * force T: the forces on 0 are (-F, -T, 0) at r = (R, 0, 0) and (F, T, 0)
 * at r = (-R, 0, 0) -- equal and opposite.  So
 *   sigma_0 = (1/V) sum F (x) r:  sigma_xx = -2FR/V, sigma_yx = -2TR/V,
 * every other entry 0, I1 = -2FR/V.  Particle 1 also touches a wall at
 * (3R, 0, 0) with force (-W, 0, 0): sigma_1,xx = (-FR - WR)/V + 0,
 * sigma_1,yx = -TR/V ... worked out below. */
static void test_stress_two_contacts(void **state)
{
    (void)state;
    const double V = 2e-6, R = 0.01, F = 3, T = 0.5, Wf = 1.5; /* [m^3], [m], [N], [N], [N] */
    cd_an_snapshot s;
    bare_snapshot(&s, 3, 2, 1, V, 4 * R);
    s.pos[0] = cd_v3(0, 0, 0);
    s.pos[1] = cd_v3(2 * R, 0, 0);
    s.pos[2] = cd_v3(-2 * R, 0, 0);
    /* contact 0: from 0 to 1, force on 1 = F e_x + T e_y */
    contact(&s, 0, 0, 1, F, cd_v3(1, 0, 0), cd_v3(0, T, 0), cd_v3(R, 0, 0));
    /* contact 1: from 2 to 0, force on 0 = F e_x + T e_y */
    contact(&s, 1, 2, 0, F, cd_v3(1, 0, 0), cd_v3(0, T, 0), cd_v3(-R, 0, 0));
    s.w_prim[0] = 1;
    s.w_wall[0] = 0;
    s.w_force[0] = cd_v3(-Wf, 0, 0);
    s.w_point[0] = cd_v3(3 * R, 0, 0);
    double sigma[27];
    int32_t nc[3];
    assert_int_equal(cd_an_particle_stress(&s, sigma, nc), 0);
    double want0[9] = {-2 * F * R / V, 0, 0, -2 * T * R / V, 0, 0, 0, 0, 0};
    /* particle 1: force (F, T, 0) at r = (-R, 0, 0) and (-W, 0, 0) at (R, 0, 0) */
    double want1[9] = {(-F * R - Wf * R) / V, 0, 0, -T * R / V, 0, 0, 0, 0, 0};
    /* particle 2: force (-F, -T, 0) at r = (R, 0, 0) */
    double want2[9] = {-F * R / V, 0, 0, -T * R / V, 0, 0, 0, 0, 0};
    const double *want[3] = {want0, want1, want2};
    for (int p = 0; p < 3; p++)
        for (int k = 0; k < 9; k++)
            if (fabs(sigma[9 * p + k] - want[p][k]) > 1e-9 * F * R / V)
                fail_msg("sigma[%d][%d] = %g, expected %g", p, k, sigma[9 * p + k], want[p][k]);
    assert_int_equal(nc[0], 2);
    assert_int_equal(nc[1], 2);
    assert_int_equal(nc[2], 1);

    /* Through the measure, without tangential forces and the wall: I1 =
     * -2FR/V, -FR/V, -FR/V; <I1> = -4FR/(3V); i = 1.5, 0.75, 0.75; the
     * principal stresses of particle 0 are 0, 0, -2FR/V. */
    s.ft[0] = s.ft[1] = cd_v3(0, 0, 0);
    s.nw = 0;
    cd_an_geometry g;
    memset(&g, 0, sizeof g);
    g.dim = 3;
    g.L = 4 * R;
    cd_an_options opt;
    cd_an_options_defaults(&opt);
    cd_an_bonds b;
    memset(&b, 0, sizeof b);
    cd_an_input in = {&s, &g, &b, &opt, F};
    cd_an_report rep;
    memset(&rep, 0, sizeof rep);
    char err[512];
    assert_int_equal(cd_an_stress(&in, &rep, err, sizeof err), 0);
    double u = F * R / V;
    assert_true(fabs(cd_an_value(&rep, "stress", "mean_I1") + 4 * u / 3) < 1e-9 * u);
    assert_true(fabs(cd_an_value(&rep, "stress", "mean_sigma_1")) < 1e-9 * u);
    assert_true(fabs(cd_an_value(&rep, "stress", "mean_sigma_3") + 4 * u / 3) < 1e-9 * u);
    const cd_an_curve *pdf = cd_an_curve_find(&rep, "stress", "pdf");
    /* i = 0.75 falls in bin 3 ([0.6, 0.8)), i = 1.5 in bin 7 ([1.4, 1.6)) */
    assert_true(fabs(pdf->data[3 * 3 + 2] - 2) < 1e-12 && fabs(pdf->data[3 * 7 + 2] - 1) < 1e-12);
    cd_an_report_free(&rep);
    cd_an_snapshot_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_network_by_hand),
        cmocka_unit_test(test_stress_two_contacts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
