/* Procedural paper and canvas (docs/design.md §3.12): a screen-space height field from periodic
 * lattice noise, cellular bumps, fibre strokes or a plain weave, and the paper colour it shades.
 * See nprfx/paper.h.
 *
 * Everything is a pure function of the pixel position, the params and the seed: random numbers
 * are hashes of integer lattice or cell indices (nprfx_hash), taken modulo the tile's period,
 * and the position is reduced modulo the tile before any floating-point work, so a pixel and
 * its copy one tile away run the very same operations. No libm function but exact ones (floor,
 * sqrt, fabs, fmin, fmax) enters a pixel, so the paper is also the same on every machine. */
#include <math.h>
#include <stdint.h>

#include "nprfx/exec.h"
#include "nprfx/paper.h"
#include "nprfx/rng.h"

/* Streams of the seed's hashes, one range per use (fBm octaves and the x/y pairs take
 * consecutive streams). */
enum {
    S_GRAIN = 0x10,
    S_FORMATION = 0x20,
    S_COCKLE = 0x30,
    S_FIBRE = 0x40,
    S_BUMPS = 0x50,
    S_BUMPS2 = 0x60,
    S_WARP = 0x70,
    S_WOBBLE = 0x80,
    S_THREAD = 0x90,
    S_STREAK = 0xa0,
    S_OFFSET = 0x1000,   /* + the lattice's stream */
    S_FIBRE_DIR = 0x2000 /* + the rejection sampler's try */
};

/* 16 unit gradients, k * 22.5 degrees, written out rather than computed with cos and sin,
 * whose last bit may differ between C libraries. */
#define C1 0.9238795325112867
#define S1 0.3826834323650898
#define H1 0.7071067811865476
static const double grad16[16][2] = {
    {1, 0},  {C1, S1},   {H1, H1},   {S1, C1},   {0, 1},  {-S1, C1}, {-H1, H1}, {-C1, S1},
    {-1, 0}, {-C1, -S1}, {-H1, -H1}, {-S1, -C1}, {0, -1}, {S1, -C1}, {H1, -H1}, {C1, -S1}};

/* i modulo period in [0, period); period 0: i itself (not periodic). */
static int32_t wrap_index(int64_t i, int period)
{
    if (period <= 0) return (int32_t)i;
    int64_t m = i % period;
    return (int32_t)(m < 0 ? m + period : m);
}

/* The cell size nearest to c that fits a whole multiple of `multiple` cells in the tile, and
 * that number of cells (0: no tile, c kept). */
static void fit_period(double c, int tile, int multiple, double *cell, int *n)
{
    if (tile <= 0) {
        *cell = c;
        *n = 0;
        return;
    }
    double k = floor((double)tile / (c * multiple) + 0.5);
    if (k < 1) k = 1;
    *n = (int)k * multiple;
    *cell = (double)tile / *n;
}

/* A gradient-noise lattice (Perlin's, with quintic fade), periodic when px, py > 0. */
typedef struct lattice {
    double cx, cy; /* cell size in pixels */
    int px, py;    /* period in cells; 0: none */
    double ox, oy; /* a random shift, so that octaves do not all vanish at the same points */
    uint64_t seed;
    uint32_t stream;
} lattice;

static lattice make_lattice(double cx, double cy, int tile, uint64_t seed, uint32_t stream)
{
    lattice L;
    fit_period(cx, tile, 1, &L.cx, &L.px);
    fit_period(cy, tile, 1, &L.cy, &L.py);
    L.seed = seed;
    L.stream = stream;
    /* Any shift keeps the period (the lattice itself repeats); a whole number of cells keeps the
     * fitted cell exact. */
    L.ox = floor(nprfx_rand_u01(seed, 0, 0, 0, 0, S_OFFSET + stream) * 64.0) * L.cx;
    L.oy = floor(nprfx_rand_u01(seed, 0, 0, 0, 1, S_OFFSET + stream) * 64.0) * L.cy;
    return L;
}

