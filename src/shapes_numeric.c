/* Numerical mass properties of a union of spherocylinders (capsules).
 *
 * Used where no closed form is known: general segment lists, and crosses or
 * hexapods with aspect < 2, whose end caps overlap the other arms.
 * docs/shapes.md has the derivation and the measured convergence.
 *
 * Everything is a surface integral over the exposed part of each capsule's
 * surface (the part inside no other capsule):
 *   area   A      = sum of dA
 *   volume V      = 1/3 int p.n dA        (div p = 3)
 *   first  int x_k  dV = 1/4 int x_k p.n dA      (div(x_k p) = 4 x_k)
 *   second int x_k x_l dV = 1/5 int x_k x_l p.n dA  (div(x_k x_l p) = 5 x_k x_l)
 * The lateral cylinder of capsule i is swept by lines parallel to its axis
 * (angle theta); such a line meets every other capsule, a convex body, in
 * one interval found analytically, and the polynomials above are integrated
 * exactly over the exposed gaps.  Each hemispherical cap is swept by circles
 * of latitude (height w), on which dA = r^2 dw dphi (Archimedes); the arcs
 * inside other capsules end at roots of trigonometric polynomials of degree
 * <= 2 (found without misses, see poly_roots), and the integrands are
 * trigonometric polynomials of degree <= 3, integrated exactly.
 *
 * That leaves one 1-D integral per surface piece (over theta or w).  Its
 * integrand is analytic except where the combinatorics change: an interval
 * appears (tangency, square-root behaviour) or an exposed gap's end switches
 * from one surface to another (kink).  Each evaluation therefore also
 * returns a signature of which surfaces bound the exposed gaps; the changes
 * of signature are located by bisection to ~1e-14 of the range and the
 * integral is split there.  On each analytic piece, the map
 * x = m - h cos(t) turns square-root ends into smooth ones and adaptive
 * Gauss-Kronrod (7/15) converges geometrically.  A node whose signature
 * differs from its piece's reveals an event the sampling missed: it is
 * located and the piece split again.
 *
 * The whole calculation is done at two tolerances with different sampling;
 * their difference is reported as the error bound of the finer result. */
#include "shapes.h"
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define NUM_PI 3.14159265358979323846
#define NCOMP 11       /* area, V, 3 first moments, 6 second moments */
#ifndef NS_COARSE
#define NS_COARSE 256
#endif
#ifndef NS_FINE
#define NS_FINE 1024
#endif

typedef struct {
    double a[3], b[3];       /* axis ends, relative to the reference point [m] */
    double e[3], u[3], v[3]; /* unit axis and two unit normals (any, if len == 0) */
    double len, r;           /* axis length, radius [m] */
} capsule;

/* Labels of the ends of exposed gaps and arcs (the signature): the index
 * of the capsule whose surface bounds it, or one of these.  Which part of
 * that capsule (ball or cylinder) is left out on purpose: the two are
 * tangent along the rim, the switch is only a curvature jump that the
 * quadrature absorbs, and the roots from the two parts agree to rounding
 * over a band around it, which would make the label flicker. */
enum { SRC_CLIP_LO = CD_MAX_ARMS, SRC_CLIP_HI, SRC_START };

/* ---- small vector helpers ---------------------------------------------- */

static double dot3(const double *p, const double *q) { return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]; }

static void sub3(const double *p, const double *q, double *o)
{
    o[0] = p[0] - q[0]; o[1] = p[1] - q[1]; o[2] = p[2] - q[2];
}

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

static void capsule_init(capsule *c, const double *a, const double *b, double r)
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
        c->e[0] = 1; c->e[1] = 0; c->e[2] = 0; /* a ball: any axis will do */
    }
    normals_of(c->e, c->u, c->v);
}

