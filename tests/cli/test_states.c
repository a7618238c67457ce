/* test_states.c - what a herd's states play (issue 33): the states in the order the catalog
 * writes them and the default state decided by name (never by that order); which states follow the instance's speed,
 * decided from their words and their clips' feet and said why, and overridden in the catalog and
 * on the command line; the speed reference taken from locomotion only; and the planted feet's
 * slide, checked against the feet's own heights and speeds in the independent reference
 * matrices of Cow (../shared/reference/Cow.fps30.csv). */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <math.h>

#include "catalog/catalog_toml.h"
#include "roster/roster.h"

#define TMP TEST_TMP "/states"
#define COW "assets/quaternius-cow/Cow.glb"

/* The catalog: every state of the Cow's pack, written in this order. */
#define COW_STATES                                                                                                     \
    "states = { idle = [\"idle\"], eat = [\"eating\"], attack = [\"attack\"], hit = [\"hitreact\"], "                  \
    "wander = [\"walk\"], flee = [\"gallop\"], die = [\"death\"] }\n"

static char cow_abs[PATH_MAX];

static int setup(void **state)
{
    (void)state;
    char rel[1024];
    snprintf(rel, sizeof rel, "%s/%s", shared_dir(), COW);
    if (!realpath(rel, cow_abs)) return -1;
    return system("rm -rf " TMP " && mkdir -p " TMP);
}

/* Writes TMP/NAME.toml: a cow with `animal` lines (states, overrides) baking to TMP/NAME. */
static const char *cow_catalog(const char *name, const char *animal)
{
    static char path[PATH_MAX];
    static char text[8192];
    snprintf(text, sizeof text, "[bake]\nout_dir = \"%s\"\nfps = 30\n\n[animal.cow]\nmodel = \"%s\"\n%s", name, cow_abs, animal);
    snprintf(path, sizeof path, TMP "/%s.toml", name);
    write_text(path, text);
    return path;
}

static void bake_or_fail(const char *path, cb_catalog *cat, cb_roster *r)
{
    cb_error err = {0};
    if (cb_catalog_load(path, cat, &err)) fail_msg("%s", err.message);
    cb_roster_options opt = {0};
    opt.jobs = 1;
    if (cb_roster_bake(cat, &opt, r, &err)) fail_msg("%s", err.message);
}

static int state_index(const cb_catalog_animal *an, const char *name)
{
    for (uint32_t s = 0; s < an->state_count; ++s)
        if (strcmp(an->states[s].name, name) == 0) return (int)s;
    fail_msg("no state '%s'", name);
    return -1;
}

/* ---- the order of the states ---- */

static void test_states_keep_the_written_order(void **state)
{
    (void)state;
    /* Neither alphabetical nor reverse-alphabetical: toml++ keeps its keys sorted. */
    cb_catalog cat;
    cb_roster r;
    bake_or_fail(cow_catalog("order", "states = { wander = [\"walk\"], idle = [\"idle\"], flee = [\"gallop\"], "
                                      "attack = [\"attack\"] }\n"),
                 &cat, &r);
    const cb_catalog_animal *an = &cat.animals[0];
    const char *written[] = {"wander", "idle", "flee", "attack"};
    assert_int_equal(an->state_count, 4);
    for (int i = 0; i < 4; ++i) assert_string_equal(an->states[i].name, written[i]);
    /* No default_state given: decided by name (the state that rests), never by the order written. */
    assert_string_equal(an->default_state, "idle");
    printf("  default state: %s (%s)\n", an->default_state, an->default_state_from);
    assert_non_null(strstr(an->default_state_from, "decided by name"));
    assert_non_null(strstr(an->default_state_from, "'idle' rests, its name says 'idle'"));
    assert_non_null(strstr(an->default_state_from, "default_state or --default-state overrides"));
    /* The manifest lists them in that order too. */
    char *json = read_whole_file(TMP "/order/roster.json", NULL);
    const char *states = strstr(json, "\"states\": {");
    assert_non_null(states);
    const char *at[4];
    for (int i = 0; i < 4; ++i) {
        char key[32];
        snprintf(key, sizeof key, "\"%s\": {", written[i]);
        assert_non_null(at[i] = strstr(states, key));
        if (i) assert_true(at[i - 1] < at[i]);
    }
    free(json);
    cb_roster_free(&r);
    cb_catalog_free(&cat);

    /* A [animal.NAME.states] table, a line per state: the same rule. */
    bake_or_fail(cow_catalog("order_table", "[animal.cow.states]\nhit = [\"hitreact\"]\neat = [\"eating\"]\nidle = [\"idle\"]\n"),
                 &cat, &r);
    assert_string_equal(cat.animals[0].states[0].name, "hit");
    assert_string_equal(cat.animals[0].states[2].name, "idle");
    assert_string_equal(cat.animals[0].default_state, "idle");
    cb_roster_free(&r);
    cb_catalog_free(&cat);
}

