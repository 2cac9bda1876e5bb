/* MPI domain decomposition (docs/mpi.md): `mpirun -np R capdem run ...`
 * splits space into a Cartesian grid of R sub-domains; each rank steps the
 * particles whose centre lies in its sub-domain (owned) with copies of the
 * particles near it (ghosts), through the serial backend's own step, and
 * the run's trajectories are bitwise those of the serial program.
 *
 * The run (src/core/run.c) sees one operation table, cd_backend_mpi, wrapping
 * the omp backend: start distributes the global state, step steps the
 * local one and refreshes the ghosts; each rank writes its rows of the
 * run file from its local state; observables and wall loads are
 * reductions with the serial bits; sync gathers the owned rows on every
 * rank, where a protocol reads particles.
 *
 * Without CAPDEM_MPI the hooks below are inline no-ops: one process, which
 * writes. */
#ifndef CD_MPI_DECOMP_H
#define CD_MPI_DECOMP_H
#include <stddef.h>
#include "config/config.h"
#include "geom_types.h"

struct cd_sim;
struct cd_output;

#if defined(CAPDEM_MPI) && CAPDEM_MPI
/* Starts MPI (once per process; a no-op when already started).  On ranks
 * other than 0, stderr goes to /dev/null: every rank takes the same
 * decisions from the same data, and rank 0 reports them. */
int cd_mpi_begin(void);
/* Ends MPI; returns status (the agreed exit status of the run). */
int cd_mpi_end(int status);
/* The largest of every rank's status (0: all went well): the point where
 * the ranks agree to go on or to stop together, without a hang. */
int cd_mpi_agree(int status);
/* Rank 0 (of a run with more than one rank), or a serial run: the process
 * that writes the output. */
int cd_mpi_is_writer(void);
/* More than one rank: the run is decomposed. */
int cd_mpi_decomposed(void);
/* Whether this process opens the run's output: every rank with parallel
 * output (mpi.output = parallel, the default), else rank 0 (or the one
 * process).  Valid after cd_mpi_wrap. */
int cd_mpi_opens_output(void);
/* `capdem --version` under an MPI launcher: rank 0 prints one line naming
 * each rank's node and the device it takes in a run (the node-local rank
 * modulo the node's offload devices, docs/mpi.md "GPUs"); collective,
 * after cd_mpi_begin.  Not under a launcher: nothing.  Returns 0. */
int cd_mpi_version(void);
/* Before a snapshot, decomposed with parallel output: each rank's local
 * state synced where the writer reads it (its device's copy back), no
 * gather; collective.  0, -1 (err set, every rank), or 1: not decomposed
 * with parallel output (the caller syncs the state as in one process). */
int cd_mpi_sync_output(struct cd_sim *sim, char *err, size_t errlen);
/* A snapshot of the run, decomposed with parallel output: every rank
 * writes its rows from its local state (io_h5.h cd_output_snapshot_part);
 * collective.  0, -1 (the writer's message printed), or 1: not decomposed
 * with parallel output (the caller writes sim's state as in one process). */
int cd_mpi_write_snapshot(struct cd_output *out, struct cd_sim *sim);
/* With more than one rank: checks that the config can run decomposed
 * (solver, protocol, backend) and puts cd_backend_mpi in front of the
 * chosen backend.  0, or -1 with a message naming the key (exit 2). */
int cd_mpi_wrap(struct cd_sim *sim, const char *backend, char *err, size_t errlen);
/* The particles this rank sets up (core/sim.h cd_setup_keep_fn; src/mpi/mpi_setup.c):
 * with more than one rank, the decomposition made from every particle's
 * centre (the start takes it), and the rank's own particles and ghosts;
 * every particle (0) with one rank, or where the run needs the whole
 * state at its start (a protocol whose begin reads every particle,
 * domain.walls, whose check reads every particle's arms).  Refusals of
 * the decomposition (-1): exit 2, every rank alike. */
int cd_mpi_setup_keep(const struct cd_sim *sim, const cd_vec3 *centre, const int *species, const double *scale,
                      size_t n, long long **held, size_t *n_held, char *err, size_t errlen);
