/* The UV Jacobian of the stipple renderer's per-pixel data: finite differences that do not
 * straddle object edges or UV seams (internal_stipple_fill_jacobian). stipple_pixels.c reads the
 * inputs and builds the corner grid; stipple_outliers.c repairs the silhouette pixels whose
 * Jacobian is an outlier, and stipple_smooth.c smooths the area scale |det J| the thresholds
 * read. The fast-loop rule holds in all three: SSE2 lanes do the scalar code's operations in its
 * order, and the scalar code is the reference at edges, seams and NaNs. Where the CPU has AVX2,
 * the Jacobian takes four pixels a vector (its largest pass with uv and id inputs, 15% of a
 * render), with the same operations lane by lane (sjob.avx2; the simd param picks the baseline
 * loops for the tests). */
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

/* One column of the Jacobian at pixel k along a neighbour `step` away, given which of the
 * neighbours k + step (hf) and k - step (hb) are usable (same object, with a UV): differences
 * to those; central where both sides agree, else the smaller one-sided difference (a UV seam
 * gives a jump on one side only). Returns 0 when no neighbour qualifies, 2 when the sides
 * disagree. */
static inline int derivative(const double *su, const double *sv, size_t k, size_t step, int hf,
                             int hb, double *du, double *dv)
{
    double fu = 0, fv = 0, bu = 0, bv = 0;
    if (hf) {
        fu = su[k + step] - su[k];
        fv = sv[k + step] - sv[k];
    }
    if (hb) {
        bu = su[k] - su[k - step];
        bv = sv[k] - sv[k - step];
    }
    if (hf && hb) {
        double nf = fu * fu + fv * fv, nb = bu * bu + bv * bv;
        if (nf <= 4.0 * nb && nb <= 4.0 * nf) {
            *du = 0.5 * (fu + bu);
            *dv = 0.5 * (fv + bv);
            return 1;
        }
        if (nf < nb)
            *du = fu, *dv = fv;
        else
            *du = bu, *dv = bv;
        return 2;
    }
    if (hf) {
        *du = fu, *dv = fv;
        return 1;
    }
    if (hb) {
        *du = bu, *dv = bv;
        return 1;
    }
    return 0;
}

/* The Jacobian of pixel (x, y) at k (the reference for the fast path below). */
static void jac_pixel(pixdata *d, size_t k, int x, int up, int down)
{
    const size_t w = (size_t)d->w;
    const int *ids = d->id;
    d->jid[k] = NO_ID;
    if (!(d->ok[k] & OK_UV)) return;
    const int id = ids[k];
    double ux, vx, uy, vy;
    int ex = derivative(d->su, d->sv, k, 1, x + 1 < d->r.x1 && ids[k + 1] == id,
                        x - 1 >= d->r.x0 && ids[k - 1] == id, &ux, &vx);
    int ey =
        derivative(d->su, d->sv, k, w, down && ids[k + w] == id, up && ids[k - w] == id, &uy, &vy);
    if (!ex || !ey) return;
    if (ex == 2 || ey == 2) d->ok[k] |= OK_SEAM;
    float *jc = d->jac + 4 * k;
    jc[0] = (float)ux;
    jc[1] = (float)uy;
    jc[2] = (float)vx;
    jc[3] = (float)vy;
    double det = (double)jc[0] * jc[3] - (double)jc[1] * jc[2];
    d->adet[k] = (float)fabs(det);
    if (det != 0.0 && isfinite(det) && d->adet[k] > 0) {
        d->ok[k] |= OK_J;
        d->jid[k] = id;
    }
}

#if defined(__SSE2__)
/* The arrays fill_jacobian's fast path uses, held in registers across the byte stores to ok
 * (which could otherwise alias every pointer of the pixdata). */
typedef struct jacview {
    const double *su, *sv;
    const int *id;
    float *jac, *adet;
    int *jid;
    unsigned char *ok;
    size_t w;
} jacview;

/* For pixels k .. k + 3 (one lane each, their ids in id): do the four neighbours share the
 * pixel's id, and has it a UV? -1 in the lanes where so. */
