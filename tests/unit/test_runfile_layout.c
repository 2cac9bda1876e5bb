#define _POSIX_C_SOURCE 200809L /* open_memstream */
/* The run-file layout table (kernels/runfile.def, with the columns of
 * kernels/fields.def) against what reads and writes run files:
 *
 * - host/capdem_h5.py, the one way the Python tools open a run file: the
 *   block between its GENERATED markers must be exactly what this program
 *   writes from the C tables.  `build/tests/test_runfile_layout --write host/capdem_h5.py`
 *   (from the source folder, with the build's binary) rewrites the block
 *   after the tables changed; the rest of the module is written by hand.
 * - a file the writer wrote: every group the table says a file has, every
 *   dataset with its type and unit attribute, every column of fields.def
 *   where the table puts it, the members of the /walls/value compound, and
 *   the commit journal beside the file while it is open, and the time
 *   series of kernels/observables.def with their units and components.
 * - docs/output.md: its table of the time series, between its GENERATED
 *   markers, is what this program writes from kernels/observables.def
 *   (`--write docs/output.md` rewrites it). */
#include "test_util.h"
#include <unistd.h>
#include "io/io_h5.h"
#include "io/io_h5_layout.h"
#include "core/observables.h"

#define BEGIN_MARK     "# ---- BEGIN GENERATED"
#define END_MARK       "# ---- END GENERATED"
#define DOC_BEGIN_MARK "<!-- BEGIN GENERATED"
#define DOC_END_MARK   "<!-- END GENERATED -->"

static const char *store_name(enum cdh5_store st)
{
    return st == CDH5_FIXED ? "fixed" : st == CDH5_SERIES ? "series" : "rows";
}

static void lower(char *dst, const char *id, size_t len)
{
    size_t i = 0;
    for (; id[i] && i + 1 < len; i++) dst[i] = (char)(id[i] >= 'A' && id[i] <= 'Z' ? id[i] - 'A' + 'a' : id[i]);
    dst[i] = 0;
}

/* Components of observable k in a row: "1", "3", "W" or "3 W" (W walls). */
static const char *components(const cd_observable_desc *d)
{
    static char s[16];
    if (d->per_wall) snprintf(s, sizeof s, d->ncomp > 1 ? "%d W" : "W", d->ncomp);
    else snprintf(s, sizeof s, "%d", d->ncomp);
    return s;
}

