/* HDF5 output of a run, after H5MD 1.1: creating, reopening for a resume
 * (truncating what came after the checkpoint), time series, closing.
 * Snapshots: io_h5_snapshot.c; header and helpers: io_h5_write.c; reading
 * back: io_h5_read.c.  The layout, the order of writes and what a crash
 * leaves behind are documented in docs/output.md. */
#define _POSIX_C_SOURCE 200809L
#include "io/io_h5.h"
#include "io/io_h5_internal.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <errno.h>
#include <fcntl.h>

/* ---- observables (time series) ------------------------------------------ */

hid_t cdh5_make_clock(cd_output *o, const char *path, int is_time)
{
    hsize_t d = 0, m = H5S_UNLIMITED, c = CDH5_CLOCK_CHUNK;
    return cdh5_make_dset(o, path, is_time ? H5T_IEEE_F64LE : H5T_STD_I64LE, 1, &d, &m, &c, is_time ? "s" : NULL);
}

/* Names usable as HDF5 group names, given once, ncomp >= 1 and, for a
 * series already in the file, its ncomp. */
static int obs_check(cd_output *o, const cd_observable_info *obs, int n_obs)
{
    for (int i = 0; i < n_obs; i++) {
        const char *name = obs[i].name;
        if (!name || !*name || strchr(name, '/') || !strcmp(name, ".") || strlen(name) > 200 || obs[i].ncomp < 1)
            return FAIL("%s: observable %d: invalid name \"%s\" or ncomp %d (need a non-empty name without '/' and "
                        "ncomp >= 1)",
                        o->path, i, name ? name : "(null)", obs[i].ncomp);
        for (int j = 0; j < i; j++)
            if (!strcmp(obs[j].name, name)) return FAIL("%s: observable \"%s\" given twice", o->path, name);
        char p[CDH5_PATH_LEN];
        snprintf(p, sizeof p, "%s/%s/%s", CDH5_PATH(OBSERVABLES), name, CDH5_NAME(VALUE));
        if (!cdh5_exists(o->file, p)) continue;
        hsize_t dims[3];
        hid_t d = cdh5_open_dset(o, p);
        int rank = d < 0 ? -1 : cdh5_dims(d, dims);
        cdh5_close_dset(&d);
        if (rank < 0) return -1;
        if (rank != (obs[i].ncomp > 1 ? 2 : 1) || (rank == 2 && dims[1] != (hsize_t)obs[i].ncomp))
            return FAIL("%s: %s has %llu components per row, the run gives %d", o->path, p,
                        rank == 2 ? (unsigned long long)dims[1] : 1ULL, obs[i].ncomp);
    }
    return 0;
}

