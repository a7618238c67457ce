/* loop_decide.c - loop or one-shot: the clip's name, its poses and its feet weighed together,
 * so that no single measurement sitting near its threshold decides (a gallop whose wrap is a
 * hair above its neighbour steps is still a gallop; an attack that returns to its first pose
 * still plays once). */
#include "cb_math.h"
#include "crowdbake/core.h"
#include "crowdbake/stride.h"
#include "internal/name_words.h"
#include "internal/plumbing.h"
#include "loop_decide.h"
#include "sampler.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Words that name a gait, and words that name a cycle done in place: what a crowd plays over
 * and over. */
static const char *const gait_words[] = {"walk", "run", "trot", "canter", "gallop", "lope", "jog", "sprint", "amble",
                                         "swim", "fly", "flap", "hover", "crawl", "slither"};
static const char *const cycle_words[] = {"idle", "eat", "graze", "breathe", "dance", "loop", "cycle"};
/* Words that name an action done once: repeating it would read as a glitch (a hit reaction
 * that keeps reacting, a death that dies again). They outweigh any cycle word beside them
 * (Idle_HitReact is a reaction, from idle). */
static const char *const once_words[] = {"attack", "hit", "react", "death", "die", "dead", "dying", "punch", "kick",
                                         "headbutt", "hurt", "damage", "stun", "fall", "spawn", "shoot", "throw",
                                         "knockdown", "knockback"};
/* A leap: done once (Jump, Jump_ToIdle), unless it names a gait beside it, which then holds it
 * in its cycle (Gallop_Jump leaps in its stride). */
static const char *const leap_words[] = {"jump", "leap", "hop"};

#define NAME_CYCLE 2.0
#define NAME_ONCE (-3.0)
#define NAME_LEAP_IN_GAIT 1.0
#define POSE_RANGE 2.0 /* the pose's weight is log2(neighbour step / wrap), clamped to +-this */
#define FEET_STRIDE 1.0

static int find(const char *name, const char *const *words, size_t count, char *word, size_t size)
{
    return cb_name_find_word(name, words, count, word, size);
}
#define FIND(name, list, word) find(name, list, sizeof list / sizeof *list, word, sizeof word)

bool cb_name_says_once(const char *name, char *word, size_t size)
{
    char gait[20];
    return find(name, once_words, sizeof once_words / sizeof *once_words, word, size) >= 0 ||
           (find(name, leap_words, sizeof leap_words / sizeof *leap_words, word, size) >= 0 && FIND(name, gait_words, gait) < 0);
}

static void weigh_name(const char *name, cb_clip_info *out)
{
    char once[20], leap[20], gait[20], cycle[20]; /* four fit loop_word: "gait' and 'leap" */
    char *w = out->loop_word;
    size_t size = sizeof out->loop_word;
    bool is_gait = FIND(name, gait_words, gait) >= 0, is_cycle = FIND(name, cycle_words, cycle) >= 0;
    if (cb_name_says_once(name, once, sizeof once))
        out->loop_name = NAME_ONCE, snprintf(w, size, "%s", once);
    else if (FIND(name, leap_words, leap) >= 0 && is_gait)
        out->loop_name = NAME_LEAP_IN_GAIT, snprintf(w, size, "%s' and '%s", gait, leap);
    else if (is_gait || is_cycle)
        out->loop_name = NAME_CYCLE, snprintf(w, size, "%s", is_gait ? gait : cycle);
    else
        out->loop_name = 0, w[0] = '\0';
}

/* How well the last pose leads back to the first (root travel taken off): equal, +2; a wrap as
 * big as its neighbour steps, 0; each doubling beyond that, -1 more, down to -2. */
static double weigh_pose(const cb_clip_info *c)
{
    if (c->loop_reason == CB_LOOP_CLOSED || c->loop_reason == CB_LOOP_CLOSED_CORRECTED) return POSE_RANGE;
    if (!(c->largest_step > 0) || !(c->wrap_jump > 0)) return -POSE_RANGE;
    double w = log2(c->largest_step / c->wrap_jump);
    return w > POSE_RANGE ? POSE_RANGE : w < -POSE_RANGE ? -POSE_RANGE : w;
}

/* Whether the feet stride when the clip is played as a loop: planted feet that step back
 * together make it locomotion, which cycles. Frames `out` as a loop to measure it. */
