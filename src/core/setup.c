/* Builds a simulation from a validated config (docs/references.md,
 * Particles, Contact law, Domains and walls, Protocols):
 * the shapes, the particles with their polydisperse scale factors, random
 * orientations and velocities, their placement, the walls of the domain and
 * the time-step check against the collision time. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "core/sim.h"
#include "core/rng.h"
#include "protocols/protocol.h"
#include "rigid.h"
#include "segseg.h"
#ifdef _OPENMP
#include <omp.h>
#endif

/* Uniformly random rotation (Shoemake's method); about z only in 2D. */
static cd_quat random_orientation(cd_rng *r, int dimension)
{
    if (dimension == 2) return cd_q_from_axis_angle(cd_v3(0, 0, 1), cd_rng_range(r, 0, 2 * CD_PI));
    double u1 = cd_rng_uniform(r), u2 = cd_rng_uniform(r), u3 = cd_rng_uniform(r);
    double a = sqrt(1 - u1), b = sqrt(u1);
    return cd_q_normalize(
        cd_q(a * sin(2 * CD_PI * u2), a * cos(2 * CD_PI * u2), b * sin(2 * CD_PI * u3), b * cos(2 * CD_PI * u3)));
}

static int add_wall(cd_sim *sim, cd_wall w, char *err, size_t errlen)
{
    if (sim->s.n_walls >= CD_MAX_WALLS) {
        snprintf(err, errlen, "%s: domain.walls: too many walls (at most %d in all, the domain's included)",
                 sim->cfg.source_path, CD_MAX_WALLS);
        return -1;
    }
    sim->s.walls[sim->s.n_walls++] = w;
    return 0;
}

static cd_wall plane(cd_vec3 point, cd_vec3 normal, double mu)
{
    cd_wall w;
    memset(&w, 0, sizeof(w));
    w.type = CD_WALL_PLANE;
    w.point = point;
    w.normal = normal;
    w.friction = mu;
    return w;
}

/* Walls of the domain (y is up). box: [0,W] x [0,H] x [0,T], closed;
 * cylinder: axis along y through the origin, floor at y = 0; ball: sphere
 * about the origin. */
static int make_walls(cd_sim *sim, char *err, size_t errlen)
{
    const cd_config *c = &sim->cfg;
    double mu = c->wall_friction;
    int rc = 0;
    if (c->domain_kind == CD_DOMAIN_BOX) {
        rc |= add_wall(sim, plane(cd_v3(0, 0, 0), cd_v3(0, 1, 0), mu), err, errlen);
        rc |= add_wall(sim, plane(cd_v3(0, c->box_height, 0), cd_v3(0, -1, 0), mu), err, errlen);
        rc |= add_wall(sim, plane(cd_v3(0, 0, 0), cd_v3(1, 0, 0), mu), err, errlen);
        rc |= add_wall(sim, plane(cd_v3(c->box_width, 0, 0), cd_v3(-1, 0, 0), mu), err, errlen);
        /* Front and back only in 3D: a 2D particle moves in the plane
         * z = thickness/2, and a disc or cross thicker than the slab would
         * press on them with forces the plane motion drops, which would
         * still count as contacts, elastic energy and particle stress. */
        if (c->dimension != 2) {
            rc |= add_wall(sim, plane(cd_v3(0, 0, 0), cd_v3(0, 0, 1), mu), err, errlen);
            rc |= add_wall(sim, plane(cd_v3(0, 0, c->box_thickness), cd_v3(0, 0, -1), mu), err, errlen);
        }
    } else if (c->domain_kind == CD_DOMAIN_CYLINDER) {
        cd_wall w;
        memset(&w, 0, sizeof(w));
        w.type = CD_WALL_CYLINDER;
        w.point = cd_v3(0, 0, 0);
        w.normal = cd_v3(0, 1, 0);
        w.radius = 0.5 * c->cyl_diameter;
        w.friction = mu;
        rc |= add_wall(sim, w, err, errlen);
        rc |= add_wall(sim, plane(cd_v3(0, 0, 0), cd_v3(0, 1, 0), mu), err, errlen);
        /* deposit and compress: the top piston (the box has its top wall) */
        if (c->protocol_kind == CD_PROTOCOL_DEPOSIT)
            rc |= add_wall(sim, plane(cd_v3(0, c->cyl_height, 0), cd_v3(0, -1, 0), mu), err, errlen);
    } else if (c->domain_kind == CD_DOMAIN_BALL) {
        cd_wall w;
        memset(&w, 0, sizeof(w));
        w.type = CD_WALL_SPHERE;
        w.radius = c->ball_radius;
        w.friction = mu;
        rc |= add_wall(sim, w, err, errlen);
    }
    for (int k = 0; k < c->n_extra_walls && !rc; k++) {
        cd_wall w = c->extra_walls[k];
        w.friction = mu;
        rc |= add_wall(sim, w, err, errlen);
    }
    return rc ? -1 : 0;
}

