/* Deterministic pseudo-random numbers (xoshiro256** seeded by splitmix64):
 * the same seed gives the same packing on every machine. */
#ifndef CD_RNG_H
#define CD_RNG_H
#include <stdint.h>

typedef struct {
    uint64_t s[4];
} cd_rng;

static inline uint64_t cd_splitmix64(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

static inline void cd_rng_seed(cd_rng *r, uint64_t seed)
{
    for (int k = 0; k < 4; k++) r->s[k] = cd_splitmix64(&seed);
}

static inline uint64_t cd_rng_next(cd_rng *r)
{
    uint64_t *s = r->s;
    uint64_t x = s[1] * 5;
    uint64_t out = ((x << 7) | (x >> 57)) * 9;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = (s[3] << 45) | (s[3] >> 19);
    return out;
}

/* Uniform in [0, 1) with 53 random bits. */
static inline double cd_rng_uniform(cd_rng *r) { return (double)(cd_rng_next(r) >> 11) * 0x1.0p-53; }

/* Uniform in (a, b). */
static inline double cd_rng_range(cd_rng *r, double a, double b) { return a + (b - a) * cd_rng_uniform(r); }

#endif
