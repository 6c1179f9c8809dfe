/* Object ids in float planes (nprfx/objectid.h): a uint id read as a float and written back is
 * the same uint, for every id but the three the header names; ids up to 2^24 read as the float
 * equal to them; two uints are one object only when they are equal (or the named exceptions);
 * the comparisons see bits, so NaN and denormal ids are objects of their own. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "nprfx/objectid.h"

static float of_bits(uint32_t b)
{
    float f;
    memcpy(&f, &b, sizeof f);
    return f;
}

static uint32_t bits_of(float f)
{
    uint32_t b;
    memcpy(&b, &f, sizeof b);
    return b;
}

/* u read and written back: 1 when it does not come back (0x80000000 comes back as 0, 0xffc00000
 * as the other arithmetic NaN, 0x7fc00000: the ids the header names). */
static int round_trip_bad(uint32_t u)
{
    uint32_t back = nprfx_id_to_uint(nprfx_id_from_uint(u));
    if (u == 0x80000000u) return back != 0;
    if (u == 0xffc00000u) return back != NPRFX_ID_NONE;
    return back != u;
}

static void test_small_ids_are_their_value(void)
{
    int bad = 0;
    for (uint32_t n = 0; n <= (1u << 24); n++)
        if (nprfx_id_from_uint(n) != (float)n ||
            bits_of(nprfx_id_from_uint(n)) != bits_of((float)n))
            bad++;
    CHECK(bad == 0);
    CHECK(nprfx_id_to_uint(7.0f) == 7u);
    CHECK(nprfx_id_to_uint(16777216.0f) == 16777216u);
    CHECK(nprfx_id_to_uint(-0.0f) == 0u);
}

static void test_round_trip(void)
{
    int bad = 0;
    /* every id up to 2^24 + 2^20 (the small ones and the first past float's integers) */
    for (uint32_t u = 0; u <= (1u << 24) + (1u << 20); u++)
        bad += round_trip_bad(u);
    /* every uint whose bits are a float's integer from 1 to 2^24: the small ids' partners */
    for (uint32_t n = 1; n <= (1u << 24); n++)
        bad += round_trip_bad(bits_of((float)n));
    /* a stride through all 2^32, and the edges of every exponent */
    for (uint64_t u = 0; u <= 0xffffffffu; u += 65521)
        bad += round_trip_bad((uint32_t)u);
    for (uint32_t e = 0; e < 256; e++)
        for (uint32_t s = 0; s < 2; s++) {
            uint32_t b = s << 31 | e << 23;
            bad += round_trip_bad(b) + round_trip_bad(b | 1u) + round_trip_bad(b | 0x7fffffu) +
                   round_trip_bad(b | 0x400000u);
        }
    CHECK(bad == 0);
}

static void test_same_object(void)
{
    /* ids that differ only in their lowest bits above 2^24 (one float, rounded) stay apart */
    const uint32_t hi[] = {16777217u,   16777218u,   16777219u,   268435457u,  268435458u,
                           0x7f800001u, 0x7f800002u, 0xff800001u, 0x7f800000u, 0xff800000u,
                           0x00000001u, 0x3f800000u, 0xfffffffeu, 0xffffffffu, 0u};
    const int n = (int)(sizeof hi / sizeof hi[0]);
    int bad = 0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            if (nprfx_id_same(nprfx_id_from_uint(hi[i]), nprfx_id_from_uint(hi[j])) != (i == j))
                bad++;
    CHECK(bad == 0);
    for (int i = 0; i < n; i++)
        CHECK(nprfx_id_is_object(nprfx_id_from_uint(hi[i])));
    /* a NaN-pattern id is one object with itself (float == says otherwise) */
    float nan_id = nprfx_id_from_uint(0x7f800001u);
    CHECK(isnan(nan_id) && nprfx_id_same(nan_id, nan_id));
    /* the named exceptions: -0 is 0, the arithmetic NaNs are no object and the same "none" */
    CHECK(nprfx_id_same(-0.0f, 0.0f));
    CHECK(nprfx_id_same(nprfx_id_from_uint(0x80000000u), nprfx_id_from_uint(0u)));
    CHECK(!nprfx_id_is_object(of_bits(0x7fc00000u)) && !nprfx_id_is_object(of_bits(0xffc00000u)));
    CHECK(nprfx_id_same(of_bits(0x7fc00000u), of_bits(0xffc00000u)));
    CHECK(nprfx_id_key(nanf("")) == NPRFX_ID_NONE);
    CHECK(!nprfx_id_is_object(0.0f / (volatile float){0.0f}));
    /* canonical: one bit pattern an object */
    CHECK(bits_of(nprfx_id_canonical(-0.0f)) == 0u);
    CHECK(bits_of(nprfx_id_canonical(of_bits(0xffc00000u))) == NPRFX_ID_NONE);
    CHECK(bits_of(nprfx_id_canonical(nan_id)) == bits_of(nan_id));
}

int main(void)
{
    test_small_ids_are_their_value();
    test_round_trip();
    test_same_object();
    return check_finish();
}
