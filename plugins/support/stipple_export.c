/* The stipple node's vector export formats, outside core: a list of stipples
 * (nprfx_stipple_collect) as CSV or SVG text. stipple_export.h describes both. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support/stipple_export.h"

typedef struct sbuf {
    char *s;
    size_t n, cap;
    int failed;
} sbuf;

static void sb_printf(sbuf *b, const char *fmt, ...)
{
    if (b->failed) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        size_t room = b->cap - b->n;
        int k = vsnprintf(b->s ? b->s + b->n : NULL, b->s ? room : 0, fmt, ap);
        va_end(ap);
        if (k < 0) {
            b->failed = 1;
            return;
        }
        if (b->s && (size_t)k < room) {
            b->n += (size_t)k;
            return;
        }
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->n + (size_t)k + 1)
            cap *= 2;
        char *ns = realloc(b->s, cap);
        if (!ns) {
            b->failed = 1;
            return;
        }
        b->s = ns;
        b->cap = cap;
    }
}

/* Scene-linear to an sRGB-encoded 8-bit value, for SVG colours. */
static int srgb8(float v)
{
    double c = v <= 0 ? 0 : v >= 1 ? 1 : v;
    c = c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1 / 2.4) - 0.055;
    return (int)floor(c * 255 + 0.5);
}

nprfx_result internal_stipple_format(nprfx_context *ctx, const nprfx_stipple *list, size_t count,
                                     nprfx_rect frame, nprfx_stipple_format_kind kind,
                                     const float *ink, const float *paper, char **text, size_t *len)
{
    if (!text || (count && !list))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple export: NULL argument");
    *text = NULL;
    if (len) *len = 0;
    static const float black[4] = {0, 0, 0, 1}, white[4] = {1, 1, 1, 1};
    if (!ink) ink = black;
    if (!paper) paper = white;
    sbuf b = {0};
    double ox = 0.5 - frame.x0, oy = 0.5 - frame.y0;
    if (kind == NPRFX_STIPPLE_CSV) {
        sb_printf(&b, "x,y,radius,tone,sample,object\n");
        for (size_t i = 0; i < count; i++)
            sb_printf(&b, "%.4f,%.4f,%.4f,%.4f,%d,%d\n", list[i].x + ox, list[i].y + oy,
                      list[i].radius, list[i].tone, list[i].sample, list[i].object);
    } else if (kind == NPRFX_STIPPLE_SVG) {
        int w = nprfx_rect_width(frame), h = nprfx_rect_height(frame);
        sb_printf(&b,
                  "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                  "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
                  "viewBox=\"0 0 %d %d\">\n",
                  w, h, w, h);
        if (paper[3] > 0)
            sb_printf(&b,
                      "<rect width=\"%d\" height=\"%d\" fill=\"#%02x%02x%02x\" "
                      "fill-opacity=\"%.3f\"/>\n",
                      w, h, srgb8(paper[0]), srgb8(paper[1]), srgb8(paper[2]), fmin(1.0, paper[3]));
        sb_printf(&b, "<g fill=\"#%02x%02x%02x\" fill-opacity=\"%.3f\">\n", srgb8(ink[0]),
                  srgb8(ink[1]), srgb8(ink[2]), fmin(1.0, fmax(0.0, ink[3])));
        for (size_t i = 0; i < count; i++) {
            if (list[i].tone < 1.0f)
                sb_printf(&b, "<circle cx=\"%.3f\" cy=\"%.3f\" r=\"%.3f\" opacity=\"%.3f\"/>\n",
                          list[i].x + ox, list[i].y + oy, list[i].radius, list[i].tone);
            else
                sb_printf(&b, "<circle cx=\"%.3f\" cy=\"%.3f\" r=\"%.3f\"/>\n", list[i].x + ox,
                          list[i].y + oy, list[i].radius);
        }
        sb_printf(&b, "</g>\n</svg>\n");
    } else {
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple export: unknown format %d",
                           (int)kind);
    }
    if (b.failed) {
        free(b.s);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple export: out of memory");
    }
    *text = b.s;
    if (len) *len = b.n;
    return NPRFX_OK;
}

/* ---- the node's export ---- */

/* The format a path's extension names, case-insensitive: .csv or .svg. */
static nprfx_result format_for_path(nprfx_context *ctx, const char *path,
                                    nprfx_stipple_format_kind *kind)
{
    const char *p = path ? path : "";
    const char *slash = strrchr(p, '/'), *dot = strrchr(p, '.');
    if (dot && slash && dot < slash) dot = NULL; /* a dot in a directory name */
    const char *ext = dot ? dot + 1 : "";
    char low[8] = {0};
    size_t n = strlen(ext);
    for (size_t i = 0; i < n && i < sizeof low - 1; i++)
        low[i] = (char)(ext[i] >= 'A' && ext[i] <= 'Z' ? ext[i] - 'A' + 'a' : ext[i]);
    if (n == 3 && !strcmp(low, "csv")) {
        *kind = NPRFX_STIPPLE_CSV;
        return NPRFX_OK;
    }
    if (n == 3 && !strcmp(low, "svg")) {
        *kind = NPRFX_STIPPLE_SVG;
        return NPRFX_OK;
    }
    if (!dot)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "stipple.export: '%s' has no extension: end it in .csv or .svg", p);
    return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                       "stipple.export: unknown extension '.%s' in '%s': use .csv (a table of "
                       "dots) or .svg (vector discs)",
                       ext, p);
}

nprfx_result internal_stipple_export_text(const nprfx_render_args *args,
                                          const nprfx_stipple_node_params *np, const char *path,
                                          char **text, size_t *len)
{
    nprfx_stipple_format_kind kind = NPRFX_STIPPLE_CSV;
    nprfx_result r = format_for_path(args->ctx, path, &kind);
    if (r != NPRFX_OK) return r;
    nprfx_stipple *list = NULL;
    size_t count = 0;
    r = nprfx_stipple_node_collect(args, np, &list, &count);
    if (r == NPRFX_OK) {
        float ink[4], paper[4];
        for (int c = 0; c < 4; c++) {
            ink[c] = (float)np->ink[c];
            paper[c] = (float)np->paper[c];
        }
        r = internal_stipple_format(args->ctx, list, count, args->frame, kind, ink, paper, text,
                                    len);
    }
    free(list);
    return r;
}

nprfx_result internal_stipple_node_export(const nprfx_render_args *args,
                                          nprfx_stipple_format_kind kind, char **text, size_t *len)
{
    nprfx_context *ctx = args ? args->ctx : NULL;
    if (kind != NPRFX_STIPPLE_CSV && kind != NPRFX_STIPPLE_SVG)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple export: unknown format %d",
                           (int)kind);
    if (args && args->node && strcmp(args->node->id, "stipple") != 0)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "stipple export: render arguments of the '%s' node", args->node->id);
    /* the node's export hook picks the format from the path's extension */
    return nprfx_node_export(args, kind == NPRFX_STIPPLE_SVG ? "stipples.svg" : "stipples.csv",
                             text, len);
}
