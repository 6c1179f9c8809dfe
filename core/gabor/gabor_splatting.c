/* Splatting: a tile's kernels added to its samples, in block raster order and each block's
 * emission order, each kernel from its own tables (its factor recurrences from its first sample,
 * whatever the tile) and row spans, with the object-id and depth tests. The scalar path is the
 * reference; the vector paths (rows only on the baseline ISA; spans, batched tables and rows on
 * AVX2 and AVX-512) do its IEEE operations lane by lane in the same order. */
#include <math.h>
#include <string.h>

#include "internal_gabor.h"

/* The kernel's factor tables along x (nx samples) and y (ny samples) from their start values:
 * g (c, s) by recurrences in double, the two axes interleaved so their dependency chains
 * overlap. */
static void kernel_tables(const gaxis *ax, const gaxis *ay, double rr, int nx, int ny, float *CX,
                          float *SX, float *CY, float *SY)
{
    double g0 = ax->g, r0 = ax->r, c0 = ax->c, s0 = ax->s, cs0 = ax->cs, ss0 = ax->ss;
    double g1 = ay->g, r1 = ay->r, c1 = ay->c, s1 = ay->s, cs1 = ay->cs, ss1 = ay->ss;
    int n = nx > ny ? nx : ny;
    for (int i = 0; i < n; i++) {
        if (i < nx) {
            CX[i] = (float)(g0 * c0);
            SX[i] = (float)(g0 * s0);
        }
        if (i < ny) {
            CY[i] = (float)(g1 * c1);
            SY[i] = (float)(g1 * s1);
        }
        g0 *= r0;
        r0 *= rr;
        g1 *= r1;
        r1 *= rr;
        double t0 = c0 * cs0 - s0 * ss0, t1 = c1 * cs1 - s1 * ss1;
        s0 = s0 * cs0 + c0 * ss0;
        s1 = s1 * cs1 + c1 * ss1;
        c0 = t0;
        c1 = t1;
    }
}

/* Adding one kernel row: acc[j] += v_j where the sample passes the visibility test, with
 * v_j = A cx[j] - B sx[j] and the expected depth zp_j = zr + gx (i0 + j). Every path (vector or
 * scalar) does the same float operations in the same order (no FMA: the build uses
 * -ffp-contract=off), and a row's last partial vector is masked rather than finished in scalar
 * code, so a sample's value never depends on where its row starts. Masked lanes add +0.0,
 * which leaves any accumulator unchanged (sums that start at +0.0 are never -0.0); the
 * buffers have VPAD floats of slack for them. */
typedef struct row_job {
    float A, B, idk, zr, gx, tol; /* tol: hard: tolerance; soft: its inverse */
    int i0, n, mode;
} row_job;

static void row_scalar(float *restrict acc, const float *restrict zt, const float *restrict idt,
                       const float *restrict cx, const float *restrict sx, const row_job *R)
{
    for (int j = 0; j < R->n; j++) {
        float v = R->A * cx[j] - R->B * sx[j];
        if (R->mode == NPRFX_GABOR_DEPTH_OFF) {
            acc[j] += id_eq(idt[j], R->idk) ? v : 0.0f;
            continue;
        }
        float zp = R->zr + R->gx * (float)(R->i0 + j);
        float dz = fabsf(zt[j] - zp);
        if (R->mode == NPRFX_GABOR_DEPTH_HARD) {
            acc[j] += (id_eq(idt[j], R->idk) && dz <= R->tol) ? v : 0.0f;
        } else {
            float t = 2.0f - dz * R->tol;
            t = t > 0.0f ? t : 0.0f; /* as MAXPS(t, 0) */
            t = t < 1.0f ? t : 1.0f; /* as MINPS(t, 1) */
            acc[j] += id_eq(idt[j], R->idk) ? v * t : 0.0f;
        }
    }
}

#if GABOR_VEC
/* row_scalar 8 samples at a time (the baseline ISA's vectors: SSE2, NEON) */
static void row_vec(float *restrict acc, const float *restrict zt, const float *restrict idt,
                    const float *restrict cx, const float *restrict sx, const row_job *R);
#endif

/* The scalar splat of a tile's kernels: the reference every vector path reproduces bit for bit.
 * Per kernel: the disk's span on each row the tile holds, the factor tables (from the kernel's
 * own first sample, whatever the tile), then the rows (vrow: with row_vec). */
