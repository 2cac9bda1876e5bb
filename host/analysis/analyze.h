/* Host-side analysis of packings (docs/references.md, Analysis): `capdem analyze RUN.h5`.
 *
 * One snapshot of a run file is read into a cd_an_snapshot, the container
 * and its core region (away from the walls) are worked out into a
 * cd_an_geometry, contacts are grouped into bonds (particle pairs), and each
 * measure adds named scalars and curves to a cd_an_report, which is written
 * into the run file under /analysis and printed as JSON.  The measures,
 * their definitions and the output keys are documented in docs/analysis.md.
 *
 * Files: analyze_cli.c (command, orchestration), analyze_read.c (HDF5 in),
 * analyze_geometry.c (container, core, wall contact points), analyze_cells.c
 * (cell lists), analyze_report.c (result container, histograms),
 * analyze_fit.c (fits), analyze_forces.c (P(f), bond forces),
 * analyze_network.c (bonds, connectivity), analyze_stress.c (particle
 * stresses), analyze_structure.c (G(r), branch vectors), analyze_packing.c
 * (packing fraction, contact density, K_t), analyze_series.c (time series,
 * jamming fit), analyze_write.c (HDF5 and JSON out). */
#ifndef CD_ANALYZE_H
#define CD_ANALYZE_H
#include <stddef.h>
#include <stdint.h>
#include "defs.h"
#include "geom_types.h"
#include "vec3.h"
#include "config/config.h"

/* `capdem analyze RUN.h5 [options]`: argv holds the arguments after
 * "analyze" (the run file and options, in any order).  Returns the process
 * exit status: 0 success, 2 bad input (missing or unreadable file, snapshot
 * out of range, a snapshot without contacts, a requested measure that the
 * file cannot give), 1 other failures. */
int cd_cmd_analyze(int argc, char **argv);

/* ---- results ----------------------------------------------------------- */

typedef struct {
    char name[48];
    double value;
    char unit[24]; /* SI unit, "1" for dimensionless */
} cd_an_scalar;

typedef struct {
    char name[48];
    char text[640];
} cd_an_text;

/* A table: rows x cols doubles, row-major; columns and units are comma
 * separated, one entry per column. */
typedef struct {
    char name[48];
    size_t rows;
    int cols;
    double *data;
    char columns[512];
    char units[512];
} cd_an_curve;

typedef struct {
    char name[48];
    int n_scalars, n_texts, n_curves;
    cd_an_scalar *scalars;
    cd_an_text *texts;
    cd_an_curve *curves;
} cd_an_group;

typedef struct {
    int n_groups;
    cd_an_group *groups;
    long long step; /* of the analysed snapshot */
    double time;    /* [s] */
    int snapshot, n_snapshots;
} cd_an_report;

