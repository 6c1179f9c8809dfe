/* nprfx OpenFX test host — pixel depths: the runner's pixels are float, and a host that hands out
 * 8- or 16-bit images (MLT) converts them on the way in and back to float on the way out, so the
 * adapter meets the integer layouts it will meet there. */
#include <math.h>
#include <stdint.h>

#include "ofx_host_internal.h"

size_t internal_depth_size(hdepth d)
{
    return d == HD_BYTE ? 1 : d == HD_SHORT ? 2 : sizeof(float);
}

const char *internal_depth_name(hdepth d)
{
    return d == HD_BYTE ? kOfxBitDepthByte : d == HD_SHORT ? kOfxBitDepthShort : kOfxBitDepthFloat;
}

/* Rounded to the nearest level and clamped to [0, max]; NaN becomes 0, as an integer image has
 * no other choice. */
static unsigned quantize(float v, double max)
{
    double q = (double)v * max;
    if (!(q > 0)) return 0;
    if (q >= max) return (unsigned)max;
    return (unsigned)floor(q + 0.5);
}

void internal_depth_store(hdepth d, void *dst, size_t i, float v)
{
    if (d == HD_BYTE)
        ((uint8_t *)dst)[i] = (uint8_t)quantize(v, 255.0);
    else if (d == HD_SHORT)
        ((uint16_t *)dst)[i] = (uint16_t)quantize(v, 65535.0);
    else
        ((float *)dst)[i] = v;
}

float internal_depth_load(hdepth d, const void *src, size_t i)
{
    if (d == HD_BYTE) return (float)(((const uint8_t *)src)[i] / 255.0);
    if (d == HD_SHORT) return (float)(((const uint16_t *)src)[i] / 65535.0);
    return ((const float *)src)[i];
}