static int obs_setup(cd_output *o, const cd_observable_info *obs, int n_obs)
{
    char p[CDH5_PATH_LEN];
    o->obs = calloc(n_obs > 0 ? (size_t)n_obs : 1, sizeof *o->obs);
    if (!o->obs) return FAIL("%s: out of memory", o->path);
    for (int i = 0; i < n_obs; i++) {
        cdh5_obs *b = &o->obs[i];
        b->step = b->time = b->value = H5I_INVALID_HID;
    }
    o->n_obs = n_obs;
    for (int i = 0; i < n_obs; i++) {
        cdh5_obs *b = &o->obs[i];
        const char *name = obs[i].name;
        b->name = malloc(strlen(name) + 1);
        if (!b->name) return FAIL("%s: out of memory", o->path);
        strcpy(b->name, name);
        b->ncomp = obs[i].ncomp;
        o->width += b->ncomp;
        snprintf(p, sizeof p, "%s/%s", CDH5_PATH(OBSERVABLES), name);
        if (cdh5_exists(o->file, p)) {
            hsize_t dims[3];
            snprintf(p, sizeof p, "%s/%s/%s", CDH5_PATH(OBSERVABLES), name, CDH5_NAME(VALUE));
            b->value = cdh5_open_dset(o, p);
            if (b->value < 0 || cdh5_dims(b->value, dims) < 1) return -1;
            b->rows = dims[0];
            snprintf(p, sizeof p, "%s/%s/%s", CDH5_PATH(OBSERVABLES), name, CDH5_NAME(STEP));
            b->step = cdh5_open_dset(o, p);
            snprintf(p, sizeof p, "%s/%s/%s", CDH5_PATH(OBSERVABLES), name, CDH5_NAME(TIME));
            b->time = cdh5_open_dset(o, p);
            if (b->step < 0 || b->time < 0) return -1;
        } else {
            hsize_t d[2] = {0, (hsize_t)b->ncomp}, m[2] = {H5S_UNLIMITED, (hsize_t)b->ncomp};
            hsize_t c[2] = {CDH5_CLOCK_CHUNK, (hsize_t)b->ncomp};
            snprintf(p, sizeof p, "%s/%s/%s", CDH5_PATH(OBSERVABLES), name, CDH5_NAME(STEP));
            b->step = cdh5_make_clock(o, p, 0);
            snprintf(p, sizeof p, "%s/%s/%s", CDH5_PATH(OBSERVABLES), name, CDH5_NAME(TIME));
            b->time = cdh5_make_clock(o, p, 1);
            snprintf(p, sizeof p, "%s/%s/%s", CDH5_PATH(OBSERVABLES), name, CDH5_NAME(VALUE));
            b->value =
                cdh5_make_dset(o, p, H5T_IEEE_F64LE, b->ncomp > 1 ? 2 : 1, d, m, c, obs[i].unit ? obs[i].unit : "1");
            if (b->step < 0 || b->time < 0 || b->value < 0) return -1;
            b->rows = 0;
        }
    }
    if (n_obs > 0) {
        o->buf_step = malloc(CDH5_OBS_BLOCK * sizeof *o->buf_step);
        o->buf_time = malloc(CDH5_OBS_BLOCK * sizeof *o->buf_time);
        o->buf_val = malloc((size_t)CDH5_OBS_BLOCK * (size_t)o->width * sizeof *o->buf_val);
        if (!o->buf_step || !o->buf_time || !o->buf_val) return FAIL("%s: out of memory", o->path);
    }
    return 0;
}

int cdh5_obs_flush(cd_output *o)
{
    if (o->buf_n == 0) return 0;
    size_t n = o->buf_n;
    double *tmp = malloc(n * (size_t)o->width * sizeof *tmp);
    if (!tmp) return FAIL("%s: out of memory", o->path);
    int rc = 0, col = 0;
    for (int i = 0; i < o->n_obs && !rc; i++) {
        cdh5_obs *b = &o->obs[i];
        for (size_t r = 0; r < n; r++)
            memcpy(tmp + r * (size_t)b->ncomp, o->buf_val + r * (size_t)o->width + col, (size_t)b->ncomp * sizeof *tmp);
        col += b->ncomp;
        rc = cdh5_append(o, b->value, b->name, b->rows, n, H5T_NATIVE_DOUBLE, tmp);
        if (!rc) rc = cdh5_append(o, b->time, b->name, b->rows, n, H5T_NATIVE_DOUBLE, o->buf_time);
        if (!rc) rc = cdh5_append(o, b->step, b->name, b->rows, n, H5T_NATIVE_LLONG, o->buf_step);
        if (!rc) b->rows += n;
    }
    free(tmp);
    if (!rc) o->buf_n = 0;
    return rc;
}

int cd_output_thermo(cd_output *o, long long step, double time, const double *values)
{
    if (o->n_obs == 0) return 0;
    if (o->io_failed) return -1; /* reported when it happened */
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    int rc = 0;
    if (o->buf_n == CDH5_OBS_BLOCK) {
        unsigned long long bytes = 65536;
        for (int i = 0; i < o->n_obs; i++)
            bytes += cdh5_growth(o->obs[i].value, o->buf_n) + cdh5_growth(o->obs[i].step, o->buf_n) +
                     cdh5_growth(o->obs[i].time, o->buf_n);
        rc = cdh5_reserve(o, bytes, "the time series");
        if (!rc) rc = cdh5_obs_flush(o);
        if (rc) o->io_failed = 1;
    }
    if (!rc) {
        o->buf_step[o->buf_n] = step;
        o->buf_time[o->buf_n] = time;
        memcpy(o->buf_val + o->buf_n * (size_t)o->width, values, (size_t)o->width * sizeof *values);
        o->buf_n++;
    }
    cdh5_quiet_end(&q);
    return rc;
}

