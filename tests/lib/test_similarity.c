/* test_similarity.c - the similarity sampler (qpos bakes of rigs made of rotations, uniform
 * scales and translations) against the 4x4 matrix sampler it replaces: which rigs it takes,
 * and that it gives the same joint matrices on real assets and on rigs built here. */
#include "testutil.h"

#include <math.h>

#include "../../src/core/cb_math.h"
#include "../../src/core/palette_bake.h"
#include "../../src/core/sampler.h"

/* The largest difference between the two samplers over every row of every clip at 30 fps,
 * relative to the size of the numbers compared: the joint's scale for its 3x3, the skeleton's
 * reach for the translations. The similarities are sampled in batches, as the bake does. */
static double worst_difference(cb_model *m)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    uint32_t joints = m->skins[0].joint_count;
    double *mats = malloc(joints * 16 * sizeof(double)), worst = 0;
    cb_similarity *sims = malloc(joints * CB_SAMPLE_BATCH * sizeof *sims);
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        cb_clip_info info;
        assert_int_equal(cb_clip_analyze(s, (int32_t)a, 30, -1, NULL, &info, &err), CB_OK);
        uint32_t batch[CB_SAMPLE_BATCH], count = 0;
        for (uint32_t f = 0; f < info.frames; ++f) {
            if (count == 0) {
                while (count < CB_SAMPLE_BATCH && f + count < info.frames) batch[count] = f + count, ++count;
                cb_clip_frame_similarities(s, &info, batch, count, CB_ROOT_MOTION_IN_PLACE, sims);
            }
            const cb_similarity *row = sims + (size_t)(f - batch[0]) * joints;
            if (f == batch[count - 1]) count = 0;
            cb_clip_frame_matrices(s, &info, f, CB_ROOT_MOTION_IN_PLACE, mats);
            double reach = 1;
            for (uint32_t j = 0; j < joints; ++j)
                for (int k = 12; k < 15; ++k) reach = fmax(reach, fabs(mats[j * 16 + k]));
            for (uint32_t j = 0; j < joints; ++j) {
                double m2[16];
                cb_similarity_matrix(&row[j], m2);
                const double *mj = mats + j * 16;
                double scale = fmax(1, sqrt(mj[0] * mj[0] + mj[1] * mj[1] + mj[2] * mj[2]));
                for (int k = 0; k < 16; ++k) {
                    double d = fabs(m2[k] - mj[k]) / (k >= 12 && k < 15 ? reach : scale);
                    if (d > worst) worst = d;
                }
            }
        }
    }
    free(mats);
    free(sims);
    cb_sampler_free(s);
    return worst;
}

static bool is_similarity(cb_model *m)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    bool similar = cb_sampler_is_similarity(s);
    cb_sampler_free(s);
    return similar;
}

/* Which assets qualify is a fact of their files: the robot's and the spider's scale keys
 * differ per axis; the rigged figure's differ only by float rounding (1.0 against
 * 0.99999994). Float32 inverse bind matrices deviate from similarities by ~1e-7, so the two
 * samplers agree to a few 1e-7. */
static void test_real_assets_sample_the_same_both_ways(void **state)
{
    (void)state;
    struct { const char *path; bool similar; } assets[] = {
        {"assets/fox-bevy/Fox.glb", true},
        {"assets/derived-fox/Fox.meshopt.glb", true},
        {"assets/simpleskin-bevy/SimpleSkin.gltf", true},
        {"assets/multitrack-luanti/gltf_multi_track_1.glb", true},
        {"assets/robot-quaternius-raylib/robot.glb", false},
        {"assets/spider-animated-luanti/gltf_spider_animated.gltf", false},
        {"assets/riggedfigure-raylib/rigged_figure.glb", true}, /* scale keys equal to float rounding */
    };
    for (size_t i = 0; i < COUNT_OF(assets); ++i) {
        cb_model *m = load_shared(assets[i].path);
        bool similar = is_similarity(m);
        if (similar != assets[i].similar) fail_msg("%s: similarity rig %d, expected %d", assets[i].path, similar, assets[i].similar);
        if (similar) {
            double d = worst_difference(m);
            printf("  %-72s worst difference %.2g\n", assets[i].path, d);
            if (!(d < 2e-6)) fail_msg("%s: the similarity sampler differs by %g", assets[i].path, d);
        }
        cb_model_free(m);
    }
    for (size_t i = 0; i < COUNT_OF(sample_names); ++i) {
        char path[1024];
        sample_path(path, sizeof path, sample_names[i]);
        cb_model *m = load_or_fail(path);
        assert_true(is_similarity(m));
        double d = worst_difference(m);
        if (!(d < 2e-6)) fail_msg("%s: the similarity sampler differs by %g", path, d);
        cb_model_free(m);
    }
}

