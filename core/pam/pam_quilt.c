/* PAM builder: one level of tile synthesis (docs/design.md §3.7).
 *
 * A map of n x n tiles is filled in raster order. Tile (i, j) receives a block of tile + overlap
 * pixels whose first `overlap` rows and columns lie over the previous tiles (the L-shaped
 * neighbourhood of Eq. 4). Coordinates wrap around the map, so the first row and column write into
 * the last ones' overlap, and the last tile of a row (or column) is matched on both sides: the
 * left and top boundaries constrain the right and bottom ones, which makes the map tileable (end
 * of §4.3). A block is cut along minimum-error paths through each filled overlap strip (dynamic
 * programming, as in Efros & Freeman's quilting), one of the stitching methods the paper
 * defers to, and feathered across the cut by a pixel each side so no hard step remains. */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "internal_pam.h"
#include "nprfx/exec.h"

nprfx_result internal_pam_level_init(nprfx_context *ctx, int n, int tile, int overlap,
                                     internal_pam_level *lv)
{
    memset(lv, 0, sizeof *lv);
    lv->n = n;
    lv->tile = tile;
    lv->overlap = overlap;
    lv->size = n * tile;
    nprfx_result r = internal_pam_img_alloc(ctx, lv->size, lv->size, 3, &lv->out);
    if (r) return r;
    lv->filled = calloc((size_t)lv->size * (size_t)lv->size, 1);
    lv->qx = calloc((size_t)n * (size_t)n, sizeof(int));
    lv->qy = calloc((size_t)n * (size_t)n, sizeof(int));
    if (!lv->filled || !lv->qx || !lv->qy) {
        internal_pam_level_free(lv);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam: out of memory");
    }
    return NPRFX_OK;
}

void internal_pam_level_free(internal_pam_level *lv)
{
    internal_pam_img_free(&lv->out);
    free(lv->filled);
    free(lv->qx);
    free(lv->qy);
    memset(lv, 0, sizeof *lv);
}

static int wrap(int v, int m)
{
    v %= m;
    return v < 0 ? v + m : v;
}

/* Map position of block pixel (u, v) of tile t. */
static void block_to_map(const internal_pam_level *lv, int t, int u, int v, int *x, int *y)
{
    int i = t % lv->n, j = t / lv->n;
    *x = wrap(i * lv->tile - lv->overlap + u, lv->size);
    *y = wrap(j * lv->tile - lv->overlap + v, lv->size);
}

typedef struct cost_job {
    const internal_pam_img *src;
    const int *cx, *cy;
    double *cost;
    int m;              /* filled pixels of the block */
    const int *fu, *fv; /* their block coordinates */
    const float *ft;    /* their current RGB */
} cost_job;

static void cost_range(void *user, int begin, int end, int worker)
{
    const cost_job *j = user;
    for (int i = begin; i < end; i++) {
        double s = 0;
        for (int k = 0; k < j->m; k++) {
            const float *p = internal_pam_px(j->src, j->cx[i] + j->fu[k], j->cy[i] + j->fv[k]);
            for (int c = 0; c < 3; c++) {
                double d = (double)p[c] - j->ft[3 * k + c];
                s += d * d;
            }
        }
        j->cost[i] = s;
    }
}

nprfx_result internal_pam_overlap_costs(nprfx_context *ctx, const internal_pam_level *lv,
                                        const internal_pam_img *src, int t, const int *cx,
                                        const int *cy, int nc, double *cost)
{
    int b = lv->tile + lv->overlap;
    int *fu = malloc(sizeof(int) * (size_t)b * b), *fv = malloc(sizeof(int) * (size_t)b * b);
    float *ft = malloc(sizeof(float) * 3 * (size_t)b * b);
    if (!fu || !fv || !ft) {
        free(fu);
        free(fv);
        free(ft);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam: out of memory");
    }
    int m = 0;
    for (int v = 0; v < b; v++)
        for (int u = 0; u < b; u++) {
            int x, y;
            block_to_map(lv, t, u, v, &x, &y);
            if (!lv->filled[(size_t)y * lv->size + x]) continue;
            fu[m] = u;
            fv[m] = v;
            memcpy(&ft[3 * m], internal_pam_px(&lv->out, x, y), 3 * sizeof(float));
            m++;
        }
    cost_job j = {src, cx, cy, cost, m, fu, fv, ft};
    nprfx_parallel_for(nprfx_context_executor(ctx), nc, 64, cost_range, &j);
    free(fu);
    free(fv);
    free(ft);
    return NPRFX_OK;
}

