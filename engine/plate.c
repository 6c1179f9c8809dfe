/* nprfx graph engine — plate and file-info helpers (plate.h): plain C, independent of the image
 * library behind the readers. */
#include <stdlib.h>
#include <string.h>

#include "engine_util.h"
#include "nprfx/io.h"

void nprfx_plate_free(nprfx_plate *p)
{
    if (!p) return;
    engine_names_free(p->names, p->nchannels);
    free(p->pixels);
    free(p->types);
    free(p->note);
    memset(p, 0, sizeof *p);
}

nprfx_image nprfx_plate_view(const nprfx_plate *p, int first, int count)
{
    nprfx_image v;
    memset(&v, 0, sizeof v);
    /* An out-of-range request yields an absent input (data NULL) rather than a view that would
     * read past the pixels; core code is limited to NPRFX_MAX_CHANNELS per view. */
    if (!p || !p->pixels || first < 0 || count < 1 || count > NPRFX_MAX_CHANNELS ||
        first + count > p->nchannels)
        return v;
    v.data = p->pixels + first;
    v.pixel_stride = p->nchannels;
    v.row_stride = (ptrdiff_t)nprfx_rect_width(p->bounds) * p->nchannels;
    v.channels = count;
    v.bounds = p->bounds;
    return v;
}

int nprfx_plate_channel(const nprfx_plate *p, const char *name)
{
    if (!p || !name) return -1;
    for (int i = 0; i < p->nchannels; i++)
        if (p->names[i] && !strcmp(p->names[i], name)) return i;
    return -1;
}

void nprfx_file_info_free(nprfx_file_info *info)
{
    if (!info) return;
    engine_names_free(info->names, info->nchannels);
    engine_names_free(info->types, info->nchannels);
    for (int i = 0; info->parts && i < info->nparts; i++) {
        engine_names_free(info->parts[i].names, info->parts[i].nchannels);
        engine_names_free(info->parts[i].types, info->parts[i].nchannels);
    }
    free(info->parts);
    engine_names_free(info->views, info->nviews);
    engine_names_free(info->attr_names, info->nattributes);
    engine_names_free(info->attr_values, info->nattributes);
    memset(info, 0, sizeof *info);
}
