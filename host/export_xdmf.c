/* capdem export: an XDMF description of a run file, for ParaView and VisIt
 * (docs/visualization.md).
 *
 * The .xmf file holds no numbers of the run; every data item names a dataset
 * of the run file.  Three temporal collections, one grid per snapshot each:
 *   arms       one 2-point line per primitive (arm), points a_0..a_{P-1},
 *              b_0..b_{P-1}; radius and owning particle as cell and point data
 *              (ParaView's Tube filter varies the radius by a POINT scalar);
 *   particles  one vertex per particle centre, every particle column;
 *   contacts   one line per active contact between the two particle centres,
 *              every contact column as cell data.
 *
 * Why the helper datasets under /visualization: a grid of snapshot k needs
 * row k of (S, P, 3) datasets, and the arms need prim_a[k] and prim_b[k] as
 * ONE point array.  XDMF can say that with HyperSlab and JOIN function data
 * items, but ParaView 5.11 reads those only with its XDMF2 reader: its Xdmf3
 * readers skip such items ("Skipping unrecognized array type [None]") and
 * then crash.  So each snapshot gets small HDF5 virtual datasets (VDS), which
 * map rows of the run's datasets without copying them, and the .xmf uses
 * plain whole-dataset items only, which every XDMF reader understands.  The
 * only real helper data are the connectivities (arm_cells, contact_cells,
 * particle_id), a few integers per arm and per contact.
 *
 * Layout (version CD_EXPORT_LAYOUT):
 *   /visualization                 attributes layout, n_particles, n_prims
 *     particle_id      (N) int32        0..N-1: vertex connectivity, particle id
 *     arm_cells        (P, 2) int32     (i, P+i): the line of arm i
 *     arm_point_radius (2P) VDS         prim_radius twice (a ends, b ends)
 *     arm_point_particle (2P) VDS       prim_particle twice
 *     snapshots/<k>                attributes step, time, contact_rows [c0, c1)
 *       arm_points     (2P, 3) VDS      prim_a/value[k] then prim_b/value[k]
 *       <field>        (N, c) VDS       /particles/all/<field>/value[k]
 *       contact_cells  (C_k, 2) int32   particle_i, particle_j of rows c0..c1-1
 *       <column>       (C_k, c) VDS     /contacts/<column>[c0..c1-1]
 *       analysis_...   VDS              per-snapshot /analysis datasets, if any
 *
 * A second export of the same file keeps what is already there (HDF5 does
 * not give back the space of deleted objects, so rebuilding every time would
 * grow the file); it adds snapshots written since and drops snapshots a
 * resume cut away.  When the run file cannot be opened for writing (read-only
 * file), the helpers go into a sidecar RUN.viz.h5 whose virtual datasets name
 * the run file. */
#define _XOPEN_SOURCE 700
#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <hdf5.h>
#include "export.h"
#include "io_h5.h"

#define CD_EXPORT_LAYOUT 1
#define CD_EXPORT_MAX_FIELDS 64
#define CD_EXPORT_MAX_COMP 16
#define CD_EXPORT_PATH 4200   /* > PATH_MAX: room for a resolved path and a suffix */

enum { CD_EXPORT_OK = 0, CD_EXPORT_FAIL = 1, CD_EXPORT_BAD_INPUT = 2 };

typedef struct {
    char name[96];         /* attribute name shown in ParaView */
    char src[300];         /* dataset in the run file */
    int rank;
    hsize_t dims[3];
    int ncomp;             /* values per row: product of the dims after the row axis/axes */
    char number_type[8];   /* XDMF NumberType: Float, Int, UInt */
    int precision;         /* bytes */
} cd_export_field;

typedef struct {
    const char *path;                 /* run file as given */
    hid_t f;                          /* run file */
    hid_t vf;                         /* file holding /visualization: f or the sidecar */
    hid_t viz;                        /* /visualization */
    char vds_src[CD_EXPORT_PATH];     /* run file as the virtual datasets name it */
    char h5_ref[CD_EXPORT_PATH];      /* run file as the .xmf names it */
    char viz_ref[CD_EXPORT_PATH];     /* file holding /visualization as the .xmf names it */
    int S;                            /* complete snapshots */
    hsize_t N, P;
    long long *off;                   /* S + 1 contact row offsets */
    long long *step;
    double *time;
    cd_export_field pt[CD_EXPORT_MAX_FIELDS]; int npt;   /* per snapshot, per particle */
    cd_export_field pf[CD_EXPORT_MAX_FIELDS]; int npf;   /* fixed, per particle */
    cd_export_field cf[CD_EXPORT_MAX_FIELDS]; int ncf;   /* per contact row */
    cd_export_field position, prim_a, prim_b, prim_radius, prim_particle;
    long long bad_contacts;           /* rows whose particle_i/j was -1 */
    int status;                       /* exit status of the first failure */
    char err[1536];
} cd_export_ctx;

/* Records the first failure (later ones are usually consequences). */
static int cd_export_fail(cd_export_ctx *x, int status, const char *fmt, ...)
{
    if (x->status == CD_EXPORT_OK) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(x->err, sizeof x->err, fmt, ap);
        va_end(ap);
        x->status = status;
    }
    return -1;
}

/* HDF5's innermost message (the first one walking upward: it names the
 * file and errno), appended to our own so that a failure says why. */
static herr_t cd_export_walk_err(unsigned n, const H5E_error2_t *e, void *data)
{
    if (n == 0 && e->desc && e->desc[0]) snprintf((char *)data, 256, "%s", e->desc);
    return 0;
}

static const char *cd_export_h5_reason(char *buf)
{
    buf[0] = 0;
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, cd_export_walk_err, buf);
    return buf[0] ? buf : "no detail from HDF5";
}

static int cd_export_exists(hid_t loc, const char *path)
{
    /* H5Lexists fails (instead of returning 0) when an intermediate group is
     * missing, so walk the path one component at a time. */
    char buf[CD_EXPORT_PATH];
    snprintf(buf, sizeof buf, "%s", path);
    for (char *p = buf + (buf[0] == '/'); ; ) {
        char *slash = strchr(p, '/');
        if (slash) *slash = 0;
        if (H5Lexists(loc, buf, H5P_DEFAULT) <= 0) return 0;
        if (!slash) return 1;
        *slash = '/';
        p = slash + 1;
    }
}

/* Shape and XDMF number type of a dataset; -1 when it is missing or not a
 * plain integer or floating-point array of rank 1..3. */
