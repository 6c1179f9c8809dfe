/* One step of the coherent-noise recursion: per pixel, the previous position along the motion,
 * the occlusion test against the previous depth, and the fresh value or the previous state
 * resampled (Catmull-Rom with spectral compensation, or bilinear) plus the innovation.
 *
 * Speed (the target: a 1080p frame of 3 channels in 30 ms on two cores, where moving the data
 * alone takes about 10 ms): one pass over the pixels per step. The noise fields are generated row
 * by row into per-worker scratch (a ring of four rows for the compensation field that reaches three
 * rows down) instead of as full frames; pixels whose 4x4 taps lie inside the frame take a vector
 * path with no clamping, all channels at once (lanes are (tap column, channel) pairs). Vector and
 * scalar paths perform the same IEEE operations in the same order per channel (no fused
 * multiply-adds: the project builds with -ffp-contract=off), so the result is the same on every
 * path, CPU and thread count. GCC/Clang vector extensions express the vector code; on x86-64 Linux
 * with GCC the hot functions are also cloned for AVX2 and AVX-512 and picked at load time. Other
 * compilers get the scalar path, which computes the same numbers. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_coherent_noise.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"

/* ---- the recursion ------------------------------------------------------------------------- */

/* Pixel (fr.x0, y) of a view when the view holds the whole row fr.x0..fr.x1-1; NULL otherwise
 * (then reads clamp pixel by pixel). */
static inline const float *internal_row_of(const nprfx_image *im, nprfx_rect fr, int y)
{
    if (!im || y < im->bounds.y0 || y >= im->bounds.y1 || im->bounds.x0 > fr.x0 ||
        im->bounds.x1 < fr.x1)
        return NULL;
    return nprfx_image_at(im, fr.x0, y);
}

/* The stationary resampler with compensation, for one pixel, per channel c (by, gy: the
 * vertical taps of the offset's row fraction; bx, gx: horizontal):
 *   vu_i = by0 U[iy-1][ix-1+i] + by1 U[iy][..] + by2 U[iy+1][..] + by3 U[iy+2][..]  (left to right)
 *   vn_i = gy0 n2[y][x+i] + gy1 n2[y+1][x+i] + gy2 n2[y+2][x+i] + gy3 n2[y+3][x+i]
 *   t_i  = bx_i (vu_i + vn_i) + gx_i n1[y][x+i]
 *   out  = ((t_0 + t_1) + t_2) + t_3) a + w g
 * i.e. a (Bx By U + Bx Gy n2 + Gx n1) + g w: Catmull-Rom of the previous state plus the two
 * compensation fields (1 - |Bx By|^2 = |Gx|^2 + |Bx|^2 |Gy|^2). This scalar version clamps taps
 * to the frame; the vector versions (internal_coherent_noise.h) do the same operations for
 * interior pixels. */
static void internal_px_stationary(const nprfx_image *U, nprfx_rect fr, int ix, int iy,
                                   const internal_taps *tx, const internal_taps *ty,
                                   const float *n1p, const float *const *n2p, const float *wp,
                                   float a, float g, int C, float *o)
{
    int xs[4], ys[4];
    for (int k = 0; k < 4; k++) {
        xs[k] = internal_clampi(ix - 1 + k, fr.x0, fr.x1 - 1);
        ys[k] = internal_clampi(iy - 1 + k, fr.y0, fr.y1 - 1);
    }
    for (int c = 0; c < C; c++) {
        float t[4];
        for (int i = 0; i < 4; i++) {
            float vu = ty->b[0] * nprfx_image_at(U, xs[i], ys[0])[c];
            vu = vu + ty->b[1] * nprfx_image_at(U, xs[i], ys[1])[c];
            vu = vu + ty->b[2] * nprfx_image_at(U, xs[i], ys[2])[c];
            vu = vu + ty->b[3] * nprfx_image_at(U, xs[i], ys[3])[c];
            float vn = ty->g[0] * n2p[0][i * C + c];
            vn = vn + ty->g[1] * n2p[1][i * C + c];
            vn = vn + ty->g[2] * n2p[2][i * C + c];
            vn = vn + ty->g[3] * n2p[3][i * C + c];
            t[i] = tx->b[i] * (vu + vn) + tx->g[i] * n1p[i * C + c];
        }
        float r = t[0] + t[1];
        r = r + t[2];
        r = r + t[3];
        o[c] = r * a + wp[c] * g;
    }
}

typedef struct internal_step_job {
    const nprfx_cn_params *p;
    int direction;
    int64_t frame;
    const nprfx_cn_inputs *in;
    const nprfx_cn_state *prev;
    nprfx_cn_state *out;
    /* band-pass noise: whole fields (w over the frame, n1/n2 over frame + margin, each with a
     * spare row for vector slack); NULL for white noise, which is made row by row here */
    const nprfx_image *w, *n1, *n2;
    const internal_taps *tab;
    float a, fresh_gain; /* alpha; sqrt(1-alpha^2) for noise, 1-alpha for input */
    int input_mode;
    int compensate; /* noise with the stationary resampler and alpha > 0 */
    int fast;       /* compensate, C <= 4, packed previous state: vector path for interior pixels */
    uint32_t s1, s2; /* streams of the compensation fields */
    float *scratch;  /* per worker: scratch_len floats */
    size_t scratch_len, row_len;
} internal_step_job;

