/* The sub-domains of an MPI run (src/mpi/mpi_decomp.c, docs/mpi.md): the
 * Cartesian grid chosen from the ranks and the domain, refusals of grids
 * the domain cannot hold, the owner of a point and the ranks whose halo
 * holds it, the neighbours a rank talks to, and recursive coordinate
 * bisection.  Plain C: runs in every build, with or without MPI. */
#include "test_util.h"
#include <math.h>
#include "mpi/mpi_decomp.h"

static cd_config config(int dimension, double gx, double gy, double gz)
{
    cd_config c;
    memset(&c, 0, sizeof c);
    snprintf(c.source_path, sizeof c.source_path, "test.yaml");
    c.dimension = dimension;
    c.gravity[0] = gx;
    c.gravity[1] = gy;
    c.gravity[2] = gz;
    return c;
}

/* Auto grids: the gravity axis (y) stays whole; the cut area decides
 * between x and z; 2D never splits z. */
static void test_auto_grid(void **state)
{
    (void)state;
    char err[512];
    cd_decomp_grid g;
    cd_config c = config(3, 0, -9.81, 0);
    double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 0.5}; /* [m] */
    assert_int_equal(cd_decomp_choose(&g, &c, 2, lo, hi, 0.1, 0, err, sizeof err), 0);
    /* a cut across x has area 1 x 0.5, across z 1 x 1 */
    assert_int_equal(g.dims[0], 2);
    assert_int_equal(g.dims[1], 1);
    assert_int_equal(g.dims[2], 1);
    assert_int_equal(cd_decomp_choose(&g, &c, 4, lo, hi, 0.1, 0, err, sizeof err), 0);
    assert_int_equal(g.dims[0] * g.dims[1] * g.dims[2], 4);
    assert_int_equal(g.dims[1], 1);
    assert_int_equal(g.dims[0], 2); /* 2 x 2 (area 1.5) beats 4 x 1 (1.5) by order, 1 x 4 (3) */
    assert_true(g.width[0] == 0.5);
    assert_true(g.halo == 0.1);
    cd_config c2 = config(2, 0, -9.81, 0);
    assert_int_equal(cd_decomp_choose(&g, &c2, 3, lo, hi, 0.1, 0, err, sizeof err), 0);
    assert_int_equal(g.dims[0], 3);
    assert_int_equal(g.dims[2], 1);
}

/* More ranks than sub-domains of at least the interaction range: refused,
 * naming the file and the limits; a given grid checked the same way. */
static void test_refusals(void **state)
{
    (void)state;
    char err[512];
    cd_decomp_grid g;
    cd_config c = config(2, 0, -9.81, 0);
    double lo[3] = {0, 0, 0}, hi[3] = {0.25, 0.15, 0}; /* [m]: 2 x 1 sub-domains of 0.1 m at most */
    assert_int_equal(cd_decomp_choose(&g, &c, 2, lo, hi, 0.1, 0, err, sizeof err), 0);
    assert_int_equal(cd_decomp_choose(&g, &c, 3, lo, hi, 0.1, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "test.yaml: 3 MPI ranks: more than the domain can be split into"));
    assert_non_null(strstr(err, "at most 2 x 1 x 1"));
    c.mpi_grid[0] = 1, c.mpi_grid[1] = 2, c.mpi_grid[2] = 1;
    assert_int_equal(cd_decomp_choose(&g, &c, 2, lo, hi, 0.1, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "mpi.grid = [1, 2, 1]: 2 sub-domains along y"));
    c.mpi_grid[0] = 2, c.mpi_grid[1] = 1, c.mpi_grid[2] = 1;
    assert_int_equal(cd_decomp_choose(&g, &c, 3, lo, hi, 0.1, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "makes 2 sub-domains, but the run has 3 MPI ranks"));
    c.mpi_grid[0] = 1.5;
    assert_int_equal(cd_decomp_choose(&g, &c, 3, lo, hi, 0.1, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "expected three integers >= 1"));
}

