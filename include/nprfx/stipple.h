/* nprfx — stippling from UV and shading (Ma et al. 2018; docs/design.md §3.3).
 *
 * Candidate stipples are the points of the IVS sequence (ivs.h) tiled over UV space with period
 * `tile` (A0 = tile^2 of UV area per copy; tile / sqrt(aspect) by tile * sqrt(aspect) where the
 * UV map is stretched) and shifted per object. A pixel with UV Jacobian J
 * (k = 1 / |det J| screen px^2 per UV area) and darkness g = 1 - tone keeps sample i (1-based)
 * when its screen area k * A0 / i is at least a threshold:
 *
 *   uniform    threshold area / g; every kept stipple has `area` px^2            (Eq. 5)
 *   radius     threshold a0; stipple area g * a0, dropped below delta_min         (Eq. 6)
 *   multitone  threshold a0; stipple area `area`; pen tone tau = g * a0 / area is made of the
 *              two nearest pens tau_l <= tau <= tau_l+1: the samples with i / i_max <= (tau -
 *              tau_l) / (tau_l+1 - tau_l) take the darker pen (Eq. 7-8 as read in docs/design.md)
 *
 * Which pixel a sample belongs to is decided in UV space: each pixel's footprint is the
 * quadrilateral through its four corners, a corner being the mean UV of the (same-object) pixels
 * that share it, so neighbouring footprints share edges exactly and a sample lands in exactly one
 * pixel (half-open edges). The Jacobian comes from finite differences that never straddle an
 * object-id edge (and avoid a UV seam by taking the smaller one-sided difference); the |det J|
 * the thresholds use is averaged over the 5x5 same-object pixels around, which keeps the kept
 * prefix steady where the UV pass is quantised (half floats). A pixel whose |det J| is more
 * than 8 times that of each of its same-object neighbours holds a filtered blend of two
 * surfaces' (or two UV charts') UVs, as renderers write along silhouettes and seams: it takes
 * the UV extrapolated from (and the derivatives of) its smoothest such neighbour, instead of
 * owning a huge footprint packed with dots (a dark outline).
 *
 * Stipples are drawn as discs of their exact area (analytic disc/pixel-square intersection),
 * overlapping discs combining as 1 - prod(1 - coverage * tone) in a fixed order, ink over paper.
 * Results are bit-identical for any thread count, tile split or render order. */
#ifndef NPRFX_STIPPLE_H
#define NPRFX_STIPPLE_H

#include <stddef.h>
#include <stdint.h>

#include "nprfx/image.h"
#include "nprfx/ivs.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum nprfx_stipple_mode {
    NPRFX_STIPPLE_UNIFORM = 0,
    NPRFX_STIPPLE_RADIUS = 1,
    NPRFX_STIPPLE_MULTITONE = 2
} nprfx_stipple_mode;

#define NPRFX_STIPPLE_MAX_TONES 16
/* The longest prefix of the sequence a pixel may use (darker or denser requests saturate). */
#define NPRFX_STIPPLE_MAX_SAMPLES (1 << 21)
/* Without a uv input the image is its own UV space: uv = pixel / (this * render scale). */
#define NPRFX_STIPPLE_PLANE_PIXELS 1024.0

