/* PAM builder: the coherence search space (Yan et al. 2008 §4.2, Eq. 1-3; docs/design.md §3.7).
 *
 * The paper links every pixel of A to the pixels of B whose neighbourhoods look alike in edges
 * and hue. The synthesis only ever asks for the links of the blocks the first key map was copied
 * from, so only those are computed: for each asked position p of A, S_css(p, q) against every
 * block position q of B. Two cuts keep it at a fixed cost per level, whatever the block size:
 * the neighbourhood is compared on a grid of at most TAPS x TAPS samples spread over the block,
 * and q steps by about block/16 pixels (1 on small levels; the finer level's own search refines
 * around a link anyway). Each p is independent, so the positions run in parallel, and each
 * writes only its own links: the result does not depend on the executor. */
#include <math.h>
#include <stdlib.h>

#include "internal_pam.h"
#include "nprfx/exec.h"

#define TAPS 8

typedef struct css_job {
    const internal_pam_img *fa, *fb;
    int b, taps, step;
    int off[TAPS]; /* tap offsets inside the block */
    const int *px, *py;
    int max_links;
    double tolerance;
    internal_pam_links *out;
} css_job;

static void css_one(const css_job *j, int i)
{
    const internal_pam_img *fa = j->fa, *fb = j->fb;
    internal_pam_links *L = &j->out[i];
    float ref[TAPS * TAPS][2];
    int T = j->taps;
    for (int v = 0; v < T; v++)
        for (int u = 0; u < T; u++) {
            const float *p = internal_pam_px(fa, j->px[i] + j->off[u], j->py[i] + j->off[v]);
            ref[v * T + u][0] = p[0];
            ref[v * T + u][1] = p[1];
        }
    /* Keep the max_links best in a sorted array (insertion: strict <, so earlier q win ties). */
    int n = 0, cap = j->max_links;
    int qx[INTERNAL_PAM_MAX_LINKS], qy[INTERNAL_PAM_MAX_LINKS];
    double qs[INTERNAL_PAM_MAX_LINKS];
    for (int y = 0; y + j->b <= fb->h; y += j->step)
        for (int x = 0; x + j->b <= fb->w; x += j->step) {
            double s = 0;
            double worst = n == cap ? qs[n - 1] : INFINITY;
            for (int v = 0; v < T && s < worst; v++)
                for (int u = 0; u < T; u++) {
                    const float *q = internal_pam_px(fb, x + j->off[u], y + j->off[v]);
                    double d0 = q[0] - ref[v * T + u][0], d1 = q[1] - ref[v * T + u][1];
                    s += d0 * d0 + d1 * d1; /* Eq. 1: SSD(F) + SSD(H) */
                }
            if (s >= worst) continue;
            int k = n < cap ? n++ : cap - 1;
            while (k > 0 && qs[k - 1] > s) {
                qx[k] = qx[k - 1];
                qy[k] = qy[k - 1];
                qs[k] = qs[k - 1];
                k--;
            }
            qx[k] = x;
            qy[k] = y;
            qs[k] = s;
        }
    /* Eq. 3 with a threshold relative to the best link, so it means the same on every level and
     * sample whatever the features' scale. */
    L->n = 0;
    for (int k = 0; k < n; k++) {
        if (k > 0 && qs[k] > (1.0 + j->tolerance) * qs[0] + 1e-12) break;
        L->x[L->n] = qx[k];
        L->y[L->n] = qy[k];
        L->s[L->n] = qs[k];
        L->n++;
    }
}

static void css_range(void *user, int begin, int end, int worker)
{
    const css_job *j = user;
    for (int i = begin; i < end; i++)
        css_one(j, i);
}

nprfx_result internal_pam_css_links(nprfx_context *ctx, const internal_pam_img *fa,
                                    const internal_pam_img *fb, int b, const int *px, const int *py,
                                    int np, int max_links, double tolerance,
                                    internal_pam_links *out)
{
    if (b > fb->w || b > fb->h || b > fa->w || b > fa->h)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam: a %dx%d block does not fit the sample level (%dx%d)", b, b, fb->w,
                           fb->h);
    css_job j;
    j.fa = fa;
    j.fb = fb;
    j.b = b;
    j.taps = b < TAPS ? b : TAPS;
    for (int t = 0; t < j.taps; t++)
        j.off[t] = j.taps > 1 ? (int)lround((double)t * (b - 1) / (j.taps - 1)) : 0;
    j.step = b / 16 > 1 ? b / 16 : 1;
    j.px = px;
    j.py = py;
    j.max_links = max_links < 1                        ? 1
                  : max_links > INTERNAL_PAM_MAX_LINKS ? INTERNAL_PAM_MAX_LINKS
                                                       : max_links;
    j.tolerance = tolerance;
    j.out = out;
    nprfx_parallel_for(nprfx_context_executor(ctx), np, 1, css_range, &j);
    return NPRFX_OK;
}
