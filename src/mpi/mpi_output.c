/* Each rank's part of a snapshot (docs/mpi.md, "One file"): the rows of
 * the particles it owns are written from its local state, where no rank
 * holds the whole state.  A particle's and a primitive's row in the file
 * is its global id; the active contact rows of a snapshot are in the
 * serial list's order (global primitive i, then j) and the wall-contact
 * rows in primitive x wall order, so a particle's rows start after those
 * of every particle with a smaller global id: an exclusive prefix sum of
 * the rows per particle in global id order.  The sum is spread over the
 * ranks by blocks of global ids (rank b sums ids [lo(b), lo(b + 1))), so
 * that no rank holds a count per particle of the run. */
#include <stdlib.h>
#include <string.h>
#include "mpi/mpi_halo.h"

/* The first global id of block b of N ids over R ranks. */
static long long block_lo(long long b, long long N, long long R) { return (b * N + R - 1) / R; }

/* The block (rank) of global id g. */
static int block_of(long long g, long long N, long long R) { return N > 0 ? (int)(g * R / N) : 0; }

long long *cd_mpi_output_part(cd_mpi_ctx *x, const cd_state *scal, cd_output_part *part)
{
    const cd_state *s = &x->loc.s;
    size_t n = s->n_particles, W = s->n_walls;
    long long N = (long long)scal->n_particles, R = x->size;
    /* rows per local particle: [q] contacts as particle i, [n + q] wall contacts (owned particles only) */
    long long *at = calloc(2 * n + 1, sizeof *at);
    int *cnt = calloc(4 * (size_t)R, sizeof *cnt), *sc = cnt, *sd = cnt + R, *rc = cnt + 2 * R, *rd = cnt + 3 * R;
    if (!at || !cnt) MPI_Abort(x->comm, 1); /* (the other ranks are about to wait in the exchange) */
    for (size_t k = 0; k < s->n_pairs; k++) {
        size_t q = (size_t)s->prim_particle[s->pair_prim_i[k]];
        if (s->pair_active[k] && x->owned[q]) at[q]++;
    }
    for (size_t r = 0; r < s->n_prims * W; r++) {
        size_t q = (size_t)s->prim_particle[r / W];
        if (s->wallc_active[r] && x->owned[q]) at[n + q]++;
    }
    /* (global id, contacts, wall contacts) of the owned particles with rows,
     * to the ranks of their blocks: in local order, which is global id
     * order, so the records of a block are contiguous */
    size_t m = 0;
    for (size_t q = 0; q < n; q++)
        if (x->owned[q] && (at[q] || at[n + q])) {
            sc[block_of(x->gid[q], N, R)] += 3;
            m++;
        }
    long long *send = malloc((3 * m + 1) * sizeof *send), *e = send;
    if (!send) MPI_Abort(x->comm, 1);
    for (size_t q = 0; q < n; q++)
        if (x->owned[q] && (at[q] || at[n + q])) {
            e[0] = x->gid[q];
            e[1] = at[q];
            e[2] = at[n + q];
            e += 3;
        }
    MPI_Alltoall(sc, 1, MPI_INT, rc, 1, MPI_INT, x->comm);
    int ns = 0, nr = 0;
    for (int r = 0; r < R; r++) {
        sd[r] = ns;
        rd[r] = nr;
        ns += sc[r];
        nr += rc[r];
    }
    long long lo = block_lo(x->rank, N, R), len = block_lo(x->rank + 1, N, R) - lo;
    long long *recv = malloc(((size_t)nr + 1) * sizeof *recv), *sum = calloc(2 * (size_t)len + 2, sizeof *sum);
    if (!recv || !sum) MPI_Abort(x->comm, 1);
    MPI_Alltoallv(send, sc, sd, MPI_LONG_LONG, recv, rc, rd, MPI_LONG_LONG, x->comm);
    /* this block's rows per particle, their exclusive prefix sum, and the
     * rows of the blocks before it (rank order is global id order) */
    for (int k = 0; k < nr; k += 3) {
        sum[2 * (recv[k] - lo)] = recv[k + 1];
        sum[2 * (recv[k] - lo) + 1] = recv[k + 2];
    }
    long long total[2] = {0, 0}, before[2] = {0, 0}, all[2];
    for (long long g = 0; g < len; g++)
        for (int c = 0; c < 2; c++) {
            long long v = sum[2 * g + c];
            sum[2 * g + c] = total[c];
            total[c] += v;
        }
    MPI_Exscan(total, before, 2, MPI_LONG_LONG, MPI_SUM, x->comm);
    if (x->rank == 0) before[0] = before[1] = 0; /* (MPI_Exscan leaves rank 0's undefined) */
    MPI_Allreduce(total, all, 2, MPI_LONG_LONG, MPI_SUM, x->comm);
    /* the first rows back to the particles' owners, in the order they came */
    for (int k = 0; k < nr; k += 3) {
        long long g = recv[k] - lo;
        recv[k + 1] = before[0] + sum[2 * g];
        recv[k + 2] = before[1] + sum[2 * g + 1];
    }
    MPI_Alltoallv(recv, rc, rd, MPI_LONG_LONG, send, sc, sd, MPI_LONG_LONG, x->comm);
    e = send;
    for (size_t q = 0; q < n; q++)
        if (x->owned[q] && (at[q] || at[n + q])) {
            at[q] = e[1];
            at[n + q] = e[2];
            e += 3;
        }
    free(send);
    free(recv);
    free(sum);
    free(cnt);
    *part = (cd_output_part){.s = s,
                             .scal = scal,
                             .n_particles = scal->n_particles,
                             .n_prims = scal->n_prims,
                             .gid = x->gid,
                             .gprim = x->gprim,
                             .owned = x->owned,
                             .pair_at = at,
                             .wallc_at = at + n,
                             .n_pair_rows = all[0],
                             .n_wallc_rows = all[1]};
    return at;
}
