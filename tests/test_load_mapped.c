/* test_load_mapped.c - model files of 1 MiB and more are mapped (formats/gltf_container.cpp,
 * map_model), not read: the model is the one loading the same bytes from memory gives, its
 * source hash (hashed on a second thread) is the same, and writes into buffers the model reads
 * in place stay private: the file on disk never changes. */
#include "testutil.h"

#include "crowdbake/gltf.h"

static void test_mapped_load_equals_memory_load_and_writes_stay_private(void **state)
{
    (void)state;
    char path[1024];
    shared_path(path, sizeof path, "assets/robot-quaternius-raylib/robot.glb");
    size_t size = 0;
    unsigned char *before = (unsigned char *)read_whole_file(path, &size);
    assert_non_null(before);
    assert_true(size >= (1u << 20)); /* mapped, not read */
    cb_error err = {0};
    cb_model *mapped = cb_gltf_load(path, NULL, &err);
    cb_model *memory = cb_gltf_load_memory(before, size, path, NULL, NULL, &err);
    if (!mapped || !memory) fail_msg("%s", err.message);
    assert_true(mapped->source_hash == memory->source_hash);
    assert_int_equal(mapped->animation_count, memory->animation_count);
    uint32_t rotations = 0;
    for (uint32_t a = 0; a < mapped->animation_count; ++a) {
        const cb_animation *x = &mapped->animations[a], *y = &memory->animations[a];
        assert_int_equal(x->channel_count, y->channel_count);
        for (uint32_t c = 0; c < x->channel_count; ++c) {
            const cb_channel *p = &x->channels[c], *q = &y->channels[c];
            int per_key = p->path == CB_PATH_ROTATION ? 4 : 3;
            assert_int_equal(p->key_count, q->key_count);
            assert_memory_equal(p->times, q->times, p->key_count * sizeof(float));
            assert_memory_equal(p->values, q->values, (size_t)p->key_count * per_key * sizeof(float));
            if (p->path != CB_PATH_ROTATION || rotations++) continue;
            /* What the loader does to rotation keys that are not unit length, where they lie:
             * a copy-on-write page of the mapping, never the file. */
            p->values[0] = -p->values[0];
        }
    }
    assert_true(rotations > 0);
    const cb_skin *a = &mapped->skins[0], *b = &memory->skins[0];
    assert_int_equal(a->joint_count, b->joint_count);
    assert_memory_equal(a->inverse_bind, b->inverse_bind, a->joint_count * 16 * sizeof(double));
    cb_model_free(mapped);
    size_t size_after = 0;
    unsigned char *after = (unsigned char *)read_whole_file(path, &size_after);
    assert_true(size_after == size && memcmp(before, after, size) == 0);
    cb_model_free(memory);
    free(before), free(after);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mapped_load_equals_memory_load_and_writes_stay_private),
    };
    return cmocka_run_group_tests_name("load_mapped", tests, NULL, NULL);
}
