/* The exchanges of the MPI decomposition (docs/mpi.md, "Design"): the
 * local state cut from the global one and assembled from records (the
 * migration at neighbour-list rebuilds, src/mpi/mpi_migrate.c, sends
 * them), the ghost refresh of every step, the gather on every rank.
 *
 * A rank's local state is an ordinary cd_state whose particles are its
 * owned ones and its ghosts, in ascending global id, each with all its
 * primitives and wall-contact rows.  Local order is global order, so the
 * serial step run on it orients every pair row, sorts every row list and
 * sums every particle's contacts exactly as the serial program does: an
 * owned particle gets the same bits.
 *
 * Records travel as bytes: a particle with its primitives and wall rows
 * (every column of fields.def, so a new column travels without a change
 * here), and a pair row with its two global primitive ids. */
#include <stdlib.h>
#include <string.h>
#include "mpi/mpi_halo.h"
#include "step_items.h"

typedef struct {
    long long gid, gprim_first, n_prims, pad;
} rec_head;

typedef struct {
    long long gi, gj;      /* global primitives */
    long long rank_in_row; /* gather: the row's place among the rows of primitive gi (0 in a migration) */
} pair_head;

/* A record found in a received buffer. */
typedef struct {
    long long a, b; /* particle: gid, -; pair: global primitives i, j */
    const char *at; /* the record */
} rec_ref;

static size_t group_bytes(enum cd_field_group g)
{
    size_t b = 0;
    for (size_t k = 0; k < cd_n_fields; k++)
        if (cd_fields[k].group == g) b += cd_fields[k].elem_size;
    return b;
}

size_t cd_mpi_particle_bytes(long long n_prims, size_t n_walls)
{
    return sizeof(rec_head) + group_bytes(CD_GROUP_PARTICLE) +
           (size_t)n_prims * (group_bytes(CD_GROUP_PRIM) + n_walls * group_bytes(CD_GROUP_WALLC));
}

size_t cd_mpi_pair_bytes(void) { return sizeof(pair_head) + group_bytes(CD_GROUP_PAIR); }

/* Rows [row, row + n) of every column of group g to b (pack = 1) or from
 * b; returns the end of those bytes in b. */
static char *rows_io(cd_state *s, enum cd_field_group g, size_t row, size_t n, char *b, int pack)
{
    for (size_t k = 0; k < cd_n_fields; k++) {
        const cd_field_info *f = &cd_fields[k];
        if (f->group != g) continue;
        char *col = (char *)*cd_field_ptr(s, f) + row * f->elem_size;
        if (pack) memcpy(b, col, n * f->elem_size);
        else memcpy(col, b, n * f->elem_size);
        b += n * f->elem_size;
    }
    return b;
}

/* Particle q of s with global id gid and first global primitive gp. */
char *cd_mpi_pack_particle(cd_state *s, size_t q, long long gid, long long gp, char *b)
{
    rec_head h = {gid, gp, s->prim_count[q], 0};
    memcpy(b, &h, sizeof h);
    b += sizeof h;
    size_t p0 = (size_t)s->prim_first[q], n = (size_t)s->prim_count[q];
    b = rows_io(s, CD_GROUP_PARTICLE, q, 1, b, 1);
    b = rows_io(s, CD_GROUP_PRIM, p0, n, b, 1);
    return rows_io(s, CD_GROUP_WALLC, p0 * s->n_walls, n * s->n_walls, b, 1);
}

/* A particle record into row l of s, its primitives from row pl. */
static void unpack_particle(cd_state *s, size_t l, size_t pl, const char *rec)
{
    rec_head h;
    memcpy(&h, rec, sizeof h);
    char *b = (char *)rec + sizeof h;
    size_t n = (size_t)h.n_prims;
    b = rows_io(s, CD_GROUP_PARTICLE, l, 1, b, 0);
    b = rows_io(s, CD_GROUP_PRIM, pl, n, b, 0);
    rows_io(s, CD_GROUP_WALLC, pl * s->n_walls, n * s->n_walls, b, 0);
    s->prim_first[l] = (cd_int)pl; /* the index columns in this state's numbering */
    for (size_t k = 0; k < n; k++) s->prim_particle[pl + k] = (cd_int)l;
}

