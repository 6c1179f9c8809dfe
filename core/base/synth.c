/* The analytic scene generator: plates with exact AOVs (see nprfx/synth.h).
 *
 * World space is right-handed with +y up. A camera is a pinhole looking from `eye` at `target`
 * with a 45 degree horizontal field of view over the image width, so the composition is the same
 * at any size and every motion in pixels scales with the width (figures below are for 256 wide).
 * Pixel (x, y) is the sample at its centre, the principal point is the image centre
 * ((W-1)/2, (H-1)/2), and image y grows downward.
 *
 * Each object is a rest shape (object space = Pref) placed by a pose that depends on time
 * (time = frame number): world = pos + scale * rot * Pref. Motion vectors come from pushing the
 * visited Pref through the poses and cameras of frames i-1 and i+1 and projecting, so they are
 * exact (double precision, stored as float). A point that lies behind the camera at the other
 * frame gets the offscreen motion k_offscreen, which every reader treats as "left the frame".
 *
 * Beauty: a soft checker from UV (continuous, so it is not a 1-spp aliasing mess) times a colour
 * per object, lit by one of the lights (nprfx_synth_light): RGB = albedo * (ambient + diffuse),
 * the `diffuse` channel holding the light's term. The sun (default) is 0.15 ambient + 0.85 N.L
 * from light_dir() (upper left, in front), so RGB stays in [0, 1]; the point light and the low
 * key fall off with the square of the distance, the first up to ~40 on the faces nearest it (HDR
 * highlights), the second leaving most of the frame below 0.1. RGB is scene-linear and
 * premultiplied by coverage (background RGBA = 0). There are no shadows. */
#include <math.h>
#include <string.h>

#include "nprfx/synth.h"
#include "synth_geom.h"

static const double k_pi = 3.14159265358979323846;
static const double k_background_z = 1e10;
static const double k_offscreen = 1e6; /* motion for a point behind the camera at frame i+-1 */
#define k_ambient_sun 0.15

static double deg(double d)
{
    return d * (k_pi / 180.0);
}

/* Focal length in pixels per pixel of image width: 45 degree horizontal field of view. */
static double focal_per_width(void)
{
    return 0.5 / tan(deg(22.5));
}

static sg_vec3 light_dir(void)
{
    return sg_normalize(sg_v(-0.45, 0.7, 0.55));
}

/* A light: RGB = albedo * (ambient + gain * diffuse), the diffuse channel being max(0, N.L)
 * for the sun and I cos / d^2 for a point light at (x, y, z) of intensity I. */
typedef struct point_light {
    const char *name, *help;
    double x, y, z, intensity, ambient, gain;
} point_light;

/* Index 0 is the sun (light_dir(), no position); the others are point lights. */
static const point_light k_lights[] = {
    {"sun", "0.15 ambient + 0.85 diffuse from the upper left (RGB within [0, 1])", 0, 0, 0, 1,
     k_ambient_sun, 1 - k_ambient_sun},
    {"point",
     "a strong point light in front, upper left, close to the objects: HDR highlights "
     "(beauty up to ~40), little ambient",
     -1.0, 1.4, 2.0, 40.0, 0.04, 1},
    {"lowkey",
     "a dim point light low on the right, falling off across the frame: most of it "
     "below 0.1, deep shadows",
     2.6, -0.4, 1.2, 1.5, 0.005, 1},
};
#define NLIGHTS ((int)(sizeof k_lights / sizeof k_lights[0]))

int nprfx_synth_light_count(void)
{
    return NLIGHTS;
}

const char *nprfx_synth_light_name(int i, const char **help)
{
    if (i < 0 || i >= NLIGHTS) return NULL;
    if (help) *help = k_lights[i].help;
    return k_lights[i].name;
}

/* The light's term at world point P with normal N (without the ambient). */
static double light_term(const point_light *l, sg_vec3 P, sg_vec3 N)
{
    if (l == &k_lights[0]) {
        double d = sg_dot(N, light_dir());
        return d > 0 ? d : 0.0;
    }
    sg_vec3 L = sg_sub(sg_v(l->x, l->y, l->z), P);
    double d2 = sg_dot(L, L);
    double c = sg_dot(N, L) / sqrt(d2);
    return c > 0 ? l->intensity * c / d2 : 0.0;
}

