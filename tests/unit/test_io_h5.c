/* HDF5 run file: snapshots and time series round-trip bit for bit, resume
 * truncates what came after the checkpoint, a killed writer leaves a
 * readable file, mismatched states are refused with a clear message. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <hdf5.h>

#include "io/io_h5.h"
#include "io/io_h5_journal.h"
#include "unit/io_h5_fixture.h"

static void test_io_h5_snapshots_round_trip_bit_for_bit(void **state)
{
    (void)state;
    char path[128], err[1024] = "";
    test_path(path, sizeof path, "rt");
    cd_state s[3];
    for (int j = 0; j < 3; j++) alloc_state(&s[j], NP, NPRIM, NW, NPAIR);
    write_run(path, 3, s);
    assert_int_equal(cd_h5_snapshot_count(path, err, sizeof err), 3);
    for (int j = 0; j < 3; j++) check_snapshot(path, j, &s[j]);
    check_snapshot(path, -1, &s[2]);

    char *text = cd_h5_read_config_text(path, err, sizeof err);
    assert_non_null(text);
    assert_string_equal(text, CONFIG_TEXT);
    free(text);

    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f >= 0);
    /* H5MD header */
    int version[2] = {0, 0};
    hid_t a = H5Aopen_by_name(f, "/h5md", "version", H5P_DEFAULT, H5P_DEFAULT);
    assert_true(a >= 0 && H5Aread(a, H5T_NATIVE_INT, version) >= 0);
    H5Aclose(a);
    assert_int_equal(version[0], 1);
    assert_int_equal(version[1], 1);
    assert_true(H5Aexists_by_name(f, "/h5md/creator", "version", H5P_DEFAULT) > 0);
    assert_true(H5Aexists_by_name(f, "/parameters/config", "source_path", H5P_DEFAULT) > 0);
    assert_true(H5Aexists_by_name(f, "/parameters/shapes/0/volume", "unit", H5P_DEFAULT) > 0);
    assert_true(H5Aexists_by_name(f, "/particles/all/position/value", "unit", H5P_DEFAULT) > 0);
    /* time series: 6 rows of steps 0, 50, ..., 250 */
    long long steps[16];
    assert_int_equal(read_ll_dataset(f, "/observables/momentum/step", steps, 16), 6);
    for (int i = 0; i < 6; i++) assert_int_equal(steps[i], 50 * i);
    double mom[6][3];
    hid_t d = H5Dopen2(f, "/observables/momentum/value", H5P_DEFAULT);
    assert_true(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, mom) >= 0);
    H5Dclose(d);
    for (int i = 0; i < 6; i++) {
        assert_true(mom[i][0] == 50.0 * i && mom[i][1] == -50.0 * i && mom[i][2] == 1.0 / (50.0 * i + 1));
    }
    /* contacts: offsets and owning particles */
    long long off[8];
    assert_int_equal(read_ll_dataset(f, "/contacts/offset", off, 8), 4);
    assert_int_equal(off[0], 0);
    assert_int_equal(off[2] - off[1], 0); /* snapshot 1 has no contact */
    long long pi[64];
    assert_int_equal(read_ll_dataset(f, "/contacts/particle_i", pi, 64), off[3]);
    for (int r = 0, j = 0; r < NPAIR; r++)
        if (s[0].pair_active[r]) assert_int_equal(pi[j++], s[0].prim_particle[s[0].pair_prim_i[r]]);
    H5Fclose(f);
    for (int j = 0; j < 3; j++) cd_state_free(&s[j]);
    remove_run(path);
}

