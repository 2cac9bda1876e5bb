/* The layout of kernels/runfile.def as C tables and the read primitives
 * that the writer and every reader share (io_h5_layout.h): paths and
 * names, which columns are fixed, field checks, error messages, dataset
 * shapes, the read-only open and the committed snapshot count.  Layout:
 * docs/output.md. */
#include "io/io_h5.h"
#include "io/io_h5_internal.h"
#include "io/io_h5_check.h"
#include "contact_law.h"
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const cdh5_paths[CDH5_N_PATHS] = {
#define CD_H5_GROUP(id, path, made, meaning)         path,
#define CD_H5_DATASET(id, path, type, unit, meaning) path,
#include "runfile.def"
};

const char *const cdh5_names[CDH5_N_NAMES] = {
#define CD_H5_NAME(id, name, meaning) name,
#include "runfile.def"
};

/* Columns that a run never changes: stored once as H5MD fixed data.  Every
 * other PARTICLE and PRIM column is stored per snapshot, so a column added
 * to fields.def is a time series unless runfile.def names it. */
static const char *const fixed_columns[] = {
#define CD_H5_FIXED(column) column,
#include "runfile.def"
};

enum cdh5_store cdh5_store_of(const cd_field_info *f)
{
    if (cd_group_pair_rows(f->group) || f->group == CD_GROUP_WALLC) return CDH5_ROWS;
    for (size_t i = 0; i < sizeof fixed_columns / sizeof fixed_columns[0]; i++)
        if (!strcmp(f->name, fixed_columns[i])) return CDH5_FIXED;
    return CDH5_SERIES;
}

const char *cdh5_group_path(enum cd_field_group g)
{
    switch (g) {
#define CD_H5_COLUMN_GROUP(field_group, id)                                                                            \
    case CD_GROUP_##field_group:                                                                                       \
        return CDH5_PATH(id);
#include "runfile.def"
    default:
        return "/unknown";
    }
}

const cd_field_info *cdh5_column(const char *name)
{
    for (size_t k = 0; k < cd_n_fields; k++)
        if (!strcmp(cd_fields[k].name, name)) return &cd_fields[k];
    return NULL;
}

const char *cdh5_column_path(const char *name, char *buf)
{
    const cd_field_info *f = cdh5_column(name);
    if (f) cdh5_field_path(f, buf, CDH5_PATH_LEN);
    else snprintf(buf, CDH5_PATH_LEN, "(no column %s in fields.def)", name);
    return buf;
}

void cdh5_field_path(const cd_field_info *f, char *buf, size_t len)
{
    snprintf(buf, len, "%s/%s%s", cdh5_group_path(f->group), f->name, cdh5_store_of(f) == CDH5_SERIES ? "/value" : "");
}

/* A FLAG column is one byte a row in memory (cd_flag) and an int32 in the
 * file, as it was when the step held it as a cd_int: HDF5 converts at
 * write and read, so the file's layout did not change and old files
 * resume (docs/output.md). */
hid_t cdh5_mem_type(const cd_field_info *f)
{
    return f->kind == CD_KIND_REAL ? H5T_NATIVE_DOUBLE : f->kind == CD_KIND_FLAG ? H5T_NATIVE_UINT8 : H5T_NATIVE_INT32;
}

size_t cdh5_file_row_bytes(const cd_field_info *f)
{
    return (size_t)f->ncomp * (f->kind == CD_KIND_REAL ? sizeof(double) : sizeof(int32_t));
}

int cdh5_field_check(const cd_field_info *f, char *err, size_t errlen)
{
    size_t scalar = f->kind == CD_KIND_REAL   ? sizeof(double)
                    : f->kind == CD_KIND_FLAG ? sizeof(cd_flag)
                                              : sizeof(int32_t);
    if (f->ncomp < 1 || f->ncomp > 64 || f->elem_size != (size_t)f->ncomp * scalar) {
        snprintf(err, errlen,
                 "fields.def: column %s has %zu bytes per row, expected %d x %zu: HDF5 output "
                 "stores REAL columns as doubles, INT columns as int32 and FLAG columns (a byte in memory) as int32",
                 f->name, f->elem_size, f->ncomp, scalar);
        return -1;
    }
    return 0;
}

size_t cdh5_max_row_bytes(void)
{
    size_t m = sizeof(long long);
    for (size_t k = 0; k < cd_n_fields; k++)
        if (cd_fields[k].elem_size > m) m = cd_fields[k].elem_size;
    return m;
}

/* HDF5 type of one member of /walls/value: a scalar, or an array of ncomp. */
static hid_t wall_member_type(hid_t scalar, hsize_t ncomp)
{
    return ncomp == 1 ? H5Tcopy(scalar) : H5Tarray_create2(scalar, 1, &ncomp);
}

