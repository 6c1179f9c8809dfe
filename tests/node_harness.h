/* Shared helpers for node tests: tiny images, direct calls of a node's render function through
 * its descriptor, param/input lookup by name (a missing name is a test bug: exit 2). */
#ifndef NPRFX_TEST_NODE_HARNESS_H
#define NPRFX_TEST_NODE_HARNESS_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/exec.h"
#include "nprfx/node.h"
#include "nprfx/synth.h"

/* A w x h image with ch channels at the origin, filled from vals (NULL: zeros). */
static inline nprfx_image th_image(int w, int h, int ch, const float *vals)
{
    nprfx_image im;
    if (nprfx_image_alloc(NULL, nprfx_rect_make(0, 0, w, h), ch, &im) != NPRFX_OK) {
        fprintf(stderr, "test: allocation of %dx%dx%d failed\n", w, h, ch);
        exit(2);
    }
    if (vals) memcpy(im.data, vals, sizeof(float) * (size_t)w * (size_t)h * (size_t)ch);
    return im;
}

/* The index of a synthetic plate's channel (nprfx synth --list names them). */
static inline int th_synth_channel(const char *name)
{
    const char *const *n = nprfx_synth_channel_names();
    for (int i = 0; n[i]; i++)
        if (strcmp(n[i], name) == 0) return i;
    fprintf(stderr, "test: synth has no channel %s\n", name);
    exit(2);
}

/* Frame `frame` of a synthetic scene at w x h, every channel. */
static inline nprfx_image th_synth(nprfx_context *ctx, const char *scene, int frame, int w, int h)
{
    nprfx_image im = th_image(w, h, nprfx_synth_channel_count(), NULL);
    if (nprfx_synth_render(ctx, scene, frame, &im) != NPRFX_OK) {
        fprintf(stderr, "test: synth %s failed: %s\n", scene, th_error(ctx));
        exit(2);
    }
    return im;
}

/* Render args for `window` of out at frame 1 of a one-frame shot, without fetch or state: a test
 * that needs another time, shot, fetch or state slot sets those fields and calls
 * nprfx_node_render itself. */
static inline nprfx_render_args th_args(nprfx_context *ctx, const nprfx_node_desc *node,
                                        const nprfx_image *inputs, const nprfx_value *params,
                                        nprfx_image *out, nprfx_rect window)
{
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = node;
    a.time = 1;
    a.render_scale = 1;
    a.frame = out->bounds;
    a.window = window;
    a.first_frame = a.last_frame = 1;
    a.inputs = inputs;
    a.params = params;
    a.output = out;
    return a;
}

/* Args for calling a node's core entry point directly (nprfx_bump_render(&a, &p), with the typed
 * params bypassing the descriptor): inputs in the descriptor's order (NPRFX_<NODE>_IN_*, data NULL
 * where not connected), `frame` the image domain, `window` of out, frame 1 of a one-frame shot. */
static inline nprfx_render_args th_core_args(nprfx_context *ctx, const nprfx_image *inputs,
                                             nprfx_image *out, nprfx_rect frame, nprfx_rect window)
{
    nprfx_render_args a = th_args(ctx, NULL, inputs, NULL, out, window);
    a.frame = frame;
    return a;
}

/* Render `window` of out at frame 1 of a one-frame shot, without fetch or state. */
static inline nprfx_result th_render(nprfx_context *ctx, const nprfx_node_desc *node,
                                     const nprfx_image *inputs, const nprfx_value *params,
                                     nprfx_image *out, nprfx_rect window)
{
    nprfx_render_args a = th_args(ctx, node, inputs, params, out, window);
    return nprfx_node_render(&a);
}

/* Render all of out in tiles of tw x th (the last row and column cut to its bounds), the way a
 * host that tiles does: tests compare it with the whole frame for bit identity. */
static inline nprfx_result th_render_tiled(nprfx_context *ctx, const nprfx_node_desc *node,
                                           const nprfx_image *inputs, const nprfx_value *params,
                                           nprfx_image *out, int tw, int th)
{
    nprfx_rect f = out->bounds;
    for (int y = f.y0; y < f.y1; y += th)
        for (int x = f.x0; x < f.x1; x += tw) {
            nprfx_rect w =
                nprfx_rect_make(x, y, x + tw < f.x1 ? x + tw : f.x1, y + th < f.y1 ? y + th : f.y1);
            nprfx_result r = th_render(ctx, node, inputs, params, out, w);
            if (r) return r;
        }
    return NPRFX_OK;
}

