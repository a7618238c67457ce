/* roster.c - roster logic on plain structs: see catalog.h. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "catalog/catalog.h"
#include "internal/name_words.h"
#include "internal/plumbing.h"

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

/* ---- speed or time: what a state's words and feet say ---- */

/* What the words say: the state's name first, then its keywords, then the clip's name. */
static int words_say(const cb_catalog_state *st, const char *clip_name, char *out, size_t size)
{
    char word[64];
    int kind = 0;
    if (st && (kind = cb_name_says_locomotion(st->name, word, sizeof word)))
        return snprintf(out, size, "the state's name '%s' says '%s'", st->name, word), kind;
    for (uint32_t k = 0; st && k < st->keyword_count; ++k)
        if ((kind = cb_name_says_locomotion(st->keywords[k], word, sizeof word)))
            return snprintf(out, size, "its keyword '%s' says '%s'", st->keywords[k], word), kind;
    if ((kind = cb_name_says_locomotion(clip_name, word, sizeof word)))
        return snprintf(out, size, "the clip's name says '%s'", word), kind;
    return 0;
}

void cb_decide_sync(const cb_catalog_state *st, const char *clip_name, bool loops, const cb_ground_speed *gs,
                    bool speed_given, cb_sync_decision *out)
{
    char words[200] = "";
    out->speed = false;
    if (st && st->sync != CB_SYNC_AUTO) {
        out->speed = st->sync == CB_SYNC_SPEED;
        const char *mode = out->speed ? "speed" : "time";
        if (st->sync_from_command_line) snprintf(out->reason, sizeof out->reason, "the command line says --sync %.200s=%s", st->name, mode);
        else snprintf(out->reason, sizeof out->reason, "the catalog says sync = \"%s\"", mode);
        return;
    }
    int kind = loops ? words_say(st, clip_name, words, sizeof words) : 0;
    out->speed = cb_decide_locomotion(kind, words, loops, gs, speed_given, out->reason, sizeof out->reason);
}

/* ---- the default state ---- */

/* Words of a state a herd rests in, most restful first. */
static const char *const resting_words[] = {"idle", "stand", "rest", "breathe", "graze", "eat", "sit", "sleep"};
/* Words of an action done once: no herd spawns mid-attack. */
static const char *const once_words[] = {"attack", "hit", "react", "death", "die", "dead", "dying", "punch", "kick",
                                         "headbutt", "hurt", "damage", "stun", "fall", "jump", "spawn"};

/* How restful a state is by its words: 0 for the first resting word, more for later ones;
 * RANK_ONCE for an action done once, RANK_OTHER for words that say neither. The matching word
 * and where it was found into `why`. */
enum { RANK_OTHER = 100, RANK_ONCE = 200 };
static int rest_rank(const cb_catalog_state *st, char *why, size_t size)
{
    char word[64];
    size_t n = sizeof resting_words / sizeof *resting_words;
    int i = cb_name_find_word(st->name, resting_words, n, word, sizeof word);
    if (i >= 0) return snprintf(why, size, "its name says '%s'", word), i;
    for (uint32_t k = 0; k < st->keyword_count; ++k)
        if ((i = cb_name_find_word(st->keywords[k], resting_words, n, word, sizeof word)) >= 0)
            return snprintf(why, size, "its keyword '%s' says '%s'", st->keywords[k], word), i;
    if (cb_name_find_word(st->name, once_words, sizeof once_words / sizeof *once_words, word, sizeof word) >= 0)
        return snprintf(why, size, "its name says '%s', an action done once", word), RANK_ONCE;
    return snprintf(why, size, "no word of its name says it rests"), RANK_OTHER;
}

uint32_t cb_pick_default_state(const cb_catalog_animal *an, char *why, size_t size)
{
    uint32_t best = 0;
    int best_rank = RANK_ONCE + 1;
    char best_why[200] = "", w[200];
    for (uint32_t s = 0; s < an->state_count; ++s) {
        int rank = rest_rank(&an->states[s], w, sizeof w);
        if (rank < best_rank || (rank == best_rank && strcmp(an->states[s].name, an->states[best].name) < 0))
            best = s, best_rank = rank, memcpy(best_why, w, sizeof w);
    }
    if (best_rank < RANK_OTHER)
        snprintf(why, size, "decided by name (no default_state given): '%s' rests, %s; default_state or "
                 "--default-state overrides", an->states[best].name, best_why);
    else
        snprintf(why, size, "decided by name (no default_state given): no state's words say it rests, so the first "
                 "by name (alphabetically) %s: '%s'; default_state or --default-state overrides",
                 best_rank == RANK_OTHER ? "of those that are no action done once" : "(every state is an action done once)",
                 an->states[best].name);
    return best;
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
