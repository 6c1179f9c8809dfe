/* pam-splat: a painterly art map splatted on the surfaces (Yan et al. 2008 §5, docs/design.md
 * §3.7). See nprfx/pam_splat.h for the interface.
 *
 * The splats are the points of gabor-splat's anchored-point scatter
 * (core/gabor/anchored_scatter.c): a constant number per screen area, anchored in Pref or UV, with
 * continuous level-of-detail weights w, each emitted once by its owner pixel with the depth and id
 * of its surface. They are rendered in the three passes of §5.1:
 *  1. visibility: the depth and id AOVs are the depth buffer (a renderer has already resolved
 *     what is visible); a splat reaches a pixel of its own object id whose depth is within the
 *     tolerance of the depth expected on the splat's plane (gabor-splat's hard test);
 *  2. accumulation: each fragment adds g = w exp(-pi a^2 sharpness (|d|^2 + (aspect^2 - 1)
 *     across^2)) (a as gabor's: 5% at the rim; narrower across the direction, so dabs are long
 *     and the nearest wins) times the texel's YUV deviation from its map's mean at the splat's
 *     texture coordinates and the fragment's tone, g to the weight and g times the splat's
 *     model colour;
 *  3. normalisation: D = (the tone's maps' mean - Eq. 9's mean) + detail * sum g dev / sum g,
 *     and the colour is Eq. 10 applied to the model colour (the splats' blend, or the pixel's):
 *     Y + beta D_Y, UV + gamma D_UV, back to RGB. detail = 1 is the paper's Eq. 10; more gives
 *     back the stroke contrast the average over overlapping splats takes away.
 * The tone is the fragment's; the model colour the splat's (the paper's, read at its owner
 * pixel: dab-shaped colour) or, with color_from pixel, the fragment's (sharp model edges).
 * A splat's texture coordinates, in PAM pixels: a hashed origin (Eq. 11's noise offsets, fixed
 * per splat) plus the screen offset from its centre, turned so that the map's rows (v, along
 * which its strokes run) follow the direction, divided by `texel`, and v moved back by
 * flow * time / texel, so the texture moves along the direction at `flow` pixels per frame.
 *
 * Output tiles visit the scatter's blocks in raster order and their points in emission order,
 * and every fragment's value depends only on (splat, pixel): bit-identical for any tiling. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "gabor/internal_scatter.h"
#include "base/internal_state.h"
#include "nprfx/exec.h"
#include "nprfx/pam_splat.h"
#include "nprfx/rng.h"

#define PAM_TILE 64
#define ACC 7 /* accumulated per pixel (tile_buf.acc) */

/* ---- the measured PAM, shared by the renders of an instance ---------------------------------- */

/* The PAM as splats read it: its info, each map's mean YUV and, per map, row and column, the
 * texel's YUV minus its map's mean (the stroke detail; the tone's part, the map's mean minus
 * Eq. 9's, is added per pixel after the splats are averaged). Reference-counted: a render keeps the
 * one it started with even if another render of the instance swaps in a new PAM. */
typedef struct pam_prep {
    int refs;
    uint64_t key;
    nprfx_pam_stats info;
    double map_mean[NPRFX_PAM_MAX_MAPS][3]; /* YUV */
    float *dev;                             /* count x S x S x 3 */
} pam_prep;

typedef struct pam_cache {
    pthread_mutex_t lock; /* first: internal_state.h */
    pam_prep *cur;
} pam_cache;

static void prep_free(pam_prep *p)
{
    if (!p) return;
    free(p->dev);
    free(p);
}

/* FNV-1a over the bits of the PAM's RGB and its size: an upstream change is noticed */
static uint64_t pam_key(const nprfx_image *pam)
{
    uint64_t h = 0xcbf29ce484222325ull;
    int w = nprfx_rect_width(pam->bounds), hh = nprfx_rect_height(pam->bounds);
    h = (h ^ (uint64_t)(uint32_t)w) * 0x100000001b3ull;
    h = (h ^ (uint64_t)(uint32_t)hh) * 0x100000001b3ull;
    for (int y = pam->bounds.y0; y < pam->bounds.y1; y++)
        for (int x = pam->bounds.x0; x < pam->bounds.x1; x++) {
            const float *p = nprfx_image_at(pam, x, y);
            for (int c = 0; c < 3; c++) {
                uint32_t b;
                memcpy(&b, &p[c], sizeof b);
                h = (h ^ b) * 0x100000001b3ull;
            }
        }
    return h;
}