char *cd_mpi_pack_pair(cd_state *s, size_t k, long long gi, long long gj, long long rank_in_row, char *b)
{
    pair_head h = {gi, gj, rank_in_row};
    memcpy(b, &h, sizeof h);
    return rows_io(s, CD_GROUP_PAIR, k, 1, b + sizeof h, 1);
}

static int cmp_ref(const void *pa, const void *pb)
{
    const rec_ref *a = pa, *b = pb;
    if (a->a != b->a) return a->a < b->a ? -1 : 1;
    if (a->b != b->b) return a->b < b->b ? -1 : 1;
    return 0;
}

/* The records of n bytes at buf: particles (pairs = 0) or pair rows, sorted
 * by global id or key; *count of them.  NULL only when out of memory. */
static rec_ref *parse(const char *buf, size_t n, int pairs, size_t n_walls, size_t *count)
{
    size_t cap = 16, m = 0;
    rec_ref *r = malloc(cap * sizeof *r);
    for (size_t at = 0; r && at < n; m++) {
        if (m == cap) {
            rec_ref *g = realloc(r, (cap *= 2) * sizeof *r);
            if (!g) {
                free(r);
                return NULL;
            }
            r = g;
        }
        long long h[3];
        memcpy(h, buf + at, sizeof h);
        r[m] = (rec_ref){h[0], pairs ? h[1] : 0, buf + at};
        at += pairs ? cd_mpi_pair_bytes() : cd_mpi_particle_bytes(h[2], n_walls);
    }
    if (r) qsort(r, m, sizeof *r, cmp_ref);
    *count = m;
    return r;
}

/* The pair records (sorted by key, a key given twice taken once) whose two
 * primitives the local state s holds (gprim: their global ids) into its
 * pair rows, in key order: the order the serial build keeps them in, which
 * is also local key order (the history the next build carries over). */
static int place_pairs(cd_state *s, const rec_ref *r, size_t n, const long long *gprim)
{
    if (cd_state_reserve_pairs(s, n + 16)) return -1;
    size_t m = 0;
    for (size_t k = 0; k < n; k++) {
        if (k > 0 && r[k].a == r[k - 1].a && r[k].b == r[k - 1].b) continue;
        long long i = cd_sorted_index(gprim, s->n_prims, r[k].a), j = cd_sorted_index(gprim, s->n_prims, r[k].b);
        if (i < 0 || j < 0) continue;
        rows_io(s, CD_GROUP_PAIR, m, 1, (char *)r[k].at + sizeof(pair_head), 0);
        s->pair_prim_i[m] = (cd_int)i;
        s->pair_prim_j[m] = (cd_int)j;
        m++;
    }
    s->n_pairs = m;
    return 0;
}

static void copy_scalars(cd_state *dst, const cd_state *src)
{
    dst->n_walls = src->n_walls;
    memcpy(dst->walls, src->walls, sizeof dst->walls);
    memcpy(dst->control, src->control, sizeof dst->control);
    dst->time = src->time;
    dst->step = src->step;
}

/* The ghost refresh until the next migration: owned particles to the
 * ranks whose halo they are in, ghosts from their owners, both in
 * ascending global id (the same lists, seen from either side). */
