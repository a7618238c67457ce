/* plumbing.h (internal) - what the crowdbake command needs of the library beyond its public API:
 * name lookups, arenas, large allocations, the parsers of setting names and the sentences that
 * explain a clip (the bake's own: bake_words.h). Linked into the tool from libcrowdbake.a; not exported from libcrowdbake.so,
 * not installed, and free to change (docs/library.md, "Two tiers"). */
#ifndef CB_INTERNAL_PLUMBING_H
#define CB_INTERNAL_PLUMBING_H

#include "crowdbake/palette.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- names: "did you mean" ---- */

/* Edit distance (insertions, deletions, substitutions) between two names. */
size_t cb_edit_distance(const char *a, const char *b);
/* The known name within two edits of `name` (the closest, the first on a tie), or NULL.
 * known[i] lies `stride` bytes after known[i-1], so it reads an array of strings or the name
 * field of an array of structs alike. */
const char *cb_closest_name(const char *name, const char *const *known, size_t count, size_t stride);

/* ---- memory: arenas (one owner for many small allocations), large buffers ---- */

cb_arena *cb_arena_create(void);
void cb_arena_free(cb_arena *arena);
/* Zeroed memory that lives until cb_arena_free; NULL when out of memory. */
void *cb_arena_alloc(cb_arena *arena, size_t count, size_t size);
const char *cb_arena_strdup(cb_arena *arena, const char *s);
/* Makes the arena the owner of memory allocated elsewhere: release(ptr) runs when the arena
 * is freed. Returns false when out of memory (then the caller still owns ptr). */
bool cb_arena_adopt(cb_arena *arena, void *ptr, void (*release)(void *));

/* Memory for buffers of a megabyte and more, on whole huge pages where the OS has them (the last
 * one counts whole once touched); smaller ones from malloc. Release with free(). */
void *cb_alloc_large(size_t bytes);
/* Hands the memory the allocator keeps after free() back to the OS where it can (glibc keeps a
 * model load's freed parse buffers, 8 MB for a 25 MB rig, resident in its heap), so that a
 * bake's buffers do not add to it. */
void cb_release_free_memory(void);

/* ---- sentences: why a bake decided what it did ---- */

/* Why the clip was judged a loop or not, with the measured numbers, in a few words (for `info`). */
void cb_loop_reason_text(const cb_clip_info *clip, char *out, size_t size);

/* ---- parsers of the settings' words (the command line's and a catalog's) ---- */

/* "mat4", "affine", "qpos"; "float", "half", "u16"; exr.h's lossless codes by name. */
bool cb_layout_parse(const char *text, cb_layout *out);
bool cb_bone_space_parse(const char *text, cb_bone_space *out);
bool cb_timed_rows_parse(const char *text, cb_timed_rows *out);
bool cb_precision_parse(const char *text, cb_precision *out);
bool cb_exr_compression_parse(const char *text, int *out);
/* "keep", "in-place" or "loops-in-place". */
bool cb_root_motion_parse(const char *text, cb_root_motion *out);

#ifdef __cplusplus
}
#endif

#endif
