/* The watercolor node (Bousseau, Kaplan, Thollot, Sillion, NPAR 2006): wobbling edges from the
 * paper's gradient, edge darkening from the colour gradient, then pigment turbulence, dispersion
 * and paper granulation, every effect a pigment density through the paper's colour model
 * (core/looks/internal_blend.h). Formulas in nprfx/watercolor.h and docs/design.md §3.14.
 *
 * A render runs in stages over rectangles that shrink towards the window: the paper's low-pass
 * and gradient, the gradient's local RMS, the wobbled colour Q, its blur B, then the output. Each
 * stage's rectangle is the next one's grown by the footprint it reads, cut to the frame; reads
 * clamp to the frame, so a rectangle's edge is only ever clamped to where it is the frame's edge,
 * and every tile computes each pixel from the same values by the same operations. */
#include <math.h>
#include <stdlib.h>

#include "internal_blend.h"
#include "nprfx/exec.h"
#include "nprfx/filter.h"
#include "nprfx/watercolor.h"

/* A paper slope below this (height per pixel) counts as flat, so that rounding noise on a
 * constant paper is never normalised up to a full wobble. */
#define FLAT_SLOPE 1e-5
/* The edge blur's kernel is cut at this many sigmas. */
#define EDGE_SIGMAS 3.0
#define MAX_LENGTH 256.0 /* px: the largest edge_width, wobble and wobble_scale accepted */

static inline int clampi(int v, int lo, int hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}
static inline double clamp01(double x)
{
    return x > 0.0 ? (x < 1.0 ? x : 1.0) : 0.0; /* NaN -> 0 */
}
static nprfx_rect grow(nprfx_rect r, int m, nprfx_rect frame)
{
    return nprfx_rect_intersect(nprfx_rect_make(r.x0 - m, r.y0 - m, r.x1 + m, r.y1 + m), frame);
}

/* An input's pixel nearest to (x, y) within its clamp rectangle. */
static inline const float *at_clamped(const nprfx_image *im, nprfx_rect c, int x, int y)
{
    return nprfx_image_at(im, clampi(x, c.x0, c.x1 - 1), clampi(y, c.y0, c.y1 - 1));
}

typedef struct wc_job {
    nprfx_rect frame, window;
    int nch, ncol;
    double turbulence, dispersion, granulation, edge_darkening, wobble;
    /* inputs, cropped to their data windows within the frame (NULL: not connected) */
    const nprfx_image *image, *turb, *disp, *paper, *cov;
    nprfx_rect ci, ct, cd, cp, ck; /* their clamp rectangles */
    /* wobble: the low-passed paper over rp; its gradient (gx, gy, |G|^2) over rg; the row sums
     * of |G|^2 over the box's width, over a's columns and rg's rows; the box radius */
    int wobbles, r;
    nprfx_rect rp, rg;
    nprfx_image pb, grad, hsum;
    /* the wobbled colour over a; the edge blur's horizontal pass (rb's columns, a's rows) and
     * result over rb; its taps w[k + re], |k| <= re */
    nprfx_rect a, rb;
    nprfx_image q, hq, b;
    int edges, re;
    double *w, edge_norm; /* edge_norm = 1 / (w_0 + w_1) */
    nprfx_image *out;
} wc_job;

/* G = grad(blur(P)) by central differences, and |G|^2, over rg. */
static void grad_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const wc_job *j = user;
    const nprfx_rect f = j->frame;
    for (int y = j->rg.y0 + begin; y < j->rg.y0 + end; y++) {
        const int ym = clampi(y - 1, f.y0, f.y1 - 1), yp = clampi(y + 1, f.y0, f.y1 - 1);
        for (int x = j->rg.x0; x < j->rg.x1; x++) {
            const int xm = clampi(x - 1, f.x0, f.x1 - 1), xp = clampi(x + 1, f.x0, f.x1 - 1);
            double gx = 0.5 * ((double)nprfx_image_at(&j->pb, xp, y)[0] -
                               (double)nprfx_image_at(&j->pb, xm, y)[0]);
            double gy = 0.5 * ((double)nprfx_image_at(&j->pb, x, yp)[0] -
                               (double)nprfx_image_at(&j->pb, x, ym)[0]);
            float *g = nprfx_image_at(&j->grad, x, y);
            g[0] = (float)gx;
            g[1] = (float)gy;
            g[2] = (float)(gx * gx + gy * gy);
        }
    }
}

