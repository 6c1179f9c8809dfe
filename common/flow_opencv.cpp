/* OpenCV's DIS optical flow as an nprfx flow provider (common/flow_opencv.h; docs/design.md §3.15).
 *
 * DIS takes 8-bit grey (CV_8UC1). Core hands in luminance already tone-mapped into [0, 1)
 * (x / (1 + x) of scene-linear luma, nprfx_flow_luminance), so the fixed mapping
 * round(255 * clamp(v, 0, 1)) keeps the darks' and the highlights' detail alike and never
 * depends on the frame's own range (a per-frame normalisation would make two frames of one shot
 * disagree about the same grey).
 *
 * Bit-identical results: DIS splits its patch search into as many stripes as OpenCV's thread
 * count, and spatial propagation runs within a stripe, so the flow changes with that count. The
 * provider sets it to 1 (cv::setNumThreads, a process-wide OpenCV setting; nothing else in the
 * runner or the bundle uses OpenCV), so a frame's flow is the same on any machine and at any
 * --threads. Core runs a frame's two to four solves side by side on its executor instead. */
#include "flow_opencv.h"

#if defined(NPRFX_HAVE_OPENCV)

#include <cstdio>
#include <cstring>
#include <exception>
#include <mutex>

#include <opencv2/core.hpp>
#include <opencv2/core/version.hpp>
#include <opencv2/video/tracking.hpp>

namespace
{

/* The stripes DIS's search is split into, and OpenCV's threads: see above. */
constexpr int NPRFX_FLOW_CV_THREADS = 1;

std::mutex threads_lock;

void to_u8(const float *src, int w, int h, cv::Mat &dst)
{
    dst.create(h, w, CV_8UC1);
    for (int y = 0; y < h; y++) {
        unsigned char *row = dst.ptr<unsigned char>(y);
        const float *s = src + (size_t)y * (size_t)w;
        for (int x = 0; x < w; x++) {
            float v = s[x];
            v = v > 0 ? (v < 1 ? v : 1) : 0; /* NaN too becomes 0 */
            row[x] = (unsigned char)(v * 255.0f + 0.5f);
        }
    }
}

nprfx_result dis_compute(void *user, nprfx_context *ctx, const float *from, const float *to, int w,
                         int h, nprfx_flow_preset preset, float *flow)
{
    (void)user;
    int cv_preset = preset == NPRFX_FLOW_ULTRAFAST ? cv::DISOpticalFlow::PRESET_ULTRAFAST
                    : preset == NPRFX_FLOW_FAST    ? cv::DISOpticalFlow::PRESET_FAST
                                                   : cv::DISOpticalFlow::PRESET_MEDIUM;
    try {
        {
            std::lock_guard<std::mutex> g(threads_lock);
            if (cv::getNumThreads() != NPRFX_FLOW_CV_THREADS)
                cv::setNumThreads(NPRFX_FLOW_CV_THREADS);
        }
        /* DIS needs room for its patches and its pyramid: a frame smaller than a few patches
         * has no flow worth solving (and OpenCV would refuse it), so it gets none. */
        if (w < 16 || h < 16) {
            std::memset(flow, 0, sizeof(float) * 2 * (size_t)w * (size_t)h);
            return NPRFX_OK;
        }
        cv::Mat a, b;
        to_u8(from, w, h, a);
        to_u8(to, w, h, b);
        cv::Ptr<cv::DISOpticalFlow> dis = cv::DISOpticalFlow::create(cv_preset);
        /* An empty result: DIS takes a flow of the right size as its initial guess. */
        cv::Mat f;
        dis->calc(a, b, f);
        if (f.rows != h || f.cols != w || f.type() != CV_32FC2)
            return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "flow: OpenCV DIS gave no %dx%d flow", w,
                               h);
        f.copyTo(cv::Mat(h, w, CV_32FC2, flow));
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "flow: OpenCV DIS failed on %dx%d frames: %s",
                           w, h, e.what());
    }
    return NPRFX_OK;
}

const nprfx_flow_provider dis_provider = {sizeof(nprfx_flow_provider), "OpenCV " CV_VERSION " DIS",
                                          dis_compute, nullptr};

} // namespace

const nprfx_flow_provider *flow_opencv_provider(void)
{
    return &dis_provider;
}

#else

const nprfx_flow_provider *flow_opencv_provider(void)
{
    return nullptr;
}

#endif
