/* The per-pixel attributes of an emission block: its inputs packed into a worker's strip, the
 * block's window of raw data, interior flags and Jacobians from finite differences that stay on
 * one surface, then per pixel of the block and its ring the anchor, the pseudo-inverse J+, the
 * normal, the footprint and the wanted density (edge and virtual pixels extrapolate from an
 * interior neighbour), and the labels of the block's surface patches. Vector paths 8 pixels at a
 * time; the scalar code is the reference they reproduce lane by lane. */
#include <math.h>
#include <string.h>

#include "internal_gabor.h"

#define COVERAGE_FULL 0.999 /* an anchor coverage channel below this marks a blended pixel */

void internal_gabor_strip_fill(const gsrc *S, gstrip *T, int x0, int x1, int y0, int y1)
{
    nprfx_rect reg = S->region;
    T->x0 = x0 > reg.x0 ? x0 : reg.x0;
    T->y0 = y0 > reg.y0 ? y0 : reg.y0;
    T->w = (x1 < reg.x1 ? x1 : reg.x1) - T->x0;
    T->h = (y1 < reg.y1 ? y1 : reg.y1) - T->y0;
    if (T->w <= 0 || T->h <= 0) {
        T->w = T->h = 0;
        return;
    }
    ptrdiff_t sa = S->anchor->pixel_stride, sz = S->depth->pixel_stride;
    ptrdiff_t si = S->id ? S->id->pixel_stride : 0;
    int dims = S->dims, cov = S->cov_ch;
    for (int y = T->y0; y < T->y0 + T->h; y++) {
        const float *a = nprfx_image_at(S->anchor, T->x0, y);
        const float *zp = nprfx_image_at(S->depth, T->x0, y);
        const float *ip = S->id ? nprfx_image_at(S->id, T->x0, y) : NULL;
        float *A0 = strip_plane(T, ST_A0, T->x0, y), *A1 = strip_plane(T, ST_A1, T->x0, y);
        float *A2 = strip_plane(T, ST_A2, T->x0, y), *Z = strip_plane(T, ST_Z, T->x0, y);
        float *ID = strip_plane(T, ST_ID, T->x0, y);
        int32_t *V = (int32_t *)strip_plane(T, ST_VALID, T->x0, y);
        int32_t *F = (int32_t *)strip_plane(T, ST_FULL, T->x0, y);
        for (int i = 0; i < T->w; i++, a += sa, zp += sz) {
            float a0 = a[0], a1 = a[1], a2 = dims == 3 ? a[2] : 0.0f, z = *zp;
            float id = ip ? nprfx_id_canonical(ip[i * si]) : 0.0f;
            A0[i] = a0;
            A1[i] = a1;
            A2[i] = a2;
            Z[i] = z;
            ID[i] = id;
            V[i] = -(is_surface_depth(z) && isfinite(a0) && isfinite(a1) && isfinite(a2) &&
                     nprfx_id_is_object(id));
            F[i] = -(cov < 0 || a[cov] >= COVERAGE_FULL);
        }
    }
}

/* Copy the raw data of the window at (cx0, cy0), cw x ch, from the strip (the rest of the
 * CW x CW planes is outside the inputs). */
