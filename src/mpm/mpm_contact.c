/* Frictionless contact between the bodies of the material point method
 * through their common background mesh (docs/mpm.md, "Contact"): the
 * multi-mesh algorithm of Bardenhagen et al. (the paper's refs. [9-11]).
 * Each body has its own node values (src/mpm/mpm.c); where two bodies share a
 * common node and, on the lines along their normal through the node and
 * through the mesh within a cell of it along the tangent, their material
 * comes within contact_gap of each other (kernels/mpm_contact.h), the
 * normal component of their relative velocity is removed when they
 * approach, as a perfectly inelastic collision of the two node masses
 * along the contact normal: momentum is conserved pair by pair, so exactly
 * for any number of bodies.
 *
 * Deterministic: the common nodes' body lists come from counts in a fixed
 * order (six parallel loops, the same lists as a stable counting sort),
 * each listed node is handled by one thread and writes only its own
 * body-nodes, and the pairs are counted after a sort (cd_mpm_contact_count,
 * only where a reader needs the count: not every step).  Nothing is read
 * back: the loops over listed nodes run over a bound and skip those past
 * the count, which stays where the loops run (kernels/mpm_checks.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "mpm/mpm.h"
#include "backend/omp/omp_loops.h" /* CD_STEP_FOR */
#include "mpm_checks.h"


/* The steps of kernels/mpm_step_items.h's cd_mpm_item_cn_* (stage 2). */
void cd_mpm_contact_nodes(cd_mpm *m)
{
    const cd_mpm_cols *args = m->loop_args; /* the columns, where the loops run */
    cd_int j = m->pending, *flags = m->loop_flags, *row_n = m->loop_row_n, *rows = m->loop_rows, ny = m->ny;
    cd_ulong *counts = m->loop_counts, *blocks = m->loop_blocks, nn = (cd_ulong)m->nx * (cd_ulong)m->ny,
             nblk = (nn + CD_MPM_CN_BLOCK - 1) / CD_MPM_CN_BLOCK;
    CD_WIDE_MIN
    CD_STEP_FOR(ny, firstprivate(j) CD_DEV(is_device_ptr(args, flags, row_n, rows)))
    for (cd_int row = 0; row < ny; row++)
        if (!cd_mpm_stopped(flags, j, 2)) cd_mpm_item_cn_rows(*args, row, row_n, rows);
    CD_STEP_FOR(nn, firstprivate(j) CD_DEV(is_device_ptr(args, flags, row_n, rows)))
    for (cd_ulong g = 0; g < nn; g++)
        if (!cd_mpm_stopped(flags, j, 2)) cd_mpm_item_cn_count(*args, g, row_n, rows);
    CD_STEP_FOR(nblk, firstprivate(j) CD_DEV(is_device_ptr(args, flags, blocks)))
    for (cd_ulong b = 0; b < nblk; b++)
        if (!cd_mpm_stopped(flags, j, 2)) cd_mpm_item_cn_block_sums(*args, b, blocks);
    CD_STEP_FOR(1, firstprivate(nblk, j) CD_DEV(is_device_ptr(flags, blocks, counts)))
    for (int one = 0; one < 1; one++)
        if (!cd_mpm_stopped(flags, j, 2)) cd_mpm_item_cn_block_scan(nblk, blocks, counts + CD_MPM_COUNT_LISTED);
    CD_STEP_FOR(nblk, firstprivate(j) CD_DEV(is_device_ptr(args, flags, blocks)))
    for (cd_ulong b = 0; b < nblk; b++)
        if (!cd_mpm_stopped(flags, j, 2)) cd_mpm_item_cn_block_starts(*args, b, blocks);
    CD_STEP_FOR(nn, firstprivate(j) CD_DEV(is_device_ptr(args, flags, row_n, rows)))
    for (cd_ulong g = 0; g < nn; g++)
        if (!cd_mpm_stopped(flags, j, 2)) cd_mpm_item_cn_entries(*args, g, row_n, rows);
}

static int cmp_key(const void *a, const void *b)
{
    long long x = *(const long long *)a, y = *(const long long *)b;
    return (x > y) - (x < y);
}

int cd_mpm_pair_keys_room(cd_mpm *m, size_t n, char *err, size_t errlen)
{
    if (n <= m->cap_pairs) return 0;
    long long *q = realloc(m->pair_keys, (n + 64) * sizeof(long long));
    if (!q) {
        snprintf(err, errlen, "out of memory for %zu contact pairs", n);
        return -1;
    }
    m->pair_keys = q;
    m->cap_pairs = n + 64;
    return 0;
}