static void test_io_h5_reopen_truncates_after_resume_step(void **state)
{
    (void)state;
    char path[128], err[1024] = "";
    test_path(path, sizeof path, "resume");
    cd_state s[4];
    for (int j = 0; j < 4; j++) alloc_state(&s[j], NP, NPRIM, NW, NPAIR);
    write_run(path, 3, s);

    cd_output *o = cd_output_reopen(path, 100, OBS, 2, NULL, err, sizeof err);
    if (!o) print_error("%s\n", err);
    assert_non_null(o);
    fill_state(&s[3], 3);
    s[3].step = 150;
    thermo(o, 150);
    assert_int_equal(cd_output_snapshot(o, &s[3]), 0);
    assert_int_equal(cd_output_close(o), 0);

    assert_int_equal(cd_h5_snapshot_count(path, err, sizeof err), 3);
    check_snapshot(path, 0, &s[0]);
    check_snapshot(path, 1, &s[1]);
    check_snapshot(path, 2, &s[3]);
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    long long v[16];
    static const long long want_obs[] = {0, 50, 100, 150};
    assert_int_equal(read_ll_dataset(f, "/observables/energy/step", v, 16), 4);
    assert_memory_equal(v, want_obs, sizeof want_obs);
    static const long long want_snap[] = {0, 100, 150};
    assert_int_equal(read_ll_dataset(f, "/particles/all/velocity/step", v, 16), 3);
    assert_memory_equal(v, want_snap, sizeof want_snap);
    long long off[8];
    assert_int_equal(read_ll_dataset(f, "/contacts/offset", off, 8), 4);
    assert_int_equal(read_ll_dataset(f, "/contacts/particle_j", v, 16), off[3]);
    assert_int_equal(read_ll_dataset(f, "/wall_contacts/offset", off, 8), 4);
    long long idx[64];
    assert_int_equal(read_ll_dataset(f, "/wall_contacts/index", idx, 64), off[3]);
    H5Fclose(f);
    for (int j = 0; j < 4; j++) cd_state_free(&s[j]);
    remove_run(path);
}

static void test_io_h5_reopen_before_first_snapshot(void **state)
{
    (void)state;
    char path[128], err[1024] = "";
    test_path(path, sizeof path, "empty");
    assert_int_equal(cd_output_close(create(path)), 0);
    assert_int_equal(cd_h5_snapshot_count(path, err, sizeof err), 0);
    assert_int_equal(cd_h5_read_snapshot(path, -1, &(cd_state){0}, err, sizeof err), -1);
    assert_non_null(strstr(err, "no complete snapshot"));
    cd_output *o = cd_output_reopen(path, 0, OBS, 2, NULL, err, sizeof err);
    assert_non_null(o);
    cd_state s;
    alloc_state(&s, NP, NPRIM, NW, NPAIR);
    fill_state(&s, 2);
    assert_int_equal(cd_output_snapshot(o, &s), 0);
    assert_int_equal(cd_output_close(o), 0);
    check_snapshot(path, 0, &s);
    cd_state_free(&s);
    remove_run(path);
}

/* Child: 3 snapshots, tell the parent, then keep writing (mode 0) until
 * killed, or buffer a time-series row and leave without closing (mode 1). */
static void child_writer(const char *path, int fd, int mode)
{
    cd_state s;
    if (cd_state_alloc(&s, NP, NPRIM, NW, NPAIR)) _exit(3);
    char err[512];
    cd_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.source_text = (char *)CONFIG_TEXT;
    cd_output *o = cd_output_create(path, &cfg, NULL, 0, OBS, 2, err, sizeof err);
    if (!o) _exit(4);
    double v[4] = {1, 2, 3, 4};
    for (int j = 0;; j++) {
        fill_state(&s, j);
        if (cd_output_thermo(o, s.step, s.time, v) || cd_output_snapshot(o, &s)) _exit(5);
        if (j == 2) {
            if (write(fd, "3", 1) != 1) _exit(6);
            if (mode == 1) {
                cd_output_thermo(o, s.step + 1, s.time, v);
                _exit(0);
            }
        }
    }
}

static void check_killed_file(const char *path, int exact_count)
{
    char err[1024] = "";
    int n = cd_h5_snapshot_count(path, err, sizeof err);
    if (n < 0) print_error("%s\n", err);
    assert_true(exact_count ? n == exact_count : n >= 3);
    cd_state want;
    alloc_state(&want, NP, NPRIM, NW, NPAIR);
    for (int j = 0; j < n; j++) {
        fill_state(&want, j);
        check_snapshot(path, j, &want);
    }
    cd_state_free(&want);
    /* A kill while a commit's journal was being applied leaves the file
     * plus a complete journal as the last commit (docs/output.md, "Crash
     * safety"): capdem's readers above replay it in memory; programs other
     * than capdem read the file after `capdem recover`, which this is.
     * Without the replay h5dump can meet a half-applied commit (seen in
     * about 1 of 10 runs on a loaded machine). */
    assert_true(cdh5_recover(path, err, sizeof err) >= 0);
    assert_int_equal(cd_h5_snapshot_count(path, err, sizeof err), n);
    if (system("command -v h5dump > /dev/null 2>&1") == 0) {
        char cmd[300];
        snprintf(cmd, sizeof cmd, "h5dump '%s' > /dev/null", path);
        assert_int_equal(system(cmd), 0);
    }
}

