/* Spatial index over the IVS sequence: one uniform grid per power-of-two prefix.
 *
 * A query for samples i <= limit reads level L = ceil(log2(limit)), which holds the first 2^L
 * points (so at least half of what it reads is wanted) at about two points per cell, and only
 * the cells its rectangle touches: the cost follows the answer, not the sequence length. Within a
 * cell, entries are in sequence order, so the scan stops at the first index >= limit. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/ivs.h"

typedef struct ivs_entry {
    float x, y;
    int32_t index;
} ivs_entry;

typedef struct ivs_level {
    int count;  /* points in this prefix */
    int grid;   /* cells per side */
    int *start; /* grid*grid + 1 offsets into entries */
    ivs_entry *entries;
} ivs_level;

struct nprfx_ivs_index {
    int count;
    float *xy;
    int num_levels;
    ivs_level *levels;
};

/* Exact: a float times a grid size below 2^15 fits a double's mantissa, so a query can tell
 * which cell a point is in from the same product. */
static int cell_of(float v, int grid)
{
    int c = (int)floor((double)v * (double)grid);
    return c < 0 ? 0 : c >= grid ? grid - 1 : c;
}

static int build_level(ivs_level *lv, const float *xy, int count)
{
    int grid = (int)floor(sqrt(count / 2.0));
    if (grid < 1) grid = 1;
    lv->count = count;
    lv->grid = grid;
    size_t cells = (size_t)grid * (size_t)grid;
    lv->start = calloc(cells + 1, sizeof(int));
    lv->entries = malloc((size_t)count * sizeof(ivs_entry));
    if (!lv->start || !lv->entries) return 0;
    /* counting sort by cell; stable, so each cell stays in sequence order */
    for (int i = 0; i < count; i++) {
        size_t c = (size_t)cell_of(xy[2 * i + 1], grid) * grid + cell_of(xy[2 * i], grid);
        lv->start[c + 1]++;
    }
    for (size_t c = 0; c < cells; c++)
        lv->start[c + 1] += lv->start[c];
    int *fill = malloc(cells * sizeof(int));
    if (!fill) return 0;
    memcpy(fill, lv->start, cells * sizeof(int));
    for (int i = 0; i < count; i++) {
        size_t c = (size_t)cell_of(xy[2 * i + 1], grid) * grid + cell_of(xy[2 * i], grid);
        ivs_entry *e = &lv->entries[fill[c]++];
        e->x = xy[2 * i];
        e->y = xy[2 * i + 1];
        e->index = i;
    }
    free(fill);
    return 1;
}

nprfx_result nprfx_ivs_index_create(nprfx_context *ctx, const float *xy, int n,
                                    nprfx_ivs_index **out)
{
    if (!out || !xy || n < 1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "ivs index: need n >= 1 points");
    *out = NULL;
    nprfx_ivs_index *ix = calloc(1, sizeof *ix);
    if (!ix) goto oom;
    ix->count = n;
    ix->xy = malloc((size_t)n * 2 * sizeof(float));
    if (!ix->xy) goto oom;
    memcpy(ix->xy, xy, (size_t)n * 2 * sizeof(float));
    int levels = 1;
    while (levels < 31 && (1 << (levels - 1)) < n)
        levels++;
    ix->levels = calloc((size_t)levels, sizeof(ivs_level));
    if (!ix->levels) goto oom;
    ix->num_levels = levels;
    for (int l = 0; l < levels; l++) {
        int count = l < 30 && (1 << l) < n ? (1 << l) : n;
        if (!build_level(&ix->levels[l], ix->xy, count)) goto oom;
    }
    *out = ix;
    return NPRFX_OK;
oom:
    nprfx_ivs_index_destroy(ix);
    return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "ivs index: out of memory for %d points", n);
}

void nprfx_ivs_index_destroy(nprfx_ivs_index *ix)
{
    if (!ix) return;
    for (int l = 0; ix->levels && l < ix->num_levels; l++) {
        free(ix->levels[l].start);
        free(ix->levels[l].entries);
    }
    free(ix->levels);
    free(ix->xy);
    free(ix);
}

int nprfx_ivs_index_count(const nprfx_ivs_index *ix)
{
    return ix ? ix->count : 0;
}

void nprfx_ivs_index_point(const nprfx_ivs_index *ix, int k, float *xy)
{
    xy[0] = ix->xy[2 * k];
    xy[1] = ix->xy[2 * k + 1];
}

static long long floor_div(long long a, long long b)
{
    long long q = a / b;
    return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

long long nprfx_ivs_index_query(const nprfx_ivs_index *ix, int limit, double u0, double v0,
                                double u1, double v1, nprfx_ivs_visit_fn visit, void *user)
{
    if (!ix || limit <= 0 || !(u1 > u0) || !(v1 > v0)) return 0;
    if (limit > ix->count) limit = ix->count;
    /* the first level holding limit points: level l holds min(2^l, count) */
    int l = 0;
    while (l < 30 && (1 << l) < limit)
        l++;
    if (l > ix->num_levels - 1) l = ix->num_levels - 1;
    while (l + 1 < ix->num_levels && ix->levels[l].count < limit) /* never, by the above */
        l++;
    const ivs_level *lv = &ix->levels[l];
    const int g = lv->grid;
    /* cells in the unbounded plane; cell c of the plane is cell (c mod g) of tile floor(c / g) */
    /* the products below may round across a cell edge: widen by far more than that */
    const double slack = 1e-7;
    double cu0 = floor(u0 * g - slack), cu1 = floor(u1 * g + slack);
    double cv0 = floor(v0 * g - slack), cv1 = floor(v1 * g + slack);
    if (!(cu1 - cu0 < 1e9 && cv1 - cv0 < 1e9)) return 0; /* absurd rectangles: refuse */
    long long visited = 0;
    /* cell (rx, ry) of tile (tx, ty), stepped without a division per cell */
    const long long cx0 = (long long)cu0, cx1 = (long long)cu1;
    const long long tx0 = floor_div(cx0, g);
    const int rx0 = (int)(cx0 - tx0 * g);
    long long ty = floor_div((long long)cv0, g);
    int ry = (int)((long long)cv0 - ty * g);
    for (long long cy = (long long)cv0; cy <= (long long)cv1; cy++) {
        const double dty = (double)ty;
        long long tx = tx0;
        int rx = rx0;
        const int *start = lv->start + (size_t)ry * g;
        for (long long cx = cx0; cx <= cx1; cx++) {
            const double dtx = (double)tx;
            for (int e = start[rx]; e < start[rx + 1]; e++) {
                const ivs_entry *en = &lv->entries[e];
                if (en->index >= limit) break;
                double u = (double)en->x + dtx, v = (double)en->y + dty;
                if (u < u0 || u >= u1 || v < v0 || v >= v1) continue;
                visited++;
                if (visit && visit(user, en->index, u, v)) return visited;
            }
            if (++rx == g) {
                rx = 0;
                tx++;
            }
        }
        if (++ry == g) {
            ry = 0;
            ty++;
        }
    }
    return visited;
}