/* ---- channels ------------------------------------------------------------------------------ */

enum {
    CH_R,
    CH_G,
    CH_B,
    CH_A,
    CH_Z,
    CH_MPX,
    CH_MPY,
    CH_MNX,
    CH_MNY,
    CH_PX,
    CH_PY,
    CH_PZ,
    CH_PREFX,
    CH_PREFY,
    CH_PREFZ,
    CH_NX,
    CH_NY,
    CH_NZ,
    CH_U,
    CH_V,
    CH_ID,
    CH_DIFFUSE,
    CH_COVERAGE,
    CH_ALBEDO_R,
    CH_ALBEDO_G,
    CH_ALBEDO_B,
    CH_COUNT
};

static const char *const channel_names[CH_COUNT + 1] = {"R",
                                                        "G",
                                                        "B",
                                                        "A",
                                                        "Z",
                                                        "motion_prev.X",
                                                        "motion_prev.Y",
                                                        "motion_next.X",
                                                        "motion_next.Y",
                                                        "P.X",
                                                        "P.Y",
                                                        "P.Z",
                                                        "Pref.X",
                                                        "Pref.Y",
                                                        "Pref.Z",
                                                        "N.X",
                                                        "N.Y",
                                                        "N.Z",
                                                        "UV.U",
                                                        "UV.V",
                                                        "id",
                                                        "diffuse",
                                                        "coverage",
                                                        "albedo.R",
                                                        "albedo.G",
                                                        "albedo.B",
                                                        NULL};

int nprfx_synth_channel_count(void)
{
    return CH_COUNT;
}
const char *const *nprfx_synth_channel_names(void)
{
    return channel_names;
}

/* ---- scenes -------------------------------------------------------------------------------- */

typedef enum shape_kind { SHAPE_PLANE, SHAPE_SPHERE, SHAPE_BOX, SHAPE_TORUS } shape_kind;

typedef struct object_desc {
    shape_kind kind;
    double a, b;           /* sphere radius | box half-size | torus major, minor radius */
    double freq_u, freq_v; /* checker periods per UV unit (two cells per period) */
    double colour[3];
} object_desc;

typedef struct pose {
    sg_mat3 rot;
    double scale;
    sg_vec3 pos;
} pose;

#define MAX_OBJECTS 4

typedef struct scene_def {
    nprfx_synth_scene_info info;
    int nobjects;
    object_desc objects[MAX_OBJECTS]; /* object k has id k+1 */
    void (*camera)(double t, sg_vec3 *eye, sg_vec3 *target);
    pose (*pose_at)(int object, double t);
} scene_def;

static pose make_pose(sg_mat3 rot, double scale, sg_vec3 pos)
{
    pose p = {rot, scale, pos};
    return p;
}

/* orbit: a backdrop plane at z = -3.5 filling the frame (id 1), a static tilted box (id 2) and a
 * sphere (id 3) spinning 1 degree/frame about a tilted axis while it orbits the box on a circle
 * of radius 2 at 1.5 degrees/frame (period 240 frames): in front of the box at frame 24 moving
 * left to right (it overlaps the box in the image from frame -6 to 56), behind it at frame 144. At
 * 256 wide the sphere's centre moves up to ~3.5 px/frame, its surface up to ~4.8 px/frame. */
static const double orbit_deg_per_frame = 1.5;
static void orbit_camera(double t, sg_vec3 *eye, sg_vec3 *target)
{
    (void)t;
    *eye = sg_v(0, 1.5, 6.5);
    *target = sg_v(0, 0, 0);
}
static pose orbit_pose(int object, double t)
{
    switch (object) {
    case 0:
        return make_pose(sg_identity(), 1, sg_v(0, 0, -3.5));
    case 1:
        return make_pose(sg_mul(sg_rot_x(deg(25)), sg_rot_y(deg(35))), 1, sg_v(0, 0, 0));
    default: {
        double theta = deg(orbit_deg_per_frame * (t - 24));
        sg_mat3 spin = sg_mul(sg_rot_z(deg(20)), sg_rot_y(deg(1.0 * t)));
        return make_pose(spin, 1, sg_v(2.0 * sin(theta), 0, 2.0 * cos(theta)));
    }
    }
}

