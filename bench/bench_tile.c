/* --tile KX,KZ of capdem-bench: a large settled packing built from copies
 * of a smaller one, side by side in a box KX times as wide and KZ times as
 * deep (same height).  Each copy keeps its particles' sizes, poses and
 * velocities; contact history is dropped (the list is rebuilt) and the
 * particles that touched the inner walls now touch those of the next copy.
 * The caller relaxes the result (--relax-steps) before timing.  It gives a
 * 1e5-particle packing for the price of a 1e4 settle and a relaxation,
 * instead of settling a column ten times as tall. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "core/sim.h"
#include "core/rng.h"
#include "bench_tile.h"

int cd_bench_tile_config(const char *text, int kx, int kz, char *out, size_t len)
{
    /* every species' "count: N" (they come before the domain line) times
     * kx kz, and the box kx times as wide and kz times as deep */
    const char *d = strstr(text, "domain: {type: box, width: ");
    double w, t, h;
    if (!d || sscanf(d, "domain: {type: box, width: %lf, thickness: %lf, height: %lf}", &w, &t, &h) != 3) return -1;
    const char *d_end = strchr(d, '\n');
    if (!d_end) return -1;
    size_t used = 0;
    int counts = 0;
    const char *at = text;
    for (const char *c; (c = strstr(at, "count: ")) && c < d; at = c + strcspn(c, ",}")) {
        long n;
        if (sscanf(c, "count: %ld", &n) != 1) return -1;
        int k = snprintf(out + used, len - used, "%.*scount: %ld", (int)(c - at), at, n * kx * kz);
        if (k < 0 || (size_t)k >= len - used) return -1;
        used += (size_t)k;
        counts++;
    }
    if (!counts) return -1;
    int k = snprintf(out + used, len - used, "%.*sdomain: {type: box, width: %.9g, thickness: %.9g, height: %.9g}%s",
                     (int)(d - at), at, w * kx, t * kz, h, d_end);
    return k < 0 || (size_t)k >= len - used ? -1 : 0;
}

int cd_bench_tile_state(cd_state *dst, const cd_state *src, int kx, int kz, double width, double thickness)
{
    size_t N = src->n_particles, P = src->n_prims;
    if (dst->n_particles != N * (size_t)(kx * kz) || dst->n_prims != P * (size_t)(kx * kz)) return -1;
    for (int iz = 0; iz < kz; iz++)
        for (int ix = 0; ix < kx; ix++) {
            size_t t = (size_t)(iz * kx + ix);
            cd_vec3 off = cd_v3(ix * width, 0, iz * thickness);
            for (size_t f = 0; f < cd_n_fields; f++) {
                enum cd_field_group g = cd_fields[f].group;
                if (g != CD_GROUP_PARTICLE && g != CD_GROUP_PRIM) continue;
                size_t rows = g == CD_GROUP_PARTICLE ? N : P, es = cd_fields[f].elem_size;
                char *to = *(char **)cd_field_ptr(dst, &cd_fields[f]);
                const char *from = *(char *const *)cd_field_ptr((cd_state *)src, &cd_fields[f]);
                memcpy(to + t * rows * es, from, rows * es);
            }
            for (size_t p = t * N; p < (t + 1) * N; p++) {
                dst->position[p] = cd_v3_add(dst->position[p], off);
                dst->prim_first[p] += (cd_int)(t * P);
            }
            for (size_t q = t * P; q < (t + 1) * P; q++) {
                dst->prim_particle[q] += (cd_int)(t * N);
                dst->prim_a[q] = cd_v3_add(dst->prim_a[q], off);
                dst->prim_b[q] = cd_v3_add(dst->prim_b[q], off);
                dst->prim_a_ref[q] = cd_v3_add(dst->prim_a_ref[q], off);
                dst->prim_b_ref[q] = cd_v3_add(dst->prim_b_ref[q], off);
            }
        }
    dst->n_pairs = 0;
    /* the arms anew from the copied columns, as a reader does: a start
     * first writes the state's arms back over them (omp_stop), and dst's
     * are those of its own deposit, whose copies 1.. had other sizes */
    return cd_state_arms_derive(dst);
}

/* Rows of the columns of group g moved by map (new row r = old row
 * map[r]), groups of `per` rows from first[map[r]] (primitives), or one
 * row each (first null). */
static int move_group(cd_state *s, enum cd_field_group g, const cd_int *map, size_t rows, const cd_int *first,
                      const cd_int *count)
{
    for (size_t f = 0; f < cd_n_fields; f++) {
        if (cd_fields[f].group != g) continue;
        size_t es = cd_fields[f].elem_size;
        char *col = *(char **)cd_field_ptr(s, &cd_fields[f]), *tmp = malloc(rows * es + 1), *to = tmp;
        if (!tmp) return -1;
        for (size_t r = 0; r < (first ? s->n_particles : rows); r++) {
            size_t n = first ? (size_t)count[map[r]] : 1, from = first ? (size_t)first[map[r]] : (size_t)map[r];
            memcpy(to, col + from * es, n * es);
            to += n * es;
        }
        memcpy(col, tmp, rows * es);
        free(tmp);
    }
    return 0;
}

int cd_bench_shuffle_state(cd_state *s, unsigned seed)
{
    size_t N = s->n_particles;
    cd_int *map = malloc((N + 1) * sizeof(cd_int)), *first = malloc((N + 1) * sizeof(cd_int)),
           *count = malloc((N + 1) * sizeof(cd_int));
    int rc = map && first && count ? 0 : -1;
    if (!rc) {
        cd_rng r;
        cd_rng_seed(&r, seed);
        for (size_t q = 0; q < N; q++) map[q] = (cd_int)q;
        for (size_t q = N; q > 1; q--) { /* Fisher-Yates */
            size_t k = (size_t)(cd_rng_next(&r) % q);
            cd_int t = map[q - 1];
            map[q - 1] = map[k];
            map[k] = t;
        }
        memcpy(first, s->prim_first, N * sizeof(cd_int));
        memcpy(count, s->prim_count, N * sizeof(cd_int));
        rc = move_group(s, CD_GROUP_PRIM, map, s->n_prims, first, count) ||
             move_group(s, CD_GROUP_PARTICLE, map, N, NULL, NULL);
    }
    if (!rc) {
        cd_int at = 0;
        for (size_t q = 0; q < N; q++) {
            s->prim_first[q] = at;
            for (cd_int t = 0; t < s->prim_count[q]; t++) s->prim_particle[at + t] = (cd_int)q;
            at += s->prim_count[q];
        }
        s->n_pairs = 0;
        for (size_t f = 0; f < cd_n_fields; f++)
            if (cd_fields[f].group == CD_GROUP_WALLC)
                memset(*cd_field_ptr(s, &cd_fields[f]), 0, s->n_prims * s->n_walls * cd_fields[f].elem_size);
        rc = cd_state_arms_derive(s); /* the arms with their primitives (see cd_bench_tile_state) */
    }
    free(map);
    free(first);
    free(count);
    return rc;
}
