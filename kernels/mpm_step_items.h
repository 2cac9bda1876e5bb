/* The material point method's explicit step as work items (docs/mpm.md;
 * src/mpm/mpm.c runs them in its loops, src/mpm/mpm_contact.c the contact's).
 * Device-safe: C11 and OpenCL C.  One item is one row of one loop: a point,
 * a body, a body-node or a listed common node.  Every item writes only its
 * own row, and every point-to-node sum is a gather in a fixed order (the
 * cells of the node's support in turn, each cell's points in index order,
 * from a stable counting sort), so the sums have the same bits for any
 * number of threads or teams and need no atomics.
 *
 * Indices into the point and body-node columns are cd_ulong (size_t on the
 * host's LP64), so that the same buffers serve an OpenCL device. */
#ifndef CD_MPM_STEP_ITEMS_H
#define CD_MPM_STEP_ITEMS_H
#include "defs.h"
#include "mpm_shape.h"
#include "mpm_wall.h"
#include "mpm_material.h"

#define CD_MPM_ITEM_MAX_WALLS 4

CD_DEVICE_BEGIN

/* The columns the items read and write, and the mesh they live on. */
typedef struct {
    /* material points */
    CD_GLOBAL cd_real *x, *y, *vx, *vy; /* position [m], velocity [m/s] */
    CD_GLOBAL cd_real *mass, *vol,
        *half_side; /* [kg/m], [m^3/m], half the initial side [m] ("half" is an OpenCL C type) */
    CD_GLOBAL cd_real *sxx, *syy, *sxy, *szz;     /* Cauchy stress [Pa] */
    CD_GLOBAL cd_real *eps_p;                     /* equivalent plastic strain [1] */
    CD_GLOBAL cd_real *f_xx, *f_xy, *f_yx, *f_yy; /* deformation gradient [1] */
    CD_GLOBAL cd_int *particle;                   /* body of each point */
    CD_GLOBAL cd_int *bx, *by;                    /* first node of the stencil (common mesh) */
    CD_GLOBAL cd_real *wx, *wy, *dwx, *dwy;       /* CD_MPM_STENCIL weights [1] and gradients [1/m] per point */
    CD_GLOBAL cd_real *ex, *ey;                   /* wall force on the point [N/m] */
    CD_GLOBAL cd_ulong *order;                    /* points sorted by (body, cell) */
    /* bodies and their nodes */
    CD_GLOBAL cd_ulong *pfirst, *win_off; /* points and first body-node of each body (+ 1 entry) */
    CD_GLOBAL cd_int *win_i0, *win_j0, *win_nx, *win_ny;
    CD_GLOBAL cd_int *bnode_body;      /* body of each body-node */
    CD_GLOBAL cd_ulong *cell_start;    /* first entry in order of each body-cell; + 1 */
    CD_GLOBAL cd_real *gm, *gpx, *gpy; /* node mass [kg/m], momentum [kg/s per m] */
    CD_GLOBAL cd_real *gfx, *gfy;      /* node force [N/m], then acceleration [m/s^2] */
    CD_GLOBAL cd_real *gvx, *gvy;      /* node velocity [m/s] */
    CD_GLOBAL cd_real *gnx, *gny;      /* sum m_p grad N [kg/m^2] */
    /* contact (src/mpm/mpm_contact.c): common nodes holding two or more bodies */
    CD_GLOBAL cd_ulong *cn_start; /* per common node (nx * ny + 1): its body-nodes in cn_entry */
    CD_GLOBAL cd_ulong *cn_entry; /* body-nodes sorted by common node, bodies ascending */
    CD_GLOBAL cd_ulong *cn_list;  /* common nodes with >= 2 bodies */
    CD_GLOBAL cd_uint *cn_active; /* per listed node: bit q set when its q-th body pair is in contact */
    /* the common mesh: nodes (i, j) at (ox + i h, oy + j h), i < nx, j < ny */
    cd_int nx, ny, n_bodies;
    cd_real h, ox, oy; /* [m] */
} cd_mpm_cols;

