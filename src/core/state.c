#include "core/state.h"
#include "field_groups.h"
#include "cols.h"
#include "rigid.h"
#include "vec3.h"
#include <stdlib.h>
#include <string.h>
#include <math.h>

#define CD_GROUP_OF_PARTICLE CD_GROUP_PARTICLE
#define CD_GROUP_OF_PRIM     CD_GROUP_PRIM
#define CD_GROUP_OF_PAIR     CD_GROUP_PAIR
/* PARTICLE_OUT, PARTICLE_HOST: rows of PARTICLE on the host; no device
 * holds them as columns of the table (the force and torque: kernels/cols.h). */
#define CD_GROUP_OF_PARTICLE_OUT  CD_GROUP_PARTICLE
#define CD_GROUP_OF_PARTICLE_HOST CD_GROUP_PARTICLE
/* PRIM_ARM: rows of PRIM on the host; a device holds them per arm (cd_arm,
 * cd_state_arms_derive below). */
#define CD_GROUP_OF_PRIM_ARM CD_GROUP_PRIM
#define CD_GROUP_OF_WALLC    CD_GROUP_WALLC
#define CD_GROUP_OF_PAIR_OUT CD_GROUP_PAIR_OUT
/* WALLC_OUT: the rows of WALLC on the host (I/O, reorder, copies); only
 * the devices leave it out (on_device below, kernels/field_groups.h). */
#define CD_GROUP_OF_WALLC_OUT CD_GROUP_WALLC
#define CD_KIND_OF_REAL       CD_KIND_REAL
#define CD_KIND_OF_INT        CD_KIND_INT
#define CD_KIND_OF_FLAG       CD_KIND_FLAG

