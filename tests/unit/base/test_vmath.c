/* internal_vmath.h: exp and sincos for Gabor kernels' setup. Exact values where the answer is
 * known, agreement with libm to a few double ulps and (after rounding to float, as the kernels
 * use them) exactly on 3.2M arguments over the ranges the kernels see and beyond, the edges
 * (underflow, overflow, NaN, libm's hand-over above 1e5), and the 8-lane versions bit-identical
 * to the scalar ones on every argument. */
#include <stdint.h>

#include "check.h"
#include "base/internal_vmath.h"

static double arg(uint64_t *s, int range)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    double u = (double)(*s >> 11) * (1.0 / 9007199254740992.0);
    switch (range) {
    case 0:
        return -60.0 * u; /* envelopes: -pi a^2 d^2 */
    case 1:
        return (u - 0.5) * 40.0; /* phases of low-frequency kernels, envelope ratios */
    case 2:
        return (u - 0.5) * 2.2e5; /* up to and past the reduction's range */
    default:
        return (u - 0.5) * 1e3;
    }
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0 || (a != a && b != b);
}

static int same_float(double a, double b)
{
    float fa = (float)a, fb = (float)b;
    return fa == fb || (fa != fa && fb != fb);
}

static void test_known_values(void)
{
    double s, c;
    CHECK(internal_vm_exp(0.0) == 1.0);
    CHECK(internal_vm_exp(-0.0) == 1.0);
    CHECK_NEAR(internal_vm_exp(1.0), 2.718281828459045, 1e-15);
    CHECK_NEAR(internal_vm_exp(-1.0) * 2.718281828459045, 1.0, 1e-15);
    CHECK(internal_vm_exp(-200.5) == 0.0);     /* libm's 1e-87 rounds to float 0 */
    CHECK(internal_vm_exp(100.5) == HUGE_VAL); /* and 4e43 to float inf */
    CHECK(isnan(internal_vm_exp(NAN)));
    CHECK(internal_vm_exp(-INFINITY) == 0.0);
    CHECK(internal_vm_exp(INFINITY) == HUGE_VAL);
    internal_vm_sincos(0.0, &s, &c);
    CHECK(s == 0.0 && c == 1.0);
    internal_vm_sincos(3.14159265358979323846 / 6.0, &s, &c);
    CHECK_NEAR(s, 0.5, 2e-16);
    CHECK_NEAR(c, 0.86602540378443864676, 2e-16);
    internal_vm_sincos(-3.14159265358979323846, &s, &c); /* quadrant 2 */
    CHECK_NEAR(s, 0.0, 1e-15);
    CHECK_NEAR(c, -1.0, 1e-16);
    internal_vm_sincos(1.5e5, &s, &c); /* libm's, beyond the reduction's range */
    CHECK(same_bits(s, sin(1.5e5)) && same_bits(c, cos(1.5e5)));
    internal_vm_sincos(NAN, &s, &c);
    CHECK(isnan(s) && isnan(c));
}

static void test_against_libm(void)
{
    uint64_t st = 1;
    long n = 0, fe = 0, fs = 0, fc = 0;
    double emax = 0.0, tmax = 0.0;
    for (int i = 0; i < 400000; i++)
        for (int k = 0; k < 8; k++, n++) {
            double x = arg(&st, i % 4), e = internal_vm_exp(x), s, c;
            internal_vm_sincos(x, &s, &c);
            double le = exp(x);
            if (x >= -200.0 && x <= 100.0 && fabs(e / le - 1.0) > emax) emax = fabs(e / le - 1.0);
            if (fabs(x) <= 1e5) {
                tmax = fabs(s - sin(x)) > tmax ? fabs(s - sin(x)) : tmax;
                tmax = fabs(c - cos(x)) > tmax ? fabs(c - cos(x)) : tmax;
            }
            fe += !same_float(e, le);
            fs += !same_float(s, sin(x));
            fc += !same_float(c, cos(x));
        }
    printf("vmath: %ld arguments; largest relative exp error %.3g, largest sin/cos error %.3g; "
           "float results unlike libm's: exp %ld, sin %ld, cos %ld\n",
           n, emax, tmax, fe, fs, fc);
    CHECK(emax < 1e-15); /* a few ulps */
    CHECK(tmax < 1e-15);
    /* as floats the results are libm's (none differs here; a different libm may round a
     * boundary case the other way) */
    CHECK(fe + fs + fc <= n / 1000000);
}

static void test_lanes_match_scalar(void)
{
    uint64_t st = 2;
    long bad = 0;
    const double edge[8] = {NAN, INFINITY, -INFINITY, 2e5, -300.0, 150.0, 0.0, -0.0};
    for (int i = 0; i < 400000; i++) {
        double x[8];
        for (int k = 0; k < 8; k++)
            x[k] = i == 7 ? edge[k] : arg(&st, (i + k) % 4);
        internal_vm8d v, e, s, c;
        memcpy(&v, x, sizeof v);
        e = internal_vm_exp8(v);
        internal_vm_sincos8(v, &s, &c);
        for (int k = 0; k < 8; k++) {
            double ss, cc;
            internal_vm_sincos(x[k], &ss, &cc);
            bad += !same_bits(e[k], internal_vm_exp(x[k])) + !same_bits(s[k], ss) +
                   !same_bits(c[k], cc);
        }
    }
    CHECK(bad == 0);
}

int main(void)
{
    test_known_values();
    test_against_libm();
    test_lanes_match_scalar();
    return check_finish();
}
