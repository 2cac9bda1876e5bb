/* The observables' pair leaves (kernels/observe_items.h) are functions of
 * global primitive ids, which the MPI reduction relies on (docs/mpi.md,
 * "Reductions"): a rank's list holds other inactive candidate rows than
 * the serial list (after a bulk-probe restore 90 rows against 209), and
 * the leaves must give the same bits whatever the inactive rows.  Plain
 * C: runs in every build. */
#include "test_util.h"
#include "observe_items.h"

enum { PRIMS = 200, MAX_ROWS = 4000 };

typedef struct {
    cd_flag active[MAX_ROWS];
    cd_int pi[MAX_ROWS], pj[MAX_ROWS];
    double overlap[MAX_ROWS]; /* [m] */
    cd_vec3 shear[MAX_ROWS];  /* [m] */
    long n;
} pair_rows;

static unsigned long next(unsigned long *seed)
{
    *seed = *seed * 6364136223846793005UL + 1442695040888963407UL;
    return *seed >> 33;
}

/* Rows in key order (i, then j): the active ones drawn once (every list
 * has them), plus `inactive` candidates in 1000 per row slot. */
static void make_rows(pair_rows *r, int inactive)
{
    unsigned long contacts = 7, extra = 11 + (unsigned long)inactive;
    r->n = 0;
    for (cd_int i = 0; i < PRIMS; i++)
        for (cd_int j = i + 1; j < PRIMS && j < i + 12; j++) {
            int active = next(&contacts) % 3 == 0;
            double overlap = 1e-5 * (double)(1 + next(&contacts) % 97); /* drawn for every (i, j): same inputs */
            double s = 1e-6 * (double)(next(&contacts) % 13);
            int keep = active || (long)(next(&extra) % 1000) < inactive;
            if (!keep) continue;
            r->active[r->n] = active;
            r->pi[r->n] = i;
            r->pj[r->n] = j;
            r->overlap[r->n] = active ? overlap : 0;
            r->shear[r->n] = (cd_vec3){s, -s, 0.5 * s};
            r->n++;
        }
}

static cd_cols cols_of(pair_rows *r, double *radius)
{
    cd_cols c;
    memset(&c, 0, sizeof c);
    c.pair_active = r->active;
    c.pair_prim_i = r->pi;
    c.pair_prim_j = r->pj;
    c.pair_shear = r->shear;
    c.prim_radius = radius;
    return c;
}

/* Two lists with the same active rows and 50 or 900 inactive rows per
 * thousand slots: every leaf's slots equal bit for bit, and each leaf holds
 * the contacts of its 64 primitives. */
static void test_pair_leaves_ignore_inactive_rows(void **state)
{
    (void)state;
    static pair_rows few, many;
    double radius[PRIMS]; /* [m] */
    for (int i = 0; i < PRIMS; i++) radius[i] = 1e-3 * (1 + 0.01 * (i % 7));
    make_rows(&few, 50);
    make_rows(&many, 900);
    assert_true(many.n > few.n + 500);
    cd_law_params law;
    memset(&law, 0, sizeof law);
    law.kn = 1e5;
    law.kt = 5e4;
    cd_cols a = cols_of(&few, radius), b = cols_of(&many, radius);
    long leaves = (long)cd_obs_pair_blocks(PRIMS);
    assert_int_equal(leaves, 4);
    double total = 0;
    for (long leaf = 0; leaf < leaves; leaf++) {
        double sa[CD_OBS_SLOTS], sb[CD_OBS_SLOTS];
        cd_obs_block_pairs(a, leaf, few.n, law, sa, cd_order_identity(), few.overlap, 0, 0);
        cd_obs_block_pairs(b, leaf, many.n, law, sb, cd_order_identity(), many.overlap, 0, 0);
        assert_memory_equal(sa, sb, sizeof sa);
        long contacts = 0;
        for (long k = 0; k < few.n; k++) contacts += few.active[k] && few.pi[k] / CD_OBS_BLOCK == leaf;
        assert_true(contacts > 0);
        assert_true(sa[CD_OBS_NC] == (double)contacts);
        assert_true(sa[CD_OBS_EL] > 0);
        total += sa[CD_OBS_NC];
    }
    long all = 0;
    for (long k = 0; k < few.n; k++) all += few.active[k];
    assert_true(total == (double)all);
    /* an empty list sums to nothing */
    double s[CD_OBS_SLOTS];
    cd_obs_block_pairs(a, 0, 0, law, s, cd_order_identity(), few.overlap, 0, 0);
    assert_true(s[CD_OBS_NC] == 0 && s[CD_OBS_EL] == 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_pair_leaves_ignore_inactive_rows)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
