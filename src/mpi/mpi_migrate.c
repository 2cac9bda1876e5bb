/* Migration at neighbour-list rebuilds (docs/mpi.md, "Design"): a
 * particle's holders after it are its owner by its centre now and the
 * ranks its halo reaches, which every holder computes alike from the same
 * position bits; a holder keeps its copy, and the owner sends records to
 * the new holders only (and to a new owner), with the pair rows (history)
 * the receiver lacks; the local state is assembled from both. */
#include <stdlib.h>
#include <string.h>
#include "mpi/mpi_halo.h"

/* Per local particle, the ranks that hold it after a migration: its owner
 * by its centre now first, then the ranks whose sub-domain its halo
 * reaches.  Every rank that holds a particle finds the same list (the same
 * position bits, refreshed every step). */
typedef struct {
    int *first, *count, *ranks;
    size_t n, cap;
} dest_lists;

static void dests_free(dest_lists *d)
{
    free(d->first);
    free(d->count);
    free(d->ranks);
}

static int dests_of_local(cd_mpi_ctx *x, dest_lists *d)
{
    cd_state *s = &x->loc.s;
    size_t N = s->n_particles;
    d->first = calloc(N + 1, sizeof(int));
    d->count = calloc(N + 1, sizeof(int));
    d->cap = 2 * N + (size_t)x->size + 16;
    d->ranks = malloc(d->cap * sizeof(int));
    d->n = 0;
    if (!d->first || !d->count || !d->ranks) return -1;
    double p[3];
    for (size_t q = 0; q < N; q++) {
        if (d->n + (size_t)x->size + 1 > d->cap) {
            int *g = realloc(d->ranks, (d->cap *= 2) * sizeof(int));
            if (!g) return -1;
            d->ranks = g;
        }
        int o = cd_decomp_owner(&x->grid, cd_mpi_pos3(s, q, p));
        d->first[q] = (int)d->n;
        d->ranks[d->n] = o;
        d->count[q] = 1 + cd_decomp_ghost_ranks(&x->grid, p, o, d->ranks + d->n + 1);
        d->n += (size_t)d->count[q];
    }
    return 0;
}

/* Will rank r hold particle q? */
static int goes_to(const dest_lists *d, size_t q, int r)
{
    for (int k = 0; k < d->count[q]; k++)
        if (d->ranks[d->first[q] + k] == r) return 1;
    return 0;
}

/* Does rank r (not this one) hold a ghost of owned particle q now: is q
 * in the ghost refresh to r (planned at the last migration from the ranks
 * q went to; the list per rank ascending)? */
static int ghost_now(const cd_mpi_ctx *x, size_t q, int r)
{
    const int *l = x->send_list + x->send_displ[r];
    int lo = 0, hi = x->send_count[r];
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (l[mid] < (int)q) lo = mid + 1;
        else hi = mid;
    }
    return lo < x->send_count[r] && l[lo] == (int)q;
}

/* Does this rank send particle q to rank r at this migration?  Its owner
 * sends it to each new holder, and to its new owner (which may hold a
 * ghost of it: the owner's record replaces that, so that what a rank
 * owns comes from the previous owner, every column). */
static int sends(const cd_mpi_ctx *x, const dest_lists *d, size_t q, int r)
{
    if (!x->owned[q] || r == x->rank || !goes_to(d, q, r)) return 0;
    return !ghost_now(x, q, r) || d->ranks[d->first[q]] == r;
}

/* Does this rank keep its copy of particle q?  When it still holds q, but
 * not when it comes to own a particle it held as a ghost (the previous
 * owner sends it). */
static int keeps(const cd_mpi_ctx *x, const dest_lists *d, size_t q)
{
    if (!goes_to(d, q, x->rank)) return 0;
    return x->owned[q] || d->ranks[d->first[q]] != x->rank;
}

/* The ranks that get pair row k from this rank (into out, room for twice
 * the ranks): those to which it sends one of the row's particles and
 * which will hold the other one too (a rank that keeps both has the row:
 * every rank builds the rows among all its particles).  Each rank once. */
static int row_dests(const cd_mpi_ctx *x, const dest_lists *d, size_t k, int *out)
{
    const cd_state *s = &x->loc.s;
    size_t a = (size_t)s->prim_particle[s->pair_prim_i[k]], b = (size_t)s->prim_particle[s->pair_prim_j[k]];
    int n = 0;
    for (int e = 0; x->owned[a] && e < d->count[a]; e++) {
        int r = d->ranks[d->first[a] + e];
        if (sends(x, d, a, r) && goes_to(d, b, r)) out[n++] = r;
    }
    for (int e = 0; x->owned[b] && e < d->count[b]; e++) {
        int r = d->ranks[d->first[b] + e];
        if (sends(x, d, b, r) && goes_to(d, a, r) && !sends(x, d, a, r)) out[n++] = r;
    }
    return n;
}

