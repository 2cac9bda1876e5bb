/* Writing helpers of the HDF5 output and the file header: /h5md and
 * /parameters (config text, shape catalogue).  Layout: docs/output.md. */
#include "io/io_h5.h"
#include "io/io_h5_internal.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capdem_commit.h" /* CAPDEM_COMMIT, generated at build time (src/git_commit.cmake) */

#ifndef CAPDEM_VERSION
#define CAPDEM_VERSION "unknown"
#endif

int cdh5_commit_output(cd_output *o)
{
    /* MPI-IO: a collective flush, no journal (docs/mpi.md, "One file"; asking
     * the driver which it is would duplicate the communicator each time) */
    if (cdh5_par_on() && H5Fflush(o->file, H5F_SCOPE_GLOBAL) < 0) {
        o->io_failed = 1;
        return FAIL("%s: cannot flush", o->path);
    }
    if (cdh5_par_on()) return 0;
    if (cdh5_commit(o->file, o->path, o->err, sizeof o->err) == 0) return 0;
    o->io_failed = 1;
    /* the usual cause when the journal beside it cannot be made: the file and its folder were deleted */
    if (cdh5_check_linked(o)) return -1;
    return cdh5_report(o);
}

int cdh5_report(cd_output *o)
{
    fprintf(stderr, "capdem: %s\n", o->err);
    return -1;
}

void cdh5_close_id(hid_t *id)
{
    if (*id >= 0) H5Oclose(*id);
    *id = H5I_INVALID_HID;
}

void cdh5_close_dset(hid_t *id)
{
    if (*id >= 0) H5Dclose(*id);
    *id = H5I_INVALID_HID;
}

/* ---- small writers ------------------------------------------------------ */

int cdh5_attr_write(cd_output *o, hid_t obj, const char *where, const char *name, hid_t type, hid_t space,
                    const void *buf)
{
    if (H5Aexists(obj, name) > 0 && H5Adelete(obj, name) < 0)
        return FAIL("%s: cannot replace attribute %s of %s", o->path, name, where);
    hid_t a = H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0 || H5Awrite(a, type, buf) < 0) {
        FAIL("%s: cannot write attribute %s of %s", o->path, name, where);
        if (a >= 0) H5Aclose(a);
        return -1;
    }
    H5Aclose(a);
    return 0;
}

int cdh5_attr_str(cd_output *o, hid_t obj, const char *where, const char *name, const char *value)
{
    hid_t t = H5Tcopy(H5T_C_S1), sp = H5Screate(H5S_SCALAR);
    H5Tset_size(t, strlen(value) + 1);
    H5Tset_strpad(t, H5T_STR_NULLTERM);
    int rc = cdh5_attr_write(o, obj, where, name, t, sp, value);
    H5Tclose(t);
    H5Sclose(sp);
    return rc;
}

int cdh5_attr_ints(cd_output *o, hid_t obj, const char *where, const char *name, const int *v, hsize_t n)
{
    hid_t sp = n ? H5Screate_simple(1, &n, NULL) : H5Screate(H5S_SCALAR);
    int rc = cdh5_attr_write(o, obj, where, name, H5T_NATIVE_INT, sp, v);
    H5Sclose(sp);
    return rc;
}

int cdh5_write_commit(cd_output *o, hsize_t n)
{
    long long v = (long long)n;
    hid_t sp = H5Screate(H5S_SCALAR), a = H5I_INVALID_HID;
    int rc = 0;
    if (H5Aexists(o->file, CDH5_COMMIT_ATTR) > 0) {
        a = H5Aopen(o->file, CDH5_COMMIT_ATTR, H5P_DEFAULT);
        if (a < 0 || H5Awrite(a, H5T_NATIVE_LLONG, &v) < 0)
            rc = FAIL("%s: cannot write attribute /%s", o->path, CDH5_COMMIT_ATTR);
        if (a >= 0) H5Aclose(a);
    } else {
        hid_t t = H5Tcopy(H5T_STD_I64LE);
        a = H5Acreate2(o->file, CDH5_COMMIT_ATTR, t, sp, H5P_DEFAULT, H5P_DEFAULT);
        if (a < 0 || H5Awrite(a, H5T_NATIVE_LLONG, &v) < 0)
            rc = FAIL("%s: cannot write attribute /%s", o->path, CDH5_COMMIT_ATTR);
        if (a >= 0) H5Aclose(a);
        H5Tclose(t);
    }
    H5Sclose(sp);
    return rc;
}

hid_t cdh5_make_group(cd_output *o, const char *path)
{
    hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    hid_t g = H5Gcreate2(o->file, path, lcpl, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) FAIL("%s: cannot create group %s", o->path, path);
    H5Pclose(lcpl);
    return g;
}

