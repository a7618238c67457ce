/* atomic_file.c - see atomic_file.h. */
#define _GNU_SOURCE /* mkostemp */
#include "crowdbake/atomic_file.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- temporaries to remove when the process is interrupted ----
 * A signal handler can reach nothing but globals, so this is crowdbake's one piece of global
 * mutable state: a fixed table of the temporary files being written, filled and emptied
 * lock-free, read by the handler with async-signal-safe calls only. */
enum { TEMP_SLOTS = 64, TEMP_PATH = 4096 };
static char temp_paths[TEMP_SLOTS][TEMP_PATH];
static atomic_int temp_state[TEMP_SLOTS]; /* 0 free, 1 being named, 2 named */

/* Creates the temporary file from `template` (ending in XXXXXX) inside a claimed slot, so the
 * name mkostemp chooses is visible to the handler before the file can exist. */
static int create_registered(char *template, int *slot)
{
    *slot = -1;
    size_t n = strlen(template) + 1;
    for (int i = 0; i < TEMP_SLOTS && n <= TEMP_PATH; ++i) {
        int expected = 0;
        if (!atomic_compare_exchange_strong(&temp_state[i], &expected, 1)) continue;
        memcpy(temp_paths[i], template, n);
        int fd = mkostemp(temp_paths[i], O_CLOEXEC);
        memcpy(template, temp_paths[i], n);
        if (fd < 0) {
            atomic_store(&temp_state[i], 0);
            return -1;
        }
        atomic_store(&temp_state[i], 2);
        *slot = i;
        return fd;
    }
    return mkostemp(template, O_CLOEXEC); /* untracked: still removed on every failure but a signal */
}

static void unregister_temp(int slot)
{
    if (slot >= 0) atomic_store(&temp_state[slot], 0);
}

static void write_stderr(const char *s) { (void)!write(2, s, strlen(s)); }

static void on_signal(int sig)
{
    int removed = 0;
    for (int i = 0; i < TEMP_SLOTS; ++i) {
        /* a slot being named holds either the template (no such file) or the created name */
        if (atomic_load(&temp_state[i]) != 0 && unlink(temp_paths[i]) == 0) ++removed;
    }
    write_stderr(sig == SIGINT ? "crowdbake: interrupted (SIGINT)" : sig == SIGTERM ? "crowdbake: terminated (SIGTERM)"
                                                                                  : "crowdbake: hung up (SIGHUP)");
    write_stderr(removed ? "; removed the partial output; the previous files are unchanged\n"
                         : "; no partial output was left (each file is the previous one or complete)\n");
    signal(sig, SIG_DFL);
    raise(sig);
}

void cb_atomic_cleanup_on_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGHUP, &sa, NULL);
}

/* Test hook: CROWDBAKE_TEST_STOP=mid-write stops the process (SIGSTOP) once half of its first
 * write to a temporary file is done; =before-rename stops it when the temporary is complete but
 * not yet renamed. A test then signals the stopped process at that exact point instead of racing
 * a short-lived file (tests/tools/interrupt_mid_write.py). Never set outside tests. */
static void stop_here_for_tests(const char *point)
{
    const char *at = getenv("CROWDBAKE_TEST_STOP");
    if (at && strcmp(at, point) == 0) raise(SIGSTOP);
}

static char *dir_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    if (!slash) return strdup(".");
    if (slash == path) return strdup("/");
    return strndup(path, (size_t)(slash - path));
}

cb_status cb_atomic_open(cb_atomic_file *f, const char *path, cb_error *err)
{
    memset(f, 0, sizeof *f);
    f->fd = -1;
    f->slot = -1;
    char *dir = dir_of(path);
    const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    size_t n = strlen(path) + 32;
    f->path = strdup(path);
    f->tmp_path = malloc(n);
    if (!dir || !f->path || !f->tmp_path) {
        free(dir);
        cb_atomic_abort(f);
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    snprintf(f->tmp_path, n, "%s/.%s.tmp.XXXXXX", dir, base);
    struct stat st;
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
        cb_fail(err, CB_ERR_IO, "%s: cannot write: directory %s does not exist (create it first)", path, dir);
        free(dir);
        cb_atomic_abort(f);
        return CB_ERR_IO;
    }
    free(dir);
    /* Replacing by rename would turn a device, a FIFO or a directory into a plain file. */
    if (lstat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
        cb_fail(err, CB_ERR_IO, "%s: exists and is not a regular file; crowdbake replaces outputs atomically, so give it "
                "a file path", path);
        free(f->tmp_path), f->tmp_path = NULL;
        cb_atomic_abort(f);
        return CB_ERR_IO;
    }
    f->fd = create_registered(f->tmp_path, &f->slot);
    if (f->fd < 0) {
        int e = errno;
        free(f->tmp_path), f->tmp_path = NULL; /* nothing was created */
        cb_fail(err, CB_ERR_IO, "%s: cannot write: %s", path, strerror(e));
        cb_atomic_abort(f);
        return CB_ERR_IO;
    }
    /* mkstemp makes 0600; give the file the mode a plain create would. */
    mode_t mask = umask(0);
    umask(mask);
    fchmod(f->fd, 0666 & ~mask);
    return CB_OK;
}

