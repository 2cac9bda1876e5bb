/* Material point method: cubic B-spline shape functions on a regular
 * background mesh of square cells (docs/mpm.md).  Device-safe: compiled as
 * C11 (host, OpenMP) and as OpenCL C.
 *
 * The 1D function of the normalised distance r = (x - x_i) / h between a
 * point x and a node x_i (cell size h [m]) is
 *     N(r) = |r|^3 / 2 - r^2 + 2/3           for |r| < 1
 *     N(r) = (2 - |r|)^3 / 6                 for 1 <= |r| < 2
 *     N(r) = 0                               otherwise,
 * and the 2D shape function of node (i, j) is N(r_x) N(r_y).  A point in
 * cell c (c h <= x < (c+1) h) touches the four nodes c-1 .. c+2 in each
 * direction: the weights below are those four values.  On a mesh with no
 * edge within two cells the functions sum to 1 and reproduce linear fields
 * exactly (sum_i N_i x_i = x), which the patch test relies on. */
#ifndef CD_MPM_SHAPE_H
#define CD_MPM_SHAPE_H
#include "defs.h"

/* Nodes a point touches in each direction. */
#define CD_MPM_STENCIL 4

CD_DEVICE_BEGIN

/* N(r) [1] for any r. */
CD_INLINE cd_real cd_mpm_bspline(cd_real r)
{
    cd_real a = fabs(r);
    if (a < CD_R(1)) return CD_R(0.5) * a * a * a - a * a + CD_R(2) / CD_R(3);
    if (a < CD_R(2)) {
        cd_real b = CD_R(2) - a;
        return b * b * b / CD_R(6);
    }
    return CD_R(0);
}

/* dN/dr [1] for any r. */
CD_INLINE cd_real cd_mpm_bspline_dr(cd_real r)
{
    cd_real a = fabs(r), s = r < CD_R(0) ? CD_R(-1) : CD_R(1);
    if (a < CD_R(1)) return s * (CD_R(1.5) * a * a - CD_R(2) * a);
    if (a < CD_R(2)) {
        cd_real b = CD_R(2) - a;
        return -s * CD_R(0.5) * b * b;
    }
    return CD_R(0);
}

/* The four weights w[k] = N(r_k) and gradients dw[k] = dN/dx [1/m] of the
 * nodes base .. base+3 for a point at grid coordinate g = (x - origin) / h
 * [1] (h the cell size [m]).  Returns base = floor(g) - 1, the first node. */
CD_INLINE cd_int cd_mpm_weights_1d(cd_real g, cd_real h, CD_GLOBAL cd_real *w, CD_GLOBAL cd_real *dw)
{
    cd_real c = floor(g);
    cd_int base = (cd_int)c - 1;
    for (cd_int k = 0; k < CD_MPM_STENCIL; k++) {
        cd_real r = g - (c - CD_R(1) + (cd_real)k); /* (x - x_node) / h */
        w[k] = cd_mpm_bspline(r);
        dw[k] = cd_mpm_bspline_dr(r) / h;
    }
    return base;
}

CD_DEVICE_END
#endif
