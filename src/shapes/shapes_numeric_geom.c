/* Capsule geometry for the numerical union of shapes_numeric.c: capsule
 * set-up and segment distances, the interval of a line inside a capsule,
 * the angles where a circle crosses a capsule's surfaces (with the
 * polynomial root finder they need), and the exact integrals of
 * trigonometric polynomials over arcs.  Shared declarations in
 * shapes_numeric_internal.h. */
#include "shapes/shapes_numeric_internal.h"
#include <float.h>
#include <math.h>
#include <string.h>

/* ---- capsules ---------------------------------------------------------- */

/* Unit vectors u, v completing the unit vector e to a right-handed basis. */
static void normals_of(const double *e, double *u, double *v)
{
    /* Cross with the coordinate axis least aligned with e: never degenerate. */
    double t[3] = {0, 0, 0};
    int k = fabs(e[0]) <= fabs(e[1]) ? (fabs(e[0]) <= fabs(e[2]) ? 0 : 2) : (fabs(e[1]) <= fabs(e[2]) ? 1 : 2);
    t[k] = 1.0;
    u[0] = e[1] * t[2] - e[2] * t[1];
    u[1] = e[2] * t[0] - e[0] * t[2];
    u[2] = e[0] * t[1] - e[1] * t[0];
    double n = sqrt(dot3(u, u));
    for (int i = 0; i < 3; i++) u[i] /= n;
    v[0] = e[1] * u[2] - e[2] * u[1];
    v[1] = e[2] * u[0] - e[0] * u[2];
    v[2] = e[0] * u[1] - e[1] * u[0];
}

void cd_shn_capsule_init(capsule *c, const double *a, const double *b, double r)
{
    memcpy(c->a, a, sizeof c->a);
    memcpy(c->b, b, sizeof c->b);
    c->r = r;
    double d[3];
    sub3(b, a, d);
    c->len = sqrt(dot3(d, d));
    if (c->len > 0) {
        for (int i = 0; i < 3; i++) c->e[i] = d[i] / c->len;
    } else {
        c->e[0] = 1;
        c->e[1] = 0;
        c->e[2] = 0; /* a ball: any axis will do */
    }
    normals_of(c->e, c->u, c->v);
}

/* Squared distance from p to the axis segment of c [m^2]. */
double cd_shn_dist2_segment(const capsule *c, const double *p)
{
    double w[3];
    sub3(p, c->a, w);
    double s = dot3(w, c->e);
    if (s < 0) s = 0;
    if (s > c->len) s = c->len;
    double q[3] = {w[0] - s * c->e[0], w[1] - s * c->e[1], w[2] - s * c->e[2]};
    return dot3(q, q);
}

/* ---- line / capsule ---------------------------------------------------- */

/* Roots of t^2 + 2 B t + C = 0 (the form every ball/line test takes),
 * without cancellation when |B| is much larger than the roots' spread. */
static int half_quadratic(double B, double C, double *t0, double *t1)
{
    double disc = B * B - C;
    if (disc < 0) return 0;
    double s = sqrt(disc);
    double q = B >= 0 ? -(B + s) : -(B - s);
    double x0 = q, x1 = q != 0 ? C / q : 0;
    *t0 = x0 < x1 ? x0 : x1;
    *t1 = x0 < x1 ? x1 : x0;
    return 1;
}

/* Interval of t where o + t d (|d| = 1) lies in capsule c.  The capsule is
 * convex, so the set is one interval: the hull of the pieces in the two end
 * balls and in the finite cylinder.  Returns 0 where the line misses. */
