/* Shape catalogue: named clusters of spherocylinders (sphere, rod, cross,
 * hexapod) and general segment lists, with the mass properties of the union
 * of their arms (docs/references.md, Particles, docs/shapes.md).
 *
 * Closed forms are used wherever the union decomposes into known pieces:
 * the sphere, one capsule, and crosses / hexapods with aspect >= 2, where
 * the arms overlap only in the central Steinmetz bicylinders and the
 * tricylinder (the end caps reach no other arm).  Everything else goes to
 * the converged numerical method of shapes_numeric.c. */
#include "shapes/shapes.h"
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#define SH_PI 3.14159265358979323846

static int fail(char *err, size_t errlen, const char *fmt, ...)
{
    if (err && errlen > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, errlen, fmt, ap);
        va_end(ap);
    }
    return -1;
}

/* ---- closed forms ------------------------------------------------------ */

/* One capsule of axis length l and radius r, centred, axis along x:
 * volume [m^3], area [m^2] and the second moments int x^2 dV (along the
 * axis) and int y^2 dV (= int z^2 dV, across it) [m^5]. */
static void capsule_closed(double l, double r, double *V, double *A, double *s_ax, double *s_perp)
{
    const double r2 = r * r, r3 = r2 * r, r4 = r3 * r, r5 = r4 * r;
    *V = SH_PI * r2 * l + 4.0 / 3.0 * SH_PI * r3;
    *A = 2.0 * SH_PI * r * l + 4.0 * SH_PI * r2;
    /* cylinder: pi r^2 l^3/12; two hemispheres at +-l/2, each
     * int (l/2 + u)^2 dV = (l^2/4)(2pi r^3/3) + l (pi r^4/4) + 2pi r^5/15 */
    *s_ax = SH_PI * r2 * l * l * l / 12.0 + SH_PI * r3 * l * l / 3.0 + SH_PI * r4 * l / 2.0 + 4.0 * SH_PI * r5 / 15.0;
    /* cylinder: pi r^4 l/4; the two caps make one ball: 4pi r^5/15 */
    *s_perp = SH_PI * r4 * l / 4.0 + 4.0 * SH_PI * r5 / 15.0;
}

/* Steinmetz bicylinder of two radius-r cylinders (axes x and y): volume
 * 16/3 r^3, surface 16 r^2 (half on each cylinder).  Slices z = const are
 * squares of half-side s = sqrt(r^2 - z^2), so
 *   int x^2 dV = int (4/3) s^4 dz = 64/45 r^5   (same for y),
 *   int z^2 dV = int 4 s^2 z^2 dz = 16/15 r^5   (the common normal). */
#define BICYL_V(r3)        (16.0 / 3.0 * (r3))
#define BICYL_A(r2)        (16.0 * (r2))
#define BICYL_S_IN(r5)     (64.0 / 45.0 * (r5))
#define BICYL_S_NORMAL(r5) (16.0 / 15.0 * (r5))

/* Tricylinder (three radius-r cylinders along x, y, z): volume
 * 8 (2 - sqrt2) r^3, surface 24 (2 - sqrt2) r^2 (a third on each).  Split
 * into 48 copies of {0 <= z <= y <= x, x^2 + y^2 <= r^2}, where the other
 * two cylinders are implied; in polar (rho, theta < pi/4) with
 * 0 <= z <= rho sin(theta):
 *   int (x^2 + y^2) = r^5/5 (1 - 1/sqrt2),
 *   int z^2 = r^5/15 int_0^{pi/4} sin^3 = r^5/15 (2/3 - 5/(6 sqrt2)),
 * so int x^2 dV = 48/3 (their sum) = 16/5 (11/9 - 23 sqrt2/36) r^5. */
#define SQRT2        1.41421356237309504880
#define TRICYL_V(r3) (8.0 * (2.0 - SQRT2) * (r3))
#define TRICYL_A(r2) (24.0 * (2.0 - SQRT2) * (r2))
#define TRICYL_S(r5) (16.0 / 5.0 * (11.0 / 9.0 - 23.0 * SQRT2 / 36.0) * (r5))

/* ---- common filling ---------------------------------------------------- */

/* Fills the mass properties from the volume, area and the second moments
 * S_ij = int x_i x_j dV about the centre of mass in the frame of the arms,
 * which must be principal (S diagonal). */
