/* Unit tests for core/gabor/gabor.c and the gabor-splat node: the level-of-detail rule (sum of squared
 * weights = wanted density, continuity, bounded level count), the variance normaliser against a
 * numerical integral, unit variance on a flat plane for each amplitude law and with
 * supersampling, the unit01 mapping, errors, bit-identical output across thread counts, tile
 * splits and SIMD paths, kernels never crossing object-id or depth edges, background, the
 * per-pixel orientation / frequency inputs, the frame border, and the render scale.
 * Renders call the node's render function through its descriptor on synthetic plates. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/gabor.h"
#include "nprfx/metrics.h"
#include "nprfx/node.h"
#include "nprfx/synth.h"

static const double k_pi = 3.14159265358979323846;

/* ---- helpers: synthetic plates and direct calls of the node's render function ---- */

static nprfx_context *ctx;
static const nprfx_node_desc *node;

static void set(nprfx_value *pv, const char *name, const char *text)
{
    int i = th_param(node, name);
    if (nprfx_param_parse(ctx, node, &node->params[i], text, &pv[i]) != NPRFX_OK) {
        fprintf(stderr, "bad value %s for %s: %s\n", text, name, th_error(ctx));
        exit(2);
    }
}

/* The inputs of the node from a synth plate: anchor Pref (or UV), depth Z, id. */
typedef struct gin {
    nprfx_image in[8];
} gin;

static gin plate_inputs(const nprfx_image *plate, int uv, int with_id)
{
    gin g;
    memset(&g, 0, sizeof g);
    g.in[th_input(node, "anchor")] =
        uv ? nprfx_image_channels(plate, th_synth_channel("UV.U"), 2)
           : nprfx_image_channels(plate, th_synth_channel("Pref.X"), 3);
    g.in[th_input(node, "depth")] = nprfx_image_channels(plate, th_synth_channel("Z"), 1);
    if (with_id)
        g.in[th_input(node, "id")] = nprfx_image_channels(plate, th_synth_channel("id"), 1);
    return g;
}

static nprfx_result render_with(nprfx_context *c, const gin *g, const nprfx_value *pv,
                                nprfx_image *out, nprfx_rect window, double scale)
{
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = c;
    a.node = node;
    a.time = 1;
    a.render_scale = scale;
    a.frame = out->bounds;
    a.window = window;
    a.first_frame = a.last_frame = 1;
    a.inputs = g->in;
    a.params = pv;
    a.output = out;
    return nprfx_node_render(&a);
}

static nprfx_result render(const gin *g, const nprfx_value *pv, nprfx_image *out)
{
    return render_with(ctx, g, pv, out, out->bounds, 1.0);
}

static int same_pixels(const nprfx_image *a, const nprfx_image *b)
{
    size_t n = (size_t)nprfx_rect_width(a->bounds) * nprfx_rect_height(a->bounds) * a->channels;
    return a->channels == b->channels && !memcmp(a->data, b->data, n * sizeof(float));
}

/* ---- the level-of-detail rule ---- */