int cd_shn_line_capsule(const capsule *c, const double *o, const double *d, double *lo, double *hi)
{
    double L = INFINITY, H = -INFINITY, t0, t1, w[3];
    const double r2 = c->r * c->r;

    sub3(o, c->a, w);
    if (half_quadratic(dot3(d, w), dot3(w, w) - r2, &t0, &t1)) {
        L = t0;
        H = t1;
    }
    if (c->len > 0) {
        double wb[3];
        sub3(o, c->b, wb);
        if (half_quadratic(dot3(d, wb), dot3(wb, wb) - r2, &t0, &t1)) {
            if (t0 < L) L = t0;
            if (t1 > H) H = t1;
        }
        /* Infinite cylinder, then the slab 0 <= s <= len along the axis. */
        double we = dot3(w, c->e), de = dot3(d, c->e);
        double wp[3], dp[3];
        for (int i = 0; i < 3; i++) {
            wp[i] = w[i] - we * c->e[i];
            dp[i] = d[i] - de * c->e[i];
        }
        double A = dot3(dp, dp), C = dot3(wp, wp) - r2;
        double clo = -INFINITY, chi = INFINITY;
        int hit = 1;
        if (A < 1e-300) { /* parallel to the axis: all or nothing */
            if (C > 0) hit = 0;
        } else {
            hit = half_quadratic(dot3(dp, wp) / A, C / A, &clo, &chi);
        }
        if (hit) {
            if (fabs(de) < 1e-300) {
                if (we < 0 || we > c->len) hit = 0;
            } else {
                double s0 = -we / de, s1 = (c->len - we) / de;
                if (s0 > s1) {
                    double t = s0;
                    s0 = s1;
                    s1 = t;
                }
                if (s0 > clo) clo = s0;
                if (s1 < chi) chi = s1;
                if (clo > chi) hit = 0;
            }
        }
        if (hit) {
            if (clo < L) L = clo;
            if (chi > H) H = chi;
        }
    }
    if (!(L <= H)) return 0;
    *lo = L;
    *hi = H;
    return 1;
}

/* ---- caps: circle / capsule crossings, trigonometric integrals ---------- */

static double poly_eval(const double *c, int deg, double x)
{
    double p = c[deg];
    for (int k = deg - 1; k >= 0; k--) p = p * x + c[k];
    return p;
}

/* All sign-changing real roots of the polynomial (degree <= 4) in [lo, hi],
 * ascending.  Between consecutive roots of the derivative the polynomial is
 * monotone, so each such bracket holds at most one root, found by
 * bisection: no root is skipped however close two roots are. */
static int poly_roots(const double *c, int deg, double lo, double hi, double *roots)
{
    while (deg > 0 && c[deg] == 0.0) deg--;
    if (deg == 0) return 0;
    if (deg == 1) {
        double x = -c[0] / c[1];
        if (x >= lo && x <= hi) {
            roots[0] = x;
            return 1;
        }
        return 0;
    }
    if (deg == 2) { /* closed form (a double root counts: it may be a crossing of the cubic's derivative) */
        double t0, t1;
        int nr = 0;
        if (half_quadratic(0.5 * c[1] / c[2], c[0] / c[2], &t0, &t1)) {
            if (t0 >= lo && t0 <= hi) roots[nr++] = t0;
            if (t1 >= lo && t1 <= hi && t1 != t0) roots[nr++] = t1;
        }
        return nr;
    }
    double dc[4], pts[6];
    for (int k = 1; k <= deg; k++) dc[k - 1] = k * c[k];
    int np = 0;
    pts[np++] = lo;
    np += poly_roots(dc, deg - 1, lo, hi, pts + np);
    pts[np++] = hi;
    int nr = 0;
    for (int k = 0; k + 1 < np; k++) {
        double p = pts[k], q = pts[k + 1];
        double fp = poly_eval(c, deg, p), fq = poly_eval(c, deg, q);
        if (fp == 0) {
            roots[nr++] = p;
            continue;
        }
        if (fp * fq > 0 || fq == 0) continue; /* a zero at q is the next bracket's p */
        /* Newton from the middle, kept inside the shrinking bracket; a step
         * that leaves it, or does not halve it, is replaced by bisection. */
        double x = 0.5 * (p + q), step_old = q - p;
        for (int it = 0; it < 100; it++) {
            double fx = poly_eval(c, deg, x), dfx = poly_eval(dc, deg - 1, x);
            if (fx == 0) {
                p = q = x;
                break;
            }
            if ((fx < 0) == (fp < 0)) p = x;
            else q = x;
            double xn = dfx != 0 ? x - fx / dfx : 0.5 * (p + q);
            if (!(xn > p && xn < q) || fabs(xn - x) > 0.5 * step_old) xn = 0.5 * (p + q);
            step_old = fabs(xn - x);
            if (xn == x || q - p <= 4 * DBL_EPSILON) {
                x = xn;
                break;
            }
            x = xn;
        }
        roots[nr++] = x;
    }
    if (poly_eval(c, deg, hi) == 0) roots[nr++] = hi;
    return nr;
}

