/* The material point method's set-ups from a config (docs/mpm.md), the
 * paper's section 3: mpm.setup diametral, one disk between a fixed bottom
 * wall and a top wall moving down at mpm.wall_speed; mpm.setup packing,
 * the disks of a DEM run file in a box whose top wall moves down. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "mpm/mpm.h"
#include "mpm/mpm_packing.h"

/* Whether a point centred at (x, y) [m] from the disk's centre belongs to
 * the disk of radius r [m]. */
static int in_disk(double x, double y, double r) { return x * x + y * y < r * r; }

static int setup_diametral(cd_mpm *m, const cd_config *c, char *err, size_t errlen)
{
    double D = c->mpm_diameter, R = 0.5 * D; /* [m] */
    double h = D / c->mpm_cells;             /* cell size [m] */
    int pps = c->mpm_points_per_side;
    double l = h / pps; /* point spacing [m] */
    /* The disk's centre sits on a node, the points on a lattice of spacing l
     * symmetric about it, so the discretised disk is mirror-symmetric. */
    int kr = (int)ceil(R / l) + 1; /* lattice half-width in points */
    size_t n = 0;
    for (int j = -kr; j < kr; j++)
        for (int i = -kr; i < kr; i++) n += in_disk((i + 0.5) * l, (j + 0.5) * l, R);
    /* mesh: the walls and the disk with room to bulge sideways (half a
     * diameter each side) and three cells beyond everything, so that no
     * stencil reaches the edge */
    int cells_x = (int)ceil((R + 0.5 * D) / h) + 3; /* cells from the centre to each side */
    int cells_y = (int)ceil(R / h) + 3;
    int nx = 2 * cells_x + 1, ny = 2 * cells_y + 1;
    double cx = 0, cy = R; /* disk centre [m]; bottom wall at y = 0 */
    if (cd_mpm_alloc(m, n, nx, ny, h, cx - cells_x * h, cy - cells_y * h, err, errlen)) return -1;
    size_t p = 0;
    for (int j = -kr; j < kr; j++)
        for (int i = -kr; i < kr; i++) {
            double x = (i + 0.5) * l, y = (j + 0.5) * l;
            if (!in_disk(x, y, R)) continue;
            m->x[p] = cx + x;
            m->y[p] = cy + y;
            m->vol[p] = l * l;
            m->mass[p] = c->mpm_density * l * l;
            m->half[p] = 0.5 * l;
            m->particle[p] = 0;
            p++;
        }
    m->n_walls = 2;
    m->walls[0] = (cd_mpm_wall){0, cy - R, 0, 1, 0, 0, 0, 0};                   /* bottom, fixed */
    m->walls[1] = (cd_mpm_wall){0, cy + R, 0, -1, 0, -c->mpm_wall_speed, 0, 0}; /* top, moving down */
    m->box_h0 = D;
    return 0;
}

/* Whether lattice site (x, y) [m] inside disk k goes to k: to the disk of
 * least power |x - c|^2 - r^2 among those holding it (the DEM's small
 * overlaps), the lower index on a tie. */
static int site_owner_is(const cd_mpm_packing *pk, const int *near, int n_near, size_t k, double x, double y)
{
    double pk_ = (x - pk->x[k]) * (x - pk->x[k]) + (y - pk->y[k]) * (y - pk->y[k]) - pk->r[k] * pk->r[k];
    for (int q = 0; q < n_near; q++) {
        size_t j = (size_t)near[q];
        double pj = (x - pk->x[j]) * (x - pk->x[j]) + (y - pk->y[j]) * (y - pk->y[j]) - pk->r[j] * pk->r[j];
        if (pj < 0 && (pj < pk_ || (pj == pk_ && j < k))) return 0;
    }
    return 1;
}

/* The packing: each disk of the DEM run file filled with the points of a
 * lattice of spacing l = h / points_per_cell_side aligned with the common
 * mesh (a point kept when its centre is inside the disk), h the smallest
 * diameter / cells_per_diameter; the box is the packing's bounding box:
 * bottom wall (0) and side walls (2 left, 3 right) fixed, top wall (1)
 * moving down at mpm.wall_speed. */