static void test_lod_weights(void)
{
    int bad_sum = 0, bad_count = 0, bad_range = 0, bad_cont = 0;
    for (int W = 1; W <= 6; W++) {
        double prev[48] = {0};
        int prev_first = 0, prev_n = 0;
        for (int i = 0; i <= 4000; i++) {
            double mu = pow(10.0, -2.0 + 14.0 * i / 4000.0);
            double w2[48];
            int first = -1;
            int n = nprfx_gabor_lod_weights(mu, W, &first, w2, 48);
            double sum = 0.0;
            for (int k = 0; k < n; k++) {
                sum += w2[k] * pow(4.0, first + k);
                if (!(w2[k] >= 0.0 && w2[k] <= 1.0)) bad_range++;
            }
            if (fabs(sum - mu) > 1e-9 * mu) bad_sum++;
            if (n > W + 2) bad_count++;
            /* continuity: over a 0.8% step of mu, no level's squared weight moves by more than
             * the step allows (a fading weight moves by at most about 3 dmu / mu) */
            if (i > 0) {
                for (int l = 0; l < 48; l++) {
                    double a =
                        l >= prev_first && l < prev_first + prev_n ? prev[l - prev_first] : 0;
                    double b = l >= first && l < first + n ? w2[l - first] : 0;
                    if (fabs(a - b) > 0.05) bad_cont++;
                }
            }
            memcpy(prev, w2, sizeof w2);
            prev_first = first;
            prev_n = n;
        }
    }
    CHECK(bad_sum == 0);
    CHECK(bad_count == 0);
    CHECK(bad_range == 0);
    CHECK(bad_cont == 0);
    /* the documented special cases */
    double w2[8];
    int first = -1;
    int n = nprfx_gabor_lod_weights(0.25, 3, &first, w2, 8);
    CHECK(n == 1 && first == 0);
    CHECK_NEAR(w2[0], 0.25, 1e-12); /* one point standing for a quarter: weight sqrt(0.25) */
    n = nprfx_gabor_lod_weights(1.0 + 4.0 + 16.0, 3, &first, w2, 8); /* levels 0..2 whole */
    CHECK(first == 0 && n == 3);
    CHECK_NEAR(w2[0] + w2[1] + w2[2], 3.0, 1e-12);
    /* docs/design.md's rule below W: level L+1 fades in with (D - D_L) / 4^(L+1) */
    n = nprfx_gabor_lod_weights(1.0 + 4.0 + 8.0, 3, &first, w2, 8);
    CHECK(first == 0 && n == 3);
    CHECK_NEAR(w2[2], 0.5, 1e-12);
    printf("lod: sums, counts, ranges and continuity hold for W = 1..6 over mu = 1e-2..1e12\n");
}

/* ---- the variance normaliser ---- */

static void test_variance_formula(void)
{
    const double F[3] = {0.02, 0.1, 0.3};
    for (int k = 0; k < 3; k++) {
        nprfx_gabor_params p;
        nprfx_gabor_params_default(&p);
        p.frequency = F[k];
        p.radius = 12.0;
        p.orientation = 30.0;
        double a = nprfx_gabor_bandwidth(p.radius);
        CHECK_NEAR(exp(-k_pi * a * a * p.radius * p.radius), 0.05, 1e-12);
        /* lambda E[v^2] times the integral of g^2 over the truncation disk, numerically */
        double h = 0.05, sum = 0.0, wx = cos(30.0 * k_pi / 180.0), wy = -sin(30.0 * k_pi / 180.0);
        for (double y = -p.radius; y <= p.radius; y += h)
            for (double x = -p.radius; x <= p.radius; x += h) {
                if (x * x + y * y > p.radius * p.radius) continue;
                double g =
                    exp(-k_pi * a * a * (x * x + y * y)) * cos(2 * k_pi * F[k] * (x * wx + y * wy));
                sum += g * g * h * h;
            }
        double lambda = p.n0 / (k_pi * p.radius * p.radius);
        double expect = lambda / 3.0 * sum;
        double got = nprfx_gabor_variance(&p, 1.0);
        printf("variance normaliser at F0 %.2f: formula %.5f, integral %.5f\n", F[k], got, expect);
        CHECK_NEAR(got / expect, 1.0, 0.01);
    }
    nprfx_gabor_params p;
    nprfx_gabor_params_default(&p);
    double v1 = nprfx_gabor_variance(&p, 1.0);
    p.amplitude = NPRFX_GABOR_AMP_SIGN;
    CHECK_NEAR(nprfx_gabor_variance(&p, 1.0) / v1, 3.0, 1e-12);
    p.amplitude = NPRFX_GABOR_AMP_UNIFORM;
    p.supersample = 2;
    double v2 = nprfx_gabor_variance(&p, 1.0);
    CHECK(v2 < v1 && v2 > 0.9 * v1); /* the 2x2 box attenuates 0.1 cycles/px a little */
}

/* ---- the descriptor, errors ---- */