static double fade(double t)
{
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

static double corner(const lattice *L, int64_t i, int64_t j, double dx, double dy)
{
    uint64_t h = nprfx_hash(L->seed, 0, wrap_index(i, L->px), wrap_index(j, L->py), 0, L->stream);
    const double *g = grad16[h >> 60];
    return g[0] * dx + g[1] * dy;
}

/* Gradient noise in about [-1, 1] (standard deviation about 0.3). */
static double gnoise(const lattice *L, double x, double y)
{
    double fx = (x + L->ox) / L->cx, fy = (y + L->oy) / L->cy;
    double flx = floor(fx), fly = floor(fy);
    double tx = fx - flx, ty = fy - fly;
    int64_t i = (int64_t)flx, j = (int64_t)fly;
    double n00 = corner(L, i, j, tx, ty), n10 = corner(L, i + 1, j, tx - 1.0, ty);
    double n01 = corner(L, i, j + 1, tx, ty - 1.0),
           n11 = corner(L, i + 1, j + 1, tx - 1.0, ty - 1.0);
    double sx = fade(tx), sy = fade(ty);
    double a = n00 + (n10 - n00) * sx, b = n01 + (n11 - n01) * sx;
    return 1.4142135623730951 * (a + (b - a) * sy);
}

#define OCTAVES 4

/* Fractal sum of up to OCTAVES octaves, each half the size and half the weight of the last,
 * normalised so that the weights sum to 1. */
typedef struct fbm {
    lattice oct[OCTAVES];
    int n;
} fbm;

static fbm make_fbm(double cell, int octaves, int tile, uint64_t seed, uint32_t stream)
{
    fbm f;
    f.n = octaves;
    for (int k = 0; k < octaves; k++)
        f.oct[k] = make_lattice(cell / (double)(1 << k), cell / (double)(1 << k), tile, seed,
                                stream + (uint32_t)k);
    return f;
}

static double fbm_at(const fbm *f, double x, double y)
{
    double sum = 0.0, w = 1.0, wsum = 0.0;
    for (int k = 0; k < f->n; k++) {
        sum += w * gnoise(&f->oct[k], x, y);
        wsum += w;
        w *= 0.5;
    }
    return sum / wsum;
}

/* Cellular bumps (after Worley 1996): one random point per cell, and 1 - (F1 / cell)^2, a dome
 * over each point; the creases between domes read as the valleys of cold-press paper. */
typedef struct cells {
    double cell;
    int n; /* period in cells; 0: none */
    uint64_t seed;
    uint32_t stream;
} cells;

static cells make_cells(double cell, int tile, uint64_t seed, uint32_t stream)
{
    cells c;
    fit_period(cell, tile, 1, &c.cell, &c.n);
    c.seed = seed;
    c.stream = stream;
    return c;
}

static double bumps_at(const cells *c, double x, double y)
{
    double fx = x / c->cell, fy = y / c->cell;
    double flx = floor(fx), fly = floor(fy);
    int64_t i0 = (int64_t)flx, j0 = (int64_t)fly;
    double best = 4.0;
    for (int dj = -1; dj <= 1; dj++)
        for (int di = -1; di <= 1; di++) {
            int64_t i = i0 + di, j = j0 + dj;
            uint64_t h =
                nprfx_hash(c->seed, 0, wrap_index(i, c->n), wrap_index(j, c->n), 0, c->stream);
            /* keep the points off the cell edges so the domes have similar sizes */
            double px = (double)i + 0.15 + 0.7 * nprfx_u01(h);
            double py = (double)j + 0.15 + 0.7 * nprfx_u01(nprfx_mix64(h));
            double ddx = fx - px, ddy = fy - py, d2 = ddx * ddx + ddy * ddy;
            if (d2 < best) best = d2;
        }
    return 1.0 - (best > 1.0 ? 1.0 : best);
}

/* ---- fibres ------------------------------------------------------------------------------ */

#define FIBRES_PER_CELL 2
#define FIBRE_POINTS 9

/* A fibre: a quadratic Bezier from a random point in its cell, random direction, length and
 * bend, drawn as a polyline; its whole extent (half-length + bend + width) stays below one
 * cell, so the 3 x 3 cells around a pixel hold every fibre that can reach it. */
typedef struct fibre {
    int present;
    double x0, y0, x1, y1; /* bounding box, grown by the width */
    double px[FIBRE_POINTS], py[FIBRE_POINTS];
    double w, amp;
} fibre;

typedef struct fibre_cache {
    int valid;
    int64_t ci, cj;
    fibre f[9][FIBRES_PER_CELL];
} fibre_cache;

typedef struct paper_setup {
    const nprfx_paper_params *p;
    int tile;
    fbm grain, formation, cockle;
    cells bumps, bumps2;
    lattice warp_x, warp_y;
    double fib_cell;
    int fib_n;
    uint64_t seed;
    /* canvas */
    double thread;
    int threads; /* per tile; 0: none */
    lattice wobble_v, wobble_h, streak_v, streak_h;
} paper_setup;

static void fibre_make(const paper_setup *s, int64_t ci, int64_t cj, int k, fibre *f)
{
    uint64_t h = nprfx_hash(s->seed, 0, wrap_index(ci, s->fib_n), wrap_index(cj, s->fib_n),
                            (uint32_t)k, S_FIBRE);
    double u[8];
    for (int m = 0; m < 8; m++)
        u[m] = nprfx_u01(h = nprfx_mix64(h));
    f->present = u[0] < 0.45;
    if (!f->present) return;
    double cell = s->fib_cell;
    double cx = ((double)ci + u[1]) * cell, cy = ((double)cj + u[2]) * cell;
    /* A uniform direction by rejection from the square (no cos/sin: see the top of the file). */
    double dx = 1.0, dy = 0.0;
    for (int m = 0; m < 64; m++) {
        uint64_t hd = nprfx_hash(s->seed, 1, wrap_index(ci, s->fib_n), wrap_index(cj, s->fib_n),
                                 (uint32_t)k, S_FIBRE_DIR + (uint32_t)m);
        double a = 2.0 * nprfx_u01(hd) - 1.0, b = 2.0 * nprfx_u01(nprfx_mix64(hd)) - 1.0;
        double r2 = a * a + b * b;
        if (r2 > 0.01 && r2 <= 1.0) {
            double r = sqrt(r2);
            dx = a / r;
            dy = b / r;
            break;
        }
    }
    double hl = cell * (0.2 + 0.55 * u[3]); /* half length */
    double bend = (u[4] - 0.5) * 0.5 * hl;  /* the curve's midpoint, off the chord */
    double w = cell * (0.04 + 0.03 * u[5]); /* half width */
    f->w = w;
    f->amp = (0.4 + 0.6 * u[6]) * (u[7] < 0.7 ? 1.0 : -1.0); /* most fibres stand out */
    double p0x = cx - dx * hl, p0y = cy - dy * hl, p2x = cx + dx * hl, p2y = cy + dy * hl;
    double p1x = cx - dy * 2.0 * bend, p1y = cy + dx * 2.0 * bend;
    f->x0 = f->y0 = INFINITY;
    f->x1 = f->y1 = -INFINITY;
    for (int m = 0; m < FIBRE_POINTS; m++) {
        double t = (double)m / (FIBRE_POINTS - 1), a = (1.0 - t) * (1.0 - t),
               b = 2.0 * t * (1.0 - t), c = t * t;
        f->px[m] = a * p0x + b * p1x + c * p2x;
        f->py[m] = a * p0y + b * p1y + c * p2y;
        f->x0 = fmin(f->x0, f->px[m]);
        f->x1 = fmax(f->x1, f->px[m]);
        f->y0 = fmin(f->y0, f->py[m]);
        f->y1 = fmax(f->y1, f->py[m]);
    }
    f->x0 -= w;
    f->y0 -= w;
    f->x1 += w;
    f->y1 += w;
}

/* The fibre's relief at (x, y): a smooth ridge across it, fading towards both ends. */
static double fibre_at(const fibre *f, double x, double y)
{
    if (!f->present || x < f->x0 || x > f->x1 || y < f->y0 || y > f->y1) return 0.0;
    double best = INFINITY, tbest = 0.0;
    for (int m = 0; m + 1 < FIBRE_POINTS; m++) {
        double ax = f->px[m], ay = f->py[m], ex = f->px[m + 1] - ax, ey = f->py[m + 1] - ay;
        double l2 = ex * ex + ey * ey;
        double t = l2 > 0.0 ? ((x - ax) * ex + (y - ay) * ey) / l2 : 0.0;
        t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
        double qx = ax + t * ex - x, qy = ay + t * ey - y, d2 = qx * qx + qy * qy;
        if (d2 < best) {
            best = d2;
            tbest = ((double)m + t) / (FIBRE_POINTS - 1);
        }
    }
    double q = best / (f->w * f->w);
    if (q >= 1.0) return 0.0;
    double across = (1.0 - q) * (1.0 - q);
    double e = 4.0 * tbest * (1.0 - tbest), along = e * (2.0 - e);
    return f->amp * across * along;
}

static double fibres_at(const paper_setup *s, fibre_cache *fc, double x, double y)
{
    int64_t ci = (int64_t)floor(x / s->fib_cell), cj = (int64_t)floor(y / s->fib_cell);
    if (!fc->valid || fc->ci != ci || fc->cj != cj) {
        for (int m = 0; m < 9; m++)
            for (int k = 0; k < FIBRES_PER_CELL; k++)
                fibre_make(s, ci + m % 3 - 1, cj + m / 3 - 1, k, &fc->f[m][k]);
        fc->valid = 1;
        fc->ci = ci;
        fc->cj = cj;
    }
    double sum = 0.0;
    for (int m = 0; m < 9; m++)
        for (int k = 0; k < FIBRES_PER_CELL; k++)
            sum += fibre_at(&fc->f[m][k], x, y);
    return sum;
}

/* ---- canvas -------------------------------------------------------------------------------- */

/* A cosine-like wave of period 2 from polynomials: 1 at even t, -1 at odd t, flat at both. */
static double wave2(double t)
{
    double ph = t - 2.0 * floor(t * 0.5); /* [0, 2) */
    double a = fabs(ph - 1.0), sm = a * a * (3.0 - 2.0 * a);
    return 2.0 * sm - 1.0;
}

/* Height of the weave at (x, y), in [0, 1]: the highest thread surface there (0 in the gaps).
 * Vertical thread i is over horizontal thread j where i + j is even; each thread's height along
 * it follows wave2, so it rises over the crossing threads and dips under the next ones. */
static double weave_at(const paper_setup *s, double x, double y, double *streak)
{
    /* the gaps between threads: deep, but not black holes one pixel wide */
    double p = s->thread, best = 0.3;
    *streak = 0.0;
    for (int dir = 0; dir < 2; dir++) {
        /* across: the coordinate across the thread; along: along it */
        double across = dir == 0 ? x : y, along = dir == 0 ? y : x;
        int64_t i0 = (int64_t)floor(across / p);
        for (int64_t i = i0 - 1; i <= i0 + 1; i++) {
            int32_t wi = wrap_index(i, s->threads);
            uint64_t h = nprfx_hash(s->seed, 0, wi, dir, 0, S_THREAD);
            double thick = 0.92 + 0.14 * nprfx_u01(h); /* width / period: dense, few gaps */
            double lift = 0.12 * (nprfx_u01(nprfx_mix64(h)) - 0.5);
            const lattice *wob = dir == 0 ? &s->wobble_v : &s->wobble_h;
            /* the wobble: a noise along the thread, a different row of the lattice per thread */
            double centre = ((double)i + 0.5) * p + 0.1 * p * gnoise(wob, along, (double)wi);
            double q = (across - centre) / (0.5 * thick * p);
            if (q <= -1.0 || q >= 1.0) continue;
            /* over at crossings where i + j is even: wave2 is +1 there */
            double z = 0.5 + 0.5 * wave2(along / p - 0.5 + (double)i);
            if (dir == 1) z = 1.0 - z;
            double prof = sqrt(1.0 - q * q);
            double hgt = (z + 1.2 * prof) / 2.2 + lift;
            if (hgt > best) {
                best = hgt;
                const lattice *st = dir == 0 ? &s->streak_v : &s->streak_h;
                *streak = gnoise(st, x, y);
            }
        }
    }
    return best;
}

/* ---- the height ---------------------------------------------------------------------------- */

/* Means of the weave and bump terms over a period, measured once (tests/unit/test_paper.c
 * checks the resulting mean height), subtracted so that the height centres on 0.5. */
#define WEAVE_MEAN 0.78
#define BUMPS_MEAN 0.80

static double height_at(const paper_setup *s, fibre_cache *fc, double x, double y)
{
    const nprfx_paper_params *p = s->p;
    double h = 0.5;
    switch (p->kind) {
    case NPRFX_PAPER_DRAWING:
        h += p->grain * (0.14 * fbm_at(&s->grain, x, y) + 0.10 * fbm_at(&s->formation, x, y));
        if (p->fibres > 0.0) h += p->fibres * 0.06 * fibres_at(s, fc, x, y);
        break;
    case NPRFX_PAPER_WATERCOLOR: {
        /* the domes' outlines wander (a domain warp by noise), as the felt's imprint does */
        double wx = x + s->bumps.cell * 0.35 * gnoise(&s->warp_x, x, y);
        double wy = y + s->bumps.cell * 0.35 * gnoise(&s->warp_y, x, y);
        double b = 0.65 * bumps_at(&s->bumps, wx, wy) + 0.35 * bumps_at(&s->bumps2, wx, wy);
        h += p->grain * (0.55 * (b - BUMPS_MEAN) + 0.10 * fbm_at(&s->grain, x, y) +
                         0.08 * fbm_at(&s->cockle, x, y));
        if (p->fibres > 0.0) h += p->fibres * 0.05 * fibres_at(s, fc, x, y);
        break;
    }
    default: { /* canvas */
        double streak;
        double wv = weave_at(s, x, y, &streak);
        h += p->weave * 0.5 * (wv - WEAVE_MEAN) +
             p->grain * (0.07 * streak + 0.04 * fbm_at(&s->grain, x, y));
        break;
    }
    }
    return h < 0.0 ? 0.0 : (h > 1.0 ? 1.0 : h);
}

/* The light of the colour output's relief: from the upper left (azimuth 135 degrees, elevation
 * 45, as bump's defaults), l = (cos 45 cos 135, -cos 45 sin 135, sin 45), written out exactly. */
static const double relief_light[3] = {-0.5, -0.5, 0.7071067811865476};

typedef struct paper_job {
    const paper_setup *s;
    nprfx_image *hb; /* heights (1 channel) */
    nprfx_image *out;
    nprfx_rect win;
} paper_job;

/* Pass 1: the height over win into hb. */
static void height_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const paper_job *j = user;
    const paper_setup *s = j->s;
    fibre_cache fc;
    for (int y = j->win.y0 + begin; y < j->win.y0 + end; y++) {
        fc.valid = 0;
        int64_t yw = s->tile > 0 ? wrap_index(y, s->tile) : y;
        for (int x = j->win.x0; x < j->win.x1; x++) {
            int64_t xw = s->tile > 0 ? wrap_index(x, s->tile) : x;
            nprfx_image_at(j->hb, x, y)[0] = (float)height_at(s, &fc, (double)xw, (double)yw);
        }
    }
}

