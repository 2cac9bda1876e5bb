/* The "capdem-journal" HDF5 file driver: POSIX I/O with atomic commits
 * (why and how: io_h5_journal.h, docs/output.md "Crash safety").
 *
 * Bytes [0, committed) of the file are the last commit.  A write there is
 * held in memory (the held list, in write order, read back through it);
 * a write at or past committed goes to the file at once, since nothing
 * committed points to it.  A commit syncs the file, writes the held list
 * as one checksummed journal, syncs that, applies it, syncs the file and
 * empties the journal.  Journal layout (little-endian as written by this
 * machine; a journal is only ever read on the machine that wrote it):
 *   "CAPDEMJ1", u64 inode of the file, u64 file size after replay,
 *   u64 entries, then per entry u64 address, u64 length, bytes,
 *   and last u32 crc32 of everything before it, "END!". */
#define _GNU_SOURCE /* flock */
#include "io/io_h5_journal.h"
#include "io/io_h5_layout.h"
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#define JOURNAL_SUFFIX CDH5_NAME(JOURNAL) /* "-journal" (kernels/runfile.def) */
#define JOURNAL_MAGIC  "CAPDEMJ1"
#define JOURNAL_END    "END!"
#define HEAD_BYTES     (8 + 3 * 8)
#define ENTRY_HEAD     (2 * 8)
#define TAIL_BYTES     (4 + 4)
#define MAX_ADDR       (((haddr_t)1 << (8 * sizeof(off_t) - 1)) - 1)

typedef struct {
    haddr_t addr;
    size_t len, at; /* bytes at held_bytes + at */
} held_write;

typedef struct {
    H5FD_t pub; /* first: HDF5 sees this part */
    int fd;     /* the file; get_handle hands out &fd (a POSIX descriptor) */
    int writable;
    int drop_on_close;
    dev_t dev;
    ino_t ino;
    haddr_t eoa;       /* HDF5's end of allocation */
    haddr_t eof;       /* size of the file once the held writes are applied */
    haddr_t committed; /* [0, committed) is the last commit */
    haddr_t cut;       /* a truncation below committed held for the commit, or HADDR_UNDEF */
    held_write *held;
    size_t n_held, cap_held;
    unsigned char *held_bytes;
    size_t used_bytes, cap_bytes;
    char jpath[PATH_MAX];
} cdj_file;

/* ---- counted system calls (fault injection for the crash tests) ---------- */

static long long io_count, fault_at = -1;

void cdh5_fault_after(long long n) { fault_at = n > 0 ? io_count + n : -1; }

long long cdh5_io_count(void) { return io_count; }

/* Counts one write-like call; at the chosen one, half of it happens and the
 * process dies, as a kill in the middle of the call would leave it. */
static void count_io(int fd, const void *buf, size_t len, off_t at)
{
    if (++io_count != fault_at) return;
    if (buf && len > 1) {
        ssize_t w = pwrite(fd, buf, len / 2, at);
        (void)w;
    }
    raise(SIGKILL);
}

static int write_all(int fd, const void *buf, size_t len, off_t at)
{
    count_io(fd, buf, len, at);
    const unsigned char *p = buf;
    while (len) {
        ssize_t w = pwrite(fd, p, len, at);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return -1;
        p += w;
        len -= (size_t)w;
        at += w;
    }
    return 0;
}

static int truncate_to(int fd, off_t size)
{
    count_io(fd, NULL, 0, 0);
    return ftruncate(fd, size);
}

static int sync_fd(int fd)
{
    count_io(fd, NULL, 0, 0);
    return fdatasync(fd);
}

/* Bytes at `at` (short at the end of the file: the rest zero). */
static int read_all(int fd, void *buf, size_t len, off_t at)
{
    unsigned char *p = buf;
    while (len) {
        ssize_t r = pread(fd, p, len, at);
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) return -1;
        if (r == 0) {
            memset(p, 0, len);
            return 0;
        }
        p += r;
        len -= (size_t)r;
        at += r;
    }
    return 0;
}

/* ---- the held list ---------------------------------------------------------- */