static void cache_fill(const gsrc *S, const gstrip *T, gcache *C, int cx0, int cy0, int cw, int ch)
{
    nprfx_rect reg = S->region;
    int ia = reg.x0 - cx0 > 0 ? reg.x0 - cx0 : 0;
    int ib = reg.x1 - cx0 < cw ? reg.x1 - cx0 : cw;
    memset(C->interior, 0, sizeof C->interior);
    memset(C->hasj, 0, sizeof C->hasj);
    if (ia == 0 && ib == CW && ch == CW && cy0 >= reg.y0 && cy0 + CW <= reg.y1) {
        /* the whole window lies in the inputs (most blocks): whole rows, fixed-size copies */
        for (int j = 0; j < CW; j++) {
            int y = cy0 + j, o = j * CW;
            const float *src = strip_plane(T, ST_A0, cx0, y);
            size_t pl = (size_t)T->w; /* the strip's planes follow each other in a row */
            memcpy(C->A[0] + o, src + ST_A0 * pl, sizeof(float) * CW);
            memcpy(C->A[1] + o, src + ST_A1 * pl, sizeof(float) * CW);
            memcpy(C->A[2] + o, src + ST_A2 * pl, sizeof(float) * CW);
            memcpy(C->z + o, src + ST_Z * pl, sizeof(float) * CW);
            memcpy(C->id + o, src + ST_ID * pl, sizeof(float) * CW);
            memcpy(C->valid + o, src + ST_VALID * pl, sizeof(float) * CW);
            memcpy(C->full + o, src + ST_FULL * pl, sizeof(float) * CW);
            for (int i = 0; i < CW; i++)
                C->present[o + i] = -1;
        }
        return;
    }
    memset(C->present, 0, sizeof C->present);
    memset(C->valid, 0, sizeof C->valid);
    memset(C->full, 0, sizeof C->full);
    if (ia >= ib) return;
    size_t nb = sizeof(float) * (size_t)(ib - ia);
    for (int j = 0; j < ch; j++) {
        int y = cy0 + j, o = j * CW + ia;
        if (y < reg.y0 || y >= reg.y1) continue;
        memcpy(C->A[0] + o, strip_plane(T, ST_A0, cx0 + ia, y), nb);
        memcpy(C->A[1] + o, strip_plane(T, ST_A1, cx0 + ia, y), nb);
        memcpy(C->A[2] + o, strip_plane(T, ST_A2, cx0 + ia, y), nb);
        memcpy(C->z + o, strip_plane(T, ST_Z, cx0 + ia, y), nb);
        memcpy(C->id + o, strip_plane(T, ST_ID, cx0 + ia, y), nb);
        memcpy(C->valid + o, strip_plane(T, ST_VALID, cx0 + ia, y), nb);
        memcpy(C->full + o, strip_plane(T, ST_FULL, cx0 + ia, y), nb);
        for (int i = 0; i < ib - ia; i++)
            C->present[o + i] = -1;
    }
}

/* Neighbour d lies on c's surface: same object id and no depth step beyond the tolerance. */
static int same_surface(const gsrc *S, const gcache *C, int c, int d)
{
    if (!C->present[d] || !C->valid[d] || !id_eq(C->id[d], C->id[c])) return 0;
    double zmin = C->z[c] < C->z[d] ? C->z[c] : C->z[d];
    return fabs((double)C->z[d] - C->z[c]) <= S->step_tol * zmin;
}

/* One axis of the Jacobian of interior pixel c, from its interior neighbours at c +- step.
 * Where both exist but one difference is much larger (a UV seam, a blended anchor), the smaller
 * one-sided difference is used; with neither, the axis is undefined. */
static int axis_diff(const gcache *C, int c, int step, float dA[3], float *dz)
{
    int f = c + step, b = c - step;
    int hf = C->present[f] && C->interior[f] && id_eq(C->id[f], C->id[c]);
    int hb = C->present[b] && C->interior[b] && id_eq(C->id[b], C->id[c]);
    float Df[3], Db[3];
    for (int k = 0; k < 3; k++) {
        Df[k] = C->A[k][f] - C->A[k][c];
        Db[k] = C->A[k][c] - C->A[k][b];
    }
    if (hf && hb) {
        float nf = Df[0] * Df[0] + Df[1] * Df[1] + Df[2] * Df[2];
        float nb = Db[0] * Db[0] + Db[1] * Db[1] + Db[2] * Db[2];
        if (nf > 9.0f * nb) /* squared: one difference 3x the other */
            hf = 0;
        else if (nb > 9.0f * nf)
            hb = 0;
    }
    if (hf && hb) {
        for (int k = 0; k < 3; k++)
            dA[k] = 0.5f * (Df[k] + Db[k]);
        *dz = 0.5f * (C->z[f] - C->z[b]);
    } else if (hf) {
        memcpy(dA, Df, sizeof Df);
        *dz = C->z[f] - C->z[c];
    } else if (hb) {
        memcpy(dA, Db, sizeof Db);
        *dz = C->z[c] - C->z[b];
    } else {
        return 0;
    }
    return 1;
}

/* Interior flags on the window less its outer ring, then the Jacobians of the interior pixels
 * (scalar path). */
