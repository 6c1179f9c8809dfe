/* NPR Gabor noise splatted from point-cloud AOVs (docs/design.md §3.2; Benard et al. 2010, Lagae et
 * al. 2009). See nprfx/gabor.h for the interface.
 *
 * The render runs in two phases over a region E = window grown by the kernel reach, cut into
 * BLOCK x BLOCK pixel blocks on a grid fixed in frame coordinates:
 *
 * 1. Emission, per block. Each pixel (of the block and of a 1-pixel ring around it) gets its
 *    anchor A, the Jacobian J = dA/d(x,y) from finite differences that stay on its own surface,
 *    the pseudo-inverse J+ that maps anchor offsets to screen offsets, and its wanted point
 *    density. Per surface patch of the block and per level, the block enumerates the
 *    anchor-space cells its pixels' footprints touch (once per block, not once per pixel, so
 *    the cost per pixel stays bounded) and, for each cell's point, finds the pixel that owns
 *    it: the one in whose own linearisation p + J+_p (a - A_p) the point lies nearest the
 *    pixel centre. Each visible point is emitted once, by its owner, with the level weight and
 *    (3D anchors) the slab test evaluated on the surface interpolated at its exact position.
 * 2. Splatting, per output tile. A tile visits the blocks within kernel reach in block raster
 *    order and each block's points in emission order, and adds every kernel to the samples it
 *    covers that pass the object-id and depth tests. Every sample therefore sums the same
 *    kernels in the same order whatever the tile split or thread count, and each kernel's value
 *    at a sample is a function of (kernel, sample) only (its tables start at the kernel's own
 *    bounding box, never at a tile edge): the output is bit-identical for any tiling.
 *
 * Where this departs from the letter of docs/design.md §3.2, and why:
 *  - the level window: W levels are kept whole, the finer one fades in and the coarser one
 *    fades out, instead of levels 0..L all whole; the cost per pixel then does not grow with
 *    zoom, and the fading-out level carries at most 3 / (4^(W+1) - 1) of the variance;
 *  - ownership by nearest centre rather than "falls in the owner's square": on curved surfaces
 *    neighbouring linearisations disagree and a square rule leaves gaps (lost, popping points)
 *    and overlaps; the nearest-centre rule is a partition;
 *  - the 3D slab has a soft edge, and the slab distance and level weight are read on the
 *    surface interpolated at the point rather than at the owner's centre: both then barely
 *    change when ownership passes between pixels, so points do not flicker;
 *  - one point per cell (K = 1: a jittered grid; the spectrum of the noise does not depend on
 *    the point process, only on the density and the amplitudes);
 *  - the depth test compares with the depth expected on the kernel's plane (its centre's depth
 *    extended along the depth gradient), so kernels are not cut on slanted surfaces.
 *
 * Pixels outside the inputs (a margin the kernels must still come from, or the frame edge) are
 * virtual: they extrapolate the nearest real pixel's anchor and depth along its Jacobian, so
 * kernels keep their density up to the frame edge and slide in smoothly instead of popping.
 *
 * Files: core/gabor/anchored_scatter.c runs phase 1 (strips, emission rows; shared with pam-splat,
 * internal_scatter.h); this one runs phase 2 (splat tiles, normalisation) and picks its paths;
 * gabor_kernel.c has the params, variance, level-of-detail tables and a kernel's setup;
 * gabor_pixels.c a block's pixel attributes and patch labels; gabor_emit.c its cells, owner search
 * and points; gabor_splatting.c adds a tile's kernels to its samples; internal_gabor.h holds what
 * they share (the vector helpers and the level-of-detail rule among it).
 *
 * Speed (target: a 1080p frame at N0 = 32 in 150 ms on two cores). The work per
 * frame is about 2.2M pixel attributes, 1.3M anchor cells hashed, 0.75M owner searches, 0.24M
 * kernels and 190M kernel-sample evaluations (N0 = 128: 4x the last three). What keeps it fast:
 *  - the inputs are read from the plates once per row of blocks into a worker's strip (planes),
 *    each block's window is copied from it, and emission also writes the window's depth and id
 *    planes the splat tiles read; scratch is allocated once per render and worker, never per
 *    block or tile (no frame-sized copies, few fresh pages), and points go into per-worker
 *    chunks of 8192, each block's contiguous in one (not a list per block grown by realloc);
 *  - a block's pixels live in planes (structure of arrays); interior flags, Jacobians and the
 *    per-pixel attributes are computed 8 pixels at a time, with scalar code only for pixels at
 *    edges or outside the inputs; patch links are vector masks, and a block whose pixels all
 *    link is one patch without a flood fill; patch footprints are vector reductions;
 *  - a row of anchor cells is hashed 8 cells at a time, with the points' positions and the
 *    cheap tests (stagger start, slab around the reference tangent plane) in vectors; only the
 *    cells that pass go on to the owner search, one by one in their order;
 *  - the owner search's 3 x 3 descent evaluates the 8 neighbours in one vector;
 *  - a kernel's exp and sincos (its envelope and phase at its first sample) are the project's
 *    own (core/base/internal_vmath.h), run for 8 points at a time on the vector paths: the same
 *    numbers on every path and platform, where libm's differ between C libraries;
 *  - splatting computes a kernel's row spans and row depths 8 (AVX2: 4) rows at a time, runs
 *    the factor-table recurrences of 4 kernels in the lanes of a vector, and adds rows 8
 *    samples at a time with the depth-test mode a constant.
 * The vector code is GCC/Clang vector extensions compiled for AVX-512 and AVX2 and picked at
 * run time; it performs the scalar code's IEEE operations in the same order, lane by lane (no
 * FMA: -ffp-contract=off), so every path gives bit-identical output (nprfx_gabor_params.simd
 * selects one for the tests). Other CPUs run the scalar emission and 4-lane vector rows.
 * Profile, one thread on a 2-core AMD EPYC (Zen 4, AVX-512), N0 = 32, ms per frame: emission
 * ~150 (inputs 14, pixel attributes 40, patches 6, owner search 35, cell enumeration, level
 * weights, slab tests and kernel setup 55), splatting ~90 (rows 55, spans 15, tables 10, tile
 * setup and output 10). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_scatter.h"
#include "nprfx/exec.h"

/* splat tiles, in samples: few kernels straddle two (each does its tables again), and a tile's
 * buffers stay in cache */
