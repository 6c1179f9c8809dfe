/* nprfx graph engine — the channels a read node appends to its plates. A renderer's motion
 * vectors become nprfx's (pixels, y down, to the previous and the next frame), a Cryptomatte
 * layer's rank-0 id becomes an exact object id, and Nuke's 1/z becomes depth; nodes then read
 * them as they read any channel, and a plate's own channels are never changed. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "graph_extras.h"
#include "graph_model.h"
#include "nprfx/aov.h"
#include "nprfx/channels.h"
#include "nprfx/cryptomatte.h"

enum { OP_SCALE = 0, OP_CRYPTO = 1, OP_INVERSE = 2, OP_PX = 3, OP_PY = 4, OP_PZ = 5 };

const char *const internal_graph_motion_names[4] = {"motion_prev.X", "motion_prev.Y",
                                                    "motion_next.X", "motion_next.Y"};
static const char id_name[] = "aov.id", depth_name[] = "aov.depth";
static const char *const position_names[3] = {"aov.position.X", "aov.position.Y", "aov.position.Z"};

const nprfx_aov_vectors *internal_graph_vectors(const gnode *n)
{
    if (n->kind != GK_READ) return NULL;
    if (n->prepared) return n->vec;
    if (!n->vectors || !strcmp(n->vectors, "none") || !strcmp(n->vectors, "auto")) return NULL;
    return nprfx_aov_vectors_find(n->vectors);
}

/* The appended channels in order: motion (4), the decoded id, the depth. */
static int has_motion(const gnode *n)
{
    if (internal_graph_vectors(n)) return 1;
    /* a convention no table knows still appends its channels: the read then fails naming it */
    return n->kind == GK_READ && !n->prepared && n->vectors && strcmp(n->vectors, "none") &&
           strcmp(n->vectors, "auto");
}

int internal_graph_extra_count(const gnode *n)
{
    if (n->kind != GK_READ) return 0;
    return (has_motion(n) ? 4 : 0) + (n->crypto ? 1 : 0) + (n->depth_inverse ? 1 : 0) +
           (n->position_from ? 3 : 0);
}

const char *internal_graph_extra_name(const gnode *n, int k)
{
    int motion = has_motion(n) ? 4 : 0;
    if (k < motion) return internal_graph_motion_names[k];
    k -= motion;
    if (n->crypto && k-- == 0) return id_name;
    if (n->depth_inverse && k-- == 0) return depth_name;
    if (n->position_from && k >= 0 && k < 3) return position_names[k];
    return NULL;
}

const char *internal_graph_extra_for(const gnode *n, int aov)
{
    if (n->kind != GK_READ) return NULL;
    if (aov == NPRFX_AOV_MOTION_PREV && has_motion(n)) return "motion_prev.X,motion_prev.Y";
    if (aov == NPRFX_AOV_MOTION_NEXT && has_motion(n)) return "motion_next.X,motion_next.Y";
    if (aov == NPRFX_AOV_ID && n->crypto) return id_name;
    if (aov == NPRFX_AOV_DEPTH && n->depth_inverse) return depth_name;
    if (aov == NPRFX_AOV_POSITION && n->position_from)
        return "aov.position.X,aov.position.Y,aov.position.Z";
    return NULL;
}

const char *internal_graph_extra_want(const gnode *n, int k)
{
    const nprfx_aov_vectors *v = internal_graph_vectors(n);
    if (v && k-- == 0) return v->channels;
    if (n->crypto && k-- == 0) return n->crypto;
    if (n->depth_inverse && k-- == 0) return n->depth_inverse;
    if (n->position_from && k == 0) return n->position_from;
    return NULL;
}

nprfx_result internal_graph_motion_sources(nprfx_graph *g, const gnode *n, const char *file,
                                           const char *const *names, int nc, int *idx, double *sign)
{
    const nprfx_aov_vectors *v = internal_graph_vectors(n);
    if (!v) {
        char list[256] = "none, auto";
        for (int i = 0; nprfx_aov_vectors_at(i); i++) {
            strcat(list, ", ");
            strcat(list, nprfx_aov_vectors_at(i)->name);
        }
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "node '%s': vectors '%s' is not one of: %s", n->name,
                           n->vectors ? n->vectors : "", list);
    }
    int amb;
    char bad[256];
    if (nprfx_channels_select(names, nc, v->channels, idx, 4, bad, sizeof bad, &amb) != 4)
        return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                           "node '%s': %s has no %s channel '%s' for vectors=%s", n->name, file,
                           amb ? "unique" : "", bad, v->name);
    for (int k = 0; k < 4; k++)
        sign[k] = v->scale[k];
    return NPRFX_OK;
}

