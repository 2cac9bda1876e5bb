/* A simulation: the state, the parameters every kernel needs, the shape
 * catalogue and the neighbour-list workspace. */
#ifndef CD_SIM_H
#define CD_SIM_H
#include <stdio.h>
#include "core/state.h"
#include "config/config.h"
#include "shapes/shapes.h"
#include "contact_law.h"
#include "cols.h"
#include "broadphase.h"
#include "reorder_items.h"
#include "backend/backend.h"

/* Loops over fewer rows than this run on one thread: a parallel region
 * costs microseconds, more than a small loop, and on a loaded machine the
 * threads' barriers cost far more.  Results do not depend on it. */
extern long cd_parallel_min_rows;
#define CD_PARALLEL(rows) ((long)(rows) >= cd_parallel_min_rows)
/* The host threads' sweep (src/backend/omp/sweep.c): particles a block
 * (512), the step's bytes above which its rows and moves interleave
 * (-1: 16 MiB, about half a last-level cache; below it all rows come
 * first) and above which its rows' loop prefetches (-1: 4 MiB); tests set
 * them small. */
extern size_t cd_sweep_block;
extern long cd_sweep_min_bytes;
extern long cd_sweep_prefetch_min_bytes;

/* Per-step constants handed to every kernel. */
typedef struct {
    cd_real dt;             /* time step [s] */
    cd_vec3 gravity;        /* [m/s^2] */
    cd_law_params law;      /* particle-particle contact law */
    cd_law_params wall_law; /* particle-wall contact law (mu = wall friction) */
    cd_real sin_parallel;   /* sine of the parallel-contact cut-off angle [1] */
    cd_int parallel_blend;  /* 1: the continuous parallel rule (material.parallel_blend) */
    cd_int dimension;       /* 3, or 2: motion in the x-y plane only */
    cd_int fixed_spheres;   /* 1: spheres keep their orientation (physics.sphere_orientation: fixed) */
} cd_step_params;

struct cd_sim;

/* The neighbour lists and the build's scratch (kernels/neighbor_items.h),
 * in the memory the step loops run on: the offload device's in the offload
 * variant (device addresses: never dereferenced on the host), host memory
 * otherwise.  Handed to the loops as one firstprivate struct. */
typedef struct {
    /* per-particle gather lists (CSR over pair rows): for particle p the
     * entries gather_rows[gather_start[p] .. gather_start[p+1]), 2 k + side
     * for pair row k (side 1: p owns its primitive j), in ascending order */
    cd_int *gather_start;    /* n_particles + 1 */
    cd_pair_id *gather_rows; /* 2 n_pairs */
    /* per-particle wall candidates (CSR): for particle p the wall-contact
     * rows wall_rows[wall_start[p] .. wall_start[p+1]) that the steps until
     * the next build test (kernels/step_items.h, cd_item_wall_candidates),
     * ascending */
    cd_int *wall_start;      /* n_particles + 1 */
    cd_int *wall_rows;       /* wall_start[n_particles] (cap_wall_rows) */
    cd_wall_entry *wall_out; /* per candidate: history and outputs of its wall contact (fields.def, WALLC*) */
    /* scratch of the build */
    cd_grid *grid;       /* 1 */
    cd_real *part_bound; /* bounding radius per particle [m] */
    cd_real *partial;    /* the tree of boxes (kernels/neighbor_items.h): 7 each, box of centres, largest bound [m] */
    cd_int *part_cell, *cell_count, *cell_start, *cell_parts; /* cell lists (CSR); count doubles as cursor */
    cd_int *pair_count, *pair_offset;                         /* rows per primitive, their offsets (n_prims + 1) */
    cd_prim_id *cand;                                         /* candidate slots, slot per primitive */
    cd_ulong *keys, *old_keys;                                /* sorted keys of the new and the old rows */
    cd_flag *old_active;                                      /* history of the old rows */
    cd_vec3 *old_shear;                                       /* [m] */
    cd_int *count;                                            /* per particle: gather and wall counts, then cursors */
    cd_int *chunk_sum;                                        /* prefix sums' levels (cd_scan_scratch) */
    cd_int *skin_flag; /* offload: 1 when the last advance found an end beyond half the skin (step_omp.c) */
    cd_real *ref_pose; /* CD_ENDS_FROM_POSE: each particle's pose at the build (cd_item_ref_pose; step_items.h) */
    /* memory order (kernels/reorder_items.h, src/backend/omp/reorder.c; allocated at
     * the first build with neighbor.reorder: cells) */
    cd_int *part_uid, *part_at;  /* particle: memory slot -> user id, user id -> memory slot */
    cd_int *prim_uid, *prim_at;  /* the same for primitives */
    cd_int *pair_at;             /* pair rows in user order -> memory row (pair_at_cap) */
    cd_int *pair_ustart;         /* first place of each user primitive's rows in user order (n_prims + 1) */
    cd_int *part_src, *prim_src; /* the reorder's permutation: old slot of each new slot */
    cd_int *new_first;           /* prim_first in the new order (n_particles + 1) */
    cd_ulong *sort_keys;         /* cell keys, twice n_particles (radix sort in and out) */
    cd_int *sort_vals;           /* their slots, twice n_particles */
    cd_int *hist;                /* radix sort: digit counts per chunk, then cursors */
    void *move;                  /* scratch of one column while it moves */
    /* the pair pass's visiting order, rows grouped by kind (kernels/neighbor_items.h,
     * pass 11): made only where the primitives are of both kinds, else null (the
     * direct loop); its counting sort's starts and their scan's levels */
    cd_int *pair_visit, *visit_starts, *visit_scratch;
} cd_nb_lists;

