/* rng.h - one small deterministic generator (splitmix64) for sampled states: same seed, same samples. */
#ifndef MECHC_RNG_H
#define MECHC_RNG_H

#include <stdint.h>

/* splitmix64 (Steele, Lea and Flood 2014): any seed, including 0, works. */
static inline uint64_t rng_next(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1). */
static inline double rng_unit(uint64_t *state)
{
    return (double)(rng_next(state) >> 11) * 0x1.0p-53;
}

/* Uniform in [-1, 1). */
static inline double rng_symmetric(uint64_t *state)
{
    return 2.0 * rng_unit(state) - 1.0;
}

#endif
