/* Inside the MPI decomposition (docs/mpi.md): the context of one rank, and
 * the exchanges of src/mpi/mpi_halo.c that src/mpi/mpi_backend.c drives. */
#ifndef CD_MPI_HALO_H
#define CD_MPI_HALO_H
#include <mpi.h>
#include "core/sim.h"
#include "mpi/mpi_decomp.h"
#include "io/io_h5.h"
#include "halo_items.h" /* the ghost rows packed and unpacked: cd_item_ghost_io, CD_HALO_REALS */

typedef struct {
    MPI_Comm comm;
    int rank, size;
    int node_rank; /* among the ranks of its node (an OpenCL rank's device: cd_mpi_dev_choose) */
    cd_decomp_grid grid;
    const cd_backend *inner; /* the backend that steps the local state (omp or opencl) */
    cd_sim loc;              /* owned particles and ghosts, in ascending global id */
    /* per local particle and primitive, the global ids (ascending) */
    long long *gid, *gprim;
    unsigned char *owned; /* per local particle: 1 owned here, 0 a ghost */
    size_t n_owned;
    /* the ghost refresh of every step, fixed between migrations: the owned
     * particles each rank gets (send_list, per rank in ascending order) and
     * the ghosts each rank sends (recv_list) */
    int *send_count, *send_displ, *recv_count, *recv_displ; /* per rank, in particles */
    int *send_list, *recv_list;
    double *send_buf, *recv_buf;
    /* the same lists and buffers on the offload device (src/mpi/mpi_device.c),
     * where the local state runs in an offload build: the halo is packed
     * and unpacked there and only its rows cross to the host (NULL on host
     * threads); dev_stale: the lists changed since they were copied */
    int *dev_send_list, *dev_recv_list;
    double *dev_send_buf, *dev_recv_buf;
    int dev_stale;
    /* the ranks whose sub-domain comes within the halo and the skin of this
     * one's (cd_decomp_neighbors): the only ones it exchanges with, but for
     * a migration that finds a particle beyond them (then all ranks) */
    int n_neighbors, *neighbors;
    MPI_Request *requests;        /* room for two per neighbour and one */
    long long far_migrations;     /* migrations that had to talk to all ranks */
    int all_ranks;                /* every migration through all ranks (CAPDEM_MPI_ALL_RANKS=1: tests that path) */
    long long migrations;         /* times the particles went to new owners */
    int started;                  /* the local state runs (start succeeded on every rank) */
    int ran;                      /* it ran at least once (the closing report) */
    long last_owned, last_ghosts; /* particles of this rank when it last stopped */
    long start_owned;             /* owned particles at the first start */
    /* wall-clock seconds of this rank (MPI_Wtime): in the serial step (the
     * decision and migration taken out), deciding the rebuild (waits for
     * the slowest rank included), migrating, refreshing ghosts */
    double t_step, t_decide, t_migrate, t_ghosts;
    /* what this rank sent to other ranks (exact, for docs/mpi.md "Speed"):
     * messages and bytes of the ghost refreshes (refreshes of them) and of
     * the migrations, with the particle records among them (the collectives that agree on decisions and statuses
     * not counted: one int each) */
    long long refreshes, refresh_msgs, refresh_bytes, migrate_msgs, migrate_bytes, migrate_records;
    /* the reductions (observables, wall loads: src/mpi/mpi_reduce.c) and
     * what this rank sent for them */
    long long reduces, reduce_msgs, reduce_bytes;
    long long gathers; /* times sync gathered the whole state on every rank (protocols, diagnoses; no snapshot) */
} cd_mpi_ctx;

/* Where the local state runs on a device (src/mpi/mpi_device.c): the
 * offload variant's device (offload builds, the state mapped there) or
 * the OpenCL backend's.  The ghost refresh's packing: the send rows
 * packed there into x->send_buf, or the received x->recv_buf unpacked
 * there into the ghosts' rows; only the halo's bytes cross.  Returns 1
 * when the state is on the host (the caller packs), 0 done, -1 failed
 * (out of device memory, an OpenCL error). */
int cd_mpi_dev_pack(cd_mpi_ctx *x);
int cd_mpi_dev_unpack(cd_mpi_ctx *x);
void cd_mpi_dev_free(cd_mpi_ctx *x);
/* The device of this rank: its node-local rank (MPI_COMM_TYPE_SHARED)
 * modulo the node's devices, made the default offload device before
 * anything is mapped, or the device the OpenCL backend opens at the
 * start; what it took, in words, into desc.  Collective. */