static inline __m128i same_around(const jacview *v, size_t k, __m128i id)
{
    const int *p = v->id + k;
    const ptrdiff_t w = (ptrdiff_t)v->w;
    __m128i same = _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(p - 1)), id);
    same = _mm_and_si128(same, _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(p + 1)), id));
    same = _mm_and_si128(same, _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(p - w)), id));
    same = _mm_and_si128(same, _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(p + w)), id));
    return _mm_andnot_si128(_mm_cmpeq_epi32(id, _mm_set1_epi32(NO_ID)), same);
}

/* jac_pixel for pixels k and k + 1 (one lane each, ids in the low lanes of id) whose
 * neighbours all share their id, where both sides agree in x and in y for both (the usual
 * case). Returns 0, having written nothing, where they do not. */
static inline int jac_lanes(const jacview *v, size_t k, __m128i id)
{
    const size_t w = v->w;
    const double *su = v->su + k, *sv = v->sv + k;
    const __m128d u0 = _mm_loadu_pd(su), v0 = _mm_loadu_pd(sv), four = _mm_set1_pd(4.0);
    const __m128d half = _mm_set1_pd(0.5);
    /* x: forward and backward differences, their squared lengths, the agreement test */
    __m128d fu = _mm_sub_pd(_mm_loadu_pd(su + 1), u0), fv = _mm_sub_pd(_mm_loadu_pd(sv + 1), v0);
    __m128d bu = _mm_sub_pd(u0, _mm_loadu_pd(su - 1)), bv = _mm_sub_pd(v0, _mm_loadu_pd(sv - 1));
    __m128d nf = _mm_add_pd(_mm_mul_pd(fu, fu), _mm_mul_pd(fv, fv));
    __m128d nb = _mm_add_pd(_mm_mul_pd(bu, bu), _mm_mul_pd(bv, bv));
    __m128d agree =
        _mm_and_pd(_mm_cmple_pd(nf, _mm_mul_pd(four, nb)), _mm_cmple_pd(nb, _mm_mul_pd(four, nf)));
    const __m128d ux = _mm_mul_pd(half, _mm_add_pd(fu, bu)),
                  vx = _mm_mul_pd(half, _mm_add_pd(fv, bv));
    /* y */
    fu = _mm_sub_pd(_mm_loadu_pd(su + w), u0), fv = _mm_sub_pd(_mm_loadu_pd(sv + w), v0);
    bu = _mm_sub_pd(u0, _mm_loadu_pd(su - w)), bv = _mm_sub_pd(v0, _mm_loadu_pd(sv - w));
    nf = _mm_add_pd(_mm_mul_pd(fu, fu), _mm_mul_pd(fv, fv));
    nb = _mm_add_pd(_mm_mul_pd(bu, bu), _mm_mul_pd(bv, bv));
    agree = _mm_and_pd(agree, _mm_and_pd(_mm_cmple_pd(nf, _mm_mul_pd(four, nb)),
                                         _mm_cmple_pd(nb, _mm_mul_pd(four, nf))));
    if (_mm_movemask_pd(agree) != 3) return 0;
    const __m128d uy = _mm_mul_pd(half, _mm_add_pd(fu, bu)),
                  vy = _mm_mul_pd(half, _mm_add_pd(fv, bv));
    /* the floats, stored as jac_pixel orders them: ux uy vx vy a pixel */
    const __m128 fux = _mm_cvtpd_ps(ux), fuy = _mm_cvtpd_ps(uy), fvx = _mm_cvtpd_ps(vx);
    const __m128 fvy = _mm_cvtpd_ps(vy);
    const __m128 lu = _mm_unpacklo_ps(fux, fuy), lv = _mm_unpacklo_ps(fvx, fvy);
    _mm_storeu_ps(v->jac + 4 * k, _mm_movelh_ps(lu, lv));
    _mm_storeu_ps(v->jac + 4 * k + 4, _mm_movehl_ps(lv, lu));
    /* det from the stored floats, |det|, and the usability test */
    const __m128d det = _mm_sub_pd(_mm_mul_pd(_mm_cvtps_pd(fux), _mm_cvtps_pd(fvy)),
                                   _mm_mul_pd(_mm_cvtps_pd(fuy), _mm_cvtps_pd(fvx)));
    const __m128d adet = _mm_andnot_pd(_mm_set1_pd(-0.0), det);
    const __m128 fadet = _mm_cvtpd_ps(adet);
    _mm_storel_pi((__m64 *)(v->adet + k), fadet);
    /* usable: det finite (|det| <= DBL_MAX) and |det| > 0 as a float (which implies
     * det != 0); the pixels had OK_UV only */
    const __m128d dm = _mm_cmple_pd(adet, _mm_set1_pd(1.79769313486231570815e308));
    const __m128i usable =
        _mm_and_si128(_mm_shuffle_epi32(_mm_castpd_si128(dm), _MM_SHUFFLE(3, 1, 2, 0)),
                      _mm_castps_si128(_mm_cmpgt_ps(fadet, _mm_setzero_ps())));
    _mm_storel_epi64(
        (__m128i *)(v->jid + k),
        _mm_or_si128(_mm_and_si128(usable, id), _mm_andnot_si128(usable, _mm_set1_epi32(NO_ID))));
    /* the two ok bytes in one store (x86 is little-endian): OK_UV, and OK_J where usable */
    const unsigned bits = (unsigned)_mm_movemask_ps(_mm_castsi128_ps(usable));
    const uint16_t okw =
        (uint16_t)((OK_UV | OK_UV << 8) | (bits & 1u) * OK_J | (bits & 2u) * (OK_J << 7));
    memcpy(v->ok + k, &okw, sizeof okw);
    return 1;
}

