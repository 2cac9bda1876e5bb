/* The prefix sums of the neighbour build (cd_nb_scan: a tree of 64-entry
 * chunks, kernels/neighbor_items.h) where the loops run: host threads, or
 * the offload device (CAPDEM_OFFLOAD=host: separate memory, so the test
 * copies in and out as the build does).  Sizes at every edge of the tree's
 * levels (one chunk; 64 and 4,096 entries and one more; past 262,144, three
 * levels, which the physics tests with their few thousand particles never
 * reach) against a serial sum, the total out[n] included, and the scratch
 * (cd_scan_scratch entries) not overrun. */
#include "test_util.h"
#include "backend/omp/omp_loops.h"
#include "neighbor_items.h"

/* Entries written past the scratch would overwrite this. */
#define CANARY 0x5ca9

static void scan_matches_serial_sum(cd_int n)
{
    size_t scratch = (size_t)cd_scan_scratch(n);
    cd_int *in = malloc(((size_t)n + 1) * sizeof(cd_int)), *out = malloc(((size_t)n + 1) * sizeof(cd_int));
    cd_int *sums = malloc((scratch + 1) * sizeof(cd_int));
    assert_true(in && out && sums);
    uint32_t r = 12345u + (uint32_t)n;
    for (cd_int k = 0; k < n; k++) {
        r = r * 1664525u + 1013904223u;
        in[k] = (cd_int)(r >> 28); /* 0 .. 15: a cell count, a histogram entry */
    }
    for (size_t k = 0; k <= scratch; k++) sums[k] = CANARY;
    cd_int *d_in = cd_dev_alloc(((size_t)n + 1) * sizeof(cd_int)),
           *d_out = cd_dev_alloc(((size_t)n + 1) * sizeof(cd_int));
    cd_int *d_sums = cd_dev_alloc((scratch + 1) * sizeof(cd_int));
    assert_true(d_in && d_out && d_sums);
    assert_int_equal(cd_dev_put(d_in, in, (size_t)n * sizeof(cd_int)), 0);
    assert_int_equal(cd_dev_put(d_sums, sums, (scratch + 1) * sizeof(cd_int)), 0);
    cd_nb_scan(d_in, n, d_out, d_sums);
    assert_int_equal(cd_dev_get(out, d_out, ((size_t)n + 1) * sizeof(cd_int)), 0);
    assert_int_equal(cd_dev_get(sums, d_sums, (scratch + 1) * sizeof(cd_int)), 0);
    cd_int run = 0, wrong = 0;
    for (cd_int k = 0; k < n; k++) {
        if (out[k] != run && wrong++ < 3) fprintf(stderr, "n %d: out[%d] = %d, expected %d\n", n, k, out[k], run);
        run += in[k];
    }
    assert_int_equal(wrong, 0);
    assert_int_equal(out[n], run);
    assert_int_equal(sums[scratch], CANARY);
    cd_dev_free(d_in);
    cd_dev_free(d_out);
    cd_dev_free(d_sums);
    free(in);
    free(out);
    free(sums);
}

static void test_scan_tree_equals_serial_prefix_sum(void **state)
{
    (void)state;
    const cd_int sizes[] = {0, 1, 63, 64, 65, 4095, 4096, 4097, 70000, 262144, 262145, 300001};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) scan_matches_serial_sum(sizes[k]);
}

/* The scratch the build allocates holds every level: counted here by
 * hand for the sizes the levels change at. */
static void test_scan_scratch_counts_every_level(void **state)
{
    (void)state;
    assert_int_equal(cd_scan_scratch(64), 1);         /* one chunk: no level */
    assert_int_equal(cd_scan_scratch(65), 1 + 2 + 1); /* 2 chunk sums and their total */
    assert_int_equal(cd_scan_scratch(4097), 1 + 65 + 1 + 2 + 1);
    assert_int_equal(cd_nb_box_scratch(64), 1);        /* one box */
    assert_int_equal(cd_nb_box_scratch(4097), 65 + 2); /* 65 boxes, 2 above */
    assert_int_equal(cd_reorder_hist_entries(65), 2 * CD_RADIX_BINS);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scan_tree_equals_serial_prefix_sum),
        cmocka_unit_test(test_scan_scratch_counts_every_level),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
