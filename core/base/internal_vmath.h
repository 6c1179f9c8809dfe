/* exp and sincos in double, written twice with the same IEEE operations in the same order: once
 * for one value and once for the 8 lanes of a GCC/Clang vector, so a kernel's setup gives the
 * same numbers on the scalar path and the vector paths (docs/design.md §1: every path is
 * bit-identical; the build uses -ffp-contract=off). libm's functions cannot be called in lanes,
 * and calling them per value cost a fifth of Gabor emission.
 *
 * Accuracy: a few ulps of double (Cody-Waite reduction, Taylor polynomials whose truncation is far
 * below an ulp on the reduced range); the callers round to float, which matches libm's result
 * rounded to float except where the exact value lies within a few double ulps of a float
 * rounding boundary. Range: exp for any x (0 below -200 and +inf above 100, as libm's result
 * rounds to float there); sincos reduces |x| <= 1e5 and hands larger or non-finite x to libm. */
#ifndef NPRFX_INTERNAL_VMATH_H
#define NPRFX_INTERNAL_VMATH_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#define INTERNAL_VM_SHIFT 6755399441055744.0 /* 1.5 * 2^52: adding it rounds to an integer */
#define INTERNAL_VM_INV_LN2 1.44269504088896338700e+00
#define INTERNAL_VM_LN2_HI 6.93147180369123816490e-01 /* 32 bits: k * LN2_HI is exact */
#define INTERNAL_VM_LN2_LO 1.90821492927058770002e-10
#define INTERNAL_VM_2_PI 6.36619772367581382433e-01
#define INTERNAL_VM_PIO2_1 1.57079632673412561417e+00 /* pi/2 in three 33-bit parts: */
#define INTERNAL_VM_PIO2_2 6.07710050630396597660e-11 /* n * part is exact for |n| < 2^20 */
#define INTERNAL_VM_PIO2_3 2.02226624871116645580e-21
#define INTERNAL_VM_TRIG_MAX 1e5

/* e^r on |r| <= ln2 / 2: Taylor to r^13 (the next term is below 1e-17 relative) */
#define INTERNAL_VM_EXP_POLY(r)                                                                    \
    ((((((((((((((1.0 / 6227020800.0) * (r) + 1.0 / 479001600.0) * (r) + 1.0 / 39916800.0) * (r) + \
               1.0 / 3628800.0) *                                                                  \
                  (r) +                                                                            \
              1.0 / 362880.0) *                                                                    \
                 (r) +                                                                             \
             1.0 / 40320.0) *                                                                      \
                (r) +                                                                              \
            1.0 / 5040.0) *                                                                        \
               (r) +                                                                               \
           1.0 / 720.0) *                                                                          \
              (r) +                                                                                \
          1.0 / 120.0) *                                                                           \
             (r) +                                                                                 \
         1.0 / 24.0) *                                                                             \
            (r) +                                                                                  \
        1.0 / 6.0) *                                                                               \
           (r) +                                                                                   \
       0.5) *                                                                                      \
          (r) +                                                                                    \
      1.0) *                                                                                       \
         (r) +                                                                                     \
     1.0)

/* sin(r) - r = r^3 p(r^2) and cos(r) - 1 = r^2 q(r^2) on |r| <= pi/4: Taylor to r^17 and r^18 */
#define INTERNAL_VM_SIN_P(r2)                                                                      \
    ((((((((1.0 / 355687428096000.0) * (r2)-1.0 / 1307674368000.0) * (r2) + 1.0 / 6227020800.0) *  \
         (r2)-1.0 / 39916800.0) *                                                                  \
            (r2) +                                                                                 \
        1.0 / 362880.0) *                                                                          \
       (r2)-1.0 / 5040.0) *                                                                        \
          (r2) +                                                                                   \
      1.0 / 120.0) *                                                                               \
     (r2)-1.0 / 6.0)
#define INTERNAL_VM_COS_Q(r2)                                                                      \
    (((((((((-1.0 / 6402373705728000.0) * (r2) + 1.0 / 20922789888000.0) * (r2)-1.0 /              \
           87178291200.0) *                                                                        \
              (r2) +                                                                               \
          1.0 / 479001600.0) *                                                                     \
         (r2)-1.0 / 3628800.0) *                                                                   \
            (r2) +                                                                                 \
        1.0 / 40320.0) *                                                                           \
       (r2)-1.0 / 720.0) *                                                                         \
          (r2) +                                                                                   \
      1.0 / 24.0) *                                                                                \
     (r2)-0.5)

static inline double internal_vm_exp(double x)
{
    if (x != x) return x;
    if (x > 100.0) return HUGE_VAL;
    if (x < -200.0) return 0.0;
    double t = x * INTERNAL_VM_INV_LN2 + INTERNAL_VM_SHIFT, kd = t - INTERNAL_VM_SHIFT;
    double r = (x - kd * INTERNAL_VM_LN2_HI) - kd * INTERNAL_VM_LN2_LO;
    double p = INTERNAL_VM_EXP_POLY(r);
    uint64_t bits = (uint64_t)((int64_t)kd + 1023) << 52;
    double sc;
    memcpy(&sc, &bits, sizeof sc);
    return p * sc;
}