#define TILE_SAMPLES 320

/* ---- the paths ------------------------------------------------------------------------------- */

/* simd: 0 the fastest path, 1 scalar, 2 the baseline ISA's vectors, 3 AVX2 (as 2 without it) */
static splat_fn pick_splat_fn(int simd)
{
#if GABOR_VEC
    if (simd == 1) return internal_gabor_splat_points_scalar;
#if GABOR_X86
    if (simd == 0 && internal_scatter_cpu_avx512()) return internal_gabor_splat_points_avx512;
    if ((simd == 0 || simd == 3) && internal_scatter_cpu_avx2())
        return internal_gabor_splat_points_avx2;
#endif
    return internal_gabor_splat_points_rows;
#else
    (void)simd;
    return internal_gabor_splat_points_scalar;
#endif
}

/* ---- the render: phase 2, the splat tiles (phase 1 is core/gabor/anchored_scatter.c)
 * --------------- */

/* A splat worker's buffers, for tiles of up to J->tile x J->tile pixels. */
typedef struct splat_scratch {
    float *acc, *zt, *idt, *tab;
    int *span;
} splat_scratch;

static size_t splat_tabn(const gjob *J)
{
    return (size_t)ceil(2.0 * J->G->radius * J->G->ss) + 4 + VPAD;
}

static size_t splat_npx(const gjob *J)
{
    size_t w = (size_t)J->tile * (size_t)J->G->ss;
    return w * w + VPAD;
}