hid_t cdh5_wall_mem_type(void)
{
    hid_t t = H5Tcreate(H5T_COMPOUND, sizeof(cd_wall)), m;
#define CD_H5_WALL_MEMBER(name, type, ncomp, unit)                                                                     \
    m = wall_member_type(CD_KIND_##type == CD_KIND_INT ? H5T_NATIVE_INT32 : H5T_NATIVE_DOUBLE, ncomp);                 \
    H5Tinsert(t, #name, HOFFSET(cd_wall, name), m);                                                                    \
    H5Tclose(m);
#include "runfile.def"
    return t;
}

void cdh5_wall_units(char *buf, size_t len)
{
    size_t at = 0;
    buf[0] = 0;
#define CD_H5_WALL_MEMBER(name, type, ncomp, unit)                                                                     \
    if (at < len) at += (size_t)snprintf(buf + at, len - at, "%s" #name " " unit, at ? ", " : "");
#include "runfile.def"
}

static herr_t innermost(unsigned n, const H5E_error2_t *e, void *data)
{
    if (n == 0 && e->desc) snprintf((char *)data, 256, "%s", e->desc);
    return 0;
}

void cdh5_msg(char *err, size_t errlen, const char *fmt, ...)
{
    char detail[256] = "";
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost, detail);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
    size_t l = strlen(err);
    if (*detail && l + 1 < errlen) snprintf(err + l, errlen - l, " (HDF5: %s)", detail);
    H5Eclear2(H5E_DEFAULT);
}

int cdh5_exists(hid_t loc, const char *path)
{
    char buf[CDH5_PATH_LEN];
    size_t n = strlen(path);
    if (n >= sizeof buf) return 0;
    memcpy(buf, path, n + 1);
    char *p = buf + (buf[0] == '/');
    for (;;) {
        char *slash = strchr(p, '/');
        if (slash) *slash = 0;
        if (*p && H5Lexists(loc, buf, H5P_DEFAULT) <= 0) {
            H5Eclear2(H5E_DEFAULT);
            return 0;
        }
        if (!slash) return 1;
        *slash = '/';
        p = slash + 1;
    }
}

int cdh5_dims(hid_t dset, hsize_t dims[3])
{
    hid_t sp = H5Dget_space(dset);
    if (sp < 0) return -1;
    int r = H5Sget_simple_extent_ndims(sp);
    dims[0] = dims[1] = dims[2] = 1;
    if (r < 0 || r > 3 || H5Sget_simple_extent_dims(sp, dims, NULL) < 0) r = -1;
    H5Sclose(sp);
    return r;
}

/* HDF5 clips an integer outside the memory type's range when it converts
 * (a flag of -1 or 256 in a file would read as 0 or 255): a read into a
 * FLAG column's memory type refuses such a value instead. */
static H5T_conv_ret_t refuse_out_of_range(H5T_conv_except_t e, hid_t src, hid_t dst, void *src_buf, void *dst_buf,
                                          void *data)
{
    (void)src, (void)dst, (void)src_buf, (void)dst_buf, (void)data;
    return e == H5T_CONV_EXCEPT_RANGE_HI || e == H5T_CONV_EXCEPT_RANGE_LOW ? H5T_CONV_ABORT : H5T_CONV_UNHANDLED;
}

herr_t cdh5_read(hid_t dset, hid_t memtype, hid_t ms, hid_t fs, void *buf)
{
    if (H5Tequal(memtype, H5T_NATIVE_UINT8) <= 0) return H5Dread(dset, memtype, ms, fs, H5P_DEFAULT, buf);
    hid_t x = H5Pcreate(H5P_DATASET_XFER);
    herr_t e = x < 0 || H5Pset_type_conv_cb(x, refuse_out_of_range, NULL) < 0 ? -1 : 0;
    if (e >= 0) e = H5Dread(dset, memtype, ms, fs, x, buf);
    if (x >= 0) H5Pclose(x);
    return e;
}

herr_t cdh5_read_rows(hid_t dset, hsize_t start0, hsize_t count0, hid_t memtype, void *buf)
{
    hsize_t dims[3];
    int rank = cdh5_dims(dset, dims);
    if (rank < 1) return -1;
    hsize_t start[3] = {start0, 0, 0}, cnt[3] = {count0, dims[1], dims[2]};
    if (start0 + count0 > dims[0]) return -1;
    if (cnt[0] * cnt[1] * cnt[2] == 0) return 0;
    if (!cdh5_storage_fits(dset, start0, count0)) return -1;
    hid_t fs = H5Dget_space(dset), ms = H5Screate_simple(rank, cnt, NULL);
    herr_t e = H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, cnt, NULL);
    if (e >= 0) e = cdh5_read(dset, memtype, ms, fs, buf);
    H5Sclose(fs);
    H5Sclose(ms);
    return e;
}

long long cdh5_field_rows(hid_t d, const cd_field_info *f, const char *dpath, const char *file, char *err,
                          size_t errlen)
{
    hsize_t dims[3];
    enum cdh5_store st = cdh5_store_of(f);
    int vec = f->ncomp > 1, want = (st == CDH5_SERIES ? 2 : 1) + vec;
    int rank = cdh5_dims(d, dims);
    if (rank != want || (vec && dims[rank - 1] != (hsize_t)f->ncomp)) {
        cdh5_msg(err, errlen, "%s: %s has rank %d (last dimension %llu), column %s needs rank %d%s", file, dpath, rank,
                 rank > 0 ? (unsigned long long)dims[rank - 1] : 0ULL, f->name, want,
                 vec ? " with that many components" : "");
        return -1;
    }
    hid_t t = H5Dget_type(d);
    H5T_class_t cl = H5Tget_class(t);
    size_t size = H5Tget_size(t);
    H5Tclose(t);
    int ok = f->kind == CD_KIND_REAL ? (cl == H5T_FLOAT && size == 8) : (cl == H5T_INTEGER && size == 4);
    if (!ok) {
        cdh5_msg(err, errlen, "%s: %s holds %zu-byte %s, column %s needs %s", file, dpath, size,
                 cl == H5T_FLOAT     ? "floats"
                 : cl == H5T_INTEGER ? "integers"
                                     : "values",
                 f->name, f->kind == CD_KIND_REAL ? "doubles" : "int32");
        return -1;
    }
    return (long long)(st == CDH5_SERIES ? dims[1] : dims[0]);
}

static long long rows_of_path(hid_t file, const char *path, const char *fname, char *err, size_t errlen)
{
    hsize_t dims[3];
    hid_t d = H5Dopen2(file, path, H5P_DEFAULT);
    int r = d < 0 ? -1 : cdh5_dims(d, dims);
    if (r != 1) cdh5_msg(err, errlen, "%s: cannot read the length of %s", fname, path);
    if (d >= 0) H5Dclose(d);
    return r == 1 ? (long long)dims[0] : -1;
}

long long cdh5_committed(hid_t file, const char *path, char *err, size_t errlen)
{
    if (!cdh5_exists(file, CDH5_SNAP_STEP)) return 0;
    const char *const clocks[4] = {CDH5_SNAP_STEP, CDH5_SNAP_TIME, CDH5_C_OFFSET, CDH5_W_OFFSET};
    long long n = -1;
    for (int i = 0; i < 4; i++) {
        long long r = rows_of_path(file, clocks[i], path, err, errlen);
        if (r < 0) return -1;
        if (i >= 2) r = r > 0 ? r - 1 : 0; /* offsets hold n + 1 entries */
        if (n < 0 || r < n) n = r;
    }
    if (H5Aexists(file, CDH5_COMMIT_ATTR) > 0) {
        long long c = -1;
        hid_t a = H5Aopen(file, CDH5_COMMIT_ATTR, H5P_DEFAULT);
        char what[64];
        snprintf(what, sizeof what, "/%s", CDH5_COMMIT_ATTR);
        if (a >= 0 && cd_h5_check_number_attr(a, path, what, err, errlen)) {
            H5Aclose(a);
            return -1;
        }
        if (a < 0 || H5Aread(a, H5T_NATIVE_LLONG, &c) < 0) {
            cdh5_msg(err, errlen, "%s: cannot read attribute /%s", path, CDH5_COMMIT_ATTR);
            if (a >= 0) H5Aclose(a);
            return -1;
        }
        H5Aclose(a);
        if (c >= 0 && c < n) n = c;
    }
    H5Eclear2(H5E_DEFAULT);
    return n;
}

void cdh5_quiet_begin(cdh5_quiet *q)
{
    H5Eget_auto2(H5E_DEFAULT, &q->func, &q->data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

void cdh5_quiet_end(const cdh5_quiet *q) { H5Eset_auto2(H5E_DEFAULT, q->func, q->data); }

/* ---- reading ---------------------------------------------------------------- */

hid_t cdh5_open_ro(const char *path, char *err, size_t errlen)
{
    hid_t fapl = cdh5_fapl(); /* replays a killed writer's journal in memory */
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, fapl);
    if (f < 0) cdh5_msg(err, errlen, "%s: cannot open the run file", path);
    H5Pclose(fapl);
    return f;
}

int cd_h5_snapshot_count(const char *path, char *err, size_t errlen)
{
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    hid_t f = cdh5_open_ro(path, err, errlen);
    long long n = f < 0 ? -1 : cdh5_committed(f, path, err, errlen);
    if (f >= 0) H5Fclose(f);
    cdh5_quiet_end(&q);
    return n > 2147483647LL ? 2147483647 : (int)n;
}
