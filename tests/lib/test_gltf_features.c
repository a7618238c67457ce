/* test_gltf_features.c - glTF features real exporters use rarely but the loader must get
 * right: sparse accessors, nodes given by `matrix`, embedded data URIs, and morph-weight
 * channels (ignored with a count). The file is written here, with hand-computed results. */
#include "testutil.h"

#include <math.h>

static void base64(const unsigned char *in, size_t n, char *out)
{
    static const char t[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t o = 0;
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)in[i] << 16 | (i + 1 < n ? (uint32_t)in[i + 1] << 8 : 0) | (i + 2 < n ? in[i + 2] : 0);
        out[o++] = t[v >> 18 & 63];
        out[o++] = t[v >> 12 & 63];
        out[o++] = i + 1 < n ? t[v >> 6 & 63] : '=';
        out[o++] = i + 2 < n ? t[v & 63] : '=';
    }
    out[o] = '\0';
}

/* Buffer: times (0, 1) at 0; translations (0,0,0), (0,0,0) at 8 (24 bytes); sparse index
 * 1 (u16) at 32; sparse value (2,0,0) at 36; weights times/values at 48 (2 + 2 floats). */
static cb_model *load_features(void)
{
    unsigned char bin[64] = {0};
    float times[2] = {0, 1}, value[3] = {2, 0, 0}, wt[4] = {0, 1, 0, 1};
    uint16_t index = 1;
    memcpy(bin, times, 8);
    memcpy(bin + 32, &index, 2);
    memcpy(bin + 36, value, 12);
    memcpy(bin + 48, wt, 16);
    char b64[128], json[4096];
    base64(bin, sizeof bin, b64);
    /* node 0: a parent given by matrix: rotate 90 degrees about Z, then translate (0, 5, 0).
     * node 1: the joint, animated by a sparse translation accessor: (0,0,0) -> (2,0,0). */
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0,2]}],"
             "\"nodes\":[{\"name\":\"frame\",\"matrix\":[0,1,0,0, -1,0,0,0, 0,0,1,0, 0,5,0,1],\"children\":[1]},"
             "{\"name\":\"bone\"},{\"name\":\"blob\",\"mesh\":0}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}],\"weights\":[0]}],"
             "\"skins\":[{\"joints\":[1]}],"
             "\"animations\":[{\"name\":\"slide\",\"samplers\":[{\"input\":1,\"output\":2},{\"input\":1,\"output\":3}],"
             "\"channels\":[{\"sampler\":0,\"target\":{\"node\":1,\"path\":\"translation\"}},"
             "{\"sampler\":1,\"target\":{\"node\":2,\"path\":\"weights\"}}]}],"
             "\"buffers\":[{\"byteLength\":64,\"uri\":\"data:application/octet-stream;base64,%s\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":8},{\"buffer\":0,\"byteOffset\":8,\"byteLength\":24},"
             "{\"buffer\":0,\"byteOffset\":32,\"byteLength\":2},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":12},"
             "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":16}],"
             "\"accessors\":[{\"bufferView\":1,\"componentType\":5126,\"count\":1,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[0,0,0]},"
             "{\"bufferView\":0,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\",\"min\":[0],\"max\":[1]},"
             "{\"bufferView\":1,\"componentType\":5126,\"count\":2,\"type\":\"VEC3\",\"sparse\":{\"count\":1,"
             "\"indices\":{\"bufferView\":2,\"componentType\":5123},\"values\":{\"bufferView\":3}}},"
             "{\"bufferView\":4,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\"}]}",
             b64);
    cb_error err = {0};
    cb_model *m = cb_gltf_load_memory((const unsigned char *)json, strlen(json), "features.gltf", NULL, NULL, &err);
    if (!m) fail_msg("%s", err.message);
    return m;
}

static void test_sparse_accessor_substitutes_values(void **state)
{
    (void)state;
    cb_model *m = load_features();
    assert_int_equal(m->animations[0].channel_count, 1); /* the weights channel is dropped... */
    assert_int_equal(m->ignored_morph_channels, 1);      /* ...and counted for the warning */
    const cb_channel *ch = &m->animations[0].channels[0];
    assert_float_equal(ch->values[0], 0, 0);             /* key 0 from the base view */
    assert_float_equal(ch->values[3], 2, 0);             /* key 1 replaced by the sparse value */
    double v[4];
    cb_channel_eval(ch, 0.25, v);
    assert_float_equal(v[0], 0.5, 1e-12);
    cb_model_free(m);
}

static void test_matrix_node_takes_part_in_the_hierarchy(void **state)
{
    (void)state;
    cb_model *m = load_features();
    assert_true(m->nodes[0].has_matrix);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    double j[16];
    /* At t = 1 the bone is at local (2,0,0); the parent turns +x into +y and lifts by 5:
     * the joint's origin lands at (0, 2 + 5, 0). The inverse bind matrix is identity. */
    cb_sample_joint_matrices(s, 0, 1.0, j);
    assert_float_equal(j[12], 0, 1e-12);
    assert_float_equal(j[13], 7, 1e-12);
    assert_float_equal(j[0], 0, 1e-12); /* x axis -> +y */
    assert_float_equal(j[1], 1, 1e-12);
    cb_sampler_free(s);
    cb_model_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sparse_accessor_substitutes_values),
        cmocka_unit_test(test_matrix_node_takes_part_in_the_hierarchy),
    };
    return cmocka_run_group_tests_name("gltf-features", tests, NULL, NULL);
}