/* Is a ball of radius R at p inside the domain? */
static int inside_domain(const cd_config *c, cd_vec3 p, double R)
{
    if (c->domain_kind == CD_DOMAIN_BOX)
        return p.x >= R && p.x <= c->box_width - R && p.y >= R && p.y <= c->box_height - R &&
               (c->dimension == 2 || (p.z >= R && p.z <= c->box_thickness - R));
    if (c->domain_kind == CD_DOMAIN_CYLINDER)
        return p.y >= R && p.y <= c->cyl_height - R && sqrt(p.x * p.x + p.z * p.z) <= 0.5 * c->cyl_diameter - R;
    if (c->domain_kind == CD_DOMAIN_BALL) return cd_v3_norm(p) <= c->ball_radius - R;
    return 1;
}

/* The box that holds the domain [m] (the box itself; the cylinder's and
 * the ball's bounding boxes) in lo, hi; 0 without a domain (free space). */
static int domain_bounds(const cd_config *c, double lo[3], double hi[3])
{
    if (c->domain_kind == CD_DOMAIN_BOX) {
        lo[0] = lo[1] = lo[2] = 0;
        hi[0] = c->box_width;
        hi[1] = c->box_height;
        hi[2] = c->box_thickness;
    } else if (c->domain_kind == CD_DOMAIN_CYLINDER) {
        lo[0] = lo[2] = -0.5 * c->cyl_diameter;
        hi[0] = hi[2] = 0.5 * c->cyl_diameter;
        lo[1] = 0;
        hi[1] = c->cyl_height;
    } else if (c->domain_kind == CD_DOMAIN_BALL) {
        for (int k = 0; k < 3; k++) {
            lo[k] = -c->ball_radius;
            hi[k] = c->ball_radius;
        }
    } else {
        return 0;
    }
    return 1;
}

/* Lattice sites (square in 2D, simple cubic in 3D) with spacing a inside
 * the domain, lowest layers first.  Returns the number of sites written
 * (at most max). */
static size_t lattice_sites(const cd_config *c, double a, double R, cd_vec3 *out, size_t max)
{
    double lo[3], hi[3];
    if (!domain_bounds(c, lo, hi)) {
        /* Free space: a cube of sites about the origin. */
        double side = a * ceil(cbrt((double)max) + 1);
        if (c->dimension == 2) side = a * ceil(sqrt((double)max) + 1);
        for (int k = 0; k < 3; k++) {
            lo[k] = -0.5 * side;
            hi[k] = 0.5 * side;
        }
    }
    long n[3];
    double off[3];
    for (int k = 0; k < 3; k++) {
        n[k] = (long)floor((hi[k] - lo[k]) / a);
        if (n[k] < 1) n[k] = 1;
        off[k] = lo[k] + 0.5 * (hi[k] - lo[k] - (double)(n[k] - 1) * a); /* centred rows */
    }
    if (c->dimension == 2) {
        n[2] = 1;
        off[2] = 0.5 * (lo[2] + hi[2]);
    }
    if (c->domain_kind == CD_DOMAIN_BOX && c->dimension == 3 && n[2] == 1)
        off[2] = 0.5 * c->box_thickness; /* pseudo-2D */
    size_t count = 0;
    for (long iy = 0; iy < n[1] && count < max; iy++)
        for (long iz = 0; iz < n[2] && count < max; iz++)
            for (long ix = 0; ix < n[0] && count < max; ix++) {
                cd_vec3 p = cd_v3(off[0] + a * ix, off[1] + a * iy, off[2] + a * iz);
                if (c->dimension == 2) p.z = off[2];
                if (inside_domain(c, p, R)) out[count++] = p;
            }
    return count;
}

