/* The IVS generator: a farthest-point sequence on the unit torus (docs/design.md §3.3).
 *
 * Written from the description, not from an existing implementation:
 *
 *  - Bootstrap. One seeded random point, a second one at a random offset of 0.1..0.3 in each
 *    coordinate. Two random points keep the configuration generic, so no exact lattice forms;
 *    an offset near (1/2, 1/2) would start a square lattice that the process then refines
 *    level by level (r_i * sqrt(i) swinging between 0.71 and 1.0), and this range measured best
 *    (r_i * sqrt(i) within [0.77, 0.89] past i = 16 over 200 seeds). While the largest empty circle
 *    is still big compared with the torus, further points are found by brute force: the
 *    farthest point is a vertex of the periodic Voronoi diagram, i.e. a circumcentre of three
 *    copies of points, so all such circumcentres are tried.
 *
 *  - Once every empty circle has radius < 1/4, the periodic Delaunay triangulation is built
 *    (brute force once, on a handful of points) and from then on maintained incrementally by
 *    Bowyer-Watson. Triangles live on the torus: each stores its vertex indices plus an integer
 *    offset per vertex (the vertex is drawn at point + offset). With all circumradii < 1/4 a
 *    circumdisc cannot contain two copies of a point, so the cavity of a new point is a disc
 *    whose triangles and boundary vertices are all distinct, and the planar algorithm applies
 *    with offsets carried along.
 *
 *  - The point to insert is always the circumcentre of the triangle with the largest circumcircle,
 *    kept in a max-heap (stale entries are recognised by a version stamp and skipped; only the
 *    triangles made by an insertion are pushed). It lies inside its own triangle's circumcircle,
 *    so no point location is needed: the cavity grows from that triangle.
 *
 *  - Near-ties. Exactly or nearly equal circles are where a farthest-point process locks into
 *    hexagonal lattice patches. Each triangle's heap key is its circumradius times
 *    (1 + NEAR_TIE * u), u a seeded hash of its birth: the heap then returns a random choice among
 *    the circles within NEAR_TIE of the largest, at O(log n) cost. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/ivs.h"
#include "nprfx/rng.h"

/* Relative width of the band of near-maximal circles a random choice is made in. */
#define NEAR_TIE 0.01
/* The incremental phase needs every circumradius below 1/4 (see above); switch a little below. */
#define SWITCH_RADIUS 0.22
/* Attempts with other random starting points when the bootstrap triangulation is degenerate
 * (four cocircular points); with two generic random points this practically never happens. */
#define MAX_ATTEMPTS 16

/* Hash streams, so that each use of randomness is independent. */
enum { STREAM_START = 1, STREAM_TIE = 2 };

typedef struct tri {
    int v[3];     /* vertex indices, counter-clockwise */
    int nb[3];    /* across the edge opposite v[j]: (triangle << 2) | its edge index */
    int8_t ox[3]; /* vertex j is drawn at (x[v[j]] + ox[j], y[v[j]] + oy[j]) */
    int8_t oy[3];
    uint32_t version; /* bumped whenever the slot is reused: heap entries remember it */
} tri;

typedef struct heap_entry {
    float key; /* perturbed squared circumradius */
    int t;
    uint32_t version;
} heap_entry;

typedef struct gen {
    nprfx_context *ctx;
    uint64_t seed;
    uint32_t attempt;
    int n;     /* points wanted */
    int count; /* points so far */
    double *x, *y;
    float *radius; /* may be NULL */
    tri *tris;
    double *r2; /* squared circumradius per triangle slot */
    int ntris, cap_tris;
    heap_entry *heap;
    size_t heap_n, heap_cap;
    int *tri_mark; /* insertion stamp of the cavity a triangle was last put in */
    int *vert_mark;
    int *vert_tri; /* scratch: new triangle whose boundary edge starts at a vertex */
    /* cavity scratch */
    int *cav, *cav_sx, *cav_sy;
    int cav_n, cav_cap;
    /* boundary scratch */
    int *bd_a, *bd_b, *bd_oax, *bd_oay, *bd_obx, *bd_oby, *bd_out;
    int bd_n, bd_cap;
} gen;

