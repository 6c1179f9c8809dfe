/* Flow providers for unit tests, which cannot link OpenCV (the runner's DIS provider is tested by
 * tests/cli/flow.sh). Both are exact and deterministic, so tests know the flow they get:
 *  - th_flow_zero: no motion anywhere;
 *  - th_flow_shift: frames that carry their frame number t in pixel (0, 0) (th_flow_mark) move by
 *    th_flow_shift_d per frame: flow(from -> to) = (t_to - t_from) * d everywhere. */
#ifndef NPRFX_TEST_FLOW_TEST_PROVIDER_H
#define NPRFX_TEST_FLOW_TEST_PROVIDER_H

#include <math.h>
#include <string.h>

#include "nprfx/flow.h"

static inline nprfx_result th_flow_zero_compute(void *user, nprfx_context *ctx, const float *from,
                                                const float *to, int w, int h,
                                                nprfx_flow_preset preset, float *flow)
{
    (void)user, (void)ctx, (void)from, (void)to, (void)preset;
    memset(flow, 0, sizeof(float) * 2 * (size_t)w * (size_t)h);
    return NPRFX_OK;
}

static const nprfx_flow_provider th_flow_zero = {sizeof(nprfx_flow_provider), "test: zero",
                                                 th_flow_zero_compute, NULL};

/* The per-frame motion of th_flow_shift, in pixels of the image it is called on. */
typedef struct th_flow_shift_d {
    double dx, dy;
    int calls; /* how many solves it made */
} th_flow_shift_d;

/* The value pixel (0, 0) of frame t holds: its luma x/(1+x) (nprfx_flow_luminance) gives back
 * t = 10 v / (1 - v). */
static inline float th_flow_mark(int t)
{
    return 0.1f * (float)t;
}

static inline double th_flow_frame_of(float v)
{
    return 10.0 * v / (1.0 - v);
}

static inline nprfx_result th_flow_shift_compute(void *user, nprfx_context *ctx, const float *from,
                                                 const float *to, int w, int h,
                                                 nprfx_flow_preset preset, float *flow)
{
    (void)ctx, (void)preset;
    th_flow_shift_d *d = user;
    __atomic_add_fetch(&d->calls, 1, __ATOMIC_RELAXED);
    double k = floor(th_flow_frame_of(to[0]) + 0.5) - floor(th_flow_frame_of(from[0]) + 0.5);
    for (size_t i = 0; i < (size_t)w * (size_t)h; i++) {
        flow[2 * i] = (float)(k * d->dx);
        flow[2 * i + 1] = (float)(k * d->dy);
    }
    return NPRFX_OK;
}

#endif
