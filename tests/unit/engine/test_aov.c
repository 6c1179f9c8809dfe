/* Canonical AOVs and renderer profiles (nprfx/aov.h): names both ways, each profile detected
 * from its header attributes or channel names, and each profile's candidates resolving on a
 * channel list as that renderer writes it to the channels its documentation names. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "nprfx/aov.h"
#include "nprfx/channels.h"

#define COUNT(a) ((int)(sizeof(a) / sizeof((a)[0])))

/* The channel names `aov` resolves to on `names` under `profile`, comma-joined ("" when none). */
static const char *resolve(int profile, int aov, const char *const *names, int n, char *buf,
                           size_t size)
{
    buf[0] = 0;
    const char *cand = nprfx_aov_candidates(profile, aov);
    int idx[16];
    int k = cand ? nprfx_channels_from_hint(names, n, cand, idx, 16) : -1;
    for (int i = 0; i < k; i++) {
        size_t len = strlen(buf);
        snprintf(buf + len, size - len, "%s%s", i ? "," : "", names[idx[i]]);
    }
    return buf;
}

#define CHECK_RESOLVES(profile, aov, names, want)                                                  \
    do {                                                                                           \
        char got_[512];                                                                            \
        resolve(profile, aov, names, COUNT(names), got_, sizeof got_);                             \
        if (strcmp(got_, want)) fprintf(stderr, "%s: got '%s', want '%s'\n", #aov, got_, want);   \
        CHECK(!strcmp(got_, want));                                                                \
    } while (0)

int main(void)
{
    /* names both ways, and channel counts */
    for (int a = 0; a < NPRFX_AOV_COUNT; a++) {
        CHECK(nprfx_aov_find(nprfx_aov_name(a)) == a);
        CHECK(nprfx_aov_channels(a) >= 1 && nprfx_aov_channels(a) <= 4);
    }
    CHECK(!strcmp(nprfx_aov_name(NPRFX_AOV_MOTION_PREV), "motion_prev"));
    CHECK(nprfx_aov_channels(NPRFX_AOV_BEAUTY) == 4 && nprfx_aov_channels(NPRFX_AOV_UV) == 2);
    CHECK(nprfx_aov_find("Depth") == -1 && nprfx_aov_name(NPRFX_AOV_COUNT) == NULL);
    for (int p = 0; p < NPRFX_PROFILE_COUNT; p++)
        CHECK(nprfx_aov_profile_find(nprfx_aov_profile_name(p)) == p);
    CHECK(nprfx_aov_profile_find("maya") == -1);
    CHECK(nprfx_aov_candidates(NPRFX_PROFILE_COUNT, 0) == NULL);

    /* Blender: a multilayer file, 4.x names and 5.x names */
    static const char *const blender[] = {
        "ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
        "ViewLayer.Combined.A", "ViewLayer.Depth.Z",    "ViewLayer.Normal.X",
        "ViewLayer.Normal.Y",   "ViewLayer.Normal.Z",   "ViewLayer.Vector.X",
        "ViewLayer.Vector.Y",   "ViewLayer.Vector.Z",   "ViewLayer.Vector.W",
        "ViewLayer.UV.U",       "ViewLayer.UV.V",       "ViewLayer.UV.A",
        "ViewLayer.IndexOB.X",  "ViewLayer.DiffCol.R",  "ViewLayer.DiffCol.G",
        "ViewLayer.DiffCol.B"};
    static const char *const blender5[] = {"ViewLayer.Combined.R", "ViewLayer.Object Index.X",
                                           "ViewLayer.Diffuse Color.R",
                                           "ViewLayer.Diffuse Color.G",
                                           "ViewLayer.Diffuse Color.B"};
    CHECK(nprfx_aov_detect(blender, COUNT(blender), NULL, NULL, 0) == NPRFX_PROFILE_BLENDER);
    CHECK_RESOLVES(NPRFX_PROFILE_BLENDER, NPRFX_AOV_DEPTH, blender, "ViewLayer.Depth.Z");
    CHECK_RESOLVES(NPRFX_PROFILE_BLENDER, NPRFX_AOV_BEAUTY, blender,
                   "ViewLayer.Combined.R,ViewLayer.Combined.G,ViewLayer.Combined.B,"
                   "ViewLayer.Combined.A");
    CHECK_RESOLVES(NPRFX_PROFILE_BLENDER, NPRFX_AOV_UV, blender, "ViewLayer.UV.U,ViewLayer.UV.V");
    CHECK_RESOLVES(NPRFX_PROFILE_BLENDER, NPRFX_AOV_ID, blender, "ViewLayer.IndexOB.X");
    CHECK_RESOLVES(NPRFX_PROFILE_BLENDER, NPRFX_AOV_MOTION_NEXT, blender,
                   "ViewLayer.Vector.Z,ViewLayer.Vector.W");
    CHECK_RESOLVES(NPRFX_PROFILE_BLENDER, NPRFX_AOV_REST, blender, "");
    CHECK(nprfx_aov_detect(blender5, COUNT(blender5), NULL, NULL, 0) == NPRFX_PROFILE_BLENDER);
    CHECK_RESOLVES(NPRFX_PROFILE_BLENDER, NPRFX_AOV_ID, blender5, "ViewLayer.Object Index.X");
    CHECK_RESOLVES(NPRFX_PROFILE_BLENDER, NPRFX_AOV_ALBEDO, blender5,
                   "ViewLayer.Diffuse Color.R,ViewLayer.Diffuse Color.G,"
                   "ViewLayer.Diffuse Color.B");

    /* Arnold: by its header, then by its names alone */
    static const char *const arnold[] = {"R", "G", "B", "A", "Z", "N.R", "N.G", "N.B",
                                         "Pref.R", "Pref.G", "Pref.B", "ID", "motionvector.R",
                                         "motionvector.G", "crypto_object00.R"};
    static const char *const an[] = {"arnold/version"}, *const av[] = {"Arnold 7.3.1.0"};
    CHECK(nprfx_aov_detect(arnold, 4, an, av, 1) == NPRFX_PROFILE_ARNOLD);
    CHECK(nprfx_aov_detect(arnold, COUNT(arnold), NULL, NULL, 0) == NPRFX_PROFILE_ARNOLD);
    CHECK_RESOLVES(NPRFX_PROFILE_ARNOLD, NPRFX_AOV_DEPTH, arnold, "Z");
    CHECK_RESOLVES(NPRFX_PROFILE_ARNOLD, NPRFX_AOV_REST, arnold, "Pref.R,Pref.G,Pref.B");
    CHECK_RESOLVES(NPRFX_PROFILE_ARNOLD, NPRFX_AOV_NORMAL, arnold, "N.R,N.G,N.B");
    CHECK_RESOLVES(NPRFX_PROFILE_ARNOLD, NPRFX_AOV_ID, arnold, "ID");
    CHECK_RESOLVES(NPRFX_PROFILE_ARNOLD, NPRFX_AOV_COVERAGE, arnold, "A");

    /* V-Ray: its header; its Z-depth pass is no depth */
    static const char *const vray[] = {"R", "G", "B", "A", "VRayZDepth.R", "VRayNormals.R",
                                       "VRayNormals.G", "VRayNormals.B"};
    static const char *const vn[] = {"Software", "vrayInfo/vrayversion"},
                             *const vv[] = {"3ds Max", "6.10"};
    CHECK(nprfx_aov_detect(vray, 4, vn, vv, 2) == NPRFX_PROFILE_VRAY);
    CHECK(nprfx_aov_detect(vray, COUNT(vray), NULL, NULL, 0) == NPRFX_PROFILE_VRAY);
    CHECK_RESOLVES(NPRFX_PROFILE_VRAY, NPRFX_AOV_DEPTH, vray, "");
    CHECK_RESOLVES(NPRFX_PROFILE_VRAY, NPRFX_AOV_NORMAL, vray,
                   "VRayNormals.R,VRayNormals.G,VRayNormals.B");

    /* Karma: C with CryptoObject layers; Nuke: forward and backward; RenderMan: Ci */
    static const char *const karma[] = {"C.R", "C.G", "C.B", "C.A", "CryptoObject00.R", "N.X"};
    static const char *const nuke[] = {"rgba.red", "rgba.green", "rgba.blue", "rgba.alpha",
                                       "depth.Z", "forward.u", "forward.v", "backward.u",
                                       "backward.v"};
    static const char *const rman[] = {"Ci.R", "Ci.G", "Ci.B", "a", "z", "id"};
    CHECK(nprfx_aov_detect(karma, COUNT(karma), NULL, NULL, 0) == NPRFX_PROFILE_KARMA);
    CHECK(nprfx_aov_detect(karma, 4, NULL, NULL, 0) == NPRFX_PROFILE_KARMA);
    CHECK(nprfx_aov_detect(nuke, COUNT(nuke), NULL, NULL, 0) == NPRFX_PROFILE_NUKE);
    CHECK_RESOLVES(NPRFX_PROFILE_NUKE, NPRFX_AOV_MOTION_PREV, nuke, "backward.u,backward.v");
    CHECK_RESOLVES(NPRFX_PROFILE_NUKE, NPRFX_AOV_COVERAGE, nuke, "rgba.alpha");
    CHECK(nprfx_aov_detect(rman, COUNT(rman), NULL, NULL, 0) == NPRFX_PROFILE_RENDERMAN);
    CHECK_RESOLVES(NPRFX_PROFILE_RENDERMAN, NPRFX_AOV_DEPTH, rman, "z");
    CHECK_RESOLVES(NPRFX_PROFILE_RENDERMAN, NPRFX_AOV_BEAUTY, rman, "Ci.R,Ci.G,Ci.B,a");

    /* nothing telling: generic, whose names cover the common ones */
    static const char *const plain[] = {"R", "G", "B", "A", "Z"};
    CHECK(nprfx_aov_detect(plain, COUNT(plain), NULL, NULL, 0) == NPRFX_PROFILE_GENERIC);
    CHECK_RESOLVES(NPRFX_PROFILE_GENERIC, NPRFX_AOV_DEPTH, plain, "Z");
    CHECK_RESOLVES(NPRFX_PROFILE_GENERIC, NPRFX_AOV_BEAUTY, plain, "R,G,B,A");
    CHECK_RESOLVES(NPRFX_PROFILE_GENERIC, NPRFX_AOV_DEPTH, blender, "ViewLayer.Depth.Z");
    return check_finish();
}
