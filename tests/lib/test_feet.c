/* test_feet.c - every planted foot found, on two rigs of one animal pack (Cow; Husky, whose paws
 * are weighted partly to IK bones so the toes curl at lift-off), against an independent measure:
 * the reference joint matrices (../shared/reference, sampled by another
 * implementation) skinning the mesh's own vertices (Cow.fps30.csv, Husky.fps30.csv). Here a foot is the sole a quadruped stands
 * on: the vertices in the lowest 3% of the height of Idle's first pose, split into four by
 * which side and end of the body they stand at; it is planted while its vertices' mean height is
 * within 2% of the height of its lowest (the soles and the reference's reader: reference_soles.h). For each clip `crowdbake info --json` calls a stride:
 * each foot's stance fraction, its landings and lifts (within two frames at 30 fps) and its
 * speed backwards while planted (within 10%), and the ground speed from all four. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <math.h>

#include "reference_soles.h"

#define TMP TEST_TMP "/feet"
enum { MAX_ROWS = 64 };

/* Which sole carries the most weight on a joint. */
static int sole_of_bone(const cb_model *m, const ref_sole feet[4], uint32_t bone)
{
    int best = -1;
    double top = 0;
    for (int s = 0; s < 4; ++s) {
        double sum = 0;
        for (uint32_t i = 0; i < feet[s].count; ++i) {
            const cb_primitive *p = &m->primitives[feet[s].prim[i]];
            for (int k = 0; k < 4; ++k)
                if (p->joints[(size_t)feet[s].vertex[i] * 4 + k] == bone) sum += p->weights[(size_t)feet[s].vertex[i] * 4 + k];
        }
        if (sum > top) top = sum, best = s;
    }
    return best;
}

static double cyclic(double a, double b, double period)
{
    double d = fmod(fabs(a - b), period);
    return fmin(d, period - d);
}

/* What info says: per striding foot, "F clip bone stance step_speed period ground_speed", and per
 * stance "C clip bone land lift". */
typedef struct row {
    char kind, clip[128];
    uint32_t bone;
    double a, b, period, ground;
} row;

