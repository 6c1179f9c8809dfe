/* Spatial index over the IVS sequence: one uniform grid per power-of-two prefix.
 *
 * A query for samples i <= limit reads level L = ceil(log2(limit)), which holds the first 2^L
 * points (so at least half of what it reads is wanted) at about two points per cell, and only
 * the cells its rectangle touches: the cost follows the answer, not the sequence length. The
 * cells of a grid row are stored one after the other, so each row the rectangle touches is one
 * run of entries (per tile it crosses), scanned a fixed number of entries at a time without a
 * branch per entry: queries are small (a stipple block's finds a handful of samples), and
 * there branches that do not predict cost more than the entries past the limit they would
 * skip. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "internal_ivs.h"
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if INTERNAL_X86
#include <immintrin.h>
#endif

/* Points per cell of a level's grid, about: coarser grids scan more entries outside the
 * rectangle, finer ones more rows and cells (no better either way for stipple queries). */
#define IVS_POINTS_PER_CELL 2.0

/* Entries a scan tests at once, whatever the run's length (see scan_run). */
#define SCAN_STEP 8

/* A level's entries are cell by cell in row-major order of the cells, each cell in sequence
 * order, as two parallel arrays (positions, indices), followed by SCAN_STEP entries of padding
 * that no query admits. */
typedef struct ivs_level {
    int count;  /* points in this prefix */
    int grid;   /* cells per side */
    int *start; /* grid*grid + 1 offsets into the entries */
    float *xy;  /* x, y of each entry */
    int32_t *index;
} ivs_level;

struct nprfx_ivs_index {
    int count;
    float *xy;
    int num_levels;
    ivs_level *levels;
};

/* Exact: a float times a grid size below 2^15 fits a double's mantissa, so a query can tell
 * which cell a point is in from the same product. */
static int cell_of(float v, int grid)
{
    int c = (int)floor((double)v * (double)grid);
    return c < 0 ? 0 : c >= grid ? grid - 1 : c;
}

static int build_level(ivs_level *lv, const float *xy, int count)
{
    int grid = (int)floor(sqrt(count / IVS_POINTS_PER_CELL));
    if (grid < 1) grid = 1;
    lv->count = count;
    lv->grid = grid;
    size_t cells = (size_t)grid * (size_t)grid;
    lv->start = calloc(cells + 1, sizeof(int));
    /* the padding: a scan reads whole steps */
    lv->xy = malloc((size_t)(count + SCAN_STEP) * 2 * sizeof(float));
    lv->index = malloc((size_t)(count + SCAN_STEP) * sizeof(int32_t));
    if (!lv->start || !lv->xy || !lv->index) return 0;
    for (int i = count; i < count + SCAN_STEP; i++) {
        lv->xy[2 * i] = lv->xy[2 * i + 1] = 0;
        lv->index[i] = INT32_MAX;
    }
    /* counting sort by cell; stable, so each cell stays in sequence order */
    for (int i = 0; i < count; i++) {
        size_t c = (size_t)cell_of(xy[2 * i + 1], grid) * grid + cell_of(xy[2 * i], grid);
        lv->start[c + 1]++;
    }
    for (size_t c = 0; c < cells; c++)
        lv->start[c + 1] += lv->start[c];
    int *fill = malloc(cells * sizeof(int));
    if (!fill) return 0;
    memcpy(fill, lv->start, cells * sizeof(int));
    for (int i = 0; i < count; i++) {
        size_t c = (size_t)cell_of(xy[2 * i + 1], grid) * grid + cell_of(xy[2 * i], grid);
        int e = fill[c]++;
        lv->xy[2 * e] = xy[2 * i];
        lv->xy[2 * e + 1] = xy[2 * i + 1];
        lv->index[e] = i;
    }
    free(fill);
    return 1;
}