/* A rig built here: an armature node (rotated, scaled by 2, or a matrix) over a two-joint
 * chain whose second joint is rotated, moved and scaled by keys. */
typedef struct rig_spec {
    float scale_keys[2][3];
    cb_interp scale_interp;
    bool armature_matrix; /* the armature as a matrix instead of TRS */
    double armature_shear;
    double ibm_shear;
} rig_spec;

static cb_model *build_rig(const rig_spec *r)
{
    cb_model *m = cb_model_create("test-rig");
    m->node_count = 3;
    m->nodes = cb_model_alloc(m, 3, sizeof(cb_node));
    const double half = sqrt(0.5);
    for (int i = 0; i < 3; ++i) {
        cb_node *n = &m->nodes[i];
        n->name = i == 0 ? "armature" : i == 1 ? "hip" : "knee";
        n->parent = i - 1;
        n->rotation[3] = 1;
        n->scale[0] = n->scale[1] = n->scale[2] = 1;
        n->translation[1] = i;
    }
    cb_node *arm = &m->nodes[0];
    arm->rotation[0] = half, arm->rotation[3] = half; /* 90 degrees about x */
    arm->scale[0] = arm->scale[1] = arm->scale[2] = 2;
    if (r->armature_matrix) {
        cb_mat4_from_trs(arm->matrix, (cb_vec3){0, 0, 0}, (cb_quat){half, 0, 0, half}, (cb_vec3){2, 2, 2});
        arm->matrix[4] += r->armature_shear;
        arm->has_matrix = true;
    }
    m->skin_count = 1;
    m->skins = cb_model_alloc(m, 1, sizeof(cb_skin));
    cb_skin *sk = &m->skins[0];
    sk->name = "skin";
    sk->joint_count = 2;
    sk->joints = cb_model_alloc(m, 2, sizeof(int32_t));
    sk->joints[0] = 1, sk->joints[1] = 2;
    sk->inverse_bind = cb_model_alloc(m, 32, sizeof(double));
    sk->skeleton = -1;
    for (int j = 0; j < 2; ++j) {
        double *ibm = sk->inverse_bind + j * 16;
        cb_mat4_from_trs(ibm, (cb_vec3){0, -1.0 - j, 0}, (cb_quat){0, 0, 0, 1}, (cb_vec3){0.5, 0.5, 0.5});
        ibm[1] += r->ibm_shear;
    }
    static float times[2] = {0, 1};
    static float rotations[8] = {0, 0, 0, 1, 0, 1, 0, 0}; /* exact unit keys: a half turn about y */
    static float moves[6] = {0, 1, 0, 0.5f, 1, 0};
    m->animation_count = 1;
    m->animations = cb_model_alloc(m, 1, sizeof(cb_animation));
    cb_animation *a = &m->animations[0];
    a->name = "walk";
    a->t0 = 0, a->t1 = 1;
    a->channel_count = 3;
    a->channels = cb_model_alloc(m, 3, sizeof(cb_channel));
    float *scales = cb_model_alloc(m, 18, sizeof(float)); /* room for spline tangents */
    int per_key = r->scale_interp == CB_INTERP_CUBICSPLINE ? 3 : 1;
    for (int k = 0; k < 2; ++k)
        for (int s = 0; s < per_key; ++s)
            memcpy(scales + (k * per_key + s) * 3, r->scale_keys[k], 3 * sizeof(float));
    a->channels[0] = (cb_channel){1, CB_PATH_ROTATION, CB_INTERP_LINEAR, 2, times, rotations};
    a->channels[1] = (cb_channel){2, CB_PATH_TRANSLATION, CB_INTERP_LINEAR, 2, times, moves};
    a->channels[2] = (cb_channel){2, CB_PATH_SCALE, r->scale_interp, 2, times, scales};
    return m;
}