/* ---- small geometry ---- */

static double orient2(double ax, double ay, double bx, double by, double cx, double cy)
{
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

/* > 0 when (px, py) is strictly inside the circle through the counter-clockwise a, b, c.
 * Computed relative to p, which keeps the terms small. */
static double incircle(double ax, double ay, double bx, double by, double cx, double cy, double px,
                       double py)
{
    double adx = ax - px, ady = ay - py, bdx = bx - px, bdy = by - py, cdx = cx - px, cdy = cy - py;
    double ad = adx * adx + ady * ady, bd = bdx * bdx + bdy * bdy, cd = cdx * cdx + cdy * cdy;
    return ad * (bdx * cdy - cdx * bdy) + bd * (cdx * ady - adx * cdy) +
           cd * (adx * bdy - bdx * ady);
}

/* Circumcentre and squared radius; returns 0 for a degenerate triangle. */
static int circumcircle(double ax, double ay, double bx, double by, double cx, double cy,
                        double *ux, double *uy, double *r2)
{
    double bpx = bx - ax, bpy = by - ay, cpx = cx - ax, cpy = cy - ay;
    double d = 2.0 * (bpx * cpy - bpy * cpx);
    if (d == 0.0) return 0;
    double b2 = bpx * bpx + bpy * bpy, c2 = cpx * cpx + cpy * cpy;
    double dx = (cpy * b2 - bpy * c2) / d, dy = (bpx * c2 - cpx * b2) / d;
    *ux = ax + dx;
    *uy = ay + dy;
    *r2 = dx * dx + dy * dy;
    return 1;
}

static double wrap01(double v)
{
    v -= floor(v);
    return v >= 1.0 ? 0.0 : v; /* floor can leave exactly 1 after rounding */
}

static double torus_d2(double ax, double ay, double bx, double by)
{
    double dx = fabs(ax - bx), dy = fabs(ay - by);
    dx = dx > 0.5 ? 1.0 - dx : dx;
    dy = dy > 0.5 ? 1.0 - dy : dy;
    return dx * dx + dy * dy;
}

static double hash_u01(const gen *g, uint32_t stream, int a, int b)
{
    return nprfx_rand_u01(g->seed, (int64_t)g->attempt, a, b, 0, stream);
}

/* ---- growable scratch ---- */

static int grow(void **p, int *cap, int need, size_t elem)
{
    if (need <= *cap) return 1;
    int nc = *cap ? *cap : 16;
    while (nc < need)
        nc *= 2;
    void *q = realloc(*p, (size_t)nc * elem);
    if (!q) return 0;
    *p = q;
    *cap = nc;
    return 1;
}

static int grow_cavity(gen *g, int need)
{
    int cap = g->cav_cap;
    if (!grow((void **)&g->cav, &cap, need, sizeof(int))) return 0;
    cap = g->cav_cap;
    if (!grow((void **)&g->cav_sx, &cap, need, sizeof(int))) return 0;
    cap = g->cav_cap;
    if (!grow((void **)&g->cav_sy, &cap, need, sizeof(int))) return 0;
    g->cav_cap = cap;
    return 1;
}

static int grow_boundary(gen *g, int need)
{
    int *const *arrs[] = {&g->bd_a,   &g->bd_b,   &g->bd_oax, &g->bd_oay,
                          &g->bd_obx, &g->bd_oby, &g->bd_out};
    int cap = g->bd_cap;
    for (size_t i = 0; i < sizeof arrs / sizeof arrs[0]; i++) {
        cap = g->bd_cap;
        if (!grow((void **)arrs[i], &cap, need, sizeof(int))) return 0;
    }
    g->bd_cap = cap;
    return 1;
}

/* ---- the heap ---- */

static int entry_less(const heap_entry *a, const heap_entry *b)
{
    /* Ties on the key fall back to the slot index so the order never depends on anything but
     * the data. */
    return a->key < b->key || (a->key == b->key && a->t < b->t);
}

static void sift_down(heap_entry *h, size_t n, size_t i)
{
    heap_entry e = h[i];
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= n) break;
        if (c + 1 < n && entry_less(&h[c], &h[c + 1])) c++;
        if (!entry_less(&e, &h[c])) break;
        h[i] = h[c];
        i = c;
    }
    h[i] = e;
}

