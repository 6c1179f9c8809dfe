/* nprfx OpenFX test host — the frames a render needs ("frames needed equals
 * the frames it reads"). A host plans its caches and its own fetches from getFramesNeeded: a
 * plug-in that declares more than it reads makes a host render or load frames for nothing (the
 * whole shot, for every frame), one that declares less gets refused or stale frames. So per
 * input clip this keeps the declared [lo, hi] pairs and the frames fetched, and render.c
 * compares the two sets on an instance's first render, when no cache hides a fetch. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ofx_host_internal.h"

void internal_frames_free(hframes *f)
{
    if (!f) return;
    free(f->decl);
    free(f->fetched);
    memset(f, 0, sizeof *f);
}

int internal_frames_declare(hframes *f, const double *v, int n, double time)
{
    int pairs = n / 2;
    double *d = realloc(f->decl, (size_t)(pairs > 0 ? pairs : 1) * 2 * sizeof *d);
    if (!d) return 0;
    f->decl = d;
    if (pairs <= 0) { /* getFramesNeeded's default: the frame itself */
        d[0] = d[1] = time;
        f->ndecl = 1;
        return 1;
    }
    memcpy(d, v, (size_t)pairs * 2 * sizeof *d);
    f->ndecl = pairs;
    return 1;
}

int internal_frames_allows(const hframes *f, double time)
{
    for (int j = 0; j < f->ndecl; j++)
        if (time >= f->decl[2 * j] && time <= f->decl[2 * j + 1]) return 1;
    return 0;
}

static int frame_of(double t)
{
    return (int)floor(t + 0.5);
}

int internal_frames_fetched(hframes *f, double time)
{
    int t = frame_of(time);
    for (int i = 0; i < f->nfetched; i++)
        if (f->fetched[i] == t) return 1;
    if (f->nfetched == f->cap) {
        int cap = f->cap ? f->cap * 2 : 8;
        int *v = realloc(f->fetched, (size_t)cap * sizeof *v);
        if (!v) return 0;
        f->fetched = v;
        f->cap = cap;
    }
    f->fetched[f->nfetched++] = t;
    return 1;
}

/* Integer frames of a declared pair: those within [lo, hi]. */
static int declared(const hframes *f, int t)
{
    return internal_frames_allows(f, (double)t);
}

static int was_fetched(const hframes *f, int t)
{
    for (int i = 0; i < f->nfetched; i++)
        if (f->fetched[i] == t) return 1;
    return 0;
}

/* "1-3,5" for the frames in [lo, hi] where in(f, t) holds; "none" when there are none. */
static void describe_set(const hframes *f, int (*in)(const hframes *, int), int lo, int hi,
                         char *buf, size_t n)
{
    size_t len = 0;
    buf[0] = 0;
    for (int t = lo; t <= hi; t++) {
        if (!in(f, t)) continue;
        int end = t;
        while (end < hi && in(f, end + 1))
            end++;
        int w = end > t ? snprintf(buf + len, n - len, "%s%d-%d", len ? "," : "", t, end)
                        : snprintf(buf + len, n - len, "%s%d", len ? "," : "", t);
        if (w < 0 || (size_t)w >= n - len) break;
        len += (size_t)w;
        t = end;
    }
    if (!len) snprintf(buf, n, "none");
}

int internal_frames_match(const hframes *f, char *why, size_t n)
{
    /* The span both sets lie in; a declaration far beyond the shot is cut at a million frames,
     * which is still a difference. */
    double lo = 1e300, hi = -1e300;
    for (int j = 0; j < f->ndecl; j++) {
        if (f->decl[2 * j] < lo) lo = f->decl[2 * j];
        if (f->decl[2 * j + 1] > hi) hi = f->decl[2 * j + 1];
    }
    for (int i = 0; i < f->nfetched; i++) {
        if (f->fetched[i] < lo) lo = f->fetched[i];
        if (f->fetched[i] > hi) hi = f->fetched[i];
    }
    if (lo > hi) return 1;
    int a = (int)ceil(lo > -1e6 ? lo : -1e6), b = (int)floor(hi < 1e6 ? hi : 1e6);
    int same = 1;
    for (int t = a; t <= b && same; t++)
        same = declared(f, t) == was_fetched(f, t);
    if (same) return 1;
    char d[256], g[256];
    describe_set(f, declared, a, b, d, sizeof d);
    describe_set(f, was_fetched, a, b, g, sizeof g);
    snprintf(why, n, "declared frames %s, fetched %s", d, g);
    return 0;
}