/* The generated block of host/capdem_h5.py, markers included. */
static void write_block(FILE *o)
{
    static const char *const group_names[CD_GROUP_COUNT] = {"particle", "prim", "pair", "wallc", "pair_out"};
    char key[64];
    fprintf(o,
            "%s from kernels/runfile.def, fields.def and observables.def by tests/unit/test_runfile_layout.c\n"
            "# (build/tests/test_runfile_layout --write host/capdem_h5.py); edit the tables, not this block.\n",
            BEGIN_MARK);
    fprintf(o, "# groups and datasets that are not columns: key -> absolute path\nPATH = {\n");
#define CD_H5_GROUP(id, path, made, meaning)                                                                           \
    lower(key, #id, sizeof key), fprintf(o, "    \"%s\": \"%s\",\n", key, path);
#define CD_H5_DATASET(id, path, type, unit, meaning)                                                                   \
    lower(key, #id, sizeof key), fprintf(o, "    \"%s\": \"%s\",\n", key, path);
#include "../kernels/runfile.def"
    fprintf(o, "}\n# link and attribute names: key -> name\nNAME = {\n");
#define CD_H5_NAME(id, name, meaning) lower(key, #id, sizeof key), fprintf(o, "    \"%s\": \"%s\",\n", key, name);
#include "../kernels/runfile.def"
    fprintf(o, "}\n# columns of fields.def: name -> (dataset, storage, group, components, unit); storage \"fixed\":\n"
               "# (rows, c) once, \"series\": (snapshots, rows, c), \"rows\": the active rows of every snapshot\n"
               "COLUMN = {\n");
    for (size_t k = 0; k < cd_n_fields; k++) {
        const cd_field_info *f = &cd_fields[k];
        char p[CDH5_PATH_LEN];
        cdh5_field_path(f, p, sizeof p);
        fprintf(o, "    \"%s\": (\"%s\", \"%s\", \"%s\", %d, \"%s\"),\n", f->name, p, store_name(cdh5_store_of(f)),
                group_names[f->group], f->ncomp, f->unit);
    }
    fprintf(o, "}\n# members of the compound /walls/value: (name, type, components, unit)\nWALL_MEMBERS = (\n");
#define CD_H5_WALL_MEMBER(name, type, ncomp, unit)                                                                     \
    fprintf(o, "    (\"%s\", \"%s\", %d, \"%s\"),\n", #name, CD_KIND_##type == CD_KIND_INT ? "int32" : "float64",      \
            ncomp, unit);
#include "../kernels/runfile.def"
    fprintf(o, ")\n# wall kinds: the member type of /walls/value\n");
#define CD_H5_WALL_KIND(id, value, name) fprintf(o, "WALL_%s = %d\n", #id, value);
#include "../kernels/runfile.def"
    fprintf(o, "WALL_KIND_NAME = {\n");
#define CD_H5_WALL_KIND(id, value, name) fprintf(o, "    %d: \"%s\",\n", value, name);
#include "../kernels/runfile.def"
    fprintf(o, "}\n# time series of a DEM run, /observables/<name>: name -> (unit, components per row, meaning);\n"
               "# W: the number of walls\nOBSERVABLES = {\n");
    for (int k = 0; k < CD_OBSERVABLE_COUNT; k++) {
        const cd_observable_desc *d = &cd_observable_table[k];
        if (*d->name)
            fprintf(o, "    \"%s\": (\"%s\", \"%s\", \"%s\"),\n", d->name, d->unit, components(d), d->meaning);
    }
    fprintf(o, "}\n%s\n", END_MARK);
}

/* The generated table of docs/output.md, markers included. */
static void write_doc_block(FILE *o)
{
    fprintf(o,
            "%s from kernels/observables.def by tests/unit/test_runfile_layout.c (--write docs/output.md) -->\n"
            "| name | unit | components | meaning |\n|---|---|---|---|\n",
            DOC_BEGIN_MARK);
    for (int k = 0; k < CD_OBSERVABLE_COUNT; k++) {
        const cd_observable_desc *d = &cd_observable_table[k];
        if (*d->name) fprintf(o, "| `%s` | %s | %s | %s |\n", d->name, d->unit, components(d), d->meaning);
    }
    fprintf(o, "%s\n", DOC_END_MARK);
}

static char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    size_t cap = 0, n = 0;
    for (;;) {
        if (n + 4096 + 1 > cap) {
            char *nb = realloc(buf, cap = 2 * cap + 8192);
            if (!nb) break;
            buf = nb;
        }
        size_t r = fread(buf + n, 1, cap - n - 1, f);
        n += r;
        if (r == 0) break;
    }
    fclose(f);
    if (buf) buf[n] = 0;
    *len = n;
    return buf;
}

/* The module's text with the block between (and including) the markers
 * replaced by block; NULL when the markers are missing. */
static char *with_block(const char *text, const char *block, const char *begin, const char *end)
{
    const char *b = strstr(text, begin), *e = b ? strstr(b, end) : NULL;
    if (!b || !e) return NULL;
    e += strlen(end);
    if (*e == '\n') e++;
    size_t nb = (size_t)(b - text), nblock = strlen(block), ne = strlen(e);
    char *out = malloc(nb + nblock + ne + 1);
    if (!out) return NULL;
    memcpy(out, text, nb);
    memcpy(out + nb, block, nblock);
    memcpy(out + nb + nblock, e, ne + 1);
    return out;
}

static char *block_text(void (*write)(FILE *))
{
    char *buf = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&buf, &len);
    assert_non_null(m);
    write(m);
    fclose(m);
    return buf;
}

/* A file of the source folder whose block between begin and end must be
 * what write gives. */
static void check_generated(const char *file, void (*write)(FILE *), const char *begin, const char *end)
{
    const char *src = getenv("CAPDEM_SOURCE_DIR");
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", src ? src : CAPDEM_SOURCE_DIR, file);
    size_t n;
    char *text = slurp(path, &n), *block = block_text(write);
    if (!text) fail_msg("cannot read %s", path);
    char *want = with_block(text, block, begin, end);
    if (!want) fail_msg("%s: no '%s' ... '%s' block", path, begin, end);
    if (strcmp(want, text)) {
        const char *a = text, *b = want;
        int line = 1;
        for (; *a && *a == *b; a++, b++) line += *a == '\n';
        fail_msg("%s differs from the tables in kernels/ from line %d: regenerate it with "
                 "build/tests/test_runfile_layout --write %s",
                 path, line, file);
    }
    free(want);
    free(block);
    free(text);
}

static void test_python_module_is_generated(void **state)
{
    (void)state;
    check_generated("host/capdem_h5.py", write_block, BEGIN_MARK, END_MARK);
}

static void test_docs_table_is_generated(void **state)
{
    (void)state;
    check_generated("docs/output.md", write_doc_block, DOC_BEGIN_MARK, DOC_END_MARK);
}