static nprfx_result prep_make(nprfx_context *ctx, const nprfx_image *pam, uint64_t key,
                              pam_prep **out)
{
    pam_prep *p = calloc(1, sizeof *p);
    if (!p) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam-splat: out of memory");
    nprfx_result r = nprfx_pam_measure(ctx, pam, "pam-splat: input 'pam'", &p->info);
    if (r) {
        free(p);
        return r;
    }
    int n = p->info.count, S = p->info.size;
    p->dev = malloc(sizeof(float) * 3 * (size_t)n * S * S);
    if (!p->dev) {
        free(p);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam-splat: out of memory for the PAM");
    }
    for (int m = 0; m < n; m++) {
        double sum[3] = {0.0, 0.0, 0.0};
        for (int y = 0; y < S; y++)
            for (int x = 0; x < S; x++) {
                const float *px =
                    nprfx_image_at(pam, pam->bounds.x0 + m * S + x, pam->bounds.y0 + y);
                double rgb[3] = {px[0], px[1], px[2]}, yuv[3];
                nprfx_rgb_to_yuv(rgb, yuv);
                float *d = p->dev + (((size_t)m * S + y) * S + x) * 3;
                for (int c = 0; c < 3; c++) {
                    d[c] = (float)yuv[c];
                    sum[c] += yuv[c];
                }
            }
        for (int c = 0; c < 3; c++)
            p->map_mean[m][c] = sum[c] / ((double)S * S);
        float *d = p->dev + (size_t)m * S * S * 3;
        for (size_t k = 0; k < (size_t)S * S; k++)
            for (int c = 0; c < 3; c++)
                d[3 * k + c] = (float)(d[3 * k + c] - p->map_mean[m][c]);
    }
    p->key = key;
    p->refs = 1;
    *out = p;
    return NPRFX_OK;
}

/* The prepared PAM for this render (one reference for the caller). */
static nprfx_result prep_acquire(nprfx_context *ctx, void **state, const nprfx_image *pam,
                                 pam_prep **out)
{
    uint64_t key = pam_key(pam);
    pam_cache *c = state ? internal_state_get(state, sizeof *c) : NULL;
    if (!c) return prep_make(ctx, pam, key, out);
    nprfx_result r = NPRFX_OK;
    pthread_mutex_lock(&c->lock);
    if (!c->cur || c->cur->key != key) {
        pam_prep *p = NULL;
        r = prep_make(ctx, pam, key, &p);
        if (!r) {
            if (c->cur && --c->cur->refs == 0) prep_free(c->cur);
            c->cur = p; /* the cache's reference */
        }
    }
    if (!r) {
        c->cur->refs++;
        *out = c->cur;
    }
    pthread_mutex_unlock(&c->lock);
    return r;
}

static void prep_release(void **state, pam_prep *p)
{
    pam_cache *c = state && *state ? *state : NULL;
    if (!c) {
        prep_free(p);
        return;
    }
    pthread_mutex_lock(&c->lock);
    int last = --p->refs == 0;
    pthread_mutex_unlock(&c->lock);
    if (last) prep_free(p);
}

void nprfx_pam_splat_state_free(void *state)
{
    pam_cache *c = state;
    if (!c) return;
    prep_free(c->cur); /* renders are over: the cache holds the last reference */
    internal_state_free(c);
}

/* ---- splatting ------------------------------------------------------------------------------ */

/* The node's inputs (NPRFX_PAM_SPLAT_IN_*); NULL where not connected. */
typedef struct pam_inputs {
    const nprfx_image *anchor, *tone, *color, *direction, *depth, *id, *pam;
} pam_inputs;

typedef struct pam_job {
    const gjob *J;
    const pam_prep *pam;
    const nprfx_pam_splat_params *p;
    const pam_inputs *in;
    double radius, r2, pa2, inv_texel, shift, tol, theta0;
    double pa2s; /* the weights' Gaussian, narrowed by sharpness */
    double pa2x; /* its extra narrowing across the direction */
    nprfx_image *out;
    int ntx, nty;
    int *tile_ok;
    long long *tile_splats;
} pam_job;