static void fill_mass(cd_shape *s, double density, double V, double A, const double S[3][3])
{
    s->density = density;
    s->volume = V;
    s->area = A;
    s->mass = density * V;
    /* psi = surface of the volume-equivalent sphere / surface */
    s->sphericity = cbrt(SH_PI) * pow(6.0 * V, 2.0 / 3.0) / A;
    double tr = S[0][0] + S[1][1] + S[2][2];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) s->inertia[i][j] = density * ((i == j ? tr : 0.0) - S[i][j]);
        s->principal[i] = s->inertia[i][i];
    }
    double R = 0;
    for (int k = 0; k < s->n_prims; k++) {
        double ra = sqrt(s->a[k].x * s->a[k].x + s->a[k].y * s->a[k].y + s->a[k].z * s->a[k].z) + s->radius[k];
        double rb = sqrt(s->b[k].x * s->b[k].x + s->b[k].y * s->b[k].y + s->b[k].z * s->b[k].z) + s->radius[k];
        if (ra > R) R = ra;
        if (rb > R) R = rb;
    }
    s->bounding_radius = R;
}

static int check_positive(const char *what, const char *name, double x, const char *unit, char *err, size_t errlen)
{
    if (!isfinite(x) || !(x > 0))
        return fail(err, errlen, "%s: %s = %g %s, expected a finite number > 0", what, name, x, unit);
    return 0;
}

/* ---- named shapes ------------------------------------------------------ */

/* The names of enum cd_shape_kind, in its order. */
static const char *const shape_kind_names[] = {"sphere", "rod", "cross", "hexapod", "segments"};

int cd_shape_make_named(const char *kind, double aspect, double diameter, double density, cd_shape *out, char *err,
                        size_t errlen)
{
    for (int k = CD_SHAPE_SPHERE; k <= CD_SHAPE_HEXAPOD; k++)
        if (kind && strcmp(kind, shape_kind_names[k]) == 0)
            return cd_shape_make_kind(k, aspect, diameter, density, out, err, errlen);
    return fail(err, errlen, "shape kind '%s' unknown, expected sphere, rod, cross or hexapod%s",
                kind ? kind : "(null)",
                kind && strcmp(kind, "segments") == 0 ? " (a segment list needs its segments)" : "");
}