static int plan_refresh(cd_mpi_ctx *x)
{
    cd_state *s = &x->loc.s;
    int R = x->size, *ranks = malloc((size_t)R * sizeof *ranks);
    if (!ranks) return -1;
    double p[3];
    memset(x->send_count, 0, (size_t)R * sizeof(int));
    memset(x->recv_count, 0, (size_t)R * sizeof(int));
    for (int pass = 0; pass < 2; pass++) { /* count, then fill */
        if (pass == 1) {
            int ns = 0, nr = 0;
            for (int r = 0; r < R; r++) {
                x->send_displ[r] = ns;
                x->recv_displ[r] = nr;
                ns += x->send_count[r];
                nr += x->recv_count[r];
                x->send_count[r] = x->recv_count[r] = 0;
            }
            free(x->send_list);
            free(x->recv_list);
            free(x->send_buf);
            free(x->recv_buf);
            x->send_list = malloc(((size_t)ns + 1) * sizeof(int));
            x->recv_list = malloc(((size_t)nr + 1) * sizeof(int));
            x->dev_stale = 1; /* (the device's copies follow at the next refresh) */
            x->send_buf = malloc(((size_t)ns * CD_HALO_REALS + 1) * sizeof(double));
            x->recv_buf = malloc(((size_t)nr * CD_HALO_REALS + 1) * sizeof(double));
            if (!x->send_list || !x->recv_list || !x->send_buf || !x->recv_buf) {
                free(ranks);
                return -1;
            }
        }
        for (size_t q = 0; q < s->n_particles; q++) {
            if (x->owned[q]) {
                int n = cd_decomp_ghost_ranks(&x->grid, cd_mpi_pos3(s, q, p), x->rank, ranks);
                for (int k = 0; k < n; k++) {
                    if (pass) x->send_list[x->send_displ[ranks[k]] + x->send_count[ranks[k]]] = (int)q;
                    x->send_count[ranks[k]]++;
                }
            } else {
                int o = cd_decomp_owner(&x->grid, cd_mpi_pos3(s, q, p));
                if (pass) x->recv_list[x->recv_displ[o] + x->recv_count[o]] = (int)q;
                x->recv_count[o]++;
            }
        }
    }
    free(ranks);
    return 0;
}

/* Where column f of a particle record (n primitives, W walls) starts:
 * the order of cd_mpi_pack_particle (rows_io over the groups). */
static size_t record_field_at(const cd_field_info *f, long long n, size_t W)
{
    static const enum cd_field_group order[3] = {CD_GROUP_PARTICLE, CD_GROUP_PRIM, CD_GROUP_WALLC};
    size_t at = sizeof(rec_head);
    for (int g = 0; g < 3; g++) {
        size_t rows = g == 0 ? 1 : g == 1 ? (size_t)n : (size_t)n * W;
        for (size_t k = 0; k < cd_n_fields; k++) {
            if (cd_fields[k].group != order[g]) continue;
            if (&cd_fields[k] == f) return at;
            at += rows * cd_fields[k].elem_size;
        }
    }
    return at;
}

/* A row of the new local state: row q of the state it is cut from, or a
 * received record. */
typedef struct {
    long long gid, q, n_prims, first; /* q < 0: rec; first: its first primitive in the new state */
    const char *rec;
} source;

/* The rows of from that stay (keep, ascending global id) and the records
 * (ascending global id; a record replaces a kept row of the same id) in
 * ascending global id into *out; their count, or -1 (out of memory). */
static long long merge_sources(const cd_state *from, const long long *from_gid, const unsigned char *keep,
                               const rec_ref *pr, size_t nr, source **out)
{
    size_t nf = from ? from->n_particles : 0, n = 0, a = 0, b = 0;
    source *v = malloc((nf + nr + 1) * sizeof *v);
    if (!(*out = v)) return -1;
    while (a < nf || b < nr) {
        if (a < nf && !keep[a]) {
            a++;
            continue;
        }
        long long ga = a < nf ? (from_gid ? from_gid[a] : (long long)a) : 0;
        if (b < nr && (a >= nf || pr[b].a <= ga)) {
            rec_head h;
            memcpy(&h, pr[b].at, sizeof h);
            v[n++] = (source){h.gid, -1, h.n_prims, 0, pr[b].at};
            if (a < nf && pr[b].a == ga) a++; /* (the record's bits lead) */
            b++;
        } else {
            v[n++] = (source){ga, (long long)a, from->prim_count[a], 0, NULL};
            a++;
        }
    }
    return (long long)n;
}