static void test_built_rigs_take_the_path_they_should(void **state)
{
    (void)state;
    rig_spec uniform = {{{1, 1, 1}, {1.5f, 1.5f, 1.5f}}, CB_INTERP_LINEAR, false, 0, 0};
    cb_model *m = build_rig(&uniform);
    assert_true(is_similarity(m));
    double d = worst_difference(m);
    printf("  built rig: worst difference %.2g\n", d);
    assert_true(d < 1e-12);
    cb_model_free(m);

    rig_spec as_matrix = uniform;
    as_matrix.armature_matrix = true;
    m = build_rig(&as_matrix);
    assert_true(is_similarity(m));
    assert_true(worst_difference(m) < 1e-12);
    cb_model_free(m);

    /* Each of these is something a similarity cannot hold: the matrix sampler takes them. */
    rig_spec refused[5] = {uniform, uniform, uniform, uniform, uniform};
    refused[0].scale_keys[1][2] = 1.6f;                 /* non-uniform scale key */
    refused[1].scale_interp = CB_INTERP_CUBICSPLINE;    /* a spline can pass through zero */
    refused[2].scale_keys[1][0] = refused[2].scale_keys[1][1] = refused[2].scale_keys[1][2] = -1; /* mirror */
    refused[3].armature_matrix = true, refused[3].armature_shear = 0.01; /* shear in a node matrix */
    refused[4].ibm_shear = 1e-4;                        /* shear in an inverse bind matrix */
    for (int i = 0; i < 5; ++i) {
        m = build_rig(&refused[i]);
        if (is_similarity(m)) fail_msg("built rig %d was taken as a similarity rig", i);
        cb_model_free(m);
    }
}

/* Several times per call run each step over all of them (vectorized, with the keys before the
 * first, after the last, at wide angles and at equal keys redone one by one): every batch must
 * give the bits one time per call gives, whatever its length and wherever it starts. */
static void expect_batches_match_single_times(const char *what, cb_model *m)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    uint32_t joints = m->skins[0].joint_count;
    cb_similarity *batch = malloc(joints * CB_SAMPLE_BATCH * sizeof *batch), *one = malloc(joints * sizeof *one);
    uint32_t compared = 0;
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        const cb_animation *anim = &m->animations[a];
        /* 0.5 s before the clip to 0.5 s after it, in uneven steps; batches of 1..16 times */
        double span = anim->t1 - anim->t0 + 1, times[CB_SAMPLE_BATCH];
        uint32_t steps = 97, length = 1;
        for (uint32_t i = 0; i < steps; i += length, length = length % CB_SAMPLE_BATCH + 1) {
            uint32_t count = i + length <= steps ? length : steps - i;
            for (uint32_t k = 0; k < count; ++k) {
                double u = (double)(i + k) / (steps - 1);
                times[k] = anim->t0 - 0.5 + span * (u + 0.003 * sin(7 * u) * (u > 0 && u < 1));
            }
            cb_sample_joint_similarities_batch(s, (int32_t)a, times, count, batch);
            for (uint32_t k = 0; k < count; ++k) {
                cb_sample_joint_similarities(s, (int32_t)a, times[k], one);
                if (memcmp(one, batch + (size_t)k * joints, joints * sizeof *one) != 0)
                    fail_msg("%s: clip %u at t = %.9g: lane %u of a batch of %u differs from one time alone", what, a,
                             times[k], k, count);
                ++compared;
            }
        }
    }
    printf("  %-72s %u times match bit for bit\n", what, compared);
    free(batch);
    free(one);
    cb_sampler_free(s);
}

