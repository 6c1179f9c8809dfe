/* nprfx engine — the JSON reader for graph files (never installed).
 *
 * The engine lives in libnprfx, which depends on pthreads and libm only, so it reads JSON itself
 * rather than through a JSON library. Strict RFC 8259 with two kindnesses: a UTF-8 byte order
 * mark at the very start is skipped, and duplicate keys are kept (a graph file that names a node
 * twice is refused by the loader with a message, not silently collapsed here). No global state:
 * several threads may parse at once. */
#ifndef NPRFX_ENGINE_JSON_H
#define NPRFX_ENGINE_JSON_H

#include "nprfx/context.h"

/* Nesting deeper than this is refused: the parser keeps a stack of this many open containers. */
#define INTERNAL_JSON_MAX_DEPTH 1000

typedef enum internal_json_type {
    INTERNAL_JSON_NULL,
    INTERNAL_JSON_FALSE,
    INTERNAL_JSON_TRUE,
    INTERNAL_JSON_NUMBER,
    INTERNAL_JSON_STRING,
    INTERNAL_JSON_ARRAY,
    INTERNAL_JSON_OBJECT
} internal_json_type;

typedef struct internal_json {
    internal_json_type type;
    char *key;     /* a member of an object: its name (UTF-8, NUL-terminated); NULL otherwise */
    char *string;  /* INTERNAL_JSON_STRING: the decoded value, UTF-8, NUL-terminated */
    double number; /* INTERNAL_JSON_NUMBER */
    /* Arrays and objects: elements or members in document order (duplicate keys are all kept,
     * in order); child is the first, next links siblings. */
    struct internal_json *child, *next;
    int count; /* arrays and objects: number of children */
} internal_json;

/* Parse a whole NUL-terminated text into *out (free it with internal_json_free). On failure *out
 * is NULL and the error is raised through ctx: NPRFX_ERR_PARSE with "malformed JSON near line L,
 * column C: WHAT" (1-based; C counts UTF-8 characters, not bytes), or NPRFX_ERR_OUT_OF_MEMORY.
 * Time and memory are linear in the text's length. */
nprfx_result internal_json_parse(nprfx_context *ctx, const char *text, internal_json **out);

/* Free v and everything under it (not its siblings). NULL is ignored. */
void internal_json_free(internal_json *v);

/* The first member of object named exactly key; NULL when there is none or object is NULL or not
 * an object. */
const internal_json *internal_json_member(const internal_json *object, const char *key);

#endif
