/* Reading a run file back: a snapshot for resume (whole, or one rank's
 * part by hyperslabs), one column's rows, the echoed config.  The layout
 * tables and shared read primitives are in io_h5_layout.c.  Layout:
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

typedef struct {
    const char *path;
    char *err;
    size_t errlen;
    hid_t file;
    hid_t *ds; /* one per cd_fields[] entry */
    hid_t walls, step, time, c_offset, w_offset, w_index, control;
    long long c0, c1, w0, w1;
    long long *windex;
    void *tmp;
    int legacy_force; /* the file predates /contacts/pair_force (rebuilt from F_n n + F_t) */
    /* cd_h5_read_snapshot_part: the particles read, and the rows of the
     * file that hold them (runs: start, count), its primitives, its wall
     * contacts (each's row in s) and the active contacts between two of
     * them (each's primitives in s) */
    const cd_h5_part *part;
    hsize_t *runs[4];
    size_t n_runs[4], n_sel[4];
    size_t *wall_at;
    cd_int *pair_ij;
} reader;

enum { RUN_PARTICLES, RUN_PRIMS, RUN_WALLS, RUN_PAIRS };

/* Row `row` of the file appended to the runs of kind w (rows ascending). */
static int add_run(reader *r, int w, hsize_t row)
{
    size_t n = r->n_runs[w];
    r->n_sel[w]++;
    if (n && r->runs[w][2 * n - 2] + r->runs[w][2 * n - 1] == row) {
        r->runs[w][2 * n - 1]++;
        return 0;
    }
    if ((n & (n - 1)) == 0) { /* room doubled at powers of two */
        hsize_t *g = realloc(r->runs[w], 4 * (n ? n : 1) * sizeof *g);
        if (!g) return -1;
        r->runs[w] = g;
    }
    r->runs[w][2 * n] = row;
    r->runs[w][2 * n + 1] = 1;
    r->n_runs[w] = n + 1;
    return 0;
}

/* The rows of runs w (along the row dimension of d: its second in a
 * series, read at snapshot k) into buf, one after another. */
static herr_t read_runs(reader *r, hid_t d, int w, int series, hsize_t k, hid_t mt, void *buf)
{
    hsize_t dims[3];
    int rank = cdh5_dims(d, dims), rd = series ? 1 : 0;
    if (rank < 1 || rank <= rd) return -1;
    if (!r->n_sel[w]) return 0;
    hid_t fs = H5Dget_space(d);
    herr_t e = fs < 0 ? -1 : 0;
    for (size_t i = 0; e >= 0 && i < r->n_runs[w]; i++) {
        hsize_t start[3] = {series ? k : 0, 0, 0}, cnt[3] = {series ? 1 : dims[0], dims[1], dims[2]};
        start[rd] = r->runs[w][2 * i];
        cnt[rd] = r->runs[w][2 * i + 1];
        if (start[rd] + cnt[rd] > dims[rd]) e = -1;
        else e = H5Sselect_hyperslab(fs, i ? H5S_SELECT_OR : H5S_SELECT_SET, start, NULL, cnt, NULL);
    }
    hsize_t mdims[3] = {series ? 1 : dims[0], dims[1], dims[2]};
    mdims[rd] = r->n_sel[w];
    hid_t ms = e < 0 ? -1 : H5Screate_simple(rank, mdims, NULL);
    if (ms < 0) e = -1;
    if (e >= 0) e = cdh5_read(d, mt, ms, fs, buf);
    if (ms >= 0) H5Sclose(ms);
    if (fs >= 0) H5Sclose(fs);
    return e;
}

/* Is field f the pair force, which files written before it existed lack? */
static int is_pair_force(const cd_field_info *f) { return !strcmp(f->name, "pair_force"); }

static int rfail(reader *r, const char *fmt, ...)
{
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cdh5_msg(r->err, r->errlen, "%s: %s", r->path, msg);
    return -1;
}

static hid_t ropen(reader *r, const char *dpath)
{
    hid_t d = H5Dopen2(r->file, dpath, H5P_DEFAULT);
    if (d < 0) rfail(r, "cannot open dataset %s (is this a capdem run file with snapshots?)", dpath);
    return d;
}

