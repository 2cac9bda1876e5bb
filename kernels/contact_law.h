/* The contact laws (docs/references.md, Contact law; docs/contacts.md): the linear
 * spring-dashpot and Hertz-Mindlin, each with a Coulomb-capped tangential
 * spring.  One call updates one contact: its tangential history and the
 * force it exerts.  Used for particle-particle and particle-wall contacts
 * alike (a wall is body j with infinite mass and radius: m_eff = m_i,
 * R_eff = r_i). */
#ifndef CD_CONTACT_LAW_H
#define CD_CONTACT_LAW_H
#include "vec3.h"
#include "geom_types.h"

/* material.law, stored as the index of its choice (config_schema.c). */
enum { CD_LAW_LINEAR = 0, CD_LAW_HERTZ_MINDLIN = 1 };

/* Passed by value to the OpenCL kernels: the reals first, then the ints
 * padded to a multiple of 8 bytes, so C and OpenCL C lay it out alike. */
typedef struct {
    cd_real kn;         /* particle normal stiffness [N/m]; a contact has kn/2 (two springs in series) */
    cd_real kt;         /* particle tangential stiffness [N/m]; a contact has kt/2 */
    cd_real eta_n;      /* normal damping ratio [1] */
    cd_real eta_t;      /* tangential damping ratio [1] */
    cd_real mu;         /* Coulomb friction coefficient [1] */
    cd_real e_eff;      /* Hertz-Mindlin: contact modulus E* = E / (2 (1 - nu^2)) [Pa] */
    cd_real g_eff;      /* Hertz-Mindlin: contact shear modulus G* = E / (4 (2 - nu) (1 + nu)) [Pa] */
    cd_int limit_total; /* 0: limit mu F_n,elastic (Conzelmann et al.); 1: mu F_n (Tran et al. 2024, LAMMPS) */
    /* 1: F_n = max(0, ...) (docs/references.md, Contact law); 0: the damping may pull (textbook oscillator) */
    cd_int clip_normal;
    cd_int law;  /* CD_LAW_* */
    cd_int pad_; /* keeps the size a multiple of 8 bytes on every backend */
} cd_law_params;

typedef struct {
    cd_vec3 force_j; /* force on body j [N]; body i gets -force_j */
    cd_real fn;      /* normal force magnitude F_n >= 0 [N] */
    cd_vec3 ft;      /* tangential force on body j [N] */
    cd_int sliding;  /* 1 when the Coulomb cap was reached */
} cd_contact_force;

CD_DEVICE_BEGIN

/* The contact force on body j from its parts [N]: F_n n + F_t (body i
 * gets its opposite).  The contact law, the readers of older run files and
 * the analysis all build it here, so it has one set of bits. */
CD_INLINE cd_vec3 cd_contact_force_on_j(cd_real fn, cd_vec3 n, cd_vec3 ft) { return cd_v3_axpy(ft, fn, n); }

/* Its tangential part from the whole force [N]: F_j - F_n n, the law's F_t
 * up to one rounding of F_n n (src/io/pair_output.c). */
CD_INLINE cd_vec3 cd_contact_tangential(cd_vec3 force_j, cd_real fn, cd_vec3 n) { return cd_v3_axpy(force_j, -fn, n); }

/* Effective mass m_ij = m_i m_j / (m_i + m_j) [kg]. */
CD_INLINE cd_real cd_law_effective_mass(cd_real mi, cd_real mj) { return mi * mj / (mi + mj); }

/* Damping ratio from a coefficient of restitution: e = exp(-pi eta / sqrt(1 - eta^2)). */
CD_INLINE cd_real cd_law_eta_from_restitution(cd_real e)
{
    cd_real le = log(e);
    return -le / sqrt(CD_PI * CD_PI + le * le);
}

/* Collision time of the damped oscillator: pi / sqrt((kn/2)/m_ij (1 - eta^2)) [s]. */
CD_INLINE cd_real cd_law_collision_time(cd_real kn, cd_real m_eff, cd_real eta_n)
{
    return CD_PI / sqrt(CD_R(0.5) * kn / m_eff * (CD_R(1) - eta_n * eta_n));
}

/* Contact modulus E* [Pa] of two bodies of one material (Young's modulus
 * E [Pa], Poisson ratio nu [1]): 1/E* = 2 (1 - nu^2) / E (Hertz). */
CD_INLINE cd_real cd_law_contact_modulus(cd_real E, cd_real nu) { return E / (CD_R(2) * (CD_R(1) - nu * nu)); }

