/* test_load.c - every model in ../shared/assets loads (or fails clearly), and the re-encoded
 * Fox variants skin to the same positions as Fox.glb within their quantization error. */
#define _DEFAULT_SOURCE /* realpath */
#include "testutil.h"

#include <limits.h>
#include <math.h>
#include <unistd.h>

#define TMP TEST_TMP "/load"

/* Facts from ../shared/assets/MANIFEST.md (extracted there with glTF-Transform). */
static void test_every_asset_loads_with_the_manifest_facts(void **state)
{
    (void)state;
    for (size_t i = 0; i < COUNT_OF(shared_models); ++i) {
        cb_model *m = load_shared(shared_models[i]);
        assert_true(m->node_count > 0);
        cb_model_free(m);
    }
    struct { const char *path; uint32_t joints; uint64_t vertices; uint32_t clips; } facts[] = {
        {"assets/fox-bevy/Fox.glb", 24, 1728, 3},
        {"assets/derived-fox/Fox.draco.glb", 24, 434, 3},
        {"assets/derived-fox/Fox.meshopt.glb", 24, 1728, 3},
        {"assets/riggedfigure-raylib/rigged_figure.glb", 19, 370, 1},
        {"assets/spider-animated-luanti/gltf_spider_animated.gltf", 57, 1000, 1},
        {"assets/robot-quaternius-raylib/robot.glb", 43, 7218, 14},
        {"assets/multitrack-luanti/gltf_multi_track_1.glb", 3, 72, 2},
    };
    for (size_t i = 0; i < sizeof facts / sizeof facts[0]; ++i) {
        cb_model *m = load_shared(facts[i].path);
        assert_int_equal(m->skins[0].joint_count, facts[i].joints);
        assert_int_equal(cb_model_skin_vertex_count(m, 0), facts[i].vertices);
        assert_int_equal(m->animation_count, facts[i].clips);
        cb_model_free(m);
    }
    /* The spider clip starts after 0 (MANIFEST: 0.0417-5 s). */
    cb_model *spider = load_shared("assets/spider-animated-luanti/gltf_spider_animated.gltf");
    assert_float_equal(spider->animations[0].t0, 0.0417, 1e-4);
    assert_float_equal(spider->animations[0].t1, 5.0, 1e-6);
    cb_model_free(spider);
}

static void expect_load_error(const char *rel, const char *needle)
{
    char path[1024];
    shared_path(path, sizeof path, rel);
    cb_error err = {0};
    cb_model *m = cb_gltf_load(path, NULL, &err);
    assert_null(m);
    assert_int_equal(err.status, CB_ERR_INPUT);
    if (!strstr(err.message, needle) || !strstr(err.message, path))
        fail_msg("%s: message '%s' lacks '%s' or the file name", rel, err.message, needle);
    assert_null(strchr(err.message, '\n')); /* one line */
}

static void test_invalid_magnum_files_fail_clearly(void **state)
{
    (void)state;
    /* Its skin 0 names nodes 1 and 2 as joints, neither with a parent (the file's JSON): two trees,
     * each named by its root, and the fix. */
    expect_load_error("assets/magnum-skin/skin.glb", "no common root: joint 1 (node_2) is in the tree rooted at node 2 "
                                                     "(node_2), joint 0 in the one rooted at node 1 (node_1); parent all "
                                                     "joints to one armature");
}

/* magnum's animation.glb has two clips that cannot be sampled (MANIFEST.md: "empty" has no
 * channels, "empty TRS animation" has channels without keys) beside two that can: those two
 * load, the others are skipped with their reasons instead of blocking the file. */
