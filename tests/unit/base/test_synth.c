/* The analytic scene generator: exact motion for the affine scenes, motion/Pref consistency
 * between neighbouring frames for every scene, the dolly's x4 scale, orbit's disocclusions, and
 * bit-identical output for any thread count. */
#include "check.h"

#include "nprfx/nprfx.h"
#include "base/synth_geom.h"

enum {
    C_R = 0,
    C_A = 3,
    C_Z = 4,
    C_MP = 5,
    C_MN = 7,
    C_P = 9,
    C_PREF = 12,
    C_N = 15,
    C_UV = 18,
    C_ID = 20,
    C_DIFFUSE = 21,
    C_COV = 22
};

static nprfx_context *ctx;

static nprfx_image render(const char *scene, int frame, int w, int h)
{
    nprfx_image im;
    CHECK_OK(nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, w, h), nprfx_synth_channel_count(), &im));
    CHECK_OK(nprfx_synth_render(ctx, scene, frame, &im));
    return im;
}

static const float *px(const nprfx_image *im, int x, int y)
{
    return nprfx_image_at(im, x, y);
}

static void test_channels_and_scenes(void)
{
    CHECK(nprfx_synth_channel_count() == 26);
    const char *const *n = nprfx_synth_channel_names();
    const char *want[] = {"R",
                          "G",
                          "B",
                          "A",
                          "Z",
                          "motion_prev.X",
                          "motion_prev.Y",
                          "motion_next.X",
                          "motion_next.Y",
                          "P.X",
                          "P.Y",
                          "P.Z",
                          "Pref.X",
                          "Pref.Y",
                          "Pref.Z",
                          "N.X",
                          "N.Y",
                          "N.Z",
                          "UV.U",
                          "UV.V",
                          "id",
                          "diffuse",
                          "coverage",
                          "albedo.R",
                          "albedo.G",
                          "albedo.B"};
    for (int i = 0; i < 26; i++)
        CHECK(n[i] && !strcmp(n[i], want[i]));
    CHECK(n[26] == NULL);

    const char *scenes[] = {"orbit", "dolly", "translate", "rotate", "zoom", "ground"};
    CHECK(nprfx_synth_scene_count() == 6);
    for (int i = 0; i < 6; i++) {
        const nprfx_synth_scene_info *info = nprfx_synth_scene_at(i);
        CHECK(info && !strcmp(info->name, scenes[i]) && info->help && info->help[0]);
    }
    CHECK(nprfx_synth_scene_at(6) == NULL);

    nprfx_image im;
    CHECK_OK(nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 8, 8), 26, &im));
    CHECK(nprfx_synth_render(ctx, "nope", 1, &im) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "nope") != NULL);
    nprfx_image few = nprfx_image_channels(&im, 0, 4);
    CHECK(nprfx_synth_render(ctx, "orbit", 1, &few) == NPRFX_ERR_INVALID_ARGUMENT);
    nprfx_image_free(&im);
}

static void test_poly_roots(void)
{
    /* (x-1)(x-2)(x-3)(x-4) = x^4 - 10x^3 + 35x^2 - 50x + 24 */
    const double c[5] = {24, -50, 35, -10, 1};
    double r[4];
    CHECK(internal_sg_poly_roots(c, 4, 0, 5, r) == 4);
    for (int i = 0; i < 4; i++)
        CHECK_NEAR(r[i], i + 1, 1e-12);
    CHECK(internal_sg_poly_roots(c, 4, 2.5, 3.5, r) == 1);
    CHECK_NEAR(r[0], 3, 1e-12);
    const double none[3] = {1, 0, 1}; /* x^2 + 1 */
    CHECK(internal_sg_poly_roots(none, 2, -10, 10, r) == 0);
}

