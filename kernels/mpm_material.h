/* Material point method: the material of one point, 2D plane strain
 * (docs/mpm.md).  Linear isotropic elasticity (E, nu) and rate-independent
 * von Mises plasticity with linear isotropic hardening (sigma_y, H), the
 * paper's "bilinear isotropic hardening", integrated by a radial return;
 * small-strain increments as the paper (its section 2: "in the context of
 * the infinitesimal strain theory").  Plane strain keeps eps_zz = 0, so
 * sigma_zz is a state variable of its own.  Device-safe: C11 and OpenCL C.
 *
 * Stress sign: tension positive [Pa].  Strain increments are tensor
 * components (de_xy is half the engineering shear). */
#ifndef CD_MPM_MATERIAL_H
#define CD_MPM_MATERIAL_H
#include "defs.h"

typedef struct {
    cd_real lambda;    /* Lame's first parameter E nu / ((1 + nu)(1 - 2 nu)) [Pa] */
    cd_real shear;     /* G = E / (2 (1 + nu)) [Pa] */
    cd_real yield;     /* initial yield stress sigma_y [Pa]; < 0: elastic only */
    cd_real hardening; /* plastic modulus H = d sigma_y / d eps_p [Pa] (docs/mpm.md: uniaxial tangent E H / (E + H)) */
} cd_mpm_material;

/* Cauchy stress of a plane-strain point [Pa]. */
typedef struct {
    cd_real xx, yy, xy, zz;
} cd_mpm_stress;

CD_DEVICE_BEGIN

/* Material from the engineering constants: E [Pa], nu [1], sigma_y [Pa]
 * (< 0: elastic), H [Pa]. */
CD_INLINE cd_mpm_material cd_mpm_material_make(cd_real young, cd_real poisson, cd_real yield, cd_real hardening)
{
    cd_mpm_material m;
    m.lambda = young * poisson / ((CD_R(1) + poisson) * (CD_R(1) - CD_R(2) * poisson));
    m.shear = young / (CD_R(2) * (CD_R(1) + poisson));
    m.yield = yield;
    m.hardening = hardening;
    return m;
}

/* Elastic energy per volume sigma : C^-1 : sigma / 2 [J/m^3] of a stress
 * (sigma_zz included): s:s / (4 G) - lambda tr^2 / (4 G (3 lambda + 2 G)). */
CD_INLINE cd_real cd_mpm_elastic_energy_density(cd_mpm_material m, cd_mpm_stress s)
{
    cd_real ss = s.xx * s.xx + s.yy * s.yy + s.zz * s.zz + CD_R(2) * s.xy * s.xy; /* [Pa^2] */
    cd_real tr = s.xx + s.yy + s.zz;                                              /* [Pa] */
    return ss / (CD_R(4) * m.shear) -
           m.lambda * tr * tr / (CD_R(4) * m.shear * (CD_R(3) * m.lambda + CD_R(2) * m.shear));
}

/* P-wave modulus lambda + 2 G [Pa]: the explicit step's wave speed is sqrt(it / rho). */
CD_INLINE cd_real cd_mpm_pwave_modulus(cd_mpm_material m) { return m.lambda + CD_R(2) * m.shear; }

/* Von Mises equivalent stress q = sqrt(3/2 s:s) [Pa] of a plane-strain stress. */
CD_INLINE cd_real cd_mpm_von_mises(cd_mpm_stress s)
{
    cd_real p = (s.xx + s.yy + s.zz) / CD_R(3);
    cd_real dx = s.xx - p, dy = s.yy - p, dz = s.zz - p;
    return sqrt(CD_R(1.5) * (dx * dx + dy * dy + dz * dz + CD_R(2) * s.xy * s.xy));
}

/* One strain increment (de_xx, de_yy, de_xy [1], de_zz = 0) applied to the
 * stress *s [Pa] and the equivalent plastic strain *eps_p [1]: the elastic
 * trial stress, then, when it lies outside the yield surface
 * q = sigma_y + H eps_p, the radial return onto it.  Linear hardening makes
 * the plastic multiplier closed-form: d_gamma = f / (3 G + H), where f is
 * the trial's excess of q over the current yield stress.  Returns 1 when
 * the step was plastic. */
CD_INLINE cd_int cd_mpm_stress_update(cd_mpm_material m, cd_mpm_stress *s, cd_real *eps_p, cd_real de_xx, cd_real de_yy,
                                      cd_real de_xy)
{
    cd_real tr = de_xx + de_yy; /* volumetric increment (de_zz = 0) [1] */
    cd_mpm_stress t;
    t.xx = s->xx + m.lambda * tr + CD_R(2) * m.shear * de_xx;
    t.yy = s->yy + m.lambda * tr + CD_R(2) * m.shear * de_yy;
    t.zz = s->zz + m.lambda * tr;
    t.xy = s->xy + CD_R(2) * m.shear * de_xy;
    if (m.yield < CD_R(0)) {
        *s = t;
        return 0;
    }
    cd_real q = cd_mpm_von_mises(t);
    cd_real f = q - (m.yield + m.hardening * *eps_p); /* yield function of the trial [Pa] */
    if (f <= CD_R(0)) {
        *s = t;
        return 0;
    }
    cd_real d_gamma = f / (CD_R(3) * m.shear + m.hardening);   /* plastic strain increment [1] */
    cd_real scale = CD_R(1) - CD_R(3) * m.shear * d_gamma / q; /* deviator shrink factor [1] */
    cd_real p = (t.xx + t.yy + t.zz) / CD_R(3);
    s->xx = p + scale * (t.xx - p);
    s->yy = p + scale * (t.yy - p);
    s->zz = p + scale * (t.zz - p);
    s->xy = scale * t.xy;
    *eps_p += d_gamma;
    return 1;
}

/* Volume ratio det(I + grad du) [1] of one step for the displacement
 * gradient du_a/dx_b = g[a][b] (row-major g_xx, g_xy, g_yx, g_yy): the
 * paper's eq. (4), V(t + dt) = det(I + grad du) V(t), in 2D. */
CD_INLINE cd_real cd_mpm_volume_ratio(cd_real g_xx, cd_real g_xy, cd_real g_yx, cd_real g_yy)
{
    return (CD_R(1) + g_xx) * (CD_R(1) + g_yy) - g_xy * g_yx;
}

CD_DEVICE_END
#endif
