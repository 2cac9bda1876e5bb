/* Reads what the analysis needs from one snapshot of a run file, straight
 * from the datasets of docs/output.md (no simulation state is set up):
 * centres, scale and shape of the particles, the world axis ends of the
 * primitives, the contact rows of the snapshot, the wall contacts, the
 * walls, the shape catalogue and the echoed config. */
#include "analysis/analyze.h"
#include "io/io_h5.h"
#include "io/io_h5_check.h"
#include "io/io_h5_layout.h"
#include <hdf5.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    const char *path;
    hid_t file;
    char *err;
    size_t errlen;
} rd;

static int rd_fail(rd *r, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static int rd_fail(rd *r, int code, const char *fmt, ...)
{
    char msg[700];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    snprintf(r->err, r->errlen, "%s: %s", r->path, msg);
    return code;
}

/* Dataset dpath opened, or H5I_INVALID_HID when it is absent. */
static hid_t rd_open(rd *r, const char *dpath)
{
    return cdh5_exists(r->file, dpath) ? H5Dopen2(r->file, dpath, H5P_DEFAULT) : H5I_INVALID_HID;
}

/* Shape of dataset dpath: rank and dims (up to 3); -1 when absent. */
static int rd_dims(rd *r, const char *dpath, hsize_t dims[3])
{
    hid_t d = rd_open(r, dpath);
    int rank = d < 0 ? -1 : cdh5_dims(d, dims);
    if (d >= 0) H5Dclose(d);
    return rank;
}

/* Reads count0 rows from row start0 of dataset dpath (rank 1..3; rows are
 * the first dimension; every other dimension is read whole) as memtype.
 * The dataset must have inner elements per row (1 for rank 1). */
static int rd_rows(rd *r, const char *dpath, hsize_t start0, hsize_t count0, hsize_t inner, hid_t memtype, void *buf)
{
    hsize_t dims[3];
    hid_t d = rd_open(r, dpath);
    int rank = d < 0 ? -1 : cdh5_dims(d, dims), rc = 0;
    hsize_t row = rank == 1 ? 1 : rank == 2 ? dims[1] : dims[1] * dims[2];
    if (d < 0) {
        rc = rd_fail(r, 2, "dataset %s is missing: is this a capdem run file?", dpath);
    } else if (rank < 0) {
        rc = rd_fail(r, 2, "dataset %s has more than 3 dimensions or cannot be read", dpath);
    } else if (!cdh5_storage_fits(d, start0, count0)) {
        rc = rd_fail(r, 2, "dataset %s is corrupted (its stored size does not match its type)", dpath);
    } else if (rank == 0) { /* scalar dataset: one value */
        if (start0 != 0 || count0 != 1 || inner != 1) rc = rd_fail(r, 2, "dataset %s is a scalar", dpath);
        else if (H5Dread(d, memtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0)
            rc = rd_fail(r, 2, "cannot read dataset %s", dpath);
    } else if (row != inner) {
        rc = rd_fail(r, 2, "dataset %s has %llu values per row, expected %llu", dpath, (unsigned long long)row,
                     (unsigned long long)inner);
    } else if (start0 > dims[0] || count0 > dims[0] - start0) {
        rc = rd_fail(r, 2, "dataset %s has %llu rows, rows %llu..%llu were asked for", dpath,
                     (unsigned long long)dims[0], (unsigned long long)start0, (unsigned long long)(start0 + count0));
    } else if (count0 > 0 && cdh5_read_rows(d, start0, count0, memtype, buf) < 0) {
        rc = rd_fail(r, 2, "cannot read dataset %s", dpath);
    }
    if (d >= 0) H5Dclose(d);
    return rc;
}

/* Scalar double dataset at gpath/name (shape catalogue). */
static int rd_scalar(rd *r, const char *gpath, const char *name, double *out)
{
    char p[256];
    snprintf(p, sizeof p, "%s/%s", gpath, name);
    return rd_rows(r, p, 0, 1, 1, H5T_NATIVE_DOUBLE, out);
}

/* String dataset (fixed or variable length, at most 4 KiB) into buf. */
static int rd_string(rd *r, const char *dpath, char *buf, size_t len)
{
    char *text = cdh5_read_string(r->file, r->path, dpath, 4096, r->err, r->errlen);
    snprintf(buf, len, "%s", text ? text : "");
    free(text);
    return text ? 0 : 2;
}

static int rd_shapes(rd *r, cd_an_snapshot *s)
{
    const char *shapes = CDH5_PATH(SHAPES), *cname = CDH5_NAME(SHAPE_COUNT);
    char what[96];
    snprintf(what, sizeof what, "%s %s", shapes, cname);
    if (!cdh5_exists(r->file, shapes) || H5Aexists_by_name(r->file, shapes, cname, H5P_DEFAULT) <= 0)
        return rd_fail(r, 2, "%s or its attribute %s is missing", shapes, cname);
    int32_t count = 0;
    hid_t a = H5Aopen_by_name(r->file, shapes, cname, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0 || cd_h5_check_number_attr(a, r->path, what, r->err, r->errlen)) {
        if (a >= 0) H5Aclose(a);
        return a < 0 ? rd_fail(r, 2, "cannot open the attribute %s of %s", cname, shapes) : 2;
    }
    herr_t st = H5Aread(a, H5T_NATIVE_INT32, &count);
    H5Aclose(a);
    if (st < 0 || count < 1 || count > 4096) return rd_fail(r, 2, "%s: bad count %d", shapes, (int)count);
    s->shapes = calloc((size_t)count, sizeof(cd_an_shape));
    if (!s->shapes) return rd_fail(r, 1, "out of memory");
    s->n_shapes = count;
    for (int k = 0; k < count; k++) {
        char g[64], p[96];
        cd_an_shape *sh = &s->shapes[k];
        snprintf(g, sizeof g, "%s/%d", shapes, k);
        snprintf(p, sizeof p, "%s/%s", g, CDH5_NAME(SHAPE_KIND));
        int rc = rd_string(r, p, sh->kind, sizeof sh->kind);
        if (!rc) rc = rd_scalar(r, g, "volume", &sh->volume);
        if (!rc) rc = rd_scalar(r, g, "tip_length", &sh->tip_length);
        if (!rc) rc = rd_scalar(r, g, "bounding_radius", &sh->bounding_radius);
        if (rc) return rc;
        hsize_t dims[3];
        snprintf(p, sizeof p, "%s/%s", g, CDH5_NAME(SHAPE_ARMS));
        int rank = rd_dims(r, p, dims);
        if (rank != 2 || dims[1] != 7 || dims[0] < 1 || dims[0] > CD_MAX_ARMS)
            return rd_fail(r, 2, "%s: expected (arms, 7) with 1 to %d arms", p, CD_MAX_ARMS);
        sh->n_arms = (int)dims[0];
        if ((rc = rd_rows(r, p, 0, dims[0], 7, H5T_NATIVE_DOUBLE, sh->arms))) return rc;
        if (!(sh->volume > 0) || !(sh->tip_length > 0))
            return rd_fail(r, 2, "%s: volume and tip_length must be > 0", g);
    }
    return 0;
}

int cd_an_snapshot_alloc(cd_an_snapshot *s, size_t n, size_t P, size_t nc, size_t nw, int W)
{
    s->n = n;
    s->n_prims = P;
    s->nc = nc;
    s->nw = nw;
    s->n_walls = W;
#define A(ptr, cnt) ((ptr) = calloc((cnt) ? (cnt) : 1, sizeof(*(ptr)))) == NULL
    if (A(s->pos, n) || A(s->scale, n) || A(s->shape, n) || A(s->prim_a, P) || A(s->prim_b, P) ||
        A(s->prim_radius, P) || A(s->prim_particle, P) || A(s->ci, nc) || A(s->cj, nc) || A(s->fn, nc) ||
        A(s->normal, nc) || A(s->ft, nc) || A(s->point, nc) || A(s->w_prim, nw) || A(s->w_wall, nw) ||
        A(s->w_force, nw) || A(s->w_point, nw) || A(s->walls, (size_t)W))
        return -1;
#undef A
    return 0;
}

void cd_an_snapshot_free(cd_an_snapshot *s)
{
    void *p[] = {s->pos,    s->scale,   s->shape,   s->prim_a, s->prim_b, s->prim_radius, s->prim_particle,
                 s->ci,     s->cj,      s->fn,      s->normal, s->ft,     s->point,       s->w_prim,
                 s->w_wall, s->w_force, s->w_point, s->walls,  s->shapes};
    for (size_t k = 0; k < sizeof p / sizeof p[0]; k++) free(p[k]);
    cd_config_free(&s->cfg);
    memset(s, 0, sizeof(*s));
}

/* The echoed config: domain type, dimension, k_n, parallel angle.  A
 * config that does not parse is tolerated (the caller warns); one whose
 * dataset has the wrong shape or type is refused (2). */
static int rd_config(rd *r, cd_an_snapshot *s)
{
    char err[1024];
    cd_config_defaults(&s->cfg);
    char *text = cd_h5_read_config_text(r->path, err, sizeof err);
    if (!text && strstr(err, "the file is refused")) {
        snprintf(r->err, r->errlen, "%s", err);
        return 2;
    }
    s->cfg_ok = text && cd_config_parse(text, r->path, &s->cfg, err, sizeof err) == 0;
    if (!s->cfg_ok) {
        cd_config_free(&s->cfg);
        cd_config_defaults(&s->cfg);
    }
    free(text);
    return 0;
}

static int rd_all(rd *r, int k, int S, cd_an_snapshot *s)
{
    int rc;
    if (S == 0) return rd_fail(r, 2, "the file holds no complete snapshot");
    int kk = k < 0 ? S + k : k;
    if (kk < 0 || kk >= S)
        return rd_fail(r, 2, "snapshot %d does not exist (the file holds %d, 0..%d, or -1 for the last)", k, S, S - 1);
    s->snapshot = kk;
    s->n_snapshots = S;
    if ((rc = rd_rows(r, CDH5_PATH(SNAP_STEP), (hsize_t)kk, 1, 1, H5T_NATIVE_INT64, &s->step))) return rc;
    if ((rc = rd_rows(r, CDH5_PATH(SNAP_TIME), (hsize_t)kk, 1, 1, H5T_NATIVE_DOUBLE, &s->time))) return rc;
    if ((rc = rd_shapes(r, s))) return rc;

    hsize_t dp[3], dq[3], dw[3];
    char pp[CDH5_PATH_LEN], pq[CDH5_PATH_LEN];
    if (rd_dims(r, cdh5_column_path("position", pp), dp) != 3 || dp[2] != 3)
        return rd_fail(r, 2, "%s is missing or not (snapshots, N, 3)", pp);
    if (rd_dims(r, cdh5_column_path("prim_a", pq), dq) != 3 || dq[2] != 3)
        return rd_fail(r, 2, "%s is missing or not (snapshots, P, 3)", pq);
    const char *walls = CDH5_PATH(WALLS_VALUE), *control = CDH5_PATH(CONTROL_VALUE), *windex = CDH5_PATH(W_INDEX);
    int wrank = rd_dims(r, walls, dw);
    size_t W = wrank == 2 ? (size_t)dw[1] : 0;
    if (wrank != 2 && wrank != 1) return rd_fail(r, 2, "%s is missing", walls);

    long long coff[2] = {0, 0}, woff[2] = {0, 0};
    if ((rc = rd_rows(r, CDH5_PATH(C_OFFSET), (hsize_t)kk, 2, 1, H5T_NATIVE_INT64, coff))) return rc;
    if ((rc = rd_rows(r, CDH5_PATH(W_OFFSET), (hsize_t)kk, 2, 1, H5T_NATIVE_INT64, woff))) return rc;
    if (coff[1] < coff[0] || woff[1] < woff[0]) return rd_fail(r, 2, "contact offsets of snapshot %d decrease", kk);
    size_t N = (size_t)dp[1], P = (size_t)dq[1], nc = (size_t)(coff[1] - coff[0]), nw = (size_t)(woff[1] - woff[0]);
    if (cd_an_snapshot_alloc(s, N, P, nc, nw, (int)W)) return rd_fail(r, 1, "out of memory");

    hid_t D = H5T_NATIVE_DOUBLE, I = H5T_NATIVE_INT32;
    hsize_t c0 = (hsize_t)coff[0], w0 = (hsize_t)woff[0], K = (hsize_t)kk;
    /* column (fields.def) or dataset (NULL column: path), rows start..start+count-1 */
    const struct {
        const char *column, *path;
        hsize_t start, count, inner;
        hid_t type;
        void *buf;
    } reads[] = {
        {"position", NULL, K, 1, N * 3, D, s->pos},
        {"scale", NULL, 0, N, 1, D, s->scale},
        {"shape", NULL, 0, N, 1, I, s->shape},
        {"prim_a", NULL, K, 1, P * 3, D, s->prim_a},
        {"prim_b", NULL, K, 1, P * 3, D, s->prim_b},
        {"prim_radius", NULL, 0, P, 1, D, s->prim_radius},
        {"prim_particle", NULL, 0, P, 1, I, s->prim_particle},
        {NULL, CDH5_PATH(C_PARTICLE_I), c0, nc, 1, I, s->ci},
        {NULL, CDH5_PATH(C_PARTICLE_J), c0, nc, 1, I, s->cj},
        {"pair_fn", NULL, c0, nc, 1, D, s->fn},
        {"pair_normal", NULL, c0, nc, 3, D, s->normal},
        {"pair_ft", NULL, c0, nc, 3, D, s->ft},
        {"pair_point", NULL, c0, nc, 3, D, s->point},
        {"wallc_force", NULL, w0, nw, 3, D, s->w_force},
    };
    for (size_t i = 0; i < sizeof reads / sizeof reads[0]; i++) {
        char p[CDH5_PATH_LEN];
        const char *dpath = reads[i].column ? cdh5_column_path(reads[i].column, p) : reads[i].path;
        if ((rc = rd_rows(r, dpath, reads[i].start, reads[i].count, reads[i].inner, reads[i].type, reads[i].buf)))
            return rc;
    }
    if (W > 0) {
        hid_t t = cdh5_wall_mem_type(); /* the compound the writer stores */
        rc = rd_rows(r, walls, K, 1, W, t, s->walls);
        H5Tclose(t);
        if (rc) return rc;
    }
    /* protocol state (measured bulk modulus); older files have none */
    hsize_t dc[3];
    if (rd_dims(r, control, dc) >= 0) {
        const hsize_t lo[2] = {K + 1, 1}, hi[2] = {0, sizeof s->control / sizeof s->control[0]};
        hid_t d = H5Dopen2(r->file, control, H5P_DEFAULT);
        int bad = d < 0 || cd_h5_check_dset(d, r->path, control, H5T_FLOAT, 2, lo, hi, dc, r->err, r->errlen);
        if (d >= 0) H5Dclose(d);
        if (bad) return 2;
        if ((rc = rd_rows(r, control, K, 1, dc[1], D, s->control))) return rc;
        s->n_control = (int)dc[1];
    }
    long long *idx = malloc((nw ? nw : 1) * sizeof(long long));
    if (!idx) return rd_fail(r, 1, "out of memory");
    rc = rd_rows(r, windex, w0, nw, 1, H5T_NATIVE_INT64, idx);
    for (size_t c = 0; !rc && c < nw; c++) {
        if (W == 0 || idx[c] < 0 || (size_t)idx[c] >= P * W) {
            rc = rd_fail(r, 2, "%s row %llu = %lld is out of range (P = %zu, W = %zu)", windex,
                         (unsigned long long)(w0 + c), idx[c], P, W);
            break;
        }
        s->w_prim[c] = (int32_t)(idx[c] / (long long)W);
        s->w_wall[c] = (int32_t)(idx[c] % (long long)W);
    }
    free(idx);
    if (rc) return rc;
    for (size_t p = 0; p < N; p++)
        if (s->shape[p] < 0 || s->shape[p] >= s->n_shapes)
            return rd_fail(r, 2, "%s: particle %zu has shape %d, the catalogue %d", cdh5_column_path("shape", pp), p,
                           (int)s->shape[p], s->n_shapes);
    for (size_t q = 0; q < P; q++)
        if (s->prim_particle[q] < 0 || (size_t)s->prim_particle[q] >= N)
            return rd_fail(r, 2, "%s: primitive %zu names particle %d of %zu", cdh5_column_path("prim_particle", pq), q,
                           (int)s->prim_particle[q], N);
    cd_an_wall_points(s);
    return 0;
}

int cd_an_read_snapshot(const char *path, int k, cd_an_snapshot *s, char *err, size_t errlen)
{
    memset(s, 0, sizeof(*s));
    snprintf(s->path, sizeof s->path, "%s", path);
    rd r = {path, H5I_INVALID_HID, err, errlen};
    FILE *probe = fopen(path, "rb");
    if (!probe) {
        snprintf(err, errlen, "%s: cannot open the run file: no such file or not readable", path);
        return 2;
    }
    fclose(probe);
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    int rc;
    if (H5Fis_hdf5(path) <= 0) {
        rc = rd_fail(&r, 2, "not an HDF5 file");
    } else {
        /* the count and the config (read through io_h5) first; every open
         * of a run file in a process is cdh5_open_ro's */
        int S = cd_h5_snapshot_count(path, err, errlen);
        if (S >= 0 && rd_config(&r, s)) S = -1;
        r.file = S < 0 ? H5I_INVALID_HID : cdh5_open_ro(path, err, errlen);
        rc = S < 0 || r.file < 0 ? 2 : rd_all(&r, k, S, s);
        if (r.file >= 0) H5Fclose(r.file);
    }
    cdh5_quiet_end(&q);
    return rc;
}