/* Everything after the occlusion test for one pixel that is not fresh: (ix, iy) the integer part
 * of its previous position, (qx, qy) the quantised fraction. wp, n1p, n2p: its noise (NULL where
 * unused). CF as in internal_step_row. */
INTERNAL_INLINE void internal_px_carry(const internal_step_job *j, int x, int y, int ix, int iy,
                                       int qx, int qy, const float *wp, const float *n1p,
                                       const float *const *n2p, const int CF, float *o)
{
    const nprfx_image *U = &j->prev->value;
    const nprfx_rect fr = j->out->value.bounds;
    const int C = CF ? CF : j->out->value.channels;
    const float a = j->a, g = j->fresh_gain;
    /* A quantised offset of exactly one pixel belongs to the next pixel. */
    if (qx == INTERNAL_TAB) ix++, qx = 0;
    if (qy == INTERNAL_TAB) iy++, qy = 0;
    if (qx == 0 && qy == 0) {
        /* Integer motion: an exact copy, nothing lost, nothing to compensate. */
        const float *u = nprfx_image_at(U, ix, iy);
        if (j->input_mode)
            for (int c = 0; c < C; c++)
                o[c] = internal_mix_source(a, u[c], g, internal_read(j->in->source, x, y, c));
        else
            for (int c = 0; c < C; c++)
                o[c] = a * (u[c] + 0.0f) + g * wp[c];
        return;
    }
    const internal_taps *tx = &j->tab[qx], *ty = &j->tab[qy];
    if (j->compensate) {
#if INTERNAL_VEC
        if (CF && ix - 1 >= fr.x0 && ix + 2 < fr.x1 && iy - 1 >= fr.y0 &&
            iy + (CF == 3 ? 3 : 2) < fr.y1) {
            const float *u0 = nprfx_image_at(U, ix - 1, iy - 1);
            if (CF == 1)
                internal_px_v1(u0, U->row_stride, tx, ty, n1p, n2p[0], n2p[1], n2p[2], n2p[3], wp,
                               a, g, o);
            else if (CF == 2)
                internal_px_v2(u0, U->row_stride, tx, ty, n1p, n2p[0], n2p[1], n2p[2], n2p[3], wp,
                               a, g, o);
            else if (CF == 3)
                internal_px_v3(u0, U->row_stride, tx, ty, n1p, n2p[0], n2p[1], n2p[2], n2p[3], wp,
                               a, g, o);
            else
                internal_px_v4(u0, U->row_stride, tx, ty, n1p, n2p[0], n2p[1], n2p[2], n2p[3], wp,
                               a, g, o);
            return;
        }
#endif
        internal_px_stationary(U, fr, ix, iy, tx, ty, n1p, n2p, wp, a, g, C, o);
        return;
    }
    /* No compensation: the paper's bilinear lookup, or Catmull-Rom alone (input mode,
     * alpha 0). */
    float v[NPRFX_MAX_CHANNELS];
    const float *bx = tx->b, *by = ty->b;
    if (j->p->resample == NPRFX_CN_RESAMPLE_BILINEAR) {
        int x1 = ix + 1 <= fr.x1 - 1 ? ix + 1 : ix, y1 = iy + 1 <= fr.y1 - 1 ? iy + 1 : iy;
        const float *u00 = nprfx_image_at(U, ix, iy), *u10 = nprfx_image_at(U, x1, iy);
        const float *u01 = nprfx_image_at(U, ix, y1), *u11 = nprfx_image_at(U, x1, y1);
        for (int c = 0; c < C; c++)
            v[c] = by[0] * (bx[0] * u00[c] + bx[1] * u10[c]) +
                   by[1] * (bx[0] * u01[c] + bx[1] * u11[c]);
    } else {
        int xs[4], ys[4];
        for (int k = 0; k < 4; k++) {
            xs[k] = internal_clampi(ix - 1 + k, fr.x0, fr.x1 - 1);
            ys[k] = internal_clampi(iy - 1 + k, fr.y0, fr.y1 - 1);
        }
        for (int c = 0; c < C; c++) {
            float acc = 0.0f;
            for (int k = 0; k < 4; k++)
                acc += by[k] * (bx[0] * nprfx_image_at(U, xs[0], ys[k])[c] +
                                bx[1] * nprfx_image_at(U, xs[1], ys[k])[c] +
                                bx[2] * nprfx_image_at(U, xs[2], ys[k])[c] +
                                bx[3] * nprfx_image_at(U, xs[3], ys[k])[c]);
            v[c] = acc;
        }
    }
    if (j->input_mode)
        for (int c = 0; c < C; c++)
            o[c] = internal_mix_source(a, v[c], g, internal_read(j->in->source, x, y, c));
    else
        for (int c = 0; c < C; c++)
            o[c] = a * (v[c] + 0.0f) + g * wp[c];
}

