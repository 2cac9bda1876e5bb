/* `capdem analyze` of a run file of the material point method (solver mpm,
 * docs/mpm.md "Analysis"): the compaction measures of Nezamabadi et al.
 * 2022 (the paper) from the run's series and snapshots, and the fits of its
 * eqs. (5), (11) and (17); those of eqs. (6)-(16) in analyze_mpm_models.c.
 *
 * Series (every thermo_every steps): packing fraction Phi, applied stress
 * sigma [Pa], strain ln(h_i/h) (compression positive: the paper's
 * eps = ln(h/h_i) with its sign turned, as in the run file), coordination
 * number Z.  Snapshots: Phi, the plastic volume fraction f_p (the volume of
 * the points with plastic strain > 0 over the solid volume) and the mean
 * maximum boundary curvature kappa times the mean initial diameter <d>. */
#include "analysis/analyze.h"
#include <hdf5.h>
#include "io/io_h5_layout.h"
#include "io/io_h5.h"
#include "config/config.h"
#include <gsl/gsl_cdf.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cd_an_fit_line(const double *x, const double *y, size_t n, cd_an_linfit *out)
{
    memset(out, 0, sizeof(*out));
    out->n = n;
    if (n < 3) return -1;
    double mx = 0, my = 0;
    for (size_t i = 0; i < n; i++) {
        mx += x[i];
        my += y[i];
    }
    mx /= (double)n;
    my /= (double)n;
    double sxx = 0, sxy = 0;
    for (size_t i = 0; i < n; i++) {
        sxx += (x[i] - mx) * (x[i] - mx);
        sxy += (x[i] - mx) * (y[i] - my);
    }
    if (!(sxx > 0)) return -1;
    out->slope = sxy / sxx;
    out->intercept = my - out->slope * mx;
    double ss = 0;
    for (size_t i = 0; i < n; i++) {
        double r = y[i] - out->intercept - out->slope * x[i];
        ss += r * r;
    }
    out->dof = (int)(n - 2);
    out->se = sqrt(ss / out->dof / sxx);
    double t = gsl_cdf_tdist_Pinv(0.975, out->dof);
    out->lo = out->slope - t * out->se;
    out->hi = out->slope + t * out->se;
    double se0 = sqrt(ss / out->dof * (1.0 / (double)n + mx * mx / sxx)); /* the intercept's */
    out->intercept_lo = out->intercept - t * se0;
    out->intercept_hi = out->intercept + t * se0;
    return 0;
}

static int cmp_xy(const void *a, const void *b)
{
    const double *p = a, *q = b;
    if (p[0] != q[0]) return p[0] < q[0] ? -1 : 1;
    return (p[1] > q[1]) - (p[1] < q[1]);
}

static double cross(const double *o, const double *a, const double *b)
{
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

size_t cd_an_convex_hull(double *xy, size_t n, double *hull)
{
    if (n == 0) return 0;
    /* Andrew's monotone chain, counter-clockwise; hull needs room for 2 n + 2 points */
    qsort(xy, n, 2 * sizeof(double), cmp_xy);
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        while (m >= 2 && cross(hull + 2 * (m - 2), hull + 2 * (m - 1), xy + 2 * i) <= 0) m--;
        memcpy(hull + 2 * m++, xy + 2 * i, 2 * sizeof(double));
    }
    for (size_t i = n - 1, lower = m + 1; i-- > 0;) {
        while (m >= lower && cross(hull + 2 * (m - 2), hull + 2 * (m - 1), xy + 2 * i) <= 0) m--;
        memcpy(hull + 2 * m++, xy + 2 * i, 2 * sizeof(double));
    }
    return m > 1 ? m - 1 : m; /* the last point repeats the first */
}