/* Minimum-error path through strip columns [u0, u0 + w) of the b x b error array, top to bottom
 * (transpose: through rows, left to right); cut[v] receives the path's column (row). */
static void seam(const double *err, int b, int u0, int w, int transpose, int *cut, double *acc)
{
#define ERR(v, k) (transpose ? err[(size_t)(u0 + (k)) * b + (v)] : err[(size_t)(v)*b + u0 + (k)])
    for (int k = 0; k < w; k++)
        acc[k] = ERR(0, k);
    for (int v = 1; v < b; v++)
        for (int k = 0; k < w; k++) {
            double best = acc[(size_t)(v - 1) * w + k];
            if (k > 0 && acc[(size_t)(v - 1) * w + k - 1] < best)
                best = acc[(size_t)(v - 1) * w + k - 1];
            if (k + 1 < w && acc[(size_t)(v - 1) * w + k + 1] < best)
                best = acc[(size_t)(v - 1) * w + k + 1];
            acc[(size_t)v * w + k] = ERR(v, k) + best;
        }
#undef ERR
    int k = 0;
    for (int q = 1; q < w; q++)
        if (acc[(size_t)(b - 1) * w + q] < acc[(size_t)(b - 1) * w + k]) k = q;
    cut[b - 1] = u0 + k;
    for (int v = b - 2; v >= 0; v--) {
        int best = k;
        for (int q = k - 1; q <= k + 1; q++)
            if (q >= 0 && q < w && acc[(size_t)v * w + q] < acc[(size_t)v * w + best]) best = q;
        k = best;
        cut[v] = u0 + k;
    }
}

/* Smooth the b x b weights w in place with [1 2 1] / 4 along rows, then columns (edges clamped). */
static void feather(float *w, float *tmp, int b)
{
    for (int pass = 0; pass < 2; pass++) {
        const float *in = pass ? tmp : w;
        float *out = pass ? w : tmp;
        for (int v = 0; v < b; v++)
            for (int u = 0; u < b; u++) {
                int lo = pass ? (v > 0 ? v - 1 : 0) : (u > 0 ? u - 1 : 0);
                int hi = pass ? (v + 1 < b ? v + 1 : b - 1) : (u + 1 < b ? u + 1 : b - 1);
                float m = in[v * b + u];
                float l = pass ? in[lo * b + u] : in[v * b + lo];
                float h = pass ? in[hi * b + u] : in[v * b + hi];
                out[v * b + u] = 0.25f * l + 0.5f * m + 0.25f * h;
            }
    }
}