static int heap_push(gen *g, heap_entry e)
{
    if (g->heap_n == g->heap_cap) {
        /* Entries of destroyed triangles linger until they surface; when they outnumber the
         * live ones, drop them instead of growing. */
        size_t live = 0;
        for (size_t i = 0; i < g->heap_n; i++) {
            const heap_entry *q = &g->heap[i];
            if (g->tris[q->t].version == q->version) g->heap[live++] = *q;
        }
        if (g->heap_cap == 0 || live > g->heap_cap / 2) {
            size_t nc = g->heap_cap ? g->heap_cap * 2 : 1024;
            heap_entry *nh = realloc(g->heap, nc * sizeof *nh);
            if (!nh) return 0;
            g->heap = nh;
            g->heap_cap = nc;
        }
        g->heap_n = live;
        for (size_t i = live / 2; i-- > 0;)
            sift_down(g->heap, live, i);
    }
    size_t i = g->heap_n++;
    while (i > 0) {
        size_t p = (i - 1) / 2;
        if (!entry_less(&g->heap[p], &e)) break;
        g->heap[i] = g->heap[p];
        i = p;
    }
    g->heap[i] = e;
    return 1;
}

/* Pop the live triangle with the largest key; -1 when none is left. */
static int heap_pop(gen *g)
{
    while (g->heap_n > 0) {
        heap_entry top = g->heap[0];
        g->heap[0] = g->heap[--g->heap_n];
        if (g->heap_n) sift_down(g->heap, g->heap_n, 0);
        if (g->tris[top.t].version == top.version) return top.t;
    }
    return -1;
}

/* Vertex j of triangle t in the triangle's own frame. */
static void tri_vertex(const gen *g, const tri *t, int j, double *px, double *py)
{
    *px = g->x[t->v[j]] + t->ox[j];
    *py = g->y[t->v[j]] + t->oy[j];
}

/* Circumcircle of triangle slot t in its frame; stores the squared radius and pushes it. `tag`
 * identifies the triangle's birth for the near-tie hash. */
static int tri_commit(gen *g, int t, int tag)
{
    const tri *tr = &g->tris[t];
    double ax, ay, bx, by, cx, cy, ux, uy, r2;
    tri_vertex(g, tr, 0, &ax, &ay);
    tri_vertex(g, tr, 1, &bx, &by);
    tri_vertex(g, tr, 2, &cx, &cy);
    if (!circumcircle(ax, ay, bx, by, cx, cy, &ux, &uy, &r2)) r2 = 0.0;
    g->r2[t] = r2;
    double u = hash_u01(g, STREAM_TIE, g->count, tag);
    heap_entry e;
    e.key = (float)(r2 * (1.0 + NEAR_TIE * u) * (1.0 + NEAR_TIE * u));
    e.t = t;
    e.version = tr->version;
    return heap_push(g, e);
}

static int alloc_tri(gen *g)
{
    if (g->ntris == g->cap_tris) {
        int cap = g->cap_tris ? g->cap_tris * 2 : 64;
        tri *nt = realloc(g->tris, (size_t)cap * sizeof *nt);
        if (!nt) return -1;
        g->tris = nt;
        double *nr = realloc(g->r2, (size_t)cap * sizeof *nr);
        if (!nr) return -1;
        g->r2 = nr;
        int *nm = realloc(g->tri_mark, (size_t)cap * sizeof *nm);
        if (!nm) return -1;
        g->tri_mark = nm;
        for (int i = g->cap_tris; i < cap; i++) {
            g->tri_mark[i] = -1;
            g->tris[i].version = 0;
        }
        g->cap_tris = cap;
    }
    return g->ntris++;
}