static void test_descriptor(void)
{
    const char *in_names[] = {"anchor", "depth", "id", "orientation", "frequency"};
    for (int i = 0; i < 5; i++)
        CHECK(nprfx_node_input_index(node, in_names[i]) >= 0);
    const char *p_names[] = {"anchor_space",    "frequency",   "orientation", "isotropic",
                             "radius",          "n0",          "seed",        "cell",
                             "depth_tolerance", "supersample", "output",      "contrast",
                             "amplitude",       "lod_levels",  "depth_test",  "points"};
    for (int i = 0; i < 16; i++)
        CHECK(nprfx_node_param_index(node, p_names[i]) >= 0);
    CHECK(node->inputs[th_input(node, "id")].flags & NPRFX_INPUT_OPTIONAL);
    CHECK(node->inputs[th_input(node, "orientation")].flags & NPRFX_INPUT_OPTIONAL);
    CHECK(node->inputs[th_input(node, "frequency")].flags & NPRFX_INPUT_OPTIONAL);
    CHECK(!(node->inputs[th_input(node, "anchor")].flags & NPRFX_INPUT_OPTIONAL));
    CHECK(strstr(node->help, "Pref") && strstr(node->help, "Blender") && strstr(node->help, "UV"));
    CHECK(node->params[th_param(node, "radius")].flags & NPRFX_PARAM_PIXELS);
}

static void test_errors(void)
{
    nprfx_image plate = th_synth(ctx, "orbit", 24, 32, 24);
    nprfx_value pv[32];
    nprfx_node_defaults(node, pv);
    nprfx_image out = th_image(32, 24, 1, NULL);
    gin g = plate_inputs(&plate, 0, 1);
    gin none = g;
    none.in[th_input(node, "anchor")].data = NULL;
    CHECK(render(&none, pv, &out) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "anchor") != NULL);
    none = g;
    none.in[th_input(node, "depth")].data = NULL;
    CHECK(render(&none, pv, &out) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "depth") != NULL);
    /* a 3D anchor space with a 2-channel anchor */
    gin uv = plate_inputs(&plate, 1, 1);
    CHECK(render(&uv, pv, &out) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "anchor") != NULL);
    set(pv, "anchor_space", "uv");
    CHECK_OK(render(&uv, pv, &out));
    /* the points channel needs a 2-channel output */
    nprfx_node_defaults(node, pv);
    set(pv, "points", "1");
    CHECK(render(&g, pv, &out) == NPRFX_ERR_INVALID_ARGUMENT);
    /* out of range values are refused by the descriptor */
    nprfx_value v;
    CHECK(nprfx_param_parse(ctx, node, &node->params[th_param(node, "radius")], "0", &v) ==
          NPRFX_ERR_OUT_OF_RANGE);
    CHECK(nprfx_param_parse(ctx, node, &node->params[th_param(node, "anchor_space")], "world",
                            &v) != NPRFX_OK);
    nprfx_image_free(&out);
    nprfx_image_free(&plate);
}

/* ---- statistics on a flat plane ---- */

static void test_flat_plane(void)
{
    nprfx_image plate = th_synth(ctx, "translate", 0, 256, 256);
    gin g = plate_inputs(&plate, 0, 1);
    nprfx_image out = th_image(256, 256, 1, NULL), out2 = th_image(256, 256, 1, NULL);
    nprfx_value pv[32];
    const char *laws[3] = {"uniform", "sign", "gauss"};
    for (int k = 0; k < 4; k++) {
        double var = 0.0, mean = 0.0;
        for (int seed = 1; seed <= 3; seed++) {
            nprfx_node_defaults(node, pv);
            set(pv, "amplitude", laws[k < 3 ? k : 0]);
            if (k == 3) set(pv, "supersample", "2");
            set(pv, "radius", "10");
            pv[th_param(node, "seed")].v[0] = seed;
            CHECK_OK(render(&g, pv, &out));
            nprfx_stats st;
            CHECK_OK(nprfx_image_stats(ctx, &out, 0, NULL, &st));
            var += st.variance / 3.0;
            mean += st.mean / 3.0;
        }
        printf("flat plane, %s%s: variance %.4f, mean %.4f\n", laws[k < 3 ? k : 0],
               k == 3 ? " supersample 2" : "", var, mean);
        CHECK_NEAR(var, 1.0, 0.1);
        CHECK_NEAR(mean, 0.0, 0.05);
    }
    /* unit01 = 0.5 + contrast * unit, exactly as float arithmetic gives it */
    nprfx_node_defaults(node, pv);
    CHECK_OK(render(&g, pv, &out));
    set(pv, "output", "unit01");
    set(pv, "contrast", "0.2");
    CHECK_OK(render(&g, pv, &out2));
    int bad = 0;
    for (int i = 0; i < 256 * 256; i++) {
        double u = (out2.data[i] - 0.5) / 0.2;
        if (fabs(u - out.data[i]) > 1e-5 * (1 + fabs(out.data[i]))) bad++;
    }
    CHECK(bad == 0);
    nprfx_image_free(&out);
    nprfx_image_free(&out2);
    nprfx_image_free(&plate);
}