const cd_field_info cd_fields[] = {
#define CD_FIELD(group, ctype, h5type, ncomp, name, unit, meaning)                                                     \
    {CD_GROUP_OF_##group,                                                                                              \
     CD_KIND_OF_##h5type,                                                                                              \
     ncomp,                                                                                                            \
     sizeof(ctype),                                                                                                    \
     offsetof(cd_state, name),                                                                                         \
     #name,                                                                                                            \
     unit,                                                                                                             \
     meaning,                                                                                                          \
     CD_ON_DEVICE_##group(1) + 0},
#include "fields.def"
#undef CD_FIELD
};
const size_t cd_n_fields = sizeof(cd_fields) / sizeof(cd_fields[0]);

void **cd_field_ptr(cd_state *s, const cd_field_info *f) { return (void **)((char *)s + f->offset); }

size_t cd_state_rows(const cd_state *s, enum cd_field_group g)
{
    switch (g) {
    case CD_GROUP_PARTICLE:
        return s->n_particles;
    case CD_GROUP_PRIM:
        return s->n_prims;
    case CD_GROUP_PAIR:
    case CD_GROUP_PAIR_OUT:
        return s->n_pairs;
    case CD_GROUP_WALLC:
        return s->n_prims * s->n_walls;
    default:
        return 0;
    }
}

static size_t group_capacity(const cd_state *s, enum cd_field_group g)
{
    return cd_group_pair_rows(g) ? s->cap_pairs : cd_state_rows(s, g);
}

int cd_state_alloc(cd_state *s, size_t n_particles, size_t n_prims, size_t n_walls, size_t cap_pairs)
{
    memset(s, 0, sizeof(*s));
    s->n_particles = n_particles;
    s->n_prims = n_prims;
    s->n_walls = n_walls;
    s->cap_pairs = cap_pairs > 0 ? cap_pairs : 1;
    for (size_t k = 0; k < cd_n_fields; k++) {
        size_t rows = group_capacity(s, cd_fields[k].group);
        void *p = calloc(rows > 0 ? rows : 1, cd_fields[k].elem_size);
        if (!p) {
            cd_state_free(s);
            return -1;
        }
        *cd_field_ptr(s, &cd_fields[k]) = p;
    }
    return 0;
}

int cd_state_reserve_pairs(cd_state *s, size_t cap)
{
    if (cap <= s->cap_pairs) return 0;
    for (size_t k = 0; k < cd_n_fields; k++) {
        if (!cd_group_pair_rows(cd_fields[k].group)) continue;
        void **slot = cd_field_ptr(s, &cd_fields[k]);
        void *p = realloc(*slot, cap * cd_fields[k].elem_size);
        if (!p) return -1;
        memset((char *)p + s->cap_pairs * cd_fields[k].elem_size, 0, (cap - s->cap_pairs) * cd_fields[k].elem_size);
        *slot = p;
    }
    s->cap_pairs = cap;
    return 0;
}

void cd_state_free(cd_state *s)
{
    for (size_t k = 0; k < cd_n_fields; k++) {
        void **slot = cd_field_ptr(s, &cd_fields[k]);
        free(*slot);
        *slot = NULL;
    }
    free(s->prim_arm);
    free(s->arm);
    free(s->step_inertia);
    free(s->inertia_iso);
    s->prim_arm = NULL;
    s->arm = NULL;
    s->step_inertia = NULL;
    s->inertia_iso = NULL;
    s->n_arms = 0;
}

/* dst's step inertia as src's (dst's own arrays, step_inertia and
 * inertia_iso, are the ones given: reused or freed). */
static int copy_inertia(cd_state *dst, const cd_state *src, cd_vec3 *full, cd_real *iso)
{
    size_t n = src->n_particles + 1;
    dst->step_inertia = src->step_inertia ? realloc(full, n * sizeof *full) : (free(full), NULL);
    if (src->step_inertia && !dst->step_inertia) {
        dst->inertia_iso = iso;
        return -1;
    }
    dst->inertia_iso = src->inertia_iso ? realloc(iso, n * sizeof *iso) : (free(iso), NULL);
    if (src->inertia_iso && !dst->inertia_iso) return -1;
    if (src->step_inertia) memcpy(dst->step_inertia, src->step_inertia, src->n_particles * sizeof *full);
    if (src->inertia_iso) memcpy(dst->inertia_iso, src->inertia_iso, src->n_particles * sizeof *iso);
    return 0;
}

/* dst's arms the size of src's, holding src's (dst's own arrays). */
static int copy_arms(cd_state *dst, const cd_state *src, cd_int *prim_arm, cd_arm *arm)
{
    dst->prim_arm = prim_arm;
    dst->arm = arm;
    if (!src->prim_arm) { /* src has none yet (derived at a start) */
        free(prim_arm);
        free(arm);
        dst->prim_arm = NULL;
        dst->arm = NULL;
        dst->n_arms = 0;
        return 0;
    }
    cd_int *pa = realloc(prim_arm, (src->n_prims + 1) * sizeof *pa);
    if (pa) dst->prim_arm = pa;
    cd_arm *ar = pa ? realloc(arm, (src->n_arms + 1) * sizeof *ar) : NULL;
    if (ar) dst->arm = ar;
    if (!pa || !ar) return -1;
    memcpy(pa, src->prim_arm, src->n_prims * sizeof *pa);
    memcpy(ar, src->arm, src->n_arms * sizeof *ar);
    return 0;
}

int cd_state_copy(cd_state *dst, const cd_state *src)
{
    if (!dst->position) { /* empty: allocate with src's sizes */
        if (cd_state_alloc(dst, src->n_particles, src->n_prims, src->n_walls, src->cap_pairs)) return -1;
    }
    if (dst->n_particles != src->n_particles || dst->n_prims != src->n_prims || dst->n_walls != src->n_walls) return -1;
    if (cd_state_reserve_pairs(dst, src->n_pairs)) return -1;
    cd_state keep = *dst;
    *dst = *src; /* counts, walls, control, time, step */
    dst->cap_pairs = keep.cap_pairs;
    for (size_t k = 0; k < cd_n_fields; k++) {
        void **slot = cd_field_ptr(dst, &cd_fields[k]);
        *slot = *cd_field_ptr(&keep, &cd_fields[k]);
        memcpy(*slot, *cd_field_ptr((cd_state *)src, &cd_fields[k]),
               cd_state_rows(src, cd_fields[k].group) * cd_fields[k].elem_size);
    }
    int rc = copy_arms(dst, src, keep.prim_arm, keep.arm);
    return copy_inertia(dst, src, keep.step_inertia, keep.inertia_iso) || rc ? -1 : 0;
}

/* A ball's body ends are zeros of either sign (a sphere's a = -0 in the
 * shape catalogue): their six signs, bit k for component k of a then b,
 * kept in its negative arm index -1 - signs, so that the host's columns
 * come back with the bits they had (the run file stores them). */
static cd_int zero_signs(cd_vec3 a, cd_vec3 b)
{
    const double v[6] = {a.x, a.y, a.z, b.x, b.y, b.z};
    cd_int bits = 0;
    for (int k = 0; k < 6; k++) bits |= (cd_int)(signbit(v[k]) != 0) << k;
    return bits;
}

static cd_vec3 signed_zeros(cd_int bits)
{
    return cd_v3(bits & 1 ? -0.0 : 0.0, bits & 2 ? -0.0 : 0.0, bits & 4 ? -0.0 : 0.0);
}

/* The step's inertia of s from its column inertia (cd_state_arms_derive):
 * one value a particle where all three of every particle's are equal (==:
 * an isotropic body, the test the integrator makes, kernels/rigid.h),
 * else the three. */
static int inertia_derive(cd_state *s)
{
    size_t N = s->n_particles;
    int iso = 1;
    for (size_t q = 0; q < N && iso; q++) iso = cd_rigid_isotropic(s->inertia[q]);
    /* realloc, as for the arms: a state derived again with the same
     * particles keeps its arrays (and an offload mapping of them) */
    if (iso) {
        free(s->step_inertia);
        s->step_inertia = NULL;
        cd_real *one = realloc(s->inertia_iso, (N + 1) * sizeof *one);
        if (!one) return -1;
        s->inertia_iso = one;
        for (size_t q = 0; q < N; q++) one[q] = s->inertia[q].x;
        return 0;
    }
    free(s->inertia_iso);
    s->inertia_iso = NULL;
    cd_vec3 *three = realloc(s->step_inertia, (N + 1) * sizeof *three);
    if (!three) return -1;
    s->step_inertia = three;
    memcpy(three, s->inertia, N * sizeof *three);
    return 0;
}

int cd_state_arms_derive(cd_state *s)
{
    if (inertia_derive(s)) return -1;
    size_t P = s->n_prims, n = 0;
    cd_int *pa = realloc(s->prim_arm, (P + 1) * sizeof *pa);
    if (pa) s->prim_arm = pa;
    for (size_t i = 0; pa && i < P; i++) n += !cd_ends_at_origin(s->prim_a_body[i], s->prim_b_body[i]);
    cd_arm *arm = pa ? realloc(s->arm, (n + 1) * sizeof *arm) : NULL;
    if (arm) s->arm = arm;
    if (!pa || !arm) return -1;
    s->n_arms = n;
    n = 0;
    for (size_t i = 0; i < P; i++) {
        if (cd_ends_at_origin(s->prim_a_body[i], s->prim_b_body[i])) {
            pa[i] = -1 - zero_signs(s->prim_a_body[i], s->prim_b_body[i]);
            continue;
        }
        pa[i] = (cd_int)n;
        arm[n++] = (cd_arm){s->prim_a_body[i], s->prim_b_body[i], s->prim_b[i], s->prim_b_ref[i]};
    }
    return 0;
}

void cd_state_arms_expand(cd_state *s, const cd_int *prim_arm, const cd_arm *arm)
{
    for (size_t i = 0; i < s->n_prims; i++) {
        cd_int r = prim_arm[i];
        if (r < 0) { /* a ball at the centre: both ends at the origin of the body */
            s->prim_a_body[i] = signed_zeros(-1 - r);
            s->prim_b_body[i] = signed_zeros((-1 - r) >> 3);
            s->prim_b[i] = s->prim_a[i];
            s->prim_b_ref[i] = s->prim_a_ref[i];
            continue;
        }
        s->prim_a_body[i] = arm[r].a_body;
        s->prim_b_body[i] = arm[r].b_body;
        s->prim_b[i] = arm[r].b;
        s->prim_b_ref[i] = arm[r].b_ref;
    }
}

void cd_state_expand_wall_entries(cd_state *s, const cd_int *rows, const cd_wall_entry *ent, size_t n)
{
    size_t R = s->n_prims * s->n_walls;
    memset(s->wallc_active, 0, R * sizeof *s->wallc_active);
    memset(s->wallc_shear, 0, R * sizeof *s->wallc_shear);
    memset(s->wallc_force, 0, R * sizeof *s->wallc_force);
    memset(s->wallc_torque, 0, R * sizeof *s->wallc_torque);
    memset(s->wallc_overlap, 0, R * sizeof *s->wallc_overlap);
    memset(s->wallc_fn, 0, R * sizeof *s->wallc_fn);
    for (size_t e = 0; e < n; e++) {
        size_t r = (size_t)rows[e];
        if (!ent[e].active) continue;
        s->wallc_active[r] = ent[e].active;
        s->wallc_shear[r] = ent[e].shear;
        s->wallc_force[r] = ent[e].force;
        s->wallc_torque[r] = ent[e].torque;
        s->wallc_overlap[r] = ent[e].overlap;
        s->wallc_fn[r] = ent[e].fn;
    }
}

cd_wall_entry cd_state_wall_entry(const cd_state *s, size_t r)
{
    return (cd_wall_entry){s->wallc_force[r],
                           s->wallc_torque[r],
                           s->wallc_overlap[r],
                           s->wallc_fn[r],
                           s->wallc_shear[r],
                           s->wallc_active[r],
                           0};
}

size_t cd_state_wall_entries(const cd_state *s, cd_int *rows, cd_wall_entry *ent)
{
    size_t n = 0, R = s->n_prims * s->n_walls;
    for (size_t r = 0; r < R; r++) {
        if (!s->wallc_active[r]) continue;
        if (rows) rows[n] = (cd_int)r;
        if (ent) ent[n] = cd_state_wall_entry(s, r);
        n++;
    }
    return n;
}
