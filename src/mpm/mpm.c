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
#include "backend/omp/omp_loops.h" /* CD_STEP_FOR: the loops of the step, on the host or the offload device */
#include "mpm_step_items.h"
#include "mpm_checks.h"

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
    m->observe = 1;
    return 0;
}

void cd_mpm_free(cd_mpm *m)
{
    cd_mpm_cl_close(m);
    cd_mpm_device_stop(m);
    void *cols[] = {m->x,          m->y,        m->vx,       m->vy,       m->mass,      m->vol,       m->half,
                    m->sxx,        m->syy,      m->sxy,      m->szz,      m->eps_p,     m->f_xx,      m->f_xy,
                    m->f_yx,       m->f_yy,     m->ex,       m->ey,       m->wx,        m->wy,        m->dwx,
                    m->dwy,        m->gm,       m->gpx,      m->gpy,      m->gfx,       m->gfy,       m->gvx,
                    m->gvy,        m->gnx,      m->gny,      m->particle, m->bx,        m->by,        m->order,
                    m->cell_start, m->pfirst,   m->win_i0,   m->win_j0,   m->win_nx,    m->win_ny,    m->win_off,
                    m->bnode_body, m->cn_start, m->cn_entry, m->cn_list,  m->cn_active, m->pair_keys, m->since};
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

cd_mpm_cols cd_mpm_step_cols(const cd_mpm *m)
{
    cd_mpm_cols c = {.x = m->x,
                     .y = m->y,
                     .vx = m->vx,
                     .vy = m->vy,
                     .mass = m->mass,
                     .vol = m->vol,
                     .half_side = m->half,
                     .sxx = m->sxx,
                     .syy = m->syy,
                     .sxy = m->sxy,
                     .szz = m->szz,
                     .eps_p = m->eps_p,
                     .f_xx = m->f_xx,
                     .f_xy = m->f_xy,
                     .f_yx = m->f_yx,
                     .f_yy = m->f_yy,
                     .particle = m->particle,
                     .bx = m->bx,
                     .by = m->by,
                     .wx = m->wx,
                     .wy = m->wy,
                     .dwx = m->dwx,
                     .dwy = m->dwy,
                     .ex = m->ex,
                     .ey = m->ey,
                     .order = m->order,
                     .pfirst = m->pfirst,
                     .win_off = m->win_off,
                     .win_i0 = m->win_i0,
                     .win_j0 = m->win_j0,
                     .win_nx = m->win_nx,
                     .win_ny = m->win_ny,
                     .bnode_body = m->bnode_body,
                     .cell_start = m->cell_start,
                     .gm = m->gm,
                     .gpx = m->gpx,
                     .gpy = m->gpy,
                     .gfx = m->gfx,
                     .gfy = m->gfy,
                     .gvx = m->gvx,
                     .gvy = m->gvy,
                     .gnx = m->gnx,
                     .gny = m->gny,
                     .cn_start = m->cn_start,
                     .cn_entry = m->cn_entry,
                     .cn_list = m->cn_list,
                     .cn_active = m->cn_active,
                     .nx = m->nx,
                     .ny = m->ny,
                     .n_bodies = m->n_bodies,
                     .h = m->h,
                     .ox = m->ox,
                     .oy = m->oy};
    return c;
}

cd_mpm_item_walls cd_mpm_walls_items(const cd_mpm *m)
{
    cd_mpm_item_walls walls = {.n = m->n_walls, .k = m->wall_k};
    for (int w = 0; w < m->n_walls; w++) {
        walls.px[w] = m->walls[w].px;
        walls.py[w] = m->walls[w].py;
        walls.nx[w] = m->walls[w].nx;
        walls.ny[w] = m->walls[w].ny;
    }
    return walls;
}

int cd_mpm_fail_left_mesh(cd_mpm *m, size_t p, char *err, size_t errlen)
{
    cd_mpm_device_sync(m);
    snprintf(err, errlen,
             "material point %zu at (%.6g, %.6g) m (t = %.9g s, step %lld) left the background mesh "
             "[%.6g, %.6g] x [%.6g, %.6g] m: the run blew up, or the set-up leaves too little room",
             p, m->x[p], m->y[p], m->time, m->step, m->ox, m->ox + (m->nx - 1) * m->h, m->oy,
             m->oy + (m->ny - 1) * m->h);
    return -1;
}

int cd_mpm_fail_blew_up(cd_mpm *m, long long p, char *err, size_t errlen)
{
    cd_mpm_device_sync(m);
    snprintf(err, errlen,
             "material point %lld is not finite or has a volume <= 0 at step %lld (t = %.9g s): the run "
             "blew up; reduce run.dt (limit %.3g s) or check the material",
             p, m->step + 1, m->time + m->dt, cd_mpm_dt_limit(m));
    return -1;
}

void cd_mpm_step_done(cd_mpm *m)
{
    for (int w = 0; w < m->n_walls; w++) {
        m->walls[w].px += m->dt * m->walls[w].vx;
        m->walls[w].py += m->dt * m->walls[w].vy;
    }
    m->time += m->dt;
    m->step++;
}

int cd_mpm_bnodes_room(cd_mpm *m, size_t n, char *err, size_t errlen)
{
    if (reserve_bnodes(m, n, err, errlen)) return -1;
    if (cd_mpm_device_reserve(m, n)) {
        snprintf(err, errlen, "out of device memory for %zu body-nodes", n);
        return -1;
    }
    cd_mpm_loop_args_refresh(m); /* the body-node columns may have moved */
    return 0;
}

/* The first step (since the loops started) sizes the body-node columns
 * from its count, the one read between steps (unless the step already
 * failed: then it stops before it needs them, and cd_mpm_settle reports
 * it). */
static int size_bnodes(cd_mpm *m, char *err, size_t errlen)
{
    cd_ulong nbn;
    cd_int left;
    cd_dev_get(&nbn, m->loop_counts + CD_MPM_COUNT_BNODES, sizeof nbn);
    cd_dev_get(&left, m->loop_flags + CD_MPM_FAIL_LEFT, sizeof left);
    if (left < 0 && cd_mpm_bnodes_room(m, nbn, err, errlen)) return -1;
    m->sized = 1;
    return 0;
}

/* Stencil of every point, the wall forces on it (observed steps: the
 * walls' forces), each body's window of nodes, and the points sorted by
 * body and cell: stages 0 and 1 of the checks (kernels/mpm_checks.h). */
static int prepare(cd_mpm *m, char *err, size_t errlen)
{
    size_t n = m->n;
    cd_int j = m->pending, *flags = m->loop_flags;
    cd_ulong *counts = m->loop_counts;
    double *reals = m->loop_reals;
    cd_mpm_item_walls walls = cd_mpm_walls_items(m);
    const cd_mpm_cols *args = m->loop_args; /* the columns, where the loops run */
    CD_WIDE_MIN
    CD_STEP_FOR(n, firstprivate(walls, j) CD_DEV(is_device_ptr(args, flags)))
    for (size_t p = 0; p < n; p++) cd_mpm_checked_prepare(*args, p, walls, flags, j);
    /* the walls' forces: the reaction of the points' penalty forces, summed in point order */
    int nw = m->n_walls;
    if (m->observe && nw > 0) {
        CD_STEP_FOR(nw, firstprivate(walls, n, j) CD_DEV(is_device_ptr(args, flags, reals)))
        for (int w = 0; w < nw; w++)
            if (!cd_mpm_stopped(flags, j, 1)) cd_mpm_item_wall_force(*args, n, walls, w, reals + CD_MPM_REAL_WALLS);
    }
    /* each body's window: the nodes its points' stencils reach, and where its nodes start */
    int nb = m->n_bodies;
    CD_STEP_FOR(nb, firstprivate(j) CD_DEV(is_device_ptr(args, flags)))
    for (int k = 0; k < nb; k++)
        if (!cd_mpm_stopped(flags, j, 1)) cd_mpm_item_window(*args, k);
    cd_ulong cap = m->sized ? cd_mpm_loop_rows(m) : (cd_ulong)-1;
    CD_STEP_FOR(1, firstprivate(cap, j) CD_DEV(is_device_ptr(args, flags, counts)))
    for (int one = 0; one < 1; one++) cd_mpm_checked_window_offsets(*args, counts, cap, flags, j);
    if (!m->sized && size_bnodes(m, err, errlen)) return -1;
    CD_STEP_FOR(nb, firstprivate(j) CD_DEV(is_device_ptr(args, flags)))
    for (int k = 0; k < nb; k++)
        if (!cd_mpm_stopped(flags, j, 2)) cd_mpm_item_bnode_body(*args, k);
    /* stable counting sort by (body, cell), body by body: a point's cell is
     * its stencil's second node, numbered like the body's nodes */
    CD_STEP_FOR(nb, firstprivate(j) CD_DEV(is_device_ptr(args, flags)))
    for (int k = 0; k < nb; k++)
        if (!cd_mpm_stopped(flags, j, 2)) cd_mpm_item_sort_body(*args, k);
    return 0;
}

/* The loops over body-nodes run over the rows their columns hold; those
 * past the step's count (counts[CD_MPM_COUNT_BNODES]) do nothing. */
int cd_mpm_step(cd_mpm *m, char *err, size_t errlen)
{
    double dt = m->dt;
    if (m->n_bodies == 0 && cd_mpm_bodies(m, err, errlen)) return -1;
    if (m->cl) return cd_mpm_cl_step(m, err, errlen); /* the OpenCL backend (src/mpm/mpm_cl.c) */
    if (cd_mpm_device_start(m, err, errlen) || cd_mpm_record_start(m, err, errlen) || prepare(m, err, errlen))
        return -1;
    const cd_mpm_cols *args = m->loop_args; /* the columns, where the loops run */
    size_t n = m->n, rows = cd_mpm_loop_rows(m);
    cd_int j = m->pending, *flags = m->loop_flags, normals = m->n_bodies > 1;
    cd_ulong *counts = m->loop_counts;
    CD_WIDE_MIN
    CD_STEP_FOR(rows, firstprivate(normals, j) CD_DEV(is_device_ptr(args, flags, counts)))
    for (size_t t = 0; t < rows; t++)
        if (t < counts[CD_MPM_COUNT_BNODES] && !cd_mpm_stopped(flags, j, 2)) cd_mpm_item_to_grid(*args, t, normals);
    CD_STEP_FOR(rows, firstprivate(dt, j) CD_DEV(is_device_ptr(args, flags, counts)))
    for (size_t t = 0; t < rows; t++)
        if (t < counts[CD_MPM_COUNT_BNODES] && !cd_mpm_stopped(flags, j, 2)) cd_mpm_item_node_update(*args, t, dt);
    if (m->n_bodies > 1) {
        cd_mpm_contact_nodes(m);
        cd_mpm_contact_correct(m);
    }
    double pic = m->pic_fraction; /* [1] */
    CD_STEP_FOR(n, firstprivate(dt, pic, j) CD_DEV(is_device_ptr(args, flags)))
    for (size_t p = 0; p < n; p++)
        if (!cd_mpm_stopped(flags, j, 3)) cd_mpm_item_point_update(*args, p, dt, pic);
    CD_STEP_FOR(rows, firstprivate(j) CD_DEV(is_device_ptr(args, flags, counts)))
    for (size_t t = 0; t < rows; t++)
        if (t < counts[CD_MPM_COUNT_BNODES] && !cd_mpm_stopped(flags, j, 3)) cd_mpm_item_remap(*args, t);
    /* observed steps: [J/m], summed in body-node order: the same bits for any thread count */
    double *reals = m->loop_reals;
    if (m->observe) {
        CD_STEP_FOR(1, firstprivate(j) CD_DEV(is_device_ptr(args, flags, counts, reals)))
        for (int one = 0; one < 1; one++)
            if (!cd_mpm_stopped(flags, j, 3))
                cd_mpm_item_mesh_kinetic(*args, counts[CD_MPM_COUNT_BNODES], reals + CD_MPM_REAL_KINETIC);
    }
    /* no second contact correction of the remapped velocities: the strain follows each body's own
     * remapped field, the motion its points made; re-imposing the contact there, on the contact's
     * widened nodes, made strain the points' motion did not have and fed energy (docs/mpm.md) */
    cd_mpm_material mat = m->mat;
    CD_STEP_FOR(n, firstprivate(dt, mat, j) CD_DEV(is_device_ptr(args, flags)))
    for (size_t p = 0; p < n; p++) cd_mpm_checked_stress(*args, p, dt, mat, flags, j);
    m->pending++;
    cd_mpm_step_done(m);
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
