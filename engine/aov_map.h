/* nprfx graph engine — a studio's own AOV names (aov_map.c): a small JSON file a read node's
 * "aovs" (or `nprfx run --aovs`) names instead of a renderer profile. Never installed.
 *
 *   {"profile": "arnold",                         the names of what the file does not map
 *    "aovs": {"rest": "Pref_static", "id": "objectId|oid", "albedo": null},
 *    "vectors": "arnold",                         the motion convention (nprfx/aov.h)
 *    "depth": "z"}                                or "inverse" (1/z)
 *
 * Every key is optional; a null AOV is one the studio does not write (its fallback applies). */
#ifndef NPRFX_ENGINE_AOV_MAP_H
#define NPRFX_ENGINE_AOV_MAP_H

#include "nprfx/aov.h"
#include "nprfx/context.h"

typedef struct internal_aov_map {
    char *label;                  /* the file's name, for messages */
    int base;                     /* the profile whose names the AOVs not mapped keep */
    int mapped[NPRFX_AOV_COUNT];  /* 1: cand[aov] replaces the base's */
    char *cand[NPRFX_AOV_COUNT];  /* channel selections, '|' between them; NULL: none written */
    const nprfx_aov_vectors *vec; /* the motion convention; NULL: the base's */
    int vectors_given;            /* "vectors" was given ("none": vec NULL) */
    int depth;                    /* NPRFX_DEPTH_*, or -1: the base's */
} internal_aov_map;

/* Whether an "aovs" value is a mapping rather than a profile: a file's name (it ends in ".json")
 * or the mapping itself, inline (it begins with '{': what a front end sets, e.g. a plug-in's
 * AOV layers). */
int internal_aov_map_named(const char *aovs);
int internal_aov_map_inline(const char *aovs);
/* A mapping from its text; label names it in errors. */
nprfx_result internal_aov_map_parse(nprfx_context *ctx, const char *text, const char *label,
                                    internal_aov_map **out);

/* Read the mapping file at path; errors name the file and the key. */
nprfx_result internal_aov_map_load(nprfx_context *ctx, const char *path, internal_aov_map **out);
void internal_aov_map_free(internal_aov_map *m);

/* Where a plate read with `map` (NULL: none) and `profile` holds `aov`. */
const char *internal_aov_map_candidates(const internal_aov_map *map, int profile, int aov);

#endif
