/* Analytic ray/shape intersections for the scene generator (double precision throughout).
 *
 * The torus needs the real roots of a quartic. Closed forms (Ferrari) lose digits near
 * silhouettes, and a missed or jittery root there would make the "exact" AOVs flicker between
 * frames, so roots are isolated instead: the roots of p' split [a, b] into intervals on which p
 * is monotone, each holding at most one root, found by bracketed Newton to full double
 * precision. Recursing down to a closed-form quadratic makes this robust for any coefficients,
 * and it is deterministic. */
#include <math.h>

#include "synth_geom.h"

static const double k_pi = 3.14159265358979323846;

static double poly_eval(const double *c, int deg, double x)
{
    double r = c[deg];
    for (int i = deg - 1; i >= 0; i--)
        r = r * x + c[i];
    return r;
}

/* The single root of a monotone stretch [lo, hi] with f(lo), f(hi) of opposite signs: Newton
 * steps kept inside a shrinking bracket (bisecting whenever a step would leave it), so it
 * converges quadratically yet can never escape or stall. `scale` sets the absolute tolerance
 * for roots near zero. */
static double refine(const double *c, int deg, double lo, double hi, double flo, double scale)
{
    double x = 0.5 * (lo + hi);
    for (int it = 0; it < 200; it++) {
        double mid = 0.5 * (lo + hi);
        if (!(mid > lo && mid < hi)) return mid; /* the bracket is down to adjacent doubles */
        double f = c[deg], df = 0;
        for (int i = deg - 1; i >= 0; i--) {
            df = df * x + f;
            f = f * x + c[i];
        }
        if (f == 0) return x;
        if ((f < 0) == (flo < 0))
            lo = x;
        else
            hi = x;
        double xn = df != 0 ? x - f / df : 0.5 * (lo + hi);
        if (!(xn > lo && xn < hi)) xn = 0.5 * (lo + hi);
        if (fabs(xn - x) <= 1e-15 * (fabs(x) + scale)) return xn;
        x = xn;
    }
    return x;
}

/* Real roots of c2 x^2 + c1 x + c0 (c2 != 0) in [a, b], ascending, in the cancellation-free
 * form. */
static int quadratic_roots(const double *c, double a, double b, double *roots)
{
    double disc = c[1] * c[1] - 4 * c[2] * c[0];
    if (disc < 0) return 0;
    double q = -0.5 * (c[1] + (c[1] >= 0 ? 1 : -1) * sqrt(disc));
    double r0 = q / c[2], r1 = q != 0 ? c[0] / q : r0;
    if (r0 > r1) {
        double t = r0;
        r0 = r1;
        r1 = t;
    }
    int n = 0;
    if (r0 >= a && r0 <= b) roots[n++] = r0;
    if (r1 != r0 && r1 >= a && r1 <= b) roots[n++] = r1;
    return n;
}

int internal_sg_poly_roots(const double *c, int deg, double a, double b, double *roots)
{
    if (!(a <= b)) return 0;
    while (deg > 0 && c[deg] == 0)
        deg--;
    if (deg <= 0) return 0;
    if (deg == 1) {
        double x = -c[0] / c[1];
        if (x < a || x > b) return 0;
        roots[0] = x;
        return 1;
    }
    if (deg == 2) return quadratic_roots(c, a, b, roots);
    /* Critical points split [a, b] into monotone pieces. */
    double dc[4], crit[4], edges[6];
    for (int i = 1; i <= deg; i++)
        dc[i - 1] = i * c[i];
    int ncrit = internal_sg_poly_roots(dc, deg - 1, a, b, crit);
    int nedges = 0;
    edges[nedges++] = a;
    for (int i = 0; i < ncrit; i++)
        if (crit[i] > edges[nedges - 1] && crit[i] < b) edges[nedges++] = crit[i];
    edges[nedges++] = b;

    double scale = fabs(a) > fabs(b) ? fabs(a) : fabs(b);
    int n = 0;
    double flo = poly_eval(c, deg, edges[0]);
    if (flo == 0) roots[n++] = edges[0];
    for (int i = 0; i + 1 < nedges; i++) {
        double lo = edges[i], hi = edges[i + 1];
        double fhi = poly_eval(c, deg, hi);
        if (fhi == 0) {
            roots[n++] = hi; /* also covers a tangency exactly at a critical point */
        } else if (flo != 0 && (flo < 0) != (fhi < 0)) {
            roots[n++] = refine(c, deg, lo, hi, flo, scale);
        }
        flo = fhi;
    }
    return n;
}

int internal_sg_hit_plane(sg_vec3 o, sg_vec3 d, double tmin, double tmax, sg_hit *hit)
{
    if (d.z == 0) return 0;
    double t = -o.z / d.z;
    if (!(t > tmin && t < tmax)) return 0;
    hit->t = t;
    hit->p = sg_v(o.x + t * d.x, o.y + t * d.y, 0.0);
    hit->n = sg_v(0, 0, 1);
    hit->u = hit->p.x;
    hit->v = hit->p.y;
    return 1;
}

static double wrap01(double x)
{
    x -= floor(x);
    return x >= 1.0 ? 0.0 : x;
}

