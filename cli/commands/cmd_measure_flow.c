/* nprfx measure flow — how close an optical flow sequence (the flow node's output) is to the
 * exact motion of a synthetic plate: mean endpoint error on the pixels visible in the previous
 * frame, and how well low confidence finds the disoccluded ones (precision and recall of
 * confidence.prev < threshold against the visibility the exact motion implies). The flow test
 * (tests/cli/flow.sh) bounds these figures; docs/design.md §3.15 quotes them. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cmd_measure_flow.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "nprfx/io.h"
#include "nprfx/metrics.h"
#include "nprfx/seq.h"

enum { MF_OK = 0, MF_FAILED = 1, MF_USAGE = 2 };

static void usage(FILE *f)
{
    fprintf(f, "usage: nprfx measure flow ESTIMATE TRUTH --frames SPEC [--threshold C]\n\n"
               "Compares a flow sequence ESTIMATE (channels motion_prev.X/Y and confidence.prev,\n"
               "as the flow node writes them) with a synthetic plate sequence TRUTH (motion_prev,\n"
               "motion_next and id, as nprfx synth writes them), at each frame of SPEC whose\n"
               "previous frame is in SPEC too, and prints one line per frame and the totals:\n"
               "  epe                   mean endpoint error (pixels) of motion_prev where the\n"
               "                        pixel was visible in the previous frame\n"
               "  occlusion_precision   of the pixels with confidence.prev < C (default 0.5), the\n"
               "                        share that were not visible in the previous frame\n"
               "  occlusion_recall      of the pixels not visible there, the share found so\n"
               "  conf_prev_mean        mean confidence.prev over the frame\n");
}

static void print_error(void *user, const nprfx_context *ctx, nprfx_result code,
                        const char *message)
{
    (void)user, (void)ctx, (void)code;
    fprintf(stderr, "nprfx measure flow: %s\n", message);
}

/* Frame `frame` of pattern, with the channels named (each must exist) as views. */
static int load(nprfx_context *ctx, const char *pattern, int frame, nprfx_plate *p,
                const char *const *names, int n, nprfx_image *views)
{
    char path[4096];
    if (nprfx_seq_expand(ctx, pattern, frame, path, sizeof path) || nprfx_io_read(ctx, path, p))
        return 1;
    for (int i = 0; i < n; i++) {
        int c = nprfx_plate_channel(p, names[i]);
        if (c < 0) {
            fprintf(stderr, "nprfx measure flow: %s has no channel %s\n", path, names[i]);
            return 1;
        }
        views[i] = nprfx_plate_view(p, c, 1);
    }
    return 0;
}

/* Two adjacent one-channel views as one two-channel view (X then Y, as plates store them). */
static int pair_view(const nprfx_image *x, const nprfx_image *y, nprfx_image *out)
{
    if (y->data != x->data + 1) return 1;
    *out = *x;
    out->channels = 2;
    return 0;
}

int cli_cmd_measure_flow(int argc, char **argv)
{
    const char *est = NULL, *truth = NULL, *frames = NULL;
    double thr = 0.5;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return MF_OK;
        } else if (!strcmp(a, "--frames") && i + 1 < argc) {
            frames = argv[++i];
        } else if (!strcmp(a, "--threshold") && i + 1 < argc) {
            thr = atof(argv[++i]);
        } else if (a[0] != '-' && !est) {
            est = a;
        } else if (a[0] != '-' && !truth) {
            truth = a;
        } else {
            fprintf(stderr, "nprfx measure flow: unexpected argument '%s'\n", a);
            usage(stderr);
            return MF_USAGE;
        }
    }
    if (!est || !truth || !frames) {
        usage(stderr);
        return MF_USAGE;
    }
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.error_handler = print_error;
    nprfx_context *ctx = NULL;
    if (nprfx_context_create(&init, &ctx)) return MF_FAILED;
    nprfx_frame_list fl = {0};
    int status = MF_OK;
    if (nprfx_seq_parse_frames(ctx, frames, &fl)) {
        nprfx_context_destroy(ctx);
        return MF_USAGE;
    }
    static const char *const est_names[] = {"motion_prev.X", "motion_prev.Y", "confidence.prev"};
    static const char *const truth_names[] = {"motion_prev.X", "motion_prev.Y", "motion_next.X",
                                              "motion_next.Y", "id"};
    double epe_sum = 0, conf_sum = 0;
    long long epe_n = 0, conf_n = 0, tp = 0, fp = 0, fn = 0;
    int measured = 0;
    for (int k = 0; k < fl.count && status == MF_OK; k++) {
        int t = fl.frames[k], has_prev = 0;
        for (int j = 0; j < fl.count; j++)
            has_prev |= fl.frames[j] == t - 1;
        if (!has_prev) continue;
        nprfx_plate pe = {0}, pt = {0}, pp = {0};
        nprfx_image ve[3], vt[5], vp[5], ef, tf, tn, vis = {0};
        if (load(ctx, est, t, &pe, est_names, 3, ve) ||
            load(ctx, truth, t, &pt, truth_names, 5, vt) ||
            load(ctx, truth, t - 1, &pp, truth_names, 5, vp) || pair_view(&ve[0], &ve[1], &ef) ||
            pair_view(&vt[0], &vt[1], &tf) || pair_view(&vp[2], &vp[3], &tn) ||
            nprfx_image_alloc(ctx, tf.bounds, 1, &vis) ||
            nprfx_motion_visible(ctx, &tf, &vt[4], &tn, &vp[4], 0.5, &vis)) {
            status = MF_FAILED;
        } else {
            double epe = 0;
            long long n = 0, ftp = 0, ffp = 0, ffn = 0, cn = 0;
            double cs = 0;
            nprfx_metric_epe(ctx, &ef, &tf, &vis, &epe, &n);
            nprfx_rect r = nprfx_rect_intersect(ve[2].bounds, vis.bounds);
            for (int y = r.y0; y < r.y1; y++)
                for (int x = r.x0; x < r.x1; x++) {
                    float c = nprfx_image_at(&ve[2], x, y)[0];
                    int occ = nprfx_image_at(&vis, x, y)[0] < 0.5f, low = c < thr;
                    ftp += occ && low, ffp += !occ && low, ffn += occ && !low;
                    cs += c, cn++;
                }
            printf(
                "frame %d epe %.4f visible %lld occluded %lld flagged %lld conf_prev_mean %.4f\n",
                t, epe, n, ftp + ffn, ftp + ffp, cn ? cs / (double)cn : 0.0);
            epe_sum += epe * (double)n, epe_n += n;
            conf_sum += cs, conf_n += cn;
            tp += ftp, fp += ffp, fn += ffn;
            measured++;
        }
        nprfx_image_free(&vis);
        nprfx_plate_free(&pe);
        nprfx_plate_free(&pt);
        nprfx_plate_free(&pp);
    }
    if (status == MF_OK && !measured) {
        fprintf(stderr, "nprfx measure flow: no frame of '%s' has its previous frame there\n",
                frames);
        status = MF_USAGE;
    }
    if (status == MF_OK) {
        printf("epe %.4f\n", epe_n ? epe_sum / (double)epe_n : 0.0);
        printf("occlusion_precision %.4f\n", tp + fp ? (double)tp / (double)(tp + fp) : 1.0);
        printf("occlusion_recall %.4f\n", tp + fn ? (double)tp / (double)(tp + fn) : 1.0);
        printf("conf_prev_mean %.4f\n", conf_n ? conf_sum / (double)conf_n : 0.0);
    }
    nprfx_seq_frames_free(&fl);
    nprfx_context_destroy(ctx);
    return status;
}
