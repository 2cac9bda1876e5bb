/* The OpenCL backend's own state and the functions its files share
 * (docs/opencl.md).  backend_cl_device.c: platform, device, program;
 * backend_cl_buffers.c: device buffers, upload, download;
 * backend_cl_neighbors.c: the Verlet list built on the device;
 * backend_cl.c: the operations table (start, step, sync, stop). */
#ifndef CD_BACKEND_CL_H
#define CD_BACKEND_CL_H
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include "core/sim.h"
#include "broadphase.h"
#include "field_groups.h"

/* Kernels of the .cl files in kernels/cl.  Those marked "cols" in backend_cl_device.c
 * take the state's columns as their first CD_CL_N_COLS arguments. */
enum cd_cl_kernel {
    CD_CLK_ADVANCE,
    CD_CLK_PAIR_FORCES,
    CD_CLK_WALL_FORCES,
    CD_CLK_GATHER_KICK,
    CD_CLK_CHECK_FINITE,
    CD_CLK_WALL_LOAD,
    CD_CLK_WALL_LOAD_SUM,
    CD_CLK_BOUNDS,
    CD_CLK_BOX,
    CD_CLK_BOX_UP,
    CD_CLK_GRID,
    CD_CLK_BIN,
    CD_CLK_CELL_FILL,
    CD_CLK_PAIR_COLLECT,
    CD_CLK_PAIR_PLACE,
    CD_CLK_PAIR_FILL,
    CD_CLK_PAIR_KEYS,
    CD_CLK_PAIR_CARRY,
    CD_CLK_GATHER_COUNT,
    CD_CLK_GATHER_FILL,
    CD_CLK_GATHER_SORT,
    CD_CLK_SCAN_BLOCKS,
    CD_CLK_SCAN_TOP,
    CD_CLK_SCAN_FILL,
    CD_CLK_WALL_CAND_COUNT,
    CD_CLK_WALL_CAND_FILL,
    CD_CLK_WALL_CARRY,
    CD_CLK_PRIM_REFS,
    CD_CLK_OBS_TOUCH_PAIRS,
    CD_CLK_OBS_TOUCH_WALLS,
    CD_CLK_OBS_PARTICLES,
    CD_CLK_OBS_PAIRS,
    CD_CLK_OBS_WALLS,
    CD_CLK_OBS_MERGE,
    CD_CLK_HALO_PACK,
    CD_CLK_HALO_UNPACK,
    CD_CLK_WALL_FN,
    CD_CLK_VISIT_COUNT,
    CD_CLK_VISIT_FILL,
    CD_CLK_COUNT
};

/* Column indices: the order of kernels/fields.def, which is the order of
 * cd_fields[] and of the kernels' column parameters; the device columns
 * only, which come first in cd_fields[] (kernels/field_groups.h). */
enum {
#define CD_FIELD(group, ctype, h5type, ncomp, name, unit, meaning) CD_ON_DEVICE_##group(CD_CL_F_##name CD_COMMA)
#include "fields.def"
#undef CD_FIELD
    CD_CL_N_FIELDS
};
/* Kernel arguments taken by the columns: the fields', then the
 * primitives' arms (prim_arm, arm), the step's inertia (inertia,
 * inertia_iso) and the force and torque where the step holds them (force,
 * torque: kernels/cl/col_params.h). */
#define CD_CL_N_COLS (CD_CL_N_FIELDS + 6)

/* The pair columns that carry history across a rebuild exist twice: the
 * new list is filled from the old one.  One such set, with its keys. */
typedef struct {
    cl_mem active, shear, keys; /* cd_flag, cd_vec3 [m], cd_ulong */
    size_t cap;                 /* rows */
} cd_cl_pairset;

