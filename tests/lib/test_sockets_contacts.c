/* test_sockets_contacts.c - what a game hangs on an animated instance, against Cow's independent
 * reference joint matrices (../shared/reference/Cow.fps30.csv) and the model file's own nodes:
 * sockets (`sockets`), whose origin placed by the .pal reader (cbpal_bone_matrix x bind_transform)
 * is where the node's parent joint carries it, and the rig helpers (IK pole targets) that are not
 * sockets. The footstep contacts are test_feet's. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <ctype.h>
#include <math.h>
#include <strings.h>

#include "crowdbake_pal.h"
#include "crowdbake/stride.h"
#include "reference_soles.h"

#define TMP TEST_TMP "/sockets_contacts"
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

/* The deviation a loop closed over its key span reports (mm/m), 0 for any other clip. */
static double loop_correction(const cb_model *m, const char *clip)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_clip_info info = {0};
    int32_t a = cb_model_find_animation(m, clip);
    assert_true(s && a >= 0 && cb_clip_analyze(s, a, 30, -1, NULL, &info, &err) == CB_OK);
    cb_sampler_free(s);
    return info.loop_correction_mm_per_m;
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
    assert_int_equal(n, 10); /* Head_end, the legs' and the tail's tips; not the 4 pole targets */
    /* At the rows the encoding's error is all there is: the bake's max_error, with room for a tip off the mesh. */
    double worst = 0, bound = 2 * pal.header.max_error + 1e-4 * pal.header.model_height;
    uint32_t clips_compared = 0;
    ref_clip ref = {.m = calloc(REF_MAX_FRAMES, sizeof *ref.m)}; /* every joint's reference matrices over a clip */
    assert_non_null(ref.m);
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
            /* A loop closed over its key span (Gallop_Jump) moves off the source by what it reports. */
            double closing = loop_correction(m, clip.name) / 1000 * pal.header.model_height;
            ref_read_clip(csv, clip.name, &ref);
            uint32_t at_rows = 0;
            for (uint32_t f = 0; f < ref.frames; ++f) {
                /* The reference's frames that are rows (a loop given a wrap interval, or baked at 29.76 fps, has its
                 * frames between rows, in the blend). */
                if (fabs(ref.t[f] * clip.fps - round(ref.t[f] * clip.fps)) > 1e-3) continue;
                ++at_rows;
                float b[16];
                assert_int_equal(cbpal_bone_matrix(&pal, c, ref.t[f], sockets[i].bone, b), 0);
                const double *o = sockets[i].origin, *r = ref.m[f][sockets[i].bone];
                double d2 = 0;
                for (int k = 0; k < 3; ++k) {
                    double ours = b[12 + k] + b[k] * o[0] + b[4 + k] * o[1] + b[8 + k] * o[2];
                    double ref = r[12 + k] + r[k] * local[0] + r[4 + k] * local[1] + r[8 + k] * local[2];
                    d2 += (ours - ref) * (ours - ref);
                }
                worst = fmax(worst, sqrt(d2) - closing);
            }
            clips_compared += i == 0 && at_rows >= ref.frames / 2;
        }
    }
    printf("  10 sockets, the reference frames at rows of %u clips: worst %.3g (%.3g mm/m; beyond a closed loop's reported "
           "deviation), bound %.3g\n", clips_compared, worst,
           1000 * worst / pal.header.model_height, bound);
    assert_true(clips_compared >= 8);
    assert_true(worst <= bound);
    free(ref.m);
    cb_model_free(m);
    cbpal_close(&pal);
}

/* An IK pole target's tip (PoleTarget.L_end) is where a solver aims a knee, not a place for a prop:
 * Husky's 4 are left out of the sockets, and info says why. */
static void test_pole_targets_are_not_sockets(void **state)
{
    (void)state;
    char husky[1024], cmd[4096], log[8192];
    shared_path(husky, sizeof husky, "assets/quaternius-husky/Husky.glb");
    snprintf(cmd, sizeof cmd, "mkdir -p %s", TMP);
    assert_int_equal(run_command(cmd, log, sizeof log), 0);
    socket_row sockets[32];
    uint32_t n = info_sockets(husky, sockets, 32);
    for (uint32_t i = 0; i < n; ++i) assert_null(strstr(sockets[i].name, "PoleTarget"));
    assert_int_equal(n, 12); /* head, ears, 4 lower legs, tail, 4 feet */
    snprintf(cmd, sizeof cmd, "%s info %s | grep 'not sockets'", crowdbake_exe(), husky);
    assert_int_equal(run_command(cmd, log, sizeof log), 0);
    assert_non_null(strstr(log, "PoleTargetBack.L_end PoleTarget.L_end PoleTargetBack.R_end PoleTarget.R_end"));
}

/* Whether a joint's name reads as a rig control, by this test's own reading (not the library's):
 * an IK bone ("IKBackLeg.L", "Leg_IK", "foot.ik"), a pole or a target, a "ctrl". */
static bool named_as_control(const char *name)
{
    for (size_t i = 0; name[i]; ++i) {
        bool word_start = i == 0 || !isalpha((unsigned char)name[i - 1]) ||
                          (islower((unsigned char)name[i - 1]) && isupper((unsigned char)name[i]));
        if (!word_start) continue;
        if (strncasecmp(name + i, "ik", 2) == 0 && !islower((unsigned char)name[i + 2])) return true;
        if (strncasecmp(name + i, "pole", 4) == 0 || strncasecmp(name + i, "target", 6) == 0 ||
            strncasecmp(name + i, "ctrl", 4) == 0)
            return true;
    }
    return false;
}

