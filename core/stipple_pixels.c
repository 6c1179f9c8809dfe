/* The per-pixel data of the stipple renderer: sequence UVs, darkness, the UV Jacobian from
 * finite differences that do not straddle object edges, repaired silhouette pixels, the smoothed
 * area scale, and the grid of footprint corners shared by neighbouring owners. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_stipple.h"
#include "nprfx/rng.h"

/* Hash stream of the per-object sequence offsets. */
#define STREAM_OBJECT 0x53544950u

/* Grow *p to hold n elements (keeping nothing: scratch is refilled each time). */
int internal_stipple_reserve(void **p, size_t *cap, size_t n, size_t elem)
{
    if (n <= *cap) return 1;
    free(*p);
    *p = malloc(n * elem);
    *cap = *p ? n : 0;
    return *p != NULL;
}

void internal_stipple_scratch_free(scratch *s)
{
    free(s->d.su);
    free(s->d.sv);
    free(s->d.jac);
    free(s->d.g);
    free(s->d.adet);
    free(s->d.hs);
    free(s->d.hc);
    free(s->d.id);
    free(s->d.uid);
    free(s->d.jid);
    free(s->d.ok);
    free(s->d.rowbuf);
    free(s->d.scratch);
    free(s->d.fixes);
    free(s->g.gu);
    free(s->g.gv);
    free(s->g.good);
    free(s->info);
    free(s->sdet);
    free(s->kl.k);
    free(s->sl.s);
    free(s->t);
}

static int pixdata_reserve(pixdata *d, nprfx_rect r)
{
    d->r = r;
    d->w = nprfx_rect_width(r);
    if (!internal_stipple_reserve((void **)&d->rowbuf, &d->rowcap, 6 * (size_t)d->w + 6,
                                  sizeof(float)))
        return 0;
    size_t n = (size_t)d->w * (size_t)nprfx_rect_height(r) + 1;
    if (n <= d->cap) return 1;
    size_t c;
    int ok = 1;
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->su, &c, n, sizeof(double));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->sv, &c, n, sizeof(double));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->jac, &c, n, 4 * sizeof(float));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->g, &c, n, sizeof(float));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->adet, &c, n, sizeof(float));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->hs, &c, n, sizeof(float));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->hc, &c, n, sizeof(float));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->id, &c, n, sizeof(int));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->uid, &c, n, sizeof(int));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->jid, &c, n, sizeof(int));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->ok, &c, n, 1);
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->scratch, &c, n, 1);
    d->cap = ok ? n : 0;
    return ok;
}

static double apply_curve(const float *curve, double g)
{
    double t = g * (NPRFX_STIPPLE_CURVE_SIZE - 1);
    int i = (int)t;
    if (i >= NPRFX_STIPPLE_CURVE_SIZE - 1) return curve[NPRFX_STIPPLE_CURVE_SIZE - 1];
    if (i < 0) return curve[0];
    return curve[i] + (t - i) * (curve[i + 1] - curve[i]);
}

/* One input's pixels on one row: columns [lo, hi), p pointing at column lo. */
typedef struct rowsrc {
    const float *p;
    ptrdiff_t ps;
    int lo, hi;
} rowsrc;

static rowsrc row_source(const nprfx_image *im, int y, int x0, int x1)
{
    rowsrc s = {NULL, 0, x0, x0};
    if (!im || y < im->bounds.y0 || y >= im->bounds.y1) return s;
    int lo = x0 > im->bounds.x0 ? x0 : im->bounds.x0, hi = x1 < im->bounds.x1 ? x1 : im->bounds.x1;
    if (hi <= lo) return s;
    s.lo = lo;
    s.hi = hi;
    s.p = nprfx_image_at(im, lo, y);
    s.ps = im->pixel_stride;
    return s;
}

/* Pixel x of the row, or NULL outside the input's bounds. */
static inline const float *row_at(const rowsrc *s, int x)
{
    return x >= s->lo && x < s->hi ? s->p + (ptrdiff_t)(x - s->lo) * s->ps : NULL;
}

/* floor(v + 0.5) for |v| < 2e9, without a libm call. */
static inline int round_half_up(double v)
{
    double f = v + 0.5;
    int i = (int)f; /* towards zero */
    return i - (f < (double)i);
}

