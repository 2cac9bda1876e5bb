/* The MPI run as a backend (docs/mpi.md): cd_backend_mpi wraps the omp
 * or the OpenCL backend.  Every rank sets the run up from the same config
 * (the global state, the same bits everywhere); start cuts each rank's local state
 * from it; step runs the serial step on the local state, with the
 * rebuild decided by all ranks together (the serial program's decision)
 * and the particles migrating to their new owners right before each
 * rebuild, then refreshes the ghosts; a snapshot is written by every
 * rank from its local state (cd_mpi_write_snapshot); observables and wall
 * loads are reductions with the serial bits (src/mpi/mpi_reduce.c); sync
 * gathers the owned rows on every rank, where a protocol reads particles
 * (and rank 0 writes with mpi.output = rank0). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "mpi/mpi_halo.h"
#include "broadphase.h"
#include "observe_items.h"
#include "io/io_h5.h"
#ifdef __GLIBC__
#include <malloc.h>
#endif

static int began_here; /* MPI_Init was called by cd_mpi_begin */
/* The decomposition of this process's run (cd_mpi_wrap): it outlives the
 * backend's stop, which a protocol calls to restart from a state it put
 * back (the bulk probe), and reports at cd_mpi_end. */
static cd_mpi_ctx *the_ctx;
static int parallel_output; /* every rank writes the run file (mpi.output = parallel) */
static void report(const cd_mpi_ctx *x);
static void devices_started(cd_mpi_ctx *x);
static int agree_failure(cd_mpi_ctx *x, int rc, char *err, size_t errlen);

/* The heap's free memory back to the system after the exchanges that
 * allocate and free buffers of the size of the local state (an
 * observation's rows, a snapshot's, a migration's records): glibc keeps
 * freed blocks below its mmap threshold, which rises to the largest block
 * freed, in the heap, so without this a rank's resident set grows by the
 * largest such buffers and keeps them (measured: 20 MB of 77 MB per rank
 * on 2 ranks, docs/mpi.md "Memory"). */
static void give_back_memory(void)
{
#ifdef __GLIBC__
    malloc_trim(0);
#endif
}

int cd_mpi_world(int *rank)
{
    int on = 0, size = 1;
    *rank = 0;
    MPI_Initialized(&on);
    if (on) {
        MPI_Comm_rank(MPI_COMM_WORLD, rank);
        MPI_Comm_size(MPI_COMM_WORLD, &size);
    }
    return size;
}

/* Started by an MPI launcher (mpirun, mpiexec, srun)?  Without one the
 * run is the serial program and MPI is not started at all: nothing of the
 * MPI library's start (a singleton's daemon, its files) can get in the way
 * of a plain `capdem run`. */
