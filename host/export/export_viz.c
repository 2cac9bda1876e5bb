/* capdem export, the helper datasets under /visualization: connectivity,
 * and virtual datasets that select one snapshot of the run's datasets
 * (layout at the top of export_xdmf.c; export_internal.h). */
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <hdf5.h>
#include "export/export_internal.h"
#include "io/io_h5_layout.h"
#include "io/io_h5_check.h"

/* ---- helper datasets ---------------------------------------------------- */

/* Copies the string attribute `unit` (docs/output.md: every numeric dataset
 * carries one) from the source dataset, so the helpers follow the convention. */
static void cd_export_copy_unit(cd_export_ctx *x, const char *src, hid_t dst)
{
    hid_t d = H5Dopen2(x->f, src, H5P_DEFAULT);
    if (d < 0) return;
    if (H5Aexists(d, "unit") > 0 && H5Aexists(dst, "unit") <= 0) {
        hid_t a = H5Aopen(d, "unit", H5P_DEFAULT), t = H5Aget_type(a);
        char why[8];
        int one = cd_h5_check_string(a, 1, x->path, "unit", 256, why, sizeof why) == 0; /* else not copied */
        size_t n = H5Tget_size(t);
        char *buf = one ? calloc(n + 1, 1) : NULL;
        if (buf && H5Tget_class(t) == H5T_STRING && !H5Tis_variable_str(t) && H5Aread(a, t, buf) >= 0) {
            hid_t s = H5Screate(H5S_SCALAR), b = H5Acreate2(dst, "unit", t, s, H5P_DEFAULT, H5P_DEFAULT);
            if (b >= 0) {
                H5Awrite(b, t, buf);
                H5Aclose(b);
            }
            H5Sclose(s);
        }
        free(buf);
        H5Tclose(t);
        H5Aclose(a);
    }
    H5Dclose(d);
}

/* Opens parent/name when it is a dataset of the given layout and shape;
 * otherwise removes whatever is there and returns 0 (the caller creates it). */
hid_t cd_export_reuse(hid_t parent, const char *name, H5D_layout_t layout, int rank, const hsize_t *dims)
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

int cd_export_vds(cd_export_ctx *x, hid_t parent, const char *name, int rank, const hsize_t *dims, int nblock,
                  const cd_export_block *blocks)
{
    hid_t d = cd_export_reuse(parent, name, H5D_VIRTUAL, rank, dims);
    if (d > 0) {
        H5Dclose(d);
        return 0;
    }
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
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot create the virtual dataset %s over %s (HDF5: %s)", x->path,
                              name, blocks[0].src->src, cd_export_h5_reason(why));
    }
    cd_export_copy_unit(x, blocks[0].src->src, d);
    H5Dclose(d);
    return 0;
}

/* Writes a real helper dataset of file type ftype (created, or overwritten in
 * place when one of the same shape is there: a resume may have changed its
 * values); its unit attribute is unit ("1" for ids).  0, or -1 with x failed. */
static int cd_export_data(cd_export_ctx *x, hid_t parent, const char *name, int rank, const hsize_t *dims, hid_t ftype,
                          hid_t mtype, const void *v, const char *unit)
{
    hid_t d = cd_export_reuse(parent, name, H5D_CONTIGUOUS, rank, dims);
    if (d == 0) {
        hid_t sp = H5Screate_simple(rank, dims, NULL);
        d = H5Dcreate2(parent, name, ftype, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        H5Sclose(sp);
    }
    hsize_t n = 1;
    for (int i = 0; i < rank; i++) n *= dims[i];
    if (d < 0 || (n > 0 && H5Dwrite(d, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0)) {
        char why[256];
        if (d >= 0) H5Dclose(d);
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot write /visualization/.../%s (HDF5: %s)", x->path, name,
                              cd_export_h5_reason(why));
    }
    if (H5Aexists(d, "unit") <= 0) {
        hid_t t = H5Tcopy(H5T_C_S1);
        H5Tset_size(t, strlen(unit) + 1);
        H5Tset_strpad(t, H5T_STR_NULLTERM);
        hid_t sp = H5Screate(H5S_SCALAR), a = H5Acreate2(d, "unit", t, sp, H5P_DEFAULT, H5P_DEFAULT);
        if (a >= 0) {
            H5Awrite(a, t, unit);
            H5Aclose(a);
        }
        H5Sclose(sp);
        H5Tclose(t);
    }
    H5Dclose(d);
    return 0;
}

int cd_export_ints(cd_export_ctx *x, hid_t parent, const char *name, int rank, const hsize_t *dims, const int *v)
{
    return cd_export_data(x, parent, name, rank, dims, H5T_STD_I32LE, H5T_NATIVE_INT, v, "1");
}

int cd_export_doubles(cd_export_ctx *x, hid_t parent, const char *name, int rank, const hsize_t *dims, const double *v,
                      const char *unit)
{
    return cd_export_data(x, parent, name, rank, dims, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v, unit);
}

int cd_export_read_attr_ll(hid_t loc, const char *name, long long *v, int n)
{
    if (H5Aexists(loc, name) <= 0) return -1;
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT), sp = H5Aget_space(a);
    int ok = H5Sget_simple_extent_npoints(sp) == n && H5Aread(a, H5T_NATIVE_LLONG, v) >= 0;
    H5Sclose(sp);
    H5Aclose(a);
    return ok ? 0 : -1;
}

void cd_export_write_attr(hid_t loc, const char *name, hid_t ftype, hid_t mtype, int n, const void *v)
{
    if (H5Aexists(loc, name) > 0) H5Adelete(loc, name);
    hsize_t dim = (hsize_t)n;
    hid_t sp = n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &dim, NULL);
    hid_t a = H5Acreate2(loc, name, ftype, sp, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) {
        H5Awrite(a, mtype, v);
        H5Aclose(a);
    }
    H5Sclose(sp);
}

