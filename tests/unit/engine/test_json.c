/* The engine's JSON reader: trees walked by hand, duplicate keys, escapes to the byte, numbers,
 * every refusal with its exact message and position, the depth limit, the byte order mark, a
 * comma decimal locale, and a million elements. */
#include <locale.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "engine/json.h"

static nprfx_context *ctx;

static internal_json *parse_ok(const char *text)
{
    internal_json *v = NULL;
    nprfx_result r = internal_json_parse(ctx, text, &v);
    if (r) fprintf(stderr, "parse failed: %s\n", th_error(ctx));
    CHECK(r == NPRFX_OK);
    CHECK(v != NULL);
    return v;
}

/* text is refused with NPRFX_ERR_PARSE and exactly "malformed JSON near " + where_what. */
static void check_error_at(int line, const char *text, const char *where_what)
{
    internal_json *v = (internal_json *)&v; /* must come back NULL */
    nprfx_result r = internal_json_parse(ctx, text, &v);
    char want[512];
    snprintf(want, sizeof want, "malformed JSON near %s", where_what);
    const char *got = th_error(ctx);
    if (r == NPRFX_ERR_PARSE && v == NULL && strcmp(got, want) == 0) {
        check_passed++;
    } else {
        check_failed++;
        fprintf(stderr, "%s:%d: result %d, out %s, message '%s', expected '%s'\n", __FILE__, line,
                r, v ? "set" : "NULL", got, want);
        if (r == NPRFX_OK) internal_json_free(v);
    }
}
#define CHECK_ERROR(text, where_what) check_error_at(__LINE__, text, where_what)

/* A string value's bytes are exactly `bytes`. */
static void check_string_at(int line, const char *text, const char *bytes)
{
    internal_json *v = parse_ok(text);
    if (v && v->type == INTERNAL_JSON_STRING && strcmp(v->string, bytes) == 0) {
        check_passed++;
    } else {
        check_failed++;
        fprintf(stderr, "%s:%d: %s did not decode to the expected bytes\n", __FILE__, line, text);
    }
    internal_json_free(v);
}
#define CHECK_STRING(text, bytes) check_string_at(__LINE__, text, bytes)

/* A number document reads exactly `want` (bit for bit: -0 is not 0). */
static void check_number_at(int line, const char *text, double want)
{
    internal_json *v = parse_ok(text);
    if (v && v->type == INTERNAL_JSON_NUMBER && v->number == want &&
        !signbit(v->number) == !signbit(want)) {
        check_passed++;
    } else {
        check_failed++;
        fprintf(stderr, "%s:%d: %s read as %.17g, expected %.17g\n", __FILE__, line, text,
                v ? v->number : NAN, want);
    }
    internal_json_free(v);
}
#define CHECK_NUMBER(text, want) check_number_at(__LINE__, text, want)