double cd_an_mpm_corners(const double *x, const double *v, const double *F, size_t a, size_t b, double *xy)
{
    double a0 = 0; /* initial area [m^2/m] */
    for (size_t p = a; p < b; p++) {
        const double *f = F + 4 * p; /* xx, xy, yx, yy */
        double J = f[0] * f[3] - f[1] * f[2], l = sqrt(v[p] / J), s = 0.5 * l;
        a0 += v[p] / J;
        static const double cx[4] = {-1, 1, 1, -1}, cy[4] = {-1, -1, 1, 1};
        for (int c = 0; c < 4; c++) {
            xy[2 * (4 * (p - a) + (size_t)c)] = x[2 * p] + s * (f[0] * cx[c] + f[1] * cy[c]);
            xy[2 * (4 * (p - a) + (size_t)c) + 1] = x[2 * p + 1] + s * (f[2] * cx[c] + f[3] * cy[c]);
        }
    }
    return a0;
}

double cd_an_max_boundary_curvature(double *xy, size_t n, double scale)
{
    if (n < 3 || !(scale > 0)) return NAN;
    double *hull = malloc((2 * n + 2) * 2 * sizeof(double)), *arc = malloc((2 * n + 2) * 2 * sizeof(double));
    if (!hull || !arc) {
        free(hull);
        free(arc);
        return NAN;
    }
    double *turn = arc + 2 * n + 2;
    size_t m = cd_an_convex_hull(xy, n, hull);
    double kmax = NAN;
    if (m >= 3) {
        /* exterior angle (turning of the tangent) at each vertex [rad] and arc length to it [m] */
        arc[0] = 0;
        for (size_t i = 0; i < m; i++) {
            const double *a = hull + 2 * ((i + m - 1) % m), *v = hull + 2 * i, *b = hull + 2 * ((i + 1) % m);
            double t = atan2(cross(a, v, b), (v[0] - a[0]) * (b[0] - v[0]) + (v[1] - a[1]) * (b[1] - v[1]));
            turn[i] = t;
            arc[i + 1] = arc[i] + hypot(b[0] - v[0], b[1] - v[1]);
        }
        /* the largest turning within an arc of 2 scale, over that arc: the windows that start at a vertex */
        if (arc[m] > 4 * scale) {
            kmax = 0;
            for (size_t i = 0; i < m; i++) {
                double t = 0;
                for (size_t j = 0; j < m; j++) {
                    double ds = arc[(i + j) % m] - arc[i];
                    if (ds < 0) ds += arc[m];
                    if (ds >= 2 * scale) break;
                    t += turn[(i + j) % m];
                }
                if (t / (2 * scale) > kmax) kmax = t / (2 * scale);
            }
        }
    }
    free(hull);
    free(arc);
    return kmax;
}

double *cd_an_mpm_read_rows(hid_t f, const char *path, const char *name, size_t rows, size_t per_row, char *err,
                            size_t errlen)
{
    hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
    hsize_t dims[3] = {1, 1, 1};
    int rank = d >= 0 ? cdh5_dims(d, dims) : -1;
    size_t have = rank == 1 ? 1 : rank == 2 ? (size_t)dims[1] : rank == 3 ? (size_t)dims[1] * (size_t)dims[2] : 0;
    double *buf = NULL;
    if (d < 0 || rank < 1 || dims[0] < rows || have != per_row ||
        !(buf = malloc((rows ? rows : 1) * per_row * sizeof(double))) ||
        (rows && cdh5_read_rows(d, 0, rows, H5T_NATIVE_DOUBLE, buf) < 0)) {
        snprintf(err, errlen, "%s: %s missing, or not %zu rows of %zu values", path, name, rows, per_row);
        free(buf);
        buf = NULL;
    }
    if (d >= 0) H5Dclose(d);
    return buf;
}

