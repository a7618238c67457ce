/* test_load_fast.c - the fast glTF path (formats/gltf_fast.cpp: simdjson, accessors read where
 * they lie in the GLB's BIN chunk) gives the model tinygltf gives. Each GLB is also written as a
 * .gltf with its BIN chunk in a separate .bin, which only tinygltf reads (it copies the bytes
 * into its own buffers), and every array of the two models is compared bit for bit. Hand-made
 * GLBs check the copy paths (strided, misaligned, normalized accessors) against the numbers
 * written, accessors pointing past their buffer are refused, and what simdjson reads otherwise
 * than tinygltf's RapidJSON goes to tinygltf. */
#include "testutil.h"

#include <sys/stat.h>

#include "crowdbake/gltf.h"

/* ---- the two models, compared ---- */

static void same_floats(const float *a, const float *b, size_t n, const char *what)
{
    if (!a || !b) {
        if (a != b) fail_msg("%s: present in one model only", what);
        return;
    }
    if (memcmp(a, b, n * sizeof(float)) != 0) fail_msg("%s differs", what);
}

static void same_nodes(const cb_model *x, const cb_model *y)
{
    assert_int_equal(x->node_count, y->node_count);
    for (uint32_t i = 0; i < x->node_count; ++i) {
        const cb_node *a = &x->nodes[i], *b = &y->nodes[i];
        assert_string_equal(a->name, b->name);
        assert_int_equal(a->parent, b->parent);
        assert_int_equal(a->has_matrix, b->has_matrix);
        assert_memory_equal(a->translation, b->translation, sizeof a->translation);
        assert_memory_equal(a->rotation, b->rotation, sizeof a->rotation);
        assert_memory_equal(a->scale, b->scale, sizeof a->scale);
        assert_memory_equal(a->matrix, b->matrix, sizeof a->matrix);
    }
}

static void same_skins(const cb_model *x, const cb_model *y)
{
    assert_int_equal(x->skin_count, y->skin_count);
    for (uint32_t s = 0; s < x->skin_count; ++s) {
        const cb_skin *a = &x->skins[s], *b = &y->skins[s];
        assert_string_equal(a->name, b->name);
        assert_int_equal(a->skeleton, b->skeleton);
        assert_int_equal(a->joint_count, b->joint_count);
        assert_memory_equal(a->joints, b->joints, a->joint_count * sizeof(int32_t));
        assert_memory_equal(a->inverse_bind, b->inverse_bind, a->joint_count * 16 * sizeof(double));
    }
}

static void same_primitives(const cb_model *x, const cb_model *y)
{
    assert_int_equal(x->primitive_count, y->primitive_count);
    for (uint32_t p = 0; p < x->primitive_count; ++p) {
        const cb_primitive *a = &x->primitives[p], *b = &y->primitives[p];
        size_t n = a->vertex_count;
        assert_int_equal(a->node, b->node);
        assert_int_equal(a->skin, b->skin);
        assert_int_equal(a->vertex_count, b->vertex_count);
        assert_int_equal(a->index_count, b->index_count);
        assert_int_equal(a->vertex_bytes, b->vertex_bytes);
        assert_int_equal(a->index_bytes, b->index_bytes);
        same_floats(a->positions, b->positions, n * 3, "positions");
        same_floats(a->normals, b->normals, n * 3, "normals");
        same_floats(a->texcoords, b->texcoords, n * 2, "texcoords");
        same_floats(a->weights, b->weights, n * 4, "weights");
        same_floats(a->colors, b->colors, n * 4, "colors");
        assert_int_equal(a->material ? a->material - x->materials : -1, b->material ? b->material - y->materials : -1);
        assert_memory_equal(a->joints, b->joints, n * 4 * sizeof(uint16_t));
        assert_true((a->indices == NULL) == (b->indices == NULL));
        if (a->indices) assert_memory_equal(a->indices, b->indices, a->index_count * sizeof(uint32_t));
    }
}

