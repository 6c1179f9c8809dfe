/* The optical flow provider of the runner and the OpenFX bundle: OpenCV's DIS (Kroeger et al.
 * 2016, "Fast Optical Flow using Dense Inverse Search"), behind a C header so that only
 * common/flow_opencv.cpp sees C++ and OpenCV (docs/design.md §3.15). */
#ifndef NPRFX_CLI_FLOW_OPENCV_H
#define NPRFX_CLI_FLOW_OPENCV_H

#include "nprfx/flow.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The provider to put in nprfx_context_init.flow (static: valid for the whole process), or NULL
 * when nprfx was built without OpenCV (NPRFX_WITH_OPENCV). */
const nprfx_flow_provider *flow_opencv_provider(void);

#ifdef __cplusplus
}
#endif
#endif