/* dolly: the camera moves along the z axis toward a torus (major radius 1, tube 0.35, tilted 40
 * degrees; id 1) over empty background. The distance falls geometrically, 16 at frame 1 to 4 at
 * frame 48 (image scale x4, about 3%/frame), and keeps falling the same way before and after;
 * past frame ~100 the camera nears the ring and then passes through its hole, and the frame
 * empties. At 256 wide the torus is 52 px wide at frame 1 and 216 px at frame 48, and its edges
 * move 0.8 px/frame at frame 1, 3.8 px/frame at frame 48. */
static double dolly_distance(double t)
{
    return 16.0 * pow(4.0, -(t - 1) / 47.0);
}
static void dolly_camera(double t, sg_vec3 *eye, sg_vec3 *target)
{
    *eye = sg_v(0, 0, dolly_distance(t));
    *target = sg_v(0, 0, 0);
}
static pose dolly_pose(int object, double t)
{
    (void)object;
    (void)t;
    return make_pose(sg_rot_x(deg(-40)), 1, sg_v(0, 0, 0));
}

/* translate / rotate / zoom: an infinite textured plane facing the camera at distance 5, filling
 * the frame, moved by an exact image-space affine map per frame (identity at frame 0). */
static const double plane_distance = 5.0;
static const double translate_px[2] = {0.37, 0.23}; /* pixels per frame at 256 wide, y down */
static const double rotate_deg_per_frame = 0.3;
static const double zoom_per_frame = 1.005;

static void plane_camera(double t, sg_vec3 *eye, sg_vec3 *target)
{
    (void)t;
    *eye = sg_v(0, 0, plane_distance);
    *target = sg_v(0, 0, 0);
}
static pose translate_pose(int object, double t)
{
    (void)object;
    /* World units per pixel at the plane, times 256 pixels: image motion is exactly
     * translate_px * width / 256 per frame (image y is world -y). */
    double k = plane_distance / (256.0 * focal_per_width());
    return make_pose(sg_identity(), 1, sg_v(translate_px[0] * k * t, -translate_px[1] * k * t, 0));
}
static pose rotate_pose(int object, double t)
{
    (void)object;
    /* About the view axis; counter-clockwise as seen in the image. */
    return make_pose(sg_rot_z(deg(rotate_deg_per_frame * t)), 1, sg_v(0, 0, 0));
}
static pose zoom_pose(int object, double t)
{
    (void)object;
    return make_pose(sg_identity(), pow(zoom_per_frame, t), sg_v(0, 0, 0));
}

/* ground: the textured plane seen at a grazing angle, its normal 80 degrees from the view axis
 * (the foreshortening 1 / cos 80 = 5.8 at the image centre, more towards the horizon 2 degrees
 * above the centre line), drifting sideways 0.2 plane units per frame so that its texture moves.
 * It fills the frame below the horizon; above is background. */
static const double ground_tilt_deg = 80.0;
static pose ground_pose(int object, double t)
{
    (void)object;
    return make_pose(sg_rot_x(deg(-ground_tilt_deg)), 1, sg_v(0.02 * t, 0, -1.0));
}

/* clang-format off */
#define PLANE_OBJECT {SHAPE_PLANE, 0, 0, 2, 2, {0.85, 0.62, 0.30}}
/* clang-format on */

