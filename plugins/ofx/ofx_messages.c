/* nprfx OpenFX adapter — telling the user (declared in ofx_messages.h): errors go to the host's
 * message suite as finished text, as a persistent message on the effect where the host has suite
 * version 2 (a host shows it on the node until cleared), else as a plain message. */
#include <stdio.h>
#include <string.h>

#include "ofx_messages.h"
#include "ofx_suites.h"

/* The text as a format that prints itself: '%' doubled, so no conversion is left. Some hosts
 * (Natron 2.5) hand their va_list to a second variadic formatter, so a "%s" argument comes out
 * empty there, while a format without conversions prints the same everywhere. */
static void as_format(const char *message, char *text, size_t size)
{
    size_t n = 0;
    for (const char *c = message; *c && n + 2 < size; c++) {
        if (*c == '%') text[n++] = '%';
        text[n++] = *c;
    }
    text[n] = 0;
}

void ofx_post(void *handle, const char *type, const char *message)
{
    if (!ofx_g.msg || !ofx_g.msg->message || !message) return;
    char text[2048];
    as_format(message[0] ? message : "nprfx: an error without a message", text, sizeof text);
    (void)ofx_g.msg->message(handle, type, "", text);
}

void ofx_post_error(ofx_instance *inst, const char *message)
{
    ofx_post_error_on(inst->fx, &inst->persistent, message);
}

void ofx_clear_error(ofx_instance *inst)
{
    ofx_clear_error_on(inst->fx, &inst->persistent);
}

void ofx_post_error_on(OfxImageEffectHandle fx, int *persistent, const char *message)
{
    const OfxMessageSuiteV2 *m2 = ofx_g.msg2;
    if (!m2 || !m2->setPersistentMessage) {
        ofx_post(fx, kOfxMessageError, message);
        return;
    }
    char text[2048];
    as_format(message && message[0] ? message : "nprfx: an error without a message", text,
              sizeof text);
    if (m2->setPersistentMessage(fx, kOfxMessageError, "", text) == kOfxStatOK)
        __atomic_store_n(persistent, 1, __ATOMIC_RELAXED);
    else
        ofx_post(fx, kOfxMessageError, message);
}

void ofx_clear_error_on(OfxImageEffectHandle fx, int *persistent)
{
    const OfxMessageSuiteV2 *m2 = ofx_g.msg2;
    if (!m2 || !m2->clearPersistentMessage) return;
    if (__atomic_exchange_n(persistent, 0, __ATOMIC_RELAXED)) (void)m2->clearPersistentMessage(fx);
}