static void test_nested(void)
{
    internal_json *root = parse_ok("{\"name\": \"toon\",\n"
                                   " \"list\": [1, -2.5, true, false, null, \"s\", {}, []],\n"
                                   " \"deep\": {\"x\": {\"y\": [[3]]}}}");
    if (!root) return;
    CHECK(root->type == INTERNAL_JSON_OBJECT && root->count == 3 && root->key == NULL);
    CHECK(root->next == NULL);
    const internal_json *name = root->child;
    CHECK(strcmp(name->key, "name") == 0);
    CHECK(name->type == INTERNAL_JSON_STRING && strcmp(name->string, "toon") == 0);
    const internal_json *list = name->next;
    CHECK(strcmp(list->key, "list") == 0);
    CHECK(list->type == INTERNAL_JSON_ARRAY && list->count == 8);
    const internal_json *e = list->child;
    CHECK(e->type == INTERNAL_JSON_NUMBER && e->number == 1.0 && e->key == NULL);
    e = e->next;
    CHECK(e->type == INTERNAL_JSON_NUMBER && e->number == -2.5);
    e = e->next;
    CHECK(e->type == INTERNAL_JSON_TRUE);
    e = e->next;
    CHECK(e->type == INTERNAL_JSON_FALSE);
    e = e->next;
    CHECK(e->type == INTERNAL_JSON_NULL);
    e = e->next;
    CHECK(e->type == INTERNAL_JSON_STRING && strcmp(e->string, "s") == 0 && e->key == NULL);
    e = e->next;
    CHECK(e->type == INTERNAL_JSON_OBJECT && e->count == 0 && e->child == NULL);
    e = e->next;
    CHECK(e->type == INTERNAL_JSON_ARRAY && e->count == 0 && e->child == NULL);
    CHECK(e->next == NULL);
    const internal_json *deep = list->next;
    CHECK(strcmp(deep->key, "deep") == 0 && deep->next == NULL);
    CHECK(deep->type == INTERNAL_JSON_OBJECT && deep->count == 1);
    const internal_json *x = deep->child;
    CHECK(strcmp(x->key, "x") == 0 && x->type == INTERNAL_JSON_OBJECT && x->count == 1);
    const internal_json *y = x->child;
    CHECK(strcmp(y->key, "y") == 0 && y->type == INTERNAL_JSON_ARRAY && y->count == 1);
    CHECK(y->child->type == INTERNAL_JSON_ARRAY && y->child->count == 1 && y->child->key == NULL);
    CHECK(y->child->child->type == INTERNAL_JSON_NUMBER && y->child->child->number == 3.0);
    CHECK(y->child->child->child == NULL && y->child->child->next == NULL);
    /* lookups along the same path */
    CHECK(internal_json_member(root, "deep") == deep);
    CHECK(internal_json_member(internal_json_member(deep, "x"), "y") == y);
    CHECK(internal_json_member(root, "nam") == NULL);
    CHECK(internal_json_member(list, "name") == NULL); /* an array has no members */
    CHECK(internal_json_member(NULL, "name") == NULL);
    internal_json_free(root);
    internal_json_free(NULL);

    /* the four whitespace characters, anywhere between tokens */
    internal_json *ws = parse_ok(" \t\r\n[ 1 ,\r\n\t2 ]\n ");
    if (ws)
        CHECK(ws->type == INTERNAL_JSON_ARRAY && ws->count == 2 && ws->child->next->number == 2);
    internal_json_free(ws);
    /* any value may be the root */
    internal_json *s = parse_ok("\"alone\"");
    if (s) CHECK(s->type == INTERNAL_JSON_STRING && strcmp(s->string, "alone") == 0);
    internal_json_free(s);
    internal_json *n = parse_ok("null");
    if (n) CHECK(n->type == INTERNAL_JSON_NULL && n->child == NULL && n->count == 0);
    internal_json_free(n);
}

static void test_duplicates(void)
{
    internal_json *o = parse_ok("{\"a\": 1, \"b\": 2, \"a\": 3, \"a\": {\"a\": 4}}");
    if (!o) return;
    CHECK(o->count == 4);
    const internal_json *m = o->child;
    CHECK(strcmp(m->key, "a") == 0 && m->number == 1);
    m = m->next;
    CHECK(strcmp(m->key, "b") == 0 && m->number == 2);
    m = m->next;
    CHECK(strcmp(m->key, "a") == 0 && m->number == 3);
    m = m->next;
    CHECK(strcmp(m->key, "a") == 0 && m->type == INTERNAL_JSON_OBJECT && m->next == NULL);
    CHECK(internal_json_member(o, "a") == o->child);
    CHECK(internal_json_member(o, "b") == o->child->next);
    CHECK(internal_json_member(o, "c") == NULL);
    CHECK(internal_json_member(o, "") == NULL);
    internal_json_free(o);

    /* keys are compared whole, after decoding */
    o = parse_ok("{\"ab\": 1, \"a\\u0062\": 2, \"\": 3, \"a\\\"b\": 4}");
    if (!o) return;
    CHECK(internal_json_member(o, "ab") == o->child);
    CHECK(internal_json_member(o, "")->number == 3);
    CHECK(internal_json_member(o, "a\"b")->number == 4);
    CHECK(strcmp(o->child->next->key, "ab") == 0);
    internal_json_free(o);
}

