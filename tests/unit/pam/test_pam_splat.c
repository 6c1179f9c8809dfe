/* The pam-splat node (docs/design.md §3.7) on synthetic plates, through its
 * descriptor:
 *   - BT.601 YUV by hand and round trip; a PAM's tone position by hand; the descriptor's lint;
 *   - Eq. 10 by hand: flat maps give model + (beta dY, gamma dU, gamma dV) exactly;
 *   - the mean output luminance rises with the tone (constant tones, and binned on a varying
 *     one); tones outside [0, 1] are clamped;
 *   - coherence: on the orbit, with the light moving between frames, the warp error along the
 *     motion vectors is below the same node's anchored on the screen (shower door);
 *   - flow: the texture moves along the direction at the set speed, and stands still at 0;
 *   - bit identity across threads and tiles; the state never changes results and notices a
 *     new PAM; a foreign image as PAM is refused with its name and size. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/metrics.h"
#include "nprfx/node.h"
#include "nprfx/pam_splat.h"
#include "nprfx/synth.h"

static nprfx_context *ctx;
static const nprfx_node_desc *node;

enum { IN_ANCHOR, IN_TONE, IN_COLOR, IN_DIRECTION, IN_DEPTH, IN_ID, IN_PAM, IN_N };

typedef struct pparams {
    nprfx_value v[16];
} pparams;

static pparams defaults(void)
{
    pparams p;
    nprfx_node_defaults(node, p.v);
    return p;
}

static void set(pparams *p, const char *name, double v)
{
    p->v[th_param(node, name)].v[0] = v;
}

/* Render all of out at frame `time`, with an optional state slot. */
static nprfx_result render_at(const nprfx_image *inputs, const pparams *p, nprfx_image *out,
                              double time, void **state)
{
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = node;
    a.time = time;
    a.render_scale = 1;
    a.frame = out->bounds;
    a.window = out->bounds;
    a.first_frame = 1;
    a.last_frame = 100;
    a.inputs = inputs;
    a.params = p->v;
    a.output = out;
    a.state = state;
    return nprfx_node_render(&a);
}

static double luma(const float *px)
{
    return NPRFX_YUV_KR * px[0] + (1.0 - NPRFX_YUV_KR - NPRFX_YUV_KB) * px[1] +
           NPRFX_YUV_KB * px[2];
}

/* A test PAM: n maps of S px, map m at brightness 0.1 + 0.8 m / (n - 1) with a tint, and
 * (unless `flat`) vertical streaks crossed by a weaker wave along v, tileable. */
static nprfx_image test_pam(int n, int S, int flat)
{
    nprfx_image im = th_image(n * S, S, 3, NULL);
    for (int m = 0; m < n; m++)
        for (int y = 0; y < S; y++)
            for (int x = 0; x < S; x++) {
                double b = 0.1 + 0.8 * m / (n - 1);
                double s = flat ? 0.0
                                : 0.12 * sin(2.0 * 3.14159265358979 * 3.0 * x / S) +
                                      0.08 * sin(2.0 * 3.14159265358979 * 2.0 * y / S);
                float *px = nprfx_image_at(&im, m * S + x, y);
                px[0] = (float)(b + s + 0.05);
                px[1] = (float)(b + s);
                px[2] = (float)(b + s - 0.03 * m);
            }
    return im;
}

/* A flat, frontal plane of w x h: UV anchors (64 px per unit), depth 5, one object; a constant
 * colour, tone and (2 channels) direction. Images are owned by the caller: 6 entries. */
typedef struct plane {
    nprfx_image uv, depth, id, color, tone, dir;
} plane;