void cd_mpi_dev_choose(cd_mpi_ctx *x, char *desc, size_t len);
/* After the start: the OpenCL device this rank's state is on, in words,
 * into desc, and 1 (0: the offload variant or host threads, which
 * cd_mpi_dev_choose named). */
int cd_mpi_dev_started(cd_mpi_ctx *x, char *desc, size_t len);
/* F_n [N] on wall w of every local primitive (0 where it touches none)
 * into fn, from the step's wall-candidate entries on the device: one
 * double per primitive crosses instead of the local state (a wall load,
 * at every step of a protocol).  1 when the state is on the host (the
 * caller reads its columns), 0 done, -1 with err set. */
int cd_mpi_dev_wall_fn(cd_mpi_ctx *x, int w, double *fn, char *err, size_t errlen);
/* The columns of the local state that an observation reads
 * (src/mpi/mpi_reduce.c: the particles' pose, velocity and angular
 * momentum, the pair rows' primitives, flag, overlap and spring) and its
 * wall rows (from the step's candidate entries) from the device to the
 * host, instead of every column.  1 when the state is on the host (the
 * caller syncs), 0 done, -1 with err set. */
int cd_mpi_dev_observe_cols(cd_mpi_ctx *x, char *err, size_t errlen);
/* Around a migration, which rebuilds the local state on the host: the
 * device's state copied back (and let go by the offload variant; leave:
 * 1, or 0 when the state is on the host, -1 with err set), put on the
 * device again (return, after a leave that returned 1: 0, or -1 with err
 * set). */
int cd_mpi_dev_leave(cd_mpi_ctx *x, char *err, size_t errlen);
int cd_mpi_dev_return(cd_mpi_ctx *x, char *err, size_t errlen);

/* The local state of this rank cut from a global state (every rank holds
 * the same one at start), or from this rank's part of it (gid, gprim: the
 * global ids of its particles and primitives, ascending, as a set-up of
 * part of the run builds it, core/sim.h; NULL: global is the whole run):
 * owned particles, ghosts, the active pair rows among them; the
 * neighbours and the ghost refresh planned.  release: the global state's
 * columns let go column by column as the local state is assembled (its
 * counts and scalars kept), so that a rank never holds both.  0, or -1
 * (out of memory). */
int cd_mpi_distribute(cd_mpi_ctx *x, cd_state *global, const long long *gid, const long long *gprim, int release);
/* The rank count of MPI_COMM_WORLD and this process's rank in *rank (1
 * and 0 when MPI is not started). */
int cd_mpi_world(int *rank);
/* The interaction range [m] of particles whose largest bounding radius
 * about the centre is bound_max [m], with the skin [m]: twice the bound
 * plus the skin, widened by roundings (src/mpi/mpi_setup.c). */
double cd_mpi_range(double bound_max, double skin);
/* The decomposition made by the set-up of this rank's part of the run
 * (cd_mpi_setup_keep) into g, once: 1, or 0 when none was made. */
int cd_mpi_setup_grid(cd_decomp_grid *g);
/* Particles the set-up of this rank built (its own and its ghosts), or -1
 * when it built every particle. */
long cd_mpi_setup_built(void);
/* Every particle to the ranks that hold it by its centre now (its owner,
 * and as a ghost the ranks within the interaction range): a rank keeps
 * the copies it has and gets, from the particle's owner, only the ones
 * it lacks and the particles it comes to own, with their primitive and
 * wall-contact rows and the active pair rows (history) it lacks; the
 * local state is rebuilt from both.  Point to point with the neighbours
 * (one message each), with all ranks when a particle went beyond them.
 * Collective.  0, or -1 (out of memory). */
int cd_mpi_migrate(cd_mpi_ctx *x);
/* The ghosts' pose, velocities, force and torque from their owners, after
 * a step (the serial step leaves them computed from partial forces): a
 * message to and from each neighbour that has ghosts of the other; and,
 * overlapped with them, every rank's status (failed: 0 or 1, one
 * MPI_Iallreduce), so that the ranks agree to go on or stop at the same
 * step.  Collective.  Returns the lowest rank that failed, or the rank
 * count when none did. */
