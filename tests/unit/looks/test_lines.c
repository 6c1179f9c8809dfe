/* lines (core/looks/lines.c, docs/design.md §3.11): ink lines on analytic plates. A disc seen through
 * id, depth and coverage alone: the line sits on the true circle within 0.5 px, its ink mass
 * across the edge is the width within 0.5 px and no angle has a gap. A folded plane: the crease
 * line sits on the fold and vanishes above the fold angle. Exact ink next to a straight edge by
 * hand; the width, wobble and texture inputs; bit-identity over threads and tiles; the errors. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/lines.h"
#include "nprfx/node.h"

extern const nprfx_node_desc nprfx_node_lines;
static const nprfx_node_desc *node = &nprfx_node_lines;

enum { NIN = 8 };
static nprfx_image in[NIN];
static nprfx_value pv[16];

static int II(const char *name)
{
    return th_input(node, name);
}
static int PI(const char *name)
{
    return th_param(node, name);
}

static void reset(void)
{
    for (int i = 0; i < NIN; i++)
        nprfx_image_free(&in[i]);
    memset(in, 0, sizeof in);
    nprfx_node_defaults(node, pv);
    for (int i = 0; i < node->num_params; i++)
        if (!pv[i].s) pv[i].s = "";
}

static void set(const char *name, double v)
{
    pv[PI(name)].v[0] = v;
}

static float px(const nprfx_image *im, int x, int y)
{
    return nprfx_image_at(im, x, y)[0];
}

/* Bilinear ink at (x, y), 0 outside. */
static double ink_at(const nprfx_image *im, double x, double y)
{
    int x0 = (int)floor(x), y0 = (int)floor(y);
    double fx = x - x0, fy = y - y0, s = 0.0;
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) {
            if (!nprfx_rect_contains(im->bounds, x0 + i, y0 + j)) continue;
            s += (i ? fx : 1 - fx) * (j ? fy : 1 - fy) * px(im, x0 + i, y0 + j);
        }
    return s;
}

/* ---- the disc: id, depth and coverage plates of a disc of radius R at (CX, CY) ---- */

enum { DW = 128, DH = 128 };
static const double CX = 63.37, CY = 61.71, R = 40.3;

static void disc_plates(nprfx_image *id, nprfx_image *cov, nprfx_image *z)
{
    *id = th_image(DW, DH, 1, NULL);
    *cov = th_image(DW, DH, 1, NULL);
    *z = th_image(DW, DH, 1, NULL);
    for (int y = 0; y < DH; y++)
        for (int x = 0; x < DW; x++) {
            int inside = hypot(x - CX, y - CY) < R; /* single-sample passes */
            nprfx_image_at(id, x, y)[0] = (float)inside;
            nprfx_image_at(z, x, y)[0] = inside ? 5.0f : 1e10f; /* near disc, far background */
            int n = 0;
            for (int j = 0; j < 16; j++)
                for (int i = 0; i < 16; i++)
                    n += hypot(x - 0.5 + (i + 0.5) / 16 - CX, y - 0.5 + (j + 0.5) / 16 - CY) < R;
            nprfx_image_at(cov, x, y)[0] = (float)(n / 256.0);
        }
}

/* Position, width and continuity of the ink of a disc's outline. */
/* Without coverage the edge points sit halfway between pixel centres, a staircase up to half a
 * pixel off the circle: the mean mass is the width, one ray may cross up to a pixel more where
 * the polyline zigzags (`ray_tol`). With coverage every ray is within half a pixel. */
static void check_disc_ink(const nprfx_image *ink, double width, double ray_tol, const char *what)
{
    double sw = 0.0, swr = 0.0;
    for (int y = 0; y < DH; y++)
        for (int x = 0; x < DW; x++) {
            double v = px(ink, x, y);
            sw += v;
            swr += v * hypot(x - CX, y - CY);
        }
    double mean_r = sw > 0 ? swr / sw : 0.0;
    double worst_mass = width, min_peak = 1.0, mass_sum = 0.0;
    const int angles = 720;
    const double step = 0.05;
    for (int a = 0; a < angles; a++) {
        double th = 2.0 * 3.14159265358979323846 * a / angles;
        double mass = 0.0, peak = 0.0;
        for (double r = R - 12.0; r <= R + 12.0; r += step) {
            double v = ink_at(ink, CX + r * cos(th), CY + r * sin(th));
            mass += v * step;
            peak = fmax(peak, v);
        }
        mass_sum += mass;
        if (fabs(mass - width) > fabs(worst_mass - width)) worst_mass = mass;
        min_peak = fmin(min_peak, peak);
    }
    printf("disc %-9s width %.1f: mean radius %.3f (R %.3f), mass mean %.3f worst %.3f, min "
           "peak %.3f\n",
           what, width, mean_r, R, mass_sum / angles, worst_mass, min_peak);
    CHECK_NEAR(mean_r, R, 0.5);
    CHECK_NEAR(mass_sum / angles, width, 0.5);
    CHECK_NEAR(worst_mass, width, ray_tol);
    CHECK(min_peak >= 0.5);
}

