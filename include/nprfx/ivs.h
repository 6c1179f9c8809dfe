/* nprfx — the incremental Voronoi set (IVS): a progressive blue-noise sequence on the unit torus.
 *
 * docs/design.md §3.3. The sequence is a farthest-point sequence: each new point is the centre of
 * the largest empty circle left by the points before it, found as the largest circumcircle of a
 * periodic Delaunay triangulation. Every prefix is therefore evenly spread, and sample i (1-based)
 * owns a Voronoi area of about 1/i of the torus, which is what the stipple node thresholds on.
 *
 * The generator is deterministic from its seed, and a prefix does not depend on how many points
 * are asked for: the first m points of a run for n >= m are the points of a run for m. (Results
 * are bit-exact for a given compiler and architecture; a compiler that contracts a*b+c into FMA
 * may give a different, equally good sequence: ship the encoded file where that matters.)
 *
 * Core does no file I/O: the sequence is encoded into and decoded from memory buffers, the CLI
 * (`nprfx ivs`) reads and writes the files, and the stipple node reads the shipped one through
 * plugins/support/data_files.c. */
#ifndef NPRFX_IVS_H
#define NPRFX_IVS_H

#include <stddef.h>
#include <stdint.h>

#include "nprfx/context.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The seed of the sequence the stipple node uses by default. */
#define NPRFX_IVS_DEFAULT_SEED 20180601u

/* Generate the first n >= 1 points of the sequence for `seed` into xy (2 * n floats: x0, y0, x1,
 * y1, ..., each in [0, 1)). radius, when not NULL, receives n floats: radius[k] is the radius of
 * the empty circle centred on point k just before it was inserted (its distance to the nearest
 * earlier point); radius[0] is sqrt(1/2), the largest empty circle of the empty torus. For
 * k >= ~16, radius[k] * sqrt(k + 1) stays within about [0.75, 0.9].
 *
 * Cost: O(n log n) time, about 150 bytes per point of transient memory. */
NPRFX_API nprfx_result nprfx_ivs_generate(nprfx_context *ctx, uint64_t seed, int n, float *xy,
                                          float *radius);

/* ---- the encoded form (a shipped data file) ----
 *
 * Little-endian throughout:
 *   offset 0   8 bytes  magic "NPRFXIVS"
 *   offset 8   u32      format version (1)
 *   offset 12  u32      count n
 *   offset 16  u64      seed the sequence was generated from
 *   offset 24  u32      bits per coordinate (24)
 *   offset 28  u32      FNV-1a 32-bit hash of the payload
 *   offset 32  payload: n points, each x then y as 24-bit unsigned fixed point (3 bytes each,
 *              value = q / 2^24), so 6 bytes per point.
 * 24 bits put the coordinate error below 3e-8, four orders of magnitude under the spacing of a
 * million points. */
#define NPRFX_IVS_HEADER_SIZE 32
#define NPRFX_IVS_FORMAT_VERSION 1

/* Bytes nprfx_ivs_encode writes for n points. */
NPRFX_API size_t nprfx_ivs_encoded_size(int n);

/* Encode n points (xy as from nprfx_ivs_generate) into buf, which must hold
 * nprfx_ivs_encoded_size(n) bytes. */
NPRFX_API nprfx_result nprfx_ivs_encode(nprfx_context *ctx, uint64_t seed, int n, const float *xy,
                                        unsigned char *buf, size_t buf_size);

/* Round n points (2 * n floats in [0, 1]) to the encoded form's grid, as encoding then decoding
 * them would: q / 2^24 with q the nearest integer to v * 2^24, 1.0 wrapping to 0. */
NPRFX_API void nprfx_ivs_quantize(float *xy, int n);

/* Decode and validate an encoded sequence (magic, version, bit depth, size, hash). On success
 * *xy_out is a malloc'd array of 2 * *n_out floats the caller frees; seed_out may be NULL. On
 * failure nothing is allocated and the error names what is wrong. */
NPRFX_API nprfx_result nprfx_ivs_decode(nprfx_context *ctx, const unsigned char *buf, size_t size,
                                        uint64_t *seed_out, int *n_out, float **xy_out);

/* ---- the spatial index ----
 *
 * A pixel that keeps samples i <= i_max (docs/design.md §3.3: k * A0 / i >= threshold) needs only
 * the prefix of the sequence up to i_max, and expects about (its footprint area) * i_max of them.
 * The index holds one uniform grid per power-of-two prefix (level L: the first 2^L points, about
 * two per cell), so a query reads the level just above i_max and the cells its rectangle touches:
 * time proportional to the answer, not to the sequence length. */
typedef struct nprfx_ivs_index nprfx_ivs_index;

/* Build the index over n points (xy as from nprfx_ivs_generate; copied). */
NPRFX_API nprfx_result nprfx_ivs_index_create(nprfx_context *ctx, const float *xy, int n,
                                              nprfx_ivs_index **out);
NPRFX_API void nprfx_ivs_index_destroy(nprfx_ivs_index *index);
/* Number of points indexed. */
NPRFX_API int nprfx_ivs_index_count(const nprfx_ivs_index *index);
/* Point k (0-based) of the sequence; xy must hold 2 floats. */
NPRFX_API void nprfx_ivs_index_point(const nprfx_ivs_index *index, int k, float *xy);

/* Called once per sample found: its 0-based index and its position (u, v) in the unbounded plane
 * (the torus point plus the integer tile it was found in). Return nonzero to stop the query. */
typedef int (*nprfx_ivs_visit_fn)(void *user, int index, double u, double v);

/* Visit every sample with 0-based index < limit (1-based i <= limit) whose position, tiled over
 * the plane with period 1, lies in [u0, u1) x [v0, v1). limit is clamped to the indexed count.
 * Samples are visited in a fixed order for a given query (by tile, then cell, then index).
 * Returns the number of samples visited. Thread-safe: the index is read-only. */
NPRFX_API long long nprfx_ivs_index_query(const nprfx_ivs_index *index, int limit, double u0,
                                          double v0, double u1, double v1, nprfx_ivs_visit_fn visit,
                                          void *user);

/* Samples at most handed to a batch callback at once. */
#define NPRFX_IVS_BATCH 64

/* Called with n >= 1 samples found (index[k], u[k], v[k] as a visit callback gets them), in the
 * order nprfx_ivs_index_query visits them. Return nonzero to stop the query. */
typedef int (*nprfx_ivs_batch_fn)(void *user, int n, const int32_t *index, const double *u,
                                  const double *v);

/* nprfx_ivs_index_query with the samples handed over up to NPRFX_IVS_BATCH at a time, for
 * callers whose work per sample is small next to a call (fn may be NULL: count only). The same
 * samples in the same order. Returns the number found, including those of the batch after which
 * fn stopped the query. */
NPRFX_API long long nprfx_ivs_index_query_batch(const nprfx_ivs_index *index, int limit, double u0,
                                                double v0, double u1, double v1,
                                                nprfx_ivs_batch_fn fn, void *user);

#ifdef __cplusplus
}
#endif
#endif
