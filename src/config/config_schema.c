/* The run-file key table: the single list of key names, types, units,
 * defaults, ranges and meanings (see config_schema.h), and the help text
 * printed from it. */
#include <stdio.h>
#include <string.h>
#include "config/config_schema.h"
#include "contact_law.h"

/* Selector choices as bits, in the order of the choices strings below. */
#define D_BOX         1u
#define D_CYLINDER    2u
#define D_BALL        4u
#define S_SPHERE      1u
#define S_ROD         2u
#define S_CROSS       4u
#define S_HEXAPOD     8u
#define S_SEGMENTS    16u
#define S_NAMED       (S_SPHERE | S_ROD | S_CROSS | S_HEXAPOD)
#define P_DEPOSIT     2u
#define P_RADIAL      4u
#define P_BULK        8u
#define P_ANY         (P_DEPOSIT | P_RADIAL | P_BULK)
#define L_LINEAR      1u
#define L_HERTZ       2u
#define SOLVER_DEM    1u
#define M_VON_MISES   2u
#define MPM_DIAMETRAL 1u
#define MPM_PACKING   2u

_Static_assert(CD_WALL_PLANE == 0, "domain.walls[].type stores the index of \"plane\" in its choices");
_Static_assert(CD_SHAPE_SPHERE == 0 && CD_SHAPE_ROD == 1 && CD_SHAPE_CROSS == 2 && CD_SHAPE_HEXAPOD == 3 &&
                   CD_SHAPE_SEGMENTS == 4,
               "particles[].shape stores the index of its choice");
_Static_assert(CD_LAW_LINEAR == 0 && CD_LAW_HERTZ_MINDLIN == 1, "material.law stores the index of its choice");

#define CFG(f)       .target = CD_TGT_CONFIG, .offset = offsetof(cd_config, f)
#define CFG_SIZED(f) CFG(f), .size = sizeof(((cd_config *)0)->f)
#define SPC(f)       .target = CD_TGT_SPECIES, .offset = offsetof(cd_species_config, f)
#define SPC_SIZED(f) SPC(f), .size = sizeof(((cd_species_config *)0)->f)
#define WALL(f)      .target = CD_TGT_WALL, .offset = offsetof(cd_wall, f)
#define SCRATCH(f)   .target = CD_TGT_SCRATCH, .offset = offsetof(cd_config_scratch, f)
#define GT(x)        .lo_kind = '(', .lo = (x)
#define GE(x)        .lo_kind = '[', .lo = (x)
#define LT(x)        .hi_kind = ')', .hi = (x)
#define LE(x)        .hi_kind = ']', .hi = (x)
#define ALWAYS       .required = CD_ALL_CHOICES

