/* The strip of owners (stipple_strip.c), for stipple_owners.c. Internal, never installed. */
#ifndef NPRFX_STIPPLE_STRIP_H
#define NPRFX_STIPPLE_STRIP_H

#include "stipple_footprint.h"

/* The owners of rows [y0, y1) and columns [x0, x1) of E into the strip (from its column 0):
 * the limit of every owner, and where it keeps something, i_max, the darkness and the
 * footprint's box (where it keeps nothing, an empty box). */
void internal_stipple_strip_fill(const sjob *j, const scratch *s, nprfx_rect E, int y0, int y1,
                                 int x0, int x1, strip *st);

#endif