/* ---- bootstrap: brute-force farthest points on few points ---- */

/* The farthest point from the current points (the largest empty circle's centre) and its
 * distance. Candidates are the circumcentres of three copies of points within reach; `reach`
 * bounds the distance between copies that can share an empty circle (twice the previous
 * radius). */
static double farthest_brute(const gen *g, double reach, double *bx, double *by)
{
    int m = g->count;
    double best = 0.0;
    /* copies of every point within `reach` of a base point, offsets in [-2, 2]^2 */
    for (int i = 0; i < m; i++) {
        double px = g->x[i], py = g->y[i];
        double cxs[25 * 64], cys[25 * 64];
        int nc = 0;
        for (int j = 0; j < m; j++)
            for (int oy = -2; oy <= 2; oy++)
                for (int ox = -2; ox <= 2; ox++) {
                    if (j == i && ox == 0 && oy == 0) continue;
                    double qx = g->x[j] + ox, qy = g->y[j] + oy;
                    double dx = qx - px, dy = qy - py;
                    if (dx * dx + dy * dy <= reach * reach && nc < 25 * 64) {
                        cxs[nc] = qx;
                        cys[nc] = qy;
                        nc++;
                    }
                }
        for (int a = 0; a < nc; a++)
            for (int b = a + 1; b < nc; b++) {
                double ux, uy, r2;
                if (!circumcircle(px, py, cxs[a], cys[a], cxs[b], cys[b], &ux, &uy, &r2)) continue;
                if (r2 <= best * best) continue;
                /* the candidate's value is its distance to the nearest point of all */
                double wx = wrap01(ux), wy = wrap01(uy), d2 = r2;
                for (int j = 0; j < m && d2 > best * best; j++) {
                    double e2 = torus_d2(wx, wy, g->x[j], g->y[j]);
                    if (e2 < d2) d2 = e2;
                }
                double d = sqrt(d2);
                if (d > best) {
                    best = d;
                    *bx = wx;
                    *by = wy;
                }
            }
    }
    return best;
}

/* Build the periodic Delaunay triangulation of the bootstrap points by brute force. Returns 0
 * when the result is not a valid triangulation of the torus (degenerate input). */