/* g: the nx x ny x nz grid (mpi.grid) over the box 0..hi [m], gravity-free. */
static void given_grid(cd_decomp_grid *g, int nx, int ny, int nz, const double hi[3], double range, double margin)
{
    char err[512];
    cd_config c = config(3, 0, 0, 0);
    c.mpi_grid[0] = nx, c.mpi_grid[1] = ny, c.mpi_grid[2] = nz;
    double lo[3] = {0, 0, 0};
    assert_int_equal(cd_decomp_choose(g, &c, nx * ny * nz, lo, hi, range, margin, err, sizeof err), 0);
}

/* Owners by the centre (outer sub-domains open to infinity, NaN to the
 * first); ghosts in every sub-domain within the halo, corners by the
 * Euclidean distance, ascending, never the owner. */
static void test_owner_and_ghosts(void **state)
{
    (void)state;
    cd_decomp_grid g;
    double hi[3] = {2, 1, 2}; /* [m] */
    given_grid(&g, 2, 1, 2, hi, 0.1, 0.05);
    assert_true(fabs(g.halo - 0.15) < 1e-15);
    double a[3] = {0.5, 0.5, 0.5}, b[3] = {1.5, 0.5, 0.5}, cc[3] = {0.5, 0.5, 1.5}, far[3] = {-7, 9, 30};
    assert_int_equal(cd_decomp_owner(&g, a), 0);
    assert_int_equal(cd_decomp_owner(&g, b), 1);
    assert_int_equal(cd_decomp_owner(&g, cc), 2);
    assert_int_equal(cd_decomp_owner(&g, far), 2);
    double nan3[3] = {NAN, NAN, NAN};
    assert_int_equal(cd_decomp_owner(&g, nan3), 0);
    int r[4];
    assert_int_equal(cd_decomp_ghost_ranks(&g, a, 0, r), 0);
    double edge[3] = {0.9, 0.5, 0.5}; /* 0.1 m from the x cut */
    assert_int_equal(cd_decomp_ghost_ranks(&g, edge, 0, r), 1);
    assert_int_equal(r[0], 1);
    double corner[3] = {0.9, 0.5, 0.9}; /* 0.1 m from both cuts, 0.141 m from the diagonal sub-domain */
    assert_int_equal(cd_decomp_ghost_ranks(&g, corner, 0, r), 3);
    assert_int_equal(r[0], 1);
    assert_int_equal(r[1], 2);
    assert_int_equal(r[2], 3);
    double corner2[3] = {0.88, 0.5, 0.88}; /* 0.12 m from both cuts, 0.17 m from the diagonal one */
    assert_int_equal(cd_decomp_ghost_ranks(&g, corner2, 0, r), 2);
    assert_int_equal(r[1], 2);
}

/* Neighbours: the sub-domains within reach, box to box; on a 3 x 1 x 3
 * grid of 1 m cells the centre one has all eight, a corner one three, and
 * a reach of 1 m or more brings the opposite corner in only past
 * sqrt(2) m; the relation is symmetric. */
static void test_neighbors(void **state)
{
    (void)state;
    cd_decomp_grid g;
    double hi[3] = {3, 1, 3}; /* [m] */
    given_grid(&g, 3, 1, 3, hi, 0.1, 0);
    double blo[3], bhi[3];
    cd_decomp_box(&g, 4, blo, bhi); /* the centre: x 1..2, z 1..2, y open */
    assert_true(blo[0] == 1 && bhi[0] == 2 && blo[2] == 1 && bhi[2] == 2);
    assert_true(isinf(blo[1]) && blo[1] < 0 && isinf(bhi[1]));
    cd_decomp_box(&g, 0, blo, bhi);
    assert_true(isinf(blo[0]) && blo[0] < 0 && bhi[0] == 1);
    int r[9];
    assert_int_equal(cd_decomp_neighbors(&g, 4, 0.1, r), 8);
    assert_int_equal(r[0], 0);
    assert_int_equal(r[7], 8);
    assert_int_equal(cd_decomp_neighbors(&g, 0, 0.1, r), 3);
    assert_int_equal(r[0], 1);
    assert_int_equal(r[1], 3);
    assert_int_equal(r[2], 4);
    assert_int_equal(cd_decomp_neighbors(&g, 0, 1.0, r), 7); /* + 2, 5, 6, 7: 1 m away; 8 is sqrt(2) m away */
    assert_int_equal(cd_decomp_neighbors(&g, 0, 1.5, r), 8);
    for (int a = 0; a < 9; a++)
        for (int b = 0; b < 9; b++) {
            int n = cd_decomp_neighbors(&g, a, 1.2, r), ab = 0, ba = 0;
            for (int k = 0; k < n; k++) ab |= r[k] == b;
            n = cd_decomp_neighbors(&g, b, 1.2, r);
            for (int k = 0; k < n; k++) ba |= r[k] == a;
            assert_int_equal(ab, ba);
        }
}

