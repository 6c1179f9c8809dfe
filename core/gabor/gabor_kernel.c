/* The Gabor kernel's arithmetic: the default params, the bandwidth and the theoretical variance
 * of the sum (with the box filter of supersampling), the tables of the level-of-detail rule and
 * its public weights (the rule itself is inline in internal_gabor.h, for emission), and the setup
 * of one kernel at emission: its wave vector, amplitude and the start values of its separable
 * factors. */
#include <math.h>
#include <string.h>

#include "internal_gabor.h"
#include "base/internal_vmath.h"
#include "nprfx/rng.h"

static const double k_cutoff = 0.05; /* kernel envelope at the truncation radius */

/* ---- parameters ------------------------------------------------------------------------------ */

void nprfx_gabor_params_default(nprfx_gabor_params *p)
{
    memset(p, 0, sizeof *p);
    p->size = sizeof *p;
    p->anchor_dims = 3;
    p->frequency = 0.1;
    p->orientation = 0.0;
    p->isotropic = 0;
    p->radius = 16.0;
    p->n0 = 32.0;
    p->seed = 0;
    p->cell = 1.0;
    p->lod_levels = 4;
    p->fade = NPRFX_GABOR_FADE_LEVEL;
    p->depth_test = NPRFX_GABOR_DEPTH_HARD;
    p->depth_tolerance = 0.05;
    p->supersample = 1;
    p->amplitude = NPRFX_GABOR_AMP_UNIFORM;
    p->output = NPRFX_GABOR_OUT_UNIT;
    p->contrast = 0.15;
    p->points = 0;
}

/* A frequency param in cycles per pixel at the host's render scale: the radius is scaled by the
 * host (a PIXELS param), so a frequency per pixel scales inversely. */
double nprfx_gabor_frequency_at_scale(double frequency, double render_scale)
{
    double scale = render_scale > 0.0 ? render_scale : 1.0;
    return frequency / scale;
}

double nprfx_gabor_bandwidth(double radius)
{
    /* exp(-pi a^2 r^2) = 0.05 at the truncation radius */
    return sqrt(-log(k_cutoff) / k_pi) / radius;
}

static double amplitude_power(int law)
{
    return law == NPRFX_GABOR_AMP_UNIFORM ? 1.0 / 3.0 : 1.0;
}

/* |h(f)|^2 of the average of s samples spaced 1/s: the box filter of supersampling. */
static double box_gain2(double f, int s)
{
    double d = s * sin(k_pi * f / s);
    if (fabs(d) < 1e-12) return 1.0;
    double h = sin(k_pi * f) / d;
    return h * h;
}

/* Fraction of the noise's variance left after averaging s x s samples per pixel: the kernel's
 * power spectrum |G(f)|^2 (two Gaussian lobes at +-F0 w0, width a) weighted by the box filter's
 * response, integrated numerically (isotropic: averaged over orientations). */
static double supersample_attenuation(double F, double a, double w0, int iso, int s)
{
    if (s <= 1) return 1.0;
    const int n = 48;
    double sd = a / (2.0 * sqrt(k_pi)); /* std of exp(-2 pi f^2 / a^2) */
    double range = F + 5.0 * sd, step = 2.0 * range / n;
    int nang = iso ? 8 : 1;
    double num = 0.0, den = 0.0;
    for (int k = 0; k < nang; k++) {
        double th = iso ? k_pi * k / nang : w0;
        double f0x = F * cos(th), f0y = -F * sin(th);
        for (int j = 0; j <= n; j++) {
            double fy = -range + j * step;
            double hy = box_gain2(fy, s);
            for (int i = 0; i <= n; i++) {
                double fx = -range + i * step;
                double e1 =
                    exp(-k_pi * ((fx - f0x) * (fx - f0x) + (fy - f0y) * (fy - f0y)) / (a * a));
                double e2 =
                    exp(-k_pi * ((fx + f0x) * (fx + f0x) + (fy + f0y) * (fy + f0y)) / (a * a));
                double g2 = (e1 + e2) * (e1 + e2);
                num += g2 * box_gain2(fx, s) * hy;
                den += g2;
            }
        }
    }
    return den > 0.0 ? num / den : 1.0;
}

double internal_gabor_variance_k1(const nprfx_gabor_params *p, double a)
{
    double lambda = p->n0 / (k_pi * p->radius * p->radius);
    double trunc = 1.0 - k_cutoff * k_cutoff; /* the disk holds 1 - 0.05^2 of the envelope^2 */
    double att = supersample_attenuation(p->frequency, a, p->orientation * k_pi / 180.0,
                                         p->isotropic, p->supersample);
    return lambda * amplitude_power(p->amplitude) / (4.0 * a * a) * trunc * att;
}

