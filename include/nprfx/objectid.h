/* nprfx — object ids in float planes.
 *
 * Nodes take images of floats, and an id input is one of them: one float a pixel whose 32 bits
 * name the pixel's object. Ids a renderer writes as floats (Blender's IndexOB, Cryptomatte's
 * hashes) are their own values. Ids it writes as uint (Arnold's ID, instance and object ids,
 * hashes up to 2^32 - 1) are read bit-exactly: every id up to 2^24 is the float equal to it (so
 * an id 7 reads as 7.0, as a float id would), every larger id is a float of its own. The pairs
 * (n, the bits of the float n) for 1 <= n <= 2^24 trade places and every other id keeps its
 * bits, so the read is one-to-one and nprfx_id_to_uint undoes it when a plate is written back.
 *
 * Two pixels show the same object when their ids have the same bits, with two exceptions a
 * float cannot avoid: +0 and -0 are one object (0), and the two NaNs that arithmetic makes
 * (0x7fc00000 and 0xffc00000, what a renderer's 0/0 writes) are no object. Every other NaN or
 * infinity is an id like any other (a uint hash can be one). So of the 2^32 uint ids three cannot
 * be told from another: 0x80000000 (read as 0), 0x7fc00000 and 0xffc00000 (no object).
 * Nodes compare ids through these functions, never with float ==, which a NaN id would fail. */
#ifndef NPRFX_OBJECTID_H
#define NPRFX_OBJECTID_H

#include <stdint.h>
#include <string.h>

#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What nprfx_id_key gives a pixel with no object. */
#define NPRFX_ID_NONE UINT32_C(0x7fc00000)

/* The key of the object an id value names: its bits, -0 as 0 and the arithmetic NaNs as
 * NPRFX_ID_NONE. Equal keys, same object. */
static inline uint32_t nprfx_id_key(float id)
{
    uint32_t b;
    memcpy(&b, &id, sizeof b);
    if (b == UINT32_C(0x80000000)) return 0;
    if (b == UINT32_C(0xffc00000)) return NPRFX_ID_NONE;
    return b;
}

/* The id as a float whose bits are its key (one value per object): what a node stores when it
 * copies an id for later comparisons by bits. */
static inline float nprfx_id_canonical(float id)
{
    uint32_t b = nprfx_id_key(id);
    float f;
    memcpy(&f, &b, sizeof f);
    return f;
}

/* Whether two id values name the same object. */
static inline int nprfx_id_same(float a, float b)
{
    return nprfx_id_key(a) == nprfx_id_key(b);
}

/* Whether an id value names an object (not one of arithmetic's NaNs). */
static inline int nprfx_id_is_object(float id)
{
    return nprfx_id_key(id) != NPRFX_ID_NONE;
}

/* The float a uint id is read as (see above): id itself up to 2^24, else a float of its own. */
NPRFX_API float nprfx_id_from_uint(uint32_t id);

/* The uint id a float id is written back as: nprfx_id_from_uint undone (-0 as 0, arithmetic's
 * NaNs as 0x7fc00000). A float id that is an integer from 0 to 2^24 gives that integer. */
NPRFX_API uint32_t nprfx_id_to_uint(float id);

#ifdef __cplusplus
}
#endif

#endif