/* Sums of |G|^2 along rows over the box's width, for a's columns (and rg's rows). Direct sums,
 * not running ones: a running sum's rounding would depend on where the tile starts it. */
static void hsum_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const wc_job *j = user;
    const nprfx_rect f = j->frame;
    for (int y = j->rg.y0 + begin; y < j->rg.y0 + end; y++)
        for (int x = j->a.x0; x < j->a.x1; x++) {
            double s = 0.0;
            for (int k = -j->r; k <= j->r; k++)
                s += nprfx_image_at(&j->grad, clampi(x + k, f.x0, f.x1 - 1), y)[2];
            nprfx_image_at(&j->hsum, x, y)[0] = (float)s;
        }
}

/* Step 1: the wobble offset o(p), and Q = K C(p + o) + (1 - K), over a. */
static void wobble_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const wc_job *j = user;
    const nprfx_rect f = j->frame;
    const double box = (double)(2 * j->r + 1) * (double)(2 * j->r + 1);
    float tmp[NPRFX_MAX_CHANNELS];
    for (int y = j->a.y0 + begin; y < j->a.y0 + end; y++)
        for (int x = j->a.x0; x < j->a.x1; x++) {
            double ox = 0.0, oy = 0.0;
            if (j->wobbles) {
                double s = 0.0;
                for (int k = -j->r; k <= j->r; k++)
                    s += nprfx_image_at(&j->hsum, x, clampi(y + k, f.y0, f.y1 - 1))[0];
                const float *g = nprfx_image_at(&j->grad, x, y);
                /* Dividing by |G| alone would tear the image at the paper's flat spots, where G
                 * turns; the local RMS N takes over there and brings the offset smoothly to 0. */
                double mag = sqrt((double)g[2]), rms = sqrt(s / box);
                double den = fmax(fmax(mag, rms), FLAT_SLOPE);
                ox = j->wobble * (double)g[0] / den;
                oy = j->wobble * (double)g[1] / den;
            }
            const float *c;
            double k = 1.0;
            if (ox == 0.0 && oy == 0.0) {
                /* no displacement: the pixel itself, bit for bit */
                c = at_clamped(j->image, j->ci, x, y);
                if (j->cov) k = clamp01(at_clamped(j->cov, j->ck, x, y)[0]);
            } else {
                nprfx_sample_bilinear(j->image, x + ox, y + oy, NPRFX_BORDER_CLAMP, tmp);
                c = tmp;
                if (j->cov) {
                    float kv;
                    nprfx_sample_bilinear(j->cov, x + ox, y + oy, NPRFX_BORDER_CLAMP, &kv);
                    k = clamp01(kv);
                }
            }
            float *q = nprfx_image_at(&j->q, x, y);
            for (int ch = 0; ch < j->ncol; ch++)
                /* background: white paper (k = 1 keeps c exactly) */
                q[ch] = j->cov ? (float)(k * c[ch] + (1.0 - k) * 1.0) : c[ch];
        }
}

/* acc[e] = sum over k of w[k] * src[e + k * step], k ascending from 0 and the sum in double: per
 * element the clamped loops' operations in their order, so the pixels are theirs bit for bit,
 * but over a run of pixels whose taps all lie inside the frame, a loop the compiler vectorises. */
static void conv_run(const double *w, int taps, const float *src, ptrdiff_t step, int n,
                     double *acc, float *dst)
{
    for (int e = 0; e < n; e++)
        acc[e] = 0.0;
    for (int k = 0; k < taps; k++) {
        const double wk = w[k];
        const float *s = src + (ptrdiff_t)k * step;
        for (int e = 0; e < n; e++)
            acc[e] += wk * s[e];
    }
    for (int e = 0; e < n; e++)
        dst[e] = (float)acc[e];
}

/* The edge blur at one pixel of a pass, its taps clamped to the frame. */
static void blur_px(const wc_job *j, const nprfx_image *src, int vertical, int x, int y, float *o)
{
    const nprfx_rect f = j->frame;
    double acc[NPRFX_MAX_CHANNELS] = {0};
    for (int k = -j->re; k <= j->re; k++) {
        const float *q = vertical ? nprfx_image_at(src, x, clampi(y + k, f.y0, f.y1 - 1))
                                  : nprfx_image_at(src, clampi(x + k, f.x0, f.x1 - 1), y);
        for (int ch = 0; ch < j->ncol; ch++)
            acc[ch] += j->w[k + j->re] * q[ch];
    }
    for (int ch = 0; ch < j->ncol; ch++)
        o[ch] = (float)acc[ch];
}

