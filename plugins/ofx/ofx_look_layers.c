/* nprfx OpenFX adapter — a look's layer menus in multi-plane hosts: one choice param per AOV the
 * look reads from Source ("Depth layer"), listing Source's layers once Find AOV Layers has seen
 * them and showing the one that feeds the AOV. A menu is a view of the AOV Layers text, which
 * holds the user's choices (a project keeps the text; a menu's options exist only after Find). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/aov.h"
#include "ofx_look.h"
#include "ofx_suites.h"

/* Channel name c's layer: all before its last '.' ("" for R, G, B, A). */
static size_t layer_len(const char *c)
{
    const char *dot = strrchr(c, '.');
    return dot ? (size_t)(dot - c) : 0;
}

OfxStatus ofx_look_layer_options(OfxParamHandle h, int aov, const char *const *names, int n,
                                 const char *resolved)
{
    OfxPropertySetHandle p;
    if (!h || ofx_g.param->paramGetPropertySet(h, &p) != kOfxStatOK) return kOfxStatErrBadHandle;
    (void)ofx_g.prop->propReset(p, kOfxParamPropChoiceOption);
    int want = nprfx_aov_channels(aov), count = 0, pick = 0;
    ofx_g.prop->propSetString(p, kOfxParamPropChoiceOption, count++, "auto");
    /* one channel: each channel; more: each layer with as many, its first ones */
    for (int i = 0; i < n; i++) {
        char option[1024] = "";
        size_t len = layer_len(names[i]);
        int first = 1, have = 0;
        for (int j = 0; j < i && first; j++)
            first = layer_len(names[j]) != len || strncmp(names[j], names[i], len);
        if (want > 1 && !first) continue; /* the channels without a layer are one too: R,G,B,A */
        for (int j = i; j < n && have < want; j++) {
            if (want > 1 && (layer_len(names[j]) != len || strncmp(names[j], names[i], len)))
                continue;
            size_t at = strlen(option);
            snprintf(option + at, sizeof option - at, "%s%s", have ? "," : "", names[j]);
            have++;
        }
        if (have < want) continue;
        if (resolved && !strcmp(option, resolved)) pick = count;
        ofx_g.prop->propSetString(p, kOfxParamPropChoiceOption, count++, option);
    }
    return ofx_g.param->paramSetValue(h, pick);
}

char *ofx_look_layer_edit(const char *text, int aov, const char *channels)
{
    const char *name = nprfx_aov_name(aov);
    size_t cap = (text ? strlen(text) : 0) + (channels ? strlen(channels) : 0) + 64;
    char *out = calloc(1, cap);
    if (!out) return NULL;
    size_t len = 0;
    for (const char *s = text; s && *s;) {
        const char *e = strchr(s, '\n');
        size_t n = e ? (size_t)(e - s) + 1 : strlen(s);
        const char *a = s + strspn(s, " \t");
        size_t k = strlen(name);
        /* the AOV's own line goes: "depth = ..." (not "depth_x"), and Find's "# depth: ..." */
        if (a[0] == '#') a += 1 + strspn(a + 1, " \t");
        int own = !strncmp(a, name, k) && a[k] && strchr(" \t=:", a[k]);
        if (!own) {
            memcpy(out + len, s, n);
            len += n;
            if (out[len - 1] != '\n') out[len++] = '\n';
        }
        s += n;
    }
    if (channels) len += (size_t)snprintf(out + len, cap - len, "%s = %s\n", name, channels);
    if (len && out[len - 1] == '\n') out[--len] = 0;
    return out;
}
