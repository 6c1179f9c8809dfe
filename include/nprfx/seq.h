/* nprfx — frame lists and frame-numbered path patterns.
 *
 * Frame lists: "7", "1-24", "1-24x2", "24-1" (descending), "1,3,5-7", negative frames ("-3--1").
 * Path patterns (in the last path component only, so a directory named "take#2" is left alone):
 *   "#" runs    one digit of width per '#', zero padded: "####" = 0007 (Nuke/Blender; note that
 *               oiiotool reads a single '#' as four digits)
 *   "@" runs    one digit of width per '@', zero padded: "@@@" = 007
 *   "%0Nd"      printf style, zero padded to N; "%d" unpadded; "%%" is a literal '%'
 * Every token in the file name receives the same frame number. Negative frames print as printf
 * does ("%04d" of -5 is "-005"). */
#ifndef NPRFX_SEQ_H
#define NPRFX_SEQ_H

#include <stddef.h>

#include "nprfx/context.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The frames nprfx renders: nine digits either way, so that a frame plus any offset a node
 * reaches back or ahead (time-offset's 100000 at most, a shot's warm-up) stays inside an int.
 * Frame lists and the graph's render calls refuse frames outside it with a message. */
#define NPRFX_FRAME_MAX 999999999
#define NPRFX_FRAME_MIN (-NPRFX_FRAME_MAX)

typedef struct nprfx_frame_list {
    int *frames; /* in the order given; for nprfx_seq_list: ascending */
    int count;
} nprfx_frame_list;

/* Parse a frame-list spec into out (free with nprfx_seq_frames_free). */
NPRFX_API nprfx_result nprfx_seq_parse_frames(nprfx_context *ctx, const char *spec,
                                              nprfx_frame_list *out);
NPRFX_API void nprfx_seq_frames_free(nprfx_frame_list *list);

/* 1 when the file name of path holds a frame token (see above), else 0. */
NPRFX_API int nprfx_seq_has_pattern(const char *path);

/* Write pattern with every frame token replaced by `frame` into out (size bytes). A path with no
 * token is copied unchanged. */
NPRFX_API nprfx_result nprfx_seq_expand(nprfx_context *ctx, const char *pattern, int frame,
                                        char *out, size_t size);

/* 1 when name (a file name, no directory) is the file of some frame of pattern's file name, by
 * the same exact re-expansion rule as nprfx_seq_list (*frame receives it; frame may be NULL); a
 * pattern without a token matches its own file name only. */
NPRFX_API int nprfx_seq_match(const char *pattern, const char *name, int *frame);

/* pattern's file name with every frame token written one way, so that spellings of one sequence
 * agree: zero padded tokens ("####", "@@@@", "%04d") and "%d" become '#' runs of their width,
 * "%%" becomes '%', space padded "%4d" stays as written (the output locks' names). */
NPRFX_API nprfx_result nprfx_seq_canonical(nprfx_context *ctx, const char *pattern, char *out,
                                           size_t size);

/* The frames whose files exist for pattern (ascending, no duplicates; count 0 when none). A name
 * matches only if expanding the pattern with its frame gives that name exactly, so "####" does
 * not pick up "12.exr" or "00012.exr". */
NPRFX_API nprfx_result nprfx_seq_list(nprfx_context *ctx, const char *pattern,
                                      nprfx_frame_list *out);

#ifdef __cplusplus
}
#endif
#endif
