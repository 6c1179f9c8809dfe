/* Stippling from UV and shading (Ma et al. 2018; docs/design.md §3.3). stipple.h has the model.
 *
 * A render works in two parallel phases. First the pixels that can reach the window (the window
 * plus a margin of the largest disc radius) are split into units, and each unit finds the
 * stipples its pixels own, in row-major order of the owners, with where each owner row starts;
 * every owner is handled once. Then each tile of the window draws the stipples that reach it,
 * owner row by owner row and unit by unit from the left. Every pixel therefore sees the same
 * stipples in the same order whatever the tile, unit or thread it is rendered in (or the host's
 * own tiling), which makes the output bit-identical across splits. What an owner finds depends
 * only on the inputs within a few pixels of it, which each unit reads with a margin.
 *
 * Speed (1080p, `nprfx bench stipple`): the per-pixel passes read their inputs a row at a time
 * (plates interleave many channels), test neighbours through per-pixel object ids that already
 * say whether the pixel is usable, and add without branching where the result is the same
 * float; owners are queried in blocks whose per-sample tests are branch-free; the disc coverage
 * evaluates its P and quadrant-area terms two at a time with SSE2 where there is SSE2, each
 * lane doing the scalar code's operations, so every build gives the same floats. A frame
 * without uv and id inputs (the image its own UV space) fills its rows without per-input
 * tests and its Jacobian from one derivative per column and per row (stipple_pixels.c,
 * stipple_jacobian.c); a dot whose stencil lies wholly in its tile is drawn as straight-line
 * rows (stipple_disc.c). Callgrind, one 1080p orbit frame: 1.21G / 1.49G / 1.45G instructions
 * (uniform / radius / multitone) before these, 0.82G / 1.04G / 1.05G after. */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include "internal_stipple.h"
#include "nprfx/exec.h"

/* ---- parameters ---- */

void nprfx_stipple_params_default(nprfx_stipple_params *p)
{
    memset(p, 0, sizeof *p);
    p->size = sizeof *p;
    p->mode = NPRFX_STIPPLE_UNIFORM;
    p->area = 6.0;
    p->a0 = 6.0;
    p->delta_min = 0.5;
    p->num_tones = 3;
    p->tones[0] = 1.0 / 3.0;
    p->tones[1] = 2.0 / 3.0;
    p->tones[2] = 1.0;
    p->tile = 1.0;
    p->plane_scale = NPRFX_STIPPLE_PLANE_PIXELS;
    p->aspect = 1.0;
    p->anisotropy = 1;
    p->ink[3] = 1.0f;
    for (int c = 0; c < 4; c++)
        p->paper[c] = 1.0f;
}

nprfx_result nprfx_stipple_parse_tones(nprfx_context *ctx, const char *text,
                                       nprfx_stipple_params *p)
{
    int n = 0;
    const char *s = text ? text : "";
    double prev = 0.0;
    while (*s) {
        while (*s == ' ' || *s == ',' || *s == '\t')
            s++;
        if (!*s) break;
        char *end;
        double v = strtod(s, &end);
        if (end == s)
            return nprfx_error(ctx, NPRFX_ERR_PARSE,
                               "stipple.tones: cannot read a number at \"%s\" (expected pen "
                               "darknesses like \"0.33, 0.67, 1\")",
                               s);
        if (!(v > prev && v <= 1.0))
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                               "stipple.tones: %g must be above the previous tone (%g) and at "
                               "most 1: list pen darknesses in ascending order",
                               v, prev);
        if (n == NPRFX_STIPPLE_MAX_TONES)
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "stipple.tones: at most %d pens",
                               NPRFX_STIPPLE_MAX_TONES);
        p->tones[n++] = v;
        prev = v;
        s = end;
    }
    if (n == 0)
        return nprfx_error(ctx, NPRFX_ERR_PARSE, "stipple.tones: give at least one pen tone");
    p->num_tones = n;
    return NPRFX_OK;
}

