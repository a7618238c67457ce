/* clip.c - clip framing (how many rows, at which times), loop detection and root motion. */
#include "cb_math.h"
#include "crowdbake/core.h"
#include "lanes.h"
#include "sampler.h"
#include "internal/plumbing.h"
#include "loop_decide.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Poses whose joint matrices differ by less than this (rotation terms, and translation
 * terms relative to the skeleton's size) are the same pose: a clip whose end pose equals
 * its start pose loops. */
#define CB_LOOP_TOLERANCE 1e-3

uint32_t cb_clip_step_count(double duration, double fps)
{
    double n = floor(duration * fps + 0.5);
    return n < 1 ? 1u : (uint32_t)n;
}

double cb_clip_frame_time(const cb_clip_info *clip, uint32_t frame)
{
    if (clip->duration <= 0) return clip->t0;
    return clip->t0 + (double)frame * clip->duration / clip->steps;
}

static cb_vec3 root_position(cb_sampler *s, const cb_model *m, int32_t skin, uint32_t root, int32_t anim, double t)
{
    const double *g = cb_sample_globals(s, anim, t) + (size_t)m->skins[skin].joints[root] * 16;
    return (cb_vec3){g[12], g[13], g[14]};
}

/* The root joint's position in the globals the sampler holds (its last sample's). */
static cb_vec3 root_in_globals(const cb_sampler *s, const cb_model *m, int32_t skin, uint32_t root)
{
    const double *g = s->globals + (size_t)m->skins[skin].joints[root] * 16;
    return (cb_vec3){g[12], g[13], g[14]};
}

/* Size of the skeleton in the rest pose: the diagonal of its joints' bounding box. The rest pose
 * is the sampler's for good: worked out once (every clip analyzed asks). */
static double skeleton_extent(cb_sampler *s, const cb_model *m, int32_t skin)
{
    if (s->rest_extent > 0) return s->rest_extent;
    const double *g = cb_sample_globals(s, -1, 0);
    const cb_skin *sk = &m->skins[skin];
    cb_vec3 lo = {INFINITY, INFINITY, INFINITY}, hi = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t j = 0; j < sk->joint_count; ++j) {
        const double *p = g + (size_t)sk->joints[j] * 16 + 12;
        lo.x = fmin(lo.x, p[0]), lo.y = fmin(lo.y, p[1]), lo.z = fmin(lo.z, p[2]);
        hi.x = fmax(hi.x, p[0]), hi.y = fmax(hi.y, p[1]), hi.z = fmax(hi.z, p[2]);
    }
    double e = cb_vec3_length(cb_vec3_sub(hi, lo));
    return s->rest_extent = e > 1e-9 ? e : 1.0;
}

/* How far apart two poses are: the largest difference of any joint matrix's rotation terms,
 * or of its translation (less `travel`) relative to the skeleton's size. */
static double pose_distance(const double *a, const double *b, uint32_t joints, cb_vec3 travel, double extent)
{
    double worst = 0;
    for (uint32_t j = 0; j < joints; ++j) {
        const double *ma = a + (size_t)j * 16, *mb = b + (size_t)j * 16;
        for (int k = 0; k < 12; ++k) worst = fmax(worst, fabs(ma[k] - mb[k]));
        double d[3] = {mb[12] - travel.x - ma[12], mb[13] - travel.y - ma[13], mb[14] - travel.z - ma[14]};
        for (int k = 0; k < 3; ++k) worst = fmax(worst, fabs(d[k]) / extent);
    }
    return worst;
}

double cb_animation_key_interval(const cb_animation *anim)
{
    double min_dt = INFINITY;
    const float *scanned = NULL; /* channels sharing one times array (as exporters write them) scan it once */
    uint32_t scanned_keys = 0;
    for (uint32_t c = 0; c < anim->channel_count; ++c) {
        const cb_channel *ch = &anim->channels[c];
        if (ch->times == scanned && ch->key_count == scanned_keys) continue;
        scanned = ch->times, scanned_keys = ch->key_count;
        for (uint32_t k = 1; k < ch->key_count; ++k) {
            double dt = (double)ch->times[k] - ch->times[k - 1];
            if (dt > 1e-4 && dt < min_dt) min_dt = dt;
        }
    }
    return isfinite(min_dt) ? min_dt : 0;
}