/* Box around the domain in which random positions are drawn [m]; without
 * a domain, a cube that holds max bounding spheres of radius R at a
 * quarter of their own volume each. */
static void sampling_box(const cd_config *c, double R, size_t max, double lo[3], double hi[3])
{
    if (!domain_bounds(c, lo, hi)) {
        double side = 2 * R * cbrt(4.0 * (double)max) + 2 * R;
        for (int k = 0; k < 3; k++) {
            lo[k] = -0.5 * side;
            hi[k] = 0.5 * side;
        }
    }
}

static cd_vec3 random_point(const cd_config *c, cd_rng *r, const double lo[3], const double hi[3])
{
    /* One draw per statement, z first: C leaves the order in which function
     * arguments are evaluated unspecified (GCC went right to left, Clang
     * goes left to right), and z, y, x is the order of every earlier run. */
    double z = cd_rng_range(r, lo[2], hi[2]), y = cd_rng_range(r, lo[1], hi[1]), x = cd_rng_range(r, lo[0], hi[0]);
    cd_vec3 p = cd_v3(x, y, z);
    if (c->dimension == 2) p.z = 0.5 * (lo[2] + hi[2]);
    return p;
}

/* Random non-overlapping bounding spheres in the domain (rejection with a
 * bounded number of tries per particle). */
static size_t random_sites(const cd_config *c, cd_rng *r, double R, cd_vec3 *out, size_t max)
{
    double lo[3], hi[3];
    sampling_box(c, R, max, lo, hi);
    size_t count = 0;
    for (size_t tries = 0; count < max && tries < 2000 * max; tries++) {
        cd_vec3 p = random_point(c, r, lo, hi);
        if (!inside_domain(c, p, R)) continue;
        int ok = 1;
        for (size_t k = 0; k < count && ok; k++) ok = cd_v3_norm2(cd_v3_sub(p, out[k])) >= 4 * R * R;
        if (ok) out[count++] = p;
    }
    return count;
}

/* Every particle of the run while it is placed: the set-up builds the
 * rows of the particles it keeps only (cd_sim_setup_part; an MPI rank its
 * own and its ghosts), but the placement tests each new particle against
 * every one placed before it.  Species, length scale, centre and, with
 * init.exclusion = shape, orientation. */
typedef struct {
    const cd_shape *shapes;
    int *species;
    double *scale;        /* [1] */
    cd_vec3 *position;    /* [m] */
    cd_quat *orientation; /* init.exclusion = shape only */
} placement;

/* Arm a of a particle of shape sh at length scale f [1]: its body ends [m]
 * and radius [m], as the set-up writes the primitive's rows. */
static void scaled_arm(const cd_shape *sh, int a, double f, cd_vec3 *end_a, cd_vec3 *end_b, double *radius)
{
    *end_a = cd_v3_scale(sh->a[a], f);
    *end_b = cd_v3_scale(sh->b[a], f);
    *radius = sh->radius[a] * f;
}

/* Arm a of particle q of pl in the world: both axis ends [m] and radius [m]. */
static void world_arm(const placement *pl, size_t q, int a, cd_vec3 *e0, cd_vec3 *e1, double *radius)
{
    cd_vec3 ba, bb;
    scaled_arm(&pl->shapes[pl->species[q]], a, pl->scale[q], &ba, &bb, radius);
    *e0 = cd_rigid_to_world(pl->position[q], pl->orientation[q], ba);
    *e1 = cd_rigid_to_world(pl->position[q], pl->orientation[q], bb);
}

/* Do particles i and j overlap at their places and orientations in pl?
 * Exact for spherocylinder arms: some pair of axes closer than the sum of
 * their radii. */
static int shapes_overlap(const placement *pl, size_t i, size_t j)
{
    for (int u = 0; u < pl->shapes[pl->species[i]].n_prims; u++) {
        cd_vec3 p0, p1;
        double ru; /* [m] */
        world_arm(pl, i, u, &p0, &p1, &ru);
        for (int w = 0; w < pl->shapes[pl->species[j]].n_prims; w++) {
            cd_vec3 q0, q1;
            double rw; /* [m] */
            world_arm(pl, j, w, &q0, &q1, &rw);
            double a, b, reach = ru + rw; /* [1], [1], [m] */
            cd_segseg_closest(p0, p1, q0, q1, &a, &b);
            cd_vec3 d = cd_v3_sub(cd_v3_add(q0, cd_v3_scale(cd_v3_sub(q1, q0), b)),
                                  cd_v3_add(p0, cd_v3_scale(cd_v3_sub(p1, p0), a)));
            if (cd_v3_norm2(d) < reach * reach) return 1;
        }
    }
    return 0;
}

