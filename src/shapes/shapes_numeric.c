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
 * ten times their difference (at least 1e-12) is reported as the error
 * bound of the finer result.
 *
 * This file has the surface evaluators and the driver; the capsule
 * geometry is in shapes_numeric_geom.c, the piecewise quadrature in
 * shapes_numeric_quad.c, and the declarations they share in
 * shapes_numeric_internal.h. */
#include "shapes/shapes_numeric_internal.h"
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

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
    SHARE_BALL_A, /* cap sphere = j's ball at a_j: j's inside is the side +e_j */
    SHARE_BALL_B, /* cap sphere = j's ball at b_j: side -e_j */
    SHARE_ALL,    /* cap sphere = j, a ball; or lateral cylinder = j's cylinder */
    SHARE_AXIS,   /* cap sphere centred on j's axis with j's radius: it touches
                    * j's cylinder along its equator and is inside it between
                    * j's end planes */
};

typedef struct {
    int i; /* the capsule whose surface is swept */
    const capsule *c;
    double sgn;                       /* caps: +1 at end b (outward +e), -1 at end a */
    int nnb, nb[CD_MAX_ARMS];         /* the other capsules that can reach this piece */
    unsigned char share[CD_MAX_ARMS]; /* SHARE_* per neighbour */
} piece_ctx;

typedef struct {
    double lo, hi;
    unsigned slo, shi;
} span;

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
            if (lo > hi) {
                double t = lo;
                lo = hi;
                hi = t;
            }
        } else if (!cd_shn_line_capsule(&P->c[j], q, ci->e, &lo, &hi)) {
            continue;
        }
        unsigned ulo = (unsigned)j, uhi = (unsigned)j;
        if (lo < 0) {
            lo = 0;
            ulo = SRC_CLIP_LO;
        }
        if (hi > len) {
            hi = len;
            uhi = SRC_CLIP_HI;
        }
        if (hi > lo) {
            s[ns].lo = lo;
            s[ns].hi = hi;
            s[ns].slo = ulo;
            s[ns].shi = uhi;
            ns++;
        }
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
            if (s[k].hi > hi) {
                hi = s[k].hi;
                shi = s[k].shi;
            }
        sig = sig_add(sig_add(sig, slo), shi);
        D1 += lo - t;
        D2 += 0.5 * (lo * lo - t * t);
        D3 += (lo * lo * lo - t * t * t) / 3.0;
        t = hi;
    }
    D1 += len - t;
    D2 += 0.5 * (len * len - t * t);
    D3 += (len * len * len - t * t * t) / 3.0;
    double h = dot3(q, n); /* p.n [m] */
    out[0] = r * D1;
    out[1] = r * h * D1 / 3.0;
    for (int a = 0; a < 3; a++) out[2 + a] = r * h * (q[a] * D1 + ci->e[a] * D2) / 4.0;
    int m = 5;
    for (int a = 0; a < 3; a++)
        for (int b = a; b < 3; b++)
            out[m++] =
                r * h * (q[a] * q[b] * D1 + (q[a] * ci->e[b] + q[b] * ci->e[a]) * D2 + ci->e[a] * ci->e[b] * D3) / 5.0;
    return sig_add(sig, (unsigned)ns);
}

/* ---- caps -------------------------------------------------------------- */

