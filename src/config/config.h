/* A run file (YAML), read and validated into plain values.  Every key is
 * listed in docs/config.md; the table in config_schema.c is the single source of
 * the key names, types, units and ranges. */
#ifndef CD_CONFIG_H
#define CD_CONFIG_H
#include <stddef.h>
#include "geom_types.h"

#define CD_MAX_SPECIES   8
#define CD_MAX_CFG_WALLS 8
#define CD_MAX_ARMS      16
#define CD_PATH_MAX      1024

/* One kind of particle in the run. */
/* neighbor.reorder: the memory order of the particles (src/backend/omp/reorder.c). */
enum { CD_REORDER_CELLS = 0, CD_REORDER_NONE = 1 };

/* particles[].shape, stored as the index of its choice (config_schema.c). */
enum cd_shape_kind { CD_SHAPE_SPHERE, CD_SHAPE_ROD, CD_SHAPE_CROSS, CD_SHAPE_HEXAPOD, CD_SHAPE_SEGMENTS };

typedef struct {
    int shape;                                           /* enum cd_shape_kind */
    double aspect;                                       /* alpha = L / d_p [1] (named shapes) */
    double diameter;                                     /* arm diameter d_p [m] (named shapes) */
    int n_segments;                                      /* shape: segments */
    double seg_a[CD_MAX_ARMS][3], seg_b[CD_MAX_ARMS][3]; /* body-frame axis ends [m] */
    double seg_radius[CD_MAX_ARMS];                      /* [m] */
    long count;                                          /* number of particles of this species */
    double polydispersity;                               /* p: scale factor uniform in [1-p, 1+p] [1] */
} cd_species_config;

/* The choices of domain.type and protocol.type, as the code selects on
 * them (the text stays for messages and the stored config). */
enum cd_domain_kind { CD_DOMAIN_NONE, CD_DOMAIN_BOX, CD_DOMAIN_CYLINDER, CD_DOMAIN_BALL };
enum cd_protocol_kind { CD_PROTOCOL_NONE, CD_PROTOCOL_DEPOSIT, CD_PROTOCOL_RADIAL, CD_PROTOCOL_BULK };
/* Deposit and compress in a box or cylinder; radial compaction and the
 * bulk probe in a ball. */
#define CD_PROTOCOL_IN_BALL(k) ((k) == CD_PROTOCOL_RADIAL || (k) == CD_PROTOCOL_BULK)