static void run_child(const char *path, int mode, long delay_us)
{
    int fd;
    pid_t pid = fork_with_pipe(&fd);
    if (pid == 0) {
        child_writer(path, fd, mode);
        _exit(7);
    }
    char c;
    assert_int_equal(read(fd, &c, 1), 1);
    close(fd);
    int status;
    if (mode == 0) {
        struct timespec ts = {0, (long)delay_us * 1000};
        if (delay_us) nanosleep(&ts, NULL);
        kill(pid, SIGKILL);
        assert_int_equal(waitpid(pid, &status, 0), pid);
        assert_true(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    } else {
        assert_int_equal(waitpid(pid, &status, 0), pid);
        assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    }
}

static void test_io_h5_killed_writer_leaves_readable_file(void **state)
{
    (void)state;
    char path[128];
    static const long delays[] = {0, 300, 3000, 20000};
    for (size_t i = 0; i < sizeof delays / sizeof delays[0]; i++) {
        test_path(path, sizeof path, "kill");
        run_child(path, 0, delays[i]);
        check_killed_file(path, 0);
        remove_run(path);
    }
    test_path(path, sizeof path, "exit");
    run_child(path, 1, 0);
    check_killed_file(path, 3);
    /* the time-series rows flushed with the snapshots survive, the buffered one is lost */
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    long long v[8];
    assert_int_equal(read_ll_dataset(f, "/observables/energy/step", v, 8), 3);
    H5Fclose(f);
    remove_run(path);
}

/* A run file of one snapshot of the fixture's state s, at path (named by tag). */
static void write_one_snapshot(char *path, size_t len, const char *tag, cd_state *s)
{
    test_path(path, len, tag);
    alloc_state(s, NP, NPRIM, NW, NPAIR);
    write_run(path, 1, s);
}

static void test_io_h5_wrong_counts_are_refused(void **state)
{
    (void)state;
    char path[128], err[1024] = "";
    cd_state s[1];
    write_one_snapshot(path, sizeof path, "counts", s);
    cd_state g;
    alloc_state(&g, NP + 1, NPRIM, NW, 4);
    assert_int_equal(cd_h5_read_snapshot(path, 0, &g, err, sizeof err), -1);
    assert_non_null(strstr(err, path));
    assert_non_null(strstr(err, "holds 5 particles"));
    assert_non_null(strstr(err, "the state 6"));
    cd_state_free(&g);
    alloc_state(&g, NP, NPRIM, NW - 1, 4);
    assert_int_equal(cd_h5_read_snapshot(path, 0, &g, err, sizeof err), -1);
    assert_non_null(strstr(err, "holds 2 walls"));
    cd_state_free(&g);
    alloc_state(&g, NP, NPRIM, NW, 4);
    assert_int_equal(cd_h5_read_snapshot(path, 1, &g, err, sizeof err), -1);
    assert_non_null(strstr(err, "snapshot 1 requested"));
    cd_state_free(&g);

    /* appending a state of another size, or one whose fixed columns changed */
    cd_output *o = cd_output_reopen(path, 1000, OBS, 2, NULL, err, sizeof err);
    assert_non_null(o);
    alloc_state(&g, NP + 1, NPRIM, NW, 4);
    assert_int_equal(cd_output_snapshot(o, &g), -1);
    assert_non_null(strstr(cd_output_error(o), "5 particles"));
    cd_state_free(&g);
    s[0].mass[2] += 1.0;
    assert_int_equal(cd_output_snapshot(o, &s[0]), -1);
    assert_non_null(strstr(cd_output_error(o), "column mass changed"));
    assert_int_equal(cd_output_close(o), 0);
    assert_int_equal(cd_h5_snapshot_count(path, err, sizeof err), 1);
    cd_state_free(&s[0]);
    remove_run(path);
}

/* A FLAG column (kernels/fields.def: pair_active, one byte a row in
 * memory) is a 32-bit integer in the file, as when the step held it as a
 * cd_int, so files of either kind resume; a value a byte cannot hold
 * (-1, 256: HDF5 would clip it to 0 or 255) is refused at read with the
 * column named, not turned into another flag. */
static void test_io_h5_flag_column_is_int32_in_file(void **state)
{
    (void)state;
    char path[128], err[1024] = "";
    cd_state s[1];
    write_one_snapshot(path, sizeof path, "flag", s);
    hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    assert_true(f >= 0);
    hid_t d = H5Dopen2(f, "/contacts/pair_active", H5P_DEFAULT), t = H5Dget_type(d);
    assert_true(d >= 0 && t >= 0);
    assert_int_equal(H5Tget_class(t), H5T_INTEGER);
    assert_int_equal(H5Tget_size(t), 4);
    H5Tclose(t);
    H5Dclose(d);
    H5Fclose(f);
    check_snapshot(path, 0, &s[0]); /* the flags read back (the fixture's 0s and 1s) */
    static const int bad[] = {-1, 256};
    for (int b = 0; b < 2; b++) {
        f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
        d = H5Dopen2(f, "/contacts/pair_active", H5P_DEFAULT);
        hid_t fs = H5Dget_space(d), ms = H5Screate_simple(1, (hsize_t[]){1}, NULL);
        assert_true(H5Sselect_hyperslab(fs, H5S_SELECT_SET, (hsize_t[]){0}, NULL, (hsize_t[]){1}, NULL) >= 0);
        assert_true(H5Dwrite(d, H5T_NATIVE_INT, ms, fs, H5P_DEFAULT, &bad[b]) >= 0);
        H5Sclose(ms);
        H5Sclose(fs);
        H5Dclose(d);
        H5Fclose(f);
        cd_state g;
        alloc_state(&g, NP, NPRIM, NW, 4);
        assert_int_equal(cd_h5_read_snapshot(path, 0, &g, err, sizeof err), -1);
        assert_non_null(strstr(err, "pair_active"));
        cd_state_free(&g);
    }
    cd_state_free(&s[0]);
    remove_run(path);
}

static void test_io_h5_missing_file_is_named(void **state)
{
    (void)state;
    char err[1024] = "";
    const char *path = "no_such_dir_io_h5/run.h5";
    assert_int_equal(cd_h5_snapshot_count(path, err, sizeof err), -1);
    assert_non_null(strstr(err, path));
    assert_null(cd_h5_read_config_text(path, err, sizeof err));
    assert_non_null(strstr(err, path));
    assert_null(cd_output_reopen(path, 0, NULL, 0, NULL, err, sizeof err));
    assert_non_null(strstr(err, path));
    assert_null(cd_output_create(path, NULL, NULL, 0, NULL, 0, err, sizeof err));
    assert_non_null(strstr(err, path));
}

static void test_io_h5_bad_observables_are_refused(void **state)
{
    (void)state;
    char path[128], err[1024] = "";
    test_path(path, sizeof path, "obs");
    static const cd_observable_info slash[1] = {{"a/b", "1", 1}}, twice[2] = {{"e", "J", 1}, {"e", "J", 1}};
    assert_null(cd_output_create(path, NULL, NULL, 0, slash, 1, err, sizeof err));
    assert_non_null(strstr(err, "invalid name \"a/b\""));
    assert_null(cd_output_create(path, NULL, NULL, 0, twice, 2, err, sizeof err));
    assert_non_null(strstr(err, "\"e\" given twice"));
    cd_state s[2];
    for (int j = 0; j < 2; j++) alloc_state(&s[j], NP, NPRIM, NW, NPAIR);
    write_run(path, 2, s);
    static const cd_observable_info other[2] = {{"energy", "J", 1}, {"momentum", "kg m/s", 2}};
    int refused = 0;
    assert_null(cd_output_reopen(path, 0, other, 2, &refused, err, sizeof err));
    assert_non_null(strstr(err, "/observables/momentum/value has 3 components per row, the run gives 2"));
    assert_int_equal(refused, 1); /* the input's fault: capdem run exits 2 */
    assert_null(cd_output_reopen(path, 0, twice, 2, NULL, err, sizeof err));
    assert_int_equal(cd_h5_snapshot_count(path, err, sizeof err), 2); /* refused before truncating */
    for (int j = 0; j < 2; j++) cd_state_free(&s[j]);
    remove_run(path);
}

/* A dataset the writer appends to that a resume's checks do not read (an
 * observable's value: a flipped byte in its link's name, test_corruption)
 * is missing at the reopen: refused as the input's fault (*refused 1, so
 * `capdem run --resume` exits 2, not 1 as for a failed write), with the
 * dataset named, and the file keeps every snapshot. */
static void test_io_h5_reopen_refuses_missing_dataset(void **state)
{
    (void)state;
    char path[128], err[1024] = "";
    test_path(path, sizeof path, "lnk");
    cd_state s[2];
    for (int j = 0; j < 2; j++) alloc_state(&s[j], NP, NPRIM, NW, NPAIR);
    write_run(path, 2, s);
    hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    assert_true(f >= 0);
    assert_true(H5Lmove(f, "/observables/momentum/value", f, "/observables/momentum/valve", H5P_DEFAULT, H5P_DEFAULT) >=
                0);
    H5Fclose(f);
    int refused = 0;
    assert_null(cd_output_reopen(path, 100, OBS, 2, &refused, err, sizeof err));
    assert_int_equal(refused, 1);
    assert_non_null(strstr(err, "/observables/momentum/value"));
    assert_int_equal(cd_h5_snapshot_count(path, err, sizeof err), 2);
    for (int j = 0; j < 2; j++) cd_state_free(&s[j]);
    remove_run(path);
}

/* The bytes of a file (malloc'd, *n its size), or NULL when it cannot be read. */
static unsigned char *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc(len > 0 ? (size_t)len : 1);
    *n = b && len >= 0 && fread(b, 1, (size_t)len, f) == (size_t)len ? (size_t)len : 0;
    fclose(f);
    return b;
}