/* Group of that name, created when missing (NULL when out of memory). */
cd_an_group *cd_an_group_get(cd_an_report *r, const char *name);
/* Existing group or NULL. */
const cd_an_group *cd_an_group_find(const cd_an_report *r, const char *name);
void cd_an_put(cd_an_group *g, const char *name, double value, const char *unit);
void cd_an_put_text(cd_an_group *g, const char *name, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* New zeroed table (rows x number of columns); NULL when out of memory. */
double *cd_an_put_curve(cd_an_group *g, const char *name, size_t rows, const char *columns, const char *units);
/* Value of a scalar, NAN when absent. */
double cd_an_value(const cd_an_report *r, const char *group, const char *name);
const cd_an_curve *cd_an_curve_find(const cd_an_report *r, const char *group, const char *name);
void cd_an_report_free(cd_an_report *r);

/* Histogram of x[0..n) in nb bins of width w from lo: counts[b] (as doubles),
 * *under and *over the samples outside (either may be NULL). */
void cd_an_histogram(const double *x, size_t n, double lo, double w, int nb, double *counts, size_t *under,
                     size_t *over);

/* ---- one snapshot ------------------------------------------------------ */

typedef struct {
    char kind[32];          /* sphere | rod | cross | hexapod | segments */
    double volume;          /* of the union of the arms at scale 1 [m^3] */
    double tip_length;      /* L of the longest arm [m] */
    double bounding_radius; /* [m] */
    int n_arms;
    double arms[CD_MAX_ARMS][7]; /* body frame a (3), b (3), radius [m] */
    double area2d;               /* slice z = 0 of the body frame [m^2] (2D packing fraction), 0 until computed */
} cd_an_shape;

typedef struct {
    char path[CD_PATH_MAX];
    int snapshot, n_snapshots;
    long long step;
    double time;   /* [s] */
    cd_config cfg; /* the run's config as echoed in the file */
    int cfg_ok;    /* 0: the echoed config did not parse; cfg holds defaults */
    int n_shapes;
    cd_an_shape *shapes;
    size_t n;       /* particles */
    cd_vec3 *pos;   /* centres [m] */
    double *scale;  /* length scale factors [1] */
    int32_t *shape; /* shape index */
    size_t n_prims;
    cd_vec3 *prim_a, *prim_b; /* world axis ends [m] */
    double *prim_radius;      /* [m] */
    int32_t *prim_particle;
    size_t nc;        /* particle-particle contacts of the snapshot */
    int32_t *ci, *cj; /* particles; the normal points from ci to cj */
    double *fn;       /* normal force magnitude [N] */
    cd_vec3 *normal;  /* unit normal [1] */
    cd_vec3 *ft;      /* tangential force on cj [N] */
    cd_vec3 *point;   /* contact point [m] */
    size_t nw;        /* primitive-wall contacts */
    int32_t *w_prim, *w_wall;
    cd_vec3 *w_force; /* force of the wall on the primitive [N] */
    cd_vec3 *w_point; /* contact point [m] (recomputed, see cd_an_wall_points) */
    int n_walls;
    cd_wall *walls; /* walls at the snapshot */
    int n_control;  /* protocol state of the snapshot (/walls/control, docs/protocols.md), 0 if absent */
    double control[64];
} cd_an_snapshot;

/* Reads snapshot k of path (k < 0 counts from the end: -1 is the last).
 * Returns 0, 2 for bad input (message in err names the file and what is
 * missing), 1 for other failures. */
int cd_an_read_snapshot(const char *path, int k, cd_an_snapshot *s, char *err, size_t errlen);
/* Allocates the arrays for n particles, P primitives, nc contacts, nw wall
 * contacts and W walls (zeroed), for tests that build a snapshot by hand. */
int cd_an_snapshot_alloc(cd_an_snapshot *s, size_t n, size_t P, size_t nc, size_t nw, int W);
void cd_an_snapshot_free(cd_an_snapshot *s);
/* Fills s->w_point from the primitive and wall geometry (kernels/walls.h):
 * the run file keeps the wall force and torque but not the point. */
void cd_an_wall_points(cd_an_snapshot *s);

/* ---- container and core region ----------------------------------------- */

typedef enum { CD_AN_FREE, CD_AN_BOX2D, CD_AN_PSEUDO2D, CD_AN_BOX3D, CD_AN_CYLINDER, CD_AN_BALL } cd_an_kind;

typedef struct {
    cd_an_kind kind;
    int dim;                        /* 2 for BOX2D (x-y plane), else 3 */
    double L;                       /* reference length: tip-to-tip length of the largest shape [m] */
    double lo[3], hi[3];            /* box extents, hi[1] the effective top; cylinder: lo[1] floor, hi[1] top [m] */
    cd_vec3 centre;                 /* cylinder: point on the axis (axis along y); ball: centre [m] */
    double radius;                  /* cylinder or ball radius [m] */
    double top_wall;                /* lowest plane wall facing down (lid or piston), HUGE_VAL if none [m] */
    double top_particles;           /* highest point of any particle [m] */
    double margin_side, margin_end; /* core region: distance kept from side walls and from floor/top [m] */
    double volume;                  /* container (2D: area [m^2]) [m^3] */
    double core_volume;             /* core region (2D: area [m^2]) [m^3] */
    double plane_z;                 /* BOX2D: z of the particles' plane [m] */
    char note[256];                 /* why there is no container or no core, "" otherwise */
} cd_an_geometry;

/* Margins in units of L; negative: the defaults of docs/references.md, Analysis (10 L from every
 * wall in 2D and pseudo-2D; 3 L from side walls and 10 L from floor and top
 * in 3D; 3 L from the ball).  Returns 0 (a missing container is recorded in
 * g->note, volume 0). */
int cd_an_geometry_setup(const cd_an_snapshot *s, double margin_side_L, double margin_end_L, cd_an_geometry *g);
/* 1 when x lies in the core region. */
int cd_an_in_core(const cd_an_geometry *g, cd_vec3 x);
const char *cd_an_kind_name(cd_an_kind k);

/* ---- cell lists -------------------------------------------------------- */

typedef struct {
    int dim;      /* 2: cells in x-y only */
    double lo[3]; /* [m] */
    double cs;    /* cell size [m] */
    int n[3];
    size_t ncell;
    size_t *start; /* ncell + 1 */
    size_t *item;  /* point indices sorted by cell */
    cd_vec3 *x;    /* the points in that order: a row of cells along x is one contiguous range */
} cd_an_cells;

/* Cells of size at least cs over the points (grown when the box would need
 * more than about 2 cells per point).  Returns 0 or -1 (out of memory). */
int cd_an_cells_build(cd_an_cells *c, const cd_vec3 *x, size_t n, double cs, int dim);
/* Items of the cells kx0..kx1 (clipped to the grid) of row (ky, kz): the
 * range [*t0, *t1) of item / x; empty when the row is outside. */
void cd_an_cells_row(const cd_an_cells *c, int kx0, int kx1, int ky, int kz, size_t *t0, size_t *t1);
/* Cell coordinates of x, clamped to the grid. */
void cd_an_cells_coord(const cd_an_cells *c, cd_vec3 x, int ijk[3]);
void cd_an_cells_free(cd_an_cells *c);

/* ---- bonds (pairs of touching particles) -------------------------------- */

typedef struct {
    size_t n;       /* bonds */
    int32_t *i, *j; /* the two particles, i < j */
    int32_t *k;     /* valence: number of contacts of the bond */
    cd_vec3 *force; /* vector sum of the contact forces on j [N] */
    size_t *first;  /* contacts of bond b: order[first[b] .. first[b] + k[b]) */
    size_t *order;
} cd_an_bonds;

/* Groups the contacts of s into bonds in O(contacts).  Returns 0, 2 (a
 * contact names a particle out of range or the same particle twice), 1
 * (out of memory). */
int cd_an_bonds_build(const cd_an_snapshot *s, cd_an_bonds *b, char *err, size_t errlen);
void cd_an_bonds_free(cd_an_bonds *b);

/* ---- options and measures ---------------------------------------------- */

enum {
    CD_AN_FORCES = 1u << 0,     /* P(f), tail fit, Mueth fit */
    CD_AN_BONDS = 1u << 1,      /* bond-force PDF, cascade fit, F_k */
    CD_AN_STRESS = 1u << 2,     /* particle stresses, P(i) */
    CD_AN_RDF = 1u << 3,        /* G(r), rho(r) */
    CD_AN_BRANCH = 1u << 4,     /* branch vectors, interlocking */
    CD_AN_NETWORK = 1u << 5,    /* Z, Z_c, valence, P_c, P_b, P_k */
    CD_AN_PACKING = 1u << 6,    /* packing fractions, contact density */
    CD_AN_MODULUS = 1u << 7,    /* effective-medium K_t */
    CD_AN_COMPACTION = 1u << 8, /* time series: compaction curve */
    CD_AN_JAMMING = 1u << 9,    /* (Z - Z_c) ~ (Phi - Phi_c)^(1/2) fit */
    CD_AN_ALL = (1u << 10) - 1,
    CD_AN_MPM = 1u << 10 /* run files of solver mpm (their only measure; not in CD_AN_ALL) */
};

typedef struct {
    int snapshot;                      /* index, < 0 from the end (-1: last) */
    unsigned measures;                 /* CD_AN_* bits */
    int strict;                        /* 1: a measure that cannot be computed fails the run (exit 2) */
    double margin_side, margin_end;    /* core margins [L], < 0: defaults of docs/references.md, Analysis */
    double rdf_max, rdf_bin;           /* G(r) range and bin [L], <= 0: defaults */
    long mc_points;                    /* Monte Carlo points for the core packing fraction */
    int write;                         /* 1: write /analysis into the run file */
    int json;                          /* 1: JSON on stdout instead of the text summary */
    int quiet;                         /* 1: no text summary, no warnings on stderr */
    int timings;                       /* 1: wall-clock time of each phase on stderr */
    const char *phi_series, *z_series; /* observables for the jamming fit (NULL: known names) */
    double phi_c;                      /* mpm: Phi_c of the fits of eqs. (5), (11); 0: eq. (17)'s */
    int elastic_model_set;             /* mpm: 1: elastic_model given (--elastic-model) */
    double elastic_model[3];           /* mpm: f_E, f_G, c1 of eq. (10)'s elastic part (default: the paper's) */
} cd_an_options;

void cd_an_options_defaults(cd_an_options *o);
/* Measure name (forces, bonds, ...) to its bit, 0 when unknown. */
unsigned cd_an_measure_bit(const char *name);

/* Everything a measure gets.  A measure returns 0, 2 when the snapshot
 * lacks what it needs (reason in err), 1 on other failures. */
typedef struct {
    const cd_an_snapshot *s;
    const cd_an_geometry *g;
    const cd_an_bonds *b;
    const cd_an_options *opt;
    double mean_fn; /* mean normal contact force <F_n> [N] */
} cd_an_input;

int cd_an_forces(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen);
int cd_an_bond_forces(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen);
int cd_an_stress(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen);
int cd_an_rdf(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen);
int cd_an_branch(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen);
int cd_an_network(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen);
int cd_an_packing(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen);
int cd_an_modulus(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen);
/* Time series of the whole run (/observables): compaction curve, jamming fit. */
int cd_an_compaction(const char *path, const cd_an_snapshot *s, const cd_an_geometry *g, const cd_an_options *opt,
                     cd_an_report *r, char *err, size_t errlen);
int cd_an_jamming(const char *path, const cd_an_options *opt, cd_an_report *r, char *err, size_t errlen);

/* Particle stress tensors sigma_p = (1/V_p) sum_c F_c (x) r_c, row-major
 * sigma[9 p + 3 a + b] = (1/V) sum F_a r_b [Pa], for every particle (0 for
 * particles without contact); ncontacts[p] counts its contacts, wall contacts
 * included.  Needs s->w_point.  Returns 0 or -1 (out of memory). */
int cd_an_particle_stress(const cd_an_snapshot *s, double *sigma, int32_t *ncontacts);
/* Volume of particle p: shape volume x scale^3 [m^3]. */
double cd_an_particle_volume(const cd_an_snapshot *s, size_t p);

/* The whole analysis of one file into rep (no output).  Returns the exit
 * status as cd_cmd_analyze. */
int cd_analyze_file(const char *path, const cd_an_options *opt, cd_an_report *rep, char *err, size_t errlen);
/* Writes rep under /analysis/snapshot_<step> (and /analysis/compaction)
 * of path, replacing what an earlier analysis wrote.  0 or -1. */
int cd_an_write_h5(const char *path, const cd_an_report *rep, char *err, size_t errlen);
/* Prints rep as one JSON object to stream (a FILE *).  0 or -1. */
int cd_an_print_json(const cd_an_report *rep, const char *path, void *stream);

/* ---- fits (analyze_fit.c) ----------------------------------------------- */

/* Exponential tail P(f) ~ exp(-k f) above fmin. */
typedef struct {
    double k, lo, hi; /* estimate and 95% interval [1] */
    size_t n;         /* samples (MLE) or bins (WLS) used */
} cd_an_exp_fit;

/* Maximum likelihood on the samples f > fmin: f - fmin is exponential with
 * rate k, k = n / sum (f - fmin), exact interval from 2 k sum ~ chi^2(2n).
 * Returns 0, or -1 with fewer than 2 samples in the tail. */
int cd_an_fit_exp_tail_mle(const double *f, size_t n, double fmin, cd_an_exp_fit *out);
/* Weighted least squares of log P on the non-empty bins with centre > fmin
 * (weights = counts, the inverse variance of log of a Poisson count);
 * interval from Student's t with bins - 2 degrees of freedom. */
int cd_an_fit_exp_tail_wls(const double *centre, const double *counts, int nb, double width, double total, double fmin,
                           cd_an_exp_fit *out);

/* Nonlinear least-squares result (up to 4 parameters). */
typedef struct {
    int np;
    double p[4], se[4], lo[4], hi[4]; /* estimate, standard error, 95% interval */
    double chi2;                      /* weighted sum of squared residuals */
    int dof;
    size_t n; /* points used */
} cd_an_nlfit;

/* Puts fit parameter k as names[k], with its 95% interval as
 * names[k]_lo and names[k]_hi, for k < f->np (all dimensionless). */
void cd_an_put_fit(cd_an_group *g, const char *const *names, const cd_an_nlfit *f);

/* Mueth's P = a (1 - b exp(-f^2)) exp(-beta f) on a density histogram
 * (bin centres, counts, total samples, bin width); p = {a, b, beta}. */
int cd_an_fit_mueth(const double *centre, const double *counts, int nb, double width, double total, double beta_guess,
                    cd_an_nlfit *out);

/* Cascade model (Tran et al. 2024, eq. 12-13) with the force normalised to mean 1. */
double cd_an_cascade_beta(double gamma);
double cd_an_cascade_pdf(double f, double gamma);
typedef struct {
    double gamma, lo, hi; /* maximum likelihood and 95% profile-likelihood interval [1] */
    double beta, beta_lo, beta_hi;
    size_t n;
} cd_an_cascade_fit;
/* Maximum likelihood of gamma on samples f (mean 1).  0, or -1 with fewer
 * than 10 samples. */
int cd_an_fit_cascade(const double *f, size_t n, cd_an_cascade_fit *out);
/* Z = Z_c + A sqrt(Phi - Phi_c) on the jammed part of a (Phi, Z) series
 * (points with Z NaN are left out); p = {Phi_c, Z_c, A}.  0; -1 fewer than
 * 5 jammed points; -2 no convergence; -3 the data do not resolve the law
 * (A <= 0, or Phi_c above the data or more than their range below). */
int cd_an_fit_jamming(const double *phi, const double *z, size_t n, cd_an_nlfit *out);

/* Ordinary least squares y = intercept + slope x: the slope's standard
 * error and 95% interval, the intercept's 95% interval (Student's t, n - 2
 * degrees of freedom).  0, or -1 with fewer than 3 points or all x equal. */
typedef struct {
    double slope, intercept, se, lo, hi, intercept_lo, intercept_hi;
    size_t n;
    int dof;
} cd_an_linfit;
int cd_an_fit_line(const double *x, const double *y, size_t n, cd_an_linfit *out);

/* The material point method (host/analysis/analyze_mpm.c, docs/mpm.md
 * "Analysis").  The largest curvature [1/m] of the convex hull of the n
 * points xy (x, y pairs, reordered) at the scale `scale` [m]: the largest
 * turning of its tangent over an arc of 2 scale, over 2 scale (a circle:
 * 1/R; a corner of angle theta alone in the arc: (pi - theta) / (2 scale));
 * NAN with fewer than 3 points or a perimeter under 4 scale. */
double cd_an_max_boundary_curvature(double *xy, size_t n, double scale);
/* The convex hull of the n points xy (x, y pairs, reordered), counter-
 * clockwise without repeating its first point, into hull (room for 2 n + 2
 * points); returns its vertex count. */
size_t cd_an_convex_hull(double *xy, size_t n, double *hull);
/* The outline of a particle's points a .. b-1 as the analysis sees it: the
 * corners of each point's parallelogram x_p + F_p [-l/2, l/2]^2 (l the
 * point's initial side sqrt(V / det F)), 4 (b - a) of them into xy (x, y
 * pairs); x (n, 2) [m], v (n) [m^3/m], F (n, 4) (xx, xy, yx, yy) are one
 * snapshot's.  Returns the particle's initial area sum V / det F [m^2/m].
 * `capdem analyze` takes kappa from their hull, `capdem export` draws it. */
double cd_an_mpm_corners(const double *x, const double *v, const double *F, size_t a, size_t b, double *xy);
/* The measures and fits of an mpm packing run file (every committed
 * snapshot; opt->snapshot picks the one reported alone).  0, 2 when the
 * file lacks what they need (reason in err), 1 on other failures. */
int cd_an_mpm(const char *path, const cd_an_options *opt, cd_an_report *r, char *err, size_t errlen);

/* Reads rows [0, rows) of dataset name (rank 1..3, doubles) of the open
 * file f (path: for messages) into a new buffer of `per_row` values a
 * row; NULL with a message when it is missing or shaped otherwise.  (An
 * hid_t is an int64_t.) */
double *cd_an_mpm_read_rows(int64_t f, const char *path, const char *name, size_t rows, size_t per_row, char *err,
                            size_t errlen);
/* A diametral run (set-up diametral: two walls, no packing series)? */
int cd_an_mpm_is_disk(const char *path);
/* The paper's Fig. 1 measures of a diametral run (analyze_mpm_disk.c):
 * the group mpm_disk.  0, 2 (reason in err), 1. */
int cd_an_mpm_disk(const char *path, const cd_an_options *opt, cd_an_report *r, char *err, size_t errlen);

/* The paper's compaction models beyond jamming (analyze_mpm_models.c):
 * the particle material and the models' parameters. */
typedef struct {
    double E, nu, sigma_y, H; /* Young's modulus [Pa], Poisson's ratio [1], yield stress and hardening [Pa] */
    double f_E, f_G, p_c;     /* eqs. (8), (9) (and (15), (16): the plastic ones equal, as in the paper) [1] */
    double c1, c2;            /* eqs. (6), (13) [1] */
    double alpha, phi_c;      /* eq. (11) [1] */
} cd_an_mpm_model;
/* Eqs. (7)-(9): M_eff [Pa] of a material (E [Pa], nu) at packing fraction
 * phi; 0 at or below Phi = 1 - p_c. */
double cd_an_mpm_m_eff(double E, double nu, double f_E, double f_G, double p_c, double phi);
/* Eq. (6), elastic [Pa], compression positive, at (Phi, Z). */
double cd_an_mpm_sigma_elastic(const cd_an_mpm_model *m, double phi, double z);
/* Eqs. (10), (11), (13)-(16), plastic [Pa]: E_p = E H / (E + H). */
double cd_an_mpm_sigma_plastic(const cd_an_mpm_model *m, double phi, double z);
/* Fits m's f_E, f_G, c1 (from m's values) of eq. (6) to n states (phi,
 * z, sigma [Pa]); out->p = {f_E, f_G, c1}, intervals from Student's t.
 * 0, or -1 (too few states, no convergence, a singular M_eff). */
int cd_an_mpm_fit_eq6(const double *phi, const double *z, const double *sigma, size_t n, cd_an_mpm_model *m,
                      cd_an_nlfit *out);
/* Fits m's alpha of eq. (10) (sigma linear in alpha), the rest of m fixed;
 * its 95 % interval.  0, or -1. */
int cd_an_mpm_fit_eq10(const double *phi, const double *z, const double *sigma, size_t n, cd_an_mpm_model *m,
                       double *alpha_lo, double *alpha_hi);
/* The groups mpm_eq6 (elastic material: f_E, f_G, c1 fitted, p_c = 1 -
 * Phi_c, c2 = -ln Phi_c) and mpm_eq10 (plastic: alpha fitted, the elastic
 * parameters from `elastic` = {f_E, f_G, c1} or else the paper's), each
 * with its curve against the series rows beyond Phi_c = pc and the paper's
 * parameters' curve; material: E, nu, sigma_y, H. */
void cd_an_mpm_models(cd_an_report *r, const cd_an_mpm_model *material, int plastic, const double *elastic, double pc,
                      const double *phi, const double *z, const double *sigma, const double *strain, size_t rows);

#endif