static plane make_plane(int w, int h, double tone, double dx, double dy)
{
    plane P;
    P.uv = th_image(w, h, 2, NULL);
    P.depth = th_image(w, h, 1, NULL);
    P.id = th_image(w, h, 1, NULL);
    P.color = th_image(w, h, 3, NULL);
    P.tone = th_image(w, h, 1, NULL);
    P.dir = th_image(w, h, 2, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            P.uv.data[2 * i] = (float)(x / 64.0);
            P.uv.data[2 * i + 1] = (float)(y / 64.0);
            P.depth.data[i] = 5.0f;
            P.id.data[i] = 1.0f;
            P.color.data[3 * i] = 0.5f;
            P.color.data[3 * i + 1] = 0.4f;
            P.color.data[3 * i + 2] = 0.3f;
            P.tone.data[i] = (float)tone;
            P.dir.data[2 * i] = (float)dx;
            P.dir.data[2 * i + 1] = (float)dy;
        }
    return P;
}

static void free_plane(plane *P)
{
    nprfx_image_free(&P->uv);
    nprfx_image_free(&P->depth);
    nprfx_image_free(&P->id);
    nprfx_image_free(&P->color);
    nprfx_image_free(&P->tone);
    nprfx_image_free(&P->dir);
}

static void plane_inputs(const plane *P, const nprfx_image *pam, nprfx_image in[IN_N])
{
    memset(in, 0, sizeof(nprfx_image) * IN_N);
    in[IN_ANCHOR] = P->uv;
    in[IN_TONE] = P->tone;
    in[IN_COLOR] = P->color;
    in[IN_DIRECTION] = P->dir;
    in[IN_DEPTH] = P->depth;
    in[IN_ID] = P->id;
    if (pam) in[IN_PAM] = *pam;
}

/* ---- formulas ---- */

static void test_formulas(void)
{
    CHECK_OK(nprfx_node_lint(ctx, node));
    double rgb[3] = {1.0, 0.0, 0.0}, yuv[3], back[3];
    nprfx_rgb_to_yuv(rgb, yuv);
    CHECK_NEAR(yuv[0], 0.299, 1e-12);
    CHECK_NEAR(yuv[1], 0.436 * -0.299 / 0.886, 1e-12);
    CHECK_NEAR(yuv[2], 0.615, 1e-12);
    double c[3] = {0.2, 0.7, 0.4};
    nprfx_rgb_to_yuv(c, yuv);
    nprfx_yuv_to_rgb(yuv, back);
    for (int k = 0; k < 3; k++)
        CHECK_NEAR(back[k], c[k], 1e-12);

    nprfx_pam_stats info;
    memset(&info, 0, sizeof info);
    info.count = 3;
    info.size = 8;
    info.map_y[0] = 0.1, info.map_y[1] = 0.3, info.map_y[2] = 0.5;
    int i;
    double t;
    nprfx_pam_tone_position(&info, 0.0, &i, &t);
    CHECK(i == 0 && t == 0.0);
    nprfx_pam_tone_position(&info, 0.75, &i, &t); /* Y 0.4: halfway from map 1 to map 2 */
    CHECK(i == 1);
    CHECK_NEAR(t, 0.5, 1e-12);
    nprfx_pam_tone_position(&info, 0.25, &i, &t);
    CHECK(i == 0);
    CHECK_NEAR(t, 0.5, 1e-12);
    nprfx_pam_tone_position(&info, 7.0, &i, &t); /* clamped */
    CHECK(i == 1 && t == 1.0);
    nprfx_pam_tone_position(&info, -3.0, &i, &t);
    CHECK(i == 0 && t == 0.0);
    nprfx_pam_tone_position(&info, NAN, &i, &t);
    CHECK(i == 0 && t == 0.0);

    /* the measure of a PAM: per-map means and Eq. 9's mean */
    nprfx_image pam = test_pam(4, 16, 1);
    CHECK_OK(nprfx_pam_measure(ctx, &pam, "test", &info));
    CHECK(info.count == 4 && info.size == 16);
    double m0[3] = {0.15, 0.1, 0.1}, y0[3];
    nprfx_rgb_to_yuv(m0, y0);
    CHECK_NEAR(info.map_y[0], y0[0], 1e-6);
    CHECK(info.map_y[1] > info.map_y[0] && info.map_y[3] > info.map_y[2]);
    nprfx_image_free(&pam);
}