typedef struct nprfx_stipple_params {
    size_t size;      /* sizeof(nprfx_stipple_params) */
    int mode;         /* nprfx_stipple_mode */
    double area;      /* px^2: the stipple area (uniform, multitone) */
    double a0;        /* px^2: the screen area a kept sample stands for (radius, multitone) */
    double delta_min; /* px^2: radius mode drops smaller stipples */
    int num_tones;    /* multitone: pen darknesses, ascending in (0, 1] */
    double tones[NPRFX_STIPPLE_MAX_TONES];
    double tile;        /* UV period of the sequence, > 0 */
    double plane_scale; /* without uv: pixels per UV unit (NPRFX_STIPPLE_PLANE_PIXELS * scale) */
    float ink[4], paper[4]; /* RGBA, treated as premultiplied: out = paper + d * (ink - paper) */
    uint64_t seed;          /* shifts the sequence per object id */
    int coverage_channel;   /* output a 5th channel: the ink coverage d */
    /* The sequence to use: a fixed index (its length caps the prefix a pixel may keep), or
     * NULL to take it from `sequence` below. Results do not depend on which, nor on how long
     * the sequence is beyond what a pixel keeps: only that prefix is ever read. */
    const nprfx_ivs_index *index;
    /* NULL, or NPRFX_STIPPLE_CURVE_SIZE darknesses from nprfx_stipple_tone_curve: the
     * darkness g of each pixel is replaced by curve(g) (linear interpolation) before the
     * thresholds, which compensates for overlapping dots. */
    const float *tone_curve;
    /* When index is NULL: a caller-owned, lazily grown sequence (nprfx_stipple_sequence_create;
     * the stipple node keeps one in its instance state), shared by the threads of a call and
     * reused across calls. NULL too: each call builds its own for its duration (correct, but it
     * pays the generation, ~0.15 s for the first 65536 points, every time). */
    struct nprfx_stipple_sequence *sequence;
    /* UV aspect, > 0 (1: UV units are square on the surfaces): how many times longer a unit of
     * u is than a unit of v on the surfaces, as where a UV square is mapped onto a 2:1
     * rectangle. The sequence is tiled with period tile / sqrt(aspect) in u and tile *
     * sqrt(aspect) in v (the same area A0 = tile^2), which makes its copies square on such
     * surfaces; otherwise the dots are stretched with the UV map and line up in rows. */
    double aspect;
    /* NULL, or a counter nprfx_stipple_draw adds the number of stipples drawn to: those
     * whose centre lies in the window (so tiles of a frame add up to the frame's count). */
    long long *count;
    /* Testing: 0 the fastest loops the CPU has, 1 the baseline ISA's (SSE2 on x86-64), 2 AVX2
     * (where the CPU has it, else as 1). Every path gives bit-identical output. */
    int simd;
    /* Follow the foreshortening (1, the default; 0 is Ma et al.'s reading): where the UV Jacobian
     * stretches one direction of the screen more than the other (singular values s1 > s2), the
     * sequence is read through A = R diag(sqrt(r), 1 / sqrt(r)) R^T, r = s1 / s2 and R the turn to
     * the UV direction stretched most, quantised to 13 levels (none; r = 2, 4, 8 at 0, 45, 90, 135
     * degrees) and blended: a level with share w keeps about w of the prefix, the samples about
     * the cut fading (their stipples' tone scaled), so that two levels' inks sum to the owner's
     * and a dot changing level dissolves rather than pops. det A = 1, so the thresholds of
     * Eq. 3-8 are unchanged. Beyond r = 16 the UVs alone. */
    int anisotropy;
} nprfx_stipple_params;

#define NPRFX_STIPPLE_CURVE_SIZE 17

/* Defaults matching the stipple node's. */
NPRFX_API void nprfx_stipple_params_default(nprfx_stipple_params *p);

/* Parse a pen-tone list ("0.3, 0.6, 1") into p->tones / p->num_tones. */
NPRFX_API nprfx_result nprfx_stipple_parse_tones(nprfx_context *ctx, const char *text,
                                                 nprfx_stipple_params *p);

/* Tone correction. The paper's thresholds put down ink area g per unit area, but dots that
 * overlap cover less than their summed area, so dark tones come out light (by up to ~0.15 in
 * uniform mode). This measures the darkness D(g) the params actually produce (constant-tone
 * patches rendered with the identity mapping, dots larger than 8 px^2 scaled down to 8 with
 * their ratios kept: the coverage of blue-noise discs is scale-invariant) and writes its
 * inverse: curve[k] = the g for which D(g) = k / (NPRFX_STIPPLE_CURVE_SIZE - 1), 1 where that
 * darkness cannot be reached. About 30 ms; deterministic. p->tone_curve is ignored. */
NPRFX_API nprfx_result nprfx_stipple_tone_curve(nprfx_context *ctx, const nprfx_stipple_params *p,
                                                float *curve);

typedef struct nprfx_stipple_inputs {
    const nprfx_image *tone; /* required: 1 = paper white; 3-4 channels: Rec. 709 luma */
    const nprfx_image *uv;   /* optional (NULL): 2 channels */
    const nprfx_image *id;   /* optional (NULL): object id, 1 channel (nprfx/objectid.h) */
    nprfx_rect frame;        /* the whole image domain */
} nprfx_stipple_inputs;