/* ---- opening and closing -------------------------------------------------- */

static cd_output *output_new(const char *path, char *err, size_t errlen)
{
    cd_output *o = calloc(1, sizeof *o);
    if (o) o->cols = calloc(cd_n_fields, sizeof *o->cols);
    if (!o || !o->cols || strlen(path) >= sizeof o->path) {
        snprintf(err, errlen, "%s: %s", path, o && o->cols ? "path too long" : "out of memory");
        if (o) free(o->cols);
        free(o);
        return NULL;
    }
    strcpy(o->path, path);
    o->file = o->step = o->time = o->walls = o->wall_type = H5I_INVALID_HID;
    o->c_offset = o->c_pi = o->c_pj = o->w_offset = o->w_index = o->control = H5I_INVALID_HID;
    o->old_fd = -1;
    o->own_lock = -1;
    for (size_t k = 0; k < cd_n_fields; k++) o->cols[k].dset = H5I_INVALID_HID;
    return o;
}

static void output_free(cd_output *o)
{
    hid_t *ds[] = {&o->step, &o->time,     &o->walls,   &o->c_offset, &o->c_pi,
                   &o->c_pj, &o->w_offset, &o->w_index, &o->control};
    for (size_t i = 0; i < sizeof ds / sizeof ds[0]; i++) cdh5_close_dset(ds[i]);
    if (o->wall_type >= 0) H5Tclose(o->wall_type);
    for (size_t k = 0; k < cd_n_fields; k++) {
        cdh5_close_dset(&o->cols[k].dset);
        free(o->cols[k].fixed);
    }
    for (int i = 0; i < o->n_obs; i++) {
        cdh5_close_dset(&o->obs[i].step);
        cdh5_close_dset(&o->obs[i].time);
        cdh5_close_dset(&o->obs[i].value);
        free(o->obs[i].name);
    }
    if (o->file >= 0) {
        /* a failed write keeps the file at its last commit */
        if (o->io_failed) cdh5_drop_on_close(o->file);
        H5Fclose(o->file);
    }
    /* CD_OUTPUT_REPLACE closed before its first snapshot: the old file stays */
    if (o->tmp_path[0] && o->n_snap == 0 && cdh5_par_root()) unlink(o->tmp_path);
    if (o->old_fd >= 0) close(o->old_fd);
    if (o->own_lock >= 0) close(o->own_lock);
    free(o->obs);
    free(o->cols);
    free(o->buf_step);
    free(o->buf_time);
    free(o->buf_val);
    free(o);
}

/* capdem's journaled driver (atomic commits, io_h5_journal.h), and the
 * default (earliest) file format on purpose: the 1.10 format would
 * checksum the metadata too, but it marks a file open for writing in its
 * superblock, so a killed run would leave a file that HDF5 refuses to open
 * (tests/unit/test_io_h5.c, killed writer). */
static hid_t file_access(void) { return cdh5_par_on() ? cdh5_par_fapl() : cdh5_fapl(); }

static int claim_target(cd_output *o, const char *path, enum cd_output_mode how);

/* Opens the file that o will write: path itself, created exclusively, or
 * (CD_OUTPUT_REPLACE of an existing path) a file beside it, with the old
 * one locked until the first commit.  Parallel output: rank 0 claims it,
 * every rank opens it. */