/* Files in the working folder whose name starts with prefix. */
static int count_prefixed(const char *prefix)
{
    char cmd[256];
    snprintf(cmd, sizeof cmd, "ls -a | grep -c '^%s' || true", prefix);
    FILE *p = popen(cmd, "r");
    int n = -1;
    if (p && fscanf(p, "%d", &n) != 1) n = -1;
    if (p) pclose(p);
    return n;
}

/* CD_OUTPUT_NEW refuses an existing file; CD_OUTPUT_REPLACE leaves the old
 * file byte for byte as it was (and locked against a second writer) until
 * the new file's first snapshot is committed, then puts the new one in its
 * place; closed before a snapshot, it leaves the old file and nothing
 * beside it.  An output that is an input is refused. */
static void test_io_h5_replace_keeps_old_file_until_first_snapshot(void **state)
{
    (void)state;
    char path[128], aside[160], err[1024] = "";
    test_path(path, sizeof path, "replace");
    snprintf(aside, sizeof aside, ".%s.", path);
    cd_state s[3];
    for (int j = 0; j < 3; j++) alloc_state(&s[j], NP, NPRIM, NW, NPAIR);
    remove_run(path);
    assert_int_equal(cd_output_check_target(path, CD_OUTPUT_NEW, NULL, 0, err, sizeof err), 0);
    write_run(path, 3, s);
    size_t n0, n1;
    unsigned char *before = slurp(path, &n0);
    assert_non_null(before);

    cd_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.source_text = (char *)CONFIG_TEXT;
    assert_int_equal(cd_output_check_target(path, CD_OUTPUT_NEW, NULL, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "exists"));
    assert_null(cd_output_create_mode(path, CD_OUTPUT_NEW, &cfg, NULL, 0, OBS, 2, err, sizeof err));
    assert_non_null(strstr(err, "exists"));
    const char *inputs[2] = {"no_such_input.yaml", path};
    assert_int_equal(cd_output_check_target(path, CD_OUTPUT_REPLACE, inputs, 2, err, sizeof err), -1);
    assert_non_null(strstr(err, "same file as the input"));
    assert_int_equal(cd_output_check_target(path, CD_OUTPUT_REPLACE, inputs, 1, err, sizeof err), 0);

    /* replaced, but only at the first snapshot */
    cd_output *o = cd_output_create_mode(path, CD_OUTPUT_REPLACE, &cfg, NULL, 0, OBS, 2, err, sizeof err);
    if (!o) print_error("%s\n", err);
    assert_non_null(o);
    assert_int_equal(count_prefixed(aside), 1);
    unsigned char *during = slurp(path, &n1);
    assert_true(during && n1 == n0 && memcmp(before, during, n0) == 0);
    free(during);
    assert_int_equal(cd_output_check_target(path, CD_OUTPUT_REPLACE, NULL, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "in use by another process"));
    assert_int_equal(cd_output_check_target(path, CD_OUTPUT_RESUME, NULL, 0, err, sizeof err), -1);
    fill_state(&s[0], 0);
    assert_int_equal(cd_output_snapshot(o, &s[0]), 0);
    assert_int_equal(count_prefixed(aside), 0);
    assert_int_equal(cd_output_close(o), 0);
    assert_int_equal(cd_h5_snapshot_count(path, err, sizeof err), 1);
    check_snapshot(path, 0, &s[0]);

    /* closed before its first snapshot: the old file stays, nothing beside it */
    free(before);
    before = slurp(path, &n0);
    o = cd_output_create_mode(path, CD_OUTPUT_REPLACE, &cfg, NULL, 0, OBS, 2, err, sizeof err);
    assert_non_null(o);
    assert_int_equal(cd_output_close(o), 0);
    unsigned char *after = slurp(path, &n1);
    assert_true(after && n1 == n0 && memcmp(before, after, n0) == 0);
    assert_int_equal(count_prefixed(aside), 0);
    free(before);
    free(after);

    /* CD_OUTPUT_REPLACE of a path that does not exist creates it */
    remove_run(path);
    o = cd_output_create_mode(path, CD_OUTPUT_REPLACE, &cfg, NULL, 0, OBS, 2, err, sizeof err);
    assert_non_null(o);
    assert_int_equal(cd_output_check_target(path, CD_OUTPUT_RESUME, NULL, 0, err, sizeof err), -1);
    assert_int_equal(cd_output_close(o), 0);
    assert_int_equal(cd_h5_snapshot_count(path, err, sizeof err), 0);
    assert_int_equal(cd_output_check_target(path, CD_OUTPUT_RESUME, NULL, 0, err, sizeof err), 0);
    for (int j = 0; j < 3; j++) cd_state_free(&s[j]);
    remove_run(path);
}

