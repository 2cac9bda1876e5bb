/* The material point method solver (solver: mpm; docs/mpm.md): the state
 * as structure-of-arrays columns, its set-up from a config, and the
 * explicit step.  2D plane strain: every extensive quantity is per metre of
 * thickness (mass kg/m, volume m^3/m, force N/m). */
#ifndef CD_MPM_H
#define CD_MPM_H
#include <stddef.h>
#include "config.h"
#include "../kernels/mpm_material.h"

#define CD_MPM_MAX_WALLS 4

/* A rigid plane wall driven at a given velocity. */
typedef struct {
    double px, py;   /* a point of the plane [m] */
    double nx, ny;   /* unit normal into the material [1] */
    double vx, vy;   /* velocity [m/s] */
    double fx, fy;   /* force of the material on the wall in the last step [N/m] */
} cd_mpm_wall;

typedef struct {
    /* material points (n of them) */
    size_t n;
    double *x, *y;             /* position [m] */
    double *vx, *vy;           /* velocity [m/s] */
    double *mass;              /* [kg/m] */
    double *vol;               /* volume [m^3/m] */
    double *half;              /* half the initial side of the point's square [m] */
    double *sxx, *syy, *sxy, *szz; /* Cauchy stress [Pa] */
    double *eps_p;             /* equivalent plastic strain [1] */
    double *f_xx, *f_xy, *f_yx, *f_yy; /* deformation gradient [1] */
    int *particle;             /* particle id */
    /* per-step scratch of the points */
    int *bx, *by;              /* first node of the stencil in x and y */
    double *wx, *wy, *dwx, *dwy; /* 4 weights [1] and gradients [1/m] per point and direction */
    double *ex, *ey;           /* external (wall) force on the point [N/m] */
    size_t *order;             /* point indices sorted by cell (stable) */
    size_t *cell_start;        /* first entry of each cell in order; n_cells + 1 */

    /* background mesh: nodes (i, j) at (ox + i h, oy + j h), i < nx, j < ny */
    int nx, ny;
    double h, ox, oy;          /* cell size and origin [m] */
    double *gm;                /* node mass [kg/m] */
    double *gpx, *gpy;         /* node momentum [kg/s] per metre */
    double *gfx, *gfy;         /* node force [N/m] */
    double *gvx, *gvy;         /* node velocity [m/s] */

    int n_walls;
    cd_mpm_wall walls[CD_MPM_MAX_WALLS];
    double wall_k;             /* wall penalty stiffness per point [N/m per metre] */

    cd_mpm_material mat;
    double dt, time;           /* [s] */
    long long step;
} cd_mpm;

/* Allocates n points and an nx x ny node mesh of cell size h [m] whose
 * node (0, 0) sits at (ox, oy) [m]; every column zeroed, deformation
 * gradients set to I.  0, or -1 with a message. */
int cd_mpm_alloc(cd_mpm *m, size_t n, int nx, int ny, double h, double ox, double oy, char *err, size_t errlen);
void cd_mpm_free(cd_mpm *m);

/* The set-up a config describes (mpm.setup diametral: one disk between two
 * walls, docs/mpm.md), and the time step checked against the explicit
 * scheme's stability limit.  0, or -1 with a message naming the file and
 * key (bad input). */
int cd_mpm_setup(cd_mpm *m, const cd_config *c, char *err, size_t errlen);

/* Largest stable time step estimate [s]: the mesh's wave crossing time
 * h / (c_p + v_max) and the wall penalty's 2 sqrt(m_p / k) (docs/mpm.md). */
double cd_mpm_dt_limit(const cd_mpm *m);

/* One explicit step (MUSL, docs/mpm.md).  0, or -1 with a message when a
 * point leaves the mesh or a value is not finite (the run blew up). */
int cd_mpm_step(cd_mpm *m, char *err, size_t errlen);

/* Sums over the points, in index order [J/m]. */
double cd_mpm_kinetic_energy(const cd_mpm *m);

#endif
