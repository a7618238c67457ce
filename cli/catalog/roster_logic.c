/* roster.c - roster logic on plain structs: see catalog.h. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "catalog/catalog.h"

void cb_catalog_free(cb_catalog *c)
{
    if (!c) return;
    cb_arena_free(c->arena);
    memset(c, 0, sizeof *c);
}

static bool contains_nocase(const char *hay, const char *needle)
{
    size_t n = strlen(needle);
    if (n == 0) return false;
    for (; *hay; ++hay) {
        size_t i = 0;
        while (i < n && hay[i] && tolower((unsigned char)hay[i]) == tolower((unsigned char)needle[i])) ++i;
        if (i == n) return true;
    }
    return false;
}

int cb_match_state(const char *const *clips, uint32_t clip_count, const char *const *keywords, uint32_t keyword_count)
{
    for (uint32_t k = 0; k < keyword_count; ++k)
        for (uint32_t c = 0; c < clip_count; ++c)
            if (contains_nocase(clips[c], keywords[k])) return (int)c;
    return -1;
}

/* ---- the command line's word on states ---- */

static bool parse_sync(const char *text, size_t n, cb_sync_mode *out)
{
    static const char *const names[] = {"auto", "speed", "time"};
    for (int i = 0; i < 3; ++i)
        if (strlen(names[i]) == n && strncmp(text, names[i], n) == 0) return *out = (cb_sync_mode)i, true;
    return false;
}

/* Appends " WORD" to an animal's canonical entry, so a record made without the override is not
 * taken for one made with it. */
static bool note_override(cb_catalog *cat, cb_catalog_animal *an, const char *what, const char *value)
{
    size_t n = strlen(an->canonical) + strlen(what) + strlen(value) + 3;
    char *c = cb_arena_alloc(cat->arena, n, 1);
    if (!c) return false;
    snprintf(c, n, "%s %s=%s", an->canonical, what, value);
    an->canonical = c;
    return true;
}

/* Sets `state`'s sync (or, with mode < 0, makes it the default state) in every animal that has
 * it; false when none does. */
static bool apply_to_state(cb_catalog *cat, const char *state, size_t len, int mode, bool *oom)
{
    bool found = false;
    for (uint32_t a = 0; a < cat->animal_count; ++a) {
        cb_catalog_animal *an = &cat->animals[a];
        for (uint32_t s = 0; s < an->state_count; ++s) {
            if (strlen(an->states[s].name) != len || strncmp(an->states[s].name, state, len) != 0) continue;
            found = true;
            if (mode >= 0) an->states[s].sync = (cb_sync_mode)mode, an->states[s].sync_from_command_line = true;
            else an->default_state = an->states[s].name, an->default_state_from = "the command line (--default-state)";
            static const char *const modes[] = {"auto", "speed", "time"};
            *oom |= !note_override(cat, an, mode >= 0 ? an->states[s].name : "default", mode >= 0 ? modes[mode] : state);
        }
    }
    return found;
}

cb_status cb_catalog_override_states(cb_catalog *cat, const char *syncs, const char *default_state, cb_error *err)
{
    bool oom = false;
    for (const char *p = syncs; p && *p;) {
        const char *end = strchr(p, ','), *eq = strchr(p, '=');
        if (!end) end = p + strlen(p);
        cb_sync_mode mode;
        if (!eq || eq > end || eq == p || !parse_sync(eq + 1, (size_t)(end - eq - 1), &mode))
            return cb_fail_setting(err, CB_ERR_SETTINGS, CB_SETTING_SYNC,
                                   "'%.*s': a state's sync is STATE=speed (follows the instance's speed), STATE=time "
                                   "(its own rate) or STATE=auto", (int)(end - p), p);
        if (!apply_to_state(cat, p, (size_t)(eq - p), (int)mode, &oom))
            return cb_fail_setting(err, CB_ERR_SETTINGS, CB_SETTING_SYNC, "%s: no animal has a state '%.*s'", cat->path,
                                   (int)(eq - p), p);
        p = *end ? end + 1 : end;
    }
    if (default_state && !apply_to_state(cat, default_state, strlen(default_state), -1, &oom))
        return cb_fail_setting(err, CB_ERR_SETTINGS, CB_SETTING_DEFAULT_STATE, "%s: no animal has a state '%s'", cat->path,
                               default_state);
    return oom ? cb_fail(err, CB_ERR_INTERNAL, "out of memory") : CB_OK;
}