nprfx_result nprfx_ivs_index_create(nprfx_context *ctx, const float *xy, int n,
                                    nprfx_ivs_index **out)
{
    if (!out || !xy || n < 1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "ivs index: need n >= 1 points");
    *out = NULL;
    nprfx_ivs_index *ix = calloc(1, sizeof *ix);
    if (!ix) goto oom;
    ix->count = n;
    ix->xy = malloc((size_t)n * 2 * sizeof(float));
    if (!ix->xy) goto oom;
    memcpy(ix->xy, xy, (size_t)n * 2 * sizeof(float));
    int levels = 1;
    while (levels < 31 && (1 << (levels - 1)) < n)
        levels++;
    ix->levels = calloc((size_t)levels, sizeof(ivs_level));
    if (!ix->levels) goto oom;
    ix->num_levels = levels;
    for (int l = 0; l < levels; l++) {
        int count = l < 30 && (1 << l) < n ? (1 << l) : n;
        if (!build_level(&ix->levels[l], ix->xy, count)) goto oom;
    }
    *out = ix;
    return NPRFX_OK;
oom:
    nprfx_ivs_index_destroy(ix);
    return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "ivs index: out of memory for %d points", n);
}

void nprfx_ivs_index_destroy(nprfx_ivs_index *ix)
{
    if (!ix) return;
    for (int l = 0; ix->levels && l < ix->num_levels; l++) {
        free(ix->levels[l].start);
        free(ix->levels[l].xy);
        free(ix->levels[l].index);
    }
    free(ix->levels);
    free(ix->xy);
    free(ix);
}

int nprfx_ivs_index_count(const nprfx_ivs_index *ix)
{
    return ix ? ix->count : 0;
}

void nprfx_ivs_index_point(const nprfx_ivs_index *ix, int k, float *xy)
{
    xy[0] = ix->xy[2 * k];
    xy[1] = ix->xy[2 * k + 1];
}

