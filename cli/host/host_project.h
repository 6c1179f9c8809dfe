/* nprfx CLI — a graph as compositing hosts see it (nprfx host-project): read nodes, the Shuffles
 * (and sign flips) that put each set of plate channels a node input takes into RGBA, the OpenFX
 * nodes with their clips, non-default params and channel selectors, and the write nodes.
 * host_project.c builds it with the runner's own graph loading and channel resolution, so the
 * host files (host_natron.c, host_natron_py.c, host_nuke.c) say what `nprfx run` does. */
#ifndef NPRFX_CLI_HOST_PROJECT_H
#define NPRFX_CLI_HOST_PROJECT_H

#include <stdio.h>

#include "look_desc.h"
#include "nprfx/graph.h"

#define NPRFX_HOST_NAME_MAX 96

/* One set of plate channels a node input takes: a Shuffle of the read node into R, G, B, A and,
 * where the runner transforms the channels (the read node's "vectors"), a Multiply after it. */
typedef struct host_chanset {
    int read;          /* graph index of the read node */
    int count;         /* components R.. filled, 1 to 4 */
    char want[4][128]; /* the channels as the runner names them (motion_prev.X) */
    char chan[4][128]; /* the plate channels the Shuffle takes (ViewLayer.Vector.X) */
    int rank[4];       /* their position among the plate's channels, layer by layer */
    int layer_pos[4];  /* and inside their layer */
    double sign[4];    /* the runner's factor on each (1 but for motion vectors) */
    int has_sign;      /* some sign is not 1: a Multiply follows the Shuffle */
    char shuffle[NPRFX_HOST_NAME_MAX]; /* host node names */
    char multiply[NPRFX_HOST_NAME_MAX];
    const char *out; /* what nodes connect to: multiply when has_sign, else shuffle */
} host_chanset;

/* Input k of an OpenFX node: its source and the selector option that picks its channels. */
typedef struct host_link {
    const char *src;   /* host node name, NULL: not connected */
    int option;        /* position among ofx_names_selector_options */
    const char *label; /* that option's label ("RG") */
} host_link;

typedef struct host_node {
    const nprfx_graph_node_info *n;
    char plugin_id[NPRFX_HOST_NAME_MAX];
    char name[NPRFX_HOST_NAME_MAX];
    int clips[32]; /* input indices in the order hosts number the clips */
    int nclips;
    host_link *links; /* per descriptor input */
    int look;         /* a look plug-in (look_desc.h): no channel selectors, no design width */
} host_node;

typedef struct host_read {
    const nprfx_graph_node_info *n;
    char name[NPRFX_HOST_NAME_MAX];
    char path[4096]; /* relative to the project file's folder where possible */
} host_read;

typedef struct host_write {
    const nprfx_graph_node_info *n;
    char name[NPRFX_HOST_NAME_MAX];
    const char *src;
    const char *path; /* as in the graph: relative paths are taken from the project's folder */
} host_write;

typedef struct host_project {
    nprfx_graph *g;
    nprfx_graph_node_info *info; /* every node of g, by index: what the host nodes point at */
    const char *graph_path;
    int first_frame, last_frame;
    int width, height;    /* the first read node's data window */
    int design_width;     /* the graph's "design_width" (0: none), each node's designWidth */
    char format_name[64]; /* the project format's name, from the output file's name */
    host_read *reads;     /* in graph order */
    int nreads;
    host_chanset *sets;
    int nsets;
    host_node *nodes; /* OpenFX nodes, inputs before the nodes that use them */
    int nnodes;
    host_write *writes;
    int nwrites;
    /* a look project (host_project_build with a look): per output, the look node's view of
     * itself and its params' values */
    nprfx_graph_node_info *look_nodes;
    nprfx_value *look_values;
} host_project;

/* Build the host view of graph g (loaded from graph_path) for a project file written into
 * out_dir; errors (raised on g's context) name the node the hosts cannot express. With a look
 * (look_desc.h: g's, with its knobs' values), the project is the graph's reads and one look node
 * per output instead of the graph's nodes: a multi-plane host's Source takes the read whole
 * (planar), else every AOV clip gets its Shuffle of the read. */
nprfx_result host_project_build(nprfx_graph *g, const char *graph_path, const char *out_dir,
                                const char *out_file, const look_desc *look, int planar,
                                host_project *hp);
void host_project_free(host_project *hp);

/* The designWidth knob node d gets: the graph's design width where d has params in pixels, else 0
 * (no knob). */
int host_design_width(const host_project *hp, const nprfx_node_desc *d);
/* Whether param i of node n differs from the descriptor's default. */
int host_param_changed(const nprfx_graph_node_info *n, int i);
/* A double in the fewest digits that read back as the same value (0.05, not 0.0500...03). */
char *host_double(double v, char *buf, size_t n);

/* A plate channel of the colour plane (plain "R", "G", "B", "A", no layer): its component 0-3,
 * which hosts offer as their own RGBA of the input (Natron's Shuffle: "A.r" .. "A.a"), apart
 * from the layers; -1 for any other channel. */
int host_color_component(const char *channel);

/* Natron's Shuffle option for plate channel `channel` on its A input: "A.r" .. "A.a" for the
 * colour plane, "A.<channel>" for a layer's. */
void host_natron_option(const char *channel, char *out, size_t n);

#endif