/* jac_pixel for pixels k .. k + 3, whose neighbours are all held: the id tests four at a
 * time, the rest by pairs, each pair not in the usual case going to jac_pixel. */
static inline void jac_quad(pixdata *d, const jacview *v, size_t k, int x)
{
    const __m128i id = _mm_loadu_si128((const __m128i *)(v->id + k));
    const int m = _mm_movemask_epi8(same_around(v, k, id));
    for (int h = 0; h < 2; h++) {
        const size_t kh = k + 2 * (size_t)h;
        const __m128i idh = h ? _mm_unpackhi_epi64(id, id) : id;
        if (((m >> (8 * h)) & 0xff) != 0xff || !jac_lanes(v, kh, idh)) {
            jac_pixel(d, kh, x + 2 * h, 1, 1);
            jac_pixel(d, kh + 1, x + 2 * h + 1, 1, 1);
        }
    }
}

/* The quads of a row whose neighbours are all held, from column x (pixel k) up to xb: the
 * baseline loop. Returns the column it stopped at. */
static int jac_quads(pixdata *d, const jacview *v, size_t k, int x, int xb)
{
    for (; x + 4 <= xb; x += 4, k += 4)
        jac_quad(d, v, k, x);
    return x;
}
#endif

#if INTERNAL_X86
/* The four lane masks of a 4 x 64-bit mask, as 4 x 32 bits (each lane's low half). */
__attribute__((target("avx2"))) static inline __m128i narrow_mask(__m256d m)
{
    const __m128 lo = _mm_castpd_ps(_mm256_castpd256_pd128(m));
    const __m128 hi = _mm_castpd_ps(_mm256_extractf128_pd(m, 1));
    return _mm_castps_si128(_mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0)));
}

/* One direction of jac_lanes4 (neighbours `step` away): the central differences (du, dv),
 * and -1 in the lanes where both sides agree, as derivative() computes them. */
__attribute__((target("avx2"))) static inline __m256d
central4(const double *su, const double *sv, ptrdiff_t step, __m256d *du, __m256d *dv)
{
    const __m256d u0 = _mm256_loadu_pd(su), v0 = _mm256_loadu_pd(sv);
    const __m256d four = _mm256_set1_pd(4.0), half = _mm256_set1_pd(0.5);
    const __m256d fu = _mm256_sub_pd(_mm256_loadu_pd(su + step), u0);
    const __m256d fv = _mm256_sub_pd(_mm256_loadu_pd(sv + step), v0);
    const __m256d bu = _mm256_sub_pd(u0, _mm256_loadu_pd(su - step));
    const __m256d bv = _mm256_sub_pd(v0, _mm256_loadu_pd(sv - step));
    const __m256d nf = _mm256_add_pd(_mm256_mul_pd(fu, fu), _mm256_mul_pd(fv, fv));
    const __m256d nb = _mm256_add_pd(_mm256_mul_pd(bu, bu), _mm256_mul_pd(bv, bv));
    *du = _mm256_mul_pd(half, _mm256_add_pd(fu, bu));
    *dv = _mm256_mul_pd(half, _mm256_add_pd(fv, bv));
    return _mm256_and_pd(_mm256_cmp_pd(nf, _mm256_mul_pd(four, nb), _CMP_LE_OQ),
                         _mm256_cmp_pd(nb, _mm256_mul_pd(four, nf), _CMP_LE_OQ));
}

