/* The anchored-point scatter (docs/design.md §3.2, "Anchors instead of a mesh", "Cell hierarchy",
 * "Emission"): phase 1 of gabor-splat's render, shared with pam-splat (§3.7). Over the window
 * grown by the splats' reach, cut into BLOCK x BLOCK blocks on a grid fixed in frame coordinates,
 * each block finds its pixels' anchors, Jacobians and wanted densities, enumerates the anchor
 * cells they touch and emits every visible point once, by its owner pixel (gabor_pixels.c,
 * gabor_emit.c). This file runs the rows of blocks over the context's executor, with a worker's
 * strip of packed inputs per row, and writes the window's depth and id planes the splats'
 * visibility tests read. The points of a block come out in the same order whatever the tiling,
 * which is what makes every node built on it bit-identical across tiles and threads. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_scatter.h"
#include "nprfx/exec.h"

#define MIN_STEP_TOLERANCE 0.01 /* a finite difference may always cross a 1% depth step */

/* simd: 0 the fastest path, 1 scalar, 2 the baseline ISA's vectors (emission: scalar; its vector
 * code needs AVX2's registers to pay), 3 AVX2 (as 2 without it) */
static emit_fn pick_emit_fn(int simd)
{
#if GABOR_X86
    if (simd == 0 && internal_scatter_cpu_avx512()) return internal_gabor_emit_block_avx512;
    if ((simd == 0 || simd == 3) && internal_scatter_cpu_avx2())
        return internal_gabor_emit_block_avx2;
#endif
    (void)simd;
    return internal_gabor_emit_block_scalar;
}

/* The rows [y0, y1) of the window's depth and id planes, from the strip (which holds every
 * pixel of them inside the inputs). */
static void window_rows(const gjob *J, const gstrip *T, int y0, int y1)
{
    const gsrc *S = &J->G->S;
    nprfx_rect w = J->window, reg = S->region;
    int ww = nprfx_rect_width(w);
    const float none = id_none();
    if (y0 < w.y0) y0 = w.y0;
    if (y1 > w.y1) y1 = w.y1;
    /* the window's columns inside the inputs */
    int xa = w.x0 > reg.x0 ? w.x0 : reg.x0, xb = w.x1 < reg.x1 ? w.x1 : reg.x1;
    for (int y = y0; y < y1; y++) {
        float *zr = J->zwin + (size_t)(y - w.y0) * (size_t)ww - w.x0;
        float *ir = J->idwin + (size_t)(y - w.y0) * (size_t)ww - w.x0;
        int in = y >= reg.y0 && y < reg.y1 && xa < xb;
        for (int x = w.x0; x < w.x1; x++) {
            zr[x] = 0.0f;
            ir[x] = none;
        }
        if (!in) continue;
        const float *Z = strip_plane(T, ST_Z, xa, y) - xa, *ID = strip_plane(T, ST_ID, xa, y) - xa;
        for (int x = xa; x < xb; x++) {
            double zz = Z[x];
            float ii = ID[x];
            if (is_surface_depth(zz) && nprfx_id_is_object(ii)) {
                zr[x] = (float)zz;
                ir[x] = ii;
            }
        }
    }
}

static void emit_rows(void *user, int begin, int end, int worker)
{
    gjob *J = user;
    emit_scratch *scr = J->scratch[worker];
    for (int r = begin; r < end; r++) {
        /* the inputs the row's windows read (a window depends on the block row only in y, and
         * grows with the block column in x) */
        int cx0, cy0, cw, ch, lx0, ly0, lw, lh;
        if (internal_gabor_block_window(&J->G->S, J->bx0, J->by0 + r, &cx0, &cy0, &cw, &ch) &&
            internal_gabor_block_window(&J->G->S, J->bx0 + J->nbx - 1, J->by0 + r, &lx0, &ly0, &lw,
                                        &lh))
            internal_gabor_strip_fill(&J->G->S, &scr->T, cx0, lx0 + lw, cy0, cy0 + ch);
        else
            scr->T.w = scr->T.h = 0;
        window_rows(J, &scr->T, (J->by0 + r) * BLOCK, (J->by0 + r + 1) * BLOCK);
        int ok = 1;
        for (int i = 0; i < J->nbx && ok; i++)
            ok = J->G->emit(J->G, J->bx0 + i, J->by0 + r, &J->blocks[r * J->nbx + i], scr);
        J->row_ok[r] = ok;
    }
}