/* A context whose executor is a pool of `threads` threads (*pool: destroy after the context).
 * Exits 2 when either cannot be made (a test bug or a broken machine, not a result). */
static inline nprfx_context *th_parallel_context(int threads, nprfx_pool **pool)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    if (nprfx_pool_create(threads, pool) != NPRFX_OK) {
        fprintf(stderr, "test: no pool of %d threads\n", threads);
        exit(2);
    }
    init.executor = nprfx_pool_executor(*pool);
    if (nprfx_context_create(&init, &ctx) != NPRFX_OK) {
        fprintf(stderr, "test: no context\n");
        exit(2);
    }
    return ctx;
}

/* Bit identity of a node's w x h, `channels`-channel output: rendered whole with the serial
 * context as the reference, then whole with the parallel one and in tiles of 16x16 (parallel),
 * 13x7 (serial), 9x5 (parallel) and 1 x h columns (parallel). Returns how many of those
 * differ from the reference (or failed), 0 when all agree; *ref, when not NULL, receives the
 * reference (free it). */
static inline int th_same_pixels(nprfx_context *serial, nprfx_context *par,
                                 const nprfx_node_desc *node, const nprfx_image *inputs,
                                 const nprfx_value *params, int w, int h, int channels,
                                 nprfx_image *ref_out)
{
    nprfx_image ref = th_image(w, h, channels, NULL), a = th_image(w, h, channels, NULL);
    size_t bytes = sizeof(float) * (size_t)w * (size_t)h * (size_t)channels;
    int bad = 0;
    if (th_render(serial, node, inputs, params, &ref, ref.bounds) != NPRFX_OK) bad++;
    const struct {
        nprfx_context *ctx;
        int tw, th;
    } ways[] = {{par, w, h}, {par, 16, 16}, {serial, 13, 7}, {par, 9, 5}, {par, 1, h}};
    for (size_t k = 0; k < sizeof ways / sizeof ways[0]; k++) {
        memset(a.data, 0, bytes);
        if (th_render_tiled(ways[k].ctx, node, inputs, params, &a, ways[k].tw, ways[k].th) !=
                NPRFX_OK ||
            memcmp(ref.data, a.data, bytes) != 0)
            bad++;
    }
    nprfx_image_free(&a);
    if (ref_out)
        *ref_out = ref;
    else
        nprfx_image_free(&ref);
    return bad;
}

static inline int th_param(const nprfx_node_desc *node, const char *name)
{
    int i = nprfx_node_param_index(node, name);
    if (i < 0) {
        fprintf(stderr, "test: %s has no param %s\n", node->id, name);
        exit(2);
    }
    return i;
}

/* The node's defaults, with "" for string params that have none (a front end passes text). */
static inline void th_defaults(const nprfx_node_desc *node, nprfx_value *pv)
{
    nprfx_node_defaults(node, pv);
    for (int i = 0; i < node->num_params; i++)
        if (!pv[i].s) pv[i].s = "";
}

/* Set a number param by name. */
static inline void th_set(const nprfx_node_desc *node, nprfx_value *pv, const char *name, double v)
{
    pv[th_param(node, name)].v[0] = v;
}

static inline int th_input(const nprfx_node_desc *node, const char *name)
{
    int i = nprfx_node_input_index(node, name);
    if (i < 0) {
        fprintf(stderr, "test: %s has no input %s\n", node->id, name);
        exit(2);
    }
    return i;
}

/* Set CHOICE param `param` to the option named `option`. */
static inline void th_set_choice(const nprfx_node_desc *node, nprfx_value *values,
                                 const char *param, const char *option)
{
    int pi = th_param(node, param);
    const nprfx_param_desc *p = &node->params[pi];
    for (int i = 0; p->choices && p->choices[i]; i++)
        if (strcmp(p->choices[i], option) == 0) {
            values[pi].v[0] = i;
            return;
        }
    fprintf(stderr, "test: %s.%s has no option %s\n", node->id, param, option);
    exit(2);
}

#endif
