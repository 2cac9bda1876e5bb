/* Each rank sets up its own part of the run (docs/mpi.md, "Set-up"):
 * the set-up (src/core/setup.c, cd_sim_setup_part) places every particle
 * (the placements draw from one random stream, and a random one tests
 * each particle against all placed before it: the centres, species and
 * length scales of all are kept, 40 bytes a particle), asks here which
 * particles this rank builds, and builds the rows of those only.  Here
 * the decomposition is made from the centres (the one the start would
 * make from the whole state: the same centres, the same interaction
 * range) and kept for the start; the rank keeps the particles it owns
 * and its ghosts, the particles the start would cut from the whole
 * state.  The rows are those of the whole run's set-up, bit for bit:
 * every particle draws its numbers in turn, kept or not. */
#include <stdlib.h>
#include <string.h>
#include "mpi/mpi_halo.h"

static cd_decomp_grid setup_grid; /* made at the set-up, taken by the first start */
static int setup_grid_made;
static long setup_built = -1; /* particles this rank's set-up built (-1: every particle) */
/* which of them this rank owns (1) rather than holds as a ghost (0), in
 * the set-up's row order (ascending global id): the rows it sends to
 * cd_mpi_rows_in_order */
static unsigned char *setup_owns;

double cd_mpi_range(double bound_max, double skin) { return (2 * bound_max + skin) * (1 + 1e-6); }

int cd_mpi_setup_grid(cd_decomp_grid *g)
{
    if (!setup_grid_made) return 0;
    *g = setup_grid;
    setup_grid_made = 0;
    free(setup_owns); /* the start cuts the local state: the set-up's rows are gone */
    setup_owns = NULL;
    return 1;
}

long cd_mpi_setup_built(void) { return setup_built; }

/* The largest bounding radius of the run's particles about their centre
 * [m] (the interaction range's, cd_bp_particle_bound), from each
 * particle's shape at its length scale: the primitive rows the set-up
 * writes (src/core/setup.c, scaled_arm), so the same bits as the whole
 * state's. */
static double largest_bound(const cd_shape *shapes, const int *species, const double *scale, size_t n)
{
    double bmax = 0; /* [m] */
    for (size_t q = 0; q < n; q++) {
        const cd_shape *sh = &shapes[species[q]];
        cd_vec3 a[CD_MAX_ARMS], b[CD_MAX_ARMS];
        double r[CD_MAX_ARMS]; /* [m] */
        for (int k = 0; k < sh->n_prims; k++) {
            a[k] = cd_v3_scale(sh->a[k], scale[q]);
            b[k] = cd_v3_scale(sh->b[k], scale[q]);
            r[k] = sh->radius[k] * scale[q];
        }
        double bound = cd_bp_particle_bound(a, b, r, 0, sh->n_prims, cd_v3_zero());
        if (bound > bmax) bmax = bound;
    }
    return bmax;
}

/* The centres' decomposition into setup_grid (the ranks' refusals alike)
 * and the particles of this rank (owned, or a ghost here: the test of
 * cd_mpi_distribute), ascending, into a new *held (*n_held).  0, or -1
 * (err set). */
static int decompose(const cd_sim *sim, const double *xyz, size_t n, double range, long long **held, size_t *n_held,
                     char *err, size_t errlen)
{
    int rank, size = cd_mpi_world(&rank), *ranks = malloc((size_t)size * sizeof *ranks);
    long long *mine = malloc((n + 1) * sizeof *mine);
    if (!ranks || !mine) {
        free(ranks);
        free(mine);
        snprintf(err, errlen, "out of memory while cutting the domain for %d MPI ranks", size);
        return -1;
    }
    free(setup_owns);
    setup_owns = malloc(n + 1);
    if (cd_mpi_agree(!setup_owns)) { /* (a shortage on one rank stops all, no hang) */
        free(ranks);
        free(mine);
        snprintf(err, errlen, "out of memory while cutting the domain for %d MPI ranks", size);
        return -1;
    }
    int rc = cd_decomp_make(&setup_grid, &sim->cfg, size, xyz, n, range, 0, err, errlen);
    size_t m = 0;
    for (size_t q = 0; !rc && q < n; q++) {
        int o = cd_decomp_owner(&setup_grid, xyz + 3 * q), here = o == rank;
        int k = cd_decomp_ghost_ranks(&setup_grid, xyz + 3 * q, o, ranks);
        for (int j = 0; j < k && !here; j++) here = ranks[j] == rank;
        if (here) setup_owns[m] = o == rank;
        if (here) mine[m++] = (long long)q;
    }
    free(ranks);
    if (rc) { /* every rank: the same data, the same refusal */
        free(mine);
        return -1;
    }
    setup_grid_made = 1;
    setup_built = (long)m;
    *held = mine;
    *n_held = m;
    return 0;
}

