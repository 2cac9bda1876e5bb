/* HDF5 run file of the material point method (solver: mpm): the layout of
 * docs/mpm.md ("Output").  Snapshots of the points and walls under
 * /mpm/snapshots, a time series of the walls under /mpm/series, the config
 * verbatim in /parameters/config. */
#define _POSIX_C_SOURCE 200809L
#include <hdf5.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "mpm/mpm_output.h"
#include "io/io_h5_check.h"
#include "io/io_h5_journal.h"
#include "capdem_commit.h" /* CAPDEM_COMMIT (src/git_commit.cmake) */

struct cd_mpm_output {
    hid_t file;
    char path[CD_PATH_MAX];       /* the name the file gets */
    char aside[CD_PATH_MAX + 16]; /* where it is written until the first snapshot ("" when path itself) */
    hsize_t n_snap, n_series;
    size_t n_points;
    int n_walls;
    int packing; /* set-up packing: its measures in the series */
};

/* The packing's measures in the series (cd_mpm_packing_measures), and the
 * deepest overlap of two bodies at their contact nodes. */
enum { PACKING_SERIES = 5 };
static const struct {
    const char *name, *unit;
} packing_series[PACKING_SERIES] = {{"/mpm/series/packing_fraction", "1"},
                                    {"/mpm/series/stress", "Pa"},
                                    {"/mpm/series/strain", "1"},
                                    {"/mpm/series/coordination", "1"},
                                    {"/mpm/series/penetration", "m"}};

static int fail(char *err, size_t errlen, const char *path, const char *what)
{
    snprintf(err, errlen, "%s: cannot write %s (HDF5)", path, what);
    return -1;
}

static int attr_str(hid_t obj, const char *name, const char *value)
{
    hid_t t = H5Tcopy(H5T_C_S1), sp = H5Screate(H5S_SCALAR);
    H5Tset_size(t, strlen(value) + 1);
    hid_t a = H5Acreate2(obj, name, t, sp, H5P_DEFAULT, H5P_DEFAULT);
    int rc = a >= 0 && H5Awrite(a, t, value) >= 0 ? 0 : -1;
    if (a >= 0) H5Aclose(a);
    H5Tclose(t);
    H5Sclose(sp);
    return rc;
}

/* A dataset of rank dims growing along its first axis (unlimited), in
 * chunks of `rows` rows, with a unit attribute. */
static int make_growing(hid_t file, const char *path, hid_t type, int rank, const hsize_t *tail, hsize_t rows,
                        const char *unit)
{
    hsize_t dims[3] = {0, 0, 0}, maxd[3] = {H5S_UNLIMITED, 0, 0}, chunk[3] = {rows, 1, 1};
    for (int k = 1; k < rank; k++) dims[k] = maxd[k] = chunk[k] = tail[k - 1];
    hid_t sp = H5Screate_simple(rank, dims, maxd), dcpl = H5Pcreate(H5P_DATASET_CREATE),
          lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_chunk(dcpl, rank, chunk);
    H5Pset_create_intermediate_group(lcpl, 1);
    hid_t d = H5Dcreate2(file, path, type, sp, lcpl, dcpl, H5P_DEFAULT);
    int rc = d >= 0 && attr_str(d, "unit", unit) == 0 ? 0 : -1;
    if (d >= 0) H5Dclose(d);
    H5Sclose(sp);
    H5Pclose(dcpl);
    H5Pclose(lcpl);
    return rc;
}

/* Appends row `at` (rank-1 tail from the dataset) of memory type mtype. */
static int append(hid_t file, const char *path, hid_t mtype, hsize_t at, const void *buf)
{
    hid_t d = H5Dopen2(file, path, H5P_DEFAULT);
    if (d < 0) return -1;
    hid_t fs = H5Dget_space(d);
    int rank = H5Sget_simple_extent_ndims(fs);
    hsize_t dims[3], start[3] = {at, 0, 0}, count[3];
    H5Sget_simple_extent_dims(fs, dims, NULL);
    H5Sclose(fs);
    dims[0] = at + 1;
    int rc = H5Dset_extent(d, dims) >= 0 ? 0 : -1;
    fs = H5Dget_space(d);
    count[0] = 1;
    for (int k = 1; k < rank; k++) count[k] = dims[k];
    hid_t ms = H5Screate_simple(rank, count, NULL);
    if (rc == 0 && (H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) < 0 ||
                    H5Dwrite(d, mtype, ms, fs, H5P_DEFAULT, buf) < 0))
        rc = -1;
    H5Sclose(ms);
    H5Sclose(fs);
    H5Dclose(d);
    return rc;
}

