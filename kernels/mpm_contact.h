/* Material point method: where the line through a node along a contact
 * normal crosses a material point (src/mpm/mpm_contact.c, docs/mpm.md
 * "Contact").  Device-safe: C11 and OpenCL C.
 *
 * A point stands for the parallelogram x_p + F [-l/2, l/2]^2 (l its initial
 * side [m], F its deformation gradient), as for the walls
 * (kernels/mpm_wall.h).  The line x_i + s n (s [m]) crosses it where the
 * reference coordinates xi(s) = F^-1 (x_i - x_p) + s F^-1 n lie in the
 * square: two slabs, one per reference direction.  The chord of the line
 * in the point, not the point's projection on n: the chords of points that
 * do not overlap do not overlap either, so two bodies in touch, not
 * overlapping, show no overlap. */
#ifndef CD_MPM_CONTACT_H
#define CD_MPM_CONTACT_H
#include "defs.h"
#include "mpm_step_items.h"

CD_DEVICE_BEGIN

/* The chord [*s_lo, *s_hi] [m] of the line through the node at distance
 * (dx, dy) = x_i - x_p [m] from the point, along the unit vector (nx, ny),
 * in the point's parallelogram of half-side half_side [m] and deformation
 * gradient f_*; returns 0 when the line misses it. */
