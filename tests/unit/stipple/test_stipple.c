/* The stipple node (docs/design.md §3.3): tone reproduction, blue noise on screen, exactly-once
 * ownership, the three modes' rules, determinism across threads and tiles, vector export and
 * errors. Temporal coherence and zoom live in test_stipple_motion.c. */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/filter.h"
#include "nprfx/metrics.h"
#include "nprfx/node.h"
#include "nprfx/stipple.h"
#include "support/stipple_export.h"

static nprfx_context *ctx1;         /* serial */
static nprfx_context *ctx4;         /* 4 threads */
static nprfx_stipple_sequence *seq; /* the tests' sequence, reused across calls */

/* Defaults with the tests' sequence (without one, every call would generate its own). */
static void default_params(nprfx_stipple_params *p)
{
    nprfx_stipple_params_default(p);
    p->sequence = seq;
}

static nprfx_stipple_inputs plain_inputs(const nprfx_image *tone)
{
    nprfx_stipple_inputs in = {tone, NULL, NULL, tone->bounds};
    return in;
}

/* ---- tone reproduction ---- */

/* PSNR between the Gaussian-blurred paper fraction (R of the output: ink black, paper white)
 * and the tone, away from the borders. */
static double tone_psnr(nprfx_context *ctx, const nprfx_stipple_params *p, const nprfx_image *tone,
                        double sigma)
{
    int w = nprfx_rect_width(tone->bounds), h = nprfx_rect_height(tone->bounds);
    nprfx_image out = th_image(w, h, 4, NULL), bl = th_image(w, h, 1, NULL);
    nprfx_stipple_inputs in = plain_inputs(tone);
    double psnr = 0;
    CHECK_OK(nprfx_stipple_draw(ctx, p, &in, tone->bounds, &out));
    nprfx_image r = nprfx_image_channels(&out, 0, 1);
    CHECK_OK(nprfx_gaussian_blur(ctx, &r, &bl, sigma, NPRFX_BORDER_CLAMP));
    nprfx_rect inner = nprfx_rect_make(12, 12, w - 12, h - 12);
    nprfx_image a = nprfx_image_crop(&bl, inner), b = nprfx_image_crop(tone, inner);
    CHECK_OK(nprfx_psnr(ctx, &a, 0, &b, 0, 1.0, &psnr));
    nprfx_image_free(&out);
    nprfx_image_free(&bl);
    return psnr;
}