#define CD_NB_REORDER_ALWAYS 2

/* Neighbour-list workspace. */
typedef struct {
    double skin;                     /* Verlet skin [m] */
    long long builds;                /* rebuilds so far */
    int force_rebuild;               /* 1: rebuild at the next step regardless of motion */
    cd_wall walls_ref[CD_MAX_WALLS]; /* the walls at the last build (cd_bp_wall_moved) */
    size_t n_wall_rows;              /* entries of d.wall_rows (wall_start[n_particles]) */
    size_t cap_wall_rows;            /* entries d.wall_rows and d.wall_out hold */
    int walls_from_host;             /* the next build takes the wall history from the host's rows (a start) */
    int wall_out_valid;              /* d.wall_out holds the step's wall-contact outputs (forces since start) */
    int wall_out_pending;            /* ... newer than the host's columns (expanded at sync) */
    int force_summed;                /* 1: the first advance of a call sums the force and torque from the
                                        rows (a force evaluation since the start, cd_item_advance); 0 (a
                                        start without forces, a state never started, a build between calls:
                                        cd_sim_force_before_build): it reads the host's */
    int in_step;                     /* 1 while a call of the step runs (its builds keep no force) */
    cd_nb_lists d;                   /* lists and scratch, where the loops run */
    size_t cap_rows;                 /* rows that keys and gather_rows (twice) hold */
    size_t cap_old;                  /* rows that old_keys, old_active, old_shear hold */
    size_t cell_cap;                 /* cells the cell lists hold */
    cd_int slot;                     /* candidate slot per primitive (doubles when one overflows) */
    int reorder;                     /* neighbor.reorder: 1 cells (the grid cells' order at rebuilds), 0 none;
                                 CD_NB_REORDER_ALWAYS (tests): at every rebuild that changes the order */
    int ordered;                     /* the order maps of d are set (from the first build after start) */
    int host_user;                   /* host memory (host variant, offload build's host fallback): a sync put
                                 the columns in user order; the next step puts them back in memory order
                                 (src/backend/omp/reorder.c) */
    long long reorders;              /* rebuilds that moved particles */
    size_t pair_at_cap;              /* rows d.pair_at holds */
    size_t n_visit;                  /* rows of the visiting order of the last build (0: none, the direct loop) */
    /* entries d.pair_visit and d.visit_starts hold */
    size_t cap_visit, cap_visit_starts;
    /* the visiting order where a backend other than omp keeps it (OpenCL), copied to out: its rows; NULL: d */
    size_t (*visit_get)(const struct cd_sim *sim, cd_int *out);
    /* host threads' sweep (src/backend/omp/sweep.c): the largest distance in memory slots between the
       particles of a row, and per particle 1 when one of its rows joins it to a particle of another
       thread's range, for sweep_threads threads (0: not made since the last build) */
    size_t sweep_lag, sweep_span; /* the lag the sweep uses (n: all rows first, a small state), the span */
    int sweep_prefetch;           /* 1: the rows' loop asks for primitive j's data ahead (a large state) */
    unsigned char *sweep_edge;
    size_t sweep_edge_cap;
    int sweep_threads;
} cd_neighbors;