/* Every arm of particle q inside the domain (both axis ends at least the
 * arm radius from every wall; the domains are convex, so the whole arm is). */
static int arms_inside_domain(const cd_config *c, const placement *pl, size_t q)
{
    for (int u = 0; u < pl->shapes[pl->species[q]].n_prims; u++) {
        cd_vec3 e0, e1;
        double r; /* [m] */
        world_arm(pl, q, u, &e0, &e1, &r);
        if (!inside_domain(c, e0, r) || !inside_domain(c, e1, r)) return 0;
    }
    return 1;
}

/* init.exclusion = shape: random positions and orientations such that no
 * two particles' arms overlap (their bounding spheres may), so that long
 * arms can start interleaved, much denser than bounding spheres allow.
 * Writes position and orientation of every particle placed; returns the
 * number placed (rejection with a bounded number of tries per particle). */
static size_t random_shape_placement(const cd_config *c, placement *pl, cd_rng *r, double R, size_t max)
{
    double lo[3], hi[3];
    sampling_box(c, R, max, lo, hi);
    size_t count = 0;
    for (size_t tries = 0; count < max && tries < 2000 * max; tries++) {
        pl->position[count] = random_point(c, r, lo, hi);
        pl->orientation[count] = random_orientation(r, c->dimension);
        if (!arms_inside_domain(c, pl, count)) continue;
        double Ri = pl->shapes[pl->species[count]].bounding_radius * pl->scale[count]; /* [m] */
        int ok = 1;
        for (size_t k = 0; k < count && ok; k++) {
            double Rk = pl->shapes[pl->species[k]].bounding_radius * pl->scale[k]; /* [m] */
            if (cd_v3_norm2(cd_v3_sub(pl->position[count], pl->position[k])) < (Ri + Rk) * (Ri + Rk))
                ok = !shapes_overlap(pl, count, k);
        }
        if (ok) count++;
    }
    return count;
}

static void describe_domain(const cd_config *c, char *buf, size_t n)
{
    if (c->domain_kind == CD_DOMAIN_BOX)
        snprintf(buf, n, "domain.width/height/thickness = %g/%g/%g m", c->box_width, c->box_height, c->box_thickness);
    else if (c->domain_kind == CD_DOMAIN_CYLINDER)
        snprintf(buf, n, "domain.diameter/height = %g/%g m", c->cyl_diameter, c->cyl_height);
    else if (c->domain_kind == CD_DOMAIN_BALL) snprintf(buf, n, "domain.radius = %g m", c->ball_radius);
    else snprintf(buf, n, "domain.type = none");
}

/* Largest bounding radius of any particle, polydispersity included [m]. */
static double largest_bounding_radius(const cd_sim *sim)
{
    double rmax = 0, pmax = 0;
    for (int k = 0; k < sim->n_shapes; k++) {
        if (sim->shapes[k].bounding_radius > rmax) rmax = sim->shapes[k].bounding_radius;
        if (sim->cfg.species[k].polydispersity > pmax) pmax = sim->cfg.species[k].polydispersity;
    }
    return rmax * (1 + pmax);
}

/* protocol.fill_ratio (Conzelmann et al.): as many particles as fill the container
 * to fill_ratio x its width (box) or diameter (cylinder) at the expected
 * packing fraction, i.e. N = fill_ratio W A phi / <v>, with A the cross
 * section and <v> = v (1 + p^2) the mean particle volume when the length
 * scale is uniform in [1 - p, 1 + p] (E[f^3] = 1 + p^2).  The packing
 * fraction is the time series' one (solid volume over container volume up
 * to the piston; in 2D over the slab of domain.thickness). */