/* The frame edge: kernels of surface points just outside the frame still reach into it
 * (virtual pixels extrapolate the anchors), so the variance does not fade at the border. */
static void test_frame_border(void)
{
    nprfx_image plate = th_synth(ctx, "translate", 3, 256, 256);
    gin g = plate_inputs(&plate, 0, 1);
    nprfx_image out = th_image(256, 256, 1, NULL);
    nprfx_value pv[32];
    double eb = 0, ec = 0;
    long long nb = 0, nc = 0;
    for (int seed = 0; seed < 4; seed++) {
        nprfx_node_defaults(node, pv);
        pv[th_param(node, "seed")].v[0] = seed;
        CHECK_OK(render(&g, pv, &out));
        for (int y = 0; y < 256; y++)
            for (int x = 0; x < 256; x++) {
                double v = out.data[y * 256 + x];
                int border = x < 4 || y < 4 || x >= 252 || y >= 252;
                int centre = x >= 64 && x < 192 && y >= 64 && y < 192;
                if (border) eb += v * v, nb++;
                if (centre) ec += v * v, nc++;
            }
    }
    double ratio = (eb / nb) / (ec / nc);
    printf("frame border: variance in the 4-pixel border / centre = %.3f\n", ratio);
    CHECK(ratio > 0.8 && ratio < 1.25);
    nprfx_image_free(&out);
    nprfx_image_free(&plate);
}

/* ---- determinism ---- */

static void test_determinism(void)
{
    nprfx_pool *pool = NULL;
    CHECK_OK(nprfx_pool_create(3, &pool));
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    ci.executor = nprfx_pool_executor(pool);
    nprfx_context *mt = NULL;
    CHECK_OK(nprfx_context_create(&ci, &mt));
    const char *scenes[2] = {"orbit", "dolly"};
    const int frames[2] = {24, 40};
    for (int sc = 0; sc < 2; sc++) {
        nprfx_image plate = th_synth(ctx, scenes[sc], frames[sc], 96, 72);
        gin g = plate_inputs(&plate, 0, 1);
        for (int variant = 0; variant < 3; variant++) {
            nprfx_value pv[32];
            nprfx_node_defaults(node, pv);
            set(pv, "radius", "9");
            set(pv, "points", "1");
            if (variant == 1) {
                set(pv, "isotropic", "1");
                set(pv, "depth_test", "soft");
                set(pv, "supersample", "2");
                set(pv, "amplitude", "gauss");
            }
            if (variant == 2) {
                set(pv, "depth_test", "off");
                set(pv, "output", "unit01");
                set(pv, "n0", "70");
            }
            nprfx_image ref = th_image(96, 72, 2, NULL), o = th_image(96, 72, 2, NULL);
            CHECK_OK(render(&g, pv, &ref));
            /* threads */
            CHECK_OK(render_with(mt, &g, pv, &o, o.bounds, 1.0));
            CHECK(same_pixels(&ref, &o));
            /* tile splits, rendered in a scrambled order */
            const int tiles[3][2] = {{16, 16}, {37, 23}, {96, 5}};
            for (int t = 0; t < 3; t++) {
                memset(o.data, 0, sizeof(float) * 96 * 72 * 2);
                int tw = tiles[t][0], th = tiles[t][1];
                int nx = (96 + tw - 1) / tw, ny = (72 + th - 1) / th;
                for (int k = 0; k < nx * ny; k++) {
                    int i = (k * 7) % (nx * ny); /* 7 is prime to every count here */
                    int x0 = (i % nx) * tw, y0 = (i / nx) * th;
                    nprfx_rect w =
                        nprfx_rect_intersect(o.bounds, nprfx_rect_make(x0, y0, x0 + tw, y0 + th));
                    CHECK_OK(render_with(t == 1 ? mt : ctx, &g, pv, &o, w, 1.0));
                }
                CHECK(same_pixels(&ref, &o));
            }
            /* the SIMD paths against each other, through the core (test_simd_paths goes further) */
            nprfx_gabor_params p;
            nprfx_gabor_params_default(&p);
            p.radius = 9;
            p.points = 1;
            p.isotropic = variant == 1;
            p.depth_test = variant == 1
                               ? NPRFX_GABOR_DEPTH_SOFT
                               : (variant == 2 ? NPRFX_GABOR_DEPTH_OFF : NPRFX_GABOR_DEPTH_HARD);
            p.supersample = variant == 1 ? 2 : 1;
            p.amplitude = variant == 1 ? NPRFX_GABOR_AMP_GAUSS : NPRFX_GABOR_AMP_UNIFORM;
            nprfx_gabor_inputs gi = {sizeof gi,
                                     &g.in[th_input(node, "anchor")],
                                     &g.in[th_input(node, "depth")],
                                     &g.in[th_input(node, "id")],
                                     NULL,
                                     NULL};
            nprfx_image s0 = th_image(96, 72, 2, NULL), s1 = th_image(96, 72, 2, NULL);
            for (int simd = 0; simd <= 3; simd++) {
                p.simd = simd;
                CHECK_OK(nprfx_gabor_render(ctx, &p, &gi, s1.bounds, simd ? &s1 : &s0, NULL));
                if (simd) CHECK(same_pixels(&s0, &s1));
            }
            nprfx_image_free(&s0);
            nprfx_image_free(&s1);
            nprfx_image_free(&ref);
            nprfx_image_free(&o);
        }
        nprfx_image_free(&plate);
    }
    nprfx_context_destroy(mt);
    nprfx_pool_destroy(pool);
    printf("determinism: threads, tile splits, render order and SIMD paths agree bit for bit\n");
}