/* ---- ground speed ---- */

static int classify_words(const char *text, char *out, size_t size);

/* A clip whose name says an action done in place (Attack_Kick, Idle_Scratch) is no stride,
 * whatever its feet do: a kick's feet step back while it rears, and its contacts would be
 * footsteps of a walk that is not there. */
static void no_stride_in_actions(const cb_model *m, const cb_clip_info *clip, cb_stride *st)
{
    char word[64];
    const char *name = m->animations[clip->animation].name;
    if (!st->stride || classify_words(name, word, sizeof word) >= 0) return;
    st->stride = false, st->speed = 0, st->slide_mean = st->slide_worst = st->slide_mean_varying = 0;
    for (uint32_t k = 0; k < st->foot_count; ++k) st->feet[k].strides = false, st->feet[k].stance_count = 0;
    snprintf(st->why, sizeof st->why, "the clip's name says '%s': an action in place, its feet give no stride", word);
}

void cb_measure_ground_speed(cb_sampler *s, const cb_clip_info *clip, cb_ground_speed *out)
{
    memset(out, 0, sizeof *out);
    out->method = "none";
    if (clip->duration <= 0) return;
    double lo[3], hi[3], height = cb_skin_rest_bounds(s, lo, hi);
    cb_stride_measure(s, clip, &out->stride);
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

/* ---- speed or time: what a state's words and feet say ---- */

/* Words that name a gait, and words that name an action done in place. A name's words match a
 * stem as themselves or with an ending (walks, walking, trotted, running, swimmer). */
static const char *const locomotion_words[] = {
    "walk", "run", "trot", "canter", "gallop", "lope", "amble", "jog", "sprint", "dash", "flee", "wander", "roam",
    "stroll", "march", "patrol", "migrate", "move", "locomotion", "crawl", "slither", "hop", "swim", "fly", "flight",
    "glide", "soar", "strafe", "chase", "stride"};
static const char *const in_place_words[] = {
    "idle", "stand", "eat", "graze", "drink", "sniff", "attack", "bite", "headbutt", "kick", "punch", "hit", "react",
    "hurt", "damage", "stun", "death", "die", "dead", "dying", "sit", "sleep", "lie", "rest", "look", "survey",
    "roar", "howl", "bark", "call", "emote", "dance", "wave", "yes", "no", "spawn", "pose", "scratch", "shake",
    "groom", "yawn", "breathe", "alert", "cower"};

static bool word_matches(const char *word, size_t n, const char *stem)
{
    static const char *const endings[] = {"", "s", "es", "ed", "d", "er", "ing", "ion"};
    size_t k = strlen(stem);
    if (n < k || strncmp(word, stem, k) != 0) return false;
    const char *rest = word + k;
    size_t r = n - k;
    if (r > 0 && rest[0] == stem[k - 1] && r > 1) ++rest, --r; /* a doubled consonant: running, trotted */
    for (size_t e = 0; e < sizeof endings / sizeof *endings; ++e)
        if (strlen(endings[e]) == r && strncmp(rest, endings[e], r) == 0) return true;
    return false;
}

/* The first word of `text` (split at anything not a letter and where a lower-case letter meets
 * an upper-case one: "Idle_HitReact" is idle, hit, react) in either list: *kind 1 for a gait,
 * -1 for an action in place; the matching word, lower-cased, into out. 0 when none. */
static int classify_words(const char *text, char *out, size_t size)
{
    char word[64];
    for (const char *p = text; *p;) {
        size_t n = 0;
        while (*p && !isalpha((unsigned char)*p)) ++p;
        while (isalpha((unsigned char)*p)) {
            if (n < sizeof word - 1) word[n++] = (char)tolower((unsigned char)*p);
            ++p;
            if (islower((unsigned char)p[-1]) && isupper((unsigned char)*p)) break;
        }
        for (size_t i = 0; n && i < sizeof locomotion_words / sizeof *locomotion_words; ++i)
            if (word_matches(word, n, locomotion_words[i])) return snprintf(out, size, "%.*s", (int)n, word), 1;
        for (size_t i = 0; n && i < sizeof in_place_words / sizeof *in_place_words; ++i)
            if (word_matches(word, n, in_place_words[i])) return snprintf(out, size, "%.*s", (int)n, word), -1;
    }
    return 0;
}

/* What the words say: the state's name first, then its keywords, then the clip's name. */
static int words_say(const cb_catalog_state *st, const char *clip_name, char *out, size_t size)
{
    char word[64];
    int kind = 0;
    if (st && (kind = classify_words(st->name, word, sizeof word)))
        return snprintf(out, size, "the state's name '%s' says '%s'", st->name, word), kind;
    for (uint32_t k = 0; st && k < st->keyword_count; ++k)
        if ((kind = classify_words(st->keywords[k], word, sizeof word)))
            return snprintf(out, size, "its keyword '%s' says '%s'", st->keywords[k], word), kind;
    if ((kind = classify_words(clip_name, word, sizeof word)))
        return snprintf(out, size, "the clip's name says '%s'", word), kind;
    return 0;
}

void cb_decide_sync(const cb_catalog_state *st, const char *clip_name, bool loops, const cb_ground_speed *gs,
                    bool speed_given, cb_sync_decision *out)
{
    char words[200] = "";
    const cb_stride *feet = &gs->stride;
    bool measured = gs->speed > 0;
    out->speed = false;
    if (st && st->sync != CB_SYNC_AUTO) {
        out->speed = st->sync == CB_SYNC_SPEED;
        const char *mode = out->speed ? "speed" : "time";
        if (st->sync_from_command_line) snprintf(out->reason, sizeof out->reason, "the command line says --sync %.200s=%s", st->name, mode);
        else snprintf(out->reason, sizeof out->reason, "the catalog says sync = \"%s\"", mode);
        return;
    }
    if (!loops) {
        snprintf(out->reason, sizeof out->reason, "a one-shot: it plays once at its own rate, also at standstill");
        return;
    }
    int kind = words_say(st, clip_name, words, sizeof words);
    if (kind < 0) {
        snprintf(out->reason, sizeof out->reason, "in place: %.200s%s; it plays at its own rate at standstill", words,
                 feet->stride ? " (its feet stride, but the words decide: set sync = \"speed\" to follow speed)" : "");
    } else if (kind > 0 && (measured || speed_given)) {
        out->speed = true;
        snprintf(out->reason, sizeof out->reason, "locomotion: %.200s, and %.250s", words,
                 feet->stride ? feet->why : measured ? "its root travels" : "the animal gives speed_reference");
    } else if (kind > 0) {
        snprintf(out->reason, sizeof out->reason, "plays at its own rate: %.100s, but nothing measures its ground speed "
                 "(%.200s; no root travel); give the animal a speed_reference to follow speed", words, feet->why);
    } else if (feet->stride) {
        out->speed = true;
        snprintf(out->reason, sizeof out->reason, "locomotion: no word decides, and %.250s", feet->why);
    } else if (measured) {
        out->speed = true;
        snprintf(out->reason, sizeof out->reason, "locomotion: no word decides, and its root travels %.3g units/s",
                 gs->speed);
    } else {
        snprintf(out->reason, sizeof out->reason, "in place: no word decides, and %.250s", feet->why);
    }
}

/* ---- LODs ---- */

cb_status cb_lod_remap(const cb_model *main, int32_t main_skin, const cb_model *lod, int32_t lod_skin, uint32_t *remap,
                       cb_error *err)
{
    const cb_skin *a = &main->skins[main_skin], *b = &lod->skins[lod_skin];
    for (uint32_t i = 0; i < b->joint_count; ++i) {
        const char *name = lod->nodes[b->joints[i]].name;
        uint32_t k = 0;
        while (k < a->joint_count && strcmp(main->nodes[a->joints[k]].name, name) != 0) ++k;
        if (k == a->joint_count)
            return cb_fail(err, CB_ERR_INPUT, "%s: LOD joint '%s' is not a joint of %s; a LOD must use the same rig", lod->source,
                           name, main->source);
        const double *x = a->inverse_bind + (size_t)k * 16, *y = b->inverse_bind + (size_t)i * 16;
        double scale = 1;
        for (int e = 0; e < 16; ++e) scale = fmax(scale, fabs(x[e]));
        for (int e = 0; e < 16; ++e)
            if (fabs(x[e] - y[e]) > 1e-4 * scale)
                return cb_fail(err, CB_ERR_INPUT,
                               "%s: LOD joint '%s' has another bind pose than in %s (inverse bind matrix element %d: %g vs "
                               "%g); re-export the LOD from the same rig",
                               lod->source, name, main->source, e, y[e], x[e]);
        remap[i] = k;
    }
    return CB_OK;
}