const cd_key cd_config_keys[] = {
    /* which solver; the mpm section is docs/mpm.md */
    {"solver", CD_KT_ENUM, "-", "dem", CFG(solver), .flags = CD_KF_SELECTOR, .choices = "dem|mpm", .label = "solver",
     .meaning = "dem: rigid particles (the other sections); mpm: deformable particles by the material point method "
                "(section mpm)"},

    /* run */
    {"run.name", CD_KT_STRING, "-", "capdem", CFG_SIZED(name), .flags = CD_KF_NONEMPTY | CD_KF_RESUMABLE,
     .label = "run name", .meaning = "name of the run; the output file defaults to <name>.h5"},
    {"run.seed", CD_KT_UINT, "-", "1", CFG(seed), .label = "random seed",
     .meaning = "seed of the random numbers (placement, velocities, polydispersity)"},
    {"run.dt", CD_KT_REAL, "s", "2e-6", CFG(dt), GT(0), .conflicts = "steps_per_collision", .label = "time step",
     .meaning = "time step; refused above t_col/5 unless run.force_dt, warned above t_col/20"},
    {"run.steps_per_collision", CD_KT_REAL, "1", NULL, CFG(steps_per_collision), GE(5), .conflicts = "dt",
     .label = "steps per collision", .meaning = "instead of run.dt: dt = t_col / this, t_col of the lightest pair"},
    {"run.steps", CD_KT_INT, "-", "10000", CFG_SIZED(steps), GE(0), .flags = CD_KF_RESUMABLE,
     .label = "number of steps",
     .meaning = "steps to take: the step the run stops at, counted from step 0 (a resume continues up to it)"},
    {"run.output", CD_KT_STRING, "path", "\"\"", CFG_SIZED(output), .flags = CD_KF_RESUMABLE, .label = "output file",
     .meaning = "HDF5 output file; empty: <name>.h5 in the working folder"},
    {"run.snapshot_every", CD_KT_INT, "-", "1000", CFG_SIZED(snapshot_every), GE(1), .flags = CD_KF_RESUMABLE,
     .label = "snapshot interval, steps", .meaning = "steps between full snapshots"},
    {"run.thermo_every", CD_KT_INT, "-", "100", CFG_SIZED(thermo_every), GE(1), .flags = CD_KF_RESUMABLE,
     .label = "time-series interval, steps", .meaning = "steps between rows of the time series"},
    {"run.force_dt", CD_KT_BOOL, "-", "false", CFG(force_dt), .flags = CD_KF_RESUMABLE, .label = "force the time step",
     .meaning = "run even when dt > t_col/5"},
    {"run.max_overlap", CD_KT_REAL, "1", "0.5", CFG(max_overlap), GT(0), LE(2), .flags = CD_KF_RESUMABLE,
     .label = "overlap limit", .meaning = "stop (exit 3) when an overlap exceeds this fraction of the arm diameter"},

    /* physics */
    {"physics.dimension", CD_KT_INT, "-", "3", CFG_SIZED(dimension), GE(2), LE(3), .label = "dimension",
     .meaning = "3, or 2: motion in the x-y plane only (translation in x, y; rotation about z)"},
    {"physics.gravity", CD_KT_VEC3, "m/s^2", "[0, -9.81, 0]", CFG(gravity), .label = "gravity",
     .meaning = "gravity vector (y is up)"},
    {"physics.sphere_orientation", CD_KT_ENUM, "-", "integrate", CFG(sphere_orientation_fixed),
     .choices = "integrate|fixed", .label = "orientation of spheres",
     .meaning = "integrate: every particle's orientation is integrated; fixed: spheres (one ball at the centre) keep "
                "their initial orientation, which none of their forces depends on (as LAMMPS and LIGGGHTS do; "
                "their angular velocity is integrated as before; docs/motion.md)"},

    /* material */
    {"material.law", CD_KT_ENUM, "-", "linear", CFG(law), .flags = CD_KF_SELECTOR, .choices = "linear|hertz_mindlin",
     .label = "contact law",
     .meaning =
         "linear: spring-dashpot k_n, k_t; hertz_mindlin: Hertz normal and Mindlin tangential stiffness from E and nu "
         "(docs/contacts.md)"},
    {"material.density", CD_KT_REAL, "kg/m^3", "1000", CFG(density), GT(0), .label = "particle density",
     .meaning = "density rho of the particles"},
    {"material.kn", CD_KT_REAL, "N/m", "1e5", CFG(kn), GT(0), .applies = L_LINEAR, .label = "normal stiffness",
     .meaning = "normal stiffness k_n of one particle (a contact has k_n/2)"},
    {"material.kt", CD_KT_REAL, "N/m", "0.5*kn", CFG(kt), GE(0), .flags = CD_KF_DERIVED, .applies = L_LINEAR,
     .label = "tangential stiffness", .meaning = "tangential stiffness k_t of one particle (a contact has k_t/2)"},
    {"material.young_modulus", CD_KT_REAL, "Pa", NULL, CFG(young_modulus), GT(0), .applies = L_HERTZ,
     .required = L_HERTZ, .label = "Young's modulus",
     .meaning = "Young's modulus E of the particles and the walls (one material)"},
    {"material.poisson_ratio", CD_KT_REAL, "1", NULL, CFG(poisson_ratio), GT(-1), LE(0.5), .applies = L_HERTZ,
     .required = L_HERTZ, .label = "Poisson ratio", .meaning = "Poisson ratio nu of the particles and the walls"},
    {"material.impact_speed", CD_KT_REAL, "m/s", "1", CFG(impact_speed), GT(0), .applies = L_HERTZ,
     .label = "impact speed",
     .meaning =
         "speed at which the Hertz collision time t_col is taken for the run.dt check and run.steps_per_collision"},
    {"material.damping_normal", CD_KT_REAL, "1", "0.2", CFG(eta_n), GE(0), LT(1), .conflicts = "restitution",
     .label = "normal damping ratio",
     .meaning = "normal damping ratio eta_n (linear: 0.2 gives e = 0.53; hertz_mindlin: docs/contacts.md)"},
    {"material.restitution", CD_KT_REAL, "1", NULL, SCRATCH(restitution), GT(0), LE(1), .conflicts = "damping_normal",
     .label = "coefficient of restitution",
     .meaning = "restitution e instead of eta_n: eta_n = -ln e / sqrt(pi^2 + ln^2 e) (e = 1: 0)"},
    {"material.damping_tangential", CD_KT_REAL, "1", "eta_n", CFG(eta_t), GE(0), LT(1), .flags = CD_KF_DERIVED,
     .label = "tangential damping ratio", .meaning = "tangential damping ratio eta_t"},
    {"material.friction", CD_KT_REAL, "1", "0.5", CFG(friction), GE(0), .label = "friction coefficient",
     .meaning = "Coulomb coefficient mu between particles"},
    {"material.wall_friction", CD_KT_REAL, "1", "0", CFG(wall_friction), GE(0), .label = "wall friction coefficient",
     .meaning = "Coulomb coefficient mu_w between particles and every wall"},
    {"material.friction_limit", CD_KT_ENUM, "-", "elastic", CFG(friction_limit_total), .choices = "elastic|total",
     .label = "Coulomb limit",
     .meaning =
         "elastic: mu times the elastic part of F_n, (k_n/2) delta_n when linear (Conzelmann et al.); total: mu F_n "
         "(Tran et al. 2024, LAMMPS)"},
    {"material.parallel_angle", CD_KT_REAL, "deg", "2", CFG(parallel_angle_deg), GE(0), LT(45),
     .label = "parallel-contact angle", .meaning = "arms closer than this to parallel use the parallel-contact rule"},
    {"material.parallel_blend", CD_KT_BOOL, "-", "false", CFG(parallel_blend), .label = "continuous parallel rule",
     .meaning = "true: from the cut-off to twice its sine the contact point slides from the parallel point to the "
                "closest points instead of jumping (docs/contacts.md); false: Conzelmann et al.'s rule"},

    /* particles */
    {"particles", CD_KT_LIST, "-", NULL, CFG(species), ALWAYS, .applies = SOLVER_DEM, .min_items = 1,
     .max_items = CD_MAX_SPECIES, .item_target = CD_TGT_SPECIES, .count_offset = offsetof(cd_config, n_species),
     .item_size = sizeof(cd_species_config), .label = "particle species",
     .meaning = "one mapping per kind of particle (keys particles[].*)"},
    {"particles[].shape", CD_KT_ENUM, "-", NULL, SPC(shape), ALWAYS, .flags = CD_KF_SELECTOR,
     .choices = "sphere|rod|cross|hexapod|segments", .label = "particle shape",
     .meaning = "named shape, or segments for arms given one by one"},
    {"particles[].aspect", CD_KT_REAL, "1", "1", SPC(aspect), GE(1), .applies = S_NAMED,
     .required = S_ROD | S_CROSS | S_HEXAPOD, .label = "aspect ratio",
     .meaning = "alpha = L / d_p of one arm (tip to tip); a sphere has 1"},
    {"particles[].diameter", CD_KT_REAL, "m", NULL, SPC(diameter), GT(0), .applies = S_NAMED, .required = S_NAMED,
     .label = "arm diameter", .meaning = "arm diameter d_p"},
    {"particles[].segments", CD_KT_SEGMENTS, "m", NULL, SPC(n_segments), .min_items = 1, .max_items = CD_MAX_ARMS,
     .applies = S_SEGMENTS, .required = S_SEGMENTS, .label = "segments",
     .meaning = "arms in the body frame: axis ends a, b and radius, each [ax, ay, az, bx, by, bz, radius]"},
    {"particles[].count", CD_KT_INT, "-", "protocol.fill_ratio", SPC_SIZED(count), GE(1), LE(2147483647.0),
     .flags = CD_KF_DERIVED, .label = "particle count",
     .meaning = "number of particles of this species; omitted: chosen by protocol.fill_ratio (deposit)"},
    {"particles[].polydispersity", CD_KT_REAL, "1", "0", SPC(polydispersity), GE(0), LT(1), .label = "polydispersity",
     .meaning = "p: each particle is scaled by a factor uniform in [1-p, 1+p]"},

    /* domain */
    {"domain.type", CD_KT_ENUM, "-", "none", CFG_SIZED(domain), .flags = CD_KF_SELECTOR,
     .choices = "box|cylinder|ball|none", .label = "domain type", .meaning = "container; none: only the extra walls"},
    {"domain.width", CD_KT_REAL, "m", NULL, CFG(box_width), GT(0), .applies = D_BOX, .required = D_BOX,
     .label = "box width", .meaning = "box extent in x"},
    {"domain.thickness", CD_KT_REAL, "m", NULL, CFG(box_thickness), GT(0), .applies = D_BOX, .required = D_BOX,
     .label = "box thickness", .meaning = "box extent in z"},
    {"domain.height", CD_KT_REAL, "m", "lattice fit", CFG(box_height), GT(0), .applies = D_BOX, .flags = CD_KF_DERIVED,
     .label = "box height",
     .meaning = "box extent in y (up); omitted: just high enough for the init lattice (Conzelmann et al.)"},
    {"domain.diameter", CD_KT_REAL, "m", NULL, CFG(cyl_diameter), GT(0), .applies = D_CYLINDER, .required = D_CYLINDER,
     .label = "cylinder diameter", .meaning = "diameter of the vertical cylinder"},
    {"domain.height", CD_KT_REAL, "m", "lattice fit", CFG(cyl_height), GT(0), .applies = D_CYLINDER,
     .flags = CD_KF_DERIVED, .label = "cylinder height",
     .meaning = "height of the cylinder above its floor; omitted: just high enough for the init lattice"},
    {"domain.radius", CD_KT_REAL, "m", NULL, CFG(ball_radius), GT(0), .applies = D_BALL, .required = D_BALL,
     .label = "ball radius", .meaning = "initial radius R(0) of the pressure-driven ball"},
    {"domain.walls", CD_KT_LIST, "-", NULL, CFG(extra_walls), .min_items = 0, .max_items = CD_MAX_CFG_WALLS,
     .item_target = CD_TGT_WALL, .count_offset = offsetof(cd_config, n_extra_walls), .item_size = sizeof(cd_wall),
     .label = "extra walls", .meaning = "walls added to the domain (keys domain.walls[].*)"},
    {"domain.walls[].type", CD_KT_ENUM, "-", NULL, WALL(type), .choices = "plane", ALWAYS, .label = "wall type",
     .meaning = "kind of wall (only plane so far)"},
    {"domain.walls[].point", CD_KT_VEC3, "m", NULL, WALL(point), ALWAYS, .label = "wall point",
     .meaning = "a point on the plane"},
    {"domain.walls[].normal", CD_KT_VEC3, "1", NULL, WALL(normal), ALWAYS, .flags = CD_KF_UNIT, .label = "wall normal",
     .meaning = "normal pointing into the domain; normalised on reading"},
    {"domain.walls[].velocity", CD_KT_VEC3, "m/s", "[0, 0, 0]", WALL(velocity), .label = "wall velocity",
     .meaning = "translational velocity of the wall"},

    /* initial placement */
    {"init.placement", CD_KT_ENUM, "-", "lattice", CFG_SIZED(placement), .choices = "lattice|random",
     .label = "placement", .meaning = "lattice: particles on a grid; random: random positions without overlap"},
    {"init.exclusion", CD_KT_ENUM, "-", "bounding_sphere", CFG_SIZED(exclusion), .choices = "bounding_sphere|shape",
     .label = "random exclusion",
     .meaning =
         "random placement keeps apart bounding_sphere: the bounding spheres; shape: only the arms (denser starts)"},
    {"init.clearance", CD_KT_REAL, "1", "1.5", CFG(clearance), GE(1), .conflicts = "gap", .label = "lattice clearance",
     .meaning = "lattice spacing over particle size"},
    {"init.gap", CD_KT_REAL, "m", NULL, CFG(lattice_gap), GT(0), .conflicts = "clearance", .label = "lattice gap",
     .meaning = "instead of init.clearance: lattice spacing = particle size + this gap (Conzelmann et al.: 1.5 d_p)"},
    {"init.speed", CD_KT_REAL, "m/s", "0.25", CFG(init_speed), GE(0), .label = "initial speed",
     .meaning = "each velocity component is uniform in (-v, v)"},

    /* neighbour list */
    {"neighbor.skin", CD_KT_REAL, "m", "0", CFG(skin), GE(0), .label = "Verlet skin",
     .meaning = "neighbour-list skin; 0: automatic (0.1 x smallest arm diameter)"},
    {"neighbor.reorder", CD_KT_ENUM, "-", "cells", CFG(reorder), .choices = "cells|none", .label = "memory order",
     .meaning = "cells: at rebuilds the omp backend keeps the particles in memory in the order "
                "of their grid cells where that brings neighbours closer; none: the user's order. The same trajectory "
                "bits either way"},

    /* MPI domain decomposition (docs/mpi.md): how `mpirun -np R` splits space */
    {"mpi.decomposition", CD_KT_ENUM, "-", "cartesian", CFG(mpi_decomposition), .flags = CD_KF_RESUMABLE,
     .choices = "cartesian|rcb", .label = "MPI decomposition",
     .meaning = "cartesian: a grid of sub-domains, one per rank; rcb: recursive coordinate bisection of the "
                "particle centres into sub-domains of equal particle counts (MPI build, docs/mpi.md)"},
    {"mpi.grid", CD_KT_VEC3, "-", "[0, 0, 0]", CFG(mpi_grid), .flags = CD_KF_RESUMABLE, .label = "MPI grid",
     .meaning = "cartesian: sub-domains along x, y, z, their product the ranks; [0, 0, 0]: chosen from the ranks and "
                "the domain (not with rcb)"},
    {"mpi.output", CD_KT_ENUM, "-", "parallel", CFG(mpi_output), .flags = CD_KF_RESUMABLE, .choices = "parallel|rank0",
     .label = "MPI output",
     .meaning = "parallel: every rank writes its particles' rows of the run file through parallel HDF5 (commits "
                "ordered, not journaled); rank0: rank 0 writes the gathered state with the serial writer's atomic "
                "commits (docs/mpi.md)"},

    /* protocol */
    {"protocol.type", CD_KT_ENUM, "-", "none", CFG_SIZED(protocol), .flags = CD_KF_SELECTOR,
     .choices = "none|deposit_compress|radial_compaction|bulk_modulus", .label = "protocol",
     .meaning =
         "none: run.steps of plain dynamics; else a procedure of docs/references.md, Protocols (docs/protocols.md)"},
    {"protocol.settle_time", CD_KT_REAL, "s", "0", CFG(settle_time), GE(0), .applies = P_DEPOSIT,
     .label = "settling time", .meaning = "deposit: settling before the piston moves; 0: 3 sqrt(2 h / g)"},
    {"protocol.piston_speed", CD_KT_REAL, "m/s", "0.25", CFG(piston_speed), GT(0), .applies = P_DEPOSIT,
     .label = "piston speed", .meaning = "deposit: speed of the top piston while it moves down"},
    {"protocol.piston_force", CD_KT_REAL, "N", "500", CFG(piston_force), GT(0), .applies = P_DEPOSIT,
     .label = "piston force", .meaning = "deposit: the piston stops advancing and holds this load"},
    {"protocol.piston_start", CD_KT_ENUM, "-", "packing", CFG(piston_from_top), .choices = "packing|top",
     .applies = P_DEPOSIT, .label = "piston start",
     .meaning = "deposit: where the piston starts moving down: one particle size above the settled packing, or the top "
                "of the domain"},
    {"protocol.piston_hold", CD_KT_ENUM, "-", "load", CFG(piston_hold_position), .choices = "load|position",
     .applies = P_DEPOSIT, .label = "piston hold",
     .meaning = "deposit: once the load is reached the piston carries it as a body of piston_mass (load), or stops "
                "where it is (position)"},
    {"protocol.piston_mass", CD_KT_REAL, "kg", "0", CFG(piston_mass), GE(0), .applies = P_DEPOSIT,
     .label = "piston mass", .meaning = "deposit: inertia of the load-controlled piston; 0: total particle mass"},
    {"protocol.fill_ratio", CD_KT_REAL, "1", "0", CFG(fill_ratio), GE(0), .applies = P_DEPOSIT, .label = "fill ratio",
     .meaning = "deposit: with particles[].count omitted, the count fills the container to fill_ratio x its width "
                "(Conzelmann et al.: 2)"},
    {"protocol.fill_fraction", CD_KT_REAL, "1", NULL, CFG(fill_fraction), GT(0), LT(1), .applies = P_DEPOSIT,
     .label = "expected packing fraction",
     .meaning = "deposit: packing fraction (time-series definition) the compressed packing is expected to reach; "
                "needed by fill_ratio"},
    {"protocol.pressure", CD_KT_REAL, "Pa", "0", CFG(pressure), GE(0), .applies = P_RADIAL | P_BULK,
     .label = "pressure", .meaning = "ball: pressure on the ball; 0: pressure_ratio x kn / L"},
    {"protocol.pressure_ratio", CD_KT_REAL, "1", "1e-5", CFG(pressure_ratio), GT(0), .applies = P_RADIAL | P_BULK,
     .label = "pressure ratio", .meaning = "ball: p L / kn when protocol.pressure is 0 (Tran et al. 2024)"},
    {"protocol.relax_ratio", CD_KT_REAL, "1", "1e-6", CFG(relax_ratio), GT(0), .applies = P_ANY,
     .flags = CD_KF_RESUMABLE, .label = "relaxation ratio",
     .meaning = "relaxed when kinetic energy < relax_ratio x elastic energy"},
    {"protocol.energy_tolerance", CD_KT_REAL, "1", "1e-3", CFG(energy_tolerance), GT(0), .applies = P_ANY,
     .flags = CD_KF_RESUMABLE, .label = "elastic-energy tolerance",
     .meaning = "...and the elastic energy changed by less than this fraction since the last check"},
    {"protocol.check_every", CD_KT_INT, "-", "1000", CFG_SIZED(check_every), GE(1), .applies = P_ANY,
     .flags = CD_KF_RESUMABLE, .label = "check interval, steps",
     .meaning = "steps between checks of the relaxation criterion"},
    {"protocol.relax_sample", CD_KT_INT, "-", "0", CFG_SIZED(relax_sample), GE(0), .applies = P_ANY,
     .flags = CD_KF_RESUMABLE, .label = "relaxation sample interval, steps",
     .meaning = "> 0: the kinetic/elastic ratio is sampled this often, and a check passes only if every sample since "
                "the last one was below relax_ratio; 0: the check's own ratio only"},
    {"protocol.strain_max", CD_KT_REAL, "1", "1e-6", CFG(strain_max), GT(0), LT(0.1), .applies = P_BULK,
     .label = "largest strain", .meaning = "bulk: largest volumetric strain -dV/V of the probe"},
    {"protocol.strain_min", CD_KT_REAL, "1", "1e-11", CFG(strain_min), GT(0), LT(0.1), .applies = P_BULK,
     .label = "smallest strain", .meaning = "bulk: smallest strain; one probe per decade from strain_max down"},
    {"protocol.probe_steps", CD_KT_INT, "-", "20000", CFG_SIZED(probe_steps), GE(1), .applies = P_BULK,
     .label = "probe relaxation steps",
     .meaning = "bulk: steps of relaxation after each strain before the pressure is read"},

    /* material point method (solver: mpm; docs/mpm.md) */
    {"mpm.setup", CD_KT_ENUM, "-", "diametral", CFG(mpm_setup), .flags = CD_KF_SELECTOR, .choices = "diametral|packing",
     .label = "MPM set-up",
     .meaning = "diametral: one disk compressed between a fixed bottom wall and a top wall moving down; "
                "packing: the disks of a 2D DEM run file in a box, compressed by its top wall"},
    {"mpm.diameter", CD_KT_REAL, "m", "0.06", CFG(mpm_diameter), GT(0), .applies = MPM_DIAMETRAL,
     .label = "disk diameter", .meaning = "diameter D of the disk"},
    {"mpm.packing", CD_KT_STRING, "path", NULL, CFG_SIZED(mpm_packing), .applies = MPM_PACKING, .required = MPM_PACKING,
     .label = "packing run file",
     .meaning = "capdem run file of a 2D deposit of spheres (disks): its last snapshot's centres "
                "and radii; relative to the working folder"},
    {"mpm.cells_per_diameter", CD_KT_INT, "-", "30", CFG_SIZED(mpm_cells), GE(4), LE(2000),
     .label = "cells per diameter",
     .meaning = "background mesh: square cells of side D / this (packing: D the smallest disk's)"},
    {"mpm.points_per_cell_side", CD_KT_INT, "-", "2", CFG_SIZED(mpm_points_per_side), GE(1), LE(4),
     .label = "points per cell side",
     .meaning = "material points per cell and direction at start (2: four per cell, the paper's)"},
    {"mpm.wall_speed", CD_KT_REAL, "m/s", "0.5", CFG(mpm_wall_speed), GE(0), .label = "wall speed",
     .meaning = "speed of the top wall towards the fixed bottom wall"},
    {"mpm.wall_stiffness", CD_KT_REAL, "1", "2", CFG(mpm_wall_stiffness), GT(0), LE(100),
     .label = "wall penalty stiffness",
     .meaning = "wall contact penalty k / E (k: N/m per metre of thickness and per point)"},
    {"mpm.contact_gap", CD_KT_REAL, "1", "0.25", CFG(mpm_contact_gap), GE(0), LE(2), .label = "contact gap, cells",
     .meaning = "two particles' contact acts from this gap between them on, in cells (docs/mpm.md: less "
                "interpenetration, earlier contact)"},
    {"mpm.pic_fraction", CD_KT_REAL, "1", "0.01", CFG(mpm_pic_fraction), GE(0), LE(1), .label = "PIC share",
     .meaning = "share of PIC (the new node velocities) in each step's point velocity update, the rest FLIP (the "
                "node accelerations); damps the point velocities the mesh does not see (docs/mpm.md: 0, pure "
                "FLIP, lets them grow in the packings' compaction)"},
    {"mpm.material.model", CD_KT_ENUM, "-", "elastic", CFG(mpm_model), .flags = CD_KF_SELECTOR,
     .choices = "elastic|von_mises", .label = "MPM material",
     .meaning = "elastic: linear isotropic; von_mises: plus von Mises plasticity, linear isotropic hardening"},
    {"mpm.material.density", CD_KT_REAL, "kg/m^3", "1000", CFG(mpm_density), GT(0), .label = "MPM density",
     .meaning = "density rho of the particles"},
    {"mpm.material.young_modulus", CD_KT_REAL, "Pa", "1e7", CFG(mpm_young), GT(0), .label = "Young's modulus",
     .meaning = "Young's modulus E"},
    {"mpm.material.poisson_ratio", CD_KT_REAL, "1", "0.45", CFG(mpm_poisson), GT(-1), LT(0.5),
     .label = "Poisson's ratio", .meaning = "Poisson's ratio nu (plane strain)"},
    {"mpm.material.yield_stress", CD_KT_REAL, "Pa", NULL, CFG(mpm_yield), GT(0), .applies = M_VON_MISES,
     .required = M_VON_MISES, .label = "yield stress", .meaning = "von_mises: initial yield stress sigma_y"},
    {"mpm.material.hardening", CD_KT_REAL, "Pa", "0", CFG(mpm_hardening), GE(0), .applies = M_VON_MISES,
     .label = "hardening modulus",
     .meaning = "von_mises: plastic modulus H = d sigma_y / d eps_p (uniaxial tangent E H / (E + H))"},
};
const size_t cd_config_nkeys = sizeof cd_config_keys / sizeof cd_config_keys[0];

