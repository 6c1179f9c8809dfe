/* The repair of the stipple renderer's silhouette pixels whose UV Jacobian is an outlier
 * (internal_stipple_repair_outliers), after stipple_jacobian.c computed it. SSE2 lanes, and eight
 * with AVX2 where the CPU has it, do the scalar code's operations in its order; the scalar code
 * is the reference at edges, seams and NaNs. */
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

/* A pixel whose |det J| exceeds OUTLIER times the smallest of its same-object neighbours'
 * sees a jump, not the surface: renderers filter the UV pass, so along a silhouette the
 * pixels hold a blend of the two objects' UVs (and across a UV seam, of the two charts'),
 * which sits between the surfaces and makes a huge footprint there, packed with dots (a dark
 * outline). Half-float steps and perspective change |det J| between neighbours by a few times
 * at most. */
#define OUTLIER 8.0f

/* A repaired pixel's new values, computed from the values before any repair. */
typedef struct fix {
    size_t k;
    double su, sv;
    float jac[4], adet;
} fix;

/* The repairs found so far; failed: one could not be recorded (out of memory). */
typedef struct fixlist {
    pixdata *d;
    size_t n;
    int failed;
} fixlist;

/* Is pixel (x, y) at k an outlier? Then which neighbour it takes: 1 + its index in
 * {-1, +1, -w, +w}; else 0. */
static inline int outlier_source(const pixdata *d, ptrdiff_t k, int x, int up, int down)
{
    const ptrdiff_t w = d->w;
    const int *jid = d->jid;
    const float *adet = d->adet;
    const int id = jid[k];
    if (id == NO_ID) return 0;
    const ptrdiff_t step[4] = {-1, 1, -w, w};
    const int has[4] = {x - 1 >= d->r.x0, x + 1 < d->r.x1, up, down};
    /* an outlier exceeds OUTLIER times some usable neighbour's (exactly: times the
     * smallest); the usual pixel fails all four tests and is done */
    const float a = adet[k] * (1.0f / OUTLIER);
    if (!((has[0] && a > adet[k - 1] && jid[k - 1] == id) ||
          (has[1] && a > adet[k + 1] && jid[k + 1] == id) ||
          (up && a > adet[k - w] && jid[k - w] == id) ||
          (down && a > adet[k + w] && jid[k + w] == id)))
        return 0;
    float ref = INFINITY;
    int best = 0;
    for (int n = 0; n < 4; n++)
        if (has[n] && jid[k + step[n]] == id && adet[k + step[n]] < ref) {
            ref = adet[k + step[n]];
            best = n;
        }
    return 1 + best;
}

/* Record the repair of pixel k from neighbour n (outlier_source - 1): the neighbour's UV
 * extrapolated by its derivatives, and those derivatives. Where there is no room to record
 * it, the pixel is marked OK_DROP instead. */
static void record_fix(fixlist *fl, size_t k, int n)
{
    pixdata *d = fl->d;
    if (fl->n == d->fixcap) {
        size_t cap = d->fixcap ? 2 * d->fixcap : 256;
        fix *nf = realloc(d->fixes, cap * sizeof *nf);
        if (!nf) {
            fl->failed = 1;
            d->ok[k] |= OK_DROP;
            return;
        }
        d->fixes = nf;
        d->fixcap = cap;
    }
    const ptrdiff_t w = d->w, step[4] = {-1, 1, -w, w};
    const size_t q = (size_t)((ptrdiff_t)k + step[n]);
    const double dx = n == 0 ? 1 : n == 1 ? -1 : 0, dy = n == 2 ? 1 : n == 3 ? -1 : 0;
    const float *jq = d->jac + 4 * q;
    fix *f = (fix *)d->fixes + fl->n++;
    f->k = k;
    f->su = d->su[q] + jq[0] * dx + jq[1] * dy;
    f->sv = d->sv[q] + jq[2] * dx + jq[3] * dy;
    memcpy(f->jac, jq, sizeof f->jac);
    f->adet = d->adet[q];
}

#if defined(__SSE2__)
/* Lanes where a > adet and the id is the same, at the neighbours `s` away from four pixels. */
static inline __m128 exceeds(const int *jid, const float *adet, ptrdiff_t s, __m128 a, __m128i id)
{
    const __m128i same = _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(jid + s)), id);
    return _mm_and_ps(_mm_cmpgt_ps(a, _mm_loadu_ps(adet + s)), _mm_castsi128_ps(same));
}

/* outlier_source's first test for pixels k .. k + 3, whose neighbours are all held: a bit a
 * pixel that may be an outlier. */
static inline int outlier_mask4(const pixdata *d, ptrdiff_t k)
{
    const ptrdiff_t w = d->w;
    const int *jid = d->jid + k;
    const float *adet = d->adet + k;
    const __m128i id = _mm_loadu_si128((const __m128i *)jid);
    const __m128 a = _mm_mul_ps(_mm_loadu_ps(adet), _mm_set1_ps(1.0f / OUTLIER));
    __m128 hit = _mm_or_ps(exceeds(jid, adet, -1, a, id), exceeds(jid, adet, 1, a, id));
    hit = _mm_or_ps(hit, _mm_or_ps(exceeds(jid, adet, -w, a, id), exceeds(jid, adet, w, a, id)));
    hit = _mm_andnot_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(id, _mm_set1_epi32(NO_ID))), hit);
    return _mm_movemask_ps(hit);
}
#endif