/* The fresh (restart) value of a pixel. */
static inline void internal_px_fresh(const internal_step_job *j, int x, int y, const float *wp,
                                     int C, float *o)
{
    if (j->input_mode)
        for (int c = 0; c < C; c++)
            o[c] = internal_source_fresh(internal_read(j->in->source, x, y, c));
    else
        for (int c = 0; c < C; c++)
            o[c] = wp[c];
}

/* One row of a step, pixel by pixel. wr, n1r and n2r[k] point at x = fr.x0 of the noise rows y
 * (w, n1) and y + k (n2), channels interleaved (unused ones NULL). */
static void internal_step_row(const internal_step_job *j, int y, const float *wr, const float *n1r,
                              const float *const *n2r)
{
    const nprfx_image *O = &j->out->value;
    const nprfx_rect fr = O->bounds;
    const int C = O->channels, W = nprfx_rect_width(fr);
    const nprfx_cn_inputs *in = j->in;
    const float ms = (float)j->p->motion_scale, eps = (float)j->p->epsilon;
    const float dir = (float)j->direction;
    const float xmax = (float)(fr.x1 - 1), ymax = (float)(fr.y1 - 1);
    unsigned char *fresh = j->out->fresh + (size_t)(y - fr.y0) * (size_t)W;
    for (int x = fr.x0; x < fr.x1; x++) {
        const int i = x - fr.x0;
        float *o = nprfx_image_at(O, x, y);
        float z = internal_read(in->depth, x, y, 0);
        float mx = internal_read(in->motion, x, y, 0) * ms;
        float my = internal_read(in->motion, x, y, 1) * ms;
        float px = (float)x + mx, py = (float)y + my;
        int is_fresh = internal_is_background(z) || !isfinite(mx) || !isfinite(my) ||
                       !(px >= (float)fr.x0 && px <= xmax && py >= (float)fr.y0 && py <= ymax);
        int ix = 0, iy = 0, qx = 0, qy = 0;
        if (!is_fresh) {
            /* floor without a libm call (px, py are finite here) */
            ix = (int)px;
            ix -= (float)ix > px;
            iy = (int)py;
            iy -= (float)iy > py;
            qx = (int)((px - (float)ix) * INTERNAL_TAB + 0.5f);
            qy = (int)((py - (float)iy) * INTERNAL_TAB + 0.5f);
            float zpred = z;
            if (in->zvel) {
                float vz = internal_read(in->zvel, x, y, 0);
                if (isfinite(vz)) zpred = z - dir * vz;
            }
            /* The occlusion test uses the unquantised position: it decides visibility, not
             * the noise's reconstruction. */
            is_fresh = internal_occluded(in->depth_prev, ix, iy, px - (float)ix, py - (float)iy,
                                         zpred, eps);
        }
        fresh[i] = (unsigned char)is_fresh;
        const size_t off = (size_t)i * (size_t)C;
        const float *wp = wr ? wr + off : NULL;
        if (is_fresh) {
            internal_px_fresh(j, x, y, wp, C, o);
            continue;
        }
        const float *n1p = n1r ? n1r + off : NULL;
        const float *n2p[4] = {NULL, NULL, NULL, NULL};
        if (n2r[0])
            for (int k = 0; k < 4; k++)
                n2p[k] = n2r[k] + off;
        internal_px_carry(j, x, y, ix, iy, qx, qy, wp, n1p, n2p, 0, o);
    }
}

#if INTERNAL_VEC
#define INTERNAL_SEG 64

/* Compensation noise made on demand, per worker: slot 0 holds n1 of the current row, slots 1-4 the
 * ring of n2 rows (row yy in slot 1 + yy mod 4). done[] marks the 8-pixel blocks made so far. */
typedef struct internal_lazy {
    const internal_step_job *j;
    float *buf[5];
    unsigned char *done[5];
    uint64_t keys[5][4];
    int row[5];
    int nblocks; /* blocks of 8 over the noise row's W + margin pixels */
} internal_lazy;

static void internal_lazy_assign(internal_lazy *lz, int slot, int yy)
{
    const internal_step_job *j = lz->j;
    if (lz->row[slot] == yy) return;
    lz->row[slot] = yy;
    uint32_t stream = slot ? j->s2 : j->s1;
    for (int c = 0; c < j->out->value.channels; c++)
        lz->keys[slot][c] = internal_row_key(j->p->seed, j->frame, yy, (uint32_t)c, stream);
    memset(lz->done[slot], 0, (size_t)lz->nblocks);
}

/* Make blocks b0..b1 (clamped) of a slot's row. */
static void internal_lazy_ensure(internal_lazy *lz, int slot, int b0, int b1)
{
    const int C = lz->j->out->value.channels, x0 = lz->j->out->value.bounds.x0;
    if (b1 >= lz->nblocks) b1 = lz->nblocks - 1;
    unsigned char *done = lz->done[slot];
    for (int b = b0; b <= b1; b++) {
        if (done[b]) continue;
        int e = b;
        while (e + 1 <= b1 && !done[e + 1])
            e++;
        internal_cn_gauss_row_il(lz->keys[slot], C, x0 + 8 * b, 8 * (e - b + 1),
                                 lz->buf[slot] + (size_t)8 * (size_t)b * (size_t)C);
        memset(done + b, 1, (size_t)(e - b + 1));
        b = e;
    }
}