/* The object id a pixel's id value names: -1 (no object) for NaN or infinities. */
static inline int id_of(double v)
{
    return !(v > -2e9 && v < 2e9) ? -1 : round_half_up(v);
}

static void fill_raw(const sjob *j, pixdata *d)
{
    const nprfx_stipple_params *p = j->p;
    const nprfx_stipple_inputs *in = j->in;
    /* periods tile / sqrt(aspect) in u and tile * sqrt(aspect) in v (exactly 1 / tile for
     * both at aspect 1) */
    const double sa = sqrt(p->aspect);
    const double inv_tile_u = sa / p->tile, inv_tile_v = 1.0 / (sa * p->tile);
    const float *curve = p->tone_curve;
    const int x0 = d->r.x0, x1 = d->r.x1, luma = in->tone->channels >= 3;
    int last_id = 0x7fffffff;
    double off_u = 0, off_v = 0;
    for (int y = d->r.y0; y < d->r.y1; y++) {
        rowsrc sid = row_source(in->id, y, x0, x1), suv = row_source(in->uv, y, x0, x1);
        rowsrc sto = row_source(in->tone, y, x0, x1);
        size_t k = pd_at(d, x0, y);
        if ((!in->id || (sid.lo == x0 && sid.hi == x1)) && in->uv && suv.lo == x0 && suv.hi == x1 &&
            sto.lo == x0 && sto.hi == x1) {
            /* every input covers the row (the usual case): the loop below without the
             * bounds tests, the same arithmetic. The row's values are first copied out in a
             * tight loop: plates interleave many channels, and a loop that only loads keeps
             * many cache misses in flight where the full one would wait for each. */
            float *rb = d->rowbuf;
            const int n = x1 - x0, nt = luma ? 3 : 1;
            {
                const float *qu = suv.p, *qt = sto.p;
                for (int i = 0; i < n; i++, qu += suv.ps, qt += sto.ps) {
                    rb[6 * i + 1] = qu[0];
                    rb[6 * i + 2] = qu[1];
                    for (int c = 0; c < nt; c++)
                        rb[6 * i + 3 + c] = qt[c];
                }
                const float *qi = sid.p;
                if (qi)
                    for (int i = 0; i < n; i++, qi += sid.ps)
                        rb[6 * i] = qi[0];
            }
            for (int x = x0; x < x1; x++, k++, rb += 6) {
                int id = sid.p ? id_of(rb[0]) : 0;
                d->id[k] = id;
                d->uid[k] = NO_ID;
                d->jid[k] = NO_ID;
                double u = rb[1], v = rb[2];
                if (!isfinite(u) || !isfinite(v) || id < 0) {
                    d->ok[k] = 0;
                    d->g[k] = 0.0f;
                    continue;
                }
                if (id != last_id) {
                    off_u = nprfx_rand_u01(p->seed, 0, id, 0, 0, STREAM_OBJECT);
                    off_v = nprfx_rand_u01(p->seed, 0, id, 0, 1, STREAM_OBJECT);
                    last_id = id;
                }
                d->su[k] = u * inv_tile_u + off_u;
                d->sv[k] = v * inv_tile_v + off_v;
                double tone = luma ? 0.2126 * rb[3] + 0.7152 * rb[4] + 0.0722 * rb[5] : rb[3];
                if (!(tone == tone)) tone = 1.0;
                tone = tone < 0 ? 0 : tone > 1 ? 1 : tone;
                d->g[k] = (float)(curve ? apply_curve(curve, 1.0 - tone) : 1.0 - tone);
                d->ok[k] = OK_UV;
                d->uid[k] = id;
            }
            continue;
        }
        for (int x = x0; x < x1; x++, k++) {
            d->ok[k] = 0;
            d->g[k] = 0.0f;
            d->uid[k] = NO_ID;
            d->jid[k] = NO_ID;
            int id = 0; /* no id input, or outside it: object 0 */
            const float *q = row_at(&sid, x);
            if (q) id = id_of(q[0]); /* NaN/inf: -1, no object */
            d->id[k] = id;
            double u, v;
            if (in->uv) {
                if (!(q = row_at(&suv, x))) continue;
                u = q[0];
                v = q[1];
            } else {
                u = (x - in->frame.x0) / p->plane_scale;
                v = (y - in->frame.y0) / p->plane_scale;
            }
            if (!isfinite(u) || !isfinite(v) || id < 0) continue;
            if (id != last_id) {
                /* different objects get unrelated parts of the torus */
                off_u = nprfx_rand_u01(p->seed, 0, id, 0, 0, STREAM_OBJECT);
                off_v = nprfx_rand_u01(p->seed, 0, id, 0, 1, STREAM_OBJECT);
                last_id = id;
            }
            d->su[k] = u * inv_tile_u + off_u;
            d->sv[k] = v * inv_tile_v + off_v;
            double tone = 1.0;
            if ((q = row_at(&sto, x)))
                tone = luma ? 0.2126 * q[0] + 0.7152 * q[1] + 0.0722 * q[2] : q[0];
            if (!(tone == tone)) tone = 1.0; /* NaN reads as paper */
            tone = tone < 0 ? 0 : tone > 1 ? 1 : tone;
            d->g[k] = (float)(curve ? apply_curve(curve, 1.0 - tone) : 1.0 - tone);
            d->ok[k] = OK_UV;
            d->uid[k] = id;
        }
    }
}

