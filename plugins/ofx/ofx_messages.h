/* nprfx OpenFX adapter — messages to the user through the host's message suite (ofx_messages.c).
 * Without a message suite they go nowhere, and errors reach the host only as a status. */
#ifndef NPRFX_OFX_MESSAGES_H
#define NPRFX_OFX_MESSAGES_H

#include "ofx_api.h"
#include "ofx_instance.h"

/* Post a message of `type` (kOfxMessage...) through the message suite, as finished text;
 * handle: the effect (or its descriptor) it is about. */
void ofx_post(void *handle, const char *type, const char *message);
/* Post an error to the host: a persistent message on the effect where the host has message
 * suite V2, else a message; nothing without a message suite. */
void ofx_post_error(ofx_instance *inst, const char *message);
/* A successful render takes down the persistent error of an earlier one. */
void ofx_clear_error(ofx_instance *inst);
/* The same for any effect whose flag *persistent says a persistent message is up (the look
 * plug-ins' instances). */
void ofx_post_error_on(OfxImageEffectHandle fx, int *persistent, const char *message);
void ofx_clear_error_on(OfxImageEffectHandle fx, int *persistent);

#endif