/* m ? a : b per lane (m: all ones or zero); |v|. Macros: no vector crosses a call. */
#define INTERNAL_SEL8(m, a, b)                                                                     \
    ((internal_v8f)(((internal_v8i)(a) & (m)) | ((internal_v8i)(b) & ~(m))))
#define INTERNAL_ABS8(v) ((internal_v8f)((internal_v8i)(v)&0x7fffffff))

/* internal_step_row for the vector path (noise, stationary resampler, CF = C <= 4 channels, packed
 * previous state), in segments of INTERNAL_SEG pixels: the motion, the previous position, its
 * quantised fraction and the occlusion test run eight pixels at a time (the same operations as
 * the scalar code, lane by lane: the bilinear previous depth over the non-background taps, its
 * renormalisation and the comparison); only the fetch of the four depth taps is scalar. */
INTERNAL_INLINE void internal_step_row_v(const internal_step_job *j, int y, const float *wr,
                                         const float *n1r, const float *const *n2r,
                                         internal_lazy *lz, const int CF)
{
    const nprfx_image *U = &j->prev->value;
    const nprfx_image *O = &j->out->value;
    const nprfx_rect fr = O->bounds;
    const int W = nprfx_rect_width(fr);
    const nprfx_cn_inputs *in = j->in;
    const nprfx_image *dp = in->depth_prev;
    const float ms = (float)j->p->motion_scale, eps = (float)j->p->epsilon;
    const float dir = (float)j->direction;
    const float x0f = (float)fr.x0, y0f = (float)fr.y0;
    const float xmax = (float)(fr.x1 - 1), ymax = (float)(fr.y1 - 1), yf = (float)y;
    const float bg = (float)NPRFX_CN_BACKGROUND_DEPTH;
    unsigned char *fresh = j->out->fresh + (size_t)(y - fr.y0) * (size_t)W;
    const float *zrow = internal_row_of(in->depth, fr, y);
    const float *mrow = internal_row_of(in->motion, fr, y);
    const float *vrow = internal_row_of(in->zvel, fr, y);
    const int direct = zrow && mrow && in->depth->pixel_stride == 1 &&
                       in->motion->pixel_stride == 2 &&
                       (!in->zvel || (vrow && in->zvel->pixel_stride == 1));
    const internal_v8i iota = {0, 1, 2, 3, 4, 5, 6, 7};
    const internal_v8f yv = {yf, yf, yf, yf, yf, yf, yf, yf};
    const ptrdiff_t urs = U->row_stride;
    const int dpx1 = dp->pixel_stride == 1;
    float *orow = nprfx_image_at(O, fr.x0, y); /* packed: pixel stride CF */

    for (int s = 0; s < W; s += INTERNAL_SEG) {
        const int n = W - s < INTERNAL_SEG ? W - s : INTERNAL_SEG;
        int32_t ixa[INTERNAL_SEG], iya[INTERNAL_SEG], qxa[INTERNAL_SEG], qya[INTERNAL_SEG];
        int32_t ok[INTERNAL_SEG], kd[INTERNAL_SEG];
        float fxa[INTERNAL_SEG], fya[INTERNAL_SEG], zpa[INTERNAL_SEG];
        float t0[INTERNAL_SEG], t1[INTERNAL_SEG], t2[INTERNAL_SEG], t3[INTERNAL_SEG];
        /* positions */
        for (int b = 0; b < n; b += 8) {
            internal_v8f z, mx, my, vz = {0, 0, 0, 0, 0, 0, 0, 0};
            const int i0 = s + b;
            if (direct && i0 + 8 <= W) {
                z = internal_ld8(zrow + i0);
                internal_v16f m = internal_ld16(mrow + 2 * (ptrdiff_t)i0);
                mx = __builtin_shufflevector(m, m, 0, 2, 4, 6, 8, 10, 12, 14);
                my = __builtin_shufflevector(m, m, 1, 3, 5, 7, 9, 11, 13, 15);
                if (in->zvel) vz = internal_ld8(vrow + i0);
            } else {
                for (int l = 0; l < 8; l++) {
                    int x = fr.x0 + i0 + l;
                    if (i0 + l < W) {
                        z[l] = internal_read(in->depth, x, y, 0);
                        mx[l] = internal_read(in->motion, x, y, 0);
                        my[l] = internal_read(in->motion, x, y, 1);
                        vz[l] = in->zvel ? internal_read(in->zvel, x, y, 0) : 0.0f;
                    } else {
                        z[l] = INFINITY; /* past the row: background, never used */
                        mx[l] = my[l] = vz[l] = 0.0f;
                    }
                }
            }
            mx = mx * ms;
            my = my * ms;
            const internal_v8f xf = __builtin_convertvector(iota + (fr.x0 + i0), internal_v8f);
            internal_v8f px = xf + mx, py = yv + my;
            internal_v8i valid = (INTERNAL_ABS8(z) < bg) & (INTERNAL_ABS8(mx) <= FLT_MAX) &
                                 (INTERNAL_ABS8(my) <= FLT_MAX) & (px >= x0f) & (px <= xmax) &
                                 (py >= y0f) & (py <= ymax);
            px = INTERNAL_SEL8(valid, px, xf); /* keep conversions in range */
            py = INTERNAL_SEL8(valid, py, yv);
            internal_v8i ix = __builtin_convertvector(px, internal_v8i);
            ix += __builtin_convertvector(ix, internal_v8f) > px; /* floor: true is -1 */
            internal_v8i iy = __builtin_convertvector(py, internal_v8i);
            iy += __builtin_convertvector(iy, internal_v8f) > py;
            internal_v8f fx = px - __builtin_convertvector(ix, internal_v8f);
            internal_v8f fy = py - __builtin_convertvector(iy, internal_v8f);
            internal_v8i qx = __builtin_convertvector(fx * INTERNAL_TAB + 0.5f, internal_v8i);
            internal_v8i qy = __builtin_convertvector(fy * INTERNAL_TAB + 0.5f, internal_v8i);
            internal_v8f zpred = z;
            if (in->zvel) zpred = INTERNAL_SEL8(INTERNAL_ABS8(vz) <= FLT_MAX, z - dir * vz, z);
            memcpy(ixa + b, &ix, sizeof ix);
            memcpy(iya + b, &iy, sizeof iy);
            memcpy(qxa + b, &qx, sizeof qx);
            memcpy(qya + b, &qy, sizeof qy);
            memcpy(ok + b, &valid, sizeof valid);
            memcpy(fxa + b, &fx, sizeof fx);
            memcpy(fya + b, &fy, sizeof fy);
            memcpy(zpa + b, &zpred, sizeof zpred);
        }
        /* the previous depth's taps: four vector loads where the 8 pixels of a block read
         * consecutive columns of one row (smooth motion), else one by one */
        for (int b = 0; b < n; b += 8) {
            internal_v8i ix, iy, valid;
            memcpy(&ix, ixa + b, sizeof ix);
            memcpy(&iy, iya + b, sizeof iy);
            memcpy(&valid, ok + b, sizeof valid);
            const internal_v8i run = (ix - iota == ix[0]) & (iy == iy[0]) & valid;
            if (dpx1 && ix[0] >= dp->bounds.x0 && ix[0] + 8 < dp->bounds.x1 &&
                iy[0] >= dp->bounds.y0 && iy[0] + 1 < dp->bounds.y1 && run[0] && run[1] && run[2] &&
                run[3] && run[4] && run[5] && run[6] && run[7]) {
                const float *p = nprfx_image_at(dp, ix[0], iy[0]);
                const internal_v8f z0 = internal_ld8(p), z1 = internal_ld8(p + 1);
                const internal_v8f z2 = internal_ld8(p + dp->row_stride);
                const internal_v8f z3 = internal_ld8(p + dp->row_stride + 1);
                memcpy(t0 + b, &z0, sizeof z0);
                memcpy(t1 + b, &z1, sizeof z1);
                memcpy(t2 + b, &z2, sizeof z2);
                memcpy(t3 + b, &z3, sizeof z3);
                continue;
            }
            for (int i = b; i < b + 8; i++) {
                float z[4] = {0.0f, 0.0f, 0.0f, 0.0f};
                if (ok[i]) internal_depth_taps(dp, ixa[i], iya[i], z);
                t0[i] = z[0];
                t1[i] = z[1];
                t2[i] = z[2];
                t3[i] = z[3];
            }
        }
        /* the occlusion test */
        for (int b = 0; b < n; b += 8) {
            const internal_v8f fx = internal_ld8(fxa + b), fy = internal_ld8(fya + b);
            const internal_v8f z0 = internal_ld8(t0 + b), z1 = internal_ld8(t1 + b);
            const internal_v8f z2 = internal_ld8(t2 + b), z3 = internal_ld8(t3 + b);
            const internal_v8f w0 = (1.0f - fx) * (1.0f - fy), w1 = fx * (1.0f - fy);
            const internal_v8f w2 = (1.0f - fx) * fy, w3 = fx * fy;
            const internal_v8i u0 = (INTERNAL_ABS8(z0) < bg) & (w0 > 0.0f);
            const internal_v8i u1 = (INTERNAL_ABS8(z1) < bg) & (w1 > 0.0f);
            const internal_v8i u2 = (INTERNAL_ABS8(z2) < bg) & (w2 > 0.0f);
            const internal_v8i u3 = (INTERNAL_ABS8(z3) < bg) & (w3 > 0.0f);
            internal_v8f sw = {0, 0, 0, 0, 0, 0, 0, 0}, sz = sw;
            sw = INTERNAL_SEL8(u0, sw + w0, sw);
            sz = INTERNAL_SEL8(u0, sz + w0 * z0, sz);
            sw = INTERNAL_SEL8(u1, sw + w1, sw);
            sz = INTERNAL_SEL8(u1, sz + w1 * z1, sz);
            sw = INTERNAL_SEL8(u2, sw + w2, sw);
            sz = INTERNAL_SEL8(u2, sz + w2 * z2, sz);
            sw = INTERNAL_SEL8(u3, sw + w3, sw);
            sz = INTERNAL_SEL8(u3, sz + w3 * z3, sz);
            const internal_v8i any = u0 | u1 | u2 | u3;
            sw = INTERNAL_SEL8(any, sw, sw + 1.0f); /* no 0/0 in unused lanes */
            const internal_v8f zp = sz / sw;
            const internal_v8i occ = ~any | (internal_ld8(zpa + b) > zp + eps * INTERNAL_ABS8(zp));
            internal_v8i valid;
            memcpy(&valid, ok + b, sizeof valid);
            const internal_v8i f = ~valid | occ;
            /* a quantised offset of exactly one pixel belongs to the next pixel */
            internal_v8i ix, iy, qx, qy;
            memcpy(&ix, ixa + b, sizeof ix);
            memcpy(&iy, iya + b, sizeof iy);
            memcpy(&qx, qxa + b, sizeof qx);
            memcpy(&qy, qya + b, sizeof qy);
            const internal_v8i ox = qx == INTERNAL_TAB, oy = qy == INTERNAL_TAB;
            ix -= ox; /* true is -1 */
            iy -= oy;
            qx &= ~ox;
            qy &= ~oy;
            memcpy(ixa + b, &ix, sizeof ix);
            memcpy(iya + b, &iy, sizeof iy);
            memcpy(qxa + b, &qx, sizeof qx);
            memcpy(qya + b, &qy, sizeof qy);
            /* 0 fresh, 1 exact copy (integer motion), 2 interpolated near the frame's edge,
             * 3 interpolated with all 4x4 taps inside (and, C = 3, the vector slack after them) */
            const internal_v8i inner = (ix - 1 >= fr.x0) & (ix + 2 < fr.x1) & (iy - 1 >= fr.y0) &
                                       (iy + (CF == 3 ? 3 : 2) < fr.y1);
            const internal_v8i copy = (qx == 0) & (qy == 0); /* true is -1 */
            const internal_v8i kind = ~f & ((copy & 1) | (~copy & (2 - inner)));
            memcpy(kd + b, &kind, sizeof kind);
            const internal_v8u8 fb = __builtin_convertvector(f & 1, internal_v8u8);
            memcpy(fresh + s + b, &fb, (size_t)(n - b < 8 ? n - b : 8));
        }
        /* compensation noise for the pixels that interpolate */
        if (lz) {
            int lo = n, hi = -1;
            for (int i = 0; i < n; i++)
                if (kd[i] > 1) {
                    lo = i < lo ? i : lo;
                    hi = i;
                }
            if (hi >= 0) {
                const int b0 = (s + lo) >> 3, b1 = (s + hi + INTERNAL_COMP_MARGIN) >> 3;
                for (int k = 0; k < 5; k++)
                    internal_lazy_ensure(lz, k, b0, b1);
            }
        }
        /* the values */
        for (int b = 0; b < n; b += 8) {
            const int m = n - b < 8 ? n - b : 8;
            if (m == 8 && kd[b] == 1 && kd[b + 1] == 1 && kd[b + 2] == 1 && kd[b + 3] == 1 &&
                kd[b + 4] == 1 && kd[b + 5] == 1 && kd[b + 6] == 1 && kd[b + 7] == 1 &&
                ixa[b + 7] == ixa[b] + 7 && iya[b + 7] == iya[b] && iya[b + 1] == iya[b] &&
                iya[b + 2] == iya[b] && iya[b + 3] == iya[b] && iya[b + 4] == iya[b] &&
                iya[b + 5] == iya[b] && iya[b + 6] == iya[b] && ixa[b + 1] == ixa[b] + 1 &&
                ixa[b + 2] == ixa[b] + 2 && ixa[b + 3] == ixa[b] + 3 && ixa[b + 4] == ixa[b] + 4 &&
                ixa[b + 5] == ixa[b] + 5 && ixa[b + 6] == ixa[b] + 6) {
                /* eight exact copies from consecutive pixels: internal_px_carry's copy, 8C floats
                 * at a time (both states are packed) */
                const float *u = nprfx_image_at(U, ixa[b], iya[b]);
                const float *w = wr + (size_t)(s + b) * (size_t)CF;
                float *o = orow + (size_t)(s + b) * (size_t)CF;
                for (int k = 0; k < CF; k++) {
                    internal_v8f r = j->a * (internal_ld8(u + 8 * k) + 0.0f) +
                                     j->fresh_gain * internal_ld8(w + 8 * k);
                    memcpy(o + 8 * k, &r, sizeof r);
                }
                continue;
            }
            for (int i = b; i < b + m; i++) {
                const int xi = fr.x0 + s + i;
                const size_t off = (size_t)(s + i) * (size_t)CF;
                float *o = orow + off;
                if (kd[i] == 3) {
                    const float *u0 = U->data + (ptrdiff_t)(iya[i] - 1 - fr.y0) * urs +
                                      (ptrdiff_t)(ixa[i] - 1 - fr.x0) * CF;
                    const internal_taps *tx = j->tab + qxa[i], *ty = j->tab + qya[i];
                    const float a = j->a, g = j->fresh_gain;
                    if (CF == 1)
                        internal_px_v1(u0, urs, tx, ty, n1r + off, n2r[0] + off, n2r[1] + off,
                                       n2r[2] + off, n2r[3] + off, wr + off, a, g, o);
                    else if (CF == 2)
                        internal_px_v2(u0, urs, tx, ty, n1r + off, n2r[0] + off, n2r[1] + off,
                                       n2r[2] + off, n2r[3] + off, wr + off, a, g, o);
                    else if (CF == 3)
                        internal_px_v3(u0, urs, tx, ty, n1r + off, n2r[0] + off, n2r[1] + off,
                                       n2r[2] + off, n2r[3] + off, wr + off, a, g, o);
                    else
                        internal_px_v4(u0, urs, tx, ty, n1r + off, n2r[0] + off, n2r[1] + off,
                                       n2r[2] + off, n2r[3] + off, wr + off, a, g, o);
                    continue;
                }
                if (kd[i] == 0) {
                    internal_px_fresh(j, xi, y, wr + off, CF, o);
                    continue;
                }
                const float *n2p[4] = {n2r[0] + off, n2r[1] + off, n2r[2] + off, n2r[3] + off};
                internal_px_carry(j, xi, y, ixa[i], iya[i], qxa[i], qya[i], wr + off, n1r + off,
                                  n2p, CF, o);
            }
        }
    }
}
#endif

