/* nprfx core — uint ids to and from the floats nodes compare (nprfx/objectid.h). */
#include "nprfx/objectid.h"

#include <math.h>

/* The involution on 32-bit patterns: n and the bits of (float)n trade places for
 * 1 <= n <= 2^24 (those bits are all >= 0x3f800000, the bits of 1, so no pair meets another);
 * every other pattern stays. Applying it twice gives the pattern back. */
static uint32_t trade(uint32_t b)
{
    if (b <= UINT32_C(1) << 24) {
        float f = (float)b;
        uint32_t fb;
        memcpy(&fb, &f, sizeof fb);
        return fb;
    }
    float f;
    memcpy(&f, &b, sizeof f);
    if (f >= 1.0f && f <= 16777216.0f && f == floorf(f)) return (uint32_t)f;
    return b;
}

float nprfx_id_from_uint(uint32_t id)
{
    uint32_t b = trade(id);
    float f;
    memcpy(&f, &b, sizeof f);
    return f;
}

uint32_t nprfx_id_to_uint(float id)
{
    return trade(nprfx_id_key(id));
}