/* Eq. 10 by hand: flat maps, so every fragment's deviation is its maps' colour minus the mean */
static void test_eq10(void)
{
    int w = 96, h = 64;
    const double tones[2] = {0.0, 0.3};
    nprfx_image pam = test_pam(3, 16, 1);
    nprfx_pam_stats info;
    CHECK_OK(nprfx_pam_measure(ctx, &pam, "test", &info));
    for (int k = 0; k < 2; k++) {
        plane P = make_plane(w, h, tones[k], 1.0, 0.0);
        nprfx_image in[IN_N], out = th_image(w, h, 3, NULL);
        plane_inputs(&P, &pam, in);
        pparams p = defaults();
        set(&p, "anchor_space", 1);
        set(&p, "beta", 0.8);
        set(&p, "gamma", 1.5);
        set(&p, "size", 12);
        CHECK_OK(render_at(in, &p, &out, 1, NULL));
        /* the maps' colour at this tone (the maps mixed linearly, so the flat maps' formula at a
         * fractional index), minus the PAM's mean, through Eq. 10 */
        int mi;
        double mt;
        nprfx_pam_tone_position(&info, tones[k], &mi, &mt);
        double b = 0.1 + 0.8 * (mi + mt) / 2.0;
        double texel[3] = {b + 0.05, b, b - 0.03 * (mi + mt)}, ty[3], model[3] = {0.5, 0.4, 0.3},
               my[3], want[3];
        nprfx_rgb_to_yuv(texel, ty);
        nprfx_rgb_to_yuv(model, my);
        my[0] += 0.8 * (ty[0] - info.mean[0]);
        my[1] += 1.5 * (ty[1] - info.mean[1]);
        my[2] += 1.5 * (ty[2] - info.mean[2]);
        nprfx_yuv_to_rgb(my, want);
        long long hit = 0, model_only = 0, bad = 0;
        for (int i = 0; i < w * h; i++) {
            const float *o = out.data + 3 * i;
            int is_want = 1, is_model = 1;
            for (int c = 0; c < 3; c++) {
                is_want &= fabs(o[c] - want[c]) < 2e-5;
                is_model &= o[c] == (float)model[c];
            }
            hit += is_want;
            model_only += is_model && !is_want;
            bad += !is_want && !is_model;
        }
        printf("Eq. 10, tone %.1f: %lld of %d pixels as computed by hand (%.4f %.4f %.4f), %lld "
               "untouched, %lld other\n",
               tones[k], hit, w * h, want[0], want[1], want[2], model_only, bad);
        CHECK(bad == 0);
        CHECK(hit >= (long long)(0.98 * w * h));
        nprfx_image_free(&out);
        free_plane(&P);
    }
    nprfx_image_free(&pam);
}

/* ---- colour above 1 ---- */

/* An HDR model colour (a highlight up to 100) is painted at luminance 1 and scaled back: the
 * strokes on k times a colour of luminance just above 1 are k times the strokes on that colour,
 * finite, with the contrast they have at white (added at full brightness, Eq. 10's deviation
 * would vanish into a highlight: out / k = colour + D / k). */
