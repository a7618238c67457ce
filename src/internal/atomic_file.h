/* atomic_file.h (internal: linked from libcrowdbake.a, not exported) - write a file so that readers see the old file or the complete new one,
 * never a partial one: a temporary file beside the target, renamed over it when complete. */
#ifndef CB_ATOMIC_FILE_H
#define CB_ATOMIC_FILE_H


#include "crowdbake/core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cb_atomic_file {
    int fd;
    char *path;     /* the target */
    char *tmp_path; /* .NAME.tmp.XXXXXX in the same directory */
    int slot;       /* the caller's token for the temporary (cb_temp_files.create), or -1 */
    size_t written; /* bytes written so far (through write, not the mapping) */
    void *map;      /* cb_atomic_map's mapping of the whole temporary, or NULL */
    size_t map_size;
} cb_atomic_file;

/* How a program that removes temporaries when it is interrupted (a signal handler) learns of
 * them: the library installs no handler and keeps no table, so the program creates each
 * temporary itself and is told when it is gone. All members may be NULL.
 *   create    makes the file from path_template (ending in XXXXXX, rewritten in place to the
 *             name made) and returns its descriptor or -1 with errno; *token is the program's
 *             (cb_atomic_create_temp does the creating; the program records the name first).
 *   released  the temporary with this token was renamed over its target or removed.
 *   reached   the write reached a point a test may stop the process at: "mid-write" (half of a
 *             temporary's first write done), "before-rename" (complete, not yet renamed). */
typedef struct cb_temp_files {
    int (*create)(void *ctx, char *path_template, int *token);
    void (*released)(void *ctx, int token);
    void (*reached)(void *ctx, const char *point);
    void *ctx;
} cb_temp_files;

/* Where every later cb_atomic_open creates its temporary; NULL (the default) for the library's
 * own. Process-wide, so for the program to set, once, before any thread writes; the library
 * never calls it. */
void cb_atomic_set_temp_files(const cb_temp_files *files);
/* Creates path_template (ending in XXXXXX, replaced by random letters) exclusively, mode 0666
 * less the umask, and returns its descriptor, or -1 with errno. */
int cb_atomic_create_temp(char *path_template);

cb_status cb_atomic_open(cb_atomic_file *f, const char *path, cb_error *err);
cb_status cb_atomic_write(cb_atomic_file *f, const void *data, size_t size, cb_error *err);
/* Reads back bytes already written, and writes over them (a header whose fields depend on what
 * follows it, written last). */
cb_status cb_atomic_read_back(cb_atomic_file *f, void *data, size_t size, uint64_t offset, cb_error *err);
cb_status cb_atomic_rewrite(cb_atomic_file *f, const void *data, size_t size, uint64_t offset,
                                          cb_error *err);
/* Gives the temporary `size` bytes with their blocks allocated, so that a full disk is an error
 * here and not a SIGBUS when the mapping is written, and maps it shared and writable at *out
 * (zeros; on huge pages where the file system offers them). Written through the mapping, the
 * bytes reach the file without a copy; cb_atomic_write still writes from offset 0 (a header
 * written last). The mapping is released by commit and abort. Fails (and leaves the file empty)
 * where a file system cannot allocate or map: the caller writes instead. */
cb_status cb_atomic_map(cb_atomic_file *f, size_t size, void **out, cb_error *err);
/* Flushes, renames over the target and releases f. On failure the target is untouched. A
 * library may write tmp_path itself (close fd first; set it to -1). */
cb_status cb_atomic_commit(cb_atomic_file *f, cb_error *err);
/* Removes the temporary file and releases f. Safe after a failed open or commit. */
void cb_atomic_abort(cb_atomic_file *f);

#ifdef __cplusplus
}
#endif

#endif