double nprfx_gabor_variance(const nprfx_gabor_params *p, double frequency_scale)
{
    double a = nprfx_gabor_bandwidth(p->radius);
    double F = p->frequency * frequency_scale;
    return internal_gabor_variance_k1(p, a) * (1.0 + exp(-2.0 * k_pi * F * F / (a * a)));
}

/* ---- level of detail: the tables (internal_gabor.h has the rule) ----------------------------- */

/* Staggered fade: point k's amplitude is w = clamp((x - u_k (1 - d)) / d, 0, 1) with u_k
 * uniform in [0, 1) and d = STAGGER, so E[w^2] = (G(x) - G(x - 1 + d)) / (1 - d) with
 * G(y) = integral of clamp(v / d, 0, 1)^2 dv up to y. */
static double stagger_g(double y)
{
    const double d = STAGGER;
    if (y <= 0.0) return 0.0;
    if (y <= d) return y * y * y / (3.0 * d * d);
    return d / 3.0 + (y - d);
}

static double stagger_mean(double x)
{
    return (stagger_g(x) - stagger_g(x - 1.0 + STAGGER)) / (1.0 - STAGGER);
}

void internal_gabor_lod_table_init(lod_table *t, int W)
{
    t->W = W;
    for (int L = 0; L < MAX_LEVEL + 2; L++) {
        int l0 = L - W > 0 ? L - W : 0;
        t->p4[L] = ldexp(1.0, 2 * L);
        t->S[L] = (ldexp(1.0, 2 * (L + 1)) - ldexp(1.0, 2 * l0)) / 3.0;
    }
    for (int i = 0; i <= STAGGER_N; i++) {
        double q = (double)i / STAGGER_N, lo = 0.0, hi = 1.0;
        for (int it = 0; it < 50; it++) { /* stagger_mean is increasing */
            double mid = 0.5 * (lo + hi);
            if (stagger_mean(mid) < q)
                lo = mid;
            else
                hi = mid;
        }
        t->x[i] = 0.5 * (lo + hi);
    }
}

int nprfx_gabor_lod_weights(double mu, int lod_levels, int *first_level, double *w2, int max)
{
    int L, lo, hi;
    double f;
    lod_table t;
    if (lod_levels < 1) lod_levels = 1;
    internal_gabor_lod_table_init(&t, lod_levels);
    lod_regime(&t, mu, &L, &f);
    lod_range(L, f, lod_levels, &lo, &hi);
    if (first_level) *first_level = lo;
    int n = 0;
    for (int l = lo; l <= hi && n < max; l++)
        w2[n++] = lod_w2(L, f, lod_levels, l);
    return n;
}

/* ---- a kernel's setup, at emission ----------------------------------------------------------- */

/* Wave vector (cycles per pixel, pixel axes with y down) of a kernel owned at real pixel
 * (rx, ry): orientation from the param, the orientation input or (isotropic) the point's hash;
 * frequency from the param times the frequency input. */
static void kernel_wave(const gconf *G, int rx, int ry, uint64_t h, double *kx, double *ky)
{
    if (G->uniform_wave) {
        *kx = G->kx0;
        *ky = G->ky0;
        return;
    }
    double th = G->w0;
    if (G->iso) {
        th = k_pi * nprfx_u01(nprfx_mix64(h ^ 0x3c6ef372fe94f82bull));
    } else if (G->S.orient) {
        const nprfx_image *o = G->S.orient;
        if (o->channels >= 2) {
            float dx = sample_input(o, rx, ry, 0, 0.0f), dy = sample_input(o, rx, ry, 1, 0.0f);
            if (dx != 0.0f || dy != 0.0f) th += atan2(-(double)dy, (double)dx);
        } else {
            th += sample_input(o, rx, ry, 0, 0.0f) * (k_pi / 180.0);
        }
    }
    double sc = G->S.freq ? sample_input(G->S.freq, rx, ry, 0, 1.0f) : 1.0;
    if (sc < 0.0) sc = 0.0;
    if (sc > 1e3) sc = 1e3;
    double F = G->F0 * sc;
    *kx = F * cos(th);
    *ky = -F * sin(th); /* counter-clockwise in the image: y points down */
}

