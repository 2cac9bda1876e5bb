/* Time series of the whole run (/observables): the compaction curve and the
 * fit (Z - Z_c) ~ (Phi - Phi_c)^(1/2) above jamming (Nezamabadi et al. 2022, eq. 17).
 *
 * The compaction curve gathers, per time-series row: time, contacts,
 * energies, and where the walls say it: the piston (the plane wall facing
 * down that moved most) with its force, height, the axial stress over the
 * container's cross-section and the volume below it; or the ball radius and
 * volume; the packing fraction Phi_walls = solid volume / that volume; and
 * any packing_fraction / coordination observable the protocol wrote.
 * Observables are aligned by step (they may have different rows after a
 * resume). */
#include "analysis/analyze.h"
#include <hdf5.h>
#include "io/io_h5_check.h"
#include "io/io_h5_layout.h"
#include "core/observables.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The name of observable id of kernels/observables.def. */
#define OBS_NAME(id) (cd_observable_table[CD_OBSERVABLE_##id].name)

typedef struct {
    char name[64];
    char unit[32];
    size_t rows;
    int ncomp;
    long long *step;
    double *time;  /* [s] */
    double *value; /* rows x ncomp */
} series;

typedef struct {
    int n;
    series s[64];
} series_set;

static herr_t collect_name(hid_t g, const char *name, const H5L_info_t *info, void *op)
{
    (void)g;
    (void)info;
    series_set *set = op;
    if (set->n < 64) snprintf(set->s[set->n++].name, sizeof set->s[0].name, "%s", name);
    return 0;
}

static void series_free(series_set *set)
{
    for (int k = 0; k < set->n; k++) {
        free(set->s[k].step);
        free(set->s[k].time);
        free(set->s[k].value);
    }
    set->n = 0;
}