/* The plane walls as the items see them: a point [m] and the unit normal
 * into the material [1] of each, and the penalty stiffness k [N/m per m]. */
typedef struct {
    cd_real px[CD_MPM_ITEM_MAX_WALLS], py[CD_MPM_ITEM_MAX_WALLS];
    cd_real nx[CD_MPM_ITEM_MAX_WALLS], ny[CD_MPM_ITEM_MAX_WALLS];
    cd_int n;
    cd_real k;
} cd_mpm_item_walls;

/* Wall w's penalty overlap with point p [m] (<= 0: none). */
CD_INLINE cd_real cd_mpm_item_wall_overlap(cd_mpm_cols c, cd_ulong p, cd_mpm_item_walls walls, cd_int w)
{
    return cd_mpm_wall_overlap(c.x[p], c.y[p], c.half_side[p], c.f_xx[p], c.f_xy[p], c.f_yx[p], c.f_yy[p], walls.px[w],
                               walls.py[w], walls.nx[w], walls.ny[w]);
}

/* Point p: its stencil (weights, gradients, first nodes) and the walls'
 * penalty force on it.  Returns 1 when its stencil leaves the mesh (then
 * first nodes 0), else 0. */
CD_INLINE cd_int cd_mpm_item_prepare(cd_mpm_cols c, cd_ulong p, cd_mpm_item_walls walls)
{
    cd_int bx = cd_mpm_weights_1d((c.x[p] - c.ox) / c.h, c.h, c.wx + CD_MPM_STENCIL * p, c.dwx + CD_MPM_STENCIL * p);
    cd_int by = cd_mpm_weights_1d((c.y[p] - c.oy) / c.h, c.h, c.wy + CD_MPM_STENCIL * p, c.dwy + CD_MPM_STENCIL * p);
    cd_int out = !(bx >= 0 && by >= 0 && bx + CD_MPM_STENCIL <= c.nx && by + CD_MPM_STENCIL <= c.ny);
    if (out) bx = by = 0;
    c.bx[p] = bx;
    c.by[p] = by;
    cd_real ex = 0, ey = 0; /* [N/m] */
    for (cd_int w = 0; w < walls.n; w++) {
        cd_real d = cd_mpm_item_wall_overlap(c, p, walls, w);
        if (d > 0) {
            ex += walls.k * d * walls.nx[w];
            ey += walls.k * d * walls.ny[w];
        }
    }
    c.ex[p] = ex;
    c.ey[p] = ey;
    return out;
}

/* Body k's window: the nodes its points' stencils reach. */
CD_INLINE void cd_mpm_item_window(cd_mpm_cols c, cd_int k)
{
    cd_int i0 = c.nx, j0 = c.ny, i1 = 0, j1 = 0;
    for (cd_ulong p = c.pfirst[k]; p < c.pfirst[k + 1]; p++) {
        if (c.bx[p] < i0) i0 = c.bx[p];
        if (c.by[p] < j0) j0 = c.by[p];
        if (c.bx[p] > i1) i1 = c.bx[p];
        if (c.by[p] > j1) j1 = c.by[p];
    }
    c.win_i0[k] = i0;
    c.win_j0[k] = j0;
    c.win_nx[k] = i1 - i0 + CD_MPM_STENCIL;
    c.win_ny[k] = j1 - j0 + CD_MPM_STENCIL;
}

/* The body-cell of point p: its stencil's second node, numbered like the
 * body's nodes. */
CD_INLINE cd_ulong cd_mpm_point_cell(cd_mpm_cols c, cd_ulong p)
{
    cd_int k = c.particle[p];
    return c.win_off[k] + (cd_ulong)(c.by[p] + 1 - c.win_j0[k]) * (cd_ulong)c.win_nx[k] +
           (cd_ulong)(c.bx[p] + 1 - c.win_i0[k]);
}

/* The body-node of point p's stencil entry (a, b) is this + b * win_nx + a. */
CD_INLINE cd_ulong cd_mpm_stencil_base(cd_mpm_cols c, cd_ulong p)
{
    cd_int k = c.particle[p];
    return c.win_off[k] + (cd_ulong)(c.by[p] - c.win_j0[k]) * (cd_ulong)c.win_nx[k] + (cd_ulong)(c.bx[p] - c.win_i0[k]);
}