GABOR_BODY void splat_points_sbody(const gjob *J, gtile *T, const int vrow)
{
    const gconf *G = J->G;
    int s = G->ss;
    int TX0 = T->TX0, TY0 = T->TY0, TX1 = T->TX1, TY1 = T->TY1, W = T->W, tabn = T->tabn;
    float *CX = T->tab, *SX = T->tab + tabn, *CY = T->tab + 2 * tabn, *SY = T->tab + 3 * tabn;
    int *span = T->span;
    double r2 = G->r2;
    row_job R;
    R.mode = G->dtest;
    for (int by = T->bya; by <= T->byb; by++)
        for (int bx = T->bxa; bx <= T->bxb; bx++) {
            const gblock *b = &J->blocks[(by - J->by0) * J->nbx + (bx - J->bx0)];
            for (int k = 0; k < b->n; k++) {
                const gpoint *p = &b->p[k];
                if (p->X1 < TX0 || p->X0 >= TX1 || p->Y1 < TY0 || p->Y0 >= TY1) continue;
                double sx = p->sx, sy = p->sy;
                int xe = p->X1 < TX1 - 1 ? p->X1 : TX1 - 1, ye = p->Y1 < TY1 - 1 ? p->Y1 : TY1 - 1;
                int ya = p->Y0 > TY0 ? p->Y0 : TY0;
                int rows = 0;
                for (int Y = ya; Y <= ye; Y++) {
                    double dy = sample_pos(Y, s) - sy, h2 = r2 - dy * dy;
                    int xa = p->X1 + 1, xb = p->X1;
                    if (h2 >= 0.0) {
                        double hw = sqrt(h2);
                        xa = iceil((sx - hw + 0.5) * s - 0.5);
                        xb = ifloor((sx + hw + 0.5) * s - 0.5);
                        if (xa < p->X0) xa = p->X0;
                        if (xb > p->X1) xb = p->X1;
                        if (xa < TX0) xa = TX0;
                        if (xb > TX1 - 1) xb = TX1 - 1;
                        rows += xa <= xb;
                    }
                    span[2 * (Y - ya)] = xa;
                    span[2 * (Y - ya) + 1] = xb;
                }
                if (!rows) continue;
                kernel_tables(&p->ax, &p->ay, G->rr, xe - p->X0 + 1, ye - p->Y0 + 1, CX, SX, CY,
                              SY);
                R.idk = p->id;
                R.gx = (float)(p->gzx / s);
                double zx0 = p->z + p->gzx * (sample_pos(p->X0, s) - sx);
                double tolz = G->tol * p->z;
                R.tol = G->dtest == NPRFX_GABOR_DEPTH_SOFT ? (float)(tolz > 0.0 ? 1.0 / tolz : 1e30)
                                                           : (float)tolz;
                for (int Y = ya; Y <= ye; Y++) {
                    int xa = span[2 * (Y - ya)], xb = span[2 * (Y - ya) + 1];
                    if (xa > xb) continue;
                    R.n = xb - xa + 1;
                    R.i0 = xa - p->X0;
                    R.A = p->amp * CY[Y - p->Y0];
                    R.B = p->amp * SY[Y - p->Y0];
                    R.zr = (float)(zx0 + p->gzy * (sample_pos(Y, s) - sy));
                    size_t o = (size_t)(Y - TY0) * (size_t)W + (size_t)(xa - TX0);
                    T->evals += R.n;
#if GABOR_VEC
                    if (vrow)
                        row_vec(T->acc + o, T->zt + o, T->idt + o, CX + R.i0, SX + R.i0, &R);
                    else
#endif
                        row_scalar(T->acc + o, T->zt + o, T->idt + o, CX + R.i0, SX + R.i0, &R);
                }
            }
        }
}

void internal_gabor_splat_points_scalar(const gjob *J, gtile *T)
{
    splat_points_sbody(J, T, 0);
}

/* The vector splat: the same operations as the scalar path, lane by lane, in GCC/Clang vector
 * extensions (compiled once for the baseline ISA and, on x86-64, again for AVX2 and AVX-512,
 * picked at run time). A kernel's row spans and row depths are computed 8 rows at a time (in
 * double, as the scalar path: sqrt, division and truncation are exact IEEE operations, so
 * every lane rounds as the scalar code does); the factor-table recurrences of SPLAT_BATCH
 * kernels run in the lanes of one vector (x axes in the low lanes, y axes in the high ones),
 * which hides their dependency chains; the kernels are then added in their order, rows of 8
 * samples at a time with the last vector masked. */