static nprfx_result check_params(nprfx_context *ctx, const nprfx_stipple_params *p)
{
    if (!p || p->size < sizeof *p)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: bad params struct");
    if (p->simd < 0 || p->simd > 2)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "stipple: no simd path %d", p->simd);
    if (p->mode < 0 || p->mode > NPRFX_STIPPLE_MULTITONE)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "stipple.mode: no mode %d", p->mode);
    if (!(p->area > 0) || !(p->a0 > 0) || !(p->delta_min >= 0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "stipple: size (%g) and a0 (%g) must be positive, delta_min (%g) not "
                           "negative",
                           p->area, p->a0, p->delta_min);
    if (!(p->tile > 0) || !(p->plane_scale > 0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "stipple.tile: %g is not positive",
                           p->tile);
    if (!(p->aspect > 0) || !isfinite(p->aspect))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "stipple.aspect: %g is not positive",
                           p->aspect);
    if (p->mode == NPRFX_STIPPLE_MULTITONE &&
        (p->num_tones < 1 || p->num_tones > NPRFX_STIPPLE_MAX_TONES))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "stipple.tones: need 1 to %d pens",
                           NPRFX_STIPPLE_MAX_TONES);
    return NPRFX_OK;
}

/* The largest disc radius the params can produce. */
static double max_radius(const nprfx_stipple_params *p)
{
    double a = p->mode == NPRFX_STIPPLE_RADIUS ? p->a0 : p->area;
    return sqrt(a / PI_D);
}

/* ---- the sequence: caller-owned, grown on demand ---- */

typedef struct seq_version {
    nprfx_ivs_index *index;
    struct seq_version *older; /* kept until destroy: renders may still read them */
} seq_version;

/* A tone-correction curve measured for the params that determine it (same_curve_params). */
typedef struct seq_curve {
    nprfx_stipple_params key;
    float curve[NPRFX_STIPPLE_CURVE_SIZE];
} seq_curve;

/* Curves kept per sequence: a graph rarely has more stipple looks than this. */
#define SEQ_CURVES 8
/* Radius-dot stencil tables kept per sequence (one per a0 at its render scale, 4.2 MB each):
 * made once instead of every frame (5 ms of one thread at a0 = 6). Beyond this many, each render
 * makes its own. */
#define SEQ_LEVELS 4

struct nprfx_stipple_sequence {
    pthread_mutex_t lock;        /* held while a longer version is built */
    _Atomic(seq_version *) head; /* the longest version; read without the lock */
    float *pre;                  /* preloaded points (on the grid), or NULL */
    int pre_count;
    atomic_int refs; /* nprfx_stipple_sequence_retain; the last destroy frees */
    /* The tone-correction curves measured with this sequence, so that every instance sharing
     * it measures each curve once. Its own lock: measuring renders, which take `lock`. */
    pthread_mutex_t curve_lock;
    seq_curve curves[SEQ_CURVES];
    int num_curves, next_curve;
    /* Radius-dot tables by their largest area, under their own lock (a curve is measured by
     * rendering, under curve_lock); immutable once made and kept until destroy, so renders read
     * them without a lock. */
    pthread_mutex_t levels_lock;
    double level_area[SEQ_LEVELS];
    internal_levels *levels[SEQ_LEVELS];
    int num_levels;
};

nprfx_result nprfx_stipple_sequence_create(nprfx_context *ctx, nprfx_stipple_sequence **out)
{
    if (!out) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: NULL output");
    *out = NULL;
    nprfx_stipple_sequence *s = calloc(1, sizeof *s);
    if (!s) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple: out of memory");
    if (pthread_mutex_init(&s->lock, NULL) != 0) {
        free(s);
        return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "stipple: cannot create a mutex");
    }
    if (pthread_mutex_init(&s->curve_lock, NULL) != 0) {
        pthread_mutex_destroy(&s->lock);
        free(s);
        return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "stipple: cannot create a mutex");
    }
    if (pthread_mutex_init(&s->levels_lock, NULL) != 0) {
        pthread_mutex_destroy(&s->curve_lock);
        pthread_mutex_destroy(&s->lock);
        free(s);
        return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "stipple: cannot create a mutex");
    }
    atomic_init(&s->head, NULL);
    atomic_init(&s->refs, 1);
    *out = s;
    return NPRFX_OK;
}

nprfx_stipple_sequence *nprfx_stipple_sequence_retain(nprfx_stipple_sequence *s)
{
    if (s) atomic_fetch_add(&s->refs, 1);
    return s;
}

void nprfx_stipple_sequence_destroy(nprfx_stipple_sequence *s)
{
    if (!s || atomic_fetch_sub(&s->refs, 1) != 1) return;
    pthread_mutex_destroy(&s->curve_lock);
    pthread_mutex_destroy(&s->levels_lock);
    for (int i = 0; i < s->num_levels; i++) {
        internal_stipple_levels_free(s->levels[i]);
        free(s->levels[i]);
    }
    seq_version *v = atomic_load(&s->head);
    while (v) {
        seq_version *older = v->older;
        nprfx_ivs_index_destroy(v->index);
        free(v);
        v = older;
    }
    pthread_mutex_destroy(&s->lock);
    free(s->pre);
    free(s);
}

