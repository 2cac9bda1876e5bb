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
 * the run file.
 *
 * This file holds the command and the .xmf writer; export_read.c reads the
 * run file and picks the columns, export_viz.c writes /visualization
 * (shared declarations: export_internal.h). */
#define _XOPEN_SOURCE 700
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>
#include <hdf5.h>
#include "io/io_h5_journal.h"
#include "export/export.h"
#include "io/io_h5.h"
#include "io/io_h5_guard.h"
#include "export/export_internal.h"
#include "mpm/mpm_output.h"

/* Records the first failure (later ones are usually consequences). */
int cd_export_fail(cd_export_ctx *x, int status, const char *fmt, ...)
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

const char *cd_export_h5_reason(char *buf)
{
    buf[0] = 0;
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, cd_export_walk_err, buf);
    return buf[0] ? buf : "no detail from HDF5";
}

/* ---- the XDMF file ------------------------------------------------------- */

static void cd_export_xml_text(FILE *o, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&':
            fputs("&amp;", o);
            break;
        case '<':
            fputs("&lt;", o);
            break;
        case '>':
            fputs("&gt;", o);
            break;
        case '"':
            fputs("&quot;", o);
            break;
        case '\'':
            fputs("&apos;", o);
            break;
        default:
            fputc(*s, o);
        }
    }
}

/* <DataItem> naming file:path, of the given shape (rank 1 or 2). */
void cd_export_xml_item(FILE *o, const char *indent, const char *file, const char *path, hsize_t rows, int ncomp,
                        const char *number_type, int precision)
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

void cd_export_xml_attr(FILE *o, const char *name, const char *center, const char *file, const char *path, hsize_t rows,
                        const cd_export_field *fl)
{
    fputs("      <Attribute Name=\"", o);
    cd_export_xml_text(o, name);
    fprintf(o, "\" AttributeType=\"%s\" Center=\"%s\">\n", cd_export_attr_type(fl->ncomp), center);
    cd_export_xml_item(o, "        ", file, path, rows, fl->ncomp, fl->number_type, fl->precision);
    fputs("      </Attribute>\n", o);
}

void cd_export_xml_time(FILE *o, const cd_export_ctx *x, int k)
{
    fprintf(o, "      <Time Value=\"%.17g\"/>\n", x->time[k]);
}

/* <Topology> of n cells of the given type, nodes points each, whose
 * connectivity is the int32 helper dataset cells (n, nodes). */
void cd_export_xml_topology(FILE *o, const cd_export_ctx *x, const char *type, int nodes, hsize_t n, const char *cells)
{
    fprintf(o, "      <Topology TopologyType=\"%s\" NodesPerElement=\"%d\" NumberOfElements=\"%llu\">\n", type, nodes,
            (unsigned long long)n);
    cd_export_xml_item(o, "        ", x->viz_ref, cells, n, nodes, "Int", 4);
    fprintf(o, "      </Topology>\n");
}

/* <Geometry> of snapshot k: the n points of /visualization/snapshots/<k>/<points>. */
void cd_export_xml_geometry(FILE *o, const cd_export_ctx *x, int k, const char *points, hsize_t n)
{
    char path[200];
    fprintf(o, "      <Geometry GeometryType=\"XYZ\">\n");
    snprintf(path, sizeof path, "/visualization/snapshots/%d/%s", k, points);
    cd_export_xml_item(o, "        ", x->viz_ref, path, n, 3, "Float", 8);
    fprintf(o, "      </Geometry>\n");
}

static void cd_export_xml_arms(FILE *o, const cd_export_ctx *x, int k)
{
    fprintf(o, "    <Grid Name=\"arms\" GridType=\"Uniform\">\n");
    cd_export_xml_time(o, x, k);
    cd_export_xml_topology(o, x, "Polyline", 2, x->P, "/visualization/arm_cells");
    cd_export_xml_geometry(o, x, k, "arm_points", 2 * x->P);
    /* Point copies first: the Tube filter takes its radius from point data. */
    cd_export_xml_attr(o, "radius", "Node", x->viz_ref, "/visualization/arm_point_radius", 2 * x->P, &x->prim_radius);
    cd_export_xml_attr(o, "particle", "Node", x->viz_ref, "/visualization/arm_point_particle", 2 * x->P,
                       &x->prim_particle);
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
    cd_export_xml_topology(o, x, "Polyvertex", 1, x->N, "/visualization/particle_id");
    cd_export_xml_geometry(o, x, k, "position", x->N);
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
        snprintf(path, sizeof path, "/visualization/snapshots/%d/contact_cells", k);
        cd_export_xml_topology(o, x, "Polyline", 2, C, path);
    }
    cd_export_xml_geometry(o, x, k, "position", x->N);
    for (int i = 0; i < x->ncf && C > 0; i++) {
        snprintf(path, sizeof path, "/visualization/snapshots/%d/%s", k, x->cf[i].name);
        cd_export_xml_attr(o, x->cf[i].name, "Cell", x->viz_ref, path, C, &x->cf[i]);
    }
    fprintf(o, "    </Grid>\n");
}