int cd_mpi_assemble(cd_mpi_ctx *x, cd_state *from, const long long *from_gid, const long long *from_gprim,
                    const unsigned char *keep, int release, const char *pbuf, size_t plen, const char *cbuf,
                    size_t clen, const cd_state *scal)
{
    size_t W = scal->n_walls, nr = 0, K = 0, P = 0, nf = from ? from->n_particles : 0;
    rec_ref *pr = parse(pbuf, plen, 0, W, &nr), *cr = parse(cbuf, clen, 1, W, &K);
    source *src = NULL;
    long long N = pr && cr ? merge_sources(from, from_gid, keep, pr, nr, &src) : -1;
    /* the first primitive of every row of from (its prim_first goes with
     * the other columns) */
    cd_int *old_first = malloc((nf + 1) * sizeof *old_first);
    int rc = N >= 0 && old_first ? 0 : -1;
    for (size_t q = 0; !rc && q < nf; q++) old_first[q] = from->prim_first[q];
    for (long long l = 0; !rc && l < N; l++) {
        src[l].first = (long long)P;
        P += (size_t)src[l].n_prims;
    }
    cd_state s;
    memset(&s, 0, sizeof s);
    s.n_particles = rc ? 0 : (size_t)N;
    s.n_prims = P;
    copy_scalars(&s, scal);
    long long *gid = rc ? NULL : malloc(((size_t)N + 1) * sizeof *gid),
              *gprim = rc ? NULL : malloc((P + 1) * sizeof *gprim);
    unsigned char *owned = rc ? NULL : malloc((size_t)N + 1);
    if (!gid || !gprim || !owned) rc = -1;
    if (!rc && release) /* (the kept pair rows are among cbuf's records) */
        for (size_t k = 0; k < cd_n_fields; k++)
            if (cd_group_pair_rows(cd_fields[k].group)) {
                void **slot = cd_field_ptr(from, &cd_fields[k]);
                free(*slot);
                *slot = NULL;
            }
    /* column by column: each new column filled from its rows of from and
     * from the records, the old one let go at once (release), so that a
     * rank holds one column of both at a time */
    for (size_t k = 0; !rc && k < cd_n_fields; k++) {
        const cd_field_info *f = &cd_fields[k];
        if (cd_group_pair_rows(f->group)) continue;
        /* rows per primitive (W for wall-contact rows), or a particle's one */
        int by_prim = f->group != CD_GROUP_PARTICLE;
        size_t e = f->elem_size, per = f->group == CD_GROUP_WALLC ? W : 1;
        char *col = calloc(cd_state_rows(&s, f->group) + 1, e), *old = from ? *cd_field_ptr(from, f) : NULL;
        if (!col) {
            rc = -1;
            break;
        }
        for (long long l = 0; l < N; l++) {
            const source *v = &src[l];
            size_t rows = by_prim ? (size_t)v->n_prims * per : 1, to = by_prim ? (size_t)v->first * per : (size_t)l;
            if (v->q >= 0) {
                size_t fr = by_prim ? (size_t)old_first[v->q] * per : (size_t)v->q;
                memcpy(col + to * e, old + fr * e, rows * e);
            } else {
                memcpy(col + to * e, v->rec + record_field_at(f, v->n_prims, W), rows * e);
            }
        }
        *cd_field_ptr(&s, f) = col;
        if (release && from) {
            free(old);
            *cd_field_ptr(from, f) = NULL;
        }
    }
    if (!rc && release && from) cd_state_free(from); /* (its arms; the columns are gone already) */
    /* the index columns in the new numbering, the global ids, ownership */
    x->n_owned = 0;
    for (long long l = 0; !rc && l < N; l++) {
        const source *v = &src[l];
        long long g0 = v->q < 0 ? 0 : from_gprim ? from_gprim[old_first[v->q]] : (long long)old_first[v->q];
        if (v->q < 0) {
            rec_head h;
            memcpy(&h, v->rec, sizeof h);
            g0 = h.gprim_first;
        }
        s.prim_first[l] = (cd_int)v->first;
        for (long long k = 0; k < v->n_prims; k++) {
            s.prim_particle[v->first + k] = (cd_int)l;
            gprim[v->first + k] = g0 + k;
        }
        gid[l] = v->gid;
        double p[3];
        owned[l] = cd_decomp_owner(&x->grid, cd_mpi_pos3(&s, (size_t)l, p)) == x->rank;
        x->n_owned += owned[l];
    }
    if (!rc) rc = place_pairs(&s, cr, K, gprim);
    /* the arms the step reads (kernels/cols.h), from the rows */
    if (!rc) rc = cd_state_arms_derive(&s);
    free(pr);
    free(cr);
    free(src);
    free(old_first);
    if (rc) {
        cd_state_free(&s);
        free(gid);
        free(gprim);
        free(owned);
        return -1;
    }
    cd_state_free(&x->loc.s); /* (from, when it is the local state: let go already with release) */
    x->loc.s = s;
    free(x->gid);
    free(x->gprim);
    free(x->owned);
    x->gid = gid;
    x->gprim = gprim;
    x->owned = owned;
    double skin = x->loc.nb.skin;           /* [m] */
    cd_neighbors_free(&x->loc.nb);          /* sized for the old rows */
    cd_neighbors_init(&x->loc.nb, skin, 0); /* local order = global id order (docs/mpi.md) */
    return plan_refresh(x);
}