/* The default state by name, whatever the order: a resting word in a keyword counts (graze =
 * ["eating"]); with none, the first by name of the states that are no action done once. */
static void test_default_state_by_name(void **state)
{
    (void)state;
    cb_catalog cat;
    cb_error err = {0};
    if (cb_catalog_load(cow_catalog("default_kw", "states = { attack = [\"attack\"], wander = [\"walk\"], "
                                                  "graze = [\"eating\"] }\n"), &cat, &err))
        fail_msg("%s", err.message);
    assert_string_equal(cat.animals[0].default_state, "graze");
    assert_non_null(strstr(cat.animals[0].default_state_from, "its name says 'graze'"));
    cb_catalog_free(&cat);
    if (cb_catalog_load(cow_catalog("default_none", "states = { wander = [\"walk\"], attack = [\"attack\"], "
                                                    "flee = [\"gallop\"] }\n"), &cat, &err))
        fail_msg("%s", err.message);
    assert_string_equal(cat.animals[0].default_state, "flee"); /* wander is written first */
    printf("  %s\n", cat.animals[0].default_state_from);
    assert_non_null(strstr(cat.animals[0].default_state_from, "alphabetically"));
    cb_catalog_free(&cat);
    /* An action done once never rests, though a keyword says 'idle'; a resting name beats a
     * resting keyword, whatever the names' order. */
    if (cb_catalog_load(cow_catalog("default_hit", "states = { hit = [\"Idle_HitReact_Left\"], eat = [\"Eating\"], "
                                                   "idle = [\"Idle\"], graze = [\"eating\"] }\n"), &cat, &err))
        fail_msg("%s", err.message);
    assert_string_equal(cat.animals[0].default_state, "idle");
    cb_catalog_free(&cat);
    if (cb_catalog_load(cow_catalog("default_kw2", "states = { a = [\"Idle_HitReact_Left\"], b = [\"Eating\"] }\n"),
                        &cat, &err))
        fail_msg("%s", err.message);
    assert_string_equal(cat.animals[0].default_state, "b");
    assert_non_null(strstr(cat.animals[0].default_state_from, "its keyword 'Eating' says 'eating'"));
    cb_catalog_free(&cat);
    /* The catalog's default_state still wins. */
    if (cb_catalog_load(cow_catalog("default_given", "states = { idle = [\"idle\"], wander = [\"walk\"] }\n"
                                                     "default_state = \"wander\"\n"), &cat, &err))
        fail_msg("%s", err.message);
    assert_string_equal(cat.animals[0].default_state, "wander");
    assert_string_equal(cat.animals[0].default_state_from, "the catalog's default_state");
    cb_catalog_free(&cat);
}

/* ---- the whole Cow pack: what follows the speed, and the speed reference ---- */