static void cache_derive_scalar(const gsrc *S, gcache *C, int cw, int ch)
{
    for (int j = 1; j < ch - 1; j++)
        for (int i = 1; i < cw - 1; i++) {
            int c = j * CW + i;
            if (!C->valid[c] || !C->full[c]) continue;
            const int nb[4] = {c - 1, c + 1, c - CW, c + CW};
            int ok = 1;
            for (int k = 0; k < 4 && ok; k++)
                if (C->present[nb[k]] && !same_surface(S, C, c, nb[k])) ok = 0;
            C->interior[c] = -ok;
        }
    for (int j = 1; j < ch - 1; j++)
        for (int i = 1; i < cw - 1; i++) {
            int c = j * CW + i;
            if (!C->interior[c]) continue;
            float jx[3], jy[3], gx, gy;
            if (!axis_diff(C, c, 1, jx, &gx) || !axis_diff(C, c, CW, jy, &gy)) continue;
            for (int m = 0; m < 3; m++) {
                C->J[0][m][c] = jx[m];
                C->J[1][m][c] = jy[m];
            }
            C->gz[0][c] = gx;
            C->gz[1][c] = gy;
            C->hasj[c] = -1;
        }
}

static void finish_pixel(const gconf *G, gpixels *X, int k, const double *jx, const double *jy)
{
    double g11 = dot3(jx, jx), g12 = dot3(jx, jy), g22 = dot3(jy, jy);
    double det = g11 * g22 - g12 * g12; /* = |Jx x Jy|^2 */
    X->emit[k] = 0;
    if (!(det > 0.0) || !isfinite(det)) return;
    double area = sqrt(det), iarea = 1.0 / area, idet = iarea * iarea;
    for (int m = 0; m < 3; m++) {
        X->P[m][k] = (float)((g22 * jx[m] - g12 * jy[m]) * idet);
        X->P[3 + m][k] = (float)((g11 * jy[m] - g12 * jx[m]) * idet);
        X->ext[m][k] = (float)(0.5 * (fabs(jx[m]) + fabs(jy[m])));
    }
    X->n[0][k] = (float)((jx[1] * jy[2] - jx[2] * jy[1]) * iarea);
    X->n[1][k] = (float)((jx[2] * jy[0] - jx[0] * jy[2]) * iarea);
    X->n[2][k] = (float)((jx[0] * jy[1] - jx[1] * jy[0]) * iarea);
    float mu = (float)(G->lh2 * iarea);
    X->mu[k] = mu;
    X->emit[k] = mu > 0.0f && isfinite(mu);
}

/* The attributes of block pixel (x, y) (index k): real pixels use their own anchor where they
 * are interior to their surface; pixels at an edge (renderers filter Pref and UV there, mixing
 * the two surfaces) and virtual pixels outside the inputs extrapolate from an interior
 * neighbour along its Jacobian. */
static void pixel_scalar(const gconf *G, gpixels *X, const gcache *C, int k, int x, int y, int cx0,
                         int cy0)
{
    const gsrc *S = &G->S;
    nprfx_rect reg = S->region;
    int rx = x < reg.x0 ? reg.x0 : (x >= reg.x1 ? reg.x1 - 1 : x);
    int ry = y < reg.y0 ? reg.y0 : (y >= reg.y1 ? reg.y1 - 1 : y);
    int ci = (ry - cy0) * CW + (rx - cx0);
    X->emit[k] = 0;
    if (!C->valid[ci]) return;
    int si = -1, sx = rx, sy = ry;
    if (C->hasj[ci]) {
        si = ci;
    } else {
        static const int dxs[4] = {-1, 1, 0, 0}, dys[4] = {0, 0, -1, 1};
        for (int m = 0; m < 4 && si < 0; m++) {
            int di = ci + dys[m] * CW + dxs[m];
            if (C->present[di] && C->interior[di] && same_surface(S, C, ci, di) && C->hasj[di]) {
                si = di;
                sx = rx + dxs[m];
                sy = ry + dys[m];
            }
        }
    }
    if (si < 0) return;
    double ox = x - sx, oy = y - sy;
    double jx[3], jy[3];
    for (int m = 0; m < 3; m++) {
        jx[m] = C->J[0][m][si];
        jy[m] = C->J[1][m][si];
        X->A[m][k] = (float)(C->A[m][si] + jx[m] * ox + jy[m] * oy);
    }
    /* depth is one sample, never filtered: keep the pixel's own, extrapolate only outside */
    double z = C->z[ci] + (double)C->gz[0][si] * (x - rx) + (double)C->gz[1][si] * (y - ry);
    if (!is_surface_depth(z)) return;
    X->z[k] = (float)z;
    X->gz[0][k] = C->gz[0][si];
    X->gz[1][k] = C->gz[1][si];
    X->id[k] = C->id[ci];
    X->rx[k] = rx;
    X->ry[k] = ry;
    finish_pixel(G, X, k, jx, jy);
}

