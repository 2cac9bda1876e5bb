/* The simulation state as structure-of-arrays columns generated from
 * fields.def, plus the small scalar state (time, walls) that travels with it. */
#ifndef CD_STATE_H
#define CD_STATE_H
#include <stddef.h>
#include "defs.h"
#include "geom_types.h"

/* PAIR_OUT: output columns of the pair rows, derived on the host at sync
 * (fields.def); same rows and capacity as PAIR. */
enum cd_field_group {
    CD_GROUP_PARTICLE,
    CD_GROUP_PRIM,
    CD_GROUP_PAIR,
    CD_GROUP_WALLC,
    CD_GROUP_PAIR_OUT,
    CD_GROUP_COUNT
};

/* Do the columns of group g have one row per pair row (PAIR, PAIR_OUT)? */
static inline int cd_group_pair_rows(enum cd_field_group g) { return g == CD_GROUP_PAIR || g == CD_GROUP_PAIR_OUT; }
/* The scalar kind of a column (kernels/fields.def, h5type): REAL doubles,
 * INT int32, FLAG a byte in memory (cd_flag) and an int32 in the file. */
enum cd_field_kind { CD_KIND_REAL, CD_KIND_INT, CD_KIND_FLAG };

typedef struct cd_state {
    /* rows in use and rows allocated per group */
    size_t n_particles, n_prims, n_pairs, n_walls;
    size_t cap_pairs;
#define CD_FIELD(group, ctype, h5type, ncomp, name, unit, meaning) ctype *name;
#include "fields.def"
#undef CD_FIELD
    /* The primitives' arms as a device holds them (kernels/cols.h, cd_arm):
     * prim_arm per primitive (negative: a ball at its particle's centre,
     * -1 - the signs of its zero body ends, src/core/state.c), n_arms
     * rows of arm; derived from the host's PRIM_ARM columns at a start
     * (cd_state_arms_derive), not written to files. */
    size_t n_arms;
    cd_int *prim_arm;
    cd_arm *arm;
    /* The principal moments as the step holds them (kernels/cols.h,
     * cd_inertia_of), derived with the arms from the host's column
     * inertia: inertia_iso, one value a particle, where every particle is
     * isotropic (step_inertia null), else step_inertia, the three. */
    cd_vec3 *step_inertia;
    cd_real *inertia_iso;
    cd_wall walls[CD_MAX_WALLS]; /* current wall positions and motion */
    /* State of the protocol driving the run (phase, wall dynamics,
     * convergence checks): doubles saved with every snapshot, so that a
     * protocol resumes in the middle of any phase.  Meaning: src/protocols/protocol.c. */
#define CD_CONTROL_SLOTS 32
    double control[CD_CONTROL_SLOTS];
    double time;    /* simulated time [s] */
    long long step; /* steps taken since the start of the run */
} cd_state;

/* Description of one column, for generic allocation and I/O. */
typedef struct {
    enum cd_field_group group;
    enum cd_field_kind kind;
    int ncomp;        /* scalars per row */
    size_t elem_size; /* bytes per row */
    size_t offset;    /* offset of the column pointer inside cd_state */
    const char *name, *unit, *meaning;
    int on_device; /* 1: a column the step reads or writes (kernels/field_groups.h) */
} cd_field_info;

extern const cd_field_info cd_fields[];
extern const size_t cd_n_fields;

/* Pointer to the column pointer of field f inside s. */
void **cd_field_ptr(cd_state *s, const cd_field_info *f);
/* Rows of the group the field belongs to (n, not capacity). */
size_t cd_state_rows(const cd_state *s, enum cd_field_group g);

/* Allocates every column (zeroed); pairs get cap_pairs rows.  Returns 0 or -1. */
int cd_state_alloc(cd_state *s, size_t n_particles, size_t n_prims, size_t n_walls, size_t cap_pairs);
/* Grows the pair columns to at least cap rows, keeping the first n_pairs. */
int cd_state_reserve_pairs(cd_state *s, size_t cap);
void cd_state_free(cd_state *s);
/* Copies every column (the rows in use) and every scalar of src into dst:
 * dst either zeroed (its columns are then allocated with src's sizes) or
 * allocated for the same particles, primitives and walls (its pair columns
 * grow as needed).  Returns 0, or -1 (out of memory, or other sizes). */
int cd_state_copy(cd_state *dst, const cd_state *src);
/* The arms of s (n_arms, prim_arm, arm) anew from its host columns
 * prim_a_body, prim_b_body, prim_b, prim_b_ref: a primitive has an arm
 * unless both its body-frame ends are the body origin (cd_ends_at_origin),
 * in primitive order; and the step's inertia (step_inertia or
 * inertia_iso) from the column inertia, in particle order.  Returns 0, or
 * -1 (out of memory). */
int cd_state_arms_derive(cd_state *s);
/* Has every primitive of s an arm, its own row (prim_arm the identity)?
 * Then a device neither holds nor reads prim_arm (kernels/cols.h). */
static inline int cd_state_arms_all(const cd_state *s) { return s->n_arms == s->n_prims; }
/* The reverse, at sync: the host's PRIM_ARM columns (body ends, prim_b,
 * prim_b_ref) of every primitive i from its arm prim_arm[i] in arm (where
 * the step keeps them), or for a primitive without one, its zero body ends
 * (with the signs they had: prim_arm[i] = -1 - signs) and its prim_a and prim_a_ref: every row is written, so that the rows follow
 * the primitives' order where the step moved them (src/backend/omp/reorder.c). */
void cd_state_arms_expand(cd_state *s, const cd_int *prim_arm, const cd_arm *arm);
/* The host's wall-contact rows (fields.def, WALLC and WALLC_OUT) from the
 * entries the step keeps per wall candidate: ent[e] for the candidate row
 * rows[e] (e < n) while it is in contact (active), 0 elsewhere. */
void cd_state_expand_wall_entries(cd_state *s, const cd_int *rows, const cd_wall_entry *ent, size_t n);
/* Host row r of the wall contacts as a candidate entry. */
cd_wall_entry cd_state_wall_entry(const cd_state *s, size_t r);
/* The reverse of the expansion, at a start: the rows in contact (wallc_active) as candidate
 * entries, ascending by row, into rows[] and ent[] (either may be null);
 * returns how many. */
size_t cd_state_wall_entries(const cd_state *s, cd_int *rows, cd_wall_entry *ent);

/* Index of global id g among the ascending ids[0..n) (a rank's global
 * particle or primitive ids: its part of the run, in global order), or
 * -1 when it is not there.  Binary search. */
static inline long long cd_sorted_index(const long long *ids, size_t n, long long g)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (ids[mid] < g) lo = mid + 1;
        else hi = mid;
    }
    return lo < n && ids[lo] == g ? (long long)lo : -1;
}

#endif