static void test_cow_every_state(void **state)
{
    (void)state;
    cb_catalog cat;
    cb_roster r;
    bake_or_fail(cow_catalog("cow", COW_STATES), &cat, &r);
    const cb_catalog_animal *an = &cat.animals[0];
    const cb_roster_type *t = &r.types[0];
    assert_string_equal(an->default_state, "idle");
    const char *in_place[] = {"idle", "eat", "attack", "hit", "die"}, *moving[] = {"wander", "flee"};
    for (int i = 0; i < 5; ++i) {
        const cb_sync_decision *d = &t->state_sync[state_index(an, in_place[i])];
        printf("  %-7s own rate: %s\n", in_place[i], d->reason);
        assert_false(d->speed);
    }
    for (int i = 0; i < 2; ++i) {
        int s = state_index(an, moving[i]);
        const cb_sync_decision *d = &t->state_sync[s];
        printf("  %-7s follows the speed: %s\n", moving[i], d->reason);
        assert_true(d->speed);
        assert_true(t->clips[t->state_clip[s]].speed.stride.stride);
    }
    /* Attack_Headbutt's feet shuffle: once it was taken for locomotion, and the speed reference
     * with it. The reference is now the walk's own ground speed. */
    const cb_roster_clip *walk = &t->clips[t->state_clip[state_index(an, "wander")]];
    assert_string_equal(walk->name, "AnimalArmature|Walk");
    assert_float_equal(t->speed_reference, walk->speed.speed, 0);
    assert_non_null(strstr(t->speed_reference_from, "'wander'"));
    /* The manifest: rate_per_speed only for the two gaits, each at its own ground speed, and
     * every state says why. */
    static char out[8192];
    static char cmd[8192];
    snprintf(cmd, sizeof cmd,
             "python3 -c \"import json; t = json.load(open('%s/cow/roster.json'))['types']['cow']; "
             "c = {x['name']: x for x in t['clips']}; "
             "[print(k, s['sync'], round(s['instance']['rate_per_speed'] * c[s['clip']]['ground_speed'] / c[s['clip']]['fps'], 6), "
             "len(s['sync_reason']) > 20) for k, s in t['states'].items()]; print(t['default_state'])\"",
             TMP);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    assert_string_equal(out, "idle time 0.0 True\neat time 0.0 True\nattack time 0.0 True\nhit time 0.0 True\n"
                             "wander speed 1.0 True\nflee speed 1.0 True\ndie time 0.0 True\nidle\n");
    cb_roster_free(&r);
    cb_catalog_free(&cat);
}

/* ---- the words ---- */

static cb_ground_speed moving_speed(bool stride, double speed, const char *method)
{
    cb_ground_speed gs;
    memset(&gs, 0, sizeof gs);
    gs.stride.stride = stride;
    snprintf(gs.stride.why, sizeof gs.stride.why, "%s", stride ? "4 of 4 feet planted" : "no foot lifts");
    gs.speed = speed;
    gs.method = method;
    return gs;
}

static bool decide(const char *state, const char *keyword, const char *clip, bool loops, const cb_ground_speed *gs,
                   bool speed_given, cb_sync_mode mode, const char *reason_part)
{
    const char *keywords[] = {keyword};
    cb_catalog_state st = {state, keywords, 1, mode, false, {0, 0}};
    cb_sync_decision d;
    cb_decide_sync(state ? &st : NULL, clip, loops, gs, speed_given, &d);
    if (reason_part && !strstr(d.reason, reason_part)) fail_msg("%s/%s: '%s' lacks '%s'", state, clip, d.reason, reason_part);
    return d.speed;
}