static void resolve_fill_count(cd_sim *sim)
{
    cd_config *c = &sim->cfg;
    if (!(c->fill_ratio > 0) || c->n_species != 1 || c->species[0].count > 0) return;
    double width = c->domain_kind == CD_DOMAIN_BOX ? c->box_width : c->cyl_diameter; /* [m] */
    double section = c->domain_kind == CD_DOMAIN_BOX ? c->box_width * c->box_thickness
                                                     : 0.25 * CD_PI * c->cyl_diameter * c->cyl_diameter; /* [m^2] */
    double p = c->species[0].polydispersity;
    double v = sim->shapes[0].volume * (1 + p * p); /* mean particle volume [m^3] */
    c->species[0].count = (long)ceil(c->fill_ratio * width * section * c->fill_fraction / v);
}

/* Lattice spacing [m] for particles of largest bounding radius R [m]:
 * init.gap (Conzelmann et al.'s "space of 1.5 d_p between each particle") or
 * init.clearance x the particle size. */
static double lattice_spacing(const cd_config *c, double R)
{
    return c->lattice_gap > 0 ? 2 * R + c->lattice_gap : c->clearance * 2 * R;
}

/* domain.height omitted (Conzelmann et al.): the lowest box or cylinder whose
 * lattice of spacing a holds every particle, i.e. rows x a with rows =
 * ceil(N / sites per row).  Rows are centred, so a height of exactly
 * rows x a puts the first row at a/2 >= R above the floor. */
static int resolve_lattice_height(cd_sim *sim, size_t N, char *err, size_t errlen)
{
    cd_config *c = &sim->cfg;
    double *h = c->domain_kind == CD_DOMAIN_BOX        ? &c->box_height
                : c->domain_kind == CD_DOMAIN_CYLINDER ? &c->cyl_height
                                                       : NULL;
    if (!h || *h > 0) return 0;
    double R = largest_bounding_radius(sim), a = lattice_spacing(c, R);               /* [m] */
    double wx = c->domain_kind == CD_DOMAIN_BOX ? c->box_width : c->cyl_diameter;     /* [m] */
    double wz = c->domain_kind == CD_DOMAIN_BOX ? c->box_thickness : c->cyl_diameter; /* [m] */
    size_t row_max = (size_t)(floor(wx / a) + 1) * (size_t)(floor(wz / a) + 1);
    cd_vec3 *sites = malloc(row_max * sizeof(cd_vec3));
    if (!sites) return -1;
    *h = a * (1 + 1e-9); /* one row */
    size_t per_row = lattice_sites(c, a, R, sites, row_max);
    free(sites);
    if (per_row == 0) {
        char dom[256];
        describe_domain(c, dom, sizeof dom);
        snprintf(err, errlen, "%s: domain: no particle of size %g m fits across the domain (%s)", c->source_path, 2 * R,
                 dom);
        return -1;
    }
    *h = (double)((N + per_row - 1) / per_row) * a * (1 + 1e-9);
    return 0;
}

/* The places of all N particles (and their orientations with
 * init.exclusion = shape) into pl. */
static int place_particles(cd_sim *sim, placement *pl, size_t N, cd_rng *rng, char *err, size_t errlen)
{
    const cd_config *c = &sim->cfg;
    double R = largest_bounding_radius(sim); /* [m] */
    double a = lattice_spacing(c, R);        /* [m] */
    size_t got;
    int random = c->random_placement, by_shape = random && c->exclude_by_shape;
    if (by_shape) {
        got = random_shape_placement(c, pl, rng, R, N);
    } else {
        cd_vec3 *sites = malloc((N + 1) * sizeof(cd_vec3));
        if (!sites) return -1;
        got = random ? random_sites(c, rng, R, sites, N) : lattice_sites(c, a, R, sites, N);
        for (size_t q = 0; q < got; q++) pl->position[q] = sites[q];
        free(sites);
    }
    if (got < N) {
        char dom[256], how[96];
        describe_domain(c, dom, sizeof dom);
        if (by_shape) snprintf(how, sizeof how, "random places without overlapping arms");
        else if (random) snprintf(how, sizeof how, "random places for bounding spheres of %g m", 2 * R);
        else snprintf(how, sizeof how, "lattice sites (size %g m, spacing %g m)", 2 * R, a);
        snprintf(err, errlen,
                 "%s: particles: %zu particles do not fit: %s holds only %zu %s; "
                 "enlarge the domain or lower the counts",
                 c->source_path, N, dom, got, how);
        return -1;
    }
    return 0;
}