#if GABOR_VEC
/* iceil / ifloor lane by lane: truncation, then the same comparison as the scalar code */
GV_INLINE gv8i gv_iceil_(const gv8d *pv)
{
    gv8d v = *pv;
    gv8i i = __builtin_convertvector(v, gv8i);
    return i - gv_mask(v > __builtin_convertvector(i, gv8d));
}

GV_INLINE gv8i gv_ifloor_(const gv8d *pv)
{
    gv8d v = *pv;
    gv8i i = __builtin_convertvector(v, gv8i);
    return i + gv_mask(v < __builtin_convertvector(i, gv8d));
}

#define gv_maxi(a, b) gv_seli((a) < (b), (b), (a))
#define gv_mini(a, b) gv_seli((a) > (b), (b), (a))

/* One batched kernel: its point, rows and tables. */
typedef struct gslot {
    const gpoint *p;
    int ya, ye, xe;
    int *xa, *xb;
    float *zr, *CX, *SX, *CY, *SY;
} gslot;

/* The spans and row depths of kernel p on rows ya..ye of the tile; returns the number of rows
 * with samples. As splat_points_scalar, lane by lane. */
/* The spans and row depths of kernel p on rows ya..ye of the tile, 8 rows at a time (AVX-512:
 * 32 vector registers hold the double vectors). */
GV_INLINE int gv_spans8(const gconf *G, const gpoint *p, const gtile *T, gslot *sl)
{
    const gv8d lane = {0, 1, 2, 3, 4, 5, 6, 7};
    const gv8i lanei = {0, 1, 2, 3, 4, 5, 6, 7};
    int s = G->ss;
    double sx = p->sx, sy = p->sy, r2 = G->r2, ds = (double)s;
    double zx0 = p->z + p->gzx * (sample_pos(p->X0, s) - sx), gzy = p->gzy;
    gv8i X0 = p->X0 + (gv8i){0}, X1 = p->X1 + (gv8i){0};
    gv8i tx0 = T->TX0 + (gv8i){0}, tx1 = (T->TX1 - 1) + (gv8i){0};
    gv8i cnt = {0};
    for (int Y = sl->ya; Y <= sl->ye; Y += 8) {
        gv8d sp = (double)Y + lane;
        if (s != 1) sp = (sp + 0.5) / ds - 0.5; /* sample_pos (for s = 1, the identity) */
        gv8d dy = sp - sy, h2 = r2 - dy * dy;
        gv8l ok = h2 >= 0.0;
        gv8d hw = gv_sqrt(gv_seld(ok, h2, (gv8d){0}));
        gv8d va = sx - hw + 0.5, vb = sx + hw + 0.5;
        if (s != 1) {
            va = va * ds;
            vb = vb * ds;
        }
        gv8i xa = gv_iceil(va - 0.5), xb = gv_ifloor(vb - 0.5);
        xa = gv_maxi(gv_maxi(xa, X0), tx0);
        xb = gv_mini(gv_mini(xb, X1), tx1);
        gv8i oki = __builtin_convertvector(ok, gv8i);
        xa = gv_seli(oki, xa, X1 + 1);
        xb = gv_seli(oki, xb, X1);
        gv8i in = (Y + lanei) <= sl->ye;
        cnt += in & (xa <= xb);
        gv_storei(sl->xa + (Y - sl->ya), xa);
        gv_storei(sl->xb + (Y - sl->ya), xb);
        gv_storef(sl->zr + (Y - sl->ya), __builtin_convertvector(zx0 + gzy * (sp - sy), gv8f));
    }
    int rows = 0;
    for (int k = 0; k < 8; k++)
        rows -= cnt[k];
    return rows;
}