static int read_ll(reader *r, hid_t d, const char *what, long long row, long long *v)
{
    if (cdh5_read_rows(d, (hsize_t)row, 1, H5T_NATIVE_LLONG, v) < 0)
        return rfail(r, "cannot read row %lld of %s", row, what);
    return 0;
}

/* cd_h5_read_snapshot_part: the file's rows of the part's particles and
 * primitives, of their wall contacts (of wm active rows, r->windex) and
 * of the active contacts (m rows) between two of its primitives. */
static int select_part(reader *r, const cd_state *s, long long wm, long long m)
{
    const cd_h5_part *p = r->part;
    size_t W = s->n_walls;
    int rc = 0;
    for (size_t q = 0; !rc && q < p->n; q++) rc = add_run(r, RUN_PARTICLES, (hsize_t)p->gid[q]);
    for (size_t q = 0; !rc && q < p->n_prims; q++) rc = add_run(r, RUN_PRIMS, (hsize_t)p->gprim[q]);
    r->wall_at = malloc(((size_t)wm + 1) * sizeof *r->wall_at);
    if (rc || !r->wall_at) return rfail(r, "out of memory");
    for (long long j = 0; W && j < wm; j++) {
        long long lp = cd_sorted_index(p->gprim, p->n_prims, r->windex[j] / (long long)W);
        if (lp < 0) continue;
        r->wall_at[r->n_sel[RUN_WALLS]] = (size_t)lp * W + (size_t)(r->windex[j] % (long long)W);
        if (add_run(r, RUN_WALLS, (hsize_t)(r->w0 + j))) return rfail(r, "out of memory");
    }
    /* the contacts' primitives: global ids in the file */
    const cd_field_info *fi = cdh5_column("pair_prim_i"), *fj = cdh5_column("pair_prim_j");
    cd_int *ij = malloc(2 * ((size_t)m + 1) * sizeof *ij);
    r->pair_ij = malloc(2 * ((size_t)m + 1) * sizeof *r->pair_ij);
    if (!ij || !r->pair_ij) {
        free(ij);
        return rfail(r, "out of memory");
    }
    if (m && (cdh5_read_rows(r->ds[fi - cd_fields], (hsize_t)r->c0, (hsize_t)m, H5T_NATIVE_INT32, ij) < 0 ||
              cdh5_read_rows(r->ds[fj - cd_fields], (hsize_t)r->c0, (hsize_t)m, H5T_NATIVE_INT32, ij + m) < 0)) {
        free(ij);
        return rfail(r, "cannot read the contacts' primitives of snapshot rows %lld..%lld", r->c0, r->c1);
    }
    for (long long j = 0; !rc && j < m; j++) {
        long long li = cd_sorted_index(p->gprim, p->n_prims, ij[j]),
                  lj = cd_sorted_index(p->gprim, p->n_prims, ij[m + j]);
        if (li < 0 || lj < 0) continue;
        r->pair_ij[2 * r->n_sel[RUN_PAIRS]] = (cd_int)li;
        r->pair_ij[2 * r->n_sel[RUN_PAIRS] + 1] = (cd_int)lj;
        rc = add_run(r, RUN_PAIRS, (hsize_t)(r->c0 + j));
    }
    free(ij);
    return rc ? rfail(r, "out of memory") : 0;
}

/* cd_h5_read_snapshot_part, after the rows are read: the columns that hold
 * row numbers (global ids in the file) in s's numbering. */
static void part_numbering(reader *r, cd_state *s)
{
    const cd_h5_part *p = r->part;
    for (size_t q = 0; q < s->n_particles; q++)
        s->prim_first[q] = (cd_int)cd_sorted_index(p->gprim, p->n_prims, s->prim_first[q]);
    for (size_t i = 0; i < s->n_prims; i++)
        s->prim_particle[i] = (cd_int)cd_sorted_index(p->gid, p->n, s->prim_particle[i]);
    for (size_t k = 0; k < s->n_pairs; k++) {
        s->pair_prim_i[k] = r->pair_ij[2 * k];
        s->pair_prim_j[k] = r->pair_ij[2 * k + 1];
    }
}

/* Opens everything snapshot k needs and checks it against the state, before
 * the state is touched. */