static void test_tone(void)
{
    const int w = 384, h = 160;
    nprfx_image tone = th_image(w, h, 1, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            nprfx_image_at(&tone, x, y)[0] = (float)x / (w - 1);
    /* the defaults (dots of 6 px^2; radius and multitone at one dot per 6 px^2), averaged over
     * four seeds: a single 384x160 gradient holds too few dots to rank the modes reliably */
    double plain[3] = {0}, corrected[3] = {0}, worst_plain = 1e9;
    float curve0[NPRFX_STIPPLE_CURVE_SIZE];
    const int seeds = 4;
    for (int m = 0; m < 3; m++) {
        nprfx_stipple_params p;
        default_params(&p);
        p.mode = m;
        float curve[NPRFX_STIPPLE_CURVE_SIZE];
        CHECK_OK(nprfx_stipple_tone_curve(ctx4, &p, curve));
        if (m == 0) memcpy(curve0, curve, sizeof curve);
        for (int seed = 0; seed < seeds; seed++) {
            p.seed = (uint64_t)seed;
            p.tone_curve = NULL;
            double a = tone_psnr(ctx4, &p, &tone, 3.0);
            p.tone_curve = curve;
            double b = tone_psnr(ctx4, &p, &tone, 3.0);
            plain[m] += a / seeds;
            corrected[m] += b / seeds;
            worst_plain = fmin(worst_plain, a);
        }
    }
    printf("tone reproduction (gradient, blur sigma 3), mean PSNR uniform / radius / multitone:\n"
           "  Eq. 5-8 as written:   %.2f / %.2f / %.2f dB (worst single render %.2f)\n"
           "  with tone_correction: %.2f / %.2f / %.2f dB\n",
           plain[0], plain[1], plain[2], worst_plain, corrected[0], corrected[1], corrected[2]);
    CHECK(worst_plain >= 20.0);
    for (int m = 0; m < 3; m++)
        CHECK(corrected[m] >= plain[m] + 1.0);
    /* the paper's Fig. 9 ordering */
    CHECK(corrected[2] > corrected[1] && corrected[1] > corrected[0]);
    /* the curve is monotone, and the identity for light tones (no overlaps yet) */
    int mono = 1;
    for (int k = 1; k < NPRFX_STIPPLE_CURVE_SIZE; k++)
        mono &= curve0[k] >= curve0[k - 1];
    CHECK(mono && fabs(curve0[2] - 2.0 / (NPRFX_STIPPLE_CURVE_SIZE - 1)) < 0.01);
    nprfx_image_free(&tone);

    /* curves kept by a sequence are the measurement's floats, per mode, sizes, pens and seed:
     * the seed places the dots, so its curve differs, and asking for seed 0 again after seed 3
     * gives seed 0's, not the last one measured */
    nprfx_stipple_params p;
    default_params(&p);
    p.mode = NPRFX_STIPPLE_UNIFORM;
    float c0[NPRFX_STIPPLE_CURVE_SIZE], c3[NPRFX_STIPPLE_CURVE_SIZE];
    float k0[NPRFX_STIPPLE_CURVE_SIZE], k3[NPRFX_STIPPLE_CURVE_SIZE];
    CHECK_OK(nprfx_stipple_sequence_tone_curve(ctx4, seq, &p, k0));
    p.seed = 3;
    CHECK_OK(nprfx_stipple_tone_curve(ctx4, &p, c3));
    CHECK_OK(nprfx_stipple_sequence_tone_curve(ctx4, seq, &p, k3));
    p.seed = 0;
    CHECK_OK(nprfx_stipple_sequence_tone_curve(ctx4, seq, &p, c0));
    CHECK(!memcmp(k0, curve0, sizeof k0) && !memcmp(c0, curve0, sizeof c0));
    CHECK(!memcmp(k3, c3, sizeof k3) && memcmp(c3, curve0, sizeof c3) != 0);
}

/* ---- blue noise on screen ---- */

static void test_blue_noise(void)
{
    const int n = 256;
    nprfx_image tone = th_image(n, n, 1, NULL);
    float t = 0.75f;
    nprfx_image_fill(&tone, &t);
    nprfx_stipple_params p;
    default_params(&p);
    nprfx_stipple_inputs in = plain_inputs(&tone);
    nprfx_stipple *list = NULL;
    size_t count = 0;
    CHECK_OK(nprfx_stipple_collect(ctx4, &p, &in, tone.bounds, &list, &count));
    /* expected: darkness / area dots per px^2 */
    double expect = 0.25 / p.area * n * n;
    printf("blue noise: %zu dots (expected %.0f)\n", count, expect);
    CHECK(fabs(count - expect) < 0.05 * expect);

    /* minimum distance, normalised by the hexagonal-packing spacing of that density */
    double dmin2 = 1e30;
    for (size_t i = 0; i < count; i++)
        for (size_t k = i + 1; k < count; k++) {
            double dx = list[i].x - list[k].x, dy = list[i].y - list[k].y;
            double d2 = dx * dx + dy * dy;
            if (d2 < dmin2) dmin2 = d2;
        }
    double norm = sqrt(dmin2) / sqrt(2.0 / (sqrt(3.0) * count / ((double)n * n)));
    printf("blue noise: normalised minimum distance %.3f\n", norm);
    CHECK(norm >= 0.5);

    /* radially averaged power spectrum of the dot impulses: little energy below the peak */
    nprfx_image imp = th_image(n, n, 1, NULL);
    for (size_t i = 0; i < count; i++) {
        int x = (int)floor(list[i].x + 0.5), y = (int)floor(list[i].y + 0.5);
        if (x >= 0 && x < n && y >= 0 && y < n) nprfx_image_at(&imp, x, y)[0] += 1.0f;
    }
    int nb = 0;
    CHECK_OK(nprfx_radial_spectrum(ctx1, &imp, 0, NULL, &nb));
    double *spec = calloc((size_t)nb, sizeof(double));
    CHECK_OK(nprfx_radial_spectrum(ctx1, &imp, 0, spec, &nb));
    int peak = 1;
    for (int k = 1; k < nb; k++)
        if (spec[k] > spec[peak]) peak = k;
    double low = 0, high = 0;
    int nl = 0, nh = 0;
    for (int k = 1; k < peak / 2; k++)
        low += spec[k], nl++;
    for (int k = peak; k < nb; k++)
        high += spec[k], nh++;
    double ratio = nl && nh ? (low / nl) / (high / nh) : 1;
    printf("blue noise: spectrum peak at %.3f cycles/px, mean power below half the peak / "
           "above the peak = %.3f\n",
           (double)peak / n, ratio);
    CHECK(ratio < 0.2);
    free(spec);
    free(list);
    nprfx_image_free(&imp);
    nprfx_image_free(&tone);
}

/* ---- ownership: each sample exactly once ---- */

static void test_exactly_once(void)
{
    /* identity mapping, constant tone: the kept samples are exactly the indices below i_max
     * whose position falls in the frame's pixel squares, each once, where the sequence puts it */
    const int w = 200, h = 150;
    nprfx_image tone = th_image(w, h, 1, NULL);
    float t = 0.7f;
    nprfx_image_fill(&tone, &t);
    nprfx_stipple_params p;
    default_params(&p);
    nprfx_stipple_inputs in = plain_inputs(&tone);
    nprfx_stipple *list = NULL;
    size_t count = 0;
    CHECK_OK(nprfx_stipple_collect(ctx4, &p, &in, tone.bounds, &list, &count));
    const nprfx_ivs_index *ix = NULL;
    CHECK_OK(nprfx_stipple_sequence_index(ctx1, seq, 1, &ix));
    double g = 1.0 - (double)t, px = p.plane_scale * p.tile; /* pixels per sequence unit */
    int limit = (int)(g / p.area * px * px);
    /* the frame's sequence rectangle, less the object offset (unknown here): find it from one
     * stipple, whose sample position is known */
    CHECK(count > 0 && ix && limit > 0);
    if (!count || !ix) return;
    float q[2];
    nprfx_ivs_index_point(ix, list[0].sample, q);
    double ou = q[0] - list[0].x / px, ov = q[1] - list[0].y / px;
    ou -= floor(ou);
    ov -= floor(ov);
    size_t want = 0, placed = 0;
    for (int k = 0; k < limit; k++) {
        nprfx_ivs_index_point(ix, k, q);
        for (int ty = -1; ty <= 1; ty++)
            for (int tx = -1; tx <= 1; tx++) {
                double x = (q[0] + tx - ou) * px, y = (q[1] + ty - ov) * px;
                if (x >= -0.5 && x < w - 0.5 && y >= -0.5 && y < h - 0.5) want++;
            }
    }
    for (size_t i = 0; i < count; i++) {
        nprfx_ivs_index_point(ix, list[i].sample, q);
        double x = (q[0] - ou) * px, y = (q[1] - ov) * px;
        x -= px * floor((x - list[i].x) / px + 0.5);
        y -= px * floor((y - list[i].y) / px + 0.5);
        if (fabs(x - list[i].x) < 1e-6 && fabs(y - list[i].y) < 1e-6) placed++;
    }
    printf("exactly once: %zu stipples, %zu expected, %zu at their sequence position\n", count,
           want, placed);
    CHECK(count == want);
    CHECK(placed == count);
    free(list);
    nprfx_image_free(&tone);
}

/* ---- a warped UV field with several objects, for determinism and duplicates ---- */

typedef struct scene {
    nprfx_image tone, uv, id;
} scene;

static scene make_scene(int w, int h)
{
    scene s = {th_image(w, h, 1, NULL), th_image(w, h, 2, NULL), th_image(w, h, 1, NULL)};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double cx = x - 0.5 * w, cy = y - 0.5 * h;
            /* a perspective-like warp: scale grows across the frame, plus a rotation */
            double z = 1.0 + 0.004 * (x + 0.5 * y);
            double u = (0.8 * cx - 0.6 * cy) / (300.0 * z), v = (0.6 * cx + 0.8 * cy) / (300.0 * z);
            int id = cx * cx + cy * cy < 0.1 * w * h ? 3 : (x < w / 2 ? 1 : 2);
            if (id == 3) u = 2 * u + 5, v = 2 * v; /* its own UV chart */
            nprfx_image_at(&s.uv, x, y)[0] = (float)u;
            nprfx_image_at(&s.uv, x, y)[1] = (float)v;
            nprfx_image_at(&s.id, x, y)[0] = (float)id;
            nprfx_image_at(&s.tone, x, y)[0] = (float)(0.5 + 0.45 * sin(0.05 * x) * cos(0.037 * y));
        }
    return s;
}