/* Reads every observable of path; 0, or 2 with a message. */
static int series_read(const char *path, series_set *set, char *err, size_t errlen)
{
    memset(set, 0, sizeof(*set));
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    int rc = 0;
    const char *obs = CDH5_PATH(OBSERVABLES);
    hid_t f = cdh5_open_ro(path, err, errlen);
    if (f < 0 || !cdh5_exists(f, obs)) {
        snprintf(err, errlen, "%s: no %s group", path, obs);
        rc = 2;
        goto done;
    }
    hid_t g = H5Gopen2(f, obs, H5P_DEFAULT);
    H5Literate(g, H5_INDEX_NAME, H5_ITER_INC, NULL, collect_name, set);
    H5Gclose(g);
    for (int k = 0; k < set->n && !rc; k++) {
        series *s = &set->s[k];
        char p[160];
        snprintf(p, sizeof p, "%s/%s/%s", obs, s->name, CDH5_NAME(VALUE));
        hid_t d = H5Dopen2(f, p, H5P_DEFAULT);
        if (d < 0) continue;
        /* value (rows[, ncomp]) of floats, time and step (rows) each: checked
         * before the buffers are sized from them */
        hsize_t dims[3], cl[2] = {0, 1}, ch[2] = {0, 64};
        hid_t sp = H5Dget_space(d);
        int vrank = sp >= 0 && H5Sget_simple_extent_ndims(sp) == 2 ? 2 : 1;
        if (sp >= 0) H5Sclose(sp);
        if (cd_h5_check_dset(d, path, p, H5T_FLOAT, vrank, cl, ch, dims, err, errlen)) {
            H5Dclose(d);
            rc = 2;
            break;
        }
        s->rows = (size_t)dims[0];
        s->ncomp = vrank == 2 ? (int)dims[1] : 1;
        size_t vb, tb, sb, n1 = s->rows ? s->rows : 1;
        if (cd_h5_mul(&vb, n1, (size_t)s->ncomp, sizeof(double)) || cd_h5_mul(&tb, n1, sizeof(double), 1) ||
            cd_h5_mul(&sb, n1, sizeof(long long), 1)) {
            snprintf(err, errlen, "%s: %s has %llu rows, too many to hold; the file is refused", path, p,
                     (unsigned long long)dims[0]);
            H5Dclose(d);
            rc = 2;
            break;
        }
        s->value = malloc(vb);
        s->time = malloc(tb);
        s->step = malloc(sb);
        if (H5Aexists(d, CDH5_NAME(UNIT)) > 0) {
            hid_t a = H5Aopen(d, CDH5_NAME(UNIT), H5P_DEFAULT), t = H5Aget_type(a);
            char uerr[8];
            if (cd_h5_check_string(a, 1, path, CDH5_NAME(UNIT), sizeof s->unit - 1, uerr, sizeof uerr)) {
                /* not one short string: the unit is left empty */
            } else if (H5Tis_variable_str(t) > 0) {
                char *u = NULL;
                if (H5Aread(a, t, &u) >= 0 && u) snprintf(s->unit, sizeof s->unit, "%s", u);
                if (u) H5free_memory(u);
            } else {
                H5Aread(a, t, s->unit);
            }
            H5Tclose(t);
            H5Aclose(a);
        }
        if (!s->value || !s->time || !s->step || (s->rows && !cdh5_storage_fits(d, 0, HSIZE_UNDEF)) ||
            (s->rows && H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, s->value) < 0)) {
            snprintf(err, errlen, "%s: cannot read %s", path, p);
            rc = 2;
        }
        H5Dclose(d);
        char pt[160], ps[160];
        snprintf(pt, sizeof pt, "%s/%s/%s", obs, s->name, CDH5_NAME(TIME));
        hid_t dt = H5Dopen2(f, pt, H5P_DEFAULT);
        snprintf(ps, sizeof ps, "%s/%s/%s", obs, s->name, CDH5_NAME(STEP));
        hid_t ds = H5Dopen2(f, ps, H5P_DEFAULT);
        hsize_t exact[1] = {dims[0]};
        if (!rc && s->rows && (dt < 0 || ds < 0)) {
            snprintf(err, errlen, "%s: cannot open the clock of %s/%s", path, obs, s->name);
            rc = 2;
        }
        if (!rc && s->rows &&
            (cd_h5_check_dset(dt, path, pt, H5T_FLOAT, 1, exact, exact, NULL, err, errlen) ||
             cd_h5_check_dset(ds, path, ps, H5T_INTEGER, 1, exact, exact, NULL, err, errlen)))
            rc = 2;
        if (!rc && s->rows &&
            (!cdh5_storage_fits(dt, 0, HSIZE_UNDEF) || !cdh5_storage_fits(ds, 0, HSIZE_UNDEF) ||
             H5Dread(dt, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, s->time) < 0 ||
             H5Dread(ds, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, s->step) < 0)) {
            snprintf(err, errlen, "%s: cannot read the clock of %s/%s", path, obs, s->name);
            rc = 2;
        }
        if (dt >= 0) H5Dclose(dt);
        if (ds >= 0) H5Dclose(ds);
    }
done:
    if (f >= 0) H5Fclose(f);
    cdh5_quiet_end(&q);
    if (rc) series_free(set);
    return rc;
}

static const series *series_find(const series_set *set, const char *name)
{
    for (int k = 0; k < set->n; k++)
        if (!strcmp(set->s[k].name, name)) return &set->s[k];
    return NULL;
}

/* Component c of s at each step of the master clock (NaN where s has no
 * row for that step); both clocks increase. */
static void align(const series *master, const series *s, int c, double *out)
{
    size_t j = 0;
    for (size_t i = 0; i < master->rows; i++) {
        while (j < s->rows && s->step[j] < master->step[i]) j++;
        out[i] = j < s->rows && s->step[j] == master->step[i] ? s->value[j * (size_t)s->ncomp + (size_t)c] : NAN;
    }
}

#define MAXCOL 20