static void test_sync_from_words_then_feet(void **state)
{
    (void)state;
    cb_ground_speed striding = moving_speed(true, 2.4, "planted feet"), still = moving_speed(false, 0, "none");
    cb_ground_speed travelling = moving_speed(false, 1.2, "root motion");
    /* Words that name an action in place win over feet that step. */
    assert_false(decide("hit", "hitreact", "AnimalArmature|Idle_HitReact_Left", true, &striding, false, CB_SYNC_AUTO,
                        "the state's name 'hit' says 'hit'"));
    assert_false(decide(NULL, NULL, "AnimalArmature|Attack_Headbutt", true, &striding, false, CB_SYNC_AUTO,
                        "its feet stride, but the words decide"));
    /* The state's name before its keywords before the clip's name. */
    assert_false(decide("graze", "walk", "Walk", true, &striding, false, CB_SYNC_AUTO, "'graze'"));
    assert_true(decide("x", "run", "Idle", true, &striding, false, CB_SYNC_AUTO, "its keyword 'run' says 'run'"));
    /* Word forms: endings and doubled consonants; a word is matched whole, not inside another. */
    assert_true(decide(NULL, NULL, "Robot_Running", true, &striding, false, CB_SYNC_AUTO, "'running'"));
    assert_true(decide(NULL, NULL, "trotted", true, &striding, false, CB_SYNC_AUTO, "'trotted'"));
    assert_true(decide(NULL, NULL, "Gallop_Jump", true, &striding, false, CB_SYNC_AUTO, "'gallop'"));
    assert_true(decide(NULL, NULL, "Notice", true, &striding, false, CB_SYNC_AUTO, "no word decides")); /* not 'no' */
    assert_true(decide(NULL, NULL, "Runestone", true, &striding, false, CB_SYNC_AUTO, "no word decides")); /* not 'run' */
    /* Locomotion needs a speed: a stride, root travel or the animal's speed_reference. */
    assert_true(decide("swim", "swim", "swim", true, &travelling, false, CB_SYNC_AUTO, "its root travels"));
    assert_false(decide("swim", "swim", "swim", true, &still, false, CB_SYNC_AUTO, "give the animal a speed_reference"));
    assert_true(decide("swim", "swim", "swim", true, &still, true, CB_SYNC_AUTO, "speed_reference"));
    /* No word: the feet decide. */
    assert_true(decide("state_3", "anim_3", "anim_3", true, &striding, false, CB_SYNC_AUTO, "no word decides, and 4 of 4"));
    assert_false(decide("state_3", "anim_3", "anim_3", true, &still, false, CB_SYNC_AUTO, "no foot lifts"));
    /* A one-shot plays once at its own rate, whatever it is called; the catalog overrides all. */
    assert_false(decide("flee", "run", "Run", false, &striding, false, CB_SYNC_AUTO, "a one-shot"));
    assert_true(decide("idle", "idle", "Idle", true, &still, false, CB_SYNC_SPEED, "the catalog says sync = \"speed\""));
    assert_false(decide("wander", "walk", "Walk", true, &striding, false, CB_SYNC_TIME, "sync = \"time\""));
}

/* ---- overrides: the catalog's sync, the command line's --sync and --default-state ---- */

