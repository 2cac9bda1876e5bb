/* The run file of solver: mpm (layout in docs/mpm.md, "Output"). */
#ifndef CD_MPM_OUTPUT_H
#define CD_MPM_OUTPUT_H
#include <stddef.h>
#include "config/config.h"
#include "mpm/mpm.h"

typedef struct cd_mpm_output cd_mpm_output;

/* Creates the run file at path with the config text and the fixed columns.
 * replace 0: path must not exist; 1: the file is written beside path and
 * renamed over it once its first snapshot is on disk.  NULL with a message
 * on failure. */
cd_mpm_output *cd_mpm_output_create(const char *path, int replace, const cd_config *cfg, const cd_mpm *m, char *err,
                                    size_t errlen);
/* Appends a snapshot (points and walls) and flushes the file. */
int cd_mpm_output_snapshot(cd_mpm_output *o, const cd_mpm *m, char *err, size_t errlen);
/* Appends one row of the time series (walls, kinetic energy [J/m]). */
int cd_mpm_output_series(cd_mpm_output *o, const cd_mpm *m, double kinetic, char *err, size_t errlen);
/* Reads the last committed snapshot (root attribute n_snapshots) of the
 * run file at path into m, which holds the set-up the same config makes
 * (its points' masses and particle ids are checked, bit for bit): points,
 * walls, time and step, all a resume needs for the same bits.  0, or -1
 * with a message. */
int cd_mpm_read_snapshot(const char *path, cd_mpm *m, char *err, size_t errlen);
/* Opens the run file at path to continue it from m's step (after
 * cd_mpm_read_snapshot): snapshots after the committed ones and series
 * rows after that step are cut; the config is recorded in
 * /parameters/resumes/<k> (attributes step, source_path) as the DEM runs
 * do.  NULL with a message on failure. */
cd_mpm_output *cd_mpm_output_reopen(const char *path, const cd_config *cfg, const cd_mpm *m, char *err, size_t errlen);
/* Closes; 0 or -1. */
int cd_mpm_output_close(cd_mpm_output *o);

/* 1 when path is a readable HDF5 file written by solver: mpm (root
 * attribute solver = "mpm"), else 0; prints nothing. */
int cd_mpm_is_run_file(const char *path);

#endif
