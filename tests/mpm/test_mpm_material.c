/* Material point method, one material point (kernels/mpm_material.h,
 * kernels/mpm_shape.h): the shape functions' partition of unity and linear
 * reproduction, and the return mapping against closed-form bilinear
 * curves.  Linear hardening under a radial (fixed-direction) strain path
 * makes the radial return exact for any step size, so the curves are
 * compared to rounding (1e-12 relative). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include <math.h>
#include "mpm_material.h"
#include "mpm_shape.h"

#define E_  1.0e7 /* Young's modulus [Pa] (the paper's) */
#define NU_ 0.45  /* [1] */
#define SY_ 4.0e5 /* yield stress [Pa] */

static void close_rel(double got, double want, double scale, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol * scale))
        fail_msg("%s: %.17g, expected %.17g (tolerance %g x %g)", what, got, want, tol, scale);
}

/* Sum_i N_i = 1, sum_i N_i x_i = x, sum_i dN_i = 0 and sum_i dN_i x_i = 1
 * at points all over a cell: what makes a uniform strain exact. */
static void test_shape_partition(void **state)
{
    (void)state;
    const double h = 0.37; /* [m] */
    for (int k = 0; k <= 100; k++) {
        double g = 5 + 0.01 * k * 0.999; /* grid coordinate inside cell 5 [1] */
        double w[4], dw[4], s = 0, sx = 0, sd = 0, sdx = 0;
        int base = cd_mpm_weights_1d(g, h, w, dw);
        assert_int_equal(base, 4);
        for (int a = 0; a < 4; a++) {
            double xi = (base + a) * h; /* node position [m] */
            s += w[a];
            sx += w[a] * xi;
            sd += dw[a];
            sdx += dw[a] * xi;
            assert_true(w[a] >= 0);
        }
        close_rel(s, 1, 1, 1e-14, "sum N");
        close_rel(sx, g * h, g * h, 1e-14, "sum N x");
        close_rel(sd, 0, 1 / h, 1e-14, "sum dN/dx");
        close_rel(sdx, 1, 1, 1e-14, "sum dN/dx x");
    }
    /* the function's known values: N(0) = 2/3, N(1) = 1/6, N(2) = 0 */
    close_rel(cd_mpm_bspline(0), 2.0 / 3, 1, 1e-15, "N(0)");
    close_rel(cd_mpm_bspline(1), 1.0 / 6, 1, 1e-15, "N(1)");
    close_rel(cd_mpm_bspline(-1), 1.0 / 6, 1, 1e-15, "N(-1)");
    assert_true(cd_mpm_bspline(2) == 0 && cd_mpm_bspline(-2.5) == 0);
    /* the derivative against a central difference (O(d^2) = 1e-12) */
    for (double r = -1.95; r < 1.96; r += 0.1) {
        double d = 1e-6, fd = (cd_mpm_bspline(r + d) - cd_mpm_bspline(r - d)) / (2 * d);
        close_rel(cd_mpm_bspline_dr(r), fd, 1, 1e-8, "dN/dr");
    }
}

/* Simple shear, de_xy only: tau = 2 G eps up to tau_y = sigma_y / sqrt(3),
 * then slope 2 G H / (3 G + H); eps_p = (2 G sqrt(3) (eps - eps_y)) / (3 G + H). */
static void shear_path(double H, int steps, double eps_max)
{
    cd_mpm_material m = cd_mpm_material_make(E_, NU_, SY_, H);
    cd_mpm_stress s = {0, 0, 0, 0};
    double ep = 0, G = m.shear, eps_y = SY_ / (sqrt(3.0) * 2 * G);
    for (int k = 1; k <= steps; k++) {
        double eps = eps_max * k / steps;
        cd_mpm_stress_update(m, &s, &ep, 0, 0, eps_max / steps);
        double tau = eps <= eps_y ? 2 * G * eps : SY_ / sqrt(3.0) + 2 * G * H / (3 * G + H) * (eps - eps_y);
        double epw = eps <= eps_y ? 0 : 2 * G * sqrt(3.0) * (eps - eps_y) / (3 * G + H);
        close_rel(s.xy, tau, SY_, 1e-12, "shear stress");
        close_rel(ep, epw, eps_max, 1e-12, "plastic strain (shear)");
        close_rel(s.xx, 0, SY_, 1e-12, "sigma_xx (shear)");
        close_rel(s.zz, 0, SY_, 1e-12, "sigma_zz (shear)");
    }
}

