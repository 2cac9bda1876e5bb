/* capdem export, reading the run file: the shapes of its datasets, the
 * counts, the clock and the contact offsets, and which columns the .xmf
 * shows (export_internal.h; the design is described in export_xdmf.c). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <hdf5.h>
#include "export/export_internal.h"
#include "io/io_h5_layout.h"

/* Shape and XDMF number type of a dataset; -1 when it is missing or not a
 * plain integer or floating-point array of rank 1..3. */
int cd_export_describe(hid_t f, const char *path, cd_export_field *fl)
{
    memset(fl, 0, sizeof *fl);
    snprintf(fl->src, sizeof fl->src, "%s", path);
    if (!cdh5_exists(f, path)) return -1;
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
    } else if (cls == H5T_INTEGER &&
               (fl->precision == 1 || fl->precision == 2 || fl->precision == 4 || fl->precision == 8)) {
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
    if (d < 0)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: missing dataset %s (is this a capdem run file?)", x->path,
                              path);
    hsize_t dims[3];
    int rc = cdh5_dims(d, dims) == 1 && dims[0] >= n ? cdh5_read_rows(d, 0, n, memtype, buf) : -1;
    H5Dclose(d);
    if (rc < 0)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: cannot read %llu values of %s", x->path,
                              (unsigned long long)n, path);
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
        list = x->pt;
        n = &x->npt;
        cd_export_set_ncomp(&fl, 2);
    } else if ((where == CD_EXPORT_PART_FIXED || where == CD_EXPORT_ANALYSIS) && fixed) {
        list = x->pf;
        n = &x->npf;
        cd_export_set_ncomp(&fl, 1);
    } else if ((where == CD_EXPORT_CONTACT || where == CD_EXPORT_ANALYSIS) && contact) {
        list = x->cf;
        n = &x->ncf;
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
            const char *snap = CDH5_NAME(ANALYSIS_SNAPSHOT);
            if (!strcmp(base, CDH5_PATH(ANALYSIS)) && depth == 0 && !strncmp(name, snap, strlen(snap))) continue;
            cd_export_walk(x, base, child, depth + 1);
            continue;
        }
        if (type != H5I_DATASET) continue;
        /* <name>/value (an H5MD time series) is shown as <name>; nested
         * names become a_b_c. */
        char label[96];
        snprintf(label, sizeof label, "%.95s", child);
        size_t n = strlen(label), v = strlen(CDH5_NAME(VALUE));
        if (n > v + 1 && label[n - v - 1] == '/' && !strcmp(label + n - v, CDH5_NAME(VALUE))) label[n - v - 1] = 0;
        for (char *p = label; *p; p++)
            if (*p == '/') *p = '_';
        if (!strcmp(base, CDH5_PATH(ANALYSIS))) {
            cd_export_classify(x, path, label, CD_EXPORT_ANALYSIS);
        } else if (!strcmp(base, CDH5_PATH(PARTICLES))) {
            /* Time-dependent columns are <name>/value; position is the
             * geometry, not an attribute. */
            if (strcmp(label, "position") && depth == 1 && !strcmp(name, CDH5_NAME(VALUE)))
                cd_export_classify(x, path, label, CD_EXPORT_PART_TIME);
            else if (depth == 0) cd_export_classify(x, path, label, CD_EXPORT_PART_FIXED);
        } else if (depth == 0 && strcmp(path, CDH5_PATH(C_OFFSET)) && strcmp(name, CDH5_NAME(STEP)) &&
                   strcmp(name, CDH5_NAME(TIME)) && strcmp(name, "pair_active")) {
            /* /contacts without the clock, the offsets and the all-ones
             * active flag. */
            cd_export_classify(x, path, label, CD_EXPORT_CONTACT);
        }
    }
    H5Gclose(g);
}