static void splat_scratch_free(splat_scratch *b)
{
    if (!b) return;
    free(b->acc);
    free(b->zt);
    free(b->idt);
    free(b->tab);
    free(b->span);
    free(b);
}

static splat_scratch *splat_scratch_new(const gjob *J)
{
    splat_scratch *b = calloc(1, sizeof *b);
    if (!b) return NULL;
    size_t npx = splat_npx(J), tabn = splat_tabn(J);
    b->acc = malloc(sizeof(float) * npx);
    b->zt = malloc(sizeof(float) * npx);
    b->idt = malloc(sizeof(float) * npx);
    b->tab = calloc(SPLAT_BATCH * 5 * tabn, sizeof(float));
    b->span = calloc(SPLAT_BATCH * 2 * tabn, sizeof(int));
    if (!b->acc || !b->zt || !b->idt || !b->tab || !b->span) {
        splat_scratch_free(b);
        return NULL;
    }
    return b;
}

static void splat_tile(gjob *J, int t, splat_scratch *B)
{
    const gconf *G = J->G;
    const gsrc *S = &G->S;
    int s = G->ss;
    int tx0 = J->window.x0 + (t % J->ntx) * J->tile, ty0 = J->window.y0 + (t / J->ntx) * J->tile;
    int tx1 = tx0 + J->tile < J->window.x1 ? tx0 + J->tile : J->window.x1;
    int ty1 = ty0 + J->tile < J->window.y1 ? ty0 + J->tile : J->window.y1;
    int W = (tx1 - tx0) * s, H = (ty1 - ty0) * s;
    int TX0 = tx0 * s, TY0 = ty0 * s, TX1 = tx1 * s, TY1 = ty1 * s; /* sample coordinates */
    int tabn = (int)splat_tabn(J);
    size_t npx = (size_t)W * (size_t)H + VPAD;
    float *acc = B->acc, *zt = B->zt, *idt = B->idt, *tab = B->tab;
    int *span = B->span;
    memset(acc, 0, sizeof(float) * npx);
    const float none = id_none();
    size_t ww = (size_t)nprfx_rect_width(J->window);
    for (int y = ty0; y < ty1; y++) {
        size_t wo = (size_t)(y - J->window.y0) * ww + (size_t)(tx0 - J->window.x0);
        const float *zr = J->zwin + wo, *ir = J->idwin + wo;
        if (s == 1) {
            memcpy(zt + (size_t)(y - ty0) * (size_t)W, zr, sizeof(float) * (size_t)(tx1 - tx0));
            memcpy(idt + (size_t)(y - ty0) * (size_t)W, ir, sizeof(float) * (size_t)(tx1 - tx0));
            continue;
        }
        for (int x = tx0; x < tx1; x++)
            for (int j = 0; j < s; j++)
                for (int i = 0; i < s; i++) {
                    size_t o =
                        (size_t)((y - ty0) * s + j) * (size_t)W + (size_t)((x - tx0) * s + i);
                    zt[o] = zr[x - tx0];
                    idt[o] = ir[x - tx0];
                }
    }
    for (size_t i = npx - VPAD; i < npx; i++) {
        zt[i] = 0.0f;
        idt[i] = none;
    }
    long long kernels = 0;
    double w2sum = 0.0;
    gtile T;
    T.acc = acc;
    T.zt = zt;
    T.idt = idt;
    T.W = W;
    T.TX0 = TX0;
    T.TY0 = TY0;
    T.TX1 = TX1;
    T.TY1 = TY1;
    T.tabn = tabn;
    T.tab = tab;
    T.span = span;
    T.evals = 0;
    T.bxa = internal_scatter_floor_div(tx0 - J->reach, BLOCK),
    T.bxb = internal_scatter_floor_div(tx1 - 1 + J->reach, BLOCK);
    T.bya = internal_scatter_floor_div(ty0 - J->reach, BLOCK),
    T.byb = internal_scatter_floor_div(ty1 - 1 + J->reach, BLOCK);
    if (T.bxa < J->bx0) T.bxa = J->bx0;
    if (T.bya < J->by0) T.bya = J->by0;
    if (T.bxb > J->bx0 + J->nbx - 1) T.bxb = J->bx0 + J->nbx - 1;
    if (T.byb > J->by0 + J->nby - 1) T.byb = J->by0 + J->nby - 1;
    J->splat(J, &T);
    /* normalise and write */
    double inv_ss = 1.0 / ((double)s * s);
    double sigma0 = sqrt(G->var_k1 * (1.0 + exp(-2.0 * k_pi * G->F0 * G->F0 / (G->a * G->a))));
    for (int y = ty0; y < ty1; y++)
        for (int x = tx0; x < tx1; x++) {
            float *o = nprfx_image_at(J->out, x, y);
            double sum = 0.0;
            for (int j = 0; j < s; j++)
                for (int i = 0; i < s; i++)
                    sum +=
                        acc[(size_t)((y - ty0) * s + j) * (size_t)W + (size_t)((x - tx0) * s + i)];
            double sigma = sigma0;
            if (S->freq) {
                double F = G->F0 * sample_input(S->freq, x, y, 0, 1.0f);
                sigma = sqrt(G->var_k1 * (1.0 + exp(-2.0 * k_pi * F * F / (G->a * G->a))));
            }
            double v = sum * inv_ss / sigma;
            if (G->output == NPRFX_GABOR_OUT_UNIT01) v = 0.5 + G->contrast * v;
            o[0] = (float)v;
            if (G->points) o[1] = 0.0f;
        }
    /* owned points: the debug channel and the statistics */
    int cbxa = internal_scatter_floor_div(tx0, BLOCK),
        cbxb = internal_scatter_floor_div(tx1 - 1, BLOCK);
    int cbya = internal_scatter_floor_div(ty0, BLOCK),
        cbyb = internal_scatter_floor_div(ty1 - 1, BLOCK);
    for (int by = cbya; by <= cbyb; by++)
        for (int bx = cbxa; bx <= cbxb; bx++) {
            const gblock *b = &J->blocks[(by - J->by0) * J->nbx + (bx - J->bx0)];
            for (int k = 0; k < b->n; k++) {
                const gpoint *p = &b->p[k];
                if (p->ox < tx0 || p->ox >= tx1 || p->oy < ty0 || p->oy >= ty1) continue;
                kernels++;
                w2sum += p->w2;
                if (G->points) nprfx_image_at(J->out, p->ox, p->oy)[1] += p->w2;
            }
        }
    J->t_kernels[t] = kernels;
    J->t_evals[t] = T.evals;
    J->t_w2[t] = w2sum;
    J->tile_ok[t] = 1;
}

