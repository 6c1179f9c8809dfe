/* nprfx graph engine — a studio's own AOV names: the mapping file a read node's "aovs" names.
 * A studio that renames its passes ("Pref_static", "objectId") ships one file beside its graphs
 * instead of editing every reference; the AOVs it does not map keep a renderer profile's names. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aov_map.h"
#include "engine_util.h"
#include "json.h"

int internal_aov_map_named(const char *aovs)
{
    size_t n = aovs ? strlen(aovs) : 0;
    return (n > 5 && !strcmp(aovs + n - 5, ".json")) || internal_aov_map_inline(aovs);
}

int internal_aov_map_inline(const char *aovs)
{
    return aovs && aovs[0] == '{';
}

void internal_aov_map_free(internal_aov_map *m)
{
    if (!m) return;
    for (int a = 0; a < NPRFX_AOV_COUNT; a++)
        free(m->cand[a]);
    free(m->label);
    free(m);
}

const char *internal_aov_map_candidates(const internal_aov_map *map, int profile, int aov)
{
    if (map && aov >= 0 && aov < NPRFX_AOV_COUNT && map->mapped[aov]) return map->cand[aov];
    return nprfx_aov_candidates(profile, aov);
}

static nprfx_result bad(nprfx_context *ctx, const char *path, const char *what, const char *key)
{
    return nprfx_error(ctx, NPRFX_ERR_PARSE, "AOV mapping '%s': %s%s%s", path, key ? key : "",
                       key ? ": " : "", what);
}

static nprfx_result fill(nprfx_context *ctx, const char *path, const internal_json *root,
                         internal_aov_map *m)
{
    if (!root || root->type != INTERNAL_JSON_OBJECT)
        return bad(ctx, path, "must be a JSON object", NULL);
    for (const internal_json *e = root->child; e; e = e->next) {
        if (!strcmp(e->key, "profile")) {
            m->base = e->type == INTERNAL_JSON_STRING ? nprfx_aov_profile_find(e->string) : -1;
            if (m->base < 0) {
                char list[256] = "";
                for (int p = 0; p < NPRFX_PROFILE_COUNT; p++) {
                    if (p) strcat(list, ", ");
                    strcat(list, nprfx_aov_profile_name(p));
                }
                char what[320];
                snprintf(what, sizeof what, "must be one of %s", list);
                return bad(ctx, path, what, "profile");
            }
        } else if (!strcmp(e->key, "vectors")) {
            const char *v = e->type == INTERNAL_JSON_STRING ? e->string : "";
            m->vec = nprfx_aov_vectors_find(v);
            if (!m->vec && strcmp(v, "none")) {
                char list[256] = "none";
                for (int k = 0; nprfx_aov_vectors_at(k); k++) {
                    strcat(list, ", ");
                    strcat(list, nprfx_aov_vectors_at(k)->name);
                }
                char what[320];
                snprintf(what, sizeof what, "must be one of %s", list);
                return bad(ctx, path, what, "vectors");
            }
            m->vectors_given = 1;
        } else if (!strcmp(e->key, "depth")) {
            const char *v = e->type == INTERNAL_JSON_STRING ? e->string : "";
            if (!strcmp(v, "z"))
                m->depth = NPRFX_DEPTH_Z;
            else if (!strcmp(v, "inverse"))
                m->depth = NPRFX_DEPTH_INVERSE;
            else
                return bad(ctx, path, "must be \"z\" (camera depth) or \"inverse\" (1/z)", "depth");
        } else if (!strcmp(e->key, "aovs")) {
            if (e->type != INTERNAL_JSON_OBJECT)
                return bad(ctx, path, "must be an object of canonical AOV names", "aovs");
            for (const internal_json *a = e->child; a; a = a->next) {
                int aov = nprfx_aov_find(a->key);
                if (aov < 0) {
                    char what[512] = "is not a canonical AOV (";
                    for (int k = 0; k < NPRFX_AOV_COUNT; k++) {
                        if (k) strcat(what, ", ");
                        strcat(what, nprfx_aov_name(k));
                    }
                    strcat(what, ")");
                    return bad(ctx, path, what, a->key);
                }
                if (m->mapped[aov]) return bad(ctx, path, "is given twice", a->key);
                if (a->type == INTERNAL_JSON_STRING && a->string[0])
                    m->cand[aov] = engine_strdup(a->string);
                else if (a->type != INTERNAL_JSON_NULL)
                    return bad(ctx, path,
                               "must be channel names (\"Pref_static\", \"objectId|oid\") or "
                               "null (not written)",
                               a->key);
                m->mapped[aov] = 1;
            }
        } else {
            return bad(ctx, path, "is not one of profile, aovs, vectors, depth", e->key);
        }
    }
    return NPRFX_OK;
}

nprfx_result internal_aov_map_parse(nprfx_context *ctx, const char *text, const char *label,
                                    internal_aov_map **out)
{
    *out = NULL;
    nprfx_result r;
    internal_json *root = NULL;
    nprfx_context *fctx = NULL; /* a JSON error names the file (or the read) first */
    r = nprfx_context_create_scoped(ctx, label, &fctx);
    if (!r) r = internal_json_parse(fctx, text, &root);
    nprfx_context_destroy(fctx);
    if (r) return r;
    internal_aov_map *m = calloc(1, sizeof *m);
    if (!m) {
        internal_json_free(root);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    m->base = NPRFX_PROFILE_GENERIC;
    m->depth = -1;
    const char *slash = strrchr(label, '/');
    m->label = engine_strdup(slash ? slash + 1 : label);
    r = fill(ctx, label, root, m);
    internal_json_free(root);
    if (r) {
        internal_aov_map_free(m);
        return r;
    }
    *out = m;
    return NPRFX_OK;
}

nprfx_result internal_aov_map_load(nprfx_context *ctx, const char *path, internal_aov_map **out)
{
    *out = NULL;
    /* a mapping names a dozen AOVs: anything near a megabyte is not one */
    char *text = engine_read_text(ctx, path, "AOV mapping", 1L << 20);
    if (!text) return NPRFX_ERR_IO;
    nprfx_result r = internal_aov_map_parse(ctx, text, path, out);
    free(text);
    return r;
}
