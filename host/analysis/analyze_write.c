/* Output of `capdem analyze`: the report into the run file and as JSON.
 *
 * HDF5: /analysis/snapshot_<step>/<group>/ per snapshot measure and
 * /analysis/<group>/ for the run-wide time-series measures (compaction,
 * jamming).  A scalar is an attribute <name> (double) with a string
 * attribute <name>_unit; a text is a string attribute; a table is a dataset
 * (rows, columns) of doubles with string attributes columns and unit
 * (comma separated, one per column).  Re-running replaces those groups.
 *
 * JSON: one object; see docs/analysis.md for the keys. */
#include "analysis/analyze.h"
#include <cjson/cJSON.h>
#include <hdf5.h>
#include "io/io_h5_journal.h"
#include "io/io_h5_layout.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Groups of the whole run rather than of one snapshot. */
static int run_wide(const char *name) { return !strcmp(name, "compaction") || !strcmp(name, "jamming"); }

static int attr_double(hid_t obj, const char *name, double v)
{
    hid_t sp = H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate2(obj, name, H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT);
    herr_t st = a < 0 ? -1 : H5Awrite(a, H5T_NATIVE_DOUBLE, &v);
    if (a >= 0) H5Aclose(a);
    H5Sclose(sp);
    return st < 0 ? -1 : 0;
}

static int attr_string(hid_t obj, const char *name, const char *v)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, strlen(v) + 1);
    H5Tset_strpad(t, H5T_STR_NULLTERM);
    hid_t sp = H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate2(obj, name, t, sp, H5P_DEFAULT, H5P_DEFAULT);
    herr_t st = a < 0 ? -1 : H5Awrite(a, t, v);
    if (a >= 0) H5Aclose(a);
    H5Sclose(sp);
    H5Tclose(t);
    return st < 0 ? -1 : 0;
}

