/* nprfx OpenFX test host — property sets: the typed, multi-valued properties behind every handle
 * the plug-ins see, the property suite over them, and the helpers the other files use to read
 * and write them directly (internal_set_string, internal_pstr, ...). */
#define _POSIX_C_SOURCE 200809L /* strdup */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "ofx_host_internal.h"

void internal_props_init(hprops *p, pkind kind)
{
    memset(p, 0, sizeof *p);
    p->magic = PROPS_MAGIC;
    p->kind = kind;
}

static void prop_clear(prop *q)
{
    if (q->type == PT_STRING)
        for (int k = 0; k < q->dim; k++)
            free(q->v.s[k]);
    free(q->v.p);
    q->v.p = NULL;
    q->dim = 0;
}

void internal_props_free(hprops *p)
{
    if (!p) return;
    for (int i = 0; i < p->count; i++) {
        prop_clear(&p->items[i]);
        free(p->items[i].name);
    }
    free(p->items);
    p->items = NULL;
    p->count = p->cap = 0;
    p->magic = 0;
}

hprops *internal_props_of(OfxPropertySetHandle h)
{
    hprops *p = (hprops *)h;
    return p && p->magic == PROPS_MAGIC ? p : NULL;
}

static prop *prop_find(hprops *p, const char *name)
{
    for (int i = 0; i < p->count; i++)
        if (!strcmp(p->items[i].name, name)) return &p->items[i];
    return NULL;
}

/* The property `name` of `type` with at least `dim` values, created (zeroed) when absent. */
static OfxStatus prop_get_for_set(hprops *p, const char *name, ptype type, int dim, prop **out)
{
    prop *q = prop_find(p, name);
    if (q && q->type != type) return kOfxStatErrValue;
    if (!q) {
        if (p->count == p->cap) {
            int cap = p->cap ? p->cap * 2 : 16;
            prop *items = realloc(p->items, (size_t)cap * sizeof *items);
            if (!items) return kOfxStatErrMemory;
            p->items = items;
            p->cap = cap;
        }
        q = &p->items[p->count];
        memset(q, 0, sizeof *q);
        if (!(q->name = strdup(name))) return kOfxStatErrMemory;
        q->type = type;
        p->count++;
    }
    if (dim > q->dim) {
        size_t esize = type == PT_INT      ? sizeof(int)
                       : type == PT_DOUBLE ? sizeof(double)
                                           : sizeof(void *);
        void *v = realloc(q->v.p, (size_t)dim * esize);
        if (!v) return kOfxStatErrMemory;
        memset((char *)v + (size_t)q->dim * esize, 0, (size_t)(dim - q->dim) * esize);
        q->v.p = v;
        q->dim = dim;
    }
    *out = q;
    return kOfxStatOK;
}

static OfxStatus prop_get_for_get(OfxPropertySetHandle h, const char *name, ptype type, int index,
                                  prop **out)
{
    hprops *p = internal_props_of(h);
    if (!p || !name) return kOfxStatErrBadHandle;
    prop *q = prop_find(p, name);
    if (!q) return kOfxStatErrUnknown;
    if (q->type != type) return kOfxStatErrValue;
    if (index < 0 || index >= q->dim) return kOfxStatErrBadIndex;
    *out = q;
    return kOfxStatOK;
}

OfxStatus internal_set_pointer(OfxPropertySetHandle h, const char *name, int i, void *v)
{
    prop *q;
    hprops *p = internal_props_of(h);
    if (!p || i < 0) return kOfxStatErrBadHandle;
    OfxStatus st = prop_get_for_set(p, name, PT_POINTER, i + 1, &q);
    if (st == kOfxStatOK) q->v.p[i] = v;
    return st;
}

OfxStatus internal_set_string(OfxPropertySetHandle h, const char *name, int i, const char *v)
{
    prop *q;
    hprops *p = internal_props_of(h);
    if (!p || i < 0) return kOfxStatErrBadHandle;
    OfxStatus st = prop_get_for_set(p, name, PT_STRING, i + 1, &q);
    if (st != kOfxStatOK) return st;
    char *copy = strdup(v ? v : ""); /* the host owns its copy of every string */
    if (!copy) return kOfxStatErrMemory;
    free(q->v.s[i]);
    q->v.s[i] = copy;
    return kOfxStatOK;
}

OfxStatus internal_set_double(OfxPropertySetHandle h, const char *name, int i, double v)
{
    prop *q;
    hprops *p = internal_props_of(h);
    if (!p || i < 0) return kOfxStatErrBadHandle;
    OfxStatus st = prop_get_for_set(p, name, PT_DOUBLE, i + 1, &q);
    if (st == kOfxStatOK) q->v.d[i] = v;
    return st;
}

OfxStatus internal_set_int(OfxPropertySetHandle h, const char *name, int i, int v)
{
    prop *q;
    hprops *p = internal_props_of(h);
    if (!p || i < 0) return kOfxStatErrBadHandle;
    OfxStatus st = prop_get_for_set(p, name, PT_INT, i + 1, &q);
    if (st == kOfxStatOK) q->v.i[i] = v;
    return st;
}

static OfxStatus set_pointer_n(OfxPropertySetHandle h, const char *name, int n, void *const *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = n - 1; i >= 0 && st == kOfxStatOK; i--)
        st = internal_set_pointer(h, name, i, v[i]);
    return st;
}
static OfxStatus set_string_n(OfxPropertySetHandle h, const char *name, int n, const char *const *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = n - 1; i >= 0 && st == kOfxStatOK; i--)
        st = internal_set_string(h, name, i, v[i]);
    return st;
}
OfxStatus internal_set_double_n(OfxPropertySetHandle h, const char *name, int n, const double *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = n - 1; i >= 0 && st == kOfxStatOK; i--)
        st = internal_set_double(h, name, i, v[i]);
    return st;
}
OfxStatus internal_set_int_n(OfxPropertySetHandle h, const char *name, int n, const int *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = n - 1; i >= 0 && st == kOfxStatOK; i--)
        st = internal_set_int(h, name, i, v[i]);
    return st;
}