int cd_mpi_refresh_ghosts(cd_mpi_ctx *x, int failed);
/* The owned rows of every rank into global, on every rank: particles,
 * primitives and wall-contact rows at their global row, the pair rows at
 * the serial list's row numbers (inactive ones marked); the scalars (step,
 * time, walls, control).  Every rank then holds the serial program's
 * state, so that protocols, observables and output read it as they do in
 * one process.  Collective.  0, or -1 (out of memory). */
int cd_mpi_gather(cd_mpi_ctx *x, cd_state *global);
/* Normal load on wall w [N] with the serial program's bits (the sum of
 * kernels/step_items.h, CD_LOAD_CHUNK, over the primitives), from the
 * nonzero rows alone: each chunk summed on rank chunk % R, the chunks'
 * sums merged in order on rank 0; the load on every rank
 * (src/mpi/mpi_reduce.c).  fn: F_n per local primitive
 * (cd_mpi_dev_wall_fn), or NULL: the local state's wall rows.
 * Collective. */
double cd_mpi_wall_load(cd_mpi_ctx *x, int w, const double *fn);
/* The observables' slots (kernels/observe_items.h) with the serial
 * program's bits, without gathering the state: each block of rows summed
 * by the serial block function on rank block % R from its rows' owners'
 * records, the blocks merged in order on rank 0, the total on every rank
 * (src/mpi/mpi_reduce.c).  Reads of global its counts and laws only (each
 * leaf is summed on columns of its own rows).  Collective. */
int cd_mpi_observe_slots(cd_mpi_ctx *x, const cd_sim *global, double *total);
/* This rank's part of a snapshot (io_h5.h cd_output_part) from its local
 * state, the scalars from scal (the global state's): the place of each
 * owned particle's first contact and wall-contact row among the
 * snapshot's rows, from an exclusive prefix sum over the particles in
 * global id order (src/mpi/mpi_output.c).  Returns the array that
 * part->pair_at and wallc_at point into (the caller frees it).
 * Collective; out of memory aborts the run. */
long long *cd_mpi_output_part(cd_mpi_ctx *x, const cd_state *scal, cd_output_part *part);
void cd_mpi_halo_free(cd_mpi_ctx *x);

/* ---- records, shared by src/mpi/mpi_halo.c and src/mpi/mpi_migrate.c ------
 * A particle travels as one record of bytes (a head, every column of
 * fields.def of the particle, its primitives and their wall-contact rows),
 * a pair row as its two global primitives and its columns. */
enum { CD_MPI_TAG_GHOSTS = 1, CD_MPI_TAG_MIGRATE = 2 };
size_t cd_mpi_particle_bytes(long long n_prims, size_t n_walls);
size_t cd_mpi_pair_bytes(void);
/* Particle q of s (global id gid, first global primitive gp), or pair row
 * k (global primitives gi, gj; rank_in_row: cd_mpi_gather's), packed at
 * b; returns the end of the record. */
char *cd_mpi_pack_particle(cd_state *s, size_t q, long long gid, long long gp, char *b);
char *cd_mpi_pack_pair(cd_state *s, size_t k, long long gi, long long gj, long long rank_in_row, char *b);
/* The local state, in ascending global id, from the particles of `from`
 * marked in keep (a state in ascending global id: from_gid and from_gprim
 * its particles' and primitives' global ids, NULL for a global state,
 * whose rows are its ids) and the particle records of pbuf (a record
 * replaces a kept row of its id), the pair records of cbuf (a key given
 * twice taken once; from's own pair rows are not read), the scalars of
 * scal; ownership by the centre, the ghost refresh planned, the list to be
 * rebuilt.  Column by column; with release each column of from is let go
 * as soon as its rows are copied (its pair columns first), so that a rank
 * never holds both states whole.  0, or -1 (out of memory; from then
 * partly let go when release). */
int cd_mpi_assemble(cd_mpi_ctx *x, cd_state *from, const long long *from_gid, const long long *from_gprim,
                    const unsigned char *keep, int release, const char *pbuf, size_t plen, const char *cbuf,
                    size_t clen, const cd_state *scal);
/* MPI_Alltoallv of bytes over all ranks: sc[r] bytes to rank r (in rank
 * order in send) into a new buffer *recv of *rlen bytes.  0, or -1. */
int cd_mpi_exchange_bytes(cd_mpi_ctx *x, const char *send, const int *sc, char **recv, size_t *rlen);

static inline double *cd_mpi_pos3(const cd_state *s, size_t q, double x[3])
{
    x[0] = s->position[q].x;
    x[1] = s->position[q].y;
    x[2] = s->position[q].z;
    return x;
}

#endif