static void test_disc(nprfx_context *ctx)
{
    const double widths[4] = {1, 2, 3.5, 6};
    const char *sources[3] = {"id", "depth", "coverage"};
    for (int s = 0; s < 3; s++)
        for (int k = 0; k < 4; k++) {
            reset();
            nprfx_image id, cov, z;
            disc_plates(&id, &cov, &z);
            in[II(sources[s])] = s == 0 ? id : (s == 1 ? z : cov);
            if (s != 0) nprfx_image_free(&id);
            if (s != 1) nprfx_image_free(&z);
            if (s != 2) nprfx_image_free(&cov);
            set("width", widths[k]);
            nprfx_image out = th_image(DW, DH, 1, NULL);
            CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
            check_disc_ink(&out, widths[k], s == 2 ? 0.5 : 1.0, sources[s]);
            nprfx_image_free(&out);
        }
    /* id and coverage together: the coverage places the id's line */
    reset();
    disc_plates(&in[II("id")], &in[II("coverage")], &in[II("depth")]);
    nprfx_image out = th_image(DW, DH, 1, NULL);
    CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
    check_disc_ink(&out, 2.0, 0.5, "all");
    nprfx_image_free(&out);
}

/* ---- a plane folded along x = FOLD: normals 90 degrees apart, one id, continuous depth ---- */

enum { FW = 64, FH = 40 };
static const double FOLD = 30.3;

static void test_crease(nprfx_context *ctx)
{
    const double widths[3] = {1.5, 2, 4};
    for (int k = 0; k < 4; k++) {
        reset();
        nprfx_image n = th_image(FW, FH, 3, NULL), id = th_image(FW, FH, 1, NULL);
        nprfx_image z = th_image(FW, FH, 1, NULL);
        const double h = sqrt(0.5);
        for (int y = 0; y < FH; y++)
            for (int x = 0; x < FW; x++) {
                float *p = nprfx_image_at(&n, x, y);
                p[0] = (float)(x < FOLD ? -h : h);
                p[1] = 0.0f;
                p[2] = (float)h;
                nprfx_image_at(&id, x, y)[0] = 3.0f;
                nprfx_image_at(&z, x, y)[0] = (float)(10.0 + 0.2 * fabs(x - FOLD)); /* a ridge */
            }
        in[II("normal")] = n;
        in[II("id")] = id;
        in[II("depth")] = z;
        double w = k < 3 ? widths[k] : 2.0;
        set("width", w);
        if (k == 3) set("crease_angle", 95); /* above the fold's 90 degrees */
        nprfx_image out = th_image(FW, FH, 1, NULL);
        CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
        double worst_pos = 0.0, worst_mass = w, total = 0.0;
        for (int y = 0; y < FH; y++) {
            double s = 0.0, sx = 0.0;
            for (int x = 0; x < FW; x++) {
                s += px(&out, x, y);
                sx += px(&out, x, y) * x;
            }
            total += s;
            if (s > 0 && fabs(sx / s - FOLD) > worst_pos) worst_pos = fabs(sx / s - FOLD);
            if (fabs(s - w) > fabs(worst_mass - w)) worst_mass = s;
        }
        if (k < 3) {
            printf("crease width %.1f: worst offset %.3f, worst mass %.3f\n", w, worst_pos,
                   worst_mass);
            CHECK(worst_pos <= 0.5);
            CHECK_NEAR(worst_mass, w, 0.5);
        } else {
            CHECK(total == 0.0);
        }
        nprfx_image_free(&out);
    }
}

/* ---- a straight vertical edge: exact values ---- */

enum { EW = 24, EH = 9 };

/* id 0 for x <= 10, 1 beyond: the edge at x = 10.5. */
static nprfx_image edge_id(void)
{
    nprfx_image im = th_image(EW, EH, 1, NULL);
    for (int y = 0; y < EH; y++)
        for (int x = 11; x < EW; x++)
            nprfx_image_at(&im, x, y)[0] = 1.0f;
    return im;
}

static nprfx_image constant(int ch, const float *v)
{
    nprfx_image im = th_image(EW, EH, ch, NULL);
    nprfx_image_fill(&im, v);
    return im;
}