/* Every function closes what it opened. */
/* Index of v among ids[0..n), or -1. */
static long long index_of(const long long *ids, size_t n, long long v)
{
    for (size_t i = 0; i < n; i++)
        if (ids[i] == v) return (long long)i;
    return -1;
}

/* A part of a snapshot (an MPI rank's particles, docs/mpi.md "Resume"):
 * the rows of particles 1, 3, 4 of the whole read's, their primitives',
 * their wall contacts' and the active contacts between two of their
 * primitives, in that order, with the row numbers in the part's
 * numbering; and cd_h5_read_column_rows gives rows of the whole read. */
static void test_io_h5_part_read_equals_whole_rows(void **state)
{
    (void)state;
    char path[128], err[1024] = "";
    test_path(path, sizeof path, "part");
    cd_state s[3], whole, part;
    for (int j = 0; j < 3; j++) alloc_state(&s[j], NP, NPRIM, NW, NPAIR);
    write_run(path, 3, s);
    alloc_garbage(&whole);
    assert_int_equal(cd_h5_read_snapshot(path, 0, &whole, err, sizeof err), 0);
    const long long gid[3] = {1, 3, 4}, gprim[6] = {2, 3, 6, 7, 8, 9};
    cd_h5_part sel = {3, 6, NP, NPRIM, gid, gprim};
    alloc_state(&part, 3, 6, NW, 1);
    int rc = cd_h5_read_snapshot_part(path, 0, &sel, &part, err, sizeof err);
    if (rc) print_error("%s\n", err);
    assert_int_equal(rc, 0);
    size_t m = 0;
    for (size_t k = 0; k < cd_n_fields; k++) {
        const cd_field_info *f = &cd_fields[k];
        const char *a = *cd_field_ptr(&whole, f), *b = *cd_field_ptr(&part, f);
        size_t e = f->elem_size;
        if (f->group == CD_GROUP_PARTICLE && f->offset == offsetof(cd_state, prim_first)) {
            for (size_t q = 0; q < 3; q++)
                assert_int_equal(part.prim_first[q], (cd_int)index_of(gprim, 6, whole.prim_first[gid[q]]));
        } else if (f->group == CD_GROUP_PARTICLE) {
            for (size_t q = 0; q < 3; q++) assert_memory_equal(a + (size_t)gid[q] * e, b + q * e, e);
        } else if (f->group == CD_GROUP_PRIM && f->offset == offsetof(cd_state, prim_particle)) {
            for (size_t i = 0; i < 6; i++)
                assert_int_equal(part.prim_particle[i], (cd_int)index_of(gid, 3, whole.prim_particle[gprim[i]]));
        } else if (f->group == CD_GROUP_PRIM) {
            for (size_t i = 0; i < 6; i++) assert_memory_equal(a + (size_t)gprim[i] * e, b + i * e, e);
        } else if (f->group == CD_GROUP_WALLC) {
            for (size_t i = 0; i < 6; i++) assert_memory_equal(a + ((size_t)gprim[i] * NW) * e, b + i * NW * e, NW * e);
        } else {
            m = 0; /* the whole read's rows between two of the part's primitives, in order */
            for (size_t r = 0; r < whole.n_pairs; r++) {
                long long i = index_of(gprim, 6, whole.pair_prim_i[r]), j = index_of(gprim, 6, whole.pair_prim_j[r]);
                if (i < 0 || j < 0) continue;
                if (f->offset == offsetof(cd_state, pair_prim_i)) assert_int_equal(part.pair_prim_i[m], i);
                else if (f->offset == offsetof(cd_state, pair_prim_j)) assert_int_equal(part.pair_prim_j[m], j);
                else assert_memory_equal(a + r * e, b + m * e, e);
                m++;
            }
        }
    }
    assert_true(m > 0); /* (contacts among the part: the test would prove little without) */
    assert_int_equal(part.n_pairs, m);
    assert_memory_equal(whole.walls, part.walls, NW * sizeof(cd_wall));
    assert_memory_equal(&whole.time, &part.time, sizeof whole.time);
    assert_int_equal(whole.step, part.step);
    double pos[3][3];
    assert_int_equal(cd_h5_read_column_rows(path, 0, "position", 2, 3, pos, err, sizeof err), 0);
    assert_memory_equal(pos, &whole.position[2], sizeof pos);
    assert_int_equal(cd_h5_read_column_rows(path, 0, "position", 3, 3, pos, err, sizeof err), -1);
    cd_state_free(&whole);
    cd_state_free(&part);
    for (int j = 0; j < 3; j++) cd_state_free(&s[j]);
    remove_run(path);
}

static void test_io_h5_leaves_no_hdf5_object_open(void **state)
{
    (void)state;
    assert_int_equal(H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_io_h5_snapshots_round_trip_bit_for_bit),
        cmocka_unit_test(test_io_h5_reopen_truncates_after_resume_step),
        cmocka_unit_test(test_io_h5_reopen_before_first_snapshot),
        cmocka_unit_test(test_io_h5_killed_writer_leaves_readable_file),
        cmocka_unit_test(test_io_h5_wrong_counts_are_refused),
        cmocka_unit_test(test_io_h5_flag_column_is_int32_in_file),
        cmocka_unit_test(test_io_h5_missing_file_is_named),
        cmocka_unit_test(test_io_h5_bad_observables_are_refused),
        cmocka_unit_test(test_io_h5_reopen_refuses_missing_dataset),
        cmocka_unit_test(test_io_h5_replace_keeps_old_file_until_first_snapshot),
        cmocka_unit_test(test_io_h5_part_read_equals_whole_rows),
        cmocka_unit_test(test_io_h5_leaves_no_hdf5_object_open),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
