/* Shape catalogue: rigid clusters of spherocylinders sharing one centre,
 * with the mass properties of the union of their arms (docs/references.md, Particles). */
#ifndef CD_SHAPES_H
#define CD_SHAPES_H
#include <stddef.h>
#include "defs.h"
#include "config/config.h"

typedef struct {
    char kind[32]; /* sphere | rod | cross | hexapod | segments */
    int n_prims;
    cd_vec3 a[CD_MAX_ARMS], b[CD_MAX_ARMS]; /* axis ends, principal body frame, centre of mass at origin [m] */
    double radius[CD_MAX_ARMS];             /* arm radius [m] */
    double aspect;                          /* L/d_p of the longest arm [1] */
    double tip_length;                      /* L, longest tip-to-tip extent of one arm [m] */
    double diameter;                        /* d_p of the thickest arm [m] */
    double bounding_radius;                 /* max over arms of |end| + r, from the centre [m] */
    double density;                         /* [kg/m^3] */
    double volume;                          /* of the union of the arms [m^3] */
    double area;                            /* surface area of the union [m^2] */
    double sphericity;                      /* pi^(1/3) (6V)^(2/3) / A [1] */
    double mass;                            /* rho V [kg] */
    double inertia[3][3];    /* about the centre of mass, in the body frame of a/b [kg m^2] (diagonal there) */
    double principal[3];     /* principal moments [kg m^2] */
    double volume_rel_error; /* bound on the relative error of volume/inertia (0 = closed form) */
    double area_rel_error;   /* same for the area */
} cd_shape;

/* Named shape (sphere, rod, cross, hexapod): arms along body x, y, z through
 * the centre, each of tip-to-tip length L = aspect * diameter.  For a sphere
 * aspect must be 1.  Returns 0, or -1 with a message in err. */
int cd_shape_make_named(const char *kind, double aspect, double diameter, double density, cd_shape *out, char *err,
                        size_t errlen);
/* The same for a kind of enum cd_shape_kind (sphere to hexapod): what a
 * config's particles[].shape holds after loading. */
int cd_shape_make_kind(int shape_kind, double aspect, double diameter, double density, cd_shape *out, char *err,
                       size_t errlen);

/* General cluster: n axis segments (a_i, b_i) with radii r_i in some body
 * frame.  The result is translated to its centre of mass and rotated to its
 * principal axes. */
int cd_shape_make_segments(int n, const double (*a)[3], const double (*b)[3], const double *r, double density,
                           cd_shape *out, char *err, size_t errlen);

/* Shape of a species of the config. */
int cd_shape_from_species(const cd_species_config *sp, double density, cd_shape *out, char *err, size_t errlen);

/* Writes the shape as one JSON object (SI units). */
void cd_shape_print_json(const cd_shape *s, void *stream);

/* Mass properties of a union of capsules by the converged numerical method
 * of shapes_numeric.c (docs/shapes.md), for any arrangement. */
typedef struct {
    double volume;           /* [m^3] */
    double com[3];           /* centre of mass, input frame [m] */
    double central[3][3];    /* second moments about the centre of mass, int x_i x_j dV [m^5] */
    double area;             /* surface area of the union [m^2] */
    double volume_rel_error; /* bound on the relative error of volume and second moments [1] */
    double area_rel_error;   /* [1] */
} cd_union_props;

/* Segments (a_i, b_i) with radii r_i > 0, 1 <= n <= CD_MAX_ARMS.  Returns 0,
 * or -1 on invalid input. */
int cd_shapes_union_numeric(int n, const double (*a)[3], const double (*b)[3], const double *r, cd_union_props *out);

#endif
