/* bake_words.h (internal) - the bake job's plumbing for its front ends: the parser of --format
 * and a catalog's format, the sentences that explain a bake's rates and budgets
 * (src/bake/bake_words.c), and its bone space with its reason (src/bake/bake_local.c). Linked into the tool
 * from libcrowdbake.a; not exported, not installed. */
#ifndef CB_INTERNAL_BAKE_WORDS_H
#define CB_INTERNAL_BAKE_WORDS_H

#include "crowdbake/bake.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A comma-separated set of the formats' names (outputs.h: "pal", "exr", "ktx2", "babylon"; each
 * once), or "both" (pal and exr): CB_FORMAT_* bits, 0 when it is none of those. */
unsigned cb_formats_parse(const char *text);

/* A note summing up the clips whose rates were chosen by error (their rates, how many fitted),
 * and a line per clip over its budget (cb_bake_budget_text): an "error" when the bake failed
 * for it, a "warning" when written anyway. */
void cb_bake_budget_notes(const cb_bake_job *job, const cb_bake_result *result,
                          const char *(*setting_name)(cb_setting), cb_warnings *notes);

/* Planned clip i's rows at fps, into *frames: what cb_clip_analyze on sampler s (of the job's model
 * and skin) gives, its loop set on s likewise; from the clip's rate search's kept analysis where it
 * stands in (the same bits: clip_memo.h), else analyzed (Cow's 12 clips: 19.5 M instructions). */
cb_status cb_bake_clip_frames_at(const cb_bake_job *job, cb_sampler *s, uint32_t clip, double fps, uint32_t *frames,
                                 cb_error *err);

/* Why planned clip i has its rate and rows, in words: "72 fps, fitted rows: within 1 mm/m at 45
 * rows, sampled rows need more than 72 fps", "30 fps, sampled rows: the fixed fps". */
void cb_bake_clip_reason(const cb_bake_job *job, uint32_t clip, char *buf, size_t size);
/* Clip i over its budget, in words, with what would meet it: "clip 'Gallop' reaches 1.8 mm/m at
 * 120 fps (fitted rows), over max_error 1; it meets it at 180 fps (max_fps = 180), or give it
 * max_error = 1.9". setting_name names CB_SETTING_MAX_FPS, CB_SETTING_MAX_ERROR and
 * CB_SETTING_FPS the front end's way (the command line's flags); NULL, or NULL for a setting: the
 * catalog's keys. */
void cb_bake_budget_text(const cb_bake_job *job, const cb_bake_result *result, uint32_t clip,
                         const char *(*setting_name)(cb_setting), char *buf, size_t size);
/* Why a clip over its budget was written, " (written ...)", or "" when it fails the bake: over
 * the default budget (a goal, cb_clip_budget.goal), or allowed (allow_over_budget). */
void cb_bake_goal_words(const cb_clip_budget *budget, const char *(*setting_name)(cb_setting), bool allowed, char *buf,
                        size_t size);

/* The bone space of the file of `format` (a CB_FORMAT_* bit), the bake's one decision of it (bake_local.c): as
 * asked (bone_space_set); else local in a .pal of qpos rows, u16 or float, sampled: the glTF's own interpolation in
 * fewer rows; global for every other format (no place for the parents) and other settings. */
cb_bone_space cb_bake_settings_bone_space(const cb_bake_settings *s, unsigned format);
/* Why the file of `format`, baked with s, holds its bone space `got`, in words: "local rows (the default for a .pal
 * of qpos rows): ...", "global rows, not the default local: precision half (...)"; fallback_note: the palette's
 * (cb_palette.fallback_note: why its layout is not qpos), or NULL. */
void cb_bake_bone_space_why(const cb_bake_settings *s, unsigned format, cb_bone_space got, const char *fallback_note,
                            char *buf, size_t size);

#ifdef __cplusplus
}
#endif

#endif