/* A splat's frame on screen and its texture origin, from its point. */
typedef struct splat {
    double sx, sy, w, z, gzx, gzy;
    float id;
    double eux, euy, evx, evy; /* screen offset -> map columns (u) and rows (v), per pixel */
    double u0, v0;
    double yuv[3]; /* the model colour at the splat's owner pixel (color_from splat) */
} splat;

static void splat_setup(const pam_job *P, const gpoint *pt, splat *s)
{
    s->sx = pt->sx;
    s->sy = pt->sy;
    s->w = sqrt((double)pt->w2);
    s->z = pt->z;
    s->gzx = pt->gzx;
    s->gzy = pt->gzy;
    s->id = pt->id;
    double th = P->theta0;
    const nprfx_image *d = P->in->direction;
    if (d) {
        if (d->channels >= 2) {
            float dx = sample_input(d, pt->rx, pt->ry, 0, 0.0f);
            float dy = sample_input(d, pt->rx, pt->ry, 1, 0.0f);
            if (dx != 0.0f || dy != 0.0f) th += atan2(-(double)dy, (double)dx);
        } else {
            th += sample_input(d, pt->rx, pt->ry, 0, 0.0f) * (k_pi / 180.0);
        }
    }
    /* v along the direction (counter-clockwise, y down), u across it */
    double c = cos(th), sn = sin(th);
    s->evx = c * P->inv_texel;
    s->evy = -sn * P->inv_texel;
    s->eux = sn * P->inv_texel;
    s->euy = c * P->inv_texel;
    if (P->p->color_from == NPRFX_PAM_COLOR_SPLAT) {
        const nprfx_image *col = P->in->color;
        double rgb[3];
        for (int k = 0; k < 3; k++)
            rgb[k] = sample_input(col, pt->rx, pt->ry, k, 0.0f);
        nprfx_rgb_to_yuv(rgb, s->yuv);
    } else {
        s->yuv[0] = s->yuv[1] = s->yuv[2] = 0.0;
    }
    uint64_t h = nprfx_mix64(pt->h ^ 0x1f83d9abfb41bd6bull);
    double S = P->pam->info.size, j = P->p->jitter;
    s->u0 = j * S * nprfx_u01(h);
    s->v0 = j * S * nprfx_u01(nprfx_mix64(h)) - P->shift;
}

/* i mod S in [0, S). Maps are mostly a power of two in size, where a mask gives the same value
 * as the remainder without its division (two per texel, a sixth of the node's time). */
static inline int wrap_texel(int i, int S)
{
    if ((S & (S - 1)) == 0) return i & (S - 1);
    int r = i % S;
    return r < 0 ? r + S : r;
}

#if defined(__GNUC__)
#define TEXEL_INLINE static inline __attribute__((always_inline))
#else
#define TEXEL_INLINE static inline
#endif

/* Bilinear, wrapped (the maps tile), at (u, v) in map pixels of map m: adds f * texel to acc. */
TEXEL_INLINE void texel_add(const pam_prep *pp, int m, double u, double v, double f, double acc[3])
{
    int S = pp->info.size;
    double fu = u - 0.5, fv = v - 0.5;
    double cu = floor(fu), cv = floor(fv);
    double tu = fu - cu, tv = fv - cv;
    /* |u|, |v| stay far below 2^31 (a map offset plus a splat's reach, plus the flow) */
    int x0 = wrap_texel((int)cu, S), y0 = wrap_texel((int)cv, S);
    int x1 = x0 + 1 == S ? 0 : x0 + 1, y1 = y0 + 1 == S ? 0 : y0 + 1;
    const float *base = pp->dev + (size_t)m * S * S * 3;
    const float *a = base + ((size_t)y0 * S + x0) * 3, *b = base + ((size_t)y0 * S + x1) * 3;
    const float *c = base + ((size_t)y1 * S + x0) * 3, *d = base + ((size_t)y1 * S + x1) * 3;
    double wa = (1.0 - tu) * (1.0 - tv) * f, wb = tu * (1.0 - tv) * f;
    double wc = (1.0 - tu) * tv * f, wd = tu * tv * f;
    for (int k = 0; k < 3; k++)
        acc[k] += wa * a[k] + wb * b[k] + wc * c[k] + wd * d[k];
}

/* A tile's buffers: per pixel the tone's maps and mix, the accumulated deviation and weight. */
typedef struct tile_buf {
    int *mi;
    float *mt;
    double *acc; /* ACC per pixel: deviation Y, U, V, weight, the splats' model Y, U, V */
    double *gx;  /* a splat's envelope along its columns */
} tile_buf;

