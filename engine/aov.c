/* nprfx graph engine — canonical AOVs and renderer profiles (nprfx/aov.h). The names and their
 * sources are in docs/design.md §2.4; a renderer whose pass needs decoding before it means the
 * canonical AOV (V-Ray's normalised VRayZDepth, its 0.5-grey-centred VRayVelocity) maps to
 * nothing here rather than to a channel that would be read wrong. */
#include <string.h>

#include "nprfx/aov.h"

static const struct {
    const char *name;
    int channels;
} aovs[NPRFX_AOV_COUNT] = {
    {"beauty", 4}, {"albedo", 3},   {"diffuse_light", 3}, {"depth", 1},
    {"normal", 3}, {"position", 3}, {"rest", 3},          {"uv", 2},
    {"id", 1},     {"coverage", 1}, {"motion_prev", 2},   {"motion_next", 2},
};

static const char *const profiles[NPRFX_PROFILE_COUNT] = {
    "generic", "blender", "arnold", "renderman", "karma", "vray", "redshift", "nuke",
};

/* Per profile, per AOV (in nprfx_aov order): the selections, likeliest first. Motion names the
 * raw channels; the read node's vector convention turns them into nprfx's (pixels, y down). */
static const char *const candidates[NPRFX_PROFILE_COUNT][NPRFX_AOV_COUNT] = {
    [NPRFX_PROFILE_GENERIC] =
        {
            "R,G,B,A|R,G,B|rgba|Combined.RGBA|C.RGBA",
            "albedo|diffuse_albedo|DiffCol|Diffuse Color|DiffuseFilter",
            "diffuse_light|DiffuseLightingRaw",
            "depth|Z|Depth.Z|depth.Z|z",
            "N|Normal|normal",
            "P|Position|position",
            "Pref|rest|__Pref",
            "uv|UV.UV|UV.U,UV.V|st",
            "id|ID|IndexOB.X|Object Index.X|object_id",
            "A|coverage|alpha|Combined.A",
            "motion_prev|Vector.X,Vector.Y|backward.u,backward.v",
            "motion_next|forward.u,forward.v|motionvector|MotionVectors",
        },
    [NPRFX_PROFILE_BLENDER] =
        {
            "Combined.RGBA|Combined.RGB",
            "DiffCol|Diffuse Color|Denoising Albedo",
            "DiffDir|Diffuse Direct", /* the direct part: DiffInd adds bounced light */
            "Depth.Z",
            "Normal",
            "Position",
            NULL, /* a shader AOV of the artist's naming */
            "UV.UV|UV.U,UV.V",
            "IndexOB.X|Object Index.X",
            "Combined.A",
            "Vector.X,Vector.Y",
            "Vector.Z,Vector.W",
        },
    [NPRFX_PROFILE_ARNOLD] =
        {
            "R,G,B,A|RGBA",
            "diffuse_albedo|albedo|denoise_albedo",
            NULL, /* diffuse_direct + diffuse_indirect, weighted by the albedo */
            "Z",
            "N",
            "P",
            "Pref",
            NULL,
            "ID",
            "A",
            NULL,
            "motionvector",
        },
    [NPRFX_PROFILE_RENDERMAN] =
        {
            "Ci,a|R,G,B,A",
            "albedo",
            NULL,
            "z",
            "Nn|N",
            "P",
            "__Pref",
            "st|u,v",
            "id",
            "a|A",
            NULL,
            NULL,
        },
    [NPRFX_PROFILE_KARMA] =
        {
            "C.RGBA|C",
            "albedo",
            NULL,
            "depth|Pz",
            "N",
            "P",
            NULL,
            NULL,
            NULL,
            "C.A",
            NULL,
            "motionvector",
        },
    [NPRFX_PROFILE_VRAY] =
        {
            "R,G,B,A", "VRayDiffuseFilter", "VRayRawLighting",
            NULL, /* VRayZDepth is grey between user distances, not a depth */
            "VRayNormals", "VRayWorldPosition", NULL, NULL, "VRayObjectID", "A", NULL,
            NULL, /* VRayVelocity is encoded (0.5 grey = still, scaled by a max) */
        },
    [NPRFX_PROFILE_REDSHIFT] =
        {
            "R,G,B,A",
            "DiffuseFilter|Diffuse Filter",
            "DiffuseLightingRaw|Diffuse Lighting Raw",
            "Z",
            "N",
            "P",
            NULL,
            NULL,
            "ObjectID",
            "A",
            NULL,
            "MotionVectors|Motion Vectors",
        },
    [NPRFX_PROFILE_NUKE] =
        {
            "R,G,B,A|rgba",
            NULL,
            NULL,
            "depth.Z", /* ScanlineRender's is 1/z: near is large */
            "N",
            "P",
            NULL,
            NULL,
            NULL,
            "rgba.alpha|rgba.A|A",
            "backward.u,backward.v",
            "forward.u,forward.v",
        },
};