/* Step 2, the edge blur's horizontal pass: rb's columns, a's rows (q and hq are packed). */
static void hblur_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const wc_job *j = user;
    const nprfx_rect f = j->frame;
    const int C = j->ncol, re = j->re;
    /* the columns whose taps are all inside the frame */
    const int x0 = j->rb.x0 > f.x0 + re ? j->rb.x0 : f.x0 + re;
    const int x1 = j->rb.x1 < f.x1 - re ? j->rb.x1 : f.x1 - re;
    double *acc = x1 > x0 ? malloc(sizeof(double) * (size_t)(x1 - x0) * (size_t)C) : NULL;
    for (int y = j->a.y0 + begin; y < j->a.y0 + end; y++) {
        for (int x = j->rb.x0; x < j->rb.x1; x++) {
            if (acc && x == x0) {
                conv_run(j->w, 2 * re + 1, nprfx_image_at(&j->q, x0 - re, y), C, (x1 - x0) * C, acc,
                         nprfx_image_at(&j->hq, x0, y));
                x = x1 - 1;
                continue;
            }
            blur_px(j, &j->q, 0, x, y, nprfx_image_at(&j->hq, x, y));
        }
    }
    free(acc);
}

/* ... and its vertical pass, over rb. */
static void vblur_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const wc_job *j = user;
    const nprfx_rect f = j->frame;
    const int C = j->ncol, re = j->re, n = nprfx_rect_width(j->rb) * C;
    double *acc = malloc(sizeof(double) * (size_t)n);
    for (int y = j->rb.y0 + begin; y < j->rb.y0 + end; y++) {
        if (acc && y - re >= f.y0 && y + re < f.y1) {
            conv_run(j->w, 2 * re + 1, nprfx_image_at(&j->hq, j->rb.x0, y - re), j->hq.row_stride,
                     n, acc, nprfx_image_at(&j->b, j->rb.x0, y));
            continue;
        }
        for (int x = j->rb.x0; x < j->rb.x1; x++)
            blur_px(j, &j->hq, 1, x, y, nprfx_image_at(&j->b, x, y));
    }
    free(acc);
}

/* Step 2's density: d = 1 + edge_darkening * g, g the normalised colour gradient (pigment()
 * clamps densities to [0, 2]). */
static double edge_density(const wc_job *j, int x, int y)
{
    const nprfx_rect f = j->frame;
    const nprfx_image *b = j->re > 0 ? &j->b : &j->q;
    const float *xm = nprfx_image_at(b, clampi(x - 1, f.x0, f.x1 - 1), y);
    const float *xp = nprfx_image_at(b, clampi(x + 1, f.x0, f.x1 - 1), y);
    const float *ym = nprfx_image_at(b, x, clampi(y - 1, f.y0, f.y1 - 1));
    const float *yp = nprfx_image_at(b, x, clampi(y + 1, f.y0, f.y1 - 1));
    double s = 0.0;
    for (int ch = 0; ch < j->ncol; ch++) {
        double gx = 0.5 * ((double)xp[ch] - (double)xm[ch]);
        double gy = 0.5 * ((double)yp[ch] - (double)ym[ch]);
        s += gx * gx + gy * gy;
    }
    double g = sqrt(s / j->ncol) * j->edge_norm;
    return 1.0 + j->edge_darkening * g;
}

/* Steps 2 and 3 at the window's pixels: the densities in sequence through pigment(). */
static void paint_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const wc_job *j = user;
    for (int y = j->window.y0 + begin; y < j->window.y0 + end; y++)
        for (int x = j->window.x0; x < j->window.x1; x++) {
            double d[4];
            int nd = 0;
            if (j->edges) d[nd++] = edge_density(j, x, y);
            if (j->turb)
                d[nd++] =
                    internal_pigment_density(at_clamped(j->turb, j->ct, x, y)[0], j->turbulence);
            if (j->disp)
                d[nd++] =
                    internal_pigment_density(at_clamped(j->disp, j->cd, x, y)[0], j->dispersion);
            if (j->paper && j->granulation != 0.0)
                d[nd++] =
                    internal_pigment_density(at_clamped(j->paper, j->cp, x, y)[0], j->granulation);
            const float *q = nprfx_image_at(&j->q, x, y);
            float *o = nprfx_image_at(j->out, x, y);
            for (int ch = 0; ch < j->ncol; ch++) {
                double c = q[ch];
                for (int i = 0; i < nd; i++)
                    /* density exactly 1 changes nothing: skipped, so non-finite colours and
                     * textures at their mid-grey pass untouched */
                    if (d[i] != 1.0) c = internal_pigment(c, d[i]);
                o[ch] = (float)c;
            }
            if (j->nch > j->ncol) o[3] = at_clamped(j->image, j->ci, x, y)[3];
        }
}

