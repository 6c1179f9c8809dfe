/* The stationary resampler's tables (coherent noise): per 1/INTERNAL_TAB pixel of fractional
 * offset, the interpolation weights (Catmull-Rom, or the paper's bilinear lookup) and the 4-tap
 * compensation filter G with |H|^2 + |G|^2 = 1, the closed-form spectral factor of the power the
 * interpolation removes. */
#include <math.h>
#include <pthread.h>

#include "internal_coherent_noise.h"

static void internal_catmull_rom(double t, double *w)
{
    double t2 = t * t, t3 = t2 * t;
    w[0] = 0.5 * (-t3 + 2.0 * t2 - t);
    w[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
    w[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
    w[3] = 0.5 * (t3 - t2);
}

typedef struct internal_cplx {
    double re, im;
} internal_cplx;

static internal_cplx internal_csqrt(internal_cplx z)
{
    double m = hypot(z.re, z.im);
    internal_cplx r;
    r.re = sqrt(fmax(0.0, 0.5 * (m + z.re)));
    r.im = sqrt(fmax(0.0, 0.5 * (m - z.re)));
    if (z.im < 0.0) r.im = -r.im;
    return r;
}

/* z with z + 1/z = s and |z| <= 1. */
static internal_cplx internal_root_inside(internal_cplx s)
{
    internal_cplx d = {s.re * s.re - s.im * s.im - 4.0, 2.0 * s.re * s.im};
    d = internal_csqrt(d);
    internal_cplx a = {0.5 * (s.re + d.re), 0.5 * (s.im + d.im)};
    internal_cplx b = {0.5 * (s.re - d.re), 0.5 * (s.im - d.im)};
    return hypot(a.re, a.im) <= hypot(b.re, b.im) ? a : b;
}

/* Spectral factor of the power an interpolation filter b (4 taps) removes from white noise:
 * g with |G(w)|^2 = 1 - |B(w)|^2. Because B(0) = 1 the loss has a double zero at w = 0, so
 * L = (2 - 2cos w) Q(w) with Q of degree 2; Q is factored in closed form (s = z + 1/z turns its
 * quartic into a quadratic) and G = (1 - z) * (the minimum-phase factor of Q), scaled to the
 * exact lost variance. */
static void internal_factor_loss(const double *b, double *g)
{
    double r[4];
    for (int l = 0; l < 4; l++) {
        r[l] = 0.0;
        for (int j = 0; j + l < 4; j++)
            r[l] += b[j] * b[j + l];
    }
    double rho0 = 1.0 - r[0], rho1 = -r[1], rho2 = -r[2], rho3 = -r[3];
    g[0] = g[1] = g[2] = g[3] = 0.0;
    if (rho0 < 1e-14) return;
    double q2 = -rho3, q1 = 2.0 * q2 - rho2, q0 = -q2 + 2.0 * q1 - rho1;
    double p[3];
    if (fabs(q2) < 1e-15) {
        /* Q(z) = q1 (z + 1/z) + q0: one root pair. */
        internal_cplx s = {fabs(q1) > 1e-300 ? -q0 / q1 : 2.0, 0.0};
        internal_cplx z = internal_root_inside(s);
        p[0] = -z.re;
        p[1] = 1.0;
        p[2] = 0.0;
    } else {
        double disc = q1 * q1 - 4.0 * q2 * (q0 - 2.0 * q2);
        internal_cplx s1, s2;
        if (disc >= 0.0) {
            double sq = sqrt(disc);
            s1.re = (-q1 + sq) / (2.0 * q2);
            s2.re = (-q1 - sq) / (2.0 * q2);
            s1.im = s2.im = 0.0;
        } else {
            double sq = sqrt(-disc);
            s1.re = s2.re = -q1 / (2.0 * q2);
            s1.im = sq / (2.0 * q2);
            s2.im = -s1.im;
        }
        internal_cplx z1 = internal_root_inside(s1), z2 = internal_root_inside(s2);
        /* (z - z1)(z - z2), ascending powers; the product is real for conjugate or real roots. */
        p[0] = z1.re * z2.re - z1.im * z2.im;
        p[1] = -(z1.re + z2.re);
        p[2] = 1.0;
    }
    double gg[4] = {p[0], p[1] - p[0], p[2] - p[1], -p[2]};
    double s2 = gg[0] * gg[0] + gg[1] * gg[1] + gg[2] * gg[2] + gg[3] * gg[3];
    double c = s2 > 0.0 ? sqrt(rho0 / s2) : 0.0;
    for (int k = 0; k < 4; k++)
        g[k] = gg[k] * c;
}

static void internal_make_taps(int resample, internal_taps *tab)
{
    for (int i = 0; i <= INTERNAL_TAB; i++) {
        double t = (double)i / INTERNAL_TAB, b[4], g[4];
        if (resample == NPRFX_CN_RESAMPLE_BILINEAR) {
            b[0] = 1.0 - t;
            b[1] = t;
            b[2] = b[3] = 0.0;
            double s = sqrt(t * (1.0 - t));
            g[0] = s;
            g[1] = -s;
            g[2] = g[3] = 0.0;
        } else {
            internal_catmull_rom(t, b);
            internal_factor_loss(b, g);
        }
        for (int k = 0; k < 4; k++) {
            tab[i].b[k] = (float)b[k];
            tab[i].g[k] = (float)g[k];
        }
    }
}

/* The two tables are computed once per process (pthread_once: pure functions of the resampler). */
/* Two spare entries: the vector path loads 64 bytes from an entry's b. */
static internal_taps internal_tab_stationary[INTERNAL_TAB + 3],
    internal_tab_bilinear[INTERNAL_TAB + 3];
static pthread_once_t internal_tab_once = PTHREAD_ONCE_INIT;

static void internal_tabs_init(void)
{
    internal_make_taps(NPRFX_CN_RESAMPLE_STATIONARY, internal_tab_stationary);
    internal_make_taps(NPRFX_CN_RESAMPLE_BILINEAR, internal_tab_bilinear);
}

const internal_taps *internal_cn_taps_for(int resample)
{
    pthread_once(&internal_tab_once, internal_tabs_init);
    return resample == NPRFX_CN_RESAMPLE_BILINEAR ? internal_tab_bilinear : internal_tab_stationary;
}