const char *nprfx_aov_name(int aov)
{
    return aov >= 0 && aov < NPRFX_AOV_COUNT ? aovs[aov].name : NULL;
}

int nprfx_aov_find(const char *name)
{
    for (int i = 0; name && i < NPRFX_AOV_COUNT; i++)
        if (!strcmp(name, aovs[i].name)) return i;
    return -1;
}

int nprfx_aov_channels(int aov)
{
    return aov >= 0 && aov < NPRFX_AOV_COUNT ? aovs[aov].channels : 0;
}

const char *nprfx_aov_profile_name(int profile)
{
    return profile >= 0 && profile < NPRFX_PROFILE_COUNT ? profiles[profile] : NULL;
}

int nprfx_aov_profile_find(const char *name)
{
    for (int i = 0; name && i < NPRFX_PROFILE_COUNT; i++)
        if (!strcmp(name, profiles[i])) return i;
    return -1;
}

const char *nprfx_aov_candidates(int profile, int aov)
{
    if (profile < 0 || profile >= NPRFX_PROFILE_COUNT || aov < 0 || aov >= NPRFX_AOV_COUNT)
        return NULL;
    return candidates[profile][aov];
}

/* Whether name is `tail` or ends in "." + tail (a view layer's or a part's prefix). */
static int ends_with_part(const char *name, const char *tail)
{
    size_t n = strlen(name), t = strlen(tail);
    if (n == t) return !strcmp(name, tail);
    return n > t && name[n - t - 1] == '.' && !strcmp(name + n - t, tail);
}

static int starts_with(const char *s, const char *prefix)
{
    return !strncmp(s, prefix, strlen(prefix));
}

int nprfx_aov_detect(const char *const *names, int n, const char *const *attr_names,
                     const char *const *attr_values, int nattr)
{
    /* What renderers write into the header is the surest sign. */
    for (int i = 0; attr_names && i < nattr; i++) {
        const char *a = attr_names[i], *v = attr_values ? attr_values[i] : NULL;
        if (!a) continue;
        if (!strcmp(a, "BlenderMultiChannel")) return NPRFX_PROFILE_BLENDER;
        if (!strcmp(a, "Software") && v && starts_with(v, "Blender")) return NPRFX_PROFILE_BLENDER;
        if (starts_with(a, "arnold/")) return NPRFX_PROFILE_ARNOLD;
        if (starts_with(a, "vrayInfo/")) return NPRFX_PROFILE_VRAY;
    }
    /* Then the pass names only one renderer uses. Karma's beauty is C, which no other renderer
     * writes; it shares motionvector with Arnold, so it is looked for first. */
    int karma_c = 0, karma_crypto = 0;
    for (int i = 0; names && i < n; i++) {
        karma_c |= names[i] && (!strcmp(names[i], "C.R") || ends_with_part(names[i], "C.R"));
        karma_crypto |= names[i] && starts_with(names[i], "CryptoObject00.");
    }
    if (karma_c) return NPRFX_PROFILE_KARMA;
    for (int i = 0; names && i < n; i++) {
        const char *c = names[i];
        if (!c) continue;
        if (ends_with_part(c, "Combined.R") || ends_with_part(c, "Vector.X") ||
            ends_with_part(c, "IndexOB.X") || ends_with_part(c, "Object Index.X"))
            return NPRFX_PROFILE_BLENDER;
        if (starts_with(c, "VRay")) return NPRFX_PROFILE_VRAY;
        if (starts_with(c, "forward.") || starts_with(c, "backward.")) return NPRFX_PROFILE_NUKE;
        if (starts_with(c, "crypto_object00.") || !strcmp(c, "motionvector.R") ||
            !strcmp(c, "diffuse_albedo.R"))
            return NPRFX_PROFILE_ARNOLD;
        if (!strcmp(c, "Ci.R") || !strcmp(c, "Ci.r") || starts_with(c, "dPdtime"))
            return NPRFX_PROFILE_RENDERMAN;
        if (!strcmp(c, "DiffuseLightingRaw.R") || !strcmp(c, "MotionVectors.R"))
            return NPRFX_PROFILE_REDSHIFT;
    }
    (void)karma_crypto;
    return NPRFX_PROFILE_GENERIC;
}