static void free_scene(scene *s)
{
    nprfx_image_free(&s->tone);
    nprfx_image_free(&s->uv);
    nprfx_image_free(&s->id);
}

static int cmp_stipple(const void *pa, const void *pb)
{
    const nprfx_stipple *a = pa, *b = pb;
    if (a->object != b->object) return a->object < b->object ? -1 : 1;
    if (a->sample != b->sample) return a->sample < b->sample ? -1 : 1;
    if (a->x != b->x) return a->x < b->x ? -1 : 1;
    return 0;
}

static void test_no_duplicates(void)
{
    const int w = 240, h = 180;
    scene s = make_scene(w, h);
    nprfx_stipple_params p;
    default_params(&p);
    p.tile = 0.1;
    /* the sequence read through the UVs alone: with anisotropy, two readings of it (levels)
     * may each place a sample of the same index, as different dots */
    p.anisotropy = 0;
    nprfx_stipple_inputs in = {&s.tone, &s.uv, &s.id, s.tone.bounds};
    nprfx_stipple *list = NULL;
    size_t count = 0;
    CHECK_OK(nprfx_stipple_collect(ctx4, &p, &in, s.tone.bounds, &list, &count));
    qsort(list, count, sizeof *list, cmp_stipple);
    /* one sample appears in several tile copies, but never twice at (nearly) one place */
    size_t dup = 0;
    for (size_t i = 0; i + 1 < count; i++)
        for (size_t k = i + 1;
             k < count && list[k].object == list[i].object && list[k].sample == list[i].sample; k++)
            if (fabs(list[k].x - list[i].x) < 2 && fabs(list[k].y - list[i].y) < 2) dup++;
    /* dot density follows the tone: sum of dot areas = ink, against the tone's darkness */
    double ink = 0, dark = 0;
    for (size_t i = 0; i < count; i++)
        ink += p.area;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            dark += 1.0 - nprfx_image_at(&s.tone, x, y)[0];
    printf("warped UV: %zu stipples, %zu duplicates, dot area / darkness = %.3f\n", count, dup,
           ink / dark);
    CHECK(dup == 0);
    CHECK(fabs(ink / dark - 1.0) < 0.05);
    free(list);
    free_scene(&s);
}

/* ---- filtered UVs at silhouettes and seams ---- */

/* Renderers filter the UV pass: along a silhouette the pixels on both sides hold a blend of
 * the two surfaces' UVs, and across a UV seam of the two charts'. Those pixels must not own a
 * footprint spanning the gap between the charts, which packed it with dots (a dark outline,
 * about twice the density in a 3 px band), nor leave a gap: the dot density along such an
 * edge stays about that of the surfaces. */
static double band_ratio(int seam)
{
    const int w = 240, h = 160, edge = w / 2;
    scene s = {th_image(w, h, 1, NULL), th_image(w, h, 2, NULL), th_image(w, h, 1, NULL)};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            /* object 1 left of the edge, object 2 (or a second chart of object 1) right of it,
             * each with its own planar UV chart; the two columns at the edge are blends */
            double ul = x / 200.0, vl = y / 200.0, ur = x / 200.0 + 0.6, vr = y / 200.0 + 0.3;
            double u = x < edge ? ul : ur, v = x < edge ? vl : vr;
            if (x == edge - 1) u = 0.75 * ul + 0.25 * ur, v = 0.75 * vl + 0.25 * vr;
            if (x == edge) u = 0.25 * ul + 0.75 * ur, v = 0.25 * vl + 0.75 * vr;
            nprfx_image_at(&s.uv, x, y)[0] = (float)u;
            nprfx_image_at(&s.uv, x, y)[1] = (float)v;
            nprfx_image_at(&s.id, x, y)[0] = (float)(seam || x < edge ? 1 : 2);
            nprfx_image_at(&s.tone, x, y)[0] = 0.6f;
        }
    nprfx_stipple_params p;
    default_params(&p);
    p.tile = 0.25;
    nprfx_stipple_inputs in = {&s.tone, &s.uv, &s.id, s.tone.bounds};
    nprfx_stipple *list = NULL;
    size_t count = 0;
    CHECK_OK(nprfx_stipple_collect(ctx4, &p, &in, s.tone.bounds, &list, &count));
    /* dots whose centre lies within 1.5 px of the edge, against bands as wide elsewhere */
    size_t band = 0, ref = 0;
    for (size_t i = 0; i < count; i++) {
        if (list[i].y < 8 || list[i].y > h - 9) continue;
        double x = list[i].x + 0.5;
        band += fabs(x - edge) < 1.5;
        ref += fabs(x - edge / 2) < 1.5;
        ref += fabs(x - 3 * edge / 2) < 1.5;
    }
    ref /= 2;
    free(list);
    free_scene(&s);
    return ref ? (double)band / ref : 0;
}