/* One column of the Jacobian at pixel k along a neighbour `step` away, given which of the
 * neighbours k + step (hf) and k - step (hb) are usable (same object, with a UV): differences
 * to those; central where both sides agree, else the smaller one-sided difference (a UV seam
 * gives a jump on one side only). Returns 0 when no neighbour qualifies, 2 when the sides
 * disagree. */
static inline int derivative(const pixdata *d, size_t k, size_t step, int hf, int hb, double *du,
                             double *dv)
{
    double fu = 0, fv = 0, bu = 0, bv = 0;
    if (hf) {
        fu = d->su[k + step] - d->su[k];
        fv = d->sv[k + step] - d->sv[k];
    }
    if (hb) {
        bu = d->su[k] - d->su[k - step];
        bv = d->sv[k] - d->sv[k - step];
    }
    if (hf && hb) {
        double nf = fu * fu + fv * fv, nb = bu * bu + bv * bv;
        if (nf <= 4.0 * nb && nb <= 4.0 * nf) {
            *du = 0.5 * (fu + bu);
            *dv = 0.5 * (fv + bv);
            return 1;
        }
        if (nf < nb)
            *du = fu, *dv = fv;
        else
            *du = bu, *dv = bv;
        return 2;
    }
    if (hf) {
        *du = fu, *dv = fv;
        return 1;
    }
    if (hb) {
        *du = bu, *dv = bv;
        return 1;
    }
    return 0;
}

static void fill_jacobian(pixdata *d, nprfx_rect r)
{
    const size_t w = (size_t)d->w;
    for (int y = r.y0; y < r.y1; y++) {
        const int up = y - 1 >= d->r.y0, down = y + 1 < d->r.y1;
        size_t k = pd_at(d, r.x0, y);
        for (int x = r.x0; x < r.x1; x++, k++) {
            if (!(d->ok[k] & OK_UV)) continue;
            const int id = d->uid[k];
            double ux, vx, uy, vy;
            int ex = derivative(d, k, 1, x + 1 < d->r.x1 && d->uid[k + 1] == id,
                                x - 1 >= d->r.x0 && d->uid[k - 1] == id, &ux, &vx);
            int ey = derivative(d, k, w, down && d->uid[k + w] == id, up && d->uid[k - w] == id,
                                &uy, &vy);
            if (!ex || !ey) continue;
            if (ex == 2 || ey == 2) d->ok[k] |= OK_SEAM;
            float *jc = d->jac + 4 * k;
            jc[0] = (float)ux;
            jc[1] = (float)uy;
            jc[2] = (float)vx;
            jc[3] = (float)vy;
            double det = (double)jc[0] * jc[3] - (double)jc[1] * jc[2];
            d->adet[k] = (float)fabs(det);
            if (det != 0.0 && isfinite(det) && d->adet[k] > 0) {
                d->ok[k] |= OK_J;
                d->jid[k] = id;
            }
        }
    }
}

/* A pixel whose |det J| exceeds OUTLIER times the smallest of its same-object neighbours'
 * sees a jump, not the surface: renderers filter the UV pass, so along a silhouette the
 * pixels hold a blend of the two objects' UVs (and across a UV seam, of the two charts'),
 * which sits between the surfaces and makes a huge footprint there, packed with dots (a dark
 * outline). Half-float steps and perspective change |det J| between neighbours by a few times
 * at most. */
