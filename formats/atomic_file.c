/* atomic_file.c - see atomic_file.h. */
#define _GNU_SOURCE /* mkostemp */
#include "atomic_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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
    f->fd = mkostemp(f->tmp_path, O_CLOEXEC);
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
    while (size > 0) {
        ssize_t n = write(f->fd, p, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            return cb_fail(err, CB_ERR_IO, "%s: write failed: %s; the previous file, if any, is unchanged", f->path,
                           n < 0 ? strerror(errno) : "no space");
        p += n;
        size -= (size_t)n;
    }
    return CB_OK;
}

cb_status cb_atomic_commit(cb_atomic_file *f, cb_error *err)
{
    if (fsync(f->fd) != 0 && errno != EINVAL) {
        cb_fail(err, CB_ERR_IO, "%s: write failed: %s; the previous file, if any, is unchanged", f->path, strerror(errno));
        cb_atomic_abort(f);
        return CB_ERR_IO;
    }
    int rc = close(f->fd);
    f->fd = -1;
    if (rc != 0 || rename(f->tmp_path, f->path) != 0) {
        cb_fail(err, CB_ERR_IO, "%s: cannot replace the file: %s", f->path, strerror(errno));
        cb_atomic_abort(f);
        return CB_ERR_IO;
    }
    free(f->tmp_path), f->tmp_path = NULL;
    cb_atomic_abort(f); /* releases the rest */
    return CB_OK;
}

void cb_atomic_abort(cb_atomic_file *f)
{
    if (f->fd >= 0) close(f->fd);
    if (f->tmp_path) unlink(f->tmp_path);
    free(f->tmp_path);
    free(f->path);
    f->fd = -1;
    f->tmp_path = f->path = NULL;
}
