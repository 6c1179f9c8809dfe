/* PAM builder: the entry point and the key maps (Yan et al. 2008 §4.1-4.3; docs/design.md §3.7).
 *
 * Every sample is aligned (rotated so its strokes run vertically, §4.1 and §5.3) and turned into
 * a Gaussian pyramid. The first sample, A, is synthesised level by level: the coarsest level by
 * quilting (a random block among the best few for its overlap), each finer level by searching
 * around the upsampled block of the level below, so the coarse layout carries upward. Every other
 * sample B follows A's layout: at each level, the coherence search space links the block A's tile
 * was copied from to the blocks of B with similar edges and hue (q*, Eq. 4-5), and from the
 * second level on the block B's own coarser level chose, upsampled, competes with it (q**, Eq. 6).
 * The tile grid is the same at every level (tiles halve with the level), which is what makes the
 * "correspondence of the prior level" a plain factor of two. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_pam.h"
#include "nprfx/rng.h"

#define MAX_LEVELS 5
/* The finer levels search this many pixels around the upsampled block (both axes); the last
 * column and row, matched on both sides (the wrap), search wider. */
#define REFINE 2
#define REFINE_WRAP 6
#define REFINE_MAX ((2 * REFINE_WRAP + 1) * (2 * REFINE_WRAP + 1))
/* Below this coherence a sample has no dominant stroke direction and is not rotated. */
#define ALIGN_MIN_COHERENCE 0.05
/* Rotate, measure, rotate again: two passes bring the crop within about a degree of vertical. */
#define ALIGN_PASSES 2

/* A candidate that copies (part of) the source block of a tile placed within REUSE_RADIUS tiles
 * has its overlap error multiplied by 1 + REUSE_PENALTY: the best match of a tile is often the
 * block its neighbour took (a flat patch of ground matches flat ground), and repeating it is what
 * made the quilt read as recurring blocks. The natural continuation (the neighbour's block moved
 * by one tile) does not overlap it and stays free. */
#define REUSE_RADIUS 2
#define REUSE_PENALTY 1.0

enum { STREAM_PICK = 1, STREAM_FOLLOW_LINK = 2, STREAM_FOLLOW_ROUTE = 3 };

typedef struct level_geom {
    int tile, overlap, block;
} level_geom;

typedef struct sample_pyr {
    internal_pam_img img[MAX_LEVELS];  /* RGB, coarsest first */
    internal_pam_img feat[MAX_LEVELS]; /* CSS features */
} sample_pyr;

static void pyr_free(sample_pyr *s)
{
    for (int l = 0; l < MAX_LEVELS; l++) {
        internal_pam_img_free(&s->img[l]);
        internal_pam_img_free(&s->feat[l]);
    }
}

static nprfx_result check_params(nprfx_context *ctx, const nprfx_pam_build_params *p)
{
    if (p->levels < 1 || p->levels > MAX_LEVELS)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "pam build: levels %d is outside [1, %d]",
                           p->levels, MAX_LEVELS);
    int f = 1 << (p->levels - 1);
    if (p->patch < 2 * f || p->patch % f)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "pam build: patch %d must be a multiple of %d and at least %d with %d "
                           "levels (it halves on each coarser level)",
                           p->patch, f, 2 * f, p->levels);
    if (p->map_size < 2 * p->patch || p->map_size % p->patch)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "pam build: the map size %d must be a multiple of the patch (%d), at "
                           "least two patches",
                           p->map_size, p->patch);
    if (p->overlap < 1 || p->overlap > p->patch / 2)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "pam build: overlap %d is outside [1, %d] (half the patch)", p->overlap,
                           p->patch / 2);
    if (!(p->k > 0) || !isfinite(p->k))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "pam build: k must be positive, not %g",
                           p->k);
    if (p->css_links < 1 || p->css_links > INTERNAL_PAM_MAX_LINKS)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "pam build: css_links %d is outside [1, %d]", p->css_links,
                           INTERNAL_PAM_MAX_LINKS);
    if (!(p->css_tolerance >= 0) || !(p->tolerance >= 0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "pam build: tolerances must be >= 0");
    return NPRFX_OK;
}

