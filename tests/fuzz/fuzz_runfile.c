/* libFuzzer target: the readers of run files on arbitrary bytes taken as
 * an HDF5 file -- what `capdem run --resume` (src/io/io_h5_read.c,
 * src/io/io_h5_check.c), `capdem analyze` (host/analysis/analyze_read.c,
 * analyze_series.c) and `capdem export` (host/export_*.c) read.  The input
 * is written to a scratch file (HDF5's readers take a path; in tmpfs the
 * write costs microseconds), then every reader runs on it.  A refusal is
 * fine; a crash, a sanitizer finding, a leak or a hang is a finding.
 * docs/testing.md, "Sanitizers and fuzzing", says how to run it. */
#include <fcntl.h>
#include <hdf5.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "analysis/analyze.h"
#include "config/config.h"
#include "export/export.h"
#include "io/io_h5.h"
#include "io/io_h5_guard.h"
#include "core/sim.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char dir_used[200], path[256], xmf[256], side[256];
static long n_inputs;
/* CAPDEM_FUZZ_READERS: which readers run, any of "resume,analyze,export"
 * (default: all three) */
static int do_resume = 1, do_analyze = 1, do_export = 1;

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    cdh5_guard_disable(); /* a crash inside libhdf5 stays a crash the fuzzer reports */
    const char *dir = getenv("CAPDEM_FUZZ_DIR");
    if (!dir) dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
    snprintf(dir_used, sizeof dir_used, "%s", dir);
    const char *which = getenv("CAPDEM_FUZZ_READERS");
    if (which) {
        do_resume = strstr(which, "resume") != NULL;
        do_analyze = strstr(which, "analyze") != NULL;
        do_export = strstr(which, "export") != NULL;
    }
    cd_h5_no_atexit();
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    return 0;
}

/* What `capdem run --resume` reads: the count, the stored config, then the
 * tails' checksums and the last snapshot into a state set up from that
 * config (only for small runs: the set-up itself is not under test).  The
 * set-up is kept for the next input with the same config text (most
 * mutations leave it alone, and the set-up costs more than the reading):
 * cd_h5_read_snapshot writes every column it restores, whatever the state
 * held (tests/unit/test_io_h5 reads into a state full of garbage). */
static void resume_readers(void)
{
    static cd_sim sim;
    static char *sim_text; /* the config text sim was set up from; NULL: none */
    char err[2048], where[64];
    cd_h5_snapshot_count(path, err, sizeof err);
    char *text = cd_h5_read_latest_config_text(path, where, sizeof where, err, sizeof err);
    if (!text) return;
    if (!sim_text || strcmp(text, sim_text)) {
        if (sim_text) cd_sim_free(&sim);
        free(sim_text);
        sim_text = NULL;
        cd_config cfg;
        if (cd_config_parse(text, "stored", &cfg, err, sizeof err) == 0) {
            long total = 0;
            for (int k = 0; k < cfg.n_species && total <= 64; k++)
                total += cfg.species[k].count > 64 ? 65 : cfg.species[k].count;
            if (total <= 64 && cfg.fill_ratio == 0 && cd_sim_setup(&sim, &cfg, err, sizeof err) == 0) sim_text = text;
            cd_config_free(&cfg);
        }
    }
    if (sim_text && cd_h5_check_tails(path, err, sizeof err) == 0)
        cd_h5_read_snapshot(path, -1, &sim.s, err, sizeof err);
    if (text != sim_text) free(text);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* a new name for every input: a file HDF5 failed to close (corrupted
     * metadata it cannot flush) stays open in the library, and an open of
     * the same name would share it instead of reading the new bytes */
    long id = n_inputs++;
    snprintf(path, sizeof path, "%s/capdem-fuzz-%ld-%ld.h5", dir_used, (long)getpid(), id);
    snprintf(xmf, sizeof xmf, "%s/capdem-fuzz-%ld-%ld.xmf", dir_used, (long)getpid(), id);
    snprintf(side, sizeof side, "%s/capdem-fuzz-%ld-%ld.viz.h5", dir_used, (long)getpid(), id);
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd < 0 || write(fd, data, size) != (ssize_t)size) abort();
    close(fd);
    if (do_resume) resume_readers();
    if (do_analyze) {
        /* analyze without writing, the Monte Carlo volume kept small */
        cd_an_options opt;
        cd_an_options_defaults(&opt);
        opt.write = 0;
        opt.quiet = 1;
        opt.mc_points = 1000;
        cd_an_report rep;
        char err[2048];
        cd_analyze_file(path, &opt, &rep, err, sizeof err);
        cd_an_report_free(&rep);
    }
    if (do_export) {
        /* export last: it writes its helper datasets into the file */
        char *argv[] = {path, "-o", xmf, NULL};
        cd_cmd_export(3, argv);
        unlink(xmf);
        unlink(side);
    }
    unlink(path);
    char journal[300]; /* (left by a reader that could not close the file) */
    snprintf(journal, sizeof journal, "%s-journal", path);
    unlink(journal);
    /* Any other identifier left open is a reader's leak (an error path
     * that forgot a close): a finding.  A file identifier may stay open
     * when HDF5 failed to close a corrupted file (it cannot flush it, and a
     * second close can fault inside the library); the reader has reported
     * that, and the next input gets another name. */
    hid_t ids[64];
    ssize_t n = H5Fget_obj_ids(H5F_OBJ_ALL, H5F_OBJ_ALL, 64, ids);
    for (ssize_t k = 0; k < n; k++)
        if (H5Iget_type(ids[k]) != H5I_FILE) {
            fprintf(stderr, "fuzz_runfile: the readers left an HDF5 identifier of type %d open\n",
                    (int)H5Iget_type(ids[k]));
            abort();
        }
    return 0;
}