static int write_group(hid_t parent, const cd_an_group *g)
{
    if (H5Lexists(parent, g->name, H5P_DEFAULT) > 0 && H5Ldelete(parent, g->name, H5P_DEFAULT) < 0) return -1;
    hid_t grp = H5Gcreate2(parent, g->name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (grp < 0) return -1;
    int rc = 0;
    for (int k = 0; k < g->n_scalars && !rc; k++) {
        char un[64];
        snprintf(un, sizeof un, "%s_unit", g->scalars[k].name);
        rc = attr_double(grp, g->scalars[k].name, g->scalars[k].value) || attr_string(grp, un, g->scalars[k].unit);
    }
    for (int k = 0; k < g->n_texts && !rc; k++) rc = attr_string(grp, g->texts[k].name, g->texts[k].text);
    for (int k = 0; k < g->n_curves && !rc; k++) {
        const cd_an_curve *c = &g->curves[k];
        hsize_t dims[2] = {c->rows, (hsize_t)c->cols};
        hid_t sp = H5Screate_simple(2, dims, NULL);
        hid_t d = H5Dcreate2(grp, c->name, H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        rc = d < 0 || (c->rows && H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, c->data) < 0) ||
             attr_string(d, "columns", c->columns) || attr_string(d, CDH5_NAME(UNIT), c->units);
        if (d >= 0) H5Dclose(d);
        H5Sclose(sp);
    }
    H5Gclose(grp);
    return rc ? -1 : 0;
}

/* Opens path/name as a group, creating it when missing. */
static hid_t open_or_create(hid_t loc, const char *name)
{
    if (H5Lexists(loc, name, H5P_DEFAULT) > 0) return H5Gopen2(loc, name, H5P_DEFAULT);
    return H5Gcreate2(loc, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
}

int cd_an_write_h5(const char *path, const cd_an_report *rep, char *err, size_t errlen)
{
    H5E_auto2_t func;
    void *data;
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    int rc = -1;
    hid_t fapl = cdh5_fapl(); /* as io_h5 opens run files */
    hid_t f = H5Fopen(path, H5F_ACC_RDWR, fapl), top = -1, snap = -1;
    H5Pclose(fapl);
    if (f < 0) {
        snprintf(err, errlen,
                 "%s: cannot open the run file for writing the analysis (is a run still writing it, or "
                 "is it read-only? --no-write skips this)",
                 path);
        goto done;
    }
    top = open_or_create(f, CDH5_PATH(ANALYSIS));
    if (top < 0) goto fail;
    char sname[64];
    snprintf(sname, sizeof sname, "%s%lld", CDH5_NAME(ANALYSIS_SNAPSHOT), rep->step);
    int any_snapshot = 0;
    for (int k = 0; k < rep->n_groups; k++) any_snapshot |= !run_wide(rep->groups[k].name);
    if (any_snapshot) {
        /* replace the whole snapshot group: no stale measure survives */
        if (H5Lexists(top, sname, H5P_DEFAULT) > 0 && H5Ldelete(top, sname, H5P_DEFAULT) < 0) goto fail;
        snap = H5Gcreate2(top, sname, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        if (snap < 0 || attr_double(snap, "step", (double)rep->step) || attr_double(snap, "time", rep->time) ||
            attr_string(snap, "time_unit", "s") || attr_double(snap, "snapshot", rep->snapshot) ||
            attr_string(snap, "creator", "capdem analyze " CAPDEM_VERSION))
            goto fail;
    }
    for (int k = 0; k < rep->n_groups; k++)
        if (write_group(run_wide(rep->groups[k].name) ? top : snap, &rep->groups[k])) goto fail;
    /* the analysis goes in whole or not at all (an atomic commit) */
    if (snap >= 0) H5Gclose(snap);
    snap = -1;
    if (cdh5_commit(f, path, err, errlen) < 0) goto fail;
    rc = 0;
    goto done;
fail:
    snprintf(err, errlen, "%s: cannot write the %s group", path, CDH5_PATH(ANALYSIS));
    cdh5_drop_on_close(f);
done:
    if (snap >= 0) H5Gclose(snap);
    if (top >= 0) H5Gclose(top);
    if (f >= 0 && H5Fclose(f) < 0 && rc == 0) {
        snprintf(err, errlen, "%s: closing the file after writing %s failed", path, CDH5_PATH(ANALYSIS));
        rc = -1;
    }
    H5Eset_auto2(H5E_DEFAULT, func, data);
    return rc;
}

/* JSON numbers cannot be NaN or infinite: those become null. */
static cJSON *num(double v) { return isfinite(v) ? cJSON_CreateNumber(v) : cJSON_CreateNull(); }

/* Comma-separated list as a JSON array of strings. */
static cJSON *split(const char *list)
{
    cJSON *a = cJSON_CreateArray();
    const char *p = list;
    while (a) {
        const char *e = strchr(p, ',');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        char buf[128];
        snprintf(buf, sizeof buf, "%.*s", (int)(len < sizeof buf ? len : sizeof buf - 1), p);
        cJSON_AddItemToArray(a, cJSON_CreateString(buf));
        if (!e) break;
        p = e + 1;
    }
    return a;
}

/* Long tables (a time series) are thinned to at most this many rows, evenly
 * spaced, first and last kept; the HDF5 file has every row. */
#define JSON_MAX_ROWS 1000

int cd_an_print_json(const cd_an_report *rep, const char *path, void *stream)
{
    cJSON *root = cJSON_CreateObject();
    if (!root) return -1;
    cJSON_AddStringToObject(root, "file", path);
    cJSON_AddNumberToObject(root, "snapshot", rep->snapshot);
    cJSON_AddNumberToObject(root, "n_snapshots", rep->n_snapshots);
    cJSON_AddNumberToObject(root, "step", (double)rep->step);
    cJSON_AddItemToObject(root, "time", num(rep->time));
    for (int k = 0; k < rep->n_groups; k++) {
        const cd_an_group *g = &rep->groups[k];
        cJSON *o = cJSON_CreateObject(), *units = cJSON_CreateObject();
        for (int s = 0; s < g->n_scalars; s++) {
            cJSON_AddItemToObject(o, g->scalars[s].name, num(g->scalars[s].value));
            cJSON_AddStringToObject(units, g->scalars[s].name, g->scalars[s].unit);
        }
        for (int t = 0; t < g->n_texts; t++) cJSON_AddStringToObject(o, g->texts[t].name, g->texts[t].text);
        cJSON_AddItemToObject(o, "units", units);
        if (g->n_curves) {
            cJSON *curves = cJSON_CreateObject();
            for (int c = 0; c < g->n_curves; c++) {
                const cd_an_curve *cv = &g->curves[c];
                cJSON *co = cJSON_CreateObject(), *rows = cJSON_CreateArray();
                cJSON_AddItemToObject(co, "columns", split(cv->columns));
                cJSON_AddItemToObject(co, "units", split(cv->units));
                size_t stride = cv->rows > JSON_MAX_ROWS ? (cv->rows + JSON_MAX_ROWS - 2) / (JSON_MAX_ROWS - 1) : 1;
                for (size_t i = 0; i < cv->rows; i += stride) {
                    size_t row = i + stride >= cv->rows ? cv->rows - 1 : i;
                    cJSON *r = cJSON_CreateArray();
                    for (int j = 0; j < cv->cols; j++)
                        cJSON_AddItemToArray(r, num(cv->data[row * (size_t)cv->cols + (size_t)j]));
                    cJSON_AddItemToArray(rows, r);
                    if (row == cv->rows - 1) break;
                }
                cJSON_AddItemToObject(co, "rows_in_file", cJSON_CreateNumber((double)cv->rows));
                cJSON_AddItemToObject(co, "data", rows);
                cJSON_AddItemToObject(curves, cv->name, co);
            }
            cJSON_AddItemToObject(o, "curves", curves);
        }
        cJSON_AddItemToObject(root, g->name, o);
    }
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text) return -1;
    FILE *f = stream;
    int rc = fputs(text, f) < 0 || fputc('\n', f) == EOF ? -1 : 0;
    free(text);
    return rc;
}