static int hold(cdj_file *f, haddr_t addr, size_t len, const void *buf)
{
    /* the same range again (a metadata entry or a chunk rewritten): in place */
    for (size_t i = f->n_held; i-- > 0;) {
        if (f->held[i].addr == addr && f->held[i].len == len) {
            memcpy(f->held_bytes + f->held[i].at, buf, len);
            return 0;
        }
    }
    if (f->n_held == f->cap_held) {
        size_t cap = f->cap_held ? 2 * f->cap_held : 64;
        held_write *h = realloc(f->held, cap * sizeof *h);
        if (!h) return -1;
        f->held = h;
        f->cap_held = cap;
    }
    if (f->used_bytes + len > f->cap_bytes) {
        size_t cap = f->cap_bytes ? f->cap_bytes : 65536;
        while (cap < f->used_bytes + len) cap *= 2;
        unsigned char *b = realloc(f->held_bytes, cap);
        if (!b) return -1;
        f->held_bytes = b;
        f->cap_bytes = cap;
    }
    memcpy(f->held_bytes + f->used_bytes, buf, len);
    f->held[f->n_held++] = (held_write){addr, len, f->used_bytes};
    f->used_bytes += len;
    return 0;
}

/* Held bytes over [addr, addr + len) of buf, in write order. */
static void overlay(const cdj_file *f, haddr_t addr, size_t len, unsigned char *buf)
{
    for (size_t i = 0; i < f->n_held; i++) {
        const held_write *h = &f->held[i];
        haddr_t lo = h->addr > addr ? h->addr : addr;
        haddr_t hi = h->addr + h->len < addr + len ? h->addr + h->len : addr + len;
        if (lo < hi) memcpy(buf + (lo - addr), f->held_bytes + h->at + (lo - h->addr), (size_t)(hi - lo));
    }
}

static void forget_held(cdj_file *f)
{
    f->n_held = 0;
    f->used_bytes = 0;
    f->cut = HADDR_UNDEF;
}

/* ---- the journal -------------------------------------------------------------- */

static void put64(unsigned char *p, uint64_t v) { memcpy(p, &v, 8); }

static uint64_t get64(const unsigned char *p)
{
    uint64_t v;
    memcpy(&v, p, 8);
    return v;
}

static uint32_t checksum(const unsigned char *p, size_t len)
{
    uLong c = crc32(0L, Z_NULL, 0);
    while (len) {
        uInt part = len > (1u << 30) ? (1u << 30) : (uInt)len;
        c = crc32(c, p, part);
        p += part;
        len -= part;
    }
    return (uint32_t)c;
}

/* The journal image of the held list, size in *len (caller frees). */
static unsigned char *journal_image(const cdj_file *f, haddr_t final_size, size_t *len)
{
    size_t n = HEAD_BYTES + TAIL_BYTES;
    for (size_t i = 0; i < f->n_held; i++) n += ENTRY_HEAD + f->held[i].len;
    unsigned char *img = malloc(n), *p = img;
    if (!img) return NULL;
    memcpy(p, JOURNAL_MAGIC, 8);
    put64(p + 8, (uint64_t)f->ino);
    put64(p + 16, (uint64_t)final_size);
    put64(p + 24, (uint64_t)f->n_held);
    p += HEAD_BYTES;
    for (size_t i = 0; i < f->n_held; i++) {
        put64(p, (uint64_t)f->held[i].addr);
        put64(p + 8, (uint64_t)f->held[i].len);
        memcpy(p + ENTRY_HEAD, f->held_bytes + f->held[i].at, f->held[i].len);
        p += ENTRY_HEAD + f->held[i].len;
    }
    uint32_t c = checksum(img, (size_t)(p - img));
    memcpy(p, &c, 4);
    memcpy(p + 4, JOURNAL_END, 4);
    *len = n;
    return img;
}

/* Reads jpath into f's held list when it is a complete journal of this
 * file (1), else leaves f as it is (0: no journal, an empty or torn one,
 * or one of another file); -1 when it cannot be read. */
