/* Counter-based random numbers: moments, uniformity, independence of neighbouring counters and
 * determinism. Tolerances are several standard errors of the estimates (1e6 draws). */
#include <math.h>
#include <stdint.h>

#include "check.h"
#include "nprfx/rng.h"

#define DRAWS 1000000
#define SIDE 1000 /* DRAWS = SIDE^2 pixels */

static void test_uniform(void)
{
    double s = 0, s2 = 0, lo = 1, hi = 0;
    long hist[64] = {0};
    for (int y = 0; y < SIDE; y++)
        for (int x = 0; x < SIDE; x++) {
            double u = nprfx_rand_u01(42, 7, x, y, 0, 0);
            s += u;
            s2 += u * u;
            lo = u < lo ? u : lo;
            hi = u > hi ? u : hi;
            hist[(int)(u * 64)]++;
        }
    double mean = s / DRAWS, var = s2 / DRAWS - mean * mean;
    /* standard errors: 2.9e-4 for the mean, 7.5e-5 for the variance */
    CHECK_NEAR(mean, 0.5, 2e-3);
    CHECK_NEAR(var, 1.0 / 12.0, 5e-4);
    CHECK(lo >= 0.0 && hi < 1.0);
    CHECK(lo < 1e-4 && hi > 1 - 1e-4);
    /* chi-square over 64 bins, 63 degrees of freedom: mean 63, sd 11; 130 is p ~ 1e-6 */
    double chi = 0, e = DRAWS / 64.0;
    for (int i = 0; i < 64; i++)
        chi += (hist[i] - e) * (hist[i] - e) / e;
    CHECK(chi < 130.0);
}

static void test_gauss(void)
{
    double s = 0, s2 = 0, s3 = 0, s4 = 0;
    long tail = 0, bad = 0;
    for (int y = 0; y < SIDE; y++)
        for (int x = 0; x < SIDE; x++) {
            double g = nprfx_rand_gauss(9, -3, x - 500, y - 500, 2, 1);
            bad += !isfinite(g);
            s += g;
            s2 += g * g;
            s3 += g * g * g;
            s4 += g * g * g * g;
            tail += fabs(g) > 2.0;
        }
    CHECK(bad == 0);
    double mean = s / DRAWS, var = s2 / DRAWS - mean * mean;
    /* standard errors: 1e-3 (mean), 1.4e-3 (variance), 2.4e-3 (third), 1e-2 (fourth moment) */
    CHECK_NEAR(mean, 0.0, 5e-3);
    CHECK_NEAR(var, 1.0, 7e-3);
    CHECK_NEAR(s3 / DRAWS, 0.0, 0.015);
    CHECK_NEAR(s4 / DRAWS, 3.0, 0.05);
    /* P(|g| > 2) = 0.0455003, sd 2.1e-4 */
    CHECK_NEAR((double)tail / DRAWS, 0.0455003, 1.5e-3);
}

/* Pearson correlation between draws at counters differing in one field. Under independence the
 * estimate has standard error 1/sqrt(n) = 1e-3. */
enum { FIELD_X, FIELD_Y, FIELD_FRAME, FIELD_CHANNEL, FIELD_STREAM, FIELD_SEED };

static double draw(int field, int delta, int x, int y)
{
    uint64_t seed = 1000 + (field == FIELD_SEED ? delta : 0);
    int64_t frame = 12 + (field == FIELD_FRAME ? delta : 0);
    int32_t px = x + (field == FIELD_X ? delta : 0), py = y + (field == FIELD_Y ? delta : 0);
    uint32_t ch = 1 + (field == FIELD_CHANNEL ? delta : 0);
    uint32_t st = 0 + (field == FIELD_STREAM ? delta : 0);
    return nprfx_rand_u01(seed, frame, px, py, ch, st);
}

static void test_neighbours(void)
{
    for (int field = FIELD_X; field <= FIELD_SEED; field++) {
        double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
        for (int y = 0; y < SIDE; y++)
            for (int x = 0; x < SIDE; x++) {
                double a = draw(field, 0, x, y), b = draw(field, 1, x, y);
                sa += a;
                sb += b;
                saa += a * a;
                sbb += b * b;
                sab += a * b;
            }
        const double n = DRAWS;
        double cov = sab / n - (sa / n) * (sb / n);
        double r = cov / sqrt((saa / n - (sa / n) * (sa / n)) * (sbb / n - (sb / n) * (sb / n)));
        CHECK(fabs(r) < 5e-3 || (printf("field %d: correlation %g\n", field, r), 0));
    }
    /* the low bits too: parity of neighbours agrees half the time */
    long agree = 0;
    for (int x = 0; x < DRAWS; x++)
        agree += (nprfx_hash(5, 0, x, 0, 0, 0) & 1) == (nprfx_hash(5, 0, x + 1, 0, 0, 0) & 1);
    CHECK_NEAR((double)agree / DRAWS, 0.5, 2.5e-3);
    /* x and y are not interchangeable, nor x and channel */
    int swaps = 0;
    for (int i = 0; i < 1000; i++) {
        swaps += nprfx_hash(1, 0, i, i + 1, 0, 0) == nprfx_hash(1, 0, i + 1, i, 0, 0);
        swaps += nprfx_hash(1, 0, i, 0, i + 1, 0) == nprfx_hash(1, 0, i + 1, 0, i, 0);
    }
    CHECK(swaps == 0);
}

static void test_determinism(void)
{
    /* a pure function of the counter */
    CHECK(nprfx_hash(1, 2, 3, 4, 5, 6) == nprfx_hash(1, 2, 3, 4, 5, 6));
    CHECK(nprfx_rand_gauss(1, 2, -3, 4, 5, 6) == nprfx_rand_gauss(1, 2, -3, 4, 5, 6));
    /* SplitMix64 reference: the first output of a generator seeded with 0 is mix64(0) */
    CHECK(nprfx_mix64(0) == 0xe220a8397b1dcdafull);
    /* every field matters */
    uint64_t h = nprfx_hash(1, 2, 3, 4, 5, 6);
    CHECK(h != nprfx_hash(2, 2, 3, 4, 5, 6));
    CHECK(h != nprfx_hash(1, 3, 3, 4, 5, 6));
    CHECK(h != nprfx_hash(1, 2, 4, 4, 5, 6));
    CHECK(h != nprfx_hash(1, 2, 3, 5, 5, 6));
    CHECK(h != nprfx_hash(1, 2, 3, 4, 6, 6));
    CHECK(h != nprfx_hash(1, 2, 3, 4, 5, 7));
    /* u01 keeps 53 bits: the extremes of the hash map to 0 and just below 1 */
    CHECK(nprfx_u01(0) == 0.0);
    CHECK(nprfx_u01(UINT64_MAX) < 1.0 && nprfx_u01(UINT64_MAX) > 1.0 - 1e-15);
}

int main(void)
{
    test_uniform();
    test_gauss();
    test_neighbours();
    test_determinism();
    return check_finish();
}
