/* The material point method's explicit step (docs/mpm.md): MUSL on a
 * regular mesh with cubic B-splines.  Every point-to-node sum is a gather:
 * a node visits the cells of its support in a fixed order and, in each, the
 * points in index order (a stable counting sort by cell), so the sums have
 * the same bits for any number of threads and need no atomics. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "mpm/mpm.h"
#include "core/sim.h" /* CD_PARALLEL: small loops on one thread */
#include "mpm_shape.h"
#include "mpm_wall.h"

int cd_mpm_alloc(cd_mpm *m, size_t n, int nx, int ny, double h, double ox, double oy, char *err, size_t errlen)
{
    memset(m, 0, sizeof *m);
    m->n = n;
    m->nx = nx;
    m->ny = ny;
    m->h = h;
    m->ox = ox;
    m->oy = oy;
    size_t nn = (size_t)nx * (size_t)ny, s = n ? n : 1;
    double **pcols[] = {&m->x,   &m->y,   &m->vx,    &m->vy,   &m->mass, &m->vol,  &m->half, &m->sxx, &m->syy,
                        &m->sxy, &m->szz, &m->eps_p, &m->f_xx, &m->f_xy, &m->f_yx, &m->f_yy, &m->ex,  &m->ey};
    int ok = nx >= 4 && ny >= 4;
    for (size_t i = 0; i < sizeof pcols / sizeof pcols[0]; i++) ok &= (*pcols[i] = calloc(s, sizeof(double))) != NULL;
    double **wcols[] = {&m->wx, &m->wy, &m->dwx, &m->dwy};
    for (size_t i = 0; i < 4; i++) ok &= (*wcols[i] = calloc(CD_MPM_STENCIL * s, sizeof(double))) != NULL;
    ok &= (m->particle = calloc(s, sizeof(int))) != NULL;
    ok &= (m->bx = calloc(s, sizeof(int))) != NULL && (m->by = calloc(s, sizeof(int))) != NULL;
    ok &= (m->order = calloc(s, sizeof(size_t))) != NULL;
    ok &= (m->cn_start = calloc(nn + 1, sizeof(size_t))) != NULL && (m->cn_list = calloc(nn, sizeof(size_t))) != NULL &&
          (m->cn_active = calloc(nn, sizeof(unsigned))) != NULL;
    if (!ok) {
        cd_mpm_free(m);
        snprintf(err, errlen, "out of memory for %zu material points and %d x %d nodes", n, nx, ny);
        return -1;
    }
    for (size_t p = 0; p < n; p++) m->f_xx[p] = m->f_yy[p] = 1;
    return 0;
}

void cd_mpm_free(cd_mpm *m)
{
    void *cols[] = {m->x,          m->y,        m->vx,       m->vy,       m->mass,      m->vol,      m->half,
                    m->sxx,        m->syy,      m->sxy,      m->szz,      m->eps_p,     m->f_xx,     m->f_xy,
                    m->f_yx,       m->f_yy,     m->ex,       m->ey,       m->wx,        m->wy,       m->dwx,
                    m->dwy,        m->gm,       m->gpx,      m->gpy,      m->gfx,       m->gfy,      m->gvx,
                    m->gvy,        m->gnx,      m->gny,      m->particle, m->bx,        m->by,       m->order,
                    m->cell_start, m->pfirst,   m->win_i0,   m->win_j0,   m->win_nx,    m->win_ny,   m->win_off,
                    m->bnode_body, m->cn_start, m->cn_entry, m->cn_list,  m->cn_active, m->pair_keys};
    for (size_t i = 0; i < sizeof cols / sizeof cols[0]; i++) free(cols[i]);
    memset(m, 0, sizeof *m);
}

