/* The material point method's explicit step (docs/mpm.md): MUSL on a
 * regular mesh with cubic B-splines.  Every point-to-node sum is a gather:
 * a node visits the cells of its support in a fixed order and, in each, the
 * points in index order (a stable counting sort by cell), so the sums have
 * the same bits for any number of threads and need no atomics. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "mpm.h"
#include "sim.h" /* CD_PARALLEL: small loops on one thread */
#include "../kernels/mpm_shape.h"
#include "../kernels/mpm_wall.h"

int cd_mpm_alloc(cd_mpm *m, size_t n, int nx, int ny, double h, double ox, double oy, char *err, size_t errlen)
{
    memset(m, 0, sizeof *m);
    m->n = n;
    m->nx = nx;
    m->ny = ny;
    m->h = h;
    m->ox = ox;
    m->oy = oy;
    size_t nn = (size_t)nx * (size_t)ny, nc = (size_t)(nx - 1) * (size_t)(ny - 1), s = n ? n : 1;
    double **pcols[] = {&m->x, &m->y, &m->vx, &m->vy, &m->mass, &m->vol, &m->half, &m->sxx, &m->syy, &m->sxy,
                        &m->szz, &m->eps_p, &m->f_xx, &m->f_xy, &m->f_yx, &m->f_yy, &m->ex, &m->ey};
    int ok = nx >= 4 && ny >= 4;
    for (size_t i = 0; i < sizeof pcols / sizeof pcols[0]; i++) ok &= (*pcols[i] = calloc(s, sizeof(double))) != NULL;
    double **wcols[] = {&m->wx, &m->wy, &m->dwx, &m->dwy};
    for (size_t i = 0; i < 4; i++) ok &= (*wcols[i] = calloc(CD_MPM_STENCIL * s, sizeof(double))) != NULL;
    double **gcols[] = {&m->gm, &m->gpx, &m->gpy, &m->gfx, &m->gfy, &m->gvx, &m->gvy};
    for (size_t i = 0; i < sizeof gcols / sizeof gcols[0]; i++) ok &= (*gcols[i] = calloc(nn, sizeof(double))) != NULL;
    ok &= (m->particle = calloc(s, sizeof(int))) != NULL;
    ok &= (m->bx = calloc(s, sizeof(int))) != NULL && (m->by = calloc(s, sizeof(int))) != NULL;
    ok &= (m->order = calloc(s, sizeof(size_t))) != NULL && (m->cell_start = calloc(nc + 1, sizeof(size_t))) != NULL;
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
    void *cols[] = {m->x, m->y, m->vx, m->vy, m->mass, m->vol, m->half, m->sxx, m->syy, m->sxy, m->szz, m->eps_p,
                    m->f_xx, m->f_xy, m->f_yx, m->f_yy, m->ex, m->ey, m->wx, m->wy, m->dwx, m->dwy, m->gm, m->gpx,
                    m->gpy, m->gfx, m->gfy, m->gvx, m->gvy, m->particle, m->bx, m->by, m->order, m->cell_start};
    for (size_t i = 0; i < sizeof cols / sizeof cols[0]; i++) free(cols[i]);
    memset(m, 0, sizeof *m);
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

/* Stencil of every point, the wall forces on it, and the points sorted by
 * cell.  -1 when a point's stencil leaves the mesh. */
static int prepare(cd_mpm *m, char *err, size_t errlen)
{
    size_t n = m->n, ncx = (size_t)(m->nx - 1), nc = ncx * (size_t)(m->ny - 1);
    long long bad = -1;
#pragma omp parallel for schedule(static) reduction(max : bad) if (CD_PARALLEL(n))
    for (size_t p = 0; p < n; p++) {
        int bx = cd_mpm_weights_1d((m->x[p] - m->ox) / m->h, m->h, m->wx + CD_MPM_STENCIL * p, m->dwx + CD_MPM_STENCIL * p);
        int by = cd_mpm_weights_1d((m->y[p] - m->oy) / m->h, m->h, m->wy + CD_MPM_STENCIL * p, m->dwy + CD_MPM_STENCIL * p);
        if (!(bx >= 0 && by >= 0 && bx + CD_MPM_STENCIL <= m->nx && by + CD_MPM_STENCIL <= m->ny)) {
            bad = (long long)p > bad ? (long long)p : bad;
            bx = by = 0;
        }
        m->bx[p] = bx;
        m->by[p] = by;
        double ex = 0, ey = 0; /* [N/m] */
        for (int w = 0; w < m->n_walls; w++) {
            const cd_mpm_wall *W = &m->walls[w];
            double d = cd_mpm_wall_overlap(m->x[p], m->y[p], m->half[p], m->f_xx[p], m->f_xy[p], m->f_yx[p],
                                           m->f_yy[p], W->px, W->py, W->nx, W->ny);
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
        snprintf(err, errlen, "material point %zu at (%.6g, %.6g) m (t = %.9g s, step %lld) left the background mesh "
                 "[%.6g, %.6g] x [%.6g, %.6g] m: the run blew up, or the set-up leaves too little room", p, m->x[p],
                 m->y[p], m->time, m->step, m->ox, m->ox + (m->nx - 1) * m->h, m->oy, m->oy + (m->ny - 1) * m->h);
        return -1;
    }
    /* wall forces: the reaction of the points' penalty forces, summed in point order */
    for (int w = 0; w < m->n_walls; w++) {
        cd_mpm_wall *W = &m->walls[w];
        double fx = 0, fy = 0;
        for (size_t p = 0; p < n; p++) {
            double d = cd_mpm_wall_overlap(m->x[p], m->y[p], m->half[p], m->f_xx[p], m->f_xy[p], m->f_yx[p],
                                           m->f_yy[p], W->px, W->py, W->nx, W->ny);
            if (d > 0) {
                fx -= m->wall_k * d * W->nx;
                fy -= m->wall_k * d * W->ny;
            }
        }
        W->fx = fx;
        W->fy = fy;
    }
    /* stable counting sort by cell: cell of a point = its stencil's second node */
    memset(m->cell_start, 0, (nc + 1) * sizeof(size_t));
    for (size_t p = 0; p < n; p++) m->cell_start[(size_t)(m->by[p] + 1) * ncx + (size_t)(m->bx[p] + 1) + 1]++;
    for (size_t c = 0; c < nc; c++) m->cell_start[c + 1] += m->cell_start[c];
    for (size_t p = 0; p < n; p++) {
        size_t c = (size_t)(m->by[p] + 1) * ncx + (size_t)(m->bx[p] + 1);
        m->order[m->cell_start[c]++] = p;
    }
    for (size_t c = nc; c > 0; c--) m->cell_start[c] = m->cell_start[c - 1];
    m->cell_start[0] = 0;
    return 0;
}

/* The points whose stencil holds node (i, j) lie in cells i-2 .. i+1 and
 * j-2 .. j+1: visited in that order, each cell's points in index order. */
#define FOR_SUPPORT(m, i, j, p, a, b, ...)                                                                          \
    for (int cy_ = (j) - 2; cy_ <= (j) + 1; cy_++) {                                                                \
        if (cy_ < 0 || cy_ >= (m)->ny - 1) continue;                                                                \
        for (int cx_ = (i) - 2; cx_ <= (i) + 1; cx_++) {                                                            \
            if (cx_ < 0 || cx_ >= (m)->nx - 1) continue;                                                            \
            size_t c_ = (size_t)cy_ * (size_t)((m)->nx - 1) + (size_t)cx_;                                         \
            for (size_t k_ = (m)->cell_start[c_]; k_ < (m)->cell_start[c_ + 1]; k_++) {                             \
                size_t p = (m)->order[k_];                                                                          \
                int a = (i) - (m)->bx[p], b = (j) - (m)->by[p];                                                     \
                __VA_ARGS__                                                                                         \
            }                                                                                                       \
        }                                                                                                           \
    }

/* Node mass, momentum and force from the points (the paper's eq. (3):
 * lumped mass, f_int = -sum V sigma grad N, f_ext = sum N f_p). */
static void to_grid(cd_mpm *m)
{
    int nx = m->nx, ny = m->ny;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(nx * ny))
    for (int node = 0; node < nx * ny; node++) {
        int i = node % nx, j = node / nx;
        double gm = 0, px = 0, py = 0, fx = 0, fy = 0;
        FOR_SUPPORT(m, i, j, p, a, b, {
            double wa = m->wx[CD_MPM_STENCIL * p + a], wb = m->wy[CD_MPM_STENCIL * p + b];
            double N = wa * wb;                                  /* [1] */
            double gx = m->dwx[CD_MPM_STENCIL * p + a] * wb;     /* dN/dx [1/m] */
            double gy = wa * m->dwy[CD_MPM_STENCIL * p + b];     /* dN/dy [1/m] */
            double mN = N * m->mass[p];
            gm += mN;
            px += mN * m->vx[p];
            py += mN * m->vy[p];
            fx += N * m->ex[p] - m->vol[p] * (m->sxx[p] * gx + m->sxy[p] * gy);
            fy += N * m->ey[p] - m->vol[p] * (m->sxy[p] * gx + m->syy[p] * gy);
        })
        m->gm[node] = gm;
        m->gpx[node] = px;
        m->gpy[node] = py;
        m->gfx[node] = fx;
        m->gfy[node] = fy;
    }
}

/* MUSL's second gather: node velocities from the updated point momenta. */
static void remap_velocity(cd_mpm *m)
{
    int nx = m->nx, ny = m->ny;
#pragma omp parallel for schedule(static) if (CD_PARALLEL(nx * ny))
    for (int node = 0; node < nx * ny; node++) {
        int i = node % nx, j = node / nx;
        double px = 0, py = 0;
        FOR_SUPPORT(m, i, j, p, a, b, {
            double mN = m->wx[CD_MPM_STENCIL * p + a] * m->wy[CD_MPM_STENCIL * p + b] * m->mass[p];
            px += mN * m->vx[p];
            py += mN * m->vy[p];
        })
        double gm = m->gm[node];
        m->gvx[node] = gm > 0 ? px / gm : 0;
        m->gvy[node] = gm > 0 ? py / gm : 0;
    }
}

int cd_mpm_step(cd_mpm *m, char *err, size_t errlen)
{
    double dt = m->dt;
    int nx = m->nx;
    if (prepare(m, err, errlen)) return -1;
    to_grid(m);
    /* node acceleration a = f / m into gf, new node velocity into gv */
#pragma omp parallel for schedule(static) if (CD_PARALLEL(nx * m->ny))
    for (int node = 0; node < nx * m->ny; node++) {
        double gm = m->gm[node];
        double ax = gm > 0 ? m->gfx[node] / gm : 0, ay = gm > 0 ? m->gfy[node] / gm : 0; /* [m/s^2] */
        m->gfx[node] = ax;
        m->gfy[node] = ay;
        m->gvx[node] = gm > 0 ? m->gpx[node] / gm + dt * ax : 0;
        m->gvy[node] = gm > 0 ? m->gpy[node] / gm + dt * ay : 0;
    }
    /* points: velocity from the node accelerations (FLIP), position from the new node velocities */
#pragma omp parallel for schedule(static) if (CD_PARALLEL(m->n))
    for (size_t p = 0; p < m->n; p++) {
        double ax = 0, ay = 0, ux = 0, uy = 0;
        for (int b = 0; b < CD_MPM_STENCIL; b++)
            for (int a = 0; a < CD_MPM_STENCIL; a++) {
                int node = (m->by[p] + b) * nx + m->bx[p] + a;
                double N = m->wx[CD_MPM_STENCIL * p + a] * m->wy[CD_MPM_STENCIL * p + b];
                ax += N * m->gfx[node];
                ay += N * m->gfy[node];
                ux += N * m->gvx[node];
                uy += N * m->gvy[node];
            }
        m->vx[p] += dt * ax;
        m->vy[p] += dt * ay;
        m->x[p] += dt * ux;
        m->y[p] += dt * uy;
    }
    remap_velocity(m);
    /* points: velocity gradient, stress, deformation gradient and volume */
    long long bad = -1;
#pragma omp parallel for schedule(static) reduction(max : bad) if (CD_PARALLEL(m->n))
    for (size_t p = 0; p < m->n; p++) {
        double lxx = 0, lxy = 0, lyx = 0, lyy = 0; /* dv_a/dx_b [1/s] */
        for (int b = 0; b < CD_MPM_STENCIL; b++)
            for (int a = 0; a < CD_MPM_STENCIL; a++) {
                int node = (m->by[p] + b) * nx + m->bx[p] + a;
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
        snprintf(err, errlen, "material point %lld is not finite or has a volume <= 0 at step %lld (t = %.9g s): the run "
                 "blew up; reduce run.dt (limit %.3g s) or check the material", bad, m->step + 1, m->time + dt,
                 cd_mpm_dt_limit(m));
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
