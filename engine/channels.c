/* Channel selection by name, suffix, layer+letters or layer. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/channels.h"

/* Does full name `name` end with ".suffix" (or equal suffix)? */
static int suffix_match(const char *name, const char *suffix)
{
    size_t n = strlen(name), s = strlen(suffix);
    if (s > n) return 0;
    if (s == n) return strcmp(name, suffix) == 0;
    return name[n - s - 1] == '.' && strcmp(name + n - s, suffix) == 0;
}

/* Canonical order of the last component inside a layer: colour, vectors, texture coordinates,
 * then alpha/coverage, then the rest alphabetically (EXR stores channels alphabetically, which
 * would give A,B,G,R, and Blender's UV layer A,U,V). */
int nprfx_channels_component_rank(const char *c)
{
    static const char *const order[] = {"R", "G", "B", "X", "Y", "Z", "W", "U", "V", "A", NULL};
    for (int i = 0; order[i]; i++)
        if (!strcmp(c, order[i])) return i;
    return 100;
}

static const char *last_component(const char *name)
{
    const char *dot = strrchr(name, '.');
    return dot ? dot + 1 : name;
}

/* Find the unique channel matching item exactly or by dotted suffix: index, -1 none, -2 many. */
static int find_one(const char *const *names, int n, const char *item)
{
    for (int i = 0; i < n; i++)
        if (!strcmp(names[i], item)) return i;
    if (!strchr(item, '.')) return -1; /* a bare "Z" must not match "P.Z" */
    int found = -1;
    for (int i = 0; i < n; i++)
        if (suffix_match(names[i], item)) {
            if (found >= 0) return -2;
            found = i;
        }
    return found;
}

/* Channels of a layer (names "...layer.C" with one more component), canonical order. */
static int layer_channels(const char *const *names, int n, const char *layer, int *idx, int max,
                          int *ambiguous)
{
    int count = 0;
    const char *prefix_owner = NULL; /* the full prefix the first match used */
    size_t ll = strlen(layer);
    for (int i = 0; i < n; i++) {
        const char *nm = names[i];
        const char *comp = last_component(nm);
        if (comp == nm) continue;
        size_t plen = (size_t)(comp - 1 - nm); /* length of the layer part */
        if (plen < ll) continue;
        if (strncmp(nm + plen - ll, layer, ll) != 0) continue;
        if (plen > ll && nm[plen - ll - 1] != '.') continue;
        if (prefix_owner && (strncmp(prefix_owner, nm, plen) != 0 ||
                             last_component(prefix_owner) - 1 - prefix_owner != (ptrdiff_t)plen)) {
            *ambiguous = 1; /* two different layers end with this name */
            return -1;
        }
        prefix_owner = nm;
        if (count < max) idx[count] = i;
        count++;
    }
    if (count > max) count = max;
    /* insertion sort by canonical rank, then name */
    for (int a = 1; a < count; a++)
        for (int b = a; b > 0; b--) {
            const char *x = last_component(names[idx[b - 1]]), *y = last_component(names[idx[b]]);
            int rx = nprfx_channels_component_rank(x), ry = nprfx_channels_component_rank(y);
            if (rx > ry || (rx == ry && strcmp(x, y) > 0)) {
                int t = idx[b - 1];
                idx[b - 1] = idx[b];
                idx[b] = t;
            } else
                break;
        }
    return count;
}

int nprfx_channels_select(const char *const *names, int n, const char *selection, int *idx, int max,
                          char *bad, size_t bad_size, int *ambiguous)
{
    char buf[1024];
    int count = 0;
    *ambiguous = 0;
    snprintf(buf, sizeof buf, "%s", selection);
    for (char *save = NULL, *item = strtok_r(buf, ",", &save); item;
         item = strtok_r(NULL, ",", &save)) {
        while (*item == ' ')
            item++;
        int i = find_one(names, n, item);
        if (i >= 0) {
            if (count < max) idx[count++] = i;
            continue;
        }
        if (i == -2) {
            *ambiguous = 1;
            snprintf(bad, bad_size, "%s", item);
            return -1;
        }
        /* layer + letters: "Vector.XY" */
        const char *dot = strrchr(item, '.');
        int ok = 0;
        if (dot && dot[1]) {
            char one[512];
            int tmp[16], k = 0;
            ok = 1;
            for (const char *c = dot + 1; *c && ok; c++) {
                snprintf(one, sizeof one, "%.*s.%c", (int)(dot - item), item, *c);
                int j = find_one(names, n, one);
                if (j < 0 || k == 16)
                    ok = 0;
                else
                    tmp[k++] = j;
            }
            if (ok && k > 1)
                for (int t = 0; t < k && count < max; t++)
                    idx[count++] = tmp[t];
            else
                ok = 0;
        }
        if (ok) continue;
        /* a layer name */
        int amb = 0;
        int k = layer_channels(names, n, item, idx + count, max - count, &amb);
        if (k > 0) {
            count += k;
            continue;
        }
        *ambiguous = amb;
        snprintf(bad, bad_size, "%s", item);
        return -1;
    }
    return count;
}

int nprfx_channels_from_hint(const char *const *names, int n, const char *hint, int *idx, int max)
{
    char buf[1024], bad[256];
    snprintf(buf, sizeof buf, "%s", hint);
    for (char *save = NULL, *alt = strtok_r(buf, "|", &save); alt;
         alt = strtok_r(NULL, "|", &save)) {
        int amb;
        int k = nprfx_channels_select(names, n, alt, idx, max, bad, sizeof bad, &amb);
        if (k > 0) return k;
    }
    return -1;
}
