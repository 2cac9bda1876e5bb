/* A clear refusal instead of a bare crash when libhdf5 itself fails on a
 * corrupted file.
 *
 * libhdf5 1.10 parses some of a file's metadata without checking it: a
 * corrupted layout message makes it divide by a zero chunk dimension
 * (SIGFPE inside H5Dopen), a corrupted group B-tree makes it copy from a
 * wild address (SIGSEGV), both before capdem's own checks (io_h5_check.h)
 * can look at anything (inputs in tests/fuzz/hdf5_defects; docs/testing.md,
 * "Sanitizers and fuzzing").  Between cdh5_guard_begin and cdh5_guard_end
 * such a fatal signal ends the process with exit 2 and one message that
 * names the file, as every other refusal of a bad file does.  It is armed
 * only while a user's file is read (resume, analyze, export), never while
 * a run writes: a crash there is not the file's fault. */
#ifndef CD_IO_H5_GUARD_H
#define CD_IO_H5_GUARD_H

/* Arms the guard for file `path`, read by command `tool` (e.g. "run
 * --resume"); both are copied.  A second call re-arms it for the new file. */
void cdh5_guard_begin(const char *tool, const char *path);
/* Disarms it: the signal handlers in place before cdh5_guard_begin return. */
void cdh5_guard_end(void);
/* Makes every later cdh5_guard_begin a no-op: fuzz targets, for which a
 * crash inside libhdf5 must stay a crash that the fuzzer reports. */
void cdh5_guard_disable(void);

#endif