GV_INLINE int gv_spans(const gconf *G, const gpoint *p, const gtile *T, gslot *sl)
{
    /* 4 rows at a time: the double vectors stay in registers on AVX2 too */
    const gv4d lane = {0, 1, 2, 3};
    const gv4i lanei = {0, 1, 2, 3};
    int s = G->ss;
    double sx = p->sx, sy = p->sy, r2 = G->r2, ds = (double)s;
    double zx0 = p->z + p->gzx * (sample_pos(p->X0, s) - sx), gzy = p->gzy;
    gv4i X0 = p->X0 + (gv4i){0}, X1 = p->X1 + (gv4i){0};
    gv4i tx0 = T->TX0 + (gv4i){0}, tx1 = (T->TX1 - 1) + (gv4i){0};
    gv4i cnt = {0};
    for (int Y = sl->ya; Y <= sl->ye; Y += 4) {
        gv4d sp = (double)Y + lane;
        if (s != 1) sp = (sp + 0.5) / ds - 0.5; /* sample_pos (for s = 1, the identity) */
        gv4d dy = sp - sy, h2 = r2 - dy * dy;
        gv4l ok = h2 >= 0.0;
        gv4d hw = gv_sqrt4((gv4d)((gv4l)h2 & ok));
        gv4d va = sx - hw + 0.5, vb = sx + hw + 0.5;
        if (s != 1) {
            va = va * ds;
            vb = vb * ds;
        }
        va = va - 0.5;
        vb = vb - 0.5;
        /* iceil / ifloor lane by lane: truncation, then the scalar code's comparison */
        gv4i xa = __builtin_convertvector(va, gv4i), xb = __builtin_convertvector(vb, gv4i);
        xa -= __builtin_convertvector(va > __builtin_convertvector(xa, gv4d), gv4i);
        xb += __builtin_convertvector(vb < __builtin_convertvector(xb, gv4d), gv4i);
        xa = gv4_maxi(gv4_maxi(xa, X0), tx0);
        xb = gv4_mini(gv4_mini(xb, X1), tx1);
        gv4i oki = __builtin_convertvector(ok, gv4i);
        xa = (xa & oki) | ((X1 + 1) & ~oki);
        xb = (xb & oki) | (X1 & ~oki);
        cnt += ((Y + lanei) <= sl->ye) & (xa <= xb);
        memcpy(sl->xa + (Y - sl->ya), &xa, sizeof xa);
        memcpy(sl->xb + (Y - sl->ya), &xb, sizeof xb);
        gv4f zr = __builtin_convertvector(zx0 + gzy * (sp - sy), gv4f);
        memcpy(sl->zr + (Y - sl->ya), &zr, sizeof zr);
    }
    return -(cnt[0] + cnt[1] + cnt[2] + cnt[3]);
}

/* The factor tables of nb <= SPLAT_BATCH kernels, the recurrences of kernel_tables in the lanes
 * of two vectors (x and y axes). */
GV_INLINE void gv_tables(const gconf *G, gslot *sl, int nb)
{
    gv4d gx = {0}, rx = {0}, cx = {0}, sx = {0}, csx = {0}, ssx = {0};
    gv4d gy = {0}, ry = {0}, cy = {0}, sy = {0}, csy = {0}, ssy = {0};
    int n = 0;
    for (int k = 0; k < nb; k++) {
        const gpoint *p = sl[k].p;
        gx[k] = p->ax.g, rx[k] = p->ax.r, cx[k] = p->ax.c, sx[k] = p->ax.s;
        csx[k] = p->ax.cs, ssx[k] = p->ax.ss;
        gy[k] = p->ay.g, ry[k] = p->ay.r, cy[k] = p->ay.c, sy[k] = p->ay.s;
        csy[k] = p->ay.cs, ssy[k] = p->ay.ss;
        int nx = sl[k].xe - p->X0 + 1, ny = sl[k].ye - p->Y0 + 1;
        if (nx > n) n = nx;
        if (ny > n) n = ny;
    }
    double rr = G->rr;
    for (int i = 0; i < n; i++) {
        gv4f gcx = __builtin_convertvector(gx * cx, gv4f),
             gsx = __builtin_convertvector(gx * sx, gv4f);
        gv4f gcy = __builtin_convertvector(gy * cy, gv4f),
             gsy = __builtin_convertvector(gy * sy, gv4f);
        for (int k = 0; k < SPLAT_BATCH; k++) {
            if (k >= nb) break;
            sl[k].CX[i] = gcx[k];
            sl[k].SX[i] = gsx[k];
            sl[k].CY[i] = gcy[k];
            sl[k].SY[i] = gsy[k];
        }
        gx = gx * rx;
        rx = rx * rr;
        gy = gy * ry;
        ry = ry * rr;
        gv4d tx = cx * csx - sx * ssx, ty = cy * csy - sy * ssy;
        sx = sx * csx + cx * ssx;
        sy = sy * csy + cy * ssy;
        cx = tx;
        cy = ty;
    }
}

/* Add the rows of one batched kernel to the tile, as row_scalar does. */
/* One vector of a kernel row: 8 samples, the lanes in m (a constant depth-test mode) */
typedef struct gv_rowc {
    gv8f va, vb, vid, vzr, vgx, vtol; /* a row's constants, broadcast */
} gv_rowc;