nprfx_result nprfx_stipple_sequence_preload(nprfx_context *ctx, nprfx_stipple_sequence *s,
                                            const float *xy, int n)
{
    if (!s || !xy || n < 1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: bad preload arguments");
    float *pre = malloc(sizeof(float) * 2 * (size_t)n);
    if (!pre)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple: out of memory for %d points", n);
    memcpy(pre, xy, sizeof(float) * 2 * (size_t)n);
    nprfx_ivs_quantize(pre, n); /* a no-op for decoded points */
    pthread_mutex_lock(&s->lock);
    free(s->pre);
    s->pre = pre;
    s->pre_count = n;
    pthread_mutex_unlock(&s->lock);
    return NPRFX_OK;
}

/* The first n points of the sequence into xy: preloaded while there are enough, else generated,
 * rounded to the grid either way (the same floats). Called under the lock. */
static nprfx_result sequence_points(nprfx_context *ctx, const nprfx_stipple_sequence *s, int n,
                                    float *xy)
{
    if (s->pre && s->pre_count >= n) {
        memcpy(xy, s->pre, sizeof(float) * 2 * (size_t)n);
        return NPRFX_OK;
    }
    nprfx_result r = nprfx_ivs_generate(ctx, NPRFX_IVS_DEFAULT_SEED, n, xy, NULL);
    if (r == NPRFX_OK) nprfx_ivs_quantize(xy, n);
    return r;
}

nprfx_result nprfx_stipple_sequence_index(nprfx_context *ctx, nprfx_stipple_sequence *s,
                                          int min_count, const nprfx_ivs_index **out)
{
    if (!out || !s)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: NULL sequence or output");
    if (min_count > NPRFX_STIPPLE_MAX_SAMPLES) min_count = NPRFX_STIPPLE_MAX_SAMPLES;
    /* the common case: long enough already (acquire: the index it points to is complete) */
    seq_version *v = atomic_load_explicit(&s->head, memory_order_acquire);
    if (v && nprfx_ivs_index_count(v->index) >= min_count) {
        *out = v->index;
        return NPRFX_OK;
    }
    int want = 1 << 16;
    while (want < min_count)
        want *= 2;
    nprfx_result r = NPRFX_OK;
    pthread_mutex_lock(&s->lock);
    v = atomic_load_explicit(&s->head, memory_order_relaxed);
    if (!v || nprfx_ivs_index_count(v->index) < want) {
        /* Regenerating rather than extending is simpler and costs at most twice the final
         * size; the prefix property makes the new sequence start with the old one. */
        float *xy = malloc(sizeof(float) * 2 * (size_t)want);
        seq_version *nv = calloc(1, sizeof *nv);
        if (!xy || !nv) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple: out of memory for %d points",
                            want);
        } else if ((r = sequence_points(ctx, s, want, xy)) == NPRFX_OK &&
                   (r = nprfx_ivs_index_create(ctx, xy, want, &nv->index)) == NPRFX_OK) {
            nv->older = v;
            atomic_store_explicit(&s->head, nv, memory_order_release);
            v = nv;
            nv = NULL;
        }
        free(xy);
        free(nv);
    }
    *out = r == NPRFX_OK ? v->index : NULL;
    pthread_mutex_unlock(&s->lock);
    return r;
}

/* ---- render ---- */

static void set_error(sjob *j, nprfx_result r)
{
    int expected = NPRFX_OK;
    if (r != NPRFX_OK) atomic_compare_exchange_strong(&j->error, &expected, r);
}

/* Phase 1 of a render: the stipples of one unit of owners, with where each owner row starts. */
static void unit_stipples(void *user, int begin, int end, int worker)
{
    sjob *j = user;
    nprfx_rect R = j->owners;
    for (int u = begin; u < end; u++) {
        if (atomic_load(&j->error) != NPRFX_OK) return;
        int x0 = R.x0 + (u % j->units_x) * UNIT_COLS, y0 = R.y0 + (u / j->units_x) * UNIT_ROWS;
        nprfx_rect E =
            nprfx_rect_intersect(R, nprfx_rect_make(x0, y0, x0 + UNIT_COLS, y0 + UNIT_ROWS));
        set_error(j, internal_stipple_owner_stipples(j, &j->scr[worker], E, &j->lists[u],
                                                     j->row_start + (size_t)u * (UNIT_ROWS + 1)));
    }
}