/* Contact shear modulus G* [Pa] of two bodies of one material, with the
 * shear modulus G = E / (2 (1 + nu)): 1/G* = 2 (2 - nu) / G (Mindlin). */
CD_INLINE cd_real cd_law_contact_shear_modulus(cd_real E, cd_real nu)
{
    return E / (CD_R(4) * (CD_R(2) - nu) * (CD_R(1) + nu));
}

/* Effective radius of curvature of a contact between primitives of radii
 * r_i, r_j [m]: R_eff = r_i r_j / (r_i + r_j), Hertz's value for two
 * spheres; arms use it too (docs/contacts.md, "Hertz-Mindlin").  A wall is
 * flat (R_eff = r_i) and has infinite mass. */
CD_INLINE cd_real cd_law_pair_radius(cd_real ri, cd_real rj) { return ri * rj / (ri + rj); }

/* Duration of an undamped Hertz collision at impact speed v [m/s] [s]:
 * t_c = 2.8682 (m_eff^2 / (R_eff E*^2 v))^(1/5).  The factor is
 * 2 (15/16)^(2/5) times the integral of 1/sqrt(1 - u^(5/2)) over [0, 1]
 * (= (2/5) B(2/5, 1/2) = 1.47163). */
CD_INLINE cd_real cd_law_hertz_collision_time(cd_real e_eff, cd_real r_eff, cd_real m_eff, cd_real v)
{
    return CD_R(2.86825) * pow(m_eff * m_eff / (r_eff * e_eff * e_eff * v), CD_R(0.2));
}

/* Stiffness and damping of one contact, from the law: what the update below
 * needs, so that both laws share the history and the Coulomb cap. */
typedef struct {
    cd_real kn_c;    /* normal force per overlap, F_n,elastic = kn_c delta_n [N/m] */
    cd_real kt_c;    /* tangential spring: F_t,elastic = -kt_c delta_t [N/m] */
    cd_real gamma_n; /* normal dashpot [N s/m] */
    cd_real gamma_t; /* tangential dashpot [N s/m] */
} cd_contact_coeffs;

/* sqrt(5/6): the factor of the Hertz-Mindlin dashpots (Tsuji et al. 1992;
 * the form of EDEM's Hertz-Mindlin): with the tangent stiffness S in place
 * of the linear law's contact stiffness, a damping ratio eta gives the
 * restitution of the linear law with that eta (to 1e-6, docs/contacts.md;
 * tests/physics/test_hertz_mindlin.c). */
#define CD_SQRT_5_6 CD_R(0.91287092917527685576)

CD_INLINE cd_contact_coeffs cd_contact_coefficients(cd_law_params p, cd_real m_eff, cd_real r_eff, cd_real overlap)
{
    cd_contact_coeffs k;
    if (p.law == CD_LAW_HERTZ_MINDLIN) {
        /* Hertz: F_n = (4/3) E* a delta_n with the contact radius
         * a = sqrt(R_eff delta_n); tangent stiffnesses S_n = 2 E* a and
         * Mindlin's S_t = 8 G* a (no micro-slip: the spring is linear in
         * delta_t at fixed a, as LAMMPS's tangential mindlin). */
        cd_real a = sqrt(r_eff * overlap);   /* [m] */
        cd_real s_n = CD_R(2) * p.e_eff * a; /* [N/m] */
        cd_real s_t = CD_R(8) * p.g_eff * a; /* [N/m] */
        k.kn_c = CD_R(2) / CD_R(3) * s_n;
        k.kt_c = s_t;
        k.gamma_n = CD_R(2) * CD_SQRT_5_6 * p.eta_n * sqrt(s_n * m_eff);
        k.gamma_t = CD_R(2) * CD_SQRT_5_6 * p.eta_t * sqrt(s_t * m_eff);
    } else {
        k.kn_c = CD_R(0.5) * p.kn;
        k.kt_c = CD_R(0.5) * p.kt;
        k.gamma_n = p.eta_n * sqrt(CD_R(2) * m_eff * p.kn);
        k.gamma_t = p.eta_t * sqrt(CD_R(2) * m_eff * p.kt);
    }
    return k;
}