static void test_broken_clips_are_skipped_not_fatal(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/magnum-animation/animation.glb");
    assert_int_equal(m->animation_count, 2);
    assert_string_equal(m->animations[0].name, "TRS animation");
    assert_string_equal(m->animations[1].name, "TRS animation, splines");
    assert_int_equal(m->skipped_clip_count, 2);
    assert_string_equal(m->skipped_clips[0].name, "empty");
    assert_non_null(strstr(m->skipped_clips[0].reason, "clip 'empty' has no channels"));
    assert_string_equal(m->skipped_clips[1].name, "empty TRS animation");
    assert_non_null(strstr(m->skipped_clips[1].reason, "channel 0 (rotation of node_0) has no keys"));
    assert_non_null(cb_model_find_skipped_clip(m, "empty"));
    assert_null(cb_model_find_skipped_clip(m, "TRS animation"));
    /* The kept clips span the keys MANIFEST.md lists: 0-3.75 s and 0.5-5 s. */
    assert_true(m->animations[0].t0 == 0 && m->animations[0].t1 == 3.75);
    assert_true(m->animations[1].t0 == 0.5 && m->animations[1].t1 == 5);
    cb_warnings w = {0};
    cb_model_warnings(m, true, &w);
    assert_int_equal(w.count, 2);
    assert_string_equal(w.items[0].kind, "warning");
    cb_warnings_free(&w);
    cb_model_free(m);
}

/* Skinned positions of every vertex of `m` at time t of clip `clip`, 3 doubles each. */
static double *skinned(cb_model *m, int clip, double t, uint64_t *count)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    double *mats = malloc(m->skins[0].joint_count * 16 * sizeof(double));
    cb_sample_joint_matrices(s, clip, t, mats);
    *count = cb_model_skin_vertex_count(m, 0);
    double *out = malloc(*count * 3 * sizeof(double)), *at = out;
    for (uint32_t p = 0; p < m->primitive_count; ++p) {
        cb_skin_positions(&m->primitives[p], mats, at);
        at += m->primitives[p].vertex_count * 3;
    }
    free(mats);
    cb_sampler_free(s);
    return out;
}

static double dist3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* Worst distance between a variant's skinned vertices and Fox.glb's, matching each variant
 * vertex to the original vertex nearest in the rest pose (Draco re-indexes). */
static double variant_error(const char *rel)
{
    cb_model *fox = load_shared("assets/fox-bevy/Fox.glb"), *var = load_shared(rel);
    uint64_t nf, nv;
    double *rest_f = skinned(fox, -1, 0, &nf), *rest_v = skinned(var, -1, 0, &nv);
    uint64_t *match = malloc(nv * sizeof *match);
    for (uint64_t i = 0; i < nv; ++i) {
        double best = INFINITY;
        for (uint64_t k = 0; k < nf; ++k) {
            double d = dist3(rest_v + i * 3, rest_f + k * 3);
            if (d < best) best = d, match[i] = k;
        }
    }
    double worst = 0;
    for (int clip = -1; clip < 3; ++clip)
        for (double t = 0; t <= 0.7; t += 0.1) {
            double *a = skinned(fox, clip, t, &nf), *b = skinned(var, clip, t, &nv);
            for (uint64_t i = 0; i < nv; ++i) worst = fmax(worst, dist3(b + i * 3, a + match[i] * 3));
            free(a);
            free(b);
        }
    free(match);
    free(rest_f);
    free(rest_v);
    cb_model_free(fox);
    cb_model_free(var);
    return worst;
}

static void test_fox_variants_skin_like_the_original(void **state)
{
    (void)state;
    /* Fox is about 180 units long. The quantized and meshopt files store weights in 8 bits:
     * a weight off by up to 0.5/255 moves a vertex by that share of the distance between its
     * joints' transforms of it (up to ~30 units here), ~0.06. meshopt adds 16-bit rotation
     * keys and 14-bit positions (~0.01); Draco quantizes positions to 14 bits and weights. */
    struct { const char *path; double tolerance; } v[] = {
        {"assets/derived-fox/separate/Fox.gltf", 1e-9},
        {"assets/derived-fox/Fox.quantized.glb", 0.065},
        {"assets/derived-fox/Fox.meshopt.glb", 0.08},
        {"assets/derived-fox/Fox.draco.glb", 0.02},
    };
    for (size_t i = 0; i < sizeof v / sizeof v[0]; ++i) {
        double e = variant_error(v[i].path);
        printf("  %-40s worst skinned-vertex difference %.4g (allowed %.3g)\n", v[i].path, e, v[i].tolerance);
        if (!(e <= v[i].tolerance)) fail_msg("%s differs from Fox.glb by %g", v[i].path, e);
    }
}