/* The algorithm (the node's render, nprfx_stipple_render below, completes its params and calls
 * it): draw the pixels of `window` into out (4 channels RGBA, or 5 with coverage_channel). Inputs
 * are read around the window as far as the stipples reaching it need. Parallel through the
 * context's executor. */
NPRFX_API nprfx_result nprfx_stipple_draw(nprfx_context *ctx, const nprfx_stipple_params *p,
                                          const nprfx_stipple_inputs *in, nprfx_rect window,
                                          nprfx_image *out);

/* One stipple, as the vector export (plugins/support/stipple_export.h, outside core) writes it. */
typedef struct nprfx_stipple {
    double x, y;  /* screen position in core pixel coordinates (pixel centres at integers) */
    float radius; /* px */
    float tone;   /* pen darkness in (0, 1]: 1 for uniform and radius modes */
    int sample;   /* 0-based index in the IVS sequence */
    int object;   /* object id (0 without an id input) */
} nprfx_stipple;

/* The stipples owned by the pixels of `region` (usually the frame), in row-major order of their
 * pixels. *list is malloc'd (NULL when *count is 0); the caller frees it. Core formats no files:
 * plugins/support/stipple_export.c writes the list as CSV or SVG. */
NPRFX_API nprfx_result nprfx_stipple_collect(nprfx_context *ctx, const nprfx_stipple_params *p,
                                             const nprfx_stipple_inputs *in, nprfx_rect region,
                                             nprfx_stipple **list, size_t *count);

/* A lazily grown IVS sequence (seed NPRFX_IVS_DEFAULT_SEED) with its spatial index, owned by
 * the caller: there is no process-wide sequence. Empty when created (cheap). Its points are the
 * generator's rounded to the 24-bit grid of the encoded form (nprfx_ivs_quantize), so a shipped
 * file (nprfx_stipple_sequence_preload) and the generator give the same points and the same
 * pixels; the file only saves the generation time (about 2.5 s per million points) and makes
 * the dots independent of the compiler (ivs.h). It is built on first use and regrown by powers
 * of two (from 65536 points, at most NPRFX_STIPPLE_MAX_SAMPLES) when a longer prefix is asked
 * for, from the preloaded points while they suffice. Thread-safe: concurrent calls share one
 * object; a longer version is built under its lock and published atomically, and earlier
 * versions stay valid until the object is destroyed, so an index pointer once returned never
 * dangles while a render uses it (the versions together hold at most twice the longest one).
 * The sequence is a pure function of its seed and has the prefix property, so which version a
 * pixel reads never changes a result. */
typedef struct nprfx_stipple_sequence nprfx_stipple_sequence;

NPRFX_API nprfx_result nprfx_stipple_sequence_create(nprfx_context *ctx,
                                                     nprfx_stipple_sequence **out);
/* Use the first n points of xy (the default-seed sequence, decoded from its file) instead of
 * generating them; copied. Call before the sequence is first used. The points must be the
 * sequence's (a file's header names its seed: check it); they are rounded to the grid like
 * generated ones. */
NPRFX_API nprfx_result nprfx_stipple_sequence_preload(nprfx_context *ctx,
                                                      nprfx_stipple_sequence *seq, const float *xy,
                                                      int n);
/* One more reference to seq (returned), for another owner: a process-wide cache handing one
 * sequence to every node instance (plugins/support/data_files.h) builds it once. */
NPRFX_API nprfx_stipple_sequence *nprfx_stipple_sequence_retain(nprfx_stipple_sequence *seq);
/* Drops a reference (create gives the first); the last one frees every version, when no call
 * may be using it. NULL is a no-op. */
NPRFX_API void nprfx_stipple_sequence_destroy(nprfx_stipple_sequence *seq);
/* An index holding at least min_count points (clamped to NPRFX_STIPPLE_MAX_SAMPLES), valid
 * until seq is destroyed. */
NPRFX_API nprfx_result nprfx_stipple_sequence_index(nprfx_context *ctx, nprfx_stipple_sequence *seq,
                                                    int min_count, const nprfx_ivs_index **out);