/* The points whose stencil holds body-node t lie in the body's cells
 * i-2 .. i+1 and j-2 .. j+1 (window coordinates): visited in that order,
 * each cell's points in index order.  a, b: the node's place in the
 * point's stencil.  The loop's body goes between CD_MPM_SUPPORT_BEGIN and
 * CD_MPM_SUPPORT_END (two macros, not one taking the body: OpenCL C 1.2
 * has no variadic macros, and the body has commas). */
#define CD_MPM_SUPPORT_BEGIN(c, t, p, a, b)                                                                            \
    {                                                                                                                  \
        cd_int k_ = (c).bnode_body[t], wnx_ = (c).win_nx[k_], wny_ = (c).win_ny[k_];                                   \
        cd_ulong off_ = (c).win_off[k_], loc_ = (t)-off_;                                                              \
        cd_int li_ = (cd_int)(loc_ % (cd_ulong)wnx_), lj_ = (cd_int)(loc_ / (cd_ulong)wnx_);                           \
        cd_int gi_ = (c).win_i0[k_] + li_, gj_ = (c).win_j0[k_] + lj_;                                                 \
        for (cd_int cy_ = lj_ - 2; cy_ <= lj_ + 1; cy_++) {                                                            \
            if (cy_ < 0 || cy_ >= wny_) continue;                                                                      \
            for (cd_int cx_ = li_ - 2; cx_ <= li_ + 1; cx_++) {                                                        \
                if (cx_ < 0 || cx_ >= wnx_) continue;                                                                  \
                cd_ulong c_ = off_ + (cd_ulong)cy_ * (cd_ulong)wnx_ + (cd_ulong)cx_;                                   \
                for (cd_ulong e_ = (c).cell_start[c_]; e_ < (c).cell_start[c_ + 1]; e_++) {                            \
                    cd_ulong p = (c).order[e_];                                                                        \
                    cd_int a = gi_ - (c).bx[p], b = gj_ - (c).by[p];
#define CD_MPM_SUPPORT_END                                                                                             \
    }                                                                                                                  \
    }                                                                                                                  \
    }                                                                                                                  \
    }

/* Body-node t's mass, momentum and force from the points (the paper's eq.
 * (3): lumped mass, f_int = -sum V sigma grad N, f_ext = sum N f_p); with
 * normals, also sum m_p grad N, the bodies' normals at contacts. */
CD_INLINE void cd_mpm_item_to_grid(cd_mpm_cols c, cd_ulong t, cd_int normals)
{
    cd_real gm = 0, px = 0, py = 0, fx = 0, fy = 0, nx = 0, ny = 0;
    CD_MPM_SUPPORT_BEGIN(c, t, p, a, b)
    cd_real wa = c.wx[CD_MPM_STENCIL * p + a], wb = c.wy[CD_MPM_STENCIL * p + b];
    cd_real N = wa * wb;                             /* [1] */
    cd_real gx = c.dwx[CD_MPM_STENCIL * p + a] * wb; /* dN/dx [1/m] */
    cd_real gy = wa * c.dwy[CD_MPM_STENCIL * p + b]; /* dN/dy [1/m] */
    cd_real mN = N * c.mass[p];
    gm += mN;
    px += mN * c.vx[p];
    py += mN * c.vy[p];
    fx += N * c.ex[p] - c.vol[p] * (c.sxx[p] * gx + c.sxy[p] * gy);
    fy += N * c.ey[p] - c.vol[p] * (c.sxy[p] * gx + c.syy[p] * gy);
    if (normals) {
        nx += c.mass[p] * gx;
        ny += c.mass[p] * gy;
    }
    CD_MPM_SUPPORT_END
    c.gm[t] = gm;
    c.gpx[t] = px;
    c.gpy[t] = py;
    c.gfx[t] = fx;
    c.gfy[t] = fy;
    c.gnx[t] = nx;
    c.gny[t] = ny;
}