typedef struct cd_cl {
    /* first error (sticky): later calls do nothing until it is reported */
    cl_int status;
    char failed[160];

    cl_platform_id platform;
    cl_device_id device;
    int device_index, device_count; /* the device taken among the platforms' eligible ones (cd_cl_use_nth_device) */
    cl_context ctx;
    cl_command_queue queue;
    cl_program program;
    cl_kernel k[CD_CLK_COUNT];
    size_t local;   /* work-group size of the one-item-per-row kernels */
    char desc[800]; /* platform and device, for messages */

    /* state columns; pair columns have cap_pairs rows, except pair_active
     * and pair_shear, which are those of hist[cur] (cd_cl_col) */
    cl_mem col[CD_CL_N_FIELDS];
    cl_mem prim_arm, arm; /* the primitives' arms (kernels/cols.h; no reorder: the host's rows) */
    int arms_all;         /* every primitive has an arm: prim_arm is bound as null (cd_prim_arm_of) */
    /* the step's inertia (kernels/cols.h, cd_inertia_of): one of the two,
     * the other bound as null */
    cl_mem inertia, inertia_iso;
    /* the particles' force and torque where the step holds them
     * (kernels/cols.h, cd_cols.force): from a start to its first advance
     * (the host's), for the whole run on an MPI rank; NULL otherwise (the
     * first advance and the sync sum them from the rows), bound as null */
    cl_mem force, torque;
    size_t cap_pairs;
    cd_cl_pairset hist[2];
    int cur;
    size_t n_pairs;      /* rows of the current list */
    cl_mem walls;        /* cd_wall[n_walls] */
    cl_mem flags;        /* cd_int[3]: skin exceeded, highest non-finite particle, slot overflow */
    cl_mem scratch_real; /* wall load result */
    cl_mem load_part;    /* per-chunk sums of a wall load (CD_LOAD_CHUNK) */
    /* observables (kernels/observe_items.h): contacts per particle, block
     * sums (grown with the pair rows), merged slots */
    cl_mem obs_touch, obs_part, obs_total;
    size_t obs_cap_blocks;

    /* neighbour-list workspace */
    cl_mem partial, grid; /* the tree of boxes (7 reals each, kernels/neighbor_items.h), the cd_grid */
    cl_mem part_cell, part_bound, cell_count, cell_start, cell_cursor, cell_parts;
    size_t cell_cap; /* cells the grid may have: 8 n_prims + 64 */
    cl_mem pair_count, pair_offset, block_sum;
    size_t block_sum_cap; /* entries block_sum holds (the levels of the longest scan) */
    /* the pair pass's visiting order, rows grouped by kind (kernels/neighbor_items.h,
     * pass 11; mixtures only, else none: the direct order), its counting sort's starts */
    cl_mem pair_visit, visit_starts;
    size_t cap_visit, cap_visit_starts, n_visit;
    cl_mem cand; /* candidates per primitive, slot entries each */
    cd_int slot;
    cl_mem gather_count, gather_start, gather_cursor, gather_rows;
    size_t gather_cap;
    /* wall candidates of the last build (cd_item_wall_candidates): counts
     * per particle, CSR offsets, rows (sized by the build's count) */
    cl_mem wall_count, wall_start, wall_rows;
    cl_mem wall_out; /* cd_wall_entry per candidate: history and outputs of its wall contact (fields.def, WALLC*) */
    cd_int n_wall_rows;
    size_t cap_wall_rows; /* entries wall_rows and wall_out hold */
    /* the candidates of the build before (or the host's rows in contact,
     * uploaded at the start), whose history a build carries over */
    cl_mem old_wall_rows, old_wall_out;
    cd_int n_old_wall_rows;
    size_t cap_old_wall_rows;
    int wall_out_valid;               /* wall_out holds the step's wall-contact outputs (forces since start) */
    int wall_out_pending;             /* ... newer than the host's columns (expanded at sync) */
    cd_wall host_walls[CD_MAX_WALLS]; /* the walls as the device moves them, for the rebuild test */
    int cols_dirty;                   /* a column buffer changed: rebind the column arguments */

    /* Under MPI (src/backend/opencl/backend_cl_mpi.c): the ghost refresh's
     * lists of local particles (sent, received) and their rows of
     * CD_HALO_REALS reals, and a wall load's F_n per primitive */
    cl_mem halo_send_list, halo_recv_list, halo_send, halo_recv, wall_fn;
    size_t halo_ns, halo_nr;
} cd_cl;

/* Kernel sources embedded at build time (cd_cl_sources.c, generated by
 * kernels/cl/embed_kernels.cmake): every .cl file of kernels/cl (program = 1) and
 * every header they include, by file name. */