/* nprfx_stipple_tone_curve for p, measured once per sequence: every owner of seq that asks for
 * the curve of the same mode, sizes, pens and seed gets the first measurement's floats (the
 * measurement is deterministic, so this never changes a result). seq NULL: measured afresh.
 * Thread-safe; a sequence keeps its last few curves. */
NPRFX_API nprfx_result nprfx_stipple_sequence_tone_curve(nprfx_context *ctx,
                                                         nprfx_stipple_sequence *seq,
                                                         const nprfx_stipple_params *p,
                                                         float *curve);

/* ---- the stipple node (core/stipple/stipple_node.c; its descriptor is plugins/stipple.c) ---- */

/* The node's inputs, in its descriptor's order (render_args->inputs). */
enum {
    NPRFX_STIPPLE_IN_TONE, /* required: the shading */
    NPRFX_STIPPLE_IN_UV,   /* optional: 2 channels */
    NPRFX_STIPPLE_IN_ID,   /* optional: 1 channel */
    NPRFX_STIPPLE_IN_COUNT
};

/* Makes the dot sequence a node instance keeps, on its first render: e.g. one preloaded from the
 * shipped data file (plugins/support/data_files.h), which core does not read. */
typedef nprfx_result (*nprfx_stipple_sequence_fn)(nprfx_context *ctx, nprfx_stipple_sequence **out);

/* The node's params, as its descriptor binds them (by offset; areas already multiplied by the
 * render scale squared). docs/nodes.md describes each. The algorithm's params are embedded:
 * stipple's mode, area (the param size), a0, delta_min, tile, aspect and coverage_channel (the
 * param coverage) are the params themselves; nprfx_stipple_render sets the rest of it (size, the
 * pens from `tones`, plane_scale, ink, paper, seed, the sequence, tone curve and count). */
typedef struct nprfx_stipple_node_params {
    nprfx_stipple_params stipple;
    const char *tones;       /* multitone: pen darknesses, "0.33,0.67,1" */
    double ink[4], paper[4]; /* RGBA, premultiplied: stipple.ink, stipple.paper as floats */
    int seed;                /* stipple.seed */
    int tone_correction;     /* measure and invert the darkness overlapping dots give */
    const char *export_path; /* the front end writes the node's text export there ("": none) */
    /* Bound to no param: where the instance's dot sequence comes from, made on its first use
     * (NULL: generated; a shipped file gives the same points, only sooner). The descriptor fills
     * it with the maker that reads the shipped ivs.bin: nprfx_node_render hands the descriptor a
     * zeroed struct, so this reads NULL wherever the descriptor has not set it (output() never
     * reads it). It is a param of the node as packaged, the same for every front end, so it
     * travels with the params rather than on the context: the context already carries the data
     * directory the maker reads, and a front end need not know a stipple detail to get it. */
    nprfx_stipple_sequence_fn make_sequence;
} nprfx_stipple_node_params;

/* Render args->window of args->output, inputs NPRFX_STIPPLE_IN_* (args as nprfx_node_render hands
 * them on, checked): the tones parsed (multitone; errors name stipple.tones), the pixels without a
 * uv input in units of NPRFX_STIPPLE_PLANE_PIXELS * render scale, then nprfx_stipple_draw.
 * *args->items, when not NULL, grows by the dots drawn. The instance state (args->state, NULL:
 * none, each call then generates what it needs) keeps the sequence, made by p->make_sequence on
 * first use; the tone-correction curves are kept by the sequence (shared with every instance that
 * shares it); neither ever changes a result. Free it with nprfx_stipple_state_free. Safe on
 * several tiles of one instance at once. */
NPRFX_API nprfx_result nprfx_stipple_render(const nprfx_render_args *args,
                                            const nprfx_stipple_node_params *p);
/* The stipples of the whole frame (args->frame; window is ignored) for the same arguments, as
 * nprfx_stipple_collect lists them: what the node's vector export writes. */
NPRFX_API nprfx_result nprfx_stipple_node_collect(const nprfx_render_args *args,
                                                  const nprfx_stipple_node_params *p,
                                                  nprfx_stipple **list, size_t *count);
/* Free a state left in the node's slot. */
NPRFX_API void nprfx_stipple_state_free(void *state);

#ifdef __cplusplus
}
#endif
#endif
