/* capdem export of a run file of solver mpm (docs/visualization.md,
 * "Material point runs"; the run file's layout: docs/mpm.md, "Output").
 *
 * Three temporal collections, one grid per snapshot each:
 *   points    one vertex per material point at its position (z = 0), with
 *             its particle id, mass, volume, velocity, stress (the four
 *             components together and each alone), equivalent plastic
 *             strain and deformation gradient;
 *   walls     one line per wall: the wall's trace in the plane, clipped by
 *             the walls that cross it (the box's corners) or, where none
 *             does, spanning the points' extent along it and a tenth more
 *             on each side; the wall's id, force, normal and velocity;
 *   outlines  each particle's outline as `capdem analyze` sees it (the
 *             convex hull of its points' deformed squares, the outline its
 *             boundary curvature kappa is measured on), one line per edge,
 *             with the particle's id.
 *
 * As in the DEM export (export_xdmf.c), the .xmf holds no numbers: the
 * points' columns are virtual datasets over row k of /mpm/snapshots/...
 * (2-component ones mapped into 3 columns, the third unmapped and so 0:
 * ParaView's vectors and XYZ geometry), and only what the run file does not
 * hold is real data under /visualization: the connectivities, the walls'
 * segment ends and the outlines.
 *
 * Layout (version CD_EXPORT_LAYOUT, attribute solver = "mpm"):
 *   /visualization                 attributes layout, solver, n_points, n_walls
 *     point_id     (N) int32            0..N-1: vertex connectivity
 *     wall_cells   (W, 2) int32         (2w, 2w+1): the line of wall w
 *     wall_id      (W) int32            0..W-1
 *     snapshots/<k>                attributes step, time
 *       position, velocity (N, 3) VDS   /mpm/snapshots/<x>[k] in columns 0, 1
 *       volume, plastic_strain (N) VDS, stress, deformation_gradient (N, 4) VDS
 *       stress_xx, stress_yy, stress_xy, stress_zz (N) VDS: one column each
 *       wall_force (W, 3) VDS           /mpm/snapshots/wall_force[k] in columns 0, 1
 *       wall_points (2W, 3) float64     the walls' segment ends [m]
 *       outline_points (B_k, 3) float64 the outlines' vertices [m], particle by particle
 *       outline_cells (B_k, 2) int32    their edges
 *       outline_particle (B_k) int32    each edge's particle */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <hdf5.h>
#include "export/export_internal.h"
#include "analysis/analyze.h" /* cd_an_convex_hull, cd_an_mpm_corners: the outline analyze measures */
#include "io/io_h5_layout.h"

/* Datasets of the run file the export reads or points at. */
enum {
    SNAP_POSITION,
    SNAP_VELOCITY,
    SNAP_VOLUME,
    SNAP_STRESS,
    SNAP_PLASTIC,
    SNAP_DEFG,
    SNAP_WALL_POS,
    SNAP_WALL_FORCE,
    SNAP_STEP,
    SNAP_TIME,
    POINT_PARTICLE,
    POINT_MASS,
    WALL_NORMAL,
    WALL_VELOCITY,
    MPM_FIELDS
};
static const struct {
    const char *path, *name;
    int per; /* rows: 0 snapshots x points, 1 snapshots x walls, 2 snapshots, 3 points, 4 walls */
    int ncomp;
} mpm_fields[MPM_FIELDS] = {
    {"/mpm/snapshots/position", "position", 0, 2},
    {"/mpm/snapshots/velocity", "velocity", 0, 2},
    {"/mpm/snapshots/volume", "volume", 0, 1},
    {"/mpm/snapshots/stress", "stress", 0, 4},
    {"/mpm/snapshots/plastic_strain", "plastic_strain", 0, 1},
    {"/mpm/snapshots/deformation_gradient", "deformation_gradient", 0, 4},
    {"/mpm/snapshots/wall_position", "wall_position", 1, 2},
    {"/mpm/snapshots/wall_force", "wall_force", 1, 2},
    {"/mpm/snapshots/step", "step", 2, 1},
    {"/mpm/snapshots/time", "time", 2, 1},
    {"/mpm/points/particle", "particle", 3, 1},
    {"/mpm/points/mass", "mass", 3, 1},
    {"/mpm/walls/normal", "normal", 4, 2},
    {"/mpm/walls/velocity", "wall_velocity", 4, 2},
};
static const char *stress_names[4] = {"stress_xx", "stress_yy", "stress_xy", "stress_zz"};