static void test_hdr(void)
{
    int w = 96, h = 64;
    nprfx_image pam = test_pam(3, 16, 0);
    const float base[3] = {1.1f, 1.0f, 0.9f}, gains[3] = {5.0f, 20.0f, 100.0f};
    nprfx_image ref = th_image(w, h, 3, NULL);
    double worst = 0.0, sum = 0.0, sum2 = 0.0;
    int nonfinite = 0;
    for (int g = -1; g < 3; g++) {
        float k = g < 0 ? 1.0f : gains[g];
        plane P = make_plane(w, h, 0.6, 1.0, 0.0);
        for (int i = 0; i < w * h; i++)
            for (int c = 0; c < 3; c++)
                P.color.data[3 * i + c] = base[c] * k;
        nprfx_image in[IN_N], out = th_image(w, h, 3, NULL);
        plane_inputs(&P, &pam, in);
        pparams p = defaults();
        set(&p, "anchor_space", 1);
        set(&p, "size", 12);
        CHECK_OK(render_at(in, &p, g < 0 ? &ref : &out, 1, NULL));
        for (int i = 0; i < 3 * w * h; i++) {
            if (g < 0) {
                nonfinite += !isfinite(ref.data[i]);
                continue;
            }
            nonfinite += !isfinite(out.data[i]);
            double e = fabs(out.data[i] / k - ref.data[i]);
            if (e > worst) worst = e;
        }
        if (g < 0)
            for (int i = 0; i < w * h; i++) {
                double y = luma(ref.data + 3 * i);
                sum += y;
                sum2 += y * y;
            }
        nprfx_image_free(&out);
        free_plane(&P);
    }
    double n = (double)w * h, sd = sqrt(fmax(sum2 / n - (sum / n) * (sum / n), 0.0));
    printf("HDR colour: strokes at luminance ~1 have sd %.3f; x5, x20, x100 differ from them (x "
           "the gain) by at most %.2g; %d values not finite\n",
           sd, worst, nonfinite);
    CHECK(sd > 0.02);
    CHECK(worst < 1e-4);
    CHECK(nonfinite == 0);
    nprfx_image_free(&ref);
    nprfx_image_free(&pam);
}

/* ---- tone ---- */

static double mean_surface_luma(const nprfx_image *out, const nprfx_image *depth)
{
    double s = 0.0;
    long long n = 0;
    int w = nprfx_rect_width(out->bounds), h = nprfx_rect_height(out->bounds);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            if (!(nprfx_image_at(depth, x, y)[0] < 1e9f)) continue;
            s += luma(nprfx_image_at(out, x, y));
            n++;
        }
    return n ? s / n : NAN;
}