/* Squared distance from p to the axis segment of c [m^2]. */
static double dist2_segment(const capsule *c, const double *p)
{
    double w[3];
    sub3(p, c->a, w);
    double s = dot3(w, c->e);
    if (s < 0) s = 0;
    if (s > c->len) s = c->len;
    double q[3] = {w[0] - s * c->e[0], w[1] - s * c->e[1], w[2] - s * c->e[2]};
    return dot3(q, q);
}

/* Signatures: FNV-1a over small integers. */
static uint64_t sig_add(uint64_t h, unsigned x)
{
    for (int k = 0; k < 4; k++) {
        h ^= (x >> (8 * k)) & 0xffu;
        h *= 1099511628211ull;
    }
    return h;
}
#define SIG_START 14695981039346656037ull

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
static int line_capsule(const capsule *c, const double *o, const double *d, double *lo, double *hi)
{
    double L = INFINITY, H = -INFINITY, t0, t1, w[3];
    const double r2 = c->r * c->r;

    sub3(o, c->a, w);
    if (half_quadratic(dot3(d, w), dot3(w, w) - r2, &t0, &t1)) { L = t0; H = t1; }
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
        for (int i = 0; i < 3; i++) { wp[i] = w[i] - we * c->e[i]; dp[i] = d[i] - de * c->e[i]; }
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
                if (s0 > s1) { double t = s0; s0 = s1; s1 = t; }
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

/* ---- lateral surface --------------------------------------------------- */

/* Surfaces of different capsules can coincide over an area: arms that
 * share an end and a radius share a sphere there, collinear arms of one
 * radius share a cylinder.  A point of such a patch is on both boundaries
 * and inside neither, so it must be given to one of them: to the capsule of
 * lower index.  Coincidence (to TIE of the radius) is detected once per
 * surface piece and such pairs are classified by geometry, not by a
 * tolerance on distances (which would leave bands of width sqrt(TIE)). */
#define TIE 1e-12
enum {
    SHARE_NONE = 0,
    SHARE_BALL_A,  /* cap sphere = j's ball at a_j: j's inside is the side +e_j */
    SHARE_BALL_B,  /* cap sphere = j's ball at b_j: side -e_j */
    SHARE_ALL,     /* cap sphere = j, a ball; or lateral cylinder = j's cylinder */
    SHARE_AXIS,    /* cap sphere centred on j's axis with j's radius: it touches
                    * j's cylinder along its equator and is inside it between
                    * j's end planes */
};

typedef struct {
    int i;                   /* the capsule whose surface is swept */
    const capsule *c;
    double sgn;              /* caps: +1 at end b (outward +e), -1 at end a */
    int nnb, nb[CD_MAX_ARMS]; /* the other capsules that can reach this piece */
    unsigned char share[CD_MAX_ARMS]; /* SHARE_* per neighbour */
} piece_ctx;

typedef struct { double lo, hi; unsigned slo, shi; } span;

static int span_cmp(const void *p, const void *q)
{
    const span *x = p, *y = q;
    return (x->lo > y->lo) - (x->lo < y->lo);
}

/* Line at angle theta on the lateral surface of capsule i, t in [0, len]
 * from end a.  On it p.n = q.n is constant (q = its point at t = 0), so the
 * integrands are polynomials in t of degree <= 2. */
static uint64_t lateral_eval(double theta, void *ctx, double *out)
{
    const piece_ctx *P = ctx;
    const capsule *ci = &P->c[P->i];
    const double r = ci->r, len = ci->len;
    double n[3], q[3];
    for (int k = 0; k < 3; k++) {
        n[k] = cos(theta) * ci->u[k] + sin(theta) * ci->v[k];
        q[k] = ci->a[k] + r * n[k];
    }
    span s[CD_MAX_ARMS];
    int ns = 0;
    for (int jj = 0; jj < P->nnb; jj++) {
        int j = P->nb[jj];
        double lo, hi;
        if (P->share[jj] == SHARE_ALL) {
            /* The line lies on j's cylinder: it is j's (lower index) along
             * j's length, nobody's otherwise. */
            if (j > P->i) continue;
            const capsule *cj = &P->c[j];
            double w[3];
            sub3(q, cj->a, w);
            double s0 = dot3(w, cj->e), de = dot3(ci->e, cj->e); /* de = +-1 */
            lo = -s0 / de;
            hi = (cj->len - s0) / de;
            if (lo > hi) { double t = lo; lo = hi; hi = t; }
        } else if (!line_capsule(&P->c[j], q, ci->e, &lo, &hi)) {
            continue;
        }
        unsigned ulo = (unsigned)j, uhi = (unsigned)j;
        if (lo < 0) { lo = 0; ulo = SRC_CLIP_LO; }
        if (hi > len) { hi = len; uhi = SRC_CLIP_HI; }
        if (hi > lo) { s[ns].lo = lo; s[ns].hi = hi; s[ns].slo = ulo; s[ns].shi = uhi; ns++; }
    }
    qsort(s, (size_t)ns, sizeof s[0], span_cmp);
    /* Merge into covered intervals; the gaps between them are exposed. */
    uint64_t sig = SIG_START;
    double D1 = 0, D2 = 0, D3 = 0, t = 0; /* int 1, t, t^2 dt over exposed gaps */
    int k = 0;
    while (k < ns) {
        double lo = s[k].lo, hi = s[k].hi;
        unsigned slo = s[k].slo, shi = s[k].shi;
        for (k++; k < ns && s[k].lo <= hi; k++)
            if (s[k].hi > hi) { hi = s[k].hi; shi = s[k].shi; }
        sig = sig_add(sig_add(sig, slo), shi);
        D1 += lo - t; D2 += 0.5 * (lo * lo - t * t); D3 += (lo * lo * lo - t * t * t) / 3.0;
        t = hi;
    }
    D1 += len - t; D2 += 0.5 * (len * len - t * t); D3 += (len * len * len - t * t * t) / 3.0;
    double h = dot3(q, n); /* p.n [m] */
    out[0] = r * D1;
    out[1] = r * h * D1 / 3.0;
    for (int a = 0; a < 3; a++) out[2 + a] = r * h * (q[a] * D1 + ci->e[a] * D2) / 4.0;
    int m = 5;
    for (int a = 0; a < 3; a++)
        for (int b = a; b < 3; b++)
            out[m++] = r * h * (q[a] * q[b] * D1 + (q[a] * ci->e[b] + q[b] * ci->e[a]) * D2 + ci->e[a] * ci->e[b] * D3) / 5.0;
    return sig_add(sig, (unsigned)ns);
}

/* ---- caps -------------------------------------------------------------- */

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
        if (x >= lo && x <= hi) { roots[0] = x; return 1; }
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
        if (fp == 0) { roots[nr++] = p; continue; }
        if (fp * fq > 0 || fq == 0) continue; /* a zero at q is the next bracket's p */
        /* Newton from the middle, kept inside the shrinking bracket; a step
         * that leaves it, or does not halve it, is replaced by bisection. */
        double x = 0.5 * (p + q), step_old = q - p;
        for (int it = 0; it < 100; it++) {
            double fx = poly_eval(c, deg, x), dfx = poly_eval(dc, deg - 1, x);
            if (fx == 0) { p = q = x; break; }
            if ((fx < 0) == (fp < 0)) p = x; else q = x;
            double xn = dfx != 0 ? x - fx / dfx : 0.5 * (p + q);
            if (!(xn > p && xn < q) || fabs(xn - x) > 0.5 * step_old) xn = 0.5 * (p + q);
            step_old = fabs(xn - x);
            if (xn == x || q - p <= 4 * DBL_EPSILON) { x = xn; break; }
            x = xn;
        }
        roots[nr++] = x;
    }
    if (poly_eval(c, deg, hi) == 0) roots[nr++] = hi;
    return nr;
}