/* The biggest step between the clip's poses one key interval apart, over its whole span (its
 * travel per step taken off); a and b: room for one pose each. */
static double largest_key_step(cb_sampler *s, const cb_clip_info *clip, double *a, double *b, cb_vec3 travel,
                               double extent)
{
    const cb_model *m = cb_sampler_model(s);
    uint32_t joints = m->skins[cb_sampler_skin(s)].joint_count;
    double D = clip->t1 - clip->t0, largest = 0;
    uint32_t steps = (uint32_t)fmax(1, floor(D / clip->key_interval + 0.5));
    cb_vec3 step_travel = {travel.x / steps, 0, travel.z / steps};
    cb_sample_joint_matrices(s, clip->animation, clip->t0, a);
    for (uint32_t i = 1; i <= steps; ++i) {
        cb_sample_joint_matrices(s, clip->animation, clip->t0 + D * i / steps, b);
        largest = fmax(largest, pose_distance(a, b, joints, step_travel, extent));
        double *swap = a;
        a = b, b = swap;
    }
    return largest;
}

/* Loop or one-shot, from the poses. Equal first and last poses close a loop over the key span.
 * Many exporters (FBX2glTF, anything that bakes keys on [0, D)) leave out the closing key: the
 * first pose comes round one key step after the last key. Such a clip is a loop over D plus one
 * key interval when the wrap from its last pose to its first is no bigger than the key steps on
 * either side of it (the first and the last), so the wrap is as smooth as its neighbours; a clip
 * that comes to rest, or ends in another pose, has a jump there. Two steps at least: a two-key
 * clip's only step is its jump.
 * A wrap that small is also what a closing key slightly off gives: its last pose a small part
 * of a step from its first. A missing closing key makes the wrap about one key step, so a wrap
 * under CB_LOOP_CORRECTABLE of the clip's largest key step is the closing key, corrected
 * (loop_close.c), and the loop lasts the key span. */
static void judge_loop(cb_sampler *s, cb_clip_info *out, double *pose)
{
    const cb_model *m = cb_sampler_model(s);
    int32_t skin = cb_sampler_skin(s);
    uint32_t joints = m->skins[skin].joint_count;
    double extent = skeleton_extent(s, m, skin), D = out->t1 - out->t0, h = out->key_interval;
    size_t n = (size_t)joints * 16;
    /* Horizontal root travel does not break a loop. */
    cb_vec3 travel = {out->root_displacement[0], 0, out->root_displacement[2]};
    out->wrap_jump = pose_distance(pose, pose + 3 * n, joints, travel, extent);
    out->loop_reason = out->wrap_jump <= CB_LOOP_TOLERANCE ? CB_LOOP_CLOSED : CB_LOOP_ENDS_ELSEWHERE;
    if (out->loop_reason == CB_LOOP_ENDS_ELSEWHERE && h > 0 && D >= 2 * h - 1e-6) {
        double f = h / D;
        cb_vec3 step_travel = {travel.x * f, 0, travel.z * f};
        cb_sample_joint_matrices(s, out->animation, out->t0 + h, pose + n);
        cb_sample_joint_matrices(s, out->animation, out->t1 - h, pose + 2 * n);
        out->largest_step = fmax(pose_distance(pose, pose + n, joints, step_travel, extent),
                                 pose_distance(pose + 2 * n, pose + 3 * n, joints, step_travel, extent));
        if (out->wrap_jump <= out->largest_step) {
            out->loop_reason = CB_LOOP_OPEN;
            out->largest_key_step = largest_key_step(s, out, pose, pose + n, travel, extent);
            if (out->wrap_jump <= CB_LOOP_CORRECTABLE * out->largest_key_step) out->loop_reason = CB_LOOP_CLOSED_CORRECTED;
        }
    }
}