#if INTERNAL_X86
/* exceeds, eight pixels wide. */
__attribute__((target("avx2"))) static inline __m256 exceeds8(const int *jid, const float *adet,
                                                              ptrdiff_t s, __m256 a, __m256i id)
{
    const __m256i same = _mm256_cmpeq_epi32(_mm256_loadu_si256((const __m256i *)(jid + s)), id);
    return _mm256_and_ps(_mm256_cmp_ps(a, _mm256_loadu_ps(adet + s), _CMP_GT_OQ),
                         _mm256_castsi256_ps(same));
}

/* The pixels of a row from column x (pixel k) up to xb, whose neighbours are all held, eight at
 * a time: outlier_mask4's test for eight, then outlier_source for the pixels it leaves, which
 * are recorded as the baseline loop records them. Returns the column it stopped at. */
__attribute__((target("avx2"))) static int outlier_run_avx2(fixlist *fl, ptrdiff_t k, int x, int xb,
                                                            int up, int down)
{
    const pixdata *d = fl->d;
    const ptrdiff_t w = d->w;
    const __m256i none = _mm256_set1_epi32(NO_ID);
    const __m256 eighth = _mm256_set1_ps(1.0f / OUTLIER);
    for (; x + 8 <= xb; x += 8, k += 8) {
        const int *jid = d->jid + k;
        const float *adet = d->adet + k;
        const __m256i id = _mm256_loadu_si256((const __m256i *)jid);
        const __m256 a = _mm256_mul_ps(_mm256_loadu_ps(adet), eighth);
        __m256 hit = _mm256_or_ps(exceeds8(jid, adet, -1, a, id), exceeds8(jid, adet, 1, a, id));
        hit = _mm256_or_ps(
            hit, _mm256_or_ps(exceeds8(jid, adet, -w, a, id), exceeds8(jid, adet, w, a, id)));
        hit = _mm256_andnot_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(id, none)), hit);
        for (int m = _mm256_movemask_ps(hit), i = 0; m; i++, m >>= 1) {
            const int n = m & 1 ? outlier_source(d, k + i, x + i, up, down) : 0;
            if (n) record_fix(fl, (size_t)(k + i), n - 1);
        }
    }
    return x;
}
#endif

/* Such a pixel takes the surface of that neighbour instead: its UV extrapolated from the
 * neighbour's UV and derivatives, and those derivatives, so it owns its share of the surface
 * like the pixels around (and is marked OK_SEAM, so the corners it shares with the other side
 * of a seam are checked). Every repair is computed from the values before any repair, on M,
 * from the derivatives of D1 (M plus 1) as computed: the same whatever the units. The search
 * records each repair as it finds it (the values are all read before any is stored), four
 * pixels at a time where SSE2 is there: a group none of whose pixels is an outlier, the usual
 * case, is done with one test. */
void internal_stipple_repair_outliers(pixdata *d, nprfx_rect M, int avx2)
{
    fixlist fl = {d, 0, 0};
#if defined(__SSE2__)
    /* the columns whose left and right neighbours are held */
    const int xa = M.x0 - 1 >= d->r.x0 ? M.x0 : d->r.x0 + 1;
    const int xb = M.x1 + 1 <= d->r.x1 ? M.x1 : d->r.x1 - 1;
#endif
    for (int y = M.y0; y < M.y1; y++) {
        const int up = y - 1 >= d->r.y0, down = y + 1 < d->r.y1;
        const ptrdiff_t k0 = (ptrdiff_t)pd_at(d, M.x0, y);
        int x = M.x0;
#if defined(__SSE2__)
        if (up && down) {
            for (; x < xa; x++) {
                const int n = outlier_source(d, k0 + (x - M.x0), x, up, down);
                if (n) record_fix(&fl, (size_t)(k0 + (x - M.x0)), n - 1);
            }
#if INTERNAL_X86
            if (avx2) x = outlier_run_avx2(&fl, k0 + (x - M.x0), x, xb, up, down);
#endif
            for (; x + 4 <= xb; x += 4) {
                const ptrdiff_t k = k0 + (x - M.x0);
                for (int m = outlier_mask4(d, k), i = 0; m; i++, m >>= 1) {
                    const int n = m & 1 ? outlier_source(d, k + i, x + i, up, down) : 0;
                    if (n) record_fix(&fl, (size_t)(k + i), n - 1);
                }
            }
        }
#endif
        for (; x < M.x1; x++) {
            const int n = outlier_source(d, k0 + (x - M.x0), x, up, down);
            if (n) record_fix(&fl, (size_t)(k0 + (x - M.x0)), n - 1);
        }
    }
    const fix *fx = d->fixes;
    if (fl.failed) { /* no room for them all: drop them instead (they own nothing) */
        for (size_t i = 0; i < fl.n; i++)
            d->ok[fx[i].k] |= OK_DROP;
        for (int y = M.y0; y < M.y1; y++) {
            size_t k = pd_at(d, M.x0, y);
            for (int x = M.x0; x < M.x1; x++, k++)
                if (d->ok[k] & OK_DROP)
                    d->jid[k] = NO_ID, d->ok[k] &= (unsigned char)~(OK_J | OK_DROP);
        }
        return;
    }
    for (size_t i = 0; i < fl.n; i++) {
        size_t k = fx[i].k;
        d->su[k] = fx[i].su;
        d->sv[k] = fx[i].sv;
        memcpy(d->jac + 4 * k, fx[i].jac, sizeof fx[i].jac);
        d->adet[k] = fx[i].adet;
        d->ok[k] |= OK_SEAM;
    }
}
