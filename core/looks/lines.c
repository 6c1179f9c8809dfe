/* Ink lines from AOVs (docs/design.md §3.11): edge points between neighbouring pixel centres where
 * an edge source fires, joined into segments per 2x2 cell of pixel centres (marching squares), and
 * ink from the distance to those segments, box-filtered. See nprfx/lines.h.
 *
 * Two passes over the window grown by the reach: cells_rows finds the edge points row by row
 * (from packed copies of the input rows) and lists each cell's segments; ink_rows then visits,
 * per pixel, exactly the cells the reach covers, skipping 32-pixel spans with no segment in reach
 * of any pixel. Ink is a max over segments, so the result does not depend on the visiting order,
 * the split into rows or tiles, or the thread count. */
#include <limits.h>
#include <math.h>
#include <stdlib.h>

#include "nprfx/exec.h"
#include "nprfx/lines.h"
#include "nprfx/objectid.h"

/* Depth at or beyond this is background (docs/design.md §2). */
#define LINES_FAR_DEPTH 1e9

static const double k_pi = 3.14159265358979323846;

/* The per-pair tests run twice per pixel of the grid: inlined, they cost a fraction of calls. */
#if defined(__GNUC__)
#define LINES_INLINE static inline __attribute__((always_inline))
#else
#define LINES_INLINE static inline
#endif

/* One point per pair of neighbouring pixels: t in [0, 1] along the pair, or -1 (no edge), and
 * the stroke width read there. */
/* The node's inputs (NPRFX_LINES_IN_*); NULL where not connected. */
typedef struct lines_inputs {
    const nprfx_image *id;       /* 1 channel: object index */
    const nprfx_image *coverage; /* 1 channel: anti-aliased object coverage */
    const nprfx_image *depth;    /* 1 channel; background: not finite, >= 1e9 or <= 0 */
    const nprfx_image *normal;   /* 3 channels, any length (normalised here) */
    const nprfx_image *aov;      /* 1 to 4 channels: a custom pass (shadow, light) */
    const nprfx_image *width;    /* 1 channel in [0, 1]: thickness control (tone, lighting) */
    const nprfx_image *wobble;   /* 1 or 2 channels in [0, 1] around 0.5: displacement noise */
    const nprfx_image *texture;  /* 1 channel in [0, 1]: multiplies the ink */
} lines_inputs;

typedef struct pair_pt {
    float t, w;
} pair_pt;

typedef struct lines_job {
    const nprfx_lines_params *p;
    const lines_inputs *in;
    nprfx_rect frame, grid, window;
    double cos_crease, reach;
    nprfx_image *out;
} lines_job;

LINES_INLINE int connected(const nprfx_image *im)
{
    return im && im->data;
}

/* Channel c of an input at (x, y); 0 outside its data window (docs/design.md §2). */
LINES_INLINE float rd(const nprfx_image *im, int x, int y, int c)
{
    if (!nprfx_rect_contains(im->bounds, x, y)) return 0.0f;
    return nprfx_image_at(im, x, y)[c];
}