static int launched(void)
{
    static const char *const vars[] = {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE", "MPI_LOCALNRANKS"};
    for (size_t k = 0; k < sizeof vars / sizeof vars[0]; k++)
        if (getenv(vars[k])) return 1;
    return 0;
}

int cd_mpi_begin(void)
{
    int on = 0, rank;
    MPI_Initialized(&on);
    if (!on && !launched()) return 0;
    if (!on) {
        if (MPI_Init(NULL, NULL) != MPI_SUCCESS) return -1;
        began_here = 1;
    }
    if (cd_mpi_world(&rank) > 1 && rank > 0) { /* rank 0 speaks for all (mpi_decomp.h) */
        fflush(stderr);
        if (!freopen("/dev/null", "w", stderr)) return -1;
    }
    return 0;
}

int cd_mpi_agree(int status)
{
    int rank, all = status;
    if (cd_mpi_world(&rank) > 1) MPI_Allreduce(&status, &all, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return all;
}

int cd_mpi_end(int status)
{
    if (the_ctx) {
        if (the_ctx->ran) report(the_ctx);
        free(the_ctx);
        the_ctx = NULL;
    }
    status = cd_mpi_agree(status);
    if (began_here) MPI_Finalize();
    began_here = 0;
    return status;
}

int cd_mpi_is_writer(void)
{
    int rank;
    cd_mpi_world(&rank);
    return rank == 0;
}

int cd_mpi_sync_output(cd_sim *sim, char *err, size_t errlen)
{
    cd_mpi_ctx *x = the_ctx;
    if (!x || !x->started || !parallel_output || sim->backend_data != x) return 1;
    if (agree_failure(x, x->inner->sync(&x->loc, err, errlen), err, errlen)) return -1;
    cd_sim_derive_pair_output(&x->loc); /* (as cd_sim_sync: the contacts' output columns) */
    return 0;
}

int cd_mpi_write_snapshot(cd_output *out, cd_sim *sim)
{
    cd_mpi_ctx *x = the_ctx;
    if (!x || !x->started || !parallel_output || sim->backend_data != x) return 1;
    cd_output_part part;
    long long *at = cd_mpi_output_part(x, &sim->s, &part);
    int rc = cd_output_snapshot_part(out, &part);
    free(at);
    give_back_memory();
    return rc;
}

int cd_mpi_opens_output(void) { return parallel_output || cd_mpi_is_writer(); }

int cd_mpi_decomposed(void)
{
    int rank;
    return cd_mpi_world(&rank) > 1;
}

/* The scalars of the local state (step, time, walls, protocol slots) on
 * the global one: every rank's are the same bits. */
static void scalars_back(cd_sim *sim, const cd_state *loc)
{
    sim->s.step = loc->step;
    sim->s.time = loc->time;
    memcpy(sim->s.walls, loc->walls, sizeof sim->s.walls);
    memcpy(sim->s.control, loc->control, sizeof sim->s.control);
}

/* After the ranks learned the lowest rank that failed (first; the rank
 * count: none): its message in err on every rank, and -1. */
static int failure_of(cd_mpi_ctx *x, int first, char *err, size_t errlen)
{
    if (first == x->size) return 0;
    MPI_Bcast(err, (int)errlen, MPI_CHAR, first, x->comm);
    return -1;
}

/* Whether any rank failed (rc != 0), as failure_of says. */
static int agree_failure(cd_mpi_ctx *x, int rc, char *err, size_t errlen)
{
    int who = rc ? x->rank : x->size, first;
    MPI_Allreduce(&who, &first, 1, MPI_INT, MPI_MIN, x->comm);
    return failure_of(x, first, err, errlen);
}

/* A failure that leaves the other ranks waiting in an exchange: the
 * message (seen where the rank's stderr is: rank 0's), and every rank
 * stops. */
static void abort_run(cd_mpi_ctx *x, const char *err)
{
    fprintf(stderr, "capdem: MPI rank %d: %s\n", x->rank, err);
    fflush(stderr);
    MPI_Abort(x->comm, 1);
}

/* The step's rebuild decision for all ranks (the serial program's: some
 * primitive of some particle or a wall moved more than half the skin), and
 * with it the migration: particles go to their owners by their centre now,
 * and the rebuild that follows finds every pair of an owned particle,
 * because the ghosts reach the interaction range. */
static int rebuild_hook(cd_sim *loc, int rebuild, char *err, size_t errlen)
{
    cd_mpi_ctx *x = loc->rebuild_hook_data;
    /* A rank without particles (a sub-domain the pile left) builds no list,
     * so its skin test knows no reference walls: it has no say. */
    int any = 0, vote = loc->s.n_particles ? rebuild : 0;
    double t0 = MPI_Wtime();
    MPI_Allreduce(&vote, &any, 1, MPI_INT, MPI_LOR, x->comm);
    double t1 = MPI_Wtime();
    x->t_decide += t1 - t0;
    if (!any) return 0;
    /* The wall contacts' history lives in the inner step's candidate lists:
     * into the local rows first (a sync; on a device cd_mpi_dev_leave
     * syncs the whole state back to the host), so that it
     * moves with its particles, and back into candidates at the build that
     * follows (from the rows). */
    int left = cd_mpi_dev_leave(x, err, errlen);
    if (!left && agree_failure(x, x->inner->sync(loc, err, errlen), err, errlen)) return -1;
    if (left < 0 || cd_mpi_migrate(x)) {
        if (left >= 0) snprintf(err, errlen, "out of memory while moving particles to their new MPI ranks");
        abort_run(x, err); /* the other ranks wait in the exchange */
    }
    if (left && cd_mpi_dev_return(x, err, errlen)) abort_run(x, err);
    give_back_memory();
    loc->nb.walls_from_host = 1;
    x->t_migrate += MPI_Wtime() - t1;
    if (!loc->s.n_particles) { /* still none: no list to build (the build needs a particle) */
        loc->nb.force_rebuild = 0;
        return 0;
    }
    return 1;
}

/* Interaction range [m]: twice the largest bounding radius (about the
 * centre, as the neighbour build takes it: rotation changes it by
 * roundings only, covered by the factor) plus the skin. */
static double interaction_range(const cd_sim *sim)
{
    const cd_state *s = &sim->s;
    double bmax = 0;
    for (size_t q = 0; q < s->n_particles; q++) {
        double b = cd_bp_particle_bound(s->prim_a_body, s->prim_b_body, s->prim_radius, s->prim_first[q],
                                        s->prim_count[q], cd_v3_zero());
        if (b > bmax) bmax = b;
    }
    return cd_mpi_range(bmax, sim->nb.skin);
}

/* Rank 0's summary of the decomposition: migrations, and the owned
 * particles and ghosts per rank at the end (the halo's share of the
 * work).  Collective: every rank ends the run at the same point. */
static void report(const cd_mpi_ctx *x)
{
    long mine[3] = {x->last_owned, x->last_ghosts, x->start_owned}, lo[3], hi[3], sum[3];
    MPI_Reduce(mine, lo, 3, MPI_LONG, MPI_MIN, 0, x->comm);
    MPI_Reduce(mine, hi, 3, MPI_LONG, MPI_MAX, 0, x->comm);
    MPI_Reduce(mine, sum, 3, MPI_LONG, MPI_SUM, 0, x->comm);
    double t[4] = {x->t_step, x->t_decide, x->t_migrate, x->t_ghosts}, tmax[4]; /* [s] */
    MPI_Reduce(t, tmax, 4, MPI_DOUBLE, MPI_MAX, 0, x->comm);
    /* sent per ghost refresh and per migration: messages, bytes */
    double refreshes = x->refreshes > 0 ? (double)x->refreshes : 1,
           migrations = x->migrations > 0 ? (double)x->migrations : 1;
    double c[5] = {(double)x->refresh_msgs / refreshes, (double)x->refresh_bytes / refreshes,
                   (double)x->migrate_msgs / migrations, (double)x->migrate_bytes / migrations,
                   (double)x->migrate_records / migrations},
           cmax[5], csum[5];
    MPI_Reduce(c, cmax, 5, MPI_DOUBLE, MPI_MAX, 0, x->comm);
    MPI_Reduce(c, csum, 5, MPI_DOUBLE, MPI_SUM, 0, x->comm);
    double red = x->reduces > 0 ? (double)x->reduce_bytes / (double)x->reduces : 0, rsum, rmax;
    MPI_Reduce(&red, &rsum, 1, MPI_DOUBLE, MPI_SUM, 0, x->comm);
    MPI_Reduce(&red, &rmax, 1, MPI_DOUBLE, MPI_MAX, 0, x->comm);
    long built = cd_mpi_setup_built(), bmin, bmax; /* particles each rank's set-up built (-1: all) */
    MPI_Reduce(&built, &bmin, 1, MPI_LONG, MPI_MIN, 0, x->comm);
    MPI_Reduce(&built, &bmax, 1, MPI_LONG, MPI_MAX, 0, x->comm);
    double wrote = (double)cd_output_bytes_written(), wmin, wmax; /* [bytes] into the run file */
    MPI_Reduce(&wrote, &wmin, 1, MPI_DOUBLE, MPI_MIN, 0, x->comm);
    MPI_Reduce(&wrote, &wmax, 1, MPI_DOUBLE, MPI_MAX, 0, x->comm);
    if (x->rank == 0) {
        fprintf(stderr,
                "capdem: MPI: %d ranks, %lld migrations (%lld through all ranks); per rank now %ld..%ld owned "
                "particles and %ld..%ld "
                "ghosts (%.3g ghosts per owned particle); imbalance (max / mean owned particles) at the start %.4g, "
                "now %.4g; slowest rank's seconds: step %.3g, rebuild decision %.3g, migration %.3g, ghost refresh "
                "%.3g\n",
                x->size, x->migrations, x->far_migrations, lo[0], hi[0], lo[1], hi[1],
                sum[0] > 0 ? (double)sum[1] / (double)sum[0] : 0.0,
                sum[2] > 0 ? (double)hi[2] * x->size / (double)sum[2] : 0.0,
                sum[0] > 0 ? (double)hi[0] * x->size / (double)sum[0] : 0.0, tmax[0], tmax[1], tmax[2], tmax[3]);
        fprintf(
            stderr,
            "capdem: MPI traffic: sent per rank (mean, max): per step %.4g, %.4g messages and %.6g, %.6g bytes; per "
            "migration %.4g, %.4g messages and %.6g, %.6g bytes, %.4g, %.4g particle records\n",
            csum[0] / x->size, cmax[0], csum[1] / x->size, cmax[1], csum[2] / x->size, cmax[2], csum[3] / x->size,
            cmax[3], csum[4] / x->size, cmax[4]);
        if (bmin >= 0)
            fprintf(stderr,
                    "capdem: MPI set-up: each rank built or read the rows of %ld..%ld of the %ld particles (its own "
                    "and its ghosts)\n",
                    bmin, bmax, sum[2]);
        else
            fprintf(stderr,
                    "capdem: MPI set-up: every rank built all %ld particles (domain.walls: the start checks every "
                    "particle's arms)\n",
                    sum[2]);
        if (parallel_output)
            fprintf(stderr,
                    "capdem: MPI output: each rank wrote its rows from its local state; the whole state gathered %lld "
                    "times; data bytes each rank wrote into the run file (MPI-IO): %.0f..%.0f\n",
                    x->gathers, wmin, wmax);
        else fprintf(stderr, "capdem: MPI output: rank 0 wrote the run file (mpi.output = rank0)\n");
        fprintf(stderr,
                "capdem: MPI reductions (observables, wall loads): %lld, sent per rank and reduction (mean, max) "
                "%.6g, %.6g bytes\n",
                x->reduces, rsum / x->size, rmax);
    }
}

/* Ends the local state; the context stays for a restart (cd_mpi_end
 * frees it). */
static void mpi_stop(cd_sim *sim)
{
    cd_mpi_ctx *x = sim->backend_data;
    if (!x) return;
    if (x->started) {
        x->last_owned = (long)x->n_owned;
        x->last_ghosts = (long)(x->loc.s.n_particles - x->n_owned);
    }
    cd_sim_free(&x->loc);
    cd_mpi_halo_free(x);
    x->started = 0;
}

/* The whole run's columns on this rank (every particle, primitive, wall
 * row and pair row): the set-up builds them (or a resume reads them), and
 * the start cuts the local state from them and lets them go (with
 * parallel output; cd_mpi_distribute).  After that a rank needs them only
 * where the whole state is gathered (sync: a protocol that reads
 * particles, a diagnosis; rank 0's writer with mpi.output = rank0 keeps
 * them): they come back, empty, for the gather.  The counts and scalars
 * (step, time, walls, protocol slots) stay throughout; a gathered state
 * goes at the next step (a protocol reads it right after its sync). */
static int global_columns(cd_sim *sim)
{
    if (sim->s.position) return 0;
    cd_state keep = sim->s;
    if (cd_state_alloc(&sim->s, keep.n_particles, keep.n_prims, keep.n_walls, keep.cap_pairs)) {
        sim->s = keep;
        return -1;
    }
    scalars_back(sim, &keep);
    return 0;
}

static int mpi_start(cd_sim *sim, int compute, char *err, size_t errlen)
{
    cd_mpi_ctx *x = sim->backend_data;
    cd_sim_free(&x->loc);
    cd_mpi_halo_free(x);
    x->started = 0;
    const cd_state *s = &sim->s;
    /* The sub-domains are cut at the first start and kept for a restart
     * (the bulk probe's, from a compacted packing that it might not split
     * as well): the bits do not depend on them. */
    if (!x->ran && !cd_mpi_setup_grid(&x->grid)) {                    /* (a set-up of this rank's part made it) */
        double *xyz = malloc((3 * s->n_particles + 1) * sizeof *xyz); /* [m] the centres */
        if (!xyz) {
            snprintf(err, errlen, "out of memory while cutting the domain for %d MPI ranks", x->size);
            return -1;
        }
        for (size_t q = 0; q < s->n_particles; q++) {
            xyz[3 * q] = s->position[q].x;
            xyz[3 * q + 1] = s->position[q].y;
            xyz[3 * q + 2] = s->position[q].z;
        }
        int rc =
            cd_decomp_make(&x->grid, &sim->cfg, x->size, xyz, s->n_particles, interaction_range(sim), 0, err, errlen);
        free(xyz);
        if (rc) return -1; /* every rank: the same data, the same refusal */
    }

    sim->nb.reorder = 0; /* the replicated state stays in global id order too */
    cd_sim *loc = &x->loc;
    memset(loc, 0, sizeof *loc);
    loc->cfg = sim->cfg; /* shallow: cd_sim_free leaves the config alone */
    loc->p = sim->p;
    memcpy(loc->shapes, sim->shapes, sizeof loc->shapes);
    loc->n_shapes = sim->n_shapes;
    loc->collision_time = sim->collision_time;
    loc->total_mass = sim->total_mass;
    loc->solid_volume = sim->solid_volume;
    loc->threads = sim->threads;
    loc->backend = x->inner;
    memcpy(loc->device_request, sim->device_request, sizeof loc->device_request);
    /* reorder off: the MPI layer keeps local order = global id order (docs/mpi.md) */
    cd_neighbors_init(&loc->nb, sim->nb.skin, 0);
    loc->rebuild_hook = rebuild_hook;
    loc->rebuild_hook_data = x;
    size_t R = (size_t)x->size;
    x->send_count = calloc(R, sizeof(int));
    x->send_displ = calloc(R, sizeof(int));
    x->recv_count = calloc(R, sizeof(int));
    x->recv_displ = calloc(R, sizeof(int));
    int rc = x->send_count && x->send_displ && x->recv_count && x->recv_displ ? 0 : -1;
    /* (a set-up of this rank's part: its rows always go, the counts become
     * the whole run's; a gather allocates the whole run's columns anew) */
    int part = sim->part.gid != NULL;
    if (!rc) rc = cd_mpi_distribute(x, &sim->s, sim->part.gid, sim->part.gprim, parallel_output || part);
    if (!rc && part) {
        sim->s.n_particles = sim->part.n_particles;
        sim->s.n_prims = sim->part.n_prims;
        sim->s.n_pairs = 0;
        free(sim->part.gid);
        free(sim->part.gprim);
        memset(&sim->part, 0, sizeof sim->part);
    }
    if (rc) snprintf(err, errlen, "out of memory while distributing the particles over %d MPI ranks", x->size);
    /* (a rank without particles has no list to build and no forces) */
    if (!rc) rc = x->inner->start(loc, compute && loc->s.n_particles > 0, err, errlen);
    if (agree_failure(x, rc, err, errlen)) return -1;
    if (!x->ran) {
        x->start_owned = (long)x->n_owned;
        devices_started(x);
    }
    x->started = x->ran = 1;
    /* the ghosts' forces from their owners (a start computes them from
     * the pairs this rank sees) */
    cd_mpi_refresh_ghosts(x, 0);
    return 0;
}

static int mpi_step(cd_sim *sim, long long n, char *err, size_t errlen)
{
    cd_mpi_ctx *x = sim->backend_data;
    if (parallel_output && sim->s.position) { /* gathered for a protocol: read by now */
        cd_state_free(&sim->s);
        give_back_memory();
    }
    /* the walls and protocol slots as the protocol left them (the same on
     * every rank: it decides from the same loads and observables) */
    memcpy(x->loc.s.walls, sim->s.walls, sizeof x->loc.s.walls);
    memcpy(x->loc.s.control, sim->s.control, sizeof x->loc.s.control);
    for (long long it = 0; it < n; it++) {
        double t0 = MPI_Wtime(), hook = x->t_decide + x->t_migrate;
        int rc = x->inner->step(&x->loc, 1, err, errlen);
        scalars_back(sim, &x->loc.s);
        double t1 = MPI_Wtime();
        x->t_step += t1 - t0 - (x->t_decide + x->t_migrate - hook);
        /* one exchange per step: the ghosts, and whether every rank's step
         * went well (a failed rank's ghosts are not used: all stop) */
        int first = cd_mpi_refresh_ghosts(x, rc != 0);
        x->t_ghosts += MPI_Wtime() - t1;
        if (failure_of(x, first, err, errlen)) return -1;
    }
    return 0;
}

static int mpi_sync(cd_sim *sim, char *err, size_t errlen)
{
    cd_mpi_ctx *x = sim->backend_data;
    int rc = x->inner->sync(&x->loc, err, errlen);
    if (!rc) rc = global_columns(sim);
    if (!rc) rc = cd_mpi_gather(x, &sim->s);
    x->gathers++;
    if (rc) snprintf(err, errlen, "out of memory while gathering the state on MPI rank 0");
    return agree_failure(x, rc, err, errlen);
}

/* The observables of the serial program, reduced without gathering the
 * state (src/mpi/mpi_reduce.c: the serial leaves of kernels/observe_items.h,
 * merged in the serial order), on every rank: the run's decisions on them
 * are every rank's. */
static int mpi_observe(cd_sim *sim, double *slots, char *err, size_t errlen)
{
    cd_mpi_ctx *x = sim->backend_data;
    /* on a device (offload, OpenCL) the columns the sums read alone come back */
    int dev = cd_mpi_dev_observe_cols(x, err, errlen);
    int rc = dev < 0 ? -1 : dev == 1 ? x->inner->sync(&x->loc, err, errlen) : 0;
    if (agree_failure(x, rc, err, errlen)) return -1;
    rc = cd_mpi_observe_slots(x, sim, slots);
    give_back_memory();
    return rc;
}

/* The load a protocol asks for at every control call: the nonzero wall
 * rows only, summed in the serial order (cd_mpi_wall_load).  The step
 * keeps the rows' F_n per wall candidate (kernels/fields.def WALLC_OUT):
 * on a device (offload, OpenCL) they are read there, one double per local
 * primitive copied back (cd_mpi_dev_wall_fn); on the host the local
 * state's wall rows come from the inner backend's sync.  Every rank calls
 * it, so a failure stops all. */
static int mpi_wall_load(cd_sim *sim, int w, double *load, char *err, size_t errlen)
{
    cd_mpi_ctx *x = sim->backend_data;
    /* on a device (offload, OpenCL) the rows' F_n alone come back (every
     * rank agrees either way: some ranks may hold their state on the host) */
    double *fn = malloc((x->loc.s.n_prims + 1) * sizeof *fn); /* [N] */
    int dev = fn ? cd_mpi_dev_wall_fn(x, w, fn, err, errlen) : -1;
    int rc = dev < 0 ? -1 : dev == 1 ? x->inner->sync(&x->loc, err, errlen) : 0;
    if (!fn) snprintf(err, errlen, "out of memory while summing the load on wall %d", w);
    if (agree_failure(x, rc, err, errlen)) {
        free(fn);
        return -1;
    }
    *load = cd_mpi_wall_load(x, w, dev == 0 ? fn : NULL);
    free(fn);
    return 0;
}

/* Each rank's device (taken: this rank's in words, after the start; NULL:
 * cd_mpi_dev_choose's, made its default device), on rank 0 in rank order,
 * "rank 0: ...; rank 1: ..." (with the node's name when node is set), into
 * a new string (NULL on the other ranks, or out of memory).  Collective. */
static char *devices_of_ranks(cd_mpi_ctx *x, const char *taken, int node)
{
    enum { LEN = 256 };
    char mine[LEN] = "", name[MPI_MAX_PROCESSOR_NAME] = "", *all = x->rank == 0 ? calloc((size_t)x->size, LEN) : NULL;
    if (taken) snprintf(mine, sizeof mine, "%s", taken);
    else cd_mpi_dev_choose(x, mine, sizeof mine);
    int n = 0;
    if (node && MPI_Get_processor_name(name, &n) == MPI_SUCCESS && n > 0) {
        char with[LEN];
        snprintf(with, sizeof with, "%.150s on %.90s", mine, name);
        memcpy(mine, with, LEN);
    }
    MPI_Gather(mine, LEN, MPI_CHAR, all, LEN, MPI_CHAR, 0, x->comm);
    size_t cap = (size_t)x->size * (LEN + 16) + 1, at = 0;
    char *line = all ? malloc(cap) : NULL;
    for (int r = 0; line && r < x->size; r++) {
        int k = snprintf(line + at, cap - at, "%srank %d: %s", r ? "; " : "", r, all + (size_t)r * LEN);
        at += k > 0 ? (size_t)k : 0;
    }
    free(all);
    return line;
}

/* The devices the ranks took, for the run's first line; empty on host
 * threads. */
static char rank_devices[4096];

static void devices_taken(cd_mpi_ctx *x)
{
    char *line = devices_of_ranks(x, NULL, 0); /* (every rank takes its device here, before anything is mapped) */
    rank_devices[0] = 0;
#if defined(CAPDEM_OFFLOAD_TARGET)
    if (line) snprintf(rank_devices, sizeof rank_devices, "%s", line);
#endif
    free(line);
}

/* The OpenCL devices the ranks opened at their first start, for the run's
 * first line.  Collective. */
static void devices_started(cd_mpi_ctx *x)
{
    char mine[256];
    if (!cd_mpi_dev_started(x, mine, sizeof mine)) return; /* (every rank the same inner backend) */
    char *line = devices_of_ranks(x, mine, 0);
    if (line) snprintf(rank_devices, sizeof rank_devices, "%s", line);
    free(line);
}

int cd_mpi_version(void)
{
    int rank, size = cd_mpi_world(&rank);
    int on = 0;
    MPI_Initialized(&on);
    if (!on) return 0; /* not under an MPI launcher */
    cd_mpi_ctx x = {.comm = MPI_COMM_WORLD, .rank = rank, .size = size};
    fflush(stdout);
    char *line = devices_of_ranks(&x, NULL, 1);
    if (rank == 0)
        printf("MPI: %d rank%s, each with the device it takes in a run: %s\n", size, size == 1 ? "" : "s",
               line ? line : "(out of memory)");
    free(line);
    return 0;
}

static const char *mpi_device(const cd_sim *sim)
{
    static char buf[4352];
    const cd_mpi_ctx *x = sim->backend_data;
    char grid[96];
    if (x->grid.kind == CD_DECOMP_RCB) snprintf(grid, sizeof grid, "sub-domains by recursive coordinate bisection");
    else snprintf(grid, sizeof grid, "sub-domains %d x %d x %d", x->grid.dims[0], x->grid.dims[1], x->grid.dims[2]);
    if (rank_devices[0]) snprintf(buf, sizeof buf, "%d MPI ranks (%s): %s", x->size, grid, rank_devices);
    else snprintf(buf, sizeof buf, "%d MPI ranks (%s), each: %s", x->size, grid, x->inner->device(&x->loc));
    return buf;
}

static const cd_backend cd_backend_mpi = {"mpi",    mpi_start,  mpi_step,      mpi_sync,
                                          mpi_stop, mpi_device, mpi_wall_load, mpi_observe};

int cd_mpi_wrap(cd_sim *sim, const char *backend, char *err, size_t errlen)
{
    if (!cd_mpi_decomposed()) return 0;
    (void)backend; /* (omp or opencl: cd_sim_use_backend chose it, sim->backend) */
    cd_mpi_ctx *x = calloc(1, sizeof *x);
    if (!x) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    x->comm = MPI_COMM_WORLD;
    MPI_Comm_rank(x->comm, &x->rank);
    MPI_Comm_size(x->comm, &x->size);
    x->inner = sim->backend ? sim->backend : &cd_backend_omp;
    devices_taken(x); /* an offload build: each rank its device, before anything is mapped; OpenCL: at the start */
    const char *all = getenv("CAPDEM_MPI_ALL_RANKS"); /* the fallback path of a migration, for its test */
    x->all_ranks = all && !strcmp(all, "1");
    /* one run file, every rank writing its particles' rows (docs/mpi.md,
     * "One file"), or rank 0 writing it with the serial writer */
    parallel_output = sim->cfg.mpi_output == 0;
    if (cd_output_use_mpi(parallel_output ? &x->comm : NULL)) {
        snprintf(err, errlen, "this build's HDF5 cannot write one file from several MPI ranks (docs/mpi.md)");
        free(x);
        return -1;
    }
    sim->backend = &cd_backend_mpi;
    sim->backend_data = x;
    free(the_ctx);
    the_ctx = x;
    return 0;
}