int cd_shape_make_kind(int shape_kind, double aspect, double diameter, double density, cd_shape *out, char *err,
                       size_t errlen)
{
    if (shape_kind < CD_SHAPE_SPHERE || shape_kind > CD_SHAPE_HEXAPOD)
        return fail(err, errlen, "shape kind %d is not a named shape (sphere, rod, cross or hexapod)", shape_kind);
    const char *kind = shape_kind_names[shape_kind];
    const int n_arms = shape_kind == CD_SHAPE_SPHERE ? 1 : shape_kind; /* rod 1, cross 2, hexapod 3 */
    const int is_sphere = shape_kind == CD_SHAPE_SPHERE;
    if (!isfinite(aspect) || aspect < 1.0)
        return fail(err, errlen, "%s: aspect = %g, expected a number >= 1 (tip-to-tip length L over arm diameter d_p)",
                    kind, aspect);
    if (is_sphere && fabs(aspect - 1.0) > 1e-12)
        return fail(err, errlen, "sphere: aspect = %g, expected 1 (a sphere has L = d_p; use rod for longer bodies)",
                    aspect);
    if (check_positive(kind, "diameter", diameter, "m", err, errlen)) return -1;
    if (check_positive(kind, "density", density, "kg/m^3", err, errlen)) return -1;

    memset(out, 0, sizeof *out);
    snprintf(out->kind, sizeof out->kind, "%s", kind);
    const double r = 0.5 * diameter;                              /* [m] */
    const double l = is_sphere ? 0.0 : (aspect - 1.0) * diameter; /* axis length L - d_p [m] */
    /* With aspect 1 every arm is the same ball: keep one primitive, or the
     * contact search would count each touch once per copy. */
    out->n_prims = l > 0 ? n_arms : 1;
    for (int k = 0; k < out->n_prims; k++) {
        double h = 0.5 * l, ea[3] = {0, 0, 0}, eb[3] = {0, 0, 0};
        ea[k] = -h;
        eb[k] = h;
        out->a[k] = (cd_vec3){ea[0], ea[1], ea[2]};
        out->b[k] = (cd_vec3){eb[0], eb[1], eb[2]};
        out->radius[k] = r;
    }
    out->aspect = is_sphere ? 1.0 : aspect;
    out->tip_length = l + diameter;
    out->diameter = diameter;

    const double r2 = r * r, r3 = r2 * r, r5 = r3 * r2;
    double Vc, Ac, s_ax, s_perp, S[3][3] = {{0}};
    capsule_closed(l, r, &Vc, &Ac, &s_ax, &s_perp);
    double V, A;
    if (n_arms == 1 || l == 0) {
        /* one capsule (l = 0: every arm is the same ball) */
        V = Vc;
        A = Ac;
        S[0][0] = n_arms == 1 ? s_ax : s_perp;
        S[1][1] = S[2][2] = s_perp;
    } else if (l >= 2.0 * r) {
        /* aspect >= 2: inclusion-exclusion over the central bodies */
        if (n_arms == 2) {
            V = 2 * Vc - BICYL_V(r3);
            A = 2 * Ac - BICYL_A(r2);
            S[0][0] = S[1][1] = s_ax + s_perp - BICYL_S_IN(r5);
            S[2][2] = 2 * s_perp - BICYL_S_NORMAL(r5);
        } else {
            V = 3 * Vc - 3 * BICYL_V(r3) + TRICYL_V(r3);
            /* each arm loses its halves of two bicylinder surfaces, but its
             * third of the tricylinder surface was removed twice */
            A = 3 * Ac - 3 * BICYL_A(r2) + TRICYL_A(r2);
            S[0][0] = S[1][1] = S[2][2] = s_ax + 2 * s_perp - 2 * BICYL_S_IN(r5) - BICYL_S_NORMAL(r5) + TRICYL_S(r5);
        }
    } else {
        /* short arms: the caps overlap the other arms */
        double a[3][3], b[3][3], rr[3];
        for (int k = 0; k < n_arms; k++) {
            a[k][0] = out->a[k].x;
            a[k][1] = out->a[k].y;
            a[k][2] = out->a[k].z;
            b[k][0] = out->b[k].x;
            b[k][1] = out->b[k].y;
            b[k][2] = out->b[k].z;
            rr[k] = r;
        }
        cd_union_props p;
        if (cd_shapes_union_numeric(n_arms, (const double(*)[3])a, (const double(*)[3])b, rr, &p))
            return fail(err, errlen, "%s: numerical mass properties failed", kind);
        V = p.volume;
        A = p.area;
        /* Symmetry makes the centre the centre of mass and the arm axes
         * principal with equal moments in the plane of the arms: impose it
         * rather than keep the ~1e-16 numerical asymmetry. */
        double in_plane = 0;
        for (int k = 0; k < n_arms; k++) in_plane += p.central[k][k] / n_arms;
        for (int k = 0; k < 3; k++) S[k][k] = k < n_arms ? in_plane : p.central[k][k];
        out->volume_rel_error = p.volume_rel_error;
        out->area_rel_error = p.area_rel_error;
    }
    fill_mass(out, density, V, A, (const double(*)[3])S);
    return 0;
}

/* ---- general segment lists --------------------------------------------- */

/* Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations:
 * m becomes diagonal (the eigenvalues), q holds the eigenvectors as
 * columns.  Converges quadratically; 50 sweeps is far more than needed. */
static void jacobi3(double m[3][3], double q[3][3])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) q[i][j] = i == j;
    for (int sweep = 0; sweep < 50; sweep++) {
        double off = fabs(m[0][1]) + fabs(m[0][2]) + fabs(m[1][2]);
        double diag = fabs(m[0][0]) + fabs(m[1][1]) + fabs(m[2][2]);
        if (off <= 1e-300 || off <= 1e-17 * diag) break;
        for (int p = 0; p < 2; p++)
            for (int r = p + 1; r < 3; r++) {
                if (m[p][r] == 0) continue;
                /* rotation angle that zeroes m[p][r] (the smaller root, for stability) */
                double theta = (m[r][r] - m[p][p]) / (2 * m[p][r]);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 3; k++) { /* m <- m G */
                    double mkp = m[k][p], mkr = m[k][r];
                    m[k][p] = c * mkp - s * mkr;
                    m[k][r] = s * mkp + c * mkr;
                }
                for (int k = 0; k < 3; k++) { /* m <- G^T m */
                    double mpk = m[p][k], mrk = m[r][k];
                    m[p][k] = c * mpk - s * mrk;
                    m[r][k] = s * mpk + c * mrk;
                }
                for (int k = 0; k < 3; k++) { /* q <- q G */
                    double qkp = q[k][p], qkr = q[k][r];
                    q[k][p] = c * qkp - s * qkr;
                    q[k][r] = s * qkp + c * qkr;
                }
            }
    }
}

