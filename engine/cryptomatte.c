/* nprfx graph engine — Cryptomatte (nprfx/cryptomatte.h): the hash, its float form, the layers a
 * plate's channels and header hold, and the manifest both ways.
 *
 * What the specification (Psyop, specification/cryptomatte_specification) says and this file
 * follows:
 *   - the hash is MurmurHash3_x86_32 with seed 0 over the name's bytes;
 *   - "uint32_to_float32" is a bit-for-bit copy "with logic to clamp the exponent to [1:254]"
 *     (its sample code: max(exponent, 1), min(exponent, 254), sign and mantissa kept). Psyop's
 *     later tools (the Nuke and Fusion utilities) write it as "if the exponent is 0 or 255, flip
 *     bit 23"; for those two exponents that is the same clamp (0 -> 1, 255 -> 254), so both give
 *     the same bits for every hash;
 *   - the manifest is a JSON object whose values are "%08x" of the stored float's bits (the
 *     clamped form, its example {"bunny":"13851a76", "default":"42c9679f"});
 *   - the key "should be chosen to stay the same from frame to frame", "a hash of the type name"
 *     suggested. Writers differ here (Blender: hex of the raw hash; Arnold's alShaders: hex of the
 *     clamped float), which matters only for a name whose hash has exponent 0 or 255; readers
 *     take the key from the header (nprfx_cryptomatte_find), never recompute it.
 * No allocation, no global state: every function may run on several threads at once. */
#include <stdio.h>
#include <string.h>

#include "json.h"
#include "nprfx/cryptomatte.h"

/* ---- hash and float ---------------------------------------------------------------------- */

static uint32_t rotl32(uint32_t x, int r)
{
    return (x << r) | (x >> (32 - r));
}

/* A little-endian 32-bit block read byte by byte: the reference reads a uint32_t in place, which
 * is the same on the little-endian machines renderers run on, and this needs no alignment. */
static uint32_t block32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

uint32_t nprfx_cryptomatte_hash(const char *name, size_t len)
{
    const uint32_t c1 = 0xcc9e2d51u, c2 = 0x1b873593u;
    const unsigned char *data = (const unsigned char *)name;
    if (!data) len = 0;
    uint32_t h = 0; /* the specification's seed */
    size_t nblocks = len / 4;
    for (size_t i = 0; i < nblocks; i++) {
        uint32_t k = block32(data + 4 * i);
        k *= c1;
        k = rotl32(k, 15);
        k *= c2;
        h ^= k;
        h = rotl32(h, 13);
        h = h * 5 + 0xe6546b64u;
    }
    const unsigned char *tail = data + 4 * nblocks;
    uint32_t k = 0;
    switch (len & 3) {
    case 3:
        k ^= (uint32_t)tail[2] << 16;
        /* fall through */
    case 2:
        k ^= (uint32_t)tail[1] << 8;
        /* fall through */
    case 1:
        k ^= tail[0];
        k *= c1;
        k = rotl32(k, 15);
        k *= c2;
        h ^= k;
    }
    h ^= (uint32_t)len; /* the reference takes the length as a 32-bit int */
    h ^= h >> 16;
    h *= 0x85ebca6bu;
    h ^= h >> 13;
    h *= 0xc2b2ae35u;
    h ^= h >> 16;
    return h;
}

/* The clamp on bits: exponent 0 (zero, denormals) becomes 1 and 255 (inf, NaN) becomes 254,
 * both by flipping bit 23, the exponent's lowest. */
static uint32_t clamp_bits(uint32_t bits)
{
    uint32_t exponent = (bits >> 23) & 0xffu;
    return exponent == 0 || exponent == 0xffu ? bits ^ (UINT32_C(1) << 23) : bits;
}