static void test_silhouettes(void)
{
    double sil = band_ratio(0), seam = band_ratio(1);
    printf("blended UVs at an edge: dot density along it / elsewhere = %.2f (silhouette), %.2f "
           "(seam)\n",
           sil, seam);
    CHECK(sil > 0.7 && sil < 1.35);
    CHECK(seam > 0.5 && seam < 1.35);
}

/* ---- the vector paths ---- */

/* One render of `in` per simd path (nprfx_stipple_params.simd), in the three modes: the AVX2
 * loops (where the CPU has them) must give the baseline's pixels bit for bit. Returns how many
 * renders differ. */
static int simd_differs(const nprfx_stipple_inputs *in, double tile)
{
    const int w = nprfx_rect_width(in->frame), h = nprfx_rect_height(in->frame);
    nprfx_image ref = th_image(w, h, 4, NULL), out = th_image(w, h, 4, NULL);
    const size_t bytes = sizeof(float) * 4 * (size_t)w * (size_t)h;
    int bad = 0;
    for (int mode = 0; mode < 3; mode++) {
        nprfx_stipple_params p;
        default_params(&p);
        p.tile = tile;
        p.mode = mode;
        p.simd = 1;
        CHECK_OK(nprfx_stipple_draw(ctx4, &p, in, ref.bounds, &ref));
        for (int simd = 0; simd <= 2; simd += 2) {
            p.simd = simd;
            memset(out.data, 0, bytes);
            CHECK_OK(nprfx_stipple_draw(ctx4, &p, in, out.bounds, &out));
            bad += memcmp(ref.data, out.data, bytes) != 0;
        }
    }
    nprfx_image_free(&ref);
    nprfx_image_free(&out);
    return bad;
}

static void test_simd_paths(void)
{
    /* the warped scene with three objects, some pixels without a UV, and UVs rounded to half
     * floats' steps in a band (whose differences disagree between sides) */
    const int w = 240, h = 180;
    scene s = make_scene(w, h);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float *uv = nprfx_image_at(&s.uv, x, y);
            if ((x * 7 + y * 13) % 97 == 0) uv[0] = NAN;
            if (y > 100 && y < 140)
                for (int c = 0; c < 2; c++)
                    uv[c] = ldexpf(roundf(ldexpf(uv[c], 10)), -10);
        }
    nprfx_stipple_inputs in = {&s.tone, &s.uv, &s.id, s.tone.bounds};
    int bad = simd_differs(&in, 0.1);
    free_scene(&s);
    /* a synthetic shot: spheres' UVs and ids, as the benchmark renders them */
    nprfx_image plate[3] = {th_image(320, 180, 1, NULL), th_image(320, 180, 2, NULL),
                            th_image(320, 180, 1, NULL)};
    const int tc[1] = {th_synth_channel("diffuse")}, ic[1] = {th_synth_channel("id")};
    const int uc[2] = {th_synth_channel("UV.U"), th_synth_channel("UV.V")};
    CHECK_OK(nprfx_synth_render_channels(ctx1, "orbit", 3, tc, 1, &plate[0]));
    CHECK_OK(nprfx_synth_render_channels(ctx1, "orbit", 3, uc, 2, &plate[1]));
    CHECK_OK(nprfx_synth_render_channels(ctx1, "orbit", 3, ic, 1, &plate[2]));
    nprfx_stipple_inputs shot = {&plate[0], &plate[1], &plate[2], plate[0].bounds};
    bad += simd_differs(&shot, 1.0);
    for (int i = 0; i < 3; i++)
        nprfx_image_free(&plate[i]);
    printf("simd paths: %d of 12 renders differ from the baseline's\n", bad);
    CHECK(bad == 0);
}

/* ---- determinism through the node ---- */

static const nprfx_node_desc *node;
static void *node_state; /* the instance cache, as the CLI keeps it */

static nprfx_result node_render(nprfx_context *ctx, const nprfx_image *inputs,
                                const nprfx_value *params, nprfx_image *out, nprfx_rect window)
{
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = node;
    a.time = 1;
    a.render_scale = 1;
    a.frame = out->bounds;
    a.window = window;
    a.first_frame = a.last_frame = 1;
    a.inputs = inputs;
    a.params = params;
    a.output = out;
    a.state = &node_state;
    return nprfx_node_render(&a);
}