static int check_snapshot(reader *r, long long k, const cd_state *s)
{
    static const char *const names[CD_GROUP_COUNT] = {"particles", "primitives", "contacts", "wall contacts"};
    hsize_t dims[3];
    r->walls = ropen(r, CDH5_WALLS_VALUE);
    r->step = ropen(r, CDH5_SNAP_STEP);
    r->time = ropen(r, CDH5_SNAP_TIME);
    r->c_offset = ropen(r, CDH5_C_OFFSET);
    r->w_offset = ropen(r, CDH5_W_OFFSET);
    r->w_index = ropen(r, CDH5_W_INDEX);
    r->control = ropen(r, CDH5_CONTROL_VALUE);
    if (r->control < 0) return -1;
    if (r->walls < 0 || r->step < 0 || r->time < 0 || r->c_offset < 0 || r->w_offset < 0 || r->w_index < 0) return -1;
    /* shapes first: every read below goes into a buffer sized by the layout */
    const hsize_t one_snap[1] = {(hsize_t)k + 1}, two_snap[1] = {(hsize_t)k + 2};
    const hsize_t ctl_lo[2] = {(hsize_t)k + 1, 1}, ctl_hi[2] = {0, CD_CONTROL_SLOTS}, walls_lo[2] = {(hsize_t)k + 1, 0};
    if (cd_h5_check_dset(r->step, r->path, CDH5_SNAP_STEP, H5T_INTEGER, 1, one_snap, NULL, NULL, r->err, r->errlen) ||
        cd_h5_check_dset(r->time, r->path, CDH5_SNAP_TIME, H5T_FLOAT, 1, one_snap, NULL, NULL, r->err, r->errlen) ||
        cd_h5_check_dset(r->c_offset, r->path, CDH5_C_OFFSET, H5T_INTEGER, 1, two_snap, NULL, NULL, r->err,
                         r->errlen) ||
        cd_h5_check_dset(r->w_offset, r->path, CDH5_W_OFFSET, H5T_INTEGER, 1, two_snap, NULL, NULL, r->err,
                         r->errlen) ||
        cd_h5_check_dset(r->w_index, r->path, CDH5_W_INDEX, H5T_INTEGER, 1, NULL, NULL, NULL, r->err, r->errlen) ||
        cd_h5_check_dset(r->control, r->path, CDH5_CONTROL_VALUE, H5T_FLOAT, 2, ctl_lo, ctl_hi, NULL, r->err,
                         r->errlen) ||
        cd_h5_check_dset(r->walls, r->path, CDH5_WALLS_VALUE, H5T_COMPOUND, 2, walls_lo, NULL, dims, r->err, r->errlen))
        return -1;
    if (dims[1] != s->n_walls)
        return rfail(r, "the file holds %llu walls, the state %zu: was the state set up from the same config?",
                     (unsigned long long)dims[1], s->n_walls);
    if (s->n_walls > CD_MAX_WALLS) return rfail(r, "the state has %zu walls, at most %d", s->n_walls, CD_MAX_WALLS);
    if (read_ll(r, r->c_offset, CDH5_C_OFFSET, k, &r->c0) || read_ll(r, r->c_offset, CDH5_C_OFFSET, k + 1, &r->c1) ||
        read_ll(r, r->w_offset, CDH5_W_OFFSET, k, &r->w0) || read_ll(r, r->w_offset, CDH5_W_OFFSET, k + 1, &r->w1))
        return -1;
    if (r->c0 < 0 || r->c1 < r->c0 || r->w0 < 0 || r->w1 < r->w0)
        return rfail(r, "offsets of snapshot %lld are inconsistent (contacts %lld..%lld, wall contacts %lld..%lld)", k,
                     r->c0, r->c1, r->w0, r->w1);
    for (size_t i = 0; i < cd_n_fields; i++) {
        const cd_field_info *f = &cd_fields[i];
        char p[CDH5_PATH_LEN];
        if (cdh5_field_check(f, r->err, r->errlen)) return -1;
        cdh5_field_path(f, p, sizeof p);
        if (is_pair_force(f) && !cdh5_exists(r->file, p)) {
            r->legacy_force = 1;
            continue;
        }
        r->ds[i] = ropen(r, p);
        if (r->ds[i] < 0) return -1;
        long long n = cdh5_field_rows(r->ds[i], f, p, r->path, r->err, r->errlen);
        if (n < 0) return -1;
        enum cdh5_store st = cdh5_store_of(f);
        if (st == CDH5_ROWS) {
            long long end = cd_group_pair_rows(f->group) ? r->c1 : r->w1;
            if (n < end) return rfail(r, "%s has %lld rows, snapshot %lld needs %lld", p, n, k, end);
            continue;
        }
        size_t want = !r->part                        ? cd_state_rows(s, f->group)
                      : f->group == CD_GROUP_PARTICLE ? r->part->n_all
                                                      : r->part->n_all_prims;
        if ((size_t)n != want)
            return rfail(r, "the file holds %lld %s (%s), the state %zu: was the state set up from the same config?", n,
                         names[f->group], p, want);
        if (st == CDH5_SERIES && (cdh5_dims(r->ds[i], dims) < 1 || dims[0] <= (hsize_t)k))
            return rfail(r, "%s lacks snapshot %lld", p, k);
    }
    /* wall-contact rows: where they go */
    long long wm = r->w1 - r->w0, nwc = (long long)((r->part ? r->part->n_all_prims : s->n_prims) * s->n_walls);
    size_t wbytes, big;
    if (cd_h5_mul(&wbytes, (size_t)(wm > 0 ? wm : 1), sizeof *r->windex, 1) ||
        cd_h5_mul(&big, (size_t)(wm > 0 ? wm : 1), cdh5_max_row_bytes(), 1))
        return rfail(r, "%s: %lld wall-contact rows overflow a size; the file is refused", CDH5_W_OFFSET, wm);
    r->windex = malloc(wbytes);
    if (!r->windex) return rfail(r, "out of memory");
    if (wm && cdh5_read_rows(r->w_index, (hsize_t)r->w0, (hsize_t)wm, H5T_NATIVE_LLONG, r->windex) < 0)
        return rfail(r, "cannot read %s rows %lld..%lld", CDH5_W_INDEX, r->w0, r->w1);
    for (long long j = 0; j < wm; j++)
        if (r->windex[j] < 0 || r->windex[j] >= nwc)
            return rfail(r, "%s row %lld is %lld, outside 0..%lld", CDH5_W_INDEX, r->w0 + j, r->windex[j], nwc - 1);
    long long m = r->c1 - r->c0;
    r->tmp = malloc(big);
    if (!r->tmp) return rfail(r, "out of memory");
    if (r->part && select_part(r, s, wm, m)) return -1;
    if (r->part) m = (long long)r->n_sel[RUN_PAIRS];
    if ((size_t)m > s->cap_pairs && cd_state_reserve_pairs((cd_state *)s, (size_t)m))
        return rfail(r, "out of memory for %lld contacts", m);
    return 0;
}