LINES_INLINE int clampi(int v, int lo, int hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

LINES_INLINE double clamp01(double v)
{
    return v >= 0.0 ? (v <= 1.0 ? v : 1.0) : 0.0;
}

LINES_INLINE int background(double z)
{
    return !(z > 0.0 && z < LINES_FAR_DEPTH);
}

/* The step between two depths when both are surface, else infinity (a background neighbour
 * predicts nothing about the surface's slope). */
LINES_INLINE double depth_step(double a, double b)
{
    return background(a) || background(b) ? INFINITY : fabs(a - b);
}

/* One pixel row of the inputs the pair tests read, copied into packed arrays once (the inputs are
 * often views of a plate of many interleaved channels, where every read was a cache miss).
 * Column i holds pixel x = grid.x0 - 1 + i, clamped to the frame, as is the row: that is what
 * the depth test's outer neighbours read, and inside the frame it is the pixel itself. 0 outside
 * an input's data window, as rd reads it. */
typedef struct packed_row {
    int y; /* the row it holds (before clamping); INT_MIN: none yet */
    float *id, *cov, *z, *n, *aov, *wid;
} packed_row;

enum { RING = 4 }; /* rows y - 1 .. y + 2 around a row of pairs */

typedef struct pair_rows {
    packed_row ring[RING];
    float *mem;
} pair_rows;

static void pack_input(const lines_job *j, const nprfx_image *im, int y, float *dst)
{
    if (!connected(im)) return;
    int x0 = j->grid.x0 - 1, n = nprfx_rect_width(j->grid) + 2, ch = im->channels;
    int yy = clampi(y, j->frame.y0, j->frame.y1 - 1);
    for (int i = 0; i < n; i++) {
        int xx = clampi(x0 + i, j->frame.x0, j->frame.x1 - 1);
        for (int c = 0; c < ch; c++)
            dst[(size_t)i * (size_t)ch + (size_t)c] = rd(im, xx, yy, c);
    }
}

static int pair_rows_init(const lines_job *j, pair_rows *r)
{
    const lines_inputs *in = j->in;
    size_t n = (size_t)nprfx_rect_width(j->grid) + 2;
    int ac = connected(in->aov) ? in->aov->channels : 0;
    size_t per = n * (size_t)(1 + 1 + 1 + 3 + ac + 1);
    r->mem = malloc(sizeof(float) * per * RING);
    if (!r->mem) return 0;
    for (int k = 0; k < RING; k++) {
        float *m = r->mem + per * (size_t)k;
        packed_row *pr = &r->ring[k];
        pr->y = INT_MIN;
        pr->id = m;
        pr->cov = m + n;
        pr->z = m + 2 * n;
        pr->n = m + 3 * n;
        pr->wid = m + 6 * n;
        pr->aov = m + 7 * n;
    }
    return 1;
}

/* Row y, packed (from the ring, or read now). */
static const packed_row *packed(const lines_job *j, pair_rows *r, int y)
{
    packed_row *pr = &r->ring[((y % RING) + RING) % RING];
    if (pr->y == y) return pr;
    const lines_inputs *in = j->in;
    pack_input(j, in->id, y, pr->id);
    pack_input(j, in->coverage, y, pr->cov);
    pack_input(j, in->depth, y, pr->z);
    pack_input(j, in->normal, y, pr->n);
    pack_input(j, in->width, y, pr->wid);
    pack_input(j, in->aov, y, pr->aov);
    pr->y = y;
    return pr;
}

/* Does a depth discontinuity lie between a and b (neighbours)? The jump between them, less the
 * smaller step just outside the pair (what a smooth surface's slope explains: a grazing plane
 * steps as much on either side, a silhouette does not), relative to the nearer depth. Background
 * next to surface always is one. z0 and z3 are the outer neighbours (before a, after b), clamped
 * to the frame. */
LINES_INLINE int depth_edge(const lines_job *j, double za, double zb, double z0, double z3)
{
    int ba = background(za), bb = background(zb);
    if (ba || bb) return ba != bb;
    double slope = fmin(depth_step(z0, za), depth_step(zb, z3));
    if (isinf(slope)) slope = 0.0; /* a one-pixel sliver between backgrounds: its full jump */
    double jump = fabs(za - zb) - slope;
    return jump > j->p->depth_threshold * fmin(za, zb);
}

LINES_INLINE int crease_edge(const lines_job *j, const float *na, const float *nb)
{
    double a[3], b[3], dot = 0.0, la = 0.0, lb = 0.0;
    for (int c = 0; c < 3; c++) {
        a[c] = na[c];
        b[c] = nb[c];
        dot += a[c] * b[c];
        la += a[c] * a[c];
        lb += b[c] * b[c];
    }
    /* No normal (background, outside the data window) or NaN: no crease to measure. */
    if (!(la > 1e-12 && lb > 1e-12) || !isfinite(dot)) return 0;
    return dot < j->cos_crease * sqrt(la * lb);
}

LINES_INLINE int aov_edge(const lines_job *j, const float *va, const float *vb, int channels)
{
    for (int c = 0; c < channels; c++)
        if (fabs((double)va[c] - (double)vb[c]) > j->p->aov_threshold)
            return 1; /* a NaN compares false: it makes no line */
    return 0;
}

/* The edge point between a (column ia of row ra) and b (column ib of row rb), or t = -1; z0, z3
 * the depths outside the pair. */
LINES_INLINE pair_pt edge_point(const lines_job *j, const packed_row *ra, int ia,
                                const packed_row *rb, int ib, float z0, float z3)
{
    const nprfx_lines_params *p = j->p;
    const lines_inputs *in = j->in;
    int edge = 0, cov_cross = 0;
    double ca = 0.0, cb = 0.0;
    if (connected(in->coverage)) {
        ca = ra->cov[ia];
        cb = rb->cov[ib];
        cov_cross = (ca >= 0.5) != (cb >= 0.5);
    }
    if (p->outline) {
        if (connected(in->id)) {
            edge |= !nprfx_id_same(ra->id[ia], rb->id[ib]);
        }
        edge |= cov_cross;
    }
    if (!edge && p->depth_edges && connected(in->depth))
        edge = depth_edge(j, ra->z[ia], rb->z[ib], z0, z3);
    if (!edge && p->creases && connected(in->normal))
        edge = crease_edge(j, ra->n + 3 * (size_t)ia, rb->n + 3 * (size_t)ib);
    if (!edge && p->aov_edges && connected(in->aov)) {
        int ac = in->aov->channels;
        edge =
            aov_edge(j, ra->aov + (size_t)ac * (size_t)ia, rb->aov + (size_t)ac * (size_t)ib, ac);
    }
    pair_pt r = {-1.0f, 0.0f};
    if (!edge) return r;
    /* The coverage's 0.5 crossing, linearly interpolated, is where an anti-aliased edge lies
     * (for a straight edge the box-filtered coverage is 0.5 exactly on it); without one, the
     * midpoint is off by at most half a pixel. */
    double t = cov_cross ? clamp01((0.5 - ca) / (cb - ca)) : 0.5;
    double w = p->width;
    if (connected(in->width)) {
        double wa = ra->wid[ia], wb = rb->wid[ib];
        double v = wa + t * (wb - wa);
        v = isnan(v) ? 1.0 : clamp01(v); /* NaN: no thickening */
        w = p->width * (1.0 + p->thicken * (1.0 - v));
    }
    r.t = (float)t;
    r.w = (float)w;
    return r;
}

/* One segment of a cell, in frame coordinates, with the widths at its ends. Segments are derived
 * once per cell and call, so a pixel only visits the (few) segments of the cells in its reach
 * instead of re-deriving four pairs for each of them. */
typedef struct segment {
    double ax, ay, wa, bx, by, wb;
} segment;

/* The segments of the cells of one row, cx ascending: cell cx's are seg[off[cx - grid.x0]] up to
 * seg[off[cx - grid.x0 + 1]]. */
typedef struct cell_row {
    segment *seg;
    unsigned *off; /* ncx + 1 entries, into the job's offsets */
    int failed;    /* out of memory: the frame fails */
} cell_row;

/* The pairs (x, y)-(x + 1, y) of row y, at x - grid.x0; the last has no right neighbour. */
static void pairs_row_h(const lines_job *j, pair_rows *pr, int y, pair_pt *h)
{
    pair_pt none = {-1.0f, 0.0f};
    const packed_row *r = packed(j, pr, y);
    int gw = nprfx_rect_width(j->grid);
    for (int x = 0; x + 1 < gw; x++) /* packed column of pixel x is x + 1 */
        h[x] = edge_point(j, r, x + 1, r, x + 2, r->z[x], r->z[x + 3]);
    h[gw - 1] = none;
}

/* The pairs (x, y)-(x, y + 1); none on the grid's last row. */
static void pairs_row_v(const lines_job *j, pair_rows *pr, int y, pair_pt *v)
{
    pair_pt none = {-1.0f, 0.0f};
    int gw = nprfx_rect_width(j->grid);
    if (y + 1 >= j->grid.y1) {
        for (int x = 0; x < gw; x++)
            v[x] = none;
        return;
    }
    /* the outer rows first: the ring holds y - 1 .. y + 2 */
    const packed_row *r0 = packed(j, pr, y - 1), *r3 = packed(j, pr, y + 2);
    const packed_row *ra = packed(j, pr, y), *rb = packed(j, pr, y + 1);
    for (int x = 0; x < gw; x++)
        v[x] = edge_point(j, ra, x + 1, rb, x + 1, r0->z[x + 1], r3->z[x + 1]);
}

/* The points on the four sides of cell (cx, cy), from the pairs of rows cy (top, left/right) and
 * cy + 1 (bottom); returns their count. */
static int cell_points(int cx, int cy, const pair_pt *top, const pair_pt *bottom, const pair_pt *v,
                       double *px, double *py, double *pw)
{
    pair_pt e[4] = {top[0], bottom[0], v[0], v[1]};
    int n = 0;
    for (int i = 0; i < 4; i++) {
        if (e[i].t < 0.0f) continue;
        /* top, bottom: along x at rows cy, cy + 1; left, right: along y at columns cx, cx + 1 */
        px[n] = i < 2 ? cx + (double)e[i].t : cx + (i - 2);
        py[n] = i < 2 ? cy + i : cy + (double)e[i].t;
        pw[n] = e[i].w;
        n++;
    }
    return n;
}

static int cell_segments(int n)
{
    return n == 2 ? 1 : n; /* a dot, a segment, or one segment per point of a junction */
}

/* The segments of cell (cx, cy), joined marching-squares style. */
static segment *emit_segments(int cx, int cy, const pair_pt *top, const pair_pt *bottom,
                              const pair_pt *v, segment *out)
{
    double px[4], py[4], pw[4];
    int n = cell_points(cx, cy, top, bottom, v, px, py, pw);
    if (n == 0) return out;
    if (n <= 2) {
        int b = n - 1; /* a degenerate segment is a dot */
        *out++ = (segment){px[0], py[0], pw[0], px[b], py[b], pw[b]};
        return out;
    }
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
    for (int i = 0; i < n; i++)
        *out++ = (segment){px[i], py[i], pw[i], mx, my, mw};
    return out;
}

typedef struct cells_job {
    lines_job *j;
    cell_row *rows;
    unsigned *off;
    int ncx;
} cells_job;

/* Cell rows [begin, end): the pairs of their pixel rows (two rows of horizontal pairs, rolling),
 * then each cell's segments. */
static void cells_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    cells_job *c = user;
    const lines_job *j = c->j;
    nprfx_rect g = j->grid;
    int gw = nprfx_rect_width(g), ncx = c->ncx;
    pair_pt *buf = malloc(sizeof(pair_pt) * 3 * (size_t)gw);
    pair_rows pr;
    if (!pair_rows_init(j, &pr)) pr.mem = NULL;
    if (!buf || !pr.mem) {
        free(buf);
        free(pr.mem);
        for (int r = begin; r < end; r++)
            c->rows[r].failed = 1;
        return;
    }
    pair_pt *top = buf, *bottom = buf + gw, *v = buf + 2 * (size_t)gw;
    pairs_row_h(j, &pr, g.y0 + begin, top);
    for (int r = begin; r < end; r++) {
        int cy = g.y0 + r;
        pairs_row_v(j, &pr, cy, v);
        pairs_row_h(j, &pr, cy + 1, bottom);
        unsigned *off = c->off + (size_t)r * (size_t)(ncx + 1);
        unsigned n = 0;
        for (int i = 0; i < ncx; i++) {
            off[i] = n;
            n += (unsigned)cell_segments((top[i].t >= 0.0f) + (bottom[i].t >= 0.0f) +
                                         (v[i].t >= 0.0f) + (v[i + 1].t >= 0.0f));
        }
        off[ncx] = n;
        c->rows[r].off = off;
        c->rows[r].seg = NULL;
        if (n) {
            segment *s = malloc(sizeof(segment) * n);
            if (!s) {
                c->rows[r].failed = 1;
            } else {
                c->rows[r].seg = s;
                for (int i = 0; i < ncx; i++)
                    s = emit_segments(g.x0 + i, cy, top + i, bottom + i, v + i, s);
            }
        }
        pair_pt *t = top;
        top = bottom;
        bottom = t;
    }
    free(buf);
    free(pr.mem);
}