/* Known hits, and every torus hit of a fan of rays lies on the surface with an outward normal. */
static void test_shapes(void)
{
    sg_hit hit;
    CHECK(internal_sg_hit_torus(sg_v(1, 0, 5), sg_v(0, 0, -1), 1, 0.35, 1e-9, INFINITY, &hit));
    CHECK_NEAR(hit.t, 4.65, 1e-12);
    CHECK_NEAR(hit.n.z, 1, 1e-12);
    CHECK(!internal_sg_hit_torus(sg_v(0, 0, 5), sg_v(0, 0, -1), 1, 0.35, 1e-9, INFINITY, &hit));
    CHECK(internal_sg_hit_sphere(sg_v(0, 0, 5), sg_v(0, 0, -2), 1, 1e-9, INFINITY, &hit));
    CHECK_NEAR(hit.t, 2, 1e-12);
    CHECK(internal_sg_hit_box(sg_v(0.2, 0.1, 5), sg_v(0, 0, -1), 0.5, 1e-9, INFINITY, &hit));
    CHECK_NEAR(hit.t, 4.5, 1e-12);
    CHECK(hit.n.z == 1 && hit.p.z == 0.5);
    CHECK(internal_sg_hit_plane(sg_v(0.3, 0.4, 2), sg_v(0.1, 0, -1), 1e-9, INFINITY, &hit));
    CHECK_NEAR(hit.p.x, 0.5, 1e-15);
    int hits = 0;
    double worst = 0, worst_n = 0;
    sg_vec3 eye = sg_v(0.3, -0.2, 3);
    for (int j = 0; j < 200; j++)
        for (int i = 0; i < 200; i++) {
            sg_vec3 d = sg_v(-0.2 + (i - 100) * 0.0071, 0.1 + (j - 100) * 0.0069, -1);
            if (!internal_sg_hit_torus(eye, d, 1, 0.35, 1e-9, INFINITY, &hit)) continue;
            hits++;
            double rho = sqrt(hit.p.x * hit.p.x + hit.p.y * hit.p.y);
            double e = fabs(hypot(rho - 1, hit.p.z) - 0.35);
            if (e > worst) worst = e;
            if (sg_dot(hit.n, d) > worst_n) worst_n = sg_dot(hit.n, d);
        }
    CHECK(hits > 5000);
    CHECK(worst < 1e-10);
    CHECK(worst_n <= 1e-9); /* the first hit always faces the ray */
}

/* translate: motion is exactly (0.37, 0.23) * width / 256 px per frame everywhere. */
static void test_translate_exact(int w, int h)
{
    nprfx_image im = render("translate", 7, w, h);
    double s = w / 256.0;
    double err = 0;
    int bad = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = px(&im, x, y);
            double e = fabs(p[C_MP] + 0.37 * s) + fabs(p[C_MP + 1] + 0.23 * s) +
                       fabs(p[C_MN] - 0.37 * s) + fabs(p[C_MN + 1] - 0.23 * s);
            if (e > err) err = e;
            if (p[C_ID] != 1 || p[C_COV] != 1 || p[C_A] != 1 || fabs(p[C_Z] - 5) > 1e-5 ||
                fabs(p[C_N + 2] - 1) > 1e-6)
                bad++;
        }
    CHECK(err < 2e-5);
    CHECK(bad == 0);
    nprfx_image_free(&im);
}

/* rotate / zoom: the exact image-space map about the centre ((w-1)/2, (h-1)/2). */
static void test_affine_exact(const char *scene, int w, int h)
{
    nprfx_image im = render(scene, 3, w, h);
    double cx = 0.5 * (w - 1), cy = 0.5 * (h - 1);
    double th = 0.3 * 3.14159265358979323846 / 180, k = 1.0 / 1.005;
    double err = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = px(&im, x, y);
            double dx = x - cx, dy = y - cy, prevx, prevy, nextx, nexty;
            if (!strcmp(scene, "rotate")) {
                /* Counter-clockwise on screen (y down) by th per frame. */
                prevx = dx * cos(th) - dy * sin(th);
                prevy = dx * sin(th) + dy * cos(th);
                nextx = dx * cos(th) + dy * sin(th);
                nexty = -dx * sin(th) + dy * cos(th);
            } else {
                prevx = dx * k;
                prevy = dy * k;
                nextx = dx * 1.005;
                nexty = dy * 1.005;
            }
            double e = fabs(p[C_MP] - (prevx - dx)) + fabs(p[C_MP + 1] - (prevy - dy)) +
                       fabs(p[C_MN] - (nextx - dx)) + fabs(p[C_MN + 1] - (nexty - dy));
            if (e > err) err = e;
        }
    CHECK_NEAR(err, 0, 1e-4);
    nprfx_image_free(&im);
}