static void test_determinism(void)
{
    node = nprfx_node_find("stipple");
    CHECK(node != NULL);
    if (!node) return;
    const int w = 211, h = 157;
    scene s = make_scene(w, h);
    nprfx_image inputs[3] = {s.tone, s.uv, s.id};
    nprfx_value pv[16];
    CHECK(node->num_params <= 16);
    nprfx_node_defaults(node, pv);
    pv[th_param(node, "coverage")].v[0] = 1;
    pv[th_param(node, "tile")].v[0] = 0.1;
    for (int mode = 0; mode < 3; mode++) {
        pv[th_param(node, "mode")].v[0] = mode;
        nprfx_image ref = th_image(w, h, 5, NULL), b = th_image(w, h, 5, NULL);
        CHECK_OK(node_render(ctx1, inputs, pv, &ref, ref.bounds));
        CHECK_OK(node_render(ctx4, inputs, pv, &b, b.bounds));
        CHECK(memcmp(ref.data, b.data, sizeof(float) * 5 * w * h) == 0);
        /* odd tiles, rendered out of order */
        static const int tiles[][2] = {{37, 53}, {16, 16}, {211, 3}, {29, 157}};
        for (int tsel = 0; tsel < 4; tsel++) {
            int tw = tiles[tsel][0], th = tiles[tsel][1];
            memset(b.data, 0, sizeof(float) * 5 * w * h);
            for (int ty = ((h - 1) / th) * th; ty >= 0; ty -= th)
                for (int tx = 0; tx < w; tx += tw)
                    CHECK_OK(node_render(tsel % 2 ? ctx1 : ctx4, inputs, pv, &b,
                                         nprfx_rect_make(tx, ty, tx + tw, ty + th)));
            CHECK(memcmp(ref.data, b.data, sizeof(float) * 5 * w * h) == 0);
        }
        /* some ink, and colours follow the coverage channel */
        double cov = 0;
        int bad = 0;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                const float *o = nprfx_image_at(&ref, x, y);
                cov += o[4];
                bad += fabsf(o[0] - (1.0f - o[4])) > 1e-6f || o[3] != 1.0f;
            }
        printf("mode %d: mean coverage %.3f\n", mode, cov / (w * h));
        CHECK(cov > 0.05 * w * h && bad == 0);
        nprfx_image_free(&ref);
        nprfx_image_free(&b);
    }
    free_scene(&s);
}

/* ---- the modes' rules ---- */

static void test_modes(void)
{
    const int n = 128;
    nprfx_image tone = th_image(n, n, 1, NULL);
    float t = 0.5f;
    nprfx_image_fill(&tone, &t);
    nprfx_stipple_inputs in = plain_inputs(&tone);
    nprfx_stipple_params p;
    default_params(&p);
    nprfx_stipple *list = NULL;
    size_t count = 0;

    /* radius: one dot per a0 px^2, each of area g a0 */
    p.mode = NPRFX_STIPPLE_RADIUS;
    p.a0 = 12;
    CHECK_OK(nprfx_stipple_collect(ctx1, &p, &in, tone.bounds, &list, &count));
    int wrong = 0;
    for (size_t i = 0; i < count; i++)
        wrong += fabs(list[i].radius - sqrt(0.5 * 12 / 3.14159265358979)) > 1e-5;
    CHECK(wrong == 0 && fabs(count - n * n / 12.0) < 0.05 * n * n / 12.0);
    free(list);
    p.delta_min = 6.5; /* dots of 6 px^2 are below it */
    CHECK_OK(nprfx_stipple_collect(ctx1, &p, &in, tone.bounds, &list, &count));
    CHECK(count == 0 && list == NULL);

    /* multitone: tau = g a0 / size = 0.75 between pens 0.5 and 1: half the dots each, the
     * darker pen on the lower indices */
    p.mode = NPRFX_STIPPLE_MULTITONE;
    p.a0 = 8;
    p.area = 4;
    CHECK_OK(nprfx_stipple_parse_tones(ctx1, "0.5, 1", &p));
    t = 0.625f; /* g = 0.375, tau = 0.75 */
    nprfx_image_fill(&tone, &t);
    CHECK_OK(nprfx_stipple_collect(ctx1, &p, &in, tone.bounds, &list, &count));
    size_t dark = 0;
    int max_dark = -1, min_light = 1 << 30, other = 0;
    for (size_t i = 0; i < count; i++) {
        if (list[i].tone == 1.0f) {
            dark++;
            max_dark = list[i].sample > max_dark ? list[i].sample : max_dark;
        } else if (list[i].tone == 0.5f) {
            min_light = list[i].sample < min_light ? list[i].sample : min_light;
        } else {
            other++;
        }
    }
    printf("multitone: %zu dots, %.3f with the darker pen\n", count, (double)dark / count);
    CHECK(other == 0 && fabs((double)dark / count - 0.5) < 0.05 && max_dark < min_light);
    free(list);

    /* white paper: no dots in any mode */
    t = 1.0f;
    nprfx_image_fill(&tone, &t);
    for (int m = 0; m < 3; m++) {
        p.mode = m;
        CHECK_OK(nprfx_stipple_collect(ctx1, &p, &in, tone.bounds, &list, &count));
        CHECK(count == 0);
    }
    nprfx_image_free(&tone);
}

/* ---- exact disc area ---- */

