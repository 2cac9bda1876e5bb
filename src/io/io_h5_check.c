/* Integrity of run files read back: the hostile-file guards every reader
 * uses (io_h5_check.h: class, rank and extents checked before anything is
 * allocated or read, overflow-checked sizes) and the checksum check of the
 * chunks a resume appends to (cd_h5_check_tails, io_h5.h).  docs/output.md,
 * "Corruption" and "Hostile files". */
#include "io/io_h5.h"
#include "io/io_h5_internal.h"
#include "io/io_h5_check.h"
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- hostile-file guards (io_h5_check.h) ------------------------------------ */

static const char *class_name(H5T_class_t c)
{
    switch (c) {
    case H5T_INTEGER:
        return "integers";
    case H5T_FLOAT:
        return "floats";
    case H5T_STRING:
        return "strings";
    case H5T_COMPOUND:
        return "compound records";
    default:
        return "values of another class";
    }
}

int cd_h5_check_dset(hid_t d, const char *file, const char *dpath, H5T_class_t cls, int rank, const hsize_t *lo,
                     const hsize_t *hi, hsize_t dims[3], char *err, size_t errlen)
{
    hsize_t own[3], *dm = dims ? dims : own;
    dm[0] = dm[1] = dm[2] = 1;
    hid_t t = H5Dget_type(d), sp = H5Dget_space(d);
    H5T_class_t have = t >= 0 ? H5Tget_class(t) : H5T_NO_CLASS;
    int r = sp >= 0 && H5Sget_simple_extent_type(sp) != H5S_NULL ? H5Sget_simple_extent_ndims(sp) : -1;
    hsize_t got[H5S_MAX_RANK];
    int ok = r == rank && (r == 0 || H5Sget_simple_extent_dims(sp, got, NULL) == r);
    if (t >= 0) H5Tclose(t);
    if (sp >= 0) H5Sclose(sp);
    H5Eclear2(H5E_DEFAULT);
    if (t < 0 || (cls != CD_H5_ANY_CLASS && have != cls)) {
        snprintf(err, errlen, "%s: dataset %s holds %s, the layout allows only %s; the file is refused", file, dpath,
                 class_name(have), class_name(cls));
        return -1;
    }
    if (!ok) {
        snprintf(err, errlen, "%s: dataset %s has rank %d, the layout allows only rank %d; the file is refused", file,
                 dpath, r, rank);
        return -1;
    }
    for (int k = 0; k < rank; k++) {
        hsize_t a = lo ? lo[k] : 0, b = hi && hi[k] ? hi[k] : ~(hsize_t)0;
        if (got[k] < a || got[k] > b) {
            snprintf(err, errlen,
                     "%s: dataset %s has %llu entries along dimension %d, the layout allows %llu..%llu; "
                     "the file is refused",
                     file, dpath, (unsigned long long)got[k], k, (unsigned long long)a, (unsigned long long)b);
            return -1;
        }
        dm[k] = got[k];
    }
    return 0;
}

int cd_h5_check_string(hid_t obj, int attr, const char *file, const char *what, size_t max_bytes, char *err,
                       size_t errlen)
{
    hid_t t = attr ? H5Aget_type(obj) : H5Dget_type(obj), sp = attr ? H5Aget_space(obj) : H5Dget_space(obj);
    hssize_t n = sp >= 0 ? H5Sget_simple_extent_npoints(sp) : -1;
    int str = t >= 0 && H5Tget_class(t) == H5T_STRING, var = str && H5Tis_variable_str(t) > 0;
    size_t size = t >= 0 ? H5Tget_size(t) : 0;
    if (t >= 0) H5Tclose(t);
    if (sp >= 0) H5Sclose(sp);
    H5Eclear2(H5E_DEFAULT);
    if (!str || n != 1 || (!var && size > max_bytes)) {
        snprintf(err, errlen, "%s: %s must hold one string%s, it holds %lld %s%s; the file is refused", file, what,
                 var ? "" : " of bounded length", (long long)n, str ? "strings" : "non-strings",
                 !var && size > max_bytes ? " too long" : "");
        return -1;
    }
    return 0;
}

int cd_h5_check_number_attr(hid_t a, const char *file, const char *what, char *err, size_t errlen)
{
    hid_t t = H5Aget_type(a), sp = H5Aget_space(a);
    hssize_t n = sp >= 0 ? H5Sget_simple_extent_npoints(sp) : -1;
    H5T_class_t c = t >= 0 ? H5Tget_class(t) : H5T_NO_CLASS;
    if (t >= 0) H5Tclose(t);
    if (sp >= 0) H5Sclose(sp);
    H5Eclear2(H5E_DEFAULT);
    if (n != 1 || (c != H5T_INTEGER && c != H5T_FLOAT)) {
        snprintf(err, errlen, "%s: attribute %s must hold one number, it holds %lld %s; the file is refused", file,
                 what, (long long)n, class_name(c));
        return -1;
    }
    return 0;
}