/* The same for a resume: with more than one rank, no particle (each rank
 * reads its own from the file, cd_mpi_read_snapshot). */
int cd_mpi_setup_keep_none(const struct cd_sim *sim, const cd_vec3 *centre, const int *species, const double *scale,
                           size_t n, long long **held, size_t *n_held, char *err, size_t errlen);
/* --resume with more than one rank: the decomposition made from the
 * file's centres (the start takes it), and the rows of this rank's
 * particles and ghosts read from the last snapshot of path by hyperslabs
 * (io_h5.h cd_h5_read_snapshot_part) into sim's part (core/sim.h).
 * Collective; 0, -1 (err: the lowest failing rank's message, on every
 * rank), or 1: one rank (the caller reads the whole snapshot). */
int cd_mpi_read_snapshot(struct cd_sim *sim, const char *path, char *err, size_t errlen);
/* Rows of every particle of the run in global id order, for a sum that
 * must keep the serial program's order (a protocol's begin, src/protocols):
 * pack(sim, row, out) writes `width` doubles of local row `row`.  Under a
 * set-up of part of the run (sim->part.gid: each rank built its own
 * particles and ghosts, src/mpi/mpi_setup.c), each rank sends the rows it
 * owns to rank 0, which gets them in global order in a new *rows (the
 * caller frees it; NULL on the other ranks), *n the run's particle count:
 * 0.  1: no such set-up (one process, or every rank holds the whole
 * state): the caller reads its own state.  -1: out of memory on some rank
 * (every rank alike).  Collective. */
int cd_mpi_rows_in_order(const struct cd_sim *sim, int width, void (*pack)(const struct cd_sim *, size_t, double *),
                         double **rows, size_t *n);
/* v[0 .. n) of rank 0 on every rank (what rank 0 computed from the rows
 * of cd_mpi_rows_in_order); collective.  No-op in one process. */
void cd_mpi_share(double *v, int n);
#else
static inline int cd_mpi_begin(void) { return 0; }
static inline int cd_mpi_end(int status) { return status; }
static inline int cd_mpi_agree(int status) { return status; }
static inline int cd_mpi_is_writer(void) { return 1; }
static inline int cd_mpi_decomposed(void) { return 0; }
static inline int cd_mpi_opens_output(void) { return 1; }
static inline int cd_mpi_version(void) { return 0; }
static inline int cd_mpi_sync_output(struct cd_sim *sim, char *err, size_t errlen)
{
    (void)sim;
    (void)err;
    (void)errlen;
    return 1;
}
static inline int cd_mpi_write_snapshot(struct cd_output *out, struct cd_sim *sim)
{
    (void)out;
    (void)sim;
    return 1;
}
static inline int cd_mpi_wrap(struct cd_sim *sim, const char *backend, char *err, size_t errlen)
{
    (void)sim;
    (void)backend;
    (void)err;
    (void)errlen;
    return 0;
}
static inline int cd_mpi_read_snapshot(struct cd_sim *sim, const char *path, char *err, size_t errlen)
{
    (void)sim;
    (void)path;
    (void)err;
    (void)errlen;
    return 1;
}
static inline int cd_mpi_rows_in_order(const struct cd_sim *sim, int width,
                                       void (*pack)(const struct cd_sim *, size_t, double *), double **rows, size_t *n)
{
    (void)sim;
    (void)width;
    (void)pack;
    (void)rows;
    (void)n;
    return 1;
}
static inline void cd_mpi_share(double *v, int n)
{
    (void)v;
    (void)n;
}
#define cd_mpi_setup_keep_none cd_mpi_setup_keep
static inline int cd_mpi_setup_keep(const struct cd_sim *sim, const cd_vec3 *centre, const int *species,
                                    const double *scale, size_t n, long long **held, size_t *n_held, char *err,
                                    size_t errlen)
{
    (void)sim;
    (void)centre;
    (void)species;
    (void)scale;
    (void)n;
    (void)held;
    (void)n_held;
    (void)err;
    (void)errlen;
    return 0;
}
#endif

/* ---- the sub-domains (src/mpi/mpi_decomp.c) --------------------------------
 * A Cartesian grid, or a recursive coordinate bisection (rcb) of the
 * particle centres into boxes of equal particle counts.  Plain C, no MPI:
 * unit-testable in any build. */