static void test_disc_area(void)
{
    /* sparse dots, far apart and away from the frame edges: the ink laid down sums to their
     * areas, wherever they sit relative to the pixel grid */
    const int n = 256;
    nprfx_image tone = th_image(n, n, 1, NULL), out = th_image(n, n, 5, NULL);
    for (int y = 0; y < n; y++)
        for (int x = 0; x < n; x++)
            nprfx_image_at(&tone, x, y)[0] =
                x >= 16 && x < n - 16 && y >= 16 && y < n - 16 ? 0.99f : 1.0f;
    nprfx_stipple_params p;
    default_params(&p);
    p.area = 20;
    p.coverage_channel = 1;
    nprfx_stipple_inputs in = plain_inputs(&tone);
    nprfx_stipple *list = NULL;
    size_t count = 0, dots = 0;
    double worst = 0, rmin = 1e9;
    for (int seed = 0; seed < 4; seed++) {
        p.seed = (uint64_t)seed;
        CHECK_OK(nprfx_stipple_collect(ctx1, &p, &in, tone.bounds, &list, &count));
        CHECK_OK(nprfx_stipple_draw(ctx4, &p, &in, tone.bounds, &out));
        for (size_t i = 0; i < count; i++)
            for (size_t k = i + 1; k < count; k++)
                rmin = fmin(rmin, hypot(list[i].x - list[k].x, list[i].y - list[k].y));
        double sum = 0;
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++)
                sum += nprfx_image_at(&out, x, y)[4];
        if (count) worst = fmax(worst, fabs(sum - count * p.area) / (count * p.area));
        dots += count;
        free(list);
    }
    printf("disc area: %zu dots (closest pair %.1f px), worst relative ink error %.2g\n", dots,
           rmin, worst);
    CHECK(dots > 20 && rmin > 2 * sqrt(p.area / 3.14159265358979) + 2);
    CHECK(worst < 1e-5);
    nprfx_image_free(&tone);
    nprfx_image_free(&out);
}

/* ---- the sequence: caller-owned, grown on demand, shared by concurrent renders ---- */

typedef struct render_job {
    const nprfx_image *inputs;
    const nprfx_value *pv;
    nprfx_image *out;
    nprfx_rect window;
    void **state;
    nprfx_result r;
} render_job;

static void *render_thread(void *user)
{
    render_job *rj = user;
    nprfx_context *c = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    rj->r = nprfx_context_create(&ci, &c);
    if (rj->r != NPRFX_OK) return NULL;
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = c;
    a.node = node;
    a.time = 1;
    a.render_scale = 1;
    a.frame = rj->out->bounds;
    a.window = rj->window;
    a.first_frame = a.last_frame = 1;
    a.inputs = rj->inputs;
    a.params = rj->pv;
    a.output = rj->out;
    a.state = rj->state;
    rj->r = nprfx_node_render(&a);
    nprfx_context_destroy(c);
    return NULL;
}

static void test_sequence(void)
{
    /* an index once returned stays; shorter requests get the current one; long ones clamp */
    nprfx_stipple_sequence *s2 = NULL;
    const nprfx_ivs_index *a = NULL, *b = NULL, *c = NULL;
    CHECK_OK(nprfx_stipple_sequence_create(ctx1, &s2));
    CHECK_OK(nprfx_stipple_sequence_index(ctx1, s2, 100, &a));
    CHECK_OK(nprfx_stipple_sequence_index(ctx1, s2, 1 << 16, &b));
    CHECK(a && a == b && nprfx_ivs_index_count(a) == 1 << 16);
    CHECK_OK(nprfx_stipple_sequence_index(ctx1, s2, (1 << 16) + 1, &c));
    CHECK(c && c != a && nprfx_ivs_index_count(c) == 1 << 17);
    float pa[2], pc[2]; /* the prefix property: the longer one starts with the shorter */
    int same = 1;
    for (int k = 0; k < (1 << 16); k += 97) {
        nprfx_ivs_index_point(a, k, pa);
        nprfx_ivs_index_point(c, k, pc);
        same &= pa[0] == pc[0] && pa[1] == pc[1];
    }
    CHECK(same);
    CHECK(nprfx_stipple_sequence_index(ctx1, NULL, 10, &c) == NPRFX_ERR_INVALID_ARGUMENT);

    /* results do not depend on the sequence's length beyond what pixels keep: the tests'
     * sequence (grown by earlier tests), the longer s2, and a fresh one per call */
    const int w = 160, h = 120;
    scene sc = make_scene(w, h);
    nprfx_stipple_inputs in = {&sc.tone, &sc.uv, &sc.id, sc.tone.bounds};
    nprfx_stipple_params p;
    default_params(&p);
    p.tile = 0.1;
    p.coverage_channel = 1;
    nprfx_image r1 = th_image(w, h, 5, NULL), r2 = th_image(w, h, 5, NULL),
                r3 = th_image(w, h, 5, NULL);
    CHECK_OK(nprfx_stipple_draw(ctx4, &p, &in, r1.bounds, &r1));
    p.sequence = s2;
    CHECK_OK(nprfx_stipple_draw(ctx4, &p, &in, r2.bounds, &r2));
    p.sequence = NULL;
    CHECK_OK(nprfx_stipple_draw(ctx4, &p, &in, r3.bounds, &r3));
    CHECK(memcmp(r1.data, r2.data, sizeof(float) * 5 * w * h) == 0);
    CHECK(memcmp(r1.data, r3.data, sizeof(float) * 5 * w * h) == 0);
    nprfx_stipple_sequence_destroy(s2);

    /* the count of stipples drawn (bench's stipples/s): the tiles of a frame add up to the
     * whole frame's count, which is the number of stipples the frame's pixels own (collect)
     * but for the rare one whose centre sits exactly on the frame's right or bottom edge */
    long long whole = 0, tiled = 0;
    p.count = &whole;
    CHECK_OK(nprfx_stipple_draw(ctx4, &p, &in, r1.bounds, &r1));
    p.count = &tiled;
    for (int ty = 0; ty < h; ty += 37)
        for (int tx = 0; tx < w; tx += 53)
            CHECK_OK(
                nprfx_stipple_draw(ctx4, &p, &in, nprfx_rect_make(tx, ty, tx + 53, ty + 37), &r2));
    p.count = NULL;
    nprfx_stipple *owned = NULL;
    size_t nowned = 0;
    CHECK_OK(nprfx_stipple_collect(ctx4, &p, &in, r1.bounds, &owned, &nowned));
    printf("count: %lld stipples drawn in the frame, %lld in its tiles, %zu owned\n", whole, tiled,
           nowned);
    CHECK(whole > 100 && tiled == whole);
    CHECK(whole <= (long long)nowned && whole >= (long long)nowned - 2);
    free(owned);

    /* a host rendering tiles of a fresh instance on several threads at once: the state (and
     * its sequence) is created once, and the result is the serial one */
    node = nprfx_node_find("stipple");
    if (node) {
        nprfx_image inputs[3] = {sc.tone, sc.uv, sc.id};
        nprfx_value pv[16];
        nprfx_node_defaults(node, pv);
        pv[th_param(node, "coverage")].v[0] = 1;
        pv[th_param(node, "tile")].v[0] = 0.1;
        nprfx_image ref = th_image(w, h, 5, NULL), got = th_image(w, h, 5, NULL);
        CHECK_OK(node_render(ctx1, inputs, pv, &ref, ref.bounds));
        for (int round = 0; round < 3; round++) {
            void *fresh = NULL;
            memset(got.data, 0, sizeof(float) * 5 * w * h);
            enum { T = 4 };
            pthread_t th[T];
            render_job jobs[T];
            for (int t = 0; t < T; t++) {
                jobs[t] = (render_job){inputs, pv,
                                       &got,   nprfx_rect_make(0, t * h / T, w, (t + 1) * h / T),
                                       &fresh, NPRFX_OK};
                CHECK(pthread_create(&th[t], NULL, render_thread, &jobs[t]) == 0);
            }
            int ok = 1;
            for (int t = 0; t < T; t++) {
                pthread_join(th[t], NULL);
                ok &= jobs[t].r == NPRFX_OK;
            }
            CHECK(ok && fresh != NULL);
            CHECK(memcmp(ref.data, got.data, sizeof(float) * 5 * w * h) == 0);
            if (fresh) node->state_free(fresh);
        }
        nprfx_image_free(&ref);
        nprfx_image_free(&got);
    }
    printf("sequence: caller-owned, prefix-stable, same output fresh / grown / per call, "
           "concurrent first renders\n");
    nprfx_image_free(&r1);
    nprfx_image_free(&r2);
    nprfx_image_free(&r3);
    free_scene(&sc);
}

