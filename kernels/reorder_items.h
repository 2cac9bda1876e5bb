/* Memory order against user order (docs/architecture.md, "Memory order").
 * At a neighbour-list rebuild the particles, their primitives and their
 * wall rows may be put in the order of the grid cells of their centres,
 * so that particles near in space are near in memory.  The user never sees that order: ids, the run file,
 * protocols and analysis keep the user's particle order, and every
 * floating-point sum of the step runs in an order defined by user ids
 * (pair orientation, gather order, observables, wall loads), so a run has
 * the same bits whatever the memory order.
 *
 * cd_order holds the maps; a null map is the identity (no reordering: the
 * OpenCL backend, or a run with neighbor.reorder: none).  The items below
 * are the passes of the reorder (src/backend/omp/reorder.c), run where the steps run.
 * Device-safe: C11 and OpenCL C 1.2. */
#ifndef CD_REORDER_ITEMS_H
#define CD_REORDER_ITEMS_H
#include "cols.h"
#include "broadphase.h"

/* Memory slot <-> user id of particles, primitives and pair rows. */
typedef struct {
    const CD_GLOBAL cd_int *part_uid; /* memory slot of a particle -> its user id */
    const CD_GLOBAL cd_int *prim_uid; /* memory slot of a primitive -> its user id */
    const CD_GLOBAL cd_int *part_at;  /* user id of a particle -> its memory slot */
    const CD_GLOBAL cd_int *prim_at;  /* user id of a primitive -> its memory slot */
    const CD_GLOBAL cd_int *pair_at;  /* pair row in user order (by user key) -> memory row */
} cd_order;

CD_DEVICE_BEGIN

/* The identity order (all maps null). */
CD_INLINE cd_order cd_order_identity(void)
{
    cd_order o;
    o.part_uid = o.prim_uid = o.part_at = o.prim_at = o.pair_at = 0;
    return o;
}

/* map[x], or x for the identity (null map). */
CD_INLINE cd_long cd_map(const CD_GLOBAL cd_int *map, cd_long x) { return map ? (cd_long)map[x] : x; }

/* Key of particle q: the index of the grid cell of its centre (x fastest,
 * then y, then z: cd_grid_cell_of), its memory slot the value to sort.
 * The cells' own order, not a Morton or Hilbert curve: it keeps a
 * particle's neighbours at a few fixed strides in memory (the next cell,
 * row and layer), which the CPU's prefetchers follow; Morton's jumps made
 * the step 0.67x as fast on a 1e5 bed (docs/performance.md). */
CD_INLINE void cd_reorder_item_key(cd_cols c, cd_particle_id q, const CD_GLOBAL cd_grid *grid, CD_GLOBAL cd_ulong *keys,
                                   CD_GLOBAL cd_int *vals)
{
    cd_grid g = grid[0];
    keys[q] = (cd_ulong)cd_grid_cell_of(&g, c.position[q]);
    vals[q] = q;
}

/* Stable radix sort of (key, value), CD_RADIX_BITS bits a pass, in chunks
 * of CD_SORT_CHUNK keys: pass `shift` counts the digits of chunk g into
 * hist[digit n_chunks + g]; a prefix sum over hist (cd_scan_item_*) gives
 * every (digit, chunk) its first place; each chunk then writes its items
 * in order.  Small chunks and 16 bins keep a GPU busy (one item per 64
 * keys, a histogram of n / 4 entries; 1,024-key chunks and 256 bins gave
 * it a few hundred long serial loops) at the price of twice the passes.
 * Integer work only, the result independent of the chunking and of the
 * digit width: ties keep their memory order, so the permutation is the
 * same on every run and backend. */
#define CD_RADIX_BITS 4
#define CD_RADIX_BINS (1 << CD_RADIX_BITS)
#define CD_RADIX_MASK (CD_RADIX_BINS - 1)
#define CD_SORT_CHUNK 64

/* Entries of the histogram of a pass over n keys. */
CD_INLINE cd_long cd_reorder_hist_entries(cd_long n)
{
    return (cd_long)CD_RADIX_BINS * ((n + CD_SORT_CHUNK - 1) / CD_SORT_CHUNK);
}

CD_INLINE void cd_reorder_item_hist(const CD_GLOBAL cd_ulong *keys, cd_int n, cd_int n_chunks, cd_int g, int shift,
                                    CD_GLOBAL cd_int *hist)
{
    cd_int count[CD_RADIX_BINS];
    for (cd_int d = 0; d < CD_RADIX_BINS; d++) count[d] = 0;
    cd_int end = (g + 1) * CD_SORT_CHUNK < n ? (g + 1) * CD_SORT_CHUNK : n;
    for (cd_int k = g * CD_SORT_CHUNK; k < end; k++) count[(cd_int)((keys[k] >> shift) & CD_RADIX_MASK)]++;
    for (cd_int d = 0; d < CD_RADIX_BINS; d++) hist[d * n_chunks + g] = count[d];
}

