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
#include "mpm_shape.h"
#include "mpm_contact.h"
#include "mpm_wall.h" /* cd_mpm_point_reach */

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

/* Lines parallel to the contact normal through a node, at tangential
 * offsets (q - CD_MPM_CONTACT_LINES / 2) h / 2, q < CD_MPM_CONTACT_LINES:
 * within a cell of the node, every half cell.  A point at the contact takes
 * its velocity from nodes up to two cells away along the tangent; where the
 * surfaces curve away from the contact, the line through such a node alone
 * sees a gap (two disks of radius R: x^2 / R at a tangential distance x, a
 * third of a cell at x = h on a mesh of 3 cells per radius) and left that
 * node's approach free: the points at the contact kept part of their
 * approach and the bodies crept into each other (docs/mpm.md "Contact
 * between particles").  Within one cell, not two: a node further along the
 * tangent has its own line at offset h passing within a cell of the
 * contact, and lines over two cells (9) held the overlap no better while
 * widening the contact further. */
#define CD_MPM_CONTACT_LINES 5
#define CENTRAL_LINE         (CD_MPM_CONTACT_LINES / 2)

/* The extent of body k's material on the lines through common node
 * (gi, gj) at (xi, yi) [m] along the unit vector n, offset along the tangent
 * t = (-ny, nx): for line q, the lowest and highest s of the chords
 * x_i + o_q t + s n of the points whose stencil holds the node
 * (kernels/mpm_contact.h) [m]; +inf and -inf where the line meets none. */
static void extent(const cd_mpm *m, int k, int gi, int gj, double xi, double yi, double nx, double ny,
                   double lo[CD_MPM_CONTACT_LINES], double hi[CD_MPM_CONTACT_LINES])
{
    int wnx = m->win_nx[k], wny = m->win_ny[k], li = gi - m->win_i0[k], lj = gj - m->win_j0[k];
    double tx = -ny, ty = nx, step = 0.5 * m->h; /* tangent [1], line spacing [m] */
    for (int q = 0; q < CD_MPM_CONTACT_LINES; q++) {
        lo[q] = INFINITY;
        hi[q] = -INFINITY;
    }
    for (int cy = lj - 2; cy <= lj + 1; cy++) {
        if (cy < 0 || cy >= wny) continue;
        for (int cx = li - 2; cx <= li + 1; cx++) {
            if (cx < 0 || cx >= wnx) continue;
            size_t c = m->win_off[k] + (size_t)cy * (size_t)wnx + (size_t)cx;
            for (size_t e = m->cell_start[c]; e < m->cell_start[c + 1]; e++) {
                size_t p = m->order[e];
                double dx = xi - m->x[p], dy = yi - m->y[p]; /* node - point [m] */
                /* the lines that can cross the point: its parallelogram spans c_t +- w_t along t */
                double ct = -(dx * tx + dy * ty);
                double wt = cd_mpm_point_reach(m->half[p], m->f_xx[p], m->f_xy[p], m->f_yx[p], m->f_yy[p], tx, ty);
                int q0 = (int)ceil((ct - wt) / step) + CENTRAL_LINE, q1 = (int)floor((ct + wt) / step) + CENTRAL_LINE;
                if (q0 < 0) q0 = 0;
                if (q1 > CD_MPM_CONTACT_LINES - 1) q1 = CD_MPM_CONTACT_LINES - 1;
                for (int q = q0; q <= q1; q++) {
                    double o = (q - CENTRAL_LINE) * step, s0, s1; /* offset [m], chord [m] */
                    if (!cd_mpm_point_chord(m->half[p], m->f_xx[p], m->f_xy[p], m->f_yx[p], m->f_yy[p], dx + o * tx,
                                            dy + o * ty, nx, ny, &s0, &s1))
                        continue;
                    if (s0 < lo[q]) lo[q] = s0;
                    if (s1 > hi[q]) hi[q] = s1;
                }
            }
        }
    }
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
#pragma omp parallel for schedule(static) reduction(max : bad, pen) if (CD_PARALLEL(ncn))
    for (long c = 0; c < ncn; c++) {
        size_t g = m->cn_list[c], first = m->cn_start[g], cnt = m->cn_start[g + 1] - first;
        if (cnt > CD_MPM_NODE_BODIES) {
            bad = (long long)g > bad ? (long long)g : bad;
            continue;
        }
        int gi = (int)(g % (size_t)m->nx), gj = (int)(g / (size_t)m->nx);
        double xi = m->ox + gi * m->h, yi = m->oy + gj * m->h; /* node position [m] */
        unsigned act = 0u, moved = 0u;
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
                /* in contact where a's material comes within contact_gap of b's */
                {
                    double lo_a[CD_MPM_CONTACT_LINES], hi_a[CD_MPM_CONTACT_LINES];
                    double lo_b[CD_MPM_CONTACT_LINES], hi_b[CD_MPM_CONTACT_LINES];
                    extent(m, m->bnode_body[ta], gi, gj, xi, yi, nx, ny, lo_a, hi_a);
                    extent(m, m->bnode_body[tb], gi, gj, xi, yi, nx, ny, lo_b, hi_b);
                    /* the closest approach over the lines [m]; on each, a must lie before b along n:
                     * where the mass gradients' normal disagrees with the order of the material (at
                     * the edge of the bodies' supports) the line says nothing about this contact */
                    double gap = INFINITY;
                    for (int l = 0; l < CD_MPM_CONTACT_LINES; l++)
                        if (lo_a[l] <= lo_b[l] && hi_a[l] <= hi_b[l] && lo_b[l] - hi_a[l] < gap)
                            gap = lo_b[l] - hi_a[l];
                    if (gap <= m->contact_gap) {
                        act |= 1u << q;
                        /* the overlap on the node's own line: the measure of interpenetration */
                        double over = hi_a[CENTRAL_LINE] - lo_b[CENTRAL_LINE];
                        if (lo_a[CENTRAL_LINE] <= lo_b[CENTRAL_LINE] && hi_a[CENTRAL_LINE] <= hi_b[CENTRAL_LINE] &&
                            over > pen)
                            pen = over;
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
        m->cn_active[c] = act;
        /* the acceleration that takes the node from its momentum to the corrected velocity */
        for (size_t a = 0; a < cnt; a++)
            if (moved >> a & 1u) {
                size_t t = m->cn_entry[first + a];
                m->gfx[t] = (m->gvx[t] - m->gpx[t] / m->gm[t]) / dt;
                m->gfy[t] = (m->gvy[t] - m->gpy[t] / m->gm[t]) / dt;
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
    m->penetration = pen;
    return count_pairs(m, err, errlen);
}
