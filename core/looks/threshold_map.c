/* Threshold functions and X-toon map lookup (style cookbook §3). See nprfx/threshold.h. */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <string.h>

#include "nprfx/threshold.h"
#include "nprfx/exec.h"
#include "base/internal_state.h"
#include "base/internal_simd.h"
#include "internal_threshold.h"

#define NPRFX_INV_SQRT_PI 0.56418958354775628695

/* The formulas are static inline so that the node's pixel loop inlines them; the public functions
 * call the same ones (a public function stays a call in the loop: it may be interposed). */
static inline double threshold_erf(double p, double sigma, double mu)
{
    return (erf(sigma * (p - mu)) + 1.0) / 2.0;
}

double nprfx_threshold_erf(double p, double sigma, double mu)
{
    return threshold_erf(p, sigma, mu);
}

/* K(y) = integral from y to +inf of erfc(t) dt = exp(-y^2)/sqrt(pi) - y erfc(y). Positive and
 * decreasing; for large y the two terms nearly cancel (K ~ exp(-y^2) / (2 sqrt(pi) y^2)), which
 * costs about log10(2 y^2) digits: under 3 for the y < 27 this file evaluates it at. */
static double erfc_tail_integral(double y)
{
    return exp(-y * y) * NPRFX_INV_SQRT_PI - y * erfc(y);
}

/* Mean of the threshold over p in [0,1] for mu >= 0.5, where both K arguments make the
 * difference well conditioned: threshold = erfc(sigma (mu - p)) / 2, and substituting
 * y = sigma (mu - p) gives (K(sigma (mu - 1)) - K(sigma mu)) / (2 sigma). */
static double mean_upper(double sigma, double mu)
{
    return (erfc_tail_integral(sigma * (mu - 1.0)) - erfc_tail_integral(sigma * mu)) /
           (2.0 * sigma);
}

double nprfx_threshold_erf_mean(double sigma, double mu)
{
    /* The threshold satisfies t(p, mu) = 1 - t(1 - p, 1 - mu), so the mean over [0,1] does too;
     * evaluating on the mu >= 0.5 side keeps the tail small numbers accurate. */
    if (mu >= 0.5) return mean_upper(sigma, mu);
    return 1.0 - mean_upper(sigma, 1.0 - mu);
}

/* Solve mean_upper(sigma, mu) = t for t in (0, 0.5], mu >= 0.5. mean_upper decreases in mu and
 * is log-concave (the mean is the survival function of uniform + Gaussian), so Newton on its
 * logarithm converges fast even deep in the Gaussian tail, where Newton on the mean itself
 * would crawl. A bracket [lo, hi] keeps each step safe; steps leaving it fall back to
 * bisection. */
static double solve_upper(double t, double sigma)
{
    /* mean(1 - t) >= t for mu >= 0.5 (the mean falls slower than 1 - mu there), so 1 - t is
     * at or left of the root; in the middle of [0,1] it is the root to double precision. */
    double mu = 1.0 - t;
    /* mean(mu) = (1 - mu) + (K(sigma (1 - mu)) - K(sigma mu)) / (2 sigma) since K(y) = -2y +
     * K(-y); with sigma t >= 6 both K terms are below K(6) ~ 4e-18: mu = 1 - t is exact. */
    if (sigma * t >= 6.0) return mu;
    double lo = mu;
    double hi = 1.0 + 26.0 / sigma; /* mean there is ~1e-297: below any tone worth showing */
    if (mean_upper(sigma, hi) >= t) return hi;
    const double log_t = log(t);
    for (int it = 0; it < 200; it++) {
        double m = mean_upper(sigma, mu);
        if (fabs(m - t) <= 1e-15 * t) break;
        if (m > t)
            lo = mu;
        else
            hi = mu;
        /* d mean / d mu = (erfc(sigma mu) - erfc(sigma (mu - 1))) / 2 < 0 */
        double dm = 0.5 * (erfc(sigma * mu) - erfc(sigma * (mu - 1.0)));
        double next = mu;
        if (m > 0.0 && dm < 0.0) next = mu - (log(m) - log_t) * m / dm;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (next == mu || hi - lo <= 1e-15 * hi) break;
        mu = next;
    }
    return mu;
}