/* Creates a dataset; chunk NULL: contiguous; unit NULL: no unit attribute. */
hid_t cdh5_make_dset(cd_output *o, const char *path, hid_t ftype, int rank, const hsize_t *dims, const hsize_t *maxdims,
                     const hsize_t *chunk, const char *unit)
{
    hid_t sp = rank ? H5Screate_simple(rank, dims, maxdims) : H5Screate(H5S_SCALAR);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE), lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    /* Every chunked dataset carries a Fletcher-32 checksum per chunk, which
     * HDF5 verifies on every read: a corrupted snapshot is refused, never
     * carried on (docs/output.md, "Corruption"). */
    if (chunk) {
        H5Pset_chunk(dcpl, rank, chunk);
        H5Pset_fletcher32(dcpl);
    }
    hid_t d = H5Dcreate2(o->file, path, ftype, sp, lcpl, dcpl, H5P_DEFAULT);
    if (d < 0) FAIL("%s: cannot create dataset %s", o->path, path);
    H5Sclose(sp);
    H5Pclose(dcpl);
    H5Pclose(lcpl);
    if (d >= 0 && unit && cdh5_attr_str(o, d, path, "unit", unit) < 0) cdh5_close_dset(&d);
    return d;
}

/* Whole dataset (fixed data, parameters) in one call. */
int cdh5_write_all(cd_output *o, hid_t d, const char *path, hid_t mtype, const void *buf)
{
    if (d < 0) return -1;
    if (cdh5_par_on()) { /* rank 0 writes it, collectively */
        hsize_t dims[3] = {0, 0, 0}, zero[3] = {0, 0, 0};
        hid_t fs = H5Dget_space(d), ms = H5Scopy(fs);
        int rank = H5Sget_simple_extent_dims(fs, dims, NULL);
        herr_t e = rank < 0 ? -1 : cdh5_par_write(o, d, mtype, ms, fs, rank, zero, dims, buf);
        H5Sclose(fs);
        H5Sclose(ms);
        return e < 0 ? FAIL("%s: cannot write dataset %s", o->path, path) : 0;
    }
    if (H5Dwrite(d, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0)
        return FAIL("%s: cannot write dataset %s", o->path, path);
    return 0;
}

int cdh5_write_real(cd_output *o, const char *path, int rank, const hsize_t *dims, const double *v, const char *unit)
{
    hid_t d = cdh5_make_dset(o, path, H5T_IEEE_F64LE, rank, dims, NULL, NULL, unit);
    int rc = cdh5_write_all(o, d, path, H5T_NATIVE_DOUBLE, v);
    cdh5_close_dset(&d);
    return rc;
}

int cdh5_set_rows(cd_output *o, hid_t d, const char *what, hsize_t n)
{
    hsize_t dims[3];
    if (cdh5_dims(d, dims) < 1) return FAIL("%s: cannot query %s", o->path, what);
    dims[0] = n;
    if (H5Dset_extent(d, dims) < 0)
        return FAIL("%s: cannot resize %s to %llu rows", o->path, what, (unsigned long long)n);
    return 0;
}

/* Writes count rows at row `at` of an extendible dataset, which then has
 * at + count rows. */
int cdh5_append(cd_output *o, hid_t d, const char *what, hsize_t at, hsize_t count, hid_t mtype, const void *buf)
{
    hsize_t dims[3] = {0, 1, 1};
    int rank = cdh5_dims(d, dims);
    if (rank < 1) return FAIL("%s: cannot query %s", o->path, what);
    dims[0] = at + count;
    if (H5Dset_extent(d, dims) < 0) return FAIL("%s: cannot extend %s", o->path, what);
    return cdh5_write_block(o, d, what, rank, at, count, dims, mtype, buf);
}

int cdh5_write_block(cd_output *o, hid_t d, const char *what, int rank, hsize_t at, hsize_t count, const hsize_t *dims,
                     hid_t mtype, const void *buf)
{
    hsize_t start[3] = {at, 0, 0}, cnt[3] = {count, rank > 1 ? dims[1] : 1, rank > 2 ? dims[2] : 1};
    if (cnt[0] * cnt[1] * cnt[2] == 0) return 0;
    /* parallel output from a local state: its map_rows rows in memory */
    hsize_t mcnt[3] = {cnt[0], cnt[1], cnt[2]};
    if (cdh5_par_on() && o->row_map && o->mask_dim < rank) mcnt[o->mask_dim] = o->map_rows ? o->map_rows : 1;
    hid_t fs = H5Dget_space(d), ms = H5Screate_simple(rank, mcnt, NULL);
    herr_t e = H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, cnt, NULL);
    if (e >= 0)
        e = cdh5_par_on() ? cdh5_par_write(o, d, mtype, ms, fs, rank, start, cnt, buf)
                          : H5Dwrite(d, mtype, ms, fs, H5P_DEFAULT, buf);
    if (e < 0) FAIL("%s: cannot write %s", o->path, what);
    H5Sclose(fs);
    H5Sclose(ms);
    return e < 0 ? -1 : 0;
}