/* Rows of j->hb over j->win from the one tile in j->out (bounds [0, tile)^2). */
static void tile_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const paper_job *j = user;
    const int T = j->s->tile;
    for (int y = j->win.y0 + begin; y < j->win.y0 + end; y++) {
        const float *src = nprfx_image_at(j->out, 0, wrap_index(y, T));
        for (int x = j->win.x0; x < j->win.x1; x++)
            nprfx_image_at(j->hb, x, y)[0] =
                src[(ptrdiff_t)wrap_index(x, T) * j->out->pixel_stride];
    }
}

/* The heights over win into dst. A periodic texture repeats every tile pixels, and height_at
 * sees only wrapped coordinates: over a window of more pixels than a tile, one tile is made
 * and the window copied from it, the same values for a fraction of the work (a 1920x1080
 * frame holds eight 512-pixel tiles). */
static nprfx_result fill_heights(nprfx_context *ctx, const paper_setup *s, nprfx_rect win,
                                 nprfx_image *dst)
{
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    const int T = s->tile;
    if (T <= 0 || (double)nprfx_rect_width(win) * nprfx_rect_height(win) <= (double)T * T) {
        paper_job j = {s, dst, NULL, win};
        nprfx_parallel_for(ex, nprfx_rect_height(win), 8, height_rows, &j);
        return NPRFX_OK;
    }
    nprfx_image tile;
    nprfx_result r = nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, T, T), 1, &tile);
    if (r) return r;
    paper_job jt = {s, &tile, NULL, tile.bounds}, jc = {s, dst, &tile, win};
    nprfx_parallel_for(ex, T, 8, height_rows, &jt);
    nprfx_parallel_for(ex, nprfx_rect_height(win), 8, tile_rows, &jc);
    nprfx_image_free(&tile);
    return NPRFX_OK;
}