double nprfx_threshold_builtin_mu(double tone, double sigma)
{
    /* tone 0 / 1 must give exactly 0 / 1: put the step 40 / sigma beyond the end, where
     * erf(40) rounds to 1 in double precision. */
    if (!(tone > 0.0)) return 1.0 + 40.0 / sigma;
    if (tone >= 1.0) return -40.0 / sigma;
    if (tone <= 0.5) return solve_upper(tone, sigma);
    return 1.0 - solve_upper(1.0 - tone, sigma);
}

double nprfx_threshold_builtin(double p, double tone, double sigma)
{
    return nprfx_threshold_erf(p, sigma, nprfx_threshold_builtin_mu(tone, sigma));
}

/* ---- the step position as a table (internal_threshold.h) ------------------------------------ */

/* mu for tone t <= 0.5 is solve_upper(t), and 1 - solve_upper(1 - t) above: only solve_upper
 * is tabled, as a function of s = log t. Its slope: mean_upper(sigma, mu) = t, so
 * d mu / d s = t / (d mean / d mu), where d mean / d mu = (erfc(sigma mu) - erfc(sigma (mu - 1)))
 * / 2. */
void internal_mu_table_init(internal_mu_table *tab, double sigma)
{
    tab->sigma = sigma;
    tab->t_max = 6.0 / sigma < 0.5 ? 6.0 / sigma : 0.5;
    tab->n = 0;
    if (!(tab->t_max > MU_TABLE_T_MIN)) return;
    tab->n = MU_TABLE_N;
    tab->s0 = log(MU_TABLE_T_MIN);
    double h = (log(tab->t_max) - tab->s0) / MU_TABLE_N;
    tab->inv_h = 1.0 / h;
    for (int i = 0; i <= MU_TABLE_N; i++) {
        double t = i == MU_TABLE_N ? tab->t_max : exp(tab->s0 + i * h);
        double mu = solve_upper(t, sigma);
        double dm = 0.5 * (erfc(sigma * mu) - erfc(sigma * (mu - 1.0)));
        tab->mu[i] = mu;
        tab->dmu[i] = dm < 0.0 ? t / dm : 0.0;
    }
}

static double table_upper(const internal_mu_table *tab, double t)
{
    if (tab->n == 0 || t < MU_TABLE_T_MIN || t >= tab->t_max) return solve_upper(t, tab->sigma);
    double x = (log(t) - tab->s0) * tab->inv_h;
    int i = (int)x;
    if (i >= tab->n) i = tab->n - 1;
    if (i < 0) i = 0;
    double u = x - i, u2 = u * u, u3 = u2 * u;
    double h = 1.0 / tab->inv_h;
    /* cubic Hermite on [s_i, s_i+1] with the exact end values and slopes */
    return (2 * u3 - 3 * u2 + 1) * tab->mu[i] + (u3 - 2 * u2 + u) * h * tab->dmu[i] +
           (-2 * u3 + 3 * u2) * tab->mu[i + 1] + (u3 - u2) * h * tab->dmu[i + 1];
}

double internal_mu_table_eval(const internal_mu_table *tab, double tone)
{
    /* the same cases, in the same order, as nprfx_threshold_builtin_mu */
    double sigma = tab->sigma;
    if (!(tone > 0.0)) return 1.0 + 40.0 / sigma;
    if (tone >= 1.0) return -40.0 / sigma;
    if (tone <= 0.5) return table_upper(tab, tone);
    return 1.0 - table_upper(tab, 1.0 - tone);
}

static inline double quantize(double tone, int steps)
{
    double t = tone > 0.0 ? (tone < 1.0 ? tone : 1.0) : 0.0; /* NaN -> 0 */
    if (steps < 2) return t;
    return floor(t * (steps - 1) + 0.5) / (steps - 1);
}