/* An optional input: NULL when not connected or empty; else its view cropped to the frame, with
 * the check that it has one channel. */
static nprfx_result optional_input(nprfx_context *ctx, const char *name, const nprfx_image *im,
                                   nprfx_rect frame, nprfx_image *view, nprfx_rect *clampr,
                                   const nprfx_image **use)
{
    *use = NULL;
    if (!im || !im->data) return NPRFX_OK;
    if (im->channels != 1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "watercolor: input '%s' has %d channels, needs 1", name, im->channels);
    *clampr = nprfx_rect_intersect(im->bounds, frame);
    if (nprfx_rect_empty(*clampr)) return NPRFX_OK;
    *view = nprfx_image_crop(im, *clampr);
    *use = view;
    return NPRFX_OK;
}

static nprfx_result check_length(nprfx_context *ctx, const char *name, double v)
{
    if (v >= 0.0 && v <= MAX_LENGTH) return NPRFX_OK;
    return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "watercolor.%s: %g is outside [0, %g]", name, v,
                       MAX_LENGTH);
}

static nprfx_result check_amount(nprfx_context *ctx, const char *name, double v)
{
    if (isfinite(v)) return NPRFX_OK;
    return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "watercolor.%s: %g is not a number", name, v);
}

nprfx_result nprfx_watercolor_render(const nprfx_render_args *args,
                                     const nprfx_watercolor_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    nprfx_rect frame = args->frame, window = args->window;
    nprfx_image *out = args->output;
    if (!p || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "watercolor: no params, inputs or output");
    nprfx_result r;
    if ((r = check_amount(ctx, "turbulence", p->turbulence)) ||
        (r = check_amount(ctx, "dispersion", p->dispersion)) ||
        (r = check_amount(ctx, "granulation", p->granulation)))
        return r;
    if (!(p->edge_darkening >= 0.0 && isfinite(p->edge_darkening)))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "watercolor.edge_darkening: %g is not a number >= 0", p->edge_darkening);
    if ((r = check_length(ctx, "edge_width", p->edge_width)) ||
        (r = check_length(ctx, "wobble", p->wobble)) ||
        (r = check_length(ctx, "wobble_scale", p->wobble_scale)))
        return r;
    const nprfx_image *image = nprfx_render_input(args, NPRFX_WATERCOLOR_IN_IMAGE);
    if (!image || !image->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "watercolor: input 'image' is not connected");
    if (image->channels < 1 || image->channels > 4)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "watercolor: input 'image' has %d channels; 1 to 4 are supported",
                           image->channels);
    if (out->channels != image->channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "watercolor: output has %d channels, input 'image' %d", out->channels,
                           image->channels);

    wc_job j = {0};
    j.frame = frame;
    j.window = nprfx_rect_intersect(nprfx_rect_intersect(window, out->bounds), frame);
    if (nprfx_rect_empty(j.window)) return NPRFX_OK;
    j.out = out;
    j.nch = image->channels;
    j.ncol = j.nch == 4 ? 3 : j.nch;
    j.ci = nprfx_rect_intersect(image->bounds, frame);
    if (nprfx_rect_empty(j.ci))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "watercolor: input 'image' is empty");
    nprfx_image vi = nprfx_image_crop(image, j.ci), vt, vd, vp, vk;
    j.image = &vi;
    const nprfx_image *turbulence = nprfx_render_input(args, NPRFX_WATERCOLOR_IN_TURBULENCE);
    const nprfx_image *dispersion = nprfx_render_input(args, NPRFX_WATERCOLOR_IN_DISPERSION);
    const nprfx_image *paper = nprfx_render_input(args, NPRFX_WATERCOLOR_IN_PAPER);
    const nprfx_image *coverage = nprfx_render_input(args, NPRFX_WATERCOLOR_IN_COVERAGE);
    if ((r = optional_input(ctx, "turbulence", turbulence, frame, &vt, &j.ct, &j.turb)) ||
        (r = optional_input(ctx, "dispersion", dispersion, frame, &vd, &j.cd, &j.disp)) ||
        (r = optional_input(ctx, "paper", paper, frame, &vp, &j.cp, &j.paper)) ||
        (r = optional_input(ctx, "coverage", coverage, frame, &vk, &j.ck, &j.cov)))
        return r;
    j.turbulence = p->turbulence;
    j.dispersion = p->dispersion;
    j.granulation = p->granulation;
    j.edge_darkening = p->edge_darkening;
    j.wobble = p->wobble;
    j.wobbles = j.paper && p->wobble > 0.0;
    j.edges = p->edge_darkening > 0.0;

    /* The rectangles, from the window outwards. */
    j.re = j.edges && p->edge_width > 0.0 ? (int)ceil(EDGE_SIGMAS * p->edge_width) : 0;
    j.rb = grow(j.window, 1, frame);
    j.a = j.edges ? grow(j.window, j.re + 1, frame) : j.window;
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    double *w = NULL;
    r = nprfx_image_alloc(ctx, j.a, j.ncol, &j.q);
    if (!r && j.wobbles) {
        j.r = (int)ceil(p->wobble_scale);
        if (j.r < 1) j.r = 1;
        j.rg = grow(j.a, j.r, frame);
        j.rp = grow(j.rg, 1, frame);
        nprfx_rect hs = {j.a.x0, j.rg.y0, j.a.x1, j.rg.y1};
        if (!(r = nprfx_image_alloc(ctx, j.rp, 1, &j.pb)) &&
            !(r = nprfx_image_alloc(ctx, j.rg, 3, &j.grad)) &&
            !(r = nprfx_image_alloc(ctx, hs, 1, &j.hsum)) &&
            /* The low-pass reads the paper input itself, the same source for every tile (its
             * recursive filter's result depends on the source's extent, not the tile's). */
            !(r = nprfx_gaussian_blur(ctx, j.paper, &j.pb, p->wobble_scale, NPRFX_BORDER_CLAMP))) {
            nprfx_parallel_for(ex, nprfx_rect_height(j.rg), 8, grad_rows, &j);
            nprfx_parallel_for(ex, nprfx_rect_height(j.rg), 8, hsum_rows, &j);
        }
    }
    if (!r) nprfx_parallel_for(ex, nprfx_rect_height(j.a), 8, wobble_rows, &j);
    if (!r && j.edges) {
        /* Sampled Gaussian taps of our own rather than nprfx_gaussian_blur: Q exists only over
         * this tile's rectangle, and that blur's recursive filter (sigma >= 3) would give
         * results that depend on the rectangle. */
        w = malloc(sizeof(double) * (size_t)(2 * j.re + 1));
        if (!w) r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "watercolor: out of memory");
    }
    if (!r && j.edges) {
        double sum = 0.0;
        for (int k = -j.re; k <= j.re; k++)
            sum += w[k + j.re] =
                j.re ? exp(-(double)k * k / (2.0 * p->edge_width * p->edge_width)) : 1.0;
        for (int k = 0; k <= 2 * j.re; k++)
            w[k] /= sum;
        j.w = w;
        /* A step of height h, blurred, has central differences h (w_0 + w_1) / 2 on either side
         * of it: dividing by w_0 + w_1 makes the darkening's strength independent of its
         * width. */
        j.edge_norm = 1.0 / (w[j.re] + (j.re ? w[j.re + 1] : 0.0));
        if (j.re > 0) {
            nprfx_rect hr = {j.rb.x0, j.a.y0, j.rb.x1, j.a.y1};
            if (!(r = nprfx_image_alloc(ctx, hr, j.ncol, &j.hq)) &&
                !(r = nprfx_image_alloc(ctx, j.rb, j.ncol, &j.b))) {
                nprfx_parallel_for(ex, nprfx_rect_height(j.a), 8, hblur_rows, &j);
                nprfx_parallel_for(ex, nprfx_rect_height(j.rb), 8, vblur_rows, &j);
            }
        }
    }
    if (!r) nprfx_parallel_for(ex, nprfx_rect_height(j.window), 8, paint_rows, &j);
    free(w);
    nprfx_image_free(&j.pb);
    nprfx_image_free(&j.grad);
    nprfx_image_free(&j.hsum);
    nprfx_image_free(&j.q);
    nprfx_image_free(&j.hq);
    nprfx_image_free(&j.b);
    return r;
}