size_t cd_key_section_len(const char *path)
{
    const char *dot = strrchr(path, '.');
    return dot ? (size_t)(dot - path) : 0;
}

const cd_key *cd_key_selector_of(const cd_key *k)
{
    size_t n = cd_key_section_len(k->path);
    for (size_t i = 0; i < cd_config_nkeys; i++) {
        const cd_key *s = &cd_config_keys[i];
        if ((s->flags & CD_KF_SELECTOR) && cd_key_section_len(s->path) == n && strncmp(s->path, k->path, n) == 0)
            return s;
    }
    return NULL;
}

/* ---- questions about the table ---------------------------------------- */

/* Optimal-string-alignment distance (edits and adjacent swaps). */
int cd_edit_distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    int d[40][40];
    if (la > 38 || lb > 38) return 99;
    for (size_t i = 0; i <= la; i++) d[i][0] = (int)i;
    for (size_t k = 0; k <= lb; k++) d[0][k] = (int)k;
    for (size_t i = 1; i <= la; i++)
        for (size_t k = 1; k <= lb; k++) {
            int cost = a[i - 1] != b[k - 1];
            int best = d[i - 1][k] + 1;
            if (d[i][k - 1] + 1 < best) best = d[i][k - 1] + 1;
            if (d[i - 1][k - 1] + cost < best) best = d[i - 1][k - 1] + cost;
            if (i > 1 && k > 1 && a[i - 1] == b[k - 2] && a[i - 2] == b[k - 1] && d[i - 2][k - 2] + 1 < best)
                best = d[i - 2][k - 2] + 1;
            d[i][k] = best;
        }
    return d[la][lb];
}

