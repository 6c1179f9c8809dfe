/* The stipple node's vector export: its dots as CSV or SVG text (plugins/support/stipple_export.c,
 * library nprfx_nodes). Core hands over the list of stipples (nprfx_stipple_collect); the formats
 * live here, outside core, and the front end writes the text to the frame's export path. */
#ifndef NPRFX_SUPPORT_STIPPLE_EXPORT_H
#define NPRFX_SUPPORT_STIPPLE_EXPORT_H

#include <stddef.h>

#include "nprfx/node.h"
#include "nprfx/stipple.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Vector export formats for internal_stipple_format. Coordinates in both are image-plane pixels
 * with the frame's top-left corner at (0, 0) and y down (a core position x becomes
 * x - frame.x0 + 0.5), so pixel (i, j) covers [i, i+1) x [j, j+1).
 *   CSV: the header line "x,y,radius,tone,sample,object", then one stipple per line.
 *   SVG: an <svg> with viewBox "0 0 W H" (the frame size), a rectangle of the paper colour,
 *        and one <circle cx cy r> per stipple, filled with the ink colour at opacity = tone. */
typedef enum nprfx_stipple_format_kind {
    NPRFX_STIPPLE_CSV = 0,
    NPRFX_STIPPLE_SVG = 1
} nprfx_stipple_format_kind;

/* Format a stipple list as text (malloc'd, NUL-terminated; *len excludes the NUL). ink/paper are
 * RGBA (display-referred values in [0, 1] are expected for SVG; they are clamped). */
nprfx_result internal_stipple_format(nprfx_context *ctx, const nprfx_stipple *list, size_t count,
                                     nprfx_rect frame, nprfx_stipple_format_kind kind,
                                     const float *ink, const float *paper, char **text,
                                     size_t *len);

/* The stipple node's export hook (desc->export_text, np its bound params with make_sequence
 * filled): the stipples of the whole frame (nprfx_stipple_node_collect) in the format of path's
 * extension, .csv or .svg in any case; another extension, or none, is an error that says which
 * to use. */
nprfx_result internal_stipple_export_text(const nprfx_render_args *args,
                                          const nprfx_stipple_node_params *np, const char *path,
                                          char **text, size_t *len);

/* The stipple node's vector export for render arguments of the `stipple` node (its inputs and
 * params at the frame's time; window is ignored), formatted as `kind`: nprfx_node_export with
 * a path of kind's extension, so the arguments get the checks of any node call (an output image
 * of the node's channels included). */
nprfx_result internal_stipple_node_export(const nprfx_render_args *args,
                                          nprfx_stipple_format_kind kind, char **text, size_t *len);

#ifdef __cplusplus
}
#endif
#endif
