/* The smoothed area scale |det J| the stipple renderer's thresholds read
 * (internal_stipple_smooth_area), from the Jacobian stipple_jacobian.c computed and
 * stipple_outliers.c repaired. SSE2 lanes, and eight with AVX2 where the CPU has it, do the
 * scalar code's operations in its order; the scalar code is the reference at edges and NaNs. */
#include <math.h>
#include <stdlib.h>
#include <stdint.h>
#include <string.h>

#include "internal_stipple.h"
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if INTERNAL_X86
#include <immintrin.h>
#endif

#if defined(__SSE2__)
/* The horizontal pass of smooth_area for pixels k .. k + 3 (one lane each), whose +-SMOOTH
 * neighbours are all held: the sum of adet over the same-id pixels, and their count (summed as
 * an integer: the float sum of 1s is exact), both 0 where the pixel has no usable
 * derivatives. */
static inline void horizontal4(const int *jid, const float *adet, float *hs, float *hc, size_t k)
{
    const __m128i vid = _mm_loadu_si128((const __m128i *)(jid + k));
    __m128 vs = _mm_setzero_ps();
    __m128i vc = _mm_setzero_si128();
    for (int dx = -SMOOTH; dx <= SMOOTH; dx++) {
        const __m128i same = _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(jid + k + dx)), vid);
        vs = _mm_add_ps(vs, _mm_and_ps(_mm_castsi128_ps(same), _mm_loadu_ps(adet + k + dx)));
        vc = _mm_sub_epi32(vc, same);
    }
    const __m128 none = _mm_castsi128_ps(_mm_cmpeq_epi32(vid, _mm_set1_epi32(NO_ID)));
    _mm_storeu_ps(hs + k, _mm_andnot_ps(none, vs));
    _mm_storeu_ps(hc + k, _mm_andnot_ps(none, _mm_cvtepi32_ps(vc)));
}

/* The vertical pass of smooth_area for pixels k .. k + 3 (one lane each) over rows lo .. hi
 * around them: cnt > 0 ? sum / cnt : 0, and 0 where the pixel has no usable derivatives. */
static inline __m128 vertical4(const int *jid, const float *hs, const float *hc, ptrdiff_t k,
                               ptrdiff_t w, int lo, int hi)
{
    const __m128i vid = _mm_loadu_si128((const __m128i *)(jid + k));
    __m128 vs = _mm_setzero_ps(), vc = _mm_setzero_ps();
    for (int dy = lo; dy <= hi; dy++) {
        const ptrdiff_t q = k + dy * w;
        const __m128 same =
            _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(jid + q)), vid));
        vs = _mm_add_ps(vs, _mm_and_ps(same, _mm_loadu_ps(hs + q)));
        vc = _mm_add_ps(vc, _mm_and_ps(same, _mm_loadu_ps(hc + q)));
    }
    const __m128 use = _mm_andnot_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(vid, _mm_set1_epi32(NO_ID))),
                                     _mm_cmpgt_ps(vc, _mm_setzero_ps()));
    return _mm_and_ps(use, _mm_div_ps(vs, vc));
}
#endif

#if INTERNAL_X86
/* horizontal4 eight lanes wide, over the n pixels from k (n a multiple of 8). */
__attribute__((target("avx2"))) static void
horizontal_run_avx2(const int *jid, const float *adet, float *hs, float *hc, size_t k, size_t n)
{
    const __m256i none = _mm256_set1_epi32(NO_ID);
    for (size_t e = k + n; k < e; k += 8) {
        const __m256i vid = _mm256_loadu_si256((const __m256i *)(jid + k));
        __m256 vs = _mm256_setzero_ps();
        __m256i vc = _mm256_setzero_si256();
        for (int dx = -SMOOTH; dx <= SMOOTH; dx++) {
            const __m256i same =
                _mm256_cmpeq_epi32(_mm256_loadu_si256((const __m256i *)(jid + k + dx)), vid);
            vs = _mm256_add_ps(
                vs, _mm256_and_ps(_mm256_castsi256_ps(same), _mm256_loadu_ps(adet + k + dx)));
            vc = _mm256_sub_epi32(vc, same);
        }
        const __m256 out = _mm256_castsi256_ps(_mm256_cmpeq_epi32(vid, none));
        _mm256_storeu_ps(hs + k, _mm256_andnot_ps(out, vs));
        _mm256_storeu_ps(hc + k, _mm256_andnot_ps(out, _mm256_cvtepi32_ps(vc)));
    }
}

/* vertical4 eight lanes wide, for the n pixels from k (n a multiple of 8) into o. Always
 * inlined, so that the usual rows' taps (lo = -SMOOTH, hi = SMOOTH) are unrolled. */
__attribute__((target("avx2"), always_inline)) static inline void
vertical_lanes8(const int *jid, const float *hs, const float *hc, ptrdiff_t k, ptrdiff_t w, int lo,
                int hi, float *o, int n)
{
    const __m256i none = _mm256_set1_epi32(NO_ID);
    for (int i = 0; i < n; i += 8, k += 8) {
        const __m256i vid = _mm256_loadu_si256((const __m256i *)(jid + k));
        __m256 vs = _mm256_setzero_ps(), vc = _mm256_setzero_ps();
        for (int dy = lo; dy <= hi; dy++) {
            const ptrdiff_t q = k + dy * w;
            const __m256 same = _mm256_castsi256_ps(
                _mm256_cmpeq_epi32(_mm256_loadu_si256((const __m256i *)(jid + q)), vid));
            vs = _mm256_add_ps(vs, _mm256_and_ps(same, _mm256_loadu_ps(hs + q)));
            vc = _mm256_add_ps(vc, _mm256_and_ps(same, _mm256_loadu_ps(hc + q)));
        }
        const __m256 use = _mm256_andnot_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(vid, none)),
                                            _mm256_cmp_ps(vc, _mm256_setzero_ps(), _CMP_GT_OQ));
        _mm256_storeu_ps(o + i, _mm256_and_ps(use, _mm256_div_ps(vs, vc)));
    }
}