/* Is sqrt(x2) <= limit (x2, limit >= 0 or NaN) clear without the square
 * root?  x2 < limit^2 (1 - 1e-15), with limit^2 and the product rounded
 * (each at most half an ulp up, 2.2e-16 together), means x2 < limit^2
 * exactly, so the rounded sqrt(x2) <= limit: the comparison sqrt(x2) >
 * limit would be false, and the same bits follow without it (one square
 * root of a contact's five saved wherever it does not slide).  limit above
 * 1e-150 keeps limit^2 clear of the subnormals, where the rounding is not
 * relative; NaN and the rest take the square root. */
CD_INLINE int cd_law_clearly_below(cd_real x2, cd_real limit)
{
    return limit > CD_R(1e-150) && x2 < limit * limit * CD_R(0.999999999999999);
}

/* One contact update.
 *   m_eff  : effective mass [kg]
 *   r_eff  : effective radius of curvature [m] (Hertz-Mindlin only)
 *   g      : geometry (normal from i to j, overlap > 0)
 *   vrel   : velocity of j relative to i at the contact point [m/s]
 *   dt     : time step [s]
 *   shear  : in/out tangential spring elongation delta_t [m] */
CD_INLINE cd_contact_force cd_contact_law(cd_law_params p, cd_real m_eff, cd_real r_eff, const cd_contact_geom *g,
                                          cd_vec3 vrel, cd_real dt, cd_vec3 *shear)
{
    cd_contact_force out;
    cd_vec3 n = g->normal;
    cd_contact_coeffs k = cd_contact_coefficients(p, m_eff, r_eff, g->overlap);

    /* v_n is the rate of separation: negative while approaching. */
    cd_real vn = cd_v3_dot(vrel, n);
    cd_vec3 vt = cd_v3_sub(vrel, cd_v3_scale(n, vn));
    cd_real fn = k.kn_c * g->overlap - k.gamma_n * vn;
    if (p.clip_normal && fn < CD_R(0)) fn = CD_R(0);

    /* Keep the spring in the current tangent plane, with its length. */
    cd_vec3 s = *shear;
    cd_real len0 = cd_v3_norm(s);
    s = cd_v3_sub(s, cd_v3_scale(n, cd_v3_dot(s, n)));
    cd_real len1 = cd_v3_norm(s);
    if (len1 > CD_R(0)) s = cd_v3_scale(s, len0 / len1);
    s = cd_v3_axpy(s, dt, vt);

    cd_vec3 ft = cd_v3_axpy(cd_v3_scale(s, -k.kt_c), -k.gamma_t, vt);
    cd_real limit = p.mu * (p.limit_total ? fn : k.kn_c * g->overlap);
    if (limit < CD_R(0)) limit = CD_R(0);
    out.sliding = 0;
    cd_real ftn2 = cd_v3_norm2(ft); /* |F_t|^2 [N^2] */
    int may_slide = !cd_law_clearly_below(ftn2, limit);
    cd_real ftn = may_slide ? sqrt(ftn2) : CD_R(0); /* |F_t| [N], where needed */
    if (may_slide && ftn > limit) {
        /* Sliding: cap the force and shorten the spring to match it, so that
         * no elastic energy is stored beyond the Coulomb limit. */
        ft = cd_v3_scale(ft, limit / ftn);
        s = k.kt_c > CD_R(0) ? cd_v3_scale(cd_v3_axpy(ft, k.gamma_t, vt), -CD_R(1) / k.kt_c) : cd_v3_zero();
        out.sliding = 1;
    }
    *shear = s;
    out.fn = fn;
    out.ft = ft;
    out.force_j = cd_contact_force_on_j(fn, n, ft);
    return out;
}

/* Elastic energy stored in one contact [J]: the work of the normal force,
 * kn_c delta^2 / 2 (linear) or (2/5) kn_c delta^2 (Hertz, F ~ delta^(3/2)),
 * and kt_c delta_t^2 / 2 of the tangential spring (for Mindlin at the
 * present contact radius: with a stiffness that changes with the overlap
 * this is the spring's energy now, not a potential). */
CD_INLINE cd_real cd_contact_elastic_energy(cd_law_params p, cd_real r_eff, cd_real overlap, cd_vec3 shear)
{
    if (p.law == CD_LAW_HERTZ_MINDLIN) {
        cd_contact_coeffs k = cd_contact_coefficients(p, CD_R(0), r_eff, overlap);
        return CD_R(0.4) * k.kn_c * overlap * overlap + CD_R(0.5) * k.kt_c * cd_v3_norm2(shear);
    }
    return CD_R(0.25) * p.kn * overlap * overlap + CD_R(0.25) * p.kt * cd_v3_norm2(shear);
}

CD_DEVICE_END
#endif