static void test_tone(void)
{
    int w = 128, h = 96;
    nprfx_image plate = th_synth(ctx, "orbit", 24, w, h);
    nprfx_image tone = th_image(w, h, 1, NULL), out = th_image(w, h, 3, NULL);
    nprfx_image grey = th_image(w, h, 3, NULL);
    for (int i = 0; i < w * h * 3; i++)
        grey.data[i] = 0.5f;
    nprfx_image pams[2];
    memset(&pams[0], 0, sizeof pams[0]); /* the builtin */
    pams[1] = test_pam(5, 32, 0);
    nprfx_image depth = nprfx_image_channels(&plate, th_synth_channel("Z"), 1);
    for (int q = 0; q < 2; q++) {
        nprfx_image in[IN_N];
        memset(in, 0, sizeof in);
        in[IN_ANCHOR] = nprfx_image_channels(&plate, th_synth_channel("Pref.X"), 3);
        in[IN_TONE] = tone;
        in[IN_COLOR] = grey;
        in[IN_DEPTH] = depth;
        in[IN_ID] = nprfx_image_channels(&plate, th_synth_channel("id"), 1);
        in[IN_PAM] = pams[q];
        pparams p = defaults();
        set(&p, "size", 10);
        double prev = -1e9, first = 0, last = 0;
        int rising = 1;
        printf("tone sweep (%s PAM): mean luminance", q ? "test" : "builtin");
        for (int k = 0; k <= 10; k++) {
            for (int i = 0; i < w * h; i++)
                tone.data[i] = (float)(k / 10.0);
            CHECK_OK(render_at(in, &p, &out, 1, NULL));
            double m = mean_surface_luma(&out, &depth);
            printf(" %.4f", m);
            rising &= m > prev + 1e-4;
            prev = m;
            if (k == 0) first = m;
            last = m;
        }
        printf("\n");
        CHECK(rising);
        CHECK(last - first > 0.3);
        /* clamped: beyond the ends reads as the ends */
        nprfx_image ref = th_image(w, h, 3, NULL);
        for (int i = 0; i < w * h; i++)
            tone.data[i] = 1.0f;
        CHECK_OK(render_at(in, &p, &ref, 1, NULL));
        for (int i = 0; i < w * h; i++)
            tone.data[i] = 1.7f;
        CHECK_OK(render_at(in, &p, &out, 1, NULL));
        CHECK(memcmp(ref.data, out.data, sizeof(float) * 3 * w * h) == 0);
        for (int i = 0; i < w * h; i++)
            tone.data[i] = 0.0f;
        CHECK_OK(render_at(in, &p, &ref, 1, NULL));
        for (int i = 0; i < w * h; i++)
            tone.data[i] = -0.5f;
        CHECK_OK(render_at(in, &p, &out, 1, NULL));
        CHECK(memcmp(ref.data, out.data, sizeof(float) * 3 * w * h) == 0);
        nprfx_image_free(&ref);

        /* a varying tone (the plate's diffuse light), binned in ten steps */
        nprfx_image dif = nprfx_image_channels(&plate, th_synth_channel("diffuse"), 1);
        in[IN_TONE] = dif;
        CHECK_OK(render_at(in, &p, &out, 1, NULL));
        double sum[10] = {0};
        long long cnt[10] = {0};
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                if (!(nprfx_image_at(&depth, x, y)[0] < 1e9f)) continue;
                double t = nprfx_image_at(&dif, x, y)[0];
                int b = (int)(t * 10.0);
                b = b < 0 ? 0 : (b > 9 ? 9 : b);
                sum[b] += luma(nprfx_image_at(&out, x, y));
                cnt[b]++;
            }
        printf("binned by the diffuse tone:");
        double pm = -1e9;
        int ok = 1, bins = 0;
        for (int b = 0; b < 10; b++) {
            if (cnt[b] < 30) continue;
            double m = sum[b] / cnt[b];
            printf(" [%d] %.3f", b, m);
            ok &= m > pm - 0.01;
            pm = m;
            bins++;
        }
        printf("\n");
        CHECK(ok && bins >= 5);
    }
    nprfx_image_free(&pams[1]);
    nprfx_image_free(&grey);
    nprfx_image_free(&tone);
    nprfx_image_free(&out);
    nprfx_image_free(&plate);
}

/* ---- coherence with a moving light ---- */

/* Pixels of cur visible in prev: on a surface, the previous position inside the frame, on the
 * same object at a similar depth (all four bilinear taps). */
static nprfx_image visible_moving(const nprfx_image *cur, const nprfx_image *prev)
{
    int w = cur->bounds.x1, h = cur->bounds.y1;
    int cid = th_synth_channel("id"), cz = th_synth_channel("Z"),
        cmx = th_synth_channel("motion_prev.X");
    nprfx_image m = th_image(w, h, 1, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = nprfx_image_at(cur, x, y);
            double px = x + p[cmx], py = y + p[cmx + 1];
            int ok = p[cz] < 1e9f && px >= 0 && py >= 0 && px <= w - 1 && py <= h - 1 &&
                     fabsf(p[cmx]) + fabsf(p[cmx + 1]) > 0.05f;
            for (int k = 0; k < 4 && ok; k++) {
                int xx = (int)floor(px) + (k & 1), yy = (int)floor(py) + (k >> 1);
                if (xx > w - 1) xx = w - 1;
                if (yy > h - 1) yy = h - 1;
                const float *q = nprfx_image_at(prev, xx, yy);
                ok = q[cid] == p[cid] && fabsf(q[cz] - p[cz]) < 0.1f * p[cz];
            }
            m.data[y * w + x] = (float)ok;
        }
    return m;
}