INTERNAL_CLONES
static void internal_step_rows(void *user, int begin, int end, int worker)
{
    const internal_step_job *j = user;
    const nprfx_rect fr = j->out->value.bounds;
    const int C = j->out->value.channels, W = nprfx_rect_width(fr);
    const int Wn = W + INTERNAL_COMP_MARGIN;
    const size_t L = j->row_len;
    float *base = j->scratch + (size_t)worker * j->scratch_len;
    float *wbuf = base, *n1buf = base + L, *tmp = base + 6 * L;
    float *ring[4] = {base + 2 * L, base + 3 * L, base + 4 * L, base + 5 * L};
    const int made_here = !j->input_mode && !j->w; /* white noise, generated row by row */
    int lazy_noise = 0;
#if INTERNAL_VEC
    /* the vector path makes the compensation noise only where a pixel interpolates */
    internal_lazy lazy, *lz = NULL;
    if (j->fast && made_here && j->compensate) {
        lz = &lazy;
        lazy_noise = 1;
        lazy.j = j;
        lazy.nblocks = (Wn + 7) / 8;
        unsigned char *flags = (unsigned char *)(tmp + Wn + INTERNAL_PAD);
        for (int k = 0; k < 5; k++) {
            lazy.buf[k] = k ? ring[k - 1] : n1buf;
            lazy.done[k] = flags + (size_t)k * (size_t)lazy.nblocks;
            lazy.row[k] = INT32_MIN;
        }
    }
#endif
    for (int r = begin; r < end; r++) {
        const int y = fr.y0 + r;
        const float *wr = NULL, *n1r = NULL, *n2r[4] = {NULL, NULL, NULL, NULL};
        if (!j->input_mode) {
            if (made_here) {
                internal_cn_noise_row(j->p, j->frame, 0, y, fr.x0, W, C, tmp, wbuf);
                wr = wbuf;
            } else {
                wr = nprfx_image_at(j->w, fr.x0, y);
            }
            if (j->compensate) {
                if (made_here) {
#if INTERNAL_VEC
                    if (lz) {
                        internal_lazy_assign(lz, 0, y);
                        for (int k = 0; k < 4; k++)
                            internal_lazy_assign(lz, 1 + (int)((unsigned)(y + k) & 3u), y + k);
                    }
#endif
                    if (!lazy_noise) {
                        internal_cn_noise_row(j->p, j->frame, j->s1, y, fr.x0, Wn, C, tmp, n1buf);
                        /* the ring holds rows y..y+3 of n2 (row yy in slot yy mod 4) */
                        for (int yy = r == begin ? y : y + 3; yy <= y + 3; yy++)
                            internal_cn_noise_row(j->p, j->frame, j->s2, yy, fr.x0, Wn, C, tmp,
                                                  ring[(unsigned)yy & 3u]);
                    }
                    n1r = n1buf;
                    for (int k = 0; k < 4; k++)
                        n2r[k] = ring[(unsigned)(y + k) & 3u];
                } else {
                    n1r = nprfx_image_at(j->n1, fr.x0, y);
                    for (int k = 0; k < 4; k++)
                        n2r[k] = nprfx_image_at(j->n2, fr.x0, y + k);
                }
            }
        }
        switch (j->fast ? C : 0) {
#if INTERNAL_VEC
        case 1:
            internal_step_row_v(j, y, wr, n1r, n2r, lz, 1);
            break;
        case 2:
            internal_step_row_v(j, y, wr, n1r, n2r, lz, 2);
            break;
        case 3:
            internal_step_row_v(j, y, wr, n1r, n2r, lz, 3);
            break;
        case 4:
            internal_step_row_v(j, y, wr, n1r, n2r, lz, 4);
            break;
#endif
        default:
            internal_step_row(j, y, wr, n1r, n2r);
        }
    }
}

