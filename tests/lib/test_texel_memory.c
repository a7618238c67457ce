/* test_texel_memory.c - bakes into memory the caller provides (cb_bake_options.texel_memory):
 * the same texels and facts as a bake into its own memory, for every layout and precision, on
 * several threads, through qpos falling back to affine (the memory asked for again); memory the
 * bake does not own is not freed with the palette. And the .pal written where it is baked (its
 * temporary file's payload mapped, formats/pal_write.c) against cb_pal_write's file, byte for
 * byte; where the file cannot be mapped, the bake falls back to its own memory. */
#include "testutil.h"

#include <sys/stat.h>

#include "crowdbake_pal.h"
#include "crowdbake/pal_write.h"

#define TMP TEST_TMP "/texel_memory"

/* A provider: each answer a fresh zeroed block, 64 bytes into its allocation, so that a free()
 * of the answer (memory the bake does not own) aborts even without a sanitizer. */
typedef struct provider {
    unsigned char *blocks[4];
    size_t sizes[4];
    uint32_t asked;
    bool refuse;
} provider;

static void *acquire(void *ctx, const cb_palette *p)
{
    provider *v = ctx;
    assert_true(v->asked < 4);
    assert_true(p->texel_bytes > 0 && p->texel_bytes == (size_t)p->width * p->height * cb_precision_texel_bytes(p->precision));
    v->sizes[v->asked] = p->texel_bytes;
    unsigned char *block = v->refuse ? NULL : calloc(p->texel_bytes + 64, 1);
    v->blocks[v->asked++] = block;
    return block ? block + 64 : NULL;
}

static void provider_free(provider *v)
{
    for (uint32_t i = 0; i < v->asked; ++i) free(v->blocks[i]);
}

static cb_status bake(cb_sampler *s, cb_layout l, cb_precision pr, cb_texel_memory memory, cb_palette *p, cb_error *err)
{
    cb_bake_options o = cb_default_bake_options();
    o.layout = l, o.precision = pr, o.threads = 3, o.affine_fallback = true, o.texel_memory = memory;
    return cb_palette_bake(s, &o, NULL, 0, p, err);
}

/* Every fact of the two palettes but where their texels lie. */
static void assert_same_palette(const cb_palette *a, const cb_palette *b, const char *what)
{
    if (a->layout != b->layout || a->precision != b->precision || a->rows != b->rows || a->width != b->width ||
        a->height != b->height || a->texel_bytes != b->texel_bytes || a->max_error != b->max_error ||
        a->visible_error != b->visible_error || a->linear_range != b->linear_range ||
        memcmp(a->bounds_min, b->bounds_min, sizeof a->bounds_min) || memcmp(a->bounds_max, b->bounds_max, sizeof a->bounds_max))
        fail_msg("%s: the palettes' facts differ", what);
    if (memcmp(a->texels, b->texels, a->texel_bytes) != 0) fail_msg("%s: the texels differ", what);
}

static int check_model(cb_model *m, const char *name)
{
    int fallbacks = 0;
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    for (int l = 0; l < 3; ++l)
        for (int pr = 0; pr < 3; ++pr) {
            char what[256];
            snprintf(what, sizeof what, "%s %s/%s", name, cb_layout_name((cb_layout)l), cb_precision_name((cb_precision)pr));
            cb_palette own, given, refused;
            provider v = {0}, none = {.refuse = true};
            if (bake(s, (cb_layout)l, (cb_precision)pr, (cb_texel_memory){NULL, NULL}, &own, &err)) fail_msg("%s: %s", what, err.message);
            assert_false(own.texels_borrowed);
            if (bake(s, (cb_layout)l, (cb_precision)pr, (cb_texel_memory){acquire, &v}, &given, &err)) fail_msg("%s: %s", what, err.message);
            /* qpos that fell back to affine asked twice, for two sizes: the last answer holds the texels */
            assert_int_equal(v.asked, own.fallback_note[0] ? 2 : 1);
            fallbacks += v.asked == 2;
            assert_true(given.texels_borrowed);
            assert_ptr_equal(given.texels, v.blocks[v.asked - 1] + 64);
            assert_int_equal(v.sizes[v.asked - 1], own.texel_bytes);
            assert_same_palette(&own, &given, what);
            if (bake(s, (cb_layout)l, (cb_precision)pr, (cb_texel_memory){acquire, &none}, &refused, &err)) fail_msg("%s: %s", what, err.message);
            assert_false(refused.texels_borrowed); /* refused: the bake's own memory */
            assert_same_palette(&own, &refused, what);
            cb_palette_free(&own), cb_palette_free(&refused);
            cb_palette_free(&given); /* leaves the provider's memory, freed here */
            provider_free(&v), provider_free(&none);
        }
    cb_sampler_free(s);
    return fallbacks;
}

