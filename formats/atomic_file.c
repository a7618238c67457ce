/* atomic_file.c - see atomic_file.h. */
#define _GNU_SOURCE /* fallocate, getrandom */
#include "crowdbake/atomic_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

/* The caller's way to create and release temporaries (cb_atomic_set_temp_files); all NULL: the
 * library's own, tracked by no one. Set by the program before it writes, never by the library. */
static cb_temp_files temp_files;

void cb_atomic_set_temp_files(const cb_temp_files *files)
{
    if (files) temp_files = *files;
    else memset(&temp_files, 0, sizeof temp_files);
}

int cb_atomic_create_temp(char *path_template)
{
    size_t n = strlen(path_template);
    if (n < 6 || strcmp(path_template + n - 6, "XXXXXX") != 0) {
        errno = EINVAL;
        return -1;
    }
    static const char letters[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
    for (int attempt = 0; attempt < 100; ++attempt) {
        unsigned char r[6];
        if (getrandom(r, sizeof r, 0) != (ssize_t)sizeof r) return -1;
        for (int k = 0; k < 6; ++k) path_template[n - 6 + k] = letters[r[k] % (sizeof letters - 1)];
        /* 0666 less the umask, as a plain create makes it (mkstemp's 0600 would need the umask
         * read, and reading it means setting it: process-wide, under other threads' creates) */
        int fd = open(path_template, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0 || errno != EEXIST) return fd;
    }
    errno = EEXIST;
    return -1;
}

static void release_temp(cb_atomic_file *f)
{
    if (f->slot >= 0 && temp_files.released) temp_files.released(temp_files.ctx, f->slot);
    f->slot = -1;
}

static void reached(const char *point)
{
    if (temp_files.reached) temp_files.reached(temp_files.ctx, point);
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
    f->fd = temp_files.create ? temp_files.create(temp_files.ctx, f->tmp_path, &f->slot)
                              : cb_atomic_create_temp(f->tmp_path);
    if (f->fd < 0) {
        int e = errno;
        free(f->tmp_path), f->tmp_path = NULL; /* nothing was created */
        cb_fail(err, CB_ERR_IO, "%s: cannot write: %s", path, strerror(e));
        cb_atomic_abort(f);
        return CB_ERR_IO;
    }
    return CB_OK;
}

cb_status cb_atomic_write(cb_atomic_file *f, const void *data, size_t size, cb_error *err)
{
    const char *p = data;
    size_t half = f->written == 0 ? size / 2 : 0; /* where "mid-write" falls (cb_temp_files.reached) */
    while (size > 0) {
        if (half && f->written >= half) {
            reached("mid-write");
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
    reached("before-rename");
    if (rc != 0 || rename(f->tmp_path, f->path) != 0) {
        cb_fail(err, CB_ERR_IO, "%s: cannot replace the file: %s", f->path, strerror(errno));
        cb_atomic_abort(f);
        return CB_ERR_IO;
    }
    free(f->tmp_path), f->tmp_path = NULL;
    release_temp(f);
    cb_atomic_abort(f); /* releases the rest */
    return CB_OK;
}

void cb_atomic_abort(cb_atomic_file *f)
{
    unmap(f);
    if (f->fd >= 0) close(f->fd);
    if (f->tmp_path) unlink(f->tmp_path);
    release_temp(f);
    free(f->tmp_path);
    free(f->path);
    f->fd = -1;
    f->tmp_path = f->path = NULL;
}