/* The rows of the particles kept (held: ascending global ids; NULL: every
 * particle) into sim->s, in that order: shape, mass, inertia, primitives,
 * place, and the orientation (unless placed with it) and velocity drawn
 * for every particle of the run in turn, kept or not, so that each draws
 * the numbers it draws in the whole run.  gprim (or NULL): the global id
 * of each primitive written. */
static void build_rows(cd_sim *sim, const placement *pl, size_t N, cd_rng *rng, const long long *held, long long *gprim)
{
    const cd_config *c = &sim->cfg;
    cd_state *s = &sim->s;
    int by_shape = c->random_placement && c->exclude_by_shape;
    size_t l = 0, prim = 0;
    long long global_prim = 0;
    for (size_t q = 0; q < N; q++) {
        const cd_shape *sh = &sim->shapes[pl->species[q]];
        cd_quat o = by_shape ? pl->orientation[q] : random_orientation(rng, c->dimension); /* drawn with the place */
        double v = c->init_speed;                                                          /* [m/s] */
        /* z, y, x one by one, as in random_point (argument order is unspecified) */
        double vz = c->dimension == 2 ? 0 : cd_rng_range(rng, -v, v), vy = cd_rng_range(rng, -v, v);
        double vx = cd_rng_range(rng, -v, v);
        long long g0 = global_prim;
        global_prim += sh->n_prims;
        if (held && (l >= s->n_particles || held[l] != (long long)q)) continue;
        double f = pl->scale[q]; /* length scale [1] */
        s->shape[l] = pl->species[q];
        s->scale[l] = f;
        s->mass[l] = sh->mass * f * f * f;
        s->inertia[l] = cd_v3(sh->principal[0] * pow(f, 5), sh->principal[1] * pow(f, 5), sh->principal[2] * pow(f, 5));
        s->prim_first[l] = (cd_int)prim;
        s->prim_count[l] = sh->n_prims;
        for (int a = 0; a < sh->n_prims; a++, prim++) {
            s->prim_particle[prim] = (cd_int)l;
            scaled_arm(sh, a, f, &s->prim_a_body[prim], &s->prim_b_body[prim], &s->prim_radius[prim]);
            if (gprim) gprim[prim] = g0 + a;
        }
        s->position[l] = pl->position[q];
        s->orientation[l] = o;
        s->velocity[l] = cd_v3(vx, vy, vz);
        s->angmom[l] = cd_v3_zero();
        l++;
    }
}

/* The lightest and second lightest particle [kg] and the largest arm
 * radius [m], of the whole run. */
typedef struct {
    double m1, m2, r_max;
} lightest;

/* The collision time of the lightest pair [s]; run.steps_per_collision
 * sets dt from it, otherwise dt is checked against it. */
static int check_time_step(cd_sim *sim, size_t N, const lightest *lt, char *err, size_t errlen)
{
    cd_config *c = &sim->cfg;
    /* The two lightest particles give the shortest collision. */
    double m_eff = N > 1 ? cd_law_effective_mass(lt->m1, lt->m2) : lt->m1;
    if (c->law == CD_LAW_HERTZ_MINDLIN) {
        /* The Hertz time falls with the impact speed (as v^(-1/5)) and with
         * R_eff: the lightest pair with the largest arm radius, undamped,
         * at material.impact_speed (damping only lengthens it). */
        double r_eff = N > 1 ? cd_law_pair_radius(lt->r_max, lt->r_max) : lt->r_max;
        double e_eff = cd_law_contact_modulus(c->young_modulus, c->poisson_ratio);
        sim->collision_time = cd_law_hertz_collision_time(e_eff, r_eff, m_eff, c->impact_speed);
    } else {
        sim->collision_time = cd_law_collision_time(c->kn, m_eff, c->eta_n);
    }
    if (c->steps_per_collision > 0) c->dt = sim->collision_time / c->steps_per_collision;
    if (c->dt > sim->collision_time / 5 && !c->force_dt) {
        snprintf(err, errlen,
                 "%s: run.dt = %g s: expected at most t_col/5 = %g s (collision time %g s of the lightest pair); "
                 "lower dt or set run.force_dt: true",
                 c->source_path, c->dt, sim->collision_time / 5, sim->collision_time);
        return -1;
    }
    if (c->dt > sim->collision_time / 20)
        fprintf(
            stderr,
            "capdem: warning: run.dt = %g s is above t_col/20 = %g s; contacts are resolved in fewer than 20 steps\n",
            c->dt, sim->collision_time / 20);
    return 0;
}