int cd_h5_mul(size_t *out, size_t a, size_t b, size_t c)
{
    *out = 0;
    if ((b && a > SIZE_MAX / b) || (c && a * b > SIZE_MAX / c)) return -1;
    *out = a * b * c;
    return 0;
}

/* ---- checksums of the chunks a resume appends to --------------------------- */

typedef struct {
    char *err;
    size_t errlen;
    const char *path;
    int bad;
} tail_check;

/* Bytes one chunk of dcpl's layout must occupy on disk: its elements
 * times elem, plus 4 bytes of Fletcher-32 when it has that filter; 0 when
 * that cannot be known (another filter, e.g. an h5repack'ed file, whose
 * output HDF5 sizes itself) and -1 when the layout is impossible. */
static long long chunk_bytes(hid_t dcpl, int rank, size_t elem, hsize_t ch[8])
{
    if (H5Pget_chunk(dcpl, rank, ch) != rank) return -1;
    int nf = H5Pget_nfilters(dcpl), fletcher = 0;
    for (int k = 0; k < nf; k++) {
        unsigned flags, conf;
        size_t nv = 0;
        H5Z_filter_t id = H5Pget_filter2(dcpl, (unsigned)k, &flags, &nv, NULL, 0, NULL, &conf);
        if (id != H5Z_FILTER_FLETCHER32) return 0;
        fletcher = 1;
    }
    size_t want = elem;
    for (int r = 0; r < rank; r++)
        if (!ch[r] || cd_h5_mul(&want, want, (size_t)ch[r], 1) || want > ((size_t)1 << 40)) return -1;
    return (long long)want + (fletcher ? 4 : 0);
}

/* Whether every chunk holding rows row0..row0+nrows-1 (all of every inner
 * dimension) is stored with exactly chunk_bytes (or never written, read as
 * fill values). */
static int chunks_fit(hid_t d, hid_t dcpl, int rank, size_t elem, const hsize_t *dims, hsize_t row0, hsize_t nrows)
{
    hsize_t ch[8], off[8];
    long long want = chunk_bytes(dcpl, rank, elem, ch);
    if (want <= 0) return want == 0;
    if (rank == 0 || nrows == 0) return 1;
    for (off[0] = row0 - row0 % ch[0]; off[0] < row0 + nrows; off[0] += ch[0]) {
        for (int r = 1; r < rank; r++) off[r] = 0;
        for (;;) {
            /* (the index's own entry: H5Dget_chunk_storage_size reports
             * the implied size of an unfiltered chunk, not what is stored) */
            unsigned filter_mask = 0;
            haddr_t addr = HADDR_UNDEF;
            hsize_t bytes = 0;
            if (H5Dget_chunk_info_by_coord(d, off, &filter_mask, &addr, &bytes) < 0) return 0;
            if (addr != HADDR_UNDEF && bytes != (hsize_t)want) return 0;
            int r = rank - 1;
            for (; r >= 1; r--) {
                off[r] += ch[r];
                if (off[r] < dims[r]) break;
                off[r] = 0;
            }
            if (r < 1) break;
        }
    }
    return 1;
}

/* HDF5 1.10 trusts a dataset's type and layout messages when it reads and
 * copies that many bytes from what is stored: a corrupted datatype that
 * makes elements larger than a stored chunk (found by fuzz_runfile: a
 * 12-byte chunk of a dataset whose type claimed 32-byte elements) is read
 * past its buffer, by the resume's tail check and by every row reader.
 * So every reader first compares what is stored with what the extent and
 * type imply: each chunk it will touch (chunked), the whole buffer
 * (compact), or at least the extent (contiguous, once allocated). */
