/* test_errors.c - bad input gets a one-line error naming the file and the problem, a
 * documented exit code, and never a crash or a hang. A small valid GLB is built here and
 * broken in one way per test. */
#define _DEFAULT_SOURCE /* mkstemps */
#include "testutil.h"

#include "crowdbake/exr.h"

#include <math.h>
#include <unistd.h>

typedef struct blob {
    unsigned char data[4096];
    size_t size;
} blob;

/* Binary layout: positions 0 (36), joints 36 (12), weights 48 (48), ibm 96 (128),
 * times 224 (8), rotations 232 (32) = 264 bytes. */
static void make_bin(unsigned char *bin, float t1, float rot_w1, uint8_t joint)
{
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint8_t joints[12] = {0, 0, 0, 0, joint, 0, 0, 0, 1, 0, 0, 0};
    float weights[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    float ibm[32] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1};
    float times[2] = {0, t1};
    float rot[8] = {0, 0, 0, 1, 0, 0, 0.7071068f, rot_w1};
    memcpy(bin, pos, 36);
    memcpy(bin + 36, joints, 12);
    memcpy(bin + 48, weights, 48);
    memcpy(bin + 96, ibm, 128);
    memcpy(bin + 224, times, 8);
    memcpy(bin + 232, rot, 32);
}

typedef struct spec {
    const char *extensions;   /* e.g. ",\"extensionsRequired\":[...]" */
    int position_count;
    const char *skin_joints;  /* "1,2" */
    const char *channels;     /* animation channels array contents */
    float t1, rot_w1;
    uint8_t joint;
} spec;

static spec valid_spec(void)
{
    spec s = {"", 3, "1,2", "{\"sampler\":0,\"target\":{\"node\":2,\"path\":\"rotation\"}}", 1.0f, 0.7071068f, 1};
    return s;
}

static void build(const spec *s, blob *out)
{
    char json[3000];
    int n = snprintf(json, sizeof json,
        "{\"asset\":{\"version\":\"2.0\"}%s,\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],"
        "\"nodes\":[{\"mesh\":0,\"skin\":0},{\"name\":\"hip\",\"children\":[2]},{\"name\":\"knee\",\"translation\":[0,1,0]}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"JOINTS_0\":1,\"WEIGHTS_0\":2}}]}],"
        "\"skins\":[{\"inverseBindMatrices\":3,\"joints\":[%s]}],"
        "\"animations\":[{\"name\":\"bend\",\"samplers\":[{\"input\":4,\"output\":5}],\"channels\":[%s]}],"
        "\"buffers\":[{\"byteLength\":264}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":12},"
        "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":96,\"byteLength\":128},"
        "{\"buffer\":0,\"byteOffset\":224,\"byteLength\":8},{\"buffer\":0,\"byteOffset\":232,\"byteLength\":32}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]},"
        "{\"bufferView\":1,\"componentType\":5121,\"count\":3,\"type\":\"VEC4\"},"
        "{\"bufferView\":2,\"componentType\":5126,\"count\":3,\"type\":\"VEC4\"},"
        "{\"bufferView\":3,\"componentType\":5126,\"count\":2,\"type\":\"MAT4\"},"
        "{\"bufferView\":4,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\",\"min\":[0],\"max\":[1]},"
        "{\"bufferView\":5,\"componentType\":5126,\"count\":2,\"type\":\"VEC4\"}]}",
        s->extensions, s->skin_joints, s->channels, s->position_count);
    assert_true(n > 0 && (size_t)n < sizeof json);
    while (n % 4) json[n++] = ' ';
    uint32_t header[5] = {0x46546C67u, 2, (uint32_t)(20 + n + 8 + 264), (uint32_t)n, 0x4E4F534Au};
    uint32_t bin_header[2] = {264, 0x004E4942u};
    memcpy(out->data, header, 20);
    memcpy(out->data + 20, json, (size_t)n);
    memcpy(out->data + 20 + n, bin_header, 8);
    make_bin(out->data + 28 + n, s->t1, s->rot_w1, s->joint);
    out->size = 28 + (size_t)n + 264;
}

