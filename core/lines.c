/* Ink lines from AOVs (docs/design.md §3.11): edge points between neighbouring pixel centres where
 * an edge source fires, joined into segments per 2x2 cell of pixel centres (marching squares), and
 * ink from the distance to those segments, box-filtered. See nprfx/lines.h. */
#include <math.h>
#include <stdlib.h>

#include "nprfx/exec.h"
#include "nprfx/lines.h"

/* Depth at or beyond this is background (docs/design.md §2). */
#define LINES_FAR_DEPTH 1e9

static const double k_pi = 3.14159265358979323846;

/* One point per pair of neighbouring pixels: t in [0, 1] along the pair, or -1 (no edge), and
 * the stroke width read there. */
typedef struct pair_pt {
    float t, w;
} pair_pt;

typedef struct lines_job {
    const nprfx_lines_params *p;
    const nprfx_lines_inputs *in;
    nprfx_rect frame, grid, window;
    double cos_crease, reach;
    pair_pt *h; /* (x, y)-(x+1, y) for x in [grid.x0, grid.x1 - 1), stored at (x, y) of grid */
    pair_pt *v; /* (x, y)-(x, y+1) */
    nprfx_image *out;
} lines_job;

static int connected(const nprfx_image *im)
{
    return im && im->data;
}

/* Channel c of an input at (x, y); 0 outside its data window (docs/design.md §2). */
static float rd(const nprfx_image *im, int x, int y, int c)
{
    if (!nprfx_rect_contains(im->bounds, x, y)) return 0.0f;
    return nprfx_image_at(im, x, y)[c];
}