static int cut_cmp(const void *p, const void *q)
{
    const cut *x = p, *y = q;
    return (x->phi > y->phi) - (x->phi < y->phi);
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
        if (cd_shn_dist2_segment(cj, p) < cj->r * cj->r) return 1;
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
    cut cuts[2 + 16 * CD_MAX_ARMS]; /* per capsule: 2 + 2 sphere, 8 cylinder, 4 plane */
    int nc = 0;
    cuts[nc].phi = -0.5 * NUM_PI;
    cuts[nc++].src = SRC_START;
    cuts[nc].phi = 1.5 * NUM_PI;
    cuts[nc++].src = SRC_START;
    for (int jj = 0; jj < P->nnb; jj++) {
        int j = P->nb[jj];
        const capsule *cj = &P->c[j];
        /* A circle whose centre is further than rho + r_j from the axis
         * cannot meet capsule j: skip the root finding. */
        double reach = rho + cj->r;
        if (cd_shn_dist2_segment(cj, ctr) > reach * reach) continue;
        nc += cd_shn_circle_sphere(ctr, rho, ci->u, ci->v, cj->a, cj->r, (unsigned)j, cuts + nc);
        if (cj->len > 0) {
            nc += cd_shn_circle_sphere(ctr, rho, ci->u, ci->v, cj->b, cj->r, (unsigned)j, cuts + nc);
            nc += cd_shn_circle_cylinder(ctr, rho, ci->u, ci->v, cj, (unsigned)j, cuts + nc);
            /* On a sphere shared with one of j's balls the part inside j's
             * cylinder ends at the ball's equator, where the shared part (a
             * tie) begins: no root above marks it. */
            if (P->share[jj] == SHARE_BALL_A || P->share[jj] == SHARE_BALL_B)
                nc += cd_shn_circle_plane(ctr, rho, ci->u, ci->v, end, cj->e, (unsigned)j, cuts + nc);
            if (P->share[jj] == SHARE_AXIS) { /* likewise at j's end planes */
                nc += cd_shn_circle_plane(ctr, rho, ci->u, ci->v, cj->a, cj->e, (unsigned)j, cuts + nc);
                nc += cd_shn_circle_plane(ctr, rho, ci->u, ci->v, cj->b, cj->e, (unsigned)j, cuts + nc);
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
    cd_shn_trig_antideriv(cuts[0].phi, F0);
    for (int k = 0; k + 1 < nc; k++) {
        double p0 = cuts[k].phi, p1 = cuts[k + 1].phi;
        if (!(p1 > p0)) continue;
        double m = 0.5 * (p0 + p1), p[3];
        for (int q = 0; q < 3; q++) p[q] = ctr[q] + rho * (cos(m) * ci->u[q] + sin(m) * ci->v[q]);
        int exposed = !covered_by_others(P, end, p);
        if (exposed != prev) {
            sig = sig_add(sig_add(sig, cuts[k].src), (unsigned)exposed);
            narcs++;
        }
        prev = exposed;
        cd_shn_trig_antideriv(p1, F1);
        if (exposed)
            for (int q = 0; q < 10; q++) I[q] += F1[q] - F0[q];
        memcpy(F0, F1, sizeof F0);
    }
    /* p = ctr + rho (c u + s v); n = (p - end)/r; p.n = end.n + r. */
    double h[3] = {P->sgn * w * dot3(end, ci->e) + r, rho / r * dot3(end, ci->u), rho / r * dot3(end, ci->v)};
    double px[3][3], q6[6], c10[10];
    for (int a = 0; a < 3; a++) {
        px[a][0] = ctr[a];
        px[a][1] = rho * ci->u[a];
        px[a][2] = rho * ci->v[a];
    }
    const double r2 = r * r;
    out[0] = r2 * I[0];
    out[1] = r2 * (h[0] * I[0] + h[1] * I[1] + h[2] * I[2]) / 3.0;
    for (int a = 0; a < 3; a++) {
        cd_shn_lin_times_lin(px[a], h, q6);
        double acc = 0;
        for (int q = 0; q < 6; q++) acc += q6[q] * I[q];
        out[2 + a] = r2 * acc / 4.0;
    }
    int m = 5;
    for (int a = 0; a < 3; a++)
        for (int b = a; b < 3; b++) {
            cd_shn_lin_times_lin(px[a], px[b], q6);
            cd_shn_quad_times_lin(q6, h, c10);
            double acc = 0;
            for (int q = 0; q < 10; q++) acc += c10[q] * I[q];
            out[m++] = r2 * acc / 5.0;
        }
    return sig_add(sig, (unsigned)narcs);
}

/* ---- driver ------------------------------------------------------------ */

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
static long union_integrals(int n, const capsule *c, const double *weight, double tol_rel, int nsample, double *tot)
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
            if (j == i || !(cd_shn_segment_distance(&c[i], &c[j]) < c[i].r + c[j].r)) continue;
            P.share[P.nnb] = c[i].len > 0 && c[j].len > 0 && coaxial_same(&c[i], &c[j]) ? SHARE_ALL : SHARE_NONE;
            P.nb[P.nnb++] = j;
        }
        if (c[i].len > 0) {
            pw_job J = {lateral_eval, &P, weight, 1e-14 * 2 * NUM_PI, 0, 0};
            cd_shn_pw_integrate(&J, 0.0, 2 * NUM_PI, P.nnb ? nsample : 1, tol, tot);
            evals += J.evals;
        }
        for (int end = 0; end < 2; end++) {
            P.sgn = end ? 1.0 : -1.0;
            piece_ctx Q = P; /* a cap only meets capsules within r_i + r_j of its centre */
            Q.nnb = 0;
            const double *ctr0 = end ? c[i].b : c[i].a;
            for (int jj = 0; jj < P.nnb; jj++) {
                int j = P.nb[jj];
                if (!(cd_shn_dist2_segment(&c[j], ctr0) < (c[i].r + c[j].r) * (c[i].r + c[j].r))) continue;
                Q.share[Q.nnb] = sphere_shared(ctr0, c[i].r, &c[j]);
                Q.nb[Q.nnb++] = j;
            }
            pw_job J = {cap_eval, &Q, weight, 1e-14, 0, 0};
            cd_shn_pw_integrate(&J, 0.0, 1.0, Q.nnb ? nsample : 1, tol, tot);
            evals += J.evals;
        }
    }
    return evals;
}

int cd_shapes_union_numeric(int n, const double (*a)[3], const double (*b)[3], const double *r, cd_union_props *out)
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
        cd_shn_capsule_init(&c[m], a[i], b[i], r[i]);
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
        for (int k = 0; k < 3; k++) {
            c[i].a[k] -= ref[k];
            c[i].b[k] -= ref[k];
        }
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
