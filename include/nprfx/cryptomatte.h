/* nprfx — Cryptomatte: object ids from the layers renderers write instead of an index pass.
 *
 * The Cryptomatte specification (Psyop, "Cryptomatte Specification", v1.2.0): a layer `NAME`
 * (e.g. "CryptoObject", "crypto_object") is stored as channels NAME00.R/G/B/A, NAME01.R/G/B/A,
 * ...: each channel pair (R,G), (B,A) holds one rank, an id and its coverage, ranks sorted by
 * coverage. The id is the MurmurHash3_x86_32 (seed 0) of the object's name, stored as the bits
 * of a float whose exponent is clamped to [1, 254] so that it is never denormal, inf or NaN.
 * The header carries, for a key KEY (the first 7 hex digits of the hash of NAME),
 * `cryptomatte/KEY/name`, `/hash` ("MurmurHash3_32"), `/conversion` ("uint32_to_float32") and
 * `/manifest` (a JSON object {"object name": "8 hex digits of the stored float's bits", ...}) or
 * `/manif_file` (a sidecar JSON file, relative to the image).
 *
 * nprfx decodes a layer's rank-0 id into an id input's float (nprfx/objectid.h): the stored
 * float itself, all 32 bits, with 0 for a pixel whose rank-0 coverage is 0 (nothing there). Two
 * objects share an id only when their hashes do (or differ only where the clamp flips bit 23). */
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

/* The float a renderer stores for a hash: its bits, with the exponent clamped to [1, 254] (0 and
 * 255 flip bit 23; sign and mantissa stay), so never zero, denormal, inf or NaN. */
NPRFX_API float nprfx_cryptomatte_float(uint32_t hash);

/* The bits a stored id float has (what the manifest's hex names, after clamping). */
NPRFX_API uint32_t nprfx_cryptomatte_bits(float stored);

/* nprfx's id for a rank-0 (id, coverage) pair (see above): 0 when the coverage is not above 0
 * (NaN included) or the stored id is ±0 (the specification's "no object"), else the stored
 * float, bit for bit. */
NPRFX_API float nprfx_cryptomatte_object_id(float stored, float coverage);

/* The 7 hex digits (and a NUL) naming a layer in the header: "cryptomatte/KEY/...", the first 7
 * of "%08x" of the layer name's raw hash (as Blender writes them; Arnold's alShaders take the
 * clamped float's, which differ only for a name whose hash has exponent 0 or 255). */
NPRFX_API void nprfx_cryptomatte_key(const char *layer, char key[8]);

/* A manifest for n names: {"name":"hex of the float bits",...}, names escaped as JSON strings
 * (quotes, backslashes, control characters; UTF-8 passes through), no spaces, NULL names left
 * out. Writes at most cap bytes with a NUL and returns the length the whole manifest needs,
 * without its NUL (as snprintf; buf may be NULL when cap is 0). */
NPRFX_API size_t nprfx_cryptomatte_manifest(const char *const *names, int n, char *buf, size_t cap);

/* One Cryptomatte layer found in a plate's channels and header. */
typedef struct nprfx_cryptomatte_layer {
    char name[128]; /* "CryptoObject" */
    char key[8];    /* its header key ("" when the header names none) */
    int ranks;      /* ranks present: 2 per full NAMEnn group from 00, 1 for a last R,G only */
    int id0, cov0;  /* channel indices of rank 0's id and coverage (NAME00.R, NAME00.G) */
    int kind;       /* 1 object, 2 material, 3 asset, 0 other: from the name */
} nprfx_cryptomatte_layer;

/* The Cryptomatte layers among n channel names (full names, a part's or view layer's prefix
 * allowed), their header keys from nattr attribute name/value pairs (either may be NULL):
 * layers written to out (at most max), in order of their first channel; returns how many there
 * are. A layer NAME has NAME00.R and NAME00.G at least (R/G/B/A or r/g/b/a), and a header
 * attribute "cryptomatte/KEY/name" (or "exr/cryptomatte/KEY/name") naming it, with or without
 * its prefix, or "crypto" in its name (any case): the header is required by the specification,
 * and without it "Light00.R" would be a layer too. */
NPRFX_API int nprfx_cryptomatte_find(const char *const *names, int n, const char *const *attr_names,
                                     const char *const *attr_values, int nattr,
                                     nprfx_cryptomatte_layer *out, int max);

/* Which of n layers a plate's object ids come from: the one called `want` when given (its name,
 * else its name's last component, else its header key; case-sensitive), else the first object
 * layer, else the first asset layer, else the first; -1 when none (or none called want). */
NPRFX_API int nprfx_cryptomatte_pick(const nprfx_cryptomatte_layer *layers, int n,
                                     const char *want);

/* The object name for a stored id float from a manifest's JSON text (a copy of at most cap-1
 * bytes in buf, JSON escapes decoded); 0 when found, -1 when not, or the text is no manifest (a
 * JSON object of string values, checked whole). A value matches when it is the stored float's
 * bits or a raw hash that clamps to them (some writers list the hash); the former wins. */
NPRFX_API int nprfx_cryptomatte_manifest_name(const char *manifest, float stored, char *buf,
                                              size_t cap);

#ifdef __cplusplus
}
#endif
#endif