static int clampi(int v, int lo, int hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

static double clamp01(double v)
{
    return v >= 0.0 ? (v <= 1.0 ? v : 1.0) : 0.0;
}

static int background(double z)
{
    return !(z > 0.0 && z < LINES_FAR_DEPTH);
}

/* The step between two depths when both are surface, else infinity (a background neighbour
 * predicts nothing about the surface's slope). */
static double depth_step(double a, double b)
{
    return background(a) || background(b) ? INFINITY : fabs(a - b);
}

/* Does a depth discontinuity lie between a = (x, y) and b = (x + dx, y + dy)? The jump between
 * them, less the smaller step just outside the pair (what a smooth surface's slope explains: a
 * grazing plane steps as much on either side, a silhouette does not), relative to the nearer
 * depth. Background next to surface always is one. The outer neighbours clamp to the frame. */
static int depth_edge(const lines_job *j, int x, int y, int dx, int dy)
{
    const nprfx_image *d = j->in->depth;
    nprfx_rect f = j->frame;
    double za = rd(d, x, y, 0), zb = rd(d, x + dx, y + dy, 0);
    int ba = background(za), bb = background(zb);
    if (ba || bb) return ba != bb;
    double z0 = rd(d, clampi(x - dx, f.x0, f.x1 - 1), clampi(y - dy, f.y0, f.y1 - 1), 0);
    double z3 = rd(d, clampi(x + 2 * dx, f.x0, f.x1 - 1), clampi(y + 2 * dy, f.y0, f.y1 - 1), 0);
    double slope = fmin(depth_step(z0, za), depth_step(zb, z3));
    if (isinf(slope)) slope = 0.0; /* a one-pixel sliver between backgrounds: its full jump */
    double jump = fabs(za - zb) - slope;
    return jump > j->p->depth_threshold * fmin(za, zb);
}

static int crease_edge(const lines_job *j, int xa, int ya, int xb, int yb)
{
    const nprfx_image *n = j->in->normal;
    double a[3], b[3], dot = 0.0, la = 0.0, lb = 0.0;
    for (int c = 0; c < 3; c++) {
        a[c] = rd(n, xa, ya, c);
        b[c] = rd(n, xb, yb, c);
        dot += a[c] * b[c];
        la += a[c] * a[c];
        lb += b[c] * b[c];
    }
    /* No normal (background, outside the data window) or NaN: no crease to measure. */
    if (!(la > 1e-12 && lb > 1e-12) || !isfinite(dot)) return 0;
    return dot < j->cos_crease * sqrt(la * lb);
}

static int aov_edge(const lines_job *j, int xa, int ya, int xb, int yb)
{
    const nprfx_image *a = j->in->aov;
    for (int c = 0; c < a->channels; c++)
        if (fabs((double)rd(a, xa, ya, c) - (double)rd(a, xb, yb, c)) > j->p->aov_threshold)
            return 1; /* a NaN compares false: it makes no line */
    return 0;
}

/* The edge point between a = (x, y) and b = (x + dx, y + dy), or t = -1. */
static pair_pt edge_point(const lines_job *j, int x, int y, int dx, int dy)
{
    const nprfx_lines_params *p = j->p;
    const nprfx_lines_inputs *in = j->in;
    int xb = x + dx, yb = y + dy;
    int edge = 0, cov_cross = 0;
    double ca = 0.0, cb = 0.0;
    if (connected(in->coverage)) {
        ca = rd(in->coverage, x, y, 0);
        cb = rd(in->coverage, xb, yb, 0);
        cov_cross = (ca >= 0.5) != (cb >= 0.5);
    }
    if (p->outline) {
        if (connected(in->id)) {
            float ia = rd(in->id, x, y, 0), ib = rd(in->id, xb, yb, 0);
            edge |= ia != ib && !(isnan(ia) && isnan(ib));
        }
        edge |= cov_cross;
    }
    if (!edge && p->depth_edges && connected(in->depth)) edge = depth_edge(j, x, y, dx, dy);
    if (!edge && p->creases && connected(in->normal)) edge = crease_edge(j, x, y, xb, yb);
    if (!edge && p->aov_edges && connected(in->aov)) edge = aov_edge(j, x, y, xb, yb);
    pair_pt r = {-1.0f, 0.0f};
    if (!edge) return r;
    /* The coverage's 0.5 crossing, linearly interpolated, is where an anti-aliased edge lies
     * (for a straight edge the box-filtered coverage is 0.5 exactly on it); without one, the
     * midpoint is off by at most half a pixel. */
    double t = cov_cross ? clamp01((0.5 - ca) / (cb - ca)) : 0.5;
    double w = p->width;
    if (connected(in->width)) {
        double wa = rd(in->width, x, y, 0), wb = rd(in->width, xb, yb, 0);
        double v = wa + t * (wb - wa);
        v = isnan(v) ? 1.0 : clamp01(v); /* NaN: no thickening */
        w = p->width * (1.0 + p->thicken * (1.0 - v));
    }
    r.t = (float)t;
    r.w = (float)w;
    return r;
}

static void pairs_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const lines_job *j = user;
    int gw = nprfx_rect_width(j->grid);
    for (int y = j->grid.y0 + begin; y < j->grid.y0 + end; y++)
        for (int x = j->grid.x0; x < j->grid.x1; x++) {
            size_t k = (size_t)(y - j->grid.y0) * (size_t)gw + (size_t)(x - j->grid.x0);
            pair_pt none = {-1.0f, 0.0f};
            j->h[k] = x + 1 < j->grid.x1 ? edge_point(j, x, y, 1, 0) : none;
            j->v[k] = y + 1 < j->grid.y1 ? edge_point(j, x, y, 0, 1) : none;
        }
}

/* Ink from one segment a-b (widths wa, wb) at q: the box filter of a stroke of the width read at
 * the closest point. A degenerate segment is a dot. */
static double segment_ink(double qx, double qy, double ax, double ay, double wa, double bx,
                          double by, double wb)
{
    double ex = bx - ax, ey = by - ay, l2 = ex * ex + ey * ey;
    double s = l2 > 0.0 ? clamp01(((qx - ax) * ex + (qy - ay) * ey) / l2) : 0.0;
    double dx = qx - (ax + s * ex), dy = qy - (ay + s * ey);
    double d = sqrt(dx * dx + dy * dy);
    double w = wa + s * (wb - wa);
    return clamp01(0.5 * w - d + 0.5);
}

