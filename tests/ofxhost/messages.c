/* nprfx OpenFX test host — the message suites and what becomes of messages. Every message a
 * plug-in posts is recorded where its handle points: an instance keeps the last one of the render
 * in flight and its persistent one, a plug-in being loaded keeps it as the reason it may refuse
 * to load, and a NULL handle outside loading goes to the host. A failed action's error carries
 * that message; an empty one, or none at all, is itself an error: a user would see a blank box or
 * a bare status code (Natron 2.5 showed blank errors until the adapter stopped passing its text
 * as "%s" plus an argument). Messages that are not errors are also printed, as hosts show them. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "ofx_host_internal.h"

/* The message suite version 2 of ofxMessage.h, under a name of its own so that it never meets a
 * definition of the spec's struct in the adapter's ofx_api.h: the same three members. */
typedef struct host_message_suite_v2 {
    OfxStatus (*message)(void *handle, const char *type, const char *id, const char *format, ...);
    OfxStatus (*setPersistentMessage)(void *handle, const char *type, const char *id,
                                      const char *format, ...);
    OfxStatus (*clearPersistentMessage)(void *handle);
} host_message_suite_v2;

#define QUESTION "OfxMessageQuestion"

/* Natron 2.5's result: the format printed with no arguments. "%%" is a '%'; any other
 * conversion (flags, width, precision and length included) prints nothing, as the arguments
 * were lost on the way. */
static void format_lossy(const char *fmt, char *out, size_t n)
{
    size_t len = 0;
    for (const char *c = fmt; *c && len + 1 < n; c++) {
        if (*c != '%') {
            out[len++] = *c;
            continue;
        }
        if (c[1] == '%') {
            out[len++] = '%';
            c++;
            continue;
        }
        c++;
        while (*c && strchr("-+ #0123456789.*'hlLqjzt", *c))
            c++;
        if (!*c) break; /* a '%' at the end: nothing follows to convert */
    }
    out[len] = 0;
}

static void format_text(const char *fmt, va_list ap, char *out, size_t n)
{
    const hprofile *pf = internal_g_host ? internal_g_host->profile : NULL;
    if (pf && pf->lossy_messages)
        format_lossy(fmt ? fmt : "", out, n);
    else
        vsnprintf(out, n, fmt ? fmt : "", ap);
}

static int is_error(const char *type)
{
    return !strcmp(type, kOfxMessageError) || !strcmp(type, kOfxMessageFatal);
}

/* Record text where the handle points; persistent: setPersistentMessage. */
static void record(void *handle, const char *type, const char *text, int persistent)
{
    nprfx_ofx_host *h = internal_g_host;
    if (!h) return;
    heffect *e = internal_effect_of(handle);
    pthread_mutex_lock(&h->lock);
    if (e && e->ni) {
        snprintf(e->ni->posted, sizeof e->ni->posted, "%s", text);
        e->ni->nposted++;
        if (persistent) snprintf(e->ni->persistent, sizeof e->ni->persistent, "%s", text);
    } else if (h->loading && (!e || e->pl == h->loading)) {
        snprintf(h->loading->reason, sizeof h->loading->reason, "%s", text);
    } else {
        snprintf(h->message, sizeof h->message, "%s", text);
        h->message_seq++;
    }
    pthread_mutex_unlock(&h->lock);
    /* Errors reach the user through the failed action's error; logs are not shown. */
    if (!is_error(type) && strcmp(type, kOfxMessageLog)) fprintf(stderr, "ofx: %s\n", text);
}

static OfxStatus msg_message(void *handle, const char *type, const char *id, const char *fmt, ...)
{
    (void)id;
    char text[HMSG];
    va_list ap;
    va_start(ap, fmt);
    format_text(fmt, ap, text, sizeof text);
    va_end(ap);
    if (!type) type = kOfxMessageMessage;
    if (!strcmp(type, QUESTION)) return kOfxStatFailed; /* not interactive */
    record(handle, type, text, 0);
    return kOfxStatOK;
}

static OfxStatus msg_set_persistent(void *handle, const char *type, const char *id, const char *fmt,
                                    ...)
{
    (void)id;
    char text[HMSG];
    va_list ap;
    va_start(ap, fmt);
    format_text(fmt, ap, text, sizeof text);
    va_end(ap);
    if (!type) type = kOfxMessageError;
    /* The spec allows errors, warnings and messages only. */
    if (!is_error(type) && strcmp(type, kOfxMessageWarning) && strcmp(type, kOfxMessageMessage))
        return kOfxStatErrValue;
    if (!internal_effect_of(handle) || !internal_effect_of(handle)->ni) return kOfxStatErrBadHandle;
    record(handle, type, text, 1);
    return kOfxStatOK;
}

static OfxStatus msg_clear_persistent(void *handle)
{
    heffect *e = internal_effect_of(handle);
    if (!e || !e->ni) return kOfxStatErrBadHandle;
    pthread_mutex_lock(&internal_g_host->lock);
    e->ni->persistent[0] = 0;
    pthread_mutex_unlock(&internal_g_host->lock);
    return kOfxStatOK;
}

static const OfxMessageSuiteV1 suite_v1 = {msg_message};
static const host_message_suite_v2 suite_v2 = {msg_message, msg_set_persistent,
                                               msg_clear_persistent};

const void *internal_message_suite(const hprofile *pf, int version)
{
    if (version == 1) return &suite_v1;
    if (version == 2 && pf->message_v2) return &suite_v2;
    return NULL;
}

void internal_messages_reset(node_inst *ni)
{
    ni->posted[0] = 0;
    ni->nposted = 0;
    ni->host_error[0] = 0;
    ni->message_seq = ni->h->message_seq;
}

nprfx_result internal_failure(node_inst *ni, nprfx_context *ctx, const char *what)
{
    nprfx_ofx_host *h = ni->h;
    const char *id = ni->pl->p->pluginIdentifier;
    char host[HMSG + 16] = "";
    if (ni->host_error[0]) snprintf(host, sizeof host, " [host: %s]", ni->host_error);
    /* The plug-in's words: what it posted during the action, else its persistent message, else
     * what it posted with a NULL handle meanwhile. */
    const char *text = ni->nposted ? ni->posted : "";
    if (!text[0]) text = ni->persistent;
    if (!text[0] && h->message_seq != ni->message_seq) text = h->message;
    if (text[0]) return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "%s %s: %s%s", id, what, text, host);
    return nprfx_error(ctx, NPRFX_ERR_INTERNAL,
                       "%s %s, and the plug-in's error message is empty (%s; profile %s)%s", id,
                       what,
                       ni->nposted ? "it posted an empty text: were its words passed as arguments "
                                     "that this host's formatting drops?"
                                   : "it posted no message",
                       h->profile->name, host);
}