nprfx_result internal_graph_extras(nprfx_graph *g, const gnode *n, const char *file,
                                   const char *const *names, int nc, gextra *x)
{
    memset(x, 0, sizeof *x);
    if (has_motion(n)) {
        int idx[4];
        double sign[4];
        nprfx_result r = internal_graph_motion_sources(g, n, file, names, nc, idx, sign);
        if (r) return r;
        for (int k = 0; k < 4; k++) {
            x->src[k][0] = idx[k];
            x->src[k][1] = -1;
            x->scale[k] = sign[k];
            x->op[k] = OP_SCALE;
        }
        x->count = 4;
    }
    int amb, idx[2];
    char bad[256];
    if (n->crypto) {
        if (nprfx_channels_select(names, nc, n->crypto, idx, 2, bad, sizeof bad, &amb) != 2)
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': %s has no Cryptomatte channel '%s'", n->name, file, bad);
        x->src[x->count][0] = idx[0];
        x->src[x->count][1] = idx[1];
        x->op[x->count++] = OP_CRYPTO;
    }
    if (n->depth_inverse) {
        if (nprfx_channels_select(names, nc, n->depth_inverse, idx, 1, bad, sizeof bad, &amb) != 1)
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': %s has no depth channel '%s'", n->name, file, bad);
        x->src[x->count][0] = idx[0];
        x->src[x->count][1] = -1;
        x->op[x->count++] = OP_INVERSE;
    }
    if (n->position_from) {
        if (nprfx_channels_select(names, nc, n->position_from, idx, 1, bad, sizeof bad, &amb) != 1)
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': %s has no depth channel '%s'", n->name, file, bad);
        for (int c = 0; c < 3; c++) {
            x->src[x->count][0] = idx[0];
            x->src[x->count][1] = -1;
            x->op[x->count++] = OP_PX + c;
        }
    }
    return NPRFX_OK;
}

void internal_graph_extra_fill(const gextra *x, const float *src, int nc, float *dst, int nn,
                               nprfx_rect bounds, nprfx_rect display)
{
    /* Pixel centres at integer coordinates; a pinhole of about 53 degrees across the width (the
     * focal length is the width): the scale only sizes patterns, which the nodes set anyway. */
    const double cx = 0.5 * (display.x0 + display.x1 - 1), cy = 0.5 * (display.y0 + display.y1 - 1);
    const double focal = display.x1 > display.x0 ? display.x1 - display.x0 : 1;
    const size_t w = (size_t)nprfx_rect_width(bounds), npix = w * (size_t)nprfx_rect_height(bounds);
    for (int k = 0; k < x->count; k++) {
        const float *s = src + x->src[k][0];
        const float *s2 = src + (x->src[k][1] >= 0 ? x->src[k][1] : 0);
        float *d = dst + nc + k;
        const float scale = (float)x->scale[k];
        switch (x->op[k]) {
        case OP_CRYPTO:
            for (size_t p = 0; p < npix; p++)
                d[p * nn] = nprfx_cryptomatte_object_id(s[p * nc], s2[p * nc]);
            break;
        case OP_INVERSE:
            /* 1/z with nothing there (0, or anything not a positive depth) is the background */
            for (size_t p = 0; p < npix; p++) {
                float v = s[p * nc];
                d[p * nn] = v > 0 && isfinite(v) ? 1.0f / v : INFINITY;
            }
            break;
        case OP_PX:
        case OP_PY:
        case OP_PZ:
            /* camera space from depth, y up as a renderer's; the background stays far away */
            for (size_t p = 0; p < npix; p++) {
                float v = s[p * nc];
                double z = isfinite(v) && v < 1e9f ? v : 1e9;
                double X = bounds.x0 + (double)(p % w), Y = bounds.y0 + (double)(p / w);
                d[p * nn] = (float)(x->op[k] == OP_PX   ? (X - cx) / focal * z
                                    : x->op[k] == OP_PY ? (cy - Y) / focal * z
                                                        : -z);
            }
            break;
        default:
            for (size_t p = 0; p < npix; p++) {
                float v = s[p * nc] * scale;
                d[p * nn] = isfinite(v) ? v : 0.0f;
            }
        }
    }
}
