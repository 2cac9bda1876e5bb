/* --tile KX,KZ of capdem-bench: a large settled packing built from copies
 * of a smaller one, side by side in a box KX times as wide and KZ times as
 * deep (same height).  Each copy keeps its particles' sizes, poses and
 * velocities; contact history is dropped (the list is rebuilt) and the
 * particles that touched the inner walls now touch those of the next copy.
 * The caller relaxes the result (--relax-steps) before timing.  It gives a
 * 1e5-particle packing for the price of a 1e4 settle and a relaxation,
 * instead of settling a column ten times as tall. */
#include <stdio.h>
#include <string.h>
#include "sim.h"
#include "bench_tile.h"

int cd_bench_tile_config(const char *text, int kx, int kz, char *out, size_t len)
{
    const char *c = strstr(text, "count: "), *d = strstr(text, "domain: {type: box, width: ");
    long n;
    double w, t, h;
    if (!c || !d || sscanf(c, "count: %ld", &n) != 1 ||
        sscanf(d, "domain: {type: box, width: %lf, thickness: %lf, height: %lf}", &w, &t, &h) != 3)
        return -1;
    const char *d_end = strchr(d, '\n');
    const char *c_end = c + strcspn(c, ",}");
    if (!d_end || c > d) return -1; /* the particles line comes before the domain line */
    int k = snprintf(out, len, "%.*scount: %ld%.*sdomain: {type: box, width: %.9g, thickness: %.9g, height: %.9g}%s",
                     (int)(c - text), text, n * kx * kz, (int)(d - c_end), c_end, w * kx, t * kz, h, d_end);
    return k < 0 || (size_t)k >= len ? -1 : 0;
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
    return 0;
}
