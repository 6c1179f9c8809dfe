/* nprfx — canonical AOVs and renderer profiles.
 *
 * Graphs and node descriptors name what a plate channel means (depth, normal, id, ...); a
 * profile says under which names each renderer writes it. A plate's profile is detected from
 * its header attributes and channel names, or named by the user. docs/design.md §2.4 gives the
 * table with the source of every name and convention. */
#ifndef NPRFX_AOV_H
#define NPRFX_AOV_H

#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum nprfx_aov {
    NPRFX_AOV_BEAUTY = 0,    /* RGBA, scene-linear */
    NPRFX_AOV_ALBEDO,        /* diffuse colour (3) */
    NPRFX_AOV_DIFFUSE_LIGHT, /* diffuse lighting without the albedo (3) */
    NPRFX_AOV_DEPTH,         /* camera depth (1) */
    NPRFX_AOV_NORMAL,        /* surface normal (3) */
    NPRFX_AOV_POSITION,      /* position (3) */
    NPRFX_AOV_REST,          /* rest (reference) position (3) */
    NPRFX_AOV_UV,            /* texture coordinates (2) */
    NPRFX_AOV_ID,            /* object id (1) */
    NPRFX_AOV_COVERAGE,      /* alpha (1) */
    NPRFX_AOV_MOTION_PREV,   /* screen motion to the previous frame, pixels, y down (2) */
    NPRFX_AOV_MOTION_NEXT,   /* screen motion to the next frame (2) */
    NPRFX_AOV_COUNT
} nprfx_aov;

typedef enum nprfx_aov_profile {
    NPRFX_PROFILE_GENERIC = 0, /* every renderer's common names */
    NPRFX_PROFILE_BLENDER,     /* Cycles and EEVEE, 2.8 to 5.x pass names */
    NPRFX_PROFILE_ARNOLD,
    NPRFX_PROFILE_RENDERMAN,
    NPRFX_PROFILE_KARMA,
    NPRFX_PROFILE_VRAY,
    NPRFX_PROFILE_REDSHIFT,
    NPRFX_PROFILE_NUKE,
    NPRFX_PROFILE_COUNT
} nprfx_aov_profile;

/* "depth", "motion_prev", ...; NULL outside [0, NPRFX_AOV_COUNT). */
NPRFX_API const char *nprfx_aov_name(int aov);
/* The AOV called `name`, or -1. */
NPRFX_API int nprfx_aov_find(const char *name);
/* The channels the AOV has (beauty 4, depth 1, uv 2, ...). */
NPRFX_API int nprfx_aov_channels(int aov);

/* "blender", "arnold", ...; NULL outside [0, NPRFX_PROFILE_COUNT). */
NPRFX_API const char *nprfx_aov_profile_name(int profile);
/* The profile called `name`, or -1. */
NPRFX_API int nprfx_aov_profile_find(const char *name);

/* Where the profile's renderer writes the AOV: channel selections in the syntax of
 * nprfx/channels.h, '|' between alternatives, the likeliest first ("Depth.Z"); NULL when the
 * renderer writes none under a fixed name (a rest position is a custom pass in Blender). */
NPRFX_API const char *nprfx_aov_candidates(int profile, int aov);

/* How a renderer writes screen motion, and how nprfx reads it into motion_prev and motion_next
 * (pixels, image y down; motion_prev points from a pixel to where its surface point was one
 * frame earlier, motion_next to where it will be one frame later). */
typedef struct nprfx_aov_vectors {
    const char *name; /* the read node's "vectors" value: "blender", "nuke", "arnold", ... */
    /* Four channel selections, ',' between them, for prev.x, prev.y, next.x, next.y (the raw
     * channels, as nprfx/channels.h selects them). */
    const char *channels;
    double scale[4]; /* nprfx's value = raw value * scale, per slot */
    /* 1: the renderer writes one vector, towards the next frame; the prev slots read the same
     * channels negated (motion_prev = -motion_next: exact for motion steady over the two
     * frames, and announced as a fallback). */
    int prev_from_next;
} nprfx_aov_vectors;

/* The conventions in turn (NULL past the last), and by name (NULL when none). */
NPRFX_API const nprfx_aov_vectors *nprfx_aov_vectors_at(int i);
NPRFX_API const nprfx_aov_vectors *nprfx_aov_vectors_find(const char *name);
/* The convention a profile's renderer writes its vectors in; NULL when it has none under a
 * fixed name (then the temporal nodes fall back on optical flow). */
NPRFX_API const nprfx_aov_vectors *nprfx_aov_profile_vectors(int profile);

/* How a profile's renderer stores the depth AOV. */
typedef enum nprfx_aov_depth_kind {
    NPRFX_DEPTH_Z = 0,      /* camera depth itself; background very large or infinite */
    NPRFX_DEPTH_INVERSE = 1 /* 1/depth (Nuke's ScanlineRender): background 0 */
} nprfx_aov_depth_kind;
NPRFX_API int nprfx_aov_profile_depth(int profile);

/* The profile a plate comes from: its header attributes first (nattr name/value pairs as text,
 * e.g. "arnold/version"), then its channel names (a Blender view layer's "Combined" pass, V-Ray's
 * "VRay*" elements, ...); NPRFX_PROFILE_GENERIC when nothing tells. */
NPRFX_API int nprfx_aov_detect(const char *const *names, int n, const char *const *attr_names,
                               const char *const *attr_values, int nattr);

#ifdef __cplusplus
}
#endif
#endif