/* Body-node t: acceleration a = f / m into gf, the new velocity into gv. */
CD_INLINE void cd_mpm_item_node_update(cd_mpm_cols c, cd_ulong t, cd_real dt)
{
    cd_real gm = c.gm[t];
    cd_real ax = gm > 0 ? c.gfx[t] / gm : 0, ay = gm > 0 ? c.gfy[t] / gm : 0; /* [m/s^2] */
    c.gfx[t] = ax;
    c.gfy[t] = ay;
    c.gvx[t] = gm > 0 ? c.gpx[t] / gm + dt * ax : 0;
    c.gvy[t] = gm > 0 ? c.gpy[t] / gm + dt * ay : 0;
}

/* Point p: velocity from the node accelerations (FLIP) blended with the new
 * node velocities (PIC, a share pic [1]: damps the velocity modes the mesh
 * does not see, docs/mpm.md "FLIP's noise"); position from the new node
 * velocities. */
CD_INLINE void cd_mpm_item_point_update(cd_mpm_cols c, cd_ulong p, cd_real dt, cd_real pic)
{
    cd_real ax = 0, ay = 0, ux = 0, uy = 0;
    cd_ulong base = cd_mpm_stencil_base(c, p), row = (cd_ulong)c.win_nx[c.particle[p]];
    for (cd_int b = 0; b < CD_MPM_STENCIL; b++)
        for (cd_int a = 0; a < CD_MPM_STENCIL; a++) {
            cd_ulong node = base + (cd_ulong)b * row + (cd_ulong)a;
            cd_real N = c.wx[CD_MPM_STENCIL * p + a] * c.wy[CD_MPM_STENCIL * p + b];
            ax += N * c.gfx[node];
            ay += N * c.gfy[node];
            ux += N * c.gvx[node];
            uy += N * c.gvy[node];
        }
    c.vx[p] = (1 - pic) * (c.vx[p] + dt * ax) + pic * ux;
    c.vy[p] = (1 - pic) * (c.vy[p] + dt * ay) + pic * uy;
    c.x[p] += dt * ux;
    c.y[p] += dt * uy;
}

/* MUSL's second gather: body-node t's velocity from the updated point momenta. */
CD_INLINE void cd_mpm_item_remap(cd_mpm_cols c, cd_ulong t)
{
    cd_real px = 0, py = 0;
    CD_MPM_SUPPORT_BEGIN(c, t, p, a, b)
    cd_real mN = c.wx[CD_MPM_STENCIL * p + a] * c.wy[CD_MPM_STENCIL * p + b] * c.mass[p];
    px += mN * c.vx[p];
    py += mN * c.vy[p];
    CD_MPM_SUPPORT_END
    cd_real gm = c.gm[t];
    c.gvx[t] = gm > 0 ? px / gm : 0;
    c.gvy[t] = gm > 0 ? py / gm : 0;
}

/* Point p: velocity gradient from the remapped node velocities, then the
 * stress (return mapping), deformation gradient and volume.  Returns 1 when
 * the point is not finite or its volume not positive (the run blew up). */
