/* nprfx synth — write analytic test plates: one multi-channel EXR per frame with exact AOVs.
 *
 * The scenes and channels are the core's (nprfx/synth.h); this command only parses options,
 * renders each frame through a pthread pool and writes it through the OIIO adapter. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "nprfx/aov.h"
#include "nprfx/channels.h"
#include "nprfx/cryptomatte.h"
#include "nprfx/io.h"
#include "io/io_write.h"
#include "nprfx/seq.h"
#include "util/cli_util.h"

/* Exit status: 0 written, 1 render or write error, 2 usage error. */
enum { SYNTH_OK = 0, SYNTH_FAILED = 1, SYNTH_USAGE = 2 };

static void list_scenes(FILE *f)
{
    for (int i = 0; i < nprfx_synth_scene_count(); i++) {
        const nprfx_synth_scene_info *s = nprfx_synth_scene_at(i);
        fprintf(f, "  %-10s %s\n", s->name, s->help);
    }
}

/* --layout blender: the channels as Blender's multilayer EXR names them (layer ViewLayer), so a
 * graph written for Blender plates runs on a synthetic plate with only the read path changed.
 * Each output channel is a synth channel times a sign; Vector packs the motion in Blender's
 * convention (docs/design.md §2.1: motion_prev = (X, -Y), motion_next = (-Z, W)). */
typedef struct layout_channel {
    const char *name, *src;
    float sign;
} layout_channel;
static const layout_channel blender_layout[] = {
    {"ViewLayer.Combined.R", "R", 1},
    {"ViewLayer.Combined.G", "G", 1},
    {"ViewLayer.Combined.B", "B", 1},
    {"ViewLayer.Combined.A", "A", 1},
    {"ViewLayer.Depth.Z", "Z", 1},
    {"ViewLayer.DiffCol.R", "albedo.R", 1},
    {"ViewLayer.DiffCol.G", "albedo.G", 1},
    {"ViewLayer.DiffCol.B", "albedo.B", 1},
    {"ViewLayer.DiffDir.R", "diffuse", 1},
    {"ViewLayer.DiffDir.G", "diffuse", 1},
    {"ViewLayer.DiffDir.B", "diffuse", 1},
    {"ViewLayer.IndexOB.X", "id", 1},
    {"ViewLayer.Normal.X", "N.X", 1},
    {"ViewLayer.Normal.Y", "N.Y", 1},
    {"ViewLayer.Normal.Z", "N.Z", 1},
    {"ViewLayer.Position.X", "P.X", 1},
    {"ViewLayer.Position.Y", "P.Y", 1},
    {"ViewLayer.Position.Z", "P.Z", 1},
    {"ViewLayer.Pref.R", "Pref.X", 1},
    {"ViewLayer.Pref.G", "Pref.Y", 1},
    {"ViewLayer.Pref.B", "Pref.Z", 1},
    {"ViewLayer.Pref.A", "coverage", 1},
    {"ViewLayer.UV.U", "UV.U", 1},
    {"ViewLayer.UV.V", "UV.V", 1},
    {"ViewLayer.Vector.X", "motion_prev.X", 1},
    {"ViewLayer.Vector.Y", "motion_prev.Y", -1},
    {"ViewLayer.Vector.Z", "motion_next.X", -1},
    {"ViewLayer.Vector.W", "motion_next.Y", 1},
};
enum { BLENDER_CHANNELS = (int)(sizeof blender_layout / sizeof blender_layout[0]) };

static int synth_index(const char *name)
{
    const char *const *n = nprfx_synth_channel_names();
    for (int i = 0; n[i]; i++)
        if (!strcmp(n[i], name)) return i;
    return -1;
}

/* ---- renderer layouts: --layout arnold|renderman|karma|vray|redshift|nuke --------------------
 * The channel names come from the profile table (nprfx/aov.h, engine/aov.c): for each canonical
 * AOV the first alternative of the profile's candidates, else of the generic profile's (what a
 * user names a custom pass), expanded to the AOV's channel count (a layer gets components R G B
 * A, or R G for two); motion in the raw channels of the profile's vector convention; depth as
 * 1/z for an inverse-depth profile; object ids as a Cryptomatte layer for the renderers that
 * write ids that way. What the table does not hold (the Cryptomatte layer, the header
 * attribute a renderer signs its files with) is in renderer_extras below. */
