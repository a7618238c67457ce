/* global_timed.c - see global_timed.h: timed rows for global rows.
 *
 * A global row is a local row whose bone has no parent: local_clip_timed on a skeleton of roots
 * (local_skeleton_roots) blends two of them bone by bone exactly as the runtime blends global qpos
 * rows (the quaternion the shorter way, lerped and normalised; the pivot and scale lerped) and
 * composes nothing, so its measurement - every vertex group that can raise the worst, at the
 * quarter points of every row interval, in double precision - is that of the global rows the bake
 * will keep. The bake then measures the palette it wrote the same way (local_palette_errors on
 * roots: its u16 rows as the runtime decodes them, through the map), which is what the clip's line
 * and the budget read.
 *
 * Why only when asked (timed rows on), and then where they cost fewer bytes: rows on the keys cost
 * Cow and Husky fewer rows than the default's uniform rates (bench/RESULTS.txt), but finding them
 * measures each key interval at up to four splits, which the default bake's time (issue 43 item 2)
 * has no room for; and a clip whose uniform rate is its key rate (an idle) gains nothing from a
 * map, so on weighs them as auto weighs local rows'. */
#include "global_timed.h"

#include <math.h>
#include <stdlib.h>

#include "local_rate.h"
#include "timed_rows.h"

/* The analysis a timed search frames the clip from (local_rate_search.c's and rate_search.c's
 * lowest rate: the search kept one there). */
#define ANALYSIS_FPS 2.0

bool global_timed_asked(const cb_bake_options *o, const cb_clip_plan *plan)
{
    return o->timed_rows == CB_TIMED_ROWS_ON && o->bone_space == CB_BONE_SPACE_GLOBAL && o->layout == CB_LAYOUT_QPOS &&
           !o->fit && !plan->step;
}

cb_status global_clip_timed(cb_sampler *s, const cb_bake_options *o, cb_clip_plan *plan, const palette_skin_facts *facts,
                            pose_cache *cache, double max_error, cb_rate_choice *choice, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    cb_clip_info info;
    if (!(cache && palette_take_kept_analysis(cache, s, plan->animation, plan->loop, ANALYSIS_FPS, &o->limits, &info)) &&
        cb_clip_analyze(s, plan->animation, ANALYSIS_FPS, plan->loop, &o->limits, &info, err))
        return err->status;
    uint32_t bones = m->skins[cb_sampler_skin(s)].joint_count;
    choice->uniform_fps = plan->fps;
    choice->uniform_rows = cb_clip_step_count(info.duration, plan->fps) + (info.loops ? 0 : 1);
    local_skeleton roots;
    if (!local_skeleton_roots(bones, &roots))
        return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory choosing clip %d's timed rows", m->source, plan->animation);
    local_timed t; /* given up as soon as they cannot come to fewer rows than the uniform rate's */
    cb_status rc = local_clip_timed(s, facts, &roots, &info, o->root_motion, cache, max_error,
                                    bones * cb_layout_texels_per_bone(CB_LAYOUT_QPOS), choice->uniform_rows, &t, err);
    local_skeleton_free(&roots);
    if (rc) return rc;
    if (t.too_many) { /* stated as weighed: at least that many */
        choice->timed_weighed = true, choice->timed_rows = t.rows, choice->timed_map_rows = t.map_rows;
        return CB_OK;
    }
    /* A half map holds row numbers exactly only below 2049 (docs/pal-format.md). */
    if (!t.possible || t.not_qpos || (o->precision == CB_PRECISION_HALF && t.rows > 2048)) return free(t.row_cells), CB_OK;
    choice->timed_weighed = true;
    choice->timed_rows = t.rows, choice->timed_map_rows = t.map_rows, choice->timed_cells = t.cells;
    choice->timed_cell_rate = t.cell_rate;
    if (t.rows + t.map_rows >= choice->uniform_rows) return free(t.row_cells), CB_OK; /* no fewer bytes */
    cb_clip_plan_release(plan);
    plan->fps = t.cell_rate, plan->fit = false, plan->timed_rows = t.rows, plan->row_cells = t.row_cells;
    choice->met = true, choice->fitted = false, choice->error = t.error, choice->error_mm = cb_mm_per_m(t.error, facts->height);
    choice->fps_needed = 0;
    return CB_OK;
}

cb_status palette_time_global_rows(cb_sampler *s, const cb_bake_options *o, const cb_clip_plan *plan, uint32_t count,
                                   const palette_skin_facts *facts, const palette_probe *probe, cb_palette *p, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    if (timed_keep_rows(p, plan, o->max_texture_size, m->source, err)) return err->status;
    timed_fill_maps(p, plan);
    if (!facts->skinned) return CB_OK; /* nothing skinned: nothing measured */
    /* The timed clips (which the uniform bake left unmeasured) measured as their rows were chosen
     * (on a skeleton of roots: every row, and the quarter points between every two, through the map),
     * from the poses the search sampled, on the bake's threads. */
    for (uint32_t c = 0; c < p->clip_count; ++c)
        if (p->clips[c].timed) p->error_rows_measured += p->clips[c].frames + p->clips[c].map_rows; /* as the file counts */
    if (p->layout == CB_LAYOUT_QPOS) return palette_measure_composed(s, plan, facts, probe, o->threads, true, 1, p, err);
    for (uint32_t c = 0; c < p->clip_count; ++c) { /* a rig qpos could not hold after all (baked affine): as `verify` */
        cb_palette_clip *clip = &p->clips[c];
        cb_clip_error e;
        if (!clip->timed) continue;
        if (cb_verify_clip(s, p, p->texels, c, c < count ? plan[c].animation : (int32_t)c, 0, &e, err)) return err->status;
        clip->visible_error = fmax(e.quant_max, e.interp_max);
        p->max_error = fmax(p->max_error, e.quant_max);
        p->visible_error = fmax(p->visible_error, clip->visible_error);
    }
    return CB_OK;
}