static int build_initial(gen *g)
{
    int m = g->count;
    const double rmax = SWITCH_RADIUS;
    g->ntris = 0;
    for (int i = 0; i < m; i++) {
        /* copies (point index, offset) within 2 * rmax of point i */
        int cj[9 * 64], cox[9 * 64], coy[9 * 64], nc = 0;
        for (int j = 0; j < m; j++)
            for (int oy = -1; oy <= 1; oy++)
                for (int ox = -1; ox <= 1; ox++) {
                    if (j == i && ox == 0 && oy == 0) continue;
                    double dx = g->x[j] + ox - g->x[i], dy = g->y[j] + oy - g->y[i];
                    if (dx * dx + dy * dy < 4 * rmax * rmax && nc < 9 * 64) {
                        cj[nc] = j;
                        cox[nc] = ox;
                        coy[nc] = oy;
                        nc++;
                    }
                }
        for (int a = 0; a < nc; a++)
            for (int b = 0; b < nc; b++) {
                /* each triangle once: from its lowest-index vertex, counter-clockwise */
                if (cj[a] <= i || cj[b] <= i || a == b) continue;
                double ax = g->x[i], ay = g->y[i];
                double bx = g->x[cj[a]] + cox[a], by = g->y[cj[a]] + coy[a];
                double cx = g->x[cj[b]] + cox[b], cy = g->y[cj[b]] + coy[b];
                if (orient2(ax, ay, bx, by, cx, cy) <= 0) continue;
                double ux, uy, r2;
                if (!circumcircle(ax, ay, bx, by, cx, cy, &ux, &uy, &r2)) continue;
                if (r2 >= 0.0625) continue;
                int empty = 1;
                for (int j = 0; j < m && empty; j++)
                    for (int oy = -1; oy <= 1 && empty; oy++)
                        for (int ox = -1; ox <= 1 && empty; ox++) {
                            if ((j == i && ox == 0 && oy == 0) ||
                                (j == cj[a] && ox == cox[a] && oy == coy[a]) ||
                                (j == cj[b] && ox == cox[b] && oy == coy[b]))
                                continue;
                            double dx = g->x[j] + ox - ux, dy = g->y[j] + oy - uy;
                            /* cocircular points count as inside: both diagonals of a
                             * cocircular quad are then rejected and validation fails */
                            if (dx * dx + dy * dy <= r2 * (1 + 1e-9)) empty = 0;
                        }
                if (!empty) continue;
                int t = alloc_tri(g);
                if (t < 0) return -1;
                tri *tr = &g->tris[t];
                tr->v[0] = i;
                tr->v[1] = cj[a];
                tr->v[2] = cj[b];
                tr->ox[0] = 0;
                tr->oy[0] = 0;
                tr->ox[1] = (int8_t)cox[a];
                tr->oy[1] = (int8_t)coy[a];
                tr->ox[2] = (int8_t)cox[b];
                tr->oy[2] = (int8_t)coy[b];
                tr->nb[0] = tr->nb[1] = tr->nb[2] = -1;
            }
    }
    /* A triangulation of the torus has exactly 2 triangles per vertex (Euler characteristic 0),
     * and every edge is shared by exactly two triangles. */
    if (g->ntris != 2 * m) return 0;
    for (int t = 0; t < g->ntris; t++)
        for (int e = 0; e < 3; e++) {
            const tri *tr = &g->tris[t];
            int a = tr->v[(e + 1) % 3], b = tr->v[(e + 2) % 3];
            int dx = tr->ox[(e + 2) % 3] - tr->ox[(e + 1) % 3];
            int dy = tr->oy[(e + 2) % 3] - tr->oy[(e + 1) % 3];
            int found = 0;
            for (int s = 0; s < g->ntris; s++)
                for (int f = 0; f < 3; f++) {
                    const tri *ts = &g->tris[s];
                    if (ts->v[(f + 1) % 3] != b || ts->v[(f + 2) % 3] != a) continue;
                    if (ts->ox[(f + 2) % 3] - ts->ox[(f + 1) % 3] != -dx ||
                        ts->oy[(f + 2) % 3] - ts->oy[(f + 1) % 3] != -dy)
                        continue;
                    found++;
                    g->tris[t].nb[e] = (s << 2) | f;
                }
            if (found != 1) return 0;
        }
    return 1;
}

/* ---- incremental insertion ---- */

/* Add triangle t, seen with integer shift (sx, sy) in the new point's frame, to the cavity. */
static int cavity_add(gen *g, int t, int sx, int sy)
{
    if (!grow_cavity(g, g->cav_n + 1)) return 0;
    g->cav[g->cav_n] = t;
    g->cav_sx[g->cav_n] = sx;
    g->cav_sy[g->cav_n] = sy;
    g->cav_n++;
    g->tri_mark[t] = g->count;
    return 1;
}

/* Shift of the neighbour across edge j of cavity entry q, in the new point's frame. */
static void neighbour_shift(const gen *g, int q, int j, int *sx, int *sy)
{
    const tri *c = &g->tris[g->cav[q]];
    int code = c->nb[j], nt = code >> 2, e = code & 3;
    const tri *n = &g->tris[nt];
    /* the shared edge runs c.v[j+1] -> c.v[j+2] and n.v[e+2] -> n.v[e+1] */
    int cj = (j + 1) % 3, ne = (e + 2) % 3;
    *sx = g->cav_sx[q] + c->ox[cj] - n->ox[ne];
    *sy = g->cav_sy[q] + c->oy[cj] - n->oy[ne];
}

