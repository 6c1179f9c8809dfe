/* The matte node: coverage from alpha, depth and id by its rules (hand-computed pixels),
 * softening at the rim, tile invariance, the hard rule, invert, and the error without input. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/matte.h"
#include "nprfx/objectid.h"

extern const nprfx_node_desc nprfx_node_matte;

static float px(const nprfx_image *im, int x, int y)
{
    return nprfx_image_at(im, x, y)[0];
}

static void test_matte(nprfx_context *ctx)
{
    nprfx_matte_params p = {.far = 1e9, .background_id = 0, .soften = 0, .invert = 0};
    float z_obj = 5, z_sky = INFINITY, z_blender = 1e10f, z_zero = 0, id0 = 0, id3 = 3,
          id_near0 = 0.2f, a_half = 0.5f;
    CHECK(nprfx_matte_pixel(&p, NULL, &z_obj, NULL) == 1.0);
    CHECK(nprfx_matte_pixel(&p, NULL, &z_sky, NULL) == 0.0);
    CHECK(nprfx_matte_pixel(&p, NULL, &z_blender, NULL) == 0.0);
    CHECK(nprfx_matte_pixel(&p, NULL, &z_zero, NULL) == 0.0);
    CHECK(nprfx_matte_pixel(&p, NULL, NULL, &id0) == 0.0);
    /* ids are compared exactly: 0.2 is not 0 (a uint id 0x3e4ccccd reads as 0.2f) */
    CHECK(nprfx_matte_pixel(&p, NULL, NULL, &id_near0) == 1.0);
    CHECK(nprfx_matte_pixel(&p, NULL, NULL, &id3) == 1.0);
    /* uint ids above 2^24, however small or NaN their float, are objects; -0 is 0 */
    float id_tiny = nprfx_id_from_uint(0x01000001u), id_nan = nprfx_id_from_uint(0x7f800001u),
          id_neg0 = -0.0f;
    CHECK(nprfx_matte_pixel(&p, NULL, NULL, &id_tiny) == 1.0);
    CHECK(nprfx_matte_pixel(&p, NULL, NULL, &id_nan) == 1.0);
    CHECK(nprfx_matte_pixel(&p, NULL, NULL, &id_neg0) == 0.0);
    p.background_id = 7;
    float id7 = nprfx_id_from_uint(7u);
    CHECK(id7 == 7.0f);
    CHECK(nprfx_matte_pixel(&p, NULL, NULL, &id7) == 0.0);
    p.background_id = 0;
    CHECK(nprfx_matte_pixel(&p, &a_half, &z_obj, &id3) == 0.5);
    p.background_id = -1;
    CHECK(nprfx_matte_pixel(&p, NULL, NULL, &id0) == 1.0);
    p.background_id = 0;

    /* a disc of depth 5 on an infinite background, through the descriptor */
    const nprfx_node_desc *n = &nprfx_node_matte;
    enum { S = 40 };
    nprfx_image in[3], out, whole;
    memset(in, 0, sizeof in);
    int di = th_input(n, "depth");
    in[di] = th_image(S, S, 1, NULL);
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++)
            nprfx_image_at(&in[di], x, y)[0] =
                (x - 19.3) * (x - 19.3) + (y - 20.6) * (y - 20.6) < 100 ? 5.0f : INFINITY;
    nprfx_value pv[8];
    nprfx_node_defaults(n, pv);
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, S, S), 1, &out);
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, S, S), 1, &whole);
    CHECK_OK(th_render(ctx, n, in, pv, &whole, whole.bounds));
    /* softened: 1 deep inside, 0 far outside, in between at the rim, monotone along a ray */
    CHECK(px(&whole, 19, 21) == 1.0f && px(&whole, 0, 0) == 0.0f);
    CHECK(px(&whole, 29, 21) > 0.0f && px(&whole, 29, 21) < 1.0f);
    for (int x = 20; x < S - 1; x++)
        CHECK(px(&whole, x, 21) >= px(&whole, x + 1, 21));
    /* tiles agree with the whole frame */
    for (int t = 0; t < 4; t++) {
        nprfx_rect win =
            nprfx_rect_make((t & 1) * 17, (t >> 1) * 23, (t & 1) ? S : 17, (t >> 1) ? S : 23);
        CHECK_OK(th_render(ctx, n, in, pv, &out, win));
    }
    CHECK(memcmp(out.data, whole.data, sizeof(float) * S * S) == 0);
    /* soften 0: exactly the hard rule; invert */
    pv[th_param(n, "soften")].v[0] = 0;
    pv[th_param(n, "invert")].v[0] = 1;
    CHECK_OK(th_render(ctx, n, in, pv, &out, out.bounds));
    CHECK(px(&out, 19, 21) == 0.0f && px(&out, 29, 21) == 0.0f && px(&out, 30, 21) == 1.0f);
    /* no input: the error names the inputs */
    nprfx_image none[3];
    memset(none, 0, sizeof none);
    CHECK(th_render(ctx, n, none, pv, &out, out.bounds) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "'alpha', 'depth', 'id'") != NULL);
    nprfx_image_free(&in[di]);
    nprfx_image_free(&out);
    nprfx_image_free(&whole);
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    nprfx_context_create(&ci, &ctx);
    CHECK_OK(nprfx_node_lint(ctx, &nprfx_node_matte));
    test_matte(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
