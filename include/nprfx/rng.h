/* nprfx — counter-based random numbers.
 *
 * Every random number is a pure hash of (seed, frame, x, y, channel, stream): no generator state is
 * shared between pixels, so results do not depend on thread count, tile split or render order, and
 * any frame can be rendered on any farm machine. The mixer is the SplitMix64 finaliser. */
#ifndef NPRFX_RNG_H
#define NPRFX_RNG_H

#include <math.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

static inline uint64_t nprfx_mix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* FNV-1a over bytes, from NPRFX_FNV_INIT: the fingerprints caches compare (what a measured range
 * or a kept frame was made from), never a random number. */
#define NPRFX_FNV_INIT 0xcbf29ce484222325ull
static inline uint64_t nprfx_fnv1a(uint64_t h, const void *data, size_t n)
{
    const unsigned char *b = (const unsigned char *)data;
    for (size_t i = 0; i < n; i++) {
        h ^= b[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

/* Hash of the full counter. Each field is folded in through its own mixing round, so
 * neighbouring counters give unrelated outputs. */
static inline uint64_t nprfx_hash(uint64_t seed, int64_t frame, int32_t x, int32_t y,
                                  uint32_t channel, uint32_t stream)
{
    uint64_t h = nprfx_mix64(seed ^ 0x6a09e667f3bcc908ull);
    h = nprfx_mix64(h ^ (uint64_t)frame);
    h = nprfx_mix64(h ^ (((uint64_t)(uint32_t)x << 32) | (uint64_t)(uint32_t)y));
    h = nprfx_mix64(h ^ (((uint64_t)channel << 32) | (uint64_t)stream));
    return h;
}

/* Uniform in [0, 1) with 53 random bits. */
static inline double nprfx_u01(uint64_t h)
{
    return (double)(h >> 11) * (1.0 / 9007199254740992.0);
}

/* Uniform in [0, 1) from the counter. */
static inline double nprfx_rand_u01(uint64_t seed, int64_t frame, int32_t x, int32_t y,
                                    uint32_t channel, uint32_t stream)
{
    return nprfx_u01(nprfx_hash(seed, frame, x, y, channel, stream));
}

/* Standard normal from the counter (Box-Muller on two hashes derived from one counter). */
static inline double nprfx_rand_gauss(uint64_t seed, int64_t frame, int32_t x, int32_t y,
                                      uint32_t channel, uint32_t stream)
{
    uint64_t h = nprfx_hash(seed, frame, x, y, channel, stream);
    double u1 = ((double)(h >> 11) + 0.5) * (1.0 / 9007199254740992.0); /* (0,1) */
    double u2 = nprfx_u01(nprfx_mix64(h));
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

#ifdef __cplusplus
}
#endif
#endif
