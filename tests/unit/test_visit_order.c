/* The pair pass's visiting order (kernels/neighbor_items.h, pass 11): the
 * items of its counting sort (count per chunk of rows, a scan, fill per
 * chunk), which the omp build (host threads, offload) and the OpenCL
 * kernels run alike, give a permutation of the rows grouped by kind (two
 * points, a point and a segment, two segments), each group in ascending
 * row order, for row counts around the chunk size and over many chunks;
 * and the checker the tests use (tests/test_util.h) refuses an order that
 * is not a permutation or not grouped. */
#include "test_util.h"
#include "neighbor_items.h"

/* A list of n rows over P primitives: every third primitive a ball
 * without an arm, every seventh an arm of zero length (a point too, by
 * its ends), the rest arms; rows between random primitives. */
typedef struct {
    cd_cols c;
    cd_vec3 *prim_a;
    cd_int *prim_arm, *pair_i, *pair_j, *kind;
    cd_arm *arm;
} rows_fixture;

static void make_rows(rows_fixture *f, size_t n, size_t P, unsigned seed)
{
    memset(f, 0, sizeof *f);
    f->prim_a = calloc(P, sizeof *f->prim_a);
    f->prim_arm = calloc(P, sizeof *f->prim_arm);
    f->arm = calloc(P, sizeof *f->arm);
    f->pair_i = calloc(n + 1, sizeof(cd_int));
    f->pair_j = calloc(n + 1, sizeof(cd_int));
    f->kind = calloc(n + 1, sizeof(cd_int));
    assert_non_null(f->prim_a && f->prim_arm && f->arm && f->pair_i && f->pair_j && f->kind);
    int *point = calloc(P, sizeof(int));
    assert_non_null(point);
    cd_int arms = 0;
    for (size_t i = 0; i < P; i++) {
        f->prim_a[i] = cd_v3(0.01 * (double)i, 0.002 * (double)(i % 5), 0);
        if (i % 3 == 0) {
            f->prim_arm[i] = -1; /* a ball: end b is its end a */
            point[i] = 1;
        } else {
            f->prim_arm[i] = arms;
            point[i] = i % 7 == 0;
            f->arm[arms].b = point[i] ? f->prim_a[i] : cd_v3_add(f->prim_a[i], cd_v3(0.003, 0.001, 0));
            arms++;
        }
    }
    srand(seed);
    for (size_t k = 0; k < n; k++) {
        f->pair_i[k] = (cd_int)((size_t)rand() % P);
        f->pair_j[k] = (cd_int)((size_t)rand() % P);
        f->kind[k] = 2 - point[f->pair_i[k]] - point[f->pair_j[k]];
    }
    free(point);
    f->c.prim_a = f->prim_a;
    f->c.prim_arm = f->prim_arm;
    f->c.arm = f->arm;
    f->c.pair_prim_i = f->pair_i;
    f->c.pair_prim_j = f->pair_j;
}

static void free_rows(rows_fixture *f)
{
    free(f->prim_a);
    free(f->prim_arm);
    free(f->arm);
    free(f->pair_i);
    free(f->pair_j);
    free(f->kind);
}

/* The visiting order of the n rows of f by the build's items (the scan
 * of the starts by its items too, chunk by chunk as cd_nb_scan runs them). */
static cd_int *visit_order_of(const rows_fixture *f, size_t n)
{
    cd_long m = cd_nb_visit_chunks((cd_long)n), entries = CD_ROW_KINDS * m;
    cd_int *starts = calloc((size_t)entries + 1, sizeof(cd_int)), *visit = calloc(n + 1, sizeof(cd_int));
    cd_int *scratch = calloc((size_t)cd_scan_scratch(entries), sizeof(cd_int));
    assert_non_null(starts && visit && scratch);
    for (size_t k = 0; k <= n; k++) visit[k] = -1;
    for (cd_long g = 0; g < m; g++) cd_nb_item_visit_count(f->c, g, (cd_long)n, starts);
    /* the kind-major counts scanned in place: one level of chunk sums when
     * there are more than CD_SCAN_CHUNK entries (the tests' sizes) */
    if (entries > CD_SCAN_CHUNK) {
        cd_long chunks = (entries + CD_SCAN_CHUNK - 1) / CD_SCAN_CHUNK;
        assert_true(chunks <= CD_SCAN_CHUNK);
        for (cd_long g = 0; g < chunks; g++) cd_scan_item_sum(starts, entries, g, scratch);
        cd_scan_item_top(scratch, chunks, scratch);
        for (cd_long g = 0; g < chunks; g++) cd_scan_item_fill(starts, entries, g, scratch, starts);
    } else {
        cd_scan_item_top(starts, entries, starts);
    }
    assert_int_equal(entries ? starts[entries] : 0, (cd_int)n);
    for (cd_long g = 0; g < m; g++) cd_nb_item_visit_fill(f->c, g, (cd_long)n, starts, visit);
    free(starts);
    free(scratch);
    return visit;
}

static void test_visit_order_is_a_permutation_grouped_by_kind(void **state)
{
    (void)state;
    const size_t sizes[] = {1, 2, 31, 63, 64, 65, 127, 128, 129, 1000, 3001};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        size_t n = sizes[s];
        rows_fixture f;
        make_rows(&f, n, 97, (unsigned)(11 + s));
        cd_int *visit = visit_order_of(&f, n);
        const char *defect = cdt_visit_order_defect(visit, f.kind, n, 1);
        if (defect) fail_msg("%zu rows: %s", n, defect);
        /* the kinds the items see are those of the rows' ends */
        for (size_t k = 0; k < n; k++) assert_int_equal(cd_nb_row_kind(f.c, (cd_long)k), f.kind[k]);
        /* a list of 1,000 rows holds every kind, and the order then has
         * exactly two kind boundaries */
        if (n >= 1000) {
            int boundaries = 0;
            for (size_t v = 1; v < n; v++) boundaries += f.kind[visit[v]] != f.kind[visit[v - 1]];
            assert_int_equal(boundaries, 2);
        }
        free(visit);
        free_rows(&f);
    }
}

/* The checker refuses a repeated row, a row out of range, rows of one
 * kind out of order and a kind visited after a higher one. */
static void test_visit_order_checker_refuses_defects(void **state)
{
    (void)state;
    const cd_int kind[6] = {2, 0, 1, 0, 2, 1};
    const cd_int good[6] = {1, 3, 2, 5, 0, 4};
    const cd_int repeated[6] = {1, 3, 2, 5, 0, 0}, outside[6] = {1, 3, 2, 5, 0, 6};
    const cd_int unsorted[6] = {3, 1, 2, 5, 0, 4}, ungrouped[6] = {1, 2, 3, 5, 0, 4};
    assert_null(cdt_visit_order_defect(good, kind, 6, 1));
    assert_non_null(cdt_visit_order_defect(repeated, kind, 6, 1));
    assert_non_null(cdt_visit_order_defect(outside, kind, 6, 1));
    assert_non_null(cdt_visit_order_defect(unsorted, kind, 6, 1));
    assert_non_null(cdt_visit_order_defect(ungrouped, kind, 6, 1));
    /* (rows of a kind out of order are allowed where the order was made in another row order) */
    assert_null(cdt_visit_order_defect(unsorted, kind, 6, 0));
    assert_non_null(cdt_visit_order_defect(ungrouped, kind, 6, 0));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_visit_order_is_a_permutation_grouped_by_kind),
        cmocka_unit_test(test_visit_order_checker_refuses_defects),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
