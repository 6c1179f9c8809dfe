/* The IVS sequence (docs/design.md §3.3): spacing of every prefix, the farthest-point property,
 * determinism, the encoded form, and the spatial index. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "nprfx/context.h"
#include "nprfx/ivs.h"
#include "nprfx/rng.h"

#define N 20000
#define SEED 12345u
#define WARMUP 16 /* r_i * sqrt(i) is checked for i > WARMUP */

/* ---- a uniform grid on the torus for nearest-neighbour distances ---- */

typedef struct grid {
    int g;
    int *head, *next;
    const float *xy;
} grid;

static void grid_build(grid *gr, const float *xy, int n)
{
    gr->g = (int)sqrt(n / 2.0);
    if (gr->g < 1) gr->g = 1;
    gr->xy = xy;
    gr->head = malloc(sizeof(int) * (size_t)gr->g * gr->g);
    gr->next = malloc(sizeof(int) * (size_t)n);
    for (int i = 0; i < gr->g * gr->g; i++)
        gr->head[i] = -1;
    for (int i = 0; i < n; i++) {
        int cx = (int)(xy[2 * i] * gr->g) % gr->g, cy = (int)(xy[2 * i + 1] * gr->g) % gr->g;
        gr->next[i] = gr->head[cy * gr->g + cx];
        gr->head[cy * gr->g + cx] = i;
    }
}

static void grid_free(grid *gr)
{
    free(gr->head);
    free(gr->next);
}

static double torus_d2(double ax, double ay, double bx, double by)
{
    double dx = ax - bx, dy = ay - by;
    dx -= floor(dx + 0.5);
    dy -= floor(dy + 0.5);
    return dx * dx + dy * dy;
}

/* Distance from (x, y) to the nearest point other than `skip`, searching rings of cells until
 * the ring is farther than the best found. */
static double grid_nearest(const grid *gr, double x, double y, int skip)
{
    int g = gr->g, cx = (int)(x * g) % g, cy = (int)(y * g) % g;
    double best = 1e30;
    for (int ring = 0; ring <= g / 2 + 1; ring++) {
        if (ring >= 2 && (ring - 1) * (1.0 / g) > sqrt(best)) break;
        for (int dy = -ring; dy <= ring; dy++)
            for (int dx = -ring; dx <= ring; dx++) {
                if (abs(dx) != ring && abs(dy) != ring) continue;
                int c = ((cy + dy) % g + g) % g * g + ((cx + dx) % g + g) % g;
                for (int j = gr->head[c]; j >= 0; j = gr->next[j]) {
                    if (j == skip) continue;
                    double d2 = torus_d2(x, y, gr->xy[2 * j], gr->xy[2 * j + 1]);
                    if (d2 < best) best = d2;
                }
            }
    }
    return sqrt(best);
}

/* ---- the sequence ---- */

static void test_spacing(nprfx_context *ctx, const float *xy, const float *r)
{
    /* r_i * sqrt(i), i = k + 1 */
    double lo = 1e9, hi = 0;
    int klo = 0, khi = 0;
    for (int k = WARMUP; k < N; k++) {
        double v = r[k] * sqrt(k + 1.0);
        if (v < lo) lo = v, klo = k;
        if (v > hi) hi = v, khi = k;
    }
    printf("r_i*sqrt(i) for i > %d: [%.4f (i=%d), %.4f (i=%d)]\n", WARMUP, lo, klo + 1, hi,
           khi + 1);
    CHECK(lo >= 0.7);
    CHECK(hi <= 0.9);

    /* normalised minimum distance of prefixes 64, 128, ..., N, measured on the points */
    double worst = 1e9;
    for (int n = 64;; n *= 2) {
        if (n > N) n = N;
        grid gr;
        grid_build(&gr, xy, n);
        double dmin = 1e9;
        for (int i = 0; i < n; i++) {
            double d = grid_nearest(&gr, xy[2 * i], xy[2 * i + 1], i);
            if (d < dmin) dmin = d;
        }
        grid_free(&gr);
        double norm = dmin / sqrt(2.0 / (sqrt(3.0) * n));
        printf("prefix %6d: normalised d_min %.4f\n", n, norm);
        CHECK(norm >= 0.7);
        if (norm < worst) worst = norm;
        if (n == N) break;
    }
    (void)ctx;
}

/* Farthest-point property, checked independently of the triangulation: r[k] is the distance of
 * point k to the nearest earlier point, and no place on the torus is farther than r[k] (up to
 * the 1% near-tie band) from the first k points. */