double nprfx_threshold_quantize(double tone, int steps)
{
    return quantize(tone, steps);
}

/* Clamp to [0,1]; NaN goes to 0 so a bad pattern value cannot index outside the map. */
static double clamp01(double x)
{
    return x > 0.0 ? (x < 1.0 ? x : 1.0) : 0.0;
}

/* Integer cell and fraction of a position in [0, n-1]. */
static void cell(double x, int n, int *i, double *f)
{
    if (n < 2) {
        *i = 0;
        *f = 0.0;
        return;
    }
    int k = (int)floor(x);
    if (k >= n - 1) k = n - 2;
    if (k < 0) k = 0;
    *i = k;
    *f = x - k;
}

void nprfx_threshold_map_lookup(const nprfx_image *map, double u, double v, float *out)
{
    int w = nprfx_rect_width(map->bounds), h = nprfx_rect_height(map->bounds);
    int ix, iy;
    double fx, fy;
    cell(clamp01(u) * (w - 1), w, &ix, &fx);
    /* v = 0 is the bottom row: distance from the bottom in rows, then flip to core's
     * top-down y. Row iy counts from the bottom; iy + 1 is the row above. */
    cell(clamp01(v) * (h - 1), h, &iy, &fy);
    int x0 = map->bounds.x0 + ix, x1 = w > 1 ? x0 + 1 : x0;
    int yb = map->bounds.y1 - 1 - iy, yt = h > 1 ? yb - 1 : yb;
    const float *p00 = nprfx_image_at(map, x0, yb), *p10 = nprfx_image_at(map, x1, yb);
    const float *p01 = nprfx_image_at(map, x0, yt), *p11 = nprfx_image_at(map, x1, yt);
    for (int c = 0; c < map->channels; c++) {
        /* A NaN or infinite texel is missing (docs/design.md §2.2): the bilinear weights of the
         * finite ones, renormalised. One bad texel is read by every pixel whose (pattern, tone)
         * falls near it, anywhere in the frame, so passing it on would spread it. NaN only when
         * all four are missing; exactly the plain bilinear when none is. */
        const double wt[4] = {(1.0 - fy) * (1.0 - fx), (1.0 - fy) * fx, fy * (1.0 - fx), fy * fx};
        const float t[4] = {p00[c], p10[c], p01[c], p11[c]};
        if (isfinite(t[0]) && isfinite(t[1]) && isfinite(t[2]) && isfinite(t[3])) {
            double bottom = (1.0 - fx) * p00[c] + fx * p10[c];
            double top = (1.0 - fx) * p01[c] + fx * p11[c];
            out[c] = (float)((1.0 - fy) * bottom + fy * top);
            continue;
        }
        double sum = 0.0, wsum = 0.0;
        for (int k = 0; k < 4; k++)
            if (isfinite(t[k])) sum += wt[k] * t[k], wsum += wt[k];
        out[c] = wsum > 0.0 ? (float)(sum / wsum) : NAN;
    }
}

/* ---- the threshold-map node over an image ---------------------------------------------------- */

nprfx_result nprfx_threshold_output_channels(int mode, int pattern_channels, int map_channels,
                                             int *channels)
{
    int pch = pattern_channels > 0 ? pattern_channels : 1;
    *channels = pch;
    if (mode == NPRFX_THRESHOLD_MAP) {
        if (map_channels <= 0) return NPRFX_ERR_MISSING_INPUT;
        if (map_channels > 1) {
            if (pch > 1) return NPRFX_ERR_INVALID_ARGUMENT;
            *channels = map_channels;
        }
    }
    return NPRFX_OK;
}

static const float zeros[NPRFX_MAX_CHANNELS];

/* Outside its data window an input reads as 0 (the OpenEXR convention). */
static const float *pixel_or_zero(const nprfx_image *im, int x, int y)
{
    return nprfx_rect_contains(im->bounds, x, y) ? nprfx_image_at(im, x, y) : zeros;
}