GV_INLINE void gv_row8(float *acc, const float *zt, const float *idt, const float *cx,
                       const float *sx, const gv_rowc *R, const gv8f *pvi, const gv8i *pm,
                       const int mode)
{
    gv8f va = R->va, vb = R->vb, vid = R->vid, vzr = R->vzr, vgx = R->vgx, vtol = R->vtol;
    gv8f vi = *pvi;
    gv8i m = *pm;
    const gv8i sign = (gv8i){0} + (int32_t)0x7fffffff;
    const gv8f one = (gv8f){0} + 1.0f, two = (gv8f){0} + 2.0f, zero = {0};
    gv8f v = va * gv_loadf(cx) - vb * gv_loadf(sx);
    m &= gv_loadid(idt) == (gv8i)vid;
    if (mode != NPRFX_GABOR_DEPTH_OFF) {
        gv8f zp = vzr + vgx * vi;
        gv8f dz = (gv8f)((gv8i)(gv_loadf(zt) - zp) & sign);
        if (mode == NPRFX_GABOR_DEPTH_HARD) {
            m &= dz <= vtol;
        } else {
            gv8f t = two - dz * vtol;
            t = gv_self(t > zero, t, zero);
            t = gv_self(t < one, t, one);
            v = v * t;
        }
    }
    gv_storef(acc, gv_loadf(acc) + gv_self(m, v, zero));
}

GV_INLINE void gv_rows(const gconf *G, const gslot *sl, gtile *T, const int mode)
{
    const gpoint *p = sl->p;
    const gv8f lanef = {0, 1, 2, 3, 4, 5, 6, 7};
    const gv8i lanei = {0, 1, 2, 3, 4, 5, 6, 7};
    int s = G->ss;
    float gx = (float)(p->gzx / s);
    double tolz = G->tol * p->z;
    float tol =
        mode == NPRFX_GABOR_DEPTH_SOFT ? (float)(tolz > 0.0 ? 1.0 / tolz : 1e30) : (float)tolz;
    gv8f zero = {0};
    gv_rowc R;
    R.vid = gv_splatid(p->id);
    R.vgx = gx + zero;
    R.vtol = tol + zero;
    long long evals = 0;
    for (int Y = sl->ya; Y <= sl->ye; Y++) {
        int xa = sl->xa[Y - sl->ya], xb = sl->xb[Y - sl->ya];
        if (xa > xb) continue;
        int n = xb - xa + 1, i0 = xa - p->X0;
        float A = p->amp * sl->CY[Y - p->Y0], B = p->amp * sl->SY[Y - p->Y0];
        R.va = A + zero;
        R.vb = B + zero;
        R.vzr = sl->zr[Y - sl->ya] + zero;
        size_t o = (size_t)(Y - T->TY0) * (size_t)T->W + (size_t)(xa - T->TX0);
        float *acc = T->acc + o;
        const float *zt = T->zt + o, *idt = T->idt + o;
        const float *cx = sl->CX + i0, *sx = sl->SX + i0;
        gv8f vi = (float)i0 + lanef; /* exact: small integers */
        evals += n;
        int j = 0;
        const gv8i all = (gv8i){0} - 1;
        for (; j + 8 <= n; j += 8, vi = vi + 8.0f)
            gv_row8(acc + j, zt + j, idt + j, cx + j, sx + j, &R, &vi, &all, mode);
        if (j < n) { /* the last partial vector, masked */
            gv8i tail = (j + lanei) < n;
            gv_row8(acc + j, zt + j, idt + j, cx + j, sx + j, &R, &vi, &tail, mode);
        }
    }
    T->evals += evals;
}

