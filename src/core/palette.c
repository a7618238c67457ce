/* palette.c - baking clips into a bone-matrix palette: framing every clip, encoding each
 * joint matrix in the chosen layout and precision, and measuring the error that costs. */
#include "crowdbake/palette.h"

#include "crowdbake/budget.h"
#include "error_bound.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "global_timed.h" /* timed global rows */
#include "palette_bake.h"
#include "pool.h"
#include "timed_rows.h"
#include "internal/plumbing.h"



cb_bake_options cb_default_bake_options(void)
{
    cb_bake_options o;
    o.fps = 30;
    o.layout = CB_LAYOUT_QPOS;
    o.precision = CB_PRECISION_U16;
    o.max_texture_size = 16384;
    o.root_motion = CB_ROOT_MOTION_KEEP;
    o.limits = cb_default_limits();
    o.threads = 1;
    o.affine_fallback = false;
    o.error_goal = 0;
    o.fit = false;
    o.measure_all = false;
    o.bone_space = CB_BONE_SPACE_GLOBAL;
    o.timed_rows = CB_TIMED_ROWS_AUTO;
    o.texel_memory = (cb_texel_memory){NULL, NULL};
    return o;
}

void cb_clip_plan_release(cb_clip_plan *plan)
{
    free(plan->row_cells);
    plan->row_cells = NULL, plan->timed_rows = 0;
}

void cb_palette_free(cb_palette *p)
{
    if (!p) return;
    free(p->clips);
    free(p->bind_positions);
    free(p->position_offsets);
    free(p->row_travel);
    free(p->parents);
    free(p->bone_ranges);
    if (!p->texels_borrowed) free(p->texels);
    memset(p, 0, sizeof *p);
}

/* --fit: the clip's rows moved to split the linear blend's error between rows and mid-rows. */
static cb_status fit_clip(bake_state *st, worker *w, uint32_t c, float *rows, cb_error *err)
{
    cb_palette *p = st->p;
    const cb_clip_info *info = &st->infos[c];
    size_t row_floats = (size_t)p->bone_count * CANON(p->layout);
    float *mids = malloc((size_t)info->frames * row_floats * sizeof(float));
    if (!mids) return cb_fail(err, CB_ERR_INTERNAL, "out of memory fitting %s", st->model->source);
    if (!palette_mid_rows(st, w, c, rows, mids, err)) {
        cb_fit_rows(rows, mids, info->frames, p->bone_count, CANON(p->layout), info->loops, p->layout == CB_LAYOUT_QPOS);
        range_reset(&st->ranges[c]); /* the fitted values' range */
        for (size_t b = 0; b < (size_t)info->frames * p->bone_count; ++b) {
            if (p->layout == CB_LAYOUT_QPOS) range_grow_qpos(&st->ranges[c], rows + b * 8);
            else range_grow_affine(&st->ranges[c], rows + b * 12);
        }
    }
    free(mids);
    return err->status;
}