static long long floor_div(long long a, long long b)
{
    long long q = a / b;
    return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

/* Samples found, handed over a batch at a time. */
#define SCAN_BATCH NPRFX_IVS_BATCH

typedef struct scan {
    int limit;
    double u0, v0, u1, v1;
    nprfx_ivs_batch_fn fn;
    void *user;
    int avx2; /* scan with scan_run_avx2 */
    int n;    /* samples waiting in the batch */
    long long found;
    int32_t index[SCAN_BATCH];
    double u[SCAN_BATCH], v[SCAN_BATCH];
} scan;

/* Hand the batch over; nonzero when the callback asks to stop. */
static int scan_flush(scan *q)
{
    int n = q->n;
    q->n = 0;
    q->found += n;
    return n && q->fn && q->fn(q->user, n, q->index, q->u, q->v);
}

/* Entries [e, e1) of a level, in tile (dtx, dty): those below the limit inside the rectangle go
 * into the batch. Without a branch per entry (whether one is kept does not predict), nor one
 * per run length (runs are short, and vary): SCAN_STEP entries at a time, those past the run
 * masked off (the levels are padded for them). Each is written at the end of the batch, which
 * only grows where one is kept; the batch is handed over before a step could overflow it. */
static int scan_run(scan *q, const ivs_level *lv, int e, int e1, double dtx, double dty)
{
    const int limit = q->limit;
    const double u0 = q->u0, v0 = q->v0, u1 = q->u1, v1 = q->v1;
    const float *xy = lv->xy;
    const int32_t *index = lv->index;
    int32_t *bi = q->index;
    double *bu = q->u, *bv = q->v;
#if defined(__SSE2__)
    /* two at a time: the same conversions, sums and comparisons */
    const __m128d du = _mm_set1_pd(dtx), dv = _mm_set1_pd(dty);
    const __m128d lu = _mm_set1_pd(u0), lv_ = _mm_set1_pd(v0);
    const __m128d hu = _mm_set1_pd(u1), hv = _mm_set1_pd(v1);
    const __m128i lim = _mm_set1_epi32(limit), lane = _mm_setr_epi32(0, 1, 0, 0);
#endif
    for (; e < e1; e += SCAN_STEP) {
        if (q->n > SCAN_BATCH - SCAN_STEP && scan_flush(q)) return 1;
        int n = q->n;
#if defined(__SSE2__)
        /* entries e + k with k < left */
        const __m128i left = _mm_set1_epi32(e1 - e);
        for (int k = 0; k < SCAN_STEP; k += 2) {
            const int a = e + k;
            /* x0 y0 x1 y1 -> x0 x1 y0 y1 */
            const __m128 p = _mm_shuffle_ps(_mm_loadu_ps(xy + 2 * a), _mm_loadu_ps(xy + 2 * a),
                                            _MM_SHUFFLE(3, 1, 2, 0));
            const __m128d u = _mm_add_pd(_mm_cvtps_pd(p), du);
            const __m128d v = _mm_add_pd(_mm_cvtps_pd(_mm_movehl_ps(p, p)), dv);
            const __m128i i = _mm_loadl_epi64((const __m128i *)(index + a));
            const __m128i ok =
                _mm_and_si128(_mm_cmplt_epi32(i, lim),
                              _mm_cmplt_epi32(_mm_add_epi32(lane, _mm_set1_epi32(k)), left));
            const __m128d in =
                _mm_and_pd(_mm_and_pd(_mm_cmpge_pd(u, lu), _mm_cmplt_pd(u, hu)),
                           _mm_and_pd(_mm_and_pd(_mm_cmpge_pd(v, lv_), _mm_cmplt_pd(v, hv)),
                                      _mm_castsi128_pd(_mm_unpacklo_epi32(ok, ok))));
            const int keep = _mm_movemask_pd(in);
            bi[n] = index[a];
            _mm_storel_pd(bu + n, u);
            _mm_storel_pd(bv + n, v);
            n += keep & 1;
            bi[n] = index[a + 1];
            _mm_storeh_pd(bu + n, u);
            _mm_storeh_pd(bv + n, v);
            n += keep >> 1;
        }
#else
        const int left = e1 - e;
        for (int k = 0; k < SCAN_STEP; k++) {
            const int32_t i = index[e + k];
            const double u = (double)xy[2 * (e + k)] + dtx, v = (double)xy[2 * (e + k) + 1] + dty;
            bi[n] = i;
            bu[n] = u;
            bv[n] = v;
            n += (k < left) & (i < limit) & (u >= u0) & (u < u1) & (v >= v0) & (v < v1);
        }
#endif
        q->n = n;
    }
    return 0;
}

#if INTERNAL_X86
/* scan_run with AVX2: four entries at a time, the same conversions, sums and comparisons. */
__attribute__((target("avx2"))) static int scan_run_avx2(scan *q, const ivs_level *lv, int e,
                                                         int e1, double dtx, double dty)
{
    const float *xy = lv->xy;
    const int32_t *index = lv->index;
    int32_t *bi = q->index;
    double *bu = q->u, *bv = q->v;
    const __m256d du = _mm256_set1_pd(dtx), dv = _mm256_set1_pd(dty);
    const __m256d lu = _mm256_set1_pd(q->u0), lv_ = _mm256_set1_pd(q->v0);
    const __m256d hu = _mm256_set1_pd(q->u1), hv = _mm256_set1_pd(q->v1);
    const __m128i lim = _mm_set1_epi32(q->limit), lane = _mm_setr_epi32(0, 1, 2, 3);
    /* x0 y0 .. x3 y3 -> x0 .. x3 y0 .. y3 */
    const __m256i split = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
    for (; e < e1; e += SCAN_STEP) {
        if (q->n > SCAN_BATCH - SCAN_STEP && scan_flush(q)) return 1;
        int n = q->n;
        /* entries e + k with k < left */
        const __m128i left = _mm_set1_epi32(e1 - e);
        for (int k = 0; k < SCAN_STEP; k += 4) {
            const int a = e + k;
            const __m256 p = _mm256_permutevar8x32_ps(_mm256_loadu_ps(xy + 2 * a), split);
            const __m256d u = _mm256_add_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(p)), du);
            const __m256d v = _mm256_add_pd(_mm256_cvtps_pd(_mm256_extractf128_ps(p, 1)), dv);
            const __m128i i = _mm_loadu_si128((const __m128i *)(index + a));
            const __m128i ok =
                _mm_and_si128(_mm_cmplt_epi32(i, lim),
                              _mm_cmplt_epi32(_mm_add_epi32(lane, _mm_set1_epi32(k)), left));
            const __m256d inu =
                _mm256_and_pd(_mm256_cmp_pd(u, lu, _CMP_GE_OQ), _mm256_cmp_pd(u, hu, _CMP_LT_OQ));
            const __m256d inv =
                _mm256_and_pd(_mm256_cmp_pd(v, lv_, _CMP_GE_OQ), _mm256_cmp_pd(v, hv, _CMP_LT_OQ));
            const int keep = _mm256_movemask_pd(_mm256_and_pd(
                _mm256_and_pd(inu, inv), _mm256_castsi256_pd(_mm256_cvtepi32_epi64(ok))));
            const __m128d u01 = _mm256_castpd256_pd128(u), u23 = _mm256_extractf128_pd(u, 1);
            const __m128d v01 = _mm256_castpd256_pd128(v), v23 = _mm256_extractf128_pd(v, 1);
            bi[n] = index[a];
            _mm_storel_pd(bu + n, u01);
            _mm_storel_pd(bv + n, v01);
            n += keep & 1;
            bi[n] = index[a + 1];
            _mm_storeh_pd(bu + n, u01);
            _mm_storeh_pd(bv + n, v01);
            n += keep >> 1 & 1;
            bi[n] = index[a + 2];
            _mm_storel_pd(bu + n, u23);
            _mm_storel_pd(bv + n, v23);
            n += keep >> 2 & 1;
            bi[n] = index[a + 3];
            _mm_storeh_pd(bu + n, u23);
            _mm_storeh_pd(bv + n, v23);
            n += keep >> 3;
        }
        q->n = n;
    }
    return 0;
}
#endif