int cd_key_in_section(const cd_key *k, const char *sect)
{
    size_t n = strlen(sect);
    return cd_key_section_len(k->path) == n && strncmp(k->path, sect, n) == 0;
}

const char *cd_key_leaf(const cd_key *k)
{
    size_t n = cd_key_section_len(k->path);
    return k->path + n + (k->path[n] == '.');
}

/* i-th distinct child name of sect (keys and sub-sections, not "x[]"), into buf. */
int cd_key_child(const char *sect, int want, char *buf, size_t n)
{
    size_t sl = strlen(sect);
    int count = 0;
    for (size_t i = 0; i < cd_config_nkeys; i++) {
        const char *p = cd_config_keys[i].path;
        if (sl && (strncmp(p, sect, sl) != 0 || p[sl] != '.')) continue;
        const char *c = p + (sl ? sl + 1 : 0);
        size_t len = strcspn(c, ".");
        if (len >= 2 && c[len - 2] == '[') continue;
        int dup = 0;
        for (size_t k = 0; k < i && !dup; k++) {
            const char *q = cd_config_keys[k].path;
            if (sl && (strncmp(q, sect, sl) != 0 || q[sl] != '.')) continue;
            const char *cq = q + (sl ? sl + 1 : 0);
            dup = strcspn(cq, ".") == len && strncmp(cq, c, len) == 0;
        }
        if (dup) continue;
        if (count++ == want) {
            snprintf(buf, n, "%.*s", (int)len, c);
            return 1;
        }
    }
    return 0;
}

