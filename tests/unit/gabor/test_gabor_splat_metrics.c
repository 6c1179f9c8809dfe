/* Metric tests for the gabor-splat node (docs/design.md §4), on synthetic plates rendered
 * in memory:
 *   - spectrum: on a flat plane the power spectrum peaks at F0 along w0 (within 5% / 5 degrees);
 *     isotropic mode has no preferred orientation;
 *   - LOD invariance through the 4x dolly: per-frame variance within +-10%, the frequency within
 *     5%, kernel count proportional to screen area (not object area);
 *   - coherence: correlation >= 0.8 between a frame and the previous one warped along the true
 *     motion, on visible pixels (translation, rotation, zoom, the orbit's moving sphere, the
 *     dolly), well above the shower-door baseline;
 *   - continuity: through the dolly, no frame-to-frame jump beyond a bound on non-disoccluded
 *     pixels, and no frame whose change stands out (no popping from the level of detail).
 * Renders go through the node's descriptor (and, for kernel counts, the core function). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/filter.h"
#include "nprfx/gabor.h"
#include "nprfx/metrics.h"
#include "nprfx/node.h"
#include "nprfx/synth.h"

static const double k_pi = 3.14159265358979323846;

static nprfx_context *ctx;
static const nprfx_node_desc *node;

/* Params of the node: defaults, then "name=value" settings. */
typedef struct gparams {
    nprfx_value v[32];
} gparams;

static gparams params(const char *const *sets, int n)
{
    gparams p;
    nprfx_node_defaults(node, p.v);
    for (int i = 0; i < n; i++) {
        char name[64];
        const char *eq = strchr(sets[i], '=');
        size_t len = (size_t)(eq - sets[i]);
        memcpy(name, sets[i], len);
        name[len] = 0;
        int k = nprfx_node_param_index(node, name);
        if (k < 0 || nprfx_param_parse(ctx, node, &node->params[k], eq + 1, &p.v[k])) {
            fprintf(stderr, "bad setting %s\n", sets[i]);
            exit(2);
        }
    }
    return p;
}

/* Render the node on a synth plate (Pref, Z, id) into out (1 channel). */
static void render(const nprfx_image *plate, const gparams *p, nprfx_image *out)
{
    nprfx_image in[8];
    memset(in, 0, sizeof in);
    in[nprfx_node_input_index(node, "anchor")] =
        nprfx_image_channels(plate, th_synth_channel("Pref.X"), 3);
    in[nprfx_node_input_index(node, "depth")] =
        nprfx_image_channels(plate, th_synth_channel("Z"), 1);
    in[nprfx_node_input_index(node, "id")] = nprfx_image_channels(plate, th_synth_channel("id"), 1);
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = node;
    a.time = 1;
    a.render_scale = 1;
    a.frame = a.window = out->bounds;
    a.first_frame = a.last_frame = 1;
    a.inputs = in;
    a.params = p->v;
    a.output = out;
    if (nprfx_node_render(&a) != NPRFX_OK) {
        fprintf(stderr, "render failed: %s\n", th_error(ctx));
        exit(2);
    }
}

/* ---- spectrum ---- */

/* Power spectrum of the node's output on the flat plane, summed over seeds. */
static double *plane_spectrum(const char *const *sets, int nsets, int nseeds, int *n_out)
{
    const int size = 256;
    nprfx_image plate = th_synth(ctx, "translate", 0, size, size);
    nprfx_image out = th_image(size, size, 1, NULL);
    int n = 0;
    CHECK_OK(nprfx_power_spectrum_2d(ctx, &out, 0, NULL, &n));
    double *sum = calloc((size_t)n * n, sizeof(double)), *pw = malloc(sizeof(double) * n * n);
    for (int s = 0; s < nseeds; s++) {
        gparams p = params(sets, nsets);
        p.v[nprfx_node_param_index(node, "seed")].v[0] = 11 + s;
        render(&plate, &p, &out);
        CHECK_OK(nprfx_power_spectrum_2d(ctx, &out, 0, pw, &n));
        for (int i = 0; i < n * n; i++)
            sum[i] += pw[i];
    }
    free(pw);
    nprfx_image_free(&out);
    nprfx_image_free(&plate);
    *n_out = n;
    return sum;
}