/* Recursive coordinate bisection of a settled pile: points filling the
 * bottom tenth of a 1 m box.  Every rank owns its share of the particles
 * (to one per cut), whatever the rank count; the boxes tile space (every
 * point's owner box holds it) and no cut goes across the pile's height;
 * 2D never cuts z; a given mpi.grid is refused. */
static void test_rcb(void **state)
{
    (void)state;
    enum { N = 2000 };
    static double xyz[3 * N]; /* [m] */
    unsigned long long seed = 12345;
    for (int q = 0; q < N; q++)
        for (int a = 0; a < 3; a++) {
            seed = seed * 6364136223846793005ULL + 1442695040888963407ULL; /* an LCG: reproducible */
            double u = (double)(seed >> 11) / 9007199254740992.0;
            xyz[3 * q + a] = a == 1 ? 0.1 * u : u;
        }
    char err[512];
    static cd_decomp_grid g;
    cd_config c = config(3, 0, -9.81, 0);
    c.mpi_decomposition = CD_DECOMP_RCB;
    for (int ranks = 1; ranks <= 7; ranks++) {
        assert_int_equal(cd_decomp_make(&g, &c, ranks, xyz, N, 0.01, 0, err, sizeof err), 0);
        assert_int_equal(g.kind, CD_DECOMP_RCB);
        int count[7] = {0};
        for (int q = 0; q < N; q++) {
            int r = cd_decomp_owner(&g, xyz + 3 * q);
            count[r]++;
            double lo[3], hi[3];
            cd_decomp_box(&g, r, lo, hi);
            for (int a = 0; a < 3; a++) assert_true(lo[a] <= xyz[3 * q + a] && xyz[3 * q + a] <= hi[a]);
            int ghosts[7], n = cd_decomp_ghost_ranks(&g, xyz + 3 * q, r, ghosts);
            for (int k = 0; k < n; k++) assert_true(ghosts[k] != r);
        }
        int lo = N, hi = 0;
        for (int r = 0; r < ranks; r++) lo = count[r] < lo ? count[r] : lo, hi = count[r] > hi ? count[r] : hi;
        assert_true(hi - lo <= 2);        /* N / ranks, rounded down at up to 2 cuts on the way */
        for (int r = 0; r < ranks; r++) { /* the pile is wide, not tall: no cut across y */
            double lo3[3], hi3[3];
            cd_decomp_box(&g, r, lo3, hi3);
            assert_true(isinf(lo3[1]) && isinf(hi3[1]));
        }
    }
    /* 2D (the pile flat in z): never a cut across z */
    cd_config c2 = config(2, 0, -9.81, 0);
    c2.mpi_decomposition = CD_DECOMP_RCB;
    for (int q = 0; q < N; q++) xyz[3 * q + 2] = 0;
    assert_int_equal(cd_decomp_make(&g, &c2, 4, xyz, N, 0.01, 0, err, sizeof err), 0);
    for (int r = 0; r < 4; r++) {
        double lo3[3], hi3[3];
        cd_decomp_box(&g, r, lo3, hi3);
        assert_true(isinf(lo3[2]) && isinf(hi3[2]));
    }
    c.mpi_grid[0] = 2, c.mpi_grid[1] = 1, c.mpi_grid[2] = 1; /* a cartesian grid's key */
    assert_int_equal(cd_decomp_make(&g, &c, 2, xyz, N, 0.01, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "expected no mpi.grid"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_auto_grid), cmocka_unit_test(test_refusals), cmocka_unit_test(test_owner_and_ghosts),
        cmocka_unit_test(test_neighbors), cmocka_unit_test(test_rcb),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