int cd_export_write_xml_with(cd_export_ctx *x, const char *out, const char *comment,
                             void (*body)(FILE *, const cd_export_ctx *))
{
    /* Written aside under a name nobody can guess (mkstemp: a new file,
     * O_EXCL, never through a planted link), then renamed over out, which
     * replaces a link there instead of writing through it. */
    char tmp[CD_EXPORT_PATH + 32];
    snprintf(tmp, sizeof tmp, "%s.XXXXXX", out);
    int fd = mkstemp(tmp);
    if (fd < 0) return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot write (%s)", out, strerror(errno));
    mode_t mask = umask(0); /* mkstemp makes it 0600; an .xmf is as readable as any new file */
    umask(mask);
    FILE *o = fchmod(fd, 0666 & ~mask) == 0 ? fdopen(fd, "w") : NULL;
    if (!o) {
        int e = errno;
        close(fd);
        remove(tmp);
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot write (%s)", out, strerror(e));
    }
    fprintf(o, "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    fprintf(o, "<!-- Written by `capdem export` from ");
    /* "--" is not allowed inside an XML comment. */
    for (const char *s = x->h5_ref; *s; s++) fputc(s[0] == '-' && s[1] == '-' ? '_' : s[0], o);
    fputs(comment, o);
    fprintf(o, "<Xdmf Version=\"2.0\">\n  <Domain>\n");
    body(o, x);
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

/* The DEM run's three temporal collections. */
static void cd_export_dem_grids(FILE *o, const cd_export_ctx *x)
{
    void (*grids[3])(FILE *, const cd_export_ctx *, int) = {cd_export_xml_arms, cd_export_xml_particles,
                                                            cd_export_xml_contacts};
    const char *names[3] = {"arms", "particles", "contacts"};
    for (int g = 0; g < 3; g++) {
        fprintf(o, "  <Grid Name=\"%s\" GridType=\"Collection\" CollectionType=\"Temporal\">\n", names[g]);
        for (int k = 0; k < x->S; k++) grids[g](o, x, k);
        fprintf(o, "  </Grid>\n");
    }
}

static int cd_export_write_xml(cd_export_ctx *x, const char *out)
{
    char comment[1024];
    snprintf(comment, sizeof comment,
             ": %d snapshots, %llu particles, %llu arms, %lld contact rows.\n"
             "     Three temporal collections: arms (lines; radius as point and cell data, for the Tube filter),\n"
             "     particles (centres) and contacts (lines between the centres of touching particles).\n"
             "     Every data item points into the run file or into its /visualization helpers: no copy of the data.\n"
             "     ParaView: any of its XDMF readers; docs/visualization.md. -->\n",
             x->S, (unsigned long long)x->N, (unsigned long long)x->P, x->off[x->S]);
    return cd_export_write_xml_with(x, out, comment, cd_export_dem_grids);
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


/* The sidecar of a read-only run file: a new one is created exclusively
 * (O_EXCL: never through a link planted at its name); an existing one is
 * used only when it is a regular file, not a link, that is an HDF5 file
 * holding nothing but an earlier export's /visualization.  Anything else
 * is refused (exit 2) and left as it is: export never truncates or writes
 * into a file it did not write.  Returns 0, or -1 with x failed. */
static int cd_export_open_sidecar(cd_export_ctx *x, const char *side, const char *why)
{
    struct stat before, opened;
    if (lstat(side, &before) != 0) {
        x->vf = H5Fcreate(side, H5F_ACC_EXCL, H5P_DEFAULT, H5P_DEFAULT);
        if (x->vf >= 0) return 0;
        if (lstat(side, &before) != 0) /* not a link that appeared meanwhile: no room, no permission */
            return cd_export_fail(x, CD_EXPORT_FAIL,
                                  "%s: cannot write into it (%s) nor create %s for the helper "
                                  "datasets",
                                  x->path, why, side);
    }
    const char *refused = NULL;
    if (S_ISLNK(before.st_mode)) refused = "is a symbolic link";
    else if (!S_ISREG(before.st_mode)) refused = "is not a regular file";
    else if ((x->vf = H5Fopen(side, H5F_ACC_RDWR, H5P_DEFAULT)) < 0)
        refused = "is not an HDF5 file export can write into";
    if (!refused) {
        /* the file opened must be the one looked at (no link swapped in) */
        void *handle = NULL;
        H5G_info_t info;
        if (H5Fget_vfd_handle(x->vf, H5P_DEFAULT, &handle) < 0 || !handle || fstat(*(int *)handle, &opened) != 0 ||
            lstat(side, &before) != 0 || !S_ISREG(before.st_mode) || opened.st_dev != before.st_dev ||
            opened.st_ino != before.st_ino)
            refused = "changed while it was opened";
        else if (H5Gget_info(x->vf, &info) < 0 || info.nlinks > 1 ||
                 (info.nlinks == 1 && H5Lexists(x->vf, "/visualization", H5P_DEFAULT) <= 0))
            refused = "holds other data than an earlier export's /visualization";
    }
    if (!refused) return 0;
    if (x->vf >= 0) H5Fclose(x->vf);
    x->vf = -1;
    return cd_export_fail(x, CD_EXPORT_BAD_INPUT,
                          "%s is read-only here (%s), and its sidecar %s %s: refused, the "
                          "sidecar is left as it is (remove it, or export a writable copy of %s)",
                          x->path, why, side, refused, x->path);
}

/* Opens the run file for writing the helpers, or falls back to a sidecar
 * file next to it when the run file is read-only. */
static int cd_export_open(cd_export_ctx *x, const char *out)
{
    char why[256];
    hid_t fapl = cdh5_fapl(); /* as io_h5 opens run files: journaled, atomic commits */
    x->f = H5Fopen(x->path, H5F_ACC_RDWR, fapl);
    if (x->f >= 0) {
        x->vf = x->f;
        snprintf(x->vds_src, sizeof x->vds_src, ".");
        cd_export_ref(x->h5_ref, sizeof x->h5_ref, x->path, out);
        snprintf(x->viz_ref, sizeof x->viz_ref, "%s", x->h5_ref);
        H5Pclose(fapl);
        return 0;
    }
    cd_export_h5_reason(why);
    x->f = H5Fopen(x->path, H5F_ACC_RDONLY, fapl);
    H5Pclose(fapl);
    if (x->f < 0) {
        cd_export_h5_reason(why);
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot open (HDF5: %s; is a run still writing it?)", x->path,
                              why);
    }
    char side[CD_EXPORT_PATH];
    cd_export_swap_suffix(side, sizeof side, x->path, ".viz.h5");
    if (cd_export_open_sidecar(x, side, why)) return -1;
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
    if (!x) {
        fprintf(stderr, "capdem export: out of memory\n");
        return CD_EXPORT_FAIL;
    }
    x->path = run;
    x->f = x->vf = x->viz = -1;

    H5E_auto2_t old_func;
    void *old_data;
    H5Eget_auto2(H5E_DEFAULT, &old_func, &old_data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);

    char err[512];
    /* (the run file is opened journaled: what export adds reaches it only at its commit) */
    cdh5_guard_begin("export", run);
    htri_t is_h5 = H5Fis_hdf5(run);
    int mpm = is_h5 > 0 && cd_mpm_is_run_file(run); /* solver mpm: its own layout (export_mpm.c) */
    if (is_h5 <= 0) {
        cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: not an HDF5 file", run);
    } else if ((x->S = cd_h5_snapshot_count(run, err, sizeof err)) < 0) {
        /* HDF5 locks a file that a process has open for writing. */
        int locked = strstr(err, "lock") != NULL;
        cd_export_fail(x, locked ? CD_EXPORT_FAIL : CD_EXPORT_BAD_INPUT, "%s%s", err,
                       locked ? " (is a run still writing it? export it when the run has ended)" : "");
    } else if (!cd_export_open(x, out) &&
               (mpm ? !cd_export_mpm_helpers(x)
                    : !cd_export_read_run(x) && !cd_export_discover(x) && !cd_export_helpers(x))) {
        if (x->viz >= 0) {
            H5Gclose(x->viz);
            x->viz = -1;
        }
        if (cdh5_commit(x->vf, run, err, sizeof err) < 0) {
            char why[256];
            cdh5_drop_on_close(x->vf); /* the run file keeps its last commit */
            cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot flush the helper datasets (HDF5: %s)", run,
                           cd_export_h5_reason(why));
        } else {
            cdh5_guard_end(); /* the run file has been read */
            if (mpm) cd_export_mpm_write_xml(x, out);
            else cd_export_write_xml(x, out);
        }
    }
    if (x->viz >= 0) H5Gclose(x->viz);
    if (x->status && x->f >= 0) cdh5_drop_on_close(x->f); /* a failed export adds nothing to the run file */
    if (x->vf >= 0 && x->vf != x->f) H5Fclose(x->vf);
    if (x->f >= 0 && H5Fclose(x->f) < 0 && !x->status) /* (the run file then keeps its last commit) */
        cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot close the run file after adding the helpers", run);
    cdh5_guard_end();
    H5Eset_auto2(H5E_DEFAULT, old_func, old_data);

    int status = x->status;
    if (status) {
        fprintf(stderr, "capdem export: %s\n", x->err);
    } else if (mpm) {
        printf("capdem export: wrote %s (%d snapshots, %llu material points, %llu walls, particle outlines; "
               "helper datasets in %s:/visualization)\n",
               out, x->S, (unsigned long long)x->N, (unsigned long long)x->P, x->viz_ref);
    } else {
        if (x->bad_contacts)
            fprintf(stderr,
                    "capdem export: warning: %lld contact rows name particle -1 (primitive out of range); "
                    "drawn as zero-length lines\n",
                    x->bad_contacts);
        printf("capdem export: wrote %s (%d snapshots, %llu particles, %llu arms, %lld contact rows; "
               "helper datasets in %s:/visualization)\n",
               out, x->S, (unsigned long long)x->N, (unsigned long long)x->P, x->off[x->S], x->viz_ref);
    }
    cd_export_mpm_free(x);
    free(x->off);
    free(x->step);
    free(x->time);
    free(x);
    return status;
}
