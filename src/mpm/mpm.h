/* The material point method solver (solver: mpm; docs/mpm.md): the state
 * as structure-of-arrays columns, its set-up from a config, and the
 * explicit step.  2D plane strain: every extensive quantity is per metre of
 * thickness (mass kg/m, volume m^3/m, force N/m). */
#ifndef CD_MPM_H
#define CD_MPM_H
#include <stddef.h>
#include "config/config.h"
#include "mpm_material.h"
#include "mpm_step_items.h"

#define CD_MPM_MAX_WALLS 4

/* A rigid plane wall driven at a given velocity. */
typedef struct {
    double px, py; /* a point of the plane [m] */
    double nx, ny; /* unit normal into the material [1] */
    double vx, vy; /* velocity [m/s] */
    double fx, fy; /* force of the material on the wall in the last step [N/m] */
} cd_mpm_wall;

/* Where a step began (time [s], walls' points [m]): where the run goes
 * back to when the checks show that the step failed or must run again. */
typedef struct {
    double time;
    double px[CD_MPM_MAX_WALLS], py[CD_MPM_MAX_WALLS];
} cd_mpm_step_start;

typedef struct {
    /* material points (n of them) */
    size_t n;
    double *x, *y;                     /* position [m] */
    double *vx, *vy;                   /* velocity [m/s] */
    double *mass;                      /* [kg/m] */
    double *vol;                       /* volume [m^3/m] */
    double *half;                      /* half the initial side of the point's square [m] */
    double *sxx, *syy, *sxy, *szz;     /* Cauchy stress [Pa] */
    double *eps_p;                     /* equivalent plastic strain [1] */
    double *f_xx, *f_xy, *f_yx, *f_yy; /* deformation gradient [1] */
    int *particle;                     /* particle (body) id: 0 .. n_bodies-1, the points of a body contiguous */
    /* per-step scratch of the points */
    int *bx, *by;                /* first node of the stencil in x and y (common mesh) */
    double *wx, *wy, *dwx, *dwy; /* 4 weights [1] and gradients [1/m] per point and direction */
    double *ex, *ey;             /* external (wall) force on the point [N/m] */
    cd_ulong *order;             /* point indices sorted by (body, cell), stable */

    /* the common background mesh: nodes (i, j) at (ox + i h, oy + j h), i < nx, j < ny */
    int nx, ny;
    double h, ox, oy; /* cell size and origin [m] */

    /* bodies (docs/mpm.md, "Contact"): each has its own nodes on a window
     * of the common mesh, nodes (i0 + a, j0 + b), a < wnx, b < wny, stored
     * from win_off[k] on; found at the first step from the particle column */
    int n_bodies;     /* 0 until the first step */
    cd_ulong *pfirst; /* points of body k: pfirst[k] .. pfirst[k+1]-1 */
    int *win_i0, *win_j0, *win_nx, *win_ny;
    cd_ulong *win_off;           /* n_bodies + 1 */
    size_t n_bnodes, cap_bnodes; /* body-nodes in use, allocated */
    int *bnode_body;             /* body of each body-node */
    cd_ulong *cell_start;        /* first entry in order of each body-cell (indexed like the body-nodes); + 1 */
    double *gm;                  /* node mass [kg/m] */
    double *gpx, *gpy;           /* node momentum [kg/s] per metre */
    double *gfx, *gfy;           /* node force [N/m], then acceleration [m/s^2] */
    double *gvx, *gvy;           /* node velocity [m/s] */
    double *gnx,
        *gny; /* sum m_p grad N(x_p - x_i) [kg/m^2]: minus the node's mass gradient, the body's outward normal */

    /* contact: common nodes holding two or more bodies (src/mpm/mpm_contact.c) */
    cd_ulong *cn_start;   /* per common node (nx * ny + 1): its body-nodes in cn_entry */
    cd_ulong *cn_entry;   /* body-nodes sorted by common node, bodies ascending (cap_bnodes) */
    cd_ulong *cn_list;    /* common nodes with >= 2 bodies (nx * ny) */
    cd_uint *cn_active;   /* per listed node: bit q set when its q-th body pair is in contact (gap <= contact_gap) */
    size_t n_cn;          /* listed nodes */
    long long *pair_keys; /* scratch: k * n_bodies + l of the pairs in contact */
    size_t cap_pairs;
    double contact_gap; /* two bodies' contact acts from this gap between them on [m] */
    long n_contacts;    /* body pairs in contact (at a node within contact_gap) at the last cd_mpm_contact_count */
    double penetration; /* deepest overlap of two bodies in the last step, from the contact nodes [m]; 0 if none */

    int n_walls;
    cd_mpm_wall walls[CD_MPM_MAX_WALLS];
    double wall_k; /* wall penalty stiffness per point [N/m per metre] */
    double box_h0; /* distance of walls 0 and 1 at start [m] */

    cd_mpm_material mat;
    double pic_fraction; /* PIC share of the points' velocity update, the rest FLIP [1] (docs/mpm.md) */
    double mesh_kinetic; /* sum m_i v_i^2 / 2 of the node velocities after the last step's remap [J/m]: the
                          * points' kinetic energy the mesh sees (docs/mpm.md "FLIP's noise") */
    double dt, time;     /* [s] */
    long long step;
    int observe; /* 1 (the default): the next step computes the sums only output reads (the walls' forces,
                  * the mesh's kinetic energy, the deepest overlap); steps with 0, which the run sets
                  * where it reads nothing, skip them */
    /* the checks where the loops run (kernels/mpm_checks.h): what the host has not looked at yet */
    int pending;              /* steps run since the host last looked (cd_mpm_settle) */
    cd_mpm_step_start *since; /* where each of them began */
    size_t cap_since;
    int sized; /* the body-node columns sized from the first step's count (since the loops started) */

    /* where the step's loops run (src/mpm/mpm_device.c, docs/mpm.md "Work items") */
    int loop_on;                    /* 1 from the first step on (offload builds: the state is on the device) */
    cd_mpm_cols loop_cols;          /* offload builds: the device addresses of the columns */
    size_t loop_cap, loop_cap_keys; /* offload builds: body-nodes allocated there; pair keys allocated */
    /* where the loops run (host memory or the offload device): the checks, as one block
     * (cd_mpm_checks: the host reads it in one copy), and the contact's scratch */
    void *loop_checks;
    cd_int *loop_flags;
    cd_ulong *loop_counts;
    double *loop_reals;
    cd_int *loop_row_n, *loop_rows; /* the common nodes' lists: bodies per mesh row (ny, ny x n_bodies) */
    cd_ulong *loop_blocks;          /* 2 per CD_MPM_CN_BLOCK common nodes */
    double *loop_over;              /* per listed common node: the contact's overlap [m] */
    cd_long *loop_keys;             /* the contact pairs' keys */
    cd_mpm_cols *loop_args;         /* the loops' argument: cd_mpm_loop_cols, copied there when it changes
                                     * (cd_mpm_loop_args_refresh), not at every launch */
    struct cd_mpm_cl *cl;           /* the OpenCL backend's state (src/mpm/mpm_cl.c); NULL: the omp loops */
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

/* Bodies from the particle column (ids 0 .. n_bodies-1, each body's
 * points contiguous, none empty): 0, or -1 with a message.  cd_mpm_step
 * calls it at the first step. */
int cd_mpm_bodies(cd_mpm *m, char *err, size_t errlen);

/* One explicit step (MUSL, docs/mpm.md), only launched: a point leaving
 * the mesh, a value not finite (the run blew up), a crowded common node
 * show at the next cd_mpm_settle, which also makes the columns, counts and
 * observed sums current on the host.  0, or -1 with a message (out of
 * memory, the OpenCL runtime). */
int cd_mpm_step(cd_mpm *m, char *err, size_t errlen);

/* Sums over the points, in index order [J/m]. */
double cd_mpm_kinetic_energy(const cd_mpm *m);
/* Elastic strain energy sum V (sigma : C^-1 : sigma) / 2 (plane strain,
 * sigma_zz included) [J/m]: the elastic energy of an elastic material. */
double cd_mpm_strain_energy(const cd_mpm *m);

/* The packing's measures (set-up packing, docs/mpm.md): packing fraction
 * phi, the points' area over the box's [1]; the applied stress, the bottom
 * wall's force over the box width [Pa] (compression positive); the strain
 * ln(h_i / h) of the box height h [1] (compression positive); the
 * coordination number 2 N_c / N of the body pairs in contact [1]. */
void cd_mpm_packing_measures(const cd_mpm *m, double *phi, double *sigma, double *strain, double *z);

/* Contact (src/mpm/mpm_contact.c, docs/mpm.md "Contact"), steps of
 * cd_mpm_step: lists the common nodes two or more bodies share; after the
 * forces, detects the contacts there, corrects the bodies' node velocities
 * and sets the accelerations to match (CROWDED when more bodies than
 * CD_MPM_NODE_BODIES, kernels/mpm_contact.h, meet at a node). */
void cd_mpm_contact_nodes(cd_mpm *m);
void cd_mpm_contact_correct(cd_mpm *m);
/* n_contacts from the last step's contact bits: called where the count is
 * read (a series row, the progress line), not every step (on an offload
 * device it copies the pair keys to the host and sorts them).  Before the
 * first step, and with one body, n_contacts stays as it is (0).  0, or -1
 * with a message (out of memory). */
int cd_mpm_contact_count(cd_mpm *m, char *err, size_t errlen);
/* Room for n keys in m->pair_keys (0, or -1 with a message). */
int cd_mpm_pair_keys_room(cd_mpm *m, size_t n, char *err, size_t errlen);

/* Shared by the omp loops and the OpenCL backend: the walls as the items
 * see them; the messages of a step that stopped (the host columns synced
 * first; they return -1): point p left the mesh, point p blew up, too many
 * bodies at common node g; the end of a step (walls moved, time and step
 * advanced). */
cd_mpm_item_walls cd_mpm_walls_items(const cd_mpm *m);
int cd_mpm_fail_left_mesh(cd_mpm *m, size_t p, char *err, size_t errlen);
int cd_mpm_fail_blew_up(cd_mpm *m, long long p, char *err, size_t errlen);
int cd_mpm_fail_crowded(cd_mpm *m, size_t g, char *err, size_t errlen);
void cd_mpm_step_done(cd_mpm *m);
/* Where step m->pending begins, recorded before it runs (0, or -1 out of memory). */
int cd_mpm_record_start(cd_mpm *m, char *err, size_t errlen);
/* The checks as read back from where the loops ran (kernels/mpm_checks.h):
 * 0 when no step since the last look failed (the counts and, at an
 * observed step, its sums made m's; the caller brings the columns back);
 * 1 when the body-nodes outgrew their columns (m back at that step: the
 * caller grows them to counts[CD_MPM_COUNT_BNODES] and clears the checks);
 * -1 with the message cd_mpm_step gave before it read nothing (m back at
 * the failing step).  m->pending is 0 after it. */
int cd_mpm_checks_apply(cd_mpm *m, const cd_int *flags, const cd_ulong *counts, const double *reals, char *err,
                        size_t errlen);
/* Room for n body-nodes in the columns the loops work on (host and, in
 * offload builds, device); 0, or -1 with a message. */
int cd_mpm_bnodes_room(cd_mpm *m, size_t n, char *err, size_t errlen);

/* The OpenCL backend (src/mpm/mpm_cl.c, docs/mpm.md "The OpenCL backend"):
 * cd_mpm_cl_open opens the device (request cpu | gpu | auto, NULL: auto)
 * and sets m->cl: from then on cd_mpm_step runs there (cd_mpm_cl_step), the
 * state goes to the device at the first step and cd_mpm_device_sync /
 * _stop bring it back / drop it; cd_mpm_free closes it.  0, or -1 with a
 * message (no OpenCL in this build, no device, the kernels do not
 * build). */
int cd_mpm_cl_open(cd_mpm *m, const char *device, char *err, size_t errlen);
int cd_mpm_cl_step(cd_mpm *m, char *err, size_t errlen);
void cd_mpm_cl_sync(cd_mpm *m);
int cd_mpm_cl_settle(cd_mpm *m, char *err, size_t errlen);
void cd_mpm_cl_close(cd_mpm *m);
/* The device's name, for the run's first line. */
const char *cd_mpm_cl_device(const cd_mpm *m);
/* The last step's contact pair keys into m->pair_keys, their number into *n. */
int cd_mpm_cl_pair_keys(cd_mpm *m, size_t *n, char *err, size_t errlen);
/* The columns and mesh of m's own (host) memory (valid until the
 * body-node columns grow). */
cd_mpm_cols cd_mpm_step_cols(const cd_mpm *m);

/* Where the step's loops run (src/mpm/mpm_device.c).  The default build
 * runs them on host threads over m's columns; offload builds put the state
 * on the offload device at the first step (cd_mpm_device_start, which
 * cd_mpm_step calls), and its host columns are current only after
 * cd_mpm_device_sync.  A host change to the columns after the first step
 * needs cd_mpm_device_stop first.  cd_mpm_loop_cols: the columns the
 * loops work on; cd_mpm_device_reserve / _keys: room there for n
 * body-nodes / contact keys (0, or -1 out of memory). */
int cd_mpm_device_start(cd_mpm *m, char *err, size_t errlen);
void cd_mpm_device_sync(cd_mpm *m);
/* Where the run reads the state (a series row, a snapshot, the progress
 * line): the host reads the checks (one copy) and finds out whether a step
 * since its last look failed: -1 with the message the step itself used to
 * give (step, time and walls back at that step's start), or 1 when the
 * body-nodes outgrew their columns at an earlier step: the columns grown,
 * the state back at that step, and the run steps on from there.  0
 * otherwise: the counts, the observed step's sums and the host columns
 * current (cd_mpm_device_sync). */
int cd_mpm_settle(cd_mpm *m, char *err, size_t errlen);
void cd_mpm_device_stop(cd_mpm *m);
cd_mpm_cols cd_mpm_loop_cols(const cd_mpm *m);
/* The body-node rows the loops' columns hold. */
size_t cd_mpm_loop_rows(const cd_mpm *m);
/* m->loop_args made cd_mpm_loop_cols(m) (after the columns moved). */
void cd_mpm_loop_args_refresh(cd_mpm *m);
int cd_mpm_device_reserve(cd_mpm *m, size_t n);
int cd_mpm_device_keys(cd_mpm *m, size_t n);
/* The common-mesh coordinates (i, j) of body-node t. */
static inline void cd_mpm_bnode_ij(const cd_mpm *m, size_t t, int *i, int *j)
{
    int k = m->bnode_body[t];
    size_t local = t - m->win_off[k];
    *i = m->win_i0[k] + (int)(local % (size_t)m->win_nx[k]);
    *j = m->win_j0[k] + (int)(local / (size_t)m->win_nx[k]);
}

#endif