static int cd_export_describe(hid_t f, const char *path, cd_export_field *fl)
{
    memset(fl, 0, sizeof *fl);
    snprintf(fl->src, sizeof fl->src, "%s", path);
    if (!cd_export_exists(f, path)) return -1;
    hid_t o = H5Oopen(f, path, H5P_DEFAULT);
    if (o < 0) return -1;
    H5I_type_t type = H5Iget_type(o);
    H5Oclose(o);
    if (type != H5I_DATASET) return -1;
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    if (d < 0) return -1;
    hid_t sp = H5Dget_space(d), t = H5Dget_type(d);
    int rank = H5Sget_simple_extent_ndims(sp);
    int ok = rank >= 1 && rank <= 3;
    if (ok) H5Sget_simple_extent_dims(sp, fl->dims, NULL);
    fl->rank = rank;
    H5T_class_t cls = H5Tget_class(t);
    fl->precision = (int)H5Tget_size(t);
    if (cls == H5T_FLOAT && (fl->precision == 4 || fl->precision == 8)) {
        strcpy(fl->number_type, "Float");
    } else if (cls == H5T_INTEGER && (fl->precision == 1 || fl->precision == 2 || fl->precision == 4 || fl->precision == 8)) {
        strcpy(fl->number_type, H5Tget_sign(t) == H5T_SGN_NONE ? "UInt" : "Int");
        if (fl->precision == 1) strcpy(fl->number_type, H5Tget_sign(t) == H5T_SGN_NONE ? "UChar" : "Char");
    } else {
        ok = 0;
    }
    H5Tclose(t);
    H5Sclose(sp);
    H5Dclose(d);
    return ok ? 0 : -1;
}

static int cd_export_read_all(cd_export_ctx *x, const char *path, hid_t memtype, hsize_t n, void *buf)
{
    hid_t d = H5Dopen2(x->f, path, H5P_DEFAULT);
    if (d < 0) return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: missing dataset %s (is this a capdem run file?)", x->path, path);
    hid_t fs = H5Dget_space(d);
    hsize_t start = 0, count = n;
    int rc = -1;
    if (H5Sget_simple_extent_ndims(fs) == 1) {
        hsize_t have;
        H5Sget_simple_extent_dims(fs, &have, NULL);
        if (have >= n) {
            hid_t ms = H5Screate_simple(1, &count, NULL);
            H5Sselect_hyperslab(fs, H5S_SELECT_SET, &start, NULL, &count, NULL);
            rc = n == 0 ? 0 : H5Dread(d, memtype, ms, fs, H5P_DEFAULT, buf);
            H5Sclose(ms);
        }
    }
    H5Sclose(fs);
    H5Dclose(d);
    if (rc < 0) return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: cannot read %llu values of %s", x->path, (unsigned long long)n, path);
    return 0;
}

/* ---- discovering the columns ------------------------------------------ */

static void cd_export_set_ncomp(cd_export_field *fl, int row_axes)
{
    fl->ncomp = 1;
    for (int i = row_axes; i < fl->rank; i++) fl->ncomp *= (int)fl->dims[i];
}

static int cd_export_name_taken(const cd_export_field *list, int n, const char *name)
{
    for (int i = 0; i < n; i++)
        if (!strcmp(list[i].name, name)) return 1;
    return 0;
}

static void cd_export_add(cd_export_field *list, int *n, const cd_export_field *fl)
{
    if (*n < CD_EXPORT_MAX_FIELDS && fl->ncomp >= 1 && fl->ncomp <= CD_EXPORT_MAX_COMP &&
        !cd_export_name_taken(list, *n, fl->name))
        list[(*n)++] = *fl;
}

enum { CD_EXPORT_PART_TIME, CD_EXPORT_PART_FIXED, CD_EXPORT_CONTACT, CD_EXPORT_ANALYSIS };

/* Names the snapshot groups use for themselves. */
static int cd_export_reserved(const char *name)
{
    return !strcmp(name, "position") || !strcmp(name, "arm_points") || !strcmp(name, "contact_cells") ||
           !strcmp(name, "particle");
}

/* Sorts a dataset into the lists by where it lives and by its shape:
 * (S', N, ...) per snapshot and particle, (N, ...) fixed per particle,
 * (C, ...) per contact row.  /analysis datasets go by shape alone. */
static void cd_export_classify(cd_export_ctx *x, const char *path, const char *label, int where)
{
    cd_export_field fl;
    if (cd_export_describe(x->f, path, &fl)) return;
    hsize_t C = (hsize_t)x->off[x->S];
    int per_snapshot = fl.rank >= 2 && fl.dims[0] >= (hsize_t)x->S && fl.dims[1] == x->N;
    int fixed = fl.rank <= 2 && fl.dims[0] == x->N;
    int contact = fl.rank <= 2 && C > 0 && (where == CD_EXPORT_CONTACT ? fl.dims[0] >= C : fl.dims[0] == C);
    cd_export_field *list;
    int *n;
    if ((where == CD_EXPORT_PART_TIME || where == CD_EXPORT_ANALYSIS) && per_snapshot) {
        list = x->pt; n = &x->npt;
        cd_export_set_ncomp(&fl, 2);
    } else if ((where == CD_EXPORT_PART_FIXED || where == CD_EXPORT_ANALYSIS) && fixed) {
        list = x->pf; n = &x->npf;
        cd_export_set_ncomp(&fl, 1);
    } else if ((where == CD_EXPORT_CONTACT || where == CD_EXPORT_ANALYSIS) && contact) {
        list = x->cf; n = &x->ncf;
        cd_export_set_ncomp(&fl, 1);
    } else {
        return;
    }
    snprintf(fl.name, sizeof fl.name, "%s", label);
    if (where == CD_EXPORT_ANALYSIS && (cd_export_reserved(label) || cd_export_name_taken(list, *n, label)))
        snprintf(fl.name, sizeof fl.name, "analysis_%s", label);
    cd_export_add(list, n, &fl);
}

/* Walks a group by link index (stable across HDF5 1.10 .. 1.14, unlike the
 * H5Ovisit / H5Literate callback types); rel is the path below base. */