static void splat_one(const pam_job *P, const splat *s, int tx0, int ty0, int tx1, int ty1,
                      tile_buf *B)
{
    const gjob *J = P->J;
    int tw = tx1 - tx0;
    double R = P->radius;
    int xa = (int)ceil(s->sx - R), xb = (int)floor(s->sx + R);
    int ya = (int)ceil(s->sy - R), yb = (int)floor(s->sy + R);
    if (xa < tx0) xa = tx0;
    if (ya < ty0) ya = ty0;
    if (xb > tx1 - 1) xb = tx1 - 1;
    if (yb > ty1 - 1) yb = ty1 - 1;
    if (xa > xb || ya > yb) return;
    size_t ww = (size_t)nprfx_rect_width(J->window);
    double tolz = P->tol * s->z;
    for (int x = xa; x <= xb; x++) {
        double dx = x - s->sx;
        B->gx[x - xa] = exp(-P->pa2s * dx * dx);
    }
    for (int y = ya; y <= yb; y++) {
        double dy = y - s->sy;
        double gy = s->w * exp(-P->pa2s * dy * dy);
        const float *zr = J->zwin + (size_t)(y - J->window.y0) * ww - J->window.x0;
        const float *ir = J->idwin + (size_t)(y - J->window.y0) * ww - J->window.x0;
        for (int x = xa; x <= xb; x++) {
            double dx = x - s->sx;
            if (dx * dx + dy * dy > P->r2) continue;
            if (!id_eq(ir[x], s->id)) continue; /* no surface holds an id no splat has */
            double zp = s->z + s->gzx * dx + s->gzy * dy;
            if (!(fabs(zr[x] - zp) <= tolz)) continue;
            double g = gy * B->gx[x - xa];
            size_t o = (size_t)(y - ty0) * (size_t)tw + (size_t)(x - tx0);
            double du = dx * s->eux + dy * s->euy;
            if (P->pa2x > 0.0) g *= exp(-P->pa2x * du * du);
            double u = s->u0 + du;
            double v = s->v0 + dx * s->evx + dy * s->evy;
            double t = B->mt[o], dev[3] = {0.0, 0.0, 0.0};
            int m = B->mi[o];
            texel_add(P->pam, m, u, v, 1.0 - t, dev);
            if (t > 0.0) texel_add(P->pam, m + 1, u, v, t, dev);
            double *a = B->acc + ACC * o;
            a[0] += g * dev[0];
            a[1] += g * dev[1];
            a[2] += g * dev[2];
            a[3] += g;
            a[4] += g * s->yuv[0];
            a[5] += g * s->yuv[1];
            a[6] += g * s->yuv[2];
        }
    }
}