int cd_mpi_setup_keep(const cd_sim *sim, const cd_vec3 *centre, const int *species, const double *scale, size_t n,
                      long long **held, size_t *n_held, char *err, size_t errlen)
{
    int rank, size = cd_mpi_world(&rank);
    setup_built = -1;
    setup_grid_made = 0;
    const cd_config *c = &sim->cfg;
    /* the run's start reads the whole state: check_wall_placement
     * (src/core/run.c) every arm against domain.walls (a protocol's begin
     * sums every particle's motion from the rows of cd_mpi_rows_in_order) */
    if (size < 2 || c->n_extra_walls > 0) return 0;
    double *xyz = malloc((3 * n + 1) * sizeof *xyz); /* [m] */
    if (!xyz) {
        snprintf(err, errlen, "out of memory while cutting the domain for %d MPI ranks", size);
        return -1;
    }
    for (size_t q = 0; q < n; q++) {
        xyz[3 * q] = centre[q].x;
        xyz[3 * q + 1] = centre[q].y;
        xyz[3 * q + 2] = centre[q].z;
    }
    double range = cd_mpi_range(largest_bound(sim->shapes, species, scale, n), sim->nb.skin); /* [m] */
    int rc = decompose(sim, xyz, n, range, held, n_held, err, errlen);
    free(xyz);
    return rc ? -1 : 1;
}

int cd_mpi_setup_keep_none(const cd_sim *sim, const cd_vec3 *centre, const int *species, const double *scale, size_t n,
                           long long **held, size_t *n_held, char *err, size_t errlen)
{
    (void)sim;
    (void)centre;
    (void)species;
    (void)scale;
    (void)n;
    int rank;
    setup_built = -1;
    setup_grid_made = 0;
    if (cd_mpi_world(&rank) < 2) return 0;
    *n_held = 0;
    *held = malloc(sizeof **held);
    if (*held) return 1;
    snprintf(err, errlen, "out of memory");
    return -1;
}

int cd_mpi_rows_in_order(const cd_sim *sim, int width, void (*pack)(const cd_sim *, size_t, double *), double **rows,
                         size_t *n)
{
    int rank, size = cd_mpi_world(&rank);
    const size_t local = sim->s.n_particles, N = sim->part.n_particles, w = (size_t)width;
    *rows = NULL;
    *n = N;
    if (size < 2 || !sim->part.gid || !setup_owns || setup_built != (long)local) return 1;
    /* this rank's owned rows, each its global id and its values */
    size_t own = 0;
    for (size_t l = 0; l < local; l++) own += setup_owns[l];
    double *send = malloc((own * (w + 1) + 1) * sizeof *send);
    int *counts = rank == 0 ? malloc((size_t)size * 2 * sizeof *counts) : NULL;
    int failed = !send || (rank == 0 && !counts) || own * (w + 1) > (size_t)2147483647;
    for (size_t l = 0, k = 0; !failed && l < local; l++)
        if (setup_owns[l]) {
            send[k * (w + 1)] = (double)sim->part.gid[l]; /* exact: ids below 2^53 */
            pack(sim, l, send + k * (w + 1) + 1);
            k++;
        }
    int mine = (int)(own * (w + 1));
    double *recv = NULL;
    if (!cd_mpi_agree(failed)) {
        MPI_Gather(&mine, 1, MPI_INT, counts, 1, MPI_INT, 0, MPI_COMM_WORLD);
        size_t total = 0;
        for (int r = 0; rank == 0 && r < size; r++) {
            counts[size + r] = (int)total;
            total += (size_t)counts[r];
        }
        if (rank == 0) {
            recv = malloc((total + 1) * sizeof *recv);
            *rows = malloc((N * w + 1) * sizeof **rows);
            failed = !recv || !*rows || total != N * (w + 1) || total > (size_t)2147483647;
        }
        if (!cd_mpi_agree(failed)) {
            MPI_Gatherv(send, mine, MPI_DOUBLE, recv, counts, counts + size, MPI_DOUBLE, 0, MPI_COMM_WORLD);
            /* every particle is owned by exactly one rank: place each row at its id */
            for (size_t k = 0; rank == 0 && k < N; k++)
                memcpy(*rows + (size_t)recv[k * (w + 1)] * w, recv + k * (w + 1) + 1, w * sizeof **rows);
        } else failed = 1;
    } else failed = 1;
    free(send);
    free(counts);
    free(recv);
    if (failed) {
        free(*rows);
        *rows = NULL;
        return -1;
    }
    return 0;
}

void cd_mpi_share(double *v, int n)
{
    int rank;
    if (cd_mpi_world(&rank) > 1) MPI_Bcast(v, n, MPI_DOUBLE, 0, MPI_COMM_WORLD);
}

/* Whether some rank failed (failed != 0): then the message of the lowest
 * such rank in err on every rank, and -1.  Collective. */