struct cd_export_mpm {
    cd_export_field f[MPM_FIELDS];
    int *particle;    /* (N) the points' particle ids */
    hsize_t *outline; /* (S) outline vertices of each snapshot */
};

void cd_export_mpm_free(cd_export_ctx *x)
{
    if (!x->mpm) return;
    free(x->mpm->particle);
    free(x->mpm->outline);
    free(x->mpm);
    x->mpm = NULL;
}

/* The datasets, their shapes against the counts, the clock and the particle ids. */
static int mpm_read(cd_export_ctx *x)
{
    struct cd_export_mpm *m = x->mpm = calloc(1, sizeof *x->mpm);
    if (!m) return cd_export_fail(x, CD_EXPORT_FAIL, "out of memory");
    cd_export_field *pos = &m->f[SNAP_POSITION], *wall = &m->f[SNAP_WALL_POS];
    if (cd_export_describe(x->f, mpm_fields[SNAP_POSITION].path, pos) || pos->rank != 3 ||
        cd_export_describe(x->f, mpm_fields[SNAP_WALL_POS].path, wall) || wall->rank != 3)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: not a complete mpm run file (no %s or %s)", x->path,
                              mpm_fields[SNAP_POSITION].path, mpm_fields[SNAP_WALL_POS].path);
    /* the snapshots completely on disk: root attribute n_snapshots (docs/mpm.md, "Output") */
    long long committed = -1;
    if (cd_export_read_attr_ll(x->f, "n_snapshots", &committed, 1) || committed < 0 || committed > 0x7fffffff)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: no readable root attribute n_snapshots", x->path);
    x->S = (int)committed;
    if (x->S == 0)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: the run file holds no complete snapshot", x->path);
    x->N = pos->dims[1];
    x->P = wall->dims[1]; /* the walls */
    hsize_t rows[5] = {x->N, x->P, 1, x->N, x->P};
    for (int i = 0; i < MPM_FIELDS; i++) {
        cd_export_field *fl = &m->f[i];
        int per = mpm_fields[i].per, snap = per <= 2,
            want_rank = (snap ? 1 : 0) + (per == 2 ? 0 : 1) + (mpm_fields[i].ncomp > 1 ? 1 : 0);
        int ok = !cd_export_describe(x->f, mpm_fields[i].path, fl) && fl->rank == want_rank &&
                 (!snap || fl->dims[0] >= (hsize_t)x->S) && (per == 2 || fl->dims[snap ? 1 : 0] == rows[per]) &&
                 (mpm_fields[i].ncomp == 1 || fl->dims[fl->rank - 1] == (hsize_t)mpm_fields[i].ncomp);
        if (!ok)
            return cd_export_fail(x, CD_EXPORT_BAD_INPUT,
                                  "%s: %s is missing or not of the shape docs/mpm.md (\"Output\") gives it for "
                                  "%d snapshots, %llu points and %llu walls; the file is refused",
                                  x->path, mpm_fields[i].path, x->S, (unsigned long long)x->N,
                                  (unsigned long long)x->P);
        snprintf(fl->name, sizeof fl->name, "%s", mpm_fields[i].name);
        fl->ncomp = mpm_fields[i].ncomp;
    }
    if (x->N == 0 || x->N > 0x7fffffff / 8 || x->P > 64)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: %llu material points and %llu walls: refused", x->path,
                              (unsigned long long)x->N, (unsigned long long)x->P);
    x->step = malloc(sizeof(long long) * (size_t)x->S);
    x->time = malloc(sizeof(double) * (size_t)x->S);
    m->particle = malloc(sizeof(int) * (size_t)x->N);
    m->outline = calloc((size_t)x->S, sizeof(hsize_t));
    if (!x->step || !x->time || !m->particle || !m->outline) return cd_export_fail(x, CD_EXPORT_FAIL, "out of memory");
    const struct {
        int field;
        hid_t type;
        hsize_t rows;
        void *buf;
    } reads[3] = {{SNAP_STEP, H5T_NATIVE_LLONG, (hsize_t)x->S, x->step},
                  {SNAP_TIME, H5T_NATIVE_DOUBLE, (hsize_t)x->S, x->time},
                  {POINT_PARTICLE, H5T_NATIVE_INT, x->N, m->particle}};
    for (int i = 0; i < 3; i++) {
        hid_t d = H5Dopen2(x->f, mpm_fields[reads[i].field].path, H5P_DEFAULT);
        int rc = d >= 0 ? cdh5_read_rows(d, 0, reads[i].rows, reads[i].type, reads[i].buf) : -1;
        if (d >= 0) H5Dclose(d);
        if (rc < 0)
            return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: cannot read %s", x->path,
                                  mpm_fields[reads[i].field].path);
    }
    /* the outlines take each particle's points as one block, as the solver numbers them */
    for (hsize_t p = 0; p < x->N; p++) {
        int id = m->particle[p], prev = p ? m->particle[p - 1] : 0;
        if (p == 0 ? id != 0 : id != prev && id != prev + 1)
            return cd_export_fail(x, CD_EXPORT_BAD_INPUT,
                                  "%s: /mpm/points/particle[%llu] = %d: expected the ids 0, 1, ... in blocks of "
                                  "contiguous points; the file is refused",
                                  x->path, (unsigned long long)p, id);
    }
    return 0;
}

