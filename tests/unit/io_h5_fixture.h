/* Shared by the run-file tests (test_io_h5.c, test_io_crash.c): a small
 * state with random contents that a conversion would disturb, a run file
 * written from it, and byte-for-byte checks of what is read back. */
#ifndef CD_TEST_IO_H5_FIXTURE_H
#define CD_TEST_IO_H5_FIXTURE_H
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <hdf5.h>

#include "io/io_h5.h"

#define NP    5  /* particles */
#define NPRIM 10 /* primitives, two per particle */
#define NW    2  /* walls */
#define NPAIR 9  /* rows of the pair list */

static const cd_observable_info OBS[2] = {{"energy", "J", 1}, {"momentum", "kg m/s", 3}};
static const char *CONFIG_TEXT = "run:\n  name: \"io test\"\t# t\xc3\xa4"
                                 "b, quote ' and \\\n\nphysics: {dt: 1e-6}\n  \n";

/* ---- deterministic random contents ------------------------------------- */

static uint64_t rng;
static inline uint64_t next_u64(void)
{
    uint64_t z = (rng += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* Mostly ordinary values, and negative zero, subnormals and arbitrary bit
 * patterns (NaN payloads, infinities) that a conversion would disturb. */
static inline double rand_double(void)
{
    uint64_t u = next_u64(), bits;
    double d;
    switch (u % 8) {
    case 0:
        return -0.0;
    case 1:
        bits = (next_u64() & 0x800FFFFFFFFFFFFFULL) | 1;
        break; /* subnormal */
    case 2:
        bits = next_u64();
        break;
    default:
        return ((double)(next_u64() >> 11) * 0x1.0p-53) * 20.0 - 10.0;
    }
    memcpy(&d, &bits, sizeof d);
    return d;
}

static inline void fill_random(void *col, size_t rows, const cd_field_info *f)
{
    size_t n = rows * (size_t)f->ncomp;
    for (size_t i = 0; i < n; i++) {
        if (f->kind == CD_KIND_REAL) ((double *)col)[i] = rand_double();
        else if (f->kind == CD_KIND_FLAG) ((cd_flag *)col)[i] = (cd_flag)(next_u64() % 2);
        else ((int32_t *)col)[i] = (int32_t)next_u64();
    }
}

static inline int is_fixed(const char *name)
{
    static const char *fixed[] = {"mass",       "inertia",       "scale",       "shape",       "prim_first",
                                  "prim_count", "prim_particle", "prim_a_body", "prim_b_body", "prim_radius"};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        if (!strcmp(name, fixed[i])) return 1;
    return 0;
}

/* State of snapshot j of a run: columns that never change come from one
 * seed, the rest from j.  Snapshot 1 has no active contact. */
static inline void fill_state(cd_state *s, int j)
{
    for (size_t k = 0; k < cd_n_fields; k++) {
        const cd_field_info *f = &cd_fields[k];
        rng = is_fixed(f->name) ? 1000 + k : (uint64_t)j * 7919 + k;
        size_t rows = cd_group_pair_rows(f->group) ? NPAIR : cd_state_rows(s, f->group);
        fill_random(*cd_field_ptr(s, f), rows, f);
    }
    rng = (uint64_t)j * 104729 + 17;
    s->n_pairs = NPAIR;
    for (int p = 0; p < NPRIM; p++) s->prim_particle[p] = p / 2;
    for (int r = 0; r < NPAIR; r++) {
        s->pair_prim_i[r] = r % NPRIM;
        s->pair_prim_j[r] = (r + 3 + j) % NPRIM;
        s->pair_active[r] = j == 1 ? 0 : (int)(next_u64() % 2) || r == 0;
    }
    for (size_t r = 0; r < NPRIM * NW; r++) s->wallc_active[r] = (int)(next_u64() % 3 == 0) || r == 4;
    memset(s->walls, 0, sizeof s->walls);
    for (int w = 0; w < NW; w++) {
        cd_wall *wl = &s->walls[w];
        wl->type = (cd_int)(next_u64() % 3);
        double *v[] = {&wl->point.x,    &wl->point.y,  &wl->point.z,         &wl->normal.x,
                       &wl->normal.y,   &wl->normal.z, &wl->velocity.x,      &wl->velocity.y,
                       &wl->velocity.z, &wl->radius,   &wl->radial_velocity, &wl->friction};
        for (size_t i = 0; i < sizeof v / sizeof v[0]; i++) *v[i] = rand_double();
    }
    s->time = j == 0 ? 0.0 : rand_double();
    s->step = 100LL * j;
}

static inline void alloc_state(cd_state *s, size_t np, size_t nprim, size_t nw, size_t cap)
{
    assert_int_equal(cd_state_alloc(s, np, nprim, nw, cap), 0);
}

/* A state to read into, full of garbage so that every byte must be written. */
static inline void alloc_garbage(cd_state *s)
{
    alloc_state(s, NP, NPRIM, NW, 1);
    rng = 424242;
    for (size_t k = 0; k < cd_n_fields; k++) {
        const cd_field_info *f = &cd_fields[k];
        fill_random(*cd_field_ptr(s, f), cd_group_pair_rows(f->group) ? 1 : cd_state_rows(s, f->group), f);
    }
    s->n_pairs = 1;
    memset(s->walls, 0x5a, sizeof s->walls);
    s->time = 1.5;
    s->step = -7;
}

/* What reading a snapshot of `want` must give, compared byte for byte. */
static inline void expect_snapshot(const cd_state *want, const cd_state *got)
{
    cd_state *w = (cd_state *)want, *g = (cd_state *)got;
    size_t active = 0;
    for (size_t r = 0; r < want->n_pairs; r++) active += want->pair_active[r] != 0;
    assert_int_equal(got->n_pairs, active);
    for (size_t k = 0; k < cd_n_fields; k++) {
        const cd_field_info *f = &cd_fields[k];
        const char *a = *cd_field_ptr(w, f), *b = *cd_field_ptr(g, f);
        size_t e = f->elem_size;
        if (f->group == CD_GROUP_PARTICLE || f->group == CD_GROUP_PRIM) {
            assert_memory_equal(a, b, cd_state_rows(want, f->group) * e);
        } else if (cd_group_pair_rows(f->group)) {
            for (size_t r = 0, j = 0; r < want->n_pairs; r++)
                if (want->pair_active[r]) assert_memory_equal(a + r * e, b + (j++) * e, e);
        } else {
            static const char zero[64];
            for (size_t r = 0; r < cd_state_rows(want, f->group); r++)
                assert_memory_equal(want->wallc_active[r] ? a + r * e : zero, b + r * e, e);
        }
    }
    assert_memory_equal(want->walls, got->walls, want->n_walls * sizeof(cd_wall));
    assert_memory_equal(&want->time, &got->time, sizeof want->time);
    assert_int_equal(want->step, got->step);
}

static inline void check_snapshot(const char *path, int k, const cd_state *want)
{
    char err[1024] = "";
    cd_state g;
    alloc_garbage(&g);
    int rc = cd_h5_read_snapshot(path, k, &g, err, sizeof err);
    if (rc) print_error("%s\n", err);
    assert_int_equal(rc, 0);
    expect_snapshot(want, &g);
    cd_state_free(&g);
}

static inline void test_path(char *buf, size_t len, const char *what)
{
    snprintf(buf, len, "test_io_h5_%ld_%s.h5", (long)getpid(), what);
}

/* Removes a run file and the journal a killed writer leaves beside it. */
static inline void remove_run(const char *path)
{
    char journal[200];
    snprintf(journal, sizeof journal, "%s-journal", path);
    remove(path);
    remove(journal);
}

/* fork() with a pipe from the child to the parent: in the child (0
 * returned) *fd is the pipe's write end, in the parent its read end. */
static inline pid_t fork_with_pipe(int *fd)
{
    int p[2];
    assert_int_equal(pipe(p), 0);
    fflush(NULL);
    pid_t pid = fork();
    assert_true(pid >= 0);
    close(p[pid == 0 ? 0 : 1]);
    *fd = p[pid == 0 ? 1 : 0];
    return pid;
}

static inline cd_output *create(const char *path)
{
    cd_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.source_text = (char *)CONFIG_TEXT;
    strcpy(cfg.source_path, "/runs/io test/run.yaml");
    cd_shape sh[2];
    memset(sh, 0, sizeof sh);
    strcpy(sh[0].kind, "cross");
    sh[0].n_prims = 2;
    sh[0].a[0] = (cd_vec3){-1e-3, 0, 0};
    sh[0].b[0] = (cd_vec3){1e-3, 0, 0};
    sh[0].a[1] = (cd_vec3){0, -1e-3, 0};
    sh[0].b[1] = (cd_vec3){0, 1e-3, 0};
    sh[0].radius[0] = sh[0].radius[1] = 2.5e-4;
    sh[0].volume = 1.23e-9;
    sh[0].principal[0] = 1e-12;
    strcpy(sh[1].kind, "sphere");
    sh[1].n_prims = 1;
    sh[1].radius[0] = 5e-4;
    char err[1024] = "";
    cd_output *o = cd_output_create(path, &cfg, sh, 2, OBS, 2, err, sizeof err);
    if (!o) print_error("%s\n", err);
    assert_non_null(o);
    return o;
}

static inline void thermo(cd_output *o, long long step)
{
    double v[4] = {(double)step * 0.5, (double)step, -(double)step, 1.0 / ((double)step + 1)};
    assert_int_equal(cd_output_thermo(o, step, (double)step * 1e-6, v), 0);
}

/* Writes snapshots 0..n-1 (steps 0, 100, ...) with time-series rows at
 * every 50 steps up to 100 n - 50. */
static inline void write_run(const char *path, int n, cd_state *s)
{
    cd_output *o = create(path);
    for (int j = 0; j < n; j++) {
        fill_state(&s[j], j);
        thermo(o, 100LL * j);
        assert_int_equal(cd_output_snapshot(o, &s[j]), 0);
        thermo(o, 100LL * j + 50);
    }
    assert_int_equal(cd_output_close(o), 0);
}

static inline long long read_ll_dataset(hid_t f, const char *path, long long *v, size_t cap)
{
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    assert_true(d >= 0);
    hid_t sp = H5Dget_space(d);
    hssize_t n = H5Sget_simple_extent_npoints(sp);
    assert_true(n >= 0 && (size_t)n <= cap);
    if (n) assert_true(H5Dread(d, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0);
    H5Sclose(sp);
    H5Dclose(d);
    return (long long)n;
}

#endif