typedef struct tm_job {
    const nprfx_threshold_params *p;
    nprfx_rect window;
    const nprfx_image *pattern, *tone_in, *map; /* tone_in, map: NULL when not connected */
    nprfx_image *out;
    const internal_mu_table *mu_table; /* builtin mode */
} tm_job;

/* Pointer to pixel (x0, y) when the whole row span [x0, x1) lies inside im's bounds, else NULL. */
static const float *row_span(const nprfx_image *im, int x0, int x1, int y)
{
    const nprfx_rect b = im->bounds;
    return y >= b.y0 && y < b.y1 && x0 >= b.x0 && x1 <= b.x1 ? nprfx_image_at(im, x0, y) : NULL;
}

/* ---- the erf threshold as float pixels, fast and bit for bit --------------------------------- */

/* The node writes (float)threshold_erf(p, sigma, mu); libm's erf costs 5 ns in the middle and
 * 14 ns in the tails (two exp), most of the node's time. y(x) = (erf(x) + 1) / 2 is instead
 * expanded about the nearest node t = X0 + i / STEPS of a table of y(t) and y'(t) = exp(-t^2) /
 * sqrt(pi): y(t + u) = y(t) + y'(t) u (1 - t u + (2t^2 - 1)/3 u^2 + ...), up to u^6, |u| <= 1/256
 * (truncation below 1e-18). That value is within 1.2e-16 of the true y (rounding of y(t) and of
 * the sum), and glibc's erf (1 ulp) puts its y within 1.1e-16 of it too; both measured, over
 * 2e7 random x, at most 1.1e-16 apart (3e-17 for x < -2). ERFT_SLACK(y) is that bound with room
 * to spare (2x near y = 1 over 1.1e-16, 5x below): when y - slack and y + slack round to the same
 * float, so does libm's value, and the float is taken; otherwise (a float rounding boundary
 * within the slack: mostly x < -4, where y < 1e-8 and floats are finer than the slack) libm's erf
 * decides. Outside [X0, X1] the float is known without either: see erf_sample. */
#define ERFT_X0 (-6.0)
#define ERFT_X1 4.0
#define ERFT_STEPS 128
#define ERFT_N 1280 /* (X1 - X0) * STEPS */
#define ERFT_SLACK(y) (1.5e-16 + 1e-15 * (y))
#define ERFT_BLOCK 256 /* samples per erf_block */

static double erft[ERFT_N + 1][2]; /* y(t), y'(t) at the nodes */
static pthread_once_t erft_once = PTHREAD_ONCE_INIT;

/* The nodes in long double, so that each rounds once to double (erfc below 0: y's relative
 * precision in the lower tail). */
static void erft_init(void)
{
    const long double pi = 3.14159265358979323846264338327950288L;
    for (int i = 0; i <= ERFT_N; i++) {
        const long double t = ERFT_X0 + (long double)i / ERFT_STEPS;
        const long double y = t < 0 ? erfcl(-t) / 2 : (1 + erfl(t)) / 2;
        erft[i][0] = (double)y;
        erft[i][1] = (double)(expl(-t * t) / sqrtl(pi));
    }
}

/* The Taylor step's bracket b for node t (t2 = t^2) and offset u: y(t + u) = y(t) + y'(t) u b.
 * The coefficients are y^(k+1)(t) / (k+1)! / y'(t), k = 2..5: Hermite polynomials in t (the
 * constants by multiplying: their rounding is far below the slack). A macro, so that the scalar
 * and the vector path spell the same operations in the same order and round alike. */
/* clang-format off */
#define ERFT_BRACKET(t, t2, u)                                                                     \
    (1.0 + (u) * (-(t) + (u) * ((2.0 * (t2) - 1.0) * (1.0 / 3.0) +                                 \
     (u) * ((-2.0 * (t2) + 3.0) * (t) * (1.0 / 6.0) +                                              \
     (u) * (((2.0 * (t2) - 6.0) * (t2) + 1.5) * (1.0 / 15.0) +                                     \
     (u) * (((-4.0 * (t2) + 20.0) * (t2) - 15.0) * (t) * (1.0 / 90.0)))))))
