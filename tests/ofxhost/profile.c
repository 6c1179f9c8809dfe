/* nprfx OpenFX test host — host profiles (`nprfx-ofxtest run --profile NAME`): the ways real hosts
 * differ that have broken, or could break, the adapter, so that CI meets them before users do.
 *
 *   strict  the default: both contexts (Filter where only the main input is connected), float
 *           RGBA and Alpha images, temporal clip access, render scales, message suites 1 and 2
 *           formatting their arguments; the strict checks of ofx_host_internal.h.
 *   strict8 strict with 8-bit images only (no profile of a real host: an integer host with
 *           temporal access, to show what a look needs beyond it).
 *   natron  Natron 2.5: the General context always (named clips even where Filter would fit),
 *           float images, render scale 1, temporal clip access, message suites 1 and 2 whose
 *           formatting loses the variadic arguments (Natron forwards its va_list into a second
 *           variadic formatter: "%s" comes out empty, "%%" as "%"), multi-plane (The Foundry's
 *           plane suite with Natron's layers: a Read's clip carries every layer of a
 *           multilayer EXR; look.c serves them).
 *   mlt     MLT 7's OpenFX module (Kdenlive, Shotcut): the Filter context only (Source clip
 *           only), no temporal clip access, 8-bit RGBA images whatever getClipPreferences asked,
 *           message suite 1 only, formatting correctly, and an instance of the effect made for
 *           every render and destroyed after it, as melt does: what an instance keeps does not
 *           survive it.
 *   mlt16   mlt with 16-bit images.
 *
 * The strict checks (frames needed equal to frames fetched, non-empty error messages, ...) hold
 * in every profile. */
#include <string.h>

#include "ofx_host_internal.h"

static const hprofile profiles[] = {
    /* name, like, general, filter, temporal, multires, alpha, depth, message_v2, lossy, planes,
     * instance_per_frame */
    {"strict", "the strict test host", 1, 1, 1, 1, 1, HD_FLOAT, 1, 0, 0, 0},
    {"natron", "Natron 2.5", 1, 0, 1, 0, 1, HD_FLOAT, 1, 1, 1, 0},
    {"strict8", "the strict test host at 8 bits", 1, 1, 1, 1, 1, HD_BYTE, 1, 0, 0, 0},
    {"mlt", "MLT 7 (8-bit)", 0, 1, 0, 0, 0, HD_BYTE, 0, 0, 0, 1},
    {"mlt16", "MLT 7 (16-bit)", 0, 1, 0, 0, 0, HD_SHORT, 0, 0, 0, 1},
};

const hprofile *internal_profile_find(const char *name)
{
    for (size_t i = 0; name && i < sizeof profiles / sizeof profiles[0]; i++)
        if (!strcmp(profiles[i].name, name)) return &profiles[i];
    return NULL;
}

const char *internal_profile_names(void)
{
    return "strict, strict8, natron, mlt, mlt16";
}

void internal_profile_host_props(const hprofile *pf, OfxPropertySetHandle p)
{
    int n = 0;
    if (pf->general)
        internal_set_string(p, kOfxImageEffectPropSupportedContexts, n++,
                            kOfxImageEffectContextGeneral);
    if (pf->filter)
        internal_set_string(p, kOfxImageEffectPropSupportedContexts, n++,
                            kOfxImageEffectContextFilter);
    internal_set_int(p, kOfxImageEffectPropTemporalClipAccess, 0, pf->temporal);
    internal_set_int(p, kOfxImageEffectPropSupportsMultiResolution, 0, pf->multires);
    internal_set_int(p, kFnOfxImageEffectPropMultiPlanar, 0, pf->planes);
    n = 0;
    internal_set_string(p, kOfxImageEffectPropSupportedComponents, n++, kOfxImageComponentRGBA);
    if (pf->alpha)
        internal_set_string(p, kOfxImageEffectPropSupportedComponents, n++,
                            kOfxImageComponentAlpha);
    /* MLT lists both integer depths whichever one it hands out. */
    if (pf->depth == HD_FLOAT) {
        internal_set_string(p, kOfxImageEffectPropSupportedPixelDepths, 0, kOfxBitDepthFloat);
    } else {
        internal_set_string(p, kOfxImageEffectPropSupportedPixelDepths, 0, kOfxBitDepthByte);
        internal_set_string(p, kOfxImageEffectPropSupportedPixelDepths, 1, kOfxBitDepthShort);
    }
}