static void test_farthest(const float *xy, const float *r)
{
    int bad = 0;
    for (int k = 1; k < 1500; k++) {
        double best = 1e30;
        for (int j = 0; j < k; j++) {
            double d2 = torus_d2(xy[2 * k], xy[2 * k + 1], xy[2 * j], xy[2 * j + 1]);
            if (d2 < best) best = d2;
        }
        if (fabs(sqrt(best) - r[k]) > 1e-5 * r[k] + 1e-6) bad++;
    }
    CHECK(bad == 0);

    const int prefixes[] = {100, 1000, 10000};
    for (int p = 0; p < 3; p++) {
        int n = prefixes[p];
        grid gr;
        grid_build(&gr, xy, n);
        double worst = 0;
        for (int s = 0; s < 20000; s++) {
            double x = nprfx_rand_u01(7, 0, s, n, 0, 0), y = nprfx_rand_u01(7, 0, s, n, 1, 0);
            double d = grid_nearest(&gr, x, y, -1);
            if (d > worst) worst = d;
        }
        grid_free(&gr);
        printf("prefix %5d: farthest probe %.6f, inserted circle %.6f\n", n, worst, r[n]);
        CHECK(worst <= r[n] * 1.0101 + 1e-7);
    }
}

static void test_determinism(nprfx_context *ctx, const float *xy)
{
    float *a = malloc(sizeof(float) * 2 * N), *b = malloc(sizeof(float) * 2 * 5000);
    CHECK_OK(nprfx_ivs_generate(ctx, SEED, N, a, NULL));
    CHECK(memcmp(a, xy, sizeof(float) * 2 * N) == 0);
    /* a prefix does not depend on how many points were asked for */
    CHECK_OK(nprfx_ivs_generate(ctx, SEED, 5000, b, NULL));
    CHECK(memcmp(b, xy, sizeof(float) * 2 * 5000) == 0);
    /* another seed, another sequence */
    CHECK_OK(nprfx_ivs_generate(ctx, SEED + 1, 5000, b, NULL));
    CHECK(memcmp(b, xy, sizeof(float) * 2 * 5000) != 0);
    /* tiny requests */
    float one[2], rr[3], three[6];
    CHECK_OK(nprfx_ivs_generate(ctx, SEED, 1, one, rr));
    CHECK(one[0] == xy[0] && one[1] == xy[1]);
    CHECK_OK(nprfx_ivs_generate(ctx, SEED, 3, three, rr));
    CHECK(memcmp(three, xy, sizeof three) == 0);
    CHECK(nprfx_ivs_generate(ctx, SEED, 0, one, NULL) == NPRFX_ERR_INVALID_ARGUMENT);
    for (int i = 0; i < 2 * N; i++)
        if (!(xy[i] >= 0.0f && xy[i] < 1.0f)) {
            CHECK(!"coordinate outside [0, 1)");
            break;
        }
    free(a);
    free(b);
}

/* ---- the encoded form ---- */