/* /visualization of an mpm run: for this layout version and these point
 * and wall counts. */
static int mpm_open_viz(cd_export_ctx *x)
{
    const char *names[3] = {"layout", "n_points", "n_walls"};
    long long want[3] = {CD_EXPORT_LAYOUT, (long long)x->N, (long long)x->P};
    return cd_export_open_viz_with(
        x, 3, names, want, "mpm",
        "helper datasets of `capdem export` (docs/visualization.md): connectivity, walls, particle outlines, "
        "and virtual datasets selecting one snapshot of the run's datasets; safe to delete");
}

static int mpm_fixed_helpers(cd_export_ctx *x)
{
    hsize_t W = x->P, n = x->N > 2 * W ? x->N : 2 * W;
    int *v = malloc(sizeof(int) * (size_t)n);
    if (!v) return cd_export_fail(x, CD_EXPORT_FAIL, "out of memory");
    for (hsize_t i = 0; i < n; i++) v[i] = (int)i;
    hsize_t cells[2] = {W, 2};
    int rc = cd_export_ints(x, x->viz, "point_id", 1, &x->N, v) || cd_export_ints(x, x->viz, "wall_id", 1, &W, v) ||
             (W > 0 && cd_export_ints(x, x->viz, "wall_cells", 2, cells, v));
    free(v);
    return rc ? -1 : 0;
}

/* Row k of a (S', rows, c) or (S', rows) dataset as the virtual dataset
 * name of shape (rows, width): source columns c0 .. c0+cols-1 go to the
 * virtual columns 0 .. cols-1 (width 0: a rank-1 virtual dataset). */
static int mpm_vds_row(cd_export_ctx *x, hid_t g, const char *name, const cd_export_field *fl, hsize_t k, hsize_t c0,
                       hsize_t cols, hsize_t width)
{
    hsize_t rows = fl->dims[1];
    if (fl->rank == 2) {
        cd_export_block b = {fl, {k, 0}, {1, rows}, {0}, {rows}};
        return cd_export_vds(x, g, name, 1, &rows, 1, &b);
    }
    if (width == 0) {
        cd_export_block b = {fl, {k, 0, c0}, {1, rows, 1}, {0}, {rows}};
        return cd_export_vds(x, g, name, 1, &rows, 1, &b);
    }
    hsize_t vd[2] = {rows, width};
    cd_export_block b = {fl, {k, 0, c0}, {1, rows, cols}, {0, 0}, {rows, cols}};
    return cd_export_vds(x, g, name, 2, vd, 1, &b);
}

/* Reads rows k .. k+count-1 of field i into buf (doubles). */
static int mpm_read_rows(cd_export_ctx *x, int i, hsize_t k, hsize_t count, double *buf)
{
    hid_t d = H5Dopen2(x->f, mpm_fields[i].path, H5P_DEFAULT);
    int rc = d >= 0 ? cdh5_read_rows(d, k, count, H5T_NATIVE_DOUBLE, buf) : -1;
    if (d >= 0) H5Dclose(d);
    if (rc < 0)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: cannot read rows %llu.. of %s", x->path,
                              (unsigned long long)k, mpm_fields[i].path);
    return 0;
}

/* The segment of wall w [m]: its trace through wp (a point of it) along the
 * tangent (-n_y, n_x), limited by every other wall it crosses to that
 * wall's material side (normals point into the material); a side no wall
 * limits ends at the points' extent along the tangent plus a tenth of it. */
