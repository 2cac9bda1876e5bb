/* The run-file layout of kernels/runfile.def as C names, and the read
 * primitives that every C reader of run files shares: the resume
 * (io_h5_read.c), `capdem analyze` (host/analysis/analyze_read.c) and `capdem
 * export` (host/export/export_read.c).  The writer (io_h5*.c) uses the same names
 * through io_h5_internal.h.  Implemented in io_h5_layout.c; the layout is
 * documented in docs/output.md. */
#ifndef CD_IO_H5_LAYOUT_H
#define CD_IO_H5_LAYOUT_H
#include <stddef.h>
#include <hdf5.h>
#include "core/state.h"

/* ---- the table ------------------------------------------------------------ */

/* Groups and datasets of runfile.def: CDH5_PATH(WALLS_VALUE) is "/walls/value". */
enum cdh5_path_id {
#define CD_H5_GROUP(id, path, made, meaning)         CDH5_PATH_ID_##id,
#define CD_H5_DATASET(id, path, type, unit, meaning) CDH5_PATH_ID_##id,
#include "runfile.def"
    CDH5_N_PATHS
};
extern const char *const cdh5_paths[CDH5_N_PATHS];
#define CDH5_PATH(id) (cdh5_paths[CDH5_PATH_ID_##id])

/* Link and attribute names of runfile.def: CDH5_NAME(COMMIT) is "n_snapshots". */
enum cdh5_name_id {
#define CD_H5_NAME(id, name, meaning) CDH5_NAME_ID_##id,
#include "runfile.def"
    CDH5_N_NAMES
};
extern const char *const cdh5_names[CDH5_N_NAMES];
#define CDH5_NAME(id) (cdh5_names[CDH5_NAME_ID_##id])

#define CDH5_PATH_LEN 512

/* How a column of fields.def is stored. */
enum cdh5_store {
    CDH5_FIXED,  /* once, H5MD fixed data: <group>/<name> (rows[, ncomp]) */
    CDH5_SERIES, /* per snapshot: <group>/<name>/value (snapshots, rows[, ncomp]) */
    CDH5_ROWS    /* active rows of all snapshots concatenated: <group>/<name> (rows[, ncomp]) */
};

enum cdh5_store cdh5_store_of(const cd_field_info *f);
/* The group that holds the columns of g: "/particles/all", "/particles/prims",
 * "/contacts", "/wall_contacts". */
const char *cdh5_group_path(enum cd_field_group g);
/* Path of the dataset that holds the column's values. */
void cdh5_field_path(const cd_field_info *f, char *buf, size_t len);
/* The column of fields.def called name, or NULL. */
const cd_field_info *cdh5_column(const char *name);
/* Path of the column called name into buf (CDH5_PATH_LEN bytes), which it
 * returns; a path that no file holds when fields.def has no such column. */
const char *cdh5_column_path(const char *name, char *buf);
/* H5T_NATIVE_DOUBLE, H5T_NATIVE_INT32, or H5T_NATIVE_UINT8 for a FLAG
 * column (an int32 in the file) (not to be closed). */
hid_t cdh5_mem_type(const cd_field_info *f);
/* Bytes of one row of column f in the file (a FLAG column's 4, its
 * memory's 1): what its chunks are sized by, so that the file's layout
 * does not follow the memory's. */
size_t cdh5_file_row_bytes(const cd_field_info *f);
/* Compound type of cd_wall in memory, as /walls/value stores it (the
 * members of runfile.def; caller closes). */
hid_t cdh5_wall_mem_type(void);

/* ---- reading ---------------------------------------------------------------- */

/* snprintf into err, followed by the innermost message of HDF5's error
 * stack when it holds one. */
void cdh5_msg(char *err, size_t errlen, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Silences HDF5's automatic error printing inside a public function. */
typedef struct {
    H5E_auto2_t func;
    void *data;
} cdh5_quiet;
void cdh5_quiet_begin(cdh5_quiet *q);
void cdh5_quiet_end(const cdh5_quiet *q);

/* Opens a run file read-only with the strong close degree (every reader
 * in a process must open a file the same way), err naming it on failure;
 * returns < 0 then. */
hid_t cdh5_open_ro(const char *path, char *err, size_t errlen);
/* 1 when every link of the absolute or relative path exists, else 0. */
int cdh5_exists(hid_t loc, const char *path);
/* Rank of the dataset, dims (up to 3) in dims; -1 on failure. */
int cdh5_dims(hid_t dset, hsize_t dims[3]);
/* Reads count0 rows from row start0 of a dataset of rank 1..3 into buf. */
herr_t cdh5_read_rows(hid_t dset, hsize_t start0, hsize_t count0, hid_t memtype, void *buf);
/* H5Dread of the selection fs of dset into ms: where memtype is
 * H5T_NATIVE_UINT8 (a FLAG column), a value outside 0..255 fails the read
 * instead of being clipped. */
herr_t cdh5_read(hid_t dset, hid_t memtype, hid_t ms, hid_t fs, void *buf);
/* Snapshots completely on disk: min(commit attribute, length of the
 * snapshot step and time); 0 when the file has no snapshot yet; -1 on error. */
long long cdh5_committed(hid_t file, const char *path, char *err, size_t errlen);
/* Rows of column f in dataset d (FIXED: dims[0], SERIES: dims[1], ROWS:
 * dims[0]) after checking its rank, ncomp and number class; -1 with a
 * message naming file and dpath when they do not fit. */
long long cdh5_field_rows(hid_t d, const cd_field_info *f, const char *dpath, const char *file, char *err,
                          size_t errlen);
/* The string dataset dpath of the open file (fixed or variable length,
 * at most max_bytes), malloc'd (caller frees); NULL with a message naming
 * file and dpath in err. */
char *cdh5_read_string(hid_t f, const char *file, const char *dpath, size_t max_bytes, char *err, size_t errlen);

#endif