/* Every vector path (0 the fastest, 2 the baseline ISA's vectors, 3 AVX2 where the CPU has it)
 * against the scalar one, bit for bit and with the same statistics: on plates large enough for
 * the vector block path (blocks inside the inputs) and through the variants that change code
 * paths: depth test modes, supersampling (2, 3), isotropy, the orientation input, staggered fade,
 * no id input, coverage-blended anchors, UV anchors, windows off the origin. */
static void test_simd_paths(void)
{
    const int w = 232, h = 168;
    nprfx_image orbit = th_synth(ctx, "orbit", 30, w, h), dolly = th_synth(ctx, "dolly", 20, w, h);
    nprfx_image trans = th_synth(ctx, "translate", 5, w, h);
    nprfx_image anchor4 = th_image(w, h, 4, NULL), angle = th_image(w, h, 1, NULL);
    int cp = th_synth_channel("Pref.X");
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *src = nprfx_image_at(&orbit, x, y);
            float *a = nprfx_image_at(&anchor4, x, y);
            a[0] = src[cp];
            a[1] = src[cp + 1];
            a[2] = src[cp + 2];
            a[3] = (x * 7 + y * 3) % 11 == 0 ? 0.5f : 1.0f; /* a sprinkling of blended pixels */
            nprfx_image_at(&angle, x, y)[0] = (float)(40.0 * sin(0.05 * x + 0.03 * y));
        }
    int bad = 0;
    for (int v = 0; v < 6; v++) {
        const nprfx_image *plate = v == 1 ? &dolly : (v == 5 ? &trans : &orbit);
        nprfx_image anchor = v == 5 ? nprfx_image_channels(plate, th_synth_channel("UV.U"), 2)
                                    : nprfx_image_channels(plate, cp, 3);
        nprfx_image depth = nprfx_image_channels(plate, th_synth_channel("Z"), 1);
        nprfx_image id = nprfx_image_channels(plate, th_synth_channel("id"), 1);
        nprfx_gabor_inputs gi = {sizeof gi, &anchor, &depth, &id, NULL, NULL};
        nprfx_gabor_params p;
        nprfx_gabor_params_default(&p);
        p.points = 1;
        switch (v) {
        case 0:
            p.radius = 12;
            break;
        case 1:
            p.isotropic = 1;
            p.depth_test = NPRFX_GABOR_DEPTH_SOFT;
            p.supersample = 2;
            p.radius = 7;
            p.n0 = 48;
            break;
        case 2:
            p.depth_test = NPRFX_GABOR_DEPTH_OFF;
            p.n0 = 90;
            p.radius = 6;
            gi.anchor = &anchor4;
            break;
        case 3:
            p.supersample = 3;
            p.radius = 5;
            p.fade = NPRFX_GABOR_FADE_STAGGERED;
            gi.orientation = &angle;
            break;
        case 4:
            p.amplitude = NPRFX_GABOR_AMP_SIGN;
            p.radius = 16;
            p.lod_levels = 2;
            gi.id = NULL;
            break;
        default:
            p.anchor_dims = 2;
            p.radius = 8;
            break;
        }
        nprfx_rect win =
            v % 2 ? nprfx_rect_make(17, 9, w - 5, h - 13) : nprfx_rect_make(0, 0, w, h);
        nprfx_image ref = th_image(w, h, 2, NULL), o = th_image(w, h, 2, NULL);
        nprfx_gabor_stats sref, so;
        p.simd = 1;
        CHECK_OK(nprfx_gabor_render(ctx, &p, &gi, win, &ref, &sref));
        CHECK(sref.kernels > 100);
        for (int simd = 0; simd <= 3; simd++) {
            if (simd == 1) continue;
            memset(o.data, 0, sizeof(float) * (size_t)w * h * 2);
            p.simd = simd;
            CHECK_OK(nprfx_gabor_render(ctx, &p, &gi, win, &o, &so));
            int same = same_pixels(&ref, &o) && so.kernels == sref.kernels &&
                       so.evaluations == sref.evaluations && so.weight2 == sref.weight2;
            if (!same)
                printf("simd paths: variant %d, path %d differs from the scalar one\n", v, simd);
            bad += !same;
        }
        nprfx_image_free(&ref);
        nprfx_image_free(&o);
    }
    CHECK(bad == 0);
    printf("simd paths: 6 variants, every path bit-identical to the scalar one\n");
    nprfx_image_free(&orbit);
    nprfx_image_free(&dolly);
    nprfx_image_free(&trans);
    nprfx_image_free(&anchor4);
    nprfx_image_free(&angle);
}