/* The spectral peak of an anisotropic noise: in the half plane facing the expected wave
 * vector (the spectrum of a real image is symmetric), start at the largest bin away from DC
 * and move to the power centroid of the bins within `radius` bins, until it settles (mean
 * shift: the centroid of a Gaussian lobe is its centre). */
static void spectral_peak(const double *P, int n, double dir_deg, double radius, double *freq,
                          double *angle_deg)
{
    double ux = cos(dir_deg * k_pi / 180.0), uy = -sin(dir_deg * k_pi / 180.0);
    double cx = 0, cy = 0, best = -1;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            double fx = i - n / 2, fy = j - n / 2;
            if (fx * ux + fy * uy <= 0 || fx * fx + fy * fy < 4) continue;
            if (P[j * n + i] > best) {
                best = P[j * n + i];
                cx = fx;
                cy = fy;
            }
        }
    for (int it = 0; it < 20; it++) {
        double sw = 0, sx = 0, sy = 0;
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double fx = i - n / 2, fy = j - n / 2;
                if ((fx - cx) * (fx - cx) + (fy - cy) * (fy - cy) > radius * radius) continue;
                sw += P[j * n + i];
                sx += P[j * n + i] * fx;
                sy += P[j * n + i] * fy;
            }
        cx = sx / sw;
        cy = sy / sw;
    }
    *freq = sqrt(cx * cx + cy * cy) / n;
    *angle_deg = atan2(-cy, cx) * 180.0 / k_pi;
}

static void test_spectrum(void)
{
    const struct {
        double f, w, r;
    } cases[4] = {{0.1, 0.0, 16}, {0.1, 30.0, 16}, {0.15, 120.0, 12}, {0.06, 75.0, 24}};
    for (int c = 0; c < 4; c++) {
        char sf[64], sw[64], sr[64];
        snprintf(sf, sizeof sf, "frequency=%g", cases[c].f);
        snprintf(sw, sizeof sw, "orientation=%g", cases[c].w);
        snprintf(sr, sizeof sr, "radius=%g", cases[c].r);
        const char *sets[3] = {sf, sw, sr};
        int n;
        double *P = plane_spectrum(sets, 3, 3, &n);
        double a = nprfx_gabor_bandwidth(cases[c].r), sd = a / (2.0 * sqrt(k_pi)) * n;
        double f, ang;
        spectral_peak(P, n, cases[c].w, 3.0 * sd, &f, &ang);
        double dang = fmod(ang - cases[c].w + 540.0, 180.0) - 90.0; /* orientation mod 180 */
        dang = dang < -90 ? dang + 180 : dang;
        printf("spectrum: F0 %.3f w0 %5.1f -> peak %.4f cycles/px (%+.2f%%) at %6.2f deg (%+.2f)\n",
               cases[c].f, cases[c].w, f, 100.0 * (f / cases[c].f - 1.0), ang,
               fmod(ang - cases[c].w + 450.0, 180.0) - 90.0);
        CHECK(fabs(f / cases[c].f - 1.0) <= 0.05);
        CHECK(fabs(fmod(ang - cases[c].w + 450.0, 180.0) - 90.0) <= 5.0);
        (void)dang;
        free(P);
    }
    /* isotropic: a ring at F0, no preferred orientation */
    const char *sets[3] = {"isotropic=1", "frequency=0.12", "radius=16"};
    int n;
    double *P = plane_spectrum(sets, 3, 3, &n);
    double a = nprfx_gabor_bandwidth(16), sd = a / (2.0 * sqrt(k_pi)) * n, F = 0.12 * n;
    double sw = 0, c2 = 0, s2 = 0, sr = 0;
    double ring[256] = {0}, cnt[256] = {0};
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            double fx = i - n / 2, fy = j - n / 2, rr = sqrt(fx * fx + fy * fy);
            int k = (int)floor(rr + 0.5);
            if (k < n / 2) {
                ring[k] += P[j * n + i];
                cnt[k] += 1;
            }
            if (fabs(rr - F) > 2.0 * sd) continue;
            double th = atan2(fy, fx);
            sw += P[j * n + i];
            c2 += P[j * n + i] * cos(2 * th);
            s2 += P[j * n + i] * sin(2 * th);
        }
    /* mean power per ring, then its centroid around the largest ring (mean shift) */
    double peak = 0, best = -1;
    for (int k = 3; k < n / 2; k++)
        if (cnt[k] > 0 && ring[k] / cnt[k] > best) best = ring[k] / cnt[k], peak = k;
    for (int it = 0; it < 20; it++) {
        double w = 0, m = 0;
        for (int k = 3; k < n / 2; k++) {
            if (fabs(k - peak) > 2.5 * sd || cnt[k] == 0) continue;
            w += ring[k] / cnt[k];
            m += ring[k] / cnt[k] * k;
        }
        peak = m / w;
    }
    sr = peak / n;
    double aniso = sqrt(c2 * c2 + s2 * s2) / sw;
    printf("spectrum: isotropic F0 0.120 -> ring peak %.4f cycles/px (%+.2f%%), orientation "
           "bias %.3f (anisotropic noise: about 0.9)\n",
           sr, 100.0 * (sr / 0.12 - 1.0), aniso);
    CHECK(fabs(sr / 0.12 - 1.0) <= 0.05);
    CHECK(aniso < 0.08);
    free(P);
    /* the same bias measure on an anisotropic noise, for scale */
    const char *aset[2] = {"frequency=0.12", "radius=16"};
    P = plane_spectrum(aset, 2, 1, &n);
    sw = c2 = s2 = 0;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            double fx = i - n / 2, fy = j - n / 2, rr = sqrt(fx * fx + fy * fy);
            if (fabs(rr - F) > 2.0 * sd) continue;
            double th = atan2(fy, fx);
            sw += P[j * n + i];
            c2 += P[j * n + i] * cos(2 * th);
            s2 += P[j * n + i] * sin(2 * th);
        }
    CHECK(sqrt(c2 * c2 + s2 * s2) / sw > 0.7);
    free(P);
}