/* clang-format on */

/* y(x) for x in [X0, X1] from the table (see above). t and u = x - t are exact: t is a multiple
 * of 1/128 and |u| <= 1/256. */
static inline double erft_eval(double x)
{
    const int i = (int)((x - ERFT_X0) * (double)ERFT_STEPS + 0.5);
    const double t = ERFT_X0 + (double)i * (1.0 / ERFT_STEPS), u = x - t, t2 = t * t;
    return erft[i][0] + erft[i][1] * u * ERFT_BRACKET(t, t2, u);
}

/* out = (float)threshold_erf(p, sigma, mu) when the table decides it; returns 1 when libm's erf
 * must decide instead. Past the table's ends the float is decided: for x >= 4 the double
 * (erf(x) + 1) / 2 is within 1e-8 of 1, past the midpoint 1 - 2^-25 to the float below 1, so it
 * rounds to 1 (erf first gets there at x ~ 3.83); for x <= -6, erfc(-x) < 2^-54, so erf(x)
 * rounds to -1 and the threshold is exactly 0 (glibc returns -1 for |x| >= 6, and first does at
 * x ~ -5.92). NaN is undecided. */
static inline int erf_sample(float p, double mu, double sigma, float *out)
{
    const double x = sigma * ((double)p - mu);
    const int inside = x > ERFT_X0 && x < ERFT_X1;
    const double y = erft_eval(inside ? x : 0.0);
    const double slack = ERFT_SLACK(y);
    const int sure = (float)(y - slack) == (float)(y + slack);
    *out = x >= ERFT_X1 ? 1.0f : x <= ERFT_X0 ? 0.0f : (float)y;
    return !(x >= ERFT_X1 || x <= ERFT_X0 || (inside && sure));
}

/* The float the table could not decide, from libm, inverted as asked. */
static float erf_exact(float p, double mu, double sigma, int invert)
{
    const float v = (float)threshold_erf(p, sigma, mu);
    return invert ? 1.0f - v : v;
}

#if INTERNAL_SIMD
/* 4 doubles: GCC 12 compiles comparisons of wider double vectors lane by lane. */
#define ERFT_LANES 4
typedef double erft_vd __attribute__((vector_size(8 * ERFT_LANES)));
typedef int64_t erft_vl __attribute__((vector_size(8 * ERFT_LANES)));
typedef float erft_vf __attribute__((vector_size(4 * ERFT_LANES)));
typedef int32_t erft_vi __attribute__((vector_size(4 * ERFT_LANES)));

/* erf_sample on ERFT_LANES samples at once, lane for lane the same operations, and erf_exact
 * for the lanes it leaves undecided (from the loaded samples: out may be p). Comparisons give
 * all-ones masks, which select by bits. The table's nodes are gathered into registers, element
 * by element (a store and a vector reload would stall). */