cb_status cb_clip_analyze(cb_sampler *s, int32_t animation, double fps, int loop_override, const cb_limits *limits,
                          cb_clip_info *out, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    cb_limits defaults = cb_default_limits();
    if (!limits) limits = &defaults;
    if (animation < 0 || animation >= (int32_t)m->animation_count)
        return cb_fail(err, CB_ERR_INPUT, "%s: has no clip %d", m->source, animation);
    if (!(fps > 0) || !isfinite(fps) || fps > CB_FPS_LIMIT)
        return cb_fail(err, CB_ERR_SETTINGS, "fps must be a number between 0 and %g, got %g", CB_FPS_LIMIT, fps);
    const cb_animation *anim = &m->animations[animation];
    int32_t skin = cb_sampler_skin(s);
    cb_sampler_open_clip(s, animation); /* judged as the source has it, not as a loop closed before */
    memset(out, 0, sizeof *out);
    out->animation = animation;
    out->t0 = anim->t0;
    out->t1 = anim->t1;
    out->key_interval = cb_animation_key_interval(anim);
    double span = anim->t1 - anim->t0;

    uint32_t root = cb_skin_root_joint(m, skin);
    /* The poses judge_loop compares, at t0, t0 + h, t1 - h and t1; the root's position at the
     * ends read from the globals those ends were sampled through (the same bits as sampling
     * every node again). */
    size_t n = (size_t)m->skins[skin].joint_count * 16;
    double *pose = span > 0 ? malloc(4 * n * sizeof(double)) : NULL;
    if (span > 0 && !pose) return cb_fail(err, CB_ERR_INTERNAL, "out of memory analysing clip '%s'", anim->name);
    cb_vec3 p0, p1;
    if (pose) {
        cb_sample_joint_matrices(s, animation, out->t0, pose);
        p0 = root_in_globals(s, m, skin, root);
        cb_sample_joint_matrices(s, animation, out->t1, pose + 3 * n);
        p1 = root_in_globals(s, m, skin, root);
    } else {
        p0 = root_position(s, m, skin, root, animation, out->t0);
        p1 = root_position(s, m, skin, root, animation, out->t1);
    }
    cb_vec3 d = cb_vec3_sub(p1, p0);
    out->root_displacement[0] = d.x, out->root_displacement[1] = d.y, out->root_displacement[2] = d.z;
    if (span > 0) {
        for (int k = 0; k < 3; ++k) out->root_velocity[k] = out->root_displacement[k] / span;
        out->ground_speed = hypot(out->root_velocity[0], out->root_velocity[2]);
    }

    out->loop_reason = CB_LOOP_CLOSED; /* a clip of one instant */
    if (span > 0) judge_loop(s, out, pose);
    free(pose);
    bool closes = out->loop_reason == CB_LOOP_CLOSED || out->loop_reason == CB_LOOP_CLOSED_CORRECTED;
    if (loop_override >= 0) {
        out->loops = loop_override != 0, out->loop_set = true;
        if (out->loops != (closes || out->loop_reason == CB_LOOP_OPEN)) out->loop_reason = CB_LOOP_SET;
    } else if (span > 0) {
        cb_loop_decide(s, fps, limits, out);
    } else {
        out->loops = true;
    }
    /* A loop whose last key is not its closing key wraps over one more key interval. */
    bool open = out->loops && !closes && span > 0;
    out->duration = span + (open ? out->key_interval : 0);
    if (!cb_sampler_set_loop(s, out))
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory closing the loop of clip '%s'", anim->name);
    if (out->loops && out->loop_reason == CB_LOOP_CLOSED_CORRECTED && cb_loop_correction_measure(s, out))
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory measuring the loop of clip '%s'", anim->name);
    return cb_clip_frame_at(m, fps, limits, out, err);
}

