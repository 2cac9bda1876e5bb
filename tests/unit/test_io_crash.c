/* Atomic commits of run files (docs/output.md, "Crash safety"): a writer
 * killed at each write, truncation and sync it makes, in turn, with half of
 * that call done, leaves a file that holds exactly its completed commits:
 * readable by capdem's readers as it is, and by any HDF5 program once
 * recovered.  Three writers: a new run, a run replacing an old one
 * (--overwrite), and a resume that cuts snapshots and appends new ones. */
#define _POSIX_C_SOURCE 200809L
#include <glob.h>
#include <signal.h>
#include <sys/wait.h>

#include "io/io_h5_journal.h"
#include "unit/io_h5_fixture.h"

enum scenario { NEW_RUN, REPLACE_RUN, RESUME_RUN };

/* Every kill point; under AddressSanitizer (CI's sanitizer job, where a
 * fork costs ten times more) every fifth one and the last. */
#if defined(__SANITIZE_ADDRESS__)
#define SWEEP_STRIDE 5
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SWEEP_STRIDE 5
#endif
#endif
#ifndef SWEEP_STRIDE
#define SWEEP_STRIDE 1
#endif
#define NEW_SNAPS   3 /* snapshots the writer adds */
#define OLD_SNAPS   3 /* snapshots of the file that REPLACE_RUN replaces and RESUME_RUN resumes */
#define RESUME_KEEP 2 /* snapshots RESUME_RUN keeps (it resumes at step 100) */

/* Contents of snapshot j: seed j in the file written before (write_run),
 * seed 20 + j from the writer under test. */
static void snapshot_state(cd_state *s, int j, int is_new)
{
    fill_state(s, is_new ? 20 + j : j);
    s->step = 100LL * j;
}

static void mark(int fd, char c)
{
    if (fd >= 0 && write(fd, &c, 1) != 1) _exit(6);
}

/* The writer of a scenario; marks 'o' once its output is open (its first
 * commit done) and 's' after each snapshot. */
static void writer(enum scenario sc, const char *path, int fd)
{
    cd_state s;
    if (cd_state_alloc(&s, NP, NPRIM, NW, NPAIR)) _exit(3);
    char err[1024];
    cd_output *o;
    int first = 0;
    if (sc == RESUME_RUN) {
        o = cd_output_reopen(path, 100, OBS, 2, NULL, err, sizeof err);
        first = RESUME_KEEP;
    } else {
        cd_config cfg;
        memset(&cfg, 0, sizeof cfg);
        cfg.source_text = (char *)CONFIG_TEXT;
        o = cd_output_create(path, &cfg, NULL, 0, OBS, 2, err, sizeof err);
    }
    if (!o) _exit(4);
    mark(fd, 'o');
    double v[4] = {1, 2, 3, 4};
    for (int j = first; j < first + NEW_SNAPS; j++) {
        snapshot_state(&s, j, 1);
        if (cd_output_thermo(o, s.step, s.time, v) || cd_output_snapshot(o, &s)) _exit(5);
        mark(fd, 's');
    }
    if (cd_output_close(o)) _exit(5);
    cd_state_free(&s);
}

/* Removes the run file, its journal and what a killed --overwrite left
 * beside it (.<name>.XXXXXX and its journal). */
static void clean(const char *path)
{
    char pattern[200];
    snprintf(pattern, sizeof pattern, "%s*", path);
    glob_t g;
    if (glob(pattern, 0, NULL, &g) == 0)
        for (size_t i = 0; i < g.gl_pathc; i++) remove(g.gl_pathv[i]);
    globfree(&g);
    snprintf(pattern, sizeof pattern, ".%s.*", path);
    if (glob(pattern, GLOB_PERIOD, NULL, &g) == 0)
        for (size_t i = 0; i < g.gl_pathc; i++) remove(g.gl_pathv[i]);
    globfree(&g);
}

/* The file a scenario starts from (none for NEW_RUN): a copy of a run
 * of OLD_SNAPS snapshots written once. */
static void prepare(enum scenario sc, const char *path)
{
    static unsigned char *old_run;
    static size_t old_bytes;
    clean(path);
    if (sc == NEW_RUN) return;
    if (!old_run) {
        cd_state s[OLD_SNAPS];
        for (int j = 0; j < OLD_SNAPS; j++) alloc_state(&s[j], NP, NPRIM, NW, NPAIR);
        write_run(path, OLD_SNAPS, s);
        for (int j = 0; j < OLD_SNAPS; j++) cd_state_free(&s[j]);
        FILE *f = fopen(path, "rb");
        assert_non_null(f);
        fseek(f, 0, SEEK_END);
        old_bytes = (size_t)ftell(f);
        rewind(f);
        old_run = malloc(old_bytes);
        assert_true(old_run && fread(old_run, 1, old_bytes, f) == old_bytes);
        fclose(f);
        return;
    }
    FILE *f = fopen(path, "wb");
    assert_true(f && fwrite(old_run, 1, old_bytes, f) == old_bytes && fclose(f) == 0);
}

/* Snapshots of the file, each checked byte for byte: the file's before
 * snapshot new_from, the writer's from there on. */