/* The tile's paper transmittance t (rows y0..y1 of width x1 - x0) as ink over paper, and the
 * coverage 1 - t in a fifth channel when asked. paper + dk * (ink - paper) per channel, four
 * channels at once where SSE2 is there (each lane the same float operations). */
static void write_tile(nprfx_image *o, const nprfx_stipple_params *p, const float *t, int x0,
                       int y0, int x1, int y1)
{
    const int extra = p->coverage_channel, width = x1 - x0;
    const ptrdiff_t ps = o->pixel_stride;
    float paper[4], diff[4]; /* local: stores to the output cannot alias them */
    for (int c = 0; c < 4; c++) {
        paper[c] = p->paper[c];
        diff[c] = p->ink[c] - p->paper[c];
    }
    for (int y = y0; y < y1; y++) {
        const float *trow = t + (size_t)(y - y0) * width;
        float *px = nprfx_image_at(o, x0, y);
        int i = 0;
#if defined(__SSE2__)
        const __m128 vp = _mm_loadu_ps(paper), vd = _mm_loadu_ps(diff);
        for (; i < width; i++, px += ps) {
            float dk = 1.0f - trow[i];
            _mm_storeu_ps(px, _mm_add_ps(vp, _mm_mul_ps(_mm_set1_ps(dk), vd)));
            if (extra) px[4] = dk;
        }
#endif
        for (; i < width; i++, px += ps) {
            float dk = 1.0f - trow[i];
            for (int c = 0; c < 4; c++)
                px[c] = paper[c] + dk * diff[c];
            if (extra) px[4] = dk;
        }
    }
}

/* Phase 2: draw the stipples that reach a tile of the window. They are taken owner row by
 * owner row, and within a row unit by unit from the left, so every pixel sees its stipples in
 * row-major order of their owners, however the window, units and tiles fall. */
static void render_tiles(void *user, int begin, int end, int worker)
{
    sjob *j = user;
    scratch *s = &j->scr[worker];
    const nprfx_stipple_params *p = j->p;
    nprfx_rect win = j->region, R = j->owners;
    int tiles_x = (nprfx_rect_width(win) + TILE_COLS - 1) / TILE_COLS;
    for (int st = begin; st < end; st++) {
        if (atomic_load(&j->error) != NPRFX_OK) return;
        int x0 = win.x0 + (st % tiles_x) * TILE_COLS, y0 = win.y0 + (st / tiles_x) * STRIPE_ROWS;
        int x1 = x0 + TILE_COLS < win.x1 ? x0 + TILE_COLS : win.x1;
        int y1 = y0 + STRIPE_ROWS < win.y1 ? y0 + STRIPE_ROWS : win.y1;
        nprfx_rect rows = nprfx_rect_make(x0, y0, x1, y1);
        int width = x1 - x0;
        size_t npx = (size_t)width * (size_t)(y1 - y0);
        if (!internal_stipple_reserve((void **)&s->t, &s->tcap, npx, sizeof(float))) {
            set_error(j, NPRFX_ERR_OUT_OF_MEMORY);
            return;
        }
        float *t = s->t;
        for (size_t i = 0; i < npx; i++)
            t[i] = 1.0f;
        /* the owners that can reach the tile, and the units holding them */
        nprfx_rect E = nprfx_rect_intersect(
            R, nprfx_rect_make(x0 - j->margin, y0 - j->margin, x1 + j->margin, y1 + j->margin));
        if (!nprfx_rect_empty(E)) {
            int ca = (E.x0 - R.x0) / UNIT_COLS, cb = (E.x1 - 1 - R.x0) / UNIT_COLS;
            const double lx = x0 - 1, hx = x1, ly = y0 - 1, hy = y1;
            for (int oy = E.y0; oy < E.y1; oy++) {
                int ur = (oy - R.y0) / UNIT_ROWS, r = (oy - R.y0) % UNIT_ROWS;
                for (int uc = ca; uc <= cb; uc++) {
                    int u = ur * j->units_x + uc;
                    const int *rs = j->row_start + (size_t)u * (UNIT_ROWS + 1);
                    const nprfx_stipple *q = j->lists[u].s;
                    for (int i = rs[r]; i < rs[r + 1]; i++) {
                        /* discs wholly outside the tile change nothing: skip them cheaply */
                        double rad = q[i].radius;
                        if (q[i].x + rad < lx || q[i].x - rad > hx || q[i].y + rad < ly ||
                            q[i].y - rad > hy)
                            continue;
                        if (j->stencils.cov && rad == j->stencils.r)
                            internal_stipple_splat_stencil(t, rows, &j->stencils, q[i].x, q[i].y,
                                                           q[i].tone);
                        else if (j->levels)
                            internal_stipple_splat_levels(t, rows, j->levels, q[i].x, q[i].y, rad,
                                                          q[i].tone);
                        else
                            internal_stipple_splat_disc(t, rows, q[i].x, q[i].y, rad, q[i].tone);
                    }
                }
            }
        }
        write_tile(j->out, p, t, x0, y0, x1, y1);
    }
}