int cd_key_choice_index(const char *choices, const char *s)
{
    int i = 0;
    size_t n = strlen(s);
    for (const char *p = choices; *p; i++) {
        size_t len = strcspn(p, "|");
        if (len == n && strncmp(p, s, n) == 0) return i;
        p += len;
        if (*p == '|') p++;
    }
    return -1;
}

void cd_key_choice_name(const char *choices, int i, char *buf, size_t n)
{
    const char *p = choices;
    for (int c = 0; c < i && *p; c++) {
        p += strcspn(p, "|");
        p += *p == '|';
    }
    snprintf(buf, n, "%.*s", (int)strcspn(p, "|"), p);
}

unsigned cd_key_applies(const cd_key *k) { return k->applies ? k->applies : CD_ALL_CHOICES; }

/* Known keys of sect that apply to choice, as "a, b, c". */
void cd_key_known_list(const char *sect, const cd_key *sel, int choice, char *buf, size_t n)
{
    char name[64], full[256];
    size_t j = 0;
    buf[0] = 0;
    for (int i = 0; cd_key_child(sect, i, name, sizeof name); i++) {
        snprintf(full, sizeof full, "%s%s%s", sect, *sect ? "." : "", name);
        int ok = 0, any = 0;
        for (size_t k = 0; k < cd_config_nkeys; k++)
            if (strcmp(cd_config_keys[k].path, full) == 0) {
                any = 1;
                ok |= !sel || choice < 0 || (cd_key_applies(&cd_config_keys[k]) >> choice & 1u);
            }
        if (ok || !any) j += (size_t)snprintf(buf + j, j < n ? n - j : 0, "%s%s", j ? ", " : "", name);
    }
}

