/* The container of a snapshot and its core region (docs/references.md, Analysis): which domain
 * it is (2D, pseudo-2D or 3D box, cylinder, ball), where its walls are at
 * that snapshot (a piston or a shrinking ball moves), its volume up to the
 * highest particle or the piston, and the region far enough from the walls
 * for the RDF reference particles, the core packing fraction and the core
 * contact density.  Also the wall contact points, which the run file does
 * not store. */
#include "analysis/analyze.h"
#include "walls.h"
#include <math.h>
#include <stdio.h>
#include <string.h>

const char *cd_an_kind_name(cd_an_kind k)
{
    switch (k) {
    case CD_AN_BOX2D:
        return "box-2d";
    case CD_AN_PSEUDO2D:
        return "box-pseudo-2d";
    case CD_AN_BOX3D:
        return "box-3d";
    case CD_AN_CYLINDER:
        return "cylinder";
    case CD_AN_BALL:
        return "ball";
    default:
        return "free";
    }
}

/* The point is recomputed exactly as the contact law placed it
 * (kernels/walls.h, cd_wall_contact) from the snapshot's primitive ends and
 * walls, which are the ones the last force evaluation used. */
void cd_an_wall_points(cd_an_snapshot *s)
{
    double sin_par = sin(s->cfg.parallel_angle_deg * CD_PI / 180); /* [1] */
    for (size_t c = 0; c < s->nw; c++) {
        int q = s->w_prim[c], w = s->w_wall[c];
        cd_contact_geom g;
        cd_wall_contact_rule(&s->walls[w], s->prim_a[q], s->prim_b[q], s->prim_radius[q], sin_par,
                             s->cfg.parallel_blend, &g);
        s->w_point[c] = g.point;
    }
}

/* Which container: from the config, or from the walls when the echoed
 * config did not parse. */
static cd_an_kind container_kind(const cd_an_snapshot *s, const cd_an_geometry *g)
{
    enum cd_domain_kind d = s->cfg.domain_kind;
    int planes = 0, cyl = 0, sph = 0;
    for (int w = 0; w < s->n_walls; w++) {
        planes += s->walls[w].type == CD_WALL_PLANE;
        cyl += s->walls[w].type == CD_WALL_CYLINDER;
        sph += s->walls[w].type == CD_WALL_SPHERE;
    }
    int box = s->cfg_ok ? d == CD_DOMAIN_BOX : planes >= 6 && !cyl && !sph;
    if (s->cfg_ok ? d == CD_DOMAIN_CYLINDER : cyl > 0) return cyl ? CD_AN_CYLINDER : CD_AN_FREE;
    if (s->cfg_ok ? d == CD_DOMAIN_BALL : sph > 0) return sph ? CD_AN_BALL : CD_AN_FREE;
    if (!box) return CD_AN_FREE;
    if (s->cfg.dimension == 2) return CD_AN_BOX2D;
    /* docs/references.md, Domains and walls: pseudo-2D boxes are T = L or 2L thick; 3 L separates them
     * from boxes thick enough to be 3D packings. */
    return g->hi[2] - g->lo[2] <= 3 * g->L ? CD_AN_PSEUDO2D : CD_AN_BOX3D;
}

/* Box extents from the axis-aligned plane walls (any of them may move). */
static void box_extents(const cd_an_snapshot *s, cd_an_geometry *g)
{
    for (int k = 0; k < 3; k++) {
        g->lo[k] = -HUGE_VAL;
        g->hi[k] = HUGE_VAL;
    }
    for (int w = 0; w < s->n_walls; w++) {
        const cd_wall *wl = &s->walls[w];
        if (wl->type != CD_WALL_PLANE) continue;
        const double n[3] = {wl->normal.x, wl->normal.y, wl->normal.z};
        const double p[3] = {wl->point.x, wl->point.y, wl->point.z};
        for (int k = 0; k < 3; k++) {
            if (n[k] > 0.999 && p[k] > g->lo[k]) g->lo[k] = p[k];  /* faces +k: a lower bound */
            if (n[k] < -0.999 && p[k] < g->hi[k]) g->hi[k] = p[k]; /* faces -k: an upper bound */
        }
    }
}