static void test_bakes_into_given_memory_equal_bakes_into_their_own(void **state)
{
    (void)state;
    static const char *const models[] = {"assets/fox-bevy/Fox.glb", "assets/spider-animated-luanti/gltf_spider_animated.gltf",
                                         "assets/quaternius-cow/Cow.glb"};
    int fallbacks = 0;
    for (size_t i = 0; i < COUNT_OF(models); ++i) {
        cb_model *m = load_shared(models[i]);
        fallbacks += check_model(m, models[i]);
        cb_model_free(m);
    }
    char path[1024];
    sample_path(path, sizeof path, "quadruped");
    cb_model *m = load_or_fail(path);
    check_model(m, "quadruped");
    cb_model_free(m);
    assert_true(fallbacks > 0); /* the spider's non-uniform scale: qpos fell back, memory asked again */
}

static int temporaries(void)
{
    char out[64];
    run_command("ls -a " TMP " | grep -c '\\.tmp\\.'", out, sizeof out);
    return atoi(out);
}

/* Bakes model's skin 0 in (layout, precision) into the .pal at `path`, mapped; false where the
 * file could not be mapped (the bake then held its own texels, written by cb_pal_write). */
static bool bake_mapped(cb_sampler *s, cb_layout l, cb_precision pr, const char *path, const cb_pal_write_options *po)
{
    cb_pal_mapping mapping;
    cb_pal_mapping_init(&mapping, path, cb_sampler_model(s), 0);
    cb_palette p;
    cb_error err = {0};
    if (bake(s, l, pr, (cb_texel_memory){cb_pal_map_texels, &mapping}, &p, &err)) fail_msg("%s: %s", path, err.message);
    bool mapped = cb_pal_mapping_holds(&mapping, &p);
    assert_true(mapped == p.texels_borrowed);
    cb_status rc = mapped ? cb_pal_write_mapped(&mapping, &p, po, &err) : cb_pal_write(path, &p, cb_sampler_model(s), 0, po, &err);
    if (rc) fail_msg("%s: %s", path, err.message);
    cb_pal_mapping_abort(&mapping); /* a no-op once written */
    cb_palette_free(&p);
    return mapped;
}