/* Pass 2: the colour over win from hb, which covers win grown by one pixel when relief > 0 (the
 * texture is defined beyond the frame, so no edge clamps: tiles agree). */
static void color_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const paper_job *j = user;
    const nprfx_paper_params *p = j->s->p;
    const nprfx_image *hb = j->hb;
    for (int y = j->win.y0 + begin; y < j->win.y0 + end; y++)
        for (int x = j->win.x0; x < j->win.x1; x++) {
            double h = nprfx_image_at(hb, x, y)[0];
            double k = 1.0 - p->shade * (1.0 - h);
            if (p->relief > 0.0) {
                /* bump's shade, max(0, n . l) / l_z with n = normalize(-s grad h, 1) */
                double gx = 0.5 * ((double)nprfx_image_at(hb, x + 1, y)[0] -
                                   (double)nprfx_image_at(hb, x - 1, y)[0]);
                double gy = 0.5 * ((double)nprfx_image_at(hb, x, y + 1)[0] -
                                   (double)nprfx_image_at(hb, x, y - 1)[0]);
                double nx = -p->relief * gx, ny = -p->relief * gy;
                double lam = (nx * relief_light[0] + ny * relief_light[1] + relief_light[2]) /
                             sqrt(nx * nx + ny * ny + 1.0);
                k *= (lam > 0.0 ? lam : 0.0) / relief_light[2];
            }
            float *o = nprfx_image_at(j->out, x, y);
            for (int c = 0; c < 3; c++)
                o[c] = (float)(p->color[c] * k);
            o[3] = (float)p->color[3];
        }
}

