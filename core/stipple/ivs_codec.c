/* The encoded IVS sequence: a small header and 24-bit fixed-point coordinates (ivs.h has the
 * layout). Written byte by byte so the format does not depend on the host's endianness. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/ivs.h"

static const unsigned char ivs_magic[8] = {'N', 'P', 'R', 'F', 'X', 'I', 'V', 'S'};

#define IVS_BITS 24
#define IVS_POINT_BYTES 6

static void put_u32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}
static void put_u64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}
static uint32_t get_u32(const unsigned char *p)
{
    uint32_t v = 0;
    for (int i = 0; i < 4; i++)
        v |= (uint32_t)p[i] << (8 * i);
    return v;
}
static uint64_t get_u64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 0; i < 8; i++)
        v |= (uint64_t)p[i] << (8 * i);
    return v;
}

/* FNV-1a: not cryptographic, only there to catch truncation and bit rot. */
static uint32_t fnv1a(const unsigned char *p, size_t n)
{
    uint32_t h = 2166136261u;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 16777619u;
    }
    return h;
}

size_t nprfx_ivs_encoded_size(int n)
{
    return n < 0 ? 0 : NPRFX_IVS_HEADER_SIZE + (size_t)n * IVS_POINT_BYTES;
}

/* Nearest 24-bit fixed-point value; 1.0 wraps to 0, as the torus does. */
static uint32_t quantize(float v)
{
    double q = floor((double)v * (double)(1u << IVS_BITS) + 0.5);
    if (!(q >= 0.0)) q = 0.0; /* also catches NaN */
    return (uint32_t)fmod(q, (double)(1u << IVS_BITS));
}

void nprfx_ivs_quantize(float *xy, int n)
{
    const float scale = 1.0f / (float)(1u << IVS_BITS);
    for (size_t i = 0; n > 0 && i < (size_t)n * 2; i++)
        xy[i] = (float)quantize(xy[i]) * scale; /* what nprfx_ivs_decode computes */
}

nprfx_result nprfx_ivs_encode(nprfx_context *ctx, uint64_t seed, int n, const float *xy,
                              unsigned char *buf, size_t buf_size)
{
    if (n < 1 || !xy || !buf)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "ivs encode: need n >= 1 points");
    if (buf_size < nprfx_ivs_encoded_size(n))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "ivs encode: %d points need %zu bytes, buffer has %zu", n,
                           nprfx_ivs_encoded_size(n), buf_size);
    unsigned char *payload = buf + NPRFX_IVS_HEADER_SIZE;
    for (int i = 0; i < 2 * n; i++) {
        uint32_t q = quantize(xy[i]);
        payload[3 * i] = (unsigned char)q;
        payload[3 * i + 1] = (unsigned char)(q >> 8);
        payload[3 * i + 2] = (unsigned char)(q >> 16);
    }
    memcpy(buf, ivs_magic, sizeof ivs_magic);
    put_u32(buf + 8, NPRFX_IVS_FORMAT_VERSION);
    put_u32(buf + 12, (uint32_t)n);
    put_u64(buf + 16, seed);
    put_u32(buf + 24, IVS_BITS);
    put_u32(buf + 28, fnv1a(payload, (size_t)n * IVS_POINT_BYTES));
    return NPRFX_OK;
}

nprfx_result nprfx_ivs_decode(nprfx_context *ctx, const unsigned char *buf, size_t size,
                              uint64_t *seed_out, int *n_out, float **xy_out)
{
    if (!buf || !n_out || !xy_out)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "ivs decode: NULL argument");
    *xy_out = NULL;
    *n_out = 0;
    if (size < NPRFX_IVS_HEADER_SIZE || memcmp(buf, ivs_magic, sizeof ivs_magic) != 0)
        return nprfx_error(ctx, NPRFX_ERR_PARSE,
                           "ivs: not an IVS sequence file (missing \"NPRFXIVS\" header)");
    uint32_t version = get_u32(buf + 8), count = get_u32(buf + 12), bits = get_u32(buf + 24);
    if (version != NPRFX_IVS_FORMAT_VERSION)
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                           "ivs: format version %u is not supported (this build reads %d)", version,
                           NPRFX_IVS_FORMAT_VERSION);
    if (bits != IVS_BITS)
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                           "ivs: %u bits per coordinate is not supported (expected %d)", bits,
                           IVS_BITS);
    if (count < 1 || count > (uint32_t)((0x7fffffff - NPRFX_IVS_HEADER_SIZE) / IVS_POINT_BYTES))
        return nprfx_error(ctx, NPRFX_ERR_PARSE, "ivs: invalid point count %u", count);
    size_t want = nprfx_ivs_encoded_size((int)count);
    if (size != want)
        return nprfx_error(ctx, NPRFX_ERR_PARSE,
                           "ivs: file is %s: header says %u points (%zu bytes), got %zu bytes",
                           size < want ? "truncated" : "too long", count, want, size);
    const unsigned char *payload = buf + NPRFX_IVS_HEADER_SIZE;
    uint32_t hash = fnv1a(payload, (size_t)count * IVS_POINT_BYTES);
    if (hash != get_u32(buf + 28))
        return nprfx_error(ctx, NPRFX_ERR_PARSE,
                           "ivs: checksum mismatch (stored %08x, computed %08x): the file is "
                           "corrupt",
                           get_u32(buf + 28), hash);
    float *xy = malloc((size_t)count * 2 * sizeof(float));
    if (!xy)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "ivs: out of memory for %u points", count);
    const float scale = 1.0f / (float)(1u << IVS_BITS);
    for (size_t i = 0; i < (size_t)count * 2; i++) {
        uint32_t q = (uint32_t)payload[3 * i] | (uint32_t)payload[3 * i + 1] << 8 |
                     (uint32_t)payload[3 * i + 2] << 16;
        xy[i] = (float)q * scale; /* exact: 24 bits fit a float's mantissa */
    }
    if (seed_out) *seed_out = get_u64(buf + 16);
    *n_out = (int)count;
    *xy_out = xy;
    return NPRFX_OK;
}