int cd_shape_make_segments(int n, const double (*a)[3], const double (*b)[3], const double *r, double density,
                           cd_shape *out, char *err, size_t errlen)
{
    if (n < 1 || n > CD_MAX_ARMS)
        return fail(err, errlen, "segments: %d segments, expected 1 to %d (CD_MAX_ARMS)", n, CD_MAX_ARMS);
    for (int i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++)
            if (!isfinite(a[i][k]) || !isfinite(b[i][k]))
                return fail(err, errlen, "segments: segment %d end coordinate = %g, expected a finite number [m]", i,
                            isfinite(a[i][k]) ? b[i][k] : a[i][k]);
        if (!isfinite(r[i]) || !(r[i] > 0))
            return fail(err, errlen, "segments: segment %d radius = %g m, expected a finite number > 0", i, r[i]);
    }
    if (check_positive("segments", "density", density, "kg/m^3", err, errlen)) return -1;

    double V, A, com[3], S[3][3], ev = 0, ea = 0;
    if (n == 1) {
        /* one capsule: closed form, rotated onto its axis */
        double d[3] = {b[0][0] - a[0][0], b[0][1] - a[0][1], b[0][2] - a[0][2]};
        double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), s_ax, s_perp;
        capsule_closed(l, r[0], &V, &A, &s_ax, &s_perp);
        for (int i = 0; i < 3; i++) {
            com[i] = 0.5 * (a[0][i] + b[0][i]);
            d[i] = l > 0 ? d[i] / l : (i == 0);
        }
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) S[i][j] = s_perp * (i == j) + (s_ax - s_perp) * d[i] * d[j];
    } else {
        cd_union_props p;
        if (cd_shapes_union_numeric(n, a, b, r, &p))
            return fail(err, errlen, "segments: numerical mass properties failed");
        V = p.volume;
        A = p.area;
        memcpy(com, p.com, sizeof com);
        memcpy(S, p.central, sizeof S);
        ev = p.volume_rel_error;
        ea = p.area_rel_error;
    }

    /* Principal frame: eigenvectors of S.  Moments of inertia are
     * rho (tr S - lambda), so descending lambda gives ascending moments
     * (a rod's axis becomes body x, as for the named rod). */
    double lam[3][3], q[3][3];
    memcpy(lam, S, sizeof lam);
    jacobi3(lam, q);
    int order[3] = {0, 1, 2};
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (lam[order[j]][order[j]] > lam[order[i]][order[i]]) {
                int t = order[i];
                order[i] = order[j];
                order[j] = t;
            }
    double R[3][3]; /* columns: principal axes in the input frame */
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) R[i][k] = q[i][order[k]];
    double det = R[0][0] * (R[1][1] * R[2][2] - R[1][2] * R[2][1]) - R[0][1] * (R[1][0] * R[2][2] - R[1][2] * R[2][0]) +
                 R[0][2] * (R[1][0] * R[2][1] - R[1][1] * R[2][0]);
    if (det < 0) /* keep the body frame right-handed */
        for (int i = 0; i < 3; i++) R[i][2] = -R[i][2];

    memset(out, 0, sizeof *out);
    snprintf(out->kind, sizeof out->kind, "segments");
    out->n_prims = n;
    for (int k = 0; k < n; k++) {
        double pa[3], pb[3];
        for (int j = 0; j < 3; j++) { /* body = R^T (x - com) */
            pa[j] = pb[j] = 0;
            for (int i = 0; i < 3; i++) {
                pa[j] += R[i][j] * (a[k][i] - com[i]);
                pb[j] += R[i][j] * (b[k][i] - com[i]);
            }
        }
        out->a[k] = (cd_vec3){pa[0], pa[1], pa[2]};
        out->b[k] = (cd_vec3){pb[0], pb[1], pb[2]};
        out->radius[k] = r[k];
        double len = sqrt((pb[0] - pa[0]) * (pb[0] - pa[0]) + (pb[1] - pa[1]) * (pb[1] - pa[1]) +
                          (pb[2] - pa[2]) * (pb[2] - pa[2]));
        if (len + 2 * r[k] > out->tip_length) out->tip_length = len + 2 * r[k];
        if (2 * r[k] > out->diameter) out->diameter = 2 * r[k];
        if ((len + 2 * r[k]) / (2 * r[k]) > out->aspect) out->aspect = (len + 2 * r[k]) / (2 * r[k]);
    }
    double Sd[3][3] = {{0}};
    for (int k = 0; k < 3; k++) Sd[k][k] = lam[order[k]][order[k]];
    out->volume_rel_error = ev;
    out->area_rel_error = ea;
    fill_mass(out, density, V, A, (const double(*)[3])Sd);
    return 0;
}

