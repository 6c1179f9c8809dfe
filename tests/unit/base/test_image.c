/* Image views: rectangles, allocation, addressing with negative strides, channel and crop
 * views, copy and fill, and the error channel of the context. */
#include <string.h>

#include "check.h"
#include "nprfx/context.h"
#include "nprfx/image.h"

static void test_rects(void)
{
    nprfx_rect a = nprfx_rect_make(-2, 1, 5, 4), b = nprfx_rect_make(3, 0, 10, 2);
    CHECK(nprfx_rect_width(a) == 7 && nprfx_rect_height(a) == 3);
    CHECK(!nprfx_rect_empty(a));
    CHECK(nprfx_rect_contains(a, -2, 1) && nprfx_rect_contains(a, 4, 3));
    CHECK(!nprfx_rect_contains(a, 5, 3) && !nprfx_rect_contains(a, 4, 4));
    CHECK(!nprfx_rect_contains(a, -3, 2) && !nprfx_rect_contains(a, 0, 0));
    nprfx_rect i = nprfx_rect_intersect(a, b);
    CHECK(nprfx_rect_equal(i, nprfx_rect_make(3, 1, 5, 2)));
    /* disjoint: empty, never negative sizes */
    nprfx_rect d = nprfx_rect_intersect(a, nprfx_rect_make(20, 20, 30, 30));
    CHECK(nprfx_rect_empty(d));
    CHECK(nprfx_rect_width(d) == 0 && nprfx_rect_height(d) == 0);
    CHECK(nprfx_rect_width(nprfx_rect_make(5, 5, 2, 9)) == 0);
    CHECK(nprfx_rect_empty(nprfx_rect_make(0, 0, 0, 5)));
    CHECK(!nprfx_rect_equal(a, b));
}

static int last_code;
static char last_message[256];
static const nprfx_context *last_ctx;
static void on_error(void *user, const nprfx_context *ctx, nprfx_result code, const char *message)
{
    (*(int *)user)++;
    last_code = code;
    last_ctx = ctx;
    strncpy(last_message, message, sizeof last_message - 1);
}

/* Scoped contexts: a message raised on a scope reaches the root's handler once, finished, with
 * every scope's prefix, and names the context it was raised on; each scope keeps it as far as
 * itself; nothing is re-raised. */
static void test_scoped(void)
{
    int calls = 0;
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.error_handler = on_error;
    init.error_user = &calls;
    init.data_dir = "/data";
    nprfx_context *root = NULL, *graph = NULL, *node = NULL;
    CHECK_OK(nprfx_context_create(&init, &root));
    CHECK_OK(nprfx_context_create_scoped(root, "shot.json", &graph));
    CHECK_OK(nprfx_context_create_scoped(graph, "node 'toon'", &node));
    nprfx_context *bad = root;
    CHECK(nprfx_context_create_scoped(NULL, "x", &bad) == NPRFX_ERR_INVALID_ARGUMENT && !bad);
    CHECK(strcmp(nprfx_context_data_dir(node), "/data") == 0);
    CHECK(nprfx_context_executor(node) == nprfx_context_executor(root));
    CHECK(nprfx_error(node, NPRFX_ERR_MISSING_INPUT, "blend: input '%s' is not connected",
                      "layer") == NPRFX_ERR_MISSING_INPUT);
    CHECK(calls == 1 && last_ctx == node && last_code == NPRFX_ERR_MISSING_INPUT);
    CHECK(strcmp(last_message, "shot.json: node 'toon': blend: input 'layer' is not connected") ==
          0);
    char buf[256];
    CHECK(nprfx_context_last_error(root, buf, sizeof buf) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strcmp(buf, last_message) == 0);
    CHECK(nprfx_context_last_error(node, buf, sizeof buf) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strcmp(buf, "blend: input 'layer' is not connected") == 0);
    CHECK(nprfx_context_last_error(graph, buf, 12) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strcmp(buf, "node 'toon'") == 0); /* cut to the buffer, terminated */
    /* an error on the root itself carries no prefix */
    nprfx_error(root, NPRFX_ERR_IO, "plain");
    CHECK(calls == 2 && last_ctx == root && strcmp(last_message, "plain") == 0);
    nprfx_context_destroy(node);
    nprfx_context_destroy(graph);
    nprfx_context_destroy(root);
}

static void test_alloc(void)
{
    int calls = 0;
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.error_handler = on_error;
    init.error_user = &calls;
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(&init, &ctx));
    CHECK(strcmp(th_error(ctx), "") == 0);

    nprfx_image im;
    CHECK_OK(nprfx_image_alloc(ctx, nprfx_rect_make(-3, 10, 4, 15), 3, &im));
    CHECK(im.channels == 3 && im.pixel_stride == 3 && im.row_stride == 21);
    int zero = 1;
    for (int i = 0; i < 7 * 5 * 3; i++)
        zero &= im.data[i] == 0.0f;
    CHECK(zero);
    /* addressing: pixel (x, y) at (x - x0) * 3 + (y - y0) * 21 */
    CHECK(nprfx_image_at(&im, -3, 10) == im.data);
    CHECK(nprfx_image_at(&im, 0, 12) == im.data + 3 * 3 + 2 * 21);
    /* an empty image is valid */
    nprfx_image e;
    CHECK_OK(nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 0, 0), 1, &e));
    nprfx_image_free(&e);
    CHECK(e.data == NULL && e.channels == 0);
    /* errors go to the handler and to nprfx_context_last_error, with the code returned */
    CHECK(nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 4, 4), 0, &e) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(calls == 1 && last_code == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(last_message, "0 channels") != NULL);
    CHECK(strcmp(th_error(ctx), last_message) == 0);
    CHECK(e.data == NULL);
    CHECK(nprfx_image_alloc(ctx, nprfx_rect_make(4, 0, 0, 4), 1, &e) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(calls == 2);
    /* freeing twice, or a zeroed view, is harmless */
    nprfx_image_free(&im);
    nprfx_image_free(&im);
    nprfx_image z;
    memset(&z, 0, sizeof z);
    nprfx_image_free(&z);
    nprfx_image_free(NULL);
    nprfx_context_destroy(ctx);
    /* a NULL context drops the message but still returns the code */
    CHECK(nprfx_image_alloc(NULL, nprfx_rect_make(0, 0, 1, 1), -1, &e) ==
          NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strcmp(th_error(NULL), "") == 0);
}