CD_INLINE void cd_reorder_item_scatter(const CD_GLOBAL cd_ulong *keys, const CD_GLOBAL cd_int *vals, cd_int n,
                                       cd_int n_chunks, cd_int g, int shift, const CD_GLOBAL cd_int *first,
                                       CD_GLOBAL cd_ulong *keys_out, CD_GLOBAL cd_int *vals_out)
{
    cd_int at[CD_RADIX_BINS];
    for (cd_int d = 0; d < CD_RADIX_BINS; d++) at[d] = first[d * n_chunks + g];
    cd_int end = (g + 1) * CD_SORT_CHUNK < n ? (g + 1) * CD_SORT_CHUNK : n;
    for (cd_int k = g * CD_SORT_CHUNK; k < end; k++) {
        cd_int to = at[(cd_int)((keys[k] >> shift) & CD_RADIX_MASK)]++;
        keys_out[to] = keys[k];
        vals_out[to] = vals[k];
    }
}

/* Group g of n 4-byte words (a row, or the n_walls wall rows of one
 * primitive) moved by a map of groups: gather, dst group g = src group
 * map[g], or scatter, dst group map[g] = src group g; groups start every
 * dst_stride and src_stride words (n for a column moved whole, more for
 * one wall's rows of the wall-row columns). */
CD_INLINE void cd_reorder_item_move(CD_GLOBAL cd_int *restrict dst, cd_long dst_stride,
                                    const CD_GLOBAL cd_int *restrict src, cd_long src_stride,
                                    const CD_GLOBAL cd_int *map, cd_long g, cd_long n, int scatter)
{
    cd_long to = (scatter ? (cd_long)map[g] : g) * dst_stride, from = (scatter ? g : (cd_long)map[g]) * src_stride;
    for (cd_long w = 0; w < n; w++) dst[to + w] = src[from + w];
}

/* Is the key of particle slot m (> 0) below its predecessor's?  Counted
 * over the particles, the descents say how far the memory order has
 * drifted from the cells' order since the last reorder. */
CD_INLINE int cd_reorder_item_descent(const CD_GLOBAL cd_ulong *keys, cd_particle_id m)
{
    return keys[m] < keys[m - 1];
}

/* How far apart in memory pair row k's two particles are: the difference
 * of their slots (slot_of: the slot each particle would have, null for the
 * present one).  Its largest over the rows is the host threads' sweep's
 * span (src/backend/omp/sweep.c). */
CD_INLINE cd_ulong cd_reorder_item_row_distance(cd_cols c, cd_long k, const CD_GLOBAL cd_int *slot_of)
{
    cd_long a = cd_map(slot_of, c.prim_particle[c.pair_prim_i[k]]);
    cd_long b = cd_map(slot_of, c.prim_particle[c.pair_prim_j[k]]);
    return (cd_ulong)(a > b ? a - b : b - a);
}

/* The same as the bit length of the difference.  Summed over the rows, it
 * compares two orders by what the step reads: a row's two particles. */
CD_INLINE cd_int cd_reorder_item_row_span(cd_cols c, cd_long k, const CD_GLOBAL cd_int *slot_of)
{
    cd_ulong d = cd_reorder_item_row_distance(c, k, slot_of);
    cd_int bits = 0;
    while (d) {
        bits++;
        d >>= 1;
    }
    return bits;
}

/* After particle slot m took the particle of old slot src[m]: the old
 * primitive of each of its new primitives, from the new first primitives
 * new_first (a prefix sum of the counts in the new order), the old
 * prim_first read before the columns moved. */
CD_INLINE void cd_reorder_item_prim_src(cd_particle_id m, const CD_GLOBAL cd_int *src,
                                        const CD_GLOBAL cd_int *new_first, const CD_GLOBAL cd_int *old_first,
                                        CD_GLOBAL cd_int *prim_src)
{
    cd_int from = old_first[src[m]], n = new_first[m + 1] - new_first[m];
    for (cd_int t = 0; t < n; t++) prim_src[new_first[m] + t] = from + t;
}

/* Particle m's primitive indices after the columns moved. */
CD_INLINE void cd_reorder_item_owner(cd_cols c, cd_particle_id m, const CD_GLOBAL cd_int *new_first)
{
    c.prim_first[m] = new_first[m];
    for (cd_int i = new_first[m]; i < new_first[m + 1]; i++) c.prim_particle[i] = m;
}

/* The pair rows of user primitive u in user order (rows of its memory
 * primitive, which the build sorts by the user id of j): their number, then,
 * from their first place ustart[u], the memory rows, so that pair_at lists
 * the memory rows by ascending user key. */
CD_INLINE cd_int cd_reorder_item_pair_count(const CD_GLOBAL cd_int *prim_at, const CD_GLOBAL cd_int *pair_offset,
                                            cd_prim_id u)
{
    cd_int i = prim_at[u];
    return pair_offset[i + 1] - pair_offset[i];
}

CD_INLINE void cd_reorder_item_pair_at(const CD_GLOBAL cd_int *prim_at, const CD_GLOBAL cd_int *pair_offset,
                                       const CD_GLOBAL cd_int *ustart, cd_prim_id u, CD_GLOBAL cd_int *pair_at)
{
    cd_int i = prim_at[u], n = pair_offset[i + 1] - pair_offset[i];
    for (cd_int t = 0; t < n; t++) pair_at[ustart[u] + t] = pair_offset[i] + t;
}

CD_DEVICE_END
#endif