static void test_exact(nprfx_context *ctx)
{
    nprfx_image out = th_image(EW, EH, 1, NULL);
    const int y = 4;
    /* ink = clamp(w/2 - d + 0.5, 0, 1), d the distance to x = 10.5 */
    reset();
    in[II("id")] = edge_id();
    set("width", 3);
    CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
    CHECK(px(&out, 10, y) == 1.0f && px(&out, 11, y) == 1.0f);
    CHECK(px(&out, 9, y) == 0.5f && px(&out, 12, y) == 0.5f);
    CHECK(px(&out, 8, y) == 0.0f && px(&out, 13, y) == 0.0f);
    set("width", 2.4);
    CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
    CHECK_NEAR(px(&out, 9, y), 0.2, 1e-6);
    CHECK_NEAR(px(&out, 12, y), 0.2, 1e-6);
    CHECK(px(&out, 10, y) == 1.0f);
    set("width", 0.6); /* thinner than a pixel: 0.3 - 0.5 + 0.5 */
    CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
    CHECK_NEAR(px(&out, 10, y), 0.3, 1e-6);
    CHECK(px(&out, 9, y) == 0.0f);
    /* outline off: no line; opacity scales */
    set("width", 3);
    set("outline", 0);
    CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
    CHECK(px(&out, 10, y) == 0.0f);
    set("outline", 1);
    set("opacity", 0.5);
    CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
    CHECK(px(&out, 9, y) == 0.25f && px(&out, 10, y) == 0.5f);

    /* coverage places the edge: 0.7 at x = 10, 0 beyond: t = (0.5 - 0.7) / (0 - 0.7) */
    reset();
    nprfx_image cov = th_image(EW, EH, 1, NULL);
    for (int yy = 0; yy < EH; yy++)
        for (int x = 0; x <= 10; x++)
            nprfx_image_at(&cov, x, yy)[0] = x == 10 ? 0.7f : 1.0f;
    in[II("coverage")] = cov;
    set("width", 3);
    CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
    double e = 10.0 + (0.5 - 0.7f) / (0.0 - 0.7f);
    CHECK_NEAR(px(&out, 12, y), 1.5 - (12 - e) + 0.5, 1e-6);
    CHECK_NEAR(px(&out, 9, y), 1.5 - (e - 9) + 0.5, 1e-6);
    CHECK(px(&out, 8, y) == 0.0f && px(&out, 13, y) == 0.0f);

    /* texture: ink * (1 - amount * (1 - texture)) */
    reset();
    in[II("id")] = edge_id();
    float quarter = 0.25f;
    in[II("texture")] = constant(1, &quarter);
    set("width", 3);
    set("texture_amount", 0.6);
    CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
    CHECK_NEAR(px(&out, 10, y), 1.0 - 0.6 * 0.75, 1e-6);
    CHECK_NEAR(px(&out, 9, y), 0.5 * (1.0 - 0.6 * 0.75), 1e-6);
    CHECK(px(&out, 3, y) == 0.0f); /* texture never adds ink */

    /* width input: width * (1 + thicken * (1 - w)); w = 0.25, thicken 2: 2 * 2.5 = 5 */
    reset();
    in[II("id")] = edge_id();
    in[II("width")] = constant(1, &quarter);
    set("width", 2);
    set("thicken", 2);
    CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
    CHECK(px(&out, 9, y) == 1.0f);
    CHECK(px(&out, 8, y) == 0.5f && px(&out, 13, y) == 0.5f); /* d = 2.5: 2.5 - 2.5 + 0.5 */
    CHECK(px(&out, 7, y) == 0.0f);
    /* read at the edge: 0 left, 1 right, the midpoint reads 0.5: 2 * (1 + 0.5) = 3 */
    for (int yy = 0; yy < EH; yy++)
        for (int x = 0; x < EW; x++)
            nprfx_image_at(&in[II("width")], x, yy)[0] = x <= 10 ? 0.0f : 1.0f;
    set("thicken", 1);
    CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
    CHECK(px(&out, 9, y) == 0.5f && px(&out, 12, y) == 0.5f);

    /* wobble: (0.75, 0.5) with amplitude 2 moves every lookup by (+1, 0), so the line moves
     * one pixel left */
    reset();
    in[II("id")] = edge_id();
    float wob[2] = {0.75f, 0.5f};
    in[II("wobble")] = constant(2, wob);
    set("width", 3);
    set("wobble", 2);
    CHECK_OK(th_render(ctx, node, in, pv, &out, out.bounds));
    CHECK(px(&out, 8, y) == 0.5f && px(&out, 9, y) == 1.0f && px(&out, 10, y) == 1.0f);
    CHECK(px(&out, 11, y) == 0.5f && px(&out, 12, y) == 0.0f);
    nprfx_image_free(&out);
}

/* ---- bit-identity over threads and tiles on the orbit plate, every input connected ---- */