/* The length scales of every particle (drawn in turn: the first numbers
 * of the stream) and the whole run's sums and extremes from them. */
static void scale_particles(cd_sim *sim, placement *pl, cd_rng *rng, lightest *lt, double *dmin)
{
    const cd_config *c = &sim->cfg;
    size_t q = 0;
    *lt = (lightest){INFINITY, INFINITY, 0};
    *dmin = INFINITY;
    for (int k = 0; k < c->n_species; k++) {
        const cd_shape *sh = &sim->shapes[k];
        double p = c->species[k].polydispersity;
        for (long n = 0; n < c->species[k].count; n++, q++) {
            double f = p > 0 ? cd_rng_range(rng, 1 - p, 1 + p) : 1.0; /* length scale [1] */
            pl->species[q] = k;
            pl->scale[q] = f;
            double m = sh->mass * f * f * f; /* [kg] */
            sim->total_mass += m;
            sim->solid_volume += sh->volume * f * f * f;
            if (m < lt->m1) {
                lt->m2 = lt->m1;
                lt->m1 = m;
            } else if (m < lt->m2) lt->m2 = m;
            for (int a = 0; a < sh->n_prims; a++) {
                double r = sh->radius[a] * f; /* [m] */
                if (2 * r < *dmin) *dmin = 2 * r;
                lt->r_max = fmax(lt->r_max, r);
            }
        }
    }
}

static void placement_free(placement *pl)
{
    free(pl->species);
    free(pl->scale);
    free(pl->position);
    free(pl->orientation);
}

/* The run's particles placed (pl), the particles kept counted and their
 * columns allocated: every column of sim->s for the particles held (NULL:
 * all N) with P primitives in all. */
static int alloc_rows(cd_sim *sim, const placement *pl, size_t N, size_t P, const long long *held, size_t n_held)
{
    size_t n = held ? n_held : N, prims = held ? 0 : P;
    for (size_t l = 0; held && l < n_held; l++) prims += (size_t)pl->shapes[pl->species[held[l]]].n_prims;
    cd_state *s = &sim->s;
    size_t n_walls = s->n_walls;
    cd_wall walls[CD_MAX_WALLS];
    memcpy(walls, s->walls, sizeof walls);
    if (cd_state_alloc(s, n, prims, 0, 2 * prims + 64)) return -1;
    s->n_walls = n_walls;
    memcpy(s->walls, walls, sizeof walls);
    /* wall-contact columns depend on the wall count */
    for (size_t f = 0; f < cd_n_fields; f++) {
        if (cd_fields[f].group != CD_GROUP_WALLC) continue;
        void **slot = cd_field_ptr(s, &cd_fields[f]);
        free(*slot);
        *slot = calloc(prims * (n_walls ? n_walls : 1) + 1, cd_fields[f].elem_size);
        if (!*slot) return -1;
    }
    if (held) {
        sim->part.gprim = malloc((prims + 1) * sizeof *sim->part.gprim);
        if (!sim->part.gprim) return -1;
    }
    return 0;
}

int cd_sim_setup(cd_sim *sim, const cd_config *cfg, char *err, size_t errlen)
{
    return cd_sim_setup_part(sim, cfg, NULL, err, errlen);
}