static void test_strings(void)
{
    CHECK_STRING("\"\\\"\\\\\\/\\b\\f\\n\\r\\t\"", "\x22\x5c\x2f\x08\x0c\x0a\x0d\x09");
    CHECK_STRING("\"\\u00e9\"", "\xc3\xa9");
    CHECK_STRING("\"\\u00E9\"", "\xc3\xa9");
    CHECK_STRING("\"\\ud83d\\ude00\"", "\xf0\x9f\x98\x80");
    CHECK_STRING("\"\\uD83D\\uDE00\"", "\xf0\x9f\x98\x80");
    CHECK_STRING("\"\\u0041\\u007f\\u0080\\u07ff\\u0800\\u20ac\\uffff\"",
                 "A\x7f\xc2\x80\xdf\xbf\xe0\xa0\x80\xe2\x82\xac\xef\xbf\xbf");
    CHECK_STRING("\"\\udbff\\udfff\"", "\xf4\x8f\xbf\xbf"); /* U+10FFFF */
    CHECK_STRING("\"x\\u00e9y\\nz\"", "x\xc3\xa9y\nz");
    /* bytes >= 0x80 pass through as written */
    CHECK_STRING("\"caf\xc3\xa9 \xf0\x9f\x98\x80\"", "caf\xc3\xa9 \xf0\x9f\x98\x80");
    CHECK_STRING("\"\"", "");
    CHECK_STRING("\"\\u0001\"", "\x01"); /* control characters are fine escaped */

    internal_json *o = parse_ok("{\"k\\u00e9y\": \"v\"}");
    if (o) CHECK(strcmp(o->child->key, "k\xc3\xa9y") == 0);
    internal_json_free(o);
}

static void test_numbers(void)
{
    CHECK_NUMBER("0", 0.0);
    CHECK_NUMBER("-0", -0.0);
    CHECK_NUMBER("-0.5", -0.5);
    CHECK_NUMBER("1e3", 1000.0);
    CHECK_NUMBER("1.5E-3", 1.5e-3);
    CHECK_NUMBER("123456789012", 123456789012.0);
    CHECK_NUMBER("1E+2", 100.0);
    CHECK_NUMBER("0.1", 0.1);
    CHECK_NUMBER("-12.25e-1", -1.225);
    CHECK_NUMBER("9007199254740993", 9007199254740992.0); /* 2^53 + 1 rounds to even */
    CHECK_NUMBER("1.7976931348623157e308", 1.7976931348623157e308);
    CHECK_NUMBER("1e-400", 0.0); /* underflow reads as the nearest double */
    /* longer than the converter's small buffer */
    CHECK_NUMBER("0.000000000000000000000000000000000000000000000000000000000000000000000001",
                 1e-72);
    internal_json *a = parse_ok("[0,-0.5,1e3]");
    if (a) {
        CHECK(a->count == 3 && a->child->number == 0 && a->child->next->number == -0.5);
        CHECK(a->child->next->next->number == 1000);
    }
    internal_json_free(a);
}