/* The window of raw data block (bx, by) reads: the real pixels its pixels map to (clamped into
 * the inputs) and a halo. Returns 0 when there are no inputs. (A pixel's attributes depend on
 * the inputs around it only, never on the block.) */
int internal_gabor_block_window(const gsrc *S, int bx, int by, int *cx0, int *cy0, int *cw, int *ch)
{
    nprfx_rect reg = S->region;
    if (nprfx_rect_empty(reg)) return 0;
    int x0 = bx * BLOCK - 1, y0 = by * BLOCK - 1; /* the ring's first pixel */
    int rx0 = x0 < reg.x0 ? reg.x0 : (x0 >= reg.x1 ? reg.x1 - 1 : x0);
    int rx1 = x0 + PW - 1 < reg.x0 ? reg.x0 : (x0 + PW - 1 >= reg.x1 ? reg.x1 - 1 : x0 + PW - 1);
    int ry0 = y0 < reg.y0 ? reg.y0 : (y0 >= reg.y1 ? reg.y1 - 1 : y0);
    int ry1 = y0 + PW - 1 < reg.y0 ? reg.y0 : (y0 + PW - 1 >= reg.y1 ? reg.y1 - 1 : y0 + PW - 1);
    *cx0 = rx0 - HALO;
    *cy0 = ry0 - HALO;
    *cw = rx1 - rx0 + 1 + 2 * HALO;
    *ch = ry1 - ry0 + 1 + 2 * HALO;
    return 1;
}

static void block_pixels_scalar(const gconf *G, const gstrip *T, int bx, int by, gpixels *X,
                                gcache *C)
{
    int x0 = bx * BLOCK - 1, y0 = by * BLOCK - 1, cx0, cy0, cw, ch;
    memset(X->emit, 0, sizeof X->emit);
    if (!internal_gabor_block_window(&G->S, bx, by, &cx0, &cy0, &cw, &ch)) return;
    cache_fill(&G->S, T, C, cx0, cy0, cw, ch);
    cache_derive_scalar(&G->S, C, cw, ch);
    for (int j = 0; j < PW; j++)
        for (int i = 0; i < PW; i++)
            pixel_scalar(G, X, C, j * PWS + i, x0 + i, y0 + j, cx0, cy0);
}

#if GABOR_VEC
/* Interior flags and Jacobians 8 pixels at a time, as cache_derive_scalar lane by lane (on the
 * whole rows; the flags are then cut to the window less its ring, as the scalar path leaves
 * them). */