/* floor(x) for -2^63 <= x < 2^63, as an integer (the conversion is defined there) */
static inline long long floor_ll(double x)
{
    long long t = (long long)x;
    return t - ((double)t > x);
}

/* a = q * g + r with 0 <= r < g; in 32 bits where a fits (the common case, and cheaper) */
static inline long long split_cell(long long a, int g, int *r)
{
    long long q;
    if (a >= INT32_MIN && a <= INT32_MAX) {
        int32_t a32 = (int32_t)a, q32 = a32 / g, r32 = a32 - q32 * g;
        if (r32 < 0) r32 += g, q32--;
        *r = r32;
        return q32;
    }
    q = floor_div(a, g);
    *r = (int)(a - q * g);
    return q;
}

/* The level a query reads and its cells, then every grid row the rectangle touches as one run
 * of entries per tile it crosses; the runs go in order of tile row, cell row, tile column, so
 * samples come by tile, then cell, then index. Nonzero when the callback stopped the scan. */
static int scan_query(const nprfx_ivs_index *ix, scan *q)
{
    const int limit = q->limit;
    /* the first level holding limit points: level l holds min(2^l, count) */
#if defined(__GNUC__) || defined(__clang__)
    int l = limit <= 1 ? 0 : 32 - __builtin_clz((unsigned)(limit - 1));
#else
    int l = 0;
    while (l < 30 && (1 << l) < limit)
        l++;
#endif
    if (l > 30) l = 30;
    if (l > ix->num_levels - 1) l = ix->num_levels - 1;
    while (l + 1 < ix->num_levels && ix->levels[l].count < limit) /* never, by the above */
        l++;
    const ivs_level *lv = &ix->levels[l];
    const int g = lv->grid;
    /* cells in the unbounded plane; cell c of the plane is cell (c mod g) of tile floor(c / g) */
    /* the products below may round across a cell edge: widen by far more than that */
    const double slack = 1e-7;
    const double fu0 = q->u0 * g - slack, fu1 = q->u1 * g + slack;
    const double fv0 = q->v0 * g - slack, fv1 = q->v1 * g + slack;
    /* beyond what cells can count (or NaN): refuse */
    const double far = 9223372036854775808.0; /* 2^63 */
    if (!(fu0 >= -far && fu1 < far && fv0 >= -far && fv1 < far)) return 0;
    const long long cx0 = floor_ll(fu0), cx1 = floor_ll(fu1);
    const long long cy0 = floor_ll(fv0), cy1 = floor_ll(fv1);
    /* absurd rectangles: refuse (the cells are whole doubles, so these are exact) */
    if (!((double)cx1 - (double)cx0 < 1e9 && (double)cy1 - (double)cy0 < 1e9)) return 0;
    /* cell (rx, ry) of tile (tx, ty), stepped without a division per cell */
    int rx0, ry;
    const long long tx0 = split_cell(cx0, g, &rx0);
    long long ty = split_cell(cy0, g, &ry);
    for (long long cy = cy0; cy <= cy1; cy++) {
        const double dty = (double)ty;
        const int *start = lv->start + (size_t)ry * g;
        long long tx = tx0;
        int rx = rx0;
        for (long long cx = cx0; cx <= cx1; tx++) {
            /* cells rx .. rx_end of tile tx: the rest of the row or the rest of this tile */
            int rx_end = cx1 - cx < (long long)(g - 1 - rx) ? rx + (int)(cx1 - cx) : g - 1;
            const int e = start[rx], e1 = start[rx_end + 1];
#if INTERNAL_X86
            const int stop = q->avx2 ? scan_run_avx2(q, lv, e, e1, (double)tx, dty)
                                     : scan_run(q, lv, e, e1, (double)tx, dty);
#else
            const int stop = scan_run(q, lv, e, e1, (double)tx, dty);
#endif
            if (stop) return 1;
            cx += rx_end - rx + 1;
            rx = 0;
        }
        if (++ry == g) {
            ry = 0;
            ty++;
        }
    }
    return 0;
}