static int setup_packing(cd_mpm *m, const cd_config *c, char *err, size_t errlen)
{
    cd_mpm_packing pk;
    if (cd_mpm_read_packing(c->mpm_packing, c->source_path, &pk, err, errlen)) return -1;
    double rmin = INFINITY, left = INFINITY, right = -INFINITY, bottom = INFINITY, top = -INFINITY; /* [m] */
    for (size_t k = 0; k < pk.n; k++) {
        rmin = fmin(rmin, pk.r[k]);
        left = fmin(left, pk.x[k] - pk.r[k]);
        right = fmax(right, pk.x[k] + pk.r[k]);
        bottom = fmin(bottom, pk.y[k] - pk.r[k]);
        top = fmax(top, pk.y[k] + pk.r[k]);
    }
    double h = 2 * rmin / c->mpm_cells, l = h / c->mpm_points_per_side; /* [m] */
    /* the mesh: the box and four cells around it, so that no stencil of a point near a wall reaches the edge */
    int margin = 4, nx = (int)ceil((right - left) / h) + 2 * margin + 1,
        ny = (int)ceil((top - bottom) / h) + 2 * margin + 1;
    double ox = left - margin * h, oy = bottom - margin * h;
    /* the disks that overlap disk k (the DEM's contacts), for the sites two disks hold */
    enum { NEAR = 16 }; /* a disk of a DEM packing touches at most a few others */
    int *near = malloc(pk.n * NEAR * sizeof(int)), *n_near = calloc(pk.n, sizeof(int));
    if (!near || !n_near) {
        free(near);
        free(n_near);
        cd_mpm_packing_free(&pk);
        snprintf(err, errlen, "out of memory for %zu disks", pk.n);
        return -1;
    }
    for (size_t k = 0; k < pk.n; k++)
        for (size_t j = 0; j < pk.n; j++)
            if (j != k && hypot(pk.x[k] - pk.x[j], pk.y[k] - pk.y[j]) < pk.r[k] + pk.r[j]) {
                if (n_near[k] == NEAR) {
                    snprintf(err, errlen,
                             "%s: mpm.packing = %s: disk %zu overlaps more than %d others; expected a "
                             "packing of disks that touch",
                             c->source_path, c->mpm_packing, k, NEAR);
                    free(near);
                    free(n_near);
                    cd_mpm_packing_free(&pk);
                    return -1;
                }
                near[k * NEAR + (size_t)n_near[k]++] = (int)j;
            }
    size_t n = 0;
    for (int pass = 0; pass < 2; pass++) { /* count, then fill */
        size_t p = 0;
        for (size_t k = 0; k < pk.n; k++) {
            long i0 = (long)floor((pk.x[k] - pk.r[k] - ox) / l) - 1, i1 = (long)ceil((pk.x[k] + pk.r[k] - ox) / l) + 1;
            long j0 = (long)floor((pk.y[k] - pk.r[k] - oy) / l) - 1, j1 = (long)ceil((pk.y[k] + pk.r[k] - oy) / l) + 1;
            size_t first = p;
            for (long j = j0; j <= j1; j++)
                for (long i = i0; i <= i1; i++) {
                    double x = ox + (i + 0.5) * l, y = oy + (j + 0.5) * l;
                    if ((x - pk.x[k]) * (x - pk.x[k]) + (y - pk.y[k]) * (y - pk.y[k]) >= pk.r[k] * pk.r[k] ||
                        !site_owner_is(&pk, near + k * NEAR, n_near[k], k, x, y))
                        continue;
                    if (pass == 1) {
                        m->x[p] = x;
                        m->y[p] = y;
                        m->vol[p] = l * l;
                        m->mass[p] = c->mpm_density * l * l;
                        m->half[p] = 0.5 * l;
                        m->particle[p] = (int)k;
                    }
                    p++;
                }
            if (p == first) {
                snprintf(err, errlen,
                         "%s: mpm.cells_per_diameter = %d: disk %zu of %s (radius %g m) holds no material "
                         "point; expected more cells",
                         c->source_path, c->mpm_cells, k, c->mpm_packing, pk.r[k]);
                if (pass == 1) cd_mpm_free(m);
                free(near);
                free(n_near);
                cd_mpm_packing_free(&pk);
                return -1;
            }
        }
        if (pass == 0) {
            n = p;
            if (cd_mpm_alloc(m, n, nx, ny, h, ox, oy, err, errlen)) {
                free(near);
                free(n_near);
                cd_mpm_packing_free(&pk);
                return -1;
            }
        }
    }
    free(near);
    free(n_near);
    m->n_walls = 4;
    m->walls[0] = (cd_mpm_wall){0, bottom, 0, 1, 0, 0, 0, 0};                /* bottom, fixed */
    m->walls[1] = (cd_mpm_wall){0, top, 0, -1, 0, -c->mpm_wall_speed, 0, 0}; /* top, moving down */
    m->walls[2] = (cd_mpm_wall){left, 0, 1, 0, 0, 0, 0, 0};                  /* left, fixed */
    m->walls[3] = (cd_mpm_wall){right, 0, -1, 0, 0, 0, 0, 0};                /* right, fixed */
    m->box_h0 = top - bottom;
    cd_mpm_packing_free(&pk);
    return 0;
}

int cd_mpm_setup(cd_mpm *m, const cd_config *c, char *err, size_t errlen)
{
    if (c->mpm_setup == 1 ? setup_packing(m, c, err, errlen) : setup_diametral(m, c, err, errlen)) return -1;
    m->mat = cd_mpm_material_make(c->mpm_young, c->mpm_poisson, c->mpm_model == 1 ? c->mpm_yield : -1,
                                  c->mpm_model == 1 ? c->mpm_hardening : 0);
    m->wall_k = c->mpm_wall_stiffness * c->mpm_young;
    m->contact_gap = c->mpm_contact_gap * m->h;
    m->pic_fraction = c->mpm_pic_fraction;
    m->dt = c->dt;
    double lim = cd_mpm_dt_limit(m);
    if (c->dt > lim && !c->force_dt) {
        snprintf(err, errlen,
                 "%s: run.dt = %g: above the explicit step's stability limit %.4g s (min of the mesh's wave "
                 "crossing time h / (c_p + v_wall) and the wall penalty's 2 sqrt(m_p / k), docs/mpm.md); expected "
                 "run.dt <= %.4g s, or run.force_dt: true",
                 c->source_path, c->dt, lim, lim);
        cd_mpm_free(m);
        return -1;
    }
    return 0;
}