/* The cache key of a bake must change when only an external buffer changes: the loader
 * hashes every byte it reads, not just the .gltf text. */
static void test_source_hash_covers_external_buffers(void **state)
{
    (void)state;
    char src[1024], cmd[2300];
    shared_path(src, sizeof src, "assets/derived-fox/separate");
    /* writable copies: ../shared may be read-only, and a non-root user could not change them */
    snprintf(cmd, sizeof cmd, "rm -rf " TMP " && mkdir -p " TMP " && cp %s/* " TMP "/ && chmod u+w " TMP "/*", src);
    assert_int_equal(system(cmd), 0);
    cb_model *before = load_or_fail(TMP "/Fox.gltf");
    cb_model *again = load_or_fail(TMP "/Fox.gltf");
    assert_true(before->source_hash == again->source_hash);

    /* Byte 0 of Fox.bin is the low mantissa byte of the first vertex's x: a change no
     * validation notices, so only the hash can tell. */
    FILE *f = fopen(TMP "/Fox.bin", "r+b");
    assert_non_null(f);
    int byte = fgetc(f);
    fseek(f, 0, SEEK_SET);
    fputc(byte ^ 1, f);
    fclose(f);
    cb_model *after = load_or_fail(TMP "/Fox.gltf");
    assert_true(after->source_hash != before->source_hash);
    assert_true(after->primitives[0].positions[0] != before->primitives[0].positions[0]);
    cb_model_free(before);
    cb_model_free(again);
    cb_model_free(after);
}

/* A copy of derived-fox/separate's Fox.gltf in `dir`, its buffer's uri replaced by `uri`. */
static void write_fox_naming(const char *dir, const char *uri)
{
    char src[1024], path[1024];
    shared_path(src, sizeof src, "assets/derived-fox/separate/Fox.gltf");
    size_t size;
    char *text = read_whole_file(src, &size);
    char *at = strstr(text, "\"uri\": \"Fox.bin\"");
    assert_non_null(at);
    snprintf(path, sizeof path, "%s/Fox.gltf", dir);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "%.*s\"uri\": \"%s\"%s", (int)(at - text), text, uri, at + strlen("\"uri\": \"Fox.bin\""));
    fclose(f);
    free(text);
}

static void expect_refused(const char *dir, const char *uri, const char *why)
{
    char path[1024];
    write_fox_naming(dir, uri);
    snprintf(path, sizeof path, "%s/Fox.gltf", dir);
    cb_error err = {0};
    cb_model *m = cb_gltf_load(path, NULL, &err);
    if (m) fail_msg("uri %s: loaded %s from outside the model's folder", uri, m->external_files[0]);
    assert_int_equal(err.status, CB_ERR_INPUT);
    if (!strstr(err.message, why) || !strstr(err.message, path)) fail_msg("uri %s: '%s' lacks '%s'", uri, err.message, why);
}

/* External buffers are read only from the model's folder: "../", an absolute path (plain or
 * percent-encoded) and a file missing there are refused, though each names a real Fox.bin
 * outside it (tinygltf would read them all, the last one from the working directory). */