CD_INLINE cd_int cd_mpm_item_stress(cd_mpm_cols c, cd_ulong p, cd_real dt, cd_mpm_material mat)
{
    cd_real lxx = 0, lxy = 0, lyx = 0, lyy = 0; /* dv_a/dx_b [1/s] */
    cd_ulong base = cd_mpm_stencil_base(c, p), row = (cd_ulong)c.win_nx[c.particle[p]];
    for (cd_int b = 0; b < CD_MPM_STENCIL; b++)
        for (cd_int a = 0; a < CD_MPM_STENCIL; a++) {
            cd_ulong node = base + (cd_ulong)b * row + (cd_ulong)a;
            cd_real wa = c.wx[CD_MPM_STENCIL * p + a], wb = c.wy[CD_MPM_STENCIL * p + b];
            cd_real gx = c.dwx[CD_MPM_STENCIL * p + a] * wb, gy = wa * c.dwy[CD_MPM_STENCIL * p + b];
            lxx += c.gvx[node] * gx;
            lxy += c.gvx[node] * gy;
            lyx += c.gvy[node] * gx;
            lyy += c.gvy[node] * gy;
        }
    cd_real gxx = dt * lxx, gxy = dt * lxy, gyx = dt * lyx, gyy = dt * lyy; /* grad du [1] */
    cd_mpm_stress s = {c.sxx[p], c.syy[p], c.sxy[p], c.szz[p]};
    cd_real eps = c.eps_p[p];
    cd_mpm_stress_update(mat, &s, &eps, gxx, gyy, CD_R(0.5) * (gxy + gyx));
    c.eps_p[p] = eps;
    c.sxx[p] = s.xx;
    c.syy[p] = s.yy;
    c.sxy[p] = s.xy;
    c.szz[p] = s.zz;
    cd_real fxx = c.f_xx[p], fxy = c.f_xy[p], fyx = c.f_yx[p], fyy = c.f_yy[p];
    c.f_xx[p] = (1 + gxx) * fxx + gxy * fyx;
    c.f_xy[p] = (1 + gxx) * fxy + gxy * fyy;
    c.f_yx[p] = gyx * fxx + (1 + gyy) * fyx;
    c.f_yy[p] = gyx * fxy + (1 + gyy) * fyy;
    c.vol[p] *= cd_mpm_volume_ratio(gxx, gxy, gyx, gyy);
    return !(isfinite(c.x[p]) && isfinite(c.y[p]) && isfinite(s.xx) && isfinite(s.yy) && c.vol[p] > 0);
}

/* ---- the step's serial parts, as one-item loops (run where the loops run,
 * so the state stays there; each in a fixed order: the same bits anywhere) */

/* Wall w's force from the n points [N/m]: the reaction of their penalty
 * forces, summed in point order, into f[2 w], f[2 w + 1]. */
CD_INLINE void cd_mpm_item_wall_force(cd_mpm_cols c, cd_ulong n, cd_mpm_item_walls walls, cd_int w,
                                      CD_GLOBAL cd_real *f)
{
    cd_real fx = 0, fy = 0;
    for (cd_ulong p = 0; p < n; p++) {
        cd_real d = cd_mpm_item_wall_overlap(c, p, walls, w);
        if (d > 0) {
            fx -= walls.k * d * walls.nx[w];
            fy -= walls.k * d * walls.ny[w];
        }
    }
    f[2 * w] = fx;
    f[2 * w + 1] = fy;
}

/* The windows' first body-nodes (win_off[0] = 0 stays); their total into *total. */
CD_INLINE void cd_mpm_item_window_offsets(cd_mpm_cols c, CD_GLOBAL cd_ulong *total)
{
    for (cd_int k = 0; k < c.n_bodies; k++)
        c.win_off[k + 1] = c.win_off[k] + (cd_ulong)c.win_nx[k] * (cd_ulong)c.win_ny[k];
    *total = c.win_off[c.n_bodies];
}

/* Body k's body-nodes name it. */
CD_INLINE void cd_mpm_item_bnode_body(cd_mpm_cols c, cd_int k)
{
    for (cd_ulong t = c.win_off[k]; t < c.win_off[k + 1]; t++) c.bnode_body[t] = k;
}

/* Body k's points sorted by cell into order, stably (a counting sort over
 * the body's cells), and the first entry of each of its cells in
 * cell_start; the last body also ends the list (cell_start[nbn] = n).  A
 * body's points come after those of the bodies before it and its cells
 * after theirs, so the bodies sort independently and together give the one
 * stable sort of all points by (body, cell): the same order whatever runs
 * them (every count an integer). */