static int in_circle_shifted(const gen *g, int t, int sx, int sy, double px, double py)
{
    const tri *tr = &g->tris[t];
    double v[6];
    for (int j = 0; j < 3; j++) {
        tri_vertex(g, tr, j, &v[2 * j], &v[2 * j + 1]);
        v[2 * j] += sx;
        v[2 * j + 1] += sy;
    }
    return incircle(v[0], v[1], v[2], v[3], v[4], v[5], px, py) > 0;
}

/* Insert the circumcentre of triangle t0 as point g->count. */
static nprfx_result insert_circumcentre(gen *g, int t0)
{
    const tri *t = &g->tris[t0];
    double ax, ay, bx, by, cx, cy, px, py, r2;
    tri_vertex(g, t, 0, &ax, &ay);
    tri_vertex(g, t, 1, &bx, &by);
    tri_vertex(g, t, 2, &cx, &cy);
    if (!circumcircle(ax, ay, bx, by, cx, cy, &px, &py, &r2))
        return nprfx_error(g->ctx, NPRFX_ERR_INTERNAL, "ivs: degenerate triangle at point %d",
                           g->count);
    int k = g->count;
    double fx = floor(px), fy = floor(py);
    g->x[k] = wrap01(px);
    g->y[k] = wrap01(py);
    /* the wrapped point may have rounded to 0 from just below 1: keep the frame consistent */
    int pfx = (int)fx, pfy = (int)fy;
    px = g->x[k] + pfx;
    py = g->y[k] + pfy;
    if (g->radius) g->radius[k] = (float)sqrt(g->r2[t0]);

    /* Bowyer-Watson cavity: the triangles whose circumcircle contains p, flooded from t0. */
    g->cav_n = 0;
    if (!cavity_add(g, t0, 0, 0)) goto oom;
    for (int q = 0; q < g->cav_n; q++)
        for (int j = 0; j < 3; j++) {
            int nt = g->tris[g->cav[q]].nb[j] >> 2;
            if (g->tri_mark[nt] == k) continue;
            int sx, sy;
            neighbour_shift(g, q, j, &sx, &sy);
            if (in_circle_shifted(g, nt, sx, sy, px, py) && !cavity_add(g, nt, sx, sy)) goto oom;
        }

    /* Boundary edges. Rounding can leave a cavity that is not star-shaped from p (an edge p
     * does not see strictly from inside); the triangle beyond such an edge is then taken in too,
     * which restores a valid (if locally not quite Delaunay) triangulation. */
    for (int guard = 0;; guard++) {
        g->bd_n = 0;
        int fixed = 0;
        for (int q = 0; q < g->cav_n && !fixed; q++) {
            const tri *c = &g->tris[g->cav[q]];
            for (int j = 0; j < 3; j++) {
                int code = c->nb[j], nt = code >> 2;
                if (g->tri_mark[nt] == k) continue;
                int ja = (j + 1) % 3, jb = (j + 2) % 3;
                int oax = c->ox[ja] + g->cav_sx[q], oay = c->oy[ja] + g->cav_sy[q];
                int obx = c->ox[jb] + g->cav_sx[q], oby = c->oy[jb] + g->cav_sy[q];
                double qax = g->x[c->v[ja]] + oax, qay = g->y[c->v[ja]] + oay;
                double qbx = g->x[c->v[jb]] + obx, qby = g->y[c->v[jb]] + oby;
                if (orient2(qax, qay, qbx, qby, px, py) <= 0) {
                    int sx, sy;
                    neighbour_shift(g, q, j, &sx, &sy);
                    if (!cavity_add(g, nt, sx, sy)) goto oom;
                    fixed = 1;
                    break;
                }
                if (!grow_boundary(g, g->bd_n + 1)) goto oom;
                int b = g->bd_n++;
                g->bd_a[b] = c->v[ja];
                g->bd_b[b] = c->v[jb];
                g->bd_oax[b] = oax - pfx;
                g->bd_oay[b] = oay - pfy;
                g->bd_obx[b] = obx - pfx;
                g->bd_oby[b] = oby - pfy;
                g->bd_out[b] = code;
            }
        }
        if (!fixed) break;
        if (guard > 64)
            return nprfx_error(g->ctx, NPRFX_ERR_INTERNAL, "ivs: cavity of point %d does not close",
                               k);
    }
    /* A disc triangulated from its boundary alone has two triangles fewer than edges; each
     * boundary vertex must appear once. */
    if (g->bd_n != g->cav_n + 2)
        return nprfx_error(g->ctx, NPRFX_ERR_INTERNAL,
                           "ivs: cavity of point %d is not a disc (%d triangles, %d edges)", k,
                           g->cav_n, g->bd_n);
    for (int b = 0; b < g->bd_n; b++) {
        if (g->vert_mark[g->bd_a[b]] == k)
            return nprfx_error(g->ctx, NPRFX_ERR_INTERNAL,
                               "ivs: cavity of point %d touches vertex %d twice", k, g->bd_a[b]);
        g->vert_mark[g->bd_a[b]] = k;
    }

    /* New triangles (p, a, b), in the cavity's slots first. */
    int first_new = g->ntris;
    for (int b = 0; b < g->bd_n; b++) {
        int s;
        if (b < g->cav_n) {
            s = g->cav[b];
        } else {
            s = alloc_tri(g);
            if (s < 0) goto oom;
        }
        tri *nt = &g->tris[s];
        nt->version++;
        nt->v[0] = k;
        nt->v[1] = g->bd_a[b];
        nt->v[2] = g->bd_b[b];
        nt->ox[0] = 0;
        nt->oy[0] = 0;
        nt->ox[1] = (int8_t)g->bd_oax[b];
        nt->oy[1] = (int8_t)g->bd_oay[b];
        nt->ox[2] = (int8_t)g->bd_obx[b];
        nt->oy[2] = (int8_t)g->bd_oby[b];
        int out = g->bd_out[b];
        nt->nb[0] = out;
        g->tris[out >> 2].nb[out & 3] = s << 2;
        g->vert_tri[g->bd_a[b]] = s;
    }
    for (int b = 0; b < g->bd_n; b++) {
        int s = b < g->cav_n ? g->cav[b] : first_new + (b - g->cav_n);
        int s2 = g->vert_tri[g->bd_b[b]];
        /* edge (b -> p) of s is edge (p -> b) of s2, opposite s2's third vertex */
        g->tris[s].nb[1] = (s2 << 2) | 2;
        g->tris[s2].nb[2] = (s << 2) | 1;
    }
    g->count++;
    for (int b = 0; b < g->bd_n; b++) {
        int s = b < g->cav_n ? g->cav[b] : first_new + (b - g->cav_n);
        if (!tri_commit(g, s, b)) goto oom;
    }
    return NPRFX_OK;
oom:
    return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "ivs: out of memory at point %d", k);
}