/* ---- export and errors ---- */

static int count_str(const char *s, const char *what)
{
    int n = 0;
    for (const char *q = strstr(s, what); q; q = strstr(q + 1, what))
        n++;
    return n;
}

static void test_export(void)
{
    node = nprfx_node_find("stipple");
    if (!node) return;
    CHECK_OK(nprfx_node_lint(ctx1, node)); /* params bound by offset, each to its own field */
    const int w = 64, h = 48;
    nprfx_image tone = th_image(w, h, 1, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            nprfx_image_at(&tone, x, y)[0] = (float)x / w;
    nprfx_image inputs[3] = {tone, {0}, {0}};
    nprfx_value pv[16];
    nprfx_node_defaults(node, pv);
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx1;
    a.node = node;
    a.render_scale = 1;
    a.frame = tone.bounds;
    a.window = tone.bounds;
    a.inputs = inputs;
    a.params = pv;
    a.state = &node_state;
    /* a text export needs no output image (nprfx_node_export checks one only when given) */
    nprfx_image out = th_image(w, h, 4, NULL);
    a.output = NULL;
    pv[th_param(node, "tone_correction")].v[0] = 0; /* compared with the plain core call below */
    char *csv = NULL, *svg = NULL;
    size_t len = 0;
    CHECK_OK(internal_stipple_node_export(&a, NPRFX_STIPPLE_CSV, &csv, &len));
    nprfx_stipple_params p;
    nprfx_stipple_params_default(&p); /* no sequence: the call builds its own */
    nprfx_stipple_inputs in = plain_inputs(&tone);
    nprfx_stipple *list = NULL;
    size_t count = 0;
    CHECK_OK(nprfx_stipple_collect(ctx1, &p, &in, tone.bounds, &list, &count));
    if (csv) {
        CHECK(strncmp(csv, "x,y,radius,tone,sample,object\n", 30) == 0);
        CHECK(count_str(csv, "\n") == (int)count + 1 && len == strlen(csv));
        if (count) { /* the first row is the first stipple, shifted to corner coordinates */
            double x, y, r, t;
            int smp, obj;
            CHECK(sscanf(csv + 30, "%lf,%lf,%lf,%lf,%d,%d", &x, &y, &r, &t, &smp, &obj) == 6);
            CHECK(fabs(x - (list[0].x + 0.5)) < 1e-3 && fabs(y - (list[0].y + 0.5)) < 1e-3);
            CHECK(smp == list[0].sample && obj == 0 && t == 1.0);
        }
    }
    CHECK_OK(internal_stipple_node_export(&a, NPRFX_STIPPLE_SVG, &svg, &len));
    if (svg) {
        CHECK(strstr(svg, "viewBox=\"0 0 64 48\"") != NULL);
        CHECK(count_str(svg, "<circle") == (int)count);
        CHECK(strstr(svg, "</svg>") != NULL);
    }
    printf("export: %zu stipples, csv and svg\n", count);
    free(csv);
    free(svg);
    free(list);

    /* errors name what is wrong */
    nprfx_image none[3] = {{0}, {0}, {0}};
    a.inputs = none;
    CHECK(internal_stipple_node_export(&a, NPRFX_STIPPLE_CSV, &csv, &len) ==
          NPRFX_ERR_MISSING_INPUT);
    CHECK(node_render(ctx1, none, pv, &out, out.bounds) == NPRFX_ERR_MISSING_INPUT);
    pv[th_param(node, "mode")].v[0] = NPRFX_STIPPLE_MULTITONE;
    pv[th_param(node, "tones")].s = "0.5, banana";
    CHECK(node_render(ctx1, inputs, pv, &out, out.bounds) == NPRFX_ERR_PARSE);
    printf("bad tones: %s\n", th_error(ctx1));
    pv[th_param(node, "tones")].s = "0.5, 0.3";
    CHECK(node_render(ctx1, inputs, pv, &out, out.bounds) == NPRFX_ERR_OUT_OF_RANGE);
    pv[th_param(node, "tones")].s = "0.5, 1";
    CHECK_OK(node_render(ctx1, inputs, pv, &out, out.bounds));
    nprfx_image bad = th_image(w, h, 3, NULL);
    CHECK(node_render(ctx1, inputs, pv, &bad, bad.bounds) == NPRFX_ERR_INVALID_ARGUMENT);
    nprfx_image_free(&bad);
    nprfx_image_free(&out);
    nprfx_image_free(&tone);
}

/* ---- foreshortening ---- */

/* The resultant length R = |mean exp(2 i phi)| of the directions phi from each dot to its
 * nearest neighbour, over the dots at least `margin` px inside the frame: 0 when no direction
 * is preferred, 1 when every dot's nearest neighbour lies along one line (rows). */
static double nn_orientation(const nprfx_stipple *l, size_t n, int w, int h, double margin)
{
    double c = 0, sn = 0;
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        if (l[i].x < margin || l[i].y < margin || l[i].x > w - margin || l[i].y > h - margin)
            continue;
        double best = 1e30, bx = 0, by = 0;
        for (size_t k = 0; k < n; k++) {
            double dx = l[k].x - l[i].x, dy = l[k].y - l[i].y, d2 = dx * dx + dy * dy;
            if (k != i && d2 < best) best = d2, bx = dx, by = dy;
        }
        double phi = atan2(by, bx);
        c += cos(2 * phi);
        sn += sin(2 * phi);
        m++;
    }
    return m ? hypot(c, sn) / (double)m : 1.0;
}