static void test_batches_give_the_bits_of_single_times(void **state)
{
    (void)state;
    const char *assets[] = {"assets/fox-bevy/Fox.glb", "assets/simpleskin-bevy/SimpleSkin.gltf",
                            "assets/multitrack-luanti/gltf_multi_track_1.glb",
                            "assets/riggedfigure-raylib/rigged_figure.glb"};
    for (size_t i = 0; i < COUNT_OF(assets); ++i) {
        cb_model *m = load_shared(assets[i]);
        expect_batches_match_single_times(assets[i], m);
        cb_model_free(m);
    }
    for (size_t i = 0; i < COUNT_OF(sample_names); ++i) {
        char path[1024];
        sample_path(path, sizeof path, sample_names[i]);
        cb_model *m = load_or_fail(path);
        expect_batches_match_single_times(path, m);
        cb_model_free(m);
    }
    /* a half turn between two keys: every time between them takes the wide-angle branch */
    rig_spec uniform = {{{1, 1, 1}, {1.5f, 1.5f, 1.5f}}, CB_INTERP_LINEAR, false, 0, 0};
    cb_model *m = build_rig(&uniform);
    expect_batches_match_single_times("built rig", m);
    cb_model_free(m);
}

/* The batched sampler's lanes against the one-time path, channel by channel: the key spans a
 * batch shares between channels of one times array, and the vectorized slerp and lerp, must
 * give cb_channel_eval's bits at every time (between keys, on them, before and after them). */
static uint32_t expect_lanes_match_scalar(const char *what, const cb_model *m)
{
    uint32_t compared = 0;
    for (uint32_t a = 0; a < m->animation_count; ++a)
        for (uint32_t c = 0; c < m->animations[a].channel_count; ++c) {
            const cb_channel *ch = &m->animations[a].channels[c];
            if (ch->interp != CB_INTERP_LINEAR || ch->key_count < 2) continue;
            int comps = ch->path == CB_PATH_ROTATION ? 4 : 3;
            double first = ch->times[0], span = ch->times[ch->key_count - 1] - first;
            uint32_t steps = 4 * ch->key_count + 8;
            for (uint32_t i = 0; i < steps; i += CB_SAMPLE_BATCH) {
                double times[CB_SAMPLE_BATCH], lanes[4][CB_SAMPLE_BATCH];
                for (uint32_t k = 0; k < CB_SAMPLE_BATCH; ++k) {
                    double u = (double)(i + k) / (steps - 8) - 0.05; /* from before the first key to after the last */
                    times[k] = (i + k) % 5 == 0 ? ch->times[(i + k) / 4 % ch->key_count] : first + span * u;
                }
                cb_channel_eval_lanes(ch, times, lanes);
                for (uint32_t k = 0; k < CB_SAMPLE_BATCH; ++k) {
                    double one[4];
                    cb_channel_eval(ch, times[k], one);
                    for (int v = 0; v < comps; ++v)
                        if (memcmp(&one[v], &lanes[v][k], sizeof one[v]) != 0)
                            fail_msg("%s: clip %u channel %u at t = %.9g: component %d is %.17g in lanes, %.17g alone",
                                     what, a, c, times[k], v, lanes[v][k], one[v]);
                    ++compared;
                }
            }
        }
    printf("  %-72s %u channel values match bit for bit\n", what, compared);
    return compared;
}

static void test_lanes_give_the_bits_of_the_scalar_path(void **state)
{
    (void)state;
    const char *assets[] = {"assets/fox-bevy/Fox.glb", "assets/quaternius-cow/Cow.glb",
                            "assets/spider-animated-luanti/gltf_spider_animated.gltf",
                            "assets/robot-quaternius-raylib/robot.glb",
                            "assets/riggedfigure-raylib/rigged_figure.glb"};
    for (size_t i = 0; i < COUNT_OF(assets); ++i) {
        cb_model *m = load_shared(assets[i]);
        assert_true(expect_lanes_match_scalar(assets[i], m) > 500);
        cb_model_free(m);
    }
}

