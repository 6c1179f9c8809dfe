/* nprfx engine — the JSON reader: an iterative parser (an explicit stack of open containers, so
 * neither a deep document nor a long one recurses) building internal_json trees. */

/* strtod_l and newlocale: glibc declares them with _GNU_SOURCE, the BSDs and macOS in
 * <xlocale.h>. */
#define _GNU_SOURCE
#include "json.h"

#include <locale.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#if defined(__APPLE__) || defined(__FreeBSD__)
#include <xlocale.h>
#endif

/* The depth limit in its message, spelt as json.h defines it. */
#define JSON_STR_(x) #x
#define JSON_STR(x) JSON_STR_(x)

/* An open array or object and its last child, so appending a child is O(1) and a parse linear
 * however many children a container has. */
typedef struct json_frame {
    internal_json *node, *tail;
} json_frame;

typedef struct json_parser {
    nprfx_context *ctx;
    const char *start; /* the text after any byte order mark: line 1, column 1 */
    json_frame *stack; /* INTERNAL_JSON_MAX_DEPTH frames */
    int depth;         /* open containers */
    internal_json *root;
    /* Numbers are converted with strtod_l in the "C" locale rather than with strtod in the
     * process's: a host (Nuke) may set LC_NUMERIC to a locale whose decimal point is a comma,
     * and swapping '.' for localeconv()'s point would read process-wide state that another
     * thread may change mid-parse. glibc hands out its built-in C locale here without
     * allocating. */
    locale_t c_locale;
} json_parser;

/* Raise "malformed JSON near line L, column C: WHAT" for the character at `at`. The position is
 * only computed on failure, so a parse does not track it per character. Columns count UTF-8
 * characters (continuation bytes are skipped), as an editor shows them. */
static nprfx_result json_fail(const json_parser *ps, const char *at, const char *what)
{
    int line = 1, column = 1;
    for (const char *c = ps->start; c < at; c++) {
        if (*c == '\n') {
            line++;
            column = 1;
        } else if (((unsigned char)*c & 0xc0) != 0x80) {
            column++;
        }
    }
    return nprfx_error(ps->ctx, NPRFX_ERR_PARSE, "malformed JSON near line %d, column %d: %s", line,
                       column, what);
}

