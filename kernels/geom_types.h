/* Plain data shared by the narrow phase, the wall contacts and the contact
 * law (docs/references.md, Contacts). */
#ifndef CD_GEOM_TYPES_H
#define CD_GEOM_TYPES_H
#include "defs.h"

/* Geometry of one contact between two spherocylinders, or between a
 * spherocylinder and a wall. */
typedef struct {
    cd_vec3 point; /* contact point c [m] */
    cd_vec3
        normal; /* unit normal n, from body i towards body j (wall: from wall into the particle is -n; see walls.h) */
    cd_real overlap;  /* delta_n = r_i + r_j - D [m]; > 0 means contact */
    cd_real distance; /* D, distance between the closest axis points [m] */
    cd_int parallel;  /* 1 when the parallel-contact rule placed the point */
} cd_contact_geom;

/* Wall kinds, CD_WALL_PLANE, CD_WALL_CYLINDER, CD_WALL_SPHERE: declared in
 * the run file's layout (runfile.def), which stores them as they are. */
enum {
#define CD_H5_WALL_KIND(id, value, name) CD_WALL_##id = value,
#include "runfile.def"
};

/* A wall.  Plain struct so that it can live in an OpenCL buffer. */
typedef struct {
    cd_int type;             /* CD_WALL_* */
    cd_int pad_;             /* keeps the doubles 8-byte aligned on every backend */
    cd_vec3 point;           /* plane: a point on it; cylinder: a point on the axis; sphere: centre [m] */
    cd_vec3 normal;          /* plane: unit normal pointing into the domain; cylinder: unit axis */
    cd_vec3 velocity;        /* translational velocity of the wall [m/s] */
    cd_real radius;          /* cylinder / sphere radius [m] (particles are inside) */
    cd_real radial_velocity; /* sphere: dR/dt [m/s] */
    cd_real friction;        /* Coulomb coefficient mu_w [1] */
} cd_wall;

/* What the step keeps of a wall contact per wall candidate of the last
 * neighbour-list build (not per primitive and wall): the history (flag and
 * tangential spring, carried over at each build by matching the candidates'
 * rows, src/backend/omp/neighbors.c and the OpenCL twin) and the outputs,
 * valid while the entry is in contact (active).  Sync expands the entries
 * into the host's columns of the same names (kernels/fields.def, groups
 * WALLC and WALLC_OUT).  Plain struct for an OpenCL buffer: 96 bytes on
 * every backend. */
typedef struct {
    cd_vec3 force;   /* force of the wall on the primitive [N] */
    cd_vec3 torque;  /* torque of that force about the particle centre [N m] */
    cd_real overlap; /* normal overlap [m] */
    cd_real fn;      /* normal force magnitude F_n [N] (pushes the wall outwards) */
    cd_vec3 shear;   /* tangential spring elongation [m] (history; zero while not in contact) */
    cd_int active;   /* 1 while the primitive overlaps the wall (history) */
    cd_int pad_;     /* keeps the size a multiple of 8 bytes on every backend */
} cd_wall_entry;

/* The arm of a primitive whose axis is not a point at the body origin (a
 * spherocylinder's segment, an off-centre ball): what a sphere's ball does
 * not need, kept apart so that a sphere holds its centre, radius and owner
 * only (cd_cols.prim_arm, kernels/cols.h; docs/performance.md, "Sphere
 * primitives without arm columns").  The host keeps the same values per
 * primitive in fields.def (group PRIM_ARM), derived into arms at a start
 * and expanded back at sync (src/core/state.c).  96 B of 8-byte members:
 * the same layout in C and OpenCL. */
typedef struct {
    cd_vec3 a_body; /* axis end a, principal body frame, scaled [m] */
    cd_vec3 b_body; /* axis end b, principal body frame, scaled [m] */
    cd_vec3 b;      /* axis end b, world frame [m] (end a: cd_cols.prim_a) */
    cd_vec3 b_ref;  /* end b at the last neighbour-list build [m] */
} cd_arm;

/* Walls a simulation may have (the state's table, the observables' slots). */
#define CD_MAX_WALLS 8

#endif