/* The most ink any segment of cell (cx, cy) (pixel centres cx..cx+1, cy..cy+1) gives q. */
static double cell_ink(const lines_job *j, int cx, int cy, double qx, double qy)
{
    int gw = nprfx_rect_width(j->grid);
    size_t k = (size_t)(cy - j->grid.y0) * (size_t)gw + (size_t)(cx - j->grid.x0);
    pair_pt e[4] = {j->h[k], j->h[k + (size_t)gw], j->v[k], j->v[k + 1]};
    double px[4], py[4], pw[4];
    int n = 0;
    for (int i = 0; i < 4; i++) {
        if (e[i].t < 0.0f) continue;
        /* top, bottom: along x at rows cy, cy + 1; left, right: along y at columns cx, cx + 1 */
        px[n] = i < 2 ? cx + (double)e[i].t : cx + (i - 2);
        py[n] = i < 2 ? cy + i : cy + (double)e[i].t;
        pw[n] = e[i].w;
        n++;
    }
    if (n == 0) return 0.0;
    if (n == 1) return segment_ink(qx, qy, px[0], py[0], pw[0], px[0], py[0], pw[0]);
    if (n == 2) return segment_ink(qx, qy, px[0], py[0], pw[0], px[1], py[1], pw[1]);
    /* A junction (three ids meet, or a crease ends on an outline): every point joins the mean,
     * which keeps the lines connected without choosing a pairing. */
    double mx = 0.0, my = 0.0, mw = 0.0;
    for (int i = 0; i < n; i++) {
        mx += px[i];
        my += py[i];
        mw += pw[i];
    }
    mx /= n;
    my /= n;
    mw /= n;
    double ink = 0.0;
    for (int i = 0; i < n; i++)
        ink = fmax(ink, segment_ink(qx, qy, px[i], py[i], pw[i], mx, my, mw));
    return ink;
}

/* The wobble displacement of pixel (x, y): (w - 0.5) * 2 * wobble per axis, w clamped to [0, 1]
 * (the grid of edge points covers that much). A 1-channel input
 * gives y from the value 16 pixels down and right (clamped to the frame), a point of the same
 * noise far enough away to be nearly independent of x. Outside the data window, or NaN: 0.5,
 * no displacement. */
static void wobble_offset(const lines_job *j, int x, int y, double *ox, double *oy)
{
    *ox = *oy = 0.0;
    const nprfx_image *wb = j->in->wobble;
    if (!connected(wb) || j->p->wobble <= 0.0) return;
    double v[2];
    for (int a = 0; a < 2; a++) {
        int c = wb->channels >= 2 ? a : 0;
        int xx = x, yy = y;
        if (wb->channels < 2 && a == 1) {
            xx = clampi(x + 16, j->frame.x0, j->frame.x1 - 1);
            yy = clampi(y + 16, j->frame.y0, j->frame.y1 - 1);
        }
        double s = nprfx_rect_contains(wb->bounds, xx, yy) ? rd(wb, xx, yy, c) : 0.5;
        v[a] = isnan(s) ? 0.5 : clamp01(s); /* clamped: the displacement stays within reach */
    }
    *ox = (v[0] - 0.5) * 2.0 * j->p->wobble;
    *oy = (v[1] - 0.5) * 2.0 * j->p->wobble;
}

static void ink_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const lines_job *j = user;
    const nprfx_lines_params *p = j->p;
    nprfx_rect g = j->grid;
    for (int y = j->window.y0 + begin; y < j->window.y0 + end; y++)
        for (int x = j->window.x0; x < j->window.x1; x++) {
            double ox, oy;
            wobble_offset(j, x, y, &ox, &oy);
            double qx = x + ox, qy = y + oy;
            /* cells holding a point within reach of q; a cell spans [cx, cx + 1] */
            int cx0 = (int)floor(qx - j->reach) - 1, cx1 = (int)floor(qx + j->reach);
            int cy0 = (int)floor(qy - j->reach) - 1, cy1 = (int)floor(qy + j->reach);
            cx0 = cx0 < g.x0 ? g.x0 : cx0;
            cy0 = cy0 < g.y0 ? g.y0 : cy0;
            cx1 = cx1 > g.x1 - 2 ? g.x1 - 2 : cx1;
            cy1 = cy1 > g.y1 - 2 ? g.y1 - 2 : cy1;
            double ink = 0.0;
            for (int cy = cy0; cy <= cy1 && ink < 1.0; cy++)
                for (int cx = cx0; cx <= cx1 && ink < 1.0; cx++)
                    ink = fmax(ink, cell_ink(j, cx, cy, qx, qy));
            if (connected(j->in->texture)) {
                double t = rd(j->in->texture, x, y, 0);
                t = isnan(t) ? 1.0 : clamp01(t);
                ink *= 1.0 - p->texture_amount * (1.0 - t);
            }
            nprfx_image_at(j->out, x, y)[0] = (float)(ink * p->opacity);
        }
}