/* Column i read: its dataset closed, which lets its chunk cache go (HDF5
 * keeps up to 1 MB of chunks per open dataset: 40 MB over the run file's
 * columns, measured, docs/mpi.md "Resume"). */
static void close_column(reader *r, size_t i)
{
    H5Dclose(r->ds[i]);
    r->ds[i] = H5I_INVALID_HID;
}

static int read_snapshot(reader *r, long long k, cd_state *s)
{
    long long m = r->c1 - r->c0, wm = r->w1 - r->w0;
    for (size_t i = 0; i < cd_n_fields; i++) {
        const cd_field_info *f = &cd_fields[i];
        char *col = *cd_field_ptr(s, f);
        hid_t mt = cdh5_mem_type(f);
        herr_t e = 0;
        if (r->ds[i] < 0 && is_pair_force(f) && r->legacy_force) continue; /* rebuilt below */
        int w = f->group == CD_GROUP_PARTICLE ? RUN_PARTICLES
                : f->group == CD_GROUP_PRIM   ? RUN_PRIMS
                : f->group == CD_GROUP_WALLC  ? RUN_WALLS
                                              : RUN_PAIRS;
        if (r->part) {
            enum cdh5_store st = cdh5_store_of(f);
            if (w == RUN_WALLS) memset(col, 0, cd_state_rows(s, f->group) * f->elem_size);
            hsize_t row0 = st == CDH5_SERIES  ? (hsize_t)k
                           : st == CDH5_FIXED ? 0
                                              : (hsize_t)(w == RUN_PAIRS ? r->c0 : r->w0);
            hsize_t rows = st == CDH5_SERIES ? 1 : st == CDH5_FIXED ? HSIZE_UNDEF : (hsize_t)(w == RUN_PAIRS ? m : wm);
            e = rows == 0 || cdh5_storage_fits(r->ds[i], row0, rows) ? 0 : -1;
            if (e >= 0) e = read_runs(r, r->ds[i], w, st == CDH5_SERIES, (hsize_t)k, mt, w == RUN_WALLS ? r->tmp : col);
            for (size_t j = 0; e >= 0 && w == RUN_WALLS && j < r->n_sel[w]; j++)
                memcpy(col + r->wall_at[j] * f->elem_size, (char *)r->tmp + j * f->elem_size, f->elem_size);
            if (e < 0) return rfail(r, "cannot read column %s of snapshot %lld", f->name, k);
            close_column(r, i);
            continue;
        }
        switch (cdh5_store_of(f)) {
        case CDH5_FIXED:
            if (cd_state_rows(s, f->group))
                e = cdh5_storage_fits(r->ds[i], 0, HSIZE_UNDEF) ? cdh5_read(r->ds[i], mt, H5S_ALL, H5S_ALL, col) : -1;
            break;
        case CDH5_SERIES:
            e = cdh5_read_rows(r->ds[i], (hsize_t)k, 1, mt, col);
            break;
        case CDH5_ROWS:
            if (cd_group_pair_rows(f->group)) {
                e = cdh5_read_rows(r->ds[i], (hsize_t)r->c0, (hsize_t)m, mt, col);
            } else {
                memset(col, 0, cd_state_rows(s, f->group) * f->elem_size);
                e = cdh5_read_rows(r->ds[i], (hsize_t)r->w0, (hsize_t)wm, mt, r->tmp);
                for (long long j = 0; e >= 0 && j < wm; j++)
                    memcpy(col + (size_t)r->windex[j] * f->elem_size, (char *)r->tmp + (size_t)j * f->elem_size,
                           f->elem_size);
            }
            break;
        }
        if (e < 0) return rfail(r, "cannot read column %s of snapshot %lld", f->name, k);
        close_column(r, i);
    }
    s->n_pairs = r->part ? r->n_sel[RUN_PAIRS] : (size_t)m;
    if (r->part) part_numbering(r, s);
    /* The force on j of a file that stored only its parts: F_n n + F_t,
     * the law's expression (kernels/contact_law.h), so the same bits. */
    if (r->legacy_force)
        for (size_t j = 0; j < s->n_pairs; j++)
            s->pair_force[j] = cd_contact_force_on_j(s->pair_fn[j], s->pair_normal[j], s->pair_ft[j]);
    cd_wall walls[CD_MAX_WALLS];
    memset(walls, 0, sizeof walls);
    hid_t wt = cdh5_wall_mem_type();
    herr_t e = cdh5_read_rows(r->walls, (hsize_t)k, 1, wt, walls);
    H5Tclose(wt);
    if (e < 0) return rfail(r, "cannot read %s of snapshot %lld", CDH5_WALLS_VALUE, k);
    memcpy(s->walls, walls, s->n_walls * sizeof walls[0]);
    memset(s->control, 0, sizeof s->control); /* a file may hold fewer slots (checked: never more) */
    if (cdh5_read_rows(r->control, (hsize_t)k, 1, H5T_NATIVE_DOUBLE, s->control) < 0)
        return rfail(r, "cannot read %s of snapshot %lld", CDH5_CONTROL_VALUE, k);
    long long step;
    if (read_ll(r, r->step, CDH5_SNAP_STEP, k, &step)) return -1;
    if (cdh5_read_rows(r->time, (hsize_t)k, 1, H5T_NATIVE_DOUBLE, &s->time) < 0)
        return rfail(r, "cannot read row %lld of %s", k, CDH5_SNAP_TIME);
    s->step = step;
    /* arms derived before (a set-up's) follow the ends read: the host's
     * observables derive the overlaps from them (kernels/observe_items.h) */
    if (s->prim_arm && cd_state_arms_derive(s)) return rfail(r, "out of memory for the arms of snapshot %lld", k);
    return 0;
}