enum { OUT_COPY, OUT_INVERSE, OUT_CRYPTO_ID, OUT_CRYPTO_COV, OUT_ZERO };
enum { LAYOUT_MAX = 64, LAYOUT_ATTRS = 8 };
typedef struct out_channel {
    char name[96];
    int kind, src; /* OUT_*, the synth channel it is made from (-1: none) */
    float mul;     /* OUT_COPY: the synth value times mul */
} out_channel;
typedef struct synth_layout {
    int profile; /* NPRFX_PROFILE_BLENDER: blender_layout; else a renderer's */
    int n;
    out_channel ch[LAYOUT_MAX];
    const char *names[LAYOUT_MAX + 1];
    unsigned char types[LAYOUT_MAX]; /* with --half: half, but Cryptomatte stays float */
    const char *crypto;              /* the Cryptomatte layer (NULL: none) */
    char key[8], attr_name[4][64];
    nprfx_attribute attrs[LAYOUT_ATTRS];
    int nattrs;
    char *manifest; /* the frame's */
} synth_layout;

static const struct {
    int profile;
    const char *crypto;          /* the object-id Cryptomatte layer the renderer writes */
    const char *attr, *attr_val; /* a header attribute naming the renderer (NULL: none) */
} renderer_extras[] = {
    {NPRFX_PROFILE_ARNOLD, "crypto_object", "arnold/version", "7.3.1.0"},
    {NPRFX_PROFILE_RENDERMAN, NULL, NULL, NULL},
    {NPRFX_PROFILE_KARMA, "CryptoObject", NULL, NULL},
    {NPRFX_PROFILE_VRAY, "CryptoObject", "vrayInfo/camera", "synth"},
    {NPRFX_PROFILE_REDSHIFT, "CryptoObject", NULL, NULL},
    {NPRFX_PROFILE_NUKE, NULL, NULL, NULL},
};
enum { RENDERER_EXTRAS = (int)(sizeof renderer_extras / sizeof renderer_extras[0]) };

/* The synth channels each canonical AOV is made from (nprfx_aov order). */
static const char *const aov_sources[NPRFX_AOV_COUNT][4] = {
    {"R", "G", "B", "A"},
    {"albedo.R", "albedo.G", "albedo.B"},
    {"diffuse", "diffuse", "diffuse"},
    {"Z"},
    {"N.X", "N.Y", "N.Z"},
    {"P.X", "P.Y", "P.Z"},
    {"Pref.X", "Pref.Y", "Pref.Z"},
    {"UV.U", "UV.V"},
    {"id"},
    {"coverage"},
    {"motion_prev.X", "motion_prev.Y"},
    {"motion_next.X", "motion_next.Y"},
};

/* The renderer_extras row of a profile with a layout, or -1. */
static int renderer_row(int profile)
{
    for (int i = 0; i < RENDERER_EXTRAS; i++)
        if (renderer_extras[i].profile == profile) return i;
    return -1;
}

/* The object name synth id `id` stands for in Cryptomatte layers: 1 'object "1"', 2 'Objekt ü/2',
 * 3 'object\3' (a quote, UTF-8, a slash and a backslash for the manifest's escaping), n
 * 'object_n' from 4 on. */
static void object_name(int id, char *buf, size_t n)
{
    if (id == 1)
        snprintf(buf, n, "object \"1\"");
    else if (id == 2)
        snprintf(buf, n, "Objekt \xc3\xbc/2");
    else if (id == 3)
        snprintf(buf, n, "object\\3");
    else
        snprintf(buf, n, "object_%d", id);
}

static float object_float(int id)
{
    char name[64];
    object_name(id, name, sizeof name);
    return nprfx_cryptomatte_float(nprfx_cryptomatte_hash(name, strlen(name)));
}

/* The first '|' alternative of sel expanded into `count` channel names: as many items as
 * channels name them; one item names a layer ("N" -> N.R N.G N.B) or a layer with letters
 * ("C.RGBA"); with fewer items than channels the first is the layer ("Ci,a" -> Ci.R Ci.G Ci.B a).
 * Returns 0, or -1 when the selection cannot be expanded. */
