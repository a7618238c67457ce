/* locomotion.c - ground speed, the locomotion decision and the speed reference (locomotion.h). */
#include "crowdbake/locomotion.h"
#include "internal/name_words.h"
#include "../core/clip_memo.h"
#include "../core/foot_cache.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Words that name a gait, then words that name an action done in place (one list, so a name's
 * first word in either decides). */
enum { GAIT_WORDS = 30 };
static const char *const locomotion_words[] = {
    "walk", "run", "trot", "canter", "gallop", "lope", "amble", "jog", "sprint", "dash", "flee", "wander", "roam",
    "stroll", "march", "patrol", "migrate", "move", "locomotion", "crawl", "slither", "hop", "swim", "fly", "flight",
    "glide", "soar", "strafe", "chase", "stride",
    "idle", "stand", "eat", "graze", "drink", "sniff", "attack", "bite", "headbutt", "kick", "punch", "hit", "react",
    "hurt", "damage", "stun", "death", "die", "dead", "dying", "sit", "sleep", "lie", "rest", "look", "survey",
    "roar", "howl", "bark", "call", "emote", "dance", "wave", "yes", "no", "spawn", "pose", "scratch", "shake",
    "groom", "yawn", "breathe", "alert", "cower"};

int cb_name_says_locomotion(const char *name, char *word, size_t size)
{
    int i = cb_name_find_word(name, locomotion_words, sizeof locomotion_words / sizeof *locomotion_words, word, size);
    return i < 0 ? 0 : i < GAIT_WORDS ? 1 : -1;
}

/* A clip whose name says an action done in place (Attack_Kick, Idle_Scratch) is no stride,
 * whatever its feet do: a kick's feet step back while it rears, and its contacts would be
 * footsteps of a walk that is not there. */
static void no_stride_in_actions(const cb_model *m, const cb_clip_info *clip, cb_stride *st)
{
    char word[64];
    const char *name = m->animations[clip->animation].name;
    if (!st->stride || cb_name_says_locomotion(name, word, sizeof word) >= 0) return;
    st->stride = false, st->speed = 0, st->slide_mean = st->slide_worst = st->slide_mean_varying = 0;
    for (uint32_t k = 0; k < st->foot_count; ++k) st->feet[k].strides = false, st->feet[k].stance_count = 0;
    snprintf(st->why, sizeof st->why, "the clip's name says '%s': an action in place, its feet give no stride", word);
}

void ground_speed_cached(foot_cache *feet, cb_sampler *s, const cb_clip_info *clip, cb_ground_speed *out)
{
    memset(out, 0, sizeof *out);
    out->method = "none";
    if (clip->duration <= 0) return;
    double height = foot_cache_rest_height(feet, s);
    foot_cache_stride(feet, s, clip, &out->stride);
    no_stride_in_actions(cb_sampler_model(s), clip, &out->stride);
    out->root = clip->ground_speed;
    out->feet = out->stride.stride ? out->stride.speed : 0;
    if (out->feet > 0) {
        out->speed = out->feet;
        out->method = "planted feet";
    } else if (out->root > 0.01 * (height > 0 ? height : 1)) { /* under that, root jitter */
        out->speed = out->root;
        out->method = "root motion";
    }
}

void cb_measure_ground_speed(cb_sampler *s, const cb_clip_info *clip, cb_ground_speed *out)
{
    ground_speed_cached(NULL, s, clip, out);
}

bool cb_decide_locomotion(int kind, const char *words, bool loops, const cb_ground_speed *gs, bool speed_given,
                          char *reason, size_t size)
{
    const cb_stride *feet = &gs->stride;
    bool measured = gs->speed > 0;
    if (!loops) {
        snprintf(reason, size, "a one-shot: it plays once at its own rate, also at standstill");
        return false;
    }
    if (kind < 0) {
        snprintf(reason, size, "in place: %.200s%s; it plays at its own rate at standstill", words,
                 feet->stride ? " (its feet stride, but the words decide: set sync = \"speed\" to follow speed)" : "");
        return false;
    }
    if (kind > 0 && (measured || speed_given)) {
        snprintf(reason, size, "locomotion: %.200s, and %.250s", words,
                 feet->stride ? feet->why : measured ? "its root travels" : "the animal gives speed_reference");
        return true;
    }
    if (kind > 0) {
        snprintf(reason, size, "plays at its own rate: %.100s, but nothing measures its ground speed "
                 "(%.200s; no root travel); give the animal a speed_reference to follow speed", words, feet->why);
        return false;
    }
    if (feet->stride) {
        snprintf(reason, size, "locomotion: no word decides, and %.250s", feet->why);
        return true;
    }
    if (measured) {
        snprintf(reason, size, "locomotion: no word decides, and its root travels %.3g units/s", gs->speed);
        return true;
    }
    snprintf(reason, size, "in place: no word decides, and %.250s", feet->why);
    return false;
}