static void test_codec(nprfx_context *ctx, const float *xy)
{
    const int n = 3000;
    size_t size = nprfx_ivs_encoded_size(n);
    CHECK(size == NPRFX_IVS_HEADER_SIZE + 6u * n);
    unsigned char *buf = malloc(size);
    CHECK_OK(nprfx_ivs_encode(ctx, SEED, n, xy, buf, size));
    CHECK(nprfx_ivs_encode(ctx, SEED, n, xy, buf, size - 1) == NPRFX_ERR_INVALID_ARGUMENT);

    /* through a real file, as the CLI will do */
    FILE *f = tmpfile();
    CHECK(f != NULL);
    unsigned char *back = malloc(size + 16);
    size_t got = 0;
    if (f) {
        CHECK(fwrite(buf, 1, size, f) == size);
        rewind(f);
        got = fread(back, 1, size + 16, f);
        fclose(f);
    }
    CHECK(got == size);
    uint64_t seed = 0;
    int m = 0;
    float *dec = NULL;
    CHECK_OK(nprfx_ivs_decode(ctx, back, got, &seed, &m, &dec));
    CHECK(seed == SEED && m == n);
    if (dec && m == n) {
        double err = 0;
        for (int i = 0; i < n; i++)
            err = fmax(err, sqrt(torus_d2(dec[2 * i], dec[2 * i + 1], xy[2 * i], xy[2 * i + 1])));
        printf("codec: max coordinate error %.3g\n", err);
        CHECK(err <= 1.0 / (1 << 24));
        /* nprfx_ivs_quantize gives the decoded floats bit for bit (the stipple node relies on
         * it: its generated and shipped sequences must be the same points) */
        float *q = malloc(sizeof(float) * 2 * n);
        memcpy(q, xy, sizeof(float) * 2 * n);
        nprfx_ivs_quantize(q, n);
        CHECK(memcmp(q, dec, sizeof(float) * 2 * n) == 0);
        nprfx_ivs_quantize(q, n); /* and is idempotent */
        CHECK(memcmp(q, dec, sizeof(float) * 2 * n) == 0);
        free(q);
        /* a second round trip is exact */
        unsigned char *buf2 = malloc(size);
        CHECK_OK(nprfx_ivs_encode(ctx, seed, m, dec, buf2, size));
        CHECK(memcmp(buf, buf2, size) == 0);
        free(buf2);
    }
    free(dec);

    /* corruptions are refused, with a message that says what is wrong */
    memcpy(back, buf, size);
    back[NPRFX_IVS_HEADER_SIZE + 1234] ^= 0x10;
    dec = NULL;
    CHECK(nprfx_ivs_decode(ctx, back, size, &seed, &m, &dec) == NPRFX_ERR_PARSE);
    CHECK(dec == NULL && strstr(th_error(ctx), "corrupt") != NULL);
    printf("corrupt file: %s\n", th_error(ctx));

    CHECK(nprfx_ivs_decode(ctx, buf, size - 6, &seed, &m, &dec) == NPRFX_ERR_PARSE);
    CHECK(strstr(th_error(ctx), "truncated") != NULL);
    printf("truncated file: %s\n", th_error(ctx));

    memcpy(back, buf, size);
    back[0] = 'X';
    CHECK(nprfx_ivs_decode(ctx, back, size, &seed, &m, &dec) == NPRFX_ERR_PARSE);
    CHECK(strstr(th_error(ctx), "not an IVS") != NULL);

    memcpy(back, buf, size);
    back[8] = 2;
    CHECK(nprfx_ivs_decode(ctx, back, size, &seed, &m, &dec) == NPRFX_ERR_UNSUPPORTED);
    CHECK(nprfx_ivs_decode(ctx, back, 10, &seed, &m, &dec) == NPRFX_ERR_PARSE);
    CHECK(dec == NULL);
    free(back);
    free(buf);
}

/* ---- the spatial index ---- */

typedef struct hits {
    int n, cap;
    int *index;
    double *uv;
} hits;

static int collect(void *user, int index, double u, double v)
{
    hits *h = user;
    if (h->n == h->cap) {
        h->cap = h->cap ? 2 * h->cap : 64;
        h->index = realloc(h->index, sizeof(int) * h->cap);
        h->uv = realloc(h->uv, sizeof(double) * 2 * h->cap);
    }
    h->index[h->n] = index;
    h->uv[2 * h->n] = u;
    h->uv[2 * h->n + 1] = v;
    h->n++;
    return 0;
}

/* The batches of nprfx_ivs_index_query_batch, one sample at a time into the hits. */
static int collect_batch(void *user, int n, const int32_t *index, const double *u, const double *v)
{
    for (int k = 0; k < n; k++)
        collect(user, index[k], u[k], v[k]);
    return 0;
}

/* Stops after the first batch. */
static int first_batch(void *user, int n, const int32_t *index, const double *u, const double *v)
{
    (void)index, (void)u, (void)v;
    *(int *)user = n;
    return 1;
}

/* Stops at the third sample. */
static int third_sample(void *user, int index, double u, double v)
{
    (void)index, (void)u, (void)v;
    return ++*(int *)user == 3;
}

static int cmp_key(const void *a, const void *b)
{
    const double *x = a, *y = b;
    for (int i = 0; i < 3; i++)
        if (x[i] != y[i]) return x[i] < y[i] ? -1 : 1;
    return 0;
}

/* (index, u, v) triples, sorted, for comparing answers as sets. */
static double *sorted_keys(const hits *h)
{
    double *k = malloc(sizeof(double) * 3 * (h->n + 1));
    for (int i = 0; i < h->n; i++) {
        k[3 * i] = h->index[i];
        k[3 * i + 1] = h->uv[2 * i];
        k[3 * i + 2] = h->uv[2 * i + 1];
    }
    qsort(k, (size_t)h->n, 3 * sizeof(double), cmp_key);
    return k;
}

