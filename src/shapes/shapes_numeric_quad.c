/* Piecewise-analytic adaptive quadrature for shapes_numeric.c: the 1-D
 * integral over a surface piece of an integrand that also returns a
 * signature, split at the located changes of signature, each analytic
 * piece integrated by mapped adaptive Gauss-Kronrod (7/15).  The method is
 * described in shapes_numeric.c's header comment; shared declarations in
 * shapes_numeric_internal.h. */
#include "shapes/shapes_numeric_internal.h"
#include <float.h>
#include <math.h>

/* ---- piecewise-analytic adaptive quadrature ---------------------------- */

/* Kronrod 15-point nodes (positive half, the last is 0) and weights; nodes
 * 1, 3, 5, 7 are the 7-point Gauss nodes with weights gk_g. */
static const double gk_x[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                               0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                               0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                               0.207784955007898467600689403773245, 0.0};
static const double gk_w[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                               0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                               0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                               0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
static const double gk_g[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                               0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

/* Past this many located changes in one integral the signature is no longer
 * trusted (numerical flicker at a degenerate configuration) and plain
 * adaptive bisection takes over. */
#define PW_MAX_EVENTS 400

/* One analytic piece [p, q] mapped by x = m - h cos(t), t in [0, pi]. */
typedef struct {
    double p, q, m, h;
    uint64_t sig; /* signature inside */
} pw_piece;

static uint64_t pw_eval(pw_job *J, double x, double *out)
{
    J->evals++;
    return J->f(x, J->ctx, out);
}

/* Shrinks [x_same, x_diff] (signature at x_same is s, at x_diff not) to the
 * resolution and returns its middle: the location of a change. */
static double pw_locate(pw_job *J, double x_same, uint64_t s, double x_diff)
{
    double tmp[NCOMP];
    J->events++;
    while (fabs(x_diff - x_same) > J->xres) {
        double m = 0.5 * (x_same + x_diff);
        if (pw_eval(J, m, tmp) == s) x_same = m;
        else x_diff = m;
    }
    return 0.5 * (x_same + x_diff);
}

/* 15-point panel on [ta, tb] of the mapped piece.  Returns the weighted
 * |Kronrod - Gauss| estimate, or -1 with *x_bad set if a node lies past a
 * change of signature (further than the resolution from the piece's ends,
 * where the located change may fall on either side). */
static double pw_panel(pw_job *J, const pw_piece *S, double ta, double tb, double *K, double *x_bad)
{
    const double c = 0.5 * (ta + tb), hw = 0.5 * (tb - ta), guard = 4 * J->xres;
    double G[NCOMP], f[NCOMP];
    for (int k = 0; k < NCOMP; k++) K[k] = G[k] = 0;
    for (int j = 0; j < 15; j++) {
        int idx = j < 8 ? j : 14 - j;
        double t = j < 8 ? c - hw * gk_x[idx] : c + hw * gk_x[idx];
        double x = S->m - S->h * cos(t), jac = S->h * sin(t);
        uint64_t sg = pw_eval(J, x, f);
        if (sg != S->sig && x - S->p > guard && S->q - x > guard && J->events < PW_MAX_EVENTS) {
            *x_bad = x;
            return -1;
        }
        for (int k = 0; k < NCOMP; k++) {
            K[k] += gk_w[idx] * f[k] * jac;
            if (idx & 1) G[k] += gk_g[idx / 2] * f[k] * jac;
        }
    }
    double err = 0, mag = 0;
    for (int k = 0; k < NCOMP; k++) {
        K[k] *= hw;
        G[k] *= hw;
        double e = fabs(K[k] - G[k]) * J->weight[k];
        if (e > err) err = e;
        if (fabs(K[k]) * J->weight[k] > mag) mag = fabs(K[k]) * J->weight[k];
    }
    /* Below the rounding of the sums, |K - G| is noise: do not chase it. */
    return err <= 64 * DBL_EPSILON * mag ? 0.0 : err;
}

/* Global adaptive bisection: the panel with the largest estimate is split
 * until the estimates sum to below tol.  (Near a tangency the integrand
 * carries rounding noise far above 1e-16 -- a chord length there is
 * ill-conditioned -- so a per-panel tolerance that halves with the panel
 * could never be met; the panel budget bounds the work instead.)
 * Returns 1 (and *x_bad) if the piece turned out not to be analytic. */
#define PW_MAX_PANELS 200
static int pw_adapt(pw_job *J, const pw_piece *S, double tol, double *acc, double *x_bad)
{
    static _Thread_local struct {
        double ta, tb, err, K[NCOMP];
    } P[PW_MAX_PANELS];
    int np = 1;
    P[0].ta = 0.0;
    P[0].tb = NUM_PI;
    P[0].err = pw_panel(J, S, 0.0, NUM_PI, P[0].K, x_bad);
    if (P[0].err < 0) return 1;
    double total = P[0].err;
    while (total > tol && np < PW_MAX_PANELS) {
        int w = 0;
        for (int k = 1; k < np; k++)
            if (P[k].err > P[w].err) w = k;
        double ta = P[w].ta, tb = P[w].tb, c = 0.5 * (ta + tb);
        if (!(c > ta && c < tb) || tb - ta < 1e-15) { /* cannot split further: take it as it is */
            total -= P[w].err;
            P[w].err = 0;
            continue;
        }
        total -= P[w].err;
        P[w].tb = c;
        P[w].err = pw_panel(J, S, ta, c, P[w].K, x_bad);
        if (P[w].err < 0) return 1;
        P[np].ta = c;
        P[np].tb = tb;
        P[np].err = pw_panel(J, S, c, tb, P[np].K, x_bad);
        if (P[np].err < 0) return 1;
        total += P[w].err + P[np].err;
        np++;
    }
    for (int k = 0; k < np; k++)
        for (int m = 0; m < NCOMP; m++) acc[m] += P[k].K[m];
    return 0;
}

/* Integrates over [p, q], splitting at every change of signature found. */
static void pw_piecewise(pw_job *J, double p, double q, double tol, int depth, double *acc)
{
    double f[NCOMP], part[NCOMP] = {0}, x_bad;
    pw_piece S = {p, q, 0.5 * (p + q), 0.5 * (q - p), 0};
    if (q - p <= 8 * J->xres || depth > 60) {
        /* A sliver between two located changes: its share is ~1e-14 of the
         * range, so one plain 15-point rule without checks is plenty. */
        for (int j = 0; j < 15; j++) {
            int idx = j < 8 ? j : 14 - j;
            double x = j < 8 ? S.m - S.h * gk_x[idx] : S.m + S.h * gk_x[idx];
            pw_eval(J, x, f);
            for (int k = 0; k < NCOMP; k++) acc[k] += gk_w[idx] * S.h * f[k];
        }
        return;
    }
    S.sig = pw_eval(J, S.m, f);
    if (pw_adapt(J, &S, tol, part, &x_bad)) {
        double x = pw_locate(J, S.m, S.sig, x_bad);
        pw_piecewise(J, p, x, tol * (x - p) / (q - p), depth + 1, acc);
        pw_piecewise(J, x, q, tol * (q - x) / (q - p), depth + 1, acc);
        return;
    }
    for (int k = 0; k < NCOMP; k++) acc[k] += part[k];
}

/* Integral over [A, B]: signatures sampled at nsample + 1 points, changes
 * between neighbours located, then each piece integrated. */
void cd_shn_pw_integrate(pw_job *J, double A, double B, int nsample, double tol, double *acc)
{
    double f[NCOMP];
    double brk[2 * NS_FINE + 2];
    int nb = 0;
    brk[nb++] = A;
    double xprev = A;
    uint64_t sprev = pw_eval(J, A, f);
    for (int k = 1; k <= nsample; k++) {
        double x = k == nsample ? B : A + (B - A) * k / nsample;
        uint64_t s = pw_eval(J, x, f);
        if (s != sprev && nb < 2 * NS_FINE) {
            double e = pw_locate(J, xprev, sprev, x);
            if (e - brk[nb - 1] > J->xres && B - e > J->xres) brk[nb++] = e;
        }
        xprev = x;
        sprev = s;
    }
    brk[nb++] = B;
    for (int k = 0; k + 1 < nb; k++) pw_piecewise(J, brk[k], brk[k + 1], tol * (brk[k + 1] - brk[k]) / (B - A), 0, acc);
}