int cdh5_storage_fits(hid_t d, hsize_t row0, hsize_t nrows)
{
    hid_t dcpl = H5Dget_create_plist(d), sp = H5Dget_space(d), ft = H5Dget_type(d);
    int rank = sp >= 0 ? H5Sget_simple_extent_ndims(sp) : -1, ok = 0;
    hsize_t dims[8];
    size_t elem = ft >= 0 ? H5Tget_size(ft) : 0, total = elem;
    if (dcpl >= 0 && rank >= 0 && rank <= 8 && elem && H5Sget_simple_extent_dims(sp, dims, NULL) == rank) {
        ok = 1;
        for (int r = 0; r < rank && ok; r++) ok = !cd_h5_mul(&total, total, (size_t)dims[r], 1);
        if (rank > 0) nrows = row0 > dims[0] ? 0 : (nrows < dims[0] - row0 ? nrows : dims[0] - row0);
        H5D_layout_t layout = H5Pget_layout(dcpl);
        hsize_t stored = H5Dget_storage_size(d);
        if (!ok) {
        } else if (layout == H5D_CHUNKED) {
            ok = chunks_fit(d, dcpl, rank, elem, dims, row0, nrows);
        } else if (layout == H5D_COMPACT) {
            ok = stored == (hsize_t)total;
        } else if (layout == H5D_CONTIGUOUS) {
            ok = stored == 0 || stored >= (hsize_t)total;
        }
    }
    if (ft >= 0) H5Tclose(ft);
    if (sp >= 0) H5Sclose(sp);
    if (dcpl >= 0) H5Pclose(dcpl);
    return ok;
}

/* Reads the last row of dataset `name` when it is chunked, so that HDF5
 * verifies that chunk's Fletcher-32 checksum (every other chunk a resume
 * reads is verified as it is read). */
static herr_t check_tail(hid_t loc, const char *name, const H5O_info_t *info, void *data)
{
    tail_check *t = data;
    if (info->type != H5O_TYPE_DATASET || t->bad) return 0;
    hid_t d = H5Dopen2(loc, name, H5P_DEFAULT);
    if (d < 0) {
        t->bad = 1;
        cdh5_msg(t->err, t->errlen, "%s: cannot open dataset /%s", t->path, name);
        return 1;
    }
    hid_t dcpl = H5Dget_create_plist(d), sp = H5Dget_space(d), ft = H5Dget_type(d);
    hid_t mt = ft >= 0 ? H5Tget_native_type(ft, H5T_DIR_ASCEND) : -1;
    int rank = sp >= 0 ? H5Sget_simple_extent_ndims(sp) : -1;
    hsize_t dims[8], start[8] = {0}, count[8];
    int chunked = dcpl >= 0 && H5Pget_layout(dcpl) == H5D_CHUNKED;
    int ok = rank >= 0 && rank <= 8 && mt >= 0;
    if (ok && chunked && rank >= 1 && H5Sget_simple_extent_dims(sp, dims, NULL) == rank && dims[0] > 0) {
        size_t row = H5Tget_size(mt);
        for (int r = 1; r < rank && row; r++)
            if (cd_h5_mul(&row, row, (size_t)dims[r], 1) || row > ((size_t)1 << 30)) row = 0; /* refused below */
        void *buf = row ? malloc(row) : NULL;
        start[0] = dims[0] - 1;
        count[0] = 1;
        for (int r = 1; r < rank; r++) count[r] = dims[r];
        hid_t ms = H5Screate_simple(rank, count, NULL);
        ok = buf && ms >= 0 && cdh5_storage_fits(d, start[0], 1) &&
             H5Sselect_hyperslab(sp, H5S_SELECT_SET, start, NULL, count, NULL) >= 0 &&
             H5Dread(d, mt, ms, sp, H5P_DEFAULT, buf) >= 0;
        if (ms >= 0) H5Sclose(ms);
        free(buf);
    }
    if (!ok) {
        t->bad = 1;
        cdh5_msg(t->err, t->errlen,
                 "%s: dataset /%s is corrupted (its checksum or layout does not match); the file is "
                 "refused, nothing was read from it or written to it",
                 t->path, name);
    }
    if (mt >= 0) H5Tclose(mt);
    if (ft >= 0) H5Tclose(ft);
    if (sp >= 0) H5Sclose(sp);
    if (dcpl >= 0) H5Pclose(dcpl);
    H5Dclose(d);
    return t->bad ? 1 : 0;
}

int cd_h5_check_tails(const char *path, char *err, size_t errlen)
{
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    tail_check t = {err, errlen, path, 0};
    hid_t f = cdh5_open_ro(path, err, errlen);
    if (f < 0) t.bad = 1;
    else if (H5Ovisit2(f, H5_INDEX_NAME, H5_ITER_NATIVE, check_tail, &t, H5O_INFO_BASIC) < 0 && !t.bad) {
        t.bad = 1;
        cdh5_msg(err, errlen, "%s: its object tree cannot be walked (a corrupted file?)", path);
    }
    if (f >= 0) H5Fclose(f);
    cdh5_quiet_end(&q);
    return t.bad ? -1 : 0;
}