int cd_an_compaction(const char *path, const cd_an_snapshot *snap, const cd_an_geometry *g, const cd_an_options *opt,
                     cd_an_report *r, char *err, size_t errlen)
{
    (void)opt;
    series_set set;
    int rc = series_read(path, &set, err, errlen);
    if (rc) return rc;
    const series *master = series_find(&set, OBS_NAME(NC));
    if (!master) master = set.n ? &set.s[0] : NULL;
    if (!master || master->rows == 0) {
        series_free(&set);
        snprintf(err, errlen, "%s: /observables holds no time series: no compaction curve", path);
        return 2;
    }
    size_t R = master->rows;
    double *col[MAXCOL];
    char names[MAXCOL][40], units[MAXCOL][16];
    int nc = 0;
    for (int k = 0; k < MAXCOL; k++) col[k] = calloc(R, sizeof(double));
#define ADD(nm, un)                                                                                                    \
    (snprintf(names[nc], sizeof names[0], "%s", nm), snprintf(units[nc], sizeof units[0], "%s", un), col[nc++])
    double *t = ADD("time", "s");
    for (size_t i = 0; i < R; i++) t[i] = master->time[i];
    /* the protocol's own series (docs/protocols.md) when the run has them */
    static const int plain[] = {CD_OBSERVABLE_NC,    CD_OBSERVABLE_EL,   CD_OBSERVABLE_PHI,     CD_OBSERVABLE_Z,
                                CD_OBSERVABLE_PHASE, CD_OBSERVABLE_LOAD, CD_OBSERVABLE_PRESSURE};
    for (size_t k = 0; k < sizeof plain / sizeof plain[0]; k++) {
        const cd_observable_desc *d = &cd_observable_table[plain[k]];
        const series *s = series_find(&set, d->name);
        if (s && s->ncomp == 1) align(master, s, 0, ADD(d->name, d->unit));
    }
    const series *kt = series_find(&set, OBS_NAME(KT));
    const series *kr = series_find(&set, OBS_NAME(KR));
    if (kt && kr && kt->ncomp == 1 && kr->ncomp == 1) {
        double *ke = ADD("kinetic_energy", cd_observable_table[CD_OBSERVABLE_KT].unit),
               *tmp = malloc(R * sizeof(double));
        align(master, kt, 0, ke);
        if (tmp) {
            align(master, kr, 0, tmp);
            for (size_t i = 0; i < R; i++) ke[i] += tmp[i];
            free(tmp);
        }
    }
    /* Solid volume: what the packing fraction of a wall-bounded volume
     * divides. */
    double solid = 0;
    for (size_t p = 0; p < snap->n; p++) solid += cd_an_particle_volume(snap, p);
    const series *wf = series_find(&set, OBS_NAME(WALL)), *wp = series_find(&set, OBS_NAME(WALL_POSITION));
    const series *wr = series_find(&set, OBS_NAME(WALL_RADIUS));
    int W = snap->n_walls;
    cd_an_group *grp = cd_an_group_get(r, "compaction");
    if (g->dim == 3 && wf && wp && wf->ncomp == 3 * W && wp->ncomp == 3 * W &&
        (g->kind == CD_AN_CYLINDER || g->kind == CD_AN_BOX3D || g->kind == CD_AN_PSEUDO2D)) {
        /* the piston: the downward-facing plane that moved most */
        int best = -1;
        double moved = -1;
        for (int w = 0; w < W; w++) {
            if (snap->walls[w].type != CD_WALL_PLANE || snap->walls[w].normal.y > -0.999) continue;
            double lo = HUGE_VAL, hi = -HUGE_VAL;
            for (size_t i = 0; i < wp->rows; i++) {
                double y = wp->value[i * (size_t)wp->ncomp + 3 * (size_t)w + 1];
                lo = fmin(lo, y);
                hi = fmax(hi, y);
            }
            if (hi - lo >= moved) {
                moved = hi - lo;
                best = w;
            }
        }
        if (best >= 0) {
            double area = g->kind == CD_AN_CYLINDER ? CD_PI * g->radius * g->radius
                                                    : (g->hi[0] - g->lo[0]) * (g->hi[2] - g->lo[2]); /* [m^2] */
            double *F = ADD("piston_force", "N"), *y = ADD("piston_height", "m");
            double *sy = ADD("axial_stress", "Pa"), *V = ADD("volume", "m^3"), *phi = ADD("phi_walls", "1");
            double *fy = malloc(R * sizeof(double));
            align(master, wf, 3 * best + 1, fy ? fy : F);
            align(master, wp, 3 * best + 1, y);
            for (size_t i = 0; i < R; i++) {
                F[i] = fy ? fy[i] : F[i]; /* particles push the piston up: +y */
                y[i] -= g->lo[1];
                sy[i] = F[i] / area;
                V[i] = area * y[i];
                phi[i] = solid / V[i];
            }
            free(fy);
            cd_an_put(grp, "piston_wall", best, "1");
        }
    } else if (g->kind == CD_AN_BALL && wr && wr->ncomp == W) {
        int ws = -1;
        for (int w = 0; w < W; w++)
            if (snap->walls[w].type == CD_WALL_SPHERE) ws = w;
        if (ws >= 0) {
            double *R_ = ADD("ball_radius", "m"), *V = ADD("volume", "m^3"), *phi = ADD("phi_walls", "1");
            align(master, wr, ws, R_);
            for (size_t i = 0; i < R; i++) {
                V[i] = 4.0 / 3.0 * CD_PI * R_[i] * R_[i] * R_[i];
                phi[i] = solid / V[i];
            }
        }
    }
#undef ADD
    char cols[512] = "", us[512] = "";
    for (int k = 0; k < nc; k++) {
        strncat(cols, k ? "," : "", sizeof cols - strlen(cols) - 1);
        strncat(cols, names[k], sizeof cols - strlen(cols) - 1);
        strncat(us, k ? "," : "", sizeof us - strlen(us) - 1);
        strncat(us, units[k], sizeof us - strlen(us) - 1);
    }
    double *c = cd_an_put_curve(grp, "curve", R, cols, us);
    for (size_t i = 0; c && i < R; i++)
        for (int k = 0; k < nc; k++) c[i * (size_t)nc + (size_t)k] = col[k][i];
    cd_an_put(grp, "rows", (double)R, "1");
    cd_an_put(grp, "solid_volume", solid, "m^3");
    for (int k = 0; k < MAXCOL; k++) free(col[k]);
    series_free(&set);
    return 0;
}