#define CD_DECOMP_CARTESIAN 0 /* mpi.decomposition's choices, in order */
#define CD_DECOMP_RCB       1
#define CD_RCB_MAX_RANKS    256 /* rcb: the ranks its tree has room for */

typedef struct {
    int kind;        /* CD_DECOMP_CARTESIAN or CD_DECOMP_RCB */
    int dims[3];     /* sub-domains along x, y, z (their product: the ranks; rcb: ranks x 1 x 1) */
    double lo[3];    /* [m] lower corner of the split box (box of the centres at start) */
    double width[3]; /* [m] width of an inner sub-domain; the outer ones reach to infinity */
    double range;    /* [m] interaction range: largest bounding diameter + skin */
    double margin;   /* [m] motion allowed between migrations (ghosts reach range + margin) */
    double halo;     /* [m] range + margin */
    /* rcb: the tree in preorder, node k splitting ranks [r0, r0 + n) at
     * cut[k] [m] along axis[k] (-1: a leaf) into the lower n / 2 (below the
     * cut: child k + 1) and the rest (child k + 2 (n / 2)); the box of each
     * rank [m] (outer faces at -/+infinity) */
    signed char rcb_axis[2 * CD_RCB_MAX_RANKS];
    double rcb_cut[2 * CD_RCB_MAX_RANKS];
    double rcb_lo[CD_RCB_MAX_RANKS][3], rcb_hi[CD_RCB_MAX_RANKS][3];
} cd_decomp_grid;

/* Chooses the grid of `ranks` sub-domains over the box of centres lo..hi
 * [m]: cfg's mpi.grid when given (every entry >= 1), else the grid with
 * the smallest cut area that leaves the gravity axis whole where it can
 * (a settling pile fills the bottom of its box).  A sub-domain narrower
 * than the interaction range is refused (more ranks than the domain can
 * be split into).  0, or -1 with a message naming the key (exit 2). */
int cd_decomp_choose(cd_decomp_grid *g, const cd_config *cfg, int ranks, const double lo[3], const double hi[3],
                     double range, double margin, char *err, size_t errlen);
/* The sub-domains of mpi.decomposition for `ranks` ranks over the n
 * particle centres xyz (3 n doubles [m]): cartesian (cd_decomp_choose on
 * their box) or rcb: the centres cut in two along the longest extent of
 * their box (never z in 2D) at the place that gives the lower half of the
 * ranks its share of the particles, each half again, down to one rank:
 * equal particle counts (to one particle per cut) wherever the particles
 * are, a settled pile included.  Refused (exit 2): rcb with mpi.grid given,
 * more ranks than particles or than CD_RCB_MAX_RANKS, a sub-domain
 * narrower than the interaction range where it is bounded.  Deterministic:
 * every rank finds the same.  0, or -1 with a message naming the key. */
int cd_decomp_make(cd_decomp_grid *g, const cd_config *cfg, int ranks, const double *xyz, size_t n, double range,
                   double margin, char *err, size_t errlen);
/* The rank whose sub-domain holds the point x [m] (outer sub-domains reach
 * to infinity; a non-finite coordinate counts as the lowest). */
int cd_decomp_owner(const cd_decomp_grid *g, const double x[3]);
/* The ranks other than skip whose sub-domain comes within the halo of x,
 * ascending, into out (room for every rank); returns how many. */
int cd_decomp_ghost_ranks(const cd_decomp_grid *g, const double x[3], int skip, int *out);
/* The sub-domain of rank r [m]: lo..hi, the outer faces at -/+infinity. */
void cd_decomp_box(const cd_decomp_grid *g, int r, double lo[3], double hi[3]);
/* The ranks other than `rank` whose sub-domain comes within `reach` [m] of
 * rank's (box to box, Euclidean), ascending, into out (room for every
 * rank); returns how many.  Symmetric: r is a neighbour of s when s is one
 * of r.  The ghost refresh and the migration talk to these ranks only. */
int cd_decomp_neighbors(const cd_decomp_grid *g, int rank, double reach, int *out);

#endif