static void gen_free(gen *g)
{
    free(g->x);
    free(g->y);
    free(g->tris);
    free(g->r2);
    free(g->heap);
    free(g->tri_mark);
    free(g->vert_mark);
    free(g->vert_tri);
    free(g->cav);
    free(g->cav_sx);
    free(g->cav_sy);
    free(g->bd_a);
    free(g->bd_b);
    free(g->bd_oax);
    free(g->bd_oay);
    free(g->bd_obx);
    free(g->bd_oby);
    free(g->bd_out);
}

/* One attempt from the starting points of g->attempt. Returns NPRFX_OK, an error, or -1 when the
 * bootstrap triangulation was degenerate (try other starting points). */
static nprfx_result run_attempt(gen *g)
{
    g->count = 0;
    g->ntris = 0;
    g->heap_n = 0;
    /* start: one random point and one more at a random offset of 0.3..0.7 in each coordinate */
    g->x[0] = hash_u01(g, STREAM_START, 0, 0);
    g->y[0] = hash_u01(g, STREAM_START, 0, 1);
    if (g->radius) g->radius[0] = (float)sqrt(0.5);
    g->count = 1;
    if (g->n > 1) {
        g->x[1] = wrap01(g->x[0] + 0.1 + 0.2 * hash_u01(g, STREAM_START, 1, 0));
        g->y[1] = wrap01(g->y[0] + 0.1 + 0.2 * hash_u01(g, STREAM_START, 1, 1));
        if (g->radius) g->radius[1] = (float)sqrt(torus_d2(g->x[0], g->y[0], g->x[1], g->y[1]));
        g->count = 2;
    }
    /* brute-force farthest points while empty circles are large */
    double reach = 2.0 * sqrt(0.5);
    while (g->count < g->n) {
        double fx = 0, fy = 0;
        double d = farthest_brute(g, reach + 1e-9, &fx, &fy);
        if (d < SWITCH_RADIUS) break;
        g->x[g->count] = fx;
        g->y[g->count] = fy;
        if (g->radius) g->radius[g->count] = (float)d;
        g->count++;
        reach = 2.0 * d;
    }
    if (g->count == g->n) return NPRFX_OK;
    int ok = build_initial(g);
    if (ok < 0) return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "ivs: out of memory");
    if (!ok) return -1;
    for (int t = 0; t < g->ntris; t++) {
        g->tris[t].version = 1;
        if (!tri_commit(g, t, t))
            return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "ivs: out of memory");
    }
    for (int i = 0; i < g->n; i++)
        g->vert_mark[i] = -1;
    while (g->count < g->n) {
        int t = heap_pop(g);
        if (t < 0) return nprfx_error(g->ctx, NPRFX_ERR_INTERNAL, "ivs: triangle heap ran dry");
        nprfx_result r = insert_circumcentre(g, t);
        if (r != NPRFX_OK) return r;
    }
    return NPRFX_OK;
}