CD_INLINE void cd_mpm_item_sort_body(cd_mpm_cols c, cd_int k)
{
    CD_GLOBAL cd_ulong *cs = c.cell_start;
    cd_ulong q0 = c.win_off[k], q1 = c.win_off[k + 1], p0 = c.pfirst[k], p1 = c.pfirst[k + 1];
    for (cd_ulong q = q0; q < q1; q++) cs[q] = 0;
    for (cd_ulong p = p0; p < p1; p++) cs[cd_mpm_point_cell(c, p)]++;
    cd_ulong start = p0; /* each cell's first entry: the exclusive prefix sum of the counts */
    for (cd_ulong q = q0; q < q1; q++) {
        cd_ulong count = cs[q];
        cs[q] = start;
        start += count;
    }
    for (cd_ulong p = p0; p < p1; p++) c.order[cs[cd_mpm_point_cell(c, p)]++] = p;
    if (q1 > q0) { /* each cell's entry was moved to its end: shifted back by one cell */
        for (cd_ulong q = q1 - 1; q > q0; q--) cs[q] = cs[q - 1];
        cs[q0] = p0;
    }
    if (k == c.n_bodies - 1) cs[q1] = p1;
}

/* Sum of m_i v_i^2 / 2 over the nbn body-nodes, in their order [J/m]. */
CD_INLINE void cd_mpm_item_mesh_kinetic(cd_mpm_cols c, cd_ulong nbn, CD_GLOBAL cd_real *e)
{
    cd_real sum = 0;
    for (cd_ulong t = 0; t < nbn; t++) sum += CD_R(0.5) * c.gm[t] * (c.gvx[t] * c.gvx[t] + c.gvy[t] * c.gvy[t]);
    *e = sum;
}

/* The common nodes' body-nodes with mass, sorted by common node, bodies
 * ascending, into cn_start / cn_entry, and the common nodes holding two or
 * more into cn_list (the lists of a stable counting sort by common node;
 * every count an integer, so the same lists whatever runs the steps):
 *   1. per mesh row j, the bodies whose window holds it, ascending, into
 *      rows[j * n_bodies ...], their number into row_n[j];
 *   2. per common node g, its body-nodes with mass into cn_start[g + 1];
 *   3. per block of CD_MPM_CN_BLOCK nodes, their entries and listed nodes
 *      into blocks[2 b], blocks[2 b + 1];
 *   4. one item: the blocks' running totals (nn / CD_MPM_CN_BLOCK of them),
 *      the listed nodes' count into *listed;
 *   5. per block, cn_start as the running count and cn_list;
 *   6. per common node, its body-nodes into cn_entry, bodies ascending. */
#define CD_MPM_CN_BLOCK 256

CD_INLINE void cd_mpm_item_cn_rows(cd_mpm_cols c, cd_int j, CD_GLOBAL cd_int *row_n, CD_GLOBAL cd_int *rows)
{
    cd_int m = 0;
    for (cd_int k = 0; k < c.n_bodies; k++)
        if (j >= c.win_j0[k] && j < c.win_j0[k] + c.win_ny[k]) rows[(cd_ulong)j * (cd_ulong)c.n_bodies + m++] = k;
    row_n[j] = m;
}

/* Body k's body-node at common node (i, j), or -1 when its window does not
 * hold it or the node has no mass there. */
CD_INLINE cd_long cd_mpm_cn_bnode(cd_mpm_cols c, cd_int k, cd_int i, cd_int j)
{
    if (i < c.win_i0[k] || i >= c.win_i0[k] + c.win_nx[k]) return -1;
    cd_ulong t = c.win_off[k] + (cd_ulong)(j - c.win_j0[k]) * (cd_ulong)c.win_nx[k] + (cd_ulong)(i - c.win_i0[k]);
    return c.gm[t] > 0 ? (cd_long)t : -1;
}

CD_INLINE void cd_mpm_item_cn_count(cd_mpm_cols c, cd_ulong g, CD_GLOBAL const cd_int *row_n,
                                    CD_GLOBAL const cd_int *rows)
{
    cd_int i = (cd_int)(g % (cd_ulong)c.nx), j = (cd_int)(g / (cd_ulong)c.nx);
    cd_ulong count = 0;
    for (cd_int m = 0; m < row_n[j]; m++)
        count += cd_mpm_cn_bnode(c, rows[(cd_ulong)j * (cd_ulong)c.n_bodies + m], i, j) >= 0;
    c.cn_start[g + 1] = count;
}