static int load_journal(cdj_file *f, haddr_t *final_size)
{
    int jfd = open(f->jpath, O_RDONLY | O_CLOEXEC | O_NOCTTY);
    if (jfd < 0) return errno == ENOENT ? 0 : -1;
    struct stat st;
    int rc = fstat(jfd, &st) < 0 ? -1 : 0;
    unsigned char *img = NULL;
    size_t n = rc ? 0 : (size_t)st.st_size;
    if (!rc && n >= HEAD_BYTES + TAIL_BYTES && (img = malloc(n)) && !read_all(jfd, img, n, 0)) {
        uint32_t c;
        memcpy(&c, img + n - TAIL_BYTES, 4);
        int whole = !memcmp(img, JOURNAL_MAGIC, 8) && !memcmp(img + n - 4, JOURNAL_END, 4) &&
                    c == checksum(img, n - TAIL_BYTES) && get64(img + 8) == (uint64_t)f->ino;
        uint64_t entries = whole ? get64(img + 24) : 0;
        const unsigned char *p = img + HEAD_BYTES, *end = img + n - TAIL_BYTES;
        for (uint64_t i = 0; whole && i < entries; i++) {
            if ((size_t)(end - p) < ENTRY_HEAD) break;
            uint64_t addr = get64(p), len = get64(p + 8);
            if (len > (uint64_t)(end - p - ENTRY_HEAD) || addr > MAX_ADDR) break;
            if (hold(f, (haddr_t)addr, (size_t)len, p + ENTRY_HEAD)) {
                rc = -1;
                break;
            }
            p += ENTRY_HEAD + len;
        }
        if (!rc && whole && p == end && f->n_held == entries) {
            *final_size = (haddr_t)get64(img + 16);
            rc = 1;
        } else if (!rc) {
            forget_held(f);
        }
    } else if (!rc && n >= HEAD_BYTES + TAIL_BYTES) {
        rc = -1;
    }
    free(img);
    close(jfd);
    return rc;
}

/* Applies the held list to the file and sets its size: the last step of a
 * commit and the replay of a journal. */
static int apply_held(cdj_file *f, haddr_t final_size)
{
    for (size_t i = 0; i < f->n_held; i++)
        if (write_all(f->fd, f->held_bytes + f->held[i].at, f->held[i].len, (off_t)f->held[i].addr)) return -1;
    struct stat st;
    if (fstat(f->fd, &st) < 0) return -1;
    if ((haddr_t)st.st_size != final_size && truncate_to(f->fd, (off_t)final_size)) return -1;
    if (sync_fd(f->fd)) return -1;
    forget_held(f);
    f->eof = final_size;
    return 0;
}

static int empty_journal(const char *jpath)
{
    int jfd = open(jpath, O_WRONLY | O_CLOEXEC | O_NOCTTY);
    if (jfd < 0) return errno == ENOENT ? 0 : -1;
    int rc = truncate_to(jfd, 0);
    close(jfd);
    return rc;
}

/* The held writes become the file's content (see the top of the file). */
static int commit(cdj_file *f)
{
    haddr_t final_size = f->eof > f->eoa ? f->eof : f->eoa;
    if (f->cut != HADDR_UNDEF) final_size = f->cut > f->eoa ? f->cut : f->eoa;
    /* what new bytes the commit points to are on disk before it is */
    if (sync_fd(f->fd)) return -1;
    if (f->n_held) {
        size_t len;
        unsigned char *img = journal_image(f, final_size, &len);
        if (!img) return -1;
        int jfd = open(f->jpath, O_RDWR | O_CREAT | O_CLOEXEC | O_NOCTTY, 0666);
        int rc = jfd < 0 || write_all(jfd, img, len, 0) || truncate_to(jfd, (off_t)len) || sync_fd(jfd) ? -1 : 0;
        free(img);
        if (jfd >= 0) close(jfd);
        if (rc) return -1;
    }
    if (apply_held(f, final_size)) return -1;
    /* A journal left full would be replayed once more, which is harmless
     * (the same bytes) until the next commit writes a new one. */
    if (empty_journal(f->jpath)) return -1;
    f->committed = f->eoa;
    return 0;
}

/* ---- the driver's callbacks ------------------------------------------------- */

static const H5FD_class_t journal_class;