/* Level l (0 coarsest) of L: tiles and overlaps shrink by two per level, the overlap to no less
 * than one pixel. */
static level_geom geom(const nprfx_pam_build_params *p, int l)
{
    level_geom g;
    int sh = p->levels - 1 - l;
    g.tile = p->patch >> sh;
    g.overlap = (int)lround(p->overlap / (double)(1 << sh));
    if (g.overlap < 1) g.overlap = 1;
    if (g.overlap > g.tile / 2 && g.tile >= 2) g.overlap = g.tile / 2;
    g.block = g.tile + g.overlap;
    return g;
}

static nprfx_result prepare(nprfx_context *ctx, const nprfx_pam_build_params *p,
                            const nprfx_image *view, int index, sample_pyr *out)
{
    memset(out, 0, sizeof *out);
    internal_pam_img rgb;
    nprfx_result r = internal_pam_from_view(ctx, view, &rgb);
    if (r) return r;
    int L = p->levels;
    double deg = 90, coh = 0;
    internal_pam_orientation(&rgb, &deg, &coh);
    if (p->align && coh >= ALIGN_MIN_COHERENCE) {
        double turn = fmod(90.0 - deg + 360.0, 180.0); /* to vertical, the shorter way */
        if (turn > 90.0) turn -= 180.0;
        /* The crop keeps the centre only, whose strokes lean a few degrees differently from the
         * whole sample's: measure the rotated crop and correct the turn once more. */
        for (int pass = 0; pass < ALIGN_PASSES && !r; pass++) {
            internal_pam_img_free(&out->img[L - 1]);
            r = internal_pam_rotate(ctx, &rgb, turn, &out->img[L - 1]);
            if (!r) {
                internal_pam_orientation(&out->img[L - 1], &deg, &coh);
                turn += 90.0 - deg;
            }
        }
        internal_pam_img_free(&rgb);
        if (r) return r;
    } else {
        out->img[L - 1] = rgb;
    }
    for (int l = L - 2; l >= 0; l--)
        if ((r = internal_pam_reduce(ctx, &out->img[l + 1], &out->img[l]))) goto fail;
    for (int l = 0; l < L; l++) {
        level_geom g = geom(p, l);
        const internal_pam_img *im = &out->img[l];
        if (im->w < g.block || im->h < g.block) {
            r = nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                            "pam build: sample %d is too small: %dx%d%s gives %dx%d at pyramid "
                            "level %d, smaller than a block of %d pixels (patch + overlap at that "
                            "level); use a larger sample or a smaller patch",
                            index, nprfx_rect_width(view->bounds), nprfx_rect_height(view->bounds),
                            out->img[L - 1].w != nprfx_rect_width(view->bounds)
                                ? " (after rotating its strokes upright)"
                                : "",
                            im->w, im->h, l + 1, g.block);
            goto fail;
        }
        if ((r = internal_pam_features(ctx, im, &out->feat[l]))) goto fail;
    }
    return NPRFX_OK;
fail:
    pyr_free(out);
    return r;
}

/* Index of the smallest cost (the first of equals). */
static int argmin(const double *c, int n)
{
    int k = 0;
    for (int i = 1; i < n; i++)
        if (c[i] < c[k]) k = i;
    return k;
}

/* Raise the costs of candidates that reuse the source of an already placed tile nearby (raster
 * order with the wrap: a tile is placed when its index is below t). */