typedef struct {
    char source_path[CD_PATH_MAX]; /* file the config was read from */
    char *source_text;             /* the file verbatim (echoed into the output) */

    /* run */
    char name[128];
    unsigned long long seed;    /* random seed */
    double dt;                  /* time step [s] */
    long long steps;            /* steps to take */
    char output[CD_PATH_MAX];   /* HDF5 output path ("" = <name>.h5 next to cwd) */
    long long snapshot_every;   /* steps between snapshots */
    long long thermo_every;     /* steps between time-series rows */
    double steps_per_collision; /* > 0: dt = t_col / steps_per_collision (run.dt not given) */
    int force_dt;               /* 1: run even when dt > t_col/5 */
    double max_overlap;         /* stop when an overlap exceeds this fraction of the arm diameter [1] */

    /* physics */
    int dimension;                /* 3, or 2 (x-y plane motion only) */
    double gravity[3];            /* [m/s^2] */
    int sphere_orientation_fixed; /* 1: spheres keep their orientation (physics.sphere_orientation: fixed) */
    double density;               /* rho [kg/m^3] */
    double kn, kt;                /* particle stiffness [N/m] */
    double eta_n, eta_t;          /* damping ratios [1] */
    double friction;              /* mu between particles [1] */
    double wall_friction;         /* mu_w [1] */
    /* 0: mu F_n,elastic ((kn/2) delta_n, Conzelmann et al.); 1: mu F_n (Tran et al. 2024, LAMMPS) */
    int friction_limit_total;
    int law;                   /* material.law: CD_LAW_LINEAR | CD_LAW_HERTZ_MINDLIN (kernels/contact_law.h) */
    double young_modulus;      /* hertz_mindlin: E [Pa] */
    double poisson_ratio;      /* hertz_mindlin: nu [1] */
    double impact_speed;       /* hertz_mindlin: speed of the collision time t_col [m/s] */
    double parallel_angle_deg; /* parallel-contact cut-off [deg] */
    int parallel_blend;        /* 1: contact point blended up to twice the cut-off (docs/contacts.md) */

    /* particles */
    int n_species;
    cd_species_config species[CD_MAX_SPECIES];

    /* domain: box | cylinder | ball | none, plus extra walls */
    char domain[16];
    enum cd_domain_kind domain_kind;             /* domain as a selector, set at load */
    double box_width, box_thickness, box_height; /* x, z, y extents [m] */
    double cyl_diameter, cyl_height;             /* [m] */
    double ball_radius;                          /* [m] */
    int n_extra_walls;
    cd_wall extra_walls[CD_MAX_CFG_WALLS];

    /* initial placement */
    char placement[16];   /* lattice | random */
    char exclusion[16];   /* random placement: bounding_sphere | shape */
    int random_placement; /* placement is random (set at load) */
    int exclude_by_shape; /* exclusion is shape (set at load) */
    double clearance;     /* lattice spacing / particle size [1] */
    double lattice_gap;   /* > 0: lattice spacing = particle size + this [m] (init.clearance not given) */
    double init_speed;    /* velocity components uniform in (-v, v) [m/s] */

    /* neighbour list */
    double skin; /* Verlet skin [m] (0 = 0.1 x smallest arm diameter) */
    int reorder; /* neighbor.reorder: CD_REORDER_CELLS | CD_REORDER_NONE (src/backend/omp/reorder.c) */

    /* MPI domain decomposition (docs/mpi.md; read by the MPI build only) */
    int mpi_decomposition; /* CD_DECOMP_CARTESIAN (0) or CD_DECOMP_RCB (1), src/mpi/mpi_decomp.h */
    double mpi_grid[3];    /* sub-domains along x, y, z; [0, 0, 0]: chosen from the ranks and the domain */
    int mpi_output;        /* 0 parallel: every rank writes its rows (MPI-IO); 1 rank0: rank 0 writes (journaled) */

    /* protocol (docs/references.md, Protocols; src/protocols/protocol.c) */
    char protocol[24];                   /* none | deposit_compress | radial_compaction | bulk_modulus */
    enum cd_protocol_kind protocol_kind; /* protocol as a selector, set at load */
    double settle_time;                  /* deposit: settling time [s] (0 = 3 sqrt(2 h / g)) */
    double piston_speed;                 /* deposit: piston speed while compressing [m/s] */
    double piston_force;                 /* deposit: target force on the piston [N] */
    double fill_ratio;                   /* deposit: packing height / width that picks the count (0 = counts given) */
    double fill_fraction;                /* deposit: expected packing fraction for fill_ratio [1] (0 = not given) */
    int piston_hold_position; /* deposit: 1: the piston stops where the load was reached; 0: it carries the load (mass piston_mass) */
    int piston_from_top;           /* deposit: 1: the piston starts at the top; 0: just above the settled packing */
    double piston_mass;            /* deposit: piston mass while holding [kg] (0 = total particle mass) */
    double pressure;               /* ball: applied pressure [Pa] (0 = pressure_ratio kn / L) */
    double pressure_ratio;         /* ball: p L / kn [1] */
    double relax_ratio;            /* stop when kinetic energy < relax_ratio x elastic energy [1] */
    double energy_tolerance;       /* ... and the elastic energy changed by less than this between checks [1] */
    long long check_every;         /* steps between convergence checks */
    long long relax_sample;        /* steps between samples of the kinetic/elastic ratio between checks; 0: none */
    double strain_max, strain_min; /* bulk: largest and smallest volumetric strain dV/V [1] */
    long long probe_steps;         /* bulk: relaxation steps after each strain */

    /* solver: which program runs the file (docs/mpm.md) */
    int solver; /* 0 dem (rigid particles), 1 mpm (material point method) */
    /* mpm (docs/mpm.md) */
    int mpm_setup;       /* 0 diametral: one disk between two plane walls; 1 packing: a DEM packing in a box */
    double mpm_diameter; /* disk diameter D [m] (diametral) */
    char mpm_packing[CD_PATH_MAX]; /* the DEM run file of the packing (packing) */
    int mpm_cells;                 /* background cells across D [1] */
    int mpm_points_per_side;       /* material points per cell and direction at start [1] */
    double mpm_wall_speed;         /* speed of the top wall towards the bottom one [m/s] */
    double mpm_wall_stiffness;     /* wall penalty k / E [1] */
    double mpm_contact_gap;        /* gap from which particles' contact acts, in cells [1] */
    double mpm_pic_fraction;       /* PIC share of the points' velocity update, the rest FLIP [1] */
    int mpm_model;                 /* 0 elastic, 1 von_mises */
    double mpm_density;            /* rho [kg/m^3] */
    double mpm_young;              /* E [Pa] */
    double mpm_poisson;            /* nu [1] */
    double mpm_yield;              /* sigma_y [Pa] (von_mises) */
    double mpm_hardening;          /* H [Pa] (von_mises) */
} cd_config;

/* Fills c with the documented defaults. */
void cd_config_defaults(cd_config *c);

/* Reads and validates path.  On failure returns -1 and writes a message that
 * names the file, the key, the value and what was expected into err. */
int cd_config_load(const char *path, cd_config *c, char *err, size_t errlen);

/* Same, from text in memory (tests, resume from the echoed config). */
int cd_config_parse(const char *text, const char *name_for_errors, cd_config *c, char *err, size_t errlen);

void cd_config_free(cd_config *c);

/* Compares, key by key, the config stored in a run file with the one given
 * to resume it.  Each key whose value differs is written as a line
 * "  KEY: A in the run file, B given" into accepted when the key may change
 * on a resume (CD_KF_RESUMABLE in the key table: run length, output
 * cadence, stopping criteria) or is named in allow (n_allow names, each a
 * key such as "material.friction", "particles[].count" for every item or
 * "particles[1].count" for one), else into refused.  A list with another
 * number of items is the key of the list ("particles: 1 item ..., 2
 * items given").  Returns the number of refused keys. */
int cd_config_resume_diff(const cd_config *stored, const cd_config *given, const char *const *allow, int n_allow,
                          char *refused, size_t rlen, char *accepted, size_t alen);

/* 1 when name is a key of the table ("particles[0].count" and
 * "particles[].count" both name particles[].count), else 0 with the
 * nearest key, if any is close, in suggest. */
int cd_config_key_known(const char *name, char *suggest, size_t n);

/* Parses a whole command-line number strictly: optional sign, decimal
 * digits only, nothing after them, within [lo, hi].  Returns 0, or -1 with
 * "OPT VALUE: expected an integer in [lo, hi]" (or ">= lo") in err. */
int cd_parse_cli_int(const char *opt, const char *s, long long lo, long long hi, long long *out, char *err,
                     size_t errlen);
/* The same for a real number (strtod forms, finite), within [lo, hi]. */
int cd_parse_cli_real(const char *opt, const char *s, double lo, double hi, double *out, char *err, size_t errlen);

/* Prints every key with type, unit, default and meaning (capdem run --help);
 * markdown: as the table of docs/config.md (capdem run --help-markdown). */
void cd_config_print_keys(void *stream, int markdown);

#endif
