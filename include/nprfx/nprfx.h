/* nprfx — umbrella header. */
#ifndef NPRFX_H
#define NPRFX_H
#include "nprfx/result.h"
#include "nprfx/exec.h"
#include "nprfx/context.h"
#include "nprfx/image.h"
#include "nprfx/objectid.h"
#include "nprfx/rng.h"
#include "nprfx/filter.h"
#include "nprfx/metrics.h"
#include "nprfx/node.h"
#include "nprfx/synth.h"
#define NPRFX_VERSION_MAJOR 0
#define NPRFX_VERSION_MINOR 1
#define NPRFX_VERSION_PATCH 0
#define NPRFX_VERSION_STRING "0.1.0"
#endif