int cd_h5_read_snapshot(const char *path, int k, cd_state *s, char *err, size_t errlen)
{
    return cd_h5_read_snapshot_part(path, k, NULL, s, err, errlen);
}

int cd_h5_read_snapshot_part(const char *path, int k, const cd_h5_part *part, cd_state *s, char *err, size_t errlen)
{
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    reader r = {.path = path,
                .err = err,
                .errlen = errlen,
                .file = H5I_INVALID_HID,
                .walls = H5I_INVALID_HID,
                .step = H5I_INVALID_HID,
                .time = H5I_INVALID_HID,
                .c_offset = H5I_INVALID_HID,
                .w_offset = H5I_INVALID_HID,
                .w_index = H5I_INVALID_HID,
                .control = H5I_INVALID_HID,
                .part = part};
    int rc = -1;
    r.ds = malloc(cd_n_fields * sizeof *r.ds);
    if (!r.ds) {
        snprintf(err, errlen, "%s: out of memory", path);
        goto done;
    }
    for (size_t i = 0; i < cd_n_fields; i++) r.ds[i] = H5I_INVALID_HID;
    r.file = cdh5_open_ro(path, err, errlen);
    if (r.file < 0) goto done;
    long long n = cdh5_committed(r.file, path, err, errlen);
    if (n < 0) goto done;
    long long kk = k < 0 ? n - 1 : k;
    if (n == 0) {
        rfail(&r, "the file holds no complete snapshot");
        goto done;
    }
    if (kk >= n) {
        rfail(&r, "snapshot %d requested, the file holds %lld (0..%lld)", k, n, n - 1);
        goto done;
    }
    if (check_snapshot(&r, kk, s) == 0) rc = read_snapshot(&r, kk, s);
done:
    if (r.ds)
        for (size_t i = 0; i < cd_n_fields; i++)
            if (r.ds[i] >= 0) H5Dclose(r.ds[i]);
    hid_t ids[] = {r.walls, r.step, r.time, r.c_offset, r.w_offset, r.w_index, r.control};
    for (size_t i = 0; i < sizeof ids / sizeof ids[0]; i++)
        if (ids[i] >= 0) H5Dclose(ids[i]);
    if (r.file >= 0) H5Fclose(r.file);
    free(r.ds);
    free(r.windex);
    free(r.tmp);
    for (int w = 0; w < 4; w++) free(r.runs[w]);
    free(r.wall_at);
    free(r.pair_ij);
    cdh5_quiet_end(&q);
    return rc;
}