/* Bytes that travel at a migration, per destination rank: a head (the
 * particle records' length), the particle records, the pair records. */
typedef struct {
    long long particle_bytes;
} move_head;

/* Sends out[r] (len[r] bytes, for every rank) and receives what the
 * others send into *in (*inlen bytes, the senders in rank order):
 * point to point with the neighbours (one message each way, empty ones
 * included, the receiver learning the length from the message) when
 * every destination is one, else an MPI_Alltoallv over all ranks (far:
 * agreed by all).  0, or -1 (out of memory). */
static int move_bytes(cd_mpi_ctx *x, char *const *out, const int *len, int far, char **in, size_t *inlen)
{
    int R = x->size;
    if (far) {
        size_t total = 0;
        for (int r = 0; r < R; r++) total += (size_t)len[r];
        char *flat = malloc(total + 1), *at = flat;
        if (!flat) MPI_Abort(x->comm, 1); /* the others wait in the exchange */
        for (int r = 0; r < R; r++) {
            memcpy(at, out[r], (size_t)len[r]);
            at += len[r];
        }
        int rc = cd_mpi_exchange_bytes(x, flat, len, in, inlen);
        free(flat);
        x->far_migrations++;
        return rc;
    }
    int nb = x->n_neighbors, *rlen = malloc(((size_t)nb + 1) * sizeof(int));
    if (!rlen) MPI_Abort(x->comm, 1);
    for (int k = 0; k < nb; k++) {
        int r = x->neighbors[k];
        MPI_Isend(out[r], len[r], MPI_BYTE, r, CD_MPI_TAG_MIGRATE, x->comm, &x->requests[k]);
        x->migrate_msgs++;
        x->migrate_bytes += len[r];
    }
    size_t total = 0;
    for (int k = 0; k < nb; k++) {
        MPI_Status st;
        MPI_Probe(x->neighbors[k], CD_MPI_TAG_MIGRATE, x->comm, &st);
        MPI_Get_count(&st, MPI_BYTE, &rlen[k]);
        total += (size_t)rlen[k];
    }
    *in = malloc(total + 1);
    *inlen = total;
    if (!*in) MPI_Abort(x->comm, 1);
    char *at = *in;
    for (int k = 0; k < nb; k++) {
        MPI_Recv(at, rlen[k], MPI_BYTE, x->neighbors[k], CD_MPI_TAG_MIGRATE, x->comm, MPI_STATUS_IGNORE);
        at += rlen[k];
    }
    MPI_Waitall(nb, x->requests, MPI_STATUSES_IGNORE);
    free(rlen);
    return 0;
}

/* Appends the particle and pair records of the messages in (inlen bytes,
 * each a move_head and its records) to the kept ones (pbuf, cbuf: room
 * made here). */
static int split_moved(const char *in, size_t inlen, char **pbuf, size_t *plen, char **cbuf, size_t *clen)
{
    char *p = realloc(*pbuf, *plen + inlen + 1), *c = p ? realloc(*cbuf, *clen + inlen + 1) : NULL;
    if (p) *pbuf = p;
    if (c) *cbuf = c;
    if (!p || !c) return -1;
    for (size_t at = 0; at < inlen;) { /* a message: head, particle records, a row count, pair records */
        move_head h;
        long long rows;
        memcpy(&h, in + at, sizeof h);
        at += sizeof h;
        memcpy(*pbuf + *plen, in + at, (size_t)h.particle_bytes);
        *plen += (size_t)h.particle_bytes;
        at += (size_t)h.particle_bytes;
        memcpy(&rows, in + at, sizeof rows);
        at += sizeof rows;
        memcpy(*cbuf + *clen, in + at, (size_t)rows * cd_mpi_pair_bytes());
        *clen += (size_t)rows * cd_mpi_pair_bytes();
        at += (size_t)rows * cd_mpi_pair_bytes();
    }
    return 0;
}