static const scene_def scenes[] = {
    {{"orbit", "spinning sphere orbiting a box before a backdrop: occlusion and disocclusion; up "
               "to ~4.8 px/frame at 256 wide, in front at frame 24, period 240"},
     3,
     {{SHAPE_PLANE, 0, 0, 1, 1, {0.55, 0.60, 0.70}},
      {SHAPE_BOX, 0.75, 0, 1.5, 1.5, {0.80, 0.30, 0.25}},
      {SHAPE_SPHERE, 0.65, 0, 6, 3, {0.30, 0.65, 0.35}}},
     orbit_camera,
     orbit_pose},
    {{"dolly", "camera dollies toward a torus on empty background: x4 scale from frame 1 to 48 "
               "(~3%/frame)"},
     1,
     {{SHAPE_TORUS, 1.0, 0.35, 8, 3, {0.35, 0.45, 0.85}}},
     dolly_camera,
     dolly_pose},
    {{"translate", "frame-filling plane translating (0.37, 0.23) px/frame at 256 wide (exact)"},
     1,
     {PLANE_OBJECT},
     plane_camera,
     translate_pose},
    {{"rotate", "frame-filling plane rotating 0.3 deg/frame counter-clockwise about the image "
                "centre (exact)"},
     1,
     {PLANE_OBJECT},
     plane_camera,
     rotate_pose},
    {{"zoom", "frame-filling plane scaling x1.005/frame about the image centre (exact)"},
     1,
     {PLANE_OBJECT},
     plane_camera,
     zoom_pose},
    {{"ground", "plane at a grazing angle (its normal 80 degrees from the view axis), drifting "
                "sideways: foreshortening ~6x at the centre, more towards the horizon"},
     1,
     {PLANE_OBJECT},
     plane_camera,
     ground_pose},
};

#define NSCENES ((int)(sizeof scenes / sizeof scenes[0]))

int nprfx_synth_scene_count(void)
{
    return NSCENES;
}

const nprfx_synth_scene_info *nprfx_synth_scene_at(int i)
{
    return i >= 0 && i < NSCENES ? &scenes[i].info : NULL;
}

/* ---- rendering ----------------------------------------------------------------------------- */

typedef struct camera {
    sg_vec3 eye, right, up, fwd;
    double f, cx, cy;
} camera;

static camera make_camera(const scene_def *sc, double t, int width, int height)
{
    camera c;
    sg_vec3 target;
    sc->camera(t, &c.eye, &target);
    c.fwd = sg_normalize(sg_sub(target, c.eye));
    c.right = sg_normalize(sg_cross(c.fwd, sg_v(0, 1, 0)));
    c.up = sg_cross(c.right, c.fwd);
    c.f = focal_per_width() * width;
    c.cx = 0.5 * (width - 1);
    c.cy = 0.5 * (height - 1);
    return c;
}

/* Image position of world point X; 0 when it is not in front of the camera. */
static int project(const camera *c, sg_vec3 X, double *px, double *py)
{
    sg_vec3 v = sg_sub(X, c->eye);
    double z = sg_dot(v, c->fwd);
    if (!(z > 1e-9)) return 0;
    *px = c->cx + c->f * sg_dot(v, c->right) / z;
    *py = c->cy - c->f * sg_dot(v, c->up) / z;
    return 1;
}

static sg_vec3 to_world(const pose *p, sg_vec3 rest)
{
    return sg_add(p->pos, sg_scale(sg_apply(p->rot, rest), p->scale));
}

static double texture(const object_desc *o, double u, double v)
{
    /* A checker whose edges are a clamped product of sines: continuous, so one sample per
     * pixel does not alias as badly as a hard checker. */
    double s = 4 * sin(2 * k_pi * o->freq_u * u) * sin(2 * k_pi * o->freq_v * v);
    s = s < -1 ? -1 : s > 1 ? 1 : s;
    /* A slow, non-periodic brightness swell, so the planes' checker is not a pure lattice that
     * a wrong motion field could match by whole periods. */
    double swell = 0.85 + 0.15 * sin(2 * k_pi * 0.11 * u + 1.7 * sin(2 * k_pi * 0.077 * v));
    return swell * (0.25 + 0.75 * (0.5 + 0.5 * s));
}

typedef struct render_job {
    const scene_def *scene;
    camera cam[3];              /* frames i-1, i, i+1 */
    pose poses[3][MAX_OBJECTS]; /* likewise */
    int width;
    nprfx_image *out;
    const int *pick;              /* out's channel c is synth channel pick[c] */
    int motion_prev, motion_next; /* whether they are picked: each costs two projections */
    const point_light *light;
} render_job;