typedef struct {
    const char *name; /* file name without folder, e.g. "segseg.h" */
    const char *text;
    int program; /* 1 for a .cl file, a part of the program */
} cd_cl_source;
extern const cd_cl_source cd_cl_sources[];
extern const int cd_cl_n_sources;

/* backend_cl_device.c */
int cd_cl_open(cd_cl *cl, const char *device_request, char *err, size_t errlen);
void cd_cl_close(cd_cl *cl);
const char *cd_cl_error_name(cl_int code);
/* The program text cd_cl_open builds: the kernels of kernels/cl/ with
 * their includes expanded (malloc'd; the caller frees it), or NULL with
 * err.  tests/backend/test_cl_strict.sh compiles it with Clang's strict
 * OpenCL C 1.2 (what NVIDIA's compiler refuses, PoCL may accept). */
char *cd_cl_program_source(char *err, size_t errlen);
/* Records the first failure; returns nonzero once any call has failed. */
int cd_cl_check(cd_cl *cl, cl_int rc, const char *what);
/* Formats the recorded failure into err. */
void cd_cl_report(const cd_cl *cl, char *err, size_t errlen);
int cd_cl_arg(cd_cl *cl, enum cd_cl_kernel k, cl_uint index, size_t size, const void *value);
/* Enqueues kernel k over n items (none when n is 0). */
int cd_cl_run(cd_cl *cl, enum cd_cl_kernel k, size_t n);
/* Does kernel k take the columns as its first arguments? */
int cd_cl_kernel_takes_cols(enum cd_cl_kernel k);

/* backend_cl_buffers.c */
int cd_cl_buffers_create(cd_cl *cl, cd_sim *sim);
int cd_cl_buffers_upload(cd_cl *cl, cd_sim *sim);
int cd_cl_buffers_download(cd_cl *cl, cd_sim *sim);
/* The columns of fields.def at the n_only offsets (in cd_state) alone,
 * with the arms and the wall rows in contact, as cd_cl_buffers_download
 * brings every column; only NULL: every column. */
int cd_cl_buffers_download_cols(cd_cl *cl, cd_sim *sim, const size_t *only, size_t n_only);
void cd_cl_buffers_release(cd_cl *cl);
/* Makes the pair columns, history set hist[which] and the gather rows
 * hold at least n rows (with headroom).  Contents are kept only where no
 * buffer had to grow. */
int cd_cl_reserve_pairs(cd_cl *cl, size_t n, int which);
/* Room for n wall candidates in wall_rows and wall_out (contents dropped). */
int cd_cl_reserve_wall_rows(cd_cl *cl, size_t n);
/* The wall candidates become the old ones (their history for the build's
 * carry-over); the old buffers (none after a build: released by
 * cd_cl_release_old_wall_rows) become the new, empty candidates'. */
void cd_cl_keep_wall_rows(cd_cl *cl);
/* After the carry-over: the old candidates' buffers released, so that the
 * steps hold the new candidates only. */
void cd_cl_release_old_wall_rows(cd_cl *cl);
/* The buffer bound as column f (the current history set for pair_active
 * and pair_shear). */
cl_mem cd_cl_col(const cd_cl *cl, int f);
/* Binds the column buffers to every kernel that takes them (after a buffer
 * was created or the history sets were swapped). */
int cd_cl_bind_cols(cd_cl *cl);
/* Binds force and torque (either may be NULL: bound as null) as the
 * columns' force and torque of every kernel that takes the columns
 * (kernels/cols.h, cd_cols.force). */
int cd_cl_bind_force(cd_cl *cl, cl_mem force, cl_mem torque);
/* Releases the host's force and torque that the step held since the start
 * (after the first advance, in one process) and binds null in their place. */
void cd_cl_force_release(cd_cl *cl);
cl_mem cd_cl_buffer(cd_cl *cl, size_t bytes, const char *what);
/* Sets count ints of buf from index first to value. */
int cd_cl_fill_int(cd_cl *cl, cl_mem buf, cd_int value, size_t first, size_t count);
/* Exclusive scan of n ints of in into out (n + 1 entries). */
int cd_cl_scan(cd_cl *cl, cl_mem in, size_t n, cl_mem out);

/* backend_cl_neighbors.c */
int cd_cl_neighbors_build(cd_cl *cl, cd_sim *sim);

#endif