/* What cb_clip_frame_lanes_each hands over: each joint's lanes where cb_clip_frame_lanes puts
 * them, and whether they came in joint order, each once. */
typedef struct handed_lanes {
    double *lanes;
    uint32_t next; /* the joint expected next */
    bool in_order;
} handed_lanes;

static void keep_handed(void *ctx, uint32_t joint, double (*lanes)[CB_SAMPLE_BATCH])
{
    handed_lanes *h = ctx;
    h->in_order = h->in_order && joint == h->next++;
    memcpy(h->lanes + (size_t)joint * 8 * CB_SAMPLE_BATCH, lanes, 8 * CB_SAMPLE_BATCH * sizeof(double));
}

/* The joints handed over one at a time (the bake's path) against the lanes of them all. */
static void expect_handed_lanes_match(const char *what, cb_sampler *s, const cb_clip_info *info, const uint32_t *frames,
                                      uint32_t n, const double *lanes, uint32_t joints)
{
    handed_lanes h = {malloc((size_t)joints * 8 * CB_SAMPLE_BATCH * sizeof(double)), 0, true};
    assert_non_null(h.lanes);
    cb_clip_frame_lanes_each(s, info, frames, n, CB_ROOT_MOTION_IN_PLACE, keep_handed, &h);
    if (!h.in_order || h.next != joints) fail_msg("%s: %u joints handed over, not each once in order", what, h.next);
    if (memcmp(h.lanes, lanes, (size_t)joints * 8 * CB_SAMPLE_BATCH * sizeof(double)) != 0)
        fail_msg("%s: clip %d frame %u: the joints handed over differ from the lanes", what, info->animation, frames[0]);
    free(h.lanes);
}

/* The joints' similarities as lanes (what qpos rows and the measurement read) against
 * cb_clip_frame_similarities, frame by frame: the same bits, the root's travel included; and
 * handed over joint by joint (what the bake's rows read) the same bits again. */
static void expect_frame_lanes_match_rows(const char *what, cb_model *m)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    if (!cb_sampler_is_similarity(s)) fail_msg("%s is not sampled as similarities", what);
    uint32_t joints = m->skins[0].joint_count, compared = 0;
    cb_similarity *rows = malloc(joints * CB_SAMPLE_BATCH * sizeof *rows);
    double *lanes = malloc(joints * 8 * CB_SAMPLE_BATCH * sizeof *lanes);
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        cb_clip_info info;
        assert_int_equal(cb_clip_analyze(s, (int32_t)a, 30, -1, NULL, &info, &err), CB_OK);
        for (uint32_t f = 0, count = 1; f < info.frames; f += count, count = count % CB_SAMPLE_BATCH + 1) {
            uint32_t frames[CB_SAMPLE_BATCH], n = 0;
            while (n < count && f + n < info.frames) frames[n] = f + n, ++n;
            cb_clip_frame_similarities(s, &info, frames, n, CB_ROOT_MOTION_IN_PLACE, rows);
            cb_clip_frame_lanes(s, &info, frames, n, CB_ROOT_MOTION_IN_PLACE, lanes);
            expect_handed_lanes_match(what, s, &info, frames, n, lanes, joints);
            for (uint32_t i = 0; i < CB_SAMPLE_BATCH; ++i) /* lanes past n repeat the last frame */
                for (uint32_t j = 0; j < joints; ++j) {
                    const cb_similarity *r = &rows[(i < n ? i : n - 1) * joints + j];
                    const double *l = lanes + (size_t)j * 8 * CB_SAMPLE_BATCH + i;
                    double v[8] = {r->rotation[0],    r->rotation[1],    r->rotation[2],    r->rotation[3],
                                   r->translation[0], r->translation[1], r->translation[2], r->scale};
                    for (int c = 0; c < 8; ++c)
                        if (memcmp(&v[c], &l[c * CB_SAMPLE_BATCH], sizeof v[c]) != 0)
                            fail_msg("%s: clip %u frame %u joint %u: lane value %d differs from the row's", what, a,
                                     f + i, j, c);
                    ++compared;
                }
        }
    }
    printf("  %-72s %u joint lanes match bit for bit\n", what, compared);
    free(rows);
    free(lanes);
    cb_sampler_free(s);
}