/* Everything the measures read from the run file. */
typedef struct {
    size_t rows, n, snaps;                   /* series rows, points, committed snapshots */
    double *step, *phi, *sigma, *strain, *z; /* series */
    double *wall0;                           /* series row 0's wall positions (walls x 2) [m] */
    int *particle;                           /* (n) */
    double *sstep, *stime;                   /* snapshots: step, time [s] */
    double *pos, *vol, *eps_p, *defg;        /* snapshots: (S, n, 2) [m], (S, n) [m^3/m], (S, n), (S, n, 4) */
    double *swall;                           /* snapshots' wall positions (S, 4, 2) [m] */
    int material_ok, plastic;                /* the echoed config parsed; its model von_mises */
    cd_an_mpm_model material;                /* E, nu, sigma_y, H of the config */
} mpm_data;

static void data_free(mpm_data *d)
{
    void *p[] = {d->step,  d->phi, d->sigma, d->strain, d->z,    d->wall0, d->sstep,
                 d->stime, d->pos, d->vol,   d->eps_p,  d->defg, d->swall};
    for (size_t i = 0; i < sizeof p / sizeof p[0]; i++) free(p[i]);
    free(d->particle);
    memset(d, 0, sizeof(*d));
}

static int data_read(const char *path, mpm_data *d, char *err, size_t errlen)
{
    memset(d, 0, sizeof(*d));
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    int rc = 2;
    hid_t f = cdh5_open_ro(path, err, errlen);
    if (f < 0) goto done;
    hsize_t dims[3];
    hid_t ds = H5Dopen2(f, "/mpm/series/packing_fraction", H5P_DEFAULT),
          dp = H5Dopen2(f, "/mpm/points/particle", H5P_DEFAULT);
    if (ds < 0 || dp < 0) {
        snprintf(err, errlen,
                 "%s: no /mpm/series/packing_fraction or /mpm/points/particle: not a packing run of solver mpm "
                 "(mpm.setup: packing)",
                 path);
        if (ds >= 0) H5Dclose(ds);
        if (dp >= 0) H5Dclose(dp);
        goto done;
    }
    cdh5_dims(ds, dims);
    d->rows = (size_t)dims[0];
    cdh5_dims(dp, dims);
    d->n = (size_t)dims[0];
    H5Dclose(ds);
    d->particle = malloc((d->n ? d->n : 1) * sizeof(int));
    if (!d->particle || (d->n && cdh5_read_rows(dp, 0, d->n, H5T_NATIVE_INT, d->particle) < 0)) {
        snprintf(err, errlen, "%s: /mpm/points/particle unreadable", path);
        H5Dclose(dp);
        goto done;
    }
    H5Dclose(dp);
    long long snaps = 0; /* the snapshots completely on disk (root attribute n_snapshots) */
    hid_t a = H5Aexists(f, "n_snapshots") > 0 ? H5Aopen(f, "n_snapshots", H5P_DEFAULT) : -1;
    if (a >= 0) {
        if (H5Aread(a, H5T_NATIVE_LLONG, &snaps) < 0) snaps = 0;
        H5Aclose(a);
    }
    if (snaps < 1 || d->rows < 1 || d->n < 1) {
        snprintf(err, errlen, "%s: no committed snapshot or no series row", path);
        goto done;
    }
    d->snaps = (size_t)snaps;
    size_t R = d->rows, S = d->snaps, n = d->n;
    if (!(d->step = cd_an_mpm_read_rows(f, path, "/mpm/series/step", R, 1, err, errlen)) ||
        !(d->phi = cd_an_mpm_read_rows(f, path, "/mpm/series/packing_fraction", R, 1, err, errlen)) ||
        !(d->sigma = cd_an_mpm_read_rows(f, path, "/mpm/series/stress", R, 1, err, errlen)) ||
        !(d->strain = cd_an_mpm_read_rows(f, path, "/mpm/series/strain", R, 1, err, errlen)) ||
        !(d->z = cd_an_mpm_read_rows(f, path, "/mpm/series/coordination", R, 1, err, errlen)) ||
        !(d->wall0 = cd_an_mpm_read_rows(f, path, "/mpm/series/wall_position", 1, 8, err, errlen)) ||
        !(d->sstep = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/step", S, 1, err, errlen)) ||
        !(d->stime = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/time", S, 1, err, errlen)) ||
        !(d->pos = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/position", S, 2 * n, err, errlen)) ||
        !(d->vol = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/volume", S, n, err, errlen)) ||
        !(d->eps_p = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/plastic_strain", S, n, err, errlen)) ||
        !(d->defg = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/deformation_gradient", S, 4 * n, err, errlen)) ||
        !(d->swall = cd_an_mpm_read_rows(f, path, "/mpm/snapshots/wall_position", S, 8, err, errlen)))
        goto done;
    rc = 0;
done:
    if (f >= 0) H5Fclose(f);
    cdh5_quiet_end(&q);
    if (rc == 0) { /* the material, from the config echoed in the file (the models of eqs. (6)-(16)) */
        char cerr[512];
        char *text = cd_h5_read_config_text(path, cerr, sizeof cerr);
        cd_config c;
        cd_config_defaults(&c);
        if (text && cd_config_parse(text, path, &c, cerr, sizeof cerr) == 0 && c.solver == 1) { /* mpm */
            d->material_ok = 1;
            d->plastic = c.mpm_model == 1;
            d->material.E = c.mpm_young;
            d->material.nu = c.mpm_poisson;
            d->material.sigma_y = d->plastic ? c.mpm_yield : 0;
            d->material.H = d->plastic ? c.mpm_hardening : 0;
        }
        cd_config_free(&c);
        free(text);
    }
    return rc;
}

/* Snapshot k's packing fraction, strain ln(h_i/h), plastic volume fraction
 * and mean maximum boundary curvature times the mean initial diameter. */
static int snapshot_measures(const mpm_data *d, size_t k, double *phi, double *strain, double *fp, double *kd)
{
    size_t n = d->n;
    const double *x = d->pos + 2 * n * k, *v = d->vol + n * k, *ep = d->eps_p + n * k, *F = d->defg + 4 * n * k;
    const double *w = d->swall + 8 * k; /* walls: 0 bottom, 1 top, 2 left, 3 right; (x, y) each */
    double area = 0, plastic = 0;
    for (size_t p = 0; p < n; p++) {
        area += v[p];
        if (ep[p] > 0) plastic += v[p];
    }
    double h = w[3] - w[1], h0 = d->wall0[3] - d->wall0[1];
    *phi = area / ((w[6] - w[4]) * h);
    *strain = log(h0 / h);
    *fp = area > 0 ? plastic / area : NAN;
    /* per particle: the corners of its points' parallelograms x_p + F [-l/2, l/2]^2, l the
     * initial side sqrt(V / det F); the hull's largest turning over an arc of a quarter of the
     * particle's initial diameter d (a disk: kappa d = 2) */
    double *xy = malloc(8 * (n ? n : 1) * sizeof(double));
    if (!xy) return -1;
    double ksum = 0, dsum = 0;
    size_t nb = 0;
    for (size_t a = 0; a < n;) {
        size_t b = a;
        while (b < n && d->particle[b] == d->particle[a]) b++;
        double a0 = cd_an_mpm_corners(x, v, F, a, b, xy);  /* initial area [m^2/m] */
        double dk = sqrt(4 * a0 / 3.14159265358979323846); /* [m] */
        double kmax = cd_an_max_boundary_curvature(xy, 4 * (b - a), dk / 8);
        if (isfinite(kmax)) {
            ksum += kmax;
            nb++;
        }
        dsum += dk;
        a = b;
    }
    free(xy);
    size_t bodies = (size_t)d->particle[n - 1] + 1;
    *kd = nb ? ksum / (double)nb * dsum / (double)bodies : NAN;
    return 0;
}

/* The applied stress of the series at a step [Pa]: interpolated between the rows around it (the
 * snapshots' steps need not be series rows); NAN outside the series. */
static double series_at(const mpm_data *d, double step)
{
    for (size_t i = 0; i < d->rows; i++) {
        if (d->step[i] == step) return d->sigma[i];
        if (i > 0 && d->step[i - 1] < step && step < d->step[i])
            return d->sigma[i - 1] +
                   (step - d->step[i - 1]) / (d->step[i] - d->step[i - 1]) * (d->sigma[i] - d->sigma[i - 1]);
    }
    return NAN;
}

/* The first crossing of Phi = phi_c in the series: sigma and strain there
 * by linear interpolation; -1 when the series never reaches phi_c. */
static int at_phi(const mpm_data *d, double phi_c, double *sigma_c, double *strain_c)
{
    for (size_t i = 1; i < d->rows; i++)
        if (d->phi[i - 1] < phi_c && d->phi[i] >= phi_c) {
            double u = (phi_c - d->phi[i - 1]) / (d->phi[i] - d->phi[i - 1]);
            *sigma_c = d->sigma[i - 1] + u * (d->sigma[i] - d->sigma[i - 1]);
            *strain_c = d->strain[i - 1] + u * (d->strain[i] - d->strain[i - 1]);
            return 0;
        }
    if (d->rows && d->phi[0] >= phi_c) { /* jammed from the start */
        *sigma_c = d->sigma[0];
        *strain_c = d->strain[0];
        return 0;
    }
    return -1;
}

int cd_an_mpm(const char *path, const cd_an_options *opt, cd_an_report *r, char *err, size_t errlen)
{
    if (cd_an_mpm_is_disk(path)) return cd_an_mpm_disk(path, opt, r, err, errlen);
    mpm_data d;
    int rc = data_read(path, &d, err, errlen);
    if (rc) {
        data_free(&d);
        return rc;
    }
    int k = opt->snapshot < 0 ? (int)d.snaps + opt->snapshot : opt->snapshot;
    if (k < 0 || k >= (int)d.snaps) {
        snprintf(err, errlen, "%s: snapshot %d: the file has %zu committed snapshots (0..%zu)", path, opt->snapshot,
                 d.snaps, d.snaps - 1);
        data_free(&d);
        return 2;
    }
    r->snapshot = k;
    r->n_snapshots = (int)d.snaps;
    r->step = (long long)d.sstep[k];
    r->time = d.stime[k];
    cd_an_group *g = cd_an_group_get(r, "mpm");
    cd_an_put(g, "n_points", (double)d.n, "1");
    cd_an_put(g, "n_particles", (double)(d.particle[d.n - 1] + 1), "1");
    /* the last series row: the run's end */
    size_t L = d.rows - 1;
    cd_an_put(g, "series_step", d.step[L], "1");
    cd_an_put(g, "phi", d.phi[L], "1");
    cd_an_put(g, "sigma", d.sigma[L], "Pa");
    cd_an_put(g, "strain", d.strain[L], "1");
    cd_an_put(g, "z", d.z[L], "1");
    /* every snapshot, and the chosen one's values */
    /* the whole series, for the figures (host/plot_run.py: the paper's Figs. 3-5) */
    double *ser = cd_an_put_curve(g, "series", d.rows, "step,strain,phi,sigma,z", "1,1,1,Pa,1");
    for (size_t i = 0; ser && i < d.rows; i++) {
        double row[5] = {d.step[i], d.strain[i], d.phi[i], d.sigma[i], d.z[i]};
        memcpy(ser + 5 * i, row, sizeof row);
    }
    double *c = cd_an_put_curve(g, "snapshots", d.snaps, "step,strain,phi,f_p,kappa_d,sigma", "1,1,1,1,1,Pa");
    double *sphi = malloc(d.snaps * 2 * sizeof(double)), *sfp = sphi ? sphi + d.snaps : NULL;
    if (!c || !sphi) {
        snprintf(err, errlen, "out of memory");
        free(sphi);
        data_free(&d);
        return 1;
    }
    for (size_t s = 0; s < d.snaps; s++) {
        double phi, strain, fp, kd;
        if (snapshot_measures(&d, s, &phi, &strain, &fp, &kd)) {
            snprintf(err, errlen, "out of memory");
            free(sphi);
            data_free(&d);
            return 1;
        }
        double row[6] = {d.sstep[s], strain, phi, fp, kd, series_at(&d, d.sstep[s])};
        memcpy(c + 6 * s, row, sizeof row);
        sphi[s] = phi;
        sfp[s] = fp;
        if ((int)s == k) {
            cd_an_put(g, "snapshot_phi", phi, "1");
            cd_an_put(g, "snapshot_strain", strain, "1");
            cd_an_put(g, "f_p", fp, "1");
            cd_an_put(g, "kappa_d", kd, "1");
        }
    }
    /* eq. (17): Z - Z_c = A sqrt(Phi - Phi_c), A = (Z_1 - Z_c) / sqrt(Phi_1 - Phi_c); Phi_c fitted, or
     * given (--phi-c): then a line in sqrt(Phi - Phi_c) */
    cd_an_nlfit jf;
    int fr = opt->phi_c > 0 ? 0 : cd_an_fit_jamming(d.phi, d.z, d.rows, &jf);
    cd_an_group *g17 = cd_an_group_get(r, "mpm_eq17");
    if (opt->phi_c > 0) {
        double *x = calloc(2 * d.rows, sizeof(double)), *y = x ? x + d.rows : NULL;
        size_t m = 0;
        for (size_t i = 0; x && i < d.rows; i++)
            if (d.phi[i] > opt->phi_c && d.z[i] > 0) {
                x[m] = sqrt(d.phi[i] - opt->phi_c);
                y[m++] = d.z[i];
            }
        cd_an_linfit lf;
        if (!x || cd_an_fit_line(x, y, m, &lf))
            cd_an_put_text(g17, "skipped", "fewer than 3 rows with Z > 0 beyond Phi_c = %.4g", opt->phi_c);
        else {
            double ss = 0;
            for (size_t i = 0; i < m; i++) ss += pow(y[i] - lf.intercept - lf.slope * x[i], 2);
            cd_an_put_text(g17, "phi_c_from", "--phi-c");
            cd_an_put(g17, "phi_c", opt->phi_c, "1");
            static const char *const names[2] = {"z_c", "amplitude"};
            cd_an_nlfit two = {
                .np = 2, .p = {lf.intercept, lf.slope}, .lo = {lf.intercept_lo, lf.lo}, .hi = {lf.intercept_hi, lf.hi}};
            cd_an_put_fit(g17, names, &two);
            cd_an_put(g17, "n_points", (double)m, "1");
            cd_an_put(g17, "rms_residual", sqrt(ss / (double)m), "1");
        }
        free(x);
    } else if (fr) {
        cd_an_put_text(g17, "skipped", "%s",
                       fr == -1   ? "fewer than 5 states with Z > 0"
                       : fr == -2 ? "no convergence"
                                  : "the series does not resolve Z - Z_c ~ (Phi - Phi_c)^(1/2)");
    } else {
        static const char *const names[3] = {"phi_c", "z_c", "amplitude"};
        cd_an_put_fit(g17, names, &jf);
        cd_an_put(g17, "n_points", (double)jf.n, "1");
        cd_an_put(g17, "rms_residual", sqrt(jf.chi2 / (double)jf.n), "1");
    }
    /* Phi_c of eqs. (5) and (11): --phi-c, else eq. (17)'s */
    double pc = opt->phi_c > 0 ? opt->phi_c : fr ? NAN : jf.p[0];
    const char *no_pc = "no Phi_c: eq. (17) did not fit (give it with --phi-c)";
    /* eq. (5): sigma - sigma_c = M_eff (strain - strain_c) on the rows at or beyond Phi_c */
    cd_an_group *g5 = cd_an_group_get(r, "mpm_eq5");
    double sc = NAN, ec = NAN;
    if (!(pc > 0)) cd_an_put_text(g5, "skipped", "%s", no_pc);
    else if (at_phi(&d, pc, &sc, &ec)) cd_an_put_text(g5, "skipped", "the series does not reach Phi_c = %.4g", pc);
    else {
        double *x = calloc(2 * d.rows, sizeof(double)), *y = x ? x + d.rows : NULL;
        size_t m = 0;
        for (size_t i = 1; x && i < d.rows; i++)
            if (d.phi[i] >= pc) {
                x[m] = d.strain[i] - ec;
                y[m] = d.sigma[i] - sc;
                m++;
            }
        cd_an_linfit lf;
        if (!x || cd_an_fit_line(x, y, m, &lf))
            cd_an_put_text(g5, "skipped", "fewer than 3 rows beyond Phi_c = %.4g", pc);
        else {
            cd_an_put_text(g5, "phi_c_from", "%s", opt->phi_c > 0 ? "--phi-c" : "eq. (17)");
            cd_an_put(g5, "phi_c", pc, "1");
            cd_an_put(g5, "sigma_c", sc, "Pa");
            cd_an_put(g5, "strain_c", ec, "1");
            cd_an_put(g5, "m_eff", lf.slope, "Pa");
            cd_an_put(g5, "m_eff_lo", lf.lo, "Pa");
            cd_an_put(g5, "m_eff_hi", lf.hi, "Pa");
            cd_an_put(g5, "offset", lf.intercept, "Pa");
            cd_an_put(g5, "n_points", (double)m, "1");
        }
        free(x);
    }
    /* eq. (11): f_p = alpha ln(Phi / Phi_c), least squares through the origin, over the snapshots beyond Phi_c */
    cd_an_group *g11 = cd_an_group_get(r, "mpm_eq11");
    double sxy = 0, sxx = 0, any = 0;
    size_t m = 0;
    for (size_t s = 0; pc > 0 && s < d.snaps; s++)
        if (sphi[s] > pc) {
            double u = log(sphi[s] / pc);
            sxy += u * sfp[s];
            sxx += u * u;
            any += sfp[s];
            m++;
        }
    if (!(pc > 0) || m < 2 || !(any > 0))
        cd_an_put_text(g11, "skipped", "%s",
                       !(pc > 0) ? no_pc
                       : m < 2   ? "fewer than 2 snapshots beyond Phi_c"
                                 : "no plastic point (an elastic material)");
    else {
        double alpha = sxy / sxx, ss = 0;
        for (size_t s = 0; s < d.snaps; s++)
            if (sphi[s] > pc) {
                double e = sfp[s] - alpha * log(sphi[s] / pc);
                ss += e * e;
            }
        double se = sqrt(ss / (double)(m - 1) / sxx), t = gsl_cdf_tdist_Pinv(0.975, (double)(m - 1));
        cd_an_put(g11, "alpha", alpha, "1");
        cd_an_put(g11, "alpha_lo", alpha - t * se, "1");
        cd_an_put(g11, "alpha_hi", alpha + t * se, "1");
        cd_an_put(g11, "n_points", (double)m, "1");
    }
    /* eqs. (6)-(16): the porous-medium law and the plastic mixture */
    if (d.material_ok)
        cd_an_mpm_models(r, &d.material, d.plastic, opt->elastic_model_set ? opt->elastic_model : NULL, pc, d.phi, d.z,
                         d.sigma, d.strain, d.rows);
    else {
        cd_an_put_text(cd_an_group_get(r, "mpm_eq6"), "skipped", "the echoed config does not parse: no material");
        cd_an_put_text(cd_an_group_get(r, "mpm_eq10"), "skipped", "the echoed config does not parse: no material");
    }
    free(sphi);
    data_free(&d);
    return 0;
}
