/* The tone node's measurement as text (desc->state_save / state_load): what `nprfx analyze`
 * stores once for a shot and every later run and farm chunk starts from. Lines of
 * "key value ...":
 *   range shot | frame        what was measured: every frame of the shot, or one frame
 *   frames FIRST LAST         the shot (range frame: the reference frame twice)
 *   percentiles LOW HIGH      the params that picked the range
 *   measured LO HI            the range, for people (%.9g)
 *   bits LO HI                the range exactly: the doubles' IEEE-754 bits in hex
 *   fingerprints H ...        each frame's samples' fingerprint, in hex
 * The bits, not the decimals, are read back, so a seeded render maps with the very range a
 * measured one would (and parsing needs no locale). */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/internal_state.h"
#include "internal_tone.h"
#include "nprfx/tone.h"

void nprfx_tone_state_free(void *state)
{
    internal_tone_cache *c = state;
    if (!c) return;
    free(c->hash);
    internal_state_free(c);
}

int nprfx_tone_state_range(const void *state, double *lo, double *hi)
{
    const internal_tone_cache *c = state;
    if (!c || !c->valid) return 0;
    *lo = c->lo;
    *hi = c->hi;
    return 1;
}

static uint64_t bits_of(double d)
{
    uint64_t u;
    memcpy(&u, &d, sizeof u);
    return u;
}

static double double_of(uint64_t u)
{
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

nprfx_result nprfx_tone_state_save(nprfx_context *ctx, const void *state, char **text)
{
    internal_tone_cache *c = (internal_tone_cache *)state;
    *text = NULL;
    if (!c) return NPRFX_OK;
    pthread_mutex_lock(&c->lock);
    if (!c->valid || c->range == NPRFX_TONE_RANGE_MANUAL) {
        pthread_mutex_unlock(&c->lock);
        return NPRFX_OK;
    }
    size_t n = 512 + 17 * (size_t)c->nframes;
    char *s = malloc(n);
    if (!s) {
        pthread_mutex_unlock(&c->lock);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "tone: no memory for its measurement");
    }
    int shot = c->range == NPRFX_TONE_RANGE_SHOT;
    size_t k = (size_t)snprintf(
        s, n,
        "range %s\nframes %d %d\npercentiles %.17g %.17g\nmeasured %.9g %.9g\nbits %016" PRIx64
        " %016" PRIx64 "\nfingerprints",
        shot ? "shot" : "frame", shot ? c->first : c->reference, shot ? c->last : c->reference,
        c->low, c->high, c->lo, c->hi, bits_of(c->lo), bits_of(c->hi));
    for (int f = 0; f < c->nframes && k < n; f++)
        k += (size_t)snprintf(s + k, n - k, " %016" PRIx64, c->hash[f]);
    pthread_mutex_unlock(&c->lock);
    if (k + 2 > n) {
        free(s);
        return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "tone: its measurement did not fit");
    }
    s[k++] = '\n';
    s[k] = 0;
    *text = s;
    return NPRFX_OK;
}

/* What follows `key` on its line ("key value ..."), or NULL when no line has that key. */
static const char *line_of(const char *text, const char *key)
{
    size_t n = strlen(key);
    for (const char *p = text; p && *p; p = strchr(p, '\n'), p = p ? p + 1 : NULL)
        if (!strncmp(p, key, n) && (p[n] == ' ' || p[n] == '\n' || !p[n])) return p + n;
    return NULL;
}

static nprfx_result bad(nprfx_context *ctx, const char *key, const char *why)
{
    return nprfx_error(ctx, NPRFX_ERR_PARSE, "tone: measurement line '%s': %s", key, why);
}

nprfx_result nprfx_tone_state_load(nprfx_context *ctx, void **state, const char *text)
{
    const char *range = line_of(text, "range"), *frames = line_of(text, "frames");
    const char *pct = line_of(text, "percentiles"), *bits = line_of(text, "bits");
    const char *fp = line_of(text, "fingerprints");
    if (!range) return bad(ctx, "range", "missing");
    int shot;
    if (!strncmp(range, " shot", 5) && (range[5] == '\n' || !range[5]))
        shot = 1;
    else if (!strncmp(range, " frame", 6) && (range[6] == '\n' || !range[6]))
        shot = 0;
    else
        return bad(ctx, "range", "neither 'shot' nor 'frame'");
    int first, last;
    double low, high;
    uint64_t blo, bhi;
    if (!frames || sscanf(frames, "%d %d", &first, &last) != 2 || last < first ||
        (!shot && first != last))
        return bad(ctx, "frames", "not two frames FIRST LAST in order");
    if ((long long)last - first >= 1 << 24) return bad(ctx, "frames", "a shot too long");
    if (!pct || sscanf(pct, "%lg %lg", &low, &high) != 2)
        return bad(ctx, "percentiles", "not two numbers");
    if (!bits || sscanf(bits, "%" SCNx64 " %" SCNx64, &blo, &bhi) != 2)
        return bad(ctx, "bits", "not two hexadecimal numbers");
    int nframes = shot ? last - first + 1 : 1;
    if (!fp) return bad(ctx, "fingerprints", "missing");
    uint64_t *hash = malloc((size_t)nframes * sizeof *hash);
    if (!hash) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "tone: no memory");
    const char *p = fp;
    for (int f = 0; f < nframes; f++) {
        char *end;
        while (*p == ' ')
            p++;
        hash[f] = strtoull(p, &end, 16);
        if (end == p) {
            free(hash);
            return bad(ctx, "fingerprints", "fewer than one a frame of the shot");
        }
        p = end;
    }
    while (*p == ' ')
        p++;
    if (*p && *p != '\n') {
        free(hash);
        return bad(ctx, "fingerprints", "more than one a frame of the shot");
    }
    internal_tone_cache *c = internal_state_get(state, sizeof *c);
    if (!c) {
        free(hash);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "tone: no memory for its cache");
    }
    pthread_mutex_lock(&c->lock);
    free(c->hash);
    c->hash = hash;
    c->nframes = nframes;
    c->range = shot ? NPRFX_TONE_RANGE_SHOT : NPRFX_TONE_RANGE_FRAME;
    c->reference = first;
    c->first = first;
    c->last = last;
    c->low = low;
    c->high = high;
    c->lo = double_of(blo);
    c->hi = double_of(bhi);
    c->valid = 1;
    pthread_mutex_unlock(&c->lock);
    return NPRFX_OK;
}