/* What the primitives look like (kept for `mesh`): the same materials, textures and image bytes. */
static void same_materials(const cb_model *x, const cb_model *y)
{
    assert_int_equal(x->material_count, y->material_count);
    assert_int_equal(x->texture_count, y->texture_count);
    assert_int_equal(x->image_count, y->image_count);
    for (uint32_t i = 0; i < x->image_count; ++i) {
        const cb_image *a = &x->images[i], *b = &y->images[i];
        assert_string_equal(a->mime_type, b->mime_type);
        assert_int_equal(a->size, b->size);
        if (a->size) assert_memory_equal(a->bytes, b->bytes, a->size);
    }
    for (uint32_t i = 0; i < x->texture_count; ++i) {
        const cb_texture *a = &x->textures[i], *b = &y->textures[i];
        assert_int_equal(a->image ? a->image - x->images : -1, b->image ? b->image - y->images : -1);
        assert_true(a->mag_filter == b->mag_filter && a->min_filter == b->min_filter && a->wrap_s == b->wrap_s &&
                    a->wrap_t == b->wrap_t);
    }
    for (uint32_t i = 0; i < x->material_count; ++i) {
        const cb_material *a = &x->materials[i], *b = &y->materials[i];
        assert_string_equal(a->name, b->name);
        assert_memory_equal(a->base_color, b->base_color, sizeof a->base_color);
        assert_true(a->metallic == b->metallic && a->roughness == b->roughness && a->alpha_mode == b->alpha_mode &&
                    a->alpha_cutoff == b->alpha_cutoff && a->double_sided == b->double_sided &&
                    a->base_color_texcoord == b->base_color_texcoord);
        assert_int_equal(a->base_color_texture ? a->base_color_texture - x->textures : -1,
                         b->base_color_texture ? b->base_color_texture - y->textures : -1);
    }
}