static nprfx_result check_inputs(nprfx_context *ctx, const nprfx_stipple_inputs *in)
{
    if (!in || !in->tone || !in->tone->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "stipple: input 'tone' is required");
    if (in->uv && in->uv->data && in->uv->channels < 2)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "stipple: input 'uv' needs 2 channels, it has %d", in->uv->channels);
    return NPRFX_OK;
}

/* NULL views for absent optional inputs, so the code below tests one thing. */
static nprfx_stipple_inputs normalise_inputs(const nprfx_stipple_inputs *in)
{
    nprfx_stipple_inputs n = *in;
    if (n.uv && !n.uv->data) n.uv = NULL;
    if (n.id && !n.id->data) n.id = NULL;
    return n;
}

/* Set up a job over `region` with one scratch per worker. */
static nprfx_result job_init(sjob *j, nprfx_context *ctx, const nprfx_stipple_params *p,
                             const nprfx_stipple_inputs *in, nprfx_rect region)
{
    memset(j, 0, sizeof *j);
    j->ctx = ctx;
    j->p = p;
    j->in = in;
    j->region = region;
    j->radius = (float)sqrt(p->area / PI_D);
#if INTERNAL_X86
    j->avx2 = p->simd != 1 && __builtin_cpu_supports("avx2");
#endif
    atomic_init(&j->error, NPRFX_OK);
    if (!p->index) {
        j->seq = p->sequence;
        if (!j->seq) { /* no caller's sequence: one for this call, shared by its threads */
            if (nprfx_stipple_sequence_create(ctx, &j->seq) != NPRFX_OK)
                return NPRFX_ERR_OUT_OF_MEMORY;
            j->own_seq = 1;
        }
    }
    int workers = nprfx_executor_workers(nprfx_context_executor(ctx));
    j->scr = calloc((size_t)(workers > 0 ? workers : 1), sizeof(scratch));
    return j->scr ? NPRFX_OK : NPRFX_ERR_OUT_OF_MEMORY;
}

static void job_free(sjob *j)
{
    int workers = nprfx_executor_workers(nprfx_context_executor(j->ctx));
    for (int w = 0; j->scr && w < (workers > 0 ? workers : 1); w++)
        internal_stipple_scratch_free(&j->scr[w]);
    free(j->scr);
    if (j->own_seq) nprfx_stipple_sequence_destroy(j->seq);
}

/* The radius-dot tables for the largest area amax: the sequence's (made on first use and kept),
 * or, without a sequence or beyond SEQ_LEVELS areas, made into *own for this call. *out is NULL
 * when the dots are too large for tables (drawn exactly). */
static nprfx_result sequence_levels(nprfx_stipple_sequence *seq, double amax, internal_levels *own,
                                    const internal_levels **out)
{
    internal_levels *kept = NULL;
    if (seq) {
        pthread_mutex_lock(&seq->levels_lock);
        for (int i = 0; i < seq->num_levels; i++)
            if (seq->level_area[i] == amax) kept = seq->levels[i];
        if (!kept && seq->num_levels < SEQ_LEVELS && (kept = calloc(1, sizeof *kept))) {
            if (internal_stipple_levels_init(kept, amax) < 0) {
                free(kept);
                kept = NULL;
            } else {
                seq->level_area[seq->num_levels] = amax;
                seq->levels[seq->num_levels++] = kept;
            }
        }
        pthread_mutex_unlock(&seq->levels_lock);
    }
    if (!kept) {
        if (internal_stipple_levels_init(own, amax) < 0) return NPRFX_ERR_OUT_OF_MEMORY;
        kept = own;
    }
    *out = kept->made ? kept : NULL;
    return NPRFX_OK;
}