int cd_an_jamming(const char *path, const cd_an_options *opt, cd_an_report *r, char *err, size_t errlen)
{
    series_set set;
    int rc = series_read(path, &set, err, errlen);
    if (rc) return rc;
    const char *phin[] = {OBS_NAME(PHI), "phi"}, *zn[] = {OBS_NAME(Z), "coordination_number", "Z", "z"};
    const series *ph = NULL, *z = NULL;
    if (opt->phi_series) ph = series_find(&set, opt->phi_series);
    for (int k = 0; !opt->phi_series && !ph && k < 2; k++) ph = series_find(&set, phin[k]);
    if (opt->z_series) z = series_find(&set, opt->z_series);
    for (int k = 0; !opt->z_series && !z && k < 4; k++) z = series_find(&set, zn[k]);
    if (!ph || !z || ph->ncomp != 1 || z->ncomp != 1) {
        char have[512] = "", phis[128], zs[160];
        snprintf(phis, sizeof phis, "%s or %s", phin[0], phin[1]);
        snprintf(zs, sizeof zs, "%s, %s, %s or %s", zn[0], zn[1], zn[2], zn[3]);
        for (int k = 0; k < set.n; k++) {
            strncat(have, k ? ", " : "", sizeof have - strlen(have) - 1);
            strncat(have, set.s[k].name, sizeof have - strlen(have) - 1);
        }
        snprintf(err, errlen,
                 "%s: no (Phi, Z) time series for the jamming fit: /observables holds %s; expected a packing "
                 "fraction (%s) and a coordination number (%s) series of one component each (--phi-series, "
                 "--z-series name others)",
                 path, set.n ? have : "nothing", opt->phi_series ? opt->phi_series : phis,
                 opt->z_series ? opt->z_series : zs);
        series_free(&set);
        return 2;
    }
    double *zz = malloc((ph->rows ? ph->rows : 1) * sizeof(double));
    if (!zz) {
        series_free(&set);
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    align(ph, z, 0, zz);
    /* With the protocols' phase series, only the compaction itself counts
     * (compress, hold, compact: phases 2, 3, 4 of docs/protocols.md):
     * while a deposit settles, the piston waits at the top and the packing
     * fraction of the volume below it says nothing about the packing. */
    /* Likewise a piston that does not touch the packing yet (wall_load 0)
     * bounds empty space. */
    const series *phase = series_find(&set, OBS_NAME(PHASE)), *load = series_find(&set, OBS_NAME(LOAD));
    size_t used = ph->rows;
    if (phase && phase->ncomp == 1) {
        double *pv = malloc((ph->rows ? ph->rows : 1) * 2 * sizeof(double));
        if (pv) {
            double *lv = pv + ph->rows;
            align(ph, phase, 0, pv);
            if (load && load->ncomp == 1) align(ph, load, 0, lv);
            int protocol = 0; /* phase 0 throughout: plain dynamics, no protocol */
            for (size_t i = 0; i < ph->rows; i++) protocol |= pv[i] != 0 && !isnan(pv[i]);
            used = 0;
            for (size_t i = 0; protocol && i < ph->rows; i++) {
                int ok = (pv[i] == 2 || pv[i] == 3 || pv[i] == 4) && (!load || load->ncomp != 1 || lv[i] > 0);
                if (!ok) zz[i] = NAN; /* left out of the fit */
                used += ok;
            }
            if (!protocol) used = ph->rows;
            free(pv);
        }
    }
    cd_an_nlfit fit;
    int fr = cd_an_fit_jamming(ph->value, zz, ph->rows, &fit);
    if (fr) {
        free(zz);
        snprintf(err, errlen, "%s: jamming fit of /observables/%s against /observables/%s (%zu rows used): %s", path,
                 z->name, ph->name, used,
                 fr == -1   ? "fewer than 5 jammed states"
                 : fr == -2 ? "no convergence"
                            : "the series does not resolve Z - Z_c ~ (Phi - Phi_c)^(1/2) (no rise of Z with Phi above "
                              "jamming: a compaction at one pressure ends at a single state)");
        series_free(&set);
        return 2;
    }
    cd_an_group *g = cd_an_group_get(r, "jamming");
    if (used < ph->rows)
        cd_an_put_text(g, "rows_used", "phases compress, hold, compact with a loaded wall (%zu of %zu rows)", used,
                       ph->rows);
    cd_an_put_text(g, "phi_series", "%s", ph->name);
    cd_an_put_text(g, "z_series", "%s", z->name);
    static const char *const names[3] = {"phi_c", "z_c", "amplitude"};
    cd_an_put_fit(g, names, &fit);
    cd_an_put(g, "n_points", (double)fit.n, "1");
    cd_an_put(g, "rms_residual", sqrt(fit.chi2 / (double)fit.n), "1");
    double *c = cd_an_put_curve(g, "data", ph->rows, "phi,z,z_fit", "1,1,1");
    for (size_t i = 0; c && i < ph->rows; i++) {
        c[3 * i] = ph->value[i];
        c[3 * i + 1] = zz[i];
        c[3 * i + 2] = ph->value[i] > fit.p[0] ? fit.p[1] + fit.p[2] * sqrt(ph->value[i] - fit.p[0]) : NAN;
    }
    free(zz);
    series_free(&set);
    return 0;
}