INTERNAL_SIMD_INLINE void erf_lanes(const float *p, const double *mu, double sigma, int invert,
                                    float *out)
{
    erft_vf pf;
    erft_vd m;
    memcpy(&pf, p, sizeof pf);
    memcpy(&m, mu, sizeof m);
    const erft_vd x = sigma * (__builtin_convertvector(pf, erft_vd) - m);
    const erft_vl inside = (x > ERFT_X0) & (x < ERFT_X1);
    const erft_vd xc = (erft_vd)((erft_vl)x & inside); /* 0.0 outside, as erf_sample */
    const erft_vi i = __builtin_convertvector((xc - ERFT_X0) * (double)ERFT_STEPS + 0.5, erft_vi);
    const erft_vd t = ERFT_X0 + __builtin_convertvector(i, erft_vd) * (1.0 / ERFT_STEPS);
    const erft_vd u = xc - t, t2 = t * t;
    const erft_vd y0 = {erft[i[0]][0], erft[i[1]][0], erft[i[2]][0], erft[i[3]][0]};
    const erft_vd y1 = {erft[i[0]][1], erft[i[1]][1], erft[i[2]][1], erft[i[3]][1]};
    const erft_vd y = y0 + y1 * u * ERFT_BRACKET(t, t2, u);
    const erft_vd slack = ERFT_SLACK(y);
    const erft_vi sure =
        __builtin_convertvector(y - slack, erft_vf) == __builtin_convertvector(y + slack, erft_vf);
    const erft_vi one = __builtin_convertvector(x >= ERFT_X1, erft_vi);
    const erft_vi zero = __builtin_convertvector(x <= ERFT_X0, erft_vi);
    const erft_vi f = (erft_vi) __builtin_convertvector(y, erft_vf);
    erft_vf o = (erft_vf)((one & (erft_vi)((erft_vf){0} + 1.0f)) | (~one & ~zero & f));
    const erft_vi redo = ~(one | zero | (__builtin_convertvector(inside, erft_vi) & sure));
    if (invert) o = 1.0f - o;
    memcpy(out, &o, sizeof o);
    if (redo[0] | redo[1] | redo[2] | redo[3])
        for (int l = 0; l < ERFT_LANES; l++)
            if (redo[l]) out[l] = erf_exact(pf[l], m[l], sigma, invert);
}
#endif

/* out[k] = (float)threshold_erf(p[k], sigma, mu[k]) for k < n, bit for bit (1 - that float when
 * invert): ERFT_LANES samples at a time where vectors are built. out may be p. */
INTERNAL_SIMD_CLONES
static void erf_block(const float *p, const double *mu, int n, double sigma, int invert, float *out)
{
    int k = 0;
#if INTERNAL_SIMD
    for (; k + ERFT_LANES <= n; k += ERFT_LANES)
        erf_lanes(p + k, mu + k, sigma, invert, out + k);
#endif
    for (; k < n; k++) {
        const float pk = p[k];
        float v;
        if (erf_sample(pk, mu[k], sigma, &v))
            out[k] = erf_exact(pk, mu[k], sigma, invert);
        else
            out[k] = invert ? 1.0f - v : v;
    }
}

/* The builtin step position is a pure function of the tone: the last one is remembered, since
 * neighbouring pixels (flat shading, the background, every pixel without a tone input) share
 * it. */
typedef struct tm_memo {
    double tone, mu;
} tm_memo;

static inline double memo_mu(tm_memo *memo, const internal_mu_table *tab, double tone)
{
    if (tone != memo->tone) {
        memo->mu = internal_mu_table_eval(tab, tone);
        memo->tone = tone;
    }
    return memo->mu;
}

/* mu[i] for m pixels of a row: the builtin position for the tone row tr (stride ts; NULL: the
 * tone param), or the erf mode's fixed mu. */
static void row_mu(const tm_job *j, const float *tr, ptrdiff_t ts, int m, tm_memo *memo, double *mu)
{
    const nprfx_threshold_params *pp = j->p;
    if (pp->mode != NPRFX_THRESHOLD_BUILTIN || !tr) {
        const double fixed =
            pp->mode != NPRFX_THRESHOLD_BUILTIN
                ? pp->mu
                : memo_mu(memo, j->mu_table, quantize(pp->tone * pp->tone_gain, pp->steps));
        for (int i = 0; i < m; i++)
            mu[i] = fixed;
        return;
    }
    for (int i = 0; i < m; i++, tr += ts)
        mu[i] = memo_mu(memo, j->mu_table, quantize(tr[0] * pp->tone_gain, pp->steps));
}

/* The erf and builtin modes over one row whose pattern (and tone, when connected) cover the
 * window's span, in blocks for erf_block: the step positions first, then the samples, read and
 * written in place when the pixels are packed (else through a copy). The same numbers as the
 * general loop in tm_rows. */