/* Scratch of the observables' reductions where the steps run (the offload
 * device's memory; src/backend/omp/observe.c). */
typedef struct {
    cd_int *touch;    /* per particle: active contacts (marks the particles that touch) */
    cd_real *partial; /* CD_OBS_SLOTS per block */
    cd_real *total;   /* CD_OBS_SLOTS */
    size_t cap_blocks;
} cd_sim_obs_scratch;

typedef struct cd_sim {
    cd_config cfg;
    cd_state s;
    cd_step_params p;
    cd_shape shapes[CD_MAX_SPECIES];
    int n_shapes;
    cd_neighbors nb;
    cd_sim_obs_scratch obs;
    double collision_time;     /* smallest pair collision time [s] */
    double total_mass;         /* sum of the particle masses [kg] (fixed at set-up) */
    double solid_volume;       /* sum of the particle volumes [m^3] (fixed at set-up) */
    int threads;               /* OpenMP threads in use */
    const cd_backend *backend; /* runs the steps; omp unless chosen otherwise */
    void *backend_data;        /* the backend's own state (device buffers) */
    char device_request[16];   /* --device: cpu | gpu | auto (OpenCL) */
    cd_state probe_base;       /* bulk probe: the relaxed base state every probe starts from (zeroed until then) */
    int snapshot_request;      /* set by a protocol: write a snapshot of this step (then cleared by the run) */
    /* A domain decomposition's say in the rebuild (src/mpi/mpi_backend.c,
     * docs/mpi.md); NULL in one process.  The step calls it after its skin
     * test with that test's answer for this process's particles (0/1) and
     * rebuilds the neighbour list when it returns 1: the answer of every
     * process, the particles already with their new owners; -1 with a
     * message in err: the run stops. */
    int (*rebuild_hook)(struct cd_sim *sim, int rebuild, char *err, size_t errlen);
    void *rebuild_hook_data;
    /* A set-up of part of the run (cd_sim_setup_part; src/mpi, docs/mpi.md
     * "Set-up"): s holds the particles of the global ids gid only
     * (ascending), gprim the global id of each of its primitives, and
     * n_particles, n_prims are the whole run's counts; gid NULL: s is the
     * whole run. */
    struct {
        long long *gid, *gprim;
        size_t n_particles, n_prims;
    } part;
} cd_sim;

/* Does the step hold the particles' force and torque between calls
 * (kernels/cols.h, cd_cols.force)?  On an MPI rank (its rebuild hook set,
 * src/mpi/mpi_backend.c): each call is one step and the ghosts' force and
 * torque come from their owners between calls (cd_item_ghost_io), so the
 * step writes them at its last step and its first advance reads them.  In
 * one process it holds none: the first advance and sync sum them from the
 * rows (docs/performance.md, "Session 18, force and torque not held"). */
static inline int cd_sim_keeps_force(const cd_sim *sim) { return sim->rebuild_hook != NULL; }

/* Builds a simulation from a validated config: shapes, particles placed as
 * init.* says, walls of the domain, step parameters.  Checks the time step
 * against the collision time.  Returns 0, or -1 with a message that names
 * the file and key in err (exit status 2 for the caller). */
int cd_sim_setup(cd_sim *sim, const cd_config *cfg, char *err, size_t errlen);
/* Which particles a set-up builds (an MPI rank: its own and its ghosts),
 * asked once every particle is placed: n centres [m], each particle's
 * species and length scale [1] (sim's shapes, config and skin are set).
 * Returns 0: every particle; 1: the ascending global ids in *held (a new
 * array, *n_held of them); -1: refused (err names the key, exit 2). */
