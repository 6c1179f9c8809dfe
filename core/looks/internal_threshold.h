/* The builtin threshold's step position as a table, for the node's pixel loop. Not installed.
 *
 * nprfx_threshold_builtin_mu solves mean(mu) = tone by Newton, a few erfc, exp and log per
 * solve: on a smooth tone (a diffuse pass) that is nearly every pixel, and it was most of the
 * node's time. mu is smooth in log(tone) (log(1 - tone) on the upper half), so a cubic Hermite
 * table over log t, with the exact derivative at each node, gives it to about 1e-12 for a
 * log and a few multiplies. Where mu is exactly 1 - tone (sigma t >= 6) and in the far tails
 * (t below MU_TABLE_T_MIN) the exact function is used. */
#ifndef NPRFX_INTERNAL_THRESHOLD_H
#define NPRFX_INTERNAL_THRESHOLD_H

#define MU_TABLE_N 1024
#define MU_TABLE_T_MIN 1e-6

typedef struct internal_mu_table {
    double sigma;
    double s0, inv_h; /* node i is at log t = s0 + i / inv_h */
    double t_max;     /* the table covers t in [MU_TABLE_T_MIN, t_max] */
    int n;            /* intervals; 0: no table (every t is exact or in the tails) */
    double mu[MU_TABLE_N + 1], dmu[MU_TABLE_N + 1]; /* mu and d mu / d log t at the nodes */
} internal_mu_table;

/* Fill the table for sigma (> 0). */
void internal_mu_table_init(internal_mu_table *tab, double sigma);

/* nprfx_threshold_builtin_mu(tone, sigma) for the table's sigma, to about 1e-12. */
double internal_mu_table_eval(const internal_mu_table *tab, double tone);

#endif