/* The stipples whose centre lies in the window's pixels (x0 - 0.5 <= x < x1 - 0.5, and so for
 * y): each stipple of a frame is counted by exactly one of the tiles that cover it. */
static long long count_in_window(const sjob *j, int units, nprfx_rect w)
{
    const double x0 = w.x0 - 0.5, x1 = w.x1 - 0.5, y0 = w.y0 - 0.5, y1 = w.y1 - 0.5;
    long long n = 0;
    for (int u = 0; u < units; u++)
        for (size_t i = 0; i < j->lists[u].n; i++) {
            const nprfx_stipple *q = &j->lists[u].s[i];
            n += q->x >= x0 && q->x < x1 && q->y >= y0 && q->y < y1;
        }
    return n;
}

nprfx_result nprfx_stipple_draw(nprfx_context *ctx, const nprfx_stipple_params *p,
                                const nprfx_stipple_inputs *in_, nprfx_rect window,
                                nprfx_image *out)
{
    nprfx_result r = check_params(ctx, p);
    if (r == NPRFX_OK) r = check_inputs(ctx, in_);
    if (r != NPRFX_OK) return r;
    if (!out || out->channels != (p->coverage_channel ? 5 : 4))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "stipple: the output needs %d channels, it has %d",
                           p->coverage_channel ? 5 : 4, out ? out->channels : 0);
    window = nprfx_rect_intersect(window, in_->frame);
    window = nprfx_rect_intersect(window, out->bounds);
    if (nprfx_rect_empty(window)) return NPRFX_OK;
    nprfx_stipple_inputs in = normalise_inputs(in_);
    sjob j;
    if (job_init(&j, ctx, p, &in, window) != NPRFX_OK) {
        job_free(&j);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple: out of memory");
    }
    /* an owner reaches a pixel when its disc (centre anywhere in the owner's square) does */
    j.margin = (int)ceil(max_radius(p) + 1.0);
    j.out = out;
    /* phase 1: the stipples of the owners around the window, unit by unit (each owner once);
     * phase 2: draw them tile by tile */
    j.owners =
        nprfx_rect_intersect(in.frame, nprfx_rect_make(window.x0 - j.margin, window.y0 - j.margin,
                                                       window.x1 + j.margin, window.y1 + j.margin));
    j.units_x = (nprfx_rect_width(j.owners) + UNIT_COLS - 1) / UNIT_COLS;
    int units = j.units_x * ((nprfx_rect_height(j.owners) + UNIT_ROWS - 1) / UNIT_ROWS);
    j.lists = calloc((size_t)units, sizeof(stlist));
    j.row_start = malloc(sizeof(int) * (size_t)units * (UNIT_ROWS + 1));
    if (!j.lists || !j.row_start) {
        r = NPRFX_ERR_OUT_OF_MEMORY;
    } else {
        nprfx_parallel_for(nprfx_context_executor(ctx), units, 1, unit_stipples, &j);
        r = atomic_load(&j.error);
    }
    if (r == NPRFX_OK && p->count) *p->count += count_in_window(&j, units, window);
    /* uniform and multitone discs share one radius: drawn from stencils (all of them, so that
     * the pixels never depend on the window or the tiles) */
    if (r == NPRFX_OK && p->mode != NPRFX_STIPPLE_RADIUS &&
        internal_stipple_stencils_init(&j.stencils, (double)j.radius, STENCIL_PHASES,
                                       (double)j.radius) < 0)
        r = NPRFX_ERR_OUT_OF_MEMORY;
    /* radius dots: areas g a0 <= a0 (the float radius of a0 itself may round up: a hair more) */
    if (r == NPRFX_OK && p->mode == NPRFX_STIPPLE_RADIUS)
        r = sequence_levels(j.seq, p->a0 * (1 + 1e-6), &j.own_levels, &j.levels);
    if (r == NPRFX_OK) {
        int tiles = ((nprfx_rect_height(window) + STRIPE_ROWS - 1) / STRIPE_ROWS) *
                    ((nprfx_rect_width(window) + TILE_COLS - 1) / TILE_COLS);
        nprfx_parallel_for(nprfx_context_executor(ctx), tiles, 1, render_tiles, &j);
        r = atomic_load(&j.error);
    }
    for (int u = 0; j.lists && u < units; u++)
        free(j.lists[u].s);
    free(j.lists);
    free(j.row_start);
    internal_stipple_stencils_free(&j.stencils);
    internal_stipple_levels_free(&j.own_levels);
    job_free(&j);
    if (r == NPRFX_ERR_OUT_OF_MEMORY)
        return nprfx_error(ctx, r, "stipple: out of memory rendering %dx%d pixels",
                           nprfx_rect_width(window), nprfx_rect_height(window));
    return r; /* other errors were raised where they happened */
}

