/* The packing of the mpm set-up `packing` (docs/mpm.md): the disks of a
 * capdem DEM run file, read from the file itself (its last committed
 * snapshot), so that the material point method starts from a packing the
 * DEM solver made.  Reads only what docs/output.md fixes: the root
 * attribute n_snapshots, /particles/all/position/value,
 * /particles/all/prim_count, /particles/prims/prim_radius and the
 * primitives' body-frame ends (a sphere is one primitive of zero length). */
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "io/io_h5_check.h"
#include "io/io_h5_journal.h"
#include "mpm/mpm_packing.h"

/* Reads row `row` of the (S, n, 3) dataset `name` as doubles into buf. */
static int read_row3(hid_t f, const char *name, long long row, long long n, double *buf)
{
    hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
    if (d < 0) return -1;
    hid_t fs = H5Dget_space(d);
    hsize_t start[3] = {(hsize_t)row, 0, 0}, count[3] = {1, (hsize_t)n, 3};
    hid_t ms = H5Screate_simple(3, count, NULL);
    int rc = H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) >= 0 &&
                     cdh5_storage_fits(d, (hsize_t)row, 1) &&
                     H5Dread(d, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, buf) >= 0
                 ? 0
                 : -1;
    H5Sclose(ms);
    H5Sclose(fs);
    H5Dclose(d);
    return rc;
}

/* Reads the whole dataset `name` as doubles (or ints when ints != NULL)
 * after checking its rank and dimensions (dims[k] < 0: any, returned). */
static int read_all(hid_t f, const char *name, int rank, long long *dims, double *dbl, int *ints)
{
    hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
    if (d < 0) return -1;
    hid_t sp = H5Dget_space(d);
    hsize_t got[4] = {0, 0, 0, 0};
    int ok = H5Sget_simple_extent_ndims(sp) == rank && rank <= 4;
    if (ok) H5Sget_simple_extent_dims(sp, got, NULL);
    for (int k = 0; ok && k < rank; k++) {
        if (dims[k] >= 0 && (long long)got[k] != dims[k]) ok = 0;
        dims[k] = (long long)got[k];
    }
    if (ok && (dbl || ints))
        ok = cdh5_storage_fits(d, 0, HSIZE_UNDEF) &&
             H5Dread(d, dbl ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                     dbl ? (void *)dbl : (void *)ints) >= 0;
    H5Sclose(sp);
    H5Dclose(d);
    return ok ? 0 : -1;
}

int cd_mpm_read_packing(const char *path, const char *key_where, cd_mpm_packing *pk, char *err, size_t errlen)
{
    memset(pk, 0, sizeof *pk);
    hid_t f = -1;
    int rc = -1;
    double *pos = NULL, *ends = NULL;
    int *count = NULL;
    H5E_BEGIN_TRY
    {
        hid_t fapl = cdh5_fapl(); /* replays a killed run's journal in memory */
        f = H5Fopen(path, H5F_ACC_RDONLY, fapl);
        H5Pclose(fapl);
        long long committed = 0, dims[3] = {-1, -1, 3}, n, np;
        if (f < 0) {
            snprintf(err, errlen,
                     "%s: mpm.packing = %s: cannot open it as an HDF5 file; expected a capdem run file of a 2D "
                     "deposit of spheres",
                     key_where, path);
            goto out;
        }
        hid_t a = H5Aexists(f, "n_snapshots") > 0 ? H5Aopen(f, "n_snapshots", H5P_DEFAULT) : -1;
        if (a >= 0) {
            if (H5Aread(a, H5T_NATIVE_LLONG, &committed) < 0) committed = 0;
            H5Aclose(a);
        }
        if (read_all(f, "/particles/all/position/value", 3, dims, NULL, NULL) || committed < 1 || committed > dims[0]) {
            snprintf(err, errlen,
                     "%s: mpm.packing = %s: no committed snapshot of particle positions (root attribute "
                     "n_snapshots, /particles/all/position/value); expected a capdem DEM run file",
                     key_where, path);
            goto out;
        }
        n = dims[1];
        long long d1[1] = {n}, dp[1] = {-1}, de[2] = {-1, 3};
        pos = malloc((size_t)(n * 3 + 1) * sizeof(double));
        count = malloc((size_t)(n + 1) * sizeof(int));
        if (!pos || !count || read_row3(f, "/particles/all/position/value", committed - 1, n, pos) ||
            read_all(f, "/particles/all/prim_count", 1, d1, NULL, count) ||
            read_all(f, "/particles/prims/prim_radius", 1, dp, NULL, NULL)) {
            snprintf(err, errlen, "%s: mpm.packing = %s: cannot read the particles' positions and primitives",
                     key_where, path);
            goto out;
        }
        np = dp[0];
        for (long long i = 0; i < n; i++)
            if (count[i] != 1 || np != n) {
                snprintf(err, errlen,
                         "%s: mpm.packing = %s: particle %lld has %d primitives; expected spheres (one "
                         "primitive each)",
                         key_where, path, i, count[i]);
                goto out;
            }
        pk->r = malloc((size_t)n * sizeof(double));
        pk->x = malloc((size_t)n * sizeof(double));
        pk->y = malloc((size_t)n * sizeof(double));
        ends = malloc((size_t)(2 * n * 3) * sizeof(double));
        de[0] = n;
        if (!pk->r || !pk->x || !pk->y || !ends || read_all(f, "/particles/prims/prim_radius", 1, dp, pk->r, NULL) ||
            read_all(f, "/particles/prims/prim_a_body", 2, de, ends, NULL) ||
            read_all(f, "/particles/prims/prim_b_body", 2, de, ends + 3 * n, NULL)) {
            snprintf(err, errlen, "%s: mpm.packing = %s: cannot read the primitives' radii and ends", key_where, path);
            goto out;
        }
        const double *last = pos;
        for (long long i = 0; i < n; i++) {
            double len = 0;
            for (int k = 0; k < 3; k++) len += fabs(ends[3 * i + k] - ends[3 * (n + i) + k]);
            if (len != 0 || !(pk->r[i] > 0)) {
                snprintf(err, errlen,
                         "%s: mpm.packing = %s: particle %lld is not a sphere (its primitive has length or "
                         "no radius); expected a deposit of spheres",
                         key_where, path, i);
                goto out;
            }
            if (last[3 * i + 2] != last[2]) {
                snprintf(err, errlen,
                         "%s: mpm.packing = %s: particle %lld is at z = %g m, particle 0 at z = %g m; expected "
                         "a 2D run (physics.dimension: 2, every centre in one plane)",
                         key_where, path, i, last[3 * i + 2], last[2]);
                goto out;
            }
            pk->x[i] = last[3 * i];
            pk->y[i] = last[3 * i + 1];
        }
        pk->n = (size_t)n;
        pk->snapshot = committed - 1;
        rc = 0;
    out:
        if (f >= 0) H5Fclose(f);
    }
    H5E_END_TRY
    free(pos);
    free(ends);
    free(count);
    if (rc) cd_mpm_packing_free(pk);
    return rc;
}

void cd_mpm_packing_free(cd_mpm_packing *pk)
{
    free(pk->x);
    free(pk->y);
    free(pk->r);
    memset(pk, 0, sizeof *pk);
}