/* Whether a clip alone (no catalog state) follows the speed: its name's words, then its feet. */
static bool clip_follows_speed(int kind, const char *word, bool loops, const cb_ground_speed *gs)
{
    char words[160] = "", reason[512];
    if (kind) snprintf(words, sizeof words, "the clip's name says '%s'", word);
    return cb_decide_locomotion(kind, words, loops, gs, false, reason, sizeof reason);
}

/* Whether the model's animation a may follow the speed by its name: not one whose name says an
 * action (cb_decide_locomotion), whatever its feet do; its kind into *kind. One that is not the
 * model's may (its analysis then fails). */
static bool name_may_follow(const cb_model *model, int32_t a, int *kind, char *word, size_t size)
{
    *kind = a >= 0 && (uint32_t)a < model->animation_count ? cb_name_says_locomotion(model->animations[a].name, word, size) : 0;
    return *kind >= 0;
}

bool speed_reference_may_measure(const cb_model *model, int32_t animation)
{
    int kind;
    char word[64];
    return name_may_follow(model, animation, &kind, word, sizeof word);
}

/* Clip i of the plan (or the model's clip i) analyzed at 30 fps; false when it cannot be, or when
 * it never follows the speed: a clip whose name says an action (not analyzed: a name decides
 * first), or a one-shot. Those are not measured. */
static bool clip_to_measure(clip_memo *memo, cb_sampler *s, const cb_clip_plan *plan, uint32_t i, cb_clip_info *info,
                            int *kind, char *word, size_t size)
{
    cb_error err = {0};
    cb_limits limits = cb_default_limits();
    int32_t a = plan ? plan[i].animation : (int32_t)i;
    if (!name_may_follow(cb_sampler_model(s), a, kind, word, size)) return false;
    return !clip_memo_analyze(memo, s, a, 30, plan ? plan[i].loop : -1, &limits, info, &err) && info->loops;
}

/* The analyses clip_to_measure asks for, made side by side on the threads first and kept in the
 * run's memo, from which clip_to_measure then takes each. */
static void prefetch_analyses(clip_memo *memo, const cb_sampler *s, const cb_clip_plan *plan, uint32_t n,
                              uint32_t threads)
{
    clip_ask *asks = malloc((n ? n : 1) * sizeof *asks);
    cb_limits limits = cb_default_limits();
    uint32_t count = 0;
    for (uint32_t i = 0; asks && s && i < n; ++i) {
        int32_t a = plan ? plan[i].animation : (int32_t)i;
        if (speed_reference_may_measure(cb_sampler_model(s), a)) asks[count++] = (clip_ask){a, 30, plan ? plan[i].loop : -1};
    }
    if (asks && s) clip_memo_prefetch(memo, s, asks, count, &limits, threads);
    free(asks);
}

double speed_reference_cached(foot_cache *feet, clip_memo *memo, const cb_model *model, int32_t skin,
                              const cb_clip_plan *plan, uint32_t count, uint32_t threads, char *why, size_t size)
{
    cb_error err = {0};
    cb_sampler *s = skin >= 0 ? cb_sampler_create(model, skin, &err) : NULL;
    double best = 0;
    snprintf(why, size, "none: no clip is locomotion (none follows the speed)");
    uint32_t n = plan ? count : model->animation_count, measured = 0;
    cb_ground_speed *speed = malloc(sizeof *speed);
    cb_clip_info *infos = malloc((n ? n : 1) * sizeof *infos);
    int *kinds = malloc((n ? n : 1) * sizeof *kinds);
    char(*words)[64] = malloc((n ? n : 1) * sizeof *words);
    /* Every clip analyzed first, so that their strides are measured side by side on the threads. */
    prefetch_analyses(memo, s, plan, n, threads);
    for (uint32_t i = 0; s && infos && kinds && words && i < n; ++i)
        if (clip_to_measure(memo, s, plan, i, &infos[measured], &kinds[measured], words[measured], sizeof *words))
            ++measured;
    foot_cache_measure_clips(feet, s, infos, measured, threads);
    for (uint32_t i = 0; speed && i < measured; ++i) {
        const cb_clip_info *info = &infos[i];
        cb_sampler_set_loop(s, info); /* as analyzing it left it: a stride not cached is sampled so */
        ground_speed_cached(feet, s, info, speed);
        if (!clip_follows_speed(kinds[i], words[i], info->loops, speed) || speed->speed <= 0 ||
            (best > 0 && speed->speed >= best))
            continue;
        best = speed->speed;
        snprintf(why, size, "the slowest locomotion clip '%s' (%s); --speed-reference overrides",
                 model->animations[info->animation].name, speed->method);
    }
    free(speed), free(infos), free(kinds), free(words);
    cb_sampler_free(s);
    return best;
}

double cb_speed_reference(const cb_model *model, int32_t skin, const cb_clip_plan *plan, uint32_t count, char *why,
                          size_t size)
{
    foot_cache *feet = foot_cache_create(); /* the feet found once for every clip */
    double best = speed_reference_cached(feet, NULL, model, skin, plan, count, 1, why, size);
    foot_cache_free(feet);
    return best;
}
