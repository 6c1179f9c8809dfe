/* nprfx OpenFX adapter — what the host is told about a node before any instance exists
 * (ofx_describe.c). */
#ifndef NPRFX_OFX_DESCRIBE_H
#define NPRFX_OFX_DESCRIBE_H

#include "nprfx/node.h"
#include "ofx_api.h"

/* The describe action: the effect's properties for node d (label, help, grouping, version,
 * contexts, depths, threading, tiles, temporal access). kOfxStatErrMissingHostFeature, with a
 * logged reason, for a node that needs other frames in a host that cannot give them. */
OfxStatus ofx_describe(const nprfx_node_desc *d, OfxImageEffectHandle fx);

/* The describeInContext action: the clips and params of d in the context in_args names
 * (General, or Filter where d can run on one clip); kOfxStatErrUnsupported in any other. */
OfxStatus ofx_describe_in_context(const nprfx_node_desc *d, OfxImageEffectHandle fx,
                                  OfxPropertySetHandle in_args);

/* Define param p of a node under `name` and `label`: its type, range, soft range, choices and
 * help (after `lead`, a look's words on it, when given), with default `def` (NULL: the
 * descriptor's). The node plug-ins define their params with it, the look plug-ins their knobs. */
OfxStatus ofx_define_param(OfxParamSetHandle ps, const nprfx_param_desc *p, const char *name,
                           const char *label, const char *lead, const nprfx_value *def);

/* Analyze Shot: the push button and the hidden string param that keeps what it measured, for d
 * (a node that measures over its shot, or a look); `what` completes "Measure what ..." in the
 * hint. name receives the button's name. */
OfxStatus ofx_define_analyze(OfxParamSetHandle ps, const nprfx_node_desc *d, const char *what,
                             char *name, size_t n);

/* A plug-in that needs other frames, in a host without temporal clip access: not offered, with
 * the reason logged ("nprfx: WHO is not available in this host: READS, and ..."). Returns
 * kOfxStatErrMissingHostFeature. */
OfxStatus ofx_describe_refuse(OfxImageEffectHandle fx, const char *who, const char *reads);
/* A plug-in this host cannot run, for the reason why: logged as "nprfx: WHO is not available in
 * this host: WHY". Returns kOfxStatErrMissingHostFeature. */
OfxStatus ofx_describe_unavailable(OfxImageEffectHandle fx, const char *who, const char *why);
/* The effect's label, short and long alike. */
void ofx_describe_labels(OfxPropertySetHandle p, const char *label);

#endif