static void mpm_wall_segment(const double *wp, const double *normal, int W, int w, const double *xy, size_t n,
                             double *ends)
{
    const double *p = wp + 2 * w, *nw = normal + 2 * w;
    double tx = -nw[1], ty = nw[0], lo = -INFINITY, hi = INFINITY;
    for (int v = 0; v < W; v++) {
        if (v == w) continue;
        const double *q = wp + 2 * v, *nv = normal + 2 * v;
        double tn = tx * nv[0] + ty * nv[1]; /* (p + s t - q) . n_v >= 0 */
        if (fabs(tn) < 1e-9) continue;       /* parallel */
        double s = ((q[0] - p[0]) * nv[0] + (q[1] - p[1]) * nv[1]) / tn;
        if (tn > 0 && s > lo) lo = s;
        if (tn < 0 && s < hi) hi = s;
    }
    if (!isfinite(lo) || !isfinite(hi) || lo >= hi) {
        double smin = INFINITY, smax = -INFINITY;
        for (size_t i = 0; i < n; i++) {
            double s = (xy[2 * i] - p[0]) * tx + (xy[2 * i + 1] - p[1]) * ty;
            smin = s < smin ? s : smin;
            smax = s > smax ? s : smax;
        }
        double margin = 0.1 * (smax - smin);
        if (!isfinite(lo) || lo >= hi) lo = smin - margin;
        if (!isfinite(hi) || lo >= hi) hi = smax + margin;
    }
    double e[6] = {p[0] + lo * tx, p[1] + lo * ty, 0, p[0] + hi * tx, p[1] + hi * ty, 0};
    memcpy(ends, e, sizeof e);
}

/* The walls' segments and the particles' outlines of snapshot k, real data in g. */
static int mpm_geometry(cd_export_ctx *x, hid_t g, hsize_t k)
{
    struct cd_export_mpm *m = x->mpm;
    size_t n = (size_t)x->N, W = (size_t)x->P;
    double *xy = malloc(2 * n * sizeof(double)), *vol = malloc(n * sizeof(double)), *F = malloc(4 * n * sizeof(double)),
           *corners = malloc(8 * n * sizeof(double)), *hull = malloc(2 * (8 * n + 2) * sizeof(double)),
           *pts = malloc(3 * 4 * n * sizeof(double));
    int *cells = malloc(2 * 4 * n * sizeof(int)), *owner = malloc(4 * n * sizeof(int));
    double wp[2 * 64], normal[2 * 64], ends[6 * 64];
    int rc = !xy || !vol || !F || !corners || !hull || !pts || !cells || !owner
                 ? cd_export_fail(x, CD_EXPORT_FAIL, "out of memory")
                 : 0;
    if (!rc)
        rc = mpm_read_rows(x, SNAP_POSITION, k, 1, xy) || mpm_read_rows(x, SNAP_VOLUME, k, 1, vol) ||
             mpm_read_rows(x, SNAP_DEFG, k, 1, F) ||
             (W > 0 && (mpm_read_rows(x, SNAP_WALL_POS, k, 1, wp) || mpm_read_rows(x, WALL_NORMAL, 0, W, normal)));
    if (!rc && W > 0) {
        for (size_t w = 0; w < W; w++) mpm_wall_segment(wp, normal, (int)W, (int)w, xy, n, ends + 6 * w);
        hsize_t dims[2] = {2 * W, 3};
        rc = cd_export_doubles(x, g, "wall_points", 2, dims, ends, "m");
    }
    hsize_t B = 0;
    for (size_t a = 0; a < n && !rc;) {
        size_t b = a;
        while (b < n && m->particle[b] == m->particle[a]) b++;
        cd_an_mpm_corners(xy, vol, F, a, b, corners);
        size_t h = cd_an_convex_hull(corners, 4 * (b - a), hull);
        for (size_t i = 0; i < h; i++) {
            pts[3 * (B + i)] = hull[2 * i];
            pts[3 * (B + i) + 1] = hull[2 * i + 1];
            pts[3 * (B + i) + 2] = 0;
            cells[2 * (B + i)] = (int)(B + i);
            cells[2 * (B + i) + 1] = (int)(B + (i + 1) % h);
            owner[B + i] = m->particle[a];
        }
        B += h;
        a = b;
    }
    if (!rc) {
        hsize_t pd[2] = {B, 3}, cd[2] = {B, 2};
        rc = cd_export_doubles(x, g, "outline_points", 2, pd, pts, "m") ||
             cd_export_ints(x, g, "outline_cells", 2, cd, cells) ||
             cd_export_ints(x, g, "outline_particle", 1, &B, owner);
        m->outline[k] = B;
    }
    free(xy);
    free(vol);
    free(F);
    free(corners);
    free(hull);
    free(pts);
    free(cells);
    free(owner);
    return rc ? -1 : 0;
}