void cd_key_range_text(const cd_key *k, char *buf, size_t n)
{
    if (k->lo_kind && k->hi_kind) {
        if (k->type == CD_KT_INT && k->hi - k->lo == 1) snprintf(buf, n, "%g or %g", k->lo, k->hi);
        else snprintf(buf, n, "in %c%.10g, %.10g%c", k->lo_kind, k->lo, k->hi, k->hi_kind);
    } else if (k->lo_kind) {
        snprintf(buf, n, "%s %g", k->lo_kind == '(' ? ">" : ">=", k->lo);
    } else if (k->hi_kind) {
        snprintf(buf, n, "%s %g", k->hi_kind == ')' ? "<" : "<=", k->hi);
    } else {
        buf[0] = 0;
    }
}

/* choices "a|b|c" as "a, b, c" (sep ',') or "a | b | c" (sep '|') */
static void choices_text(const char *choices, char sep, char *buf, size_t n)
{
    size_t j = 0;
    for (const char *p = choices; *p && j + 4 < n; p++) {
        if (*p != '|') {
            buf[j++] = *p;
            continue;
        }
        if (sep == '|') buf[j++] = ' ';
        buf[j++] = sep;
        buf[j++] = ' ';
    }
    buf[j] = 0;
}

void cd_key_expect_text(const cd_key *k, char *buf, size_t n)
{
    char r[96], ch[160];
    cd_key_range_text(k, r, sizeof r);
    switch (k->type) {
    case CD_KT_STRING:
        snprintf(buf, n, "%s", (k->flags & CD_KF_NONEMPTY) ? "a non-empty string" : "a string");
        break;
    case CD_KT_ENUM:
        choices_text(k->choices, ',', ch, sizeof ch);
        snprintf(buf, n, "%s%s", strchr(k->choices, '|') ? "one of " : "", ch);
        break;
    case CD_KT_BOOL:
        snprintf(buf, n, "true or false");
        break;
    case CD_KT_INT:
        if (k->lo_kind && k->hi_kind && k->hi - k->lo == 1) snprintf(buf, n, "%s", r);
        else snprintf(buf, n, "an integer%s%s", r[0] ? " " : "", r);
        break;
    case CD_KT_UINT:
        snprintf(buf, n, "an unsigned integer");
        break;
    case CD_KT_REAL:
        snprintf(buf, n, "a number%s%s", r[0] ? " " : "", r);
        break;
    case CD_KT_VEC3:
        snprintf(buf, n, "a list of 3 numbers%s", (k->flags & CD_KF_UNIT) ? ", not all zero" : "");
        break;
    case CD_KT_LIST:
        snprintf(buf, n, "a list of %d to %d mappings", k->min_items, k->max_items);
        break;
    case CD_KT_SEGMENTS:
        snprintf(buf, n, "a list of %d to %d segments [ax, ay, az, bx, by, bz, radius] (radius > 0)", k->min_items,
                 k->max_items);
        break;
    }
}