static void render_tile(pam_job *P, int t, tile_buf *B)
{
    const gjob *J = P->J;
    const pam_inputs *in = P->in;
    int tx0 = J->window.x0 + (t % P->ntx) * PAM_TILE, ty0 = J->window.y0 + (t / P->ntx) * PAM_TILE;
    int tx1 = tx0 + PAM_TILE < J->window.x1 ? tx0 + PAM_TILE : J->window.x1;
    int ty1 = ty0 + PAM_TILE < J->window.y1 ? ty0 + PAM_TILE : J->window.y1;
    int tw = tx1 - tx0;
    size_t npx = (size_t)tw * (size_t)(ty1 - ty0);
    memset(B->acc, 0, sizeof(double) * ACC * npx);
    for (int y = ty0; y < ty1; y++)
        for (int x = tx0; x < tx1; x++) {
            size_t o = (size_t)(y - ty0) * (size_t)tw + (size_t)(x - tx0);
            double tt;
            nprfx_pam_tone_position(&P->pam->info, sample_input(in->tone, x, y, 0, 0.0f), &B->mi[o],
                                    &tt);
            B->mt[o] = (float)tt;
        }
    /* pass 2: the splats within reach, blocks in raster order, points in emission order */
    int bxa = internal_scatter_floor_div(tx0 - J->reach, BLOCK);
    int bxb = internal_scatter_floor_div(tx1 - 1 + J->reach, BLOCK);
    int bya = internal_scatter_floor_div(ty0 - J->reach, BLOCK);
    int byb = internal_scatter_floor_div(ty1 - 1 + J->reach, BLOCK);
    if (bxa < J->bx0) bxa = J->bx0;
    if (bya < J->by0) bya = J->by0;
    if (bxb > J->bx0 + J->nbx - 1) bxb = J->bx0 + J->nbx - 1;
    if (byb > J->by0 + J->nby - 1) byb = J->by0 + J->nby - 1;
    long long owned = 0;
    for (int by = bya; by <= byb; by++)
        for (int bx = bxa; bx <= bxb; bx++) {
            const gblock *b = &J->blocks[(by - J->by0) * J->nbx + (bx - J->bx0)];
            for (int k = 0; k < b->n; k++) {
                const gpoint *pt = &b->p[k];
                if (pt->ox >= tx0 && pt->ox < tx1 && pt->oy >= ty0 && pt->oy < ty1) owned++;
                if (pt->sx + P->radius < tx0 || pt->sx - P->radius > tx1 - 1 ||
                    pt->sy + P->radius < ty0 || pt->sy - P->radius > ty1 - 1)
                    continue;
                splat s;
                splat_setup(P, pt, &s);
                splat_one(P, &s, tx0, ty0, tx1, ty1, B);
            }
        }
    /* pass 3: normalise, Eq. 10 on the model colour */
    size_t ww = (size_t)nprfx_rect_width(J->window);
    int och = P->out->channels;
    for (int y = ty0; y < ty1; y++)
        for (int x = tx0; x < tx1; x++) {
            size_t o = (size_t)(y - ty0) * (size_t)tw + (size_t)(x - tx0);
            float *dst = nprfx_image_at(P->out, x, y);
            float col[4];
            for (int c = 0; c < och; c++)
                col[c] = nprfx_rect_contains(in->color->bounds, x, y)
                             ? nprfx_image_at(in->color, x, y)[c]
                             : 0.0f;
            float zz = J->zwin[(size_t)(y - J->window.y0) * ww + (size_t)(x - J->window.x0)];
            const double *a = B->acc + ACC * o;
            if (!(zz > 0.0f) || !(a[3] > 0.0)) {
                /* background, or a surface pixel no splat reached: the model colour */
                for (int c = 0; c < och; c++)
                    dst[c] = col[c];
                continue;
            }
            double rgb[3] = {col[0], col[1], col[2]}, yuv[3], d[3];
            /* Eq. 9-10's deviation, texel - mean: the local maps' mean minus the PAM's (the
             * tone) plus the averaged strokes' own deviation, scaled by detail */
            const pam_prep *pp = P->pam;
            int m = B->mi[o];
            double t = B->mt[o];
            for (int c = 0; c < 3; c++)
                d[c] = (1.0 - t) * pp->map_mean[m][c] + t * pp->map_mean[m + 1][c] -
                       pp->info.mean[c] + P->p->detail * (a[c] / a[3]);
            if (P->p->color_from == NPRFX_PAM_COLOR_SPLAT)
                for (int c = 0; c < 3; c++)
                    yuv[c] = a[4 + c] / a[3]; /* each dab painted in its splat's colour */
            else
                nprfx_rgb_to_yuv(rgb, yuv);
            /* Eq. 10 paints on a canvas whose white is luminance 1: a brighter (HDR) colour is
             * painted at luminance 1 and scaled back, so its strokes keep the contrast they
             * have at white instead of vanishing into it */
            double hdr = yuv[0] > 1.0 ? yuv[0] : 1.0;
            yuv[0] = yuv[0] / hdr + P->p->beta * d[0];
            yuv[1] = yuv[1] / hdr + P->p->gamma * d[1];
            yuv[2] = yuv[2] / hdr + P->p->gamma * d[2];
            for (int c = 0; c < 3; c++)
                yuv[c] *= hdr;
            nprfx_yuv_to_rgb(yuv, rgb);
            for (int c = 0; c < 3; c++)
                dst[c] = (float)rgb[c];
            if (och > 3) dst[3] = col[3];
        }
    P->tile_splats[t] = owned;
    P->tile_ok[t] = 1;
}

static void render_tiles(void *user, int begin, int end, int worker)
{
    pam_job *P = user;
    (void)worker;
    tile_buf B;
    B.mi = malloc(sizeof(int) * PAM_TILE * PAM_TILE);
    B.mt = malloc(sizeof(float) * PAM_TILE * PAM_TILE);
    B.acc = malloc(sizeof(double) * ACC * PAM_TILE * PAM_TILE);
    B.gx = malloc(sizeof(double) * PAM_TILE);
    if (B.mi && B.mt && B.acc && B.gx)
        for (int t = begin; t < end; t++)
            render_tile(P, t, &B);
    free(B.mi);
    free(B.mt);
    free(B.acc);
    free(B.gx);
}