/* The ranks this one talks to: those whose sub-domain comes within the
 * halo (ghosts) and the skin (room for the motion between migrations) of
 * its own. */
static int find_neighbors(cd_mpi_ctx *x)
{
    free(x->neighbors);
    free(x->requests);
    x->neighbors = malloc(((size_t)x->size + 1) * sizeof(int));
    if (!x->neighbors) return -1;
    x->n_neighbors = cd_decomp_neighbors(&x->grid, x->rank, x->grid.halo + x->loc.nb.skin, x->neighbors);
    x->requests = malloc((2 * (size_t)x->n_neighbors + 1) * sizeof(MPI_Request));
    return x->requests ? 0 : -1;
}

int cd_mpi_distribute(cd_mpi_ctx *x, cd_state *global, const long long *gid, const long long *gprim, int release)
{
    size_t cb = 0, N = global->n_particles;
    int *ranks = malloc((size_t)x->size * sizeof *ranks);
    unsigned char *here = malloc(N + 1);
    double p[3];
    if (find_neighbors(x) || !ranks || !here) {
        free(ranks);
        free(here);
        return -1;
    }
    for (size_t k = 0; k < global->n_pairs; k++) cb += global->pair_active[k] ? cd_mpi_pair_bytes() : 0;
    char *cbuf = malloc(cb + 1), *at = cbuf;
    int rc = cbuf ? 0 : -1;
    for (size_t q = 0; !rc && q < N; q++) { /* this rank's particles: owned, and ghosts */
        int o = cd_decomp_owner(&x->grid, cd_mpi_pos3(global, q, p));
        here[q] = o == x->rank;
        int n = cd_decomp_ghost_ranks(&x->grid, p, o, ranks);
        for (int k = 0; k < n && !here[q]; k++) here[q] = ranks[k] == x->rank;
    }
    for (size_t k = 0; !rc && k < global->n_pairs; k++)
        if (global->pair_active[k])
            at = cd_mpi_pack_pair(global, k, gprim ? gprim[global->pair_prim_i[k]] : global->pair_prim_i[k],
                                  gprim ? gprim[global->pair_prim_j[k]] : global->pair_prim_j[k], 0, at);
    /* the particles' rows straight from the global columns (of a whole
     * run, its rows are the global ids), which go as they are copied when
     * release is set */
    if (!rc) rc = cd_mpi_assemble(x, global, gid, gprim, here, release, NULL, 0, cbuf, (size_t)(at - cbuf), global);
    free(ranks);
    free(here);
    free(cbuf);
    return rc;
}