/* Short type column for the help table. */
static void type_text(const cd_key *k, char *buf, size_t n)
{
    char r[96], ch[120];
    cd_key_range_text(k, r, sizeof r);
    switch (k->type) {
    case CD_KT_STRING:
        snprintf(buf, n, "%s", (k->flags & CD_KF_NONEMPTY) ? "non-empty string" : "string");
        break;
    case CD_KT_ENUM:
        choices_text(k->choices, '|', ch, sizeof ch);
        snprintf(buf, n, "%s", ch);
        break;
    case CD_KT_BOOL:
        snprintf(buf, n, "bool");
        break;
    case CD_KT_INT:
        snprintf(buf, n, "integer%s%s", r[0] ? " " : "", r);
        break;
    case CD_KT_UINT:
        snprintf(buf, n, "unsigned integer");
        break;
    case CD_KT_REAL:
        snprintf(buf, n, "real%s%s", r[0] ? " " : "", r);
        break;
    case CD_KT_VEC3:
        snprintf(buf, n, "[x, y, z]%s", (k->flags & CD_KF_UNIT) ? " nonzero" : "");
        break;
    case CD_KT_LIST:
        snprintf(buf, n, "list of %d..%d mappings", k->min_items, k->max_items);
        break;
    case CD_KT_SEGMENTS:
        snprintf(buf, n, "list of %d..%d [a, b, radius]", k->min_items, k->max_items);
        break;
    }
}