/* ---- visibility: object ids, depth layers, background ---- */

/* Changing the anchors of one object changes only that object's pixels: no kernel reaches
 * across an object-id edge, and no pixel of another object owns its points. */
static void test_id_edges(void)
{
    nprfx_image plate = th_synth(ctx, "orbit", 24, 128, 96);
    nprfx_image moved = th_synth(ctx, "orbit", 24, 128, 96);
    int cid = th_synth_channel("id"), cp = th_synth_channel("Pref.X");
    long long n2 = 0;
    for (int y = 0; y < 96; y++)
        for (int x = 0; x < 128; x++) {
            float *px = nprfx_image_at(&moved, x, y);
            if (px[cid] == 2.0f) {
                px[cp] += 0.37f; /* the box's points are all new */
                px[cp + 2] -= 0.21f;
                n2++;
            }
        }
    CHECK(n2 > 500);
    nprfx_value pv[32];
    nprfx_node_defaults(node, pv);
    set(pv, "radius", "12");
    gin g0 = plate_inputs(&plate, 0, 1), g1 = plate_inputs(&moved, 0, 1);
    nprfx_image a = th_image(128, 96, 1, NULL), b = th_image(128, 96, 1, NULL);
    for (int t = 0; t < 3; t++) {
        set(pv, "depth_test", t == 0 ? "off" : (t == 1 ? "hard" : "soft"));
        CHECK_OK(render(&g0, pv, &a));
        CHECK_OK(render(&g1, pv, &b));
        long long changed_other = 0, changed_box = 0;
        for (int y = 0; y < 96; y++)
            for (int x = 0; x < 128; x++) {
                int diff = a.data[y * 128 + x] != b.data[y * 128 + x];
                if (nprfx_image_at(&plate, x, y)[cid] == 2.0f)
                    changed_box += diff;
                else
                    changed_other += diff;
            }
        CHECK(changed_other == 0);
        CHECK(changed_box > n2 / 2);
    }
    nprfx_image_free(&a);
    nprfx_image_free(&b);
    nprfx_image_free(&plate);
    nprfx_image_free(&moved);
}