/* Alltoallv of bytes: send (sc[r] bytes to rank r, in rank order) into a
 * new buffer *recv of *rlen bytes. */
int cd_mpi_exchange_bytes(cd_mpi_ctx *x, const char *send, const int *sc, char **recv, size_t *rlen)
{
    int R = x->size, *rc = calloc((size_t)R * 3 + 1, sizeof(int)), *sd = malloc(((size_t)R + 1) * sizeof(int));
    if (!rc || !sd) {
        free(rc);
        free(sd);
        return -1;
    }
    int *rd = rc + R;
    MPI_Alltoall(sc, 1, MPI_INT, rc, 1, MPI_INT, x->comm);
    x->migrate_msgs += R - 1; /* the counts: one int to every other rank */
    x->migrate_bytes += (long long)(R - 1) * (long long)sizeof(int);
    for (int r = 0; r < R; r++)
        if (r != x->rank && sc[r] > 0) {
            x->migrate_msgs++;
            x->migrate_bytes += sc[r];
        }
    size_t ns = 0, nr = 0;
    for (int r = 0; r < R; r++) {
        sd[r] = (int)ns;
        rd[r] = (int)nr;
        ns += (size_t)sc[r];
        nr += (size_t)rc[r];
    }
    *recv = malloc(nr + 1);
    *rlen = nr;
    if (*recv) MPI_Alltoallv(send, sc, sd, MPI_BYTE, *recv, rc, rd, MPI_BYTE, x->comm);
    free(rc);
    free(sd);
    return *recv ? 0 : -1;
}

/* The halo could not be packed or unpacked on the device (out of its
 * memory, an OpenCL error): the other ranks wait in the exchange. */
static void device_failed(cd_mpi_ctx *x)
{
    fprintf(stderr, "capdem: MPI rank %d: the ghost refresh failed on the device (%s)\n", x->rank,
            x->loc.backend ? x->loc.backend->device(&x->loc) : "?");
    fflush(stderr);
    MPI_Abort(x->comm, 1);
}

int cd_mpi_refresh_ghosts(cd_mpi_ctx *x, int failed)
{
    cd_state *s = &x->loc.s;
    int G = CD_HALO_REALS, n = 0, who = failed ? x->rank : x->size, first = x->size;
    MPI_Iallreduce(&who, &first, 1, MPI_INT, MPI_MIN, x->comm, &x->requests[n++]);
    /* the ghosts of a neighbour here, the owned particles it has ghosts of
     * (the counts known on both sides since the last migration) */
    for (int k = 0; k < x->n_neighbors; k++) {
        int r = x->neighbors[k];
        if (x->recv_count[r])
            MPI_Irecv(x->recv_buf + (size_t)x->recv_displ[r] * G, x->recv_count[r] * G, MPI_DOUBLE, r,
                      CD_MPI_TAG_GHOSTS, x->comm, &x->requests[n++]);
    }
    cd_cols c = cd_sim_host_cols(s);
    int host = cd_mpi_dev_pack(x); /* on an offload device: every send row packed there */
    if (host < 0) device_failed(x);
    for (int k = 0; k < x->n_neighbors; k++) {
        int r = x->neighbors[k];
        if (!x->send_count[r]) continue;
        double *b = x->send_buf + (size_t)x->send_displ[r] * G;
        for (int e = 0; host && e < x->send_count[r]; e++)
            cd_item_ghost_io(c, x->send_list[x->send_displ[r] + e], b + (size_t)e * G, 1);
        MPI_Isend(b, x->send_count[r] * G, MPI_DOUBLE, r, CD_MPI_TAG_GHOSTS, x->comm, &x->requests[n++]);
        x->refresh_msgs++;
        x->refresh_bytes += (long long)x->send_count[r] * G * (long long)sizeof(double);
    }
    MPI_Waitall(n, x->requests, MPI_STATUSES_IGNORE);
    if (!host && cd_mpi_dev_unpack(x)) device_failed(x); /* the ghosts' rows written there */
    for (int k = 0; host && k < x->n_neighbors; k++) {
        int r = x->neighbors[k];
        for (int e = 0; e < x->recv_count[r]; e++)
            cd_item_ghost_io(c, x->recv_list[x->recv_displ[r] + e], x->recv_buf + (size_t)(x->recv_displ[r] + e) * G,
                             0);
    }
    x->refreshes++;
    return first;
}

