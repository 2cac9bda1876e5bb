/* The fixed-seed generator (splitmix64) of the narrow-phase tests
 * (test_segseg.c, test_narrow_paths.c): set rng_state for a sequence. */
#ifndef CD_TEST_SEGSEG_RNG_H
#define CD_TEST_SEGSEG_RNG_H
#include <stdint.h>
#include "vec3.h"

static uint64_t rng_state = 0x5eed5e95e95e9ULL;
static inline uint64_t rng_next(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}
/* uniform in [0, 1) */
static inline double rng_u(void) { return (double)(rng_next() >> 11) * (1.0 / 9007199254740992.0); }
static inline double rng_sym(void) { return 2.0 * rng_u() - 1.0; }
static inline cd_vec3 rng_vec(double scale) { return cd_v3(scale * rng_sym(), scale * rng_sym(), scale * rng_sym()); }

#endif