static void test_invariance(nprfx_context *serial)
{
    nprfx_pool *pool = NULL;
    nprfx_context *par = th_parallel_context(3, &pool);
    const int w = 97, h = 61;
    nprfx_image plate = th_synth(serial, "orbit", 7, w, h);
    for (int variant = 0; variant < 2; variant++) {
        reset();
        nprfx_image ch[8] = {
            nprfx_image_channels(&plate, th_synth_channel("id"), 1),
            nprfx_image_channels(&plate, th_synth_channel("coverage"), 1),
            nprfx_image_channels(&plate, th_synth_channel("Z"), 1),
            nprfx_image_channels(&plate, th_synth_channel("N.X"), 3),
            nprfx_image_channels(&plate, th_synth_channel("diffuse"), 1),
            nprfx_image_channels(&plate, th_synth_channel("diffuse"), 1),
            /* UV runs past 1: the wobble clamps it, so the displacement stays in reach */
            nprfx_image_channels(&plate, th_synth_channel("UV.U"), variant ? 1 : 2),
            nprfx_image_channels(&plate, th_synth_channel("UV.V"), 1)};
        const char *names[8] = {"id",  "coverage", "depth",  "normal",
                                "aov", "width",    "wobble", "texture"};
        for (int i = 0; i < 8; i++)
            in[II(names[i])] = ch[i];
        set("width", 2.5);
        set("wobble", 1.5);
        set("texture_amount", 0.5);
        nprfx_image ref, a = th_image(w, h, 1, NULL);
        size_t bytes = sizeof(float) * (size_t)(w * h);
        CHECK(th_same_pixels(serial, par, node, in, pv, w, h, 1, &ref) == 0);
        double sum = 0;
        for (int i = 0; i < w * h; i++)
            sum += ref.data[i];
        CHECK(sum > 50.0); /* there are lines */
        /* the core function with the typed params: the same pixels */
        nprfx_lines_params lp = {.width = 2.5,
                                 .thicken = 1,
                                 .outline = 1,
                                 .depth_edges = 1,
                                 .depth_threshold = 0.1,
                                 .creases = 1,
                                 .crease_angle = 60,
                                 .aov_edges = 1,
                                 .aov_threshold = 0.25,
                                 .wobble = 1.5,
                                 .texture_amount = 0.5,
                                 .opacity = 1};
        nprfx_render_args la = th_core_args(serial, ch, &a, a.bounds, a.bounds);
        memset(a.data, 0, bytes);
        CHECK_OK(nprfx_lines_render(&la, &lp));
        CHECK(memcmp(ref.data, a.data, bytes) == 0);
        nprfx_image_free(&ref);
        nprfx_image_free(&a);
        memset(in, 0, sizeof in); /* views of the plate */
    }
    nprfx_image_free(&plate);
    nprfx_context_destroy(par);
    nprfx_pool_destroy(pool);
}

static void test_errors(nprfx_context *ctx)
{
    CHECK_OK(nprfx_node_lint(ctx, node));
    CHECK(node->params_size == sizeof(nprfx_lines_params));
    nprfx_image out = th_image(EW, EH, 1, NULL);
    /* no edge input: the message names them */
    reset();
    float half = 0.5f;
    in[II("texture")] = constant(1, &half);
    CHECK(th_render(ctx, node, in, pv, &out, out.bounds) == NPRFX_ERR_MISSING_INPUT);
    const char *msg = th_error(ctx);
    CHECK(strstr(msg, "'id'") && strstr(msg, "'coverage'") && strstr(msg, "'depth'") &&
          strstr(msg, "'normal'") && strstr(msg, "'aov'"));
    /* wrong channel counts name the input: by the descriptor's check and by the core */
    reset();
    in[II("id")] = edge_id();
    in[II("normal")] = constant(1, &half);
    CHECK(th_render(ctx, node, in, pv, &out, out.bounds) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "'normal'") != NULL);
    nprfx_image_free(&in[II("normal")]);
    float three[3] = {0.5f, 0.5f, 0.5f};
    in[II("wobble")] = constant(3, three);
    CHECK(th_render(ctx, node, in, pv, &out, out.bounds) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "lines: input 'wobble' has 3 channels, expected 1 to 2") != NULL);
    nprfx_lines_params lp = {.width = -1};
    nprfx_image id_only[NPRFX_LINES_IN_COUNT] = {in[II("id")]};
    nprfx_render_args la = th_core_args(ctx, id_only, &out, out.bounds, out.bounds);
    CHECK(nprfx_lines_render(&la, &lp) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "lines.width") != NULL);
    nprfx_image_free(&out);
    reset();
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    nprfx_context_create(&ci, &ctx);
    test_errors(ctx);
    test_exact(ctx);
    test_disc(ctx);
    test_crease(ctx);
    test_invariance(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
