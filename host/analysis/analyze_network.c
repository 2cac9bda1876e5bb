/* Bonds and connectivity (Tran et al. 2024, section 3.3).  A bond is a pair of
 * particles with at least one contact; its valence k is its number of
 * contacts.  Over the N_p* particles with at least one particle contact
 * (rattlers excluded; wall contacts are not neighbours):
 *   Z_c = 2 N_c / N_p*   contacts per particle      (Tran et al. 2024, eq. 9)
 *   Z   = 2 N_b / N_p*   contact neighbours per particle
 *   valence = Z_c / Z = N_c / N_b = sum_k k P_k
 *   P_c  fraction of those particles with exactly c contacts (Z_c = sum c P_c)
 *   P_b  fraction with exactly b contact neighbours          (Z = sum b P_b)
 *   P_k  fraction of bonds with exactly k contacts. */
#include "analysis/analyze.h"
#include "contact_law.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cd_an_bonds_free(cd_an_bonds *b)
{
    free(b->i);
    free(b->j);
    free(b->k);
    free(b->force);
    free(b->first);
    free(b->order);
    memset(b, 0, sizeof(*b));
}

/* Contacts are bucketed by their lower particle with a counting sort, then
 * each (short) bucket is sorted by the other particle; equal runs are the
 * bonds.  O(contacts) overall, no global sort. */
int cd_an_bonds_build(const cd_an_snapshot *s, cd_an_bonds *b, char *err, size_t errlen)
{
    memset(b, 0, sizeof(*b));
    size_t N = s->n, C = s->nc;
    for (size_t c = 0; c < C; c++) {
        int32_t i = s->ci[c], j = s->cj[c];
        if (i < 0 || j < 0 || (size_t)i >= N || (size_t)j >= N || i == j) {
            snprintf(err, errlen, "%s: contact row %zu of snapshot %d joins particles %d and %d (N = %zu)", s->path, c,
                     s->snapshot, (int)i, (int)j, N);
            return 2;
        }
    }
    size_t *start = calloc(N + 1, sizeof(size_t));
    int32_t *other = malloc((C ? C : 1) * sizeof(int32_t));
    b->order = malloc((C ? C : 1) * sizeof(size_t));
    if (!start || !other || !b->order) goto oom;
    for (size_t c = 0; c < C; c++) {
        int32_t lo = s->ci[c] < s->cj[c] ? s->ci[c] : s->cj[c];
        start[lo + 1]++;
    }
    for (size_t p = 0; p < N; p++) start[p + 1] += start[p];
    {
        size_t *fill = malloc((N ? N : 1) * sizeof(size_t));
        if (!fill) goto oom;
        memcpy(fill, start, N * sizeof(size_t));
        for (size_t c = 0; c < C; c++) {
            int32_t lo = s->ci[c] < s->cj[c] ? s->ci[c] : s->cj[c];
            b->order[fill[lo]++] = c;
        }
        free(fill);
    }
    /* Sort every bucket by the other particle (insertion sort: buckets
     * hold a particle's contacts, a few tens at most), count the runs. */
    size_t nb = 0;
    for (size_t p = 0; p < N; p++) {
        size_t s0 = start[p], s1 = start[p + 1];
        for (size_t a = s0; a < s1; a++) {
            size_t c = b->order[a];
            other[a] = s->ci[c] == (int32_t)p ? s->cj[c] : s->ci[c];
        }
        for (size_t a = s0 + 1; a < s1; a++) {
            size_t c = b->order[a];
            int32_t o = other[a];
            size_t q = a;
            while (q > s0 && other[q - 1] > o) {
                other[q] = other[q - 1];
                b->order[q] = b->order[q - 1];
                q--;
            }
            other[q] = o;
            b->order[q] = c;
        }
        for (size_t a = s0; a < s1; a++) nb += a == s0 || other[a] != other[a - 1];
    }
    b->n = nb;
    b->i = malloc((nb ? nb : 1) * sizeof(int32_t));
    b->j = malloc((nb ? nb : 1) * sizeof(int32_t));
    b->k = malloc((nb ? nb : 1) * sizeof(int32_t));
    b->force = calloc(nb ? nb : 1, sizeof(cd_vec3));
    b->first = malloc((nb ? nb : 1) * sizeof(size_t));
    if (!b->i || !b->j || !b->k || !b->force || !b->first) goto oom;
    size_t q = 0;
    for (size_t p = 0; p < N; p++)
        for (size_t a = start[p]; a < start[p + 1]; a++) {
            if (a == start[p] || other[a] != other[a - 1]) {
                b->i[q] = (int32_t)p;
                b->j[q] = other[a];
                b->k[q] = 0;
                b->first[q] = a;
                q++;
            }
            size_t c = b->order[a];
            /* force of the contact on cj is F_n n + F_t (fields.def);
             * the bond force is the force on its higher particle j */
            cd_vec3 F = cd_contact_force_on_j(s->fn[c], s->normal[c], s->ft[c]); /* [N] */
            double sign = s->cj[c] == b->j[q - 1] ? 1 : -1;
            b->force[q - 1] = cd_v3_axpy(b->force[q - 1], sign, F);
            b->k[q - 1]++;
        }
    free(start);
    free(other);
    return 0;
oom:
    free(start);
    free(other);
    cd_an_bonds_free(b);
    snprintf(err, errlen, "%s: out of memory grouping %zu contacts into bonds", s->path, C);
    return 1;
}