static H5FD_t *j_open(const char *name, unsigned flags, hid_t fapl, haddr_t maxaddr)
{
    (void)fapl;
    if (!name || !*name || !maxaddr || maxaddr == HADDR_UNDEF || strlen(name) + strlen(JOURNAL_SUFFIX) >= PATH_MAX)
        return NULL;
    int oflags = (flags & H5F_ACC_RDWR) ? O_RDWR : O_RDONLY;
    if (flags & H5F_ACC_TRUNC) oflags |= O_TRUNC;
    if (flags & H5F_ACC_CREAT) oflags |= O_CREAT;
    if (flags & H5F_ACC_EXCL) oflags |= O_EXCL;
    int fd = open(name, oflags | O_CLOEXEC | O_NOCTTY, 0666);
    if (fd < 0) return NULL;
    cdj_file *f = calloc(1, sizeof *f);
    struct stat st;
    if (!f || fstat(fd, &st) < 0) {
        free(f);
        close(fd);
        return NULL;
    }
    f->fd = fd;
    f->writable = (flags & H5F_ACC_RDWR) != 0;
    f->dev = st.st_dev;
    f->ino = st.st_ino;
    f->cut = HADDR_UNDEF;
    snprintf(f->jpath, sizeof f->jpath, "%s%s", name, JOURNAL_SUFFIX);
    haddr_t final_size = (haddr_t)st.st_size;
    int replay = (flags & H5F_ACC_TRUNC) ? 0 : load_journal(f, &final_size);
    int rc = replay < 0 ? -1 : 0;
    if (replay > 0 && f->writable) {
        /* the writer killed between journal and file: finish its commit,
         * alone (another process must not be writing it) */
        if (flock(fd, LOCK_EX | LOCK_NB) < 0 && (errno == EWOULDBLOCK || errno == EAGAIN)) rc = -1;
        else rc = apply_held(f, final_size) || empty_journal(f->jpath) ? -1 : 0;
    }
    if (rc) {
        free(f->held);
        free(f->held_bytes);
        free(f);
        close(fd);
        return NULL;
    }
    /* read-only with a journal: the held list is the replay, kept in memory */
    f->eof = final_size;
    f->committed = f->writable ? f->eof : 0;
    return &f->pub;
}

static herr_t j_close(H5FD_t *file)
{
    cdj_file *f = (cdj_file *)file;
    herr_t rc = 0;
    if (f->writable) {
        if (f->drop_on_close) forget_held(f);
        if (commit(f)) rc = -1;
        else if (unlink(f->jpath) < 0 && errno != ENOENT) rc = -1;
    }
    if (close(f->fd) < 0) rc = -1;
    free(f->held);
    free(f->held_bytes);
    free(f);
    return rc;
}

static int j_cmp(const H5FD_t *a, const H5FD_t *b)
{
    const cdj_file *f = (const cdj_file *)a, *g = (const cdj_file *)b;
    if (f->dev != g->dev) return f->dev < g->dev ? -1 : 1;
    if (f->ino != g->ino) return f->ino < g->ino ? -1 : 1;
    return 0;
}

static herr_t j_query(const H5FD_t *file, unsigned long *flags)
{
    (void)file;
    *flags = H5FD_FEAT_AGGREGATE_METADATA | H5FD_FEAT_ACCUMULATE_METADATA | H5FD_FEAT_DATA_SIEVE |
             H5FD_FEAT_AGGREGATE_SMALLDATA;
    return 0;
}

static haddr_t j_get_eoa(const H5FD_t *file, H5FD_mem_t type)
{
    (void)type;
    return ((const cdj_file *)file)->eoa;
}

static herr_t j_set_eoa(H5FD_t *file, H5FD_mem_t type, haddr_t addr)
{
    (void)type;
    ((cdj_file *)file)->eoa = addr;
    return 0;
}

static haddr_t j_get_eof(const H5FD_t *file, H5FD_mem_t type)
{
    (void)type;
    return ((const cdj_file *)file)->eof;
}

static herr_t j_get_handle(H5FD_t *file, hid_t fapl, void **handle)
{
    (void)fapl;
    *handle = &((cdj_file *)file)->fd;
    return 0;
}