static void test_errors(void)
{
    CHECK_ERROR("", "line 1, column 1: the document is empty");
    CHECK_ERROR("  \n\t ", "line 2, column 3: the document is empty");
    CHECK_ERROR("\xef\xbb\xbf", "line 1, column 1: the document is empty");
    CHECK_ERROR("{\"a\": 1 \"b\": 2}", "line 1, column 9: expected ',' or '}'");
    CHECK_ERROR("[1 2]", "line 1, column 4: expected ',' or ']'");
    CHECK_ERROR("[1,]", "line 1, column 4: expected a value");
    CHECK_ERROR("[,1]", "line 1, column 2: expected a value");
    CHECK_ERROR("{\"a\":1,}", "line 1, column 8: expected a string key");
    CHECK_ERROR("{1: 2}", "line 1, column 2: expected a string key or '}'");
    CHECK_ERROR("{\"a\" 1}", "line 1, column 6: expected ':'");
    CHECK_ERROR("{\"a\": }", "line 1, column 7: expected a value");
    CHECK_ERROR("tru", "line 1, column 1: expected a value");
    CHECK_ERROR("[nul]", "line 1, column 2: expected a value");
    CHECK_ERROR("\f1", "line 1, column 1: expected a value"); /* form feed is no JSON space */
    CHECK_ERROR("'a'", "line 1, column 1: expected a value");
    /* truncated documents */
    CHECK_ERROR("[1,", "line 1, column 4: unexpected end of the document");
    CHECK_ERROR("[", "line 1, column 2: unexpected end of the document");
    CHECK_ERROR("{", "line 1, column 2: unexpected end of the document");
    CHECK_ERROR("{\"a\"", "line 1, column 5: unexpected end of the document");
    CHECK_ERROR("{\"a\":", "line 1, column 6: unexpected end of the document");
    CHECK_ERROR("[[1]", "line 1, column 5: unexpected end of the document");
    /* after the root */
    CHECK_ERROR("{} x", "line 1, column 4: unexpected text after the end of the document");
    CHECK_ERROR("1 2", "line 1, column 3: unexpected text after the end of the document");
    CHECK_ERROR("[]]", "line 1, column 3: unexpected text after the end of the document");
    CHECK_ERROR("\"a\"\n\"b\"", "line 2, column 1: unexpected text after the end of the document");
    CHECK_ERROR("truex", "line 1, column 5: unexpected text after the end of the document");
    CHECK_ERROR("0x10", "line 1, column 2: unexpected text after the end of the document");
    /* strings */
    CHECK_ERROR("\"abc", "line 1, column 1: unterminated string");
    CHECK_ERROR("{\"a\": \"abc}", "line 1, column 7: unterminated string");
    CHECK_ERROR("\"abc\\", "line 1, column 1: unterminated string");
    CHECK_ERROR("\"abc\\\"", "line 1, column 1: unterminated string");
    CHECK_ERROR("\"a\\qb\"", "line 1, column 3: invalid escape");
    CHECK_ERROR("\"a\\U00e9\"", "line 1, column 3: invalid escape");
    CHECK_ERROR("\"\\x41\"", "line 1, column 2: invalid escape");
    CHECK_ERROR("\"\\u12G4\"", "line 1, column 2: invalid \\u escape: expected four hex digits");
    CHECK_ERROR("\"\\u12\"", "line 1, column 2: invalid \\u escape: expected four hex digits");
    CHECK_ERROR("\"\\u0000\"", "line 1, column 2: a NUL character in a string");
    CHECK_ERROR("\"ab\\u0000\"", "line 1, column 4: a NUL character in a string");
    CHECK_ERROR("\"\\ud83d\"", "line 1, column 2: an unpaired UTF-16 surrogate");
    CHECK_ERROR("\"\\ud83dx\"", "line 1, column 2: an unpaired UTF-16 surrogate");
    CHECK_ERROR("\"\\ud83d\\u0041\"", "line 1, column 2: an unpaired UTF-16 surrogate");
    CHECK_ERROR("\"\\ud83d\\ud83d\"", "line 1, column 2: an unpaired UTF-16 surrogate");
    CHECK_ERROR("\"\\ude00\"", "line 1, column 2: an unpaired UTF-16 surrogate");
    CHECK_ERROR("\"\\ude00\\ud83d\"", "line 1, column 2: an unpaired UTF-16 surrogate");
    CHECK_ERROR("\"a\tb\"", "line 1, column 3: a control character in a string");
    CHECK_ERROR("[\"a\nb\"]", "line 1, column 4: a control character in a string");
    CHECK_ERROR("\"\x1f\"", "line 1, column 2: a control character in a string");
    /* numbers */
    CHECK_ERROR("01", "line 1, column 1: invalid number (a leading zero)");
    CHECK_ERROR("-01", "line 1, column 1: invalid number (a leading zero)");
    CHECK_ERROR("[0, 00]", "line 1, column 5: invalid number (a leading zero)");
    CHECK_ERROR("1.", "line 1, column 1: invalid number");
    CHECK_ERROR(".5", "line 1, column 1: invalid number");
    CHECK_ERROR("+1", "line 1, column 1: invalid number");
    CHECK_ERROR("-", "line 1, column 1: invalid number");
    CHECK_ERROR("-a", "line 1, column 1: invalid number");
    CHECK_ERROR("1e", "line 1, column 1: invalid number");
    CHECK_ERROR("1e+", "line 1, column 1: invalid number");
    CHECK_ERROR("1.e5", "line 1, column 1: invalid number");
    CHECK_ERROR("[1, -.5]", "line 1, column 5: invalid number");
    CHECK_ERROR("1e999", "line 1, column 1: number out of range");
    CHECK_ERROR("[-1e999]", "line 1, column 2: number out of range");
    /* positions: lines, and columns in characters after multi-byte ones (é is 2 bytes, € 3,
     * 😀 4); the graph file of tests/cli/run_errors.sh as well */
    CHECK_ERROR("{\"nodes\": {\"a\": {\"node\": \"synth\",\n \"scene\": }}}",
                "line 2, column 11: expected a value");
    CHECK_ERROR("{\"nodes\": {\"a\": {\"node\": \"synth\",\n  \"\xc3\xa9\": 1 2}}}",
                "line 2, column 10: expected ',' or '}'");
    CHECK_ERROR("[\"\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80\", x]",
                "line 1, column 9: expected a value");
    CHECK_ERROR("{\"caf\xc3\xa9\": 1,\n \"\xe2\x82\xac\": [1,\n\n    \"\xc3\xa9\\q\"]}",
                "line 4, column 7: invalid escape");
    CHECK_ERROR("[1,\r\n 2,\r\n x]", "line 3, column 2: expected a value");
    /* a byte order mark is no column, and only skipped at the very start */
    CHECK_ERROR("\xef\xbb\xbf[1 2]", "line 1, column 4: expected ',' or ']'");
    CHECK_ERROR(" \xef\xbb\xbf\x31", "line 1, column 2: expected a value");
    CHECK_ERROR("[1, \xef\xbb\xbf]", "line 1, column 5: expected a value");

    /* bad arguments are refused, not parsed */
    internal_json *v = NULL;
    CHECK(internal_json_parse(ctx, NULL, &v) == NPRFX_ERR_INVALID_ARGUMENT && v == NULL);
    CHECK(internal_json_parse(ctx, "1", NULL) == NPRFX_ERR_INVALID_ARGUMENT);
}

