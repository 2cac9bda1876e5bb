/* Linear spring-dashpot contact with a Coulomb-capped tangential spring
 * (SPEC section 3).  One call updates one contact: its tangential history
 * and the force it exerts.  Used for particle-particle and particle-wall
 * contacts alike (a wall is body j with infinite mass: m_eff = m_i). */
#ifndef CD_CONTACT_LAW_H
#define CD_CONTACT_LAW_H
#include "vec3.h"
#include "geom_types.h"

typedef struct {
    cd_real kn;          /* particle normal stiffness [N/m]; a contact has kn/2 (two springs in series) */
    cd_real kt;          /* particle tangential stiffness [N/m]; a contact has kt/2 */
    cd_real eta_n;       /* normal damping ratio [1] */
    cd_real eta_t;       /* tangential damping ratio [1] */
    cd_real mu;          /* Coulomb friction coefficient [1] */
    cd_int limit_total;  /* 0: limit mu (kn/2) delta_n (seed 000); 1: mu F_n (seed 001, LAMMPS) */
    cd_int clip_normal;  /* 1: F_n = max(0, ...) as SPEC 3; 0: allow the damping to pull (textbook oscillator) */
} cd_law_params;

typedef struct {
    cd_vec3 force_j;     /* force on body j [N]; body i gets -force_j */
    cd_real fn;          /* normal force magnitude F_n >= 0 [N] */
    cd_vec3 ft;          /* tangential force on body j [N] */
    cd_int sliding;      /* 1 when the Coulomb cap was reached */
} cd_contact_force;

CD_DEVICE_BEGIN

/* The contact force on body j from its parts [N]: F_n n + F_t (body i
 * gets its opposite).  The contact law, the readers of older run files and
 * the analysis all build it here, so it has one set of bits. */
CD_INLINE cd_vec3 cd_contact_force_on_j(cd_real fn, cd_vec3 n, cd_vec3 ft) { return cd_v3_axpy(ft, fn, n); }

/* Its tangential part from the whole force [N]: F_j - F_n n, the law's F_t
 * up to one rounding of F_n n (src/pair_output.c). */
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

/* One contact update.
 *   g      : geometry (normal from i to j, overlap > 0)
 *   m_eff  : effective mass [kg]
 *   vrel   : velocity of j relative to i at the contact point [m/s]
 *   dt     : time step [s]
 *   shear  : in/out tangential spring elongation delta_t [m] */
CD_INLINE cd_contact_force cd_contact_law(cd_law_params p, cd_real m_eff, const cd_contact_geom *g,
                                          cd_vec3 vrel, cd_real dt, cd_vec3 *shear)
{
    cd_contact_force out;
    cd_vec3 n = g->normal;
    cd_real kn_c = CD_R(0.5) * p.kn;                /* contact normal stiffness [N/m] */
    cd_real kt_c = CD_R(0.5) * p.kt;                /* contact tangential stiffness [N/m] */
    cd_real gamma_n = p.eta_n * sqrt(CD_R(2) * m_eff * p.kn); /* [N s/m] */
    cd_real gamma_t = p.eta_t * sqrt(CD_R(2) * m_eff * p.kt); /* [N s/m] */

    /* v_n is the rate of separation: negative while approaching. */
    cd_real vn = cd_v3_dot(vrel, n);
    cd_vec3 vt = cd_v3_axpy(vrel, -vn, n);
    cd_real fn = kn_c * g->overlap - gamma_n * vn;
    if (p.clip_normal && fn < CD_R(0)) fn = CD_R(0);

    /* Keep the spring in the current tangent plane, with its length. */
    cd_vec3 s = *shear;
    cd_real len0 = cd_v3_norm(s);
    s = cd_v3_axpy(s, -cd_v3_dot(s, n), n);
    cd_real len1 = cd_v3_norm(s);
    if (len1 > CD_R(0)) s = cd_v3_scale(s, len0 / len1);
    s = cd_v3_axpy(s, dt, vt);

    cd_vec3 ft = cd_v3_axpy(cd_v3_scale(s, -kt_c), -gamma_t, vt);
    cd_real limit = p.mu * (p.limit_total ? fn : kn_c * g->overlap);
    if (limit < CD_R(0)) limit = CD_R(0);
    cd_real ftn = cd_v3_norm(ft);
    out.sliding = 0;
    if (ftn > limit) {
        /* Sliding: cap the force and shorten the spring to match it, so that
         * no elastic energy is stored beyond the Coulomb limit. */
        ft = cd_v3_scale(ft, limit / ftn);
        s = kt_c > CD_R(0) ? cd_v3_scale(cd_v3_axpy(ft, gamma_t, vt), -CD_R(1) / kt_c) : cd_v3_zero();
        out.sliding = 1;
    }
    *shear = s;
    out.fn = fn;
    out.ft = ft;
    out.force_j = cd_contact_force_on_j(fn, n, ft);
    return out;
}

/* Elastic energy stored in one contact [J]. */
CD_INLINE cd_real cd_contact_elastic_energy(cd_law_params p, cd_real overlap, cd_vec3 shear)
{
    return CD_R(0.25) * p.kn * overlap * overlap + CD_R(0.25) * p.kt * cd_v3_norm2(shear);
}

CD_DEVICE_END
#endif