float nprfx_cryptomatte_float(uint32_t hash)
{
    uint32_t bits = clamp_bits(hash);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

uint32_t nprfx_cryptomatte_bits(float stored)
{
    uint32_t bits;
    memcpy(&bits, &stored, sizeof bits);
    return bits;
}

float nprfx_cryptomatte_object_id(float stored, float coverage)
{
    if (!(coverage > 0.0f)) return 0.0f; /* NaN coverage too: nothing we can trust is there */
    uint32_t bits = nprfx_cryptomatte_bits(stored);
    /* ±0 is the specification's "no object in the sample" and never a clamped hash (its exponent
     * is 0), so it stays "nothing" whatever coverage a writer left beside it. */
    if ((bits & 0x7fffffffu) == 0) return 0.0f;
    /* The stored float itself: an id of its own for every hash (nprfx/objectid.h), compared by
     * its bits. */
    return stored;
}

static void hex8(uint32_t v, char out[8])
{
    static const char digits[] = "0123456789abcdef";
    for (int i = 0; i < 8; i++)
        out[i] = digits[(v >> (28 - 4 * i)) & 0xfu];
}

void nprfx_cryptomatte_key(const char *layer, char key[8])
{
    char hex[8];
    /* The raw hash's hex (as Blender writes it); see the file comment on writers that differ. */
    hex8(nprfx_cryptomatte_hash(layer, layer ? strlen(layer) : 0), hex);
    memcpy(key, hex, 7);
    key[7] = 0;
}

/* ---- manifest writer --------------------------------------------------------------------- */

/* An snprintf-like sink: counts every byte, stores those that fit before the NUL. */
typedef struct sink {
    char *buf;
    size_t cap, len;
} sink;

static void put(sink *s, char c)
{
    if (s->len + 1 < s->cap) s->buf[s->len] = c;
    s->len++;
}

static void put_str(sink *s, const char *str)
{
    while (*str)
        put(s, *str++);
}

/* name as a JSON string: quotes, backslashes and control characters escaped (RFC 8259 forbids
 * them raw); every other byte, UTF-8 included, as it is. */
static void put_json_string(sink *s, const char *name)
{
    static const char digits[] = "0123456789abcdef";
    put(s, '"');
    for (const unsigned char *p = (const unsigned char *)name; *p; p++) {
        unsigned char c = *p;
        if (c == '"' || c == '\\') {
            put(s, '\\');
            put(s, (char)c);
        } else if (c < 0x20) {
            const char *esc = c == '\n'   ? "\\n"
                              : c == '\r' ? "\\r"
                              : c == '\t' ? "\\t"
                              : c == '\b' ? "\\b"
                              : c == '\f' ? "\\f"
                                          : NULL;
            if (esc) {
                put_str(s, esc);
            } else {
                put_str(s, "\\u00");
                put(s, digits[c >> 4]);
                put(s, digits[c & 0xf]);
            }
        } else {
            put(s, (char)c);
        }
    }
    put(s, '"');
}

size_t nprfx_cryptomatte_manifest(const char *const *names, int n, char *buf, size_t cap)
{
    sink s = {buf, buf ? cap : 0, 0};
    int first = 1;
    put(&s, '{');
    for (int i = 0; names && i < n; i++) {
        if (!names[i]) continue; /* no name, nothing a manifest could say of it */
        char hex[9];
        const char *name = names[i];
        float stored = nprfx_cryptomatte_float(nprfx_cryptomatte_hash(name, strlen(name)));
        hex8(nprfx_cryptomatte_bits(stored), hex);
        hex[8] = 0;
        if (!first) put(&s, ',');
        first = 0;
        put_json_string(&s, name);
        put(&s, ':');
        put(&s, '"');
        put_str(&s, hex);
        put(&s, '"');
    }
    put(&s, '}');
    if (s.cap) s.buf[s.len < s.cap ? s.len : s.cap - 1] = 0;
    return s.len;
}

/* ---- manifest reader --------------------------------------------------------------------- */

/* The text comes from a file's header or a sidecar: it is parsed whole by the engine's JSON
 * reader (strict RFC 8259), and a text that is not an object of string values is refused whole
 * rather than half read. */

static int hex_digit(char c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* A manifest value as a uint32: 1 to 8 hex digits and nothing else; 0 when it is not one. */
static int parse_hex_value(const char *v, uint32_t *out)
{
    size_t len = strlen(v);
    if (len < 1 || len > 8) return 0;
    uint32_t x = 0;
    for (size_t i = 0; i < len; i++) {
        int d = hex_digit(v[i]);
        if (d < 0) return 0;
        x = x << 4 | (uint32_t)d;
    }
    *out = x;
    return 1;
}

int nprfx_cryptomatte_manifest_name(const char *manifest, float stored, char *buf, size_t cap)
{
    if (!manifest) return -1;
    nprfx_context *quiet = NULL; /* a malformed manifest is an answer here, not an error */
    internal_json *root = NULL;
    if (nprfx_context_create(NULL, &quiet)) return -1;
    nprfx_result r = internal_json_parse(quiet, manifest, &root);
    nprfx_context_destroy(quiet);
    if (r || root->type != INTERNAL_JSON_OBJECT) {
        internal_json_free(root);
        return -1;
    }
    uint32_t want = nprfx_cryptomatte_bits(stored);
    /* The member whose value is the stored bits; failing that, one whose value is a raw hash
     * that clamps to them (some writers list the hash, not the float's bits). */
    const char *exact = NULL, *raw = NULL;
    int ok = 1;
    for (const internal_json *m = root->child; m && ok; m = m->next) {
        uint32_t v;
        ok = m->type == INTERNAL_JSON_STRING;
        if (ok && parse_hex_value(m->string, &v)) {
            if (!exact && v == want) exact = m->key;
            if (!raw && clamp_bits(v) == want) raw = m->key;
        }
    }
    const char *found = ok ? (exact ? exact : raw) : NULL;
    if (found && buf && cap) snprintf(buf, cap, "%s", found);
    internal_json_free(root);
    return found ? 0 : -1;
}

/* ---- layers ------------------------------------------------------------------------------ */

/* A Cryptomatte channel's parts: "STEMnn.C" with nn two digits and C one of RGBA (or rgba, as
 * some writers spell them). *stem_len is STEM's length (at least 1), *group nn, *comp 0..3. */
static int parse_channel(const char *name, size_t *stem_len, int *group, int *comp)
{
    const char *dot = strrchr(name, '.');
    if (!dot || !dot[1] || dot[2]) return 0;
    static const char upper[] = "RGBA", lower[] = "rgba";
    const char *u = strchr(upper, dot[1]), *l = strchr(lower, dot[1]);
    if (!u && !l) return 0;
    size_t d = (size_t)(dot - name);
    if (d < 3) return 0;
    char t = name[d - 2], o = name[d - 1];
    if (t < '0' || t > '9' || o < '0' || o > '9') return 0;
    *stem_len = d - 2;
    *group = (t - '0') * 10 + (o - '0');
    *comp = (int)(u ? u - upper : l - lower);
    return 1;
}

static const char *last_component(const char *name)
{
    const char *dot = strrchr(name, '.');
    return dot ? dot + 1 : name;
}

/* Does s (of length n) contain word, ignoring ASCII case? */
static int contains_ci(const char *s, size_t n, const char *word)
{
    size_t w = strlen(word);
    for (size_t i = 0; i + w <= n; i++) {
        size_t j = 0;
        while (j < w) {
            char c = s[i + j];
            if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
            if (c != word[j]) break;
            j++;
        }
        if (j == w) return 1;
    }
    return 0;
}

/* The key of an attribute "cryptomatte/KEY/name" (or "exr/cryptomatte/KEY/name", as Nuke shows
 * it): its start and length (1 to 7 characters, the specification's maximum); 0 otherwise. */
static int attribute_key(const char *attr, const char **key, size_t *len)
{
    static const char prefix[] = "cryptomatte/", suffix[] = "/name";
    const char *p = attr;
    if (!strncmp(p, "exr/", 4)) p += 4;
    if (strncmp(p, prefix, sizeof prefix - 1)) return 0;
    p += sizeof prefix - 1;
    const char *slash = strchr(p, '/');
    if (!slash || strcmp(slash, suffix)) return 0;
    size_t n = (size_t)(slash - p);
    if (n < 1 || n > 7) return 0;
    *key = p;
    *len = n;
    return 1;
}

/* The header key for layer `name`. The header's name may differ from the channels' stem by a
 * prefix (a part's or a view layer's) on either side, so the closest match wins: the whole name,
 * then the value naming the stem without its prefix, then both without theirs; the first of
 * equals. */
static void layer_key(const char *name, const char *const *attr_names,
                      const char *const *attr_values, int nattr, char key[8])
{
    const char *bare = last_component(name), *best = NULL;
    size_t best_len = 0;
    int best_rank = 0;
    key[0] = 0;
    for (int i = 0; attr_names && attr_values && i < nattr; i++) {
        const char *k, *v = attr_values[i];
        size_t len;
        if (!attr_names[i] || !v || !attribute_key(attr_names[i], &k, &len)) continue;
        int rank = !strcmp(v, name) ? 3 : !strcmp(v, bare) ? 2 : !strcmp(last_component(v), bare);
        if (rank > best_rank) {
            best = k;
            best_len = len;
            best_rank = rank;
        }
    }
    if (best) {
        memcpy(key, best, best_len);
        key[best_len] = 0;
    }
}

static int kind_of(const char *name)
{
    const char *c = last_component(name); /* a prefix such as "objects_pass." says nothing */
    size_t n = strlen(c);
    if (contains_ci(c, n, "object")) return 1;
    if (contains_ci(c, n, "material")) return 2;
    if (contains_ci(c, n, "asset")) return 3;
    return 0;
}

/* Layer `stem` (stem_len bytes of a channel name) evaluated over all n channels: 1 and *out
 * filled when it is a Cryptomatte layer. */
static int evaluate_layer(const char *const *names, int n, const char *stem, size_t stem_len,
                          const char *const *attr_names, const char *const *attr_values, int nattr,
                          nprfx_cryptomatte_layer *out)
{
    unsigned char have[100] = {0}; /* per group nn, a bit per component present */
    int id0 = -1, cov0 = -1;
    for (int i = 0; i < n; i++) {
        size_t len;
        int group, comp;
        if (!names[i] || !parse_channel(names[i], &len, &group, &comp) || len != stem_len ||
            memcmp(names[i], stem, len))
            continue;
        have[group] |= (unsigned char)(1u << comp);
        /* the first when a file has both R and r: either holds the same data */
        if (group == 0 && comp == 0 && id0 < 0) id0 = i;
        if (group == 0 && comp == 1 && cov0 < 0) cov0 = i;
    }
    if (id0 < 0 || cov0 < 0) return 0;
    memcpy(out->name, stem, stem_len);
    out->name[stem_len] = 0;
    layer_key(out->name, attr_names, attr_values, nattr, out->key);
    /* A stem with two digits before an R and a G is common outside Cryptomatte ("Light00.R"):
     * a layer is one when its header names it or its name says so. The specification requires
     * the header; "crypto" covers callers that have no attributes to give. */
    if (!out->key[0] && !contains_ci(out->name, stem_len, "crypto")) return 0;
    /* Ranks in order from 00: a group with all four channels holds two, one with only R and G
     * holds one and ends them, as does a gap (later ranks could not be told apart from it). */
    int ranks = 0;
    for (int g = 0; g < 100; g++) {
        if (have[g] == 0xf) {
            ranks += 2;
            continue;
        }
        if ((have[g] & 3) == 3) ranks++;
        break;
    }
    out->ranks = ranks;
    out->id0 = id0;
    out->cov0 = cov0;
    out->kind = kind_of(out->name);
    return 1;
}

int nprfx_cryptomatte_find(const char *const *names, int n, const char *const *attr_names,
                           const char *const *attr_values, int nattr, nprfx_cryptomatte_layer *out,
                           int max)
{
    /* Quadratic in n, without allocating: a plate has tens to a few hundred channels. */
    int count = 0;
    for (int i = 0; names && i < n; i++) {
        size_t len;
        int group, comp;
        if (!names[i] || !parse_channel(names[i], &len, &group, &comp)) continue;
        if (len >= sizeof out->name) continue; /* a name the struct cannot hold matches nothing */
        /* a layer is evaluated at its first channel only, so layers come in file order */
        int seen = 0;
        for (int j = 0; j < i && !seen; j++) {
            size_t lj;
            int gj, cj;
            seen = names[j] && parse_channel(names[j], &lj, &gj, &cj) && lj == len &&
                   !memcmp(names[j], names[i], len);
        }
        if (seen) continue;
        nprfx_cryptomatte_layer layer;
        if (!evaluate_layer(names, n, names[i], len, attr_names, attr_values, nattr, &layer))
            continue;
        if (out && count < max) out[count] = layer;
        count++;
    }
    return count;
}

int nprfx_cryptomatte_pick(const nprfx_cryptomatte_layer *layers, int n, const char *want)
{
    if (!layers || n <= 0) return -1;
    if (want && *want) {
        /* the whole name first, so that "ViewLayer.CryptoObject" is never shadowed by another
         * part's "CryptoObject" coming earlier */
        for (int i = 0; i < n; i++)
            if (!strcmp(layers[i].name, want)) return i;
        for (int i = 0; i < n; i++)
            if (!strcmp(last_component(layers[i].name), want)) return i;
        for (int i = 0; i < n; i++)
            if (layers[i].key[0] && !strcmp(layers[i].key, want)) return i;
        return -1;
    }
    /* Object ids mean objects: an object layer first; an asset groups objects, so it is the
     * next best; a material layer would merge every object that shares a shader. */
    for (int i = 0; i < n; i++)
        if (layers[i].kind == 1) return i;
    for (int i = 0; i < n; i++)
        if (layers[i].kind == 3) return i;
    return 0;
}
