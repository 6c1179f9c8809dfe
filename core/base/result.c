/* Result code names. */
#include "nprfx/result.h"

const char *nprfx_result_name(nprfx_result code)
{
    switch (code) {
    case NPRFX_OK:
        return "ok";
    case NPRFX_ERR_OUT_OF_MEMORY:
        return "out-of-memory";
    case NPRFX_ERR_INVALID_ARGUMENT:
        return "invalid-argument";
    case NPRFX_ERR_MISSING_INPUT:
        return "missing-input";
    case NPRFX_ERR_SIZE_MISMATCH:
        return "size-mismatch";
    case NPRFX_ERR_IO:
        return "io";
    case NPRFX_ERR_UNKNOWN_NODE:
        return "unknown-node";
    case NPRFX_ERR_UNKNOWN_PARAM:
        return "unknown-param";
    case NPRFX_ERR_OUT_OF_RANGE:
        return "out-of-range";
    case NPRFX_ERR_PARSE:
        return "parse";
    case NPRFX_ERR_CANCELLED:
        return "cancelled";
    case NPRFX_ERR_UNSUPPORTED:
        return "unsupported";
    case NPRFX_ERR_INTERNAL:
        return "internal";
    default:
        return "unknown-code";
    }
}