static void expect_error(const blob *b, const char *needle)
{
    cb_error err = {0};
    cb_model *m = cb_gltf_load_memory(b->data, b->size, "broken.glb", NULL, NULL, &err);
    if (m) fail_msg("loaded although it should fail with '%s'", needle);
    assert_int_equal(err.status, CB_ERR_INPUT);
    if (!strstr(err.message, needle)) fail_msg("message '%s' lacks '%s'", err.message, needle);
    assert_non_null(strstr(err.message, "broken.glb"));
    assert_null(strchr(err.message, '\n'));
}

static void test_the_valid_file_loads(void **state)
{
    (void)state;
    spec s = valid_spec();
    blob b;
    build(&s, &b);
    cb_error err = {0};
    cb_model *m = cb_gltf_load_memory(b.data, b.size, "valid.glb", NULL, NULL, &err);
    if (!m) fail_msg("%s", err.message);
    assert_int_equal(m->skins[0].joint_count, 2);
    assert_int_equal(m->primitives[0].vertex_count, 3);
    cb_model_free(m);
}

static void test_truncated_glb_at_every_length(void **state)
{
    (void)state;
    spec s = valid_spec();
    blob b;
    build(&s, &b);
    for (size_t len = 0; len < b.size; len += 7) {
        blob t = b;
        t.size = len;
        cb_error err = {0};
        cb_model *m = cb_gltf_load_memory(t.data, t.size, "broken.glb", NULL, NULL, &err);
        assert_null(m);
        assert_int_equal(err.status, CB_ERR_INPUT);
        assert_non_null(strstr(err.message, "broken.glb"));
    }
    blob t = b;
    t.size = 16;
    expect_error(&t, "truncated GLB");
    t.size = b.size - 10;
    expect_error(&t, "truncated GLB");
}

static void test_wrong_magic_and_version(void **state)
{
    (void)state;
    spec s = valid_spec();
    blob b;
    build(&s, &b);
    blob t = b;
    memcpy(t.data, "glTX", 4);
    expect_error(&t, "wrong magic");
    t = b;
    t.data[4] = 1;
    expect_error(&t, "GLB version 1");
    t = b; /* found by fuzzing: a header length that leaves no room for the JSON chunk */
    t.data[8] = 12, t.data[9] = t.data[10] = t.data[11] = 0;
    expect_error(&t, "too few for the required JSON chunk");
}

static void test_chunk_length_past_the_end(void **state)
{
    (void)state;
    spec s = valid_spec();
    blob b;
    build(&s, &b);
    uint32_t json_len;
    memcpy(&json_len, b.data + 12, 4);
    uint32_t huge = 1u << 30;
    memcpy(b.data + 20 + json_len, &huge, 4); /* the BIN chunk's length */
    expect_error(&b, "past the end");
}

static void test_accessor_out_of_bounds(void **state)
{
    (void)state;
    spec s = valid_spec();
    s.position_count = 1000;
    blob b;
    build(&s, &b);
    expect_error(&b, "reads 12000 bytes");
}

static void test_joint_index_past_the_skin(void **state)
{
    (void)state;
    spec s = valid_spec();
    s.joint = 7;
    blob b;
    build(&s, &b);
    expect_error(&b, "uses joint 7, but its skin has 2 joints");
}

static void test_key_times_not_increasing(void **state)
{
    (void)state;
    spec s = valid_spec();
    s.t1 = 0.0f;
    blob b;
    build(&s, &b);
    expect_error(&b, "key times are not increasing");
}

static void test_nan_values(void **state)
{
    (void)state;
    spec s = valid_spec();
    s.rot_w1 = NAN;
    blob b;
    build(&s, &b);
    expect_error(&b, "NaN or infinite value");
    s = valid_spec();
    s.t1 = INFINITY;
    build(&s, &b);
    expect_error(&b, "NaN or infinite time");
}