/* Uniaxial strain in y (the plane-strain oedometer): pressure K eps
 * throughout; von Mises q = 2 G |eps| up to sigma_y, then
 * q = sigma_y + 2 G H / (3 G + H) (|eps| - eps_y); sigma_yy = p - 2/3 q in
 * compression, sigma_xx = sigma_zz = p + q / 3. */
static void oedometer_path(double H, int steps, double eps_min)
{
    cd_mpm_material m = cd_mpm_material_make(E_, NU_, SY_, H);
    cd_mpm_stress s = {0, 0, 0, 0};
    double ep = 0, G = m.shear, K = m.lambda + 2 * G / 3, eps_y = SY_ / (2 * G);
    for (int k = 1; k <= steps; k++) {
        double eps = eps_min * k / steps, a = fabs(eps);
        int plastic = cd_mpm_stress_update(m, &s, &ep, 0, eps_min / steps, 0);
        double q = a <= eps_y ? 2 * G * a : SY_ + 2 * G * H / (3 * G + H) * (a - eps_y);
        double p = K * eps;
        close_rel(s.yy, p - 2 * q / 3, SY_, 1e-12, "sigma_yy (oedometer)");
        close_rel(s.xx, p + q / 3, SY_, 1e-12, "sigma_xx (oedometer)");
        close_rel(s.zz, p + q / 3, SY_, 1e-12, "sigma_zz (oedometer)");
        close_rel(cd_mpm_von_mises(s), q, SY_, 1e-12, "von Mises stress");
        if (a > eps_y * (1 + 1e-9)) assert_int_equal(plastic, 1);
    }
}

static void test_return_mapping_shear(void **state)
{
    (void)state;
    for (int h = 0; h < 3; h++) {
        double H[3] = {0, 1e6, 3e6}; /* the paper's hardening moduli [Pa] */
        shear_path(H[h], 1000, 0.1);
        shear_path(H[h], 7, 0.1); /* large steps: still exact (radial path) */
    }
}

static void test_return_mapping_oedometer(void **state)
{
    (void)state;
    for (int h = 0; h < 3; h++) {
        double H[3] = {0, 1e6, 3e6};
        oedometer_path(H[h], 1000, -0.17);
        oedometer_path(H[h], 5, -0.17);
    }
}

/* Elastic only (sigma_y < 0): any strain gives Hooke's plane-strain law. */
static void test_elastic(void **state)
{
    (void)state;
    cd_mpm_material m = cd_mpm_material_make(E_, NU_, -1, 0);
    cd_mpm_stress s = {0, 0, 0, 0};
    double ep = 0, ex = 0.03, ey = -0.2, exy = 0.05; /* [1] */
    assert_int_equal(cd_mpm_stress_update(m, &s, &ep, ex, ey, exy), 0);
    double lam = E_ * NU_ / ((1 + NU_) * (1 - 2 * NU_)), G = E_ / (2 * (1 + NU_));
    close_rel(s.xx, lam * (ex + ey) + 2 * G * ex, E_, 1e-14, "sigma_xx");
    close_rel(s.yy, lam * (ex + ey) + 2 * G * ey, E_, 1e-14, "sigma_yy");
    close_rel(s.zz, lam * (ex + ey), E_, 1e-14, "sigma_zz");
    close_rel(s.xy, 2 * G * exy, E_, 1e-14, "sigma_xy");
    assert_true(ep == 0);
}

/* Eq. (4) under pure dilation du = e x: det(I + grad du) = (1 + e)^2, and n
 * steps compound to (1 + e)^(2 n). */
static void test_volume_dilation(void **state)
{
    (void)state;
    double e = 1e-3, V = 2.5e-7; /* [1], [m^3/m] */
    close_rel(cd_mpm_volume_ratio(e, 0, 0, e), (1 + e) * (1 + e), 1, 1e-15, "one step");
    for (int k = 0; k < 100; k++) V *= cd_mpm_volume_ratio(e, 0, 0, e);
    close_rel(V, 2.5e-7 * pow(1 + e, 200), 2.5e-7, 1e-13, "100 steps");
    /* a rotation-free shear keeps the area to second order: det = 1 - g^2 */
    close_rel(cd_mpm_volume_ratio(0, 0.01, 0.01, 0), 1 - 1e-4, 1, 1e-15, "shear");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shape_partition),      cmocka_unit_test(test_elastic),
        cmocka_unit_test(test_return_mapping_shear), cmocka_unit_test(test_return_mapping_oedometer),
        cmocka_unit_test(test_volume_dilation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