/* Blender's Vector pass (docs/design.md §2.1, measured on the sample renders), image y up:
 * (X, Y) = position at frame i-1 minus position at i, (Z, W) = position at i minus position at
 * i+1, so motion_prev = (X, -Y) and motion_next = (-Z, W). Nuke's backward and forward vectors
 * point from this frame to the previous and the next one, in pixels, y up. Arnold's, Karma's and
 * Redshift's single vector points to the next frame, in pixels, y up (§2.4 lists what of this
 * their documentation leaves open). */
static const nprfx_aov_vectors vectors[] = {
    {"blender", "Vector.X,Vector.Y,Vector.Z,Vector.W", {1, -1, -1, 1}, 0},
    {"nuke", "backward.u,backward.v,forward.u,forward.v", {1, -1, 1, -1}, 0},
    {"arnold", "motionvector.R,motionvector.G,motionvector.R,motionvector.G", {-1, 1, 1, -1}, 1},
    {"karma", "motionvector.R,motionvector.G,motionvector.R,motionvector.G", {-1, 1, 1, -1}, 1},
    {"redshift",
     "MotionVectors.R,MotionVectors.G,MotionVectors.R,MotionVectors.G",
     {-1, 1, 1, -1},
     1},
};
enum { VECTORS_COUNT = (int)(sizeof vectors / sizeof vectors[0]) };

const nprfx_aov_vectors *nprfx_aov_vectors_at(int i)
{
    return i >= 0 && i < VECTORS_COUNT ? &vectors[i] : NULL;
}

const nprfx_aov_vectors *nprfx_aov_vectors_find(const char *name)
{
    for (int i = 0; name && i < VECTORS_COUNT; i++)
        if (!strcmp(name, vectors[i].name)) return &vectors[i];
    return NULL;
}

const nprfx_aov_vectors *nprfx_aov_profile_vectors(int profile)
{
    switch (profile) {
    case NPRFX_PROFILE_BLENDER:
        return nprfx_aov_vectors_find("blender");
    case NPRFX_PROFILE_NUKE:
        return nprfx_aov_vectors_find("nuke");
    case NPRFX_PROFILE_ARNOLD:
        return nprfx_aov_vectors_find("arnold");
    case NPRFX_PROFILE_KARMA:
        return nprfx_aov_vectors_find("karma");
    case NPRFX_PROFILE_REDSHIFT:
        return nprfx_aov_vectors_find("redshift");
    default:
        return NULL;
    }
}

int nprfx_aov_profile_depth(int profile)
{
    return profile == NPRFX_PROFILE_NUKE ? NPRFX_DEPTH_INVERSE : NPRFX_DEPTH_Z;
}