/* ---- level of detail through the dolly ---- */

/* Pixels whose whole kernel disk lies on their own object: the variance there is not reduced
 * by kernels cut at edges. */
static nprfx_image interior_mask(const nprfx_image *plate, int r)
{
    int w = plate->bounds.x1, h = plate->bounds.y1, cid = th_synth_channel("id"),
        cz = th_synth_channel("Z");
    nprfx_image m = th_image(w, h, 1, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = nprfx_image_at(plate, x, y);
            int ok = p[cz] < 1e9f;
            for (int dy = -r; dy <= r && ok; dy++)
                for (int dx = -r; dx <= r && ok; dx++) {
                    if (dx * dx + dy * dy > r * r) continue;
                    int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
                    const float *q = nprfx_image_at(plate, xx, yy);
                    /* same object, no depth step (the torus overlaps itself) */
                    ok = q[cid] == p[cid] && fabsf(q[cz] - p[cz]) < 0.1f * p[cz];
                }
            m.data[y * w + x] = (float)ok;
        }
    return m;
}

/* A frequency estimate that works on masked regions: the ratio of gradient to value energy,
 * E[|grad n|^2] / E[n^2] = (2 pi f)^2 for a single frequency (central differences: sin^2). */
static double gradient_frequency(const nprfx_image *im, const nprfx_image *mask)
{
    int w = im->bounds.x1, h = im->bounds.y1;
    double e0 = 0, e1 = 0;
    for (int y = 1; y < h - 1; y++)
        for (int x = 1; x < w - 1; x++) {
            if (mask->data[y * w + x] < 0.5f || mask->data[y * w + x - 1] < 0.5f ||
                mask->data[y * w + x + 1] < 0.5f || mask->data[(y - 1) * w + x] < 0.5f ||
                mask->data[(y + 1) * w + x] < 0.5f)
                continue;
            const float *d = im->data;
            double v = d[y * w + x];
            double gx = 0.5 * (d[y * w + x + 1] - d[y * w + x - 1]);
            double gy = 0.5 * (d[(y + 1) * w + x] - d[(y - 1) * w + x]);
            e0 += v * v;
            e1 += gx * gx + gy * gy;
        }
    double s = sqrt(e1 / e0);
    return asin(s < 1 ? s : 1) / (2 * k_pi);
}