static double seconds_now(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Values encoding waits for: u16's need the ranges of every clip, half's positions each bone's
 * offset (the centre of its positions over every clip). */
static bool keeps_values(const cb_palette *p) { return p->precision != CB_PRECISION_FLOAT; }

/* Rows first_row + f0 .. + n of clip c, sampled into `rows`: encoded, or staged, at once. */
static void emit_rows(bake_state *st, uint32_t c, const float *rows, uint32_t f0, uint32_t n)
{
    cb_palette *p = st->p;
    uint32_t first = p->clips[c].first_row + f0;
    double start = seconds_now();
    if (!keeps_values(p))
        palette_encode_rows(p, rows, first, n);
    else if (p->layout == CB_LAYOUT_QPOS)
        palette_stage_qpos(p, rows, st->stash, first, n);
    else
        palette_stage_rows(p, rows, st->stash, first, n);
    st->encode_seconds[c] += seconds_now() - start;
}

/* Samples clip c and emits its rows: CB_SAMPLE_BATCH at a time from the worker's small buffer,
 * still in cache, or (--fit, which moves every row by its neighbours) the whole clip at once. */
static cb_status sample_clip(bake_state *st, worker *w, uint32_t c, cb_error *err)
{
    cb_palette *p = st->p;
    const cb_clip_info *info = &st->infos[c];
    cb_palette_clip *clip = &p->clips[c];
    extent bounds = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    range_reset(&st->ranges[c]);
    bool similar = p->layout == CB_LAYOUT_QPOS && cb_sampler_is_similarity(w->sampler), fit = clip->fitted;
    size_t row_floats = (size_t)p->bone_count * CANON(p->layout);
    uint32_t chunk = fit ? info->frames : CB_SAMPLE_BATCH, qv = CANON(p->layout);
    uint32_t room = fit && st->max_clip_frames > CB_SAMPLE_BATCH ? st->max_clip_frames : CB_SAMPLE_BATCH;
    if (w->rows_held < room) { /* a palette may mix sampled clips and fitted ones, which need the whole clip */
        free(w->rows);
        if (!(w->rows = malloc(room * row_floats * sizeof(float))))
            return w->rows_held = 0, cb_fail(err, CB_ERR_INTERNAL, "out of memory sampling %s", st->model->source);
        w->rows_held = room;
    }
    /* The clip's rows as its search's probe made (and fitted) them, or made (a probe's into the
     * block it keeps them in: no copy either way). */
    const float *taken = palette_take_rows(st, c, fit, &bounds);
    float *keep = taken ? NULL : palette_keep_rows(st, c, fit);
    for (uint32_t f0 = 0; f0 < info->frames; f0 += chunk) { /* a fitted clip's in one chunk */
        uint32_t n = info->frames - f0 < chunk ? info->frames - f0 : chunk;
        float *made_at = keep ? keep + f0 * row_floats : w->rows;
        const float *rows = taken ? taken + f0 * row_floats : made_at;
        /* A fitted probe's rows before the fit: a sampled probe's at the same rate, where one was. */
        bool ready = taken || (fit && palette_take_sampled_for_fit(st, c, made_at, &bounds));
        for (uint32_t f = f0; !ready && similar && f < f0 + n; f += CB_SAMPLE_BATCH) {
            uint32_t count = f0 + n - f < CB_SAMPLE_BATCH ? f0 + n - f : CB_SAMPLE_BATCH;
            palette_similarity_rows(st, w, c, f, count, made_at + (f - f0) * row_floats, &bounds);
        }
        for (uint32_t f = f0; !ready && !similar && f < f0 + n; ++f) {
            if ((f - f0) % CB_SAMPLE_BATCH == 0) { /* the next rows' poses, a batch at once where they are kept */
                uint32_t next[CB_SAMPLE_BATCH], k = 0;
                for (; k < CB_SAMPLE_BATCH && f + k < f0 + n; ++k) next[k] = f + k;
                palette_prefetch_poses(st, w, c, info, next, k);
            }
            if (palette_matrix_row(st, w, c, f, made_at + (f - f0) * row_floats, &bounds, err)) return err->status;
        }
        if (!taken && fit && fit_clip(st, w, c, made_at, err)) return err->status;
        for (uint32_t j = 0; f0 == 0 && j < p->bone_count; ++j) memcpy(w->first + j * 4, rows + j * qv, 4 * sizeof(float));
        if (p->layout == CB_LAYOUT_QPOS && info->loops && info->frames > 1 && f0 + n == info->frames) {
            /* The wrap from the last row to the first: a full turn over the loop ends on -q. */
            const float *last = rows + (n - 1) * row_floats;
            for (uint32_t j = 0; j < p->bone_count; ++j) {
                const float *qa = w->first + j * 4, *qb = last + (size_t)j * qv;
                if (qa[0] * qb[0] + qa[1] * qb[1] + qa[2] * qb[2] + qa[3] * qb[3] < 0) st->breaks[c]++;
            }
        }
        emit_rows(st, c, rows, f0, n);
    }
    if (keep) palette_kept_rows_done(st, c, &bounds);
    if (st->local) st->local->sampled[c] = st->local->sampled[c] && similar && !taken && !fit; /* local_rows_from_lanes' */
    bool empty = !(bounds.lo[0] <= bounds.hi[0]); /* no skinned vertex */
    for (int k = 0; k < 3; ++k) {
        clip->bounds_min[k] = empty ? 0 : (float)bounds.lo[k];
        clip->bounds_max[k] = empty ? 0 : (float)bounds.hi[k];
    }
    return CB_OK;
}

/* ---- running clips on several threads ---- */

typedef struct job {
    bake_state *st;
    void (*run)(bake_state *st, worker *w, uint32_t clip);
    bool samples;   /* run uses the worker's sampler and scratch */
    uint32_t count; /* jobs: one per clip, or per part of a clip */
    atomic_uint next; /* the next job not taken */
} job;

/* One thread's share: the next job not taken, until none is left. Jobs differ in cost (a
 * clip's blends take longer than its rows, clips differ in length): taken in turn, not by a
 * fixed stride, no thread waits with jobs left. Which thread runs a job does not change what
 * it writes (a worker's sampler only caches where its keys were). */
static void job_main(void *arg, uint32_t first, uint32_t stride)
{
    job *jb = arg;
    bake_state *st = jb->st;
    (void)stride;
    worker w = {0};
    cb_error *err0 = &st->errors[first < st->p->clip_count ? first : 0];
    bool closed = true;
    if (jb->samples) {
        w.sampler = st->lent ? st->lent : cb_sampler_create(st->model, st->skin, err0);
        /* Loops without a closing key wrap; those whose closing key is slightly off are closed.
         * (One-shots never sample past their last key: a clip planned twice, as a loop and as a
         * one-shot, keeps its loop's period.) */
        for (uint32_t c = 0; w.sampler && c < st->p->clip_count; ++c)
            if (st->infos[c].loops) closed = cb_sampler_set_loop(w.sampler, &st->infos[c]) && closed;
        w.mats = malloc((size_t)st->p->bone_count * 16 * sizeof(double));
        w.prev = malloc((size_t)st->p->bone_count * sizeof(cb_quat));
        w.first = malloc((size_t)st->p->bone_count * 4 * sizeof(float));
        if (st->local) w.local_lanes = malloc((size_t)st->p->bone_count * 8 * CB_SAMPLE_BATCH * sizeof(double));
    }
    if (jb->samples && (!w.sampler || !closed || !w.mats || !w.prev || !w.first || (st->local && !w.local_lanes))) {
        cb_fail(err0, CB_ERR_INTERNAL, "out of memory sampling %s", st->model->source);
    } else {
        for (uint32_t c = atomic_fetch_add(&jb->next, 1); c < jb->count; c = atomic_fetch_add(&jb->next, 1))
            jb->run(st, &w, c);
    }
    if (w.sampler != st->lent) cb_sampler_free(w.sampler);
    free(w.mats);
    free(w.prev);
    free(w.first);
    free(w.rows);
    palette_measure_scratch_free(w.measure);
    pose_batch_free(w.batch);
    free(w.local_lanes);
}

static uint32_t threads_used(const bake_state *st, uint32_t jobs)
{
    uint32_t threads = st->opt->threads ? st->opt->threads : 1;
    if (threads > jobs) threads = jobs ? jobs : 1;
    return threads > 64 ? 64 : threads;
}

/* Runs `run` for jobs 0 .. count - 1 (default: every clip) on the threads. Each job writes only
 * its own rows and slots, so the result depends neither on the thread count nor on timing. */
static void for_each_clip(bake_state *st, void (*run)(bake_state *, worker *, uint32_t), bool samples, uint32_t count)
{
    job jb = {st, run, samples, count ? count : st->p->clip_count, 0};
    cb_pool_dispatch(st->pool, threads_used(st, jb.count), job_main, &jb);
}



/* Samples a clip and encodes it as it goes: all of it, or for u16 and half what needs no range
 * or offset, keeping the rest for encode_staged_job. */
static void sample_clip_job(bake_state *st, worker *w, uint32_t c)
{
    if (!st->errors[c].status) sample_clip(st, w, c, &st->errors[c]);
    cb_model_release_clip(st->model, st->infos[c].animation); /* not read again until measured */
}

/* u16 and half, once the ranges and offsets of every clip are known: the values a clip staged. */
static void encode_staged_job(bake_state *st, worker *w, uint32_t c)
{
    (void)w;
    cb_palette *p = st->p;
    const cb_palette_clip *clip = &p->clips[c];
    if (p->layout == CB_LAYOUT_QPOS) {
        palette_finish_qpos(p, st->stash, clip->first_row, clip->frames);
        return;
    }
    float *row = malloc((size_t)p->bone_count * CANON(p->layout) * sizeof(float));
    if (!row) {
        cb_fail(&st->errors[c], CB_ERR_INTERNAL, "out of memory encoding %s", st->model->source);
        return;
    }
    for (uint32_t r = clip->first_row; r < clip->first_row + clip->frames; ++r) {
        palette_gather_row(p, st->stash, r, row); /* read before the encoder writes over them */
        palette_encode_rows(p, row, r, 1);
    }
    free(row);
}

/* ---- the bake ---- */

static void free_bake_state(bake_state *st)
{
    cb_pool_free(st->pool);
    free(st->stash), free(st->breaks), free(st->errors), free(st->clip_error), free(st->clip_blend_error), free(st->ranges);
    free(st->encode_seconds), free(st->pending);
}

/* The first error in clip order, so the message does not depend on the thread count. */
static cb_status first_clip_error(const bake_state *st, cb_error *err)
{
    for (uint32_t c = 0; c < 2 * st->p->clip_count; ++c) /* a clip's, then its baked rows' measurement's */
        if (st->errors[c].status) {
            *err = st->errors[c];
            return err->status;
        }
    return CB_OK;
}

cb_status cb_palette_bake(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                          uint32_t plan_count, cb_palette *p, cb_error *err)
{
    return palette_bake_with_facts(sampler, opt, plan, plan_count, NULL, NULL, p, err);
}

/* Whether the bake lays out its plan's timed clips (global_timed.c) once baked uniform at their cell
 * rate: global rows of a format that holds a map (local rows lay out their own, local_rows.c). */
static bool lays_out_timed(const cb_bake_options *opt, const cb_clip_plan *plan, uint32_t plan_count)
{
    return opt->bone_space == CB_BONE_SPACE_GLOBAL && opt->timed_rows != CB_TIMED_ROWS_OFF && timed_any(plan, plan_count);
}

uint32_t palette_error_stride(uint32_t rows, uint32_t vertices, bool measure_all)
{
    uint64_t work = (uint64_t)rows * vertices;
    bool subset = rows > CB_ERROR_ROWS && work > CB_ERROR_BUDGET && !measure_all;
    return subset ? (uint32_t)((work + CB_ERROR_BUDGET - 1) / CB_ERROR_BUDGET) : 1;
}

/* The rows the palette will hold: a timed clip's (baked here at its cell rate) its rows on its cells and its map's. */
static uint32_t shipped_rows(const bake_state *st)
{
    const cb_palette *p = st->p;
    uint32_t rows = p->rows;
    for (uint32_t c = 0; c < p->clip_count; ++c)
        if (palette_clip_timed(st, c)) {
            const cb_palette_clip *k = &p->clips[c];
            uint32_t cells = k->frames - (k->loops ? 0 : 1);
            rows = rows - k->frames + st->plan[c].timed_rows + cb_timed_map_rows(cells, p->row_texels);
        }
    return rows;
}

static cb_status bake_once(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                           uint32_t plan_count, const palette_skin_facts *facts, const palette_probe *probe,
                           const local_sampling *local, cb_palette *p, cb_error *err)
{
    const cb_model *m = cb_sampler_model(sampler);
    int32_t skin_index = cb_sampler_skin(sampler);
    const cb_skin *skin = &m->skins[skin_index];
    memset(p, 0, sizeof *p);
    p->layout = opt->layout;
    p->precision = opt->precision;
    p->fps = opt->fps;
    p->bone_count = skin->joint_count;
    p->texels_per_bone = cb_layout_texels_per_bone(opt->layout);
    p->row_texels = p->bone_count * p->texels_per_bone;
    if (m->animation_count == 0 || (plan && plan_count == 0))
        return cb_fail(err, CB_ERR_INPUT, "%s: has no animations to bake (export the clips with the model)", m->source);
    double t0 = seconds_now();
    bake_state st = {0};
    st.p = p, st.model = m, st.skin = skin_index, st.opt = opt, st.plan = lays_out_timed(opt, plan, plan_count) ? plan : NULL;
    st.local = local;
    cb_clip_info *infos = NULL;
    st.facts = facts, st.radius = facts->reach, st.groups = &facts->groups;
    if (probe && plan && plan_count == 1 && opt->threads <= 1) /* one clip's, one thread's */
        st.poses = probe->poses, st.analysis = probe->analysis, st.lent = sampler, /* no sampler made per pass */
        st.batch = probe->batch;
    if (probe) st.clip_poses = probe->clip_poses, st.memo = probe->memo;
    if (palette_frame_clips(&st, sampler, plan, plan_count, &infos, err) || palette_plan_texture(p, opt->max_texture_size, m->source, err))
        goto fail;
    p->fitted = p->clip_count > 0;
    for (uint32_t c = 0; c < p->clip_count; ++c) p->fitted = p->fitted && p->clips[c].fitted;
    st.infos = infos;
    /* Threads for every pass (at most one per job: a clip's blends and rows may be two), started
     * here so that they start while the buffers are set up. */
    st.pool = cb_pool_create(threads_used(&st, 2 * p->clip_count));
    p->texel_bytes = (size_t)p->width * p->height * cb_precision_texel_bytes(p->precision);
    if (p->texel_bytes > opt->limits.max_palette_bytes) {
        cb_fail_setting(err, CB_ERR_INPUT, CB_SETTING_MAX_PALETTE_BYTES, "%s: the palette would be %zu bytes (%ux%u "
                        "texels), over the limit of %llu; lower the fps, bake fewer clips, use a smaller encoding or raise the limit",
                m->source, p->texel_bytes, p->width, p->height, (unsigned long long)opt->limits.max_palette_bytes);
        goto fail;
    }
    p->positions_relative = p->precision == CB_PRECISION_HALF;
    p->texels = opt->texel_memory.acquire ? opt->texel_memory.acquire(opt->texel_memory.ctx, p) : NULL;
    p->texels_borrowed = p->texels != NULL;
    if (!p->texels) p->texels = cb_alloc_large(p->texel_bytes);
    p->bind_positions = calloc((size_t)p->bone_count * 3, sizeof(float));
    p->position_offsets = calloc((size_t)p->bone_count * 3, sizeof(float));
    if (keeps_values(p)) st.stash = cb_alloc_large((size_t)p->rows * p->bone_count * palette_stash_bytes(p));
    for (uint32_t c = 0; c < p->clip_count; ++c)
        if (p->clips[c].frames > st.max_clip_frames) st.max_clip_frames = p->clips[c].frames;
    st.breaks = calloc(p->clip_count, sizeof *st.breaks);
    st.errors = calloc(2 * (size_t)p->clip_count, sizeof *st.errors);
    st.clip_error = calloc(p->clip_count, sizeof *st.clip_error);
    st.clip_blend_error = calloc(p->clip_count, sizeof *st.clip_blend_error);
    st.ranges = calloc(p->clip_count, sizeof *st.ranges);
    st.encode_seconds = calloc(p->clip_count, sizeof *st.encode_seconds);
    if (!p->texels || !p->bind_positions || !p->position_offsets || (keeps_values(p) && !st.stash) ||
        !st.breaks || !st.errors || !st.clip_error || !st.clip_blend_error || !st.ranges || !st.encode_seconds) {
        cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory for a %ux%u palette", m->source, p->width, p->height);
        goto fail;
    }
    palette_zero_padding(p);
    memcpy(p->bind_positions, facts->bind_positions, (size_t)p->bone_count * 3 * sizeof(float));
    for_each_clip(&st, sample_clip_job, true, 0);
    if (first_clip_error(&st, err)) goto fail;
    for (uint32_t c = 0; c < p->clip_count; ++c) p->quat_hemisphere_breaks += st.breaks[c];
    palette_merge_ranges(p, st.ranges);
    if (p->positions_relative && !palette_position_offsets(p, st.stash)) {
        cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory for a %ux%u palette", m->source, p->width, p->height);
        goto fail;
    }
    double t1 = seconds_now();
    if (keeps_values(p)) for_each_clip(&st, encode_staged_job, false, 0);
    free(st.stash), st.stash = NULL; /* encoded: its memory goes before measuring reads the keys again */
    if (first_clip_error(&st, err)) goto fail;
    double t2 = seconds_now();
    /* Clips encoded as they were sampled: their encoding time, spread over the threads, moves
     * from the sampling phase to the encoding phase. */
    double encoded_while_sampling = 0;
    for (uint32_t c = 0; c < p->clip_count; ++c) encoded_while_sampling += st.encode_seconds[c];
    encoded_while_sampling /= threads_used(&st, p->clip_count);
    p->model_height = facts->height;
    /* what the file will hold: a timed clip's rows on its cells and its map */
    st.error_stride = palette_error_stride(shipped_rows(&st), cb_model_skin_vertex_count(m, skin_index),
                                           st.opt->measure_all);
    p->error_rows_measured = 0;
    if (facts->skinned) {
        for_each_clip(&st, palette_measure_job, true, palette_measure_jobs(&st));
        if (first_clip_error(&st, err)) goto fail;
        if (palette_measure_rest(&st)) for_each_clip(&st, palette_measure_rest_job, true, 0);
        if (first_clip_error(&st, err)) goto fail;
        for (uint32_t c = 0; c < p->clip_count; ++c) {
            if (palette_clip_timed(&st, c)) continue; /* measured once laid out */
            p->max_error = fmax(p->max_error, st.clip_error[c]);
            p->clips[c].visible_error = fmax(st.clip_error[c], st.clip_blend_error[c]);
            p->visible_error = fmax(p->visible_error, p->clips[c].visible_error);
            p->error_rows_measured += (p->clips[c].frames + st.error_stride - 1) / st.error_stride +
                                      ((p->clips[c].frames - 1) % st.error_stride != 0);
        }
    }
    palette_settle_rows(&st, p->visible_error); /* a probe's rows, kept by how they met its goal */
    double t3 = seconds_now();
    p->seconds_sample = t1 - t0 - encoded_while_sampling;
    p->seconds_encode = t2 - t1 + encoded_while_sampling;
    p->seconds_measure = t3 - t2;
    free_bake_state(&st);
    free(infos);
    return CB_OK;
fail:
    free_bake_state(&st);
    free(infos);
    cb_palette_free(p);
    return err->status;
}

static cb_status bake_with_fallback(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                                    uint32_t plan_count, const palette_skin_facts *facts, const palette_probe *probe,
                                    const local_sampling *local, cb_palette *p, cb_error *err)
{
    cb_error first = {0};
    cb_status rc = bake_once(sampler, opt, plan, plan_count, facts, probe, local, p, &first);
    if (rc == CB_ERR_LAYOUT && opt->affine_fallback && opt->layout == CB_LAYOUT_QPOS) {
        cb_bake_options affine = *opt; /* a rig qpos cannot hold: the next smallest layout */
        affine.layout = CB_LAYOUT_AFFINE;
        rc = bake_once(sampler, &affine, plan, plan_count, facts, probe, local, p, err);
        if (!rc) snprintf(p->fallback_note, sizeof p->fallback_note, "%.460s; baked with affine instead", first.message);
        return rc;
    }
    if (rc) *err = err->status ? *err : first;
    return rc;
}

cb_status palette_bake_with_facts(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                                  uint32_t plan_count, const palette_skin_facts *facts, const palette_probe *probe,
                                  cb_palette *p, cb_error *err)
{
    if (opt->bone_space == CB_BONE_SPACE_LOCAL) return palette_bake_local(sampler, opt, plan, plan_count, facts, probe, p, err);
    palette_skin_facts own = {0};
    cb_status rc = facts ? CB_OK : palette_skin_facts_build(sampler, &own, err);
    if (!facts) facts = &own;
    if (!rc) rc = bake_with_fallback(sampler, opt, plan, plan_count, facts, probe, NULL, p, err);
    /* Timed clips (global_timed.c) were baked uniform at their cell rate: their rows on their cells kept */
    if (!rc && lays_out_timed(opt, plan, plan_count) && (rc = palette_time_global_rows(sampler, opt, plan, plan_count, facts, probe, p, err)))
        cb_palette_free(p);
    palette_skin_facts_free(&own);
    return rc;
}

cb_status palette_bake_sampled_local(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                                     uint32_t plan_count, const palette_skin_facts *facts, const palette_probe *probe,
                                     const local_sampling *local, cb_palette *p, cb_error *err)
{
    return bake_with_fallback(sampler, opt, plan, plan_count, facts, probe, local, p, err);
}
