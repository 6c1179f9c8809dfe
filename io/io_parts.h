/* nprfx I/O (libnprfx-io) — what a file holds and what a read takes of it (io_parts.cpp, OpenImageIO): the
 * parts, views and channels the reader and the writer share. C++ only. */
#ifndef NPRFX_CLI_IO_PARTS_H
#define NPRFX_CLI_IO_PARTS_H

#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "nprfx/io.h"

namespace io_internal
{

using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;

/* One part (subimage) of a file, as its header describes it. */
struct part {
    int index = 0;
    ImageSpec spec;
    std::string name; /* oiio:subimagename, "" when unnamed */
    std::string view; /* the part's "view" attribute (multi-part stereo), "" when none */
    int miplevels = 1;
};

struct header {
    std::string format;
    std::vector<part> parts;
    std::vector<std::string> views; /* views[0] is the default view; empty: not multi-view */
};

/* A channel a read delivers: file channel c of part p under its final, plate-unique name. */
struct chan {
    const part *p;
    int c;
    std::string name;
    unsigned char type; /* nprfx_pixel_type */
};

/* What a read takes: parts of one data and display window, one view, and what to tell. */
struct choice {
    std::vector<const part *> group;
    std::vector<chan> chans;
    std::string view;
    std::string note;
    bool warn = false;
};

/* An error found while choosing: raised by the caller (nprfx info reports a file it cannot read
 * instead of failing). */
struct failure {
    nprfx_result code = NPRFX_OK;
    std::string message;
};

/* OIIO's per-thread error string, taken (and cleared). */
std::string oiio_error(const ImageInput *in);
std::string oiio_error(const ImageOutput *out);
/* A part as messages name it: its index and, when it has one, its name. */
std::string part_label(const part &p);
/* A spec's data and display windows. */
nprfx_rect data_rect(const ImageSpec &s);
nprfx_rect display_rect(const ImageSpec &s);
/* Open path and describe every part and the file's views into h. */
nprfx_result scan(nprfx_context *ctx, const char *path, std::unique_ptr<ImageInput> &in, header &h);
/* Choose the parts and view a read takes (docs/design.md §2.3). */
failure choose(const char *path, const header &h, const nprfx_read_options &o, choice &ch);
/* malloc'd copies for the C side (NULL on no memory). */
char *dup_cstr(const std::string &s);
char **dup_names(const std::vector<std::string> &v);
/* s into a fixed-size field, truncated and terminated. */
void copy_field(char *dst, size_t n, const std::string &s);

} // namespace io_internal
#endif