static int agreed(int failed, char *err, size_t errlen)
{
    int rank, size = cd_mpi_world(&rank), who = failed ? rank : size, first;
    MPI_Allreduce(&who, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (first == size) return 0;
    MPI_Bcast(err, (int)errlen, MPI_CHAR, first, MPI_COMM_WORLD);
    return -1;
}

/* The largest reach of the run's primitives about their particle's centre
 * [m] (cd_bp_reach) among primitives p0 .. p1 - 1 of the file at path. */
static int largest_reach(const char *path, size_t p0, size_t p1, double *reach, char *err, size_t errlen)
{
    size_t n = p1 - p0;
    cd_vec3 *a = malloc((n + 1) * sizeof *a), *b = malloc((n + 1) * sizeof *b);
    double *r = malloc((n + 1) * sizeof *r); /* [m] */
    int rc = a && b && r ? 0 : -1;
    if (rc) snprintf(err, errlen, "out of memory");
    if (!rc)
        rc = cd_h5_read_column_rows(path, -1, "prim_a_body", (long long)p0, (long long)n, a, err, errlen) ||
                     cd_h5_read_column_rows(path, -1, "prim_b_body", (long long)p0, (long long)n, b, err, errlen) ||
                     cd_h5_read_column_rows(path, -1, "prim_radius", (long long)p0, (long long)n, r, err, errlen)
                 ? -1
                 : 0;
    *reach = 0;
    for (size_t i = 0; !rc && i < n; i++) {
        double e = cd_bp_reach(a[i], b[i], r[i], cd_v3_zero());
        if (e > *reach) *reach = e;
    }
    free(a);
    free(b);
    free(r);
    return rc;
}

int cd_mpi_read_snapshot(cd_sim *sim, const char *path, char *err, size_t errlen)
{
    if (!sim->part.gid) return 1; /* one rank: the whole snapshot */
    int rank, size = cd_mpi_world(&rank);
    size_t N = sim->part.n_particles, P = sim->part.n_prims, W = sim->s.n_walls;
    /* the centres of all, and the interaction range: the largest reach of
     * the primitives, each rank a block of them (a maximum: any split gives
     * its bits); widened as cd_bp_particle_bound widens each particle's */
    double *xyz = malloc((3 * N + 1) * sizeof *xyz), reach = 0, all = 0; /* [m] */
    cd_int *first = malloc((N + 1) * sizeof *first), *count = malloc((N + 1) * sizeof *count);
    int rc = xyz && first && count ? 0 : -1;
    if (rc) snprintf(err, errlen, "out of memory");
    if (!rc)
        rc = cd_h5_read_column_rows(path, -1, "position", 0, (long long)N, xyz, err, errlen) ||
                     cd_h5_read_column_rows(path, -1, "prim_first", 0, (long long)N, first, err, errlen) ||
                     cd_h5_read_column_rows(path, -1, "prim_count", 0, (long long)N, count, err, errlen) ||
                     largest_reach(path, (size_t)rank * P / (size_t)size, (size_t)(rank + 1) * P / (size_t)size, &reach,
                                   err, errlen)
                 ? -1
                 : 0;
    if (!agreed(rc, err, errlen)) MPI_Allreduce(&reach, &all, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    else rc = -1;
    long long *held = NULL, *gprim = NULL;
    size_t n = 0, prims = 0;
    if (!rc) rc = decompose(sim, xyz, N, cd_mpi_range(cd_bp_widened(all), sim->nb.skin), &held, &n, err, errlen);
    for (size_t l = 0; !rc && l < n; l++) prims += (size_t)count[held[l]];
    if (!rc) rc = (gprim = malloc((prims + 1) * sizeof *gprim)) ? 0 : -1;
    for (size_t l = 0, i = 0; !rc && l < n; l++)
        for (cd_int k = 0; k < count[held[l]]; k++) gprim[i++] = (long long)first[held[l]] + k;
    free(xyz);
    free(first);
    free(count);
    /* this rank's rows of the snapshot (the set-up built none) */
    cd_wall walls[CD_MAX_WALLS];
    memcpy(walls, sim->s.walls, sizeof walls);
    if (!rc) {
        cd_state_free(&sim->s);
        rc = cd_state_alloc(&sim->s, n, prims, W, 2 * prims + 64);
        sim->s.n_walls = W;
        memcpy(sim->s.walls, walls, sizeof walls);
        if (rc) snprintf(err, errlen, "out of memory for %zu particles", n);
    }
    cd_h5_part part = {n, prims, N, P, held, gprim};
    if (!rc) rc = cd_h5_read_snapshot_part(path, -1, &part, &sim->s, err, errlen);
    if (agreed(rc, err, errlen)) {
        free(held);
        free(gprim);
        return -1;
    }
    free(sim->part.gid);
    free(sim->part.gprim);
    sim->part.gid = held;
    sim->part.gprim = gprim;
    return 0;
}
