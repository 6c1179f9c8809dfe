/* Private to the scene generator: small double-precision vector helpers and the analytic
 * ray/shape intersections (synth_geom.c). Everything is double so that the AOVs derived from a
 * hit (depth, positions, motion) are exact to float precision once stored. */
#ifndef NPRFX_SYNTH_GEOM_H
#define NPRFX_SYNTH_GEOM_H

#include <math.h>

typedef struct sg_vec3 {
    double x, y, z;
} sg_vec3;

static inline sg_vec3 sg_v(double x, double y, double z)
{
    sg_vec3 r = {x, y, z};
    return r;
}
static inline sg_vec3 sg_add(sg_vec3 a, sg_vec3 b)
{
    return sg_v(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline sg_vec3 sg_sub(sg_vec3 a, sg_vec3 b)
{
    return sg_v(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline sg_vec3 sg_scale(sg_vec3 a, double s)
{
    return sg_v(a.x * s, a.y * s, a.z * s);
}
static inline double sg_dot(sg_vec3 a, sg_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline sg_vec3 sg_cross(sg_vec3 a, sg_vec3 b)
{
    return sg_v(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double sg_len(sg_vec3 a)
{
    return sqrt(sg_dot(a, a));
}
static inline sg_vec3 sg_normalize(sg_vec3 a)
{
    double l = sg_len(a);
    return l > 0 ? sg_scale(a, 1.0 / l) : a;
}

/* Row-major 3x3 matrix. */
typedef struct sg_mat3 {
    double m[3][3];
} sg_mat3;

static inline sg_mat3 sg_identity(void)
{
    sg_mat3 r = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    return r;
}
/* Right-handed rotations about the axes. */
static inline sg_mat3 sg_rot_x(double a)
{
    double c = cos(a), s = sin(a);
    sg_mat3 r = {{{1, 0, 0}, {0, c, -s}, {0, s, c}}};
    return r;
}
static inline sg_mat3 sg_rot_y(double a)
{
    double c = cos(a), s = sin(a);
    sg_mat3 r = {{{c, 0, s}, {0, 1, 0}, {-s, 0, c}}};
    return r;
}
static inline sg_mat3 sg_rot_z(double a)
{
    double c = cos(a), s = sin(a);
    sg_mat3 r = {{{c, -s, 0}, {s, c, 0}, {0, 0, 1}}};
    return r;
}
static inline sg_mat3 sg_mul(sg_mat3 a, sg_mat3 b)
{
    sg_mat3 r;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
    return r;
}
static inline sg_vec3 sg_apply(sg_mat3 a, sg_vec3 v)
{
    return sg_v(a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z,
                a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
                a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z);
}
/* The inverse of a rotation. */
static inline sg_vec3 sg_apply_transpose(sg_mat3 a, sg_vec3 v)
{
    return sg_v(a.m[0][0] * v.x + a.m[1][0] * v.y + a.m[2][0] * v.z,
                a.m[0][1] * v.x + a.m[1][1] * v.y + a.m[2][1] * v.z,
                a.m[0][2] * v.x + a.m[1][2] * v.y + a.m[2][2] * v.z);
}

/* A shape's hit in object space: ray parameter, position, unit normal, surface UV. */
typedef struct sg_hit {
    double t;
    sg_vec3 p, n;
    double u, v;
} sg_hit;

/* Each returns 1 and fills *hit for the nearest intersection with t in (tmin, tmax), else 0.
 * The ray is o + t d with d not necessarily unit length; t is in the caller's parameter. */

/* The plane z = 0 (normal +z); uv = (x, y). */
int internal_sg_hit_plane(sg_vec3 o, sg_vec3 d, double tmin, double tmax, sg_hit *hit);
/* The sphere of radius r about the origin; u = longitude around +y in [0,1), v = colatitude in
 * [0,1] (0 at +y). */
int internal_sg_hit_sphere(sg_vec3 o, sg_vec3 d, double r, double tmin, double tmax, sg_hit *hit);
/* The cube [-h, h]^3; uv in [0,1]^2 per face from the two coordinates across the face. */
int internal_sg_hit_box(sg_vec3 o, sg_vec3 d, double h, double tmin, double tmax, sg_hit *hit);
/* The torus about the z axis with major radius R and tube radius r; u around the axis, v around
 * the tube, both in [0,1). */
int internal_sg_hit_torus(sg_vec3 o, sg_vec3 d, double R, double r, double tmin, double tmax,
                       sg_hit *hit);

/* Real roots of sum c[i] x^i (deg <= 4) inside [a, b], ascending; returns their count.  */
int internal_sg_poly_roots(const double *c, int deg, double a, double b, double *roots);

#endif