static void cd_export_walk(cd_export_ctx *x, const char *base, const char *rel, int depth)
{
    char gpath[2 * CD_EXPORT_PATH];
    snprintf(gpath, sizeof gpath, "%s%s%s", base, rel[0] ? "/" : "", rel);
    hid_t g = H5Gopen2(x->f, gpath, H5P_DEFAULT);
    if (g < 0) return;
    H5G_info_t gi;
    if (H5Gget_info(g, &gi) < 0) gi.nlinks = 0;
    for (hsize_t i = 0; i < gi.nlinks; i++) {
        char name[256], child[CD_EXPORT_PATH], path[2 * CD_EXPORT_PATH];
        if (H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT) < 0) continue;
        snprintf(child, sizeof child, "%s%s%s", rel, rel[0] ? "/" : "", name);
        snprintf(path, sizeof path, "%s/%s", base, child);
        hid_t o = H5Oopen(x->f, path, H5P_DEFAULT);
        if (o < 0) continue;
        H5I_type_t type = H5Iget_type(o);
        H5Oclose(o);
        if (type == H5I_GROUP && depth < 4) {
            /* `capdem analyze` keeps per-snapshot summary tables (histograms,
             * fits: docs/analysis.md) in /analysis/snapshot_<step>; their
             * rows are bins, not particles, whatever their length. */
            if (!strcmp(base, "/analysis") && depth == 0 && !strncmp(name, "snapshot_", 9)) continue;
            cd_export_walk(x, base, child, depth + 1);
            continue;
        }
        if (type != H5I_DATASET) continue;
        /* <name>/value (an H5MD time series) is shown as <name>; nested
         * names become a_b_c. */
        char label[96];
        snprintf(label, sizeof label, "%.95s", child);
        size_t n = strlen(label);
        if (n > 6 && !strcmp(label + n - 6, "/value")) label[n - 6] = 0;
        for (char *p = label; *p; p++)
            if (*p == '/') *p = '_';
        if (!strcmp(base, "/analysis")) {
            cd_export_classify(x, path, label, CD_EXPORT_ANALYSIS);
        } else if (!strcmp(base, "/particles/all")) {
            /* Time-dependent columns are <name>/value; position is the
             * geometry, not an attribute. */
            if (strcmp(label, "position") && depth == 1 && !strcmp(name, "value"))
                cd_export_classify(x, path, label, CD_EXPORT_PART_TIME);
            else if (depth == 0)
                cd_export_classify(x, path, label, CD_EXPORT_PART_FIXED);
        } else if (depth == 0 && strcmp(name, "offset") && strcmp(name, "step") && strcmp(name, "time") &&
                   strcmp(name, "pair_active")) {
            /* /contacts without the clock, the offsets and the all-ones
             * active flag. */
            cd_export_classify(x, path, label, CD_EXPORT_CONTACT);
        }
    }
    H5Gclose(g);
}

static int cd_export_discover(cd_export_ctx *x)
{
    static const char *bases[] = {"/particles/all", "/contacts", "/analysis"};
    for (int i = 0; i < 3; i++)
        if (cd_export_exists(x->f, bases[i])) cd_export_walk(x, bases[i], "", 0);
    if (cd_export_describe(x->f, "/particles/prims/prim_radius", &x->prim_radius) || x->prim_radius.rank != 1 ||
        x->prim_radius.dims[0] != x->P ||
        cd_export_describe(x->f, "/particles/prims/prim_particle", &x->prim_particle) || x->prim_particle.rank != 1 ||
        x->prim_particle.dims[0] != x->P)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: /particles/prims/prim_radius and prim_particle must be (%llu) datasets",
                              x->path, (unsigned long long)x->P);
    x->prim_radius.ncomp = x->prim_particle.ncomp = 1;
    return 0;
}

/* ---- helper datasets ---------------------------------------------------- */

/* Copies the string attribute `unit` (docs/output.md: every numeric dataset
 * carries one) from the source dataset, so the helpers follow the convention. */
static void cd_export_copy_unit(cd_export_ctx *x, const char *src, hid_t dst)
{
    hid_t d = H5Dopen2(x->f, src, H5P_DEFAULT);
    if (d < 0) return;
    if (H5Aexists(d, "unit") > 0 && H5Aexists(dst, "unit") <= 0) {
        hid_t a = H5Aopen(d, "unit", H5P_DEFAULT), t = H5Aget_type(a);
        size_t n = H5Tget_size(t);
        char *buf = calloc(n + 1, 1);
        if (buf && H5Tget_class(t) == H5T_STRING && !H5Tis_variable_str(t) && H5Aread(a, t, buf) >= 0) {
            hid_t s = H5Screate(H5S_SCALAR), b = H5Acreate2(dst, "unit", t, s, H5P_DEFAULT, H5P_DEFAULT);
            if (b >= 0) { H5Awrite(b, t, buf); H5Aclose(b); }
            H5Sclose(s);
        }
        free(buf);
        H5Tclose(t);
        H5Aclose(a);
    }
    H5Dclose(d);
}

static void cd_export_set_unit_one(hid_t d)
{
    if (H5Aexists(d, "unit") > 0) return;
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, 2);
    H5Tset_strpad(t, H5T_STR_NULLTERM);
    hid_t s = H5Screate(H5S_SCALAR), a = H5Acreate2(d, "unit", t, s, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) { H5Awrite(a, t, "1"); H5Aclose(a); }
    H5Sclose(s);
    H5Tclose(t);
}

/* Opens parent/name when it is a dataset of the given layout and shape;
 * otherwise removes whatever is there and returns 0 (the caller creates it). */
static hid_t cd_export_reuse(hid_t parent, const char *name, H5D_layout_t layout, int rank, const hsize_t *dims)
{
    if (H5Lexists(parent, name, H5P_DEFAULT) <= 0) return 0;
    hid_t d = H5Dopen2(parent, name, H5P_DEFAULT);
    int same = 0;
    if (d >= 0) {
        hid_t sp = H5Dget_space(d), pl = H5Dget_create_plist(d);
        hsize_t have[3];
        if (H5Sget_simple_extent_ndims(sp) == rank && H5Pget_layout(pl) == layout) {
            H5Sget_simple_extent_dims(sp, have, NULL);
            same = 1;
            for (int i = 0; i < rank; i++) same &= have[i] == dims[i];
        }
        H5Pclose(pl);
        H5Sclose(sp);
        if (same) return d;
        H5Dclose(d);
    }
    H5Ldelete(parent, name, H5P_DEFAULT);
    return 0;
}

/* One block of a virtual dataset: the source's hyperslab (start, count) goes
 * to the virtual hyperslab (vstart, vcount); both hold the same number of
 * elements. */
typedef struct {
    const cd_export_field *src;
    hsize_t start[3], count[3];
    hsize_t vstart[3], vcount[3];
} cd_export_block;

