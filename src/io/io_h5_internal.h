/* Private to the io_h5*.c files: the writer's state and helpers.  The
 * layout (kernels/runfile.def) and the read primitives the writer shares
 * with every reader are in io_h5_layout.h; the layout is documented in
 * docs/output.md. */
#ifndef CD_IO_H5_INTERNAL_H
#define CD_IO_H5_INTERNAL_H
#include <stddef.h>
#include <hdf5.h>
#include "core/state.h"
#include "config/config.h"
#include "shapes/shapes.h"
#include "io/io_h5.h"
#include "io/io_h5_journal.h"
#include "io/io_h5_layout.h"

/* Short names of the table entries (kernels/runfile.def) the writer and
 * the resume use most. */
#define CDH5_SNAP_STEP     CDH5_PATH(SNAP_STEP)
#define CDH5_SNAP_TIME     CDH5_PATH(SNAP_TIME)
#define CDH5_WALLS_VALUE   CDH5_PATH(WALLS_VALUE)
#define CDH5_CONTROL_VALUE CDH5_PATH(CONTROL_VALUE)
#define CDH5_C_OFFSET      CDH5_PATH(C_OFFSET)
#define CDH5_W_OFFSET      CDH5_PATH(W_OFFSET)
#define CDH5_W_INDEX       CDH5_PATH(W_INDEX)
/* Root attribute: snapshots completely on disk (the commit record). */
#define CDH5_COMMIT_ATTR CDH5_NAME(COMMIT)

/* 0 when a row of f is ncomp scalars of its kind, else -1 with a message. */
int cdh5_field_check(const cd_field_info *f, char *err, size_t errlen);

/* Largest row of any column, and at least 8 (int64 scratch). */
size_t cdh5_max_row_bytes(void);

/* The attribute units of /walls/value: "type 1, point m, ...", the wall
 * members of runfile.def and their units. */
void cdh5_wall_units(char *buf, size_t len);

/* ---- writer: io_h5.c, io_h5_write.c, io_h5_snapshot.c ------------------- */

#define CDH5_OBS_BLOCK   1024            /* time-series rows buffered before a write */
#define CDH5_CLOCK_CHUNK 1024            /* rows per chunk of step, time, offset, observables */
#define CDH5_SMALL_CHUNK (64u * 1024u)   /* bytes: target chunk of a small per-snapshot dataset */
#define CDH5_LARGE_CHUNK (1024u * 1024u) /* bytes: largest chunk */

typedef struct {
    hid_t dset;  /* FIXED: the data; SERIES: value; ROWS: the rows */
    void *fixed; /* FIXED: what the file holds, to catch changes */
    size_t fixed_bytes;
} cdh5_col;

typedef struct {
    char *name;
    int ncomp;
    hid_t step, time, value;
    hsize_t rows;
} cdh5_obs;

struct cd_output {
    hid_t file;
    char path[1024];
    char err[1024];
    int have_layout;
    size_t n_particles, n_prims, n_walls;
    hsize_t n_snap, c_rows, w_rows; /* snapshots, contact rows, wall-contact rows written */
    hid_t step, time, walls, wall_type, c_offset, c_pi, c_pj, w_offset, w_index, control;
    cdh5_col *cols;   /* one per cd_fields[] entry */
    int n_obs, width; /* width: sum of ncomp */
    cdh5_obs *obs;
    size_t buf_n;
    long long *buf_step;
    double *buf_time, *buf_val;
    /* CD_OUTPUT_REPLACE until the first commit: the file written aside
     * (tmp_path, "" once renamed to path) and the locked file it replaces
     * (old_fd, -1 when none; its device and inode) */
    char tmp_path[1024];
    int old_fd;
    unsigned long long old_dev, old_ino;
    int own_lock;  /* descriptor holding capdem's mark on the file (cdh5_mark), or -1 */
    int io_failed; /* a write failed or found no room: nothing more is written */
    /* reopen: the file cannot be appended to as it is (not a run file,
     * other observables, a dataset the writer appends to missing or
     * unreadable): the input's fault, not a failed write (exit status 2) */
    int refused;
    int writing; /* inside a snapshot, past its checks */
    /* parallel output (io_h5_mpi.c): the rows of the write under way that
     * this rank writes, from its local state (cd_output_snapshot_part):
     * memory row r (of map_rows along dimension mask_dim) into row
     * row_map[r] of the block written, or nowhere (-1); NULL: rank 0
     * writes all of the block */
    const long long *row_map;
    size_t map_rows;
    int mask_dim;
    /* during cd_output_snapshot_part: the part, and the rows in the file
     * of its particles and primitives (global ids, -1: not written here) */
    const cd_output_part *part;
    long long *map_particle, *map_prim;
};

/* Makes sure bytes more can be written at the end of the file (the space
 * is allocated with posix_fallocate past HDF5's end of allocation, so a
 * full disk or a file size limit shows here, before anything of what
 * follows is written, rather than halfway through a flush); -1 with a
 * message naming what, and o->io_failed set, when it cannot. */
int cdh5_reserve(cd_output *o, unsigned long long bytes, const char *what);
/* Puts capdem's mark (an F_OFD_SETLK read lock, see io_h5_target.c) on
 * the file open as fd; -1 when the file system has no such locks. */
int cdh5_mark(int fd);
/* -1 with a message (and o->io_failed) when the file has no name left
 * (deleted, or its folder, while open), else 0. */
int cdh5_check_linked(cd_output *o);
/* Bytes the file grows by when add rows are appended to the chunked
 * dataset d: the chunks those rows start (each allocated whole) and room
 * for its chunk index to grow (0 when no chunk starts). */
unsigned long long cdh5_growth(hid_t d, unsigned long long add);