int cd_mpm_bodies(cd_mpm *m, char *err, size_t errlen)
{
    int nb = m->n ? m->particle[m->n - 1] + 1 : 0;
    for (size_t p = 0; p < m->n; p++)
        if (m->particle[p] < 0 ||
            (p > 0 && m->particle[p] != m->particle[p - 1] && m->particle[p] != m->particle[p - 1] + 1) ||
            (p == 0 && m->particle[0] != 0)) {
            snprintf(err, errlen,
                     "material point %zu: particle id %d out of order (expected the ids 0, 1, ... in "
                     "blocks of contiguous points)",
                     p, m->particle[p]);
            return -1;
        }
    if (nb < 1) {
        snprintf(err, errlen, "no material points");
        return -1;
    }
    size_t b = (size_t)nb;
    m->pfirst = calloc(b + 1, sizeof(size_t));
    m->win_off = calloc(b + 1, sizeof(size_t));
    m->win_i0 = calloc(b, sizeof(int));
    m->win_j0 = calloc(b, sizeof(int));
    m->win_nx = calloc(b, sizeof(int));
    m->win_ny = calloc(b, sizeof(int));
    if (!m->pfirst || !m->win_off || !m->win_i0 || !m->win_j0 || !m->win_nx || !m->win_ny) {
        snprintf(err, errlen, "out of memory for %d bodies", nb);
        return -1;
    }
    for (size_t p = 0; p < m->n; p++) m->pfirst[m->particle[p] + 1] = p + 1;
    m->n_bodies = nb;
    return 0;
}

/* Grows the body-node columns to hold n body-nodes. */
static int reserve_bnodes(cd_mpm *m, size_t n, char *err, size_t errlen)
{
    if (n <= m->cap_bnodes) return 0;
    size_t cap = n + n / 4 + 64;
    double **cols[] = {&m->gm, &m->gpx, &m->gpy, &m->gfx, &m->gfy, &m->gvx, &m->gvy, &m->gnx, &m->gny};
    int ok = 1;
    for (size_t i = 0; i < sizeof cols / sizeof cols[0]; i++) {
        double *q = realloc(*cols[i], cap * sizeof(double));
        ok &= q != NULL;
        if (q) *cols[i] = q;
    }
    int *b = realloc(m->bnode_body, cap * sizeof(int));
    if (b) m->bnode_body = b;
    size_t *c = realloc(m->cell_start, (cap + 1) * sizeof(size_t));
    if (c) m->cell_start = c;
    size_t *e = realloc(m->cn_entry, cap * sizeof(size_t));
    if (e) m->cn_entry = e;
    if (!ok || !b || !c || !e) {
        snprintf(err, errlen, "out of memory for %zu body-nodes", n);
        return -1;
    }
    m->cap_bnodes = cap;
    return 0;
}

double cd_mpm_dt_limit(const cd_mpm *m)
{
    double rho = INFINITY, vmax = 0, mmin = INFINITY; /* [kg/m^3], [m/s], [kg/m] */
    for (size_t p = 0; p < m->n; p++) {
        double r = m->mass[p] / m->vol[p];
        if (r < rho) rho = r;
        if (m->mass[p] < mmin) mmin = m->mass[p];
    }
    for (int w = 0; w < m->n_walls; w++) {
        double v = hypot(m->walls[w].vx, m->walls[w].vy);
        if (v > vmax) vmax = v;
    }
    double cp = sqrt(cd_mpm_pwave_modulus(m->mat) / rho); /* P-wave speed [m/s] */
    double lim = m->h / (cp + vmax);
    if (m->n_walls && m->wall_k > 0) {
        double pen = 2 * sqrt(mmin / m->wall_k);
        if (pen < lim) lim = pen;
    }
    return lim;
}

/* The body-cell of point p: its stencil's second node, numbered like the
 * body's nodes. */
static inline size_t point_cell(const cd_mpm *m, size_t p)
{
    int k = m->particle[p];
    return m->win_off[k] + (size_t)(m->by[p] + 1 - m->win_j0[k]) * (size_t)m->win_nx[k] +
           (size_t)(m->bx[p] + 1 - m->win_i0[k]);
}

/* Stencil of every point, the wall forces on it, each body's window of
 * nodes, and the points sorted by body and cell.  -1 when a point's stencil leaves the mesh. */
