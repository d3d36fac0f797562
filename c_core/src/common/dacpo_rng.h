/* SPDX-License-Identifier: BSD-3-Clause */
/* Small deterministic RNG: xoshiro256** seeded by splitmix64 (public-domain
 * algorithms by Blackman and Vigna). Header-only so that the core and the
 * scene generator of wrappers/support draw the same streams from one copy.
 * Each (seed, stream) pair gives an independent sequence: the core uses the
 * block id as stream, so results do not depend on threads. Nothing here is
 * installed. */
#ifndef DACPO_RNG_H
#define DACPO_RNG_H

#include <stddef.h>
#include <stdint.h>

typedef struct dacpo_rng {
  uint64_t s[4];
} dacpo_rng;

static inline uint64_t
dacpo_splitmix64(uint64_t* x)
{
  uint64_t z = (*x += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

static inline void
dacpo_rng_seed(dacpo_rng* rng, uint64_t seed, uint64_t stream)
{
  uint64_t x = seed ^ (stream * 0xD1B54A32D192ED03ull);
  for (int i = 0; i < 4; ++i)
    rng->s[i] = dacpo_splitmix64(&x);
}

static inline uint64_t
dacpo_rotl64(uint64_t x, int k)
{
  return (x << k) | (x >> (64 - k));
}

static inline uint64_t
dacpo_rng_next(dacpo_rng* rng)
{
  uint64_t* s = rng->s;
  const uint64_t result = dacpo_rotl64(s[1] * 5, 7) * 9;
  const uint64_t t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = dacpo_rotl64(s[3], 45);
  return result;
}

/* Uniform in [0, 1), 53 random bits. */
static inline double
dacpo_rng_uniform(dacpo_rng* rng)
{
  return (double)(dacpo_rng_next(rng) >> 11) * (1.0 / 9007199254740992.0);
}

/* Uniform integer in [0, n), n > 0. u * n can round up to n, which gives 0
 * (the value (u * n) % n gives, without a division: stage 2's shuffles draw
 * about one number per neighbour per point and order). */
static inline size_t
dacpo_rng_below(dacpo_rng* rng, size_t n)
{
  const size_t r = (size_t)(dacpo_rng_uniform(rng) * (double)n);
  return r < n ? r : 0;
}

#endif /* DACPO_RNG_H */