static void test_index(nprfx_context *ctx, const float *xy)
{
    nprfx_ivs_index *ix = NULL;
    CHECK_OK(nprfx_ivs_index_create(ctx, xy, N, &ix));
    if (!ix) return;
    CHECK(nprfx_ivs_index_count(ix) == N);
    float p[2];
    nprfx_ivs_index_point(ix, 777, p);
    CHECK(p[0] == xy[2 * 777] && p[1] == xy[2 * 777 + 1]);

    int mismatches = 0;
    for (int q = 0; q < 300; q++) {
        /* rectangles from tiny to several tiles, anywhere in the plane, and any limit */
        double w = 0.002 * pow(1000.0, nprfx_rand_u01(3, 0, q, 0, 0, 0));
        double h = w * (0.2 + 2 * nprfx_rand_u01(3, 0, q, 0, 1, 0));
        double u0 = -3 + 6 * nprfx_rand_u01(3, 0, q, 0, 2, 0);
        double v0 = -3 + 6 * nprfx_rand_u01(3, 0, q, 0, 3, 0);
        int limit = (int)(1 + (N + 100) * pow(nprfx_rand_u01(3, 0, q, 0, 4, 0), 3));
        if (q == 0) u0 = 0, v0 = 0, w = 1, h = 1, limit = N; /* the whole tile */
        hits got = {0}, want = {0};
        long long c = nprfx_ivs_index_query(ix, limit, u0, v0, u0 + w, v0 + h, collect, &got);
        CHECK(c == got.n);
        int lim = limit < N ? limit : N;
        for (int ty = (int)floor(v0); ty <= (int)floor(v0 + h); ty++)
            for (int tx = (int)floor(u0); tx <= (int)floor(u0 + w); tx++)
                for (int i = 0; i < lim; i++) {
                    double u = xy[2 * i] + (double)tx, v = xy[2 * i + 1] + (double)ty;
                    if (u >= u0 && u < u0 + w && v >= v0 && v < v0 + h) collect(&want, i, u, v);
                }
        if (q == 0) CHECK(got.n == N);
        /* in batches: the same samples in the same order; and both stop when asked */
        hits bat = {0};
        CHECK(nprfx_ivs_index_query_batch(ix, limit, u0, v0, u0 + w, v0 + h, collect_batch, &bat) ==
              got.n);
        if (bat.n != got.n || (got.n && (memcmp(bat.index, got.index, sizeof(int) * got.n) ||
                                         memcmp(bat.uv, got.uv, sizeof(double) * 2 * got.n))))
            mismatches++;
        free(bat.index);
        free(bat.uv);
        int first = 0, seen = 0;
        long long c1 =
            nprfx_ivs_index_query_batch(ix, limit, u0, v0, u0 + w, v0 + h, first_batch, &first);
        CHECK(c1 == first && (got.n == 0 || (first >= 1 && first <= NPRFX_IVS_BATCH)));
        long long c3 =
            nprfx_ivs_index_query(ix, limit, u0, v0, u0 + w, v0 + h, third_sample, &seen);
        CHECK(c3 == (got.n < 3 ? got.n : 3));
        if (got.n != want.n) {
            mismatches++;
        } else {
            double *a = sorted_keys(&got), *b = sorted_keys(&want);
            if (memcmp(a, b, sizeof(double) * 3 * got.n) != 0) mismatches++;
            free(a);
            free(b);
        }
        free(got.index);
        free(got.uv);
        free(want.index);
        free(want.uv);
    }
    CHECK(mismatches == 0);

    /* cost independent of the sequence length: a small footprint reads a handful of entries
     * whatever the limit (timed loosely, as a regression guard) */
    clock_t t0 = clock();
    long long total = 0;
    for (int q = 0; q < 200000; q++) {
        double u = nprfx_rand_u01(5, 0, q, 0, 0, 0), v = nprfx_rand_u01(5, 0, q, 0, 1, 0);
        int limit = 64 << (q % 9);       /* 64 .. 16384 */
        double side = sqrt(4.0 / limit); /* about 4 samples expected */
        total += nprfx_ivs_index_query(ix, limit, u, v, u + side, v + side, NULL, NULL);
    }
    double secs = (double)(clock() - t0) / CLOCKS_PER_SEC;
    printf("index: 200000 queries of ~4 samples: %.3f s, %.2f samples/query\n", secs,
           total / 200000.0);
    CHECK(fabs(total / 200000.0 - 4.0) < 0.5);
    nprfx_ivs_index_destroy(ix);

    CHECK(nprfx_ivs_index_create(ctx, xy, 0, &ix) == NPRFX_ERR_INVALID_ARGUMENT);
}

int main(void)
{
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    float *xy = malloc(sizeof(float) * 2 * N), *r = malloc(sizeof(float) * N);
    clock_t t0 = clock();
    CHECK_OK(nprfx_ivs_generate(ctx, SEED, N, xy, r));
    printf("generated %d points in %.3f s\n", N, (double)(clock() - t0) / CLOCKS_PER_SEC);
    test_spacing(ctx, xy, r);
    test_farthest(xy, r);
    test_determinism(ctx, xy);
    test_codec(ctx, xy);
    test_index(ctx, xy);
    free(xy);
    free(r);
    nprfx_context_destroy(ctx);
    return check_finish();
}