static int prepare(cd_mpm *m, char *err, size_t errlen)
{
    size_t n = m->n;
    long long bad = -1;
#pragma omp parallel for schedule(static) reduction(max : bad) if (CD_PARALLEL(n))
    for (size_t p = 0; p < n; p++) {
        int bx =
            cd_mpm_weights_1d((m->x[p] - m->ox) / m->h, m->h, m->wx + CD_MPM_STENCIL * p, m->dwx + CD_MPM_STENCIL * p);
        int by =
            cd_mpm_weights_1d((m->y[p] - m->oy) / m->h, m->h, m->wy + CD_MPM_STENCIL * p, m->dwy + CD_MPM_STENCIL * p);
        if (!(bx >= 0 && by >= 0 && bx + CD_MPM_STENCIL <= m->nx && by + CD_MPM_STENCIL <= m->ny)) {
            bad = (long long)p > bad ? (long long)p : bad;
            bx = by = 0;
        }
        m->bx[p] = bx;
        m->by[p] = by;
        double ex = 0, ey = 0; /* [N/m] */
        for (int w = 0; w < m->n_walls; w++) {
            const cd_mpm_wall *W = &m->walls[w];
            double d = cd_mpm_wall_overlap(m->x[p], m->y[p], m->half[p], m->f_xx[p], m->f_xy[p], m->f_yx[p], m->f_yy[p],
                                           W->px, W->py, W->nx, W->ny);
            if (d > 0) {
                ex += m->wall_k * d * W->nx;
                ey += m->wall_k * d * W->ny;
            }
        }
        m->ex[p] = ex;
        m->ey[p] = ey;
    }
    if (bad >= 0) {
        size_t p = (size_t)bad;
        snprintf(err, errlen,
                 "material point %zu at (%.6g, %.6g) m (t = %.9g s, step %lld) left the background mesh "
                 "[%.6g, %.6g] x [%.6g, %.6g] m: the run blew up, or the set-up leaves too little room",
                 p, m->x[p], m->y[p], m->time, m->step, m->ox, m->ox + (m->nx - 1) * m->h, m->oy,
                 m->oy + (m->ny - 1) * m->h);
        return -1;
    }
    /* wall forces: the reaction of the points' penalty forces, summed in point order */
    for (int w = 0; w < m->n_walls; w++) {
        cd_mpm_wall *W = &m->walls[w];
        double fx = 0, fy = 0;
        for (size_t p = 0; p < n; p++) {
            double d = cd_mpm_wall_overlap(m->x[p], m->y[p], m->half[p], m->f_xx[p], m->f_xy[p], m->f_yx[p], m->f_yy[p],
                                           W->px, W->py, W->nx, W->ny);
            if (d > 0) {
                fx -= m->wall_k * d * W->nx;
                fy -= m->wall_k * d * W->ny;
            }
        }
        W->fx = fx;
        W->fy = fy;
    }
    /* each body's window: the nodes its points' stencils reach */
    int nb = m->n_bodies;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(n))
    for (int k = 0; k < nb; k++) {
        int i0 = m->nx, j0 = m->ny, i1 = 0, j1 = 0;
        for (size_t p = m->pfirst[k]; p < m->pfirst[k + 1]; p++) {
            if (m->bx[p] < i0) i0 = m->bx[p];
            if (m->by[p] < j0) j0 = m->by[p];
            if (m->bx[p] > i1) i1 = m->bx[p];
            if (m->by[p] > j1) j1 = m->by[p];
        }
        m->win_i0[k] = i0;
        m->win_j0[k] = j0;
        m->win_nx[k] = i1 - i0 + CD_MPM_STENCIL;
        m->win_ny[k] = j1 - j0 + CD_MPM_STENCIL;
    }
    for (int k = 0; k < nb; k++) m->win_off[k + 1] = m->win_off[k] + (size_t)m->win_nx[k] * (size_t)m->win_ny[k];
    size_t nbn = m->win_off[nb];
    if (reserve_bnodes(m, nbn, err, errlen)) return -1;
    m->n_bnodes = nbn;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(n))
    for (int k = 0; k < nb; k++)
        for (size_t t = m->win_off[k]; t < m->win_off[k + 1]; t++) m->bnode_body[t] = k;
    /* stable counting sort by (body, cell): a point's cell is its stencil's
     * second node, numbered like the body's nodes */
    size_t *cs = m->cell_start;
    memset(cs, 0, (nbn + 1) * sizeof(size_t));
    for (size_t p = 0; p < n; p++) cs[point_cell(m, p) + 1]++;
    for (size_t c = 0; c < nbn; c++) cs[c + 1] += cs[c];
    for (size_t p = 0; p < n; p++) m->order[cs[point_cell(m, p)]++] = p;
    for (size_t c = nbn; c > 0; c--) cs[c] = cs[c - 1];
    cs[0] = 0;
    return 0;
}