/* n arrays (or objects with member "k") nested, around a 7. */
static char *nested(int n, int objects)
{
    const char *open = objects ? "{\"k\":" : "[";
    size_t olen = strlen(open);
    char *s = malloc(n * (olen + 1) + 2), *o = s;
    if (!s) return NULL;
    for (int i = 0; i < n; i++, o += olen)
        memcpy(o, open, olen);
    *o++ = '7';
    memset(o, objects ? '}' : ']', (size_t)n);
    o[n] = '\0';
    return s;
}

static void test_depth(void)
{
    for (int objects = 0; objects < 2; objects++) {
        char *ok = nested(INTERNAL_JSON_MAX_DEPTH, objects);
        char *deep = nested(INTERNAL_JSON_MAX_DEPTH + 1, objects);
        if (!ok || !deep) {
            CHECK(!"out of memory");
            free(ok);
            free(deep);
            return;
        }
        internal_json *v = parse_ok(ok);
        int levels = 0;
        const internal_json *at = v;
        while (at && at->type == (objects ? INTERNAL_JSON_OBJECT : INTERNAL_JSON_ARRAY)) {
            CHECK(at->count == 1);
            levels++;
            at = at->child;
        }
        CHECK(levels == 1000);
        CHECK(at && at->type == INTERNAL_JSON_NUMBER && at->number == 7);
        CHECK(at && (objects ? at->key && strcmp(at->key, "k") == 0 : at->key == NULL));
        internal_json_free(v);
        /* the 1001st opening bracket: column 1001, or 5 * 1000 + 1 for {"k": */
        CHECK_ERROR(deep, objects ? "line 1, column 5001: nested deeper than 1000 levels"
                                  : "line 1, column 1001: nested deeper than 1000 levels");
        free(ok);
        free(deep);
    }
    /* a million unclosed brackets stop at the limit, without recursion */
    char *many = malloc(1000001);
    if (many) {
        memset(many, '[', 1000000);
        many[1000000] = '\0';
        CHECK_ERROR(many, "line 1, column 1001: nested deeper than 1000 levels");
    }
    free(many);
}