static int cd_export_vds(cd_export_ctx *x, hid_t parent, const char *name, int rank, const hsize_t *dims,
                         int nblock, const cd_export_block *blocks)
{
    hid_t d = cd_export_reuse(parent, name, H5D_VIRTUAL, rank, dims);
    if (d > 0) { H5Dclose(d); return 0; }
    hid_t src = H5Dopen2(x->f, blocks[0].src->src, H5P_DEFAULT);
    if (src < 0) return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: cannot open %s", x->path, blocks[0].src->src);
    hid_t ftype = H5Dget_type(src);
    H5Dclose(src);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    hid_t vspace = H5Screate_simple(rank, dims, NULL);
    int ok = 1;
    for (int b = 0; b < nblock && ok; b++) {
        const cd_export_block *k = &blocks[b];
        hid_t sspace = H5Screate_simple(k->src->rank, k->src->dims, NULL);
        ok = H5Sselect_hyperslab(sspace, H5S_SELECT_SET, k->start, NULL, k->count, NULL) >= 0 &&
             H5Sselect_hyperslab(vspace, H5S_SELECT_SET, k->vstart, NULL, k->vcount, NULL) >= 0 &&
             H5Pset_virtual(dcpl, vspace, x->vds_src, k->src->src, sspace) >= 0;
        H5Sclose(sspace);
    }
    H5Sselect_all(vspace);
    if (ok) d = H5Dcreate2(parent, name, ftype, vspace, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    H5Sclose(vspace);
    H5Pclose(dcpl);
    H5Tclose(ftype);
    if (!ok || d < 0) {
        char why[256];
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot create the virtual dataset %s over %s (HDF5: %s)",
                              x->path, name, blocks[0].src->src, cd_export_h5_reason(why));
    }
    cd_export_copy_unit(x, blocks[0].src->src, d);
    H5Dclose(d);
    return 0;
}

/* Writes a real int32 helper dataset (created, or overwritten in place when
 * one of the same shape is there: a resume may have changed its values). */
static int cd_export_ints(cd_export_ctx *x, hid_t parent, const char *name, int rank, const hsize_t *dims, const int *v)
{
    hid_t d = cd_export_reuse(parent, name, H5D_CONTIGUOUS, rank, dims);
    if (d == 0) {
        hid_t sp = H5Screate_simple(rank, dims, NULL);
        d = H5Dcreate2(parent, name, H5T_STD_I32LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        H5Sclose(sp);
    }
    hsize_t n = 1;
    for (int i = 0; i < rank; i++) n *= dims[i];
    if (d < 0 || (n > 0 && H5Dwrite(d, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0)) {
        char why[256];
        if (d >= 0) H5Dclose(d);
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot write /visualization/.../%s (HDF5: %s)", x->path, name, cd_export_h5_reason(why));
    }
    cd_export_set_unit_one(d);
    H5Dclose(d);
    return 0;
}

static int cd_export_read_attr_ll(hid_t loc, const char *name, long long *v, int n)
{
    if (H5Aexists(loc, name) <= 0) return -1;
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT), sp = H5Aget_space(a);
    int ok = H5Sget_simple_extent_npoints(sp) == n && H5Aread(a, H5T_NATIVE_LLONG, v) >= 0;
    H5Sclose(sp);
    H5Aclose(a);
    return ok ? 0 : -1;
}

static void cd_export_write_attr(hid_t loc, const char *name, hid_t ftype, hid_t mtype, int n, const void *v)
{
    if (H5Aexists(loc, name) > 0) H5Adelete(loc, name);
    hsize_t dim = (hsize_t)n;
    hid_t sp = n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &dim, NULL);
    hid_t a = H5Acreate2(loc, name, ftype, sp, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) { H5Awrite(a, mtype, v); H5Aclose(a); }
    H5Sclose(sp);
}

/* Opens /visualization, or makes a fresh one when the stored one was made for
 * another layout version or another particle / primitive count. */
static int cd_export_open_viz(cd_export_ctx *x)
{
    long long want[3] = {CD_EXPORT_LAYOUT, (long long)x->N, (long long)x->P}, have[3];
    if (H5Lexists(x->vf, "visualization", H5P_DEFAULT) > 0) {
        hid_t g = H5Gopen2(x->vf, "visualization", H5P_DEFAULT);
        int same = g >= 0 && !cd_export_read_attr_ll(g, "layout", &have[0], 1) &&
                   !cd_export_read_attr_ll(g, "n_particles", &have[1], 1) &&
                   !cd_export_read_attr_ll(g, "n_prims", &have[2], 1) && !memcmp(want, have, sizeof want);
        if (same) { x->viz = g; return 0; }
        if (g >= 0) H5Gclose(g);
        H5Ldelete(x->vf, "visualization", H5P_DEFAULT);
    }
    x->viz = H5Gcreate2(x->vf, "visualization", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (x->viz < 0) {
        char why[256];
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot create /visualization (HDF5: %s)", x->path, cd_export_h5_reason(why));
    }
    cd_export_write_attr(x->viz, "layout", H5T_STD_I64LE, H5T_NATIVE_LLONG, 1, &want[0]);
    cd_export_write_attr(x->viz, "n_particles", H5T_STD_I64LE, H5T_NATIVE_LLONG, 1, &want[1]);
    cd_export_write_attr(x->viz, "n_prims", H5T_STD_I64LE, H5T_NATIVE_LLONG, 1, &want[2]);
    const char *about = "helper datasets of `capdem export` (docs/visualization.md): connectivity, and virtual datasets "
                        "selecting one snapshot of the run's datasets; safe to delete";
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, strlen(about) + 1);
    cd_export_write_attr(x->viz, "about", t, t, 1, about);
    H5Tclose(t);
    return 0;
}

/* The helpers shared by every snapshot. */
static int cd_export_fixed_helpers(cd_export_ctx *x)
{
    hsize_t n = x->N > 2 * x->P ? x->N : 2 * x->P;
    int *v = malloc(sizeof(int) * (size_t)(n > 0 ? n : 1));
    if (!v) return cd_export_fail(x, CD_EXPORT_FAIL, "out of memory");
    for (hsize_t i = 0; i < x->N; i++) v[i] = (int)i;
    int rc = cd_export_ints(x, x->viz, "particle_id", 1, &x->N, v);
    for (hsize_t i = 0; i < x->P; i++) {
        v[2 * i] = (int)i;
        v[2 * i + 1] = (int)(i + x->P);
    }
    hsize_t cdims[2] = {x->P, 2};
    if (!rc) rc = cd_export_ints(x, x->viz, "arm_cells", 2, cdims, v);
    free(v);
    hsize_t two_p = 2 * x->P;
    const cd_export_field *per_arm[2] = {&x->prim_radius, &x->prim_particle};
    const char *names[2] = {"arm_point_radius", "arm_point_particle"};
    for (int i = 0; i < 2 && !rc; i++) {
        cd_export_block b[2] = {{per_arm[i], {0}, {x->P}, {0}, {x->P}}, {per_arm[i], {0}, {x->P}, {x->P}, {x->P}}};
        rc = cd_export_vds(x, x->viz, names[i], 1, &two_p, 2, b);
    }
    return rc;
}

/* contact_cells of rows c0..c1-1: particle_i, particle_j; a -1 (primitive out
 * of range, docs/output.md) becomes the other end, a zero-length line. */