static void splat_tiles(void *user, int begin, int end, int worker)
{
    gjob *J = user;
    for (int t = begin; t < end; t++)
        splat_tile(J, t, J->scratch[worker]);
}

nprfx_result nprfx_gabor_render(nprfx_context *ctx, const nprfx_gabor_params *p,
                                const nprfx_gabor_inputs *in, nprfx_rect window, nprfx_image *out,
                                nprfx_gabor_stats *stats)
{
    if (stats) memset(stats, 0, sizeof *stats);
    if (!p || p->size < sizeof *p || !in || in->size < sizeof *in || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "gabor: incomplete arguments");
    if (!in->anchor || !in->anchor->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "gabor: input 'anchor' is missing");
    if (!in->depth || !in->depth->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "gabor: input 'depth' is missing");
    if (p->anchor_dims != 2 && p->anchor_dims != 3)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "gabor: anchor_dims is %d; 2 (UV) or 3 (Pref, P) are supported",
                           p->anchor_dims);
    if (in->anchor->channels < p->anchor_dims)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "gabor: input 'anchor' has %d channels; a %dD anchor needs %d",
                           in->anchor->channels, p->anchor_dims, p->anchor_dims);
    if (!(p->frequency > 0.0 && p->frequency <= 1e3))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "gabor: frequency %g is outside (0, 1000] cycles per pixel",
                           p->frequency);
    if (!(p->radius >= 0.25 && p->radius <= 4096))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: radius %g is outside [0.25, 4096]",
                           p->radius);
    if (!(p->n0 > 0.0 && p->n0 <= 1e5))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: n0 %g is outside (0, 100000]",
                           p->n0);
    if (!(p->cell > 0.0 && isfinite(p->cell)))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: cell %g is not positive", p->cell);
    if (p->lod_levels < 1 || p->lod_levels > 30)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: lod_levels %d is outside [1, 30]",
                           p->lod_levels);
    if (p->supersample < 1 || p->supersample > 16)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: supersample %d is outside [1, 16]",
                           p->supersample);
    if (p->depth_test < 0 || p->depth_test >= NPRFX_GABOR_DEPTH_COUNT || p->amplitude < 0 ||
        p->fade < 0 || p->fade >= NPRFX_GABOR_FADE_COUNT || p->amplitude >= NPRFX_GABOR_AMP_COUNT ||
        p->output < 0 || p->output >= NPRFX_GABOR_OUT_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "gabor: depth_test, amplitude, fade or "
                           "output is not a known choice");
    if (!(p->depth_tolerance >= 0.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: depth_tolerance %g is negative",
                           p->depth_tolerance);
    if (out->channels != 1 + (p->points != 0))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "gabor: the output has %d channels, expected %d", out->channels,
                           1 + (p->points != 0));
    window = nprfx_rect_intersect(window, out->bounds);
    if (nprfx_rect_empty(window)) return NPRFX_OK;

    gconf G;
    internal_scatter_conf_init(&G, p, in);

    gjob J;
    /* an owner lies within r + 1/2 of its point, a sample within 1/2 of its pixel centre */
    internal_scatter_job_init(&J, &G, window, (int)ceil(p->radius) + 1, out);
    J.tile = TILE_SAMPLES / p->supersample > 32 ? TILE_SAMPLES / p->supersample : 32;
    J.splat = pick_splat_fn(p->simd);
    J.ntx = (nprfx_rect_width(window) + J.tile - 1) / J.tile;
    J.nty = (nprfx_rect_height(window) + J.tile - 1) / J.tile;
    int ntiles = J.ntx * J.nty;
    J.tile_ok = calloc((size_t)ntiles, sizeof(int));
    J.t_kernels = calloc((size_t)ntiles, sizeof(long long));
    J.t_evals = calloc((size_t)ntiles, sizeof(long long));
    J.t_w2 = calloc((size_t)ntiles, sizeof(double));
    nprfx_result r = NPRFX_OK;
    if (!J.tile_ok || !J.t_kernels || !J.t_evals || !J.t_w2) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "gabor: out of memory");
        goto done;
    }
    r = internal_scatter_emit(ctx, &J, "gabor");
    if (r) goto done;
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    int ok = 1;
    for (int i = 0; i < J.nworkers && ok; i++)
        ok = (J.scratch[i] = splat_scratch_new(&J)) != NULL;
    if (!ok) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "gabor: out of memory for the tiles");
        goto done;
    }
    nprfx_parallel_for(ex, ntiles, 1, splat_tiles, &J);
    for (int t = 0; t < ntiles; t++) {
        if (!J.tile_ok[t]) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "gabor: out of memory for a tile");
            goto done;
        }
        if (stats) {
            stats->kernels += J.t_kernels[t];
            stats->evaluations += J.t_evals[t];
            stats->weight2 += J.t_w2[t];
        }
    }
done:
    /* the scatter's scratch slots hold the splat's buffers by now (or NULL) */
    for (int i = 0; J.scratch && i < J.nworkers; i++)
        splat_scratch_free(J.scratch[i]);
    internal_scatter_job_free(&J);
    free(J.tile_ok);
    free(J.t_kernels);
    free(J.t_evals);
    free(J.t_w2);
    return r;
}