static int intersect(const object_desc *o, const pose *p, sg_vec3 eye, sg_vec3 dir, double tmax,
                     sg_hit *hit)
{
    /* The ray in object space; the parameter t (= view depth) is unchanged by the similarity. */
    double inv = 1.0 / p->scale;
    sg_vec3 oo = sg_scale(sg_apply_transpose(p->rot, sg_sub(eye, p->pos)), inv);
    sg_vec3 od = sg_scale(sg_apply_transpose(p->rot, dir), inv);
    const double tmin = 1e-6;
    switch (o->kind) {
    case SHAPE_PLANE:
        return internal_sg_hit_plane(oo, od, tmin, tmax, hit);
    case SHAPE_SPHERE:
        return internal_sg_hit_sphere(oo, od, o->a, tmin, tmax, hit);
    case SHAPE_BOX:
        return internal_sg_hit_box(oo, od, o->a, tmin, tmax, hit);
    case SHAPE_TORUS:
        return internal_sg_hit_torus(oo, od, o->a, o->b, tmin, tmax, hit);
    }
    return 0;
}

/* Screen offset of the surface point `rest` from where it projects now (cam/pose `now`) to where
 * it projects at the other frame. Differencing two projections (rather than subtracting the
 * pixel centre) makes static points under a static camera move by exactly 0. */
static void motion_to(const camera *c_now, const pose *p_now, const camera *c, const pose *p,
                      sg_vec3 rest, float *mx, float *my)
{
    double x0, y0, x1, y1;
    if (project(c_now, to_world(p_now, rest), &x0, &y0) &&
        project(c, to_world(p, rest), &x1, &y1)) {
        *mx = (float)(x1 - x0);
        *my = (float)(y1 - y0);
    } else {
        *mx = *my = (float)k_offscreen;
    }
}

static void shade_pixel(const render_job *job, int x, int y, float *px)
{
    const scene_def *sc = job->scene;
    const camera *c = &job->cam[1];
    /* Unnormalised direction with unit component along the view axis: t is the view depth. */
    double sx = (x - c->cx) / c->f, sy = -(y - c->cy) / c->f;
    sg_vec3 dir = sg_add(c->fwd, sg_add(sg_scale(c->right, sx), sg_scale(c->up, sy)));

    sg_hit best = {0}, hit;
    int best_obj = -1;
    double tmax = INFINITY;
    for (int k = 0; k < sc->nobjects; k++)
        if (intersect(&sc->objects[k], &job->poses[1][k], c->eye, dir, tmax, &hit)) {
            best = hit;
            best_obj = k;
            tmax = hit.t;
        }

    for (int ch = 0; ch < CH_COUNT; ch++)
        px[ch] = 0.0f;
    if (best_obj < 0) {
        /* Background: infinitely far, so no motion under a translating camera (the only moving
         * camera here is the dolly's). */
        px[CH_Z] = (float)k_background_z;
        return;
    }
    const object_desc *o = &sc->objects[best_obj];
    const pose *p = &job->poses[1][best_obj];
    sg_vec3 P = to_world(p, best.p);
    sg_vec3 N = sg_normalize(sg_apply(p->rot, best.n));
    double diffuse = light_term(job->light, P, N);
    double albedo = texture(o, best.u, best.v);
    double shade = albedo * (job->light->ambient + job->light->gain * diffuse);

    px[CH_R] = (float)(o->colour[0] * shade);
    px[CH_G] = (float)(o->colour[1] * shade);
    px[CH_B] = (float)(o->colour[2] * shade);
    px[CH_A] = 1.0f;
    px[CH_Z] = (float)sg_dot(sg_sub(P, c->eye), c->fwd);
    if (job->motion_prev)
        motion_to(c, p, &job->cam[0], &job->poses[0][best_obj], best.p, &px[CH_MPX], &px[CH_MPY]);
    if (job->motion_next)
        motion_to(c, p, &job->cam[2], &job->poses[2][best_obj], best.p, &px[CH_MNX], &px[CH_MNY]);
    px[CH_PX] = (float)P.x;
    px[CH_PY] = (float)P.y;
    px[CH_PZ] = (float)P.z;
    px[CH_PREFX] = (float)best.p.x;
    px[CH_PREFY] = (float)best.p.y;
    px[CH_PREFZ] = (float)best.p.z;
    px[CH_NX] = (float)N.x;
    px[CH_NY] = (float)N.y;
    px[CH_NZ] = (float)N.z;
    px[CH_U] = (float)best.u;
    px[CH_V] = (float)best.v;
    px[CH_ID] = (float)(best_obj + 1);
    px[CH_DIFFUSE] = (float)diffuse;
    px[CH_COVERAGE] = 1.0f;
    /* the surface colour, so that RGB = albedo * (ambient + gain diffuse) */
    px[CH_ALBEDO_R] = (float)(o->colour[0] * albedo);
    px[CH_ALBEDO_G] = (float)(o->colour[1] * albedo);
    px[CH_ALBEDO_B] = (float)(o->colour[2] * albedo);
}