#define OUTLIER 8.0f

/* Such a pixel takes the surface of that neighbour instead: its UV extrapolated from the
 * neighbour's UV and derivatives, and those derivatives, so it owns its share of the surface
 * like the pixels around (and is marked OK_SEAM, so the corners it shares with the other side
 * of a seam are checked). Every repair is computed from the values before any repair, on M,
 * from the derivatives of D1 (M plus 1) as computed: the same whatever the units. */
static void repair_outliers(pixdata *d, nprfx_rect M)
{
    const ptrdiff_t w = d->w;
    const int *jid = d->jid;
    const float *adet = d->adet;
    unsigned char *src = d->scratch; /* 0, or 1 + which neighbour the pixel takes */
    const ptrdiff_t step[4] = {-1, 1, -w, w};
    size_t nfix = 0;
    for (int y = M.y0; y < M.y1; y++) {
        const int up = y - 1 >= d->r.y0, down = y + 1 < d->r.y1;
        ptrdiff_t k = (ptrdiff_t)pd_at(d, M.x0, y);
        for (int x = M.x0; x < M.x1; x++, k++) {
            src[k] = 0;
            const int id = jid[k];
            if (id == NO_ID) continue;
            const int has[4] = {x - 1 >= d->r.x0, x + 1 < d->r.x1, up, down};
            /* an outlier exceeds OUTLIER times some usable neighbour's (exactly: times the
             * smallest); the usual pixel fails all four tests and is done */
            const float a = adet[k] * (1.0f / OUTLIER);
            if (!((has[0] && a > adet[k - 1] && jid[k - 1] == id) ||
                  (has[1] && a > adet[k + 1] && jid[k + 1] == id) ||
                  (up && a > adet[k - w] && jid[k - w] == id) ||
                  (down && a > adet[k + w] && jid[k + w] == id)))
                continue;
            float ref = INFINITY;
            int best = 0;
            for (int n = 0; n < 4; n++)
                if (has[n] && jid[k + step[n]] == id && adet[k + step[n]] < ref) {
                    ref = adet[k + step[n]];
                    best = n;
                }
            src[k] = (unsigned char)(1 + best);
            nfix++;
        }
    }
    if (!nfix) return;
    /* the new values, all from the old ones, then stored */
    typedef struct fix {
        size_t k;
        double su, sv;
        float jac[4], adet;
    } fix;
    fix *fx = d->fixes;
    size_t nf = 0;
    if (nfix > d->fixcap) {
        free(d->fixes);
        d->fixes = fx = malloc(nfix * sizeof *fx);
        d->fixcap = fx ? nfix : 0;
        if (!fx) { /* no room: drop them instead (they own nothing) */
            for (int y = M.y0; y < M.y1; y++) {
                size_t k = pd_at(d, M.x0, y);
                for (int x = M.x0; x < M.x1; x++, k++)
                    if (src[k]) d->jid[k] = NO_ID, d->ok[k] &= (unsigned char)~OK_J;
            }
            return;
        }
    }
    for (int y = M.y0; y < M.y1; y++) {
        size_t k = pd_at(d, M.x0, y);
        for (int x = M.x0; x < M.x1; x++, k++) {
            if (!src[k]) continue;
            const int n = src[k] - 1;
            const size_t q = (size_t)((ptrdiff_t)k + step[n]);
            const double dx = n == 0 ? 1 : n == 1 ? -1 : 0, dy = n == 2 ? 1 : n == 3 ? -1 : 0;
            const float *jq = d->jac + 4 * q;
            fix *f = &fx[nf++];
            f->k = k;
            f->su = d->su[q] + jq[0] * dx + jq[1] * dy;
            f->sv = d->sv[q] + jq[2] * dx + jq[3] * dy;
            memcpy(f->jac, jq, sizeof f->jac);
            f->adet = d->adet[q];
        }
    }
    for (size_t i = 0; i < nf; i++) {
        size_t k = fx[i].k;
        d->su[k] = fx[i].su;
        d->sv[k] = fx[i].sv;
        memcpy(d->jac + 4 * k, fx[i].jac, sizeof fx[i].jac);
        d->adet[k] = fx[i].adet;
        d->ok[k] |= OK_SEAM;
    }
}