nprfx_result nprfx_ivs_generate(nprfx_context *ctx, uint64_t seed, int n, float *xy, float *radius)
{
    if (n < 1 || !xy)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "ivs: need n >= 1 and an output array (n = %d)", n);
    gen g;
    memset(&g, 0, sizeof g);
    g.ctx = ctx;
    g.seed = seed;
    g.n = n;
    g.radius = radius;
    g.x = malloc((size_t)n * sizeof(double));
    g.y = malloc((size_t)n * sizeof(double));
    g.vert_mark = malloc((size_t)n * sizeof(int));
    g.vert_tri = malloc((size_t)n * sizeof(int));
    if (!g.x || !g.y || !g.vert_mark || !g.vert_tri) {
        gen_free(&g);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "ivs: out of memory for %d points", n);
    }
    nprfx_result r = -1;
    for (g.attempt = 0; g.attempt < MAX_ATTEMPTS && r == -1; g.attempt++)
        r = run_attempt(&g);
    if (r == -1)
        r = nprfx_error(ctx, NPRFX_ERR_INTERNAL, "ivs: no non-degenerate start found for seed %llu",
                        (unsigned long long)seed);
    if (r == NPRFX_OK)
        for (int i = 0; i < n; i++) {
            /* rounding to float can reach 1.0: wrap it, the torus is periodic */
            float fx = (float)g.x[i], fy = (float)g.y[i];
            xy[2 * i] = fx >= 1.0f ? 0.0f : fx;
            xy[2 * i + 1] = fy >= 1.0f ? 0.0f : fy;
        }
    gen_free(&g);
    return r;
}
