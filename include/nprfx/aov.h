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

/* The profile a plate comes from: its header attributes first (nattr name/value pairs as text,
 * e.g. "arnold/version"), then its channel names (a Blender view layer's "Combined" pass, V-Ray's
 * "VRay*" elements, ...); NPRFX_PROFILE_GENERIC when nothing tells. */
NPRFX_API int nprfx_aov_detect(const char *const *names, int n, const char *const *attr_names,
                               const char *const *attr_values, int nattr);

#ifdef __cplusplus
}
#endif
#endif