int cd_an_geometry_setup(const cd_an_snapshot *s, double margin_side_L, double margin_end_L, cd_an_geometry *g)
{
    memset(g, 0, sizeof(*g));
    g->dim = 3;
    for (int k = 0; k < s->n_shapes; k++)
        if (s->shapes[k].tip_length > g->L) g->L = s->shapes[k].tip_length;
    g->top_particles = -HUGE_VAL;
    for (size_t q = 0; q < s->n_prims; q++) {
        double y = fmax(s->prim_a[q].y, s->prim_b[q].y) + s->prim_radius[q]; /* [m] */
        if (y > g->top_particles) g->top_particles = y;
    }
    box_extents(s, g);
    /* A 2D box has no front and back walls (docs/motion.md): its slab is
     * [0, domain.thickness]. */
    if (s->cfg_ok && s->cfg.dimension == 2 && s->cfg.domain_kind == CD_DOMAIN_BOX && isinf(g->lo[2]) &&
        isinf(g->hi[2])) {
        g->lo[2] = 0;
        g->hi[2] = s->cfg.box_thickness;
    }
    g->top_wall = g->hi[1];
    g->kind = container_kind(s, g);
    double L = g->L;
    double ms = 3 * L, me = 10 * L; /* docs/references.md, Analysis margins in 3D [m] */
    if (g->kind == CD_AN_BOX2D || g->kind == CD_AN_PSEUDO2D) ms = me = 10 * L;
    if (margin_side_L >= 0) ms = margin_side_L * L;
    if (margin_end_L >= 0) me = margin_end_L * L;
    g->margin_side = ms;
    g->margin_end = me;
    /* The container ends at the lid or piston, or at the packing's free
     * surface when that is lower: the empty space above a settled packing
     * is not part of it. */
    double top = fmin(g->top_wall, g->top_particles);

    switch (g->kind) {
    case CD_AN_BOX2D:
    case CD_AN_PSEUDO2D:
    case CD_AN_BOX3D: {
        g->hi[1] = top;
        int bounded = 1;
        for (int k = 0; k < 3; k++) bounded &= isfinite(g->lo[k]) && isfinite(g->hi[k]) && g->hi[k] > g->lo[k];
        if (!bounded) {
            snprintf(g->note, sizeof g->note, "the box walls do not enclose the particles");
            g->kind = CD_AN_FREE;
            break;
        }
        double W = g->hi[0] - g->lo[0], H = g->hi[1] - g->lo[1], T = g->hi[2] - g->lo[2]; /* [m] */
        double cw = fmax(0, W - 2 * ms), ch = fmax(0, H - 2 * me), ct = fmax(0, T - 2 * ms);
        if (g->kind == CD_AN_BOX2D) {
            g->dim = 2;
            g->volume = W * H;
            g->core_volume = cw * ch;
            double zs = 0;
            for (size_t p = 0; p < s->n; p++) zs += s->pos[p].z;
            g->plane_z = s->n ? zs / (double)s->n : 0;
        } else if (g->kind == CD_AN_PSEUDO2D) {
            g->volume = W * H * T;
            g->core_volume = cw * ch * T; /* the core spans the whole thickness */
        } else {
            g->volume = W * H * T;
            g->core_volume = cw * ch * ct;
        }
        break;
    }
    case CD_AN_CYLINDER: {
        for (int w = 0; w < s->n_walls; w++)
            if (s->walls[w].type == CD_WALL_CYLINDER) {
                g->centre = s->walls[w].point;
                g->radius = s->walls[w].radius;
            }
        g->lo[1] = isfinite(g->lo[1]) ? g->lo[1] : 0;
        g->hi[1] = top;
        double H = fmax(0, g->hi[1] - g->lo[1]);
        double cr = fmax(0, g->radius - ms), ch = fmax(0, H - 2 * me);
        g->volume = CD_PI * g->radius * g->radius * H;
        g->core_volume = CD_PI * cr * cr * ch;
        break;
    }
    case CD_AN_BALL: {
        for (int w = 0; w < s->n_walls; w++)
            if (s->walls[w].type == CD_WALL_SPHERE) {
                g->centre = s->walls[w].point;
                g->radius = s->walls[w].radius;
            }
        double cr = fmax(0, g->radius - ms);
        g->volume = 4.0 / 3.0 * CD_PI * g->radius * g->radius * g->radius;
        g->core_volume = 4.0 / 3.0 * CD_PI * cr * cr * cr;
        break;
    }
    default:
        break;
    }
    if (g->kind == CD_AN_FREE && !g->note[0])
        snprintf(g->note, sizeof g->note, "domain.type %s has no container", s->cfg_ok ? s->cfg.domain : "(unknown)");
    else if (g->kind == CD_AN_BALL && !(g->core_volume > 0))
        snprintf(g->note, sizeof g->note,
                 "no core region: the ball is within %.3g L of its wall everywhere; set "
                 "--margins",
                 ms / L);
    else if (g->kind != CD_AN_FREE && !(g->core_volume > 0))
        snprintf(g->note, sizeof g->note,
                 "no core region: the container is within %.3g L (sides) / %.3g L (floor and top) of its walls "
                 "everywhere; set --margins",
                 ms / L, me / L);
    return 0;
}

int cd_an_in_core(const cd_an_geometry *g, cd_vec3 x)
{
    double ms = g->margin_side, me = g->margin_end;
    switch (g->kind) {
    case CD_AN_BOX2D:
    case CD_AN_PSEUDO2D:
        return x.x >= g->lo[0] + ms && x.x <= g->hi[0] - ms && x.y >= g->lo[1] + me && x.y <= g->hi[1] - me;
    case CD_AN_BOX3D:
        return x.x >= g->lo[0] + ms && x.x <= g->hi[0] - ms && x.y >= g->lo[1] + me && x.y <= g->hi[1] - me &&
               x.z >= g->lo[2] + ms && x.z <= g->hi[2] - ms;
    case CD_AN_CYLINDER: {
        double dx = x.x - g->centre.x, dz = x.z - g->centre.z; /* from the axis (along y) [m] */
        double rc = g->radius - ms;
        return rc > 0 && dx * dx + dz * dz <= rc * rc && x.y >= g->lo[1] + me && x.y <= g->hi[1] - me;
    }
    case CD_AN_BALL: {
        double rc = g->radius - ms;
        return rc > 0 && cd_v3_norm2(cd_v3_sub(x, g->centre)) <= rc * rc;
    }
    default:
        return 0;
    }
}