cb_status cb_clip_frame_at(const cb_model *model, double fps, const cb_limits *limits, cb_clip_info *clip,
                           cb_error *err)
{
    cb_limits defaults = cb_default_limits();
    if (!limits) limits = &defaults;
    if (!(fps > 0) || !isfinite(fps) || fps > CB_FPS_LIMIT)
        return cb_fail(err, CB_ERR_SETTINGS, "fps must be a number between 0 and %g, got %g", CB_FPS_LIMIT, fps);
    if (clip->duration * fps > (double)limits->max_frames)
        return cb_fail_setting(err, CB_ERR_INPUT, CB_SETTING_MAX_FRAMES, "%s: clip '%s' lasts %gs: %.0f frames at %g fps is over the limit of %u frames",
                       model->source, model->animations[clip->animation].name, clip->duration, clip->duration * fps,
                       fps, limits->max_frames);
    uint32_t steps = cb_clip_step_count(clip->duration, fps);
    clip->steps = steps;
    clip->effective_fps = clip->duration > 0 ? steps / clip->duration : fps;
    clip->frames = clip->loops ? steps : steps + 1;
    return CB_OK;
}

double cb_root_travel_time(double t, double span, double duration, bool loops)
{
    if (!loops || t <= span || !(duration > span)) return t;
    return span * (duration - t) / (duration - span);
}

/* The root's average horizontal travel from the clip's start to time t, which in-place bakes
 * take off every joint. */
static void root_travel(const cb_clip_info *clip, double t, double *dx, double *dz)
{
    double tau = cb_root_travel_time(t - clip->t0, clip->t1 - clip->t0, clip->duration, clip->loops);
    *dx = clip->root_velocity[0] * tau;
    *dz = clip->root_velocity[2] * tau;
}

bool cb_root_motion_in_place(cb_root_motion root_motion, const cb_clip_info *clip)
{
    return root_motion == CB_ROOT_MOTION_IN_PLACE || (root_motion == CB_ROOT_MOTION_LOOPS_IN_PLACE && clip->loops);
}

void cb_clip_frame_matrices(cb_sampler *s, const cb_clip_info *clip, uint32_t frame, cb_root_motion root_motion,
                            double *out)
{
    const cb_model *m = cb_sampler_model(s);
    int32_t skin = cb_sampler_skin(s);
    double t = cb_clip_frame_time(clip, frame);
    cb_sample_joint_matrices(s, clip->animation, t, out);
    if (!cb_root_motion_in_place(root_motion, clip)) return;
    double dx, dz;
    root_travel(clip, t, &dx, &dz);
    for (uint32_t j = 0; j < m->skins[skin].joint_count; ++j) {
        out[(size_t)j * 16 + 12] -= dx;
        out[(size_t)j * 16 + 14] -= dz;
    }
}

void cb_clip_frame_similarities(cb_sampler *s, const cb_clip_info *clip, const uint32_t *frames, uint32_t count,
                                cb_root_motion root_motion, cb_similarity *out)
{
    uint32_t joints = cb_sampler_model(s)->skins[cb_sampler_skin(s)].joint_count;
    for (uint32_t first = 0; first < count; first += CB_SAMPLE_BATCH) {
        uint32_t n = count - first < CB_SAMPLE_BATCH ? count - first : CB_SAMPLE_BATCH;
        double times[CB_SAMPLE_BATCH];
        for (uint32_t i = 0; i < n; ++i) times[i] = cb_clip_frame_time(clip, frames[first + i]);
        cb_similarity *rows = out + (size_t)first * joints;
        cb_sample_joint_similarities_batch(s, clip->animation, times, n, rows);
        for (uint32_t i = 0; cb_root_motion_in_place(root_motion, clip) && i < n; ++i) {
            double dx, dz;
            root_travel(clip, times[i], &dx, &dz);
            for (uint32_t j = 0; j < joints; ++j) {
                rows[(size_t)i * joints + j].translation[0] -= dx;
                rows[(size_t)i * joints + j].translation[2] -= dz;
            }
        }
    }
}