/* The points whose stencil holds body-node t lie in the body's cells
 * i-2 .. i+1 and j-2 .. j+1 (window coordinates): visited in that order,
 * each cell's points in index order.  a, b: the node's place in the
 * point's stencil. */
#define FOR_SUPPORT(m, t, p, a, b, ...)                                                                                \
    do {                                                                                                               \
        int k_ = (m)->bnode_body[t], wnx_ = (m)->win_nx[k_], wny_ = (m)->win_ny[k_];                                   \
        size_t off_ = (m)->win_off[k_], loc_ = (t)-off_;                                                               \
        int li_ = (int)(loc_ % (size_t)wnx_), lj_ = (int)(loc_ / (size_t)wnx_);                                        \
        int gi_ = (m)->win_i0[k_] + li_, gj_ = (m)->win_j0[k_] + lj_;                                                  \
        for (int cy_ = lj_ - 2; cy_ <= lj_ + 1; cy_++) {                                                               \
            if (cy_ < 0 || cy_ >= wny_) continue;                                                                      \
            for (int cx_ = li_ - 2; cx_ <= li_ + 1; cx_++) {                                                           \
                if (cx_ < 0 || cx_ >= wnx_) continue;                                                                  \
                size_t c_ = off_ + (size_t)cy_ * (size_t)wnx_ + (size_t)cx_;                                           \
                for (size_t e_ = (m)->cell_start[c_]; e_ < (m)->cell_start[c_ + 1]; e_++) {                            \
                    size_t p = (m)->order[e_];                                                                         \
                    int a = gi_ - (m)->bx[p], b = gj_ - (m)->by[p];                                                    \
                    __VA_ARGS__                                                                                        \
                }                                                                                                      \
            }                                                                                                          \
        }                                                                                                              \
    } while (0)

/* Node mass, momentum and force from the points (the paper's eq. (3):
 * lumped mass, f_int = -sum V sigma grad N, f_ext = sum N f_p); with more
 * than one body also the mass gradient, the bodies' normals at contacts. */
static void to_grid(cd_mpm *m)
{
    long nbn = (long)m->n_bnodes;
    int normals = m->n_bodies > 1;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(nbn))
    for (long tt = 0; tt < nbn; tt++) {
        size_t t = (size_t)tt;
        double gm = 0, px = 0, py = 0, fx = 0, fy = 0, nx = 0, ny = 0;
        FOR_SUPPORT(m, t, p, a, b, {
            double wa = m->wx[CD_MPM_STENCIL * p + a], wb = m->wy[CD_MPM_STENCIL * p + b];
            double N = wa * wb;                              /* [1] */
            double gx = m->dwx[CD_MPM_STENCIL * p + a] * wb; /* dN/dx [1/m] */
            double gy = wa * m->dwy[CD_MPM_STENCIL * p + b]; /* dN/dy [1/m] */
            double mN = N * m->mass[p];
            gm += mN;
            px += mN * m->vx[p];
            py += mN * m->vy[p];
            fx += N * m->ex[p] - m->vol[p] * (m->sxx[p] * gx + m->sxy[p] * gy);
            fy += N * m->ey[p] - m->vol[p] * (m->sxy[p] * gx + m->syy[p] * gy);
            if (normals) {
                nx += m->mass[p] * gx;
                ny += m->mass[p] * gy;
            }
        });
        m->gm[t] = gm;
        m->gpx[t] = px;
        m->gpy[t] = py;
        m->gfx[t] = fx;
        m->gfy[t] = fy;
        m->gnx[t] = nx;
        m->gny[t] = ny;
    }
}