/* The area scale |det J| averaged over the same-object pixels of a (2 SMOOTH + 1)^2 window
 * (a horizontal pass within the object, then a vertical one), for the density thresholds only.
 * UV passes are often stored as half floats, whose steps make per-pixel differences of a slowly
 * varying UV jump by factors of two; the kept prefix would then change from pixel to pixel,
 * which scatters the dots like white noise. Needs adet on E plus SMOOTH; writes out[] over E. */
static void smooth_area(pixdata *d, nprfx_rect E, nprfx_rect R, float *out)
{
    const ptrdiff_t w = d->w;
    /* Sums start at +0 and add values >= +0 (|det|, and sums of them), so adding +0 for a
     * pixel that does not count gives the same float as skipping it: the interior loops test
     * without branching. */
    const int *jid = d->jid;
    const float *adet = d->adet;
    /* columns of E whose +-SMOOTH neighbours are all held */
    const int xa = E.x0 - SMOOTH >= d->r.x0 ? E.x0 : d->r.x0 + SMOOTH;
    const int xb = E.x1 + SMOOTH <= d->r.x1 ? E.x1 : d->r.x1 - SMOOTH;
    for (int y = R.y0; y < R.y1; y++) {
        size_t k = pd_at(d, E.x0, y);
        for (int x = E.x0; x < E.x1; x++, k++) {
            float sum = 0, cnt = 0;
            const int id = jid[k];
            if (id == NO_ID) {
            } else if (x >= xa && x < xb) {
                for (int dx = -SMOOTH; dx <= SMOOTH; dx++) {
                    const int same = jid[k + dx] == id;
                    sum += same ? adet[k + dx] : 0.0f;
                    cnt += same ? 1.0f : 0.0f;
                }
            } else {
                int lo = x - SMOOTH < d->r.x0 ? d->r.x0 - x : -SMOOTH;
                int hi = x + SMOOTH >= d->r.x1 ? d->r.x1 - 1 - x : SMOOTH;
                for (int dx = lo; dx <= hi; dx++)
                    if (jid[k + dx] == id) {
                        sum += adet[k + dx];
                        cnt += 1;
                    }
            }
            d->hs[k] = sum;
            d->hc[k] = cnt;
        }
    }
    int ew = nprfx_rect_width(E);
    for (int y = E.y0; y < E.y1; y++) {
        int lo = y - SMOOTH < R.y0 ? R.y0 - y : -SMOOTH;
        int hi = y + SMOOTH >= R.y1 ? R.y1 - 1 - y : SMOOTH;
        ptrdiff_t k = (ptrdiff_t)pd_at(d, E.x0, y);
        float *o = out + (size_t)(y - E.y0) * ew;
        for (int x = E.x0; x < E.x1; x++, k++) {
            float sum = 0, cnt = 0;
            const int id = jid[k];
            if (id != NO_ID)
                for (int dy = lo; dy <= hi; dy++) {
                    const ptrdiff_t q = k + dy * w;
                    const int same = jid[q] == id;
                    sum += same ? d->hs[q] : 0.0f;
                    cnt += same ? d->hc[q] : 0.0f;
                }
            o[x - E.x0] = cnt > 0 ? sum / cnt : 0.0f;
        }
    }
}

/* Is (u, v) more than half a pixel, measured with pixel k's own derivatives, from where pixel
 * k's derivatives put the corner at offset (ox, oy) pixels? Then the corner straddles a UV seam
 * (or a fold) as seen from k. */
int internal_stipple_off_corner(const pixdata *d, size_t k, double ox, double oy, double u,
                                double v)
{
    const float *jc = d->jac + 4 * k;
    double du = u - (d->su[k] + jc[0] * ox + jc[1] * oy);
    double dv = v - (d->sv[k] + jc[2] * ox + jc[3] * oy);
    /* J^-1 (du, dv), within half a pixel: compared as |adj(J) (du, dv)| <= |det| / 2 */
    double det = (double)jc[0] * jc[3] - (double)jc[1] * jc[2];
    double px = jc[3] * du - jc[1] * dv, py = -jc[2] * du + jc[0] * dv;
    double lim = 0.5 * fabs(det);
    return !(fabs(px) <= lim && fabs(py) <= lim);
}

