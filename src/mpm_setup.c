/* The material point method's set-ups from a config (docs/mpm.md):
 * mpm.setup diametral, the paper's section 3: one disk between a fixed
 * bottom wall and a top wall moving down at mpm.wall_speed. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "mpm.h"

/* Whether a point centred at (x, y) [m] from the disk's centre belongs to
 * the disk of radius r [m]. */
static int in_disk(double x, double y, double r) { return x * x + y * y < r * r; }

int cd_mpm_setup(cd_mpm *m, const cd_config *c, char *err, size_t errlen)
{
    double D = c->mpm_diameter, R = 0.5 * D;           /* [m] */
    double h = D / c->mpm_cells;                        /* cell size [m] */
    int pps = c->mpm_points_per_side;
    double l = h / pps;                                 /* point spacing [m] */
    /* The disk's centre sits on a node, the points on a lattice of spacing l
     * symmetric about it, so the discretised disk is mirror-symmetric. */
    int kr = (int)ceil(R / l) + 1;                      /* lattice half-width in points */
    size_t n = 0;
    for (int j = -kr; j < kr; j++)
        for (int i = -kr; i < kr; i++) n += in_disk((i + 0.5) * l, (j + 0.5) * l, R);
    /* mesh: the walls and the disk with room to bulge sideways (half a
     * diameter each side) and three cells beyond everything, so that no
     * stencil reaches the edge */
    int cells_x = (int)ceil((R + 0.5 * D) / h) + 3;    /* cells from the centre to each side */
    int cells_y = (int)ceil(R / h) + 3;
    int nx = 2 * cells_x + 1, ny = 2 * cells_y + 1;
    double cx = 0, cy = R;                              /* disk centre [m]; bottom wall at y = 0 */
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
    m->mat = cd_mpm_material_make(c->mpm_young, c->mpm_poisson, c->mpm_model == 1 ? c->mpm_yield : -1,
                                  c->mpm_model == 1 ? c->mpm_hardening : 0);
    m->wall_k = c->mpm_wall_stiffness * c->mpm_young;
    m->n_walls = 2;
    m->walls[0] = (cd_mpm_wall){0, cy - R, 0, 1, 0, 0, 0, 0};                   /* bottom, fixed */
    m->walls[1] = (cd_mpm_wall){0, cy + R, 0, -1, 0, -c->mpm_wall_speed, 0, 0}; /* top, moving down */
    m->dt = c->dt;
    double lim = cd_mpm_dt_limit(m);
    if (c->dt > lim && !c->force_dt) {
        snprintf(err, errlen, "%s: run.dt = %g: above the explicit step's stability limit %.4g s (min of the mesh's wave "
                 "crossing time h / (c_p + v_wall) and the wall penalty's 2 sqrt(m_p / k), docs/mpm.md); expected "
                 "run.dt <= %.4g s, or run.force_dt: true", c->source_path, c->dt, lim, lim);
        cd_mpm_free(m);
        return -1;
    }
    return 0;
}
