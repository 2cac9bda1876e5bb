/* Material point method, the explicit step (src/mpm.c): patch tests on a
 * block of points, the volume update under pure dilation, the vibration of
 * an elastic bar against theory, the same bits for 1 and 2 threads, and
 * the diametral compression of the paper's disk against the elastic
 * solution of a disk under two opposite line loads. */
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
#include "mpm.h"

#define RHO 1000.0 /* [kg/m^3] */
#define E_ 1.0e7   /* [Pa] */
#define NU_ 0.3    /* [1] */

static void close_rel(double got, double want, double scale, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol * scale)) fail_msg("%s: %.17g, expected %.17g (tolerance %g x %g)", what, got, want, tol, scale);
}

/* A block of cx x cy cells of side h [m] filled with 2 x 2 points per
 * cell, its lower-left corner on node (4, 4) of a mesh with 4 free cells
 * around it; no walls. */
static void block(cd_mpm *m, int cx, int cy, double h, double dt)
{
    char err[256];
    int pps = 2;
    double l = h / pps;
    if (cd_mpm_alloc(m, (size_t)(cx * pps) * (size_t)(cy * pps), cx + 9, cy + 9, h, -4 * h, -4 * h, err, sizeof err))
        fail_msg("%s", err);
    size_t p = 0;
    for (int j = 0; j < cy * pps; j++)
        for (int i = 0; i < cx * pps; i++, p++) {
            m->x[p] = (i + 0.5) * l;
            m->y[p] = (j + 0.5) * l;
            m->vol[p] = l * l;
            m->mass[p] = RHO * l * l;
            m->half[p] = 0.5 * l;
        }
    m->mat = cd_mpm_material_make(E_, NU_, -1, 0);
    m->dt = dt;
}

/* Interior: every node of the point's stencil has its whole support
 * (two cells each side) inside the block. */
static int interior(const cd_mpm *m, size_t p, int cx, int cy)
{
    int i = (int)floor(m->x[p] / m->h), j = (int)floor(m->y[p] / m->h); /* cell */
    return i - 1 - 2 >= 0 && i + 2 + 2 <= cx && j - 1 - 2 >= 0 && j + 2 + 2 <= cy;
}

static void step(cd_mpm *m)
{
    char err[512];
    if (cd_mpm_step(m, err, sizeof err)) fail_msg("step: %s", err);
}

/* Patch test 1: a linear velocity field v = A x + b, no stress.  The
 * B-splines reproduce linear fields and the point lattice is symmetric
 * about every node, so every interior point sees grad v = A exactly and
 * takes the uniform stress increment C : sym(A) dt. */
static void test_patch_uniform_strain(void **state)
{
    (void)state;
    cd_mpm m;
    int cx = 16, cy = 14;
    double h = 0.01, dt = 1e-6, A[2][2] = {{0.3, -0.7}, {1.1, -0.4}}, b[2] = {0.2, -0.1}; /* [1/s], [m/s] */
    block(&m, cx, cy, h, dt);
    for (size_t p = 0; p < m.n; p++) {
        m.vx[p] = A[0][0] * m.x[p] + A[0][1] * m.y[p] + b[0];
        m.vy[p] = A[1][0] * m.x[p] + A[1][1] * m.y[p] + b[1];
    }
    step(&m);
    double lam = m.mat.lambda, G = m.mat.shear;
    double exx = A[0][0] * dt, eyy = A[1][1] * dt, exy = 0.5 * (A[0][1] + A[1][0]) * dt;
    double sxx = lam * (exx + eyy) + 2 * G * exx, syy = lam * (exx + eyy) + 2 * G * eyy, sxy = 2 * G * exy;
    double scale = E_ * 1e-6, vol = 0.25 * h * h * (1 + exx + eyy + (A[0][0] * A[1][1] - A[0][1] * A[1][0]) * dt * dt);
    int n_in = 0;
    for (size_t p = 0; p < m.n; p++) {
        if (!interior(&m, p, cx, cy)) continue;
        n_in++;
        close_rel(m.sxx[p], sxx, scale, 1e-12, "sigma_xx");
        close_rel(m.syy[p], syy, scale, 1e-12, "sigma_yy");
        close_rel(m.sxy[p], sxy, scale, 1e-12, "sigma_xy");
        close_rel(m.szz[p], lam * (exx + eyy), scale, 1e-12, "sigma_zz");
        close_rel(m.vol[p], vol, 0.25 * h * h, 1e-13, "volume");
    }
    assert_true(n_in >= 16);
    cd_mpm_free(&m);
}

/* Patch test 2: a uniform stress at rest is in equilibrium: the internal
 * forces of every node whose support lies inside the block cancel, so
 * interior points keep zero velocity while the block's edges accelerate
 * (sigma / (rho h) scale). */
static void test_patch_uniform_stress(void **state)
{
    (void)state;
    cd_mpm m;
    int cx = 16, cy = 16;
    double h = 0.01, dt = 1e-6;
    block(&m, cx, cy, h, dt);
    for (size_t p = 0; p < m.n; p++) m.sxx[p] = 3e5, m.syy[p] = -2e5, m.sxy[p] = 1e5, m.szz[p] = 4e4;
    step(&m);
    double edge = 3e5 / (RHO * h) * dt, vmax_in = 0, vmax = 0; /* [m/s] */
    for (size_t p = 0; p < m.n; p++) {
        double v = hypot(m.vx[p], m.vy[p]);
        if (v > vmax) vmax = v;
        if (interior(&m, p, cx, cy) && v > vmax_in) vmax_in = v;
    }
    print_message("uniform stress: interior |v| <= %.3g m/s, edges up to %.3g m/s (scale %.3g)\n", vmax_in, vmax, edge);
    assert_true(vmax > 0.1 * edge);      /* the test can see a force */
    assert_true(vmax_in <= 1e-10 * edge); /* and there is none inside */
    cd_mpm_free(&m);
}

/* Pure dilation v = a x: one step multiplies each interior point's volume
 * by det(I + a dt I) = (1 + a dt)^2 (eq. 4) and its deformation gradient
 * by (1 + a dt). */
static void test_volume_pure_dilation(void **state)
{
    (void)state;
    cd_mpm m;
    int cx = 14, cy = 14;
    double h = 0.02, dt = 1e-5, a = 50; /* [m], [s], [1/s] */
    block(&m, cx, cy, h, dt);
    for (size_t p = 0; p < m.n; p++) m.vx[p] = a * m.x[p], m.vy[p] = a * m.y[p];
    step(&m);
    double r = 1 + a * dt;
    int n_in = 0;
    for (size_t p = 0; p < m.n; p++) {
        if (!interior(&m, p, cx, cy)) continue;
        n_in++;
        close_rel(m.vol[p], 0.25 * h * h * r * r, 0.25 * h * h, 1e-13, "volume");
        close_rel(m.f_xx[p], r, 1, 1e-13, "F_xx");
        close_rel(m.f_yy[p], r, 1, 1e-13, "F_yy");
        close_rel(m.f_xy[p], 0, 1, 1e-13, "F_xy");
    }
    assert_true(n_in >= 16);
    cd_mpm_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_patch_uniform_strain),
        cmocka_unit_test(test_patch_uniform_stress),
        cmocka_unit_test(test_volume_pure_dilation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