int cd_shape_from_species(const cd_species_config *sp, double density, cd_shape *out, char *err, size_t errlen)
{
    if (sp->shape == CD_SHAPE_SEGMENTS)
        return cd_shape_make_segments(sp->n_segments, (const double(*)[3])sp->seg_a, (const double(*)[3])sp->seg_b,
                                      sp->seg_radius, density, out, err, errlen);
    return cd_shape_make_kind(sp->shape, sp->aspect, sp->diameter, density, out, err, errlen);
}

/* ---- JSON -------------------------------------------------------------- */

/* %.17g round-trips a double; JSON has no inf or nan. */
static void json_num(FILE *f, double x)
{
    if (isfinite(x)) fprintf(f, "%.17g", x);
    else fputs("null", f);
}

static void json_vec(FILE *f, double x, double y, double z)
{
    fputc('[', f);
    json_num(f, x);
    fputs(", ", f);
    json_num(f, y);
    fputs(", ", f);
    json_num(f, z);
    fputc(']', f);
}

void cd_shape_print_json(const cd_shape *s, void *stream)
{
    FILE *f = stream;
    fputs("{\n  \"kind\": \"", f);
    for (const char *c = s->kind; *c; c++) { /* kinds are plain words; escape anyway */
        if (*c == '"' || *c == '\\') fputc('\\', f);
        if ((unsigned char)*c >= 0x20) fputc(*c, f);
    }
    fputs("\",\n", f);
    const struct {
        const char *key;
        double v;
    } scalars[] = {
        {"aspect", s->aspect}, {"diameter", s->diameter}, {"tip_length", s->tip_length}, {"density", s->density},
        {"volume", s->volume}, {"area", s->area},         {"sphericity", s->sphericity}, {"mass", s->mass},
    };
    for (size_t k = 0; k < sizeof scalars / sizeof scalars[0]; k++) {
        fprintf(f, "  \"%s\": ", scalars[k].key);
        json_num(f, scalars[k].v);
        fputs(",\n", f);
    }
    fputs("  \"inertia\": [", f);
    for (int i = 0; i < 3; i++) {
        json_vec(f, s->inertia[i][0], s->inertia[i][1], s->inertia[i][2]);
        fputs(i < 2 ? ", " : "],\n", f);
    }
    fputs("  \"principal_moments\": ", f);
    json_vec(f, s->principal[0], s->principal[1], s->principal[2]);
    fputs(",\n  \"bounding_radius\": ", f);
    json_num(f, s->bounding_radius);
    fprintf(f, ",\n  \"n_arms\": %d,\n  \"arms\": [", s->n_prims);
    for (int k = 0; k < s->n_prims; k++) {
        fputs(k ? ",\n    {\"a\": " : "\n    {\"a\": ", f);
        json_vec(f, s->a[k].x, s->a[k].y, s->a[k].z);
        fputs(", \"b\": ", f);
        json_vec(f, s->b[k].x, s->b[k].y, s->b[k].z);
        fputs(", \"radius\": ", f);
        json_num(f, s->radius[k]);
        fputc('}', f);
    }
    fputs("\n  ],\n  \"volume_rel_error\": ", f);
    json_num(f, s->volume_rel_error);
    fputs(",\n  \"area_rel_error\": ", f);
    json_num(f, s->area_rel_error);
    fprintf(f, ",\n  \"method\": \"%s\",\n",
            s->volume_rel_error == 0 && s->area_rel_error == 0 ? "closed form" : "numeric");
    fputs("  \"units\": {\"length\": \"m\", \"density\": \"kg/m^3\", \"volume\": \"m^3\", \"area\": \"m^2\", "
          "\"mass\": \"kg\", \"inertia\": \"kg m^2\", \"aspect\": \"1\", \"sphericity\": \"1\"}\n}\n",
          f);
}
