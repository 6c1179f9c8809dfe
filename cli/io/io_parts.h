/* nprfx CLI — what a file holds and what a read takes of it (io_parts.cpp, OpenImageIO): the
 * parts, views and channels the reader and the writer share. C++ only. */
#ifndef NPRFX_CLI_IO_PARTS_H
#define NPRFX_CLI_IO_PARTS_H

#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "io.h"

namespace cli_io
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
    unsigned char type; /* cli_pixel_type */
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

std::string oiio_error(const ImageInput *in);
std::string oiio_error(const ImageOutput *out);
std::string part_label(const part &p);
std::string rect_text(nprfx_rect r);
nprfx_rect data_rect(const ImageSpec &s);
nprfx_rect display_rect(const ImageSpec &s);
bool same_windows(const ImageSpec &a, const ImageSpec &b);
unsigned char pixel_type(const header &h, const ImageSpec &s, int c);
nprfx_result scan(nprfx_context *ctx, const char *path, std::unique_ptr<ImageInput> &in, header &h);
std::vector<std::string> split_dots(const std::string &s);
std::string channel_view(const header &h, const part &p, const std::string &name,
                         std::string &bare);
std::vector<chan> group_channels(const header &h, const std::vector<const part *> &group,
                                 const std::string &view);
bool holds_all(const std::vector<chan> &chans, const cli_read_options &o);
failure refuse_part(const char *path, const part &p);
std::string list_text(const std::vector<std::string> &v);
failure choose(const char *path, const header &h, const cli_read_options &o, choice &ch);
char *dup_cstr(const std::string &s);
char **dup_names(const std::vector<std::string> &v);
void copy_field(char *dst, size_t n, const std::string &s);

} // namespace cli_io
#endif