/* ---- the table against a written file ------------------------------------ */

static const char *small_run =
    "run: {dt: 5.0e-6, steps: 0}\n"
    "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0.2, friction: 0.5, wall_friction: 0.5}\n"
    "particles: [{shape: cross, aspect: 3, diameter: 0.005, count: 2}]\n"
    "domain: {type: none, walls: [{type: plane, point: [0, 0, 0], normal: [0, 1, 0]}]}\n"
    "init: {speed: 0}\n";

/* Class and size of the table's dataset types. */
static void check_type(hid_t d, const char *path, const char *type)
{
    hid_t t = H5Dget_type(d);
    H5T_class_t cl = H5Tget_class(t);
    size_t size = H5Tget_size(t);
    H5Tclose(t);
    int ok = !strcmp(type, "I32")      ? cl == H5T_INTEGER && size == 4
             : !strcmp(type, "I64")    ? cl == H5T_INTEGER && size == 8
             : !strcmp(type, "F64")    ? cl == H5T_FLOAT && size == 8
             : !strcmp(type, "STRING") ? cl == H5T_STRING
             : !strcmp(type, "WALLS")  ? cl == H5T_COMPOUND
                                       : 0;
    if (!ok) fail_msg("%s: class %d, %zu bytes, the table says %s", path, (int)cl, size, type);
}

static void check_unit(hid_t d, const char *path, const char *unit)
{
    if (!*unit) return;
    char err[1024];
    if (H5Aexists(d, CDH5_NAME(UNIT)) <= 0) fail_msg("%s has no %s attribute", path, CDH5_NAME(UNIT));
    hid_t a = H5Aopen(d, CDH5_NAME(UNIT), H5P_DEFAULT), t = H5Aget_type(a);
    char got[256] = "";
    size_t size = H5Tget_size(t);
    assert_true(size < sizeof got);
    assert_true(H5Aread(a, t, got) >= 0);
    H5Tclose(t);
    H5Aclose(a);
    snprintf(err, sizeof err, "%s: unit \"%s\", the table says \"%s\"", path, got, unit);
    if (strcmp(got, unit)) fail_msg("%s", err);
}