/* jac_lanes for pixels k .. k + 3 (one lane each, ids in id), whose neighbours all share
 * their id: the same operations four lanes wide. Returns 0, having written nothing, unless
 * both sides agree in x and in y for all four. */
__attribute__((target("avx2"))) static inline int jac_lanes4(const jacview *v, size_t k, __m128i id)
{
    const double *su = v->su + k, *sv = v->sv + k;
    __m256d ux, vx, uy, vy;
    const __m256d agree =
        _mm256_and_pd(central4(su, sv, 1, &ux, &vx), central4(su, sv, (ptrdiff_t)v->w, &uy, &vy));
    if (_mm256_movemask_pd(agree) != 15) return 0;
    /* the floats, stored as jac_pixel orders them: ux uy vx vy a pixel (a 4 x 4 transpose) */
    const __m128 fux = _mm256_cvtpd_ps(ux), fuy = _mm256_cvtpd_ps(uy);
    const __m128 fvx = _mm256_cvtpd_ps(vx), fvy = _mm256_cvtpd_ps(vy);
    const __m128 lu = _mm_unpacklo_ps(fux, fuy), lv = _mm_unpacklo_ps(fvx, fvy);
    const __m128 hu = _mm_unpackhi_ps(fux, fuy), hv = _mm_unpackhi_ps(fvx, fvy);
    float *jc = v->jac + 4 * k;
    _mm_storeu_ps(jc, _mm_movelh_ps(lu, lv));
    _mm_storeu_ps(jc + 4, _mm_movehl_ps(lv, lu));
    _mm_storeu_ps(jc + 8, _mm_movelh_ps(hu, hv));
    _mm_storeu_ps(jc + 12, _mm_movehl_ps(hv, hu));
    /* det from the stored floats (products of floats as doubles are exact), |det|, and
     * jac_lanes' usability test */
    const __m256d det = _mm256_sub_pd(_mm256_mul_pd(_mm256_cvtps_pd(fux), _mm256_cvtps_pd(fvy)),
                                      _mm256_mul_pd(_mm256_cvtps_pd(fuy), _mm256_cvtps_pd(fvx)));
    const __m256d adet = _mm256_andnot_pd(_mm256_set1_pd(-0.0), det);
    const __m128 fadet = _mm256_cvtpd_ps(adet);
    _mm_storeu_ps(v->adet + k, fadet);
    const __m256d dm = _mm256_cmp_pd(adet, _mm256_set1_pd(1.79769313486231570815e308), _CMP_LE_OQ);
    const __m128i usable =
        _mm_and_si128(narrow_mask(dm), _mm_castps_si128(_mm_cmpgt_ps(fadet, _mm_setzero_ps())));
    _mm_storeu_si128((__m128i *)(v->jid + k), _mm_blendv_epi8(_mm_set1_epi32(NO_ID), id, usable));
    /* the four ok bytes in one store (x86 is little-endian): OK_UV, and OK_J where usable */
    const uint32_t bits = (uint32_t)_mm_movemask_ps(_mm_castsi128_ps(usable));
    const uint32_t spread = (bits & 1u) | (bits & 2u) << 7 | (bits & 4u) << 14 | (bits & 8u) << 21;
    const uint32_t okw = (uint32_t)OK_UV * 0x01010101u | spread * (uint32_t)OK_J;
    memcpy(v->ok + k, &okw, sizeof okw);
    return 1;
}

/* jac_quads with AVX2: a quad whose pixels all have their four neighbours in their object and
 * agree on both sides goes through jac_lanes4, any other through jac_quad (pairs, then
 * jac_pixel), whose results are the same. */
