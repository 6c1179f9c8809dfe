/* nprfx graph engine — the memory bound on images (nprfx/io.h): the context's, else
 * NPRFX_READ_LIMIT, else half the physical memory. */
#define _DEFAULT_SOURCE /* sysconf(_SC_PHYS_PAGES) */
#include "nprfx/io.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define GIB ((uint64_t)1 << 30)

/* Half the physical memory: room for the process's other memory and for the system, and on a
 * farm node shared by two renders each stays clear of the OOM killer. A 4K frame of 56 float
 * channels is 1.9 GiB, so a fixed few GiB would refuse production plates on big machines. */
static uint64_t default_limit(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page > 0 ? (uint64_t)pages * (uint64_t)page / 2 : 4 * GIB;
}

nprfx_result nprfx_parse_size(const char *e, uint64_t *bytes)
{
    char *end = NULL;
    double v = strtod(e, &end);
    double unit = 1;
    if (end != e && *end) {
        switch (toupper((unsigned char)*end)) {
        case 'K':
            unit = 1024.0;
            break;
        case 'M':
            unit = 1024.0 * 1024;
            break;
        case 'G':
            unit = 1024.0 * 1024 * 1024;
            break;
        case 'T':
            unit = 1024.0 * 1024 * 1024 * 1024;
            break;
        default:
            unit = 0;
        }
        if (unit != 0) end++;
        if (unit != 0 && (*end == 'i' || *end == 'I')) end++; /* "4GiB" */
        if (unit != 0 && (*end == 'b' || *end == 'B')) end++;
    }
    if (end == e || *end || unit == 0 || !(v >= 0) || !isfinite(v))
        return NPRFX_ERR_INVALID_ARGUMENT;
    double b = v * unit;
    *bytes = b == 0 || b >= 18e18 ? UINT64_MAX : (uint64_t)b;
    return NPRFX_OK;
}

nprfx_result nprfx_image_limit(nprfx_context *ctx, uint64_t *bytes)
{
    if (nprfx_context_memory_limit(ctx, bytes, NULL)) return NPRFX_OK;
    const char *e = getenv("NPRFX_READ_LIMIT");
    *bytes = default_limit();
    if (!e || !*e) return NPRFX_OK;
    if (nprfx_parse_size(e, bytes))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "NPRFX_READ_LIMIT='%s' is not a size (e.g. 4G, 512M, or 0 for none)", e);
    return NPRFX_OK;
}

const char *nprfx_memory_limit_origin(const nprfx_context *ctx)
{
    const char *origin = NULL;
    if (nprfx_context_memory_limit(ctx, NULL, &origin)) return origin;
    const char *e = getenv("NPRFX_READ_LIMIT");
    if (e && *e) return "NPRFX_READ_LIMIT";
    return "half the physical memory; --mem-limit or NPRFX_READ_LIMIT sets it";
}

void nprfx_format_bytes(char *buf, size_t n, uint64_t bytes)
{
    static const char *const units[] = {"KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    if (bytes < 1024) {
        snprintf(buf, n, "%u bytes", (unsigned)bytes);
        return;
    }
    double v = (double)bytes / 1024.0;
    int u = 0;
    while (v >= 1024.0 && u < 5) {
        v /= 1024.0;
        u++;
    }
    /* Whole numbers as they are ("4 GiB"), others with one decimal ("44.7 GiB"). */
    if (v == floor(v) || v >= 100)
        snprintf(buf, n, "%.0f %s", v, units[u]);
    else
        snprintf(buf, n, "%.1f %s", v, units[u]);
}

nprfx_result nprfx_image_limit_check(nprfx_context *ctx, const char *what, int64_t w, int64_t h,
                                     int64_t channels, uint64_t extra_bytes)
{
    uint64_t limit;
    nprfx_result r = nprfx_image_limit(ctx, &limit);
    if (r) return r;
    if (w < 0 || h < 0 || channels < 0) return NPRFX_OK; /* the caller's own check reports it */
    /* In long double: w*h*channels*4 overflows 64 bits for windows a damaged header can give. */
    long double need =
        (long double)w * (long double)h * (long double)channels * 4.0L + (long double)extra_bytes;
    if (limit == UINT64_MAX || need <= (long double)limit) return NPRFX_OK;
    char needs[32], lim[32];
    nprfx_format_bytes(needs, sizeof needs, need >= 1.8e19L ? UINT64_MAX : (uint64_t)need);
    nprfx_format_bytes(lim, sizeof lim, limit);
    return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY,
                       "%s %lldx%lld with %lld channel%s needs %s, above the %s memory limit (%s)",
                       what, (long long)w, (long long)h, (long long)channels,
                       channels == 1 ? "" : "s", needs, lim, nprfx_memory_limit_origin(ctx));
}