static herr_t j_read(H5FD_t *file, H5FD_mem_t type, hid_t dxpl, haddr_t addr, size_t size, void *buf)
{
    (void)type;
    (void)dxpl;
    cdj_file *f = (cdj_file *)file;
    /* nothing past HDF5's end of allocation: an address there comes from
     * corrupted metadata, and refusing it keeps HDF5 from parsing zeros */
    if (addr == HADDR_UNDEF || addr > MAX_ADDR || size > MAX_ADDR - addr || addr + size > f->eoa) return -1;
    if (read_all(f->fd, buf, size, (off_t)addr)) return -1;
    /* past a held truncation the file reads as zeros, as it will after it */
    if (f->cut != HADDR_UNDEF && addr + size > f->cut) {
        haddr_t from = addr > f->cut ? addr : f->cut;
        memset((unsigned char *)buf + (from - addr), 0, (size_t)(addr + size - from));
    }
    overlay(f, addr, size, buf);
    return 0;
}

static herr_t j_write(H5FD_t *file, H5FD_mem_t type, hid_t dxpl, haddr_t addr, size_t size, const void *buf)
{
    (void)type;
    (void)dxpl;
    cdj_file *f = (cdj_file *)file;
    if (!f->writable || addr == HADDR_UNDEF || addr > MAX_ADDR || size > MAX_ADDR - addr || addr + size > f->eoa)
        return -1;
    const unsigned char *p = buf;
    if (addr < f->committed) {
        size_t part = addr + size <= f->committed ? size : (size_t)(f->committed - addr);
        if (hold(f, addr, part, p)) return -1;
        addr += part;
        size -= part;
        p += part;
    }
    if (size && write_all(f->fd, p, size, (off_t)addr)) return -1;
    if (addr + size > f->eof) f->eof = addr + size;
    return 0;
}

static herr_t j_flush(H5FD_t *file, hid_t dxpl, hbool_t closing)
{
    (void)file;
    (void)dxpl;
    (void)closing;
    return 0; /* durability comes with cdh5_commit */
}

static herr_t j_truncate(H5FD_t *file, hid_t dxpl, hbool_t closing)
{
    (void)dxpl;
    (void)closing;
    cdj_file *f = (cdj_file *)file;
    if (!f->writable || f->eoa == f->eof) return 0;
    if (f->eoa >= f->committed) {
        if (truncate_to(f->fd, (off_t)f->eoa)) return -1;
    } else {
        f->cut = f->eoa; /* committed bytes go only with the next commit */
    }
    f->eof = f->eoa;
    return 0;
}

static herr_t j_lock(H5FD_t *file, hbool_t rw)
{
    cdj_file *f = (cdj_file *)file;
    if (flock(f->fd, (rw ? LOCK_EX : LOCK_SH) | LOCK_NB) == 0) return 0;
    /* file systems without flock: go on unlocked, as HDF5's own driver does */
    return errno == ENOSYS || errno == ENOLCK || errno == EOPNOTSUPP || errno == EINVAL ? 0 : -1;
}

static herr_t j_unlock(H5FD_t *file)
{
    cdj_file *f = (cdj_file *)file;
    if (flock(f->fd, LOCK_UN) == 0) return 0;
    return errno == ENOSYS || errno == ENOLCK || errno == EOPNOTSUPP || errno == EINVAL ? 0 : -1;
}

static const H5FD_class_t journal_class = {
    .name = "capdem-journal",
    .maxaddr = MAX_ADDR,
    .fc_degree = H5F_CLOSE_WEAK,
    .open = j_open,
    .close = j_close,
    .cmp = j_cmp,
    .query = j_query,
    .get_eoa = j_get_eoa,
    .set_eoa = j_set_eoa,
    .get_eof = j_get_eof,
    .get_handle = j_get_handle,
    .read = j_read,
    .write = j_write,
    .flush = j_flush,
    .truncate = j_truncate,
    .lock = j_lock,
    .unlock = j_unlock,
    .fl_map = H5FD_FLMAP_DICHOTOMY,
};

/* ---- the public side ------------------------------------------------------ */

static hid_t driver_id = H5I_INVALID_HID;

static hid_t driver(void)
{
    if (driver_id < 0 || H5Iis_valid(driver_id) <= 0) driver_id = H5FDregister(&journal_class);
    return driver_id;
}

hid_t cdh5_fapl(void)
{
    hid_t id = driver(), fapl = id < 0 ? H5I_INVALID_HID : H5Pcreate(H5P_FILE_ACCESS);
    if (fapl < 0) return H5I_INVALID_HID;
    if (H5Pset_driver(fapl, id, NULL) < 0 || H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG) < 0) {
        H5Pclose(fapl);
        return H5I_INVALID_HID;
    }
    return fapl;
}

