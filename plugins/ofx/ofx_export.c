/* nprfx OpenFX adapter — a node's text export (stipple dots as CSV/SVG) written from a host
 * (declared in ofx_export.h). The runner writes it beside its images; in a host the export
 * param's path is all there is, so the adapter writes it: the path's frame token expanded as the
 * runner expands it (nprfx/seq.h), folders created, a temporary name
 * renamed into place so a reader never sees half a file. Tiles of one frame, and repeated
 * renders of it with the same params, write it once. */
#define _POSIX_C_SOURCE 200809L /* mkdir, getpid */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ofx_export.h"
#include "ofx_fetch.h"
#include "nprfx/seq.h"

/* FNV-1a over what the export is made of. */
static unsigned long long mix(unsigned long long h, const void *p, size_t n)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++)
        h = (h ^ b[i]) * 1099511628211ull;
    return h;
}

static unsigned long long export_key(const nprfx_render_args *a, const char *path)
{
    unsigned long long h = 14695981039346656037ull;
    h = mix(h, &a->time, sizeof a->time);
    h = mix(h, &a->frame, sizeof a->frame);
    for (int i = 0; i < a->node->num_params; i++) {
        h = mix(h, a->params[i].v, sizeof a->params[i].v);
        if (a->params[i].s) h = mix(h, a->params[i].s, strlen(a->params[i].s) + 1);
    }
    return mix(h, path, strlen(path) + 1);
}

/* mkdir -p of the folder that holds path. */
static nprfx_result make_parents(nprfx_context *ctx, const char *path)
{
    char dir[4096];
    if (snprintf(dir, sizeof dir, "%s", path) >= (int)sizeof dir)
        return nprfx_error(ctx, NPRFX_ERR_IO, "the path is too long");
    char *slash = strrchr(dir, '/');
    if (!slash || slash == dir) return NPRFX_OK;
    *slash = 0;
    for (char *p = dir + 1;; p++) {
        if (*p && *p != '/') continue;
        char c = *p;
        *p = 0;
        if (mkdir(dir, 0777) != 0 && errno != EEXIST)
            return nprfx_error(ctx, NPRFX_ERR_IO, "cannot create folder '%s': %s", dir,
                               strerror(errno));
        *p = c;
        if (!c) break;
    }
    return NPRFX_OK;
}

static nprfx_result write_file(nprfx_context *ctx, const char *path, const char *text, size_t len)
{
    nprfx_result r = make_parents(ctx, path);
    if (r) return r;
    char tmp[4200];
    snprintf(tmp, sizeof tmp, "%s.tmp%ld", path, (long)getpid());
    FILE *f = fopen(tmp, "wb");
    int ok = f && fwrite(text, 1, len, f) == len;
    if (f && fclose(f) != 0) ok = 0;
    if (ok && rename(tmp, path) != 0) ok = 0;
    if (!ok) {
        int e = errno;
        remove(tmp);
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", path, strerror(e));
    }
    return NPRFX_OK;
}

nprfx_result ofx_export(ofx_instance *inst, const nprfx_render_args *a)
{
    const nprfx_node_desc *d = inst->desc;
    nprfx_result r = NPRFX_OK;
    for (int i = 0; i < d->num_params && !r; i++) {
        const char *pattern = a->params[i].s;
        if (!(d->params[i].flags & NPRFX_PARAM_EXPORT) || !pattern || !pattern[0]) continue;
        char path[4096];
        int frame = ofx_round_frame(a->time);
        if ((r = nprfx_seq_expand(a->ctx, pattern, frame, path, sizeof path))) break;
        unsigned long long key = export_key(a, path);
        pthread_mutex_lock(&inst->lock);
        if (!(inst->export_done && inst->export_key == key)) {
            char what[4200];
            snprintf(what, sizeof what, "%s: export to %s", d->id, path);
            nprfx_context *ectx = NULL;
            char *text = NULL;
            size_t len = 0;
            nprfx_render_args e = *a;
            if (!(r = nprfx_context_create_scoped(a->ctx, what, &ectx))) {
                e.ctx = ectx;
                if (!(r = nprfx_node_export(&e, path, &text, &len)))
                    r = write_file(ectx, path, text, len);
            }
            free(text);
            nprfx_context_destroy(ectx);
            if (!r) {
                inst->export_done = 1;
                inst->export_key = key;
            }
        }
        pthread_mutex_unlock(&inst->lock);
    }
    return r;
}