/* The tone under a light that turns about the vertical by 4 degrees a frame. */
static void moving_light_tone(const nprfx_image *plate, int frame, nprfx_image *tone)
{
    int cn = th_synth_channel("N.X");
    double a = 4.0 * frame * 3.14159265358979 / 180.0;
    double L[3] = {0.5 * cos(a), 0.6, 0.5 * sin(a) + 0.4};
    double n = sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
    int w = tone->bounds.x1, h = tone->bounds.y1;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = nprfx_image_at(plate, x, y);
            double d = (p[cn] * L[0] + p[cn + 1] * L[1] + p[cn + 2] * L[2]) / n;
            tone->data[y * w + x] = (float)(0.15 + 0.85 * (d > 0 ? d : 0));
        }
}

static void luma_image(const nprfx_image *rgb, nprfx_image *y)
{
    int n = rgb->bounds.x1 * rgb->bounds.y1;
    for (int i = 0; i < n; i++)
        y->data[i] = (float)luma(rgb->data + 3 * i);
}

static void test_coherence(void)
{
    int w = 256, h = 192, f = 24;
    nprfx_image plate[2] = {th_synth(ctx, "orbit", f - 1, w, h), th_synth(ctx, "orbit", f, w, h)};
    nprfx_image screen = th_image(w, h, 2, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            screen.data[2 * (y * w + x)] = (float)(x / 256.0);
            screen.data[2 * (y * w + x) + 1] = (float)(y / 256.0);
        }
    nprfx_image grey = th_image(w, h, 3, NULL);
    for (int i = 0; i < w * h * 3; i++)
        grey.data[i] = 0.55f;
    nprfx_image lum[2][2]; /* [anchored, shower door][frame] */
    for (int k = 0; k < 2; k++) {
        nprfx_image tone = th_image(w, h, 1, NULL);
        moving_light_tone(&plate[k], f - 1 + k, &tone);
        for (int mode = 0; mode < 2; mode++) {
            nprfx_image in[IN_N], out = th_image(w, h, 3, NULL);
            memset(in, 0, sizeof in);
            in[IN_ANCHOR] =
                mode == 0 ? nprfx_image_channels(&plate[k], th_synth_channel("Pref.X"), 3) : screen;
            in[IN_TONE] = tone;
            in[IN_COLOR] = grey;
            in[IN_DEPTH] = nprfx_image_channels(&plate[k], th_synth_channel("Z"), 1);
            in[IN_ID] = nprfx_image_channels(&plate[k], th_synth_channel("id"), 1);
            pparams p = defaults();
            set(&p, "size", 16);
            if (mode == 1) set(&p, "anchor_space", 1);
            CHECK_OK(render_at(in, &p, &out, f - 1 + k, NULL));
            lum[mode][k] = th_image(w, h, 1, NULL);
            luma_image(&out, &lum[mode][k]);
            nprfx_image_free(&out);
        }
        nprfx_image_free(&tone);
    }
    nprfx_image mask = visible_moving(&plate[1], &plate[0]);
    nprfx_image mp = nprfx_image_channels(&plate[1], th_synth_channel("motion_prev.X"), 2);
    nprfx_warp_error a, s;
    CHECK_OK(nprfx_warp_compare(ctx, &lum[0][1], &lum[0][0], 0, &mp, &mask, &a));
    CHECK_OK(nprfx_warp_compare(ctx, &lum[1][1], &lum[1][0], 0, &mp, &mask, &s));
    printf("orbit with a moving light, %lld moving pixels: warp RMS error %.4f (correlation "
           "%.3f); shower door %.4f (%.3f)\n",
           a.count, a.rms, a.correlation, s.rms, s.correlation);
    CHECK(a.count > 1000);
    CHECK(a.rms < 0.7 * s.rms);
    for (int m = 0; m < 2; m++)
        for (int k = 0; k < 2; k++)
            nprfx_image_free(&lum[m][k]);
    nprfx_image_free(&mask);
    nprfx_image_free(&grey);
    nprfx_image_free(&screen);
    nprfx_image_free(&plate[0]);
    nprfx_image_free(&plate[1]);
}