GV_INLINE void cache_derive_vec(const gsrc *S, gcache *C, int cw, int ch)
{
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    double step_tol = S->step_tol;
    for (int j = 1; j < ch - 1; j++)
        for (int i0 = 0; i0 < CW; i0 += 8) {
            int c = j * CW + i0;
            gv8i col = i0 + lane;
            gv8f zc = gv_loadf(C->z + c);
            gv8i idc = gv_loadid(C->id + c);
            gv8d zcd = gv_wide(zc);
            gv8i ok = gv_loadi(C->valid + c) & gv_loadi(C->full + c) & (col >= 1) & (col < cw - 1);
            const int nb[4] = {c - 1, c + 1, c - CW, c + CW};
            for (int k = 0; k < 4; k++) {
                int d = nb[k];
                gv8f zd = gv_loadf(C->z + d);
                gv8f zmin = gv_self(zc < zd, zc, zd);
                gv8i same = gv_loadi(C->valid + d) & (gv_loadid(C->id + d) == idc) &
                            gv_mask(gv_absd(gv_wide(zd) - zcd) <= step_tol * gv_wide(zmin));
                ok &= ~gv_loadi(C->present + d) | same;
            }
            gv_storei(C->interior + c, ok);
        }
    for (int j = 1; j < ch - 1; j++)
        for (int i0 = 0; i0 < CW; i0 += 8) {
            int c = j * CW + i0;
            gv8i in = gv_loadi(C->interior + c);
            if (!gv_any(in)) {
                gv_storei(C->hasj + c, in);
                continue;
            }
            gv8i idc = gv_loadid(C->id + c);
            gv8f zc = gv_loadf(C->z + c);
            gv8f Ac[3];
            for (int m = 0; m < 3; m++)
                Ac[m] = gv_loadf(C->A[m] + c);
            gv8i okall = in;
            for (int ax = 0; ax < 2; ax++) {
                int step = ax ? CW : 1, f = c + step, b = c - step;
                gv8i hf = gv_loadi(C->present + f) & gv_loadi(C->interior + f) &
                          (gv_loadid(C->id + f) == idc);
                gv8i hb = gv_loadi(C->present + b) & gv_loadi(C->interior + b) &
                          (gv_loadid(C->id + b) == idc);
                gv8f Df[3], Db[3];
                for (int m = 0; m < 3; m++) {
                    Df[m] = gv_loadf(C->A[m] + f) - Ac[m];
                    Db[m] = Ac[m] - gv_loadf(C->A[m] + b);
                }
                gv8f nf = Df[0] * Df[0] + Df[1] * Df[1] + Df[2] * Df[2];
                gv8f nb = Db[0] * Db[0] + Db[1] * Db[1] + Db[2] * Db[2];
                gv8i both = hf & hb;
                gv8i dropf = both & (nf > 9.0f * nb);
                gv8i dropb = both & ~dropf & (nb > 9.0f * nf);
                hf &= ~dropf;
                hb &= ~dropb;
                both = hf & hb;
                gv8f zf = gv_loadf(C->z + f), zb = gv_loadf(C->z + b);
                for (int m = 0; m < 3; m++) {
                    gv8f d = gv_self(both, 0.5f * (Df[m] + Db[m]), gv_self(hf, Df[m], Db[m]));
                    gv_storef(C->J[ax][m] + c, d);
                }
                gv_storef(C->gz[ax] + c,
                          gv_self(both, 0.5f * (zf - zb), gv_self(hf, zf - zc, zc - zb)));
                okall &= hf | hb;
            }
            gv_storei(C->hasj + c, okall);
        }
}

/* The attributes of 8 block pixels k.. (row j, columns i0..) whose real pixels are themselves
 * and interior with a Jacobian (the lanes in sel; the others are left to pixel_scalar): as
 * pixel_scalar and finish_pixel lane by lane. */
GV_INLINE void pixels_vec8(const gconf *G, gpixels *X, const gcache *C, int k, int c, int x, int y,
                           const gv8i *psel)
{
    gv8i sel = *psel;
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    gv8d jx[3], jy[3], zero = {0};
    for (int m = 0; m < 3; m++) {
        jx[m] = gv_wide(gv_loadf(C->J[0][m] + c));
        jy[m] = gv_wide(gv_loadf(C->J[1][m] + c));
        gv_storef(X->A[m] + k,
                  gv_narrow(gv_wide(gv_loadf(C->A[m] + c)) + jx[m] * zero + jy[m] * zero));
    }
    gv8f gz0 = gv_loadf(C->gz[0] + c), gz1 = gv_loadf(C->gz[1] + c);
    gv8d z = gv_wide(gv_loadf(C->z + c)) + gv_wide(gz0) * zero + gv_wide(gz1) * zero;
    gv8i ok = sel & gv_mask((z > 0.0) & (z < BACKGROUND_DEPTH));
    gv_storef(X->z + k, gv_narrow(z));
    gv_storef(X->gz[0] + k, gz0);
    gv_storef(X->gz[1] + k, gz1);
    gv_storef(X->id + k, gv_loadf(C->id + c));
    gv_storei(X->rx + k, x + lane);
    gv_storei(X->ry + k, y + (gv8i){0});
    gv8d g11 = jx[0] * jx[0] + jx[1] * jx[1] + jx[2] * jx[2];
    gv8d g12 = jx[0] * jy[0] + jx[1] * jy[1] + jx[2] * jy[2];
    gv8d g22 = jy[0] * jy[0] + jy[1] * jy[1] + jy[2] * jy[2];
    gv8d det = g11 * g22 - g12 * g12;
    gv8l okd = (det > 0.0) & (det < HUGE_VAL);
    gv8d one = zero + 1.0;
    gv8d area = gv_sqrt(gv_seld(okd, det, one)), iarea = 1.0 / area, idet = iarea * iarea;
    for (int m = 0; m < 3; m++) {
        gv_storef(X->P[m] + k, gv_narrow((g22 * jx[m] - g12 * jy[m]) * idet));
        gv_storef(X->P[3 + m] + k, gv_narrow((g11 * jy[m] - g12 * jx[m]) * idet));
        gv_storef(X->ext[m] + k, gv_narrow(0.5 * (gv_absd(jx[m]) + gv_absd(jy[m]))));
    }
    gv_storef(X->n[0] + k, gv_narrow((jx[1] * jy[2] - jx[2] * jy[1]) * iarea));
    gv_storef(X->n[1] + k, gv_narrow((jx[2] * jy[0] - jx[0] * jy[2]) * iarea));
    gv_storef(X->n[2] + k, gv_narrow((jx[0] * jy[1] - jx[1] * jy[0]) * iarea));
    gv8f mu = gv_narrow(G->lh2 * iarea);
    gv_storef(X->mu + k, mu);
    ok &= gv_mask(okd) & (mu > 0.0f) & (mu < HUGE_VALF);
    gv_storei(X->emit + k, ok);
}

