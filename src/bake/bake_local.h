/* bake_local.h - the bake job's bone space (local rows, .pal version 6, src/core/local_rows.c):
 * which outputs get local rows, which settings they need, and the notes that say so. */
#ifndef CB_BAKE_LOCAL_H
#define CB_BAKE_LOCAL_H

#include "crowdbake/bake.h"

/* CB_ERR_SETTINGS where the settings ask for local rows (bone_space_set) that cannot be written: no .pal among the
 * outputs (`formats`, CB_FORMAT_* bits), a layout other than qpos, or precision half. */
cb_status bake_check_bone_space(const cb_bake_job *job, unsigned formats, cb_error *err);
/* The notes of a bake whose .pal was to hold local rows (p: the .pal's palette, or the first format's):
 * why it does not (the rig's palette is not qpos), or which other outputs stay global. */
void bake_local_notes(const cb_bake_job *job, const cb_palette *p, cb_warnings *w);

#endif
