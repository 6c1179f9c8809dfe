/* Optical flow metrics against ground truth: endpoint error and the visibility (disocclusion)
 * mask exact motion implies (nprfx/metrics.h; docs/design.md §3.15). */
#include <math.h>

#include "nprfx/metrics.h"

nprfx_result nprfx_metric_epe(nprfx_context *ctx, const nprfx_image *est, const nprfx_image *truth,
                              const nprfx_image *valid, double *mean, long long *count)
{
    if (!est || !truth || !mean || !est->data || !truth->data || est->channels < 2 ||
        truth->channels < 2 || (valid && !valid->data))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "epe: needs two-channel estimate and truth");
    nprfx_rect r = nprfx_rect_intersect(est->bounds, truth->bounds);
    double sum = 0;
    long long n = 0;
    for (int y = r.y0; y < r.y1; y++)
        for (int x = r.x0; x < r.x1; x++) {
            if (valid && (!nprfx_rect_contains(valid->bounds, x, y) ||
                          !(nprfx_image_at(valid, x, y)[0] > 0.5f)))
                continue;
            const float *e = nprfx_image_at(est, x, y), *t = nprfx_image_at(truth, x, y);
            if (!isfinite(e[0]) || !isfinite(e[1]) || !isfinite(t[0]) || !isfinite(t[1])) continue;
            double dx = (double)e[0] - t[0], dy = (double)e[1] - t[1];
            sum += sqrt(dx * dx + dy * dy);
            n++;
        }
    *mean = n ? sum / (double)n : 0;
    if (count) *count = n;
    return NPRFX_OK;
}

nprfx_result nprfx_motion_visible(nprfx_context *ctx, const nprfx_image *motion_prev,
                                  const nprfx_image *id, const nprfx_image *motion_next_prev,
                                  const nprfx_image *id_prev, double tol, nprfx_image *visible)
{
    if (!motion_prev || !motion_next_prev || !visible || !motion_prev->data ||
        !motion_next_prev->data || !visible->data || motion_prev->channels < 2 ||
        motion_next_prev->channels < 2 || (id && !id->data) || (id_prev && !id_prev->data))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "visibility: needs both frames' motion and an output");
    nprfx_rect b = motion_prev->bounds, pb = motion_next_prev->bounds;
    nprfx_rect r = nprfx_rect_intersect(b, visible->bounds);
    int ids = id && id_prev;
    for (int y = r.y0; y < r.y1; y++)
        for (int x = r.x0; x < r.x1; x++) {
            const float *m = nprfx_image_at(motion_prev, x, y);
            float vis = 0;
            if (isfinite(m[0]) && isfinite(m[1])) {
                int qx = (int)floor(x + m[0] + 0.5), qy = (int)floor(y + m[1] + 0.5);
                if (nprfx_rect_contains(pb, qx, qy) &&
                    (!ids || (nprfx_rect_contains(id->bounds, x, y) &&
                              nprfx_rect_contains(id_prev->bounds, qx, qy) &&
                              nprfx_image_at(id, x, y)[0] == nprfx_image_at(id_prev, qx, qy)[0]))) {
                    const float *n = nprfx_image_at(motion_next_prev, qx, qy);
                    double ex = (double)m[0] + n[0], ey = (double)m[1] + n[1];
                    vis = ex * ex + ey * ey <= tol * tol ? 1.0f : 0.0f;
                }
            }
            nprfx_image_at(visible, x, y)[0] = vis;
        }
    return NPRFX_OK;
}
