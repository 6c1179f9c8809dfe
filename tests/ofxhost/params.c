/* nprfx OpenFX test host — the parameter suite: params defined in describeInContext with the
 * types a host knows, and their values without animation (every time gives the current value;
 * keys, derivatives, integrals and copies are unsupported). */
#define _POSIX_C_SOURCE 200809L /* strdup */
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "ofx_host_internal.h"

int internal_type_is(const hparam *p, const char *t)
{
    return !strcmp(p->type, t);
}

static OfxStatus pm_define(OfxParamSetHandle ps, const char *type, const char *name,
                           OfxPropertySetHandle *out)
{
    static const char *const known[] = {
        kOfxParamTypeInteger, kOfxParamTypeDouble, kOfxParamTypeBoolean,  kOfxParamTypeChoice,
        kOfxParamTypeRGBA,    kOfxParamTypeRGB,    kOfxParamTypeDouble2D, kOfxParamTypeInteger2D,
        kOfxParamTypeString,  kOfxParamTypeGroup,  kOfxParamTypePage,     kOfxParamTypePushButton};
    heffect *e = internal_effect_of(ps);
    if (!e || !type || !name) return kOfxStatErrBadHandle;
    if (e->ni) return kOfxStatErrUnsupported;
    int ok = 0;
    for (size_t i = 0; i < sizeof known / sizeof known[0]; i++)
        ok |= !strcmp(type, known[i]);
    if (!ok) return kOfxStatErrUnknown;
    if (internal_effect_param(e, name)) return kOfxStatErrExists;
    hparam *p = internal_param_add(e, type, name);
    if (!p) return kOfxStatErrMemory;
    OfxPropertySetHandle pp = (OfxPropertySetHandle)&p->props;
    internal_set_string(pp, kOfxPropType, 0, kOfxTypeParameter);
    internal_set_string(pp, kOfxPropName, 0, name);
    internal_set_string(pp, kOfxPropLabel, 0, name);
    internal_set_string(pp, kOfxParamPropType, 0, type);
    internal_set_string(pp, kOfxParamPropScriptName, 0, name);
    internal_set_string(pp, kOfxParamPropHint, 0, "");
    internal_set_int(pp, kOfxParamPropAnimates, 0, 1);
    if (out) *out = pp;
    return kOfxStatOK;
}

static OfxStatus pm_get_handle(OfxParamSetHandle ps, const char *name, OfxParamHandle *param,
                               OfxPropertySetHandle *props)
{
    heffect *e = internal_effect_of(ps);
    if (!e || !name) return kOfxStatErrBadHandle;
    hparam *p = internal_effect_param(e, name);
    if (!p) return kOfxStatErrUnknown;
    if (param) *param = (OfxParamHandle)p;
    if (props) *props = (OfxPropertySetHandle)&p->props;
    return kOfxStatOK;
}

static OfxStatus pm_set_get_props(OfxParamSetHandle ps, OfxPropertySetHandle *out)
{
    heffect *e = internal_effect_of(ps);
    if (!e || !out) return kOfxStatErrBadHandle;
    *out = (OfxPropertySetHandle)&e->props;
    return kOfxStatOK;
}

static OfxStatus pm_get_props(OfxParamHandle param, OfxPropertySetHandle *out)
{
    hparam *p = internal_param_of(param);
    if (!p || !out) return kOfxStatErrBadHandle;
    *out = (OfxPropertySetHandle)&p->props;
    return kOfxStatOK;
}

int internal_param_dims(const hparam *p, int *is_int)
{
    *is_int =
        internal_type_is(p, kOfxParamTypeInteger) || internal_type_is(p, kOfxParamTypeBoolean) ||
        internal_type_is(p, kOfxParamTypeChoice) || internal_type_is(p, kOfxParamTypeInteger2D);
    if (internal_type_is(p, kOfxParamTypeRGBA)) return 4;
    if (internal_type_is(p, kOfxParamTypeRGB)) return 3;
    if (internal_type_is(p, kOfxParamTypeDouble2D) || internal_type_is(p, kOfxParamTypeInteger2D))
        return 2;
    if (internal_type_is(p, kOfxParamTypeInteger) || internal_type_is(p, kOfxParamTypeBoolean) ||
        internal_type_is(p, kOfxParamTypeChoice) || internal_type_is(p, kOfxParamTypeDouble))
        return 1;
    return 0; /* strings, pages, groups, buttons */
}

/* No animation: every time gives the current value. */
static OfxStatus param_get(hparam *p, va_list ap)
{
    int is_int;
    int n = internal_param_dims(p, &is_int);
    if (internal_type_is(p, kOfxParamTypeString)) {
        char **s = va_arg(ap, char **);
        *s = p->s;
        return kOfxStatOK;
    }
    if (!n) return kOfxStatErrBadHandle;
    for (int k = 0; k < n; k++) {
        if (is_int)
            *va_arg(ap, int *) = n == 1 ? p->i : (int)p->d[k];
        else
            *va_arg(ap, double *) = p->d[k];
    }
    return kOfxStatOK;
}