static uint32_t info_rows(const char *model, row *out)
{
    char cmd[4096], log[4096];
    snprintf(cmd, sizeof cmd,
             "mkdir -p %s && %s info %s --json > %s/info.json && python3 -c \"import json\n"
             "for c in json.load(open('%s/info.json'))['clips']:\n"
             "  if not c.get('stride'): continue\n"
             "  for k in c['foot_slide']['feet']: print('F', c['name'], k['bone'], k['stance'], k['step_speed'], c['period'], c['ground_speed'])\n"
             "  for k in c.get('contacts', []): print('C', c['name'], k['bone'], k['time'], k['lift'], c['period'], c['ground_speed'])\" > %s/rows.txt",
             TMP, crowdbake_exe(), model, TMP, TMP, TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    FILE *f = fopen(TMP "/rows.txt", "r");
    assert_non_null(f);
    uint32_t n = 0;
    while (n < MAX_ROWS && fscanf(f, " %c %127s %u %lf %lf %lf %lf", &out[n].kind, out[n].clip, &out[n].bone, &out[n].a, &out[n].b,
                                  &out[n].period, &out[n].ground) == 7)
        ++n;
    fclose(f);
    return n;
}

/* One foot over a clip, measured from the reference: heights and ground-plane positions per frame. */
typedef struct foot_track {
    uint32_t frames;
    double t[REF_MAX_FRAMES + 1], h[REF_MAX_FRAMES + 1], x[REF_MAX_FRAMES + 1], z[REF_MAX_FRAMES + 1], band;
} foot_track;

static void track_foot(const cb_model *m, const ref_sole *f, const ref_clip *ref, double period, double height, foot_track *tr)
{
    uint32_t n = ref->frames;
    /* A loop whose last frame is its first pose again (a closing key) ends there; one without a
     * closing key wraps from its last frame to the period. */
    if (n > 1 && fabs(ref->t[n - 1] - period) < 1e-4) --n;
    double lo = INFINITY, p[3];
    for (uint32_t i = 0; i < n; ++i) {
        ref_sole_at(m, f, (const double (*)[16])ref->m[i], p);
        tr->t[i] = ref->t[i], tr->h[i] = p[1], tr->x[i] = p[0], tr->z[i] = p[2], lo = fmin(lo, p[1]);
    }
    tr->t[n] = period, tr->h[n] = tr->h[0], tr->x[n] = tr->x[0], tr->z[n] = tr->z[0];
    tr->frames = n;
    tr->band = lo + 0.02 * height;
}

/* The crossing of the band nearest `at`, going down (a landing) or up (a lift). */
static double nearest_crossing(const foot_track *tr, double period, double at, bool down)
{
    double best = INFINITY, best_t = NAN;
    for (uint32_t i = 0; i < tr->frames; ++i) {
        double ha = tr->h[i], hb = tr->h[i + 1];
        if (!(down ? ha > tr->band && hb <= tr->band : ha <= tr->band && hb > tr->band)) continue;
        double x = tr->t[i] + (tr->t[i + 1] - tr->t[i]) * (tr->band - ha) / (hb - ha);
        if (cyclic(x, at, period) < best) best = cyclic(x, at, period), best_t = x;
    }
    return best_t;
}

/* The fraction of the cycle planted and the speed backwards while planted: an interval the band
 * crosses counts for its planted part (the heights and positions linear between frames). */
static void stance_of(const foot_track *tr, double period, double *fraction, double *speed)
{
    double time = 0, dx = 0, dz = 0;
    for (uint32_t i = 0; i < tr->frames; ++i) {
        double ha = tr->h[i], hb = tr->h[i + 1], part;
        if (ha <= tr->band && hb <= tr->band) part = 1;
        else if (ha > tr->band && hb > tr->band) part = 0;
        else part = ha <= tr->band ? (tr->band - ha) / (hb - ha) : (hb - tr->band) / (hb - ha);
        time += part * (tr->t[i + 1] - tr->t[i]);
        dx += part * (tr->x[i + 1] - tr->x[i]), dz += part * (tr->z[i + 1] - tr->z[i]);
    }
    *fraction = time / period;
    *speed = time > 0 ? hypot(dx, dz) / time : 0;
}

static void check_model(const char *asset, const char *reference, uint32_t *walk_feet, uint32_t *gallop_feet)
{
    char model[1024], csv[1024];
    shared_path(model, sizeof model, asset);
    shared_path(csv, sizeof csv, reference);
    cb_model *m = load_or_fail(model);
    ref_clip ref = {.m = calloc(REF_MAX_FRAMES, sizeof *ref.m)};
    assert_non_null(ref.m);
    ref_read_clip(csv, "AnimalArmature|Idle", &ref);
    assert_true(ref.frames > 0 && ref.bones == m->skins[0].joint_count);
    ref_sole feet[4];
    double height = ref_find_soles(m, (const double (*)[16])ref.m[0], feet);
    for (int s = 0; s < 4; ++s) assert_true(feet[s].count >= 4);
    static row rows[MAX_ROWS];
    uint32_t n = info_rows(model, rows);
    char clip[128] = "";
    double speed_sum = 0, stance_sum = 0, worst_time = 0, worst_speed = 0, worst_stance = 0;
    uint32_t speeds = 0;
    for (uint32_t i = 0; i <= n; ++i) {
        if (i == n || strcmp(rows[i].clip, clip) != 0) { /* a clip's ground speed: from all its feet */
            if (speeds) {
                /* The speed that slides least over every planted moment: near the feet's mean weighted by how
                 * long each is planted (not the speed of two of them). */
                double mean = speed_sum / stance_sum;
                printf("  %-28s ground speed %.3f, its feet's mean %.3f (reference)\n", clip, rows[i - 1].ground, mean);
                assert_true(fabs(rows[i - 1].ground / mean - 1) <= 0.15);
            }
            if (i == n) break;
            snprintf(clip, sizeof clip, "%s", rows[i].clip);
            ref_read_clip(csv, clip, &ref);
            speed_sum = stance_sum = 0, speeds = 0;
        }
        int s = sole_of_bone(m, feet, rows[i].bone);
        assert_true(s >= 0);
        foot_track tr;
        track_foot(m, &feet[s], &ref, rows[i].period, height, &tr);
        assert_true(tr.frames >= 10);
        if (rows[i].kind == 'F') {
            double fraction, speed;
            stance_of(&tr, rows[i].period, &fraction, &speed);
            printf("  %-28s %-16s planted %.0f%% (reference %.0f%%), steps back at %.3f units/s (reference %.3f)\n", clip,
                   m->nodes[m->skins[0].joints[rows[i].bone]].name, 100 * rows[i].a, 100 * fraction, rows[i].b, speed);
            /* The reference's stance is counted in whole 30 fps frames: two frames of the cycle either way. */
            assert_true(fabs(rows[i].a - fraction) <= 2.0 / 30 / rows[i].period);
            assert_true(fabs(rows[i].b / speed - 1) <= 0.10);
            worst_stance = fmax(worst_stance, fabs(rows[i].a - fraction));
            worst_speed = fmax(worst_speed, fabs(rows[i].b / speed - 1));
            speed_sum += fraction * speed, stance_sum += fraction, ++speeds;
            *walk_feet += strstr(clip, "|Walk") != NULL;
            *gallop_feet += strstr(clip, "|Gallop") != NULL && !strstr(clip, "Jump");
        } else {
            double land = nearest_crossing(&tr, rows[i].period, rows[i].a, true);
            double lift = nearest_crossing(&tr, rows[i].period, rows[i].b, false);
            double dl = cyclic(land, rows[i].a, rows[i].period), du = cyclic(lift, rows[i].b, rows[i].period);
            printf("  %-28s bone %2u lands %.3f s (reference %.3f), lifts %.3f s (reference %.3f)\n", clip, rows[i].bone, rows[i].a,
                   land, rows[i].b, lift);
            assert_true(dl <= 2.0 / 30 && du <= 2.0 / 30);
            worst_time = fmax(worst_time, fmax(dl, du));
        }
    }
    printf("  %s: worst stance %.1f%% of the cycle, step speed %.1f%%, land/lift %.1f ms\n", asset, 100 * worst_stance,
           100 * worst_speed, 1000 * worst_time);
    free(ref.m);
    cb_model_free(m);
}

static void test_husky_every_paw_planted(void **state)
{
    (void)state;
    uint32_t walk = 0, gallop = 0;
    check_model("assets/quaternius-husky/Husky.glb", "reference/Husky.fps30.csv", &walk, &gallop);
    assert_int_equal(walk, 4); /* the front paws too (their toes curl as they lift) */
    assert_int_equal(gallop, 4);
}

static void test_cow_every_hoof_planted(void **state)
{
    (void)state;
    uint32_t walk = 0, gallop = 0;
    check_model("assets/quaternius-cow/Cow.glb", "reference/Cow.fps30.csv", &walk, &gallop);
    assert_int_equal(walk, 4);
    assert_int_equal(gallop, 4);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_husky_every_paw_planted),
        cmocka_unit_test(test_cow_every_hoof_planted),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