/* The driver's record of an open file, or NULL when another driver has it. */
static cdj_file *journal_of(hid_t file)
{
    hid_t fapl = H5Fget_access_plist(file);
    int ours = fapl >= 0 && H5Pget_driver(fapl) == driver_id;
    void *handle = NULL;
    if (ours && H5Fget_vfd_handle(file, fapl, &handle) < 0) handle = NULL;
    if (fapl >= 0) H5Pclose(fapl);
    return ours && handle ? (cdj_file *)((char *)handle - offsetof(cdj_file, fd)) : NULL;
}

int cdh5_commit(hid_t file, const char *path, char *err, size_t errlen)
{
    if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) {
        snprintf(err, errlen, "%s: cannot flush", path);
        return -1;
    }
    cdj_file *f = journal_of(file);
    if (f && commit(f)) {
        snprintf(err, errlen, "%s: cannot commit what was written (journal %s): %s", path, f->jpath, strerror(errno));
        return -1;
    }
    return 0;
}

int cdh5_journal_eoa(hid_t file, haddr_t *eoa)
{
    cdj_file *f = journal_of(file);
    if (!f) return -1;
    *eoa = f->eoa;
    return 0;
}

void cdh5_drop_on_close(hid_t file)
{
    cdj_file *f = journal_of(file);
    if (f) f->drop_on_close = 1;
}

int cdh5_journal_follow(hid_t file, const char *new_path, char *err, size_t errlen)
{
    cdj_file *f = journal_of(file);
    if (!f) return 0;
    char jpath[PATH_MAX];
    if ((size_t)snprintf(jpath, sizeof jpath, "%s%s", new_path, JOURNAL_SUFFIX) >= sizeof jpath) {
        snprintf(err, errlen, "%s: path too long", new_path);
        return -1;
    }
    /* the journal is empty between commits: whether moved or made anew, it holds nothing yet */
    if (rename(f->jpath, jpath) < 0 && errno != ENOENT) {
        snprintf(err, errlen, "%s: cannot move the journal %s to %s: %s", new_path, f->jpath, jpath, strerror(errno));
        return -1;
    }
    memcpy(f->jpath, jpath, sizeof jpath);
    return 0;
}

int cdh5_recover(const char *path, char *err, size_t errlen)
{
    cdj_file f;
    memset(&f, 0, sizeof f);
    f.cut = HADDR_UNDEF;
    if ((size_t)snprintf(f.jpath, sizeof f.jpath, "%s%s", path, JOURNAL_SUFFIX) >= sizeof f.jpath) {
        snprintf(err, errlen, "%s: path too long", path);
        return -1;
    }
    f.fd = open(path, O_RDWR | O_CLOEXEC | O_NOCTTY);
    struct stat st;
    if (f.fd < 0 || fstat(f.fd, &st) < 0) {
        snprintf(err, errlen, "%s: %s", path, strerror(errno));
        if (f.fd >= 0) close(f.fd);
        return -1;
    }
    /* alone: a running writer's journal is its own business */
    if (flock(f.fd, LOCK_EX | LOCK_NB) < 0 && (errno == EWOULDBLOCK || errno == EAGAIN)) {
        snprintf(err, errlen, "%s is in use by another process: nothing done", path);
        close(f.fd);
        return -1;
    }
    f.ino = st.st_ino;
    haddr_t size;
    int full = load_journal(&f, &size);
    int rc = full;
    if (full < 0) {
        snprintf(err, errlen, "%s: cannot read its journal %s: %s", path, f.jpath, strerror(errno));
    } else if (full > 0 && apply_held(&f, size)) {
        snprintf(err, errlen, "%s: cannot replay its journal %s: %s", path, f.jpath, strerror(errno));
        rc = -1;
    }
    if (rc >= 0 && unlink(f.jpath) < 0 && errno != ENOENT) {
        snprintf(err, errlen, "%s: cannot remove its journal %s: %s", path, f.jpath, strerror(errno));
        rc = -1;
    }
    free(f.held);
    free(f.held_bytes);
    close(f.fd);
    return rc;
}
