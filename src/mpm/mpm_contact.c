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
 * Deterministic: the common nodes' body lists come from a stable counting
 * sort, each listed node is handled by one thread and writes only its own
 * body-nodes, and the pairs are counted after a sort. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "mpm/mpm.h"
#include "core/sim.h" /* CD_PARALLEL */
#include "mpm_contact.h"


static size_t common_node(const cd_mpm *m, size_t t)
{
    int i, j;
    cd_mpm_bnode_ij(m, t, &i, &j);
    return (size_t)j * (size_t)m->nx + (size_t)i;
}

void cd_mpm_contact_nodes(cd_mpm *m)
{
    size_t nn = (size_t)m->nx * (size_t)m->ny, nbn = m->n_bnodes, *cs = m->cn_start;
    memset(cs, 0, (nn + 1) * sizeof(size_t));
    for (size_t t = 0; t < nbn; t++)
        if (m->gm[t] > 0) cs[common_node(m, t) + 1]++;
    for (size_t g = 0; g < nn; g++) cs[g + 1] += cs[g];
    for (size_t t = 0; t < nbn; t++)
        if (m->gm[t] > 0) m->cn_entry[cs[common_node(m, t)]++] = t;
    for (size_t g = nn; g > 0; g--) cs[g] = cs[g - 1];
    cs[0] = 0;
    m->n_cn = 0;
    for (size_t g = 0; g < nn; g++)
        if (cs[g + 1] - cs[g] >= 2) m->cn_list[m->n_cn++] = g;
}

static int cmp_key(const void *a, const void *b)
{
    long long x = *(const long long *)a, y = *(const long long *)b;
    return (x > y) - (x < y);
}

/* Body pairs in contact (exchanging force), each counted once, from the
 * contact bits. */
static int count_pairs(cd_mpm *m, char *err, size_t errlen)
{
    size_t n = 0;
    for (size_t c = 0; c < m->n_cn; c++) n += (size_t)__builtin_popcount(m->cn_active[c]);
    if (n > m->cap_pairs) {
        long long *q = realloc(m->pair_keys, (n + 64) * sizeof(long long));
        if (!q) {
            snprintf(err, errlen, "out of memory for %zu contact pairs", n);
            return -1;
        }
        m->pair_keys = q;
        m->cap_pairs = n + 64;
    }
    size_t w = 0;
    for (size_t c = 0; c < m->n_cn; c++) {
        size_t g = m->cn_list[c], first = m->cn_start[g], cnt = m->cn_start[g + 1] - first;
        int q = 0;
        for (size_t a = 0; a < cnt; a++)
            for (size_t b = a + 1; b < cnt; b++, q++)
                if (m->cn_active[c] >> q & 1u)
                    m->pair_keys[w++] = (long long)m->bnode_body[m->cn_entry[first + a]] * m->n_bodies +
                                        m->bnode_body[m->cn_entry[first + b]];
    }
    if (w) qsort(m->pair_keys, w, sizeof(long long), cmp_key); /* (no keys: pair_keys may be NULL) */
    long distinct = 0;
    for (size_t i = 0; i < w; i++) distinct += i == 0 || m->pair_keys[i] != m->pair_keys[i - 1];
    m->n_contacts = distinct;
    return 0;
}

int cd_mpm_contact_correct(cd_mpm *m, char *err, size_t errlen)
{
    long long bad = -1;
    double pen = 0, dt = m->dt;
    long ncn = (long)m->n_cn;
    double gap_max = m->contact_gap; /* [m] */
    cd_mpm_cols c = cd_mpm_step_cols(m);
#pragma omp parallel for schedule(static) reduction(max : bad, pen) if (CD_PARALLEL(ncn))
    for (long ci = 0; ci < ncn; ci++) {
        double over = pen;
        if (cd_mpm_item_contact(c, (size_t)ci, gap_max, dt, &over)) {
            long long g = (long long)m->cn_list[ci];
            bad = g > bad ? g : bad;
        }
        pen = over;
    }
    if (bad >= 0) {
        size_t g = (size_t)bad;
        snprintf(err, errlen,
                 "common node (%zu, %zu) at step %lld: %zu bodies meet there, more than the %d the contact "
                 "handles: refine the mesh (mpm.cells_per_diameter)",
                 g % (size_t)m->nx, g / (size_t)m->nx, m->step + 1, m->cn_start[g + 1] - m->cn_start[g],
                 CD_MPM_NODE_BODIES);
        return -1;
    }
    m->penetration = pen;
    return count_pairs(m, err, errlen);
}
