/* Private to shapes_numeric.c, shapes_numeric_geom.c and
 * shapes_numeric_quad.c: the numerical mass properties of a union of
 * capsules (method in shapes_numeric.c's header comment and
 * docs/shapes.md).
 *   shapes_numeric_geom.c  capsule geometry: line and circle crossings with
 *                          a capsule, polynomial roots, trigonometric
 *                          antiderivatives, segment distances
 *   shapes_numeric_quad.c  piecewise adaptive 1-D quadrature with location
 *                          of the changes of signature (pw_*)
 *   shapes_numeric.c       lateral and cap surface evaluators, the driver
 *                          cd_shapes_union_numeric */
#ifndef CD_SHAPES_NUMERIC_INTERNAL_H
#define CD_SHAPES_NUMERIC_INTERNAL_H
#include "shapes/shapes.h"
#include <stdint.h>

#define NUM_PI 3.14159265358979323846
#define NCOMP  11 /* area, V, 3 first moments, 6 second moments */
/* Signature samples per surface piece in the two passes.  A change narrower
 * than the spacing can slip between samples and quadrature nodes; with 256
 * and 1024 the passes miss different things, so such a miss shows up in the
 * reported error (seen at 1e-7 to 1e-6 for 16 random arms, never for the
 * named shapes). */
#define NS_COARSE 256
#define NS_FINE   1024

typedef struct {
    double a[3], b[3];       /* axis ends, relative to the reference point [m] */
    double e[3], u[3], v[3]; /* unit axis and two unit normals (any, if len == 0) */
    double len, r;           /* axis length, radius [m] */
} capsule;

/* Labels of the ends of exposed gaps and arcs (the signature): the index
 * of the capsule whose surface bounds it, or one of these.  Which part of
 * that capsule (ball or cylinder) is left out on purpose: the two are
 * tangent along the rim, the switch is only a curvature jump that the
 * quadrature absorbs, and the roots from the two parts agree to rounding
 * over a band around it, which would make the label flicker. */
enum { SRC_CLIP_LO = CD_MAX_ARMS, SRC_CLIP_HI, SRC_START };

/* ---- small vector helpers ---------------------------------------------- */

static inline double dot3(const double *p, const double *q) { return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]; }

static inline void sub3(const double *p, const double *q, double *o)
{
    o[0] = p[0] - q[0];
    o[1] = p[1] - q[1];
    o[2] = p[2] - q[2];
}

/* ---- shapes_numeric_geom.c ---------------------------------------------- */

/* An angle on a circle of latitude of a cap where it may cross another
 * capsule's surface, and the label (SRC_* or capsule index) of that
 * surface. */
typedef struct {
    double phi;
    unsigned src;
} cut;

void cd_shn_capsule_init(capsule *c, const double *a, const double *b, double r);
/* Squared distance from p to the axis segment of c [m^2]. */
double cd_shn_dist2_segment(const capsule *c, const double *p);
/* Distance between the axis segments of two capsules [m]. */
double cd_shn_segment_distance(const capsule *p, const capsule *q);
/* Interval of t where o + t d (|d| = 1) lies in capsule c; 0 if none. */
int cd_shn_line_capsule(const capsule *c, const double *o, const double *d, double *lo, double *hi);
/* Angles where the circle ctr + rho (cos phi U + sin phi W) crosses a
 * sphere, a plane, or the infinite cylinder of c (within c's slab); each
 * returns the number of cuts written to out. */
int cd_shn_circle_sphere(const double *ctr, double rho, const double *U, const double *W, const double *q, double R,
                         unsigned src, cut *out);
int cd_shn_circle_plane(const double *ctr, double rho, const double *U, const double *W, const double *q,
                        const double *n, unsigned src, cut *out);
int cd_shn_circle_cylinder(const double *ctr, double rho, const double *U, const double *W, const capsule *c,
                           unsigned src, cut *out);
/* Antiderivatives of cos^m sin^n, m + n <= 3 (10 monomials), and products
 * of linear forms x0 + x1 cos + x2 sin in that monomial order. */
void cd_shn_trig_antideriv(double phi, double *F);
void cd_shn_lin_times_lin(const double *a, const double *b, double *q);
void cd_shn_quad_times_lin(const double *q, const double *l, double *c);

/* ---- shapes_numeric_quad.c ---------------------------------------------- */

typedef uint64_t (*pw_fn)(double x, void *ctx, double *out);

typedef struct {
    pw_fn f;
    void *ctx;
    const double *weight; /* per component: makes the error comparable across units */
    double xres;          /* events are located to this width (parameter units) */
    long evals;
    int events; /* changes located so far */
} pw_job;

/* Integral over [A, B] of the NCOMP components of J->f, added to acc:
 * signatures sampled at nsample + 1 points (nsample <= NS_FINE), changes
 * between neighbours located, then each analytic piece integrated. */
void cd_shn_pw_integrate(pw_job *J, double A, double B, int nsample, double tol, double *acc);

#endif