cb_status cb_atomic_write(cb_atomic_file *f, const void *data, size_t size, cb_error *err)
{
    const char *p = data;
    size_t half = f->written == 0 ? size / 2 : 0; /* where the mid-write test stop falls */
    while (size > 0) {
        if (half && f->written >= half) {
            stop_here_for_tests("mid-write");
            half = 0;
        }
        ssize_t n = write(f->fd, p, half ? half - f->written : size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            return cb_fail(err, CB_ERR_IO, "%s: write failed: %s; the previous file, if any, is unchanged", f->path,
                           n < 0 ? strerror(errno) : "no space");
        p += n;
        size -= (size_t)n;
        f->written += (size_t)n;
    }
    return CB_OK;
}

cb_status cb_atomic_read_back(cb_atomic_file *f, void *data, size_t size, uint64_t offset, cb_error *err)
{
    char *p = data;
    while (size > 0) {
        ssize_t n = pread(f->fd, p, size, (off_t)offset);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            return cb_fail(err, CB_ERR_IO, "%s: reading back the temporary file failed: %s", f->path,
                           n < 0 ? strerror(errno) : "it is shorter than what was written");
        p += n, offset += (uint64_t)n, size -= (size_t)n;
    }
    return CB_OK;
}

cb_status cb_atomic_rewrite(cb_atomic_file *f, const void *data, size_t size, uint64_t offset, cb_error *err)
{
    const char *p = data;
    if (offset + size > f->written)
        return cb_fail(err, CB_ERR_INTERNAL, "%s: a rewrite past the bytes written", f->path);
    while (size > 0) {
        ssize_t n = pwrite(f->fd, p, size, (off_t)offset);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            return cb_fail(err, CB_ERR_IO, "%s: write failed: %s; the previous file, if any, is unchanged", f->path,
                           n < 0 ? strerror(errno) : "no space");
        p += n, offset += (uint64_t)n, size -= (size_t)n;
    }
    return CB_OK;
}

cb_status cb_atomic_map(cb_atomic_file *f, size_t size, void **out, cb_error *err)
{
    *out = NULL;
    if (f->fd < 0 || f->map || f->written || size == 0)
        return cb_fail(err, CB_ERR_INTERNAL, "%s: only a new, empty temporary is mapped", f->path);
#if defined(__linux__)
    /* fallocate, not posix_fallocate: where the file system cannot allocate, glibc's fallback
     * writes every block, which costs what writing the file costs. */
    if (fallocate(f->fd, 0, 0, (off_t)size) != 0)
        return cb_fail(err, CB_ERR_IO, "%s: cannot allocate %zu bytes: %s", f->path, size, strerror(errno));
    void *map = mmap(NULL, size, PROT_READ | PROT_WRITE, MAP_SHARED, f->fd, 0);
    if (map == MAP_FAILED) {
        int e = errno;
        (void)!ftruncate(f->fd, 0);
        return cb_fail(err, CB_ERR_IO, "%s: cannot map the temporary file: %s", f->path, strerror(e));
    }
#if defined(MADV_HUGEPAGE)
    /* Page-cache folios of 2 MB where the file system has them (ext4 on Linux 6.16+): 28 faults
     * for 29 MB instead of 2,700. A hint; refused elsewhere. */
    madvise(map, size, MADV_HUGEPAGE);
#endif
    f->map = map, f->map_size = size;
    *out = map;
    return CB_OK;
#else
    return cb_fail(err, CB_ERR_IO, "%s: not mapped on this system", f->path);
#endif
}

static void unmap(cb_atomic_file *f)
{
    if (f->map) munmap(f->map, f->map_size);
    f->map = NULL, f->map_size = 0;
}

cb_status cb_atomic_commit(cb_atomic_file *f, cb_error *err)
{
    unmap(f); /* the written pages stay in the page cache, dirty, like write()'s */
    if (f->fd < 0) f->fd = open(f->tmp_path, O_RDONLY | O_CLOEXEC); /* written by another library */
    /* No fsync: rename makes the replacement atomic for every reader and for crashes of this
     * process; flushing to the disk (tens of ms for a large palette, the slowest step of a bake)
     * only matters on power loss, and then the .pal checksum, which the incremental check
     * verifies, makes the next run bake again. Compilers and build tools make the same choice. */
    if (f->fd < 0) {
        cb_fail(err, CB_ERR_IO, "%s: write failed: %s; the previous file, if any, is unchanged", f->path, strerror(errno));
        cb_atomic_abort(f);
        return CB_ERR_IO;
    }
    int rc = close(f->fd);
    f->fd = -1;
    stop_here_for_tests("before-rename");
    if (rc != 0 || rename(f->tmp_path, f->path) != 0) {
        cb_fail(err, CB_ERR_IO, "%s: cannot replace the file: %s", f->path, strerror(errno));
        cb_atomic_abort(f);
        return CB_ERR_IO;
    }
    free(f->tmp_path), f->tmp_path = NULL;
    unregister_temp(f->slot), f->slot = -1;
    cb_atomic_abort(f); /* releases the rest */
    return CB_OK;
}

void cb_atomic_abort(cb_atomic_file *f)
{
    unmap(f);
    if (f->fd >= 0) close(f->fd);
    if (f->tmp_path) unlink(f->tmp_path);
    unregister_temp(f->slot);
    f->slot = -1;
    free(f->tmp_path);
    free(f->path);
    f->fd = -1;
    f->tmp_path = f->path = NULL;
}