int cd_mpi_migrate(cd_mpi_ctx *x)
{
    cd_state *s = &x->loc.s;
    int R = x->size;
    size_t W = s->n_walls, N = s->n_particles;
    dest_lists d = {0};
    int *len = calloc((size_t)R + 1, sizeof(int)), *rows = calloc((size_t)R + 1, sizeof(int));
    int *rd = malloc((2 * (size_t)R + 1) * sizeof(int));
    size_t *pl = calloc((size_t)R + 1, sizeof(size_t));
    char **out = calloc((size_t)R + 1, sizeof(char *)), *in = NULL, *pbuf = NULL, *cbuf = NULL;
    unsigned char *keep = malloc(N + 1); /* the copies this rank keeps: copied into the new state, not packed */
    size_t inlen = 0, plen = 0, clen = 0, kept_c = 0;
    int rc = len && rows && rd && pl && out && keep ? dests_of_local(x, &d) : -1;
    /* what goes where: particle records, then the pair rows */
    for (size_t q = 0; !rc && q < N; q++) {
        for (int e = 0; x->owned[q] && e < d.count[q]; e++)
            if (sends(x, &d, q, d.ranks[d.first[q] + e]))
                pl[d.ranks[d.first[q] + e]] += cd_mpi_particle_bytes(s->prim_count[q], W);
        keep[q] = (unsigned char)keeps(x, &d, q);
    }
    for (size_t k = 0; !rc && k < s->n_pairs; k++) {
        if (!s->pair_active[k]) continue;
        int n = row_dests(x, &d, k, rd);
        for (int e = 0; e < n; e++) rows[rd[e]]++;
        size_t a = (size_t)s->prim_particle[s->pair_prim_i[k]], b = (size_t)s->prim_particle[s->pair_prim_j[k]];
        if (keep[a] && keep[b]) kept_c += cd_mpi_pair_bytes();
    }
    int far = 0;
    for (int r = 0; !rc && r < R; r++) {
        size_t n = pl[r] || rows[r]
                       ? sizeof(move_head) + pl[r] + sizeof(long long) + (size_t)rows[r] * cd_mpi_pair_bytes()
                       : 0;
        len[r] = (int)n;
        out[r] = malloc(n + 1);
        if (!out[r]) rc = -1;
        else if (n) {
            move_head h = {(long long)pl[r]};
            memcpy(out[r], &h, sizeof h);
            long long nr = rows[r];
            memcpy(out[r] + sizeof h + pl[r], &nr, sizeof nr);
        }
        int near = r == x->rank;
        for (int k = 0; k < x->n_neighbors && !near; k++) near = x->neighbors[k] == r;
        far |= n > 0 && !near;
        pl[r] = sizeof(move_head); /* now: where the next particle record goes */
        rows[r] = 0;               /* and how many pair records are in */
    }
    cbuf = rc ? NULL : malloc(kept_c + 1);
    if (!rc && !cbuf) rc = -1;
    /* pack: the records sent, the pair rows kept (the local ones, no message) */
    char *ck = cbuf;
    for (size_t q = 0; !rc && q < N; q++) {
        long long gp = x->gprim[s->prim_first[q]];
        for (int e = 0; x->owned[q] && e < d.count[q]; e++) {
            int r = d.ranks[d.first[q] + e];
            if (!sends(x, &d, q, r)) continue;
            pl[r] = (size_t)(cd_mpi_pack_particle(s, q, x->gid[q], gp, out[r] + pl[r]) - out[r]);
            x->migrate_records++;
        }
    }
    for (size_t k = 0; !rc && k < s->n_pairs; k++) {
        if (!s->pair_active[k]) continue;
        long long gi = x->gprim[s->pair_prim_i[k]], gj = x->gprim[s->pair_prim_j[k]];
        int n = row_dests(x, &d, k, rd);
        for (int e = 0; e < n; e++) {
            int r = rd[e];
            size_t at = pl[r] + sizeof(long long) + (size_t)rows[r]++ * cd_mpi_pair_bytes();
            cd_mpi_pack_pair(s, k, gi, gj, 0, out[r] + at);
        }
        size_t a = (size_t)s->prim_particle[s->pair_prim_i[k]], b = (size_t)s->prim_particle[s->pair_prim_j[k]];
        if (keep[a] && keep[b]) ck = cd_mpi_pack_pair(s, k, gi, gj, 0, ck);
    }
    /* a particle beyond the neighbours (it moved far, or is not finite):
     * this migration goes through all ranks, which all must know */
    int any_far = 0;
    far |= x->all_ranks;
    if (!rc) MPI_Allreduce(&far, &any_far, 1, MPI_INT, MPI_LOR, x->comm);
    if (!rc) rc = move_bytes(x, out, len, any_far, &in, &inlen);
    clen = rc ? 0 : (size_t)(ck - cbuf);
    if (!rc) rc = split_moved(in, inlen, &pbuf, &plen, &cbuf, &clen);
    /* the kept rows copied column by column from the local state, which
     * goes as they are (a rank never holds the old and the new state whole) */
    cd_state scal = *s; /* the scalars only: assemble replaces s */
    if (!rc) rc = cd_mpi_assemble(x, s, x->gid, x->gprim, keep, 1, pbuf, plen, cbuf, clen, &scal);
    if (!rc) x->migrations++;
    dests_free(&d);
    for (int r = 0; out && r < R; r++) free(out[r]);
    free(out);
    free(len);
    free(rows);
    free(rd);
    free(pl);
    free(in);
    free(pbuf);
    free(cbuf);
    free(keep);
    return rc;
}