static void test_bom(void)
{
    internal_json *v = parse_ok("\xef\xbb\xbf{\"a\": [1, 2]}");
    if (v) {
        CHECK(v->type == INTERNAL_JSON_OBJECT && v->count == 1);
        CHECK(internal_json_member(v, "a")->count == 2);
    }
    internal_json_free(v);
    v = parse_ok("\xef\xbb\xbf 3 ");
    if (v) CHECK(v->type == INTERNAL_JSON_NUMBER && v->number == 3);
    internal_json_free(v);
}

/* Under a locale whose decimal point is a comma (as a host may set), "0.5" still reads 0.5. */
static void test_locale(void)
{
    static const char *names[] = {"de_DE.UTF-8", "de_DE.utf8", "de_DE",       "fr_FR.UTF-8",
                                  "fr_FR.utf8",  "fr_FR",      "nl_NL.UTF-8", "ru_RU.UTF-8",
                                  "es_ES.UTF-8", "it_IT.UTF-8"};
    const char *used = NULL;
    for (size_t i = 0; i < sizeof names / sizeof *names && !used; i++) {
        if (setlocale(LC_NUMERIC, names[i]) && strcmp(localeconv()->decimal_point, ",") == 0)
            used = names[i];
    }
    if (!used) {
        setlocale(LC_NUMERIC, "C");
        printf("note: no locale with a comma decimal point is installed (tried de_DE, fr_FR, "
               "nl_NL, ru_RU, es_ES, it_IT); the locale check is skipped\n");
        return;
    }
    printf("locale check under LC_NUMERIC=%s\n", used);
    CHECK(strtod("0,5", NULL) == 0.5); /* the locale is in effect */
    CHECK_NUMBER("0.5", 0.5);
    CHECK_NUMBER("-1.25e2", -125.0);
    internal_json *v = parse_ok("[0.5, 2.75]");
    if (v) CHECK(v->count == 2 && v->child->number == 0.5 && v->child->next->number == 2.75);
    internal_json_free(v);
    CHECK_ERROR("0,5", "line 1, column 2: unexpected text after the end of the document");
    setlocale(LC_NUMERIC, "C");
}

/* A million elements and a hundred thousand members: parsing and freeing are linear (appending
 * by walking the list would take minutes here). */
static void test_large(void)
{
    enum { N = 1000000, M = 100000 };
    char *text = malloc((size_t)N * 2 + 2), *o = text;
    if (!text) {
        CHECK(!"out of memory");
        return;
    }
    *o++ = '[';
    for (int i = 0; i < N; i++) {
        *o++ = (char)('0' + i % 10);
        *o++ = i + 1 < N ? ',' : ']';
    }
    *o = '\0';
    internal_json *v = parse_ok(text);
    if (v) {
        CHECK(v->type == INTERNAL_JSON_ARRAY && v->count == N);
        long sum = 0, seen = 0;
        for (const internal_json *e = v->child; e; e = e->next, seen++)
            sum += (long)e->number;
        CHECK(seen == N && sum == 4500000L);
    }
    internal_json_free(v);
    free(text);

    text = malloc((size_t)M * 24 + 2);
    if (!text) {
        CHECK(!"out of memory");
        return;
    }
    o = text;
    *o++ = '{';
    for (int i = 0; i < M; i++)
        o += sprintf(o, "\"n%d\": {\"i\": %d}%s", i, i, i + 1 < M ? "," : "}");
    v = parse_ok(text);
    if (v) {
        CHECK(v->type == INTERNAL_JSON_OBJECT && v->count == M);
        const internal_json *last = internal_json_member(v, "n99999");
        CHECK(last && last->next == NULL && internal_json_member(last, "i")->number == 99999);
    }
    internal_json_free(v);
    free(text);
}

int main(void)
{
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    test_nested();
    test_duplicates();
    test_strings();
    test_numbers();
    test_errors();
    test_depth();
    test_bom();
    test_locale();
    test_large();
    nprfx_context_destroy(ctx);
    return check_finish();
}