CD_INLINE void cd_mpm_item_cn_block_sums(cd_mpm_cols c, cd_ulong b, CD_GLOBAL cd_ulong *blocks)
{
    cd_ulong nn = (cd_ulong)c.nx * (cd_ulong)c.ny,
             end = (b + 1) * CD_MPM_CN_BLOCK < nn ? (b + 1) * CD_MPM_CN_BLOCK : nn;
    cd_ulong entries = 0, listed = 0;
    for (cd_ulong g = b * CD_MPM_CN_BLOCK; g < end; g++) {
        entries += c.cn_start[g + 1];
        listed += c.cn_start[g + 1] >= 2;
    }
    blocks[2 * b] = entries;
    blocks[2 * b + 1] = listed;
}

CD_INLINE void cd_mpm_item_cn_block_scan(cd_ulong n_blocks, CD_GLOBAL cd_ulong *blocks, CD_GLOBAL cd_ulong *listed)
{
    cd_ulong entries = 0, lists = 0;
    for (cd_ulong b = 0; b < n_blocks; b++) {
        cd_ulong e = blocks[2 * b], l = blocks[2 * b + 1];
        blocks[2 * b] = entries;
        blocks[2 * b + 1] = lists;
        entries += e;
        lists += l;
    }
    *listed = lists;
}

CD_INLINE void cd_mpm_item_cn_block_starts(cd_mpm_cols c, cd_ulong b, CD_GLOBAL const cd_ulong *blocks)
{
    cd_ulong nn = (cd_ulong)c.nx * (cd_ulong)c.ny,
             end = (b + 1) * CD_MPM_CN_BLOCK < nn ? (b + 1) * CD_MPM_CN_BLOCK : nn;
    cd_ulong start = blocks[2 * b], listed = blocks[2 * b + 1];
    if (b == 0) c.cn_start[0] = 0;
    for (cd_ulong g = b * CD_MPM_CN_BLOCK; g < end; g++) {
        cd_ulong count = c.cn_start[g + 1];
        if (count >= 2) c.cn_list[listed++] = g;
        start += count;
        c.cn_start[g + 1] = start;
    }
}

CD_INLINE void cd_mpm_item_cn_entries(cd_mpm_cols c, cd_ulong g, CD_GLOBAL const cd_int *row_n,
                                      CD_GLOBAL const cd_int *rows)
{
    cd_int i = (cd_int)(g % (cd_ulong)c.nx), j = (cd_int)(g / (cd_ulong)c.nx);
    cd_ulong e = c.cn_start[g];
    for (cd_int m = 0; m < row_n[j]; m++) {
        cd_long t = cd_mpm_cn_bnode(c, rows[(cd_ulong)j * (cd_ulong)c.n_bodies + m], i, j);
        if (t >= 0) c.cn_entry[e++] = (cd_ulong)t;
    }
}

/* The body pairs in contact at the n_cn listed nodes (bit q of cn_active
 * for a node's q-th pair), as keys k n_bodies + l, node by node, into keys
 * when not NULL; their number into *count. */
CD_INLINE void cd_mpm_item_pair_keys(cd_mpm_cols c, cd_ulong n_cn, CD_GLOBAL cd_long *keys, CD_GLOBAL cd_ulong *count)
{
    cd_ulong w = 0;
    for (cd_ulong ci = 0; ci < n_cn; ci++) {
        cd_ulong g = c.cn_list[ci], first = c.cn_start[g], cnt = c.cn_start[g + 1] - first;
        cd_int q = 0;
        for (cd_ulong a = 0; a < cnt; a++)
            for (cd_ulong b = a + 1; b < cnt; b++, q++)
                if (c.cn_active[ci] >> q & 1u) {
                    if (keys)
                        keys[w] = (cd_long)c.bnode_body[c.cn_entry[first + a]] * c.n_bodies +
                                  c.bnode_body[c.cn_entry[first + b]];
                    w++;
                }
    }
    *count = w;
}

CD_DEVICE_END
#endif