int cd_export_open_viz_with(cd_export_ctx *x, int n, const char *const *names, const long long *want,
                            const char *solver, const char *about)
{
    if (H5Lexists(x->vf, "visualization", H5P_DEFAULT) > 0) {
        hid_t g = H5Gopen2(x->vf, "visualization", H5P_DEFAULT);
        int same = g >= 0;
        long long have;
        for (int i = 0; i < n && same; i++) same = !cd_export_read_attr_ll(g, names[i], &have, 1) && have == want[i];
        if (same) {
            x->viz = g;
            return 0;
        }
        if (g >= 0) H5Gclose(g);
        H5Ldelete(x->vf, "visualization", H5P_DEFAULT);
    }
    x->viz = H5Gcreate2(x->vf, "visualization", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (x->viz < 0) {
        char why[256];
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot create /visualization (HDF5: %s)", x->path,
                              cd_export_h5_reason(why));
    }
    for (int i = 0; i < n; i++) cd_export_write_attr(x->viz, names[i], H5T_STD_I64LE, H5T_NATIVE_LLONG, 1, &want[i]);
    const char *text[2][2] = {{"solver", solver}, {"about", about}};
    for (int i = solver ? 0 : 1; i < 2; i++) {
        hid_t t = H5Tcopy(H5T_C_S1);
        H5Tset_size(t, strlen(text[i][1]) + 1);
        cd_export_write_attr(x->viz, text[i][0], t, t, 1, text[i][1]);
        H5Tclose(t);
    }
    return 0;
}

/* /visualization of a DEM run: for this layout version and these particle
 * and primitive counts. */
static int cd_export_open_viz(cd_export_ctx *x)
{
    const char *names[3] = {"layout", "n_particles", "n_prims"};
    long long want[3] = {CD_EXPORT_LAYOUT, (long long)x->N, (long long)x->P};
    return cd_export_open_viz_with(
        x, 3, names, want, NULL,
        "helper datasets of `capdem export` (docs/visualization.md): connectivity, and virtual datasets "
        "selecting one snapshot of the run's datasets; safe to delete");
}

/* The helpers shared by every snapshot. */
static int cd_export_fixed_helpers(cd_export_ctx *x)
{
    /* ids are ints: counts past INT_MAX (a crafted extent) are refused */
    if (x->N > INT_MAX || x->P > INT_MAX / 2)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT,
                              "%s: %llu particles, %llu primitives: more than ids can name; "
                              "the file is refused",
                              x->path, (unsigned long long)x->N, (unsigned long long)x->P);
    hsize_t n = x->N > 2 * x->P ? x->N : 2 * x->P;
    size_t vb;
    if (cd_h5_mul(&vb, (size_t)(n > 0 ? n : 1), sizeof(int), 1))
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: helper sizes overflow; the file is refused", x->path);
    int *v = malloc(vb);
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
    size_t ijb, colb;
    if (cd_h5_mul(&ijb, (size_t)C, 2, sizeof(int)) || cd_h5_mul(&colb, (size_t)C, sizeof(int), 1) ||
        C > (hsize_t)SIZE_MAX)
        return cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: %s: %llu contact rows overflow a size; the file is refused",
                              x->path, CDH5_PATH(C_OFFSET), (unsigned long long)C);
    int *ij = malloc(ijb), *col = malloc(colb);
    if (!ij || !col) {
        free(ij);
        free(col);
        return cd_export_fail(x, CD_EXPORT_FAIL, "out of memory");
    }
    const char *names[2] = {CDH5_PATH(C_PARTICLE_I), CDH5_PATH(C_PARTICLE_J)};
    int rc = 0;
    for (int e = 0; e < 2 && !rc; e++) {
        hid_t d = H5Dopen2(x->f, names[e], H5P_DEFAULT);
        if (d < 0) {
            rc = cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: missing %s", x->path, names[e]);
            break;
        }
        if (cdh5_read_rows(d, (hsize_t)c0, C, H5T_NATIVE_INT, col) < 0)
            rc = cd_export_fail(x, CD_EXPORT_BAD_INPUT, "%s: cannot read rows %lld..%lld of %s", x->path, c0, c1 - 1,
                                names[e]);
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
        return cd_export_fail(x, CD_EXPORT_FAIL, "%s: cannot create /visualization/snapshots/%s (HDF5: %s)", x->path,
                              name, cd_export_h5_reason(why));
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

int cd_export_snapshots_group(cd_export_ctx *x)
{
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
        char(*stale)[64] = calloc(gi.nlinks, sizeof *stale);
        hsize_t nstale = 0;
        for (hsize_t i = 0; stale && i < gi.nlinks; i++) {
            char name[64], *end;
            if (H5Lget_name_by_idx(snaps, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT) < 0)
                continue;
            long k = strtol(name, &end, 10);
            if (end == name || *end || k < 0 || k >= x->S) snprintf(stale[nstale++], 64, "%s", name);
        }
        for (hsize_t i = 0; i < nstale; i++) H5Ldelete(snaps, stale[i], H5P_DEFAULT);
        free(stale);
    }
    if (snaps >= 0) H5Gclose(snaps);
    return 0;
}

int cd_export_helpers(cd_export_ctx *x)
{
    if (cd_export_open_viz(x) || cd_export_fixed_helpers(x) || cd_export_snapshots_group(x)) return -1;
    for (int k = 0; k < x->S; k++)
        if (cd_export_snapshot_helpers(x, k)) return -1;
    return 0;
}
