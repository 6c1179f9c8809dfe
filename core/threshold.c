/* Threshold functions and X-toon map lookup (style cookbook §3). See nprfx/threshold.h. */
#include <math.h>
#include <pthread.h>
#include <string.h>

#include "nprfx/threshold.h"
#include "nprfx/exec.h"
#include "internal_state.h"
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
 * decides. Outside [X0, X1] the float is known without either: see erf_block. */
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

/* y(x) for x in [X0, X1] from the table (see above). t and u = x - t are exact: t is a multiple
 * of 1/128 and |u| <= 1/256. */
static inline double erft_eval(double x)
{
    const int i = (int)((x - ERFT_X0) * ERFT_STEPS + 0.5);
    const double t = ERFT_X0 + i * (1.0 / ERFT_STEPS), u = x - t, t2 = t * t;
    /* y^(k+1)(t) / (k+1)! / y'(t), k = 2..5: Hermite polynomials in t (the constants by
     * multiplying: their rounding is far below the slack) */
    const double c2 = (2.0 * t2 - 1.0) * (1.0 / 3.0);
    const double c3 = (-2.0 * t2 + 3.0) * t * (1.0 / 6.0);
    const double c4 = ((2.0 * t2 - 6.0) * t2 + 1.5) * (1.0 / 15.0);
    const double c5 = ((-4.0 * t2 + 20.0) * t2 - 15.0) * t * (1.0 / 90.0);
    const double b = 1.0 + u * (-t + u * (c2 + u * (c3 + u * (c4 + u * c5))));
    return erft[i][0] + erft[i][1] * u * b;
}

/* out[k] = (float)threshold_erf(p[k], sigma, mu[k]) for k < n <= ERFT_BLOCK, bit for bit. The
 * first loop has no calls, for the compiler to vectorise; libm's erf redoes the few it could not
 * decide. Past the table's ends the float is decided: for x >= 4 the double (erf(x) + 1) / 2 is
 * within 1e-8 of 1, past the midpoint 1 - 2^-25 to the float below 1, so it rounds to 1 (erf
 * first gets there at x ~ 3.83); for x <= -6, erfc(-x) < 2^-54, so erf(x) rounds to -1 and the
 * threshold is exactly 0 (glibc returns -1 for |x| >= 6, and first does at x ~ -5.92). NaN is
 * redone. */
static void erf_block(const float *p, const double *mu, int n, double sigma, float *out)
{
    unsigned char redo[ERFT_BLOCK];
    for (int k = 0; k < n; k++) {
        const double x = sigma * (p[k] - mu[k]);
        const int inside = x > ERFT_X0 && x < ERFT_X1;
        const double y = erft_eval(inside ? x : 0.0);
        const double slack = ERFT_SLACK(y);
        const float f = (float)y;
        const int sure = (float)(y - slack) == (float)(y + slack);
        out[k] = x >= ERFT_X1 ? 1.0f : x <= ERFT_X0 ? 0.0f : f;
        redo[k] = !(x >= ERFT_X1 || x <= ERFT_X0 || (inside && sure));
    }
    for (int k = 0; k < n; k++)
        if (redo[k]) out[k] = (float)threshold_erf(p[k], sigma, mu[k]);
}

/* The erf and builtin modes over one row whose pattern (and tone, when connected) cover the
 * window's span: row pointers walked by their strides, the mode tested once per row, and the
 * pixels in blocks for erf_block. The same numbers as the general loop in tm_rows. */
static void erf_row(const tm_job *j, const float *pr, const float *tr, float *o, double *last_tone,
                    double *mu)
{
    const nprfx_threshold_params *pp = j->p;
    const ptrdiff_t ps = j->pattern->pixel_stride, os = j->out->pixel_stride;
    const ptrdiff_t ts = tr ? j->tone_in->pixel_stride : 0;
    const int nout = j->out->channels, builtin = pp->mode == NPRFX_THRESHOLD_BUILTIN;
    const int per_block = ERFT_BLOCK / nout;
    float pv[ERFT_BLOCK], ov[ERFT_BLOCK];
    double mv[ERFT_BLOCK];
    for (int x = j->window.x0; x < j->window.x1;) {
        const int m = j->window.x1 - x < per_block ? j->window.x1 - x : per_block;
        /* gather: the pattern's samples and each one's step position */
        const float *pb = pr;
        for (int i = 0, k = 0; i < m; i++, pb += ps) {
            if (builtin) {
                const double tone = quantize((tr ? tr[0] : pp->tone) * pp->tone_gain, pp->steps);
                if (tone != *last_tone) {
                    *mu = internal_mu_table_eval(j->mu_table, tone);
                    *last_tone = tone;
                }
                if (tr) tr += ts;
            }
            for (int c = 0; c < nout; c++, k++) {
                pv[k] = pb[c];
                mv[k] = *mu;
            }
        }
        erf_block(pv, mv, m * nout, pp->sigma, ov);
        for (int i = 0, k = 0; i < m; i++, pr += ps, o += os)
            for (int c = 0; c < nout; c++, k++)
                o[c] = pp->invert ? 1.0f - ov[k] : ov[k];
        x += m;
    }
}

static void tm_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const tm_job *j = user;
    const nprfx_threshold_params *pp = j->p;
    /* The builtin step position is a pure function of the tone: remember the last one, since
     * neighbouring pixels (and every pixel, with no tone input) share it. */
    double last_tone = -1.0, mu = pp->mu;
    const internal_mu_table *tab = j->mu_table;
    const int x0 = j->window.x0, x1 = j->window.x1;
    for (int y = j->window.y0 + begin; y < j->window.y0 + end; y++) {
        if (pp->mode != NPRFX_THRESHOLD_MAP) {
            const float *pr = row_span(j->pattern, x0, x1, y);
            /* the erf mode ignores the tone */
            const int tone_used = j->tone_in && pp->mode == NPRFX_THRESHOLD_BUILTIN;
            const float *tr = tone_used ? row_span(j->tone_in, x0, x1, y) : NULL;
            if (pr && (!tone_used || tr)) {
                erf_row(j, pr, tr, nprfx_image_at(j->out, x0, y), &last_tone, &mu);
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
                if (pp->mode == NPRFX_THRESHOLD_BUILTIN && tone != last_tone) {
                    mu = internal_mu_table_eval(tab, tone);
                    last_tone = tone;
                }
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