/* Bilinear sample of channel c at (x, y); returns 0 (not sampled) unless all four neighbours
 * are inside, carry object `id`, and lie on one smooth piece of surface (depth spread small). */
static int sample(const nprfx_image *im, double x, double y, int c, int n, float id, double *out)
{
    int w = im->bounds.x1, h = im->bounds.y1;
    int x0 = (int)floor(x), y0 = (int)floor(y);
    if (x0 < 0 || y0 < 0 || x0 + 1 >= w || y0 + 1 >= h) return 0;
    const float *q[4] = {px(im, x0, y0), px(im, x0 + 1, y0), px(im, x0, y0 + 1),
                         px(im, x0 + 1, y0 + 1)};
    float zmin = q[0][C_Z], zmax = q[0][C_Z];
    for (int i = 0; i < 4; i++) {
        if (q[i][C_ID] != id) return 0;
        if (q[i][C_Z] < zmin) zmin = q[i][C_Z];
        if (q[i][C_Z] > zmax) zmax = q[i][C_Z];
    }
    if (zmax - zmin > 0.05 * zmin) return 0;
    double fx = x - x0, fy = y - y0;
    for (int k = 0; k < n; k++)
        out[k] = (1 - fy) * ((1 - fx) * q[0][c + k] + fx * q[1][c + k]) +
                 fy * ((1 - fx) * q[2][c + k] + fx * q[3][c + k]);
    return 1;
}

/* Largest second difference of channels [c, c+3) along x and y around the bilinear cell at
 * (x0, y0): bilinear interpolation of a curved field errs by up to 1/8 of it. -1 when the
 * stencil leaves the image or crosses into another object. */
static double curvature(const nprfx_image *im, int x0, int y0, int c, float id)
{
    int w = im->bounds.x1, h = im->bounds.y1;
    if (x0 < 1 || y0 < 1 || x0 + 2 >= w || y0 + 2 >= h) return -1;
    double m = 0;
    for (int j = 0; j < 2; j++)
        for (int i = -1; i <= 0; i++) {
            const float *ax = px(im, x0 + i, y0 + j), *bx = px(im, x0 + i + 1, y0 + j),
                        *cx = px(im, x0 + i + 2, y0 + j);
            const float *ay = px(im, x0 + j, y0 + i), *by = px(im, x0 + j, y0 + i + 1),
                        *cy = px(im, x0 + j, y0 + i + 2);
            if (ax[C_ID] != id || cx[C_ID] != id || ay[C_ID] != id || cy[C_ID] != id) return -1;
            double sx = 0, sy = 0;
            for (int k = 0; k < 3; k++) {
                sx += fabs(ax[c + k] - 2 * bx[c + k] + cx[c + k]);
                sy += fabs(ay[c + k] - 2 * by[c + k] + cy[c + k]);
            }
            if (sx > m) m = sx;
            if (sy > m) m = sy;
        }
    return m;
}

/* For every scene: following motion_prev from frame i lands, at frame i-1, on the same surface
 * point (same Pref), and motion_next there leads back. Points that were hidden at frame i-1
 * (another id there, or a depth edge) are skipped; self-occlusions are rare and counted. */