static int write_fixed(hid_t file, const char *path, hid_t ftype, hid_t mtype, int rank, const hsize_t *dims,
                       const void *buf, const char *unit)
{
    hid_t sp = H5Screate_simple(rank, dims, NULL), lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    hid_t d = H5Dcreate2(file, path, ftype, sp, lcpl, H5P_DEFAULT, H5P_DEFAULT);
    int rc = d >= 0 && H5Dwrite(d, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0 &&
                     (!unit || attr_str(d, "unit", unit) == 0)
                 ? 0
                 : -1;
    if (d >= 0) H5Dclose(d);
    H5Sclose(sp);
    H5Pclose(lcpl);
    return rc;
}

/* A writer for path with m's counts, no file open yet; NULL with a
 * message when out of memory. */
static cd_mpm_output *output_new(const char *path, const cd_mpm *m, char *err, size_t errlen)
{
    cd_mpm_output *o = calloc(1, sizeof *o);
    if (!o) {
        snprintf(err, errlen, "%s: out of memory", path);
        return NULL;
    }
    snprintf(o->path, sizeof o->path, "%s", path);
    o->file = -1;
    o->n_points = m->n;
    o->n_walls = m->n_walls;
    o->packing = m->n_walls == 4;
    return o;
}

cd_mpm_output *cd_mpm_output_create(const char *path, int replace, const cd_config *cfg, const cd_mpm *m, char *err,
                                    size_t errlen)
{
    cd_mpm_output *o = output_new(path, m, err, errlen);
    if (!o) return NULL;
    const char *target = path;
    if (replace) { /* written aside, renamed over path at the first snapshot: the old file stays until then */
        snprintf(o->aside, sizeof o->aside, "%s.XXXXXX", path);
        int fd = mkstemp(o->aside);
        if (fd < 0) {
            snprintf(err, errlen, "%s: cannot create a file beside it to write the new run into", path);
            free(o);
            return NULL;
        }
        close(fd);
        target = o->aside;
    }
    hid_t fapl = cdh5_fapl(); /* atomic commits, as every run file (docs/output.md, "Crash safety") */
    o->file = H5Fcreate(target, replace ? H5F_ACC_TRUNC : H5F_ACC_EXCL, H5P_DEFAULT, fapl);
    H5Pclose(fapl);
    if (o->file < 0) {
        snprintf(err, errlen, "%s: cannot create the run file (HDF5)", path);
        if (replace) unlink(o->aside);
        free(o);
        return NULL;
    }
    hsize_t n = m->n, w = (hsize_t)m->n_walls, one = 1;
    hsize_t t2[2] = {n, 2}, t4[2] = {n, 4}, tw[2] = {w, 2};
    const char *text = cfg->source_text ? cfg->source_text : "";
    hid_t st = H5Tcopy(H5T_C_S1);
    H5Tset_size(st, strlen(text) + 1);
    int rc = attr_str(o->file, "solver", "mpm") |
             attr_str(o->file, "creator", "capdem " CAPDEM_VERSION " (commit " CAPDEM_COMMIT ")");
    rc |= write_fixed(o->file, "/parameters/config", st, st, 1, &one, text, NULL);
    H5Tclose(st);
    rc |= write_fixed(o->file, "/mpm/points/particle", H5T_STD_I32LE, H5T_NATIVE_INT, 1, &n, m->particle, NULL);
    rc |= write_fixed(o->file, "/mpm/points/mass", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, &n, m->mass, "kg/m");
    double normals[2 * CD_MPM_MAX_WALLS], vel[2 * CD_MPM_MAX_WALLS];
    for (int k = 0; k < m->n_walls; k++) {
        normals[2 * k] = m->walls[k].nx, normals[2 * k + 1] = m->walls[k].ny;
        vel[2 * k] = m->walls[k].vx, vel[2 * k + 1] = m->walls[k].vy;
    }
    rc |= write_fixed(o->file, "/mpm/walls/normal", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 2, tw, normals, "1");
    rc |= write_fixed(o->file, "/mpm/walls/velocity", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 2, tw, vel, "m/s");
    rc |= make_growing(o->file, "/mpm/snapshots/step", H5T_STD_I64LE, 1, NULL, 64, "1");
    rc |= make_growing(o->file, "/mpm/snapshots/time", H5T_IEEE_F64LE, 1, NULL, 64, "s");
    rc |= make_growing(o->file, "/mpm/snapshots/position", H5T_IEEE_F64LE, 3, t2, 1, "m");
    rc |= make_growing(o->file, "/mpm/snapshots/velocity", H5T_IEEE_F64LE, 3, t2, 1, "m/s");
    rc |= make_growing(o->file, "/mpm/snapshots/volume", H5T_IEEE_F64LE, 2, &n, 1, "m^3/m");
    rc |= make_growing(o->file, "/mpm/snapshots/stress", H5T_IEEE_F64LE, 3, t4, 1, "Pa");
    rc |= make_growing(o->file, "/mpm/snapshots/plastic_strain", H5T_IEEE_F64LE, 2, &n, 1, "1");
    rc |= make_growing(o->file, "/mpm/snapshots/deformation_gradient", H5T_IEEE_F64LE, 3, t4, 1, "1");
    rc |= make_growing(o->file, "/mpm/snapshots/wall_position", H5T_IEEE_F64LE, 3, tw, 64, "m");
    rc |= make_growing(o->file, "/mpm/snapshots/wall_force", H5T_IEEE_F64LE, 3, tw, 64, "N/m");
    rc |= make_growing(o->file, "/mpm/series/step", H5T_STD_I64LE, 1, NULL, 1024, "1");
    rc |= make_growing(o->file, "/mpm/series/time", H5T_IEEE_F64LE, 1, NULL, 1024, "s");
    rc |= make_growing(o->file, "/mpm/series/wall_position", H5T_IEEE_F64LE, 3, tw, 1024, "m");
    rc |= make_growing(o->file, "/mpm/series/wall_force", H5T_IEEE_F64LE, 3, tw, 1024, "N/m");
    rc |= make_growing(o->file, "/mpm/series/kinetic_energy", H5T_IEEE_F64LE, 1, NULL, 1024, "J/m");
    rc |= make_growing(o->file, "/mpm/series/kinetic_energy_mesh", H5T_IEEE_F64LE, 1, NULL, 1024, "J/m");
    for (int k = 0; o->packing && k < PACKING_SERIES; k++)
        rc |= make_growing(o->file, packing_series[k].name, H5T_IEEE_F64LE, 1, NULL, 1024, packing_series[k].unit);
    if (rc) {
        fail(err, errlen, path, "the file header");
        cd_mpm_output_close(o);
        return NULL;
    }
    return o;
}

static void walls_rows(const cd_mpm *m, double *pos, double *force)
{
    for (int k = 0; k < m->n_walls; k++) {
        pos[2 * k] = m->walls[k].px, pos[2 * k + 1] = m->walls[k].py;
        force[2 * k] = m->walls[k].fx, force[2 * k + 1] = m->walls[k].fy;
    }
}

int cd_mpm_output_snapshot(cd_mpm_output *o, const cd_mpm *m, char *err, size_t errlen)
{
    size_t n = m->n;
    double *buf = malloc((4 * n + 1) * sizeof(double));
    if (!buf) return fail(err, errlen, o->path, "a snapshot (out of memory)");
    hid_t f = o->file, D = H5T_NATIVE_DOUBLE;
    hsize_t at = o->n_snap;
    long long step = m->step;
    int rc = append(f, "/mpm/snapshots/step", H5T_NATIVE_LLONG, at, &step);
    rc |= append(f, "/mpm/snapshots/time", D, at, &m->time);
    for (size_t p = 0; p < n; p++) buf[2 * p] = m->x[p], buf[2 * p + 1] = m->y[p];
    rc |= append(f, "/mpm/snapshots/position", D, at, buf);
    for (size_t p = 0; p < n; p++) buf[2 * p] = m->vx[p], buf[2 * p + 1] = m->vy[p];
    rc |= append(f, "/mpm/snapshots/velocity", D, at, buf);
    rc |= append(f, "/mpm/snapshots/volume", D, at, m->vol);
    for (size_t p = 0; p < n; p++)
        buf[4 * p] = m->sxx[p], buf[4 * p + 1] = m->syy[p], buf[4 * p + 2] = m->sxy[p], buf[4 * p + 3] = m->szz[p];
    rc |= append(f, "/mpm/snapshots/stress", D, at, buf);
    rc |= append(f, "/mpm/snapshots/plastic_strain", D, at, m->eps_p);
    for (size_t p = 0; p < n; p++)
        buf[4 * p] = m->f_xx[p], buf[4 * p + 1] = m->f_xy[p], buf[4 * p + 2] = m->f_yx[p], buf[4 * p + 3] = m->f_yy[p];
    rc |= append(f, "/mpm/snapshots/deformation_gradient", D, at, buf);
    double pos[2 * CD_MPM_MAX_WALLS], force[2 * CD_MPM_MAX_WALLS];
    walls_rows(m, pos, force);
    rc |= append(f, "/mpm/snapshots/wall_position", D, at, pos);
    rc |= append(f, "/mpm/snapshots/wall_force", D, at, force);
    free(buf);
    long long committed = (long long)at + 1;
    hid_t sp = H5Screate(H5S_SCALAR);
    hid_t a = H5Aexists(f, "n_snapshots") > 0
                  ? H5Aopen(f, "n_snapshots", H5P_DEFAULT)
                  : H5Acreate2(f, "n_snapshots", H5T_STD_I64LE, sp, H5P_DEFAULT, H5P_DEFAULT);
    rc |= a >= 0 && H5Awrite(a, H5T_NATIVE_LLONG, &committed) >= 0 ? 0 : -1;
    if (a >= 0) H5Aclose(a);
    H5Sclose(sp);
    if (rc || cdh5_commit(f, o->path, err, errlen) < 0) {
        cdh5_drop_on_close(f); /* the file keeps its last commit */
        return fail(err, errlen, o->path, "a snapshot");
    }
    o->n_snap++;
    if (o->aside[0]) { /* the first snapshot is on disk: the new file takes the name */
        if (rename(o->aside, o->path) != 0) return fail(err, errlen, o->path, "the file over the old one (rename)");
        o->aside[0] = 0;
        if (cdh5_journal_follow(f, o->path, err, errlen)) return -1;
    }
    return 0;
}

int cd_mpm_output_series(cd_mpm_output *o, const cd_mpm *m, double kinetic, char *err, size_t errlen)
{
    hid_t f = o->file, D = H5T_NATIVE_DOUBLE;
    hsize_t at = o->n_series;
    long long step = m->step;
    double pos[2 * CD_MPM_MAX_WALLS], force[2 * CD_MPM_MAX_WALLS];
    walls_rows(m, pos, force);
    int rc = append(f, "/mpm/series/step", H5T_NATIVE_LLONG, at, &step);
    rc |= append(f, "/mpm/series/time", D, at, &m->time);
    rc |= append(f, "/mpm/series/wall_position", D, at, pos);
    rc |= append(f, "/mpm/series/wall_force", D, at, force);
    rc |= append(f, "/mpm/series/kinetic_energy", D, at, &kinetic);
    rc |= append(f, "/mpm/series/kinetic_energy_mesh", D, at, &m->mesh_kinetic);
    if (o->packing) {
        double v[PACKING_SERIES];
        cd_mpm_packing_measures(m, &v[0], &v[1], &v[2], &v[3]);
        v[4] = m->penetration;
        for (int k = 0; k < PACKING_SERIES; k++) rc |= append(f, packing_series[k].name, D, at, &v[k]);
    }
    if (rc) return fail(err, errlen, o->path, "a time-series row");
    o->n_series++;
    return 0;
}

int cd_mpm_output_close(cd_mpm_output *o)
{
    if (!o) return 0;
    int rc = o->file >= 0 && H5Fclose(o->file) < 0 ? -1 : 0;
    if (o->aside[0]) unlink(o->aside); /* never reached its first snapshot: the old file stays */
    free(o);
    return rc;
}

/* Reads row `at` of a growing dataset (rank 1 to 3) into buf; the row
 * must have `count` values. */
static int read_row(hid_t file, const char *path, hid_t mtype, hsize_t at, size_t count, void *buf)
{
    hid_t d = H5Dopen2(file, path, H5P_DEFAULT);
    if (d < 0) return -1;
    hid_t fs = H5Dget_space(d);
    int rank = H5Sget_simple_extent_ndims(fs), rc = -1;
    hsize_t dims[3] = {0, 1, 1}, start[3] = {at, 0, 0}, cnt[3] = {1, 1, 1};
    if (rank >= 1 && rank <= 3) {
        H5Sget_simple_extent_dims(fs, dims, NULL);
        size_t row = 1;
        for (int k = 1; k < rank; k++) row *= (size_t)(cnt[k] = dims[k]);
        if (at < dims[0] && row == count) {
            hid_t ms = H5Screate_simple(rank, cnt, NULL);
            rc = H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, cnt, NULL) >= 0 && cdh5_storage_fits(d, at, 1) &&
                         H5Dread(d, mtype, ms, fs, H5P_DEFAULT, buf) >= 0
                     ? 0
                     : -1;
            H5Sclose(ms);
        }
    }
    H5Sclose(fs);
    H5Dclose(d);
    return rc;
}