static void test_dolly_lod(void)
{
    const int w = 512, h = 384, r = 6;
    const char *sets[3] = {"radius=6", "frequency=0.15", "n0=32"};
    const int frames[7] = {1, 8, 16, 24, 32, 40, 48};
    double lambda = 32.0 / (k_pi * r * r);
    /* reference: the flat plane's frequency estimate with the same kernels */
    double fref;
    {
        nprfx_image plate = th_synth(ctx, "translate", 0, 256, 256);
        nprfx_image out = th_image(256, 256, 1, NULL), m = interior_mask(&plate, r);
        double s = 0;
        for (int seed = 0; seed < 4; seed++) {
            gparams p = params(sets, 3);
            p.v[nprfx_node_param_index(node, "seed")].v[0] = seed;
            render(&plate, &p, &out);
            s += gradient_frequency(&out, &m) / 4;
        }
        fref = s;
        nprfx_image_free(&out);
        nprfx_image_free(&m);
        nprfx_image_free(&plate);
    }
    double ratio_first = 0, ratio_last = 0, area_first = 0, area_last = 0;
    for (int fi = 0; fi < 7; fi++) {
        nprfx_image plate = th_synth(ctx, "dolly", frames[fi], w, h);
        nprfx_image mask = interior_mask(&plate, r), out = th_image(w, h, 1, NULL);
        long long inside = 0, area = 0;
        int cz = th_synth_channel("Z");
        for (int i = 0; i < w * h; i++) {
            inside += mask.data[i] > 0.5f;
            area += nprfx_image_at(&plate, i % w, i / w)[cz] < 1e9f;
        }
        /* pool the variance over enough seeds for about 6e4 interior samples */
        int nseeds = (int)(60000 / (inside + 1)) + 1;
        if (nseeds > 24) nseeds = 24;
        double sum2 = 0, freq = 0;
        long long cnt = 0;
        for (int seed = 0; seed < nseeds; seed++) {
            gparams p = params(sets, 3);
            p.v[nprfx_node_param_index(node, "seed")].v[0] = 100 + seed;
            render(&plate, &p, &out);
            for (int i = 0; i < w * h; i++)
                if (mask.data[i] > 0.5f) sum2 += (double)out.data[i] * out.data[i], cnt++;
            freq += gradient_frequency(&out, &mask) / nseeds;
        }
        double var = sum2 / cnt;
        /* kernel counts through the core */
        nprfx_gabor_params gp;
        nprfx_gabor_params_default(&gp);
        gp.radius = r;
        gp.frequency = 0.15;
        nprfx_image anchor = nprfx_image_channels(&plate, th_synth_channel("Pref.X"), 3);
        nprfx_image depth = nprfx_image_channels(&plate, cz, 1);
        nprfx_image id = nprfx_image_channels(&plate, th_synth_channel("id"), 1);
        nprfx_gabor_inputs gi = {sizeof gi, &anchor, &depth, &id, NULL, NULL};
        nprfx_gabor_stats st;
        CHECK_OK(nprfx_gabor_render(ctx, &gp, &gi, out.bounds, &out, &st));
        double kr = st.kernels / (lambda * area), wr = st.weight2 / (lambda * area);
        printf("dolly frame %2d: object %6lld px, variance %.3f (%d seeds, %lld samples), "
               "frequency %+.2f%%, kernels %.2f lambda, squared weights %.3f lambda\n",
               frames[fi], area, var, nseeds, cnt, 100 * (freq / fref - 1), kr, wr);
        CHECK_NEAR(var, 1.0, 0.1);
        CHECK(fabs(freq / fref - 1.0) <= 0.05);
        CHECK(wr > 0.9 && wr < 1.1);
        CHECK(kr > 0.9 && kr < 4.5);
        if (fi == 0) ratio_first = kr, area_first = (double)area;
        ratio_last = kr;
        area_last = (double)area;
        nprfx_image_free(&out);
        nprfx_image_free(&mask);
        nprfx_image_free(&plate);
    }
    /* the object grows about 16x on screen (its object-space area is fixed); the kernel count
     * per screen pixel stays within the bounded fade-in factor */
    printf("dolly: screen area x%.1f, kernels per screen pixel x%.2f\n", area_last / area_first,
           ratio_last / ratio_first);
    CHECK(area_last / area_first > 10.0);
    CHECK(ratio_last / ratio_first > 0.5 && ratio_last / ratio_first < 2.0);
}