static void test_external_files_only_inside_the_model_folder(void **state)
{
    (void)state;
    char src[1024], cmd[2300], abs_bin[PATH_MAX + 16], cwd[PATH_MAX];
    shared_path(src, sizeof src, "assets/derived-fox/separate/Fox.bin");
    snprintf(cmd, sizeof cmd, "rm -rf " TMP "/uri && mkdir -p " TMP "/uri/model/sub && cp %s " TMP "/uri/ && cp %s "
             TMP "/uri/model/sub/ && chmod -R u+w " TMP "/uri", src, src);
    assert_int_equal(system(cmd), 0);
    assert_non_null(realpath(TMP "/uri/Fox.bin", abs_bin));

    write_fox_naming(TMP "/uri/model", "sub/Fox.bin"); /* below the folder: fine */
    cb_model *m = load_or_fail(TMP "/uri/model/Fox.gltf");
    assert_int_equal(m->external_file_count, 1);
    cb_model_free(m);

    expect_refused(TMP "/uri/model", "../Fox.bin", "outside the model's folder");
    expect_refused(TMP "/uri/model", "sub/../../Fox.bin", "outside the model's folder");
    expect_refused(TMP "/uri/model", "%2E%2E/Fox.bin", "outside the model's folder");
    expect_refused(TMP "/uri/model", abs_bin, "outside the model's folder");
    expect_refused(TMP "/uri/model", "Missing.bin", "not found");
    /* The working directory holds a Fox.bin, the model's folder none. */
    assert_non_null(getcwd(cwd, sizeof cwd));
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/" TMP "/uri/model/Fox.gltf", cwd);
    write_fox_naming(TMP "/uri/model", "Fox.bin");
    assert_int_equal(chdir(TMP "/uri"), 0);
    cb_error err = {0};
    m = cb_gltf_load(path, NULL, &err);
    assert_int_equal(chdir(cwd), 0);
    if (m) fail_msg("loaded %s from the working directory", m->external_files[0]);
    assert_non_null(strstr(err.message, "not found"));
}

/* The same file loaded from memory: cb_gltf_load_memory copies what it reads, where
 * cb_gltf_load reads a GLB's BIN chunk in place, in the file's own bytes. */
static cb_model *load_copied(const char *path)
{
    size_t size;
    char *bytes = read_whole_file(path, &size);
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", path);
    *strrchr(dir, '/') = 0;
    cb_error err = {0};
    cb_model *m = cb_gltf_load_memory((const unsigned char *)bytes, size, path, dir, NULL, &err);
    free(bytes);
    if (!m) fail_msg("%s", err.message);
    return m;
}

#define SAME_ARRAY(a, b, n, what) \
    if (((a) == NULL) != ((b) == NULL) || ((a) && memcmp((a), (b), (n) * sizeof *(a)))) fail_msg("%s: %s differ", path, what)