static void test_pal_written_where_baked_equals_pal_written(void **state)
{
    (void)state;
    assert_int_equal(system("rm -rf " TMP " && mkdir -p " TMP), 0);
    cb_model *m = load_shared("assets/spider-animated-luanti/gltf_spider_animated.gltf");
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    cb_pal_write_options po = {false, 0, 0x1234567890abcdefull, 1.5f, false};
    for (int l = 0; l < 3; ++l)
        for (int pr = 0; pr < 3; ++pr) {
            cb_palette p;
            if (bake(s, (cb_layout)l, (cb_precision)pr, (cb_texel_memory){NULL, NULL}, &p, &err)) fail_msg("%s", err.message);
            assert_int_equal(cb_pal_write(TMP "/written.pal", &p, m, 0, &po, &err), CB_OK);
            cb_palette_free(&p);
            assert_true(bake_mapped(s, (cb_layout)l, (cb_precision)pr, TMP "/mapped.pal", &po));
            size_t a_size, b_size;
            char *a = read_whole_file(TMP "/written.pal", &a_size), *b = read_whole_file(TMP "/mapped.pal", &b_size);
            assert_non_null(a), assert_non_null(b);
            assert_int_equal(a_size, b_size);
            if (memcmp(a, b, a_size) != 0) fail_msg("%s/%s: the mapped .pal differs", cb_layout_name((cb_layout)l),
                                                    cb_precision_name((cb_precision)pr));
            free(a), free(b);
            cbpal_file f;
            char why[256];
            if (cbpal_open(TMP "/mapped.pal", CBPAL_VERIFY_CHECKSUM, &f, why, sizeof why) != 0) fail_msg("%s", why);
            cbpal_close(&f);
        }
    assert_int_equal(temporaries(), 0);
    /* Where no temporary can be made (no such directory), nothing is mapped: the bake falls back
     * to its own memory, and cb_pal_write says what is wrong. */
    cb_pal_mapping mapping;
    cb_pal_mapping_init(&mapping, TMP "/missing/x.pal", m, 0);
    cb_palette p;
    assert_int_equal(bake(s, CB_LAYOUT_QPOS, CB_PRECISION_U16, (cb_texel_memory){cb_pal_map_texels, &mapping}, &p, &err), CB_OK);
    assert_false(p.texels_borrowed);
    assert_false(cb_pal_mapping_holds(&mapping, &p));
    assert_int_equal(cb_pal_write(TMP "/missing/x.pal", &p, m, 0, &po, &err), CB_ERR_IO);
    assert_non_null(strstr(err.message, "does not exist"));
    cb_pal_mapping_abort(&mapping);
    cb_palette_free(&p);
    cb_sampler_free(s);
    cb_model_free(m);
}

/* The bake's notes take a loop's ground speed from the clips the palette planned (no second
 * analysis): each palette clip carries cb_clip_analyze's, and the CLI says so for a travelling loop. */
static void test_palette_clips_carry_their_ground_speed(void **state)
{
    (void)state;
    char path[1024], cmd[2048], out[4096];
    sample_path(path, sizeof path, "quadruped");
    cb_model *m = load_or_fail(path);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_palette p;
    assert_int_equal(bake(s, CB_LAYOUT_QPOS, CB_PRECISION_U16, (cb_texel_memory){NULL, NULL}, &p, &err), CB_OK);
    int travelling = 0;
    for (uint32_t c = 0; c < p.clip_count; ++c) {
        cb_clip_info info;
        assert_int_equal(cb_clip_analyze(s, (int32_t)c, 30, -1, NULL, &info, &err), CB_OK);
        assert_true(p.clips[c].ground_speed == info.ground_speed);
        travelling += p.clips[c].loops && info.ground_speed > 1;
    }
    assert_true(travelling > 0);
    cb_palette_free(&p);
    cb_sampler_free(s);
    cb_model_free(m);
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/q.pal 2>&1", crowdbake_exe(), path);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    if (!strstr(out, "note: clip 'walk' loops and travels 1.2 units/s")) fail_msg("%s", out);

    /* The Cow's loops are in place: its Gallop's root drifts 0.0176 units/s, 11 mm over a loop of a
     * 4.6-unit animal (0.24% of its height), which is jitter, not travel worth a note. */
    shared_path(path, sizeof path, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/cow.pal 2>&1", crowdbake_exe(), path);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    if (strstr(out, "travels")) fail_msg("%s", out);
    m = load_or_fail(path);
    s = cb_sampler_create(m, 0, &err);
    bool drifts = false;
    for (int32_t c = 0; c < (int32_t)m->animation_count; ++c) {
        cb_clip_info info;
        assert_int_equal(cb_clip_analyze(s, c, 30, -1, NULL, &info, &err), CB_OK);
        drifts |= info.loops && info.ground_speed > 0.01;
    }
    assert_true(drifts); /* the note is held back by the threshold, not for want of drift */
    cb_sampler_free(s);
    cb_model_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bakes_into_given_memory_equal_bakes_into_their_own),
        cmocka_unit_test(test_pal_written_where_baked_equals_pal_written),
        cmocka_unit_test(test_palette_clips_carry_their_ground_speed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