int cd_sim_setup_part(cd_sim *sim, const cd_config *cfg, cd_setup_keep_fn keep, char *err, size_t errlen)
{
    memset(sim, 0, sizeof(*sim));
    sim->cfg = *cfg;
    sim->cfg.source_text = NULL; /* owned by the caller's config */
    const cd_config *c = &sim->cfg;
    size_t N = 0, P = 0;
    sim->n_shapes = c->n_species;
    for (int k = 0; k < c->n_species; k++) {
        char why[512];
        if (cd_shape_from_species(&c->species[k], c->density, &sim->shapes[k], why, sizeof why)) {
            snprintf(err, errlen, "%s: particles[%d]: %s", c->source_path, k, why);
            return -1;
        }
    }
    resolve_fill_count(sim);
    for (int k = 0; k < c->n_species; k++) {
        N += (size_t)c->species[k].count;
        P += (size_t)c->species[k].count * (size_t)sim->shapes[k].n_prims;
    }
    int by_shape = c->random_placement && c->exclude_by_shape;
    placement pl = {sim->shapes, malloc((N + 1) * sizeof(int)), malloc((N + 1) * sizeof(double)),
                    malloc((N + 1) * sizeof(cd_vec3)), by_shape ? malloc((N + 1) * sizeof(cd_quat)) : NULL};
    if (!pl.species || !pl.scale || !pl.position || (by_shape && !pl.orientation)) {
        placement_free(&pl);
        snprintf(err, errlen, "out of memory for %zu particles", N);
        return -1;
    }
    long long *held = NULL;
    size_t n_held = 0;
    int rc =
        cd_protocol_check(c, err, errlen) || resolve_lattice_height(sim, N, err, errlen) || make_walls(sim, err, errlen)
            ? -1
            : 0;
    cd_rng rng;
    cd_rng_seed(&rng, c->seed);
    lightest lt = {0, 0, 0};
    double dmin = 0; /* [m] the thinnest arm's diameter */
    if (!rc) {
        scale_particles(sim, &pl, &rng, &lt, &dmin);
        cd_neighbors_init(&sim->nb, c->skin > 0 ? c->skin : 0.1 * dmin, c->reorder == CD_REORDER_CELLS);
        rc = place_particles(sim, &pl, N, &rng, err, errlen);
    }
    if (!rc) rc = check_time_step(sim, N, &lt, err, errlen);
    int kept = rc || !keep ? 0 : keep(sim, pl.position, pl.species, pl.scale, N, &held, &n_held, err, errlen);
    if (kept < 0) rc = -1;
    if (!rc && kept == 1) {
        sim->part.gid = held;
        sim->part.n_particles = N;
        sim->part.n_prims = P;
    } else free(held);
    if (!rc && alloc_rows(sim, &pl, N, P, sim->part.gid, n_held)) {
        snprintf(err, errlen, "out of memory for %zu particles", N);
        rc = -1;
    }
    if (!rc) build_rows(sim, &pl, N, &rng, sim->part.gid, sim->part.gprim);
    placement_free(&pl);
    if (rc) return -1;
    cd_state *s = &sim->s;
    /* the arms the step reads (kernels/cols.h); a start derives them anew */
    if (cd_state_arms_derive(s)) {
        snprintf(err, errlen, "out of memory while setting up the primitives' arms");
        return -1;
    }

    cd_step_params *sp = &sim->p;
    sp->dt = c->dt;
    sp->gravity = cd_v3(c->gravity[0], c->gravity[1], c->gravity[2]);
    sp->dimension = c->dimension;
    sp->fixed_spheres = c->sphere_orientation_fixed;
    sp->sin_parallel = sin(c->parallel_angle_deg * CD_PI / 180);
    sp->parallel_blend = c->parallel_blend;
    sp->law.kn = c->kn;
    sp->law.kt = c->kt;
    sp->law.eta_n = c->eta_n;
    sp->law.eta_t = c->eta_t;
    sp->law.mu = c->friction;
    sp->law.limit_total = c->friction_limit_total;
    sp->law.clip_normal = 1;
    sp->law.law = c->law;
    if (c->law == CD_LAW_HERTZ_MINDLIN) {
        /* walls are of the particles' material */
        sp->law.e_eff = cd_law_contact_modulus(c->young_modulus, c->poisson_ratio);
        sp->law.g_eff = cd_law_contact_shear_modulus(c->young_modulus, c->poisson_ratio);
    }
    sp->wall_law = sp->law;
    sp->wall_law.mu = c->wall_friction;
    sim->threads = 1;
#ifdef _OPENMP
    sim->threads = omp_get_max_threads();
#endif
    return 0;
}

void cd_sim_free(cd_sim *sim)
{
    if (sim->backend) sim->backend->stop(sim);
    cd_state_free(&sim->s);
    cd_state_free(&sim->probe_base);
    free(sim->part.gid);
    free(sim->part.gprim);
    sim->part.gid = sim->part.gprim = NULL;
    cd_neighbors_free(&sim->nb);
    cd_sim_observe_free(sim);
}
