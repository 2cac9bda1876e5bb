/* Material point method, contact between bodies (src/mpm/mpm_contact.c): two
 * elastic disks colliding head-on without damping conserve momentum to
 * round-off, lose energy only to the contact and do not interpenetrate by
 * more than a cell; the same bits for 1 and 2 threads. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif
#include "mpm/mpm.h"
#include "core/sim.h" /* cd_parallel_min_rows */

#define RHO   1000.0 /* [kg/m^3] */
#define E_    1.0e7  /* [Pa] */
#define NU_   0.3    /* [1] */
#define D_    0.01   /* disk diameter [m] */
#define CELLS 12     /* cells across D */
#define V_A   1.5    /* disk a's speed towards b [m/s] */
#define V_B   (-0.5) /* disk b's [m/s] */

/* Two disks of diameter D on the x axis, gap_cells cells apart, 2 x 2 points per cell, disk a moving at V_A, b at V_B. */
static void two_disks(cd_mpm *m, double gap_cells, double dt)
{
    char err[256];
    double h = D_ / CELLS, l = h / 2, R = D_ / 2;
    int kr = (int)ceil(R / l) + 1;
    size_t n1 = 0;
    for (int j = -kr; j < kr; j++)
        for (int i = -kr; i < kr; i++) {
            double x = (i + 0.5) * l, y = (j + 0.5) * l;
            n1 += x * x + y * y < R * R;
        }
    /* centres at -c and +c */
    double c = (CELLS / 2 + 0.5 * gap_cells) * h;
    int half_x = (int)ceil(c / h) + CELLS + 4, half_y = CELLS / 2 + 4; /* mesh: room for the disks to bulge */
    if (cd_mpm_alloc(m, 2 * n1, 2 * half_x + 1, 2 * half_y + 1, h, -half_x * h, -half_y * h, err, sizeof err))
        fail_msg("%s", err);
    size_t p = 0;
    for (int body = 0; body < 2; body++)
        for (int j = -kr; j < kr; j++)
            for (int i = -kr; i < kr; i++) {
                double x = (i + 0.5) * l, y = (j + 0.5) * l;
                if (!(x * x + y * y < R * R)) continue;
                m->x[p] = (body ? c : -c) + x;
                m->y[p] = y;
                m->vx[p] = body ? V_B : V_A;
                m->vol[p] = l * l;
                m->mass[p] = RHO * l * l;
                m->half[p] = 0.5 * l;
                m->particle[p] = body;
                p++;
            }
    m->mat = cd_mpm_material_make(E_, NU_, -1, 0);
    m->contact_gap = 0.25 * h; /* the default mpm.contact_gap */
    m->dt = dt;
}

static void step(cd_mpm *m)
{
    char err[512];
    /* the step's checks, counts, sums and (offload builds) columns, where the loops ran; 1: the
     * body-nodes outgrew their columns, grown now, and the step runs again */
    int rc;
    do {
        if (cd_mpm_step(m, err, sizeof err)) fail_msg("step: %s", err);
    } while ((rc = cd_mpm_settle(m, err, sizeof err)) == 1);
    if (rc) fail_msg("step: %s", err);
    if (cd_mpm_contact_count(m, err, sizeof err)) fail_msg("count: %s", err); /* n_contacts, read below */
}

/* Overlap [m] of the two disks along the x axis: the rightmost reach of
 * a's points past the leftmost reach of b's (each point a square of
 * half-side F-deformed, as the walls see it); < 0 while apart. */
static double axial_overlap(const cd_mpm *m)
{
    double hi_a = -INFINITY, lo_b = INFINITY;
    for (size_t p = 0; p < m->n; p++) {
        double r = m->half[p] * (fabs(m->f_xx[p]) + fabs(m->f_xy[p])); /* reach along x [m] */
        if (m->particle[p] == 0) hi_a = fmax(hi_a, m->x[p] + r);
        else lo_b = fmin(lo_b, m->x[p] - r);
    }
    return hi_a - lo_b;
}

static void momentum(const cd_mpm *m, double *px, double *py, double *scale)
{
    *px = *py = *scale = 0;
    for (size_t p = 0; p < m->n; p++) {
        *px += m->mass[p] * m->vx[p];
        *py += m->mass[p] * m->vy[p];
        *scale += m->mass[p] * hypot(m->vx[p], m->vy[p]);
    }
}

/* Head-on collision: disk a at 1.5 m/s, b at -0.5 m/s (1/60 of the P-wave
 * speed: small strains, elastic), dt a fifth of the stability limit, until
 * well after they part.  Checks at every step:
 *  - momentum: the node forces sum to zero (partition of unity) and every
 *    contact correction is an equal and opposite impulse, so the total
 *    changes by round-off only: 1e-12 of sum m |v| (the sums have ~1e3
 *    terms of relative error 1e-16 each, a thousand steps);
 *  - energy (kinetic + elastic strain energy): the contact removes the
 *    normal relative velocity of node masses, a perfectly inelastic
 *    collision, so it can only take energy away; the explicit step itself
 *    changes a free elastic body's energy a little (measured: the total
 *    never rose above its start by 1e-6 here): the total
 *    must stay within 1 % above its start; and the loss must stay small,
 *    since the correction acts on the nodes of the contact patch only, a
 *    share of the mass of order h / D: measured 1.9 % at 12 cells across
 *    D, the bound 15 %;
 *  - interpenetration along the axis below one cell (h).
 * The disks must really collide (their velocities reverse) and part. */