/* Ink from one segment a-b (widths wa, wb) at q: the box filter of a stroke of the width read at
 * the closest point. A degenerate segment is a dot. */
static double segment_ink(double qx, double qy, const segment *g)
{
    double ax = g->ax, ay = g->ay, wa = g->wa, bx = g->bx, by = g->by, wb = g->wb;
    double ex = bx - ax, ey = by - ay, l2 = ex * ex + ey * ey;
    double s = l2 > 0.0 ? clamp01(((qx - ax) * ex + (qy - ay) * ey) / l2) : 0.0;
    double dx = qx - (ax + s * ex), dy = qy - (ay + s * ey);
    double d = sqrt(dx * dx + dy * dy);
    double w = wa + s * (wb - wa);
    return clamp01(0.5 * w - d + 0.5);
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

typedef struct ink_job {
    const lines_job *j;
    const cell_row *rows;
    double wob;    /* the most the wobble moves a pixel */
    double reject; /* a segment whose bounding box is farther than this gives no ink */
} ink_job;

/* Does any cell in [cx0, cx1] x [cy0, cy1] (clamped to the cells) hold a segment? */
static int any_segment(const lines_job *j, const cell_row *rows, int cx0, int cx1, int cy0, int cy1)
{
    nprfx_rect g = j->grid;
    cx0 = cx0 < g.x0 ? g.x0 : cx0;
    cy0 = cy0 < g.y0 ? g.y0 : cy0;
    cx1 = cx1 > g.x1 - 2 ? g.x1 - 2 : cx1;
    cy1 = cy1 > g.y1 - 2 ? g.y1 - 2 : cy1;
    for (int cy = cy0; cy <= cy1 && cx0 <= cx1; cy++) {
        const unsigned *off = rows[cy - g.y0].off;
        if (off[cx1 + 1 - g.x0] != off[cx0 - g.x0]) return 1;
    }
    return 0;
}

/* Pixels are visited in spans of this many; a span with no segment in reach of any of its
 * pixels (most of a frame) is written as 0 without looking at each pixel. */
enum { SPAN = 32 };

static void ink_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const ink_job *k = user;
    const lines_job *j = k->j;
    const nprfx_lines_params *p = j->p;
    nprfx_rect g = j->grid;
    double reach = j->reach, rej = k->reject;
    int tex = connected(j->in->texture);
    for (int y = j->window.y0 + begin; y < j->window.y0 + end; y++) {
        /* the cell rows any pixel of this row can reach, with a cell to spare for rounding */
        int sy0 = (int)floor(y - k->wob - reach) - 2, sy1 = (int)floor(y + k->wob + reach) + 1;
        for (int x0 = j->window.x0; x0 < j->window.x1; x0 += SPAN) {
            int x1 = x0 + SPAN < j->window.x1 ? x0 + SPAN : j->window.x1;
            int sx0 = (int)floor(x0 - k->wob - reach) - 2;
            int sx1 = (int)floor(x1 - 1 + k->wob + reach) + 1;
            if (!any_segment(j, k->rows, sx0, sx1, sy0, sy1)) {
                for (int x = x0; x < x1; x++)
                    nprfx_image_at(j->out, x, y)[0] = 0.0f;
                continue;
            }
            for (int x = x0; x < x1; x++) {
                double ox, oy;
                wobble_offset(j, x, y, &ox, &oy);
                double qx = x + ox, qy = y + oy;
                /* cells holding a point within reach of q; a cell spans [cx, cx + 1] */
                int cx0 = (int)floor(qx - reach) - 1, cx1 = (int)floor(qx + reach);
                int cy0 = (int)floor(qy - reach) - 1, cy1 = (int)floor(qy + reach);
                cx0 = cx0 < g.x0 ? g.x0 : cx0;
                cy0 = cy0 < g.y0 ? g.y0 : cy0;
                cx1 = cx1 > g.x1 - 2 ? g.x1 - 2 : cx1;
                cy1 = cy1 > g.y1 - 2 ? g.y1 - 2 : cy1;
                double ink = 0.0;
                for (int cy = cy0; cy <= cy1 && cx0 <= cx1 && ink < 1.0; cy++) {
                    const cell_row *row = &k->rows[cy - g.y0];
                    const segment *s = row->seg + row->off[cx0 - g.x0];
                    const segment *e = row->seg + row->off[cx1 + 1 - g.x0];
                    for (; s < e && ink < 1.0; s++) {
                        /* farther than reach along an axis: no ink, and no sqrt */
                        if (qx - fmax(s->ax, s->bx) > rej || fmin(s->ax, s->bx) - qx > rej ||
                            qy - fmax(s->ay, s->by) > rej || fmin(s->ay, s->by) - qy > rej)
                            continue;
                        ink = fmax(ink, segment_ink(qx, qy, s));
                    }
                }
                if (ink > 0.0 && tex) {
                    double t = rd(j->in->texture, x, y, 0);
                    t = isnan(t) ? 1.0 : clamp01(t);
                    ink *= 1.0 - p->texture_amount * (1.0 - t);
                }
                nprfx_image_at(j->out, x, y)[0] = (float)(ink * p->opacity);
            }
        }
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

nprfx_result nprfx_lines_render(const nprfx_render_args *args, const nprfx_lines_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    const lines_inputs inputs = {nprfx_render_input(args, NPRFX_LINES_IN_ID),
                                 nprfx_render_input(args, NPRFX_LINES_IN_COVERAGE),
                                 nprfx_render_input(args, NPRFX_LINES_IN_DEPTH),
                                 nprfx_render_input(args, NPRFX_LINES_IN_NORMAL),
                                 nprfx_render_input(args, NPRFX_LINES_IN_AOV),
                                 nprfx_render_input(args, NPRFX_LINES_IN_WIDTH),
                                 nprfx_render_input(args, NPRFX_LINES_IN_WOBBLE),
                                 nprfx_render_input(args, NPRFX_LINES_IN_TEXTURE)};
    const lines_inputs *in = &inputs;
    nprfx_rect frame = args->frame, window = args->window;
    nprfx_image *out = args->output;
    if (!p || !out || !out->data)
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
    /* Cells span neighbouring pixel centres: one fewer than pixels each way. */
    int ncx = nprfx_rect_width(j.grid) - 1, ncy = nprfx_rect_height(j.grid) - 1;
    ncx = ncx > 0 ? ncx : 0;
    ncy = ncy > 0 ? ncy : 0;
    cells_job c = {&j, NULL, NULL, ncx};
    c.rows = calloc((size_t)ncy + 1, sizeof(cell_row));
    c.off = malloc(sizeof(unsigned) * ((size_t)ncy * (size_t)(ncx + 1) + 1));
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    if (c.rows && c.off) nprfx_parallel_for(ex, ncy, 8, cells_rows, &c);
    int failed = !c.rows || !c.off;
    for (int r = 0; !failed && r < ncy; r++)
        failed = c.rows[r].failed;
    nprfx_result res = NPRFX_OK;
    if (failed) {
        res = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "lines: out of memory");
    } else {
        ink_job k = {&j, c.rows, wob, 0.0};
        /* A segment's ink is 0 beyond reach; the slack covers a width rounded up to float. */
        k.reject = j.reach * (1.0 + 1e-6) + 1e-6;
        nprfx_parallel_for(ex, nprfx_rect_height(window), 4, ink_rows, &k);
    }
    if (c.rows)
        for (int r = 0; r < ncy; r++)
            free(c.rows[r].seg);
    free(c.rows);
    free(c.off);
    return res;
}