static void penalise_reuse(const internal_pam_level *lv, int t, const int *cx, const int *cy,
                           int nc, double *cost)
{
    int n = lv->n, i = t % n, j = t / n;
    int near[(2 * REUSE_RADIUS + 1) * (2 * REUSE_RADIUS + 1)], m = 0;
    for (int dj = -REUSE_RADIUS; dj <= REUSE_RADIUS; dj++)
        for (int di = -REUSE_RADIUS; di <= REUSE_RADIUS; di++) {
            int o = ((j + dj + n) % n) * n + (i + di + n) % n;
            int dup = 0;
            for (int k = 0; k < m; k++)
                dup |= near[k] == o;
            if (o < t && !dup) near[m++] = o;
        }
    for (int c = 0; c < nc; c++)
        for (int k = 0; k < m; k++)
            if (abs(cx[c] - lv->qx[near[k]]) < lv->tile &&
                abs(cy[c] - lv->qy[near[k]]) < lv->tile) {
                cost[c] *= 1.0 + REUSE_PENALTY;
                break;
            }
}

/* Quilting's randomness: one of the candidates whose cost is within (1 + tolerance) of the
 * best, chosen by the hash h (counter-based, so any thread count picks the same). */
static int choose(const double *cost, int nc, double tolerance, uint64_t h, int *pick)
{
    int k = argmin(cost, nc), m = 0;
    double lim = cost[k] * (1.0 + tolerance);
    for (int i = 0; i < nc; i++)
        if (cost[i] <= lim) pick[m++] = i;
    return pick[h % (uint64_t)m];
}

/* The hash of one choice: the seed, the sample, the level, the tile's position and the stream. */
static uint64_t pick_hash(const nprfx_pam_build_params *p, int sample, int l,
                          const internal_pam_level *lv, int t, uint32_t stream)
{
    return nprfx_hash(p->seed, sample, t % lv->n, t / lv->n, (uint32_t)l, stream);
}

/* Candidates around the upsampled block of tile t of the level below, clamped to src. */
static int refine_candidates(const internal_pam_level *below, level_geom gb, level_geom g,
                             const internal_pam_img *src, int t, int *cx, int *cy)
{
    int bx = 2 * (below->qx[t] + gb.overlap) - g.overlap;
    int by = 2 * (below->qy[t] + gb.overlap) - g.overlap;
    int last = below->n - 1,
        R = t % below->n == last || t / below->n == last ? REFINE_WRAP : REFINE;
    int n = 0;
    for (int dy = -R; dy <= R; dy++)
        for (int dx = -R; dx <= R; dx++) {
            int x = bx + dx, y = by + dy;
            x = x < 0 ? 0 : x > src->w - g.block ? src->w - g.block : x;
            y = y < 0 ? 0 : y > src->h - g.block ? src->h - g.block : y;
            cx[n] = x;
            cy[n] = y;
            n++;
        }
    return n;
}

/* The first key map, every level kept (the others follow its choices). */
static nprfx_result synth_first(nprfx_context *ctx, const nprfx_pam_build_params *p,
                                const sample_pyr *a, internal_pam_level *lv)
{
    int n = p->map_size / p->patch, L = p->levels;
    const internal_pam_img *s0 = &a->img[0];
    level_geom g0 = geom(p, 0);
    int maxc = (s0->w - g0.block + 1) * (s0->h - g0.block + 1);
    if (maxc < REFINE_MAX) maxc = REFINE_MAX;
    int *cx = malloc(sizeof(int) * (size_t)maxc), *cy = malloc(sizeof(int) * (size_t)maxc);
    int *pick = malloc(sizeof(int) * (size_t)maxc);
    double *cost = malloc(sizeof(double) * (size_t)maxc);
    nprfx_result r = NPRFX_OK;
    if (!cx || !cy || !pick || !cost) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam build: out of memory");
        goto done;
    }
    for (int l = 0; l < L && !r; l++) {
        level_geom g = geom(p, l);
        const internal_pam_img *src = &a->img[l];
        if ((r = internal_pam_level_init(ctx, n, g.tile, g.overlap, &lv[l]))) break;
        for (int t = 0; t < n * n && !r; t++) {
            int nc = 0;
            if (l == 0) {
                for (int y = 0; y + g.block <= src->h; y++)
                    for (int x = 0; x + g.block <= src->w; x++) {
                        cx[nc] = x;
                        cy[nc] = y;
                        nc++;
                    }
            } else {
                nc = refine_candidates(&lv[l - 1], geom(p, l - 1), g, src, t, cx, cy);
            }
            if ((r = internal_pam_overlap_costs(ctx, &lv[l], src, t, cx, cy, nc, cost))) break;
            penalise_reuse(&lv[l], t, cx, cy, nc, cost);
            /* Random among the near-best at every level: on the finer ones this is a jitter of a
             * pixel or two around the coarse choice, which still breaks exact repeats. */
            int k =
                choose(cost, nc, p->tolerance, pick_hash(p, 0, l, &lv[l], t, STREAM_PICK), pick);
            r = internal_pam_paste(ctx, &lv[l], src, t, cx[k], cy[k]);
        }
    }
