/* --tile of capdem-bench: see bench_tile.c. */
#ifndef CD_BENCH_TILE_H
#define CD_BENCH_TILE_H
#include <stddef.h>
#include "core/state.h"

/* The config text of a capdem-bench case with count x kx kz particles in a
 * box kx times as wide (x) and kz times as deep (z).  Returns 0, or -1 if
 * text is not a capdem-bench case or out is too small. */
int cd_bench_tile_config(const char *text, int kx, int kz, char *out, size_t len);

/* Fills the particle and primitive columns of dst (set up from the tiled
 * config) with kx x kz copies of src, shifted by multiples of the small
 * box's width and thickness, and derives their arms (cd_state_arms_derive).
 * Returns 0, or -1 if the counts do not match or memory runs out. */
int cd_bench_tile_state(cd_state *dst, const cd_state *src, int kx, int kz, double width, double thickness);

/* --shuffle SEED: the particles of s in a random order (a permutation of
 * seed), their primitives with them; contact history is dropped (pair
 * rows and wall rows), as by tiling, so the caller relaxes the result.
 * The memory order of a packing made by random placement, or mixed by a
 * flow, instead of the lattice order of a deposit.  0, or -1 out of memory. */
int cd_bench_shuffle_state(cd_state *s, unsigned seed);

#endif