/* ---- collect ---- */

static void collect_stripes(void *user, int begin, int end, int worker)
{
    sjob *j = user;
    for (int st = begin; st < end; st++) {
        int y0 = j->region.y0 + st * STRIPE_ROWS;
        int y1 = y0 + STRIPE_ROWS < j->region.y1 ? y0 + STRIPE_ROWS : j->region.y1;
        nprfx_rect E = nprfx_rect_make(j->region.x0, y0, j->region.x1, y1);
        set_error(j, internal_stipple_owner_stipples(j, &j->scr[worker], E, &j->lists[st], NULL));
    }
}

nprfx_result nprfx_stipple_collect(nprfx_context *ctx, const nprfx_stipple_params *p,
                                   const nprfx_stipple_inputs *in_, nprfx_rect region,
                                   nprfx_stipple **list, size_t *count)
{
    if (!list || !count)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: NULL output list");
    *list = NULL;
    *count = 0;
    nprfx_result r = check_params(ctx, p);
    if (r == NPRFX_OK) r = check_inputs(ctx, in_);
    if (r != NPRFX_OK) return r;
    region = nprfx_rect_intersect(region, in_->frame);
    if (nprfx_rect_empty(region)) return NPRFX_OK;
    nprfx_stipple_inputs in = normalise_inputs(in_);
    sjob j;
    int stripes = (nprfx_rect_height(region) + STRIPE_ROWS - 1) / STRIPE_ROWS;
    r = job_init(&j, ctx, p, &in, region);
    if (r == NPRFX_OK) {
        j.lists = calloc((size_t)stripes, sizeof(stlist));
        if (!j.lists) r = NPRFX_ERR_OUT_OF_MEMORY;
    }
    if (r == NPRFX_OK) {
        nprfx_parallel_for(nprfx_context_executor(ctx), stripes, 1, collect_stripes, &j);
        r = atomic_load(&j.error);
    }
    size_t total = 0;
    for (int st = 0; j.lists && st < stripes; st++)
        total += j.lists[st].n;
    if (r == NPRFX_OK && total) {
        *list = malloc(total * sizeof **list);
        if (!*list) {
            r = NPRFX_ERR_OUT_OF_MEMORY;
        } else {
            for (int st = 0; st < stripes; st++) {
                if (j.lists[st].n)
                    memcpy(*list + *count, j.lists[st].s, j.lists[st].n * sizeof **list);
                *count += j.lists[st].n;
            }
        }
    }
    for (int st = 0; j.lists && st < stripes; st++)
        free(j.lists[st].s);
    free(j.lists);
    job_free(&j);
    if (r == NPRFX_ERR_OUT_OF_MEMORY)
        return nprfx_error(ctx, r, "stipple: out of memory collecting stipples");
    return r;
}

/* ---- tone correction ---- */