static nprfx_result check_channels(nprfx_context *ctx, const nprfx_image *im, const char *name,
                                   int lo, int hi)
{
    if (!connected(im) || (im->channels >= lo && im->channels <= hi)) return NPRFX_OK;
    if (lo == hi)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "lines: input '%s' has %d channels, expected %d", name, im->channels,
                           lo);
    return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                       "lines: input '%s' has %d channels, expected %d to %d", name, im->channels,
                       lo, hi);
}

static nprfx_result check_range(nprfx_context *ctx, const char *name, double v, double lo,
                                double hi)
{
    if (v >= lo && v <= hi) return NPRFX_OK;
    return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "lines.%s: %g is outside [%g, %g]", name, v, lo,
                       hi);
}

nprfx_result nprfx_lines_render(nprfx_context *ctx, const nprfx_lines_params *p,
                                const nprfx_lines_inputs *in, nprfx_rect frame, nprfx_rect window,
                                nprfx_image *out)
{
    if (!p || !in || in->size < sizeof(nprfx_lines_inputs) || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "lines: no params, inputs or output");
    if (out->channels != 1)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH, "lines: output has %d channels, not 1",
                           out->channels);
    nprfx_result r;
    if ((r = check_range(ctx, "width", p->width, 0, 256)) ||
        (r = check_range(ctx, "thicken", p->thicken, 0, 64)) ||
        (r = check_range(ctx, "depth_threshold", p->depth_threshold, 0, 1e6)) ||
        (r = check_range(ctx, "crease_angle", p->crease_angle, 0, 180)) ||
        (r = check_range(ctx, "aov_threshold", p->aov_threshold, 0, 1e30)) ||
        (r = check_range(ctx, "wobble", p->wobble, 0, 256)) ||
        (r = check_range(ctx, "texture_amount", p->texture_amount, 0, 1)) ||
        (r = check_range(ctx, "opacity", p->opacity, 0, 1)))
        return r;
    if (!connected(in->id) && !connected(in->coverage) && !connected(in->depth) &&
        !connected(in->normal) && !connected(in->aov))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "lines: no edge input is connected: connect 'id', 'coverage', "
                           "'depth', 'normal' or 'aov'");
    if ((r = check_channels(ctx, in->id, "id", 1, 1)) ||
        (r = check_channels(ctx, in->coverage, "coverage", 1, 1)) ||
        (r = check_channels(ctx, in->depth, "depth", 1, 1)) ||
        (r = check_channels(ctx, in->normal, "normal", 3, 3)) ||
        (r = check_channels(ctx, in->aov, "aov", 1, 4)) ||
        (r = check_channels(ctx, in->width, "width", 1, 1)) ||
        (r = check_channels(ctx, in->wobble, "wobble", 1, 2)) ||
        (r = check_channels(ctx, in->texture, "texture", 1, 1)))
        return r;
    window = nprfx_rect_intersect(nprfx_rect_intersect(window, out->bounds), frame);
    if (nprfx_rect_empty(window)) return NPRFX_OK;

    lines_job j = {0};
    j.p = p;
    j.in = in;
    j.frame = frame;
    j.window = window;
    j.out = out;
    j.cos_crease = cos(p->crease_angle * (k_pi / 180.0));
    double wmax = p->width * (connected(in->width) ? 1.0 + p->thicken : 1.0);
    j.reach = 0.5 * wmax + 0.5; /* ink is 0 farther than this from a segment */
    double wob = connected(in->wobble) ? p->wobble : 0.0;
    /* Every cell a window pixel can reach, and the pairs around it; cut to the frame, so the
     * pairs are the same whatever the window. */
    int grow = (int)ceil(j.reach + wob) + 2;
    j.grid = nprfx_rect_intersect(
        nprfx_rect_make(window.x0 - grow, window.y0 - grow, window.x1 + grow, window.y1 + grow),
        frame);
    size_t n = (size_t)nprfx_rect_width(j.grid) * (size_t)nprfx_rect_height(j.grid);
    j.h = malloc(sizeof(pair_pt) * n);
    j.v = malloc(sizeof(pair_pt) * n);
    if (!j.h || !j.v) {
        free(j.h);
        free(j.v);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "lines: out of memory");
    }
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    nprfx_parallel_for(ex, nprfx_rect_height(j.grid), 8, pairs_rows, &j);
    nprfx_parallel_for(ex, nprfx_rect_height(window), 4, ink_rows, &j);
    free(j.h);
    free(j.v);
    return NPRFX_OK;
}