static void test_views(void)
{
    nprfx_image im;
    CHECK_OK(nprfx_image_alloc(NULL, nprfx_rect_make(0, 0, 4, 3), 4, &im));
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 4; x++)
            for (int c = 0; c < 4; c++)
                nprfx_image_at(&im, x, y)[c] = (float)(100 * c + 10 * y + x);

    /* channels 1..2 as a 2-channel view sharing the pixels */
    nprfx_image ch = nprfx_image_channels(&im, 1, 2);
    CHECK(ch.channels == 2 && ch.pixel_stride == 4);
    CHECK(nprfx_image_at(&ch, 3, 2)[0] == 123.0f && nprfx_image_at(&ch, 3, 2)[1] == 223.0f);
    nprfx_image_at(&ch, 1, 1)[1] = -1.0f;
    CHECK(nprfx_image_at(&im, 1, 1)[2] == -1.0f);

    /* crop keeps absolute coordinates and clips to the bounds */
    nprfx_image cr = nprfx_image_crop(&im, nprfx_rect_make(2, 1, 9, 9));
    CHECK(nprfx_rect_equal(cr.bounds, nprfx_rect_make(2, 1, 4, 3)));
    CHECK(nprfx_image_at(&cr, 2, 1) == nprfx_image_at(&im, 2, 1));
    CHECK(nprfx_image_at(&cr, 3, 2)[0] == 23.0f);
    nprfx_image none = nprfx_image_crop(&im, nprfx_rect_make(10, 10, 12, 12));
    CHECK(nprfx_rect_empty(none.bounds));

    /* bottom-up storage: row y0 is the last in memory, the row stride negative */
    float buf[4 * 3];
    for (int i = 0; i < 12; i++)
        buf[i] = (float)i;
    nprfx_image up = {buf + 8, 1, -4, 1, {0, 0, 4, 3}};
    CHECK(nprfx_image_at(&up, 0, 0)[0] == 8.0f);
    CHECK(nprfx_image_at(&up, 3, 2)[0] == 3.0f);
    CHECK(nprfx_image_at(&up, 1, 1)[0] == 5.0f);

    /* copy: only the overlap is written, across layouts */
    nprfx_image dst;
    CHECK_OK(nprfx_image_alloc(NULL, nprfx_rect_make(-1, 1, 3, 5), 1, &dst));
    const float mark = 7.0f;
    nprfx_image_fill(&dst, &mark);
    CHECK_OK(nprfx_image_copy(NULL, &up, &dst));
    CHECK(nprfx_image_at(&dst, 0, 1)[0] == 4.0f);  /* up (0,1) */
    CHECK(nprfx_image_at(&dst, 2, 2)[0] == 2.0f);  /* up (2,2) */
    CHECK(nprfx_image_at(&dst, -1, 1)[0] == 7.0f); /* outside up */
    CHECK(nprfx_image_at(&dst, 1, 4)[0] == 7.0f);
    nprfx_image two = nprfx_image_channels(&im, 0, 2);
    CHECK(nprfx_image_copy(NULL, &two, &dst) == NPRFX_ERR_INVALID_ARGUMENT);

    /* fill through a channel view touches only its channels */
    const float v2[2] = {0.5f, 0.25f};
    nprfx_image mid = nprfx_image_channels(&im, 2, 2);
    nprfx_image_fill(&mid, v2);
    CHECK(nprfx_image_at(&im, 0, 0)[1] == 100.0f && nprfx_image_at(&im, 0, 0)[2] == 0.5f);
    CHECK(nprfx_image_at(&im, 3, 2)[3] == 0.25f && nprfx_image_at(&im, 3, 2)[0] == 23.0f);

    nprfx_image_free(&dst);
    nprfx_image_free(&im);
}

static void test_context(void)
{
    /* an older, shorter init struct (without executor) is accepted; a wrong size is not */
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    nprfx_context *ctx = NULL;
    init.size = offsetof(nprfx_context_init, executor);
    CHECK_OK(nprfx_context_create(&init, &ctx));
    CHECK(nprfx_context_executor(ctx) != NULL);
    nprfx_context_destroy(ctx);
    init.size = 3;
    CHECK(nprfx_context_create(&init, &ctx) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(ctx == NULL);
    CHECK(nprfx_error(NULL, NPRFX_ERR_IO, "dropped %d", 1) == NPRFX_ERR_IO);
    CHECK(strcmp(nprfx_result_name(NPRFX_ERR_MISSING_INPUT), "missing-input") == 0);
    CHECK(nprfx_result_name(12345) != NULL);
}

int main(void)
{
    test_rects();
    test_alloc();
    test_scoped();
    test_views();
    test_context();
    return check_finish();
}
