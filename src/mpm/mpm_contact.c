/* Frictionless contact between the bodies of the material point method
 * through their common background mesh (docs/mpm.md, "Contact"): the
 * multi-mesh algorithm of Bardenhagen et al. (the paper's refs. [9-11]).
 * Each body has its own node values (src/mpm/mpm.c); where two bodies share a
 * common node and, on the line through it along their normal, their
 * material comes within contact_gap of each other (kernels/mpm_contact.h),
 * the normal component of their relative velocity is removed when they
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
#include "mpm_shape.h"
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

/* The extent of body k's material on the line through common node
 * (gi, gj) at (xi, yi) [m] along the unit vector n: the lowest and highest
 * s of the chords x_i + s n of the points whose stencil holds the node
 * (kernels/mpm_contact.h) [m]; +inf and -inf when the line meets none. */
static void extent(const cd_mpm *m, int k, int gi, int gj, double xi, double yi, double nx, double ny, double *lo,
                   double *hi)
{
    int wnx = m->win_nx[k], wny = m->win_ny[k], li = gi - m->win_i0[k], lj = gj - m->win_j0[k];
    double l = INFINITY, u = -INFINITY;
    for (int cy = lj - 2; cy <= lj + 1; cy++) {
        if (cy < 0 || cy >= wny) continue;
        for (int cx = li - 2; cx <= li + 1; cx++) {
            if (cx < 0 || cx >= wnx) continue;
            size_t c = m->win_off[k] + (size_t)cy * (size_t)wnx + (size_t)cx;
            for (size_t e = m->cell_start[c]; e < m->cell_start[c + 1]; e++) {
                size_t p = m->order[e];
                double s0, s1;
                if (!cd_mpm_point_chord(m->half[p], m->f_xx[p], m->f_xy[p], m->f_yx[p], m->f_yy[p], xi - m->x[p],
                                        yi - m->y[p], nx, ny, &s0, &s1))
                    continue;
                if (s0 < l) l = s0;
                if (s1 > u) u = s1;
            }
        }
    }
    *lo = l;
    *hi = u;
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

int cd_mpm_contact_correct(cd_mpm *m, int phase, char *err, size_t errlen)
{
    long long bad = -1;
    double pen = 0, dt = m->dt;
    long ncn = (long)m->n_cn;
#pragma omp parallel for schedule(static) reduction(max : bad, pen) if (CD_PARALLEL(ncn))
    for (long c = 0; c < ncn; c++) {
        size_t g = m->cn_list[c], first = m->cn_start[g], cnt = m->cn_start[g + 1] - first;
        if (cnt > CD_MPM_NODE_BODIES) {
            bad = (long long)g > bad ? (long long)g : bad;
            continue;
        }
        int gi = (int)(g % (size_t)m->nx), gj = (int)(g / (size_t)m->nx);
        double xi = m->ox + gi * m->h, yi = m->oy + gj * m->h; /* node position [m] */
        unsigned act = phase ? m->cn_active[c] : 0u, moved = 0u;
        int q = 0;
        for (size_t a = 0; a < cnt; a++)
            for (size_t b = a + 1; b < cnt; b++, q++) {
                size_t ta = m->cn_entry[first + a], tb = m->cn_entry[first + b];
                /* normal from body a towards body b: the difference of their outward normals (gn is
                 * sum m_p grad_p N, the node's mass gradient with its sign turned) */
                double nx = m->gnx[ta] - m->gnx[tb], ny = m->gny[ta] - m->gny[tb], len = hypot(nx, ny);
                if (!(len > 0)) continue;
                nx /= len;
                ny /= len;
                if (phase == 0) { /* in contact where a's material comes within contact_gap of b's */
                    double lo_a, hi_a, lo_b, hi_b;
                    extent(m, m->bnode_body[ta], gi, gj, xi, yi, nx, ny, &lo_a, &hi_a);
                    extent(m, m->bnode_body[tb], gi, gj, xi, yi, nx, ny, &lo_b, &hi_b);
                    /* on the line, a must lie before b along n: where the mass gradients' normal
                     * disagrees with the order of the material (at the edge of the bodies' supports)
                     * the node says nothing about this contact */
                    double gap = lo_b - hi_a; /* [m] */
                    if (gap <= m->contact_gap && lo_a <= lo_b && hi_a <= hi_b) {
                        act |= 1u << q;
                        if (-gap > pen) pen = -gap;
                    }
                }
                if (!(act >> q & 1u)) continue;
                double vn = (m->gvx[ta] - m->gvx[tb]) * nx + (m->gvy[ta] - m->gvy[tb]) * ny; /* approach [m/s] */
                if (!(vn > 0)) continue;
                double ma = m->gm[ta], mb = m->gm[tb];
                double J = vn * (ma * mb / (ma + mb)); /* normal impulse per metre [kg/s] */
                m->gvx[ta] -= J / ma * nx;
                m->gvy[ta] -= J / ma * ny;
                m->gvx[tb] += J / mb * nx;
                m->gvy[tb] += J / mb * ny;
                moved |= 1u << a | 1u << b;
            }
        if (phase == 0) {
            m->cn_active[c] = act;
            /* the acceleration that takes the node from its momentum to the corrected velocity */
            for (size_t a = 0; a < cnt; a++)
                if (moved >> a & 1u) {
                    size_t t = m->cn_entry[first + a];
                    m->gfx[t] = (m->gvx[t] - m->gpx[t] / m->gm[t]) / dt;
                    m->gfy[t] = (m->gvy[t] - m->gpy[t] / m->gm[t]) / dt;
                }
        }
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
    if (phase == 0) {
        m->penetration = pen;
        return count_pairs(m, err, errlen);
    }
    return 0;
}
