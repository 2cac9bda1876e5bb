/* `capdem analyze` of a diametral mpm run (set-up diametral, docs/mpm.md
 * "Diametral compression of one disk"): the measures of the paper's Fig. 1.
 *
 * Series (every thermo_every steps): the strain eps_yy = (D - gap) / D of
 * the gap between the bottom (0) and top (1) walls, D the gap at row 0,
 * and F/D, the walls' forces over the diameter [Pa] (each wall's, and
 * their mean: the two differ by the ringing of the undamped disk).
 * Snapshots: -<sigma_yy>, the volume average of the points' stress [Pa]
 * (the mean-stress theorem makes it F (gap - l) / V), and the plastic area
 * fraction (points with plastic strain > 0). */
#include "analysis/analyze.h"
#include <hdf5.h>
#include "io/io_h5_layout.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cd_an_mpm_is_disk(const char *path)
{
    char err[256];
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    hid_t f = cdh5_open_ro(path, err, sizeof err);
    int disk = f >= 0 && !cdh5_exists(f, "/mpm/series/packing_fraction") && cdh5_exists(f, "/mpm/series/wall_force") &&
               cdh5_exists(f, "/mpm/walls/normal");
    if (disk) { /* two walls */
        hid_t d = H5Dopen2(f, "/mpm/walls/normal", H5P_DEFAULT);
        hsize_t dims[3] = {0, 0, 0};
        disk = d >= 0 && cdh5_dims(d, dims) == 2 && dims[0] == 2 && dims[1] == 2;
        if (d >= 0) H5Dclose(d);
    }
    if (f >= 0) H5Fclose(f);
    cdh5_quiet_end(&q);
    return disk;
}

/* The rows of a dataset's first dimension (0 when missing). */
static size_t rows_of(hid_t f, const char *name)
{
    hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
    hsize_t dims[3] = {0, 0, 0};
    if (d < 0) return 0;
    int rank = cdh5_dims(d, dims);
    H5Dclose(d);
    return rank >= 1 ? (size_t)dims[0] : 0;
}

int cd_an_mpm_disk(const char *path, const cd_an_options *opt, cd_an_report *r, char *err, size_t errlen)
{
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    int rc = 2;
    double *step = NULL, *wpos = NULL, *wf = NULL, *sstep = NULL, *stime = NULL, *vol = NULL, *str = NULL, *ep = NULL;
    hid_t f = cdh5_open_ro(path, err, errlen);
    if (f < 0) goto done;
    long long snaps = 0; /* the snapshots completely on disk */
    hid_t a = H5Aexists(f, "n_snapshots") > 0 ? H5Aopen(f, "n_snapshots", H5P_DEFAULT) : -1;
    if (a >= 0) {
        if (H5Aread(a, H5T_NATIVE_LLONG, &snaps) < 0) snaps = 0;
        H5Aclose(a);
    }
    size_t R = rows_of(f, "/mpm/series/step"), n = rows_of(f, "/mpm/points/mass"), S = snaps > 0 ? (size_t)snaps : 0;
    if (R < 2 || n < 1 || S < 1) {
        snprintf(err, errlen, "%s: a diametral mpm run with fewer than 2 series rows or no committed snapshot", path);
        goto done;
    }
    if (!(step = cd_an_mpm_read_rows(f, path, "/mpm/series/step", R, 1, err, errlen)) ||
        !(wpos = cd_an_mpm_read_rows(f, path, "/mpm/series/wall_position", R, 4, err, errlen)) ||
        !(wf = cd_an_mpm_read_rows(f, path, "/mpm/series/wall_force", R, 4, err, errlen)) ||
        !(sstep = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/step", S, 1, err, errlen)) ||
        !(stime = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/time", S, 1, err, errlen)) ||
        !(vol = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/volume", S, n, err, errlen)) ||
        !(str = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/stress", S, 4 * n, err, errlen)) ||
        !(ep = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/plastic_strain", S, n, err, errlen)))
        goto done;
    int k = opt->snapshot < 0 ? (int)S + opt->snapshot : opt->snapshot;
    if (k < 0 || k >= (int)S) {
        snprintf(err, errlen, "%s: snapshot %d: the file has %zu committed snapshots (0..%zu)", path, opt->snapshot, S,
                 S - 1);
        goto done;
    }
    rc = 1;
    r->snapshot = k;
    r->n_snapshots = (int)S;
    r->step = (long long)sstep[k];
    r->time = stime[k];
    cd_an_group *g = cd_an_group_get(r, "mpm_disk");
    double D = wpos[3] - wpos[1]; /* the gap at row 0: the disk's diameter [m] */
    cd_an_put(g, "diameter", D, "m");
    /* the series: rows x (step, eps_yy, F/D bottom, F/D top, F/D) */
    double *c = cd_an_put_curve(g, "curve", R, "step,strain,f_over_d_bottom,f_over_d_top,f_over_d", "1,1,Pa,Pa,Pa");
    if (!c) goto oom;
    for (size_t i = 0; i < R; i++) {
        double gap = wpos[4 * i + 3] - wpos[4 * i + 1];
        double fb = -wf[4 * i + 1] / D, ft = wf[4 * i + 3] / D; /* the material pushes the bottom wall down [Pa] */
        double row[5] = {step[i], (D - gap) / D, fb, ft, 0.5 * (fb + ft)};
        memcpy(c + 5 * i, row, sizeof row);
    }
    cd_an_put(g, "strain", c[5 * (R - 1) + 1], "1");
    cd_an_put(g, "f_over_d", c[5 * (R - 1) + 4], "Pa");
    /* the snapshots: the volume-mean stress and the plastic area fraction */
    double *t = cd_an_put_curve(g, "snapshots", S, "step,mean_sigma_yy,plastic_fraction", "1,Pa,1");
    if (!t) goto oom;
    for (size_t s = 0; s < S; s++) {
        double v = 0, vs = 0, vp = 0; /* [m^2/m], [N], [m^2/m] */
        for (size_t p = 0; p < n; p++) {
            double V = vol[n * s + p];
            v += V;
            vs += V * str[4 * n * s + 4 * p + 1];
            if (ep[n * s + p] > 0) vp += V;
        }
        double row[3] = {sstep[s], -vs / v, vp / v};
        memcpy(t + 3 * s, row, sizeof row);
        if ((int)s == k) {
            cd_an_put(g, "snapshot_mean_sigma_yy", -vs / v, "Pa");
            cd_an_put(g, "snapshot_plastic_fraction", vp / v, "1");
        }
    }
    rc = 0;
    goto done;
oom:
    snprintf(err, errlen, "out of memory");
done:
    if (f >= 0) H5Fclose(f);
    cdh5_quiet_end(&q);
    free(step);
    free(wpos);
    free(wf);
    free(sstep);
    free(stime);
    free(vol);
    free(str);
    free(ep);
    return rc;
}