static void same_animations(const cb_model *x, const cb_model *y)
{
    assert_int_equal(x->animation_count, y->animation_count);
    assert_int_equal(x->skipped_clip_count, y->skipped_clip_count);
    assert_int_equal(x->ignored_morph_channels, y->ignored_morph_channels);
    for (uint32_t i = 0; i < x->skipped_clip_count; ++i) assert_string_equal(x->skipped_clips[i].name, y->skipped_clips[i].name);
    for (uint32_t i = 0; i < x->animation_count; ++i) {
        const cb_animation *a = &x->animations[i], *b = &y->animations[i];
        assert_string_equal(a->name, b->name);
        assert_int_equal(a->channel_count, b->channel_count);
        assert_true(a->t0 == b->t0 && a->t1 == b->t1);
        for (uint32_t c = 0; c < a->channel_count; ++c) {
            const cb_channel *p = &a->channels[c], *q = &b->channels[c];
            assert_int_equal(p->node, q->node);
            assert_int_equal(p->path, q->path);
            assert_int_equal(p->interp, q->interp);
            assert_int_equal(p->key_count, q->key_count);
            size_t values = (size_t)p->key_count * (p->path == CB_PATH_ROTATION ? 4 : 3) *
                            (p->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
            same_floats(p->times, q->times, p->key_count, "key times");
            same_floats(p->values, q->values, values, "key values");
        }
    }
}

/* ---- a GLB rewritten as .gltf + .bin ---- */

static uint32_t le32(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

/* Writes DIR/NAME.gltf (the GLB's JSON, buffers[0] given "uri": "NAME.bin") and DIR/NAME.bin
 * (the buffer's bytes from the BIN chunk); returns the .gltf's path. */
static void split_glb(const unsigned char *glb, size_t size, const char *dir, const char *name, char *gltf_path, size_t n)
{
    assert_true(size >= 28);
    size_t json_length = le32(glb + 12);
    char *json = malloc(json_length + 1);
    memcpy(json, glb + 20, json_length);
    json[json_length] = '\0';
    char *buffers = strstr(json, "\"buffers\"");
    assert_non_null(buffers);
    char *open = strchr(buffers, '{');
    char *length = strstr(open, "\"byteLength\"");
    assert_non_null(length);
    size_t byte_length = strtoul(strchr(length, ':') + 1, NULL, 10);
    assert_true(20 + json_length + 8 + byte_length <= size);
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.bin", dir, name);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(glb + 20 + json_length + 8, 1, byte_length, f), byte_length);
    fclose(f);
    snprintf(gltf_path, n, "%s/%s.gltf", dir, name);
    f = fopen(gltf_path, "wb");
    assert_non_null(f);
    fwrite(json, 1, (size_t)(open + 1 - json), f);
    fprintf(f, "\"uri\":\"%s.bin\",", name);
    fputs(open + 1, f);
    fclose(f);
    free(json);
}

static void test_fast_path_equals_tinygltf_on_real_models(void **state)
{
    (void)state;
    static const char *const glbs[] = {
        "assets/fox-bevy/Fox.glb", "assets/quaternius-cow/Cow.glb", "assets/robot-quaternius-raylib/robot.glb",
        "assets/riggedfigure-raylib/rigged_figure.glb", "assets/multitrack-luanti/gltf_multi_track_1.glb",
        "assets/derived-fox/Fox.quantized.glb", "assets/derived-spider-luanti/gltf_spider_animated.quantized.glb",
    };
    char dir[] = TEST_TMP "/load_fast";
    mkdir(TEST_TMP, 0755);
    mkdir(dir, 0755);
    for (size_t i = 0; i < COUNT_OF(glbs) + COUNT_OF(sample_names); ++i) {
        char path[1024], gltf[1024], name[32];
        if (i < COUNT_OF(glbs)) shared_path(path, sizeof path, glbs[i]);
        else sample_path(path, sizeof path, sample_names[i - COUNT_OF(glbs)]);
        size_t size = 0;
        unsigned char *bytes = (unsigned char *)read_whole_file(path, &size);
        assert_non_null(bytes);
        if (!cb_gltf_fast_path_applies(bytes, size)) fail_msg("%s: not on the fast path", path);
        snprintf(name, sizeof name, "model%zu", i);
        split_glb(bytes, size, dir, name, gltf, sizeof gltf);
        cb_error err = {0};
        cb_model *fast = cb_gltf_load(path, NULL, &err);
        if (!fast) fail_msg("%s: %s", path, err.message);
        cb_model *memory = cb_gltf_load_memory(bytes, size, path, NULL, NULL, &err); /* buffer copied, not mapped */
        if (!memory) fail_msg("%s: %s", path, err.message);
        cb_model *slow = cb_gltf_load(gltf, NULL, &err);
        if (!slow) fail_msg("%s: %s", gltf, err.message);
        assert_int_equal(slow->external_file_count, 1); /* tinygltf read the .bin */
        assert_true(fast->source_hash == memory->source_hash);
        for (int k = 0; k < 2; ++k) {
            const cb_model *m = k ? memory : fast;
            same_nodes(m, slow);
            same_skins(m, slow);
            same_primitives(m, slow);
            same_materials(m, slow);
            same_animations(m, slow);
        }
        assert_true(fast->animation_count + fast->primitive_count > 0);
        cb_model_free(fast), cb_model_free(memory), cb_model_free(slow);
        free(bytes);
    }
}

/* ---- hand-made GLBs ---- */

typedef struct glb {
    unsigned char data[2048];
    size_t size;
} glb;

static void make_glb(glb *out, const char *json, const unsigned char *bin, size_t bin_size)
{
    size_t n = strlen(json), padded = (n + 3) / 4 * 4, bin_padded = (bin_size + 3) / 4 * 4;
    assert_true(28 + padded + bin_padded <= sizeof out->data);
    uint32_t header[5] = {0x46546C67u, 2, (uint32_t)(28 + padded + bin_padded), (uint32_t)padded, 0x4E4F534Au};
    uint32_t bin_header[2] = {(uint32_t)bin_padded, 0x004E4942u};
    memset(out->data, ' ', sizeof out->data);
    memcpy(out->data, header, 20);
    memcpy(out->data + 20, json, n);
    memcpy(out->data + 20 + padded, bin_header, 8);
    memset(out->data + 28 + padded, 0, bin_padded);
    memcpy(out->data + 28 + padded, bin, bin_size);
    out->size = 28 + padded + bin_padded;
}

/* One joint node, a 3-vertex mesh, one clip translating the joint. The BIN layout (bytes):
 * 0 positions, VEC3 floats 16 bytes apart (48); 48 joints (12); 60 weights as normalized
 * u8 (12); 72 times, 2 floats at an offset of 2 (misaligned; 10); 84 translations (24).
 * `extra` goes into the JSON's accessors array, `view` in place of the translations' view. */
#define SCENE_JSON                                                                                                        \
    "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],"                                        \
    "\"nodes\":[{\"mesh\":0,\"skin\":0},{\"name\":\"hip\"}],"                                                             \
    "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"JOINTS_0\":1,\"WEIGHTS_0\":2}}]}],"                   \
    "\"skins\":[{\"joints\":[1]}],"                                                                                       \
    "\"animations\":[{\"name\":\"slide\",\"samplers\":[{\"input\":3,\"output\":4}],"                                      \
    "\"channels\":[{\"sampler\":0,\"target\":{\"node\":1,\"path\":\"translation\"}}]}],"                                  \
    "\"buffers\":[{\"byteLength\":%d}],"                                                                                  \
    "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48,\"byteStride\":16},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":12}," \
    "{\"buffer\":0,\"byteOffset\":60,\"byteLength\":12},{\"buffer\":0,\"byteOffset\":72,\"byteLength\":10},%s],"          \
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"                            \
    "{\"bufferView\":1,\"componentType\":5121,\"count\":3,\"type\":\"VEC4\"},"                                           \
    "{\"bufferView\":2,\"componentType\":5121,\"normalized\":true,\"count\":3,\"type\":\"VEC4\"},"                      \
    "{\"bufferView\":3,\"byteOffset\":2,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\"},"                        \
    "{\"bufferView\":4,\"componentType\":5126,\"count\":2,\"type\":\"VEC3\"}]}"

static const float kPositions[9] = {0.5f, 1, 2, -3, 4.25f, 5, 6, -7, 8.125f};
static const float kTimes[2] = {0.25f, 1.75f};
static const float kMoves[6] = {1, 2, 3, -4, 5.5f, 6};

static void scene_bin(unsigned char *bin)
{
    memset(bin, 0xEE, 108); /* the bytes between strided elements: never read */
    for (int v = 0; v < 3; ++v) memcpy(bin + 16 * v, kPositions + 3 * v, 12);
    memset(bin + 48, 0, 12); /* every vertex on joint 0 */
    const unsigned char weights[12] = {255, 0, 0, 0, 51, 204, 0, 0, 255, 0, 0, 0};
    memcpy(bin + 60, weights, 12);
    memcpy(bin + 74, kTimes, 8);
    memcpy(bin + 84, kMoves, 24);
}

/* `first`: members put first in the JSON's root object, e.g. "\"cameras\":[{}],". */
static void scene_glb_with(glb *out, int byte_length, const char *translation_view, const char *first)
{
    char json[2048];
    size_t n = (size_t)snprintf(json, sizeof json, "{%s", first);
    snprintf(json + n, sizeof json - n, SCENE_JSON + 1, byte_length, translation_view);
    unsigned char bin[108];
    scene_bin(bin);
    make_glb(out, json, bin, sizeof bin);
}

static void scene_glb(glb *out, int byte_length, const char *translation_view)
{
    scene_glb_with(out, byte_length, translation_view, "");
}

static void test_strided_misaligned_and_normalized_accessors_are_copied_right(void **state)
{
    (void)state;
    glb g;
    scene_glb(&g, 108, "{\"buffer\":0,\"byteOffset\":84,\"byteLength\":24}");
    assert_true(cb_gltf_fast_path_applies(g.data, g.size));
    cb_error err = {0};
    cb_model *m = cb_gltf_load_memory(g.data, g.size, "scene.glb", NULL, NULL, &err);
    if (!m) fail_msg("%s", err.message);
    assert_int_equal(m->primitive_count, 1);
    const cb_primitive *p = &m->primitives[0];
    assert_int_equal(p->vertex_count, 3);
    assert_memory_equal(p->positions, kPositions, sizeof kPositions); /* stride 16: copied */
    const float weights[12] = {1, 0, 0, 0, 51 / 255.0f, 204 / 255.0f, 0, 0, 1, 0, 0, 0};
    for (int i = 0; i < 12; ++i) assert_true(p->weights[i] == weights[i]);
    const cb_channel *ch = &m->animations[0].channels[0];
    assert_int_equal(ch->key_count, 2);
    assert_memory_equal(ch->times, kTimes, sizeof kTimes); /* misaligned: copied */
    assert_memory_equal(ch->values, kMoves, sizeof kMoves); /* packed and aligned: in place */
    assert_true(m->animations[0].t0 == 0.25 && m->animations[0].t1 == 1.75);
    cb_model_free(m);
}

static void expect_refused(const glb *g, const char *needle)
{
    cb_error err = {0};
    cb_model *m = cb_gltf_load_memory(g->data, g->size, "bad.glb", NULL, NULL, &err);
    if (m) fail_msg("loaded a file that should be refused for '%s'", needle);
    if (!strstr(err.message, needle)) fail_msg("message '%s' lacks '%s'", err.message, needle);
    assert_non_null(strstr(err.message, "bad.glb"));
    assert_null(strchr(err.message, '\n'));
}

static void test_accessors_past_their_buffer_are_refused(void **state)
{
    (void)state;
    glb g;
    /* The view ends inside the BIN chunk but past the buffer's byteLength (100 of the chunk's
     * 108 bytes): the buffer is what may be read, not the chunk. */
    scene_glb(&g, 100, "{\"buffer\":0,\"byteOffset\":84,\"byteLength\":24}");
    assert_true(cb_gltf_fast_path_applies(g.data, g.size));
    expect_refused(&g, "past the end of buffer 0");
    /* An offset that wraps around when added to the view's length. */
    scene_glb(&g, 108, "{\"buffer\":0,\"byteOffset\":18446744073709551608,\"byteLength\":24}");
    assert_true(cb_gltf_fast_path_applies(g.data, g.size));
    expect_refused(&g, "past the end of buffer 0");
    /* A view in the buffer whose accessor reads 24 bytes from 20. */
    scene_glb(&g, 108, "{\"buffer\":0,\"byteOffset\":64,\"byteLength\":20}");
    expect_refused(&g, "reads 24 bytes from byte 0 of bufferView 4, which has 20");
    /* A buffer longer than the BIN chunk: tinygltf's message (the fast path leaves it). */
    scene_glb(&g, 112, "{\"buffer\":0,\"byteOffset\":84,\"byteLength\":24}");
    assert_false(cb_gltf_fast_path_applies(g.data, g.size));
    expect_refused(&g, "byteLength");
    /* What the fast path does not read the way tinygltf does goes to tinygltf, and its
     * message is the one the file gets: a camera without a type, a count given as a string. */
    const char *view = "{\"buffer\":0,\"byteOffset\":84,\"byteLength\":24}";
    scene_glb_with(&g, 108, view, "\"cameras\":[{}],");
    assert_false(cb_gltf_fast_path_applies(g.data, g.size));
    expect_refused(&g, "not a valid glTF 2.0 file");
    scene_glb_with(&g, 108, view, "\"accessors\":[{\"componentType\":5126,\"count\":\"3\",\"type\":\"VEC3\"}],");
    assert_false(cb_gltf_fast_path_applies(g.data, g.size)); /* and a key given twice */
    expect_refused(&g, "not a valid glTF 2.0 file: 'count' property is not a positive integer");
    /* Truncated: one line from the container check, on either path. */
    scene_glb(&g, 108, "{\"buffer\":0,\"byteOffset\":84,\"byteLength\":24}");
    g.size -= 40;
    expect_refused(&g, "truncated GLB");
}

/* ---- what simdjson and RapidJSON read differently ---- */

/* The scene GLB with the first `from` in its JSON replaced by `to`. */
static void scene_variant(glb *out, const char *from, const char *to)
{
    char json[2048], variant[2048];
    snprintf(json, sizeof json, SCENE_JSON, 108, "{\"buffer\":0,\"byteOffset\":84,\"byteLength\":24}");
    const char *at = strstr(json, from);
    assert_non_null(at);
    snprintf(variant, sizeof variant, "%.*s%s%s", (int)(at - json), json, to, at + strlen(from));
    unsigned char bin[108];
    scene_bin(bin);
    make_glb(out, variant, bin, sizeof bin);
}

/* The GLB loaded from memory (on the fast path where it applies) and as .gltf + .bin (always
 * tinygltf): the same model, or both refused. */
static void same_as_tinygltf(const glb *g, const char *name)
{
    char dir[] = TEST_TMP "/load_fast", gltf[1024];
    mkdir(TEST_TMP, 0755);
    mkdir(dir, 0755);
    split_glb(g->data, g->size, dir, name, gltf, sizeof gltf);
    cb_error fast_err = {0}, slow_err = {0};
    cb_model *fast = cb_gltf_load_memory(g->data, g->size, "case.glb", NULL, NULL, &fast_err);
    cb_model *slow = cb_gltf_load(gltf, NULL, &slow_err);
    if (!fast != !slow) fail_msg("%s: '%s' / '%s'", name, fast ? "loaded" : fast_err.message, slow ? "loaded" : slow_err.message);
    if (fast) {
        same_nodes(fast, slow);
        same_skins(fast, slow);
        same_primitives(fast, slow);
        same_animations(fast, slow);
    }
    cb_model_free(fast), cb_model_free(slow);
}

static void test_what_simdjson_reads_otherwise_goes_to_tinygltf(void **state)
{
    (void)state;
    static const struct {
        const char *from, *to;
        bool fast; /* whether the fast path takes it */
    } cases[] = {
        /* Numbers both read alike: the fast path keeps them. An integer written -0 is an int
         * to RapidJSON (IsInt) and to simdjson. */
        {"{\"name\":\"hip\"}", "{\"name\":\"hip\",\"translation\":[0.1,-2.5e-3,-1.0E+2],\"scale\":[0.12345678901234568,1,-0.0]}", true},
        {"\"mesh\":0", "\"mesh\":-0", true},
        /* Not an int32 to either: tinygltf's answer. */
        {"\"mesh\":0", "\"mesh\":2147483648", false},
        {"\"mesh\":0", "\"mesh\":1.0", false},
        {"\"mesh\":0", "\"mesh\":0e0", false},
        /* A key given twice: RapidJSON and simdjson keep both, tinygltf reads the first. */
        {"\"name\":\"hip\"", "\"name\":\"hip\",\"name\":\"hop\"", false},
        /* A NUL inside a string: tinygltf's C string ends there. */
        {"\"name\":\"hip\"", "\"name\":\"h\\u0000ip\"", false},
        /* Strings simdjson refuses and RapidJSON takes: invalid UTF-8, a lone low surrogate. */
        {"\"name\":\"hip\"", "\"name\":\"h\xff" "ip\"", false},
        {"\"name\":\"hip\"", "\"name\":\"h\\udc00ip\"", false},
        /* Numbers RapidJSON's full precision reads otherwise than the correctly rounded double
         * simdjson gives: more than 17 digits near a halfway point, a subnormal; and a zero past
         * 1e308 that RapidJSON refuses in a member the fast path never reads. */
        {"{\"name\":\"hip\"}", "{\"name\":\"hip\",\"translation\":[1.47886842255842055882e-41,0,0]}", false},
        {"{\"name\":\"hip\"}", "{\"name\":\"hip\",\"translation\":[2.4703282292062327e-324,0,0]}", false},
        {"\"type\":\"VEC3\"}", "\"type\":\"VEC3\",\"min\":[0e400,0,0]}", false},
        /* An integer past 64 bits, which simdjson refuses and RapidJSON reads as a double. */
        {"\"type\":\"VEC3\"}", "\"type\":\"VEC3\",\"min\":[18446744073709551616,0,0]}", false},
    };
    for (size_t i = 0; i < COUNT_OF(cases); ++i) {
        glb g;
        char name[32];
        scene_variant(&g, cases[i].from, cases[i].to);
        if (cb_gltf_fast_path_applies(g.data, g.size) != cases[i].fast)
            fail_msg("case %zu (%s): the fast path %s it", i, cases[i].to, cases[i].fast ? "refuses" : "takes");
        snprintf(name, sizeof name, "variant%zu", i);
        same_as_tinygltf(&g, name);
    }
    /* Zeros whose exponent less their fraction's digits is past +-22: RapidJSON 1.1.0 reads
     * them as whatever its buffer held (1.27e30 for 0e56 once), so tinygltf gives no fixed
     * answer to compare with; the fast path leaves them to it. */
    static const char *const far_zeros[] = {"0e56", "0.0e-22", "-0e23", "0.00000000000000000000000"};
    for (size_t i = 0; i < COUNT_OF(far_zeros); ++i) {
        char hip[128];
        glb g;
        snprintf(hip, sizeof hip, "{\"name\":\"hip\",\"translation\":[1,%s,2]}", far_zeros[i]);
        scene_variant(&g, "{\"name\":\"hip\"}", hip);
        if (cb_gltf_fast_path_applies(g.data, g.size)) fail_msg("the fast path takes %s", far_zeros[i]);
    }
    /* The zeros it keeps: 0e22 is 0 to RapidJSON's exact path too. */
    glb g;
    scene_variant(&g, "{\"name\":\"hip\"}", "{\"name\":\"hip\",\"translation\":[0e22,0.0e-21,-0.0]}");
    assert_true(cb_gltf_fast_path_applies(g.data, g.size));
    same_as_tinygltf(&g, "zeros");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fast_path_equals_tinygltf_on_real_models),
        cmocka_unit_test(test_strided_misaligned_and_normalized_accessors_are_copied_right),
        cmocka_unit_test(test_accessors_past_their_buffer_are_refused),
        cmocka_unit_test(test_what_simdjson_reads_otherwise_goes_to_tinygltf),
    };
    return cmocka_run_group_tests_name("load_fast", tests, NULL, NULL);
}