void internal_scatter_conf_init(gconf *G, const nprfx_gabor_params *p, const nprfx_gabor_inputs *in)
{
    memset(G, 0, sizeof *G);
    G->S.anchor = in->anchor;
    G->S.depth = in->depth;
    G->S.id = in->id && in->id->data ? in->id : NULL;
    G->S.orient = in->orientation && in->orientation->data ? in->orientation : NULL;
    G->S.freq = in->frequency && in->frequency->data ? in->frequency : NULL;
    G->S.dims = p->anchor_dims;
    G->S.cov_ch = in->anchor->channels > p->anchor_dims ? p->anchor_dims : -1;
    G->S.region = nprfx_rect_intersect(in->anchor->bounds, in->depth->bounds);
    if (G->S.id) G->S.region = nprfx_rect_intersect(G->S.region, G->S.id->bounds);
    G->S.step_tol =
        p->depth_tolerance > MIN_STEP_TOLERANCE ? p->depth_tolerance : MIN_STEP_TOLERANCE;
    G->a = nprfx_gabor_bandwidth(p->radius);
    G->radius = p->radius;
    G->r2 = p->radius * p->radius;
    G->lambda = p->n0 / (k_pi * G->r2);
    G->h0 = p->cell;
    G->F0 = p->frequency;
    G->w0 = p->orientation * (k_pi / 180.0);
    G->tol = p->depth_tolerance;
    G->W = p->lod_levels;
    G->stagger = p->fade == NPRFX_GABOR_FADE_STAGGERED;
    G->dims = p->anchor_dims;
    G->ss = p->supersample;
    G->iso = p->isotropic != 0;
    G->amp = p->amplitude;
    G->dtest = p->depth_test;
    G->points = p->points != 0;
    G->output = p->output;
    G->contrast = p->contrast;
    G->seed = p->seed;
    G->var_k1 = internal_gabor_variance_k1(p, G->a);
    internal_gabor_lod_table_init(&G->lod, G->W);
    G->pa2 = k_pi * G->a * G->a;
    G->lh2 = G->lambda * G->h0 * G->h0;
    G->emit = pick_emit_fn(p->simd);
    G->step_tolf = (float)G->S.step_tol;
    G->uniform_wave = !G->iso && !G->S.orient && !G->S.freq;
    if (G->uniform_wave) {
        /* as kernel_wave computes it for every point */
        double F = G->F0 * 1.0, step = 1.0 / G->ss;
        G->kx0 = F * cos(G->w0);
        G->ky0 = -F * sin(G->w0);
        G->csx = (float)cos(2.0 * k_pi * G->kx0 * step);
        G->ssx = (float)sin(2.0 * k_pi * G->kx0 * step);
        G->csy = (float)cos(2.0 * k_pi * G->ky0 * step);
        G->ssy = (float)sin(2.0 * k_pi * G->ky0 * step);
    }
    G->rr = exp(-2.0 * G->pa2 / ((double)G->ss * G->ss));
}

void internal_scatter_job_init(gjob *J, const gconf *G, nprfx_rect window, int reach,
                               nprfx_image *out)
{
    memset(J, 0, sizeof *J);
    J->G = G;
    J->window = window;
    J->out = out;
    J->reach = reach;
    J->bx0 = internal_scatter_floor_div(window.x0 - reach, BLOCK);
    J->by0 = internal_scatter_floor_div(window.y0 - reach, BLOCK);
    J->nbx = internal_scatter_floor_div(window.x1 - 1 + reach, BLOCK) - J->bx0 + 1;
    J->nby = internal_scatter_floor_div(window.y1 - 1 + reach, BLOCK) - J->by0 + 1;
}

nprfx_result internal_scatter_emit(nprfx_context *ctx, gjob *J, const char *who)
{
    J->blocks = calloc((size_t)J->nbx * (size_t)J->nby, sizeof(gblock));
    J->row_ok = calloc((size_t)J->nby, sizeof(int));
    size_t wpx = (size_t)nprfx_rect_width(J->window) * (size_t)nprfx_rect_height(J->window);
    J->zwin = malloc(sizeof(float) * wpx);
    J->idwin = malloc(sizeof(float) * wpx);
    if (!J->blocks || !J->row_ok || !J->zwin || !J->idwin)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "%s: out of memory", who);
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    J->nworkers = nprfx_executor_workers(ex);
    if (J->nworkers < 1) J->nworkers = 1;
    J->scratch = calloc((size_t)J->nworkers, sizeof(void *));
    J->chunks = calloc((size_t)J->nworkers, sizeof(gchunk *));
    int ok = J->scratch != NULL && J->chunks != NULL;
    /* a row of blocks reads at most CW input rows, and columns from its first window to its
     * last */
    size_t strip_w = (size_t)J->nbx * BLOCK + 2 * (1 + HALO);
    for (int i = 0; i < J->nworkers && ok; i++) {
        emit_scratch *e = calloc(1, sizeof(emit_scratch)); /* padding rows: zero */
        J->scratch[i] = e;
        if (e) e->chunks = &J->chunks[i];
        ok = e != NULL && (e->T.data = malloc(sizeof(float) * ST_PLANES * CW * strip_w)) != NULL;
    }
    if (ok) nprfx_parallel_for(ex, J->nby, 1, emit_rows, J);
    for (int i = 0; J->scratch && i < J->nworkers; i++) {
        emit_scratch *e = J->scratch[i];
        if (e) free(e->T.data);
        free(e);
        J->scratch[i] = NULL;
    }
    if (!ok) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "%s: out of memory", who);
    for (int i = 0; i < J->nby; i++)
        if (!J->row_ok[i])
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "%s: out of memory for the points",
                               who);
    return NPRFX_OK;
}

void internal_scatter_job_free(gjob *J)
{
    free(J->zwin);
    free(J->idwin);
    free(J->scratch);
    for (int i = 0; J->chunks && i < J->nworkers; i++)
        for (gchunk *c = J->chunks[i], *next; c; c = next) {
            next = c->next;
            free(c);
        }
    free(J->chunks);
    J->chunks = NULL;
    free(J->blocks);
    free(J->row_ok);
    J->zwin = J->idwin = NULL;
    J->scratch = NULL;
    J->blocks = NULL;
    J->row_ok = NULL;
}
