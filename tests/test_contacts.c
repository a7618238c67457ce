/* test_contacts.c - footstep contacts (the manifest's and info's `contacts`): on Cow, each
 * landing and lift agrees within two frames with the moments the foot's joint enters and leaves
 * the lowest 15% of its own lift, computed here from the independent reference joint matrices
 * (../shared/reference/Cow.fps30.csv) and the inverse bind matrices of the model file. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <math.h>

#define TMP TEST_TMP "/contacts"
enum { MAX_FRAMES = 128, MAX_CONTACTS = 32 };

typedef struct contact {
    char clip[128];
    uint32_t bone;
    double period, land, lift;
} contact;

/* The contacts `crowdbake info --json` gives Cow's clips, flattened by Python. */
static uint32_t info_contacts(const char *cow, contact *out)
{
    char cmd[4096], log[4096];
    snprintf(cmd, sizeof cmd,
             "mkdir -p %s && %s info %s --json > %s/info.json && python3 -c \"import json\n"
             "for c in json.load(open('%s/info.json'))['clips']:\n"
             "  for k in c.get('contacts', []): print(c['name'], k['bone'], c['period'], k['time'], k['lift'])\" > %s/contacts.txt",
             TMP, crowdbake_exe(), cow, TMP, TMP, TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    FILE *f = fopen(TMP "/contacts.txt", "r");
    assert_non_null(f);
    uint32_t n = 0;
    while (n < MAX_CONTACTS && fscanf(f, "%127s %u %lf %lf %lf", out[n].clip, &out[n].bone, &out[n].period, &out[n].land,
                                      &out[n].lift) == 5)
        ++n;
    fclose(f);
    return n;
}

/* The joint's world height at each reference frame of a clip (times from the clip's start). */
static uint32_t reference_heights(const char *csv, const char *clip, uint32_t joint, const double bind[3], double *t,
                                  double *h)
{
    FILE *f = fopen(csv, "r");
    assert_non_null(f);
    char line[4096], quoted[160];
    snprintf(quoted, sizeof quoted, ",\"%.140s\",", clip);
    uint32_t n = 0;
    double t0 = 0;
    while (fgets(line, sizeof line, f)) {
        char *at = strstr(line, quoted);
        if (line[0] == '#' || !at) continue;
        unsigned frame, frames, skin, j;
        double time, m[16];
        if (sscanf(at + strlen(quoted), "%u,%u,%lf,%u,%u,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &frame,
                   &frames, &time, &skin, &j, &m[0], &m[1], &m[2], &m[3], &m[4], &m[5], &m[6], &m[7], &m[8], &m[9], &m[10], &m[11],
                   &m[12], &m[13], &m[14], &m[15]) != 21 || j != joint || frame >= MAX_FRAMES)
            continue;
        if (frame == 0) t0 = time;
        t[frame] = time - t0;
        h[frame] = m[1] * bind[0] + m[5] * bind[1] + m[9] * bind[2] + m[13];
        if (frame + 1 > n) n = frame + 1;
    }
    fclose(f);
    return n;
}

/* The joint's position in bind space: the inverse bind matrix's inverse applied to the origin. */
static void bind_position(const double *ibm, double out[3])
{
    const double *a = ibm; /* column-major; upper 3x3 inverted by cofactors */
    double c[9] = {a[5] * a[10] - a[9] * a[6], a[9] * a[2] - a[1] * a[10], a[1] * a[6] - a[5] * a[2],
                   a[8] * a[6] - a[4] * a[10], a[0] * a[10] - a[8] * a[2], a[4] * a[2] - a[0] * a[6],
                   a[4] * a[9] - a[8] * a[5], a[8] * a[1] - a[0] * a[9], a[0] * a[5] - a[4] * a[1]};
    double det = a[0] * c[0] + a[4] * c[1] + a[8] * c[2];
    for (int r = 0; r < 3; ++r) /* inverse row r = c[r], c[3 + r], c[6 + r] (column-major cofactor layout) */
        out[r] = -(c[r] * a[12] + c[3 + r] * a[13] + c[6 + r] * a[14]) / det;
}

/* Shortest distance between two times on a cycle. */
static double cyclic(double a, double b, double period)
{
    double d = fmod(fabs(a - b), period);
    return fmin(d, period - d);
}

/* The nearest moment the heights cross the lowest 15% of their lift going down (land) or up. */
static double nearest_crossing(const double *t, const double *h, uint32_t n, double period, double at, bool down)
{
    double lo = INFINITY, hi = -INFINITY, best = INFINITY, best_t = NAN;
    for (uint32_t i = 0; i < n; ++i) lo = fmin(lo, h[i]), hi = fmax(hi, h[i]);
    double band = lo + 0.15 * (hi - lo);
    for (uint32_t i = 0; i < n; ++i) { /* the last frame wraps to the first: the loop's closing interval */
        uint32_t k = (i + 1) % n;
        double ta = t[i], tb = k ? t[k] : period, ha = h[i], hb = h[k];
        if (!(down ? ha > band && hb <= band : ha <= band && hb > band)) continue;
        double x = ta + (tb - ta) * (band - ha) / (hb - ha);
        if (cyclic(x, at, period) < best) best = cyclic(x, at, period), best_t = x;
    }
    return best_t;
}

static void test_contacts_follow_the_reference_feet(void **state)
{
    (void)state;
    char cow[1024], csv[1024];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    shared_path(csv, sizeof csv, "reference/Cow.fps30.csv");
    cb_model *m = load_or_fail(cow);
    contact cs[MAX_CONTACTS];
    uint32_t n = info_contacts(cow, cs), walk = 0, gallop = 0;
    assert_true(n >= 8);
    double worst = 0;
    for (uint32_t i = 0; i < n; ++i) {
        double bind[3], t[MAX_FRAMES], h[MAX_FRAMES];
        assert_true(cs[i].bone < m->skins[0].joint_count);
        bind_position(m->skins[0].inverse_bind + (size_t)cs[i].bone * 16, bind);
        uint32_t frames = reference_heights(csv, cs[i].clip, cs[i].bone, bind, t, h);
        /* A loop without a closing key (Gallop) ends a key step before its period: its last frame is
         * then not the first pose again, and the wrap runs from it to the period. */
        if (frames > 1 && fabs(t[frames - 1] - cs[i].period) < 1e-4) --frames;
        assert_true(frames >= 10);
        double land = nearest_crossing(t, h, frames, cs[i].period, cs[i].land, true);
        double lift = nearest_crossing(t, h, frames, cs[i].period, cs[i].lift, false);
        double dl = cyclic(land, cs[i].land, cs[i].period), du = cyclic(lift, cs[i].lift, cs[i].period);
        printf("  %-28s bone %2u lands %.3f s (reference %.3f), lifts %.3f s (reference %.3f)\n", cs[i].clip, cs[i].bone,
               cs[i].land, land, cs[i].lift, lift);
        assert_true(dl <= 2.0 / 30 && du <= 2.0 / 30); /* within two frames of the reference's 30 fps */
        worst = fmax(worst, fmax(dl, du));
        walk += strcmp(cs[i].clip, "AnimalArmature|Walk") == 0;
        gallop += strcmp(cs[i].clip, "AnimalArmature|Gallop") == 0;
    }
    printf("  worst %.1f ms\n", 1000 * worst);
    assert_int_equal(walk, 4); /* four hooves, one step each per cycle */
    assert_int_equal(gallop, 4);
    cb_model_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_contacts_follow_the_reference_feet),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