/* ---- flow ---- */

/* correlation of a's luminance with b's shifted by (sx, sy) over the interior */
static double shifted_corr(const nprfx_image *a, const nprfx_image *b, int sx, int sy, int margin)
{
    int w = a->bounds.x1, h = a->bounds.y1;
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
    long long n = 0;
    for (int y = margin; y < h - margin; y++)
        for (int x = margin; x < w - margin; x++) {
            double u = luma(nprfx_image_at(a, x, y)), v = luma(nprfx_image_at(b, x - sx, y - sy));
            sa += u, sb += v, saa += u * u, sbb += v * v, sab += u * v;
            n++;
        }
    double cov = sab / n - sa / n * sb / n;
    return cov / sqrt((saa / n - sa / n * sa / n) * (sbb / n - sb / n * sb / n));
}

static void test_flow(void)
{
    int w = 128, h = 96;
    nprfx_image pam = test_pam(4, 32, 0);
    /* direction 30 degrees up from +x (y down: (cos, -sin)); a speed of 2 * sqrt(2)... kept to
     * whole pixels along both axes: direction (1, -1) at 2 sqrt(2) px per frame moves (2, -2) */
    plane P = make_plane(w, h, 0.5, 1.0, -1.0);
    nprfx_image in[IN_N];
    plane_inputs(&P, &pam, in);
    nprfx_image o1 = th_image(w, h, 3, NULL), o2 = th_image(w, h, 3, NULL);
    pparams p = defaults();
    set(&p, "anchor_space", 1);
    set(&p, "size", 32);
    set(&p, "jitter", 0.0);
    /* the model colour per pixel: dabs of the plane's colour would be a still pattern over the
     * moving strokes, and this measures the strokes */
    set(&p, "color_from", 1);
    set(&p, "texel", 1.0); /* the 32-px test maps at their own scale: a fine pattern to track */
    CHECK_OK(render_at(in, &p, &o1, 5, NULL));
    CHECK_OK(render_at(in, &p, &o2, 6, NULL));
    CHECK(memcmp(o1.data, o2.data, sizeof(float) * 3 * w * h) == 0); /* no flow: still */
    set(&p, "flow", 2.0 * sqrt(2.0));
    CHECK_OK(render_at(in, &p, &o1, 5, NULL));
    CHECK_OK(render_at(in, &p, &o2, 6, NULL));
    int bx = 0, by = 0;
    double best = -2;
    for (int sy = -4; sy <= 4; sy++)
        for (int sx = -4; sx <= 4; sx++) {
            double c = shifted_corr(&o2, &o1, sx, sy, 8);
            if (c > best) best = c, bx = sx, by = sy;
        }
    double still = shifted_corr(&o2, &o1, 0, 0, 8);
    printf("flow 2.83 px/frame along (1, -1): best shift (%d, %d), correlation %.4f (unshifted "
           "%.4f)\n",
           bx, by, best, still);
    CHECK(bx == 2 && by == -2);
    CHECK(best > 0.9);
    CHECK(still < best - 0.05);
    nprfx_image_free(&o1);
    nprfx_image_free(&o2);
    free_plane(&P);
    nprfx_image_free(&pam);
}

/* ---- invariance, state, errors ---- */