int cd_export_discover(cd_export_ctx *x)
{
    const char *bases[] = {CDH5_PATH(PARTICLES), CDH5_PATH(CONTACTS), CDH5_PATH(ANALYSIS)};
    for (int i = 0; i < 3; i++)
        if (cdh5_exists(x->f, bases[i])) cd_export_walk(x, bases[i], "", 0);
    char radius[CDH5_PATH_LEN], owner[CDH5_PATH_LEN];
    if (cd_export_describe(x->f, cdh5_column_path("prim_radius", radius), &x->prim_radius) ||
        x->prim_radius.rank != 1 || x->prim_radius.dims[0] != x->P ||
        cd_export_describe(x->f, cdh5_column_path("prim_particle", owner), &x->prim_particle) ||
        x->prim_particle.rank != 1 || x->prim_particle.dims[0] != x->P)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: %s and %s must be (%llu) datasets", x->path, radius, owner,
                              (unsigned long long)x->P);
    x->prim_radius.ncomp = x->prim_particle.ncomp = 1;
    return 0;
}

/* ---- counts, clock and contact offsets ---------------------------------- */

/* Reads the counts, the clock and the contact offsets. */
int cd_export_read_run(cd_export_ctx *x)
{
    cd_export_field *pos = &x->position, *pa = &x->prim_a, *pb = &x->prim_b;
    char ppos[CDH5_PATH_LEN], pa_path[CDH5_PATH_LEN], pb_path[CDH5_PATH_LEN];
    /* (all three paths first: the message names them even when the first check fails) */
    cdh5_column_path("position", ppos);
    cdh5_column_path("prim_a", pa_path);
    cdh5_column_path("prim_b", pb_path);
    if (cd_export_describe(x->f, ppos, pos) || pos->rank != 3 || pos->dims[2] != 3 ||
        cd_export_describe(x->f, pa_path, pa) || pa->rank != 3 || pa->dims[2] != 3 ||
        cd_export_describe(x->f, pb_path, pb) || pb->rank != 3 || pb->dims[2] != 3 || pa->dims[1] != pb->dims[1])
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT,
                              "%s: not a capdem run file (needs %s (S, N, 3) and %s, %s (S, P, 3))", x->path, ppos,
                              pa_path, pb_path);
    snprintf(pos->name, sizeof pos->name, "position");
    pos->ncomp = 3;
    x->N = pos->dims[1];
    x->P = pa->dims[1];
    /* A crash may leave a partly written row beyond the committed snapshots;
     * never describe rows the datasets do not have either. */
    hsize_t rows = pos->dims[0] < pa->dims[0] ? pos->dims[0] : pa->dims[0];
    if (pb->dims[0] < rows) rows = pb->dims[0];
    if ((hsize_t)x->S > rows) x->S = (int)rows;
    if (x->S == 0)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: the run file holds no complete snapshot", x->path);
    x->off = malloc(sizeof(long long) * (size_t)(x->S + 1));
    x->step = malloc(sizeof(long long) * (size_t)x->S);
    x->time = malloc(sizeof(double) * (size_t)x->S);
    if (!x->off || !x->step || !x->time) return cd_export_fail(x, CD_EXPORT_FAIL, "out of memory");
    if (cd_export_read_all(x, CDH5_PATH(C_OFFSET), H5T_NATIVE_LLONG, (hsize_t)x->S + 1, x->off) ||
        cd_export_read_all(x, CDH5_PATH(SNAP_STEP), H5T_NATIVE_LLONG, (hsize_t)x->S, x->step) ||
        cd_export_read_all(x, CDH5_PATH(SNAP_TIME), H5T_NATIVE_DOUBLE, (hsize_t)x->S, x->time))
        return -1;
    for (int k = 0; k < x->S; k++)
        if (x->off[k + 1] < x->off[k] || x->off[k] < 0)
            return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: %s decreases at snapshot %d", x->path,
                                  CDH5_PATH(C_OFFSET), k);
    cd_export_field pi, pj;
    if (x->off[x->S] > 0 && (cd_export_describe(x->f, CDH5_PATH(C_PARTICLE_I), &pi) ||
                             cd_export_describe(x->f, CDH5_PATH(C_PARTICLE_J), &pj) || pi.rank != 1 || pj.rank != 1 ||
                             pi.dims[0] < (hsize_t)x->off[x->S] || pj.dims[0] < (hsize_t)x->off[x->S]))
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: %s and %s must hold the %lld contact rows", x->path,
                              CDH5_PATH(C_PARTICLE_I), CDH5_PATH(C_PARTICLE_J), x->off[x->S]);
    return 0;
}