/* The vertical pass of a row's first n pixels (n a multiple of 8), eight lanes wide. */
__attribute__((target("avx2"))) static void vertical_run_avx2(const int *jid, const float *hs,
                                                              const float *hc, ptrdiff_t k,
                                                              ptrdiff_t w, int lo, int hi, float *o,
                                                              int n)
{
    if (lo == -SMOOTH && hi == SMOOTH)
        vertical_lanes8(jid, hs, hc, k, w, -SMOOTH, SMOOTH, o, n);
    else
        vertical_lanes8(jid, hs, hc, k, w, lo, hi, o, n);
}
#endif

/* The area scale |det J| averaged over the same-object pixels of a (2 SMOOTH + 1)^2 window
 * (a horizontal pass within the object, then a vertical one), for the density thresholds only.
 * UV passes are often stored as half floats, whose steps make per-pixel differences of a slowly
 * varying UV jump by factors of two; the kept prefix would then change from pixel to pixel,
 * which scatters the dots like white noise. Needs adet on E plus SMOOTH; writes out[] over E.
 * Sums start at +0 and add values >= +0 (|det|, and sums of them), so adding +0 for a pixel
 * that does not count gives the same float as skipping it: the interior loops test without
 * branching, four pixels at a time where SSE2 is there, each lane adding in the scalar
 * order. */
void internal_stipple_smooth_area(pixdata *d, nprfx_rect E, nprfx_rect R, float *out, int avx2)
{
    const ptrdiff_t w = d->w;
    const int *restrict jid = d->jid;
    const float *restrict adet = d->adet;
    float *restrict hs = d->hs, *restrict hc = d->hc;
    /* columns of E whose +-SMOOTH neighbours are all held */
    const int xa = E.x0 - SMOOTH >= d->r.x0 ? E.x0 : d->r.x0 + SMOOTH;
    const int xb = E.x1 + SMOOTH <= d->r.x1 ? E.x1 : d->r.x1 - SMOOTH;
    for (int y = R.y0; y < R.y1; y++) {
        const size_t k0 = pd_at(d, E.x0, y);
        for (int x = E.x0; x < E.x1; x++) {
            const size_t k = k0 + (size_t)(x - E.x0);
#if INTERNAL_X86
            if (avx2 && x >= xa && x + 8 <= xb) { /* the row's interior, eight at a time */
                const int n = (xb - x) & ~7;
                horizontal_run_avx2(jid, adet, hs, hc, k, (size_t)n);
                x += n - 1;
                continue;
            }
#endif
#if defined(__SSE2__)
            if (x >= xa && x + 4 <= xb) {
                horizontal4(jid, adet, hs, hc, k);
                x += 3;
                continue;
            }
#endif
            float sum = 0, cnt = 0;
            const int id = jid[k];
            if (id == NO_ID) {
            } else if (x >= xa && x < xb) {
                for (int dx = -SMOOTH; dx <= SMOOTH; dx++) {
                    const int same = jid[k + dx] == id;
                    sum += same ? adet[k + dx] : 0.0f;
                    cnt += same ? 1.0f : 0.0f;
                }
            } else {
                int lo = x - SMOOTH < d->r.x0 ? d->r.x0 - x : -SMOOTH;
                int hi = x + SMOOTH >= d->r.x1 ? d->r.x1 - 1 - x : SMOOTH;
                for (int dx = lo; dx <= hi; dx++)
                    if (jid[k + dx] == id) {
                        sum += adet[k + dx];
                        cnt += 1;
                    }
            }
            hs[k] = sum;
            hc[k] = cnt;
        }
    }
    int ew = nprfx_rect_width(E);
    for (int y = E.y0; y < E.y1; y++) {
        int lo = y - SMOOTH < R.y0 ? R.y0 - y : -SMOOTH;
        int hi = y + SMOOTH >= R.y1 ? R.y1 - 1 - y : SMOOTH;
        const ptrdiff_t k0 = (ptrdiff_t)pd_at(d, E.x0, y);
        float *restrict o = out + (size_t)(y - E.y0) * ew;
        int i = 0;
#if INTERNAL_X86
        if (avx2) {
            vertical_run_avx2(jid, hs, hc, k0, w, lo, hi, o, ew & ~7);
            i = ew & ~7;
        }
#endif
#if defined(__SSE2__)
        if (lo == -SMOOTH && hi == SMOOTH) /* the usual row: the taps unrolled */
            for (; i + 4 <= ew; i += 4)
                _mm_storeu_ps(o + i, vertical4(jid, hs, hc, k0 + i, w, -SMOOTH, SMOOTH));
        for (; i + 4 <= ew; i += 4)
            _mm_storeu_ps(o + i, vertical4(jid, hs, hc, k0 + i, w, lo, hi));
#endif
        for (; i < ew; i++) {
            const ptrdiff_t k = k0 + i;
            float sum = 0, cnt = 0;
            const int id = jid[k];
            if (id != NO_ID)
                for (int dy = lo; dy <= hi; dy++) {
                    const ptrdiff_t q = k + dy * w;
                    const int same = jid[q] == id;
                    sum += same ? hs[q] : 0.0f;
                    cnt += same ? hc[q] : 0.0f;
                }
            o[i] = cnt > 0 ? sum / cnt : 0.0f;
        }
    }
}