hid_t cdh5_open_dset(cd_output *o, const char *path)
{
    hid_t d = H5Dopen2(o->file, path, H5P_DEFAULT);
    if (d < 0) {
        o->refused = 1;
        FAIL("%s: cannot open dataset %s (is this a capdem run file?)", o->path, path);
    }
    return d;
}

/* ---- file header: /h5md, /parameters, groups ----------------------------- */

static int write_h5md(cd_output *o)
{
    static const int version[2] = {1, 1};
    const char *author = getenv("USER");
    if (!author || !*author) author = "unknown";
    hid_t g = cdh5_make_group(o, "/h5md"), ga = cdh5_make_group(o, "/h5md/author");
    hid_t gc = cdh5_make_group(o, "/h5md/creator");
    int rc = (g < 0 || ga < 0 || gc < 0) ? -1 : 0;
    if (!rc) rc = cdh5_attr_ints(o, g, "/h5md", "version", version, 2);
    if (!rc) rc = cdh5_attr_str(o, ga, "/h5md/author", "name", author);
    if (!rc) rc = cdh5_attr_str(o, gc, "/h5md/creator", "name", "capdem");
    if (!rc) rc = cdh5_attr_str(o, gc, "/h5md/creator", "version", CAPDEM_VERSION);
    if (!rc) rc = cdh5_attr_str(o, gc, "/h5md/creator", "commit", CAPDEM_COMMIT);
    cdh5_close_id(&g);
    cdh5_close_id(&ga);
    cdh5_close_id(&gc);
    return rc;
}

/* The H5MD box of a particles group. */
static int write_box(cd_output *o, const char *group)
{
    static const int dim = 3;
    static const char boundary[3][5] = {"none", "none", "none"};
    char path[CDH5_PATH_LEN];
    snprintf(path, sizeof path, "%s/box", group);
    hid_t g = cdh5_make_group(o, path);
    if (g < 0) return -1;
    hid_t t = H5Tcopy(H5T_C_S1);
    hsize_t n = 3;
    hid_t sp = H5Screate_simple(1, &n, NULL);
    H5Tset_size(t, 5);
    int rc = cdh5_attr_ints(o, g, path, "dimension", &dim, 0);
    if (!rc) rc = cdh5_attr_write(o, g, path, "boundary", t, sp, boundary);
    H5Tclose(t);
    H5Sclose(sp);
    cdh5_close_id(&g);
    return rc;
}

static int write_config(cd_output *o, const cd_config *cfg)
{
    const char *text = cfg && cfg->source_text ? cfg->source_text : "";
    size_t len = strlen(text);
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, len ? len : 1);
    H5Tset_strpad(t, H5T_STR_NULLPAD);
    const char *p = CDH5_PATH(CONFIG);
    hid_t d = cdh5_make_dset(o, p, t, 0, NULL, NULL, NULL, NULL);
    int rc = cdh5_write_all(o, d, p, t, text);
    if (!rc) rc = cdh5_attr_str(o, d, p, "source_path", cfg ? cfg->source_path : "");
    if (!rc) rc = cdh5_attr_str(o, d, p, "format", "yaml");
    cdh5_close_dset(&d);
    H5Tclose(t);
    return rc;
}

int cd_output_note_resume(cd_output *o, long long step, const cd_config *cfg)
{
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    char p[CDH5_PATH_LEN];
    int k = 0;
    do snprintf(p, sizeof p, "%s/%d", CDH5_PATH(RESUMES), k++);
    while (cdh5_exists(o->file, p) && k < 1000000);
    const char *text = cfg && cfg->source_text ? cfg->source_text : "";
    size_t len = strlen(text);
    /* room first, and written through at once: a full disk fails here with
     * nothing of it left in HDF5's cache for a later flush */
    if (o->io_failed || cdh5_reserve(o, len + 131072, p)) {
        cdh5_quiet_end(&q);
        return -1;
    }
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, len ? len : 1);
    H5Tset_strpad(t, H5T_STR_NULLPAD);
    hid_t d = cdh5_make_dset(o, p, t, 0, NULL, NULL, NULL, NULL);
    int rc = cdh5_write_all(o, d, p, t, text);
    if (!rc) rc = cdh5_attr_str(o, d, p, "source_path", cfg ? cfg->source_path : "");
    if (!rc) {
        hid_t sp = H5Screate(H5S_SCALAR);
        rc = cdh5_attr_write(o, d, p, "step", H5T_NATIVE_LLONG, sp, &step);
        H5Sclose(sp);
    }
    cdh5_close_dset(&d);
    H5Tclose(t);
    if (!rc) rc = cdh5_commit_output(o);
    if (rc) o->io_failed = 1;
    cdh5_quiet_end(&q);
    return rc;
}