int cd_an_network(const cd_an_input *in, cd_an_report *r, char *err, size_t errlen)
{
    const cd_an_snapshot *s = in->s;
    const cd_an_bonds *b = in->b;
    if (s->nc == 0) {
        snprintf(err, errlen, "%s: snapshot %d (step %lld) has no contacts: no contact network", s->path, s->snapshot,
                 s->step);
        return 2;
    }
    int32_t *nc = calloc(s->n ? s->n : 1, sizeof(int32_t)), *nb = calloc(s->n ? s->n : 1, sizeof(int32_t));
    if (!nc || !nb) {
        free(nc);
        free(nb);
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    int kmax = 0;
    for (size_t q = 0; q < b->n; q++) {
        nc[b->i[q]] += b->k[q];
        nc[b->j[q]] += b->k[q];
        nb[b->i[q]]++;
        nb[b->j[q]]++;
        if (b->k[q] > kmax) kmax = b->k[q];
    }
    size_t np = 0;
    int cmax = 0, bmax = 0;
    for (size_t p = 0; p < s->n; p++)
        if (nc[p] > 0) {
            np++;
            if (nc[p] > cmax) cmax = nc[p];
            if (nb[p] > bmax) bmax = nb[p];
        }
    cd_an_group *g = cd_an_group_get(r, "network");
    double Np = (double)np, Nc = (double)s->nc, Nb = (double)b->n;
    cd_an_put(g, "n_particles", (double)s->n, "1");
    cd_an_put(g, "n_particles_in_contact", Np, "1");
    cd_an_put(g, "n_rattlers", (double)(s->n - np), "1");
    cd_an_put(g, "n_contacts", Nc, "1");
    cd_an_put(g, "n_bonds", Nb, "1");
    cd_an_put(g, "n_wall_contacts", (double)s->nw, "1");
    cd_an_put(g, "Z", 2 * Nb / Np, "1");
    cd_an_put(g, "Z_c", 2 * Nc / Np, "1");
    cd_an_put(g, "valence", Nc / Nb, "1");
    /* Isostatic value for frictionless rigid particles with all 6 (3 in
     * 2D) degrees of freedom and the rigid-body soft modes of a free
     * aggregate (Tran et al. 2024, eq. 11): 12 - 12/N_p* in 3D. */
    double dof = in->g->dim == 2 ? 3 : 6;
    cd_an_put(g, "Z_c_isostatic", 2 * dof - 2 * dof / Np, "1");

    double *pc = cd_an_put_curve(g, "contacts_per_particle", (size_t)cmax, "c,P_c", "1,1");
    double *pb = cd_an_put_curve(g, "neighbours_per_particle", (size_t)bmax, "b,P_b", "1,1");
    double *pk = cd_an_put_curve(g, "valence", (size_t)kmax, "k,P_k,F_k,n_bonds", "1,1,1,1");
    if (!pc || !pb || !pk) {
        free(nc);
        free(nb);
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    for (int c = 0; c < cmax; c++) pc[2 * c] = c + 1;
    for (int c = 0; c < bmax; c++) pb[2 * c] = c + 1;
    for (size_t p = 0; p < s->n; p++)
        if (nc[p] > 0) {
            pc[2 * (nc[p] - 1) + 1] += 1 / Np;
            pb[2 * (nb[p] - 1) + 1] += 1 / Np;
        }
    /* F_k: mean magnitude of the bond force of valence-k bonds over the
     * mean normal contact force (Tran et al. 2024, Fig. 15). */
    for (int k = 0; k < kmax; k++) pk[4 * k] = k + 1;
    for (size_t q = 0; q < b->n; q++) {
        double *row = pk + 4 * (b->k[q] - 1);
        row[2] += cd_v3_norm(b->force[q]);
        row[3] += 1;
    }
    for (int k = 0; k < kmax; k++) {
        double *row = pk + 4 * k;
        row[1] = row[3] / Nb;
        row[2] = row[3] > 0 && in->mean_fn > 0 ? row[2] / row[3] / in->mean_fn : 0;
    }
    free(nc);
    free(nb);
    return 0;
}