__attribute__((target("avx2"))) static int jac_quads_avx2(pixdata *d, const jacview *v, size_t k,
                                                          int x, int xb)
{
    for (; x + 4 <= xb; x += 4, k += 4) {
        const __m128i id = _mm_loadu_si128((const __m128i *)(v->id + k));
        if (_mm_movemask_epi8(same_around(v, k, id)) != 0xffff || !jac_lanes4(v, k, id))
            jac_quad(d, v, k, x);
    }
    return x;
}
#endif

#if defined(__SSE2__)
/* Two floats from p into the low lanes (an 8-byte load that may alias anything). */
static inline __m128 load_2f(const float *p)
{
    return _mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)p));
}
#endif

/* fill_jacobian where the held pixels are a plane (pixdata.plane): every pixel has a UV and
 * object 0; su is the same in every row and sv the same along a row. So the x differences of
 * a column are the same in every row (those of sv exactly 0), and the y differences of a row
 * the same in every column (those of su exactly 0): derivative() gives the same values, and
 * jac_pixel the same floats, computed once per column and once per row (the reference code
 * on row r.y0 and column r.x0), then per pixel only the determinant and the stores. The
 * per-pixel differences were the largest pass of a render without a uv input. 0 when out of
 * memory (nothing written: the caller takes the general path). */
static int plane_jacobian(pixdata *d, nprfx_rect r)
{
    const int nx = nprfx_rect_width(r), ny = nprfx_rect_height(r);
    if (nx <= 0 || ny <= 0) return 1;
    float *f = malloc(sizeof(float) * 2 * ((size_t)nx + (size_t)ny));
    unsigned char *e = malloc((size_t)nx + (size_t)ny);
    if (!f || !e) {
        free(f);
        free(e);
        return 0;
    }
    float *fux = f, *fvx = f + nx, *fuy = f + 2 * (size_t)nx, *fvy = fuy + ny;
    unsigned char *ex = e, *ey = e + nx;
    const size_t w = (size_t)d->w;
    for (int x = r.x0; x < r.x1; x++) {
        double du = 0, dv = 0;
        const int i = x - r.x0;
        ex[i] = (unsigned char)derivative(d->su, d->sv, pd_at(d, x, r.y0), 1, x + 1 < d->r.x1,
                                          x - 1 >= d->r.x0, &du, &dv);
        fux[i] = (float)du;
        fvx[i] = (float)dv;
    }
    for (int y = r.y0; y < r.y1; y++) {
        double du = 0, dv = 0;
        const int i = y - r.y0;
        ey[i] = (unsigned char)derivative(d->su, d->sv, pd_at(d, r.x0, y), w, y + 1 < d->r.y1,
                                          y - 1 >= d->r.y0, &du, &dv);
        fuy[i] = (float)du;
        fvy[i] = (float)dv;
    }
    /* whether every column has a derivative: then a row whose own has one is the usual row */
    int cols_all = 1;
    for (int i = 0; i < nx; i++)
        cols_all &= ex[i] != 0;
    for (int y = r.y0; y < r.y1; y++) {
        const size_t k0 = pd_at(d, r.x0, y);
        const int j = y - r.y0;
        float *restrict jac = d->jac + 4 * k0, *restrict adet = d->adet + k0;
        int *restrict jid = d->jid + k0;
        unsigned char *restrict ok = d->ok + k0;
        const int *restrict id = d->id + k0;
        int i = 0;
#if defined(__SSE2__)
        if (cols_all && ey[j]) {
            /* two at a time: the stored floats, det from them as jac_pixel orders it (a
             * product of floats as doubles is exact, so the order of its factors does not
             * matter), and jac_lanes' usability test */
            const __m128d uy = _mm_set1_pd((double)fuy[j]), vy = _mm_set1_pd((double)fvy[j]);
            const __m128d dmax = _mm_set1_pd(1.79769313486231570815e308);
            const __m128i none = _mm_set1_epi32(NO_ID);
            const unsigned char seam_row = ey[j] == 2 ? OK_SEAM : 0;
            for (; i + 2 <= nx; i += 2) {
                const __m128 ux2 = load_2f(fux + i), vx2 = load_2f(fvx + i);
                const __m128 lu = _mm_unpacklo_ps(ux2, _mm_set1_ps(fuy[j]));
                const __m128 lv = _mm_unpacklo_ps(vx2, _mm_set1_ps(fvy[j]));
                _mm_storeu_ps(jac + 4 * (size_t)i, _mm_movelh_ps(lu, lv));
                _mm_storeu_ps(jac + 4 * (size_t)i + 4, _mm_movehl_ps(lv, lu));
                const __m128d det = _mm_sub_pd(_mm_mul_pd(_mm_cvtps_pd(ux2), vy),
                                               _mm_mul_pd(uy, _mm_cvtps_pd(vx2)));
                const __m128d ad = _mm_andnot_pd(_mm_set1_pd(-0.0), det);
                const __m128 fad = _mm_cvtpd_ps(ad);
                _mm_storel_pi((__m64 *)(adet + i), fad);
                const __m128i usable =
                    _mm_and_si128(_mm_shuffle_epi32(_mm_castpd_si128(_mm_cmple_pd(ad, dmax)),
                                                    _MM_SHUFFLE(3, 1, 2, 0)),
                                  _mm_castps_si128(_mm_cmpgt_ps(fad, _mm_setzero_ps())));
                const __m128i idv = _mm_loadl_epi64((const __m128i *)(id + i));
                _mm_storel_epi64(
                    (__m128i *)(jid + i),
                    _mm_or_si128(_mm_and_si128(usable, idv), _mm_andnot_si128(usable, none)));
                const int bits = _mm_movemask_ps(_mm_castsi128_ps(usable));
                ok[i] |=
                    (unsigned char)((ex[i] == 2 ? OK_SEAM : 0) | seam_row | (bits & 1 ? OK_J : 0));
                ok[i + 1] |= (unsigned char)((ex[i + 1] == 2 ? OK_SEAM : 0) | seam_row |
                                             (bits & 2 ? OK_J : 0));
            }
        }
#endif
        for (; i < nx; i++) {
            jid[i] = NO_ID;
            if (!ex[i] || !ey[j]) continue;
            if (ex[i] == 2 || ey[j] == 2) ok[i] |= OK_SEAM;
            float *jc = jac + 4 * (size_t)i;
            jc[0] = fux[i];
            jc[1] = fuy[j];
            jc[2] = fvx[i];
            jc[3] = fvy[j];
            const double det = (double)jc[0] * jc[3] - (double)jc[1] * jc[2];
            adet[i] = (float)fabs(det);
            if (det != 0.0 && isfinite(det) && adet[i] > 0) {
                ok[i] |= OK_J;
                jid[i] = id[i];
            }
        }
    }
    free(f);
    free(e);
    return 1;
}