/* Angles phi with A cos(phi) + B sin(phi) = C: none, or the two
 * base -+ off with base = atan2(B, A), off = acos(C / |(A, B)|). */
static int crossings(double A, double B, double C, unsigned src, cut *out)
{
    double M = sqrt(A * A + B * B);
    if (!(M > 0) || fabs(C) > M) return 0;
    double base = atan2(B, A), off = acos(C / M);
    out[0].phi = base - off;
    out[0].src = src;
    out[1].phi = base + off;
    out[1].src = src;
    return 2;
}

/* Angles where the circle ctr + rho (cos phi U + sin phi W) crosses the
 * sphere |p - q| = R: A cos + B sin = C, solved in closed form. */
int cd_shn_circle_sphere(const double *ctr, double rho, const double *U, const double *W, const double *q, double R,
                         unsigned src, cut *out)
{
    double w[3];
    sub3(ctr, q, w);
    double A = 2 * rho * dot3(w, U), B = 2 * rho * dot3(w, W), C = R * R - dot3(w, w) - rho * rho;
    return crossings(A, B, C, src, out);
}

/* Angles where the circle crosses the plane (p - q).n = 0. */
int cd_shn_circle_plane(const double *ctr, double rho, const double *U, const double *W, const double *q,
                        const double *n, unsigned src, cut *out)
{
    double w[3];
    sub3(ctr, q, w);
    double A = rho * dot3(U, n), B = rho * dot3(W, n), C = -dot3(w, n);
    return crossings(A, B, C, src, out);
}

/* Angles where the circle crosses the infinite cylinder around c's axis:
 * |perp(p - a)|^2 - r^2 is a trigonometric polynomial of degree 2 in phi;
 * with t = tan(phi/2) on each half turn it is a quartic in t on [-1, 1]. */
int cd_shn_circle_cylinder(const double *ctr, double rho, const double *U, const double *W, const capsule *c,
                           unsigned src, cut *out)
{
    double w[3], wp[3], up[3], vp[3];
    sub3(ctr, c->a, w);
    double we = dot3(w, c->e), ue = dot3(U, c->e), ve = dot3(W, c->e);
    for (int k = 0; k < 3; k++) {
        wp[k] = w[k] - we * c->e[k];
        up[k] = rho * (U[k] - ue * c->e[k]);
        vp[k] = rho * (W[k] - ve * c->e[k]);
    }
    /* f = k0 + k1 cos + k2 sin + k3 cos 2phi + k4 sin 2phi */
    double uu = dot3(up, up), vv = dot3(vp, vp), uv = dot3(up, vp);
    double k0 = dot3(wp, wp) + 0.5 * (uu + vv) - c->r * c->r;
    double k1 = 2 * dot3(wp, up), k2 = 2 * dot3(wp, vp), k3 = 0.5 * (uu - vv), k4 = uv;
    /* No crossing where the constant term outweighs all the harmonics, nor
     * where the circle's extent along the axis misses the slab [0, len]
     * (the capsule's balls cover the rest). */
    if (fabs(k0) > fabs(k1) + fabs(k2) + fabs(k3) + fabs(k4)) return 0;
    double ax = rho * sqrt(ue * ue + ve * ve);
    if (we + ax < 0 || we - ax > c->len) return 0;
    int n = 0;
    for (int half = 0; half < 2; half++) {
        double s = half ? -1.0 : 1.0; /* phi = pi + psi flips the odd harmonics */
        double q[5] = {k0 + s * k1 + k3, 2 * s * k2 + 4 * k4, 2 * k0 - 6 * k3, 2 * s * k2 - 4 * k4, k0 - s * k1 + k3};
        double t[4];
        int nt = poly_roots(q, 4, -1.0, 1.0, t);
        for (int k = 0; k < nt; k++) {
            out[n].phi = 2 * atan(t[k]) + (half ? NUM_PI : 0.0);
            out[n].src = src;
            n++;
        }
    }
    return n;
}