static int check_contents(const char *path, int new_from)
{
    char err[1024] = "";
    int n = cd_h5_snapshot_count(path, err, sizeof err);
    if (n < 0) print_error("%s\n", err);
    assert_true(n >= 0);
    cd_state want;
    alloc_state(&want, NP, NPRIM, NW, NPAIR);
    for (int j = 0; j < n; j++) {
        snapshot_state(&want, j, j >= new_from);
        check_snapshot(path, j, &want);
    }
    cd_state_free(&want);
    return n;
}

/* After recovery a plain HDF5 open (HDF5's own driver) reads the commit record. */
static void check_plain_hdf5(const char *path, int n)
{
    char err[1024] = "";
    int rc = cdh5_recover(path, err, sizeof err);
    if (rc < 0) print_error("%s\n", err);
    assert_true(rc >= 0);
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f >= 0);
    int count = 0; /* no commit record before the first snapshot */
    if (n > 0) {
        long long steps[OLD_SNAPS + NEW_SNAPS + 1];
        assert_true(read_ll_dataset(f, "/walls/step", steps, sizeof steps / sizeof steps[0]) >= n);
        hid_t a = H5Aopen(f, "n_snapshots", H5P_DEFAULT);
        assert_true(a >= 0 && H5Aread(a, H5T_NATIVE_INT, &count) >= 0);
        H5Aclose(a);
    }
    H5Fclose(f);
    assert_int_equal(count, n);
}

/* Runs the writer with a fault at its k-th counted call (k <= 0: none);
 * returns its marks, and whether it was killed in *killed. */
static int run_writer(enum scenario sc, const char *path, long long k, char *marks, int cap, int *killed)
{
    int fd;
    pid_t pid = fork_with_pipe(&fd);
    if (pid == 0) {
        cdh5_fault_after(k);
        writer(sc, path, fd);
        _exit(0);
    }
    int n = 0;
    ssize_t r;
    while (n < cap && (r = read(fd, marks + n, (size_t)(cap - n))) > 0) n += (int)r;
    close(fd);
    int status;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    *killed = WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
    if (!*killed) assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    return n;
}

/* After kill point k: the next one of the stride, the last (total) and
 * one past it (the writer that must finish). */
static long long next_kill_point(long long k, long long total)
{
    if (k >= total) return k + 1;
    return k + SWEEP_STRIDE < total ? k + SWEEP_STRIDE : total;
}

static void sweep(enum scenario sc, const char *what)
{
    char path[128];
    test_path(path, sizeof path, what);
    /* the writer's counted calls, from an unfaulted run in this process */
    prepare(sc, path);
    long long before = cdh5_io_count();
    writer(sc, path, -1);
    long long total = cdh5_io_count() - before;
    assert_true(total > 20);
    for (long long k = 1; k <= total + 1; k = next_kill_point(k, total)) {
        prepare(sc, path);
        char marks[16];
        int killed, m = run_writer(sc, path, k, marks, (int)sizeof marks, &killed);
        /* the fault is reached at every k up to the count, and only there */
        assert_int_equal(killed, k <= total);
        int opened = m > 0, done = opened ? m - 1 : 0;
        char err[256] = "";
        int n = access(path, F_OK) == 0 ? cd_h5_snapshot_count(path, err, sizeof err) : -1;
        if (sc == NEW_RUN && !opened) {
            /* (HDF5 1.10.8 keeps something of a failed open of such a
             * half-made file until exit, where it prints "infinite loop
             * closing library"; its own sec2 driver does the same) */
            if (n > 0) fail_msg("k = %lld: a snapshot before the first commit", k);
            continue; /* killed before its first commit: nothing promised */
        }
        int base = sc == RESUME_RUN ? RESUME_KEEP : 0;
        if (n < 0) fail_msg("k = %lld: %s", k, err);
        if (sc == REPLACE_RUN && done == 0 && n == OLD_SNAPS) {
            check_contents(path, n); /* the old run, whole, until the new one holds a snapshot */
        } else if (sc == RESUME_RUN && !opened) {
            /* the old run whole, or cut at the resume step once that was committed */
            if (n != OLD_SNAPS && n != RESUME_KEEP) fail_msg("k = %lld: %d snapshots before the resume", k, n);
            check_contents(path, n);
        } else {
            /* every completed snapshot, and at most the one being committed when killed */
            if (n < base + done || n > base + done + 1) fail_msg("k = %lld: %d snapshots, %d completed", k, n, done);
            check_contents(path, base);
        }
        check_plain_hdf5(path, n);
    }
    clean(path);
}

static void test_io_crash_new_run(void **state)
{
    (void)state;
    sweep(NEW_RUN, "crash_new");
}

static void test_io_crash_replacing_run(void **state)
{
    (void)state;
    sweep(REPLACE_RUN, "crash_replace");
}

static void test_io_crash_resumed_run(void **state)
{
    (void)state;
    sweep(RESUME_RUN, "crash_resume");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_io_crash_new_run),
        cmocka_unit_test(test_io_crash_replacing_run),
        cmocka_unit_test(test_io_crash_resumed_run),
    };
    /* About 800 writers, each syncing its file a dozen times: in memory
     * (tmpfs) when the machine has it, so that the disk's sync latency does
     * not make the sweep slow; the syncs are made all the same. */
    char dir[] = "/dev/shm/capdem_crash_XXXXXX";
    int in_shm = mkdtemp(dir) && chdir(dir) == 0;
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    if (in_shm && chdir("/") == 0) rmdir(dir);
    return rc;
}