/* The Jacobian, |det J|, OK_J, OK_SEAM and jid (NO_ID where not usable) over r. */
void internal_stipple_fill_jacobian(pixdata *d, nprfx_rect r, int avx2)
{
    if (d->plane && plane_jacobian(d, r)) return;
#if defined(__SSE2__)
    /* the columns whose left and right neighbours are held */
    const int xa = r.x0 - 1 >= d->r.x0 ? r.x0 : d->r.x0 + 1;
    const int xb = r.x1 + 1 <= d->r.x1 ? r.x1 : d->r.x1 - 1;
    const jacview v = {d->su, d->sv, d->id, d->jac, d->adet, d->jid, d->ok, (size_t)d->w};
#endif
    for (int y = r.y0; y < r.y1; y++) {
        const int up = y - 1 >= d->r.y0, down = y + 1 < d->r.y1;
        const size_t k0 = pd_at(d, r.x0, y);
        int x = r.x0;
#if defined(__SSE2__)
        if (up && down) {
            for (; x < xa; x++)
                jac_pixel(d, k0 + (size_t)(x - r.x0), x, up, down);
            const size_t k = k0 + (size_t)(x - r.x0);
#if INTERNAL_X86
            if (avx2)
                x = jac_quads_avx2(d, &v, k, x, xb);
            else
#endif
                x = jac_quads(d, &v, k, x, xb);
        }
#endif
        for (; x < r.x1; x++)
            jac_pixel(d, k0 + (size_t)(x - r.x0), x, up, down);
    }
}