static int create_file(cd_output *o, const char *path, enum cd_output_mode how)
{
    int rc = cdh5_par_root() ? claim_target(o, path, how) : 0;
    if (cdh5_par_max(rc != 0)) return -1; /* (rank 0 said why) */
    cdh5_par_bcast(o->tmp_path, sizeof o->tmp_path);
    const char *target = o->tmp_path[0] ? o->tmp_path : path;
    hid_t fapl = file_access();
    /* TRUNC only on the empty file made here (or by mkstemp) */
    o->file = H5Fcreate(target, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    rc = o->file < 0 ? FAIL("%s: cannot create the output file", target) : 0; /* (before H5Pclose clears the stack) */
    H5Pclose(fapl);
    if (cdh5_par_max(rc != 0)) {
        if (target == path && cdh5_par_root()) unlink(path); /* the empty file made by claim_target */
        return -1;
    }
    cdh5_par_lock(o->own_lock);
    return 0;
}

/* The file system side of create_file: the old file locked and a file
 * beside it made (o->tmp_path), or path created exclusively and marked. */
static int claim_target(cd_output *o, const char *path, enum cd_output_mode how)
{
    const char *target = path;
    if (how == CD_OUTPUT_REPLACE) {
        int fd = cdh5_target_lock(path, &o->old_dev, &o->old_ino, o->err, sizeof o->err);
        if (fd == -1) return cdh5_report(o);
        if (fd >= 0) {
            o->old_fd = fd;
            if (cdh5_target_aside(path, o->tmp_path, sizeof o->tmp_path, o->err, sizeof o->err, &o->own_lock))
                return cdh5_report(o);
            target = o->tmp_path;
        }
    } else if (how != CD_OUTPUT_NEW) {
        return FAIL("%s: cd_output_create_mode: mode %d is not a way to create a file", path, (int)how);
    }
    if (target == path) {
        /* created here, exclusively, and marked before HDF5 writes a byte: a
         * second capdem finds it in use from the start */
        o->own_lock = open(path, O_RDWR | O_CREAT | O_EXCL | O_NOCTTY | O_CLOEXEC, 0666);
        if (o->own_lock < 0)
            return errno == EEXIST ? FAIL("%s exists (created by another process after the checks?): refused, the "
                                          "file is left as it is",
                                          path)
                                   : FAIL("%s: cannot create the output file: %s", path, strerror(errno));
        cdh5_mark(o->own_lock);
    }
    return 0;
}

/* The start of cd_output_create_mode and cd_output_reopen: HDF5's own
 * messages silenced (q) and a new output for path; NULL (q ended, the
 * message printed and in err) when there is no memory. */
static cd_output *open_begin(const char *path, cdh5_quiet *q, char *err, size_t errlen)
{
    cdh5_quiet_begin(q);
    cd_output *o = output_new(path, err, errlen);
    if (!o) {
        fprintf(stderr, "capdem: %s\n", err);
        cdh5_quiet_end(q);
    }
    return o;
}

/* Their end: the observables' series set up and the first commit made
 * unless rc already failed; on failure the output is let go (the file
 * keeps its last commit; a resumed one stays as it was before) and NULL
 * returned with the reason in err, and *refused (where not NULL) says
 * whether the file's content was the cause (cd_output.refused).  Ends q. */
static cd_output *open_end(cd_output *o, int rc, const cd_observable_info *obs, int n_obs, cdh5_quiet *q, int *refused,
                           char *err, size_t errlen)
{
    if (!rc) rc = obs_setup(o, obs, n_obs);
    if (!rc) rc = cdh5_commit_output(o);
    if (refused) *refused = rc && o->refused;
    if (rc) {
        o->io_failed = 1;
        snprintf(err, errlen, "%s", o->err);
        output_free(o);
        o = NULL;
    }
    cdh5_quiet_end(q);
    return o;
}

cd_output *cd_output_create(const char *path, const cd_config *cfg, const cd_shape *shapes, int n_shapes,
                            const cd_observable_info *obs, int n_obs, char *err, size_t errlen)
{
    return cd_output_create_mode(path, CD_OUTPUT_REPLACE, cfg, shapes, n_shapes, obs, n_obs, err, errlen);
}

cd_output *cd_output_create_mode(const char *path, enum cd_output_mode how, const cd_config *cfg,
                                 const cd_shape *shapes, int n_shapes, const cd_observable_info *obs, int n_obs,
                                 char *err, size_t errlen)
{
    cdh5_quiet q;
    cd_output *o = open_begin(path, &q, err, errlen);
    if (!o) return NULL;
    int rc = create_file(o, path, how);
    if (!rc) rc = obs_check(o, obs, n_obs);
    if (!rc) rc = cdh5_write_header(o, cfg, shapes, n_shapes);
    return open_end(o, rc, obs, n_obs, &q, NULL, err, errlen);
}

int cd_output_close(cd_output *o)
{
    if (!o) return 0;
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    /* After a failed write nothing more is written (and nothing more said):
     * the file keeps what its last commit left. */
    int rc = o->io_failed ? -1 : cdh5_obs_flush(o);
    if (!o->io_failed && cdh5_commit_output(o)) rc = -1;
    output_free(o);
    cdh5_quiet_end(&q);
    return rc;
}

void cd_h5_no_atexit(void) { H5dont_atexit(); }

const char *cd_output_error(const cd_output *o) { return o ? o->err : ""; }

/* ---- resume ------------------------------------------------------------------ */

static int read_ll(cd_output *o, hid_t d, const char *what, hsize_t row, long long *v)
{
    if (cdh5_read_rows(d, row, 1, H5T_NATIVE_LLONG, v) < 0)
        return FAIL("%s: cannot read row %llu of %s", o->path, (unsigned long long)row, what);
    return 0;
}

/* Leading rows of a 1-D step dataset (first n) with step <= resume_step. */
static long long rows_upto(cd_output *o, hid_t step, const char *what, hsize_t n, long long resume_step)
{
    long long *v = malloc((n ? n : 1) * sizeof *v);
    if (!v) return FAIL("%s: out of memory", o->path);
    if (n && cdh5_read_rows(step, 0, n, H5T_NATIVE_LLONG, v) < 0) {
        free(v);
        return FAIL("%s: cannot read %s", o->path, what);
    }
    hsize_t keep = 0;
    while (keep < n && v[keep] <= resume_step) keep++;
    free(v);
    return (long long)keep;
}

static int truncate_snapshots(cd_output *o, long long resume_step)
{
    long long keep = rows_upto(o, o->step, CDH5_SNAP_STEP, o->n_snap, resume_step), cend, wend;
    if (keep < 0 || read_ll(o, o->c_offset, CDH5_C_OFFSET, (hsize_t)keep, &cend) ||
        read_ll(o, o->w_offset, CDH5_W_OFFSET, (hsize_t)keep, &wend))
        return -1;
    hsize_t n = (hsize_t)keep;
    /* the smaller count and the cut rows go into the file in one commit (cd_output_reopen) */
    if (cdh5_write_commit(o, n)) return -1;
    for (size_t k = 0; k < cd_n_fields; k++) {
        enum cdh5_store st = cdh5_store_of(&cd_fields[k]);
        if (st == CDH5_FIXED) continue;
        hsize_t rows = st == CDH5_SERIES ? n : (hsize_t)(cd_group_pair_rows(cd_fields[k].group) ? cend : wend);
        if (cdh5_set_rows(o, o->cols[k].dset, cd_fields[k].name, rows)) return -1;
    }
    if (cdh5_set_rows(o, o->step, CDH5_SNAP_STEP, n) || cdh5_set_rows(o, o->time, CDH5_SNAP_TIME, n) ||
        cdh5_set_rows(o, o->walls, CDH5_WALLS_VALUE, n) || cdh5_set_rows(o, o->control, CDH5_CONTROL_VALUE, n) ||
        cdh5_set_rows(o, o->c_offset, CDH5_C_OFFSET, n + 1) || cdh5_set_rows(o, o->w_offset, CDH5_W_OFFSET, n + 1) ||
        cdh5_set_rows(o, o->c_pi, CDH5_PATH(C_PARTICLE_I), (hsize_t)cend) ||
        cdh5_set_rows(o, o->c_pj, CDH5_PATH(C_PARTICLE_J), (hsize_t)cend) ||
        cdh5_set_rows(o, o->w_index, CDH5_W_INDEX, (hsize_t)wend))
        return -1;
    o->n_snap = n;
    o->c_rows = (hsize_t)cend;
    o->w_rows = (hsize_t)wend;
    return 0;
}

/* Every series under /observables, given now or not, loses its rows for
 * steps > resume_step. */
static int truncate_observables(cd_output *o, long long resume_step)
{
    hid_t g = H5Gopen2(o->file, CDH5_PATH(OBSERVABLES), H5P_DEFAULT);
    if (g < 0) return FAIL("%s: cannot open %s", o->path, CDH5_PATH(OBSERVABLES));
    H5G_info_t info;
    int rc = H5Gget_info(g, &info) < 0 ? FAIL("%s: cannot list /observables", o->path) : 0;
    for (hsize_t i = 0; !rc && i < info.nlinks; i++) {
        char name[256], p[CDH5_PATH_LEN];
        if (H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT) < 0) {
            rc = FAIL("%s: cannot list /observables", o->path);
            break;
        }
        hid_t d[3];
        const char *parts[3] = {CDH5_NAME(STEP), CDH5_NAME(TIME), CDH5_NAME(VALUE)};
        hsize_t n = (hsize_t)-1, dims[3];
        for (int j = 0; j < 3; j++) {
            snprintf(p, sizeof p, "%s/%s/%s", CDH5_PATH(OBSERVABLES), name, parts[j]);
            d[j] = cdh5_open_dset(o, p);
            if (d[j] < 0 || cdh5_dims(d[j], dims) < 1) rc = -1;
            else if (dims[0] < n) n = dims[0];
        }
        long long keep = rc ? -1 : rows_upto(o, d[0], name, n, resume_step);
        for (int j = 0; j < 3; j++) {
            if (keep >= 0 && cdh5_set_rows(o, d[j], name, (hsize_t)keep)) keep = -1;
            cdh5_close_dset(&d[j]);
        }
        if (keep < 0) rc = -1;
    }
    cdh5_close_id(&g);
    return rc;
}