/* Allgatherv of n bytes from every rank: all of them, in rank order, in
 * *all (*alen bytes) on every rank.  0, or -1 (out of memory: aborts the
 * run, the other ranks being in the exchange). */
static int allgather_bytes(cd_mpi_ctx *x, const void *buf, int n, char **all, size_t *alen)
{
    int R = x->size, *cnt = malloc((size_t)R * sizeof(int)), *dsp = malloc((size_t)R * sizeof(int));
    if (!cnt || !dsp) MPI_Abort(x->comm, 1);
    MPI_Allgather(&n, 1, MPI_INT, cnt, 1, MPI_INT, x->comm);
    size_t t = 0;
    for (int r = 0; r < R; r++) {
        dsp[r] = (int)t;
        t += (size_t)cnt[r];
    }
    *all = malloc(t + 1);
    *alen = t;
    if (!*all) MPI_Abort(x->comm, 1);
    MPI_Allgatherv(buf, n, MPI_BYTE, *all, cnt, dsp, MPI_BYTE, x->comm);
    free(cnt);
    free(dsp);
    return 0;
}

/* The serial program's list rebuilt from the rows each primitive
 * has (counts: global primitive, rows; as many as n_counts) and the active
 * rows at their place among them: the same row numbers as the serial list
 * (the same build, at the same step), inactive rows marked so.  The
 * observables sum the pair rows in blocks of row numbers
 * (kernels/observe_items.h), so they get the serial bits. */
static int place_serial_rows(cd_state *g, const long long *counts, size_t n_counts, const rec_ref *r, size_t n)
{
    size_t P = g->n_prims;
    long long *first = calloc(P + 1, sizeof *first);
    if (!first) return -1;
    for (size_t e = 0; e < n_counts; e++) first[counts[2 * e] + 1] = counts[2 * e + 1];
    for (size_t i = 0; i < P; i++) first[i + 1] += first[i];
    size_t rows = (size_t)first[P];
    int rc = cd_state_reserve_pairs(g, rows + 16);
    for (size_t k = 0; !rc && k < rows; k++) {
        g->pair_active[k] = 0;
        g->pair_prim_i[k] = g->pair_prim_j[k] = 0;
    }
    for (size_t k = 0; !rc && k < n; k++) {
        pair_head h;
        memcpy(&h, r[k].at, sizeof h);
        long long row = first[h.gi] + h.rank_in_row;
        if (row >= first[h.gi + 1]) {
            rc = -1;
            break;
        } /* cannot happen: the row is among its primitive's */
        rows_io(g, CD_GROUP_PAIR, (size_t)row, 1, (char *)r[k].at + sizeof h, 0);
        g->pair_prim_i[row] = (cd_int)h.gi;
        g->pair_prim_j[row] = (cd_int)h.gj;
    }
    if (!rc) g->n_pairs = rows;
    free(first);
    return rc;
}

