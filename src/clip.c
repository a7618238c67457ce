/* clip.c - clip framing (how many rows, at which times), loop detection and root motion. */
#include "cb_math.h"
#include "crowdbake.h"

#include <math.h>
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

/* Size of the skeleton in the rest pose: the diagonal of its joints' bounding box. */
static double skeleton_extent(cb_sampler *s, const cb_model *m, int32_t skin)
{
    const double *g = cb_sample_globals(s, -1, 0);
    const cb_skin *sk = &m->skins[skin];
    cb_vec3 lo = {INFINITY, INFINITY, INFINITY}, hi = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t j = 0; j < sk->joint_count; ++j) {
        const double *p = g + (size_t)sk->joints[j] * 16 + 12;
        lo.x = fmin(lo.x, p[0]), lo.y = fmin(lo.y, p[1]), lo.z = fmin(lo.z, p[2]);
        hi.x = fmax(hi.x, p[0]), hi.y = fmax(hi.y, p[1]), hi.z = fmax(hi.z, p[2]);
    }
    double e = cb_vec3_length(cb_vec3_sub(hi, lo));
    return e > 1e-9 ? e : 1.0;
}

static bool poses_match(const double *a, const double *b, uint32_t joints, cb_vec3 travel, double extent)
{
    for (uint32_t j = 0; j < joints; ++j) {
        const double *ma = a + (size_t)j * 16, *mb = b + (size_t)j * 16;
        for (int k = 0; k < 12; ++k)
            if (fabs(ma[k] - mb[k]) > CB_LOOP_TOLERANCE) return false;
        double d[3] = {mb[12] - travel.x - ma[12], mb[13] - travel.y - ma[13], mb[14] - travel.z - ma[14]};
        for (int k = 0; k < 3; ++k)
            if (fabs(d[k]) > CB_LOOP_TOLERANCE * extent) return false;
    }
    return true;
}

cb_status cb_clip_analyze(cb_sampler *s, int32_t animation, double fps, int loop_override, const cb_limits *limits,
                          cb_clip_info *out, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    cb_limits defaults = cb_default_limits();
    if (!limits) limits = &defaults;
    if (animation < 0 || animation >= (int32_t)m->animation_count)
        return cb_fail(err, CB_ERR_INPUT, "%s: has no clip %d", m->source, animation);
    if (!(fps > 0) || !isfinite(fps) || fps > 10000)
        return cb_fail(err, CB_ERR_USAGE, "fps must be a number between 0 and 10000, got %g", fps);
    const cb_animation *anim = &m->animations[animation];
    int32_t skin = cb_sampler_skin(s);
    memset(out, 0, sizeof *out);
    out->animation = animation;
    out->t0 = anim->t0;
    out->t1 = anim->t1;
    out->duration = anim->t1 - anim->t0;
    if (out->duration * fps > (double)limits->max_frames)
        return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' lasts %gs: %.0f frames at %g fps is over the limit of %u (--max-frames)",
                       m->source, anim->name, out->duration, out->duration * fps, fps, limits->max_frames);
    uint32_t steps = cb_clip_step_count(out->duration, fps);
    out->steps = steps;
    out->effective_fps = out->duration > 0 ? steps / out->duration : fps;

    uint32_t root = cb_skin_root_joint(m, skin);
    cb_vec3 p0 = root_position(s, m, skin, root, animation, out->t0);
    cb_vec3 p1 = root_position(s, m, skin, root, animation, out->t1);
    cb_vec3 d = cb_vec3_sub(p1, p0);
    out->root_displacement[0] = d.x, out->root_displacement[1] = d.y, out->root_displacement[2] = d.z;
    if (out->duration > 0) {
        for (int k = 0; k < 3; ++k) out->root_velocity[k] = out->root_displacement[k] / out->duration;
        out->ground_speed = hypot(out->root_velocity[0], out->root_velocity[2]);
    }

    if (loop_override >= 0) {
        out->loops = loop_override != 0;
    } else {
        uint32_t joints = m->skins[skin].joint_count;
        double *a = malloc((size_t)joints * 32 * sizeof(double));
        if (!a) return cb_fail(err, CB_ERR_INTERNAL, "out of memory analysing clip '%s'", anim->name);
        cb_sample_joint_matrices(s, animation, out->t0, a);
        cb_sample_joint_matrices(s, animation, out->t1, a + (size_t)joints * 16);
        cb_vec3 travel = {d.x, 0, d.z}; /* horizontal root travel does not break a loop */
        out->loops = poses_match(a, a + (size_t)joints * 16, joints, travel, skeleton_extent(s, m, skin));
        free(a);
    }
    out->frames = out->loops ? steps : steps + 1;
    return CB_OK;
}

/* The root's average horizontal travel from the clip's start to time t, which in-place bakes
 * take off every joint. */
static void root_travel(const cb_clip_info *clip, double t, double *dx, double *dz)
{
    *dx = clip->root_velocity[0] * (t - clip->t0);
    *dz = clip->root_velocity[2] * (t - clip->t0);
}

void cb_clip_frame_matrices(cb_sampler *s, const cb_clip_info *clip, uint32_t frame, cb_root_motion root_motion,
                            double *out)
{
    const cb_model *m = cb_sampler_model(s);
    int32_t skin = cb_sampler_skin(s);
    double t = cb_clip_frame_time(clip, frame);
    cb_sample_joint_matrices(s, clip->animation, t, out);
    if (root_motion != CB_ROOT_MOTION_IN_PLACE) return;
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
        for (uint32_t i = 0; root_motion == CB_ROOT_MOTION_IN_PLACE && i < n; ++i) {
            double dx, dz;
            root_travel(clip, times[i], &dx, &dz);
            for (uint32_t j = 0; j < joints; ++j) {
                rows[(size_t)i * joints + j].translation[0] -= dx;
                rows[(size_t)i * joints + j].translation[2] -= dz;
            }
        }
    }
}