done:
    free(cx);
    free(cy);
    free(pick);
    free(cost);
    return r;
}

/* A key map that follows the first one's layout (§4.3.1-4.3.2); the finest level is left in
 * *out (its image is the key map). */
static nprfx_result synth_follow(nprfx_context *ctx, const nprfx_pam_build_params *p,
                                 const sample_pyr *a, const internal_pam_level *alv,
                                 const sample_pyr *b, int sample, internal_pam_level *out)
{
    int n = p->map_size / p->patch, L = p->levels, T = n * n;
    internal_pam_level cur, prev;
    memset(&cur, 0, sizeof cur);
    memset(&prev, 0, sizeof prev);
    internal_pam_links *links = malloc(sizeof *links * (size_t)T);
    int cx[INTERNAL_PAM_MAX_LINKS + REFINE_MAX], cy[INTERNAL_PAM_MAX_LINKS + REFINE_MAX];
    double cost[INTERNAL_PAM_MAX_LINKS + REFINE_MAX];
    int pick[INTERNAL_PAM_MAX_LINKS + REFINE_MAX];
    nprfx_result r = NPRFX_OK;
    if (!links) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam build: out of memory");
    for (int l = 0; l < L && !r; l++) {
        level_geom g = geom(p, l);
        const internal_pam_img *src = &b->img[l];
        if ((r = internal_pam_level_init(ctx, n, g.tile, g.overlap, &cur))) break;
        /* The CSS from A to B at this level, for the blocks A's tiles came from (Eq. 3). */
        r = internal_pam_css_links(ctx, &a->feat[l], &b->feat[l], g.block, alv[l].qx, alv[l].qy, T,
                                   p->css_links, p->css_tolerance, links);
        /* Eq. 6's weight of the first key map at level l (1-based) of L. The paper's l / L gives
         * the finest level a weight of 1, which would make the route through the coarser level
         * unreachable there; l / (L + 1) keeps the paper's ordering with no degenerate level. */
        double w = (double)(l + 1) / (L + 1);
        for (int t = 0; t < T && !r; t++) {
            const internal_pam_links *lk = &links[t];
            int m = lk->n;
            for (int i = 0; i < m; i++) {
                cx[i] = lk->x[i];
                cy[i] = lk->y[i];
            }
            int nc = m, nr = 0;
            if (l > 0) nr = refine_candidates(&prev, geom(p, l - 1), g, src, t, cx + m, cy + m);
            nc += nr;
            if ((r = internal_pam_overlap_costs(ctx, &cur, src, t, cx, cy, nc, cost))) break;
            penalise_reuse(&cur, t, cx, cy, nc, cost);
            /* q*: a link among the near-best by overlap error (Eq. 4-5), and q**: the coarser
             * level's route; each drawn like the first key map's blocks. */
            int ks = choose(cost, m, p->tolerance,
                            pick_hash(p, sample, l, &cur, t, STREAM_FOLLOW_LINK), pick);
            int k = ks;
            if (l > 0) {
                int kr = m + choose(cost + m, nr, p->tolerance,
                                    pick_hash(p, sample, l, &cur, t, STREAM_FOLLOW_ROUTE), pick);
                if (w * cost[kr] < (1.0 - w) * cost[ks]) k = kr;
            }
            r = internal_pam_paste(ctx, &cur, src, t, cx[k], cy[k]);
        }
        internal_pam_level_free(&prev);
        prev = cur;
        memset(&cur, 0, sizeof cur);
    }
    free(links);
    internal_pam_level_free(&cur);
    if (r) {
        internal_pam_level_free(&prev);
        return r;
    }
    *out = prev;
    return NPRFX_OK;
}