static int cd_export_contact_cells(cd_export_ctx *x, hid_t g, long long c0, long long c1)
{
    hsize_t C = (hsize_t)(c1 - c0);
    if (C == 0) {
        if (H5Lexists(g, "contact_cells", H5P_DEFAULT) > 0) H5Ldelete(g, "contact_cells", H5P_DEFAULT);
        return 0;
    }
    int *ij = malloc(sizeof(int) * 2 * C), *col = malloc(sizeof(int) * C);
    if (!ij || !col) { free(ij); free(col); return cd_export_fail(x, CD_EXPORT_FAIL, "out of memory"); }
    const char *names[2] = {"/contacts/particle_i", "/contacts/particle_j"};
    int rc = 0;
    for (int e = 0; e < 2 && !rc; e++) {
        hid_t d = H5Dopen2(x->f, names[e], H5P_DEFAULT);
        if (d < 0) { rc = cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: missing %s", x->path, names[e]); break; }
        hid_t fs = H5Dget_space(d), ms = H5Screate_simple(1, &C, NULL);
        hsize_t start = (hsize_t)c0;
        if (H5Sselect_hyperslab(fs, H5S_SELECT_SET, &start, NULL, &C, NULL) < 0 ||
            H5Dread(d, H5T_NATIVE_INT, ms, fs, H5P_DEFAULT, col) < 0)
            rc = cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: cannot read rows %lld..%lld of %s", x->path, c0, c1 - 1, names[e]);
        H5Sclose(ms);
        H5Sclose(fs);
        H5Dclose(d);
        for (hsize_t r = 0; r < C && !rc; r++) ij[2 * r + (hsize_t)e] = col[r];
    }
    for (hsize_t r = 0; r < C && !rc; r++) {
        int *a = &ij[2 * r], *b = a + 1;
        if (*a < 0 || *b < 0 || (hsize_t)*a >= x->N || (hsize_t)*b >= x->N) {
            x->bad_contacts++;
            int good = (*a >= 0 && (hsize_t)*a < x->N) ? *a : (*b >= 0 && (hsize_t)*b < x->N) ? *b : 0;
            *a = *b = good;
        }
    }
    hsize_t dims[2] = {C, 2};
    if (!rc) rc = cd_export_ints(x, g, "contact_cells", 2, dims, ij);
    free(ij);
    free(col);
    return rc;
}

static int cd_export_snapshot_helpers(cd_export_ctx *x, int k)
{
    hid_t snaps = H5Gopen2(x->viz, "snapshots", H5P_DEFAULT);
    char name[32];
    snprintf(name, sizeof name, "%d", k);
    long long c0 = x->off[k], c1 = x->off[k + 1], rows[2] = {c0, c1}, have[2];
    hid_t g = -1;
    if (H5Lexists(snaps, name, H5P_DEFAULT) > 0) {
        g = H5Gopen2(snaps, name, H5P_DEFAULT);
        /* Contact rows that moved (a resume rewrote this snapshot) make the
         * contact VDS point at the wrong rows: rebuild the whole group. */
        if (g >= 0 && (cd_export_read_attr_ll(g, "contact_rows", have, 2) || have[0] != c0 || have[1] != c1)) {
            H5Gclose(g);
            H5Ldelete(snaps, name, H5P_DEFAULT);
            g = -1;
        }
    }
    if (g < 0) g = H5Gcreate2(snaps, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Gclose(snaps);
    if (g < 0) {
        char why[256];
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot create /visualization/snapshots/%s (HDF5: %s)", x->path, name, cd_export_h5_reason(why));
    }
    cd_export_write_attr(g, "contact_rows", H5T_STD_I64LE, H5T_NATIVE_LLONG, 2, rows);
    cd_export_write_attr(g, "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, 1, &x->step[k]);
    cd_export_write_attr(g, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, &x->time[k]);

    hsize_t P = x->P, N = x->N, C = (hsize_t)(c1 - c0), uk = (hsize_t)k;
    hsize_t arm_dims[2] = {2 * P, 3};
    cd_export_block arms[2] = {{&x->prim_a, {uk, 0, 0}, {1, P, 3}, {0, 0}, {P, 3}},
                               {&x->prim_b, {uk, 0, 0}, {1, P, 3}, {P, 0}, {P, 3}}};
    int rc = cd_export_vds(x, g, "arm_points", 2, arm_dims, 2, arms);
    for (int i = -1; i < x->npt && !rc; i++) {
        const cd_export_field *fl = i < 0 ? &x->position : &x->pt[i];
        hsize_t c = (hsize_t)fl->ncomp;
        if (fl->rank == 2) {
            cd_export_block b = {fl, {uk, 0}, {1, N}, {0}, {N}};
            rc = cd_export_vds(x, g, fl->name, 1, &N, 1, &b);
        } else {
            hsize_t vd[2] = {N, c};
            cd_export_block b = {fl, {uk, 0, 0}, {1, N, c}, {0, 0}, {N, c}};
            rc = cd_export_vds(x, g, fl->name, 2, vd, 1, &b);
        }
    }
    if (!rc) rc = cd_export_contact_cells(x, g, c0, c1);
    for (int i = 0; i < x->ncf && !rc && C > 0; i++) {
        const cd_export_field *fl = &x->cf[i];
        hsize_t c = (hsize_t)fl->ncomp, uc0 = (hsize_t)c0;
        if (fl->rank == 1) {
            cd_export_block b = {fl, {uc0}, {C}, {0}, {C}};
            rc = cd_export_vds(x, g, fl->name, 1, &C, 1, &b);
        } else {
            hsize_t vd[2] = {C, c};
            cd_export_block b = {fl, {uc0, 0}, {C, c}, {0, 0}, {C, c}};
            rc = cd_export_vds(x, g, fl->name, 2, vd, 1, &b);
        }
    }
    H5Gclose(g);
    return rc;
}

static int cd_export_helpers(cd_export_ctx *x)
{
    if (cd_export_open_viz(x) || cd_export_fixed_helpers(x)) return -1;
    if (H5Lexists(x->viz, "snapshots", H5P_DEFAULT) <= 0) {
        hid_t g = H5Gcreate2(x->viz, "snapshots", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        if (g < 0) return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot create /visualization/snapshots", x->path);
        H5Gclose(g);
    }
    /* Snapshots a resume cut away (and anything else that is not a snapshot
     * of this run): collect the names first, deleting while walking by index
     * would skip links. */
    hid_t snaps = H5Gopen2(x->viz, "snapshots", H5P_DEFAULT);
    H5G_info_t gi;
    if (snaps >= 0 && H5Gget_info(snaps, &gi) >= 0 && gi.nlinks > 0) {
        char (*stale)[64] = calloc(gi.nlinks, sizeof *stale);
        hsize_t nstale = 0;
        for (hsize_t i = 0; stale && i < gi.nlinks; i++) {
            char name[64], *end;
            if (H5Lget_name_by_idx(snaps, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT) < 0) continue;
            long k = strtol(name, &end, 10);
            if (end == name || *end || k < 0 || k >= x->S) snprintf(stale[nstale++], 64, "%s", name);
        }
        for (hsize_t i = 0; i < nstale; i++) H5Ldelete(snaps, stale[i], H5P_DEFAULT);
        free(stale);
    }
    if (snaps >= 0) H5Gclose(snaps);
    for (int k = 0; k < x->S; k++)
        if (cd_export_snapshot_helpers(x, k)) return -1;
    return 0;
}

/* ---- the XDMF file ------------------------------------------------------- */

static void cd_export_xml_text(FILE *o, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&': fputs("&amp;", o); break;
        case '<': fputs("&lt;", o); break;
        case '>': fputs("&gt;", o); break;
        case '"': fputs("&quot;", o); break;
        case '\'': fputs("&apos;", o); break;
        default: fputc(*s, o);
        }
    }
}

/* <DataItem> naming file:path, of the given shape (rank 1 or 2). */
static void cd_export_xml_item(FILE *o, const char *indent, const char *file, const char *path,
                               hsize_t rows, int ncomp, const char *number_type, int precision)
{
    fprintf(o, "%s<DataItem Dimensions=\"%llu", indent, (unsigned long long)rows);
    if (ncomp > 1) fprintf(o, " %d", ncomp);
    fprintf(o, "\" NumberType=\"%s\" Precision=\"%d\" Format=\"HDF\">", number_type, precision);
    cd_export_xml_text(o, file);
    fputc(':', o);
    cd_export_xml_text(o, path);
    fputs("</DataItem>\n", o);
}

static const char *cd_export_attr_type(int ncomp)
{
    return ncomp == 1 ? "Scalar" : ncomp == 3 ? "Vector" : ncomp == 6 ? "Tensor6" : ncomp == 9 ? "Tensor" : "Matrix";
}

static void cd_export_xml_attr(FILE *o, const char *name, const char *center, const char *file, const char *path,
                               hsize_t rows, const cd_export_field *fl)
{
    fputs("      <Attribute Name=\"", o);
    cd_export_xml_text(o, name);
    fprintf(o, "\" AttributeType=\"%s\" Center=\"%s\">\n", cd_export_attr_type(fl->ncomp), center);
    cd_export_xml_item(o, "        ", file, path, rows, fl->ncomp, fl->number_type, fl->precision);
    fputs("      </Attribute>\n", o);
}

static void cd_export_xml_time(FILE *o, const cd_export_ctx *x, int k)
{
    fprintf(o, "      <Time Value=\"%.17g\"/>\n", x->time[k]);
}

static void cd_export_xml_arms(FILE *o, const cd_export_ctx *x, int k)
{
    char path[128];
    fprintf(o, "    <Grid Name=\"arms\" GridType=\"Uniform\">\n");
    cd_export_xml_time(o, x, k);
    fprintf(o, "      <Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" NumberOfElements=\"%llu\">\n", (unsigned long long)x->P);
    cd_export_xml_item(o, "        ", x->viz_ref, "/visualization/arm_cells", x->P, 2, "Int", 4);
    fprintf(o, "      </Topology>\n      <Geometry GeometryType=\"XYZ\">\n");
    snprintf(path, sizeof path, "/visualization/snapshots/%d/arm_points", k);
    cd_export_xml_item(o, "        ", x->viz_ref, path, 2 * x->P, 3, "Float", 8);
    fprintf(o, "      </Geometry>\n");
    /* Point copies first: the Tube filter takes its radius from point data. */
    cd_export_xml_attr(o, "radius", "Node", x->viz_ref, "/visualization/arm_point_radius", 2 * x->P, &x->prim_radius);
    cd_export_xml_attr(o, "particle", "Node", x->viz_ref, "/visualization/arm_point_particle", 2 * x->P, &x->prim_particle);
    cd_export_xml_attr(o, "radius", "Cell", x->h5_ref, x->prim_radius.src, x->P, &x->prim_radius);
    cd_export_xml_attr(o, "particle", "Cell", x->h5_ref, x->prim_particle.src, x->P, &x->prim_particle);
    fprintf(o, "    </Grid>\n");
}

static void cd_export_xml_particles(FILE *o, const cd_export_ctx *x, int k)
{
    char path[200];
    fprintf(o, "    <Grid Name=\"particles\" GridType=\"Uniform\">\n");
    cd_export_xml_time(o, x, k);
    /* Explicit vertex connectivity: the Xdmf3 readers make no cells for a
     * Polyvertex topology without it. */
    fprintf(o, "      <Topology TopologyType=\"Polyvertex\" NodesPerElement=\"1\" NumberOfElements=\"%llu\">\n", (unsigned long long)x->N);
    cd_export_xml_item(o, "        ", x->viz_ref, "/visualization/particle_id", x->N, 1, "Int", 4);
    fprintf(o, "      </Topology>\n      <Geometry GeometryType=\"XYZ\">\n");
    snprintf(path, sizeof path, "/visualization/snapshots/%d/position", k);
    cd_export_xml_item(o, "        ", x->viz_ref, path, x->N, 3, "Float", 8);
    fprintf(o, "      </Geometry>\n");
    cd_export_field id = {.ncomp = 1, .number_type = "Int", .precision = 4};
    cd_export_xml_attr(o, "particle", "Node", x->viz_ref, "/visualization/particle_id", x->N, &id);
    for (int i = 0; i < x->npt; i++) {
        snprintf(path, sizeof path, "/visualization/snapshots/%d/%s", k, x->pt[i].name);
        cd_export_xml_attr(o, x->pt[i].name, "Node", x->viz_ref, path, x->N, &x->pt[i]);
    }
    for (int i = 0; i < x->npf; i++)
        cd_export_xml_attr(o, x->pf[i].name, "Node", x->h5_ref, x->pf[i].src, x->N, &x->pf[i]);
    fprintf(o, "    </Grid>\n");
}

static void cd_export_xml_contacts(FILE *o, const cd_export_ctx *x, int k)
{
    char path[200];
    hsize_t C = (hsize_t)(x->off[k + 1] - x->off[k]);
    fprintf(o, "    <Grid Name=\"contacts\" GridType=\"Uniform\">\n");
    cd_export_xml_time(o, x, k);
    if (C == 0) {
        /* No data item at all: a zero-size one is an error to the XDMF2
         * reader, an empty topology is not. */
        fprintf(o, "      <Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" NumberOfElements=\"0\"/>\n");
    } else {
        fprintf(o, "      <Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" NumberOfElements=\"%llu\">\n", (unsigned long long)C);
        snprintf(path, sizeof path, "/visualization/snapshots/%d/contact_cells", k);
        cd_export_xml_item(o, "        ", x->viz_ref, path, C, 2, "Int", 4);
        fprintf(o, "      </Topology>\n");
    }
    fprintf(o, "      <Geometry GeometryType=\"XYZ\">\n");
    snprintf(path, sizeof path, "/visualization/snapshots/%d/position", k);
    cd_export_xml_item(o, "        ", x->viz_ref, path, x->N, 3, "Float", 8);
    fprintf(o, "      </Geometry>\n");
    for (int i = 0; i < x->ncf && C > 0; i++) {
        snprintf(path, sizeof path, "/visualization/snapshots/%d/%s", k, x->cf[i].name);
        cd_export_xml_attr(o, x->cf[i].name, "Cell", x->viz_ref, path, C, &x->cf[i]);
    }
    fprintf(o, "    </Grid>\n");
}

static int cd_export_write_xml(cd_export_ctx *x, const char *out)
{
    char tmp[CD_EXPORT_PATH + 32];
    snprintf(tmp, sizeof tmp, "%s.tmp%ld", out, (long)getpid());
    FILE *o = fopen(tmp, "w");
    if (!o) return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot write (%s)", out, strerror(errno));
    fprintf(o, "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    fprintf(o, "<!-- Written by `capdem export` from ");
    /* "--" is not allowed inside an XML comment. */
    for (const char *s = x->h5_ref; *s; s++) fputc(s[0] == '-' && s[1] == '-' ? '_' : s[0], o);
    fprintf(o, ": %d snapshots, %llu particles, %llu arms, %lld contact rows.\n"
               "     Three temporal collections: arms (lines; radius as point and cell data, for the Tube filter),\n"
               "     particles (centres) and contacts (lines between the centres of touching particles).\n"
               "     Every data item points into the run file or into its /visualization helpers: no copy of the data.\n"
               "     ParaView: any of its XDMF readers; docs/visualization.md. -->\n",
            x->S, (unsigned long long)x->N, (unsigned long long)x->P, x->off[x->S]);
    fprintf(o, "<Xdmf Version=\"2.0\">\n  <Domain>\n");
    void (*grids[3])(FILE *, const cd_export_ctx *, int) = {cd_export_xml_arms, cd_export_xml_particles, cd_export_xml_contacts};
    const char *names[3] = {"arms", "particles", "contacts"};
    for (int g = 0; g < 3; g++) {
        fprintf(o, "  <Grid Name=\"%s\" GridType=\"Collection\" CollectionType=\"Temporal\">\n", names[g]);
        for (int k = 0; k < x->S; k++) grids[g](o, x, k);
        fprintf(o, "  </Grid>\n");
    }
    fprintf(o, "  </Domain>\n</Xdmf>\n");
    int bad = ferror(o);
    bad |= fclose(o) != 0;
    if (bad || rename(tmp, out) != 0) {
        int e = errno;
        remove(tmp);
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot write (%s)", out, strerror(e));
    }
    return 0;
}

/* ---- command ------------------------------------------------------------ */

static const char *cd_export_base(const char *p)
{
    const char *s = strrchr(p, '/');
    return s ? s + 1 : p;
}

/* path with its .h5 / .hdf5 suffix replaced by suffix. */
static void cd_export_swap_suffix(char *dst, size_t n, const char *path, const char *suffix)
{
    size_t len = strlen(path);
    if (len > 3 && !strcmp(path + len - 3, ".h5")) len -= 3;
    else if (len > 5 && !strcmp(path + len - 5, ".hdf5")) len -= 5;
    snprintf(dst, n, "%.*s%s", (int)len, path, suffix);
}

static int cd_export_same_dir(const char *a, const char *b)
{
    char da[CD_EXPORT_PATH], db[CD_EXPORT_PATH], ra[PATH_MAX], rb[PATH_MAX];
    snprintf(da, sizeof da, "%.*s", (int)(cd_export_base(a) - a), a);
    snprintf(db, sizeof db, "%.*s", (int)(cd_export_base(b) - b), b);
    if (!da[0]) strcpy(da, ".");
    if (!db[0]) strcpy(db, ".");
    return realpath(da, ra) && realpath(db, rb) && !strcmp(ra, rb);
}

/* How the .xmf at out names the file at path: its base name when both lie in
 * one folder (the readers resolve it against the .xmf's folder, so the pair
 * can be moved together), else its absolute path. */
static void cd_export_ref(char *dst, size_t n, const char *path, const char *out)
{
    char abs[PATH_MAX];
    if (cd_export_same_dir(path, out)) snprintf(dst, n, "%s", cd_export_base(path));
    else if (realpath(path, abs)) snprintf(dst, n, "%s", abs);
    else snprintf(dst, n, "%s", path);
}

static int cd_export_usage(FILE *f)
{
    fprintf(f, "usage: capdem export RUN.h5 [-o OUT.xmf]\n"
               "  writes OUT.xmf (default: RUN.xmf next to RUN.h5), an XDMF description of every\n"
               "  snapshot (arms, particle centres, contact network) for ParaView or VisIt; its data\n"
               "  items point into RUN.h5, through helper datasets written once under /visualization\n"
               "  (docs/visualization.md)\n");
    return f == stdout ? 0 : CD_EXPORT_BAD_INPUT;
}

/* Reads the counts, the clock and the contact offsets. */
static int cd_export_read_run(cd_export_ctx *x)
{
    cd_export_field *pos = &x->position, *pa = &x->prim_a, *pb = &x->prim_b;
    if (cd_export_describe(x->f, "/particles/all/position/value", pos) || pos->rank != 3 || pos->dims[2] != 3 ||
        cd_export_describe(x->f, "/particles/prims/prim_a/value", pa) || pa->rank != 3 || pa->dims[2] != 3 ||
        cd_export_describe(x->f, "/particles/prims/prim_b/value", pb) || pb->rank != 3 || pb->dims[2] != 3 ||
        pa->dims[1] != pb->dims[1])
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT,
                              "%s: not a capdem run file (needs /particles/all/position/value (S, N, 3) and "
                              "/particles/prims/prim_a/value, prim_b/value (S, P, 3))", x->path);
    snprintf(pos->name, sizeof pos->name, "position");
    pos->ncomp = 3;
    x->N = pos->dims[1];
    x->P = pa->dims[1];
    /* A crash may leave a partly written row beyond the committed snapshots;
     * never describe rows the datasets do not have either. */
    hsize_t rows = pos->dims[0] < pa->dims[0] ? pos->dims[0] : pa->dims[0];
    if (pb->dims[0] < rows) rows = pb->dims[0];
    if ((hsize_t)x->S > rows) x->S = (int)rows;
    if (x->S == 0) return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: the run file holds no complete snapshot", x->path);
    x->off = malloc(sizeof(long long) * (size_t)(x->S + 1));
    x->step = malloc(sizeof(long long) * (size_t)x->S);
    x->time = malloc(sizeof(double) * (size_t)x->S);
    if (!x->off || !x->step || !x->time) return cd_export_fail(x, CD_EXPORT_FAIL, "out of memory");
    if (cd_export_read_all(x, "/contacts/offset", H5T_NATIVE_LLONG, (hsize_t)x->S + 1, x->off) ||
        cd_export_read_all(x, "/walls/step", H5T_NATIVE_LLONG, (hsize_t)x->S, x->step) ||
        cd_export_read_all(x, "/walls/time", H5T_NATIVE_DOUBLE, (hsize_t)x->S, x->time))
        return -1;
    for (int k = 0; k < x->S; k++)
        if (x->off[k + 1] < x->off[k] || x->off[k] < 0)
            return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: /contacts/offset decreases at snapshot %d", x->path, k);
    cd_export_field pi, pj;
    if (x->off[x->S] > 0 &&
        (cd_export_describe(x->f, "/contacts/particle_i", &pi) || cd_export_describe(x->f, "/contacts/particle_j", &pj) ||
         pi.dims[0] < (hsize_t)x->off[x->S] || pj.dims[0] < (hsize_t)x->off[x->S]))
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: /contacts/particle_i and particle_j must hold the %lld contact rows",
                              x->path, x->off[x->S]);
    return 0;
}

/* Opens the run file for writing the helpers, or falls back to a sidecar
 * file next to it when the run file is read-only. */
static int cd_export_open(cd_export_ctx *x, const char *out)
{
    char why[256];
    x->f = H5Fopen(x->path, H5F_ACC_RDWR, H5P_DEFAULT);
    if (x->f >= 0) {
        x->vf = x->f;
        snprintf(x->vds_src, sizeof x->vds_src, ".");
        cd_export_ref(x->h5_ref, sizeof x->h5_ref, x->path, out);
        snprintf(x->viz_ref, sizeof x->viz_ref, "%s", x->h5_ref);
        return 0;
    }
    cd_export_h5_reason(why);
    x->f = H5Fopen(x->path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (x->f < 0) {
        cd_export_h5_reason(why);
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot open (HDF5: %s; is a run still writing it?)", x->path, why);
    }
    char side[CD_EXPORT_PATH];
    cd_export_swap_suffix(side, sizeof side, x->path, ".viz.h5");
    x->vf = access(side, F_OK) == 0 ? H5Fopen(side, H5F_ACC_RDWR, H5P_DEFAULT) : -1;
    if (x->vf < 0) x->vf = H5Fcreate(side, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (x->vf < 0)
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot write into it (%s) nor create %s for the helper datasets",
                              x->path, why, side);
    fprintf(stderr, "capdem export: %s is read-only here (%s); helper datasets go to %s\n", x->path, why, side);
    /* The sidecar lies next to the run file, and HDF5 looks for a relative
     * VDS source in the folder of the file holding the VDS. */
    snprintf(x->vds_src, sizeof x->vds_src, "%s", cd_export_base(x->path));
    cd_export_ref(x->h5_ref, sizeof x->h5_ref, x->path, out);
    cd_export_ref(x->viz_ref, sizeof x->viz_ref, side, out);
    return 0;
}

int cd_cmd_export(int argc, char **argv)
{
    const char *run = NULL, *out_opt = NULL;
    for (int i = 0; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) return cd_export_usage(stdout);
        if ((!strcmp(argv[i], "-o") || !strcmp(argv[i], "--output")) && i + 1 < argc) out_opt = argv[++i];
        else if (argv[i][0] != '-' && !run) run = argv[i];
        else {
            fprintf(stderr, "capdem export: unknown or incomplete option '%s'\n", argv[i]);
            return cd_export_usage(stderr);
        }
    }
    if (!run) {
        fprintf(stderr, "capdem export: missing RUN.h5\n");
        return cd_export_usage(stderr);
    }
    if (access(run, R_OK) != 0) {
        fprintf(stderr, "capdem export: %s: %s\n", run, strerror(errno));
        return CD_EXPORT_BAD_INPUT;
    }
    char out[CD_EXPORT_PATH];
    if (out_opt) snprintf(out, sizeof out, "%s", out_opt);
    else cd_export_swap_suffix(out, sizeof out, run, ".xmf");

    cd_export_ctx *x = calloc(1, sizeof *x);
    if (!x) { fprintf(stderr, "capdem export: out of memory\n"); return CD_EXPORT_FAIL; }
    x->path = run;
    x->f = x->vf = x->viz = -1;

    H5E_auto2_t old_func;
    void *old_data;
    H5Eget_auto2(H5E_DEFAULT, &old_func, &old_data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);

    char err[512];
    htri_t is_h5 = H5Fis_hdf5(run);
    if (is_h5 <= 0) {
        cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: not an HDF5 file", run);
    } else if ((x->S = cd_h5_snapshot_count(run, err, sizeof err)) < 0) {
        /* HDF5 locks a file that a process has open for writing. */
        int locked = strstr(err, "lock") != NULL;
        cd_export_fail(x, locked ? CD_EXPORT_FAIL : CD_EXPORT_BAD_INPUT, "%s%s", err,
                       locked ? " (is a run still writing it? export it when the run has ended)" : "");
    } else if (!cd_export_open(x, out) && !cd_export_read_run(x) && !cd_export_discover(x) && !cd_export_helpers(x)) {
        if (x->viz >= 0) { H5Gclose(x->viz); x->viz = -1; }
        if (H5Fflush(x->vf, H5F_SCOPE_GLOBAL) < 0) {
            char why[256];
            cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot flush the helper datasets (HDF5: %s)", run, cd_export_h5_reason(why));
        } else {
            cd_export_write_xml(x, out);
        }
    }
    if (x->viz >= 0) H5Gclose(x->viz);
    if (x->vf >= 0 && x->vf != x->f) H5Fclose(x->vf);
    if (x->f >= 0) H5Fclose(x->f);
    H5Eset_auto2(H5E_DEFAULT, old_func, old_data);

    int status = x->status;
    if (status) {
        fprintf(stderr, "capdem export: %s\n", x->err);
    } else {
        if (x->bad_contacts)
            fprintf(stderr, "capdem export: warning: %lld contact rows name particle -1 (primitive out of range); "
                            "drawn as zero-length lines\n", x->bad_contacts);
        printf("capdem export: wrote %s (%d snapshots, %llu particles, %llu arms, %lld contact rows; "
               "helper datasets in %s:/visualization)\n",
               out, x->S, (unsigned long long)x->N, (unsigned long long)x->P, x->off[x->S], x->viz_ref);
    }
    free(x->off);
    free(x->step);
    free(x->time);
    free(x);
    return status;
}