/* ---- output target: io_h5_target.c ------------------------------------------ */

/* Opens the existing regular file path without truncating it and takes an
 * exclusive flock on it (released by closing the descriptor; refused when
 * another process holds a lock: HDF5 writers and readers lock their files).
 * Returns the descriptor, -2 when path does not exist, -1 with a message. */
int cdh5_target_lock(const char *path, unsigned long long *dev, unsigned long long *ino, char *err, size_t errlen);
/* Creates an empty file with a unique name (mkstemp) next to path, with
 * the permissions a plain create would give and capdem's mark on it; its
 * name into tmp, its descriptor into *fd (kept open while it is written). */
int cdh5_target_aside(const char *path, char *tmp, size_t len, char *err, size_t errlen, int *fd);
/* After the first commit: renames tmp_path over path, unless path no
 * longer is the file locked at creation. */
int cdh5_target_publish(cd_output *o);

/* ---- parallel output: io_h5_mpi.c (MPI builds; else one writer) --------------- */

/* The writer's file is shared by the ranks of cd_output_use_mpi's
 * communicator: every cd_output_* call is collective. */
int cdh5_par_on(void);
/* Rank 0 of it, or the one writer when output is not parallel. */
int cdh5_par_root(void);
/* File access through HDF5's MPI-IO driver on that communicator. */
hid_t cdh5_par_fapl(void);
/* The largest v of the ranks (v alone when not parallel). */
int cdh5_par_max(int v);
/* bytes of buf from rank 0 to every rank (nothing when not parallel). */
void cdh5_par_bcast(void *buf, size_t bytes);
/* Rank 0: the exclusive flock HDF5's serial driver would hold on fd's file. */
void cdh5_par_lock(int fd);
/* Rank 0, before the ranks open a run file to append to it (a resume):
 * 0 when every chunked dataset got its chunks when it was extended (a
 * file written through MPI-IO), else -1 with err set (written by the
 * serial writer: HDF5 1.10 cannot append to it from several ranks). */
int cdh5_par_appendable(const char *path, char *err, size_t errlen);
/* The collective H5Dwrite of the block start..start+cnt (rank dims; the
 * file selection fs; memory ms of shape cnt, or with o->row_map of
 * o->map_rows rows along o->mask_dim): this rank's rows of it (o->row_map)
 * or, with no map, all of it on rank 0 and none on the others.  Not
 * parallel: H5Dwrite as given. */
herr_t cdh5_par_write(const cd_output *o, hid_t d, hid_t mtype, hid_t ms, hid_t fs, int rank, const hsize_t *start,
                      const hsize_t *cnt, const void *buf);

/* Every writer failure goes through FAIL: message into o->err (with the
 * HDF5 detail), printed to stderr, value -1. */
int cdh5_report(cd_output *o);
/* Flush and atomic commit of everything written (io_h5_journal.h); -1
 * with the message reported and o->io_failed set when it fails. */
int cdh5_commit_output(cd_output *o);
#define FAIL(...) (cdh5_msg(o->err, sizeof o->err, __VA_ARGS__), cdh5_report(o))

void cdh5_close_id(hid_t *id); /* group or any object */
void cdh5_close_dset(hid_t *id);

int cdh5_attr_write(cd_output *o, hid_t obj, const char *where, const char *name, hid_t type, hid_t space,
                    const void *buf);
int cdh5_attr_str(cd_output *o, hid_t obj, const char *where, const char *name, const char *value);
int cdh5_attr_ints(cd_output *o, hid_t obj, const char *where, const char *name, const int *v, hsize_t n);
/* Root attribute n_snapshots = n (the commit record). */
int cdh5_write_commit(cd_output *o, hsize_t n);
hid_t cdh5_make_group(cd_output *o, const char *path);
/* Creates a dataset; chunk NULL: contiguous; unit NULL: no unit attribute. */
hid_t cdh5_make_dset(cd_output *o, const char *path, hid_t ftype, int rank, const hsize_t *dims, const hsize_t *maxdims,
                     const hsize_t *chunk, const char *unit);
/* 1-D extendible step (int64) or time (double, unit s) dataset. */
hid_t cdh5_make_clock(cd_output *o, const char *path, int is_time);
int cdh5_write_all(cd_output *o, hid_t d, const char *path, hid_t mtype, const void *buf);
int cdh5_write_real(cd_output *o, const char *path, int rank, const hsize_t *dims, const double *v, const char *unit);
hid_t cdh5_open_dset(cd_output *o, const char *path);
/* Sets the first dimension to n rows. */
int cdh5_set_rows(cd_output *o, hid_t d, const char *what, hsize_t n);
/* Writes count rows at row `at` of an extendible dataset, which then has
 * at + count rows. */
int cdh5_append(cd_output *o, hid_t d, const char *what, hsize_t at, hsize_t count, hid_t mtype, const void *buf);
/* The rows at..at+count of d (rank dims: the dataset's extent dims) from
 * buf, as cdh5_append writes them, without changing the extent. */
int cdh5_write_block(cd_output *o, hid_t d, const char *what, int rank, hsize_t at, hsize_t count, const hsize_t *dims,
                     hid_t mtype, const void *buf);

/* /h5md, /parameters (config, shapes), the empty groups, box, commit 0. */
int cdh5_write_header(cd_output *o, const cd_config *cfg, const cd_shape *shapes, int n_shapes);
/* Writes the buffered time-series rows. */
int cdh5_obs_flush(cd_output *o);
/* Snapshot datasets: created at the first snapshot, or opened on reopen. */
int cdh5_layout_create(cd_output *o, const cd_state *s);
int cdh5_layout_open(cd_output *o);

#endif
