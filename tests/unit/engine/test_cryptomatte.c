/* Cryptomatte (nprfx/cryptomatte.h): the hash against vectors computed by an independent
 * implementation (and the specification's own example manifest), the exponent clamp on hashes
 * built to need it, nprfx's integer ids, layer keys, the manifest written and read back
 * (escapes, raw-hash entries, malformed and huge texts), and the layers found in channel lists
 * as Arnold, Blender and V-Ray write them. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "nprfx/cryptomatte.h"
#include "nprfx/objectid.h"

#define COUNT(a) ((int)(sizeof(a) / sizeof((a)[0])))

static uint32_t hash_str(const char *s)
{
    return nprfx_cryptomatte_hash(s, strlen(s));
}

/* The stored float's bits for a name, as a manifest lists them. */
static uint32_t name_bits(const char *s)
{
    return nprfx_cryptomatte_bits(nprfx_cryptomatte_float(hash_str(s)));
}

static float float_of_bits(uint32_t bits)
{
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

#define CHECK_STR(got, want)                                                                       \
    do {                                                                                           \
        const char *got_ = (got), *want_ = (want);                                                 \
        if (strcmp(got_, want_)) fprintf(stderr, "got '%s', want '%s'\n", got_, want_);            \
        CHECK(!strcmp(got_, want_));                                                               \
    } while (0)

static void test_hash(void)
{
    /* MurmurHash3_x86_32, seed 0: every tail length (0 to 3 bytes after the 4-byte blocks),
     * the specification's example manifest (bunny, default, bunny_porcelain_mat) and names
     * with the characters object paths carry. Computed with a separate Python implementation. */
    static const struct {
        const char *name;
        uint32_t hash;
    } vectors[] = {
        {"", 0x00000000u},
        {"hello", 0x248bfa47u},
        {"Hello, world!", 0xc0363e43u},
        {"a", 0x3c2569b2u},
        {"ab", 0x9bbfd75fu},
        {"abc", 0xb3dd93fau},
        {"abcd", 0x43ed676au},
        {"abcde", 0xe89b9af6u},
        {"bunny", 0x13851a76u},
        {"default", 0x42c9679fu},
        {"bunny_porcelain_mat", 0xb24b26d4u},
        {"my object", 0xf4f27cebu},
        {"say \"hi\"", 0x5e1b3b18u},
        {"back\\slash", 0xaa5ce9edu},
        {"/root/geo/sphere", 0x2fbb1b05u},
        {"Kugel \xc3\xbc", 0x11c0a03bu}, /* "Kugel ü" in UTF-8 */
        {"CryptoObject", 0x3ae39a58u},
        {"crypto_object", 0xf834d0a6u},
        {"n17", 0x000738c5u},  /* exponent 0, sign 0 */
        {"n132", 0x802d7680u}, /* exponent 0, sign 1 */
        {"n752", 0x7f9513e2u}, /* exponent 255, sign 0 */
        {"n535", 0xff8d97efu}, /* exponent 255, sign 1 */
    };
    for (int i = 0; i < COUNT(vectors); i++) {
        uint32_t got = hash_str(vectors[i].name);
        if (got != vectors[i].hash)
            fprintf(stderr, "hash('%s') = %08x, want %08x\n", vectors[i].name, (unsigned)got,
                    (unsigned)vectors[i].hash);
        CHECK(got == vectors[i].hash);
    }
    /* len, not the NUL, bounds the bytes hashed */
    CHECK(nprfx_cryptomatte_hash("hello, there", 5) == 0x248bfa47u);
    CHECK(nprfx_cryptomatte_hash(NULL, 0) == 0);
}

static void test_float(void)
{
    /* Exponents 1..254 pass bit for bit; 0 becomes 1 and 255 becomes 254, sign and mantissa
     * kept (the names above whose hashes have those exponents, then constructed extremes). */
    static const uint32_t cases[][2] = {
        {0x248bfa47u, 0x248bfa47u}, {0xc0363e43u, 0xc0363e43u}, {0x000738c5u, 0x008738c5u},
        {0x802d7680u, 0x80ad7680u}, {0x7f9513e2u, 0x7f1513e2u}, {0xff8d97efu, 0xff0d97efu},
        {0x00000000u, 0x00800000u}, {0x80000001u, 0x80800001u}, {0x7fffffffu, 0x7f7fffffu},
        {0xff800000u, 0xff000000u}, {0x7f800000u, 0x7f000000u}, {0x00800000u, 0x00800000u},
        {0x7f7fffffu, 0x7f7fffffu},
    };
    for (int i = 0; i < COUNT(cases); i++) {
        uint32_t got = nprfx_cryptomatte_bits(nprfx_cryptomatte_float(cases[i][0]));
        if (got != cases[i][1])
            fprintf(stderr, "float(%08x) has bits %08x, want %08x\n", (unsigned)cases[i][0],
                    (unsigned)got, (unsigned)cases[i][1]);
        CHECK(got == cases[i][1]);
    }
    CHECK(name_bits("n17") == 0x008738c5u && name_bits("n535") == 0xff0d97efu);
    /* never zero, denormal, inf or NaN: a sweep over hashes of every exponent */
    int bad = 0;
    for (uint32_t i = 0; i < 20000; i++) {
        uint32_t h = i * 0x00123457u; /* wraps: about five sweeps, every exponent */
        float f = nprfx_cryptomatte_float(h);
        uint32_t e = nprfx_cryptomatte_bits(f) >> 23 & 0xff;
        if (fpclassify(f) != FP_NORMAL || e == 0 || e == 255) bad++;
    }
    CHECK(bad == 0);
    /* bits is the inverse of the float's representation */
    CHECK(nprfx_cryptomatte_bits(1.0f) == 0x3f800000u);
    CHECK(nprfx_cryptomatte_bits(-2.0f) == 0xc0000000u);
    CHECK(nprfx_cryptomatte_bits(float_of_bits(0x13851a76u)) == 0x13851a76u);
}

static void test_object_id(void)
{
    float bunny = nprfx_cryptomatte_float(0x13851a76u);
    /* the stored float, bit for bit */
    CHECK(nprfx_cryptomatte_bits(nprfx_cryptomatte_object_id(bunny, 0.25f)) == 0x13851a76u);
    CHECK(nprfx_cryptomatte_bits(nprfx_cryptomatte_object_id(bunny, 1.0f)) == 0x13851a76u);
    /* no coverage: nothing there, whatever the id */
    CHECK(nprfx_cryptomatte_object_id(bunny, 0.0f) == 0.0f);
    CHECK(nprfx_cryptomatte_object_id(bunny, -0.5f) == 0.0f);
    CHECK(nprfx_cryptomatte_object_id(bunny, NAN) == 0.0f);
    /* the specification's "no object" id 0 stays nothing even with coverage beside it */
    CHECK(nprfx_cryptomatte_bits(nprfx_cryptomatte_object_id(0.0f, 1.0f)) == 0u);
    CHECK(nprfx_cryptomatte_bits(nprfx_cryptomatte_object_id(-0.0f, 1.0f)) == 0u);
    /* hashes that differ in any bit are distinct objects: the sign, the exponent, the lowest
     * bit, and bits above the 24 a float's integers hold */
    float ids[5] = {nprfx_cryptomatte_object_id(float_of_bits(0x13851a76u), 1.0f),
                    nprfx_cryptomatte_object_id(float_of_bits(0x93851a76u), 1.0f),
                    nprfx_cryptomatte_object_id(float_of_bits(0x14851a76u), 1.0f),
                    nprfx_cryptomatte_object_id(float_of_bits(0x13851a77u), 1.0f),
                    nprfx_cryptomatte_object_id(float_of_bits(0x23851a76u), 1.0f)};
    for (int i = 0; i < 5; i++)
        for (int j = 0; j < 5; j++)
            CHECK(nprfx_id_same(ids[i], ids[j]) == (i == j));
    /* every hash an object, none the empty pixel, distinct hashes distinct ids */
    int bad = 0;
    for (uint32_t i = 0; i < 20000; i++) {
        uint32_t h = 7 + i * 0x000f4243u;
        float stored = nprfx_cryptomatte_float(h);
        float id = nprfx_cryptomatte_object_id(stored, 0.5f);
        if (!nprfx_id_is_object(id) || nprfx_id_key(id) == 0 ||
            nprfx_id_key(id) != nprfx_cryptomatte_bits(stored))
            bad++;
    }
    CHECK(bad == 0);
}

static void test_key(void)
{
    char key[8];
    memset(key, 'x', sizeof key);
    nprfx_cryptomatte_key("CryptoObject", key);
    CHECK_STR(key, "3ae39a5");
    nprfx_cryptomatte_key("crypto_object", key);
    CHECK_STR(key, "f834d0a");
    nprfx_cryptomatte_key("ViewLayer.CryptoObject", key);
    CHECK_STR(key, "542cafa");
    nprfx_cryptomatte_key("n17", key); /* the raw hash's digits, not the clamped float's */
    CHECK_STR(key, "000738c");
}

static void test_manifest_write(void)
{
    /* quotes, a backslash, a slash (left as it is), UTF-8 (passed through), a tab and a control
     * character; the text checked against Python's json.dumps of the same object */
    static const char *const names[] = {"bunny", "say \"hi\"", "C:\\dir/Kugel \xc3\xbc\t\x01"};
    static const char want[] = "{\"bunny\":\"13851a76\",\"say \\\"hi\\\"\":\"5e1b3b18\","
                               "\"C:\\\\dir/Kugel \xc3\xbc\\t\\u0001\":\"a6772304\"}";
    char buf[256];
    size_t need = nprfx_cryptomatte_manifest(names, 3, buf, sizeof buf);
    CHECK(need == strlen(want) && need == 82);
    CHECK_STR(buf, want);
    /* as snprintf: the whole length whatever fits, a NUL always when cap > 0 */
    CHECK(nprfx_cryptomatte_manifest(names, 3, NULL, 0) == 82);
    memset(buf, 'x', sizeof buf);
    CHECK(nprfx_cryptomatte_manifest(names, 3, buf, 10) == 82);
    CHECK(!memcmp(buf, want, 9) && buf[9] == 0 && buf[10] == 'x');
    CHECK(nprfx_cryptomatte_manifest(names, 3, buf, 82) == 82);
    CHECK(strlen(buf) == 81 && !strncmp(buf, want, 81));
    CHECK(nprfx_cryptomatte_manifest(names, 3, buf, 83) == 82 && !strcmp(buf, want));
    memset(buf, 'x', sizeof buf);
    CHECK(nprfx_cryptomatte_manifest(names, 3, buf, 1) == 82 && buf[0] == 0 && buf[1] == 'x');
    /* the float's bits, clamped: n17's raw hash 000738c5 is listed as 008738c5 */
    static const char *const clamped[] = {"n17"};
    CHECK(nprfx_cryptomatte_manifest(clamped, 1, buf, sizeof buf) == 18);
    CHECK_STR(buf, "{\"n17\":\"008738c5\"}");
    CHECK(nprfx_cryptomatte_manifest(names, 0, buf, sizeof buf) == 2);
    CHECK_STR(buf, "{}");
}

/* The name manifest_name gives for `name`'s stored float ("" and -1 printed when none). */
static int lookup(const char *manifest, uint32_t bits, char *buf, size_t cap)
{
    buf[0] = 0;
    return nprfx_cryptomatte_manifest_name(manifest, float_of_bits(bits), buf, cap);
}

static void test_manifest_read(void)
{
    char buf[256];
    /* round trip through the writer, names with every escape it makes */
    static const char *const names[] = {"bunny",          "say \"hi\"",
                                        "back\\slash",    "/root/geo/sphere",
                                        "Kugel \xc3\xbc", "tab\there\x01"};
    char text[1024];
    CHECK(nprfx_cryptomatte_manifest(names, COUNT(names), text, sizeof text) < sizeof text);
    for (int i = 0; i < COUNT(names); i++) {
        CHECK_OK(lookup(text, name_bits(names[i]), buf, sizeof buf));
        CHECK_STR(buf, names[i]);
    }
    CHECK(lookup(text, name_bits("default"), buf, sizeof buf) == -1);

    /* written by hand: whitespace, upper-case hex, \u escapes (ü as \u00fc, an emoji as a
     * surrogate pair), an escaped slash; the specification's example with its space */
    static const char hand[] = " \n{ \"Kugel \\u00FC\" : \"11C0A03B\" ,\r\n\t"
                               "\"smile \\ud83d\\ude00\":\"5e1b3b18\", \"a\\/b\":\"13851a76\","
                               "\"default\":\"42c9679f\"}\n";
    CHECK_OK(lookup(hand, 0x11c0a03bu, buf, sizeof buf));
    CHECK_STR(buf, "Kugel \xc3\xbc");
    CHECK_OK(lookup(hand, 0x5e1b3b18u, buf, sizeof buf));
    CHECK_STR(buf, "smile \xf0\x9f\x98\x80");
    CHECK_OK(lookup(hand, 0x13851a76u, buf, sizeof buf));
    CHECK_STR(buf, "a/b");
    CHECK_OK(
        lookup("{\"bunny\":\"13851a76\", \"default\":\"42c9679f\"}", 0x42c9679fu, buf, sizeof buf));
    CHECK_STR(buf, "default");
    /* a copy of at most cap-1 bytes */
    CHECK_OK(lookup(hand, 0x13851a76u, buf, 2));
    CHECK_STR(buf, "a");

    /* a writer that lists the raw hash: found through its clamp, but the float's own bits win */
    CHECK_OK(lookup("{\"n17\":\"000738c5\"}", name_bits("n17"), buf, sizeof buf));
    CHECK_STR(buf, "n17");
    CHECK_OK(lookup("{\"raw\":\"000738c5\",\"exact\":\"008738c5\"}", 0x008738c5u, buf, sizeof buf));
    CHECK_STR(buf, "exact");
    /* the clamp goes one way: a listed float's bits never stand for a stored raw hash */
    CHECK(lookup("{\"n17\":\"008738c5\"}", 0x000738c5u, buf, sizeof buf) == -1);
    CHECK(lookup("{\"n17\":\"000738c5\"}", 0x008738c4u, buf, sizeof buf) == -1);
    CHECK(lookup("{}", 0x13851a76u, buf, sizeof buf) == -1);

    /* not manifests: each would name bunny to a reader that gave up checking too early */
    static const char *const bad[] = {
        "",
        "   ",
        "[\"bunny\",\"13851a76\"]",
        "\"bunny\"",
        "{",
        "{\"bunny\"",
        "{\"bunny\":",
        "{\"bunny\":\"13851a76\"",
        "{\"bunny\":\"13851a76\",",
        "{\"bunny\":\"13851a76\",}",
        "{\"bunny\":\"13851a76",
        "{\"bunny\":13851a76}",
        "{\"bunny\":\"13851a76\",\"x\":1}",
        "{\"bunny\":[\"13851a76\"]}",
        "{\"bunny\":{\"id\":\"13851a76\"}}",
        "{\"bunny\" \"13851a76\"}",
        "{\"bunny\":\"13851a76\" \"x\":\"1\"}",
        "{\"bunny\":\"13851a76\"} trailing",
        "{\"bunny\":\"13851a76\"}{}",
        "{bunny:\"13851a76\"}",
        "{\"bun\\q\":\"13851a76\"}",
        "{\"bun\\",
        "{\"bun\\u00\":\"13851a76\"}",
        "{\"bun\\ud800\":\"13851a76\"}",
        "{\"bun\\ude00\":\"13851a76\"}",
        "{\"bun\\ud83d\\u0041\":\"13851a76\"}",
        "{\"bun\\u0000ny\":\"13851a76\"}",
    };
    for (int i = 0; i < COUNT(bad); i++) {
        int r = lookup(bad[i], 0x13851a76u, buf, sizeof buf);
        if (r != -1) fprintf(stderr, "manifest %d ('%s') gave %d '%s'\n", i, bad[i], r, buf);
        CHECK(r == -1);
    }
    CHECK(nprfx_cryptomatte_manifest_name(NULL, 1.0f, buf, sizeof buf) == -1);
    /* values that are no 8-digit hex match nothing, and spoil nothing */
    CHECK(lookup("{\"x\":\"13851a76ff\",\"y\":\"zz\",\"z\":\"\",\"bunny\":\"13851a76\"}",
                 0x13851a76u, buf, sizeof buf) == 0);
    CHECK_STR(buf, "bunny");
    CHECK(lookup("{\"x\":\"0x13851a76\"}", 0x13851a76u, buf, sizeof buf) == -1);

    /* huge: 20000 names, the last one found; cut short anywhere, refused */
    enum { N = 20000 };
    char(*storage)[16] = malloc(N * sizeof *storage);
    const char **many = malloc(N * sizeof *many);
    CHECK(storage && many);
    if (!storage || !many) return;
    for (int i = 0; i < N; i++) {
        snprintf(storage[i], sizeof storage[i], "object_%d", i);
        many[i] = storage[i];
    }
    size_t need = nprfx_cryptomatte_manifest(many, N, NULL, 0);
    char *big = malloc(need + 1);
    CHECK(big != NULL);
    if (big) {
        CHECK(nprfx_cryptomatte_manifest(many, N, big, need + 1) == need);
        CHECK(need > 500000);
        CHECK_OK(lookup(big, name_bits("object_19999"), buf, sizeof buf));
        CHECK_STR(buf, "object_19999");
        CHECK_OK(lookup(big, name_bits("object_491"), buf, sizeof buf)); /* clamped exponent */
        CHECK_STR(buf, "object_491");
        big[need - 1] = 0; /* the closing brace gone */
        CHECK(lookup(big, name_bits("object_0"), buf, sizeof buf) == -1);
        big[need / 2] = 0;
        CHECK(lookup(big, name_bits("object_0"), buf, sizeof buf) == -1);
        /* one unterminated string the length of the whole text */
        memset(big, 'a', need);
        big[0] = '{';
        big[1] = '"';
        big[need] = 0;
        CHECK(lookup(big, name_bits("object_0"), buf, sizeof buf) == -1);
        free(big);
    }
    free(many);
    free(storage);
}

static void test_find_arnold(void)
{
    /* Arnold's EXR, channels in the file's (alphabetical) order: crypto_material before
     * crypto_object, A, B, G before R inside each group, three groups for the objects of
     * which the last has R and G only (5 ranks), and the header's keys */
    static const char *const names[] = {
        "A",
        "B",
        "G",
        "R",
        "crypto_material00.A",
        "crypto_material00.B",
        "crypto_material00.G",
        "crypto_material00.R",
        "crypto_material01.A",
        "crypto_material01.B",
        "crypto_material01.G",
        "crypto_material01.R",
        "crypto_object00.A",
        "crypto_object00.B",
        "crypto_object00.G",
        "crypto_object00.R",
        "crypto_object01.A",
        "crypto_object01.B",
        "crypto_object01.G",
        "crypto_object01.R",
        "crypto_object02.G",
        "crypto_object02.R",
    };
    static const char *const an[] = {
        "cryptomatte/bda530a/conversion", "cryptomatte/bda530a/hash",
        "cryptomatte/bda530a/manifest",   "cryptomatte/bda530a/name",
        "cryptomatte/f834d0a/conversion", "cryptomatte/f834d0a/hash",
        "cryptomatte/f834d0a/manifest",   "cryptomatte/f834d0a/name",
    };
    static const char *const av[] = {
        "uint32_to_float32", "MurmurHash3_32", "{}", "crypto_material",
        "uint32_to_float32", "MurmurHash3_32", "{}", "crypto_object",
    };
    nprfx_cryptomatte_layer l[4];
    memset(l, 0, sizeof l);
    CHECK(nprfx_cryptomatte_find(names, COUNT(names), an, av, COUNT(an), l, 4) == 2);
    CHECK_STR(l[0].name, "crypto_material");
    CHECK_STR(l[0].key, "bda530a");
    CHECK(l[0].ranks == 4 && l[0].id0 == 7 && l[0].cov0 == 6 && l[0].kind == 2);
    CHECK_STR(l[1].name, "crypto_object");
    CHECK_STR(l[1].key, "f834d0a");
    CHECK(l[1].ranks == 5 && l[1].id0 == 15 && l[1].cov0 == 14 && l[1].kind == 1);
    /* object over material, though the material comes first */
    CHECK(nprfx_cryptomatte_pick(l, 2, NULL) == 1);
    CHECK(nprfx_cryptomatte_pick(l, 2, "") == 1);
    CHECK(nprfx_cryptomatte_pick(l, 2, "crypto_material") == 0);
    CHECK(nprfx_cryptomatte_pick(l, 2, "f834d0a") == 1);
    CHECK(nprfx_cryptomatte_pick(l, 2, "crypto_asset") == -1);
    CHECK(nprfx_cryptomatte_pick(l, 1, NULL) == 0); /* material alone: the first */

    /* at most max written, all counted; no header: no keys */
    memset(l, 0, sizeof l);
    CHECK(nprfx_cryptomatte_find(names, COUNT(names), NULL, NULL, 0, l, 1) == 2);
    CHECK_STR(l[0].name, "crypto_material");
    CHECK(l[0].key[0] == 0 && l[1].name[0] == 0);
    CHECK(nprfx_cryptomatte_find(names, COUNT(names), NULL, NULL, 0, NULL, 0) == 2);
    CHECK(nprfx_cryptomatte_find(names, 4, an, av, COUNT(an), l, 4) == 0);
}

static void test_find_blender(void)
{
    /* Blender's multilayer EXR: a view layer's prefix, CryptoObject, CryptoMaterial and
     * CryptoAsset with two groups each, header names with the prefix */
    static const char *const names[] = {
        "ViewLayer.Combined.R",         "ViewLayer.Combined.G",
        "ViewLayer.Combined.B",         "ViewLayer.Combined.A",
        "ViewLayer.CryptoObject00.R",   "ViewLayer.CryptoObject00.G",
        "ViewLayer.CryptoObject00.B",   "ViewLayer.CryptoObject00.A",
        "ViewLayer.CryptoObject01.R",   "ViewLayer.CryptoObject01.G",
        "ViewLayer.CryptoObject01.B",   "ViewLayer.CryptoObject01.A",
        "ViewLayer.CryptoMaterial00.R", "ViewLayer.CryptoMaterial00.G",
        "ViewLayer.CryptoMaterial00.B", "ViewLayer.CryptoMaterial00.A",
        "ViewLayer.CryptoAsset00.R",    "ViewLayer.CryptoAsset00.G",
        "ViewLayer.CryptoAsset00.B",    "ViewLayer.CryptoAsset00.A",
        "ViewLayer.CryptoAsset01.R",    "ViewLayer.CryptoAsset01.G",
    };
    static const char *const an[] = {"cryptomatte/542cafa/name", "cryptomatte/c7dbf5e/name",
                                     "cryptomatte/aa21542/name", "cryptomatte/542cafa/hash"};
    static const char *const av[] = {"ViewLayer.CryptoObject", "ViewLayer.CryptoMaterial",
                                     "ViewLayer.CryptoAsset", "MurmurHash3_32"};
    nprfx_cryptomatte_layer l[4];
    CHECK(nprfx_cryptomatte_find(names, COUNT(names), an, av, COUNT(an), l, 4) == 3);
    CHECK_STR(l[0].name, "ViewLayer.CryptoObject");
    CHECK_STR(l[0].key, "542cafa");
    CHECK(l[0].ranks == 4 && l[0].id0 == 4 && l[0].cov0 == 5 && l[0].kind == 1);
    CHECK_STR(l[1].name, "ViewLayer.CryptoMaterial");
    CHECK_STR(l[1].key, "c7dbf5e");
    CHECK(l[1].ranks == 2 && l[1].id0 == 12 && l[1].kind == 2);
    CHECK_STR(l[2].name, "ViewLayer.CryptoAsset");
    CHECK_STR(l[2].key, "aa21542");
    CHECK(l[2].ranks == 3 && l[2].id0 == 16 && l[2].cov0 == 17 && l[2].kind == 3);

    CHECK(nprfx_cryptomatte_pick(l, 3, NULL) == 0);
    CHECK(nprfx_cryptomatte_pick(l, 3, "ViewLayer.CryptoAsset") == 2);
    CHECK(nprfx_cryptomatte_pick(l, 3, "CryptoMaterial") == 1);
    CHECK(nprfx_cryptomatte_pick(l, 3, "c7dbf5e") == 1);
    CHECK(nprfx_cryptomatte_pick(l, 3, "cryptomaterial") == -1); /* names are case-sensitive */
    CHECK(nprfx_cryptomatte_pick(l, 3, "Other.CryptoObject") == -1);
    CHECK(nprfx_cryptomatte_pick(l + 1, 2, NULL) == 1); /* asset over material */
    CHECK(nprfx_cryptomatte_pick(l, 0, NULL) == -1);
    CHECK(nprfx_cryptomatte_pick(NULL, 3, NULL) == -1);
}

static void test_find_others(void)
{
    nprfx_cryptomatte_layer l[4];

    /* lower-case components, no header: found by name */
    static const char *const lower[] = {"rgba.r", "CryptoObject00.r", "CryptoObject00.g",
                                        "CryptoObject00.b", "CryptoObject00.a"};
    CHECK(nprfx_cryptomatte_find(lower, COUNT(lower), NULL, NULL, 0, l, 4) == 1);
    CHECK_STR(l[0].name, "CryptoObject");
    CHECK(l[0].key[0] == 0 && l[0].ranks == 2 && l[0].id0 == 1 && l[0].cov0 == 2);

    /* V-Ray: a name that says no kind, its key from the header ("exr/" as Nuke shows it) */
    static const char *const vray[] = {"VRayCryptomatte00.R", "VRayCryptomatte00.G",
                                       "VRayCryptomatte00.B", "VRayCryptomatte00.A"};
    static const char *const vn[] = {"exr/cryptomatte/0a1b2c3/name"};
    static const char *const vv[] = {"VRayCryptomatte"};
    CHECK(nprfx_cryptomatte_find(vray, COUNT(vray), vn, vv, 1, l, 4) == 1);
    CHECK_STR(l[0].key, "0a1b2c3");
    CHECK(l[0].kind == 0);
    CHECK(nprfx_cryptomatte_pick(l, 1, NULL) == 0);

    /* two digits before R and G are no Cryptomatte by themselves: a light group is not one,
     * unless the header names it; a layer without NAME00.G, or without 00, is none */
    static const char *const light[] = {"Light00.R",    "Light00.G",    "Light00.B",
                                        "crypto_x00.R", "crypto_x00.B", "crypto_y01.R",
                                        "crypto_y01.G"};
    CHECK(nprfx_cryptomatte_find(light, COUNT(light), NULL, NULL, 0, l, 4) == 0);
    static const char *const ln[] = {"cryptomatte/abc1234/name"};
    static const char *const lv[] = {"Light"};
    CHECK(nprfx_cryptomatte_find(light, COUNT(light), ln, lv, 1, l, 4) == 1);
    CHECK_STR(l[0].name, "Light");
    CHECK_STR(l[0].key, "abc1234");
    CHECK(l[0].ranks == 1);

    /* a gap ends the ranks: 00 and 02 give 2; keys too long or not "/name" are no keys */
    static const char *const gap[] = {"CryptoAsset00.R", "CryptoAsset00.G", "CryptoAsset00.B",
                                      "CryptoAsset00.A", "CryptoAsset02.R", "CryptoAsset02.G",
                                      "CryptoAsset02.B", "CryptoAsset02.A"};
    static const char *const gn[] = {"cryptomatte/abcdef01/name", "cryptomatte/abc/names",
                                     "cryptomatte//name", "other/abc/name"};
    static const char *const gv[] = {"CryptoAsset", "CryptoAsset", "CryptoAsset", "CryptoAsset"};
    CHECK(nprfx_cryptomatte_find(gap, COUNT(gap), gn, gv, COUNT(gn), l, 4) == 1);
    CHECK(l[0].ranks == 2 && l[0].key[0] == 0 && l[0].kind == 3);

    /* a part's prefix the header leaves out, and the closest header name wins */
    static const char *const part[] = {"beauty.CryptoObject00.R", "beauty.CryptoObject00.G",
                                       "other.CryptoObject00.R", "other.CryptoObject00.G"};
    static const char *const pn[] = {"cryptomatte/aaaaaaa/name", "cryptomatte/bbbbbbb/name"};
    static const char *const pv[] = {"CryptoObject", "other.CryptoObject"};
    CHECK(nprfx_cryptomatte_find(part, COUNT(part), pn, pv, 2, l, 4) == 2);
    CHECK_STR(l[0].name, "beauty.CryptoObject");
    CHECK_STR(l[0].key, "aaaaaaa");
    CHECK_STR(l[1].name, "other.CryptoObject");
    CHECK_STR(l[1].key, "bbbbbbb");
    CHECK(nprfx_cryptomatte_pick(l, 2, "CryptoObject") == 0);
    CHECK(nprfx_cryptomatte_pick(l, 2, "other.CryptoObject") == 1);
    /* a header name with a prefix the channels lack (Blender's single-layer files) */
    static const char *const bare[] = {"CryptoObject00.R", "CryptoObject00.G"};
    static const char *const bn[] = {"cryptomatte/542cafa/name"};
    static const char *const bv[] = {"ViewLayer.CryptoObject"};
    CHECK(nprfx_cryptomatte_find(bare, 2, bn, bv, 1, l, 4) == 1);
    CHECK_STR(l[0].key, "542cafa");
    CHECK(l[0].ranks == 1 && l[0].kind == 1);

    /* the kind from the name's last component, not a prefix */
    static const char *const pre[] = {"objects.CryptoMaterial00.R", "objects.CryptoMaterial00.G"};
    CHECK(nprfx_cryptomatte_find(pre, 2, NULL, NULL, 0, l, 4) == 1);
    CHECK(l[0].kind == 2);

    /* NULL entries, a name too long for the struct, no names at all */
    char longname[200];
    memset(longname, 'c', sizeof longname);
    memcpy(longname, "Crypto", 6);
    strcpy(longname + 150, "00.R");
    char longg[200];
    memcpy(longg, longname, sizeof longg);
    longg[153] = 'G';
    const char *odd[] = {NULL, longname, longg, "CryptoObject00.R", NULL, "CryptoObject00.G"};
    CHECK(nprfx_cryptomatte_find(odd, COUNT(odd), NULL, NULL, 0, l, 4) == 1);
    CHECK(l[0].id0 == 3 && l[0].cov0 == 5);
    CHECK(nprfx_cryptomatte_find(NULL, 5, NULL, NULL, 0, l, 4) == 0);
}

int main(void)
{
    test_hash();
    test_float();
    test_object_id();
    test_key();
    test_manifest_write();
    test_manifest_read();
    test_find_arnold();
    test_find_blender();
    test_find_others();
    return check_finish();
}
