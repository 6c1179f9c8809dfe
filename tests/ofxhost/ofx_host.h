/* nprfx OpenFX test host — a minimal OpenFX host that runs graph nodes through the plug-in
 * bundle instead of calling their render functions:
 * `nprfx-ofxtest run GRAPH --ofx build/plugins/ofx/nprfx.ofx.bundle`.
 *
 * It proves the OFX path (the adapter in plugins/ofx/) gives the same pixels as the direct path;
 * it is not a substitute for real hosts. It loads the bundle with dlopen, describes every plug-in
 * (checking that each param's type, default and ranges match the node's descriptor), creates
 * one instance per graph node, sets params and channel selectors from the graph, serves clip
 * images from the runner's inputs (at other times through the runner's fetch), and copies the
 * rendered window back. A profile (--profile) makes it behave as a real host does where hosts
 * differ (contexts, pixel depths, temporal access, message formatting; profile.c). It is a test
 * program, never part of the shipped runner. */
#ifndef NPRFX_TESTS_OFX_HOST_H
#define NPRFX_TESTS_OFX_HOST_H

#include "nprfx/graph.h"
#include "nprfx/nprfx.h"

typedef struct nprfx_ofx_host nprfx_ofx_host;

/* Load BUNDLE (an "X.ofx.bundle" folder or the .ofx binary inside it), load and describe all its
 * plug-ins as the host of `profile` would (profile.c: strict, natron, mlt, mlt16; NULL: strict).
 * Errors go to ctx; its executor backs the multithread suite. One host per process. */
nprfx_result nprfx_ofx_host_open(nprfx_context *ctx, const char *bundle, const char *profile,
                                 nprfx_ofx_host **out);

/* --footage: render every node whose flow-derivable inputs (ofx_derive.h) are connected to a
 * flow node in the Filter context, with Source the picture that flow node reads instead of
 * those inputs: the plug-in derives them itself, and the graph is the equivalent General one
 * (tests/cli/ofx_footage.sh). Flow nodes then render as the runner renders them (only their
 * size matters). */
void nprfx_ofx_host_set_footage(nprfx_ofx_host *h, int on);

/* --analyze-shot: before a node's first render, press its Analyze Shot button, as a user does
 * (an instance-changed action in which the plug-in fetches its clips at every frame of the
 * shot); the first render must then fetch exactly the frames it declares. */
void nprfx_ofx_host_set_analyze(nprfx_ofx_host *h, int on);

/* Number of plug-ins the bundle exports. */
int nprfx_ofx_host_plugin_count(const nprfx_ofx_host *h);
/* The profile's name. */
const char *nprfx_ofx_host_profile(const nprfx_ofx_host *h);
/* The identifier of plug-in i when it is unavailable in this host (refused to load, or has no
 * context the host supports), with the reason; NULL when it is available. */
const char *nprfx_ofx_host_unavailable(const nprfx_ofx_host *h, int i, const char **reason);

/* The hook to pass in nprfx_graph_options.hook; valid until the host is closed. */
const nprfx_render_hook *nprfx_ofx_host_hook(nprfx_ofx_host *h);

/* Unload the plug-ins and the bundle. Free every graph using the hook first (that destroys the
 * instances). NULL is ignored. */
void nprfx_ofx_host_close(nprfx_ofx_host *h);

#endif