typedef int (*cd_setup_keep_fn)(const struct cd_sim *sim, const cd_vec3 *centre, const int *species,
                                const double *scale, size_t n, long long **held, size_t *n_held, char *err,
                                size_t errlen);
/* cd_sim_setup building the particles keep chooses only (sim->part; keep
 * NULL: every particle, cd_sim_setup).  Every random number is drawn as
 * the whole run draws it, so the rows built have the whole run's bits. */
int cd_sim_setup_part(cd_sim *sim, const cd_config *cfg, cd_setup_keep_fn keep, char *err, size_t errlen);
void cd_sim_free(cd_sim *sim);

/* Chooses the backend (before cd_sim_start).  device: cpu | gpu | auto,
 * used by OpenCL.  Returns 0, or -1 with a message. */
int cd_sim_use_backend(cd_sim *sim, const char *name, const char *device, char *err, size_t errlen);

/* Hands the host state to the backend.  compute_forces = 1 for a new run
 * (neighbour list and forces of the initial state), 0 after reading a
 * checkpoint (its forces are kept, the neighbour list is rebuilt). */
int cd_sim_start(cd_sim *sim, int compute_forces, char *err, size_t errlen);

/* Refresh, neighbour list and the forces of the initial state on the
 * chosen backend: cd_sim_start(sim, 1, ...) failing the process on error.
 * For tests and tools. */
int cd_sim_initial_forces(cd_sim *sim);

/* Advances n steps. Returns 0, or -1 when the run blew up (message in err). */
int cd_sim_step(cd_sim *sim, long long n, char *err, size_t errlen);

/* Makes sim->s current: copies the device state back and derives the
 * output-only pair columns (cd_sim_derive_pair_output). */
int cd_sim_sync(cd_sim *sim, char *err, size_t errlen);

/* Sum of the normal forces the particles exert on wall w [N] at the last
 * force evaluation: the backend's reduction, or a sync and a host sum in a
 * fixed order. */
int cd_sim_wall_load(cd_sim *sim, int w, double *load, char *err, size_t errlen);

/* The host columns of s as the per-item functions of kernels/step_items.h
 * take them (the device columns of fields.def only). */
cd_cols cd_sim_host_cols(cd_state *s);

/* Fills the output-only pair columns (fields.def, PAIR_OUT: normal,
 * tangential force, torques) of every row from the step's columns of the
 * host state (src/io/pair_output.c).  cd_sim_sync calls it. */
void cd_sim_derive_pair_output(cd_sim *sim);

/* The same sum over the host columns, in the same chunk order. */
double cd_sim_wall_load_host(cd_sim *sim, int w);

/* Checks the host state for non-finite values (a blown-up run). */
int cd_sim_check_state(const cd_sim *sim, char *err, size_t errlen);

/* Host-side helpers of the omp backend, shared with other backends for
 * set-up work: world axis ends and angular velocities from the poses. */
void cd_sim_refresh(cd_sim *sim);

/* Observables (deterministic sums): one member per SUM or MAX row of
 * kernels/observables.def, which gives its unit and meaning. */
#define CD_OBS_DIMS_ONE
#define CD_OBS_DIMS_VEC3              [3]
#define CD_OBS_DIMS_WALL1             [CD_MAX_WALLS]
#define CD_OBS_DIMS_WALL3             [CD_MAX_WALLS][3]
#define CD_OBS_MEMBER_(member, count) double member CD_OBS_DIMS_##count;
#define CD_OBS_MEMBER_NONE_(member, count)
#define CD_OBS_MEMBER_SUM      CD_OBS_MEMBER_
#define CD_OBS_MEMBER_MAX      CD_OBS_MEMBER_
#define CD_OBS_MEMBER_WALLS    CD_OBS_MEMBER_NONE_
#define CD_OBS_MEMBER_PROTOCOL CD_OBS_MEMBER_NONE_
typedef struct {
#define CD_OBSERVABLE(id, name, unit, count, source, member, meaning) CD_OBS_MEMBER_##source(member, count)
#include "observables.def"
} cd_observables;
/* From the host columns (current after a sync). */
void cd_sim_observe(const cd_sim *sim, cd_observables *o);
/* From the columns the steps work on, without a state copy where the
 * backend sums on its device (the offload variant), else after a sync;
 * the same bits either way.  0, or -1 with a message. */