/* ---- coherence and continuity ---- */

/* Pixels of cur visible in prev too: foreground, their previous position inside the frame, on
 * the same object and at the depth the motion predicts there. */
static nprfx_image visible_mask(const nprfx_image *cur, const nprfx_image *prev)
{
    int w = cur->bounds.x1, h = cur->bounds.y1;
    int cid = th_synth_channel("id"), cz = th_synth_channel("Z"),
        cmx = th_synth_channel("motion_prev.X");
    nprfx_image m = th_image(w, h, 1, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = nprfx_image_at(cur, x, y);
            double px = x + p[cmx], py = y + p[cmx + 1];
            int ok = p[cz] < 1e9f && px >= 0 && py >= 0 && px <= w - 1 && py <= h - 1;
            if (ok) {
                /* all four bilinear taps on the same object at a similar depth */
                for (int k = 0; k < 4 && ok; k++) {
                    int xx = (int)floor(px) + (k & 1), yy = (int)floor(py) + (k >> 1);
                    if (xx > w - 1) xx = w - 1;
                    if (yy > h - 1) yy = h - 1;
                    const float *q = nprfx_image_at(prev, xx, yy);
                    ok = q[cid] == p[cid] && fabsf(q[cz] - p[cz]) < 0.1f * p[cz];
                }
            }
            m.data[y * w + x] = (float)ok;
        }
    return m;
}