/* The choices of sel whose bits are in mask, as "a, b". */
static void mask_text(const cd_key *sel, unsigned mask, char *buf, size_t n)
{
    size_t j = 0;
    unsigned bit = 1;
    buf[0] = 0;
    for (const char *p = sel->choices; *p; bit <<= 1) {
        size_t len = strcspn(p, "|");
        if (mask & bit) j += (size_t)snprintf(buf + j, j < n ? n - j : 0, "%s%.*s", j ? ", " : "", (int)len, p);
        p += len;
        if (*p == '|') p++;
    }
}

static int bits_of(const cd_key *sel)
{
    int n = 1;
    for (const char *p = sel->choices; *p; p++) n += *p == '|';
    return n;
}

/* Default and condition text of one key, as both listings print them. */
static void key_texts(const cd_key *k, char *def, size_t ndef, char *cond, size_t ncond)
{
    char m[160];
    const cd_key *sel = cd_key_selector_of(k);
    unsigned all = sel ? (1u << bits_of(sel)) - 1u : CD_ALL_CHOICES;
    unsigned applies = k->applies ? k->applies : all;
    unsigned required = k->required & applies;
    if (k->def) snprintf(def, ndef, "%s", k->def);
    else snprintf(def, ndef, "%s", required == applies ? "required" : required ? "see below" : "-");
    cond[0] = 0;
    if (sel && applies != all) {
        mask_text(sel, applies, m, sizeof m);
        snprintf(cond + strlen(cond), ncond - strlen(cond), " Only for %s = %s.", sel->path, m);
    }
    if (sel && required && required != applies) {
        mask_text(sel, required, m, sizeof m);
        snprintf(cond + strlen(cond), ncond - strlen(cond), " Required for %s = %s.", sel->path, m);
    }
    if (k->flags & CD_KF_RESUMABLE) snprintf(cond + strlen(cond), ncond - strlen(cond), " May change on --resume.");
    if (k->conflicts) {
        size_t sl = cd_key_section_len(k->path);
        snprintf(cond + strlen(cond), ncond - strlen(cond), " Not together with %.*s.%s.", (int)sl, k->path,
                 k->conflicts);
    }
}

/* Text for a Markdown table cell: | and < escaped. */
static void md_cell(FILE *f, const char *t)
{
    for (; *t; t++) {
        if (*t == '|') fputs("\\|", f);
        else if (*t == '<') fputs("&lt;", f);
        else fputc(*t, f);
    }
}

void cd_config_print_keys(void *stream, int markdown)
{
    FILE *f = stream ? (FILE *)stream : stdout;
    char type[128], def[64], cond[256];
    if (markdown) {
        fprintf(f, "| key | type and range | unit | default | meaning |\n|---|---|---|---|---|\n");
        for (size_t i = 0; i < cd_config_nkeys; i++) {
            const cd_key *k = &cd_config_keys[i];
            type_text(k, type, sizeof type);
            key_texts(k, def, sizeof def, cond, sizeof cond);
            fprintf(f, "| `%s` | ", k->path);
            md_cell(f, type);
            fprintf(f, " | %s | %s%s%s | ", k->unit,
                    strcmp(def, "required") && strcmp(def, "-") && strcmp(def, "see below") ? "`" : "", def,
                    strcmp(def, "required") && strcmp(def, "-") && strcmp(def, "see below") ? "`" : "");
            md_cell(f, k->meaning);
            fprintf(f, ".");
            md_cell(f, cond);
            fprintf(f, " |\n");
        }
        return;
    }
    int wk = 3, wt = 4, wu = 4;
    for (size_t i = 0; i < cd_config_nkeys; i++) {
        const cd_key *k = &cd_config_keys[i];
        type_text(k, type, sizeof type);
        if ((int)strlen(k->path) > wk) wk = (int)strlen(k->path);
        if ((int)strlen(type) > wt) wt = (int)strlen(type);
        if ((int)strlen(k->unit) > wu) wu = (int)strlen(k->unit);
    }
    fprintf(f, "Run-file keys (YAML 1.1, SI units).  name[] stands for every item of the list name.\n\n");
    fprintf(f, "%-*s  %-*s  %-*s  %s\n", wk, "KEY", wt, "TYPE", wu, "UNIT", "DEFAULT");
    fprintf(f, "    MEANING\n\n");
    for (size_t i = 0; i < cd_config_nkeys; i++) {
        const cd_key *k = &cd_config_keys[i];
        type_text(k, type, sizeof type);
        key_texts(k, def, sizeof def, cond, sizeof cond);
        fprintf(f, "%-*s  %-*s  %-*s  %s\n", wk, k->path, wt, type, wu, k->unit, def);
        fprintf(f, "    %s.%s\n", k->meaning, cond);
    }
}
