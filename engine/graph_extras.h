/* nprfx graph engine — the channels a read node appends to its plates (graph_extras.c): motion in
 * nprfx's convention, object ids decoded from Cryptomatte, depth from 1/z. Never installed. */
#ifndef NPRFX_ENGINE_GRAPH_EXTRAS_H
#define NPRFX_ENGINE_GRAPH_EXTRAS_H

#include "graph_model.h"

enum { GRAPH_EXTRA_MAX = 9 };

/* How each appended channel is made from at most two of the plate's channels. */
typedef struct gextra {
    int count;
    int src[GRAPH_EXTRA_MAX][2];
    double scale[GRAPH_EXTRA_MAX];
    int op[GRAPH_EXTRA_MAX];
} gextra;

/* The names of the 4 motion channels a read node appends (motion_prev.X, ...). */
extern const char *const internal_graph_motion_names[4];

/* The motion convention read node n applies: the one its first frame showed (graph_aovs.c), or
 * before that the one "vectors" names; NULL: none. */
const nprfx_aov_vectors *internal_graph_vectors(const gnode *n);
/* How many channels n appends, and the name of the k-th. */
int internal_graph_extra_count(const gnode *n);
const char *internal_graph_extra_name(const gnode *n, int k);
/* The appended channels that hold canonical AOV `aov`, as a selection; NULL when none. */
const char *internal_graph_extra_for(const gnode *n, int aov);
/* The k-th selection of plate channels the appended ones are made of (for the reads' wants);
 * NULL past the last. */
const char *internal_graph_extra_want(const gnode *n, int k);
/* The plate channels (indices into names) each appended channel is made of; an error names the
 * file and the channel that is missing. */
nprfx_result internal_graph_extras(nprfx_graph *g, const gnode *n, const char *file,
                                   const char *const *names, int nc, gextra *x);
/* Fill the appended channels of a plate's pixels: src holds the plate's nc channels per pixel
 * over bounds, dst nn >= nc + x->count per pixel, its first nc already copied; display is the
 * plate's display window, on which a position made from depth is centred. One channel at a
 * time over the whole plate: the loops stay simple enough to vectorise. */
void internal_graph_extra_fill(const gextra *x, const float *src, int nc, float *dst, int nn,
                               nprfx_rect bounds, nprfx_rect display);

/* Read node n's motion convention: the plate channels the 4 motion channels are made of, and the
 * factor each is multiplied by. */
nprfx_result internal_graph_motion_sources(nprfx_graph *g, const gnode *n, const char *file,
                                           const char *const *names, int nc, int *idx,
                                           double *sign);

#endif
