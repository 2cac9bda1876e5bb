/* HDF5 output of a run (layout after H5MD) and reading it back for resume.
 * The layout is documented in docs/output.md. */
#ifndef CD_IO_H5_H
#define CD_IO_H5_H
#include <stddef.h>
#include <stdint.h>
#include "core/state.h"
#include "config/config.h"
#include "shapes/shapes.h"

typedef struct cd_output cd_output;

/* One named series of the time series (H5MD observables): ncomp values per row. */
typedef struct {
    const char *name; /* dataset group name under /observables */
    const char *unit; /* SI unit */
    int ncomp;        /* values per row (1 for scalars) */
} cd_observable_info;

/* How an output path may be used (cd_output_check_target, cd_output_create_mode). */
enum cd_output_mode {
    CD_OUTPUT_NEW,     /* path must not exist; created exclusively (O_EXCL) */
    CD_OUTPUT_REPLACE, /* an existing path is replaced, but only once the new file's first snapshot is
                         * committed: the new file is written aside (a mkstemp name in the same folder) and
                         * renamed over path then; the old file is locked (flock) meanwhile and is never
                         * replaced while another process holds it */
    CD_OUTPUT_RESUME   /* path must exist, be a regular file and not be held by another process */
};

/* Checks, before anything is written, that path may be used as `how` says:
 * it must not be the same file (device and inode) as any of the n_inputs
 * paths in inputs (NULL entries skipped), must be a regular file when it
 * exists, must not exist for CD_OUTPUT_NEW and must exist for
 * CD_OUTPUT_RESUME, must not be locked by another process (a running
 * capdem, any HDF5 writer), and its folder must exist.  Returns 0, or -1
 * with a message naming path in err.  Touches nothing. */
int cd_output_check_target(const char *path, enum cd_output_mode how, const char *const *inputs, int n_inputs,
                           char *err, size_t errlen);

/* Creates a run file at path as `how` says (CD_OUTPUT_NEW or
 * CD_OUTPUT_REPLACE) and writes the config text verbatim, units, the shape
 * catalogue and the static particle columns.  Nothing existing is truncated:
 * CD_OUTPUT_NEW fails when path exists (created meanwhile by someone else),
 * CD_OUTPUT_REPLACE writes aside and renames at the first committed snapshot
 * (closing before any snapshot leaves the old file as it was and removes the
 * one written aside).  Returns NULL with a message in err on failure. */
cd_output *cd_output_create_mode(const char *path, enum cd_output_mode how, const cd_config *cfg,
                                 const cd_shape *shapes, int n_shapes, const cd_observable_info *obs, int n_obs,
                                 char *err, size_t errlen);

/* cd_output_create_mode(path, CD_OUTPUT_REPLACE, ...): the writer of
 * programs that deliberately rewrite their file (tests, capdem-bench
 * --save-settled). */
cd_output *cd_output_create(const char *path, const cd_config *cfg, const cd_shape *shapes, int n_shapes,
                            const cd_observable_info *obs, int n_obs, char *err, size_t errlen);

/* Opens an existing run file to append to it after a resume: later snapshots
 * and time-series rows are added after the ones for steps <= resume_step, and
 * rows for steps > resume_step (written after that checkpoint by the
 * interrupted run) are discarded.  On failure (NULL) *refused, where not
 * NULL, is 1 when the file as it is cannot be appended to (not a run file,
 * other observables, a dataset the writer appends to missing or unreadable:
 * a refusal of the input) and 0 when a write failed. */
cd_output *cd_output_reopen(const char *path, long long resume_step, const cd_observable_info *obs, int n_obs,
                            int *refused, char *err, size_t errlen);

/* Records, after cd_output_reopen, the config a resume from step `step`
 * runs with: /parameters/resumes/<k> (k = 0, 1, ... in the order of the
 * resumes), the config text verbatim, attributes step and source_path;
 * /parameters/config stays the run's first config.  Written with the next
 * snapshot's flush. */
int cd_output_note_resume(cd_output *o, long long step, const cd_config *cfg);

/* Appends a snapshot: every PARTICLE column, the active contacts (every PAIR
 * column of the active rows) and the active wall contacts, the walls, time
 * and step.  Everything needed to resume bit for bit.  Flushes the file. */
int cd_output_snapshot(cd_output *o, const cd_state *s);

/* Appends one time-series row: values holds, for each observable in the
 * order given at creation, ncomp doubles. */
int cd_output_thermo(cd_output *o, long long step, double time, const double *values);

/* Message of the last failure of a cd_output_* call on o (also printed to
 * stderr when it happened); "" when none. */
const char *cd_output_error(const cd_output *o);

/* Flushes and closes. Returns 0 or -1. */
int cd_output_close(cd_output *o);

/* To be called before any other HDF5 call of a program that writes run
 * files: HDF5 then installs no exit handler.  (HDF5 1.10's exit handler
 * closes the files still open, and crashes on a file whose close failed,
 * as one does after a full disk.)  Every file is closed explicitly. */
