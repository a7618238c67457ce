/* enum_names.c - every enum's words, in one place: the names files, logs and manifests write
 * (layouts, precisions, root motion, where a setting came from) and the parsers of the words a
 * command line or catalog gives. The core owns them, so the formats and the bake use them
 * without reaching up a layer. */
#include "crowdbake/clip_settings.h"
#include "internal/plumbing.h"

#include <string.h>

static const char *const layout_names[] = {"mat4", "affine", "qpos"};
static const char *const precision_names[] = {"float", "half", "u16"};
static const char *const root_motion_names[] = {"keep", "in-place", "loops-in-place"}; /* cb_root_motion's order */
static const char *const bone_space_names[] = {"global", "local"}; /* cb_bone_space's order */
static const char *const timed_rows_names[] = {"auto", "on", "off"}; /* cb_timed_rows' order */

/* The index of `text` among `count` names, or -1. */
static int name_index(const char *text, const char *const *names, int count)
{
    for (int i = 0; i < count; ++i)
        if (strcmp(text, names[i]) == 0) return i;
    return -1;
}

const char *cb_layout_name(cb_layout l) { return (unsigned)l < 3 ? layout_names[l] : "?"; }
const char *cb_precision_name(cb_precision p) { return (unsigned)p < 3 ? precision_names[p] : "?"; }
const char *cb_root_motion_name(cb_root_motion r) { return (unsigned)r < 3 ? root_motion_names[r] : "keep"; }

bool cb_layout_parse(const char *text, cb_layout *out)
{
    int i = name_index(text, layout_names, 3);
    return i >= 0 && (*out = (cb_layout)i, true);
}

bool cb_precision_parse(const char *text, cb_precision *out)
{
    int i = name_index(text, precision_names, 3);
    return i >= 0 && (*out = (cb_precision)i, true);
}

const char *cb_timed_rows_name(cb_timed_rows t) { return (unsigned)t < 3 ? timed_rows_names[t] : "?"; }

bool cb_timed_rows_parse(const char *text, cb_timed_rows *out)
{
    int i = name_index(text, timed_rows_names, 3);
    return i >= 0 && (*out = (cb_timed_rows)i, true);
}

const char *cb_bone_space_name(cb_bone_space b) { return (unsigned)b < 2 ? bone_space_names[b] : "?"; }

bool cb_holds_local_rows(cb_layout layout, cb_precision precision)
{
    return layout == CB_LAYOUT_QPOS && precision != CB_PRECISION_HALF;
}

bool cb_bone_space_parse(const char *text, cb_bone_space *out)
{
    int i = name_index(text, bone_space_names, 2);
    return i >= 0 && (*out = (cb_bone_space)i, true);
}

bool cb_root_motion_parse(const char *text, cb_root_motion *out)
{
    int i = name_index(text, root_motion_names, 3);
    return i >= 0 && (*out = (cb_root_motion)i, true);
}

const char *cb_setting_from_name(cb_setting_from from)
{
    switch (from) {
    case CB_FROM_CATALOG: return "catalog [bake]";
    case CB_FROM_ANIMAL: return "catalog animal";
    case CB_FROM_COMMAND_LINE: return "command line";
    case CB_FROM_CLIP: return "catalog clip";
    case CB_FROM_RIG: return "rig: no skinned mesh";
    case CB_FROM_TRAVEL: return "a loop travels";
    case CB_FROM_TRANSIENT: return "a fast transient: the default max_error is out of reach at the default max_fps";
    default: return "default";
    }
}