cd_output *cd_output_reopen(const char *path, long long resume_step, const cd_observable_info *obs, int n_obs,
                            int *refused, char *err, size_t errlen)
{
    cdh5_quiet q;
    if (refused) *refused = 0;
    cd_output *o = open_begin(path, &q, err, errlen);
    if (!o) return NULL;
    int rc = 0;
    /* parallel output: a journal a killed writer left (io_h5_journal.h) is
     * replayed in place by rank 0 before the ranks open the file through
     * MPI-IO (which knows no journal; the serial driver does it on open),
     * and a file of the serial writer is refused (cdh5_par_appendable) */
    if (cdh5_par_on() && cdh5_par_max(cdh5_par_root() && (cdh5_recover(path, o->err, sizeof o->err) < 0 ||
                                                          cdh5_par_appendable(path, o->err, sizeof o->err) < 0))) {
        if (cdh5_par_root()) cdh5_report(o);
        rc = -1;
    }
    hid_t fapl = rc ? H5I_INVALID_HID : file_access();
    o->file = rc ? H5I_INVALID_HID : H5Fopen(path, H5F_ACC_RDWR, fapl);
    if (!rc && cdh5_par_max(o->file < 0)) rc = FAIL("%s: cannot open the run file for appending", path);
    if (fapl >= 0) H5Pclose(fapl);
    if (!rc && cdh5_par_root()) {
        o->own_lock = open(path, O_RDONLY | O_NOCTTY | O_CLOEXEC);
        if (o->own_lock >= 0) cdh5_mark(o->own_lock);
        cdh5_par_lock(o->own_lock);
    }
    if (rc) o->refused = 1; /* (the file cannot be opened for writing, or is a serial writer's on several ranks) */
    if (!rc && (!cdh5_exists(o->file, CDH5_PATH(H5MD)) || !cdh5_exists(o->file, CDH5_PATH(OBSERVABLES))))
        rc = FAIL("%s: not a capdem run file (no %s or %s)", path, CDH5_PATH(H5MD), CDH5_PATH(OBSERVABLES));
    if (!rc) rc = obs_check(o, obs, n_obs);
    if (rc) o->refused = 1;
    if (!rc && cdh5_exists(o->file, CDH5_SNAP_STEP))
        rc = (cdh5_layout_open(o) || truncate_snapshots(o, resume_step)) ? -1 : 0;
    if (!rc) rc = truncate_observables(o, resume_step);
    return open_end(o, rc, obs, n_obs, &q, refused, err, errlen);
}