static void test_consistency(const char *scene, int frame, int w, int h, double max_bad_fraction)
{
    nprfx_image a = render(scene, frame - 1, w, h);
    nprfx_image b = render(scene, frame, w, h);
    int covered = 0, checked = 0, bad_pref = 0, bad_back = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = px(&b, x, y);
            if (p[C_ID] == 0) {
                CHECK(p[C_MP] == 0 && p[C_MP + 1] == 0);
                continue;
            }
            covered++;
            double qx = x + p[C_MP], qy = y + p[C_MP + 1], pref[3], mn[2];
            if (!sample(&a, qx, qy, C_PREF, 3, p[C_ID], pref)) continue;
            double curv = curvature(&a, (int)floor(qx), (int)floor(qy), C_PREF, p[C_ID]);
            if (curv < 0) continue;
            sample(&a, qx, qy, C_MN, 2, p[C_ID], mn);
            /* Tolerance: a small part of the Pref step between neighbouring pixels, plus the
             * bilinear interpolation error on a curved surface. A motion vector off by a pixel
             * would miss by a whole step. */
            const float *r = px(&a, (int)floor(qx), (int)floor(qy));
            const float *r1 = px(&a, (int)floor(qx) + 1, (int)floor(qy) + 1);
            double step = 0, d = 0;
            for (int k = 0; k < 3; k++) {
                step += fabs(r1[C_PREF + k] - r[C_PREF + k]);
                d += fabs(pref[k] - p[C_PREF + k]);
            }
            checked++;
            if (d > 0.05 * step + 0.25 * curv + 1e-5) {
                bad_pref++;
                if (getenv("SYNTH_DEBUG"))
                    fprintf(stderr, "  %s (%d,%d) q=(%.3f,%.3f) d=%g step=%g curv=%g z=%g\n", scene,
                            x, y, qx, qy, d, step, curv, p[C_Z]);
            }
            if (fabs(mn[0] + p[C_MP]) + fabs(mn[1] + p[C_MP + 1]) > 0.05) bad_back++;
        }
    CHECK(checked > covered / 2);
    if (bad_pref > max_bad_fraction * checked || bad_back > max_bad_fraction * checked)
        fprintf(stderr, "%s frame %d: %d checked, %d Pref mismatches, %d motion_next mismatches\n",
                scene, frame, checked, bad_pref, bad_back);
    CHECK(bad_pref <= max_bad_fraction * checked);
    CHECK(bad_back <= max_bad_fraction * checked);
    nprfx_image_free(&a);
    nprfx_image_free(&b);
}

static void extent(const nprfx_image *im, int *width, int *area)
{
    int x0 = im->bounds.x1, x1 = -1, n = 0;
    for (int y = 0; y < im->bounds.y1; y++)
        for (int x = 0; x < im->bounds.x1; x++)
            if (px(im, x, y)[C_COV] > 0) {
                n++;
                if (x < x0) x0 = x;
                if (x > x1) x1 = x;
            }
    *width = x1 - x0 + 1;
    *area = n;
}

static void test_dolly_scale(void)
{
    nprfx_image a = render("dolly", 1, 256, 256), b = render("dolly", 48, 256, 256);
    int wa, aa, wb, ab;
    extent(&a, &wa, &aa);
    extent(&b, &wb, &ab);
    CHECK_NEAR((double)wb / wa, 4.0, 0.2);
    CHECK_NEAR(sqrt((double)ab / aa), 4.0, 0.2);
    /* Background: no object, far depth, no motion, no coverage. */
    const float *corner = px(&a, 0, 0);
    CHECK(corner[C_ID] == 0 && corner[C_Z] == 1e10f && corner[C_COV] == 0 && corner[C_A] == 0);
    CHECK(corner[C_MP] == 0 && corner[C_MN + 1] == 0 && corner[C_R] == 0);
    /* Frames beyond 48 stay defined: the camera keeps approaching. */
    nprfx_image c = render("dolly", 60, 64, 64);
    int wc, ac;
    extent(&c, &wc, &ac);
    CHECK(ac > 0);
    nprfx_image_free(&a);
    nprfx_image_free(&b);
    nprfx_image_free(&c);
}

/* orbit: the sphere (id 3) passes in front of the box (id 2): pixels that were sphere at i-1
 * show box or backdrop at i (disocclusion) and the reverse (occlusion). */
static void test_orbit_occlusion(void)
{
    nprfx_image a = render("orbit", 23, 128, 128), b = render("orbit", 24, 128, 128);
    int disocc_box = 0, disocc_any = 0, occ = 0, diff_ok = 1;
    for (int y = 0; y < 128; y++)
        for (int x = 0; x < 128; x++) {
            float ia = px(&a, x, y)[C_ID], ib = px(&b, x, y)[C_ID];
            if (ia == 3 && ib != 3) disocc_any++;
            if (ia == 3 && ib == 2) disocc_box++;
            if (ia == 2 && ib == 3) occ++;
            const float *p = px(&b, x, y);
            if (p[C_DIFFUSE] < 0 || p[C_DIFFUSE] > 1) diff_ok = 0;
            CHECK(ib >= 1); /* the backdrop fills the frame */
        }
    CHECK(disocc_box > 10);
    CHECK(disocc_any > disocc_box);
    CHECK(occ > 10);
    CHECK(diff_ok);
    /* Static objects do not move. */
    const float *corner = px(&b, 0, 0);
    CHECK(corner[C_ID] == 1 && corner[C_MP] == 0 && corner[C_MN] == 0);
    nprfx_image_free(&a);
    nprfx_image_free(&b);
}