/* A plane seen at a grazing angle (the screen squeezes it 6x along y: v changes six times as
 * fast per pixel as u) against the same plane head-on. Read through the UVs alone, the
 * sequence's dots are squeezed with the surface and line up in rows; read through the
 * foreshortening (anisotropy, the default), they are as evenly spread as head-on, with the
 * same ink. */
static void test_foreshortening(void)
{
    const int w = 160, h = 120;
    double r[2][2], ink[2][2];
    for (int squeeze = 0; squeeze < 2; squeeze++)
        for (int an = 0; an < 2; an++) {
            nprfx_image tone = th_image(w, h, 1, NULL), uv = th_image(w, h, 2, NULL);
            for (int y = 0; y < h; y++)
                for (int x = 0; x < w; x++) {
                    nprfx_image_at(&tone, x, y)[0] = 0.8f;
                    nprfx_image_at(&uv, x, y)[0] = (float)(x / 400.0);
                    nprfx_image_at(&uv, x, y)[1] = (float)(y * (squeeze ? 6.0 : 1.0) / 400.0);
                }
            nprfx_stipple_params p;
            default_params(&p);
            p.anisotropy = an;
            nprfx_stipple_inputs in = {&tone, &uv, NULL, tone.bounds};
            nprfx_stipple *list = NULL;
            size_t n = 0;
            CHECK_OK(nprfx_stipple_collect(ctx4, &p, &in, tone.bounds, &list, &n));
            r[squeeze][an] = nn_orientation(list, n, w, h, 6);
            ink[squeeze][an] = 0; /* dots, one fading between levels by its tone */
            for (size_t k = 0; k < n; k++)
                ink[squeeze][an] += list[k].tone;
            free(list);
            nprfx_image_free(&tone);
            nprfx_image_free(&uv);
        }
    printf("nearest-neighbour orientation R (ink in dots): head-on %.3f (%.0f) / %.3f (%.0f); "
           "squeezed 6x along y, UVs alone %.3f (%.0f), through the foreshortening %.3f (%.0f)\n",
           r[0][0], ink[0][0], r[0][1], ink[0][1], r[1][0], ink[1][0], r[1][1], ink[1][1]);
    CHECK(r[0][1] < 0.1 && r[0][0] < 0.1);
    CHECK(r[1][0] > 0.25); /* the rows the test is for */
    CHECK(r[1][1] < 0.1);
    CHECK(fabs(ink[1][1] / ink[1][0] - 1.0) < 0.05);
}

int main(void)
{
    nprfx_pool *pool = NULL;
    CHECK_OK(nprfx_pool_create(4, &pool));
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    CHECK_OK(nprfx_context_create(&ci, &ctx1));
    ci.executor = nprfx_pool_executor(pool);
    CHECK_OK(nprfx_context_create(&ci, &ctx4));
    CHECK_OK(nprfx_stipple_sequence_create(ctx1, &seq));
    test_tone();
    test_blue_noise();
    test_exactly_once();
    test_no_duplicates();
    test_foreshortening();
    test_silhouettes();
    test_simd_paths();
    test_determinism();
    test_modes();
    test_disc_area();
    test_sequence();
    test_export();
    if (node && node->state_free) node->state_free(node_state);
    nprfx_stipple_sequence_destroy(seq);
    nprfx_context_destroy(ctx1);
    nprfx_context_destroy(ctx4);
    nprfx_pool_destroy(pool);
    return check_finish();
}
