/* test_sockets_contacts.c - what a game hangs on an animated instance, against Cow's independent
 * reference joint matrices (../shared/reference/Cow.fps30.csv) and the model file's own nodes:
 * footstep contacts (the manifest's and info's `contacts`), each landing and lift within two
 * frames of the moments the foot's joint enters and leaves the lowest 15% of its own lift; and
 * sockets (`sockets`), whose origin placed by the .pal reader (cbpal_bone_matrix x bind_transform)
 * is where the node's parent joint carries it. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <math.h>

#include "crowdbake_pal.h"

#define TMP TEST_TMP "/sockets_contacts"
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

/* The joint's reference matrix at each frame of a clip (times from the clip's start). */
static uint32_t reference_matrices(const char *csv, const char *clip, uint32_t joint, double *t, double (*mats)[16])
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
        memcpy(mats[frame], m, sizeof m);
        if (frame + 1 > n) n = frame + 1;
    }
    fclose(f);
    return n;
}

/* The point whose image under the affine matrix a (column-major) is q: the joint's bind position
 * for q = 0 and a its inverse bind matrix. */
static void solve_affine(const double *a, const double q[3], double out[3])
{
    double c[9] = {a[5] * a[10] - a[9] * a[6], a[9] * a[2] - a[1] * a[10], a[1] * a[6] - a[5] * a[2],
                   a[8] * a[6] - a[4] * a[10], a[0] * a[10] - a[8] * a[2], a[4] * a[2] - a[0] * a[6],
                   a[4] * a[9] - a[8] * a[5], a[8] * a[1] - a[0] * a[9], a[0] * a[5] - a[4] * a[1]};
    double det = a[0] * c[0] + a[4] * c[1] + a[8] * c[2];
    for (int r = 0; r < 3; ++r) /* inverse row r = c[r], c[3 + r], c[6 + r] (column-major cofactor layout) */
        out[r] = (c[r] * (q[0] - a[12]) + c[3 + r] * (q[1] - a[13]) + c[6 + r] * (q[2] - a[14])) / det;
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
        double bind[3], t[MAX_FRAMES], h[MAX_FRAMES], mats[MAX_FRAMES][16], origin[3] = {0, 0, 0};
        assert_true(cs[i].bone < m->skins[0].joint_count);
        solve_affine(m->skins[0].inverse_bind + (size_t)cs[i].bone * 16, origin, bind);
        uint32_t frames = reference_matrices(csv, cs[i].clip, cs[i].bone, t, mats);
        for (uint32_t f = 0; f < frames; ++f)
            h[f] = mats[f][1] * bind[0] + mats[f][5] * bind[1] + mats[f][9] * bind[2] + mats[f][13];
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

/* Cow's sockets as `crowdbake info --json` gives them: name, bone and the bind-space origin. */
typedef struct socket_row {
    char name[64];
    uint32_t bone;
    double origin[3];
} socket_row;

static uint32_t info_sockets(const char *cow, socket_row *out, uint32_t cap)
{
    char cmd[4096], log[4096];
    snprintf(cmd, sizeof cmd,
             "%s info %s --json | python3 -c \"import json, sys\n"
             "for k in json.load(sys.stdin)['sockets']: print(k['name'], k['bone'], *k['bind_transform'][12:15])\" > %s/sockets.txt",
             crowdbake_exe(), cow, TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    FILE *f = fopen(TMP "/sockets.txt", "r");
    assert_non_null(f);
    uint32_t n = 0;
    while (n < cap && fscanf(f, "%63s %u %lf %lf %lf", out[n].name, &out[n].bone, &out[n].origin[0], &out[n].origin[1],
                             &out[n].origin[2]) == 5)
        ++n;
    fclose(f);
    return n;
}

static void test_sockets_follow_their_joints(void **state)
{
    (void)state;
    char cow[1024], csv[1024], cmd[4096], log[4096], err[256];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    shared_path(csv, sizeof csv, "reference/Cow.fps30.csv");
    snprintf(cmd, sizeof cmd, "mkdir -p %s && %s bake %s -o %s/cow.pal -q --fps 30 --max-error 1000 2>&1", TMP, crowdbake_exe(),
             cow, TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    cbpal_file pal;
    if (cbpal_open(TMP "/cow.pal", 0, &pal, err, sizeof err)) fail_msg("%s", err);
    cb_model *m = load_or_fail(cow);
    socket_row sockets[32];
    uint32_t n = info_sockets(cow, sockets, 32);
    assert_int_equal(n, 14); /* Head_end, the legs' and the tail's tips */
    /* At the rows the encoding's error is all there is: the bake's max_error, with room for a tip off the mesh. */
    double worst = 0, bound = 2 * pal.header.max_error + 1e-4 * pal.header.model_height;
    uint32_t clips_compared = 0;
    for (uint32_t i = 0; i < n; ++i) {
        /* The reference: the node's own translation under its parent joint, J(t) IBM^-1 T. */
        const cb_node *node = NULL;
        for (uint32_t k = 0; k < m->node_count && !node; ++k)
            if (strcmp(m->nodes[k].name, sockets[i].name) == 0) node = &m->nodes[k];
        assert_non_null(node);
        assert_int_equal(node->parent, m->skins[0].joints[sockets[i].bone]);
        double local[3];
        solve_affine(m->skins[0].inverse_bind + (size_t)sockets[i].bone * 16, node->translation, local);
        for (uint32_t c = 0; c < pal.header.clip_count; ++c) {
            cbpal_clip clip;
            cbpal_get_clip(&pal, c, &clip);
            double t[MAX_FRAMES], mats[MAX_FRAMES][16];
            uint32_t frames = reference_matrices(csv, clip.name, sockets[i].bone, t, mats), at_rows = 0;
            for (uint32_t f = 0; f < frames; ++f) {
                /* The reference's frames that are rows (a loop given a wrap interval, or baked at 29.76 fps, has its
                 * frames between rows, in the blend). */
                if (fabs(t[f] * clip.fps - round(t[f] * clip.fps)) > 1e-3) continue;
                ++at_rows;
                float b[16];
                assert_int_equal(cbpal_bone_matrix(&pal, c, t[f], sockets[i].bone, b), 0);
                const double *o = sockets[i].origin, *r = mats[f];
                double d2 = 0;
                for (int k = 0; k < 3; ++k) {
                    double ours = b[12 + k] + b[k] * o[0] + b[4 + k] * o[1] + b[8 + k] * o[2];
                    double ref = r[12 + k] + r[k] * local[0] + r[4 + k] * local[1] + r[8 + k] * local[2];
                    d2 += (ours - ref) * (ours - ref);
                }
                worst = fmax(worst, sqrt(d2));
            }
            clips_compared += i == 0 && at_rows >= frames / 2;
        }
    }
    printf("  14 sockets, the reference frames at rows of %u clips: worst %.3g (%.3g mm/m), bound %.3g\n", clips_compared, worst,
           1000 * worst / pal.header.model_height, bound);
    assert_true(clips_compared >= 8);
    assert_true(worst <= bound);
    cb_model_free(m);
    cbpal_close(&pal);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_contacts_follow_the_reference_feet),
        cmocka_unit_test(test_sockets_follow_their_joints),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