static int mpm_snapshot_helpers(cd_export_ctx *x, int k)
{
    struct cd_export_mpm *m = x->mpm;
    hid_t snaps = H5Gopen2(x->viz, "snapshots", H5P_DEFAULT);
    char name[32];
    snprintf(name, sizeof name, "%d", k);
    hid_t g = H5Lexists(snaps, name, H5P_DEFAULT) > 0 ? H5Gopen2(snaps, name, H5P_DEFAULT)
                                                      : H5Gcreate2(snaps, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Gclose(snaps);
    if (g < 0) {
        char why[256];
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot create /visualization/snapshots/%s (HDF5: %s)", x->path,
                              name, cd_export_h5_reason(why));
    }
    cd_export_write_attr(g, "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, 1, &x->step[k]);
    cd_export_write_attr(g, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, &x->time[k]);
    hsize_t uk = (hsize_t)k;
    /* 2-component columns into 3 (the third reads 0), 1 and 4 as they are */
    const int fields[] = {SNAP_POSITION, SNAP_VELOCITY, SNAP_VOLUME, SNAP_PLASTIC, SNAP_STRESS, SNAP_DEFG};
    int rc = 0;
    for (size_t i = 0; i < sizeof fields / sizeof fields[0] && !rc; i++) {
        const cd_export_field *fl = &m->f[fields[i]];
        hsize_t c = (hsize_t)fl->ncomp;
        rc = mpm_vds_row(x, g, fl->name, fl, uk, 0, c, c == 2 ? 3 : c == 1 ? 0 : c);
    }
    for (int c = 0; c < 4 && !rc; c++)
        rc = mpm_vds_row(x, g, stress_names[c], &m->f[SNAP_STRESS], uk, (hsize_t)c, 1, 0);
    if (!rc && x->P > 0) rc = mpm_vds_row(x, g, "wall_force", &m->f[SNAP_WALL_FORCE], uk, 0, 2, 3);
    if (!rc) rc = mpm_geometry(x, g, uk);
    H5Gclose(g);
    return rc;
}

int cd_export_mpm_helpers(cd_export_ctx *x)
{
    if (mpm_read(x) || mpm_open_viz(x) || mpm_fixed_helpers(x) || cd_export_snapshots_group(x)) return -1;
    for (int k = 0; k < x->S; k++)
        if (mpm_snapshot_helpers(x, k)) return -1;
    return 0;
}

/* ---- the .xmf ------------------------------------------------------------ */

/* An attribute on the points or walls: a helper of snapshot k (ncomp values a row). */
static void mpm_xml_snap_attr(FILE *o, const cd_export_ctx *x, int k, const char *name, const char *center,
                              hsize_t rows, int ncomp, const cd_export_field *like)
{
    char path[200];
    snprintf(path, sizeof path, "/visualization/snapshots/%d/%s", k, name);
    cd_export_field fl = *like;
    fl.ncomp = ncomp;
    cd_export_xml_attr(o, name, center, x->viz_ref, path, rows, &fl);
}

static void mpm_xml_points(FILE *o, const cd_export_ctx *x, int k)
{
    const struct cd_export_mpm *m = x->mpm;
    fprintf(o, "    <Grid Name=\"points\" GridType=\"Uniform\">\n");
    cd_export_xml_time(o, x, k);
    cd_export_xml_topology(o, x, "Polyvertex", 1, x->N, "/visualization/point_id");
    cd_export_xml_geometry(o, x, k, "position", x->N);
    cd_export_field id = {.ncomp = 1, .number_type = "Int", .precision = 4};
    cd_export_xml_attr(o, "point", "Node", x->viz_ref, "/visualization/point_id", x->N, &id);
    const int fixed[] = {POINT_PARTICLE, POINT_MASS};
    for (int i = 0; i < 2; i++)
        cd_export_xml_attr(o, m->f[fixed[i]].name, "Node", x->h5_ref, m->f[fixed[i]].src, x->N, &m->f[fixed[i]]);
    const int snap[] = {SNAP_VOLUME, SNAP_PLASTIC, SNAP_VELOCITY, SNAP_STRESS, SNAP_DEFG};
    for (int i = 0; i < 5; i++) {
        const cd_export_field *fl = &m->f[snap[i]];
        mpm_xml_snap_attr(o, x, k, fl->name, "Node", x->N, fl->ncomp == 2 ? 3 : fl->ncomp, fl);
    }
    for (int c = 0; c < 4; c++) mpm_xml_snap_attr(o, x, k, stress_names[c], "Node", x->N, 1, &m->f[SNAP_STRESS]);
    fprintf(o, "    </Grid>\n");
}

static void mpm_xml_walls(FILE *o, const cd_export_ctx *x, int k)
{
    const struct cd_export_mpm *m = x->mpm;
    fprintf(o, "    <Grid Name=\"walls\" GridType=\"Uniform\">\n");
    cd_export_xml_time(o, x, k);
    cd_export_xml_topology(o, x, "Polyline", 2, x->P, "/visualization/wall_cells");
    cd_export_xml_geometry(o, x, k, "wall_points", 2 * x->P);
    cd_export_field id = {.ncomp = 1, .number_type = "Int", .precision = 4};
    cd_export_xml_attr(o, "wall", "Cell", x->viz_ref, "/visualization/wall_id", x->P, &id);
    mpm_xml_snap_attr(o, x, k, "wall_force", "Cell", x->P, 3, &m->f[SNAP_WALL_FORCE]);
    cd_export_xml_attr(o, "normal", "Cell", x->h5_ref, m->f[WALL_NORMAL].src, x->P, &m->f[WALL_NORMAL]);
    cd_export_xml_attr(o, "wall_velocity", "Cell", x->h5_ref, m->f[WALL_VELOCITY].src, x->P, &m->f[WALL_VELOCITY]);
    fprintf(o, "    </Grid>\n");
}

static void mpm_xml_outlines(FILE *o, const cd_export_ctx *x, int k)
{
    char path[200];
    hsize_t B = x->mpm->outline[k];
    fprintf(o, "    <Grid Name=\"outlines\" GridType=\"Uniform\">\n");
    cd_export_xml_time(o, x, k);
    snprintf(path, sizeof path, "/visualization/snapshots/%d/outline_cells", k);
    cd_export_xml_topology(o, x, "Polyline", 2, B, path);
    cd_export_xml_geometry(o, x, k, "outline_points", B);
    cd_export_field id = {.ncomp = 1, .number_type = "Int", .precision = 4};
    snprintf(path, sizeof path, "/visualization/snapshots/%d/outline_particle", k);
    cd_export_xml_attr(o, "particle", "Cell", x->viz_ref, path, B, &id);
    fprintf(o, "    </Grid>\n");
}

static void mpm_grids(FILE *o, const cd_export_ctx *x)
{
    void (*grids[3])(FILE *, const cd_export_ctx *, int) = {mpm_xml_points, mpm_xml_walls, mpm_xml_outlines};
    const char *names[3] = {"points", "walls", "outlines"};
    for (int g = 0; g < 3; g++) {
        if (g == 1 && x->P == 0) continue; /* no walls: no empty grid (a zero-size item is an error to XDMF2) */
        fprintf(o, "  <Grid Name=\"%s\" GridType=\"Collection\" CollectionType=\"Temporal\">\n", names[g]);
        for (int k = 0; k < x->S; k++) grids[g](o, x, k);
        fprintf(o, "  </Grid>\n");
    }
}

int cd_export_mpm_write_xml(cd_export_ctx *x, const char *out)
{
    char comment[1024];
    snprintf(comment, sizeof comment,
             " (solver mpm): %d snapshots, %llu material points, %llu walls.\n"
             "     Three temporal collections: points (vertices with the points' columns), walls (lines) and\n"
             "     outlines (each particle's convex outline, as `capdem analyze` measures its curvature).\n"
             "     Data items point into the run file or into its /visualization helpers.\n"
             "     ParaView: any of its XDMF readers; docs/visualization.md. -->\n",
             x->S, (unsigned long long)x->N, (unsigned long long)x->P);
    return cd_export_write_xml_with(x, out, comment, mpm_grids);
}