/* A band-pass field over `r` plus one spare row (vector slack), filled for stream s. */
static nprfx_result internal_field(nprfx_context *ctx, const nprfx_cn_params *p, int64_t frame,
                                   uint32_t s, nprfx_rect r, nprfx_image *out)
{
    nprfx_result res =
        nprfx_image_alloc(ctx, nprfx_rect_make(r.x0, r.y0, r.x1, r.y1 + 1), p->channels, out);
    if (res) return res;
    return nprfx_cn_noise_fill(ctx, p, frame, s, out);
}

nprfx_result nprfx_cn_step(nprfx_context *ctx, const nprfx_cn_params *p, int direction,
                           int64_t frame, const nprfx_cn_inputs *in, const nprfx_cn_state *prev,
                           nprfx_cn_state *out)
{
    nprfx_result r = nprfx_cn_params_check(ctx, p);
    if (r) return r;
    if (direction != NPRFX_CN_FORWARD && direction != NPRFX_CN_BACKWARD)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "coherent-noise: bad direction %d",
                           direction);
    if (!in || !prev || !out || prev == out)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "coherent-noise: bad step buffers");
    const char *mname = direction > 0 ? "motion_prev" : "motion_next";
    if ((r = internal_cn_check_view(ctx, in->depth, 1, "depth"))) return r;
    if ((r = internal_cn_check_view(ctx, in->motion, 2, mname))) return r;
    if ((r = internal_cn_check_view(ctx, in->depth_prev, 1, "depth (neighbouring frame)")))
        return r;
    if (in->zvel && in->zvel->data && (r = internal_cn_check_view(ctx, in->zvel, 1, "zvel")))
        return r;
    int input_mode = p->noise == NPRFX_CN_NOISE_INPUT;
    if (input_mode && (r = internal_cn_check_view(ctx, in->source, p->channels, "source")))
        return r;
    nprfx_rect fr = out->value.bounds;
    if (!nprfx_rect_equal(fr, prev->value.bounds) || out->value.channels != p->channels ||
        prev->value.channels != p->channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "coherent-noise: states differ in size or channel count");
    const int C = p->channels, W = nprfx_rect_width(fr), H = nprfx_rect_height(fr);
    if (W <= 0 || H <= 0) return NPRFX_OK;

    nprfx_cn_inputs local = *in;
    if (local.zvel && !local.zvel->data) local.zvel = NULL;

    internal_step_job job;
    memset(&job, 0, sizeof job);
    job.p = p;
    job.direction = direction;
    job.frame = frame;
    job.in = &local;
    job.prev = prev;
    job.out = out;
    job.input_mode = input_mode;
    job.a = (float)p->alpha;
    job.fresh_gain = input_mode ? (float)(1.0 - p->alpha) : (float)sqrt(1.0 - p->alpha * p->alpha);
    job.tab = internal_cn_taps_for(p->resample);
    job.compensate = !input_mode && p->alpha > 0.0 && p->resample == NPRFX_CN_RESAMPLE_STATIONARY;
    /* Stream 0 is w_i, shared by both passes (Eq. 11 needs the same w); the compensation fields
     * are per pass so the passes stay independent apart from w. */
    job.s1 = direction > 0 ? 1u : 3u;
    job.s2 = job.s1 + 1u;
    const nprfx_image *U = &prev->value;
    const nprfx_image *O = &out->value;
    job.fast = INTERNAL_VEC && job.compensate && C <= 4 && U->pixel_stride == C &&
               U->row_stride == (ptrdiff_t)W * C && O->pixel_stride == C;

    nprfx_image w = {0}, n1 = {0}, n2 = {0};
    if (!input_mode && internal_is_bandpass(p)) {
        /* Band-pass noise is a filtered field: made whole, once per step. */
        nprfx_rect ext = nprfx_rect_make(fr.x0, fr.y0, fr.x1 + INTERNAL_COMP_MARGIN,
                                         fr.y1 + INTERNAL_COMP_MARGIN);
        if ((r = internal_field(ctx, p, frame, 0, fr, &w))) goto done;
        job.w = &w;
        if (job.compensate) {
            if ((r = internal_field(ctx, p, frame, job.s1, ext, &n1)) ||
                (r = internal_field(ctx, p, frame, job.s2, ext, &n2)))
                goto done;
            job.n1 = &n1;
            job.n2 = &n2;
        }
    }
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    int workers = nprfx_executor_workers(ex);
    if (workers < 1) workers = 1;
    /* a noise row: W + margin pixels rounded up to whole blocks of 8 (the lazy path makes
     * blocks), plus vector slack */
    job.row_len = (size_t)((W + INTERNAL_COMP_MARGIN + 7) & ~7) * (size_t)C + INTERNAL_PAD;
    /* w, n1, the n2 ring, a planar row, and the lazy path's block flags */
    job.scratch_len = 6 * job.row_len + (size_t)(W + INTERNAL_COMP_MARGIN) + INTERNAL_PAD +
                      (size_t)(W + INTERNAL_COMP_MARGIN + 7) / 8 * 5 / sizeof(float) + 8;
    job.scratch = malloc((size_t)workers * job.scratch_len * sizeof(float));
    if (!job.scratch) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "coherent-noise: out of memory");
        goto done;
    }
    nprfx_parallel_for(ex, H, INTERNAL_STEP_GRAIN, internal_step_rows, &job);
done:
    free(job.scratch);
    nprfx_image_free(&w);
    nprfx_image_free(&n1);
    nprfx_image_free(&n2);
    return r;
}