int cd_h5_read_column_rows(const char *path, int k, const char *name, long long row0, long long n, void *buf, char *err,
                           size_t errlen)
{
    const cd_field_info *f = cdh5_column(name);
    char p[CDH5_PATH_LEN];
    if (!f || (f->group != CD_GROUP_PARTICLE && f->group != CD_GROUP_PRIM) || cdh5_field_check(f, err, errlen)) {
        snprintf(err, errlen, "%s: %s is not a particle or primitive column", path, name);
        return -1;
    }
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    cdh5_field_path(f, p, sizeof p);
    hid_t file = cdh5_open_ro(path, err, errlen), d = H5I_INVALID_HID;
    long long snaps = file < 0 ? -1 : cdh5_committed(file, path, err, errlen), kk = k < 0 ? snaps - 1 : k;
    int rc = snaps < 1 || kk >= snaps ? -1 : 0;
    if (!rc && snaps >= 1) rc = (d = H5Dopen2(file, p, H5P_DEFAULT)) < 0 ? -1 : 0;
    long long rows = rc ? -1 : cdh5_field_rows(d, f, p, path, err, errlen);
    if (!rc && (rows < 0 || row0 < 0 || n < 0 || row0 + n > rows)) rc = -1;
    if (!rc && n > 0) {
        reader r = {.path = path, .err = err, .errlen = errlen};
        int series = cdh5_store_of(f) == CDH5_SERIES;
        if (add_run(&r, RUN_PARTICLES, (hsize_t)row0)) rc = -1;
        else {
            r.runs[RUN_PARTICLES][1] = (hsize_t)n; /* one run of n rows */
            r.n_sel[RUN_PARTICLES] = (size_t)n;
        }
        if (!rc && (!cdh5_storage_fits(d, series ? (hsize_t)kk : 0, series ? 1 : HSIZE_UNDEF) ||
                    read_runs(&r, d, RUN_PARTICLES, series, (hsize_t)kk, cdh5_mem_type(f), buf) < 0))
            rc = -1;
        free(r.runs[RUN_PARTICLES]);
    }
    if (rc && snaps >= 0) cdh5_msg(err, errlen, "%s: cannot read rows %lld..%lld of %s", path, row0, row0 + n, p);
    if (d >= 0) H5Dclose(d);
    if (file >= 0) H5Fclose(file);
    cdh5_quiet_end(&q);
    return rc;
}

