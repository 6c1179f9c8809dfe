/* Internal to the IVS index (core/stipple/ivs_index.c) and its callers in core, never installed. */
#ifndef NPRFX_INTERNAL_IVS_H
#define NPRFX_INTERNAL_IVS_H

#include "base/internal_simd.h"
#include "nprfx/ivs.h"

/* The index scan has an AVX2 copy of its loop where INTERNAL_X86 (internal_simd.h), picked at
 * run time (docs/design.md §1: each lane does the baseline loop's IEEE operations, so the same
 * samples come in the same order). */
/* nprfx_ivs_index_query_batch, scanning with the AVX2 loop where avx2 is set (the CPU must have
 * AVX2) and the baseline one otherwise: what the stipple renderer's simd param picks. */
long long internal_ivs_index_query_batch(const nprfx_ivs_index *ix, int limit, double u0, double v0,
                                         double u1, double v1, nprfx_ivs_batch_fn fn, void *user,
                                         int avx2);

#endif