static void test_threads(void)
{
    nprfx_pool *pool;
    CHECK_OK(nprfx_pool_create(3, &pool));
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.executor = nprfx_pool_executor(pool);
    nprfx_context *ctx3;
    CHECK_OK(nprfx_context_create(&init, &ctx3));
    const char *scenes[] = {"orbit", "dolly", "rotate"};
    for (int i = 0; i < 3; i++) {
        nprfx_image a = render(scenes[i], 30, 96, 80), b;
        CHECK_OK(nprfx_image_alloc(ctx3, a.bounds, a.channels, &b));
        CHECK_OK(nprfx_synth_render(ctx3, scenes[i], 30, &b));
        size_t n = (size_t)96 * 80 * (size_t)a.channels;
        CHECK(memcmp(a.data, b.data, n * sizeof(float)) == 0);
        nprfx_image_free(&a);
        nprfx_image_free(&b);
    }
    nprfx_context_destroy(ctx3);
    nprfx_pool_destroy(pool);
}

/* Picked channels (what a graph's synth makes: only those its readers take) are the whole
 * plate's, bit for bit, in the order picked, with or without the motion channels; bad picks
 * are refused. */
static void test_pick(const char *scene)
{
    nprfx_image all = render(scene, 4, 96, 64);
    const int picks[][5] = {{4, 5, 6, 21, 0}, {7, 8, 14, 15, 16}, {25, 3, 9, 0, 24}};
    for (int k = 0; k < 3; k++) {
        nprfx_image sub;
        CHECK_OK(nprfx_image_alloc(ctx, all.bounds, 5, &sub));
        CHECK_OK(nprfx_synth_render_channels(ctx, scene, 4, picks[k], 5, &sub));
        int bad = 0;
        for (int y = 0; y < 64; y++)
            for (int x = 0; x < 96; x++)
                for (int c = 0; c < 5; c++)
                    bad += memcmp(&px(&sub, x, y)[c], &px(&all, x, y)[picks[k][c]], 4) != 0;
        CHECK(bad == 0);
        nprfx_image_free(&sub);
    }
    nprfx_image one;
    CHECK_OK(nprfx_image_alloc(ctx, all.bounds, 1, &one));
    const int out_of_range[] = {26}, two[] = {0, 1};
    CHECK(nprfx_synth_render_channels(ctx, scene, 4, out_of_range, 1, &one) ==
          NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(nprfx_synth_render_channels(ctx, scene, 4, two, 2, &one) == NPRFX_ERR_INVALID_ARGUMENT);
    nprfx_image_free(&one);
    nprfx_image_free(&all);
}

int main(void)
{
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    if (nprfx_context_create(&init, &ctx) != NPRFX_OK) return 1;
    test_channels_and_scenes();
    test_poly_roots();
    test_shapes();
    test_pick("orbit");
    test_pick("dolly");
    test_translate_exact(256, 256);
    test_translate_exact(100, 60);
    test_affine_exact("rotate", 128, 96);
    test_affine_exact("zoom", 128, 96);
    test_consistency("translate", 5, 96, 64, 0);
    test_consistency("translate", 1000, 64, 64, 0);
    test_consistency("rotate", 5, 96, 64, 0);
    test_consistency("rotate", -200, 64, 64, 0);
    test_consistency("zoom", 5, 96, 64, 0);
    test_consistency("zoom", -100, 64, 64, 0);
    test_consistency("ground", 5, 96, 64, 0.002);
    const int orbit_frames[] = {1, 24, 60, 96, 130};
    for (int i = 0; i < 5; i++)
        test_consistency("orbit", orbit_frames[i], 128, 96, 0.002);
    const int dolly_frames[] = {2, 30, 48, 80};
    for (int i = 0; i < 4; i++)
        test_consistency("dolly", dolly_frames[i], 128, 96, 0.002);
    test_dolly_scale();
    test_orbit_occlusion();
    test_threads();
    nprfx_context_destroy(ctx);
    return check_finish();
}