static void cgrid_fill(cgrid *g, const pixdata *d)
{
    static const double ox[4] = {0.5, -0.5, 0.5, -0.5}, oy[4] = {0.5, 0.5, -0.5, -0.5};
    const size_t w = (size_t)d->w;
    for (int gy = 0; gy < g->gh; gy++)
        for (int gx = 0; gx < g->gw; gx++) {
            size_t i = (size_t)gy * g->gw + gx;
            int xa = g->E.x0 + gx - 1, ya = g->E.y0 + gy - 1;
            g->good[i] = 0;
            if (!nprfx_rect_contains(d->r, xa, ya) || xa + 1 >= d->r.x1 || ya + 1 >= d->r.y1)
                continue;
            size_t k[4] = {pd_at(d, xa, ya), 0, 0, 0};
            k[1] = k[0] + 1;
            k[2] = k[0] + w;
            k[3] = k[2] + 1;
            /* the 2x2 pixels around the corner: one object, all with usable derivatives */
            int id = d->jid[k[0]];
            if (id == NO_ID || d->jid[k[1]] != id || d->jid[k[2]] != id || d->jid[k[3]] != id)
                continue;
            double u = ((d->su[k[0]] + d->su[k[1]]) + (d->su[k[2]] + d->su[k[3]])) * 0.25;
            double v = ((d->sv[k[0]] + d->sv[k[1]]) + (d->sv[k[2]] + d->sv[k[3]])) * 0.25;
            /* the seam test, only where a pixel's differences hinted at one */
            int good = 1;
            if ((d->ok[k[0]] | d->ok[k[1]] | d->ok[k[2]] | d->ok[k[3]]) & OK_SEAM)
                for (int q = 0; q < 4 && good; q++)
                    if (internal_stipple_off_corner(d, k[q], ox[q], oy[q], u, v)) good = 0;
            g->gu[i] = u;
            g->gv[i] = v;
            g->good[i] = (unsigned char)good;
        }
}

int internal_stipple_prepare(const sjob *j, scratch *s, nprfx_rect E)
{
    nprfx_rect frame = j->in->frame;
    /* usable derivatives are needed on E plus 1 (corners) and plus SMOOTH (densities): that
     * is M; telling whether a derivative is usable takes those of the neighbours (D1), and
     * each derivative the UVs around it (D) */
    const int mj = SMOOTH > 1 ? SMOOTH : 1;
    nprfx_rect M =
        nprfx_rect_intersect(frame, nprfx_rect_make(E.x0 - mj, E.y0 - mj, E.x1 + mj, E.y1 + mj));
    nprfx_rect D1 = nprfx_rect_intersect(
        frame, nprfx_rect_make(E.x0 - mj - 1, E.y0 - mj - 1, E.x1 + mj + 1, E.y1 + mj + 1));
    nprfx_rect D = nprfx_rect_intersect(
        frame, nprfx_rect_make(E.x0 - mj - 2, E.y0 - mj - 2, E.x1 + mj + 2, E.y1 + mj + 2));
    int ew = nprfx_rect_width(E), eh = nprfx_rect_height(E);
    pixdata *d = &s->d;
    cgrid *g = &s->g;
    size_t gn = (size_t)(ew + 1) * (size_t)(eh + 1), c = s->gcap;
    int ok = pixdata_reserve(d, D);
    ok &= internal_stipple_reserve((void **)&g->gu, &c, gn, sizeof(double));
    c = s->gcap, ok &= internal_stipple_reserve((void **)&g->gv, &c, gn, sizeof(double));
    c = s->gcap, ok &= internal_stipple_reserve((void **)&g->good, &c, gn, 1);
    s->gcap = ok ? (gn > s->gcap ? gn : s->gcap) : 0;
    ok &= internal_stipple_reserve((void **)&s->info, &s->icap, (size_t)ew * (size_t)eh,
                                   sizeof(oinfo));
    ok &= internal_stipple_reserve((void **)&s->sdet, &s->scap, (size_t)ew * (size_t)eh,
                                   sizeof(float));
    if (!ok) return 0;
    fill_raw(j, d);
    fill_jacobian(d, D1);
    repair_outliers(d, M);
    smooth_area(d, E, M, s->sdet);
    g->E = E;
    g->gw = ew + 1;
    g->gh = eh + 1;
    cgrid_fill(g, d);
    return 1;
}