static void test_frame_lanes_give_the_bits_of_frame_rows(void **state)
{
    (void)state;
    const char *assets[] = {"assets/fox-bevy/Fox.glb", "assets/riggedfigure-raylib/rigged_figure.glb",
                            "assets/multitrack-luanti/gltf_multi_track_1.glb"};
    for (size_t i = 0; i < COUNT_OF(assets); ++i) {
        cb_model *m = load_shared(assets[i]);
        expect_frame_lanes_match_rows(assets[i], m);
        cb_model_free(m);
    }
    for (size_t i = 0; i < COUNT_OF(sample_names); ++i) { /* animals that travel: the root motion */
        char path[1024];
        sample_path(path, sizeof path, sample_names[i]);
        cb_model *m = load_or_fail(path);
        expect_frame_lanes_match_rows(path, m);
        cb_model_free(m);
    }
}

/* The rows' hemispheres, which the bake takes as a product of signs over the lanes, against
 * the rule one row after another: a zero or NaN dot (not flipped, whatever came before) at
 * every lane, -0, tiny dots, and runs of flips. */
static void test_row_signs_follow_the_rows_one_by_one(void **state)
{
    (void)state;
    enum { B = CB_SAMPLE_BATCH };
    const double odd[] = {0.0, -0.0, NAN, -NAN, 1e-300, -1e-300, 4.9e-324, -4.9e-324, INFINITY, -INFINITY};
    uint32_t seed = 12345, checked = 0, one_by_one = 0;
    for (int round = 0; round < 4000; ++round) {
        double dot[B];
        for (int i = 0; i < B; ++i) {
            seed = seed * 1664525u + 1013904223u;
            dot[i] = ((double)(seed >> 8) / (1 << 24) - 0.5) * 2; /* -1 .. 1 */
        }
        if (round % 4 == 1) { /* one odd value */
            seed = seed * 1664525u + 1013904223u;
            dot[1 + (seed >> 8) % (B - 1)] = odd[(seed >> 20) % (sizeof odd / sizeof *odd)];
        }
        if (round % 4 == 2) dot[B - 1] = odd[(round / 4) % 2]; /* +0 or -0 at the last lane */
        if (round % 4 == 3) dot[0] = odd[(round / 4) % 4];       /* lane 0's dot is not used */
        bool flip0 = round % 3 == 0;
        float got[B], want[B];
        palette_row_signs(dot, flip0, got);
        bool flip = flip0;
        for (int i = 0; i < B; ++i) {
            if (i) flip = (flip ? -dot[i] : dot[i]) < 0;
            want[i] = flip ? -1.0f : 1.0f;
            if (i && !(dot[i] < 0 || dot[i] > 0)) ++one_by_one;
        }
        for (int i = 0; i < B; ++i) {
            if (got[i] != want[i]) fail_msg("round %d lane %d: %g, want %g (dot %g)", round, i, got[i], want[i], dot[i]);
            ++checked;
        }
    }
    printf("  %u lanes checked, %u with a zero or NaN dot\n", checked, one_by_one);
    assert_int_equal(checked, 4000 * CB_SAMPLE_BATCH);
    assert_true(one_by_one >= 1000); /* about 1400: the zeros at the last lane and some odd values */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_real_assets_sample_the_same_both_ways),
        cmocka_unit_test(test_built_rigs_take_the_path_they_should),
        cmocka_unit_test(test_batches_give_the_bits_of_single_times),
        cmocka_unit_test(test_lanes_give_the_bits_of_the_scalar_path),
        cmocka_unit_test(test_frame_lanes_give_the_bits_of_frame_rows),
        cmocka_unit_test(test_row_signs_follow_the_rows_one_by_one),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