static int write_shape(cd_output *o, int k, const cd_shape *sh)
{
    char g[96], p[160];
    if (sh->n_prims < 0 || sh->n_prims > CD_MAX_ARMS)
        return FAIL("%s: shape %d has %d arms (0..%d allowed)", o->path, k, sh->n_prims, CD_MAX_ARMS);
    snprintf(g, sizeof g, "%s/%d", CDH5_PATH(SHAPES), k);
    hid_t gid = cdh5_make_group(o, g);
    if (gid < 0) return -1;
    cdh5_close_id(&gid);
    /* kind */
    hid_t t = H5Tcopy(H5T_C_S1);
    const char *nul = memchr(sh->kind, 0, sizeof sh->kind);
    size_t klen = nul ? (size_t)(nul - sh->kind) : sizeof sh->kind;
    char kind[sizeof sh->kind + 1];
    memcpy(kind, sh->kind, klen);
    kind[klen] = 0;
    H5Tset_size(t, klen + 1);
    snprintf(p, sizeof p, "%s/%s", g, CDH5_NAME(SHAPE_KIND));
    hid_t d = cdh5_make_dset(o, p, t, 0, NULL, NULL, NULL, NULL);
    int rc = cdh5_write_all(o, d, p, t, kind);
    cdh5_close_dset(&d);
    H5Tclose(t);
    if (rc) return rc;
    /* arms: a, b, radius */
    double arms[CD_MAX_ARMS][7];
    for (int i = 0; i < sh->n_prims; i++) {
        double row[7] = {sh->a[i].x, sh->a[i].y, sh->a[i].z, sh->b[i].x, sh->b[i].y, sh->b[i].z, sh->radius[i]};
        memcpy(arms[i], row, sizeof row);
    }
    hsize_t ad[2] = {(hsize_t)sh->n_prims, 7};
    snprintf(p, sizeof p, "%s/%s", g, CDH5_NAME(SHAPE_ARMS));
    d = cdh5_make_dset(o, p, H5T_IEEE_F64LE, 2, ad, NULL, NULL, "m");
    rc = sh->n_prims ? cdh5_write_all(o, d, p, H5T_NATIVE_DOUBLE, arms) : (d < 0 ? -1 : 0);
    if (!rc) rc = cdh5_attr_str(o, d, p, "columns", "a_x a_y a_z b_x b_y b_z radius");
    cdh5_close_dset(&d);
    if (rc) return rc;
    struct {
        const char *name, *unit;
        const double *v;
        int rank;
        hsize_t dims[2];
    } items[] = {
#define CD_H5_SHAPE_VALUE(name, member, rank, dim0, dim1, unit) {name, unit, &sh->member, rank, {dim0, dim1}},
#include "runfile.def"
    };
    for (size_t i = 0; i < sizeof items / sizeof items[0] && !rc; i++) {
        snprintf(p, sizeof p, "%s/%s", g, items[i].name);
        rc = cdh5_write_real(o, p, items[i].rank, items[i].dims, items[i].v, items[i].unit);
    }
    return rc;
}

int cdh5_write_header(cd_output *o, const cd_config *cfg, const cd_shape *shapes, int n_shapes)
{
    const char *groups[] = {
#define CD_H5_GROUP(id, path, made, meaning) CD_H5_IF_##made(path)
#define CD_H5_IF_HEADER(path)                path,
#define CD_H5_IF_WRITER(path)
#define CD_H5_IF_OPTIONAL(path)
#include "runfile.def"
#undef CD_H5_IF_HEADER
#undef CD_H5_IF_WRITER
#undef CD_H5_IF_OPTIONAL
    };
    if (write_h5md(o) || write_config(o, cfg)) return -1;
    for (size_t i = 0; i < sizeof groups / sizeof groups[0]; i++) {
        hid_t g = cdh5_make_group(o, groups[i]);
        if (g < 0) return -1;
        cdh5_close_id(&g);
    }
    hid_t g = H5Gopen2(o->file, CDH5_PATH(SHAPES), H5P_DEFAULT);
    int rc = cdh5_attr_ints(o, g, CDH5_PATH(SHAPES), CDH5_NAME(SHAPE_COUNT), &n_shapes, 0);
    cdh5_close_id(&g);
    for (int k = 0; k < n_shapes && !rc; k++) rc = write_shape(o, k, &shapes[k]);
    if (!rc) rc = write_box(o, CDH5_PATH(PARTICLES));
    if (!rc) rc = write_box(o, CDH5_PATH(PRIMS));
    if (!rc) rc = cdh5_write_commit(o, 0);
    return rc;
}