int cd_sim_observe_step(cd_sim *sim, cd_observables *o, char *err, size_t errlen);
void cd_sim_observe_free(cd_sim *sim);
/* The merged slots (kernels/observe_items.h, CD_OBS_SLOTS) from the host
 * columns: backends' observe. */
void cd_observables_slots(const cd_sim *sim, double *slots);
/* The omp backend's wall_load and observe (src/backend/omp/observe.c):
 * where the steps run (the offload device, or host memory). */
int cd_omp_wall_load(cd_sim *sim, int w, double *load, char *err, size_t errlen);
int cd_omp_observe(cd_sim *sim, double *slots, char *err, size_t errlen);

/* Neighbour list (neighbors.c). */
/* reorder: 1 for neighbor.reorder: cells (src/backend/omp/reorder.c) */
void cd_neighbors_init(cd_neighbors *nb, double skin, int reorder);
void cd_neighbors_free(cd_neighbors *nb);
/* 0, -1 (out of memory) or CD_NB_BLOWUP (particle centres not finite or
 * spread over more than 1e12 particle sizes: the run blew up, and a cell
 * grid of them would overflow its integer coordinates). */
#define CD_NB_BLOWUP (-2)
int cd_neighbors_build(cd_sim *sim);
/* The bounding radii [m] of the last build, copied to out (n_particles,
 * user order); 0, or -1 before the first build.  For tests. */
int cd_neighbors_part_bounds(const cd_sim *sim, double *out);
/* The pair pass's visiting order of the last build (kernels/neighbor_items.h, pass 11) copied to
 * out (room for n_pairs entries) as indices of the host's pair rows after a sync (user order where
 * the omp backend keeps a memory order; out NULL: nothing copied): returns its rows (n_pairs), or 0
 * where the build made none (the rows are visited in order: one kind of row, or before the first
 * build).  For tests and capdem-bench. */
size_t cd_neighbors_pair_visit(const struct cd_sim *sim, cd_int *out);
/* The host's wall-contact outputs (fields.def, WALLC_OUT) from the step's
 * per-candidate ones, when these are newer (nb.wall_out_pending), in the
 * memory order of the step's columns: call after the other columns came
 * back and before they go to user order.  0 or -1 (out of memory). */
int cd_neighbors_wall_out_to_host(cd_sim *sim);

/* Memory order (src/backend/omp/reorder.c, docs/architecture.md "Memory order"). */
/* The maps the step columns are in now (the identity when not reordered),
 * and those of the host columns (the same on host threads; the identity
 * in the offload variant, whose host columns a sync leaves in user order). */
cd_order cd_sim_step_order(const cd_sim *sim);
cd_order cd_sim_host_order(const cd_sim *sim);
/* At a rebuild, before the particles are binned: the particles, their
 * primitives and wall rows put in the order of their grid cells (the
 * grid of the build, d.grid, a host copy of which is g), the maps
 * updated; *moved = 1 when some particle moved (then d.prim_src holds the
 * primitives' old slots).  0, or -1 out of memory. */
int cd_reorder_build(cd_sim *sim, const cd_grid *g, int *moved);
/* At the end of a build: d.pair_at for the new rows.  0, or -1. */
int cd_reorder_pair_rows(cd_sim *sim);
/* The host columns in user order (a sync; rows copied back from a device
 * are in memory order), and (host variant) back in memory order before
 * the next step.  Both no-ops when not reordered.  0, or -1 out of memory. */
int cd_reorder_to_user(cd_sim *sim);
int cd_reorder_to_memory(cd_sim *sim);
/* Frees the maps and forgets the order (backend start and stop). */
void cd_reorder_forget(cd_sim *sim);

#endif