typedef struct { double phi; unsigned src; } cut;

static int cut_cmp(const void *p, const void *q)
{
    const cut *x = p, *y = q;
    return (x->phi > y->phi) - (x->phi < y->phi);
}

/* Angles where the circle ctr + rho (cos phi U + sin phi W) crosses the
 * sphere |p - q| = R: A cos + B sin = C, solved in closed form. */
static int circle_sphere(const double *ctr, double rho, const double *U, const double *W, const double *q,
                         double R, unsigned src, cut *out)
{
    double w[3];
    sub3(ctr, q, w);
    double A = 2 * rho * dot3(w, U), B = 2 * rho * dot3(w, W), C = R * R - dot3(w, w) - rho * rho;
    double M = sqrt(A * A + B * B);
    if (!(M > 0) || fabs(C) > M) return 0;
    double base = atan2(B, A), off = acos(C / M);
    out[0].phi = base - off; out[0].src = src;
    out[1].phi = base + off; out[1].src = src;
    return 2;
}

/* Angles where the circle crosses the plane (p - q).n = 0. */
static int circle_plane(const double *ctr, double rho, const double *U, const double *W, const double *q,
                        const double *n, unsigned src, cut *out)
{
    double w[3];
    sub3(ctr, q, w);
    double A = rho * dot3(U, n), B = rho * dot3(W, n), C = -dot3(w, n);
    double M = sqrt(A * A + B * B);
    if (!(M > 0) || fabs(C) > M) return 0;
    double base = atan2(B, A), off = acos(C / M);
    out[0].phi = base - off; out[0].src = src;
    out[1].phi = base + off; out[1].src = src;
    return 2;
}