static void expect_same_models(const char *path, const cb_model *a, const cb_model *b)
{
    assert_int_equal(a->node_count, b->node_count);
    for (uint32_t i = 0; i < a->node_count; ++i) {
        SAME_ARRAY(a->nodes[i].translation, b->nodes[i].translation, 3, "node translations");
        SAME_ARRAY(a->nodes[i].rotation, b->nodes[i].rotation, 4, "node rotations");
    }
    assert_int_equal(a->skin_count, b->skin_count);
    for (uint32_t i = 0; i < a->skin_count; ++i)
        SAME_ARRAY(a->skins[i].inverse_bind, b->skins[i].inverse_bind, a->skins[i].joint_count * 16u, "inverse binds");
    assert_int_equal(a->primitive_count, b->primitive_count);
    for (uint32_t i = 0; i < a->primitive_count; ++i) {
        const cb_primitive *p = &a->primitives[i], *q = &b->primitives[i];
        assert_int_equal(p->vertex_count, q->vertex_count);
        SAME_ARRAY(p->positions, q->positions, p->vertex_count * 3u, "positions");
        SAME_ARRAY(p->normals, q->normals, p->vertex_count * 3u, "normals");
        SAME_ARRAY(p->joints, q->joints, p->vertex_count * 4u, "joints");
        SAME_ARRAY(p->weights, q->weights, p->vertex_count * 4u, "weights");
    }
    assert_int_equal(a->animation_count, b->animation_count);
    for (uint32_t i = 0; i < a->animation_count; ++i) {
        assert_int_equal(a->animations[i].channel_count, b->animations[i].channel_count);
        for (uint32_t c = 0; c < a->animations[i].channel_count; ++c) {
            const cb_channel *x = &a->animations[i].channels[c], *y = &b->animations[i].channels[c];
            assert_int_equal(x->key_count, y->key_count);
            size_t values = (size_t)x->key_count * (x->path == CB_PATH_ROTATION ? 4 : 3) *
                            (x->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
            SAME_ARRAY(x->times, y->times, x->key_count, "key times");
            SAME_ARRAY(x->values, y->values, values, "key values");
        }
    }
}

/* The file read by cb_gltf_load (its BIN chunk used in place, a big one read on a second
 * thread) against the same bytes given to cb_gltf_load_memory. */
static void expect_in_place_matches_copied(const char *path)
{
    cb_model *a = load_or_fail(path), *b = load_copied(path);
    expect_same_models(path, a, b);
    if (a->source_hash != b->source_hash) fail_msg("%s: source hashes differ", path);
    cb_model_free(a);
    cb_model_free(b);
}

static void test_in_place_and_copied_loads_agree(void **state)
{
    (void)state;
    char path[1024];
    for (size_t i = 0; i < COUNT_OF(shared_models); ++i) {
        shared_path(path, sizeof path, shared_models[i]);
        expect_in_place_matches_copied(path);
    }
    for (size_t i = 0; i < COUNT_OF(sample_names); ++i) {
        sample_path(path, sizeof path, sample_names[i]);
        expect_in_place_matches_copied(path);
    }
}

/* A GLB of several megabytes is read on two threads (its BIN chunk while the JSON is parsed):
 * the model and its source hash must be those of the file read at once. Cut short, the file
 * is refused with the truncation named. */
static void test_big_glb_read_on_two_threads_loads_the_same(void **state)
{
    (void)state;
    char gen[1100], cmd[2400];
    snprintf(gen, sizeof gen, "%s", crowdbake_exe());
    *strrchr(gen, '/') = 0;
    snprintf(cmd, sizeof cmd, "mkdir -p " TMP " && %s/gen_samples --bench " TMP " 200 6 10 >/dev/null", gen);
    assert_int_equal(system(cmd), 0);
    const char *path = TMP "/bench_j200_c6_s10.glb";
    size_t size;
    char *bytes = read_whole_file(path, &size);
    assert_true(size > (4u << 20)); /* over the 4 MB under which a file is read at once */
    expect_in_place_matches_copied(path);

    FILE *f = fopen(TMP "/cut.glb", "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, size - 4096, f), size - 4096);
    fclose(f);
    free(bytes);
    cb_error err = {0};
    assert_null(cb_gltf_load(TMP "/cut.glb", NULL, &err));
    assert_non_null(strstr(err.message, "truncated GLB"));
}

static void put_le32(unsigned char *d, uint32_t v)
{
    for (int i = 0; i < 4; ++i) d[i] = (unsigned char)(v >> (8 * i));
}

/* Rotation keys are read where they lie. Here the bytes of a rotation accessor (keys of length
 * 2) are also a translation accessor's: normalizing them in place would move the translation,
 * so validation must normalize a copy (src/core/model_validate.c, validate_channel). */
static void test_normalizing_rotation_keys_never_touches_shared_bytes(void **state)
{
    (void)state;
    const char *json =
        "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
        "\"nodes\":[{\"name\":\"a\",\"children\":[1]},{\"name\":\"b\"}],"
        "\"buffers\":[{\"byteLength\":40}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":8},"
        "{\"buffer\":0,\"byteOffset\":8,\"byteLength\":32}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\",\"min\":[0],\"max\":[1]},"
        "{\"bufferView\":1,\"componentType\":5126,\"count\":2,\"type\":\"VEC4\"},"
        "{\"bufferView\":1,\"componentType\":5126,\"count\":2,\"type\":\"VEC3\"}],"
        "\"animations\":[{\"name\":\"clip\",\"samplers\":[{\"input\":0,\"output\":1},{\"input\":0,\"output\":2}],"
        "\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"rotation\"}},"
        "{\"sampler\":1,\"target\":{\"node\":1,\"path\":\"translation\"}}]}]}";
    const float bin[10] = {0, 1, 0, 0, 0, 2, 0, 0, 0, 2};
    size_t json_len = (strlen(json) + 3) / 4 * 4, total = 12 + 8 + json_len + 8 + sizeof bin;
    unsigned char *glb = calloc(1, total);
    memcpy(glb, "glTF", 4);
    put_le32(glb + 4, 2), put_le32(glb + 8, (uint32_t)total);
    put_le32(glb + 12, (uint32_t)json_len), put_le32(glb + 16, 0x4E4F534Au);
    memset(glb + 20, ' ', json_len);
    memcpy(glb + 20, json, strlen(json));
    put_le32(glb + 20 + json_len, sizeof bin), put_le32(glb + 24 + json_len, 0x004E4942u);
    memcpy(glb + 28 + json_len, bin, sizeof bin); /* little-endian host, as everywhere we build */
    assert_int_equal(system("mkdir -p " TMP), 0);
    FILE *f = fopen(TMP "/shared-bytes.glb", "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(glb, 1, total, f), total);
    fclose(f);
    free(glb);
    cb_model *m = load_or_fail(TMP "/shared-bytes.glb");
    const cb_channel *rot = &m->animations[0].channels[0], *move = &m->animations[0].channels[1];
    assert_int_equal(rot->path, CB_PATH_ROTATION);
    assert_float_equal(rot->values[3], 1.0, 0); /* (0, 0, 0, 2) normalized */
    assert_float_equal(rot->values[7], 1.0, 0);
    assert_float_equal(move->values[3], 2.0, 0); /* the second translation key, (2, 0, 0), as stored */
    cb_model_free(m);
}

/* glTF numbers are decimals: the loader must give the doubles strtod gives (correctly rounded),
 * or node transforms written with 17 digits bake differently from file to file. These five
 * come from the spider asset; a JSON parser's fast path is an ulp off on each. */
static void test_json_numbers_are_correctly_rounded(void **state)
{
    (void)state;
    const char *numbers[6] = {"-0.23922589421272278", "8.097286041675034e-08", "0.9999997615814209",
                              "1.3833086898173974e-09", "-2.0781445141115906e-16", "1"};
    char json[1024];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
             "\"nodes\":[{\"translation\":[%s,%s,%s],\"scale\":[%s,%s,%s]}]}",
             numbers[0], numbers[1], numbers[2], numbers[3], numbers[4], numbers[5]);
    cb_error err = {0};
    cb_model *m = cb_gltf_load_memory((const unsigned char *)json, strlen(json), "numbers.gltf", NULL, NULL, &err);
    assert_non_null(m);
    for (int k = 0; k < 3; ++k) {
        assert_true(m->nodes[0].translation[k] == strtod(numbers[k], NULL));
        assert_true(m->nodes[0].scale[k] == strtod(numbers[3 + k], NULL));
    }
    cb_model_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_asset_loads_with_the_manifest_facts),
        cmocka_unit_test(test_invalid_magnum_files_fail_clearly),
        cmocka_unit_test(test_broken_clips_are_skipped_not_fatal),
        cmocka_unit_test(test_fox_variants_skin_like_the_original),
        cmocka_unit_test(test_source_hash_covers_external_buffers),
        cmocka_unit_test(test_external_files_only_inside_the_model_folder),
        cmocka_unit_test(test_in_place_and_copied_loads_agree),
        cmocka_unit_test(test_normalizing_rotation_keys_never_touches_shared_bytes),
        cmocka_unit_test(test_json_numbers_are_correctly_rounded),
        cmocka_unit_test(test_big_glb_read_on_two_threads_loads_the_same),
    };
    return cmocka_run_group_tests_name("load", tests, NULL, NULL);
}