void cb_clip_frame_lanes(cb_sampler *s, const cb_clip_info *clip, const uint32_t *frames, uint32_t count,
                         cb_root_motion root_motion, double *out)
{
    uint32_t joints = cb_sampler_model(s)->skins[cb_sampler_skin(s)].joint_count;
    double times[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < CB_SAMPLE_BATCH; ++i) times[i] = cb_clip_frame_time(clip, frames[i < count ? i : count - 1]);
    cb_sample_joint_lanes(s, clip->animation, times, count, out);
    if (!cb_root_motion_in_place(root_motion, clip)) return;
    double dx[CB_SAMPLE_BATCH], dz[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < CB_SAMPLE_BATCH; ++i) root_travel(clip, times[i], &dx[i], &dz[i]);
    /* Joint by joint, a lane row at a time (one subtraction per value, so the order of the
     * loops changes no bit): contiguous, where time by time strode over every joint's lanes. */
    for (uint32_t j = 0; j < joints; ++j) {
        double *x = out + ((size_t)j * 8 + 4) * CB_SAMPLE_BATCH, *z = out + ((size_t)j * 8 + 6) * CB_SAMPLE_BATCH;
        for (uint32_t i = 0; i < CB_SAMPLE_BATCH; ++i) x[i] -= dx[i], z[i] -= dz[i];
    }
}

/* cb_clip_frame_lanes_each's sink between the sampler and the caller's: the root's travel
 * taken off each joint (the same subtraction as cb_clip_frame_lanes). */
typedef struct travel_sink {
    double dx[CB_SAMPLE_BATCH], dz[CB_SAMPLE_BATCH];
    cb_joint_lanes_sink sink;
    void *ctx;
} travel_sink;

CB_TARGET_CLONES
static void take_off_travel(void *ctx, uint32_t joint, double (*lanes)[CB_SAMPLE_BATCH])
{
    const travel_sink *t = ctx;
#if defined(__GNUC__) /* four lanes a subtraction (-O2 leaves the plain loop scalar) */
    for (int i = 0; i < CB_SAMPLE_BATCH; i += 4) {
        v4df x, z, dx, dz;
        memcpy(&x, &lanes[4][i], sizeof x), memcpy(&z, &lanes[6][i], sizeof z);
        memcpy(&dx, &t->dx[i], sizeof dx), memcpy(&dz, &t->dz[i], sizeof dz);
        x -= dx, z -= dz;
        memcpy(&lanes[4][i], &x, sizeof x), memcpy(&lanes[6][i], &z, sizeof z);
    }
#else
    for (int i = 0; i < CB_SAMPLE_BATCH; ++i) lanes[4][i] -= t->dx[i], lanes[6][i] -= t->dz[i];
#endif
    t->sink(t->ctx, joint, lanes);
}

void cb_clip_frame_lanes_each(cb_sampler *s, const cb_clip_info *clip, const uint32_t *frames, uint32_t count,
                              cb_root_motion root_motion, cb_joint_lanes_sink sink, void *ctx)
{
    double times[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < CB_SAMPLE_BATCH; ++i) times[i] = cb_clip_frame_time(clip, frames[i < count ? i : count - 1]);
    if (!cb_root_motion_in_place(root_motion, clip)) {
        cb_sample_joint_lanes_each(s, clip->animation, times, count, sink, ctx);
        return;
    }
    travel_sink t = {.sink = sink, .ctx = ctx};
    for (uint32_t i = 0; i < CB_SAMPLE_BATCH; ++i) root_travel(clip, times[i], &t.dx[i], &t.dz[i]);
    cb_sample_joint_lanes_each(s, clip->animation, times, count, take_off_travel, &t);
}

void cb_clip_frame_matrices_batch(cb_sampler *s, const cb_clip_info *clip, const uint32_t *frames, uint32_t count,
                                  cb_root_motion root_motion, cb_joint_subset *all, double *lanes, double *const *out)
{
    uint32_t joints = all->joint_count;
    double times[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < CB_SAMPLE_BATCH; ++i) times[i] = cb_clip_frame_time(clip, frames[i < count ? i : count - 1]);
    cb_sample_joint_subset_poses(s, clip->animation, times, count, all, lanes, out);
    bool in_place = cb_root_motion_in_place(root_motion, clip);
    for (uint32_t i = 0; i < count; ++i) {
        if (!out[i] || !in_place) continue;
        double dx, dz; /* as cb_clip_frame_matrices takes it off */
        root_travel(clip, times[i], &dx, &dz);
        for (uint32_t j = 0; j < joints; ++j) out[i][(size_t)j * 16 + 12] -= dx, out[i][(size_t)j * 16 + 14] -= dz;
    }
}