GV_INLINE void splat_points_body(const gjob *J, gtile *T, const int mode, const int wide)
{
    const gconf *G = J->G;
    int TX0 = T->TX0, TY0 = T->TY0, TX1 = T->TX1, TY1 = T->TY1, tabn = T->tabn;
    gslot sl[SPLAT_BATCH];
    for (int k = 0; k < SPLAT_BATCH; k++) {
        float *t = T->tab + (size_t)k * 5 * (size_t)tabn;
        sl[k].CX = t;
        sl[k].SX = t + tabn;
        sl[k].CY = t + 2 * tabn;
        sl[k].SY = t + 3 * tabn;
        sl[k].zr = t + 4 * tabn;
        sl[k].xa = T->span + (size_t)k * 2 * (size_t)tabn;
        sl[k].xb = sl[k].xa + tabn;
    }
    int nb = 0;
    for (int by = T->bya; by <= T->byb; by++)
        for (int bx = T->bxa; bx <= T->bxb; bx++) {
            const gblock *b = &J->blocks[(by - J->by0) * J->nbx + (bx - J->bx0)];
            for (int k = 0; k < b->n; k++) {
                const gpoint *p = &b->p[k];
                if (p->X1 < TX0 || p->X0 >= TX1 || p->Y1 < TY0 || p->Y0 >= TY1) continue;
                gslot *q = &sl[nb];
                q->p = p;
                q->xe = p->X1 < TX1 - 1 ? p->X1 : TX1 - 1;
                q->ye = p->Y1 < TY1 - 1 ? p->Y1 : TY1 - 1;
                q->ya = p->Y0 > TY0 ? p->Y0 : TY0;
                if (!(wide ? gv_spans8(G, p, T, q) : gv_spans(G, p, T, q))) continue;
                if (++nb < SPLAT_BATCH) continue;
                gv_tables(G, sl, nb);
                for (int m = 0; m < nb; m++)
                    gv_rows(G, &sl[m], T, mode);
                nb = 0;
            }
        }
    if (nb) {
        gv_tables(G, sl, nb);
        for (int m = 0; m < nb; m++)
            gv_rows(G, &sl[m], T, mode);
    }
}

/* (4 lanes: the baseline ISA's native vector width, so that no operation is split lane by
 * lane) */
static void row_vec(float *restrict acc, const float *restrict zt, const float *restrict idt,
                    const float *restrict cx, const float *restrict sx, const row_job *R)
{
    const gv4i lane = {0, 1, 2, 3}, sign = (gv4i){0} + (int32_t)0x7fffffff;
    const gv4f one = (gv4f){0} + 1.0f, two = (gv4f){0} + 2.0f, zero = {0};
    gv4f va = R->A + zero, vb = R->B + zero;
    gv4i vid = (gv4i){0} + (int32_t)id_bits(R->idk);
    gv4f vzr = R->zr + zero, vgx = R->gx + zero, vtol = R->tol + zero;
    gv4f vi = (float)R->i0 + __builtin_convertvector(lane, gv4f); /* exact: small integers */
    int n = R->n;
    for (int j = 0; j < n; j += 4, vi = vi + 4.0f) {
        gv4f c, s_, z, d, a;
        memcpy(&c, cx + j, sizeof c);
        memcpy(&s_, sx + j, sizeof s_);
        memcpy(&d, idt + j, sizeof d);
        gv4f v = va * c - vb * s_;
        gv4i m = ((gv4i)d == vid) & ((j + lane) < n);
        if (R->mode != NPRFX_GABOR_DEPTH_OFF) {
            memcpy(&z, zt + j, sizeof z);
            gv4f dz = (gv4f)((gv4i)(z - (vzr + vgx * vi)) & sign);
            if (R->mode == NPRFX_GABOR_DEPTH_HARD) {
                m &= dz <= vtol;
            } else {
                gv4f t = two - dz * vtol;
                gv4i up = t > zero, lo = t < one;
                t = (gv4f)((gv4i)t & up);                       /* t > 0 ? t : 0 */
                t = (gv4f)(((gv4i)t & lo) | ((gv4i)one & ~lo)); /* t < 1 ? t : 1 */
                v = v * t;
            }
        }
        memcpy(&a, acc + j, sizeof a);
        a = a + (gv4f)((gv4i)v & m);
        memcpy(acc + j, &a, sizeof a);
    }
}

/* The baseline ISA's path: the scalar spans and tables, vector rows. */
void internal_gabor_splat_points_rows(const gjob *J, gtile *T)
{
    splat_points_sbody(J, T, 1);
}

#if GABOR_X86
__attribute__((target("avx2"))) void internal_gabor_splat_points_avx2(const gjob *J, gtile *T)
{
    switch (J->G->dtest) {
    case NPRFX_GABOR_DEPTH_OFF:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_OFF, 0);
        break;
    case NPRFX_GABOR_DEPTH_HARD:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_HARD, 0);
        break;
    default:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_SOFT, 0);
        break;
    }
}

__attribute__((target("avx512f,avx512vl,avx512bw,avx512dq"))) void
internal_gabor_splat_points_avx512(const gjob *J, gtile *T)
{
    switch (J->G->dtest) {
    case NPRFX_GABOR_DEPTH_OFF:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_OFF, 1);
        break;
    case NPRFX_GABOR_DEPTH_HARD:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_HARD, 1);
        break;
    default:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_SOFT, 1);
        break;
    }
}
#endif
#endif /* GABOR_VEC */