int cd_mpi_gather(cd_mpi_ctx *x, cd_state *global)
{
    cd_state *s = &x->loc.s;
    size_t pb = 0, cb = 0, nc = 0, P = s->n_prims;
    /* the rows of each primitive: contiguous, the list being in key order */
    long long *row0 = malloc((P + 1) * sizeof *row0), *rows = calloc(P + 1, sizeof *rows);
    long long *counts = malloc((2 * P + 1) * sizeof *counts);
    if (!row0 || !rows || !counts) MPI_Abort(x->comm, 1); /* the other ranks are about to wait in the exchange */
    for (size_t k = s->n_pairs; k-- > 0;) {
        row0[s->pair_prim_i[k]] = (long long)k;
        rows[s->pair_prim_i[k]]++;
    }
    for (size_t q = 0; q < s->n_particles; q++) {
        if (!x->owned[q]) continue;
        pb += cd_mpi_particle_bytes(s->prim_count[q], s->n_walls);
        for (cd_int i = s->prim_first[q]; i < s->prim_first[q] + s->prim_count[q]; i++)
            if (rows[i]) {
                counts[2 * nc] = x->gprim[i];
                counts[2 * nc + 1] = rows[i];
                nc++;
            }
    }
    for (size_t k = 0; k < s->n_pairs; k++) /* each row once: by the owner of its particle i */
        if (s->pair_active[k] && x->owned[s->prim_particle[s->pair_prim_i[k]]]) cb += cd_mpi_pair_bytes();
    char *pbuf = malloc(pb + 1), *cbuf = malloc(cb + 1), *pall = NULL, *call = NULL, *nall = NULL;
    if (!pbuf || !cbuf) MPI_Abort(x->comm, 1);
    char *at = pbuf;
    for (size_t q = 0; q < s->n_particles; q++)
        if (x->owned[q]) at = cd_mpi_pack_particle(s, q, x->gid[q], x->gprim[s->prim_first[q]], at);
    at = cbuf;
    for (size_t k = 0; k < s->n_pairs; k++) {
        cd_int i = s->pair_prim_i[k];
        if (s->pair_active[k] && x->owned[s->prim_particle[i]])
            at = cd_mpi_pack_pair(s, k, x->gprim[i], x->gprim[s->pair_prim_j[k]], (long long)k - row0[i], at);
    }
    size_t plen, clen, nlen;
    int rc = allgather_bytes(x, pbuf, (int)pb, &pall, &plen);
    rc |= allgather_bytes(x, cbuf, (int)cb, &call, &clen);
    rc |= allgather_bytes(x, counts, (int)(2 * nc * sizeof *counts), &nall, &nlen);
    /* (the scalars not: the global ones lead between steps, where a protocol sets walls and slots) */
    if (!rc) {
        size_t N, K;
        rec_ref *pr = parse(pall, plen, 0, s->n_walls, &N), *cr = parse(call, clen, 1, s->n_walls, &K);
        rc = pr && cr ? 0 : -1;
        for (size_t q = 0; !rc && q < N; q++) {
            rec_head h;
            memcpy(&h, pr[q].at, sizeof h);
            unpack_particle(global, (size_t)h.gid, (size_t)h.gprim_first, pr[q].at);
        }
        if (!rc) rc = place_serial_rows(global, (const long long *)nall, nlen / (2 * sizeof(long long)), cr, K);
        if (!rc) rc = cd_state_arms_derive(global); /* its arms of these rows (kernels/cols.h) */
        free(pr);
        free(cr);
    }
    free(row0);
    free(rows);
    free(counts);
    free(pbuf);
    free(cbuf);
    free(pall);
    free(call);
    free(nall);
    return rc;
}

void cd_mpi_halo_free(cd_mpi_ctx *x)
{
    cd_mpi_dev_free(x);
    free(x->gid);
    free(x->gprim);
    free(x->owned);
    free(x->send_count);
    free(x->send_displ);
    free(x->recv_count);
    free(x->recv_displ);
    free(x->send_list);
    free(x->recv_list);
    free(x->send_buf);
    free(x->recv_buf);
    free(x->neighbors);
    free(x->requests);
    x->neighbors = NULL;
    x->requests = NULL;
    x->n_neighbors = 0;
    x->gid = x->gprim = NULL;
    x->owned = NULL;
    x->send_count = x->send_displ = x->recv_count = x->recv_displ = x->send_list = x->recv_list = NULL;
    x->send_buf = x->recv_buf = NULL;
}