/* ---- the render ----------------------------------------------------------------------------- */

static nprfx_result check(nprfx_context *ctx, const nprfx_pam_splat_params *p, const pam_inputs *in,
                          const nprfx_image *out)
{
    if (!p || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "pam-splat: incomplete arguments");
    const struct {
        const nprfx_image *im;
        const char *name;
    } req[4] = {
        {in->anchor, "anchor"}, {in->tone, "tone"}, {in->color, "color"}, {in->depth, "depth"}};
    for (int k = 0; k < 4; k++)
        if (!req[k].im || !req[k].im->data)
            return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                               "pam-splat: input '%s' is not connected", req[k].name);
    if (p->color_from < 0 || p->color_from >= NPRFX_PAM_COLOR_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "pam-splat.color_from: no choice with index %d", p->color_from);
    if (!(p->aspect >= 1.0 && p->aspect <= 100.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "pam-splat.aspect: %g is outside [1, 100]",
                           p->aspect);
    if (p->anchor_space < 0 || p->anchor_space >= NPRFX_PAM_SPACE_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "pam-splat.anchor_space: no anchor space with index %d",
                           p->anchor_space);
    int dims = p->anchor_space == NPRFX_PAM_SPACE_UV ? 2 : 3;
    int ach = in->anchor->channels;
    if (ach < dims || ach > dims + 1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam-splat: input 'anchor' has %d channels; this anchor_space needs "
                           "%d (or %d with coverage), e.g. %s",
                           ach, dims, dims + 1, dims == 2 ? "plate:UV.U,UV.V" : "plate:Pref");
    if (in->tone->channels != 1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam-splat: input 'tone' has %d channels; 1 is needed",
                           in->tone->channels);
    if (in->color->channels < 3 || in->color->channels > 4)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam-splat: input 'color' has %d channels; RGB or RGBA is needed",
                           in->color->channels);
    if (out->channels != in->color->channels)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam-splat: the output has %d channels; input 'color' has %d",
                           out->channels, in->color->channels);
    if (in->direction && in->direction->data && in->direction->channels > 2)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam-splat: input 'direction' has %d channels; 1 (angle) or 2 "
                           "(direction) are supported",
                           in->direction->channels);
    if (!(p->size >= 1.0 && p->size <= 4096.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "pam-splat.size: %g is outside [1, 4096]",
                           p->size);
    if (!(p->density > 0.0 && p->density <= 1e4))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "pam-splat.density: %g is outside (0, 10000]", p->density);
    if (!(p->texel >= 0.0) || !(p->cell > 0.0) || !(p->depth_tolerance >= 0.0) ||
        !isfinite(p->flow) || !isfinite(p->beta) || !isfinite(p->gamma) || !isfinite(p->detail) ||
        !(p->sharpness >= 1.0 && p->sharpness <= 100.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "pam-splat: texel must not be negative, cell positive, depth_tolerance "
                           "not negative, sharpness in [1, 100], flow, beta, gamma and detail "
                           "finite");
    return NPRFX_OK;
}