int internal_sg_hit_sphere(sg_vec3 o, sg_vec3 d, double r, double tmin, double tmax, sg_hit *hit)
{
    double a = sg_dot(d, d), b = sg_dot(o, d), c = sg_dot(o, o) - r * r;
    double disc = b * b - a * c;
    if (a == 0 || disc < 0) return 0;
    /* The stable form of the quadratic: no cancellation in either root. */
    double q = -(b + (b >= 0 ? 1 : -1) * sqrt(disc));
    double t0 = q / a, t1 = q != 0 ? c / q : t0;
    if (t0 > t1) {
        double s = t0;
        t0 = t1;
        t1 = s;
    }
    double t = t0 > tmin ? t0 : t1;
    if (!(t > tmin && t < tmax)) return 0;
    hit->t = t;
    hit->p = sg_add(o, sg_scale(d, t));
    hit->n = sg_normalize(hit->p);
    hit->u = wrap01(atan2(hit->n.x, hit->n.z) / (2 * k_pi));
    double cy = hit->n.y < -1 ? -1 : hit->n.y > 1 ? 1 : hit->n.y;
    hit->v = acos(cy) / k_pi;
    return 1;
}

int internal_sg_hit_box(sg_vec3 o, sg_vec3 d, double h, double tmin, double tmax, sg_hit *hit)
{
    const double oa[3] = {o.x, o.y, o.z}, da[3] = {d.x, d.y, d.z};
    double tnear = -INFINITY, tfar = INFINITY;
    int near_axis = -1, far_axis = -1;
    for (int i = 0; i < 3; i++) {
        if (da[i] == 0) {
            if (oa[i] < -h || oa[i] > h) return 0;
            continue;
        }
        double t0 = (-h - oa[i]) / da[i], t1 = (h - oa[i]) / da[i];
        if (t0 > t1) {
            double s = t0;
            t0 = t1;
            t1 = s;
        }
        if (t0 > tnear) {
            tnear = t0;
            near_axis = i;
        }
        if (t1 < tfar) {
            tfar = t1;
            far_axis = i;
        }
    }
    if (tnear > tfar || near_axis < 0) return 0;
    double t;
    int axis;
    if (tnear > tmin) {
        t = tnear;
        axis = near_axis;
    } else {
        t = tfar; /* the ray starts inside */
        axis = far_axis;
    }
    if (!(t > tmin && t < tmax)) return 0;
    double p[3] = {oa[0] + t * da[0], oa[1] + t * da[1], oa[2] + t * da[2]};
    /* Snap the face coordinate so Pref lies exactly on the face. */
    double side = p[axis] >= 0 ? 1.0 : -1.0;
    p[axis] = side * h;
    double n[3] = {0, 0, 0};
    n[axis] = side;
    int i1 = (axis + 1) % 3, i2 = (axis + 2) % 3;
    hit->t = t;
    hit->p = sg_v(p[0], p[1], p[2]);
    hit->n = sg_v(n[0], n[1], n[2]);
    hit->u = 0.5 * (p[i1] / h + 1);
    hit->v = 0.5 * (p[i2] / h + 1);
    return 1;
}

int internal_sg_hit_torus(sg_vec3 o, sg_vec3 d, double R, double r, double tmin, double tmax,
                       sg_hit *hit)
{
    /* Work with a unit direction from where the ray enters the bounding sphere, so the
     * quartic's coefficients stay of order one whatever the camera distance. */
    double dl = sg_len(d);
    if (dl == 0) return 0;
    sg_vec3 dn = sg_scale(d, 1.0 / dl);
    double br = R + r;
    double b = sg_dot(o, dn), c = sg_dot(o, o) - br * br;
    double disc = b * b - c;
    if (disc <= 0) return 0;
    double sq = sqrt(disc);
    double s0 = -b - sq, s1 = -b + sq; /* along dn */
    double smin = tmin * dl, smax = tmax * dl;
    if (s1 <= smin || s0 >= smax) return 0;
    double base = s0 > smin ? s0 : smin;
    double end = s1 < smax ? s1 : smax;
    sg_vec3 q = sg_add(o, sg_scale(dn, base));

    /* (|q + s dn|^2 + R^2 - r^2)^2 - 4 R^2 ((qx + s dnx)^2 + (qy + s dny)^2) = 0 */
    double qb = sg_dot(q, dn), e = sg_dot(q, q) + R * R - r * r, R4 = 4 * R * R;
    double cf[5];
    cf[4] = 1;
    cf[3] = 4 * qb;
    cf[2] = 4 * qb * qb + 2 * e - R4 * (dn.x * dn.x + dn.y * dn.y);
    cf[1] = 4 * qb * e - 2 * R4 * (q.x * dn.x + q.y * dn.y);
    cf[0] = e * e - R4 * (q.x * q.x + q.y * q.y);
    double roots[4];
    int n = internal_sg_poly_roots(cf, 4, 0.0, end - base, roots);
    double s = -1;
    for (int i = 0; i < n; i++)
        if (base + roots[i] > smin) {
            s = roots[i];
            break;
        }
    if (s < 0) return 0;
    double t = (base + s) / dl;
    if (!(t > tmin && t < tmax)) return 0;
    sg_vec3 p = sg_add(q, sg_scale(dn, s));
    double rho = sqrt(p.x * p.x + p.y * p.y);
    /* The normal points from the tube's centre line to p. */
    sg_vec3 centre = rho > 0 ? sg_v(p.x * R / rho, p.y * R / rho, 0) : sg_v(R, 0, 0);
    hit->t = t;
    hit->p = p;
    hit->n = sg_normalize(sg_sub(p, centre));
    hit->u = wrap01(atan2(p.y, p.x) / (2 * k_pi));
    hit->v = wrap01(atan2(p.z, rho - R) / (2 * k_pi));
    return 1;
}