long long internal_ivs_index_query_batch(const nprfx_ivs_index *ix, int limit, double u0, double v0,
                                         double u1, double v1, nprfx_ivs_batch_fn fn, void *user,
                                         int avx2)
{
    if (!ix || limit <= 0 || !(u1 > u0) || !(v1 > v0)) return 0;
    scan q;
    q.avx2 = avx2;
    q.limit = limit > ix->count ? ix->count : limit;
    q.u0 = u0;
    q.v0 = v0;
    q.u1 = u1;
    q.v1 = v1;
    q.fn = fn;
    q.user = user;
    q.n = 0;
    q.found = 0;
    if (!scan_query(ix, &q)) scan_flush(&q);
    return q.found;
}

long long nprfx_ivs_index_query_batch(const nprfx_ivs_index *ix, int limit, double u0, double v0,
                                      double u1, double v1, nprfx_ivs_batch_fn fn, void *user)
{
#if INTERNAL_X86
    const int avx2 = __builtin_cpu_supports("avx2");
#else
    const int avx2 = 0;
#endif
    return internal_ivs_index_query_batch(ix, limit, u0, v0, u1, v1, fn, user, avx2);
}

typedef struct visit_each {
    nprfx_ivs_visit_fn visit;
    void *user;
    long long visited; /* before the stop */
} visit_each;

static int visit_batch(void *user, int n, const int32_t *index, const double *u, const double *v)
{
    visit_each *w = user;
    for (int k = 0; k < n; k++) {
        w->visited++;
        if (w->visit(w->user, index[k], u[k], v[k])) return 1;
    }
    return 0;
}

long long nprfx_ivs_index_query(const nprfx_ivs_index *ix, int limit, double u0, double v0,
                                double u1, double v1, nprfx_ivs_visit_fn visit, void *user)
{
    if (!visit) return nprfx_ivs_index_query_batch(ix, limit, u0, v0, u1, v1, NULL, NULL);
    visit_each w = {visit, user, 0};
    nprfx_ivs_index_query_batch(ix, limit, u0, v0, u1, v1, visit_batch, &w);
    return w.visited;
}