static void test_sync_overrides(void **state)
{
    (void)state;
    cb_catalog cat;
    cb_roster r;
    bake_or_fail(cow_catalog("forced", "states = { idle = [\"idle\"], attack = { keywords = [\"attack\"], sync = \"speed\" }, "
                                       "wander = { keywords = [\"walk\"], sync = \"time\" }, flee = [\"gallop\"] }\n"),
                 &cat, &r);
    const cb_catalog_animal *an = &cat.animals[0];
    const cb_roster_type *t = &r.types[0];
    assert_true(t->state_sync[state_index(an, "attack")].speed);
    assert_string_equal(t->state_sync[state_index(an, "attack")].reason, "the catalog says sync = \"speed\"");
    assert_false(t->state_sync[state_index(an, "wander")].speed);
    /* With the walk out, the gallop is the only gait that measures a speed: the reference. */
    const cb_roster_clip *gallop = &t->clips[t->state_clip[state_index(an, "flee")]];
    assert_float_equal(t->speed_reference, gallop->speed.speed, 0);
    cb_roster_free(&r);
    cb_catalog_free(&cat);

    /* No gait at all: no speed reference, and it says so. */
    bake_or_fail(cow_catalog("still", "states = { idle = [\"idle\"], eat = [\"eating\"] }\n"), &cat, &r);
    assert_float_equal(r.types[0].speed_reference, 0, 0);
    assert_non_null(strstr(r.types[0].speed_reference_from, "none: no state is locomotion"));
    cb_roster_free(&r);
    cb_catalog_free(&cat);

    /* Forced to follow a speed nothing gives: refused, naming the state's line and the fix. */
    cb_error err = {0};
    assert_int_equal(cb_catalog_load(cow_catalog("nospeed", "states = { idle = { keywords = [\"idle\"], sync = \"speed\" } }\n"),
                                     &cat, &err),
                     CB_OK);
    cb_roster_options opt = {0};
    opt.jobs = 1;
    assert_int_not_equal(cb_roster_bake(&cat, &opt, &r, &err), CB_OK);
    if (!strstr(err.message, "nospeed.toml:7:") || !strstr(err.message, "state 'idle' follows the speed") ||
        !strstr(err.message, "speed_reference = UNITS_PER_S"))
        fail_msg("%s", err.message);
    cb_roster_free(&r);
    cb_catalog_free(&cat);

    /* A sync that is not a mode: the catalog's line. */
    memset(&err, 0, sizeof err);
    assert_int_equal(cb_catalog_load(cow_catalog("badsync", "states = { idle = { keywords = [\"idle\"], sync = \"fast\" } }\n"),
                                     &cat, &err),
                     CB_ERR_INPUT);
    if (!strstr(err.message, "badsync.toml:7:") || !strstr(err.message, "sync must be \"speed\"")) fail_msg("%s", err.message);

    /* The command line, over the catalog. */
    static char cmd[8192];
    static char out[16384];
    snprintf(cmd, sizeof cmd,
             "%s bake %s -q --sync attack=speed,wander=time --default-state flee 2>&1 && python3 -c \"import json; "
             "t = json.load(open('" TMP "/cmdline/roster.json'))['types']['cow']; s = t['states']; "
             "print(t['default_state'], t['default_state_from'], s['attack']['sync'], s['wander']['sync'], "
             "s['attack']['sync_reason'])\"",
             crowdbake_exe(), cow_catalog("cmdline", COW_STATES));
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    if (!strstr(out, "flee the command line (--default-state) speed time the command line says --sync attack=speed"))
        fail_msg("%s", out);
    snprintf(cmd, sizeof cmd, "%s bake %s -q --sync atack=speed 2>&1", crowdbake_exe(), cow_catalog("cmdline", COW_STATES));
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_USAGE);
    assert_non_null(strstr(out, "no animal has a state 'atack' [--sync]"));
}

/* ---- the feet, against the reference matrices ---- */

static void test_cow_walk_feet_disagree(void **state)
{
    (void)state;
    cb_catalog cat;
    cb_roster r;
    bake_or_fail(cow_catalog("feet", COW_STATES), &cat, &r);
    const cb_roster_type *t = &r.types[0];
    const cb_roster_clip *walk = &t->clips[t->state_clip[state_index(&cat.animals[0], "wander")]];
    const cb_stride *st = &walk->speed.stride;
    /* crowdbake's feet: the four hooves, named by the foot bones that move them (each foot's stance
     * and step speed against the reference matrices: test_feet). */
    assert_true(st->stride && st->foot_count == 4);
    double fmax_ = 0, hmin = INFINITY;
    for (int k = 0; k < 4; ++k) {
        bool front = strncmp(st->feet[k].name, "FF.", 3) == 0;
        assert_true(front || strncmp(st->feet[k].name, "FFB.", 4) == 0);
        if (front) fmax_ = fmax(fmax_, st->feet[k].step_speed);
        else hmin = fmin(hmin, st->feet[k].step_speed);
    }
    /* Front and hind feet disagree by over a quarter: no single speed plants them all. */
    printf("  front feet %.3f, hind feet %.3f units/s; crowdbake's ground speed %.3f\n", fmax_, hmin, walk->speed.speed);
    assert_true(hmin > 1.25 * fmax_);
    /* The speed with the least slide lies between them (not the hind feet's, as it once was). */
    assert_true(walk->speed.speed > fmax_ && walk->speed.speed < hmin);
    assert_true(st->slide_mean > CB_SLIDE_WARN); /* so the bake warns */
    bool warned = false;
    for (uint32_t i = 0; i < t->warnings.count; ++i)
        warned |= strstr(t->warnings.items[i].message, "clip 'AnimalArmature|Walk': its planted feet slide") != NULL;
    assert_true(warned);
    cb_roster_free(&r);
    cb_catalog_free(&cat);
}