/* MUSL's second gather: node velocities from the updated point momenta. */
static void remap_velocity(cd_mpm *m)
{
    long nbn = (long)m->n_bnodes;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(nbn))
    for (long tt = 0; tt < nbn; tt++) {
        size_t t = (size_t)tt;
        double px = 0, py = 0;
        FOR_SUPPORT(m, t, p, a, b, {
            double mN = m->wx[CD_MPM_STENCIL * p + a] * m->wy[CD_MPM_STENCIL * p + b] * m->mass[p];
            px += mN * m->vx[p];
            py += mN * m->vy[p];
        });
        double gm = m->gm[t];
        m->gvx[t] = gm > 0 ? px / gm : 0;
        m->gvy[t] = gm > 0 ? py / gm : 0;
    }
}

/* The body-node of point p's stencil entry (a, b) is stencil_base + b *
 * win_nx + a. */
static inline size_t stencil_base(const cd_mpm *m, size_t p)
{
    int k = m->particle[p];
    return m->win_off[k] + (size_t)(m->by[p] - m->win_j0[k]) * (size_t)m->win_nx[k] + (size_t)(m->bx[p] - m->win_i0[k]);
}

int cd_mpm_step(cd_mpm *m, char *err, size_t errlen)
{
    double dt = m->dt;
    if (m->n_bodies == 0 && cd_mpm_bodies(m, err, errlen)) return -1;
    if (prepare(m, err, errlen)) return -1;
    to_grid(m);
    long nbn = (long)m->n_bnodes;
    /* node acceleration a = f / m into gf, new node velocity into gv */
#pragma omp parallel for schedule(static) if (CD_PARALLEL(nbn))
    for (long t = 0; t < nbn; t++) {
        double gm = m->gm[t];
        double ax = gm > 0 ? m->gfx[t] / gm : 0, ay = gm > 0 ? m->gfy[t] / gm : 0; /* [m/s^2] */
        m->gfx[t] = ax;
        m->gfy[t] = ay;
        m->gvx[t] = gm > 0 ? m->gpx[t] / gm + dt * ax : 0;
        m->gvy[t] = gm > 0 ? m->gpy[t] / gm + dt * ay : 0;
    }
    if (m->n_bodies > 1) {
        cd_mpm_contact_nodes(m);
        if (cd_mpm_contact_correct(m, err, errlen)) return -1;
    }
    /* points: velocity from the node accelerations (FLIP) blended with the new node velocities
     * (PIC, a share pic_fraction: damps the velocity modes the mesh does not see, which FLIP
     * keeps and the compaction feeds; docs/mpm.md "FLIP's noise"); position from the new node
     * velocities */
    double pic = m->pic_fraction; /* [1] */
#pragma omp parallel for schedule(static) if (CD_PARALLEL(m->n))
    for (size_t p = 0; p < m->n; p++) {
        double ax = 0, ay = 0, ux = 0, uy = 0;
        size_t base = stencil_base(m, p), row = (size_t)m->win_nx[m->particle[p]];
        for (int b = 0; b < CD_MPM_STENCIL; b++)
            for (int a = 0; a < CD_MPM_STENCIL; a++) {
                size_t node = base + (size_t)b * row + (size_t)a;
                double N = m->wx[CD_MPM_STENCIL * p + a] * m->wy[CD_MPM_STENCIL * p + b];
                ax += N * m->gfx[node];
                ay += N * m->gfy[node];
                ux += N * m->gvx[node];
                uy += N * m->gvy[node];
            }
        m->vx[p] = (1 - pic) * (m->vx[p] + dt * ax) + pic * ux;
        m->vy[p] = (1 - pic) * (m->vy[p] + dt * ay) + pic * uy;
        m->x[p] += dt * ux;
        m->y[p] += dt * uy;
    }
    remap_velocity(m);
    double mesh_kinetic = 0; /* [J/m], summed in body-node order: the same bits for any thread count */
    for (size_t t = 0; t < m->n_bnodes; t++)
        mesh_kinetic += 0.5 * m->gm[t] * (m->gvx[t] * m->gvx[t] + m->gvy[t] * m->gvy[t]);
    m->mesh_kinetic = mesh_kinetic;
    /* no second contact correction of the remapped velocities: the strain follows each body's own
     * remapped field, the motion its points made; re-imposing the contact there, on the contact's
     * widened nodes, made strain the points' motion did not have and fed energy (docs/mpm.md) */
    /* points: velocity gradient, stress, deformation gradient and volume */
    long long bad = -1;
#pragma omp parallel for schedule(static) reduction(max : bad) if (CD_PARALLEL(m->n))
    for (size_t p = 0; p < m->n; p++) {
        double lxx = 0, lxy = 0, lyx = 0, lyy = 0; /* dv_a/dx_b [1/s] */
        size_t base = stencil_base(m, p), row = (size_t)m->win_nx[m->particle[p]];
        for (int b = 0; b < CD_MPM_STENCIL; b++)
            for (int a = 0; a < CD_MPM_STENCIL; a++) {
                size_t node = base + (size_t)b * row + (size_t)a;
                double wa = m->wx[CD_MPM_STENCIL * p + a], wb = m->wy[CD_MPM_STENCIL * p + b];
                double gx = m->dwx[CD_MPM_STENCIL * p + a] * wb, gy = wa * m->dwy[CD_MPM_STENCIL * p + b];
                lxx += m->gvx[node] * gx;
                lxy += m->gvx[node] * gy;
                lyx += m->gvy[node] * gx;
                lyy += m->gvy[node] * gy;
            }
        double gxx = dt * lxx, gxy = dt * lxy, gyx = dt * lyx, gyy = dt * lyy; /* grad du [1] */
        cd_mpm_stress s = {m->sxx[p], m->syy[p], m->sxy[p], m->szz[p]};
        cd_mpm_stress_update(m->mat, &s, &m->eps_p[p], gxx, gyy, 0.5 * (gxy + gyx));
        m->sxx[p] = s.xx;
        m->syy[p] = s.yy;
        m->sxy[p] = s.xy;
        m->szz[p] = s.zz;
        double fxx = m->f_xx[p], fxy = m->f_xy[p], fyx = m->f_yx[p], fyy = m->f_yy[p];
        m->f_xx[p] = (1 + gxx) * fxx + gxy * fyx;
        m->f_xy[p] = (1 + gxx) * fxy + gxy * fyy;
        m->f_yx[p] = gyx * fxx + (1 + gyy) * fyx;
        m->f_yy[p] = gyx * fxy + (1 + gyy) * fyy;
        m->vol[p] *= cd_mpm_volume_ratio(gxx, gxy, gyx, gyy);
        if (!(isfinite(m->x[p]) && isfinite(m->y[p]) && isfinite(s.xx) && isfinite(s.yy) && m->vol[p] > 0))
            bad = (long long)p > bad ? (long long)p : bad;
    }
    if (bad >= 0) {
        snprintf(err, errlen,
                 "material point %lld is not finite or has a volume <= 0 at step %lld (t = %.9g s): the run "
                 "blew up; reduce run.dt (limit %.3g s) or check the material",
                 bad, m->step + 1, m->time + dt, cd_mpm_dt_limit(m));
        return -1;
    }
    for (int w = 0; w < m->n_walls; w++) {
        m->walls[w].px += dt * m->walls[w].vx;
        m->walls[w].py += dt * m->walls[w].vy;
    }
    m->time += dt;
    m->step++;
    return 0;
}

double cd_mpm_kinetic_energy(const cd_mpm *m)
{
    double e = 0;
    for (size_t p = 0; p < m->n; p++) e += 0.5 * m->mass[p] * (m->vx[p] * m->vx[p] + m->vy[p] * m->vy[p]);
    return e;
}

double cd_mpm_strain_energy(const cd_mpm *m)
{
    double e = 0;
    for (size_t p = 0; p < m->n; p++) {
        cd_mpm_stress s = {m->sxx[p], m->syy[p], m->sxy[p], m->szz[p]};
        e += m->vol[p] * cd_mpm_elastic_energy_density(m->mat, s);
    }
    return e;
}

void cd_mpm_packing_measures(const cd_mpm *m, double *phi, double *sigma, double *strain, double *z)
{
    double area = 0; /* [m^2 per m] */
    for (size_t p = 0; p < m->n; p++) area += m->vol[p];
    double w = m->walls[3].px - m->walls[2].px, h = m->walls[1].py - m->walls[0].py; /* box [m] */
    *phi = area / (w * h);
    *sigma = -m->walls[0].fy / w;
    *strain = log(m->box_h0 / h);
    *z = m->n_bodies > 0 ? 2.0 * (double)m->n_contacts / m->n_bodies : 0;
}