void cd_h5_no_atexit(void);

/* MPI builds with parallel HDF5 (docs/mpi.md, "One file"): comm (a
 * pointer to an MPI_Comm of more than one rank) shares the run files that
 * cd_output_create_mode and cd_output_reopen open from now on: they go
 * through HDF5's MPI-IO driver, every cd_output_* call on them is
 * collective (every rank calls it), and each rank writes its part of a
 * snapshot (cd_output_snapshot_part).  NULL: one
 * writer again.  0, or -1 in a build without parallel HDF5. */
int cd_output_use_mpi(const void *comm);
/* Under cd_output_use_mpi: one rank's part of a snapshot, written from its
 * local state (docs/mpi.md, "One file"): the rows of the particles it
 * owns, of their primitives, of the active contacts whose particle i it
 * owns and of the active wall contacts of its primitives, each at its
 * place in the serial layout; the scalars (step, time, walls, control)
 * from scal, by rank 0.  s's particles are in ascending global id. */
typedef struct {
    const cd_state *s;                   /* the local state */
    const cd_state *scal;                /* step, time, walls, control: every rank's alike */
    size_t n_particles, n_prims;         /* of the whole run */
    const long long *gid, *gprim;        /* per particle, per primitive of s: its global id */
    const unsigned char *owned;          /* per particle of s: this rank writes its rows */
    const long long *pair_at, *wallc_at; /* per owned particle of s: the snapshot's row of its first active
                                          * contact (as particle i) and of its first active wall contact */
    long long n_pair_rows, n_wallc_rows; /* the snapshot's active contact and wall-contact rows, every rank's */
} cd_output_part;
/* The snapshot of which every rank of cd_output_use_mpi's communicator
 * gives its part (collective); as cd_output_snapshot. */
int cd_output_snapshot_part(cd_output *o, const cd_output_part *part);
/* Under cd_output_use_mpi: the bytes of data this rank has written into
 * run files (its rows, and on rank 0 the rest), for the closing report. */
unsigned long long cd_output_bytes_written(void);
/* Under cd_output_use_mpi, before a resume: can the ranks append to the
 * run file at path?  A file of the serial writer cannot be (docs/mpi.md,
 * "Resume"): -1 on every rank, the reason in err on rank 0 (empty on the
 * others), a refusal of the input (exit 2).  Collective; 0 without
 * cd_output_use_mpi. */
int cd_output_check_appendable(const char *path, char *err, size_t errlen);

/* Number of snapshots in a run file, or -1 (message in err). */
int cd_h5_snapshot_count(const char *path, char *err, size_t errlen);

/* Reads snapshot k (k < 0: the last) into s, which must already hold the
 * particles, primitives and walls of the same run set up from its config
 * (counts are checked).  Restores every PARTICLE column, the pair list as
 * the active contacts with their history, the wall contacts, walls, time and
 * step. */
int cd_h5_read_snapshot(const char *path, int k, cd_state *s, char *err, size_t errlen);
/* Some of a snapshot's particles (an MPI rank's own and its ghosts,
 * docs/mpi.md "Resume"): n of the file's n_all particles, their global
 * ids ascending, and their primitives' (n_prims of n_all_prims). */
typedef struct {
    size_t n, n_prims, n_all, n_all_prims;
    const long long *gid, *gprim;
} cd_h5_part;
/* cd_h5_read_snapshot for the particles of part only (NULL: all): s holds
 * part->n particles, part->n_prims primitives and the run's walls; it gets
 * their rows, their wall contacts and the active contacts between two of
 * them, numbered in s (ascending global ids), read by hyperslabs of those
 * rows alone. */
int cd_h5_read_snapshot_part(const char *path, int k, const cd_h5_part *part, cd_state *s, char *err, size_t errlen);
/* Rows row0 .. row0 + n - 1 of the particle or primitive column `name`
 * (fields.def) of snapshot k (k < 0: the last) into buf (doubles or
 * int32, as the state holds them).  0, or -1 with a message. */
int cd_h5_read_column_rows(const char *path, int k, const char *name, long long row0, long long n, void *buf, char *err,
                           size_t errlen);

/* Reads the last row of every chunked dataset of the run file at path, so
 * that HDF5 verifies the Fletcher-32 checksums of the chunks a resume
 * appends to.  Returns 0, or -1 naming the corrupted dataset in err. */
int cd_h5_check_tails(const char *path, char *err, size_t errlen);

/* Reads the config text echoed in a run file (malloc'd, caller frees). */
char *cd_h5_read_config_text(const char *path, char *err, size_t errlen);

/* The config the run file's latest part ran with: that of its last resume
 * (/parameters/resumes/<k>, cd_output_note_resume), else /parameters/config;
 * the dataset's path into where.  Malloc'd, caller frees. */
char *cd_h5_read_latest_config_text(const char *path, char *where, size_t wlen, char *err, size_t errlen);

#endif