/* Angles where the circle crosses the infinite cylinder around c's axis:
 * |perp(p - a)|^2 - r^2 is a trigonometric polynomial of degree 2 in phi;
 * with t = tan(phi/2) on each half turn it is a quartic in t on [-1, 1]. */
static int circle_cylinder(const double *ctr, double rho, const double *U, const double *W, const capsule *c,
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
static void trig_antideriv(double phi, double *F)
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
static void lin_times_lin(const double *a, const double *b, double *q)
{
    q[0] = a[0] * b[0];
    q[1] = a[0] * b[1] + a[1] * b[0];
    q[2] = a[0] * b[2] + a[2] * b[0];
    q[3] = a[1] * b[1];
    q[4] = a[1] * b[2] + a[2] * b[1];
    q[5] = a[2] * b[2];
}

static void quad_times_lin(const double *q, const double *l, double *c)
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

/* Is the point p of the cap sphere (centre ctr0) inside another capsule? */
static int covered_by_others(const piece_ctx *P, const double *ctr0, const double *p)
{
    for (int jj = 0; jj < P->nnb; jj++) {
        const int j = P->nb[jj];
        const capsule *cj = &P->c[j];
        int share = P->share[jj];
        if (share == SHARE_BALL_A || share == SHARE_BALL_B) {
            /* on the shared sphere: inside j's cylinder on j's side of the
             * ball's centre, on j's surface (a tie) elsewhere */
            double w[3];
            sub3(p, ctr0, w);
            double side = dot3(w, cj->e) * (share == SHARE_BALL_A ? 1.0 : -1.0);
            if (side <= 0) {
                share = SHARE_ALL;
            } else if (side < cj->len) {
                /* within j's slab, and |p - ctr0| = r_j: strictly inside j's
                 * cylinder (decided here because the distance test would
                 * round the points near the equator either way) */
                return 1;
            }
        }
        if (share == SHARE_ALL) {
            if (j < P->i) return 1;
            continue;
        }
        if (share == SHARE_AXIS) {
            double w[3];
            sub3(p, cj->a, w);
            double s = dot3(w, cj->e);
            if (s > 0 && s < cj->len) return 1;
        }
        if (dist2_segment(cj, p) < cj->r * cj->r) return 1;
    }
    return 0;
}

/* Circle of latitude at axial height w r above the cap's base. */
static uint64_t cap_eval(double w, void *ctx, double *out)
{
    const piece_ctx *P = ctx;
    const capsule *ci = &P->c[P->i];
    const double r = ci->r, *end = P->sgn > 0 ? ci->b : ci->a;
    const double rho = r * sqrt(fmax(0.0, 1.0 - w * w));
    double ctr[3];
    for (int k = 0; k < 3; k++) ctr[k] = end[k] + P->sgn * r * w * ci->e[k];
    /* Every angle where the circle may cross another capsule's surface; the
     * arcs between them are classified by their midpoints. */
    cut cuts[2 + 10 * CD_MAX_ARMS];
    int nc = 0;
    cuts[nc].phi = -0.5 * NUM_PI; cuts[nc++].src = SRC_START;
    cuts[nc].phi = 1.5 * NUM_PI; cuts[nc++].src = SRC_START;
    for (int jj = 0; jj < P->nnb; jj++) {
        int j = P->nb[jj];
        const capsule *cj = &P->c[j];
        /* A circle whose centre is further than rho + r_j from the axis
         * cannot meet capsule j: skip the root finding. */
        double reach = rho + cj->r;
        if (dist2_segment(cj, ctr) > reach * reach) continue;
        nc += circle_sphere(ctr, rho, ci->u, ci->v, cj->a, cj->r, (unsigned)j, cuts + nc);
        if (cj->len > 0) {
            nc += circle_sphere(ctr, rho, ci->u, ci->v, cj->b, cj->r, (unsigned)j, cuts + nc);
            nc += circle_cylinder(ctr, rho, ci->u, ci->v, cj, (unsigned)j, cuts + nc);
            /* On a sphere shared with one of j's balls the part inside j's
             * cylinder ends at the ball's equator, where the shared part (a
             * tie) begins: no root above marks it. */
            if (P->share[jj] == SHARE_BALL_A || P->share[jj] == SHARE_BALL_B)
                nc += circle_plane(ctr, rho, ci->u, ci->v, end, cj->e, (unsigned)j, cuts + nc);
            if (P->share[jj] == SHARE_AXIS) { /* likewise at j's end planes */
                nc += circle_plane(ctr, rho, ci->u, ci->v, cj->a, cj->e, (unsigned)j, cuts + nc);
                nc += circle_plane(ctr, rho, ci->u, ci->v, cj->b, cj->e, (unsigned)j, cuts + nc);
            }
        }
    }
    for (int k = 0; k < nc; k++) { /* wrap into [-pi/2, 3pi/2] */
        while (cuts[k].phi < -0.5 * NUM_PI) cuts[k].phi += 2 * NUM_PI;
        while (cuts[k].phi > 1.5 * NUM_PI) cuts[k].phi -= 2 * NUM_PI;
    }
    qsort(cuts, (size_t)nc, sizeof cuts[0], cut_cmp);
    double I[10] = {0}, F0[10], F1[10];
    uint64_t sig = SIG_START;
    int prev = -1, narcs = 0;
    trig_antideriv(cuts[0].phi, F0);
    for (int k = 0; k + 1 < nc; k++) {
        double p0 = cuts[k].phi, p1 = cuts[k + 1].phi;
        if (!(p1 > p0)) continue;
        double m = 0.5 * (p0 + p1), p[3];
        for (int q = 0; q < 3; q++) p[q] = ctr[q] + rho * (cos(m) * ci->u[q] + sin(m) * ci->v[q]);
        int exposed = !covered_by_others(P, end, p);
        if (exposed != prev) { sig = sig_add(sig_add(sig, cuts[k].src), (unsigned)exposed); narcs++; }
        prev = exposed;
        trig_antideriv(p1, F1);
        if (exposed)
            for (int q = 0; q < 10; q++) I[q] += F1[q] - F0[q];
        memcpy(F0, F1, sizeof F0);
    }
    /* p = ctr + rho (c u + s v); n = (p - end)/r; p.n = end.n + r. */
    double h[3] = {P->sgn * w * dot3(end, ci->e) + r, rho / r * dot3(end, ci->u), rho / r * dot3(end, ci->v)};
    double px[3][3], q6[6], c10[10];
    for (int a = 0; a < 3; a++) { px[a][0] = ctr[a]; px[a][1] = rho * ci->u[a]; px[a][2] = rho * ci->v[a]; }
    const double r2 = r * r;
    out[0] = r2 * I[0];
    out[1] = r2 * (h[0] * I[0] + h[1] * I[1] + h[2] * I[2]) / 3.0;
    for (int a = 0; a < 3; a++) {
        lin_times_lin(px[a], h, q6);
        double acc = 0;
        for (int q = 0; q < 6; q++) acc += q6[q] * I[q];
        out[2 + a] = r2 * acc / 4.0;
    }
    int m = 5;
    for (int a = 0; a < 3; a++)
        for (int b = a; b < 3; b++) {
            lin_times_lin(px[a], px[b], q6);
            quad_times_lin(q6, h, c10);
            double acc = 0;
            for (int q = 0; q < 10; q++) acc += c10[q] * I[q];
            out[m++] = r2 * acc / 5.0;
        }
    return sig_add(sig, (unsigned)narcs);
}

/* ---- piecewise-analytic adaptive quadrature ---------------------------- */

/* Kronrod 15-point nodes (positive half, the last is 0) and weights; nodes
 * 1, 3, 5, 7 are the 7-point Gauss nodes with weights gk_g. */
static const double gk_x[8] = {
    0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
    0.207784955007898467600689403773245, 0.0};
static const double gk_w[8] = {
    0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
    0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
static const double gk_g[4] = {
    0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
    0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

typedef uint64_t (*pw_fn)(double x, void *ctx, double *out);

typedef struct {
    pw_fn f;
    void *ctx;
    const double *weight;    /* per component: makes the error comparable across units */
    double xres;             /* events are located to this width (parameter units) */
    long evals;
    int events;              /* changes located so far */
} pw_job;

/* Past this many located changes in one integral the signature is no longer
 * trusted (numerical flicker at a degenerate configuration) and plain
 * adaptive bisection takes over. */
#define PW_MAX_EVENTS 400

/* One analytic piece [p, q] mapped by x = m - h cos(t), t in [0, pi]. */
typedef struct {
    double p, q, m, h;
    uint64_t sig;            /* signature inside */
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
        if (pw_eval(J, m, tmp) == s) x_same = m; else x_diff = m;
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
    static _Thread_local struct { double ta, tb, err, K[NCOMP]; } P[PW_MAX_PANELS];
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
static void pw_integrate(pw_job *J, double A, double B, int nsample, double tol, double *acc)
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
    for (int k = 0; k + 1 < nb; k++)
        pw_piecewise(J, brk[k], brk[k + 1], tol * (brk[k + 1] - brk[k]) / (B - A), 0, acc);
}

/* ---- driver ------------------------------------------------------------ */

/* Distance between the axis segments of two capsules [m]: the smallest of
 * the four end-to-segment distances and, if it lies inside both, the
 * common perpendicular. */
static double segment_distance(const capsule *p, const capsule *q)
{
    double d = sqrt(fmin(fmin(dist2_segment(q, p->a), dist2_segment(q, p->b)),
                         fmin(dist2_segment(p, q->a), dist2_segment(p, q->b))));
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

/* Same axis line and radius (to TIE): the lateral surfaces coincide. */
static int coaxial_same(const capsule *p, const capsule *q)
{
    if (fabs(p->r - q->r) > TIE * p->r) return 0;
    double x[3] = {p->e[1] * q->e[2] - p->e[2] * q->e[1], p->e[2] * q->e[0] - p->e[0] * q->e[2],
                   p->e[0] * q->e[1] - p->e[1] * q->e[0]};
    if (dot3(x, x) > TIE * TIE) return 0;
    double w[3];
    sub3(q->a, p->a, w);
    double s = dot3(w, p->e);
    for (int k = 0; k < 3; k++) w[k] -= s * p->e[k];
    return dot3(w, w) <= TIE * TIE * p->r * p->r;
}

/* How the sphere of centre ctr, radius r meets q's surface (SHARE_*). */
static unsigned char sphere_shared(const double *ctr, double r, const capsule *q)
{
    if (fabs(q->r - r) > TIE * r) return SHARE_NONE;
    double da[3], db[3];
    sub3(ctr, q->a, da);
    sub3(ctr, q->b, db);
    const double tol2 = TIE * TIE * r * r;
    if (dot3(da, da) <= tol2) return q->len > 0 ? SHARE_BALL_A : SHARE_ALL;
    if (dot3(db, db) <= tol2) return SHARE_BALL_B;
    if (q->len > 0) {
        double s = dot3(da, q->e);
        for (int k = 0; k < 3; k++) da[k] -= s * q->e[k];
        if (dot3(da, da) <= tol2) return SHARE_AXIS;
    }
    return SHARE_NONE;
}

/* Surface integrals of every capsule's exposed surface, summed:
 * {A, V, Sx, Sy, Sz, Sxx, Sxy, Sxz, Syy, Syz, Szz} about the reference. */
static long union_integrals(int n, const capsule *c, const double *weight, double tol_rel, int nsample,
                            double *tot)
{
    long evals = 0;
    for (int k = 0; k < NCOMP; k++) tot[k] = 0;
    double tol = tol_rel / (3.0 * n); /* three surface pieces per capsule share it */
    for (int i = 0; i < n; i++) {
        /* Only capsules within reach of this capsule's surface matter: the
         * evaluations get cheaper and the signatures simpler. */
        piece_ctx P;
        memset(&P, 0, sizeof P);
        P.i = i;
        P.c = c;
        for (int j = 0; j < n; j++) {
            if (j == i || !(segment_distance(&c[i], &c[j]) < c[i].r + c[j].r)) continue;
            P.share[P.nnb] = c[i].len > 0 && c[j].len > 0 && coaxial_same(&c[i], &c[j]) ? SHARE_ALL : SHARE_NONE;
            P.nb[P.nnb++] = j;
        }
        if (c[i].len > 0) {
            pw_job J = {lateral_eval, &P, weight, 1e-14 * 2 * NUM_PI, 0, 0};
            pw_integrate(&J, 0.0, 2 * NUM_PI, P.nnb ? nsample : 1, tol, tot);
            evals += J.evals;
        }
        for (int end = 0; end < 2; end++) {
            P.sgn = end ? 1.0 : -1.0;
            piece_ctx Q = P; /* a cap only meets capsules within r_i + r_j of its centre */
            Q.nnb = 0;
            const double *ctr0 = end ? c[i].b : c[i].a;
            for (int jj = 0; jj < P.nnb; jj++) {
                int j = P.nb[jj];
                if (!(dist2_segment(&c[j], ctr0) < (c[i].r + c[j].r) * (c[i].r + c[j].r))) continue;
                Q.share[Q.nnb] = sphere_shared(ctr0, c[i].r, &c[j]);
                Q.nb[Q.nnb++] = j;
            }
            pw_job J = {cap_eval, &Q, weight, 1e-14, 0, 0};
            pw_integrate(&J, 0.0, 1.0, Q.nnb ? nsample : 1, tol, tot);
            evals += J.evals;
        }
    }
    return evals;
}

int cd_shapes_union_numeric(int n, const double (*a)[3], const double (*b)[3], const double *r,
                            cd_union_props *out)
{
    if (n < 1 || n > CD_MAX_ARMS) return -1;
    capsule c[CD_MAX_ARMS];
    int m = 0;
    double ref[3] = {0, 0, 0}, vol_est = 0, area_est = 0;
    for (int i = 0; i < n; i++) {
        if (!(r[i] > 0) || !isfinite(r[i])) return -1;
        for (int k = 0; k < 3; k++)
            if (!isfinite(a[i][k]) || !isfinite(b[i][k])) return -1;
        /* Identical arms (either orientation) have coincident surfaces, each
         * inside neither: keep one. */
        int dup = 0;
        for (int j = 0; j < i && !dup; j++) {
            int same = r[i] == r[j], swap = r[i] == r[j];
            for (int k = 0; k < 3; k++) {
                same = same && a[i][k] == a[j][k] && b[i][k] == b[j][k];
                swap = swap && a[i][k] == b[j][k] && b[i][k] == a[j][k];
            }
            dup = same || swap;
        }
        if (dup) continue;
        capsule_init(&c[m], a[i], b[i], r[i]);
        double vi = NUM_PI * r[i] * r[i] * (c[m].len + 4.0 / 3.0 * r[i]);
        vol_est += vi;
        area_est += 2 * NUM_PI * r[i] * (c[m].len + 2 * r[i]);
        for (int k = 0; k < 3; k++) ref[k] += vi * 0.5 * (a[i][k] + b[i][k]);
        m++;
    }
    /* Work about the volume-weighted centre of the arms: close to the centre
     * of mass, so neither p.n nor the parallel-axis shift lose digits. */
    for (int k = 0; k < 3; k++) ref[k] /= vol_est;
    double R = 0;
    for (int i = 0; i < m; i++) {
        for (int k = 0; k < 3; k++) { c[i].a[k] -= ref[k]; c[i].b[k] -= ref[k]; }
        double ra = sqrt(dot3(c[i].a, c[i].a)) + c[i].r, rb = sqrt(dot3(c[i].b, c[i].b)) + c[i].r;
        if (ra > R) R = ra;
        if (rb > R) R = rb;
    }
    /* Error weights: area against the sum of the arms' areas, a moment of
     * degree p against V R^p. */
    double weight[NCOMP];
    weight[0] = 1.0 / area_est;
    weight[1] = 1.0 / vol_est;
    for (int k = 2; k < 5; k++) weight[k] = 1.0 / (vol_est * R);
    for (int k = 5; k < NCOMP; k++) weight[k] = 1.0 / (vol_est * R * R);

    /* Two tolerances 1e4 apart, with different sampling of the events: the
     * change bounds the error of the finer result. */
    double coarse[NCOMP], fine[NCOMP];
    union_integrals(m, c, weight, 1e-9, NS_COARSE, coarse);
    union_integrals(m, c, weight, 1e-13, NS_FINE, fine);

    const int idx[3][3] = {{5, 6, 7}, {6, 8, 9}, {7, 9, 10}};
    double V = fine[1], g[3] = {fine[2] / V, fine[3] / V, fine[4] / V};
    double Vc = coarse[1], gc[3] = {coarse[2] / Vc, coarse[3] / Vc, coarse[4] / Vc};
    out->volume = V;
    out->area = fine[0];
    double ei = 0, tr = 0;
    for (int i = 0; i < 3; i++) {
        out->com[i] = ref[i] + g[i];
        for (int j = 0; j < 3; j++) {
            out->central[i][j] = fine[idx[i][j]] - V * g[i] * g[j]; /* parallel axes */
            double cc = coarse[idx[i][j]] - Vc * gc[i] * gc[j];
            if (fabs(out->central[i][j] - cc) > ei) ei = fabs(out->central[i][j] - cc);
        }
        tr += out->central[i][i];
    }
    double ev = fmax(fabs(V - Vc) / V, ei / tr);
    double ea = fabs(fine[0] - coarse[0]) / fine[0];
    /* The finer pass converges far faster than the change between the
     * passes, but rounding near tangent contacts (chord ends there are
     * ill-conditioned) leaves a bias both passes share: a factor 10 and a
     * floor of 1e-12 cover what was measured (docs/shapes.md). */
    out->volume_rel_error = fmax(10 * ev, 1e-12);
    out->area_rel_error = fmax(10 * ea, 1e-12);
    return 0;
}
