/* bake_local.h - the bake job's bone space (local rows, .pal version 6, src/core/local_rows.c):
 * which outputs get local rows, which settings they need, and the notes that say so. */
#ifndef CB_BAKE_LOCAL_H
#define CB_BAKE_LOCAL_H

#include "crowdbake/bake.h"

/* The bone space of the bake for `format`: the settings' for a .pal, global for every other format
 * (EXR, KTX2 and Babylon have no place for the parents). */
cb_bone_space bake_bone_space(const cb_bake_job *job, unsigned format);
/* CB_ERR_SETTINGS where the settings ask for local rows that cannot be written: no .pal among the
 * outputs (`formats`, CB_FORMAT_* bits), a layout other than qpos, or precision half. */
cb_status bake_check_bone_space(const cb_bake_job *job, unsigned formats, cb_error *err);
/* The notes of a bake asked for local rows (p: the .pal's palette, or the first format's): that
 * its .pal holds them and why, the rows sampled and the rates' source, what else stays global. */
void bake_local_notes(const cb_bake_job *job, const cb_palette *p, cb_warnings *w);

#endif