/* One object (one id) in two depth layers: a near plane over the left half at depth 5 and a
 * far one over the right half at depth 10. Changing the far layer's anchors leaves the near
 * layer alone with the depth test on, and reaches across with it off. */
static void test_depth_edges(void)
{
    const int w = 96, h = 64;
    nprfx_image anchor = th_image(w, h, 3, NULL), depth = th_image(w, h, 1, NULL);
    nprfx_image anchor2 = th_image(w, h, 3, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float *a = nprfx_image_at(&anchor, x, y), *a2 = nprfx_image_at(&anchor2, x, y);
            int far = x >= w / 2;
            a[0] = (float)(x * 0.01 + (far ? 3.0 : 0.0));
            a[1] = (float)(y * 0.01);
            a[2] = far ? 1.0f : 0.0f;
            a2[0] = a[0] + (far ? 0.5f : 0.0f);
            a2[1] = a[1];
            a2[2] = a[2];
            nprfx_image_at(&depth, x, y)[0] = far ? 10.0f : 5.0f;
        }
    gin g0, g1;
    memset(&g0, 0, sizeof g0);
    g0.in[th_input(node, "anchor")] = anchor;
    g0.in[th_input(node, "depth")] = depth;
    g1 = g0;
    g1.in[th_input(node, "anchor")] = anchor2;
    nprfx_value pv[32];
    nprfx_node_defaults(node, pv);
    set(pv, "radius", "10");
    nprfx_image a = th_image(w, h, 1, NULL), b = th_image(w, h, 1, NULL);
    for (int t = 0; t < 3; t++) {
        set(pv, "depth_test", t == 0 ? "hard" : (t == 1 ? "soft" : "off"));
        CHECK_OK(render(&g0, pv, &a));
        CHECK_OK(render(&g1, pv, &b));
        long long near_changed = 0;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w / 2; x++)
                near_changed += a.data[y * w + x] != b.data[y * w + x];
        if (t < 2)
            CHECK(near_changed == 0);
        else
            CHECK(near_changed > 0); /* without the test, far kernels do reach the near layer */
    }
    nprfx_image_free(&a);
    nprfx_image_free(&b);
    nprfx_image_free(&anchor);
    nprfx_image_free(&anchor2);
    nprfx_image_free(&depth);
}

static void test_background(void)
{
    nprfx_image plate = th_synth(ctx, "dolly", 10, 96, 72);
    gin g = plate_inputs(&plate, 0, 0); /* no id input: one object */
    nprfx_value pv[32];
    nprfx_node_defaults(node, pv);
    nprfx_image out = th_image(96, 72, 1, NULL);
    int cz = th_synth_channel("Z");
    for (int m = 0; m < 2; m++) {
        if (m) set(pv, "output", "unit01");
        CHECK_OK(render(&g, pv, &out));
        int bad = 0, fg = 0;
        for (int y = 0; y < 72; y++)
            for (int x = 0; x < 96; x++) {
                float v = out.data[y * 96 + x];
                if (nprfx_image_at(&plate, x, y)[cz] >= 1e9f)
                    bad += v != (m ? 0.5f : 0.0f);
                else
                    fg += v != (m ? 0.5f : 0.0f);
            }
        CHECK(bad == 0);
        CHECK(fg > 100);
    }
    nprfx_image_free(&out);
    nprfx_image_free(&plate);
}

/* ---- per-pixel drivers and the render scale ---- */