static void erf_row(const tm_job *j, const float *pr, const float *tr, float *o, tm_memo *memo)
{
    const nprfx_threshold_params *pp = j->p;
    const ptrdiff_t ps = j->pattern->pixel_stride, os = j->out->pixel_stride;
    const ptrdiff_t ts = tr ? j->tone_in->pixel_stride : 0;
    const int nout = j->out->channels, per_block = ERFT_BLOCK / nout;
    float pv[ERFT_BLOCK], ov[ERFT_BLOCK];
    double mp[ERFT_BLOCK], mv[ERFT_BLOCK];
    for (int x = j->window.x0; x < j->window.x1;) {
        const int m = j->window.x1 - x < per_block ? j->window.x1 - x : per_block;
        row_mu(j, tr, ts, m, memo, mp);
        /* per sample: each pixel's position for each of its channels */
        const double *ms = mp;
        if (nout > 1) {
            for (int i = 0, k = 0; i < m; i++)
                for (int c = 0; c < nout; c++, k++)
                    mv[k] = mp[i];
            ms = mv;
        }
        const float *ps_in = pr;
        if (ps != nout) {
            for (int i = 0, k = 0; i < m; i++)
                for (int c = 0; c < nout; c++, k++)
                    pv[k] = pr[i * ps + c];
            ps_in = pv;
        }
        float *os_out = os == nout ? o : ov;
        erf_block(ps_in, ms, m * nout, pp->sigma, pp->invert, os_out);
        if (os != nout)
            for (int i = 0, k = 0; i < m; i++)
                for (int c = 0; c < nout; c++, k++)
                    o[i * os + c] = ov[k];
        x += m;
        pr += m * ps;
        o += m * os;
        if (tr) tr += m * ts;
    }
}

static void tm_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const tm_job *j = user;
    const nprfx_threshold_params *pp = j->p;
    tm_memo memo = {-1.0, pp->mu};
    const int x0 = j->window.x0, x1 = j->window.x1;
    for (int y = j->window.y0 + begin; y < j->window.y0 + end; y++) {
        if (pp->mode != NPRFX_THRESHOLD_MAP) {
            const float *pr = row_span(j->pattern, x0, x1, y);
            /* the erf mode ignores the tone */
            const int tone_used = j->tone_in && pp->mode == NPRFX_THRESHOLD_BUILTIN;
            const float *tr = tone_used ? row_span(j->tone_in, x0, x1, y) : NULL;
            if (pr && (!tone_used || tr)) {
                erf_row(j, pr, tr, nprfx_image_at(j->out, x0, y), &memo);
                continue;
            }
        }
        for (int x = x0; x < x1; x++) {
            const float *p = pixel_or_zero(j->pattern, x, y);
            float *o = nprfx_image_at(j->out, x, y);
            int nout = j->out->channels;
            double tone = j->tone_in ? pixel_or_zero(j->tone_in, x, y)[0] : pp->tone;
            tone = quantize(tone * pp->tone_gain, pp->steps);
            if (pp->mode == NPRFX_THRESHOLD_MAP) {
                if (j->map->channels == 1) {
                    for (int c = 0; c < nout; c++)
                        nprfx_threshold_map_lookup(j->map, p[c], tone, &o[c]);
                } else {
                    nprfx_threshold_map_lookup(j->map, p[0], tone, o);
                }
            } else {
                /* builtin is the erf threshold at the position mu(tone) */
                const double mu = pp->mode == NPRFX_THRESHOLD_BUILTIN
                                      ? memo_mu(&memo, j->mu_table, tone)
                                      : pp->mu;
                for (int c = 0; c < nout; c++)
                    o[c] = (float)threshold_erf(p[c], pp->sigma, mu);
            }
            if (pp->invert)
                for (int c = 0; c < nout; c++)
                    o[c] = 1.0f - o[c];
        }
    }
}

/* The per-instance cache: the builtin mode's table for the last sigma. Building it costs 1-3 ms
 * of one thread, which a strip render or a host's tiles would pay at every call. */
typedef struct tm_cache {
    pthread_mutex_t lock; /* first: internal_state.h */
    int valid;
    internal_mu_table table;
} tm_cache;