static void test_identity_and_state(void)
{
    int w = 96, h = 72;
    nprfx_image plate = th_synth(ctx, "orbit", 24, w, h);
    nprfx_image pam = test_pam(3, 24, 0);
    nprfx_image in[IN_N];
    memset(in, 0, sizeof in);
    in[IN_ANCHOR] = nprfx_image_channels(&plate, th_synth_channel("Pref.X"), 3);
    in[IN_TONE] = nprfx_image_channels(&plate, th_synth_channel("diffuse"), 1);
    in[IN_COLOR] = nprfx_image_channels(&plate, th_synth_channel("R"), 4);
    in[IN_DIRECTION] = nprfx_image_channels(&plate, th_synth_channel("motion_prev.X"), 2);
    in[IN_DEPTH] = nprfx_image_channels(&plate, th_synth_channel("Z"), 1);
    in[IN_ID] = nprfx_image_channels(&plate, th_synth_channel("id"), 1);
    in[IN_PAM] = pam;
    pparams p = defaults();
    set(&p, "size", 9);
    set(&p, "flow", 1.5);
    nprfx_pool *pool = NULL;
    nprfx_context *par = th_parallel_context(3, &pool);
    nprfx_context *serial = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    CHECK_OK(nprfx_context_create(&ci, &serial));
    nprfx_image ref;
    int bad = th_same_pixels(serial, par, node, in, p.v, w, h, 4, &ref);
    printf("bit identity across threads and tiles: %d of 5 ways differ\n", bad);
    CHECK(bad == 0);
    /* alpha passes, the background is the colour as it is */
    int cz = th_synth_channel("Z"), ca = th_synth_channel("A"), cr = th_synth_channel("R");
    int alpha_ok = 1, bg_ok = 1;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *q = nprfx_image_at(&plate, x, y), *o = nprfx_image_at(&ref, x, y);
            alpha_ok &= o[3] == q[ca];
            if (!(q[cz] < 1e9f)) bg_ok &= o[0] == q[cr] && o[1] == q[cr + 1] && o[2] == q[cr + 2];
        }
    CHECK(alpha_ok && bg_ok);

    /* a state slot: same pixels; a new PAM in the same instance is noticed */
    void *state = NULL;
    nprfx_image o = th_image(w, h, 4, NULL);
    CHECK_OK(render_at(in, &p, &o, 1, &state));
    CHECK_OK(render_at(in, &p, &o, 1, &state)); /* from the cache */
    CHECK(memcmp(o.data, ref.data, sizeof(float) * 4 * w * h) == 0);
    nprfx_image pam2 = test_pam(3, 24, 1);
    in[IN_PAM] = pam2;
    nprfx_image fresh = th_image(w, h, 4, NULL);
    CHECK_OK(render_at(in, &p, &fresh, 1, NULL));
    CHECK_OK(render_at(in, &p, &o, 1, &state));
    CHECK(memcmp(o.data, fresh.data, sizeof(float) * 4 * w * h) == 0);
    CHECK(memcmp(o.data, ref.data, sizeof(float) * 4 * w * h) != 0);
    node->state_free(state);

    /* a foreign image as the PAM: refused, naming the input and its size */
    nprfx_image foreign = th_image(100, 70, 3, NULL);
    in[IN_PAM] = foreign;
    nprfx_result r = render_at(in, &p, &o, 1, NULL);
    const char *msg = th_error(ctx);
    printf("foreign PAM: %s\n", msg);
    CHECK(r != NPRFX_OK);
    CHECK(strstr(msg, "'pam'") != NULL && strstr(msg, "100x70") != NULL);
    nprfx_image_free(&foreign);
    nprfx_image_free(&pam2);
    nprfx_image_free(&fresh);
    nprfx_image_free(&o);
    nprfx_image_free(&ref);
    nprfx_image_free(&pam);
    nprfx_image_free(&plate);
    nprfx_context_destroy(serial);
    nprfx_context_destroy(par);
    nprfx_pool_destroy(pool);
}

int main(void)
{
    nprfx_pool *pool = NULL;
    if (nprfx_pool_create(0, &pool) != NPRFX_OK) return 2;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    ci.executor = nprfx_pool_executor(pool);
    if (nprfx_context_create(&ci, &ctx) != NPRFX_OK) return 2;
    node = nprfx_node_find("pam-splat");
    CHECK(node != NULL);
    if (!node) return check_finish();
    test_formulas();
    test_eq10();
    test_hdr();
    test_tone();
    test_coherence();
    test_flow();
    test_identity_and_state();
    nprfx_context_destroy(ctx);
    nprfx_pool_destroy(pool);
    return check_finish();
}