static void test_unsupported_required_extension(void **state)
{
    (void)state;
    spec s = valid_spec();
    s.extensions = ",\"extensionsUsed\":[\"EXT_future_thing\"],\"extensionsRequired\":[\"EXT_future_thing\"]";
    blob b;
    build(&s, &b);
    expect_error(&b, "requires extension EXT_future_thing");
}

static void test_skin_without_joints(void **state)
{
    (void)state;
    spec s = valid_spec();
    s.skin_joints = "";
    blob b;
    build(&s, &b);
    cb_error err = {0};
    cb_model *m = cb_gltf_load_memory(b.data, b.size, "broken.glb", NULL, NULL, &err);
    assert_null(m);
    assert_int_equal(err.status, CB_ERR_INPUT);
    assert_string_equal(err.message, "broken.glb: skin 0 (skin_0) has no joints");
}

static void test_clip_without_channels(void **state)
{
    (void)state;
    spec s = valid_spec();
    s.channels = "";
    blob b;
    build(&s, &b);
    expect_error(&b, "clip 'bend' has no channels");
}

static void test_cli_exit_code_and_one_line(void **state)
{
    (void)state;
    spec s = valid_spec();
    blob b;
    build(&s, &b);
    char path[] = "/tmp/crowdbake-test-XXXXXX.glb";
    int fd = mkstemps(path, 4);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, b.data, b.size / 2), (ssize_t)(b.size / 2));
    close(fd);
    char cmd[2048], out[4096];
    snprintf(cmd, sizeof cmd, "%s info %s 2>&1", crowdbake_exe(), path);
    int rc = run_command(cmd, out, sizeof out);
    unlink(path);
    assert_int_equal(rc, EXIT_INPUT);
    assert_non_null(strstr(out, path));
    assert_non_null(strstr(out, "truncated GLB"));
    assert_int_equal(strchr(out, '\n') - out, (long)strlen(out) - 1); /* exactly one line */
    snprintf(cmd, sizeof cmd, "%s info /nonexistent/x.glb 2>/dev/null", crowdbake_exe());
    assert_int_equal(run_command(cmd, NULL, 0), EXIT_IO);
    snprintf(cmd, sizeof cmd, "%s info --bogus 2>/dev/null", crowdbake_exe());
    assert_int_equal(run_command(cmd, NULL, 0), EXIT_USAGE);
}

/* A palette EXR whose header claims 2^31 - 1 clips (tests/fuzz/regressions/exr, from a bake of
 * fish.exr) is refused as inconsistent, naming the file, before the clip table is allocated:
 * it asked for 512 GiB and reported "out of memory" without the file's name. */
static void test_exr_palette_with_huge_clip_count(void **state)
{
    (void)state;
    const char *path = "tests/fuzz/regressions/exr/clip-count-huge.exr";
    cb_exr_palette pal;
    cb_error err = {0};
    assert_int_equal(cb_exr_read_palette(path, &pal, &err), CB_ERR_INPUT);
    if (!strstr(err.message, path) || !strstr(err.message, "consistent crowdbake palette header"))
        fail_msg("%s", err.message);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_valid_file_loads),
        cmocka_unit_test(test_truncated_glb_at_every_length),
        cmocka_unit_test(test_wrong_magic_and_version),
        cmocka_unit_test(test_chunk_length_past_the_end),
        cmocka_unit_test(test_accessor_out_of_bounds),
        cmocka_unit_test(test_joint_index_past_the_skin),
        cmocka_unit_test(test_key_times_not_increasing),
        cmocka_unit_test(test_nan_values),
        cmocka_unit_test(test_unsupported_required_extension),
        cmocka_unit_test(test_skin_without_joints),
        cmocka_unit_test(test_clip_without_channels),
        cmocka_unit_test(test_cli_exit_code_and_one_line),
        cmocka_unit_test(test_exr_palette_with_huge_clip_count),
    };
    return cmocka_run_group_tests_name("errors", tests, NULL, NULL);
}