int nprfx_paper_output_channels(const nprfx_paper_params *p)
{
    return p && p->output == NPRFX_PAPER_HEIGHT ? 1 : 4;
}

nprfx_result nprfx_paper_texture(nprfx_context *ctx, const nprfx_paper_params *p, nprfx_rect window,
                                 nprfx_image *out)
{
    if (!p || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "paper: no params or output");
    if (p->kind < 0 || p->kind >= NPRFX_PAPER_KIND_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "paper.kind: no kind %d", p->kind);
    if (p->output < 0 || p->output >= NPRFX_PAPER_OUTPUT_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "paper.output: no output %d", p->output);
    if (!(p->scale > 0.0 && p->scale <= 1024.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "paper.scale: %g is outside (0, 1024]",
                           p->scale);
    if (!(p->thread >= 1.0 && p->thread <= 4096.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "paper.thread: %g is outside [1, 4096]",
                           p->thread);
    if (!(p->tile >= 0.0 && p->tile <= 65536.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "paper.tile: %g is outside [0, 65536]",
                           p->tile);
    const double amounts[3] = {p->grain, p->fibres, p->weave};
    const char *const amount_names[3] = {"grain", "fibres", "weave"};
    for (int k = 0; k < 3; k++)
        if (!(amounts[k] >= 0.0 && amounts[k] <= 4.0))
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "paper.%s: %g is outside [0, 4]",
                               amount_names[k], amounts[k]);
    if (!(p->relief >= 0.0 && p->relief <= 1e4))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "paper.relief: %g is outside [0, 10000]",
                           p->relief);
    if (!(p->shade >= 0.0 && p->shade <= 1.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "paper.shade: %g is outside [0, 1]",
                           p->shade);
    int ch = nprfx_paper_output_channels(p);
    if (out->channels != ch)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "paper: output has %d channels, output '%s' makes %d", out->channels,
                           p->output == NPRFX_PAPER_HEIGHT ? "height" : "color", ch);
    window = nprfx_rect_intersect(window, out->bounds);
    if (nprfx_rect_empty(window)) return NPRFX_OK;

    paper_setup s;
    s.p = p;
    s.tile = (int)floor(p->tile + 0.5);
    s.seed = (uint64_t)(uint32_t)p->seed;
    double sc = p->scale;
    s.grain = make_fbm(3.0 * sc, p->kind == NPRFX_PAPER_CANVAS ? 2 : 3, s.tile, s.seed, S_GRAIN);
    s.formation = make_fbm(24.0 * sc, 2, s.tile, s.seed, S_FORMATION);
    s.cockle = make_fbm(60.0 * sc, 2, s.tile, s.seed, S_COCKLE);
    s.bumps = make_cells(6.0 * sc, s.tile, s.seed, S_BUMPS);
    s.bumps2 = make_cells(3.0 * sc, s.tile, s.seed, S_BUMPS2);
    s.warp_x = make_lattice(8.0 * sc, 8.0 * sc, s.tile, s.seed, S_WARP);
    s.warp_y = make_lattice(8.0 * sc, 8.0 * sc, s.tile, s.seed, S_WARP + 1);
    fit_period(20.0 * sc, s.tile, 1, &s.fib_cell, &s.fib_n);
    /* two threads per over-under repeat: an even number of threads per tile */
    fit_period(p->thread, s.tile, 2, &s.thread, &s.threads);
    s.wobble_v = make_lattice(6.0 * s.thread, 1.0, s.tile, s.seed, S_WOBBLE);
    s.wobble_h = make_lattice(6.0 * s.thread, 1.0, s.tile, s.seed, S_WOBBLE + 1);
    /* The wobble's second coordinate is the (wrapped) thread index, one lattice row per thread:
     * a 1D noise along each thread, unrelated between threads. */
    s.wobble_v.cy = s.wobble_h.cy = 1.0;
    s.wobble_v.py = s.wobble_h.py = 0;
    s.wobble_v.oy = s.wobble_h.oy = 0.0;
    s.streak_v = make_lattice(0.35 * s.thread, 2.5 * s.thread, s.tile, s.seed, S_STREAK);
    s.streak_h = make_lattice(2.5 * s.thread, 0.35 * s.thread, s.tile, s.seed, S_STREAK + 1);

    const nprfx_executor *ex = nprfx_context_executor(ctx);
    if (p->output == NPRFX_PAPER_HEIGHT) {
        return fill_heights(ctx, &s, window, out);
    }
    int g = p->relief > 0.0 ? 1 : 0;
    nprfx_rect grown = nprfx_rect_make(window.x0 - g, window.y0 - g, window.x1 + g, window.y1 + g);
    nprfx_image hb;
    nprfx_result r = nprfx_image_alloc(ctx, grown, 1, &hb);
    if (r) return r;
    paper_job jc = {&s, &hb, out, window};
    r = fill_heights(ctx, &s, grown, &hb);
    if (!r) nprfx_parallel_for(ex, nprfx_rect_height(window), 8, color_rows, &jc);
    nprfx_image_free(&hb);
    return r;
}