/* The total skin weight each joint carries over the skin's vertices, from the primitives. */
static void joint_weights(const cb_model *m, int32_t skin, double *weight)
{
    memset(weight, 0, m->skins[skin].joint_count * sizeof *weight);
    for (uint32_t p = 0; p < m->primitive_count; ++p) {
        const cb_primitive *pr = &m->primitives[p];
        if (pr->skin != skin || !pr->joints || !pr->weights) continue;
        for (uint32_t v = 0; v < pr->vertex_count * 4; ++v) weight[pr->joints[v]] += pr->weights[v];
    }
}

/* No shared rig names a foot after an IK control: Husky's hind paws are weighted partly to
 * IKBackLeg.L/.R, yet its feet are named after the deforming leg bones; every foot of every clip
 * of every shared rig is a joint that carries skin weight and is not named as a control. */
static void test_no_foot_is_named_after_an_ik_control(void **state)
{
    (void)state;
    static const char *const rigs[] = {"assets/quaternius-husky/Husky.glb", "assets/quaternius-cow/Cow.glb",
                                       "assets/fox-bevy/Fox.glb", "assets/robot-quaternius-raylib/robot.glb",
                                       "assets/spider-animated-luanti/gltf_spider_animated.gltf",
                                       "assets/riggedfigure-raylib/rigged_figure.glb"};
    uint32_t husky_feet = 0;
    for (size_t r = 0; r < sizeof rigs / sizeof *rigs; ++r) {
        cb_model *m = load_shared(rigs[r]);
        cb_error err = {0};
        cb_sampler *s = cb_sampler_create(m, 0, &err);
        assert_non_null(s);
        double *weight = malloc(m->skins[0].joint_count * sizeof *weight);
        joint_weights(m, 0, weight);
        uint32_t feet = 0;
        for (uint32_t a = 0; a < m->animation_count; ++a) {
            cb_clip_info info;
            cb_limits limits = cb_default_limits();
            if (cb_clip_analyze(s, (int32_t)a, 30, 1, &limits, &info, &err)) fail_msg("%s: %s", rigs[r], err.message);
            cb_stride st;
            cb_stride_measure(s, &info, &st);
            for (uint32_t k = 0; k < st.foot_count; ++k) {
                if (named_as_control(st.feet[k].name))
                    fail_msg("%s '%s': a foot is named after the control '%s'", rigs[r], m->animations[a].name, st.feet[k].name);
                if (!(weight[st.feet[k].joint] > 0))
                    fail_msg("%s '%s': foot '%s' moves no vertex", rigs[r], m->animations[a].name, st.feet[k].name);
            }
            if (st.foot_count > feet) feet = st.foot_count;
        }
        printf("  %s: up to %u feet, none named as a control\n", rigs[r], feet);
        if (r == 0) husky_feet = feet;
        free(weight);
        cb_sampler_free(s);
        cb_model_free(m);
    }
    assert_int_equal(husky_feet, 4); /* the hind paws too, where the IK bones carry part of the weight */

    /* The rule bites where the heaviest bone of a paw is named as a control (as on another animal of
     * the pack, whose hind contacts were named IKBackLeg.L): Husky's hind paw bones (FFB.L, FFB.R)
     * renamed so, those feet are named after their legs' deforming bones, never the control. */
    cb_model *m = load_shared(rigs[0]);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_clip_info info;
    assert_int_equal(cb_clip_analyze(s, cb_model_find_animation(m, "AnimalArmature|Walk"), 30, -1, NULL, &info, &err), CB_OK);
    cb_stride before, after;
    cb_stride_measure(s, &info, &before);
    static char renamed[CB_MAX_FEET][80];
    const char *own[CB_MAX_FEET];
    uint32_t hind = 0;
    for (uint32_t k = 0; k < before.foot_count; ++k) {
        uint32_t node = m->skins[0].joints[before.feet[k].joint];
        own[k] = m->nodes[node].name;
        if (strncmp(own[k], "FFB.", 4) != 0) continue;
        snprintf(renamed[k], sizeof renamed[k], "IK%s", own[k]);
        m->nodes[node].name = renamed[k], ++hind;
    }
    assert_int_equal(hind, 2);
    cb_stride_measure(s, &info, &after);
    for (uint32_t k = 0; k < before.foot_count; ++k) m->nodes[m->skins[0].joints[before.feet[k].joint]].name = own[k];
    assert_int_equal(after.foot_count, before.foot_count);
    uint32_t legs = 0;
    for (uint32_t k = 0; k < after.foot_count; ++k) {
        printf("  hind paw bones renamed IKFFB.*: a foot is named %s\n", after.feet[k].name);
        assert_false(named_as_control(after.feet[k].name));
        legs += strncmp(after.feet[k].name, "BackLowerLeg.", 13) == 0;
    }
    assert_int_equal(legs, 2);
    cb_sampler_free(s);
    cb_model_free(m);
    /* The check itself reads controls as controls. */
    assert_true(named_as_control("IKBackLeg.L") && named_as_control("PoleTarget.L_end") && named_as_control("Leg_IK"));
    assert_false(named_as_control("BackLeg.L") || named_as_control("Pike") || named_as_control("Kick"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sockets_follow_their_joints),
        cmocka_unit_test(test_pole_targets_are_not_sockets),
        cmocka_unit_test(test_no_foot_is_named_after_an_ik_control),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