static nprfx_result json_oom(const json_parser *ps)
{
    return nprfx_error(ps->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
}

static const char *skip_space(const char *s)
{
    while (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r')
        s++;
    return s;
}

static int is_digit(char c)
{
    return c >= '0' && c <= '9';
}

/* A new node (JSON null until filled in): the root when no container is open, else the last
 * child of the innermost one. It is in the tree at once, so a failure later frees it with the
 * rest. */
static internal_json *json_append(json_parser *ps)
{
    internal_json *v = calloc(1, sizeof *v);
    if (!v) return NULL;
    if (ps->depth == 0) {
        ps->root = v;
        return v;
    }
    json_frame *f = &ps->stack[ps->depth - 1];
    if (f->tail)
        f->tail->next = v;
    else
        f->node->child = v;
    f->tail = v;
    f->node->count++;
    return v;
}

/* What a backslash and c stand for, for the escapes of one character; 0 for the others. */
static char simple_escape(char c)
{
    static const char from[] = "\"\\/bfnrt", to[] = "\"\\/\b\f\n\r\t";
    const char *k = c ? strchr(from, c) : NULL;
    return k ? to[k - from] : 0;
}

/* Four hex digits at s (either case) into *u; 0 when they are not. Stops at the first non-hex
 * character, so it never reads past the text's end. */
static int read_hex4(const char *s, unsigned *u)
{
    *u = 0;
    for (int i = 0; i < 4; i++) {
        char c = s[i];
        unsigned d;
        if (c >= '0' && c <= '9')
            d = (unsigned)(c - '0');
        else if (c >= 'a' && c <= 'f')
            d = (unsigned)(c - 'a' + 10);
        else if (c >= 'A' && c <= 'F')
            d = (unsigned)(c - 'A' + 10);
        else
            return 0;
        *u = *u << 4 | d;
    }
    return 1;
}

/* Code point u (not a surrogate, at most 0x10FFFF) as UTF-8 at o; returns the end. */
static char *put_utf8(char *o, unsigned u)
{
    if (u < 0x80) {
        *o++ = (char)u;
    } else if (u < 0x800) {
        *o++ = (char)(0xc0 | u >> 6);
        *o++ = (char)(0x80 | (u & 0x3f));
    } else if (u < 0x10000) {
        *o++ = (char)(0xe0 | u >> 12);
        *o++ = (char)(0x80 | (u >> 6 & 0x3f));
        *o++ = (char)(0x80 | (u & 0x3f));
    } else {
        *o++ = (char)(0xf0 | u >> 18);
        *o++ = (char)(0x80 | (u >> 12 & 0x3f));
        *o++ = (char)(0x80 | (u >> 6 & 0x3f));
        *o++ = (char)(0x80 | (u & 0x3f));
    }
    return o;
}

/* The \u escape at esc (the backslash): its code point into *u and the escape's end into *end,
 * a surrogate pair read as one; NULL, or the reason it is refused. */
static const char *read_u_escape(const char *esc, unsigned *u, const char **end)
{
    if (!read_hex4(esc + 2, u)) return "invalid \\u escape: expected four hex digits";
    *end = esc + 6;
    if (*u == 0) return "a NUL character in a string";
    if (*u >= 0xdc00 && *u <= 0xdfff) return "an unpaired UTF-16 surrogate";
    if (*u < 0xd800 || *u > 0xdbff) return NULL;
    /* a high surrogate: the low one must follow at once */
    unsigned lo;
    if ((*end)[0] != '\\' || (*end)[1] != 'u') return "an unpaired UTF-16 surrogate";
    if (!read_hex4(*end + 2, &lo)) return "invalid \\u escape: expected four hex digits";
    if (lo < 0xdc00 || lo > 0xdfff) return "an unpaired UTF-16 surrogate";
    *u = 0x10000 + ((*u - 0xd800) << 10) + (lo - 0xdc00);
    *end += 6;
    return NULL;
}

/* The string whose opening quote is at *sp, decoded into a new *out; *sp moves past the closing
 * quote. Two passes: the first finds the end (and refuses raw control characters), which bounds
 * the decoded length, as no escape decodes to more bytes than it is written with. */
static nprfx_result read_string(json_parser *ps, const char **sp, char **out)
{
    const char *open = *sp, *s = open + 1;
    for (; *s != '"'; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '\\' && s[1] != '\0') {
            s++; /* the escaped character, checked below; it may be a quote */
        } else if (c == '\0' || c == '\\') {
            return json_fail(ps, open, "unterminated string");
        } else if (c < 0x20) {
            return json_fail(ps, s, "a control character in a string");
        }
    }
    const char *close = s;
    char *buf = malloc((size_t)(close - open)), *o = buf;
    if (!buf) return json_oom(ps);
    for (s = open + 1; s < close;) {
        if (*s != '\\') {
            *o++ = *s++;
            continue;
        }
        const char *esc = s;
        s += 2;
        char simple = simple_escape(esc[1]);
        if (simple) {
            *o++ = simple;
        } else if (esc[1] == 'u') {
            unsigned u;
            const char *why = read_u_escape(esc, &u, &s);
            if (why) {
                free(buf);
                return json_fail(ps, esc, why);
            }
            o = put_utf8(o, u);
        } else {
            free(buf);
            return json_fail(ps, esc, "invalid escape");
        }
    }
    *o = '\0';
    *out = buf;
    *sp = close + 1;
    return NPRFX_OK;
}

/* The number at *sp, checked against JSON's grammar
 * -?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)? and converted; *sp moves past it. */
static nprfx_result read_number(json_parser *ps, const char **sp, double *out)
{
    const char *start = *sp, *s = start;
    if (*s == '-') s++;
    if (*s == '0') {
        s++;
        if (is_digit(*s)) return json_fail(ps, start, "invalid number (a leading zero)");
    } else if (is_digit(*s)) {
        while (is_digit(*s))
            s++;
    } else {
        return json_fail(ps, start, "invalid number");
    }
    if (*s == '.') {
        s++;
        if (!is_digit(*s)) return json_fail(ps, start, "invalid number");
        while (is_digit(*s))
            s++;
    }
    if (*s == 'e' || *s == 'E') {
        s++;
        if (*s == '+' || *s == '-') s++;
        if (!is_digit(*s)) return json_fail(ps, start, "invalid number");
        while (is_digit(*s))
            s++;
    }
    /* A copy ends exactly where the grammar does: strtod alone would read on into "0x1p3". */
    size_t n = (size_t)(s - start);
    char small[64], *copy = n < sizeof small ? small : malloc(n + 1);
    if (!copy) return json_oom(ps);
    memcpy(copy, start, n);
    copy[n] = '\0';
    double v = strtod_l(copy, NULL, ps->c_locale);
    if (copy != small) free(copy);
    /* overflow is refused; an underflow reads as the nearest double (0 or subnormal) */
    if (isinf(v)) return json_fail(ps, start, "number out of range");
    *out = v;
    *sp = s;
    return NPRFX_OK;
}

/* A string, number or literal at *sp into v; *sp moves past it. */
static nprfx_result read_scalar(json_parser *ps, const char **sp, internal_json *v)
{
    static const struct {
        const char *word;
        internal_json_type type;
    } literals[] = {
        {"null", INTERNAL_JSON_NULL}, {"false", INTERNAL_JSON_FALSE}, {"true", INTERNAL_JSON_TRUE}};
    const char *s = *sp;
    if (*s == '"') {
        v->type = INTERNAL_JSON_STRING;
        return read_string(ps, sp, &v->string);
    }
    /* '+' and '.' are no number's start, but "+1" and ".5" are meant as numbers */
    if (*s == '-' || *s == '+' || *s == '.' || is_digit(*s)) {
        v->type = INTERNAL_JSON_NUMBER;
        return read_number(ps, sp, &v->number);
    }
    for (size_t i = 0; i < sizeof literals / sizeof *literals; i++) {
        size_t n = strlen(literals[i].word);
        if (strncmp(s, literals[i].word, n) == 0) {
            v->type = literals[i].type;
            *sp = s + n;
            return NPRFX_OK;
        }
    }
    if (*s == '\0')
        return json_fail(ps, s,
                         ps->depth ? "unexpected end of the document" : "the document is empty");
    return json_fail(ps, s, "expected a value");
}

/* An object member's key at *sp (after whitespace): the member is appended with it and returned
 * in *member, and *sp moves past the ':'. `what` is the message when no key is there. */
static nprfx_result read_key(json_parser *ps, const char **sp, internal_json **member,
                             const char *what)
{
    const char *s = skip_space(*sp);
    if (*s != '"') return json_fail(ps, s, *s ? what : "unexpected end of the document");
    internal_json *m = json_append(ps);
    if (!m) return json_oom(ps);
    nprfx_result r = read_string(ps, &s, &m->key);
    if (r) return r;
    s = skip_space(s);
    if (*s != ':') return json_fail(ps, s, *s ? "expected ':'" : "unexpected end of the document");
    *sp = s + 1;
    *member = m;
    return NPRFX_OK;
}

/* After a value: close the containers that end here, then move to the next value (*member set
 * when it is an object member's) or, when the root is complete, check nothing follows it and
 * set *done. */
static nprfx_result after_value(json_parser *ps, const char **sp, internal_json **member, int *done)
{
    const char *s = skip_space(*sp);
    for (;;) {
        if (ps->depth == 0) {
            if (*s) return json_fail(ps, s, "unexpected text after the end of the document");
            *done = 1;
            return NPRFX_OK;
        }
        int object = ps->stack[ps->depth - 1].node->type == INTERNAL_JSON_OBJECT;
        if (*s == ',') {
            *sp = s + 1;
            return object ? read_key(ps, sp, member, "expected a string key") : NPRFX_OK;
        }
        if (*s != (object ? '}' : ']')) {
            if (!*s) return json_fail(ps, s, "unexpected end of the document");
            return json_fail(ps, s, object ? "expected ',' or '}'" : "expected ',' or ']'");
        }
        ps->depth--;
        s = skip_space(s + 1);
    }
}

/* The document at s into ps->root. One loop iteration per value: a container opens a frame, a
 * scalar is read; after_value closes frames and finds the next value. */
static nprfx_result parse_document(json_parser *ps, const char *s)
{
    internal_json *member = NULL; /* an object member whose key is read: the next value's node */
    for (;;) {
        s = skip_space(s);
        internal_json *v = member ? member : json_append(ps);
        member = NULL;
        if (!v) return json_oom(ps);
        nprfx_result r;
        if (*s == '[' || *s == '{') {
            if (ps->depth == INTERNAL_JSON_MAX_DEPTH)
                return json_fail(ps, s,
                                 "nested deeper than " JSON_STR(INTERNAL_JSON_MAX_DEPTH) " levels");
            int object = *s == '{';
            v->type = object ? INTERNAL_JSON_OBJECT : INTERNAL_JSON_ARRAY;
            ps->stack[ps->depth++] = (json_frame){v, NULL};
            s = skip_space(s + 1);
            if (*s != (object ? '}' : ']')) {
                /* not empty: on to the first value (an object's after its key) */
                r = object ? read_key(ps, &s, &member, "expected a string key or '}'") : NPRFX_OK;
                if (r) return r;
                continue;
            }
            ps->depth--;
            s++;
        } else if ((r = read_scalar(ps, &s, v))) {
            return r;
        }
        int done = 0;
        if ((r = after_value(ps, &s, &member, &done))) return r;
        if (done) return NPRFX_OK;
    }
}

nprfx_result internal_json_parse(nprfx_context *ctx, const char *text, internal_json **out)
{
    if (!out) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "internal_json_parse: no out");
    *out = NULL;
    if (!text) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "internal_json_parse: no text");
    /* a UTF-8 byte order mark, as editors on Windows write, is not part of the document */
    if ((unsigned char)text[0] == 0xef && (unsigned char)text[1] == 0xbb &&
        (unsigned char)text[2] == 0xbf)
        text += 3;
    json_parser ps = {.ctx = ctx, .start = text};
    ps.stack = malloc(INTERNAL_JSON_MAX_DEPTH * sizeof *ps.stack);
    ps.c_locale = newlocale(LC_ALL_MASK, "C", (locale_t)0);
    nprfx_result r = ps.stack && ps.c_locale ? parse_document(&ps, text) : json_oom(&ps);
    if (ps.c_locale) freelocale(ps.c_locale);
    free(ps.stack);
    if (r)
        internal_json_free(ps.root);
    else
        *out = ps.root;
    return r;
}

void internal_json_free(internal_json *v)
{
    if (!v) return;
    /* Without recursion: each node's children are spliced into the list of nodes still to free,
     * just after it. Every child list is walked once, so this is linear too. */
    v->next = NULL; /* its siblings are not freed */
    while (v) {
        if (v->child) {
            internal_json *last = v->child;
            while (last->next)
                last = last->next;
            last->next = v->next;
            v->next = v->child;
        }
        internal_json *next = v->next;
        free(v->key);
        free(v->string);
        free(v);
        v = next;
    }
}

const internal_json *internal_json_member(const internal_json *object, const char *key)
{
    if (!object || object->type != INTERNAL_JSON_OBJECT || !key) return NULL;
    for (const internal_json *m = object->child; m; m = m->next)
        if (m->key && strcmp(m->key, key) == 0) return m;
    return NULL;
}