GV_INLINE void block_pixels_body(const gconf *G, const gstrip *T, int bx, int by, gpixels *X,
                                 gcache *C)
{
    const gsrc *S = &G->S;
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    int x0 = bx * BLOCK - 1, y0 = by * BLOCK - 1, cx0, cy0, cw, ch;
    memset(X->emit, 0, sizeof X->emit);
    if (!internal_gabor_block_window(S, bx, by, &cx0, &cy0, &cw, &ch)) return;
    cache_fill(S, T, C, cx0, cy0, cw, ch);
    cache_derive_vec(S, C, cw, ch);
    nprfx_rect reg = S->region;
    /* The lanes whose pixel lies inside the inputs (its own real pixel, raw pixel c + l of the
     * window) and has a Jacobian go 8 at a time; the rest (edges, and the virtual pixels of a
     * block on the frame's border) to pixel_scalar. */
    for (int j = 0; j < PW; j++) {
        int y = y0 + j, yin = y >= reg.y0 && y < reg.y1;
        for (int i0 = 0; i0 < PWS; i0 += 8) {
            int k = j * PWS + i0, x = x0 + i0;
            int c = (y - cy0) * CW + (x - cx0);
            gv8i real = (i0 + lane) < PW;
            gv8i self = real & 0;
            if (yin && c >= 0 && c + 8 <= CNP) {
                self = real & ((x + lane) >= reg.x0) & ((x + lane) < reg.x1);
                self &= gv_loadi(C->hasj + c);
                pixels_vec8(G, X, C, k, c, x, y, &self);
            }
            for (int l = 0; l < 8; l++)
                if (real[l] && !self[l]) pixel_scalar(G, X, C, k + l, x + l, y, cx0, cy0);
        }
    }
}

#endif /* GABOR_VEC */

/* Label the emitting pixels of a block (not its ring) by connected surface patch (4-neighbours,
 * raster order of each patch's first pixel). Each patch enumerates the anchor cells of its own
 * footprint, so a block straddling two surfaces does not enumerate everything between their
 * anchors. */
#if GABOR_VEC
/* patch_link between the block's pixels and their right and lower neighbours, 8 at a time (as
 * patch_link lane by lane; it is symmetric), and between the ring's top row and the block's
 * first (emission's surface_at reads the links of a block pixel to its 4-neighbours). */
GV_INLINE void patch_links_vec(const gconf *G, gpixels *X)
{
    gv8f tol = G->step_tolf + (gv8f){0};
    for (int j = 0; j <= BLOCK; j++)
        for (int i0 = 0; i0 < PWS; i0 += 8) {
            int k = j * PWS + i0;
            gv8f za = gv_loadf(X->z + k);
            gv8i ida = gv_loadid(X->id + k);
            gv8i ea = gv_loadi(X->emit + k) != 0;
            for (int dir = 0; dir < 2; dir++) {
                int o = k + (dir ? PWS : 1);
                gv8f zb = gv_loadf(X->z + o);
                gv8f zmin = gv_self(za < zb, za, zb);
                gv8i m = ea & (gv_loadi(X->emit + o) != 0) & (gv_loadid(X->id + o) == ida) &
                         (gv_absf(za - zb) <= tol * zmin);
                gv8f d2 = {0}, e2 = {0};
                for (int c = 0; c < 3; c++) {
                    gv8f d = gv_loadf(X->A[c] + k) - gv_loadf(X->A[c] + o);
                    gv8f e = gv_loadf(X->ext[c] + k) + gv_loadf(X->ext[c] + o);
                    d2 += d * d;
                    e2 += e * e;
                }
                m &= d2 <= 4.0f * e2;
                gv_storei((dir ? X->ld : X->lr) + k, m);
            }
        }
}
#endif