nprfx_result nprfx_pam_splat_render(const nprfx_render_args *args, const nprfx_pam_splat_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    const pam_inputs inputs = {nprfx_render_input(args, NPRFX_PAM_SPLAT_IN_ANCHOR),
                               nprfx_render_input(args, NPRFX_PAM_SPLAT_IN_TONE),
                               nprfx_render_input(args, NPRFX_PAM_SPLAT_IN_COLOR),
                               nprfx_render_input(args, NPRFX_PAM_SPLAT_IN_DIRECTION),
                               nprfx_render_input(args, NPRFX_PAM_SPLAT_IN_DEPTH),
                               nprfx_render_input(args, NPRFX_PAM_SPLAT_IN_ID),
                               nprfx_render_input(args, NPRFX_PAM_SPLAT_IN_PAM)};
    const pam_inputs *in = &inputs;
    double time = args->time;
    void **state = args->state;
    nprfx_rect window = args->window;
    nprfx_image *out = args->output;
    /* args of the first release end before items */
    long long *splats = args->size > NPRFX_RENDER_ARGS_SIZE_V1 ? args->items : NULL;
    nprfx_result r = check(ctx, p, in, out);
    if (r) return r;
    window = nprfx_rect_intersect(window, out->bounds);
    if (nprfx_rect_empty(window)) return NPRFX_OK;

    nprfx_image builtin;
    memset(&builtin, 0, sizeof builtin);
    const nprfx_image *pam = in->pam && in->pam->data ? in->pam : NULL;
    if (!pam) {
        r = nprfx_pam_builtin(ctx, 0, 0, 0x9a1, &builtin);
        if (r) return r;
        pam = &builtin;
    }
    pam_prep *pp = NULL;
    r = prep_acquire(ctx, state, pam, &pp);
    nprfx_image_free(&builtin);
    if (r) return r;

    /* the scatter, configured as gabor-splat's with the splat's radius and density */
    nprfx_gabor_params gp;
    nprfx_gabor_params_default(&gp);
    gp.anchor_dims = p->anchor_space == NPRFX_PAM_SPACE_UV ? 2 : 3;
    gp.radius = 0.5 * p->size;
    gp.n0 = p->density;
    gp.seed = (uint64_t)p->seed;
    gp.cell = p->cell;
    gp.depth_tolerance = p->depth_tolerance;
    gp.amplitude = NPRFX_GABOR_AMP_SIGN;
    nprfx_gabor_inputs gi = {sizeof gi, in->anchor, in->depth, in->id, NULL, NULL};
    if (gi.id && !gi.id->data) gi.id = NULL;
    gconf G;
    internal_scatter_conf_init(&G, &gp, &gi);
    gjob J;
    internal_scatter_job_init(&J, &G, window, (int)ceil(gp.radius) + 1, out);

    pam_job P;
    memset(&P, 0, sizeof P);
    pam_inputs ins = *in;
    if (ins.direction && !ins.direction->data) ins.direction = NULL;
    P.J = &J;
    P.pam = pp;
    P.p = p;
    P.in = &ins;
    P.radius = gp.radius;
    P.r2 = gp.radius * gp.radius;
    double a = nprfx_gabor_bandwidth(gp.radius);
    P.pa2 = k_pi * a * a;
    P.pa2s = P.pa2 * p->sharpness;
    /* across the direction the Gaussian is aspect times narrower: dabs along the strokes */
    P.pa2x = P.pa2s * (p->aspect * p->aspect - 1.0); /* per map pixel^2: times texel^2 below */
    /* texel 0: a splat's diameter spans a quarter of a map, a few strokes wide for any PAM (the
     * builder's strokes are about a third of a map long), at any splat size */
    double texel = p->texel > 0.0 ? p->texel : p->size / (0.25 * pp->info.size);
    P.inv_texel = 1.0 / texel;
    P.pa2x *= texel * texel; /* du is in map pixels */
    /* Eq. 11: v_t = v_0 + noise_v + t flow; the maps tile, so the shift is taken modulo a map
     * (exactly: fmod is exact), which keeps texture coordinates small at any frame */
    P.shift = fmod(p->flow * time / texel, (double)pp->info.size);
    P.tol = p->depth_tolerance;
    P.theta0 = p->orientation * (k_pi / 180.0);
    P.out = out;
    P.ntx = (nprfx_rect_width(window) + PAM_TILE - 1) / PAM_TILE;
    P.nty = (nprfx_rect_height(window) + PAM_TILE - 1) / PAM_TILE;
    int ntiles = P.ntx * P.nty;
    P.tile_ok = calloc((size_t)ntiles, sizeof(int));
    P.tile_splats = calloc((size_t)ntiles, sizeof(long long));
    if (!P.tile_ok || !P.tile_splats) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam-splat: out of memory");
        goto done;
    }
    r = internal_scatter_emit(ctx, &J, "pam-splat"); /* pass 1's buffers and the splats */
    if (r) goto done;
    nprfx_parallel_for(nprfx_context_executor(ctx), ntiles, 1, render_tiles, &P);
    for (int t = 0; t < ntiles; t++) {
        if (!P.tile_ok[t]) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam-splat: out of memory for a tile");
            goto done;
        }
        if (splats) *splats += P.tile_splats[t];
    }
done:
    internal_scatter_job_free(&J);
    free(P.tile_ok);
    free(P.tile_splats);
    prep_release(state, pp);
    return r;
}