static void render_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const render_job *job = user;
    float tmp[CH_COUNT];
    for (int y = begin; y < end; y++)
        for (int x = 0; x < job->width; x++) {
            shade_pixel(job, x, y, tmp);
            float *dst = nprfx_image_at(job->out, x, y);
            for (int ch = 0; ch < job->out->channels; ch++)
                dst[ch] = tmp[job->pick[ch]];
        }
}

static const scene_def *find_scene(const char *name)
{
    for (int i = 0; i < NSCENES; i++)
        if (!strcmp(scenes[i].info.name, name)) return &scenes[i];
    return NULL;
}

nprfx_result nprfx_synth_render(nprfx_context *ctx, const char *name, int frame, nprfx_image *out)
{
    int all[CH_COUNT];
    for (int c = 0; c < CH_COUNT; c++)
        all[c] = c;
    if (out && out->channels != CH_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "synth: the output needs %d channels, it has %d", CH_COUNT,
                           out->channels);
    return nprfx_synth_render_channels(ctx, name, frame, all, CH_COUNT, out);
}

nprfx_result nprfx_synth_render_channels(nprfx_context *ctx, const char *name, int frame,
                                         const int *channels, int count, nprfx_image *out)
{
    return nprfx_synth_render_lit(ctx, name, NULL, frame, channels, count, out);
}

nprfx_result nprfx_synth_render_lit(nprfx_context *ctx, const char *name, const char *light,
                                    int frame, const int *channels, int count, nprfx_image *out)
{
    const point_light *lt = &k_lights[0];
    if (light && light[0]) {
        lt = NULL;
        for (int i = 0; i < NLIGHTS && !lt; i++)
            if (!strcmp(k_lights[i].name, light)) lt = &k_lights[i];
        if (!lt)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "synth: unknown light '%s' (known: sun, point, lowkey)", light);
    }
    if (!name || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "synth: scene name and output image are required");
    const scene_def *sc = find_scene(name);
    if (!sc) {
        char list[256] = "";
        for (int i = 0; i < NSCENES; i++) {
            if (i) strncat(list, ", ", sizeof list - strlen(list) - 1);
            strncat(list, scenes[i].info.name, sizeof list - strlen(list) - 1);
        }
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "synth: unknown scene '%s' (known: %s)",
                           name, list);
    }
    if (!channels || count < 1 || out->channels != count)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "synth: the output has %d channels for %d picked", out->channels, count);
    for (int c = 0; c < count; c++)
        if (channels[c] < 0 || channels[c] >= CH_COUNT)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "synth: channel index %d is outside [0, %d)", channels[c], CH_COUNT);
    if (out->bounds.x0 != 0 || out->bounds.y0 != 0 || nprfx_rect_empty(out->bounds))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "synth: the output must be a non-empty image with bounds from (0,0), "
                           "not (%d,%d)-(%d,%d)",
                           out->bounds.x0, out->bounds.y0, out->bounds.x1, out->bounds.y1);

    render_job job;
    memset(&job, 0, sizeof job);
    job.scene = sc;
    job.width = out->bounds.x1;
    job.out = out;
    job.pick = channels;
    job.light = lt;
    for (int c = 0; c < count; c++) {
        job.motion_prev |= channels[c] == CH_MPX || channels[c] == CH_MPY;
        job.motion_next |= channels[c] == CH_MNX || channels[c] == CH_MNY;
    }
    for (int i = 0; i < 3; i++) {
        double t = (double)frame + (i - 1);
        job.cam[i] = make_camera(sc, t, out->bounds.x1, out->bounds.y1);
        for (int k = 0; k < sc->nobjects; k++)
            job.poses[i][k] = sc->pose_at(k, t);
    }
    nprfx_parallel_for(nprfx_context_executor(ctx), out->bounds.y1, 4, render_rows, &job);
    return NPRFX_OK;
}