/* An attack made a loop (Attack_Kick, whose feet step back as it rears) is no stride: no contacts,
 * no ground speed from its feet (issue 45). And a stride's reason quotes the striding feet's
 * ranges, the numbers in its foot_slide (a shuffling foot left out is not among them). */
static void test_attack_kick_is_no_stride(void **state)
{
    (void)state;
    cb_catalog cat;
    cb_roster r;
    bake_or_fail(cow_catalog("kick", "clips = [{ source = \"AnimalArmature|Attack_Kick\", loop = true }, \"AnimalArmature|Walk\"]\n"
                                     "states = { attack = [\"kick\"], wander = [\"walk\"] }\n"),
                 &cat, &r);
    const cb_roster_type *t = &r.types[0];
    const cb_stride *kick = &t->clips[0].speed.stride, *walk = &t->clips[1].speed.stride;
    printf("  Attack_Kick (a loop): %s\n  Walk: %s\n", kick->why, walk->why);
    assert_true(t->clips[0].loops && !kick->stride);
    assert_non_null(strstr(kick->why, "the clip's name says 'attack'"));
    for (uint32_t k = 0; k < kick->foot_count; ++k) assert_int_equal(kick->feet[k].stance_count, 0); /* no contacts */
    double lo = INFINITY, hi = 0;
    for (uint32_t k = 0; k < walk->foot_count; ++k)
        if (walk->feet[k].strides) lo = fmin(lo, walk->feet[k].step_speed), hi = fmax(hi, walk->feet[k].step_speed);
    char range[64];
    snprintf(range, sizeof range, "at %.3g-%.3g units/s", lo, hi);
    assert_non_null(strstr(walk->why, range));
    cb_roster_free(&r);
    cb_catalog_free(&cat);
}

/* ---- info and report say it ---- */

static void test_info_and_report_say_why(void **state)
{
    (void)state;
    static char out[131072];
    static char cmd[8192];
    snprintf(cmd, sizeof cmd, "%s info %s", crowdbake_exe(), cow_abs);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    if (!strstr(out, "follows the speed: locomotion: the clip's name says 'walk', and 4 of 4 feet planted") ||
        !strstr(out, "own rate: in place: the clip's name says 'eating'") || /* the attacks play once now */
        !strstr(out, "own rate: in place: the clip's name says 'idle'") ||
        !strstr(out, "own rate: a one-shot") || !strstr(out, "feet slide 53% of the ground speed"))
        fail_msg("%s", out);
    snprintf(cmd, sizeof cmd,
             "%s info %s --json | python3 -c \"import json, sys; c = {x['name']: x for x in json.load(sys.stdin)['clips']}; "
             "w = c['AnimalArmature|Walk']; print(w['sync'], len(w['foot_slide']['feet']), c['AnimalArmature|Eating']['sync'])\"",
             crowdbake_exe(), cow_abs);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    assert_string_equal(out, "speed 4 time\n");
    snprintf(cmd, sizeof cmd,
             "%s report %s --json | python3 -c \"import json, sys; g = json.load(sys.stdin)['types'][0]['gaits']; "
             "print([(x['state'], x['feet_slide_at_any_rate'], x['row_travel']) for x in g])\"",
             crowdbake_exe(), cow_catalog("report", COW_STATES));
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    /* The gallop's per-row travel leaves 12% of its 35%: a herd's feet slide at any rate only on the walk. */
    assert_string_equal(out, "[('wander', True, False), ('flee', False, True)]\n");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_states_keep_the_written_order),
        cmocka_unit_test(test_default_state_by_name),
        cmocka_unit_test(test_cow_every_state),
        cmocka_unit_test(test_sync_from_words_then_feet),
        cmocka_unit_test(test_sync_overrides),
        cmocka_unit_test(test_cow_walk_feet_disagree),
        cmocka_unit_test(test_attack_kick_is_no_stride),
        cmocka_unit_test(test_info_and_report_say_why),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