static char *read_text(const char *path, const char *dpath, char *err, size_t errlen);

char *cd_h5_read_config_text(const char *path, char *err, size_t errlen)
{
    return read_text(path, CDH5_PATH(CONFIG), err, errlen);
}

char *cd_h5_read_latest_config_text(const char *path, char *where, size_t wlen, char *err, size_t errlen)
{
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    hid_t f = cdh5_open_ro(path, err, errlen);
    int k = 0;
    char p[CDH5_PATH_LEN];
    while (f >= 0 && k < 1000000) {
        snprintf(p, sizeof p, "%s/%d", CDH5_PATH(RESUMES), k);
        if (!cdh5_exists(f, p)) break;
        k++;
    }
    if (f >= 0) H5Fclose(f);
    cdh5_quiet_end(&q);
    if (f < 0) return NULL;
    if (k > 0) snprintf(where, wlen, "%s/%d", CDH5_PATH(RESUMES), k - 1);
    else snprintf(where, wlen, "%s", CDH5_PATH(CONFIG));
    return read_text(path, where, err, errlen);
}

static char *read_text(const char *path, const char *dpath, char *err, size_t errlen)
{
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    hid_t f = cdh5_open_ro(path, err, errlen);
    char *out = f < 0 ? NULL : cdh5_read_string(f, path, dpath, (size_t)1 << 26, err, errlen);
    if (f >= 0) H5Fclose(f);
    cdh5_quiet_end(&q);
    return out;
}

char *cdh5_read_string(hid_t f, const char *path, const char *dpath, size_t max_bytes, char *err, size_t errlen)
{
    char *out = NULL;
    hid_t d = -1, t = -1, mt = -1;
    d = H5Dopen2(f, dpath, H5P_DEFAULT);
    if (d < 0) {
        cdh5_msg(err, errlen, "%s: cannot open dataset %s", path, dpath);
        goto done;
    }
    if (cd_h5_check_string(d, 0, path, dpath, max_bytes, err, errlen)) goto done;
    if (!cdh5_storage_fits(d, 0, HSIZE_UNDEF)) {
        cdh5_msg(err, errlen, "%s: %s is corrupted (its stored size does not match its type)", path, dpath);
        goto done;
    }
    t = H5Dget_type(d);
    mt = H5Tcopy(t);
    if (H5Tis_variable_str(t) > 0) {
        char *p = NULL;
        if (H5Dread(d, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, &p) < 0 || !p) {
            cdh5_msg(err, errlen, "%s: cannot read %s", path, dpath);
            goto done;
        }
        size_t len = strlen(p);
        out = malloc(len + 1);
        if (out) memcpy(out, p, len + 1);
        H5free_memory(p);
    } else {
        size_t size = H5Tget_size(t);
        out = malloc(size + 1);
        if (out && H5Dread(d, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) < 0) {
            cdh5_msg(err, errlen, "%s: cannot read %s", path, dpath);
            free(out);
            out = NULL;
            goto done;
        }
        if (out) out[size] = 0;
    }
    if (!out) snprintf(err, errlen, "%s: out of memory", path);
done:
    if (mt >= 0) H5Tclose(mt);
    if (t >= 0) H5Tclose(t);
    if (d >= 0) H5Dclose(d);
    return out;
}
