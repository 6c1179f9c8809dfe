/* nprfx — picking channels out of a named multi-channel image by reference text. */
#ifndef NPRFX_CHANNELS_H
#define NPRFX_CHANNELS_H

#include <stddef.h>

#include "nprfx/context.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Resolve a comma-separated selection against `names` (n channels) into indices.
 * Each item is, in order of preference:
 *   - an exact channel name ("ViewLayer.Depth.Z");
 *   - a dotted suffix of exactly one channel ("Depth.Z" matches "ViewLayer.Depth.Z");
 *   - a layer with channel letters ("Vector.XY" -> Vector.X, Vector.Y; "Combined.RGBA");
 *   - a layer name ("Vector", "Pref") -> its channels, R G B A / X Y Z W / U V first.
 * Returns the number of indices written (<= max), or -1 with *bad set to the item that matched
 * nothing (or matched several channels: *ambiguous = 1). */
NPRFX_API int nprfx_channels_select(const char *const *names, int n, const char *selection,
                                    int *idx, int max, char *bad, size_t bad_size, int *ambiguous);

/* Try each '|'-separated alternative of an AOV hint; returns the count of the first alternative
 * that resolves completely, or -1. */
NPRFX_API int nprfx_channels_from_hint(const char *const *names, int n, const char *hint, int *idx,
                                       int max);

/* Rank of a channel's last component inside its layer: colour, vectors, texture coordinates,
 * then alpha, then the rest (the order layer selections and hosts list them in). */
NPRFX_API int nprfx_channels_component_rank(const char *component);

#ifdef __cplusplus
}
#endif
#endif