static void test_written_file_matches_table(void **state)
{
    (void)state;
    cd_sim sim;
    cd_config cfg;
    char err[2048];
    const char *path = "test_runfile_layout.h5";
    cdt_setup(&sim, &cfg, small_run);
    /* as `capdem run` does: a start before the first step (an offload
     * device or OpenCL holds the state from there on) */
    if (cd_sim_start(&sim, 1, err, sizeof err)) fail_msg("start: %s", err);
    cdt_step(&sim, 10);
    /* the time series `capdem run` writes, one row */
    cd_observable_info info[CD_OBSERVABLE_COUNT];
    int n_obs = cd_observable_series(&sim, info);
    double row[CD_OBS_ROW_MAX];
    cd_observables obs;
    cd_sim_observe(&sim, &obs);
    cd_observable_row(&sim, &obs, row);
    cd_output *o = cd_output_create(path, &cfg, sim.shapes, sim.n_shapes, info, n_obs, err, sizeof err);
    if (!o) fail_msg("%s", err);
    assert_int_equal(cd_output_thermo(o, sim.s.step, sim.s.time, row), 0);
    assert_int_equal(cd_output_snapshot(o, &sim.s), 0);
    /* the commit journal beside the file, under the table's name, while the file is open */
    char journal[CDH5_PATH_LEN];
    snprintf(journal, sizeof journal, "%s%s", path, CDH5_NAME(JOURNAL));
    if (access(journal, F_OK)) fail_msg("no commit journal %s beside the open run file", journal);
    assert_int_equal(cd_output_close(o), 0);
    hid_t f = cdh5_open_ro(path, err, sizeof err);
    if (f < 0) fail_msg("%s", err);
        /* groups (the optional ones only some files have) */
#define CD_H5_GROUP(id, path, made, meaning)                                                                           \
    if (strcmp(#made, "OPTIONAL") && !cdh5_exists(f, path)) fail_msg("group %s (%s) is missing", path, #id);
#include "../kernels/runfile.def"
        /* datasets: type and unit */
#define CD_H5_DATASET(id, path, type, unit, meaning)                                                                   \
    {                                                                                                                  \
        hid_t d = cdh5_exists(f, path) ? H5Dopen2(f, path, H5P_DEFAULT) : -1;                                          \
        if (d < 0) fail_msg("dataset %s (%s) is missing", path, #id);                                                  \
        check_type(d, path, #type);                                                                                    \
        check_unit(d, path, unit);                                                                                     \
        H5Dclose(d);                                                                                                   \
    }
#include "../kernels/runfile.def"
    /* columns */
    for (size_t k = 0; k < cd_n_fields; k++) {
        char p[CDH5_PATH_LEN];
        cdh5_field_path(&cd_fields[k], p, sizeof p);
        hid_t d = cdh5_exists(f, p) ? H5Dopen2(f, p, H5P_DEFAULT) : -1;
        if (d < 0) fail_msg("column %s: %s is missing", cd_fields[k].name, p);
        assert_true(cdh5_field_rows(d, &cd_fields[k], p, path, err, sizeof err) >= 0);
        check_unit(d, p, cd_fields[k].unit);
        H5Dclose(d);
    }
    /* the wall compound: the table's members, in its order, as stored */
    hid_t d = H5Dopen2(f, CDH5_PATH(WALLS_VALUE), H5P_DEFAULT), t = H5Dget_type(d);
    int m = 0;
#define CD_H5_WALL_MEMBER(name, type, ncomp, unit)                                                                     \
    {                                                                                                                  \
        char *got = H5Tget_member_name(t, (unsigned)m);                                                                \
        if (!got || strcmp(got, #name)) fail_msg("/walls/value member %d is %s, the table says %s", m, got, #name);    \
        H5free_memory(got);                                                                                            \
        m++;                                                                                                           \
    }
#include "../kernels/runfile.def"
    assert_int_equal(H5Tget_nmembers(t), m);
    H5Tclose(t);
    H5Dclose(d);
    /* the wall of this run, read back through the table's compound: a plane */
    cd_wall w;
    t = cdh5_wall_mem_type();
    d = H5Dopen2(f, CDH5_PATH(WALLS_VALUE), H5P_DEFAULT);
    assert_true(cdh5_read_rows(d, 0, 1, t, &w) >= 0);
    assert_int_equal(w.type, CD_WALL_PLANE);
    H5Dclose(d);
    H5Tclose(t);
    /* every named observable of kernels/observables.def: one row, its unit,
     * its components for the run's walls (here one plane) */
    int named = 0;
    for (int k = 0; k < CD_OBSERVABLE_COUNT; k++) {
        const cd_observable_desc *od = &cd_observable_table[k];
        if (!*od->name) continue;
        char p[CDH5_PATH_LEN];
        snprintf(p, sizeof p, "%s/%s/%s", CDH5_PATH(OBSERVABLES), od->name, CDH5_NAME(VALUE));
        hid_t v = cdh5_exists(f, p) ? H5Dopen2(f, p, H5P_DEFAULT) : -1;
        if (v < 0) fail_msg("time series %s (%s) is missing", p, od->id);
        check_unit(v, p, od->unit);
        hsize_t dims[2] = {0, 1};
        hid_t sp = H5Dget_space(v);
        int rank = H5Sget_simple_extent_dims(sp, dims, NULL);
        H5Sclose(sp);
        H5Dclose(v);
        int want = cd_observable_ncomp(k, sim.s.n_walls);
        if (dims[0] != 1 || rank != (want > 1 ? 2 : 1) || (int)dims[1] != want)
            fail_msg("%s: %d rows of %d components, expected 1 of %d", p, (int)dims[0], (int)dims[1], want);
        named++;
    }
    assert_int_equal(named, n_obs);
    /* the commit record */
    assert_int_equal(cdh5_committed(f, path, err, sizeof err), 1);
    H5Fclose(f);
    remove(path);
    cd_sim_free(&sim);
    cd_config_free(&cfg);
}

int main(int argc, char **argv)
{
    if (argc == 3 && !strcmp(argv[1], "--write")) {
        size_t n, len = strlen(argv[2]);
        int doc = len > 3 && !strcmp(argv[2] + len - 3, ".md"); /* docs/output.md, else host/capdem_h5.py */
        char *text = slurp(argv[2], &n), *block = block_text(doc ? write_doc_block : write_block);
        char *out =
            text ? with_block(text, block, doc ? DOC_BEGIN_MARK : BEGIN_MARK, doc ? DOC_END_MARK : END_MARK) : NULL;
        FILE *f = out ? fopen(argv[2], "wb") : NULL;
        if (!f || fputs(out, f) < 0 || fclose(f)) {
            fprintf(stderr, "test_runfile_layout: cannot rewrite the generated block of %s\n", argv[2]);
            return 1;
        }
        printf("%s: generated block rewritten\n", argv[2]);
        return 0;
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_python_module_is_generated),
        cmocka_unit_test(test_docs_table_is_generated),
        cmocka_unit_test(test_written_file_matches_table),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