static inline void internal_vm_sincos(double x, double *s, double *c)
{
    if (!(fabs(x) <= INTERNAL_VM_TRIG_MAX)) {
        *s = sin(x);
        *c = cos(x);
        return;
    }
    double t = x * INTERNAL_VM_2_PI + INTERNAL_VM_SHIFT, nd = t - INTERNAL_VM_SHIFT;
    uint64_t tb;
    memcpy(&tb, &t, sizeof tb);
    double r = ((x - nd * INTERNAL_VM_PIO2_1) - nd * INTERNAL_VM_PIO2_2) - nd * INTERNAL_VM_PIO2_3;
    double r2 = r * r;
    double sp = r + (r * r2) * (INTERNAL_VM_SIN_P(r2));
    double cp = 1.0 + r2 * (INTERNAL_VM_COS_Q(r2));
    switch (tb & 3u) { /* the quadrant: n mod 4 */
    case 0:
        *s = sp;
        *c = cp;
        break;
    case 1:
        *s = cp;
        *c = -sp;
        break;
    case 2:
        *s = -sp;
        *c = -cp;
        break;
    default:
        *s = -cp;
        *c = sp;
        break;
    }
}

#if defined(__GNUC__) || defined(__clang__)
/* no vector type crosses a call (the functions are always inlined): no ABI question */
#if defined(__clang__)
#pragma clang diagnostic ignored "-Wpsabi"
#else
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
typedef double internal_vm8d __attribute__((vector_size(64)));
typedef int64_t internal_vm8l __attribute__((vector_size(64)));
typedef uint64_t internal_vm8u __attribute__((vector_size(64)));

#define INTERNAL_VM_SEL(m, a, b)                                                                   \
    ((internal_vm8d)(((internal_vm8l)(a) & (m)) | ((internal_vm8l)(b) & ~(m))))

/* internal_vm_exp in 8 lanes (always inlined: each instruction set's copy gets its own code) */
static inline __attribute__((always_inline)) internal_vm8d internal_vm_exp8(internal_vm8d x)
{
    internal_vm8l big = x > 100.0, small = x < -200.0, nan = x != x;
    internal_vm8d xc = INTERNAL_VM_SEL(big | small | nan, (internal_vm8d){0}, x);
    internal_vm8d t = xc * INTERNAL_VM_INV_LN2 + INTERNAL_VM_SHIFT, kd = t - INTERNAL_VM_SHIFT;
    internal_vm8d r = (xc - kd * INTERNAL_VM_LN2_HI) - kd * INTERNAL_VM_LN2_LO;
    internal_vm8d p = INTERNAL_VM_EXP_POLY(r);
    internal_vm8u bits = (internal_vm8u)(__builtin_convertvector(kd, internal_vm8l) + 1023) << 52;
    internal_vm8d e = p * (internal_vm8d)bits;
    e = INTERNAL_VM_SEL(big, (internal_vm8d){0} + HUGE_VAL, e);
    e = INTERNAL_VM_SEL(small, (internal_vm8d){0}, e);
    return INTERNAL_VM_SEL(nan, x, e);
}

/* internal_vm_sincos in 8 lanes */
static inline __attribute__((always_inline)) void
internal_vm_sincos8(internal_vm8d x, internal_vm8d *ps, internal_vm8d *pc)
{
    internal_vm8d ax = (internal_vm8d)((internal_vm8l)x & 0x7fffffffffffffffll);
    internal_vm8l far = ~(ax <= INTERNAL_VM_TRIG_MAX); /* NaN too */
    internal_vm8d xc = INTERNAL_VM_SEL(far, (internal_vm8d){0}, x);
    internal_vm8d t = xc * INTERNAL_VM_2_PI + INTERNAL_VM_SHIFT, nd = t - INTERNAL_VM_SHIFT;
    internal_vm8u q = (internal_vm8u)t & 3u;
    internal_vm8d r =
        ((xc - nd * INTERNAL_VM_PIO2_1) - nd * INTERNAL_VM_PIO2_2) - nd * INTERNAL_VM_PIO2_3;
    internal_vm8d r2 = r * r;
    internal_vm8d sp = r + (r * r2) * (INTERNAL_VM_SIN_P(r2));
    internal_vm8d cp = 1.0 + r2 * (INTERNAL_VM_COS_Q(r2));
    internal_vm8l odd = (internal_vm8l)((q & 1u) != 0);
    internal_vm8d s = INTERNAL_VM_SEL(odd, cp, sp), c = INTERNAL_VM_SEL(odd, -sp, cp);
    internal_vm8l neg = (internal_vm8l)((q & 2u) != 0);
    s = INTERNAL_VM_SEL(neg, -s, s);
    c = INTERNAL_VM_SEL(neg, -c, c);
    for (int k = 0; k < 8; k++)
        if (far[k]) {
            s[k] = sin(x[k]);
            c[k] = cos(x[k]);
        }
    *ps = s;
    *pc = c;
}
#endif

#endif