static double amplitude(int law, uint64_t h)
{
    uint64_t h2 = nprfx_mix64(h ^ 0xa54ff53a5f1d36f1ull);
    switch (law) {
    case NPRFX_GABOR_AMP_SIGN:
        return (h2 >> 63) ? 1.0 : -1.0;
    case NPRFX_GABOR_AMP_GAUSS: {
        double u1 = ((double)(h2 >> 11) + 0.5) * (1.0 / 9007199254740992.0);
        double u2 = nprfx_u01(nprfx_mix64(h2));
        return sqrt(-2.0 * log(u1)) * cos(2.0 * k_pi * u2);
    }
    default:
        return 2.0 * nprfx_u01(h2) - 1.0;
    }
}

int internal_gabor_point_begin(const gconf *G, const gpixels *X, int o, int ox, int oy, double sx,
                               double sy, double w2, uint64_t h, float id, gpoint *pt, double *args)
{
    double z = X->z[o] + X->gz[0][o] * (sx - ox) + X->gz[1][o] * (sy - oy);
    if (!is_surface_depth(z)) return 0;
    int s = G->ss;
    double r = G->radius;
    pt->sx = (float)sx;
    pt->sy = (float)sy;
    /* everything below derives from the float position, which is what splatting sees */
    sx = pt->sx;
    sy = pt->sy;
    pt->X0 = iceil((sx - r + 0.5) * s - 0.5);
    pt->X1 = ifloor((sx + r + 0.5) * s - 0.5);
    pt->Y0 = iceil((sy - r + 0.5) * s - 0.5);
    pt->Y1 = ifloor((sy + r + 0.5) * s - 0.5);
    pt->w2 = (float)w2;
    pt->amp = (float)(amplitude(G->amp, h) * sqrt(w2));
    pt->z = (float)z;
    pt->gzx = X->gz[0][o];
    pt->gzy = X->gz[1][o];
    pt->id = id;
    pt->ox = ox;
    pt->oy = oy;
    pt->rx = X->rx[o];
    pt->ry = X->ry[o];
    pt->h = h;
    double kx, ky;
    kernel_wave(G, X->rx[o], X->ry[o], h, &kx, &ky);
    /* per axis: the envelope exp(-pi a^2 d^2) at the first sample (offset d0) and its ratio to
     * the next, the phase k d0, and (when the wave varies) the phase step */
    double step = 1.0 / s, k[2] = {2.0 * k_pi * kx, 2.0 * k_pi * ky};
    double d0[2] = {sample_pos(pt->X0, s) - sx, sample_pos(pt->Y0, s) - sy};
    for (int a = 0; a < 2; a++) {
        args[GABOR_ARG_ENV + 2 * a] = -G->pa2 * d0[a] * d0[a];
        args[GABOR_ARG_ENV + 2 * a + 1] = -G->pa2 * (2.0 * d0[a] * step + step * step);
        args[GABOR_ARG_PHASE + a] = k[a] * d0[a];
        args[GABOR_ARG_STEP + a] = k[a] * step;
    }
    return 1;
}

void internal_gabor_point_end(const gconf *G, gpoint *pt, const double *ex, const double *sn,
                              const double *cs)
{
    gaxis *ax[2] = {&pt->ax, &pt->ay};
    for (int a = 0; a < 2; a++) {
        ax[a]->g = (float)ex[2 * a];
        ax[a]->r = (float)ex[2 * a + 1];
        ax[a]->c = (float)cs[a];
        ax[a]->s = (float)sn[a];
        if (G->uniform_wave) {
            ax[a]->cs = a ? G->csy : G->csx;
            ax[a]->ss = a ? G->ssy : G->ssx;
        } else {
            ax[a]->cs = (float)cs[2 + a];
            ax[a]->ss = (float)sn[2 + a];
        }
    }
}

int internal_gabor_make_point(const gconf *G, const gpixels *X, int o, int ox, int oy, double sx,
                              double sy, double w2, uint64_t h, float id, gpoint *pt)
{
    double args[GABOR_ARGS], ex[4], sn[4], cs[4];
    if (!internal_gabor_point_begin(G, X, o, ox, oy, sx, sy, w2, h, id, pt, args)) return 0;
    for (int i = 0; i < 4; i++)
        ex[i] = internal_vm_exp(args[GABOR_ARG_ENV + i]);
    int nt = G->uniform_wave ? 2 : 4;
    for (int i = 0; i < nt; i++)
        internal_vm_sincos(args[GABOR_ARG_PHASE + i], &sn[i], &cs[i]);
    internal_gabor_point_end(G, pt, ex, sn, cs);
    return 1;
}