static int expand_selection(const char *sel, int count, char out[][96])
{
    static const char *const comps[5][4] = {
        {0}, {0}, {"R", "G"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
    char first[256], *items[8];
    int k = 0;
    snprintf(first, sizeof first, "%s", sel);
    char *bar = strchr(first, '|');
    if (bar) *bar = '\0';
    for (char *save = NULL, *it = strtok_r(first, ",", &save); it && k < 8;
         it = strtok_r(NULL, ",", &save))
        items[k++] = it;
    if (k == 0 || k > count || count > 4) return -1;
    if (k == count) {
        for (int c = 0; c < count; c++)
            snprintf(out[c], 96, "%s", items[c]);
        return 0;
    }
    int lc = count - (k - 1); /* the first item's components */
    const char *dot = strrchr(items[0], '.');
    int letters = dot && (int)strlen(dot + 1) == lc;
    for (int c = 0; letters && c < lc; c++)
        letters = strchr("RGBAXYZWUV", dot[1 + c]) != NULL;
    for (int c = 0; c < lc; c++) {
        if (letters)
            snprintf(out[c], 96, "%.*s.%c", (int)(dot - items[0]), items[0], dot[1 + c]);
        else
            snprintf(out[c], 96, "%s.%s", items[0], comps[lc][c]);
    }
    for (int c = 1; c < k; c++)
        snprintf(out[lc + c - 1], 96, "%s", items[c]);
    return 0;
}

static int layout_add(synth_layout *L, const char *name, int kind, const char *src, float mul)
{
    if (L->n >= LAYOUT_MAX) return -1;
    out_channel *o = &L->ch[L->n];
    snprintf(o->name, sizeof o->name, "%s", name);
    o->kind = kind;
    o->src = src ? synth_index(src) : -1;
    o->mul = mul;
    if (src && o->src < 0) return -1;
    L->types[L->n] = NPRFX_PIXEL_HALF;
    L->names[L->n] = o->name;
    L->n++;
    L->names[L->n] = NULL;
    return 0;
}

static int layout_find(const synth_layout *L, const char *name)
{
    for (int c = 0; c < L->n; c++)
        if (!strcmp(L->ch[c].name, name)) return c;
    return -1;
}

/* Does the engine's selection of `hint` find exactly channels want[0..count), in order? */
static int selects(const synth_layout *L, const char *hint, const int *want, int count)
{
    int idx[16];
    if (nprfx_channels_from_hint(L->names, L->n, hint, idx, 16) != count) return 0;
    for (int c = 0; c < count; c++)
        if (idx[c] != want[c]) return 0;
    return 1;
}

/* Build a renderer's layout; 0, or -1 with a message in err. The engine's channel selection is
 * run on the result: every AOV written must resolve, through the profile's candidates (the
 * generic ones where the profile has none) or its vector convention, to the channels made for
 * it, in order. */
static int layout_build(int profile, synth_layout *L, char *err, size_t errn)
{
    const char *pname = nprfx_aov_profile_name(profile);
    int row = renderer_row(profile);
    memset(L, 0, sizeof *L);
    L->profile = profile;
    L->crypto = row >= 0 ? renderer_extras[row].crypto : NULL;
    const nprfx_aov_vectors *vec = nprfx_aov_profile_vectors(profile);
    for (int a = 0; a < NPRFX_AOV_COUNT; a++) {
        int count = nprfx_aov_channels(a), first = L->n;
        const char *cand = nprfx_aov_candidates(profile, a);
        int motion = a == NPRFX_AOV_MOTION_PREV || a == NPRFX_AOV_MOTION_NEXT;
        if (motion && vec) continue; /* below, in the convention's raw channels */
        if (a == NPRFX_AOV_DIFFUSE_LIGHT && !cand) continue; /* no such pass in the renderer */
        if (a == NPRFX_AOV_ID && L->crypto) {
            char nm[96];
            for (int r = 0; r < 2; r++)
                for (int c = 0; c < 4; c++) {
                    snprintf(nm, sizeof nm, "%s%02d.%c", L->crypto, r, "RGBA"[c]);
                    int kind = r == 0 && c == 0   ? OUT_CRYPTO_ID
                               : r == 0 && c == 1 ? OUT_CRYPTO_COV
                                                  : OUT_ZERO;
                    if (layout_add(L, nm, kind, kind == OUT_CRYPTO_COV ? "coverage" : "id", 1))
                        goto overflow;
                    L->types[L->n - 1] = NPRFX_PIXEL_FLOAT; /* ids are never half */
                }
            continue;
        }
        if (a == NPRFX_AOV_COVERAGE && cand && L->n >= 4) {
            /* the beauty's alpha (written first) when the profile's candidates find it */
            int alpha = 3;
            if (selects(L, cand, &alpha, 1)) continue;
        }
        const char *hint = cand ? cand : nprfx_aov_candidates(NPRFX_PROFILE_GENERIC, a);
        char names[4][96];
        if (expand_selection(hint, count, names)) {
            snprintf(err, errn, "layout %s: cannot name %s's channels from '%s'", pname,
                     nprfx_aov_name(a), hint);
            return -1;
        }
        int inverse =
            a == NPRFX_AOV_DEPTH && nprfx_aov_profile_depth(profile) == NPRFX_DEPTH_INVERSE;
        for (int c = 0; c < count; c++)
            if (layout_add(L, names[c], inverse ? OUT_INVERSE : OUT_COPY, aov_sources[a][c], 1))
                goto overflow;
        int want[4];
        for (int c = 0; c < count; c++)
            want[c] = first + c;
        if (!selects(L, hint, want, count)) {
            snprintf(err, errn, "layout %s: '%s' does not select the %s channels made for it",
                     pname, hint, nprfx_aov_name(a));
            return -1;
        }
    }
    if (vec) {
        /* raw = nprfx's value / scale; a single next vector is written once, from motion_next */
        static const char *const src[4] = {"motion_prev.X", "motion_prev.Y", "motion_next.X",
                                           "motion_next.Y"};
        char sel[256], *item[4];
        int k = 0, want[4];
        snprintf(sel, sizeof sel, "%s", vec->channels);
        for (char *save = NULL, *it = strtok_r(sel, ",", &save); it && k < 4;
             it = strtok_r(NULL, ",", &save))
            item[k++] = it;
        if (k != 4) {
            snprintf(err, errn, "layout %s: vectors '%s' are not 4 channels", pname, vec->channels);
            return -1;
        }
        for (int s = vec->prev_from_next ? 2 : 0; s < 4; s++) {
            want[s] = L->n;
            if (layout_add(L, item[s], OUT_COPY, src[s], (float)(1.0 / vec->scale[s])))
                goto overflow;
        }
        if (vec->prev_from_next) {
            want[0] = layout_find(L, item[0]);
            want[1] = layout_find(L, item[1]);
        }
        int idx[4], amb;
        char bad[128];
        int got =
            nprfx_channels_select(L->names, L->n, vec->channels, idx, 4, bad, sizeof bad, &amb);
        for (int s = 0; s < 4; s++)
            if (got != 4 || idx[s] != want[s]) {
                snprintf(err, errn,
                         "layout %s: vectors '%s' do not select the channels made for them", pname,
                         vec->channels);
                return -1;
            }
    }
    int na = 0;
    if (row >= 0 && renderer_extras[row].attr)
        L->attrs[na++] = (nprfx_attribute){renderer_extras[row].attr, NPRFX_ATTR_STRING,
                                           renderer_extras[row].attr_val};
    if (L->crypto) {
        static const char *const what[4] = {"name", "hash", "conversion", "manifest"};
        nprfx_cryptomatte_key(L->crypto, L->key);
        for (int i = 0; i < 4; i++)
            snprintf(L->attr_name[i], sizeof L->attr_name[i], "cryptomatte/%s/%s", L->key, what[i]);
        L->attrs[na++] = (nprfx_attribute){L->attr_name[0], NPRFX_ATTR_STRING, L->crypto};
        L->attrs[na++] = (nprfx_attribute){L->attr_name[1], NPRFX_ATTR_STRING, "MurmurHash3_32"};
        L->attrs[na++] = (nprfx_attribute){L->attr_name[2], NPRFX_ATTR_STRING, "uint32_to_float32"};
        L->attrs[na++] = (nprfx_attribute){L->attr_name[3], NPRFX_ATTR_STRING, "{}"};
    }
    L->nattrs = na;
    return 0;
overflow:
    snprintf(err, errn, "layout %s: too many channels", pname);
    return -1;
}

/* The blender layout in the same form. */
static void layout_blender(synth_layout *L)
{
    memset(L, 0, sizeof *L);
    L->profile = NPRFX_PROFILE_BLENDER;
    for (int c = 0; c < BLENDER_CHANNELS; c++)
        layout_add(L, blender_layout[c].name, OUT_COPY, blender_layout[c].src,
                   blender_layout[c].sign);
}

/* The frame's Cryptomatte manifest: the names of the object ids present, ascending. 0, or -1
 * out of memory. */
static int layout_manifest(synth_layout *L, const nprfx_image *src)
{
    enum { MAX_IDS = 4096, MAX_NAMES = 256 };
    static unsigned char seen[MAX_IDS];
    memset(seen, 0, sizeof seen);
    int id_ch = synth_index("id");
    for (int y = src->bounds.y0; y < src->bounds.y1; y++)
        for (int x = src->bounds.x0; x < src->bounds.x1; x++) {
            float v = nprfx_image_at(src, x, y)[id_ch];
            if (v >= 1 && v < MAX_IDS) seen[(int)v] = 1;
        }
    static char names[MAX_NAMES][64];
    const char *list[MAX_NAMES];
    int n = 0;
    for (int id = 1; id < MAX_IDS && n < MAX_NAMES; id++)
        if (seen[id]) {
            object_name(id, names[n], sizeof names[n]);
            list[n] = names[n];
            n++;
        }
    size_t need = nprfx_cryptomatte_manifest(list, n, NULL, 0);
    free(L->manifest);
    L->manifest = malloc(need + 1);
    if (!L->manifest) return -1;
    nprfx_cryptomatte_manifest(list, n, L->manifest, need + 1);
    L->attrs[L->nattrs - 1].value = L->manifest;
    return 0;
}

/* Repack a synth frame into a layout. */
static void to_layout(const synth_layout *L, const nprfx_image *src, nprfx_image *dst)
{
    float crypto[256];
    int id_ch = synth_index("id");
    for (int i = 0; L->crypto && i < 256; i++)
        crypto[i] = i ? object_float(i) : 0.0f;
    for (int y = dst->bounds.y0; y < dst->bounds.y1; y++)
        for (int x = dst->bounds.x0; x < dst->bounds.x1; x++) {
            const float *s = nprfx_image_at(src, x, y);
            float *d = nprfx_image_at(dst, x, y);
            int id = (int)s[id_ch];
            for (int c = 0; c < L->n; c++) {
                const out_channel *o = &L->ch[c];
                float v = o->src >= 0 ? s[o->src] : 0.0f;
                switch (o->kind) {
                case OUT_COPY:
                    d[c] = v * o->mul;
                    break;
                case OUT_INVERSE:
                    d[c] = v >= 1e10f ? 0.0f : 1.0f / v;
                    break;
                case OUT_CRYPTO_ID:
                    d[c] = id <= 0 ? 0.0f : id < 256 ? crypto[id] : object_float(id);
                    break;
                case OUT_CRYPTO_COV:
                    d[c] = id > 0 ? v : 0.0f;
                    break;
                default:
                    d[c] = 0.0f;
                }
            }
        }
}

/* "synth, blender, arnold, ...": the layouts, the renderers' named by the profile table (with
 * synth and blender when `all`). */
static void layout_names(char *buf, size_t n, const char *sep, int all)
{
    snprintf(buf, n, "%s", all ? "synth" : "");
    if (all) snprintf(buf + strlen(buf), n - strlen(buf), "%sblender", sep);
    for (int p = 0; p < NPRFX_PROFILE_COUNT; p++)
        if (renderer_row(p) >= 0) {
            size_t l = strlen(buf);
            snprintf(buf + l, n - l, "%s%s", l ? sep : "", nprfx_aov_profile_name(p));
        }
}

/* One line per renderer layout: its channels, as the profile table names them. */
static void usage_layouts(FILE *f)
{
    for (int p = 0; p < NPRFX_PROFILE_COUNT; p++) {
        synth_layout L;
        char err[256], line[2048];
        if (renderer_row(p) < 0 || layout_build(p, &L, err, sizeof err)) continue;
        snprintf(line, sizeof line, "    %-10s", nprfx_aov_profile_name(p));
        for (int c = 0; c < L.n; c++) {
            const char *nm = L.ch[c].name, *dot = strrchr(nm, '.');
            size_t l = strlen(line);
            /* a layer's channels as one item: N.R N.G N.B -> N.RGB */
            int same_prev = c > 0 && dot && strrchr(L.ch[c - 1].name, '.') &&
                            strrchr(L.ch[c - 1].name, '.') - L.ch[c - 1].name == dot - nm &&
                            !strncmp(L.ch[c - 1].name, nm, (size_t)(dot - nm));
            if (same_prev)
                snprintf(line + l, sizeof line - l, "%s", dot + 1);
            else
                snprintf(line + l, sizeof line - l, " %s", nm);
        }
        /* wrapped at 88 columns, continued lines indented */
        const char *s = line;
        int first = 1;
        while (strlen(s) > (first ? 88u : 73u)) {
            const char *cut = s + (first ? 88 : 73);
            while (cut > s && *cut != ' ')
                cut--;
            fprintf(f, "%s%.*s\n", first ? "" : "               ", (int)(cut - s), s);
            s = cut + 1;
            first = 0;
        }
        fprintf(f, "%s%s\n", first ? "" : "               ", s);
        if (L.crypto)
            fprintf(f, "               (%s: Cryptomatte object ids, key %s)\n", L.crypto, L.key);
    }
}

/* Every channel of the scene's frame under the light. */
static nprfx_result synth_render(nprfx_context *ctx, const char *scene, const char *light,
                                 int frame, nprfx_image *im)
{
    int all[64], n = nprfx_synth_channel_count();
    for (int c = 0; c < n && c < 64; c++)
        all[c] = c;
    return nprfx_synth_render_lit(ctx, scene, light, frame, all, n, im);
}

static void usage(FILE *f)
{
    char layouts[256];
    layout_names(layouts, sizeof layouts, "|", 0);
    fprintf(f,
            "usage: nprfx synth SCENE -o PATH [--frames LIST] [--size WxH] [--half]\n"
            "                   [--layout L] [--light L] [--compression C] [--threads N]\n"
            "       nprfx synth --list\n\n"
            "Ray-casts an analytic scene and writes one multi-channel EXR per frame with exact\n"
            "AOVs: ground truth for the coherence metrics and plates for trying the nodes.\n\n"
            "options:\n"
            "  -o PATH          output; with several frames it needs a frame token in the file\n"
            "                   name: '####' (zero padded to 4), '@@@', '%%04d'\n"
            "  --frames LIST    frames to write, e.g. 1-48, 1-48x2, 7, 1,5,9 (default 1); any\n"
            "                   integer frame, negative too, is defined (time = frame)\n"
            "  --size WxH       image size (default 256x256); the composition is the same at\n"
            "                   any size, so motion in pixels scales with the width\n"
            "  --half           store channels as half floats (Z's 1e10 background becomes inf;\n"
            "                   Cryptomatte layers stay float)\n"
            "  --layout L       channel names: synth (below, the default); blender (Blender's\n"
            "                   multilayer names and Vector convention, as samples/plates has: a\n"
            "                   graph written for Blender plates runs with only its read path\n"
            "                   changed; the read node needs \"vectors\": \"blender\"); or a\n"
            "                   renderer's, as its profile (\"aovs\") looks for them:\n"
            "                   %s (renderer layouts, below)\n"
            "  --light L        the scene's light (below): sun (default), point, lowkey\n"
            "  --compression C  EXR compression: zip (default), piz, none, dwaa, ...\n"
            "  --threads N      worker threads (default $NPRFX_THREADS, else all cores)\n"
            "  --list           list the scenes\n\n"
            "scenes (motion figures for 256 pixels wide):\n",
            layouts);
    list_scenes(f);
    fprintf(f, "\nlights (beauty and diffuse change; no shadows):\n");
    for (int i = 0; i < nprfx_synth_light_count(); i++) {
        const char *help = NULL, *name = nprfx_synth_light_name(i, &help);
        fprintf(f, "  %-10s %s\n", name, help);
    }
    fprintf(f, "\nchannels:");
    const char *const *names = nprfx_synth_channel_names();
    for (int i = 0; i < nprfx_synth_channel_count(); i++)
        fprintf(f, " %s", names[i]);
    fprintf(f,
            "\n  motion_prev/next: pixels to the same surface point at frame-1/+1; Z: view depth\n"
            "  (background 1e10); P world, Pref object-space rest position; id 0 = background.\n"
            "  Camera: pinhole, 45 degree horizontal field of view, pixel centres at integer\n"
            "  coordinates, y down.\n\n"
            "renderer layouts: per canonical AOV (nprfx/aov.h) the first name the profile looks\n"
            "for, else the generic profile's (a custom pass); a layer's channels are R G B (A),\n"
            "or R G for two. Motion is the raw channels of the profile's vector convention\n"
            "(nprfx value / scale; a single next vector for those that write one), depth 1/Z\n"
            "where the profile's depth is inverse (background 0), diffuse light only where the\n"
            "renderer has the pass. Object ids are a Cryptomatte layer where the renderer writes\n"
            "them so (rank 0 id and coverage, ranks 1-3 zero; header name, hash, conversion and\n"
            "the frame's manifest), id n standing for the object named 'object \"1\"' (n = 1),\n"
            "'Objekt \xc3\xbc/2' (2), 'object\\3' (3), 'object_n' (n > 3). Arnold's plates carry\n"
            "arnold/version, V-Ray's vrayInfo/camera.\n");
    usage_layouts(f);
    fprintf(f,
            "\nexample: nprfx synth orbit --frames 1-48 --size 512x512 -o plates/orbit.####.exr\n");
}

int cli_cmd_synth(int argc, char **argv)
{
    const char *scene = NULL, *out = NULL, *frames_spec = "1", *size = "256x256";
    const char *compression = NULL, *light = NULL;
    int half = 0, threads = 0, profile = -1; /* -1: synth's own names */
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int has = i + 1 < argc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return SYNTH_OK;
        } else if (!strcmp(a, "--list")) {
            list_scenes(stdout);
            return SYNTH_OK;
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has) {
            out = argv[++i];
        } else if (!strcmp(a, "--frames") && has) {
            frames_spec = argv[++i];
        } else if (!strcmp(a, "--size") && has) {
            size = argv[++i];
        } else if (!strcmp(a, "--threads") && has) {
            threads = atoi(argv[++i]);
        } else if (!strcmp(a, "--compression") && has) {
            compression = argv[++i];
        } else if (!strcmp(a, "--layout") && has) {
            const char *l = argv[++i];
            int p = nprfx_aov_profile_find(l);
            if (strcmp(l, "synth") && p != NPRFX_PROFILE_BLENDER && renderer_row(p) < 0) {
                char list[256];
                layout_names(list, sizeof list, ", ", 1);
                fprintf(stderr, "nprfx synth: --layout must be one of %s, not '%s'\n", list, l);
                return SYNTH_USAGE;
            }
            profile = strcmp(l, "synth") ? p : -1;
        } else if (!strcmp(a, "--light") && has) {
            light = argv[++i];
            int found = 0;
            for (int k = 0; k < nprfx_synth_light_count(); k++)
                found |= !strcmp(nprfx_synth_light_name(k, NULL), light);
            if (!found) {
                fprintf(stderr, "nprfx synth: --light must be sun, point or lowkey, not '%s'\n",
                        light);
                return SYNTH_USAGE;
            }
        } else if (!strcmp(a, "--half")) {
            half = 1;
        } else if (a[0] != '-' && !scene) {
            scene = a;
        } else {
            fprintf(stderr, "nprfx synth: unexpected argument '%s' (nprfx synth --help)\n", a);
            return SYNTH_USAGE;
        }
    }
    if (!scene || !out) {
        fprintf(stderr, "nprfx synth: %s\n\n", !scene ? "name a scene" : "-o PATH is required");
        usage(stderr);
        return SYNTH_USAGE;
    }
    int known = 0;
    for (int i = 0; i < nprfx_synth_scene_count(); i++)
        if (!strcmp(nprfx_synth_scene_at(i)->name, scene)) known = 1;
    if (!known) {
        fprintf(stderr, "nprfx synth: unknown scene '%s'; the scenes are:\n", scene);
        list_scenes(stderr);
        return SYNTH_USAGE;
    }
    int w = 0, h = 0;
    char tail;
    if (sscanf(size, "%dx%d%c", &w, &h, &tail) != 2 || w < 1 || h < 1 || w > 65536 || h > 65536) {
        fprintf(stderr, "nprfx synth: --size must be WxH with positive sizes, e.g. 256x256\n");
        return SYNTH_USAGE;
    }
    if (threads < 0) {
        fprintf(stderr, "nprfx synth: --threads must be a positive number\n");
        return SYNTH_USAGE;
    }

    /* The layout, checked against the engine's channel selection before anything is written. */
    static synth_layout layout;
    int packing = profile >= 0;
    if (profile == NPRFX_PROFILE_BLENDER)
        layout_blender(&layout);
    else if (packing) {
        char err[512];
        if (layout_build(profile, &layout, err, sizeof err)) {
            fprintf(stderr, "nprfx synth: %s\n", err);
            return SYNTH_FAILED;
        }
    }

    cli_env env;
    if (cli_env_init(&env, threads)) return SYNTH_FAILED;
    /* Refused before anything is allocated, with the size and the limit (NPRFX_READ_LIMIT). */
    if (nprfx_image_limit_check(env.ctx, "nprfx synth: --size", w, h,
                                nprfx_synth_channel_count() + (packing ? layout.n : 0), 0)) {
        fprintf(stderr, "%s\n", cli_message(env.ctx));
        cli_env_free(&env);
        return SYNTH_USAGE;
    }
    nprfx_frame_list frames = {NULL, 0};
    nprfx_image im = {0}, packed = {0};
    int status = SYNTH_OK;
    if (nprfx_seq_parse_frames(env.ctx, frames_spec, &frames) != NPRFX_OK) {
        fprintf(stderr, "nprfx synth: --frames: %s\n", cli_message(env.ctx));
        status = SYNTH_USAGE;
        goto done;
    }
    if (frames.count > 1 && !nprfx_seq_has_pattern(out)) {
        fprintf(stderr,
                "nprfx synth: %d frames but '%s' has no frame token; use e.g. "
                "name.####.exr\n",
                frames.count, out);
        status = SYNTH_USAGE;
        goto done;
    }
    if (nprfx_image_alloc(env.ctx, nprfx_rect_make(0, 0, w, h), nprfx_synth_channel_count(), &im) !=
        NPRFX_OK) {
        fprintf(stderr, "nprfx synth: %s\n", cli_message(env.ctx));
        status = SYNTH_FAILED;
        goto done;
    }
    if (packing && nprfx_image_alloc(env.ctx, im.bounds, layout.n, &packed) != NPRFX_OK) {
        fprintf(stderr, "nprfx synth: %s\n", cli_message(env.ctx));
        status = SYNTH_FAILED;
        goto done;
    }
    const nprfx_image *written = packing ? &packed : &im;
    const char *const *names = packing ? layout.names : nprfx_synth_channel_names();
    /* With --half a Cryptomatte layer stays float: the channels' own types then. */
    int mixed = half && layout.crypto;
    nprfx_write_options opt = {sizeof opt,
                               compression,
                               mixed ? 0 : half,
                               layout.nattrs ? layout.attrs : NULL,
                               layout.nattrs,
                               mixed ? layout.types : NULL,
                               0.0f};
    for (int i = 0; i < frames.count; i++) {
        int frame = frames.frames[i];
        char path[4096];
        if (nprfx_seq_expand(env.ctx, out, frame, path, sizeof path) != NPRFX_OK ||
            synth_render(env.ctx, scene, light, frame, &im) != NPRFX_OK) {
            fprintf(stderr, "nprfx synth: frame %d: %s\n", frame, cli_message(env.ctx));
            status = SYNTH_FAILED;
            goto done;
        }
        if (packing) to_layout(&layout, &im, &packed);
        if (layout.crypto && layout_manifest(&layout, &im)) {
            fprintf(stderr, "nprfx synth: frame %d: out of memory\n", frame);
            status = SYNTH_FAILED;
            goto done;
        }
        if (nprfx_io_write(env.ctx, path, written, names, NULL, &opt) != NPRFX_OK) {
            fprintf(stderr, "nprfx synth: frame %d: %s\n", frame, cli_message(env.ctx));
            status = SYNTH_FAILED;
            goto done;
        }
        printf("wrote %s (%s frame %d, %dx%d, %d channels%s)\n", path, scene, frame, w, h,
               written->channels, half ? ", half" : "");
        fflush(stdout);
    }
done:
    free(layout.manifest);
    layout.manifest = NULL;
    nprfx_image_free(&im);
    nprfx_image_free(&packed);
    nprfx_seq_frames_free(&frames);
    cli_env_free(&env);
    return status;
}