static void test_two_disks_collide(void **state)
{
    (void)state;
    cd_mpm m;
    two_disks(&m, 2, 1e-6);
    double lim = cd_mpm_dt_limit(&m);
    m.dt = 0.2 * lim;
    double px0, py0, scale0, e0 = cd_mpm_kinetic_energy(&m), emax = e0, worst_p = 0, worst_pen = -INFINITY;
    momentum(&m, &px0, &py0, &scale0);
    /* the gap of 2 h closes in 0.83 ms; the contact lasts a few D / c (0.1 ms); then 1 ms apart */
    long contact_steps = 0, steps = (long)((2 * m.h / (V_A - V_B) + 1.5e-3) / m.dt);
    for (long k = 0; k < steps; k++) {
        step(&m);
        double px, py, sc;
        momentum(&m, &px, &py, &sc);
        worst_p = fmax(worst_p, fmax(fabs(px - px0), fabs(py - py0)) / scale0);
        double e = cd_mpm_kinetic_energy(&m) + cd_mpm_strain_energy(&m);
        emax = fmax(emax, e);
        worst_pen = fmax(worst_pen, axial_overlap(&m));
        contact_steps += m.n_contacts > 0;
    }
    double ef = cd_mpm_kinetic_energy(&m) + cd_mpm_strain_energy(&m);
    double va = 0, vb = 0, ma = 0, mb = 0;
    for (size_t p = 0; p < m.n; p++) {
        if (m.particle[p] == 0) va += m.mass[p] * m.vx[p], ma += m.mass[p];
        else vb += m.mass[p] * m.vx[p], mb += m.mass[p];
    }
    va /= ma;
    vb /= mb;
    double restitution = (vb - va) / (V_A - V_B);
    print_message("two disks: %ld steps (dt = %.3g s, limit / 5), %ld in contact; momentum drift %.2e of sum m|v|; "
                  "energy max %.6f, end %.4f of the start; restitution %.3f (va %.3f, vb %.3f m/s); deepest axial "
                  "overlap %.3g h\n",
                  steps, m.dt, contact_steps, worst_p, emax / e0, ef / e0, restitution, va, vb, worst_pen / m.h);
    assert_true(contact_steps > 10);
    assert_true(vb > va);           /* they parted */
    assert_true(m.n_contacts == 0); /* and are apart at the end */
    assert_true(worst_p < 1e-12);
    assert_true(emax <= 1.01 * e0);
    assert_true(ef > 0.85 * e0);
    assert_true(worst_pen < m.h);
    cd_mpm_free(&m);
}

/* Same bits for 1 and 2 threads through the contact: every loop runs on
 * the threads (cd_parallel_min_rows lowered to 1), 0.05 ms into the
 * collision, every point column compared. */
static void test_contact_threads_same_bits(void **state)
{
    (void)state;
#ifdef _OPENMP
    long saved = cd_parallel_min_rows;
    cd_parallel_min_rows = 1;
    cd_mpm m[2];
    for (int t = 0; t < 2; t++) {
        omp_set_num_threads(t + 1);
        two_disks(&m[t], 0.25, 1e-6);
        m[t].dt = 0.2 * cd_mpm_dt_limit(&m[t]);
        long steps = (long)((0.25 * m[t].h / (V_A - V_B) + 0.05e-3) / m[t].dt); /* 0.05 ms into the contact */
        for (long k = 0; k < steps; k++) step(&m[t]);
    }
    omp_set_num_threads(2);
    cd_parallel_min_rows = saved;
    assert_true(m[0].n_contacts > 0); /* compared inside the collision */
    assert_int_equal(m[0].n_contacts, m[1].n_contacts);
    size_t n = m[0].n;
    for (int t = 0; t < 2; t++) assert_int_equal(m[t].n, n);
    double *a[] = {m[0].x,   m[0].y,   m[0].vx,   m[0].vy,   m[0].vol,  m[0].sxx, m[0].syy,
                   m[0].sxy, m[0].szz, m[0].f_xx, m[0].f_xy, m[0].f_yx, m[0].f_yy};
    double *b[] = {m[1].x,   m[1].y,   m[1].vx,   m[1].vy,   m[1].vol,  m[1].sxx, m[1].syy,
                   m[1].sxy, m[1].szz, m[1].f_xx, m[1].f_xy, m[1].f_yx, m[1].f_yy};
    for (size_t k = 0; k < sizeof a / sizeof a[0]; k++) assert_memory_equal(a[k], b[k], n * sizeof(double));
    assert_memory_equal(&m[0].penetration, &m[1].penetration, sizeof(double));
    cd_mpm_free(&m[0]);
    cd_mpm_free(&m[1]);
#else
    skip();
#endif
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_disks_collide),
        cmocka_unit_test(test_contact_threads_same_bits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