nprfx_result nprfx_pam_build(nprfx_context *ctx, const nprfx_pam_build_params *params,
                             const nprfx_image *samples, int nsamples, nprfx_image *strip_out,
                             nprfx_pam_info *info_out)
{
    if (!params || !samples || !strip_out)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "pam build: NULL argument");
    if (params->size < sizeof(size_t) || params->size > sizeof(nprfx_pam_build_params))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam build: bad nprfx_pam_build_params size %zu", params->size);
    if (info_out && info_out->size != sizeof(nprfx_pam_info))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam build: bad nprfx_pam_info size %zu", info_out->size);
    /* Fields an older, shorter struct lacks keep their defaults. */
    nprfx_pam_build_params p = NPRFX_PAM_BUILD_PARAMS_DEFAULT;
    memcpy(&p, params, params->size);
    p.size = sizeof p;
    nprfx_result r = check_params(ctx, &p);
    if (r) return r;
    if (nsamples < 2)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam build: needs at least 2 samples (a PAM has 2 or more maps), got %d",
                           nsamples);
    for (int s = 0; s < nsamples; s++) {
        const nprfx_image *v = &samples[s];
        if (!v->data || v->channels < 3 || nprfx_rect_empty(v->bounds))
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "pam build: sample %d is not an RGB image (%d channels)", s,
                               v->data ? v->channels : 0);
        if (nprfx_rect_width(v->bounds) != nprfx_rect_width(samples[0].bounds) ||
            nprfx_rect_height(v->bounds) != nprfx_rect_height(samples[0].bounds))
            return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                               "pam build: sample %d is %dx%d but sample 0 is %dx%d (all samples "
                               "must have one size, so their strokes have one scale)",
                               s, nprfx_rect_width(v->bounds), nprfx_rect_height(v->bounds),
                               nprfx_rect_width(samples[0].bounds),
                               nprfx_rect_height(samples[0].bounds));
    }
    sample_pyr *pyr = calloc((size_t)nsamples, sizeof *pyr);
    internal_pam_level alv[MAX_LEVELS];
    internal_pam_img *keys = calloc((size_t)nsamples, sizeof *keys);
    memset(alv, 0, sizeof alv);
    if (!pyr || !keys) {
        free(pyr);
        free(keys);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam build: out of memory");
    }
    for (int s = 0; s < nsamples && !r; s++)
        r = prepare(ctx, &p, &samples[s], s, &pyr[s]);
    if (!r) r = synth_first(ctx, &p, &pyr[0], alv);
    if (!r) {
        /* The first key map is its finest level; take its image over. */
        keys[0] = alv[p.levels - 1].out;
        memset(&alv[p.levels - 1].out, 0, sizeof alv[0].out);
    }
    for (int s = 1; s < nsamples && !r; s++) {
        internal_pam_level fin;
        r = synth_follow(ctx, &p, &pyr[0], alv, &pyr[s], s, &fin);
        if (r) break;
        keys[s] = fin.out;
        memset(&fin.out, 0, sizeof fin.out);
        internal_pam_level_free(&fin);
    }
    if (!r) r = internal_pam_assemble(ctx, keys, nsamples, p.k, strip_out, info_out);
    for (int s = 0; s < nsamples; s++) {
        pyr_free(&pyr[s]);
        internal_pam_img_free(&keys[s]);
    }
    for (int l = 0; l < MAX_LEVELS; l++)
        internal_pam_level_free(&alv[l]);
    free(pyr);
    free(keys);
    return r;
}