/* Antiderivatives of the monomials cos^m sin^n, m + n <= 3, in the order
 * 1, c, s, cc, cs, ss, ccc, ccs, css, sss. */
void cd_shn_trig_antideriv(double phi, double *F)
{
    double c = cos(phi), s = sin(phi);
    F[0] = phi;
    F[1] = s;
    F[2] = -c;
    F[3] = 0.5 * (phi + s * c);
    F[4] = 0.5 * s * s;
    F[5] = 0.5 * (phi - s * c);
    F[6] = s - s * s * s / 3.0;
    F[7] = -c * c * c / 3.0;
    F[8] = s * s * s / 3.0;
    F[9] = -c + c * c * c / 3.0;
}

/* Products of linear forms x0 + x1 cos + x2 sin, in the monomial order
 * above: quadratic (6 terms) and cubic (10 terms). */
void cd_shn_lin_times_lin(const double *a, const double *b, double *q)
{
    q[0] = a[0] * b[0];
    q[1] = a[0] * b[1] + a[1] * b[0];
    q[2] = a[0] * b[2] + a[2] * b[0];
    q[3] = a[1] * b[1];
    q[4] = a[1] * b[2] + a[2] * b[1];
    q[5] = a[2] * b[2];
}

void cd_shn_quad_times_lin(const double *q, const double *l, double *c)
{
    c[0] = q[0] * l[0];
    c[1] = q[0] * l[1] + q[1] * l[0];
    c[2] = q[0] * l[2] + q[2] * l[0];
    c[3] = q[1] * l[1] + q[3] * l[0];
    c[4] = q[1] * l[2] + q[2] * l[1] + q[4] * l[0];
    c[5] = q[2] * l[2] + q[5] * l[0];
    c[6] = q[3] * l[1];
    c[7] = q[3] * l[2] + q[4] * l[1];
    c[8] = q[4] * l[2] + q[5] * l[1];
    c[9] = q[5] * l[2];
}

/* ---- segment / segment ------------------------------------------------- */

/* Distance between the axis segments of two capsules [m]: the smallest of
 * the four end-to-segment distances and, if it lies inside both, the
 * common perpendicular. */
double cd_shn_segment_distance(const capsule *p, const capsule *q)
{
    double d = sqrt(fmin(fmin(cd_shn_dist2_segment(q, p->a), cd_shn_dist2_segment(q, p->b)),
                         fmin(cd_shn_dist2_segment(p, q->a), cd_shn_dist2_segment(p, q->b))));
    if (p->len > 0 && q->len > 0) {
        double w[3];
        sub3(p->a, q->a, w);
        double b = dot3(p->e, q->e), den = 1 - b * b;
        if (den > 1e-14) {
            double dw = dot3(p->e, w), ew = dot3(q->e, w);
            double s = (b * ew - dw) / den, t = (ew - b * dw) / den;
            if (s > 0 && s < p->len && t > 0 && t < q->len) {
                double x[3];
                for (int k = 0; k < 3; k++) x[k] = w[k] + s * p->e[k] - t * q->e[k];
                d = fmin(d, sqrt(dot3(x, x)));
            }
        }
    }
    return d;
}
