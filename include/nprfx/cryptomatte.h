/* nprfx — Cryptomatte: object ids from the layers renderers write instead of an index pass.
 *
 * The Cryptomatte specification (Psyop, "Cryptomatte Specification", v1.2.0): a layer `NAME`
 * (e.g. "CryptoObject", "crypto_object") is stored as channels NAME00.R/G/B/A, NAME01.R/G/B/A,
 * ...: each channel pair (R,G), (B,A) holds one rank, an id and its coverage, ranks sorted by
 * coverage. The id is the MurmurHash3_x86_32 (seed 0) of the object's name, stored as the bits
 * of a float whose exponent is clamped to [1, 254] so that it is never denormal, inf or NaN.
 * The header carries, for a key KEY (the first 7 hex digits of the hash of NAME),
 * `cryptomatte/KEY/name`, `/hash` ("MurmurHash3_32"), `/conversion` ("uint32_to_float32") and
 * `/manifest` (a JSON object {"object name": "hex of the hash", ...}) or `/manif_file` (a
 * sidecar JSON file, relative to the image).
 *
 * nprfx decodes a layer's rank-0 id into an exact integer id: the low 24 bits of the stored
 * float's bits, with 0 for a pixel whose rank-0 coverage is 0 (nothing there) and 2^24 for a
 * non-empty pixel whose low bits are 0, so every id is a float an id input holds exactly. */
#ifndef NPRFX_CRYPTOMATTE_H
#define NPRFX_CRYPTOMATTE_H

#include <stddef.h>
#include <stdint.h>

#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* MurmurHash3_x86_32 of len bytes of name, seed 0 (the specification's hash). */
NPRFX_API uint32_t nprfx_cryptomatte_hash(const char *name, size_t len);

/* The float a renderer stores for a hash: its bits, with the exponent clamped to [1, 254]. */
NPRFX_API float nprfx_cryptomatte_float(uint32_t hash);

/* The bits a stored id float has (what the manifest's hex names, after clamping). */
NPRFX_API uint32_t nprfx_cryptomatte_bits(float stored);

/* nprfx's integer id for a rank-0 (id, coverage) pair, as a float (see above). */
NPRFX_API float nprfx_cryptomatte_object_id(float stored, float coverage);

/* The 7 hex digits (and a NUL) naming a layer in the header: "cryptomatte/KEY/...". */
NPRFX_API void nprfx_cryptomatte_key(const char *layer, char key[8]);

/* A manifest for n names: {"name":"hex of the float bits",...}, names escaped as JSON strings
 * (quotes, backslashes, control characters; UTF-8 passes through). Writes at most cap bytes with
 * a NUL and returns the length the whole manifest needs (as snprintf). */
NPRFX_API size_t nprfx_cryptomatte_manifest(const char *const *names, int n, char *buf,
                                            size_t cap);

/* One Cryptomatte layer found in a plate's channels and header. */
typedef struct nprfx_cryptomatte_layer {
    char name[128]; /* "CryptoObject" */
    char key[8];    /* its header key ("" when the header names none) */
    int ranks;      /* the rank pairs present: 2 per NAMEnn channel group */
    int id0, cov0;  /* channel indices of rank 0's id and coverage (NAME00.R, NAME00.G) */
    int kind;       /* 1 object, 2 material, 3 asset, 0 other: from the name */
} nprfx_cryptomatte_layer;

/* The Cryptomatte layers among n channel names (full names, a part's or view layer's prefix
 * allowed), their header keys from nattr attribute name/value pairs (either may be NULL):
 * layers written to out (at most max), returns how many there are. */
NPRFX_API int nprfx_cryptomatte_find(const char *const *names, int n,
                                     const char *const *attr_names,
                                     const char *const *attr_values, int nattr,
                                     nprfx_cryptomatte_layer *out, int max);

/* Which of n layers a plate's object ids come from: the one called `want` when given (its name,
 * or its name's last component), else the first object layer, else the first asset layer, else
 * the first; -1 when none (or none called want). */
NPRFX_API int nprfx_cryptomatte_pick(const nprfx_cryptomatte_layer *layers, int n,
                                     const char *want);

/* The object name for a stored id float from a manifest's JSON text (a copy of at most cap-1
 * bytes in buf); 0 when found, -1 when not, or the text is no manifest. */
NPRFX_API int nprfx_cryptomatte_manifest_name(const char *manifest, float stored, char *buf,
                                              size_t cap);

#ifdef __cplusplus
}
#endif
#endif