void nprfx_threshold_state_free(void *state)
{
    internal_state_free(state);
}

double nprfx_threshold_state_bytes(void)
{
    return (double)sizeof(tm_cache);
}

/* The table for sigma into tab: copied from the cache when it holds this sigma, else built
 * (and kept). The copy keeps the render off the lock, whatever another call stores meanwhile. */
static void mu_table_for(void **state, double sigma, internal_mu_table *tab)
{
    tm_cache *c = state ? internal_state_get(state, sizeof *c) : NULL;
    if (c) {
        pthread_mutex_lock(&c->lock);
        int hit = c->valid && c->table.sigma == sigma;
        if (hit) memcpy(tab, &c->table, sizeof *tab);
        pthread_mutex_unlock(&c->lock);
        if (hit) return;
    }
    internal_mu_table_init(tab, sigma);
    if (!c) return;
    pthread_mutex_lock(&c->lock);
    memcpy(&c->table, tab, sizeof *tab);
    c->valid = 1;
    pthread_mutex_unlock(&c->lock);
}

nprfx_result nprfx_threshold_render(nprfx_context *ctx, const nprfx_threshold_params *p,
                                    const nprfx_image *pattern, const nprfx_image *tone,
                                    const nprfx_image *map, nprfx_rect window, nprfx_image *out)
{
    return nprfx_threshold_render_cached(ctx, p, pattern, tone, map, window, out, NULL);
}

nprfx_result nprfx_threshold_render_cached(nprfx_context *ctx, const nprfx_threshold_params *p,
                                           const nprfx_image *pattern, const nprfx_image *tone,
                                           const nprfx_image *map, nprfx_rect window,
                                           nprfx_image *out, void **state)
{
    if (!p || !pattern || !pattern->data || !out)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "threshold-map: no pattern or output");
    if (p->mode < 0 || p->mode >= NPRFX_THRESHOLD_MODE_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "threshold-map.mode: no mode with index %d",
                           p->mode);
    if (!(p->sigma > 0.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "threshold-map.sigma: %g is not positive",
                           p->sigma);
    if (map && !map->data) map = NULL;
    if (tone && !tone->data) tone = NULL;
    if (p->mode == NPRFX_THRESHOLD_MAP) {
        if (!map)
            return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                               "threshold-map: mode 'map' needs the 'map' input (an X-toon map "
                               "image, e.g. samples/maps/soft_step.exr)");
        if (nprfx_rect_empty(map->bounds))
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "threshold-map: input 'map' is empty");
    }
    int want = 0;
    if (nprfx_threshold_output_channels(p->mode, pattern->channels, map ? map->channels : 0,
                                        &want) != NPRFX_OK)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "threshold-map: a %d-channel map needs a 1-channel pattern "
                           "(input 'pattern' has %d); pick one channel of the pattern",
                           map ? map->channels : 0, pattern->channels);
    if (out->channels != want)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "threshold-map: output has %d channels, expected %d", out->channels,
                           want);
    if (nprfx_rect_empty(window)) return NPRFX_OK;
    internal_mu_table mu_table;
    if (p->mode == NPRFX_THRESHOLD_BUILTIN) mu_table_for(state, p->sigma, &mu_table);
    pthread_once(&erft_once, erft_init);
    tm_job j = {p, window, pattern, tone, map, out, &mu_table};
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(window), 8, tm_rows, &j);
    return NPRFX_OK;
}

nprfx_result nprfx_threshold_map_render(const nprfx_render_args *args,
                                        const nprfx_threshold_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    return nprfx_threshold_render_cached(args->ctx, p,
                                         nprfx_render_input(args, NPRFX_THRESHOLD_MAP_IN_PATTERN),
                                         nprfx_render_input(args, NPRFX_THRESHOLD_MAP_IN_TONE),
                                         nprfx_render_input(args, NPRFX_THRESHOLD_MAP_IN_MAP),
                                         args->window, args->output, args->state);
}