static long long committed_snapshots(hid_t f)
{
    long long committed = 0;
    hid_t a = H5Aexists(f, "n_snapshots") > 0 ? H5Aopen(f, "n_snapshots", H5P_DEFAULT) : -1;
    if (a >= 0) {
        if (H5Aread(a, H5T_NATIVE_LLONG, &committed) < 0) committed = 0;
        H5Aclose(a);
    }
    return committed;
}

/* A fixed column of the run file equal, bit for bit, to the set-up's. */
static int same_fixed(hid_t f, const char *path, hid_t mtype, size_t n, size_t size, const void *want)
{
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    if (d < 0) return 0;
    hid_t fs = H5Dget_space(d);
    hsize_t dims[1] = {0};
    int same = H5Sget_simple_extent_ndims(fs) == 1 && (H5Sget_simple_extent_dims(fs, dims, NULL), dims[0] == n);
    void *buf = same ? malloc(n * size + 1) : NULL;
    same = same && buf && cdh5_storage_fits(d, 0, HSIZE_UNDEF) &&
           H5Dread(d, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0 && memcmp(buf, want, n * size) == 0;
    free(buf);
    H5Sclose(fs);
    H5Dclose(d);
    return same;
}

int cd_mpm_read_snapshot(const char *path, cd_mpm *m, char *err, size_t errlen)
{
    int rc = -1;
    size_t n = m->n;
    double *buf = malloc((4 * n + 1) * sizeof(double));
    if (!buf) {
        snprintf(err, errlen, "%s: out of memory", path);
        return -1;
    }
    H5E_BEGIN_TRY
    {
        hid_t fapl = cdh5_fapl();
        hid_t f = H5Fopen(path, H5F_ACC_RDONLY, fapl), D = H5T_NATIVE_DOUBLE;
        H5Pclose(fapl);
        long long k = f >= 0 ? committed_snapshots(f) - 1 : -1, step = 0;
        double pos[2 * CD_MPM_MAX_WALLS];
        if (f < 0 || k < 0) {
            snprintf(err, errlen, "%s: no snapshot to resume from (root attribute n_snapshots)", path);
        } else if (!same_fixed(f, "/mpm/points/mass", D, n, sizeof(double), m->mass) ||
                   !same_fixed(f, "/mpm/points/particle", H5T_NATIVE_INT, n, sizeof(int), m->particle)) {
            snprintf(err, errlen,
                     "%s: its material points (/mpm/points/mass, particle) differ from those the config "
                     "sets up now (%zu points): a resume continues the same set-up (was mpm.packing's file changed?)",
                     path, n);
        } else {
            hsize_t at = (hsize_t)k;
            int bad = read_row(f, "/mpm/snapshots/step", H5T_NATIVE_LLONG, at, 1, &step) ||
                      read_row(f, "/mpm/snapshots/time", D, at, 1, &m->time) ||
                      read_row(f, "/mpm/snapshots/wall_position", D, at, 2 * (size_t)m->n_walls, pos);
            if (!bad && !(bad = read_row(f, "/mpm/snapshots/position", D, at, 2 * n, buf)))
                for (size_t p = 0; p < n; p++) m->x[p] = buf[2 * p], m->y[p] = buf[2 * p + 1];
            if (!bad && !(bad = read_row(f, "/mpm/snapshots/velocity", D, at, 2 * n, buf)))
                for (size_t p = 0; p < n; p++) m->vx[p] = buf[2 * p], m->vy[p] = buf[2 * p + 1];
            if (!bad)
                bad = read_row(f, "/mpm/snapshots/volume", D, at, n, m->vol) ||
                      read_row(f, "/mpm/snapshots/plastic_strain", D, at, n, m->eps_p);
            if (!bad && !(bad = read_row(f, "/mpm/snapshots/stress", D, at, 4 * n, buf)))
                for (size_t p = 0; p < n; p++)
                    m->sxx[p] = buf[4 * p], m->syy[p] = buf[4 * p + 1], m->sxy[p] = buf[4 * p + 2],
                    m->szz[p] = buf[4 * p + 3];
            if (!bad && !(bad = read_row(f, "/mpm/snapshots/deformation_gradient", D, at, 4 * n, buf)))
                for (size_t p = 0; p < n; p++)
                    m->f_xx[p] = buf[4 * p], m->f_xy[p] = buf[4 * p + 1], m->f_yx[p] = buf[4 * p + 2],
                    m->f_yy[p] = buf[4 * p + 3];
            if (bad) {
                snprintf(err, errlen, "%s: cannot read snapshot %lld (of %zu points and %d walls) to resume from", path,
                         k, n, m->n_walls);
            } else {
                m->step = step;
                for (int w = 0; w < m->n_walls; w++) m->walls[w].px = pos[2 * w], m->walls[w].py = pos[2 * w + 1];
                rc = 0;
            }
        }
        if (f >= 0) H5Fclose(f);
    }
    H5E_END_TRY
    free(buf);
    return rc;
}

/* Cuts a growing dataset to its first `rows` rows. */
static int truncate_rows(hid_t file, const char *path, hsize_t rows)
{
    hid_t d = H5Dopen2(file, path, H5P_DEFAULT);
    if (d < 0) return -1;
    hid_t fs = H5Dget_space(d);
    hsize_t dims[3] = {0, 0, 0};
    H5Sget_simple_extent_dims(fs, dims, NULL);
    H5Sclose(fs);
    int rc = 0;
    if (dims[0] > rows) {
        dims[0] = rows;
        rc = H5Dset_extent(d, dims) >= 0 ? 0 : -1;
    }
    H5Dclose(d);
    return rc;
}

cd_mpm_output *cd_mpm_output_reopen(const char *path, const cd_config *cfg, const cd_mpm *m, char *err, size_t errlen)
{
    cd_mpm_output *o = output_new(path, m, err, errlen);
    long long *steps = NULL;
    if (!o) return NULL;
    int rc = -1;
    H5E_BEGIN_TRY
    {
        hid_t fapl = cdh5_fapl();
        o->file = H5Fopen(path, H5F_ACC_RDWR, fapl);
        H5Pclose(fapl);
        if (o->file >= 0) {
            o->n_snap = (hsize_t)committed_snapshots(o->file);
            /* the series rows up to the resumed step stay; those the interrupted run wrote after it go */
            hid_t d = H5Dopen2(o->file, "/mpm/series/step", H5P_DEFAULT);
            hsize_t rows = 0;
            if (d >= 0) {
                hid_t fs = H5Dget_space(d);
                if (H5Sget_simple_extent_ndims(fs) != 1 || !cdh5_storage_fits(d, 0, HSIZE_UNDEF))
                    rows = (hsize_t)-1; /* refused below: not a series of steps */
                else H5Sget_simple_extent_dims(fs, &rows, NULL);
                H5Sclose(fs);
                steps = rows < ((hsize_t)1 << 40) ? malloc((rows + 1) * sizeof(long long)) : NULL;
                if (steps && H5Dread(d, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, steps) >= 0) {
                    while (o->n_series < rows && steps[o->n_series] <= m->step) o->n_series++;
                    rc = 0;
                }
                H5Dclose(d);
            }
            const char *snaps[] = {"step",          "time",      "position",       "velocity",
                                   "volume",        "stress",    "plastic_strain", "deformation_gradient",
                                   "wall_position", "wall_force"};
            const char *series[] = {"step",       "time",           "wall_position",
                                    "wall_force", "kinetic_energy", "kinetic_energy_mesh"};
            char p[96];
            for (size_t k = 0; rc == 0 && k < sizeof snaps / sizeof snaps[0]; k++) {
                snprintf(p, sizeof p, "/mpm/snapshots/%s", snaps[k]);
                rc = truncate_rows(o->file, p, o->n_snap);
            }
            for (size_t k = 0; rc == 0 && k < sizeof series / sizeof series[0]; k++) {
                snprintf(p, sizeof p, "/mpm/series/%s", series[k]);
                rc = truncate_rows(o->file, p, o->n_series);
            }
            for (int k = 0; rc == 0 && o->packing && k < PACKING_SERIES; k++)
                rc = truncate_rows(o->file, packing_series[k].name, o->n_series);
            /* the config this part runs with, as the DEM runs record it (docs/output.md) */
            int r = 0;
            do snprintf(p, sizeof p, "/parameters/resumes/%d", r++);
            while (rc == 0 && H5Lexists(o->file, "/parameters/resumes", H5P_DEFAULT) > 0 &&
                   H5Lexists(o->file, p, H5P_DEFAULT) > 0);
            const char *text = cfg->source_text ? cfg->source_text : "";
            hid_t st = H5Tcopy(H5T_C_S1);
            H5Tset_size(st, strlen(text) + 1);
            hsize_t one = 1;
            long long step = m->step;
            if (rc == 0) rc = write_fixed(o->file, p, st, st, 1, &one, text, NULL);
            H5Tclose(st);
            if (rc == 0) {
                hid_t ds = H5Dopen2(o->file, p, H5P_DEFAULT), sp = H5Screate(H5S_SCALAR);
                hid_t a = H5Acreate2(ds, "step", H5T_STD_I64LE, sp, H5P_DEFAULT, H5P_DEFAULT);
                rc = a >= 0 && H5Awrite(a, H5T_NATIVE_LLONG, &step) >= 0 &&
                             attr_str(ds, "source_path", cfg->source_path) == 0
                         ? 0
                         : -1;
                if (a >= 0) H5Aclose(a);
                H5Sclose(sp);
                H5Dclose(ds);
                /* the cut and the resume's record in one commit */
                if (rc == 0) rc = cdh5_commit(o->file, path, err, errlen);
            }
            if (rc) cdh5_drop_on_close(o->file); /* a failed resume leaves the file as it was */
        }
    }
    H5E_END_TRY
    free(steps);
    if (rc) {
        snprintf(err, errlen, "%s: cannot open the run file to continue it (HDF5)", path);
        cd_mpm_output_close(o);
        return NULL;
    }
    return o;
}

int cd_mpm_is_run_file(const char *path)
{
    H5E_BEGIN_TRY
    {
        hid_t fapl = cdh5_fapl();
        hid_t f = H5Fopen(path, H5F_ACC_RDONLY, fapl);
        H5Pclose(fapl);
        int yes = 0;
        if (f >= 0) {
            if (H5Aexists(f, "solver") > 0) {
                hid_t a = H5Aopen(f, "solver", H5P_DEFAULT), t = H5Aget_type(a);
                char v[16] = "";
                if (H5Tget_class(t) == H5T_STRING && !H5Tis_variable_str(t) && H5Tget_size(t) == 4) {
                    hid_t m = H5Tcopy(H5T_C_S1);
                    H5Tset_size(m, 4);
                    yes = H5Aread(a, m, v) >= 0 && !strcmp(v, "mpm");
                    H5Tclose(m);
                }
                H5Tclose(t);
                H5Aclose(a);
            }
            H5Fclose(f);
        }
        return yes;
    }
    H5E_END_TRY
}