static void test_coherence(void)
{
    const struct {
        const char *scene;
        int frame, w, h;
    } cases[5] = {{"translate", 10, 256, 192},
                  {"rotate", 10, 256, 192},
                  {"zoom", 10, 256, 192},
                  {"orbit", 24, 256, 192},
                  {"dolly", 30, 256, 192}};
    const char *sets[2] = {"radius=8", "frequency=0.12"};
    for (int c = 0; c < 5; c++) {
        int w = cases[c].w, h = cases[c].h;
        nprfx_image p0 = th_synth(ctx, cases[c].scene, cases[c].frame - 1, w, h);
        nprfx_image p1 = th_synth(ctx, cases[c].scene, cases[c].frame, w, h);
        nprfx_image a = th_image(w, h, 1, NULL), b = th_image(w, h, 1, NULL);
        gparams p = params(sets, 2);
        render(&p0, &p, &a);
        render(&p1, &p, &b);
        nprfx_image mask = visible_mask(&p1, &p0);
        nprfx_image mp = nprfx_image_channels(&p1, th_synth_channel("motion_prev.X"), 2);
        nprfx_warp_error we, sd;
        CHECK_OK(nprfx_warp_compare(ctx, &b, &a, 0, &mp, &mask, &we));
        /* the shower door: the pattern left where it was */
        nprfx_image zero = th_image(w, h, 2, NULL);
        CHECK_OK(nprfx_warp_compare(ctx, &b, &a, 0, &zero, &mask, &sd));
        /* restricted to the moving pixels (the orbit's box and backdrop stand still) */
        int cmx = th_synth_channel("motion_prev.X");
        nprfx_image moving = th_image(w, h, 1, NULL);
        for (int i = 0; i < w * h; i++) {
            const float *q = nprfx_image_at(&p1, i % w, i / w);
            moving.data[i] = mask.data[i] * (fabsf(q[cmx]) + fabsf(q[cmx + 1]) > 0.05f);
        }
        nprfx_warp_error wm, sm;
        CHECK_OK(nprfx_warp_compare(ctx, &b, &a, 0, &mp, &moving, &wm));
        CHECK_OK(nprfx_warp_compare(ctx, &b, &a, 0, &zero, &moving, &sm));
        printf("coherence %-9s: warp correlation %.4f on %lld visible pixels; moving pixels: "
               "%.4f, RMS error %.3f (shower door: %.4f, %.3f)\n",
               cases[c].scene, we.correlation, we.count, wm.correlation, wm.rms, sm.correlation,
               sm.rms);
        CHECK(we.correlation >= 0.8);
        CHECK(wm.count > 1000 && wm.correlation >= 0.8);
        /* following the motion beats leaving the pattern in place, even at 0.3 px/frame */
        CHECK(wm.rms < 0.5 * sm.rms);
        nprfx_image_free(&zero);
        nprfx_image_free(&moving);
        nprfx_image_free(&mask);
        nprfx_image_free(&a);
        nprfx_image_free(&b);
        nprfx_image_free(&p0);
        nprfx_image_free(&p1);
    }
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Through the whole dolly, every frame against the previous one warped along the motion, on
 * pixels visible in both and farther than a kernel radius from object edges and from the frame
 * edge (surface coming into view over a silhouette or into the frame brings new kernels: that
 * is disocclusion, not popping): the change per frame stays bounded and no frame stands out
 * (the level-of-detail transitions do not pop). */
static void test_continuity(void)
{
    const int w = 256, h = 192;
    const char *sets[2] = {"radius=8", "frequency=0.12"};
    gparams p = params(sets, 2);
    nprfx_image prev_plate = th_synth(ctx, "dolly", 1, w, h);
    nprfx_image prev = th_image(w, h, 1, NULL), cur = th_image(w, h, 1, NULL);
    render(&prev_plate, &p, &prev);
    double rms[48], worst = 0;
    int nf = 0, worst_frame = 0;
    for (int f = 2; f <= 48; f++) {
        nprfx_image plate = th_synth(ctx, "dolly", f, w, h);
        render(&plate, &p, &cur);
        nprfx_image vis = visible_mask(&plate, &prev_plate), in = interior_mask(&plate, 8);
        int cmx = th_synth_channel("motion_prev.X");
        double s2 = 0;
        long long n = 0;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                if (vis.data[y * w + x] < 0.5f || in.data[y * w + x] < 0.5f) continue;
                if (x < 10 || y < 10 || x >= w - 10 || y >= h - 10) continue;
                const float *q = nprfx_image_at(&plate, x, y);
                float v;
                nprfx_sample_bilinear(&prev, x + q[cmx], y + q[cmx + 1], NPRFX_BORDER_CLAMP, &v);
                double d = cur.data[y * w + x] - v;
                s2 += d * d;
                n++;
                if (fabs(d) > worst) worst = fabs(d), worst_frame = f;
            }
        if (n > 200) rms[nf++] = sqrt(s2 / n);
        nprfx_image_free(&vis);
        nprfx_image_free(&in);
        nprfx_image_free(&prev_plate);
        prev_plate = plate;
        nprfx_image t = prev;
        prev = cur;
        cur = t;
    }
    double sorted[48];
    memcpy(sorted, rms, sizeof(double) * nf);
    qsort(sorted, (size_t)nf, sizeof(double), cmp_double);
    double median = sorted[nf / 2], maxr = sorted[nf - 1];
    printf("continuity through the dolly: %d frames, change per frame RMS median %.4f, max %.4f; "
           "largest single-pixel change %.3f (frame %d)\n",
           nf, median, maxr, worst, worst_frame);
    CHECK(nf >= 30);
    CHECK(maxr <= 0.25);
    CHECK(maxr <= 1.6 * median);
    CHECK(worst <= 1.0);
    nprfx_image_free(&prev);
    nprfx_image_free(&cur);
    nprfx_image_free(&prev_plate);
}

int main(void)
{
    nprfx_pool *pool = NULL;
    if (nprfx_pool_create(0, &pool) != NPRFX_OK) return 2;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    ci.executor = nprfx_pool_executor(pool);
    if (nprfx_context_create(&ci, &ctx) != NPRFX_OK) return 2;
    node = nprfx_node_find("gabor-splat");
    CHECK(node != NULL);
    if (!node) return check_finish();
    test_spectrum();
    test_dolly_lod();
    test_coherence();
    test_continuity();
    nprfx_context_destroy(ctx);
    nprfx_pool_destroy(pool);
    return check_finish();
}