/* The pair keys of the last step's contact bits into m->pair_keys, their
 * number into *w, where the omp loops run. */
static int loop_pair_keys(cd_mpm *m, size_t *w, char *err, size_t errlen)
{
    const cd_mpm_cols *args = m->loop_args; /* the columns, where the loops run */
    cd_ulong *count = m->loop_counts + CD_MPM_COUNT_KEYS, n_cn = m->n_cn, n;
    cd_long *none = NULL;
    CD_WIDE_MIN
    CD_STEP_FOR(1, firstprivate(n_cn, none) CD_DEV(is_device_ptr(args, count)))
    for (int one = 0; one < 1; one++) cd_mpm_item_pair_keys(*args, n_cn, none, count);
    cd_dev_get(&n, count, sizeof n);
    if (cd_mpm_pair_keys_room(m, n, err, errlen)) return -1;
    if (cd_mpm_device_keys(m, n)) {
        snprintf(err, errlen, "out of device memory for %zu contact pairs", (size_t)n);
        return -1;
    }
    cd_long *keys = m->loop_keys;
    CD_STEP_FOR(1, firstprivate(n_cn) CD_DEV(is_device_ptr(args, keys, count)))
    for (int one = 0; one < 1; one++) cd_mpm_item_pair_keys(*args, n_cn, keys, count);
    cd_dev_get(m->pair_keys, keys, n * sizeof(cd_long));
    *w = (size_t)n;
    return 0;
}

/* Body pairs in contact (exchanging force), each counted once, from the
 * contact bits of the last step (mpm.h). */
int cd_mpm_contact_count(cd_mpm *m, char *err, size_t errlen)
{
    if (!m->loop_on || m->n_bodies < 2) return 0; /* no step yet, or no contact: the count stays as it is */
    size_t w;
    if (m->cl ? cd_mpm_cl_pair_keys(m, &w, err, errlen) : loop_pair_keys(m, &w, err, errlen)) return -1;
    if (w) qsort(m->pair_keys, w, sizeof(long long), cmp_key); /* (no keys: pair_keys may be NULL) */
    long distinct = 0;
    for (size_t i = 0; i < w; i++) distinct += i == 0 || m->pair_keys[i] != m->pair_keys[i - 1];
    m->n_contacts = distinct;
    return 0;
}

int cd_mpm_fail_crowded(cd_mpm *m, size_t g, char *err, size_t errlen)
{
    cd_mpm_device_sync(m); /* the common node's body count, for the message */
    snprintf(err, errlen,
             "common node (%zu, %zu) at step %lld: %zu bodies meet there, more than the %d the contact "
             "handles: refine the mesh (mpm.cells_per_diameter)",
             g % (size_t)m->nx, g / (size_t)m->nx, m->step + 1, (size_t)(m->cn_start[g + 1] - m->cn_start[g]),
             CD_MPM_NODE_BODIES);
    return -1;
}

void cd_mpm_contact_correct(cd_mpm *m)
{
    const cd_mpm_cols *args = m->loop_args; /* the columns, where the loops run */
    size_t rows = cd_mpm_loop_rows(m), nn = (size_t)m->nx * (size_t)m->ny;
    cd_ulong listed = rows / 2 + 1 < nn ? rows / 2 + 1 : nn; /* >= the listed nodes: each holds 2 body-nodes */
    cd_int j = m->pending, *flags = m->loop_flags;
    cd_ulong *counts = m->loop_counts;
    double gap_max = m->contact_gap, dt = m->dt, *over = m->loop_over, *reals = m->loop_reals; /* [m], [s] */
    CD_WIDE_MIN
    /* (the check apart from the contact: it stops the contact of a step that has a crowded node) */
    CD_STEP_FOR(listed, firstprivate(j) CD_DEV(is_device_ptr(args, flags, counts)))
    for (cd_ulong ci = 0; ci < listed; ci++) cd_mpm_checked_crowded(*args, ci, counts, flags, j);
    CD_STEP_FOR(listed, firstprivate(gap_max, dt, j) CD_DEV(is_device_ptr(args, flags, counts, over)))
    for (cd_ulong ci = 0; ci < listed; ci++) cd_mpm_checked_contact(*args, ci, gap_max, dt, over, counts, flags, j);
    if (m->observe) {
        CD_STEP_FOR(1, firstprivate(j) CD_DEV(is_device_ptr(flags, counts, over, reals)))
        for (int one = 0; one < 1; one++) cd_mpm_checked_max_over(over, counts, reals, flags, j);
    }
}