nprfx_result internal_pam_paste(nprfx_context *ctx, internal_pam_level *lv,
                                const internal_pam_img *src, int t, int qx, int qy)
{
    int b = lv->tile + lv->overlap, O = lv->overlap, P = lv->tile;
    double *err = calloc((size_t)b * b, sizeof(double));
    double *acc = malloc(sizeof(double) * (size_t)b * (O > 0 ? O : 1));
    int *cut = malloc(sizeof(int) * (size_t)b);
    unsigned char *old = calloc((size_t)b * b, 1);
    unsigned char *fil = calloc((size_t)b * b, 1);
    float *wgt = malloc(sizeof(float) * (size_t)b * b),
          *tmp = malloc(sizeof(float) * (size_t)b * b);
    nprfx_result r = NPRFX_OK;
    if (!err || !acc || !cut || !old || !fil || !wgt || !tmp) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam: out of memory");
        goto done;
    }
    for (int v = 0; v < b; v++)
        for (int u = 0; u < b; u++) {
            int x, y;
            block_to_map(lv, t, u, v, &x, &y);
            if (!lv->filled[(size_t)y * lv->size + x]) continue;
            fil[v * b + u] = 1;
            const float *p = internal_pam_px(src, qx + u, qy + v),
                        *o = internal_pam_px(&lv->out, x, y);
            double s = 0;
            for (int c = 0; c < 3; c++)
                s += ((double)p[c] - o[c]) * ((double)p[c] - o[c]);
            err[v * b + u] = s;
        }
    if (O > 0) {
        /* A strip is cut when its middle is filled: the left/top ones by the previous tiles, the
         * right/bottom ones by the first column/row wrapped round (the tileable constraint). */
        int mid = b / 2;
        /* The paths keep off the strip's outer line when the strip is wide enough, so the block's
         * edge stays old and the cut (with its feather) lies wholly inside the overlap: a path on
         * the edge would put new pixels right against the old ones outside the block. */
        int e = O >= 3 ? 1 : 0, w = O - 2 * e;
        if (fil[mid * b + 0]) { /* left: keep old pixels left of the path */
            seam(err, b, e, w, 0, cut, acc);
            for (int v = 0; v < b; v++)
                for (int u = 0; u < cut[v]; u++)
                    old[v * b + u] = 1;
        }
        if (fil[mid * b + b - 1]) { /* right: old pixels right of the path */
            seam(err, b, P + e, w, 0, cut, acc);
            for (int v = 0; v < b; v++)
                for (int u = cut[v] + 1; u < b; u++)
                    old[v * b + u] = 1;
        }
        if (fil[0 * b + mid]) { /* top: old pixels above the path */
            seam(err, b, e, w, 1, cut, acc);
            for (int u = 0; u < b; u++)
                for (int v = 0; v < cut[u]; v++)
                    old[v * b + u] = 1;
        }
        if (fil[(b - 1) * b + mid]) { /* bottom: old pixels below the path */
            seam(err, b, P + e, w, 1, cut, acc);
            for (int u = 0; u < b; u++)
                for (int v = cut[u] + 1; v < b; v++)
                    old[v * b + u] = 1;
        }
    }
    /* The new block's weight: 0 on the old side of a cut, 1 elsewhere, then softened by the 3-tap
     * binomial across both axes so the cut is a two-pixel cross-fade instead of a hard step (a cut
     * across a stroke would otherwise show as a notch). Only pixels already filled are blended;
     * the rest take the new block whatever the weight. */
    for (int i = 0; i < b * b; i++)
        wgt[i] = old[i] && fil[i] ? 0.0f : 1.0f;
    feather(wgt, tmp, b);
    /* Old pixels on the block's edge stay old: the feather cannot see the pixels beyond it. */
    for (int i = 0; i < b; i++) {
        int edge[4] = {i, (b - 1) * b + i, i * b, i * b + b - 1};
        for (int k = 0; k < 4; k++)
            if (old[edge[k]] && fil[edge[k]]) wgt[edge[k]] = 0.0f;
    }
    for (int v = 0; v < b; v++)
        for (int u = 0; u < b; u++) {
            float a = fil[v * b + u] ? wgt[v * b + u] : 1.0f;
            if (a <= 0.0f) continue;
            int x, y;
            block_to_map(lv, t, u, v, &x, &y);
            float *o = internal_pam_px(&lv->out, x, y);
            const float *n = internal_pam_px(src, qx + u, qy + v);
            for (int c = 0; c < 3; c++)
                o[c] = a >= 1.0f ? n[c] : a * n[c] + (1.0f - a) * o[c];
            lv->filled[(size_t)y * lv->size + x] = 1;
        }
    lv->qx[t] = qx;
    lv->qy[t] = qy;
done:
    free(err);
    free(acc);
    free(cut);
    free(old);
    free(fil);
    free(wgt);
    free(tmp);
    return r;
}