CD_INLINE cd_int cd_mpm_point_chord(cd_real half_side, cd_real f_xx, cd_real f_xy, cd_real f_yx, cd_real f_yy,
                                    cd_real dx, cd_real dy, cd_real nx, cd_real ny, cd_real *s_lo, cd_real *s_hi)
{
    cd_real det = f_xx * f_yy - f_xy * f_yx;                                         /* det F > 0 [1] */
    cd_real a0 = (f_yy * dx - f_xy * dy) / det, a1 = (-f_yx * dx + f_xx * dy) / det; /* F^-1 (x_i - x_p) [m] */
    cd_real d0 = (f_yy * nx - f_xy * ny) / det, d1 = (-f_yx * nx + f_xx * ny) / det; /* F^-1 n [1] */
    cd_real lo = -CD_R(1e300), hi = CD_R(1e300);
    cd_real a[2] = {a0, a1}, d[2] = {d0, d1};
    for (cd_int k = 0; k < 2; k++) {
        if (d[k] == CD_R(0)) {
            if (fabs(a[k]) > half_side) return 0;
            continue;
        }
        cd_real t1 = (-half_side - a[k]) / d[k], t2 = (half_side - a[k]) / d[k];
        lo = fmax(lo, fmin(t1, t2));
        hi = fmin(hi, fmax(t1, t2));
    }
    *s_lo = lo;
    *s_hi = hi;
    return lo <= hi;
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
#define CD_MPM_CENTRAL_LINE  (CD_MPM_CONTACT_LINES / 2)
/* Bodies a common node may hold (more: the step stops, asking for a finer mesh). */
#define CD_MPM_NODE_BODIES 8

/* The extent of body k's material on the lines through common node
 * (gi, gj) at (xi, yi) [m] along the unit vector n, offset along the tangent
 * t = (-ny, nx): for line q, the lowest and highest s of the chords
 * x_i + o_q t + s n of the points whose stencil holds the node [m]; +inf
 * and -inf where the line meets none. */
CD_INLINE void cd_mpm_contact_extent(cd_mpm_cols c, cd_int k, cd_int gi, cd_int gj, cd_real xi, cd_real yi, cd_real nx,
                                     cd_real ny, cd_real *lo, cd_real *hi)
{
    cd_int wnx = c.win_nx[k], wny = c.win_ny[k], li = gi - c.win_i0[k], lj = gj - c.win_j0[k];
    cd_real tx = -ny, ty = nx, step = CD_R(0.5) * c.h; /* tangent [1], line spacing [m] */
    for (cd_int q = 0; q < CD_MPM_CONTACT_LINES; q++) {
        lo[q] = INFINITY;
        hi[q] = -INFINITY;
    }
    for (cd_int cy = lj - 2; cy <= lj + 1; cy++) {
        if (cy < 0 || cy >= wny) continue;
        for (cd_int cx = li - 2; cx <= li + 1; cx++) {
            if (cx < 0 || cx >= wnx) continue;
            cd_ulong cell = c.win_off[k] + (cd_ulong)cy * (cd_ulong)wnx + (cd_ulong)cx;
            for (cd_ulong e = c.cell_start[cell]; e < c.cell_start[cell + 1]; e++) {
                cd_ulong p = c.order[e];
                cd_real dx = xi - c.x[p], dy = yi - c.y[p]; /* node - point [m] */
                /* the lines that can cross the point: its parallelogram spans c_t +- w_t along t */
                cd_real ct = -(dx * tx + dy * ty);
                cd_real wt = cd_mpm_point_reach(c.half_side[p], c.f_xx[p], c.f_xy[p], c.f_yx[p], c.f_yy[p], tx, ty);
                cd_int q0 = (cd_int)ceil((ct - wt) / step) + CD_MPM_CENTRAL_LINE,
                       q1 = (cd_int)floor((ct + wt) / step) + CD_MPM_CENTRAL_LINE;
                if (q0 < 0) q0 = 0;
                if (q1 > CD_MPM_CONTACT_LINES - 1) q1 = CD_MPM_CONTACT_LINES - 1;
                for (cd_int q = q0; q <= q1; q++) {
                    cd_real o = (q - CD_MPM_CENTRAL_LINE) * step, s0, s1; /* offset [m], chord [m] */
                    if (!cd_mpm_point_chord(c.half_side[p], c.f_xx[p], c.f_xy[p], c.f_yx[p], c.f_yy[p], dx + o * tx,
                                            dy + o * ty, nx, ny, &s0, &s1))
                        continue;
                    if (s0 < lo[q]) lo[q] = s0;
                    if (s1 > hi[q]) hi[q] = s1;
                }
            }
        }
    }
}

/* 1 when more than CD_MPM_NODE_BODIES bodies meet at listed common node ci. */
CD_INLINE cd_int cd_mpm_item_contact_crowded(cd_mpm_cols c, cd_ulong ci)
{
    cd_ulong g = c.cn_list[ci];
    return c.cn_start[g + 1] - c.cn_start[g] > CD_MPM_NODE_BODIES;
}

/* Listed common node ci: every pair of its bodies whose material comes
 * within gap_max [m] of each other on the lines is in contact (bit q of
 * cn_active); an approaching pair loses the normal component of its
 * relative velocity, as a perfectly inelastic collision of the two node
 * masses along the contact normal, and the moved body-nodes get the
 * acceleration that takes them there in dt [s].  *pen: raised to the
 * overlap on the node's own line [m].  Returns 1 when more than
 * CD_MPM_NODE_BODIES bodies meet at the node (nothing done), else 0. */
CD_INLINE cd_int cd_mpm_item_contact(cd_mpm_cols c, cd_ulong ci, cd_real gap_max, cd_real dt, cd_real *pen)
{
    if (cd_mpm_item_contact_crowded(c, ci)) return 1;
    cd_ulong g = c.cn_list[ci], first = c.cn_start[g], cnt = c.cn_start[g + 1] - first;
    cd_int gi = (cd_int)(g % (cd_ulong)c.nx), gj = (cd_int)(g / (cd_ulong)c.nx);
    cd_real xi = c.ox + gi * c.h, yi = c.oy + gj * c.h; /* node position [m] */
    cd_uint act = 0u, moved = 0u;
    cd_int q = 0;
    for (cd_ulong a = 0; a < cnt; a++)
        for (cd_ulong b = a + 1; b < cnt; b++, q++) {
            cd_ulong ta = c.cn_entry[first + a], tb = c.cn_entry[first + b];
            /* normal from body a towards body b: the difference of their outward normals (gn is
             * sum m_p grad_p N, the node's mass gradient with its sign turned) */
            /* (sqrt of the sum of squares, not hypot: sqrt, + and * round correctly on every OpenCL
             * device and GPU, hypot may differ by ulps from the host's: the same bits everywhere) */
            cd_real nx = c.gnx[ta] - c.gnx[tb], ny = c.gny[ta] - c.gny[tb], len = sqrt(nx * nx + ny * ny);
            if (!(len > 0)) continue;
            nx /= len;
            ny /= len;
            /* in contact where a's material comes within gap_max of b's */
            {
                cd_real lo_a[CD_MPM_CONTACT_LINES], hi_a[CD_MPM_CONTACT_LINES];
                cd_real lo_b[CD_MPM_CONTACT_LINES], hi_b[CD_MPM_CONTACT_LINES];
                cd_mpm_contact_extent(c, c.bnode_body[ta], gi, gj, xi, yi, nx, ny, lo_a, hi_a);
                cd_mpm_contact_extent(c, c.bnode_body[tb], gi, gj, xi, yi, nx, ny, lo_b, hi_b);
                /* the closest approach over the lines [m]; on each, a must lie before b along n:
                 * where the mass gradients' normal disagrees with the order of the material (at
                 * the edge of the bodies' supports) the line says nothing about this contact */
                cd_real gap = INFINITY;
                for (cd_int l = 0; l < CD_MPM_CONTACT_LINES; l++)
                    if (lo_a[l] <= lo_b[l] && hi_a[l] <= hi_b[l] && lo_b[l] - hi_a[l] < gap) gap = lo_b[l] - hi_a[l];
                if (gap <= gap_max) {
                    act |= 1u << q;
                    /* the overlap on the node's own line: the measure of interpenetration */
                    cd_int m = CD_MPM_CENTRAL_LINE;
                    cd_real over = hi_a[m] - lo_b[m];
                    if (lo_a[m] <= lo_b[m] && hi_a[m] <= hi_b[m] && over > *pen) *pen = over;
                }
            }
            if (!(act >> q & 1u)) continue;
            cd_real vn = (c.gvx[ta] - c.gvx[tb]) * nx + (c.gvy[ta] - c.gvy[tb]) * ny; /* approach [m/s] */
            if (!(vn > 0)) continue;
            cd_real ma = c.gm[ta], mb = c.gm[tb];
            cd_real J = vn * (ma * mb / (ma + mb)); /* normal impulse per metre [kg/s] */
            c.gvx[ta] -= J / ma * nx;
            c.gvy[ta] -= J / ma * ny;
            c.gvx[tb] += J / mb * nx;
            c.gvy[tb] += J / mb * ny;
            moved |= 1u << a | 1u << b;
        }
    c.cn_active[ci] = act;
    /* the acceleration that takes the node from its momentum to the corrected velocity */
    for (cd_ulong a = 0; a < cnt; a++)
        if (moved >> a & 1u) {
            cd_ulong t = c.cn_entry[first + a];
            c.gfx[t] = (c.gvx[t] - c.gpx[t] / c.gm[t]) / dt;
            c.gfy[t] = (c.gvy[t] - c.gpy[t] / c.gm[t]) / dt;
        }
    return 0;
}

CD_DEVICE_END
#endif