static OfxStatus param_set(hparam *p, va_list ap)
{
    int is_int;
    int n = internal_param_dims(p, &is_int);
    if (internal_type_is(p, kOfxParamTypeString)) {
        char *s = strdup(va_arg(ap, const char *));
        if (!s) return kOfxStatErrMemory;
        free(p->s);
        p->s = s;
        return kOfxStatOK;
    }
    if (!n) return kOfxStatErrBadHandle;
    for (int k = 0; k < n; k++) {
        if (is_int && n == 1)
            p->i = va_arg(ap, int);
        else if (is_int)
            p->d[k] = va_arg(ap, int);
        else
            p->d[k] = va_arg(ap, double);
    }
    return kOfxStatOK;
}

static OfxStatus pm_get_value(OfxParamHandle param, ...)
{
    hparam *p = internal_param_of(param);
    if (!p) return kOfxStatErrBadHandle;
    va_list ap;
    va_start(ap, param);
    OfxStatus st = param_get(p, ap);
    va_end(ap);
    return st;
}

static OfxStatus pm_get_value_at_time(OfxParamHandle param, OfxTime time, ...)
{
    hparam *p = internal_param_of(param);
    if (!p) return kOfxStatErrBadHandle;
    va_list ap;
    va_start(ap, time);
    OfxStatus st = param_get(p, ap);
    va_end(ap);
    return st;
}

static OfxStatus pm_get_derivative(OfxParamHandle param, OfxTime time, ...)
{
    (void)param;
    (void)time;
    return kOfxStatErrUnsupported;
}

static OfxStatus pm_get_integral(OfxParamHandle param, OfxTime t1, OfxTime t2, ...)
{
    (void)param;
    (void)t1;
    (void)t2;
    return kOfxStatErrUnsupported;
}

static OfxStatus pm_set_value(OfxParamHandle param, ...)
{
    hparam *p = internal_param_of(param);
    if (!p) return kOfxStatErrBadHandle;
    va_list ap;
    va_start(ap, param);
    OfxStatus st = param_set(p, ap);
    va_end(ap);
    return st;
}

static OfxStatus pm_set_value_at_time(OfxParamHandle param, OfxTime time, ...)
{
    hparam *p = internal_param_of(param);
    if (!p) return kOfxStatErrBadHandle;
    va_list ap;
    va_start(ap, time);
    OfxStatus st = param_set(p, ap);
    va_end(ap);
    return st;
}

static OfxStatus pm_num_keys(OfxParamHandle param, unsigned int *n)
{
    if (!internal_param_of(param) || !n) return kOfxStatErrBadHandle;
    *n = 0;
    return kOfxStatOK;
}
static OfxStatus pm_key_time(OfxParamHandle param, unsigned int nth, OfxTime *time)
{
    (void)nth;
    (void)time;
    return internal_param_of(param) ? kOfxStatErrBadIndex : kOfxStatErrBadHandle;
}
static OfxStatus pm_key_index(OfxParamHandle param, OfxTime time, int dir, int *index)
{
    (void)time;
    (void)dir;
    (void)index;
    return internal_param_of(param) ? kOfxStatFailed : kOfxStatErrBadHandle;
}
static OfxStatus pm_delete_key(OfxParamHandle param, OfxTime time)
{
    (void)time;
    return internal_param_of(param) ? kOfxStatErrBadIndex : kOfxStatErrBadHandle;
}
static OfxStatus pm_delete_all_keys(OfxParamHandle param)
{
    return internal_param_of(param) ? kOfxStatOK : kOfxStatErrBadHandle;
}
static OfxStatus pm_copy(OfxParamHandle to, OfxParamHandle from, OfxTime offset,
                         const OfxRangeD *range)
{
    (void)to;
    (void)from;
    (void)offset;
    (void)range;
    return kOfxStatErrUnsupported;
}
static OfxStatus pm_edit_begin(OfxParamSetHandle ps, const char *name)
{
    (void)name;
    return internal_effect_of(ps) ? kOfxStatOK : kOfxStatErrBadHandle;
}
static OfxStatus pm_edit_end(OfxParamSetHandle ps)
{
    return internal_effect_of(ps) ? kOfxStatOK : kOfxStatErrBadHandle;
}

const OfxParameterSuiteV1 internal_parameter_suite = {
    pm_define,     pm_get_handle,        pm_set_get_props,   pm_get_props,
    pm_get_value,  pm_get_value_at_time, pm_get_derivative,  pm_get_integral,
    pm_set_value,  pm_set_value_at_time, pm_num_keys,        pm_key_time,
    pm_key_index,  pm_delete_key,        pm_delete_all_keys, pm_copy,
    pm_edit_begin, pm_edit_end};