static void test_driver_inputs(void)
{
    nprfx_image plate = th_synth(ctx, "orbit", 24, 96, 72);
    gin g = plate_inputs(&plate, 0, 1);
    nprfx_image angle = th_image(96, 72, 1, NULL), dir = th_image(96, 72, 2, NULL);
    nprfx_image scale = th_image(96, 72, 1, NULL);
    for (int i = 0; i < 96 * 72; i++) {
        angle.data[i] = 90.0f;
        dir.data[2 * i] = 0.0f;
        dir.data[2 * i + 1] = -3.0f; /* up in the image: 90 degrees counter-clockwise */
        scale.data[i] = 2.0f;
    }
    nprfx_value pv[32];
    nprfx_image a = th_image(96, 72, 1, NULL), b = th_image(96, 72, 1, NULL);
    /* orientation input 90 == orientation param 90 */
    nprfx_node_defaults(node, pv);
    set(pv, "orientation", "90");
    CHECK_OK(render(&g, pv, &a));
    nprfx_node_defaults(node, pv);
    gin ga = g;
    ga.in[th_input(node, "orientation")] = angle;
    CHECK_OK(render(&ga, pv, &b));
    CHECK(same_pixels(&a, &b));
    ga.in[th_input(node, "orientation")] = dir;
    CHECK_OK(render(&ga, pv, &b));
    long long far = 0;
    for (int i = 0; i < 96 * 72; i++)
        far += fabsf(a.data[i] - b.data[i]) > 1e-4f;
    CHECK(far == 0);
    /* frequency input 2 == frequency param doubled */
    nprfx_node_defaults(node, pv);
    set(pv, "frequency", "0.2");
    CHECK_OK(render(&g, pv, &a));
    nprfx_node_defaults(node, pv);
    set(pv, "frequency", "0.1");
    gin gf = g;
    gf.in[th_input(node, "frequency")] = scale;
    CHECK_OK(render(&gf, pv, &b));
    CHECK(same_pixels(&a, &b));
    /* a host proxy at half scale: radius arrives scaled, the frequency is doubled inside */
    nprfx_node_defaults(node, pv);
    set(pv, "frequency", "0.1");
    nprfx_node_apply_render_scale(node, pv, 0.5);
    CHECK_NEAR(pv[th_param(node, "radius")].v[0], 8.0, 1e-12);
    CHECK_OK(render_with(ctx, &g, pv, &a, a.bounds, 0.5));
    nprfx_node_defaults(node, pv);
    set(pv, "frequency", "0.2");
    set(pv, "radius", "8");
    CHECK_OK(render(&g, pv, &b));
    CHECK(same_pixels(&a, &b));
    nprfx_image_free(&a);
    nprfx_image_free(&b);
    nprfx_image_free(&angle);
    nprfx_image_free(&dir);
    nprfx_image_free(&scale);
    nprfx_image_free(&plate);
}

/* UV anchors (2D) on the flat plane: unit variance too, and the pattern moves with the plane. */
static void test_uv_anchor(void)
{
    nprfx_image p0 = th_synth(ctx, "translate", 20, 128, 128),
                p1 = th_synth(ctx, "translate", 21, 128, 128);
    nprfx_value pv[32];
    nprfx_node_defaults(node, pv);
    set(pv, "anchor_space", "uv");
    set(pv, "radius", "8");
    nprfx_image a = th_image(128, 128, 1, NULL), b = th_image(128, 128, 1, NULL);
    gin g0 = plate_inputs(&p0, 1, 1), g1 = plate_inputs(&p1, 1, 1);
    CHECK_OK(render(&g0, pv, &a));
    CHECK_OK(render(&g1, pv, &b));
    nprfx_stats st;
    CHECK_OK(nprfx_image_stats(ctx, &b, 0, NULL, &st));
    nprfx_image mp = nprfx_image_channels(&p1, th_synth_channel("motion_prev.X"), 2);
    nprfx_warp_error we;
    CHECK_OK(nprfx_warp_compare(ctx, &b, &a, 0, &mp, NULL, &we));
    printf("uv anchors: variance %.3f, warp correlation %.4f\n", st.variance, we.correlation);
    CHECK_NEAR(st.variance, 1.0, 0.2);
    CHECK(we.correlation > 0.95);
    nprfx_image_free(&a);
    nprfx_image_free(&b);
    nprfx_image_free(&p0);
    nprfx_image_free(&p1);
}

int main(void)
{
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    if (nprfx_context_create(&ci, &ctx) != NPRFX_OK) return 2;
    node = nprfx_node_find("gabor-splat");
    CHECK(node != NULL);
    if (!node) return check_finish();
    test_descriptor();
    test_lod_weights();
    test_variance_formula();
    test_errors();
    test_flat_plane();
    test_frame_border();
    test_determinism();
    test_simd_paths();
    test_id_edges();
    test_depth_edges();
    test_background();
    test_driver_inputs();
    test_uv_anchor();
    nprfx_context_destroy(ctx);
    return check_finish();
}