static OfxStatus get_pointer(OfxPropertySetHandle h, const char *name, int i, void **v)
{
    prop *q;
    OfxStatus st = prop_get_for_get(h, name, PT_POINTER, i, &q);
    if (st == kOfxStatOK) *v = q->v.p[i];
    return st;
}
OfxStatus internal_get_string(OfxPropertySetHandle h, const char *name, int i, char **v)
{
    prop *q;
    OfxStatus st = prop_get_for_get(h, name, PT_STRING, i, &q);
    if (st == kOfxStatOK) *v = q->v.s[i];
    return st;
}
OfxStatus internal_get_double(OfxPropertySetHandle h, const char *name, int i, double *v)
{
    prop *q;
    OfxStatus st = prop_get_for_get(h, name, PT_DOUBLE, i, &q);
    if (st == kOfxStatOK) *v = q->v.d[i];
    return st;
}
OfxStatus internal_get_int(OfxPropertySetHandle h, const char *name, int i, int *v)
{
    prop *q;
    OfxStatus st = prop_get_for_get(h, name, PT_INT, i, &q);
    if (st == kOfxStatOK) *v = q->v.i[i];
    return st;
}
static OfxStatus get_pointer_n(OfxPropertySetHandle h, const char *name, int n, void **v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = 0; i < n && st == kOfxStatOK; i++)
        st = get_pointer(h, name, i, &v[i]);
    return st;
}
static OfxStatus get_string_n(OfxPropertySetHandle h, const char *name, int n, char **v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = 0; i < n && st == kOfxStatOK; i++)
        st = internal_get_string(h, name, i, &v[i]);
    return st;
}
OfxStatus internal_get_double_n(OfxPropertySetHandle h, const char *name, int n, double *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = 0; i < n && st == kOfxStatOK; i++)
        st = internal_get_double(h, name, i, &v[i]);
    return st;
}
static OfxStatus get_int_n(OfxPropertySetHandle h, const char *name, int n, int *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = 0; i < n && st == kOfxStatOK; i++)
        st = internal_get_int(h, name, i, &v[i]);
    return st;
}

static OfxStatus prop_reset(OfxPropertySetHandle h, const char *name)
{
    hprops *p = internal_props_of(h);
    if (!p) return kOfxStatErrBadHandle;
    prop *q = prop_find(p, name);
    if (!q) return kOfxStatErrUnknown;
    /* a choice's options default to none (a plug-in resets them to list others) */
    if (!strcmp(name, kOfxParamPropChoiceOption) && q->type == PT_STRING) {
        for (int i = 0; i < q->dim; i++)
            free(q->v.s[i]);
        q->dim = 0;
    }
    return kOfxStatOK; /* no other defaults are tracked: values stay as they are */
}

static OfxStatus prop_dimension(OfxPropertySetHandle h, const char *name, int *count)
{
    hprops *p = internal_props_of(h);
    if (!p) return kOfxStatErrBadHandle;
    prop *q = prop_find(p, name);
    if (!q) return kOfxStatErrUnknown;
    *count = q->dim;
    return kOfxStatOK;
}

const OfxPropertySuiteV1 internal_property_suite = {
    internal_set_pointer, internal_set_string, internal_set_double,   internal_set_int,
    set_pointer_n,        set_string_n,        internal_set_double_n, internal_set_int_n,
    get_pointer,          internal_get_string, internal_get_double,   internal_get_int,
    get_pointer_n,        get_string_n,        internal_get_double_n, get_int_n,
    prop_reset,           prop_dimension};

/* Copy every property of src into dst (dst's own values of the same names are replaced). */
OfxStatus internal_props_copy(hprops *dst, const hprops *src)
{
    for (int i = 0; i < src->count; i++) {
        const prop *q = &src->items[i];
        OfxPropertySetHandle d = (OfxPropertySetHandle)dst;
        OfxStatus st = kOfxStatOK;
        for (int k = q->dim - 1; k >= 0 && st == kOfxStatOK; k--)
            switch (q->type) {
            case PT_INT:
                st = internal_set_int(d, q->name, k, q->v.i[k]);
                break;
            case PT_DOUBLE:
                st = internal_set_double(d, q->name, k, q->v.d[k]);
                break;
            case PT_STRING:
                st = internal_set_string(d, q->name, k, q->v.s[k]);
                break;
            case PT_POINTER:
                st = internal_set_pointer(d, q->name, k, q->v.p[k]);
                break;
            }
        if (st != kOfxStatOK) return st;
    }
    return kOfxStatOK;
}

const char *internal_pstr(hprops *p, const char *name, int i, const char *fallback)
{
    char *v = NULL;
    return internal_get_string((OfxPropertySetHandle)p, name, i, &v) == kOfxStatOK && v ? v
                                                                                        : fallback;
}
int internal_pint(hprops *p, const char *name, int i, int fallback)
{
    int v;
    return internal_get_int((OfxPropertySetHandle)p, name, i, &v) == kOfxStatOK ? v : fallback;
}
int internal_pdim(hprops *p, const char *name)
{
    int n = 0;
    return prop_dimension((OfxPropertySetHandle)p, name, &n) == kOfxStatOK ? n : 0;
}