nprfx_result nprfx_stipple_tone_curve(nprfx_context *ctx, const nprfx_stipple_params *p_,
                                      float *curve)
{
    nprfx_result r = check_params(ctx, p_);
    if (r != NPRFX_OK) return r;
    if (!curve) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: NULL curve");
    nprfx_stipple_params p = *p_;
    p.tone_curve = NULL;
    nprfx_stipple_sequence *own = NULL; /* the caller gave none: one for all the renders */
    if (!p.index && !p.sequence) {
        if ((r = nprfx_stipple_sequence_create(ctx, &own)) != NPRFX_OK) return r;
        p.sequence = own;
    }
    p.coverage_channel = 1;
    p.plane_scale = NPRFX_STIPPLE_PLANE_PIXELS;
    p.tile = 0.25;
    p.aspect = 1.0; /* the ideal isotropic spread the aspect param aims at */
    /* scale invariance: measure small dots, on a patch holding a few hundred of them */
    double big = p.mode == NPRFX_STIPPLE_UNIFORM ? p.area : p.a0;
    if (big > 8.0) {
        double s = 8.0 / big;
        p.area *= s;
        p.a0 *= s;
        p.delta_min *= s;
    }
    const int n = 160, levels = NPRFX_STIPPLE_CURVE_SIZE;
    nprfx_image tone, out;
    if ((r = nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, n, n), 1, &tone)) != NPRFX_OK) {
        nprfx_stipple_sequence_destroy(own);
        return r;
    }
    if ((r = nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, n, n), 5, &out)) != NPRFX_OK) {
        nprfx_image_free(&tone);
        nprfx_stipple_sequence_destroy(own);
        return r;
    }
    nprfx_stipple_inputs in = {&tone, NULL, NULL, tone.bounds};
    /* D at g = k / (levels - 1), measured away from the patch border (dots owned outside the
     * patch are missing there) */
    double dk[NPRFX_STIPPLE_CURVE_SIZE];
    dk[0] = 0;
    const int m = 8;
    for (int k = 1; k < levels && r == NPRFX_OK; k++) {
        float t = (float)(1.0 - (double)k / (levels - 1));
        nprfx_image_fill(&tone, &t);
        r = nprfx_stipple_draw(ctx, &p, &in, tone.bounds, &out);
        double sum = 0;
        for (int y = m; y < n - m; y++)
            for (int x = m; x < n - m; x++)
                sum += nprfx_image_at(&out, x, y)[4];
        dk[k] = sum / ((double)(n - 2 * m) * (n - 2 * m));
        if (dk[k] < dk[k - 1]) dk[k] = dk[k - 1]; /* keep it monotone */
    }
    nprfx_image_free(&tone);
    nprfx_image_free(&out);
    nprfx_stipple_sequence_destroy(own);
    if (r != NPRFX_OK) return r;
    /* invert the piecewise-linear D */
    for (int k = 0; k < levels; k++) {
        double want = (double)k / (levels - 1);
        if (want <= 0) {
            curve[k] = 0.0f;
            continue;
        }
        int i = 1;
        while (i < levels && dk[i] < want)
            i++;
        if (i == levels) {
            curve[k] = 1.0f;
            continue;
        }
        double f = dk[i] > dk[i - 1] ? (want - dk[i - 1]) / (dk[i] - dk[i - 1]) : 1.0;
        curve[k] = (float)(((i - 1) + f) / (levels - 1));
    }
    return NPRFX_OK;
}

/* ---- tone curves shared through the sequence ---- */

/* Everything nprfx_stipple_tone_curve reads of its params: the mode, the dot sizes, the pens
 * and the seed (which places the sequence); not the tile, aspect or colours it replaces. */
static int same_curve_params(const nprfx_stipple_params *a, const nprfx_stipple_params *b)
{
    if (a->mode != b->mode || a->area != b->area || a->a0 != b->a0 ||
        a->delta_min != b->delta_min || a->num_tones != b->num_tones || a->seed != b->seed)
        return 0;
    for (int i = 0; i < a->num_tones; i++)
        if (a->tones[i] != b->tones[i]) return 0;
    return 1;
}

nprfx_result nprfx_stipple_sequence_tone_curve(nprfx_context *ctx, nprfx_stipple_sequence *seq,
                                               const nprfx_stipple_params *p, float *curve)
{
    if (!seq) return nprfx_stipple_tone_curve(ctx, p, curve);
    if (!p || !curve)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: NULL params or curve");
    nprfx_result r = NPRFX_OK;
    pthread_mutex_lock(&seq->curve_lock);
    int found = -1;
    for (int i = 0; i < seq->num_curves && found < 0; i++)
        if (same_curve_params(&seq->curves[i].key, p)) found = i;
    if (found < 0) {
        /* measured with this sequence, under the curve lock: an instance that wants the same
         * curve meanwhile waits for it instead of measuring it again */
        nprfx_stipple_params mp = *p;
        mp.index = NULL;
        mp.sequence = seq;
        mp.count = NULL;
        float c[NPRFX_STIPPLE_CURVE_SIZE];
        r = nprfx_stipple_tone_curve(ctx, &mp, c);
        if (r == NPRFX_OK) {
            found = seq->next_curve;
            seq->next_curve = (seq->next_curve + 1) % SEQ_CURVES;
            if (seq->num_curves < SEQ_CURVES) seq->num_curves++;
            seq->curves[found].key = *p;
            seq->curves[found].key.sequence = NULL; /* the key's pointers are not kept */
            seq->curves[found].key.index = NULL;
            seq->curves[found].key.tone_curve = NULL;
            seq->curves[found].key.count = NULL;
            memcpy(seq->curves[found].curve, c, sizeof c);
        }
    }
    if (r == NPRFX_OK) memcpy(curve, seq->curves[found].curve, sizeof seq->curves[found].curve);
    pthread_mutex_unlock(&seq->curve_lock);
    return r;
}