#if GABOR_VEC
/* Every pixel of the block emits and links to its right and lower neighbours in the block. */
GV_INLINE int one_patch_vec(const gpixels *X)
{
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    gv8i all = (gv8i){0} - 1;
    for (int j = 1; j <= BLOCK; j++)
        for (int i0 = 1; i0 <= BLOCK; i0 += 8) {
            int k = j * PWS + i0;
            all &= gv_loadi(X->emit + k) != 0;
            all &= (gv_loadi(X->lr + k) != 0) | ((i0 + lane) == BLOCK); /* the last: no link */
            if (j < BLOCK) all &= gv_loadi(X->ld + k) != 0;
        }
    for (int l = 0; l < 8; l++)
        if (!all[l]) return 0;
    return 1;
}
#endif

GABOR_BODY int label_patches(const gconf *G, gpixels *X, const int vec)
{
    int stack[BLOCK * BLOCK], n = 0;
    for (int k = 0; k < PN; k++)
        X->comp[k] = -1;
#if GABOR_VEC
    if (vec) {
        patch_links_vec(G, X);
        if (one_patch_vec(X)) {
            /* every pixel of the block emits and links to its neighbours: one patch */
            for (int j = 1; j <= BLOCK; j++)
                for (int i = 1; i <= BLOCK; i++)
                    X->comp[j * PWS + i] = 0;
            return 1;
        }
    }
#endif
    for (int kj = 1; kj <= BLOCK; kj++)
        for (int ki = 1; ki <= BLOCK; ki++) {
            int k = kj * PWS + ki; /* raster order over the block */
            if (!X->emit[k] || X->comp[k] >= 0) continue;
            int sp = 0;
            X->comp[k] = n;
            stack[sp++] = k;
            while (sp > 0) {
                int c = stack[--sp], ci = c % PWS, cj = c / PWS;
                const int nb[4] = {c - 1, c + 1, c - PWS, c + PWS};
                const int in[4] = {ci > 1, ci<BLOCK, cj> 1, cj < BLOCK}; /* in_block(nb[m]) */
                for (int m = 0; m < 4; m++) {
                    int d = nb[m];
                    if (!in[m] || X->comp[d] >= 0) continue;
                    int link;
                    if (vec) {
                        static const int lo[4] = {-1, 0, -PWS, 0};
                        link = (m < 2 ? X->lr : X->ld)[c + lo[m]] != 0;
                    } else {
                        link = patch_link(G, X, c, d);
                    }
                    if (!link) continue;
                    X->comp[d] = n;
                    stack[sp++] = d;
                }
            }
            n++;
        }
    return n;
}

/* The attributes and patches of block (bx, by): vec as in emit_block_body (a constant in each
 * instance). */
GABOR_BODY int block_prepare_body(const gconf *G, const gstrip *T, int bx, int by, gpixels *X,
                                  gcache *C, const int vec)
{
#if GABOR_VEC
    if (vec)
        block_pixels_body(G, T, bx, by, X, C);
    else
#endif
        block_pixels_scalar(G, T, bx, by, X, C);
    return label_patches(G, X, vec);
}

int internal_gabor_block_prepare_scalar(const gconf *G, const gstrip *T, int bx, int by, gpixels *X,
                                        gcache *C)
{
    return block_prepare_body(G, T, bx, by, X, C, GABOR_ISA_BASE);
}

#if GABOR_X86
__attribute__((target("avx2"))) int internal_gabor_block_prepare_avx2(const gconf *G,
                                                                      const gstrip *T, int bx,
                                                                      int by, gpixels *X, gcache *C)
{
    return block_prepare_body(G, T, bx, by, X, C, GABOR_ISA_AVX2);
}

__attribute__((target("avx512f,avx512vl,avx512bw,avx512dq"))) int
internal_gabor_block_prepare_avx512(const gconf *G, const gstrip *T, int bx, int by, gpixels *X,
                                    gcache *C)
{
    return block_prepare_body(G, T, bx, by, X, C, GABOR_ISA_AVX512);
}
#endif