static double weigh_feet(cb_sampler *s, double fps, const cb_limits *limits, cb_clip_info *out)
{
    double span = out->t1 - out->t0;
    out->loops = true;
    bool closes = out->loop_reason == CB_LOOP_CLOSED || out->loop_reason == CB_LOOP_CLOSED_CORRECTED;
    out->duration = span + (closes ? 0 : out->key_interval);
    cb_sampler_set_loop(s, out); /* out of memory: measured uncorrected, which only weighs the feet */
    cb_error ignored = {0};
    out->loop_striding_feet = 0;
    if (cb_clip_frame_at(cb_sampler_model(s), fps, limits, out, &ignored)) return 0;
    cb_stride st;
    cb_stride_measure(s, out, &st);
    for (uint32_t k = 0; st.stride && k < st.foot_count; ++k) out->loop_striding_feet += st.feet[k].strides;
    return st.stride ? FEET_STRIDE : 0;
}

void cb_loop_decide(cb_sampler *s, double fps, const cb_limits *limits, cb_clip_info *out)
{
    const cb_model *m = cb_sampler_model(s);
    weigh_name(m->animations[out->animation].name, out);
    out->loop_pose = weigh_pose(out);
    /* The feet weigh at most FEET_STRIDE: measured (a stride analysis) only where that can turn
     * the decision. */
    double sum = out->loop_name + out->loop_pose;
    out->loop_feet_weighed = sum <= 0 && sum > -FEET_STRIDE;
    out->loop_feet = out->loop_feet_weighed ? weigh_feet(s, fps, limits, out) : 0;
    out->loops = out->loop_name + out->loop_pose + out->loop_feet > 0;
}

void cb_loop_reason_text(const cb_clip_info *c, char *out, size_t size)
{
    char pose[224];
    switch (c->loop_reason) {
    case CB_LOOP_CLOSED: snprintf(pose, sizeof pose, "last pose = first pose"); break;
    case CB_LOOP_CLOSED_CORRECTED: {
        int n = snprintf(pose, sizeof pose, "closing key slightly off: wrap %.3g <= %g x its largest key step %.3g",
                         c->wrap_jump, CB_LOOP_CORRECTABLE, c->largest_key_step);
        if (c->loops && n > 0 && (size_t)n < sizeof pose)
            snprintf(pose + n, sizeof pose - n, ", spread over the cycle (moves the source up to %.3g mm/m)",
                     c->loop_correction_mm_per_m);
        break;
    }
    case CB_LOOP_OPEN:
        snprintf(pose, sizeof pose, "no closing key: wrap %.3g <= its neighbour steps %.3g", c->wrap_jump, c->largest_step);
        break;
    default:
        if (c->largest_step > 0) snprintf(pose, sizeof pose, "ends elsewhere: wrap %.3g > its neighbour steps %.3g", c->wrap_jump, c->largest_step);
        else snprintf(pose, sizeof pose, "ends elsewhere: wrap %.3g", c->wrap_jump);
    }
    if (c->loop_set) {
        snprintf(out, size, "%s, set by the catalog or --loop/--one-shot (the poses say: %s)", c->loops ? "loops" : "plays once", pose);
        return;
    }
    char name[96], feet[64];
    if (c->loop_word[0]) snprintf(name, sizeof name, "the name says '%s' (%+.3g)", c->loop_word, c->loop_name);
    else snprintf(name, sizeof name, "no word of the name decides (0)");
    if (!c->loop_feet_weighed) snprintf(feet, sizeof feet, "its feet not needed (their %+.3g could not turn it)", FEET_STRIDE);
    else if (c->loop_feet > 0) snprintf(feet, sizeof feet, "%u feet stride (%+.3g)", c->loop_striding_feet, c->loop_feet);
    else snprintf(feet, sizeof feet, "no stride of the feet (0)");
    double total = c->loop_name + c->loop_pose + c->loop_feet;
    snprintf(out, size, "%s (%+.2f): %s, %s (%+.2f), %s; --loop/--one-shot or a catalog's loop overrides",
             c->loops ? "loops" : "plays once", total, name, pose, c->loop_pose, feet);
    if (c->loops && c->loop_reason != CB_LOOP_CLOSED && c->loop_reason != CB_LOOP_CLOSED_CORRECTED) {
        size_t n = strlen(out);
        snprintf(out + n, size - n, "; period + %.4gs", c->key_interval);
    }
}
