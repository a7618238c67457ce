/* test_load_mapped.c - model files of 1 MiB and more are mapped (formats/gltf_container.cpp,
 * map_model), not read: the model is the one loading the same bytes from memory gives, its
 * source hash (hashed on a second thread) is the same. The mapping is read-only: rotation keys
 * the loader normalizes are copies outside it, and nothing can write into it. A bake drops a
 * clip's key pages once it has sampled and measured it (cb_model.release); reading them again
 * gives the file's bytes, so palettes stay byte-identical however often they are dropped. */
#define _DEFAULT_SOURCE /* realpath */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <fcntl.h>
#include <unistd.h>

#include "crowdbake/gltf.h"
#include "crowdbake/palette.h"

#define TMP TEST_TMP "/load_mapped"

/* The mapping of `path` in this process, from /proc/self/maps: its range and permissions. */
typedef struct mapping {
    uintptr_t begin, end;
    char perms[5];
} mapping;

static bool find_mapping(const char *path, mapping *out)
{
    char real[4096], line[4096 + 256];
    if (!realpath(path, real)) return false;
    FILE *f = fopen("/proc/self/maps", "r");
    assert_non_null(f);
    bool found = false;
    while (!found && fgets(line, sizeof line, f)) {
        char *name = strchr(line, '/');
        if (!name) continue;
        name[strcspn(name, "\n")] = 0;
        unsigned long b, e;
        found = strcmp(name, real) == 0 && sscanf(line, "%lx-%lx %4s", &b, &e, out->perms) == 3;
        out->begin = b, out->end = e;
    }
    fclose(f);
    return found;
}

/* Kilobytes of the mapping at `begin` resident in this process (/proc/self/smaps). */
static long resident_kb(uintptr_t begin)
{
    char line[4352];
    FILE *f = fopen("/proc/self/smaps", "r");
    assert_non_null(f);
    long kb = -1;
    bool in = false;
    while (kb < 0 && fgets(line, sizeof line, f)) {
        unsigned long b, e;
        if (sscanf(line, "%lx-%lx ", &b, &e) == 2) /* a mapping's first line; its fields start "Name:" */
            in = b == begin;
        else if (in && strncmp(line, "Rss:", 4) == 0)
            kb = strtol(line + 4, NULL, 10);
    }
    fclose(f);
    return kb;
}

static bool inside(const mapping *m, const void *p, size_t bytes)
{
    uintptr_t a = (uintptr_t)p;
    return a >= m->begin && a + bytes <= m->end;
}

static size_t channel_values(const cb_channel *ch)
{
    return (size_t)ch->key_count * (ch->path == CB_PATH_ROTATION ? 4 : 3) * (ch->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
}

/* A rig of `joints` x `clips` x `seconds` from gen_samples --bench, over 1 MiB (so mapped). */
static void generate_rig(char *path, size_t size)
{
    char gen[1100], cmd[2400];
    snprintf(gen, sizeof gen, "%s", crowdbake_exe());
    *strrchr(gen, '/') = 0;
    snprintf(cmd, sizeof cmd, "mkdir -p " TMP " && %s/gen_samples --bench " TMP " 100 4 6 >/dev/null", gen);
    assert_int_equal(system(cmd), 0);
    snprintf(path, size, TMP "/bench_j100_c4_s6.glb");
}

static void test_mapped_load_equals_memory_load_and_mapping_is_read_only(void **state)
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
    assert_non_null(mapped->release);   /* keys read in place from the mapping: droppable */
    assert_null(memory->release);       /* the caller's bytes: never */
    mapping map;
    assert_true(find_mapping(path, &map));
    assert_string_equal(map.perms, "r--p");
    assert_int_equal(mapped->animation_count, memory->animation_count);
    uint32_t in_place = 0, copied = 0;
    int zero = open("/dev/zero", O_RDONLY);
    assert_true(zero >= 0);
    for (uint32_t a = 0; a < mapped->animation_count; ++a) {
        const cb_animation *x = &mapped->animations[a], *y = &memory->animations[a];
        assert_int_equal(x->channel_count, y->channel_count);
        for (uint32_t c = 0; c < x->channel_count; ++c) {
            const cb_channel *p = &x->channels[c], *q = &y->channels[c];
            size_t values = channel_values(p);
            assert_int_equal(p->key_count, q->key_count);
            assert_memory_equal(p->times, q->times, p->key_count * sizeof(float));
            assert_memory_equal(p->values, q->values, values * sizeof(float));
            if (p->path != CB_PATH_ROTATION) continue;
            if (!inside(&map, p->values, values * sizeof(float))) {
                copied++; /* normalized in the model's arena */
                continue;
            }
            in_place++;
            /* Nothing can write there: the kernel refuses to copy into it (EFAULT) where a
             * writable private mapping would take the bytes. */
            errno = 0;
            if (in_place == 1) assert_int_equal(read(zero, p->values, sizeof(float)), -1), assert_int_equal(errno, EFAULT);
            for (uint32_t k = 0; k < p->key_count; ++k) { /* only unit keys stay in place */
                const float *r = p->values + (size_t)k * 4;
                double len2 = (double)r[0] * r[0] + (double)r[1] * r[1] + (double)r[2] * r[2] + (double)r[3] * r[3];
                assert_true(fabs(len2 - 1) <= 0x1p-22);
            }
        }
    }
    close(zero);
    /* robot.glb: 602 rotation outputs, 38 of them with a key whose squared length is off 1 by
     * more than 2^-22 (counted from the file's floats with Python's struct module). */
    assert_int_equal(copied, 38);
    assert_int_equal(in_place, 602 - 38);
    cb_model_free(mapped);
    size_t size_after = 0;
    unsigned char *after = (unsigned char *)read_whole_file(path, &size_after);
    assert_true(size_after == size && memcmp(before, after, size) == 0);
    cb_model_free(memory);
    free(before), free(after);
}

/* A release hook that drops every clip's keys whenever the bake drops one: each clip is read
 * back from the page cache again and again while it is sampled and measured. Read-only state,
 * so it is safe on the bake's threads. */
typedef struct stress {
    void (*release)(void *ctx, const cb_byte_range *ranges, size_t count);
    void *ctx;
    cb_byte_range *all;
    size_t count;
    int calls;
} stress;

static void stress_release(void *ctx, const cb_byte_range *ranges, size_t count)
{
    stress *s = ctx;
    __atomic_fetch_add(&s->calls, 1, __ATOMIC_RELAXED);
    s->release(s->ctx, ranges, count);
    s->release(s->ctx, s->all, s->count);
}

static void stress_model(cb_model *m, stress *s)
{
    memset(s, 0, sizeof *s);
    size_t n = 0;
    for (uint32_t a = 0; a < m->animation_count; ++a) n += 2 * m->animations[a].channel_count;
    s->all = malloc((n ? n : 1) * sizeof *s->all);
    assert_non_null(s->all);
    for (uint32_t a = 0; a < m->animation_count; ++a)
        for (uint32_t c = 0; c < m->animations[a].channel_count; ++c) {
            const cb_channel *ch = &m->animations[a].channels[c];
            s->all[s->count++] = (cb_byte_range){ch->times, ch->key_count * sizeof(float)};
            s->all[s->count++] = (cb_byte_range){ch->values, channel_values(ch) * sizeof(float)};
        }
    s->release = m->release, s->ctx = m->release_ctx;
    if (m->release) m->release = stress_release, m->release_ctx = s;
}

static cb_status bake(cb_model *m, cb_layout layout, cb_precision precision, cb_palette *p, cb_error *err)
{
    cb_sampler *s = cb_sampler_create(m, 0, err);
    if (!s) return err->status;
    cb_bake_options o = cb_default_bake_options();
    o.layout = layout, o.precision = precision, o.threads = 2, o.affine_fallback = true;
    cb_status rc = cb_palette_bake(s, &o, NULL, 0, p, err);
    cb_sampler_free(s);
    return rc;
}

/* One model loaded from its file (mapped when 1 MiB and more, its keys dropped all the time)
 * and from memory (never dropped): the same palettes, errors included (measuring samples the
 * keys again), and after the bakes the same keys. */
static void expect_same_bakes(const char *path, bool must_map)
{
    size_t size = 0;
    unsigned char *bytes = (unsigned char *)read_whole_file(path, &size);
    assert_non_null(bytes);
    cb_error err = {0};
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", path);
    *strrchr(dir, '/') = 0; /* for a .gltf's own files */
    cb_model *file = cb_gltf_load(path, NULL, &err);
    cb_model *memory = cb_gltf_load_memory(bytes, size, path, dir, NULL, &err);
    if (!file || !memory) fail_msg("%s: %s", path, err.message);
    if (must_map) assert_non_null(file->release);
    stress s;
    stress_model(file, &s);
    static const struct { cb_layout layout; cb_precision precision; } encodings[] = {
        {CB_LAYOUT_QPOS, CB_PRECISION_U16}, {CB_LAYOUT_MAT4, CB_PRECISION_FLOAT}, {CB_LAYOUT_AFFINE, CB_PRECISION_HALF}};
    for (size_t e = 0; e < COUNT_OF(encodings) && file->skin_count; ++e) {
        cb_palette a, b;
        cb_error ea = {0}, eb = {0};
        cb_status ra = bake(file, encodings[e].layout, encodings[e].precision, &a, &ea);
        cb_status rb = bake(memory, encodings[e].layout, encodings[e].precision, &b, &eb);
        assert_int_equal(ra, rb);
        if (ra) {
            assert_string_equal(ea.message, eb.message);
            continue;
        }
        assert_int_equal(a.texel_bytes, b.texel_bytes);
        if (memcmp(a.texels, b.texels, a.texel_bytes) != 0) fail_msg("%s: encoding %zu: texels differ", path, e);
        assert_true(a.max_error == b.max_error && a.visible_error == b.visible_error);
        cb_palette_free(&a), cb_palette_free(&b);
    }
    if (must_map && file->skin_count) assert_true(s.calls > 0);
    for (uint32_t a = 0; a < file->animation_count; ++a)
        for (uint32_t c = 0; c < file->animations[a].channel_count; ++c) {
            const cb_channel *p = &file->animations[a].channels[c], *q = &memory->animations[a].channels[c];
            if (memcmp(p->values, q->values, channel_values(p) * sizeof(float)) || memcmp(p->times, q->times, p->key_count * sizeof(float)))
                fail_msg("%s: clip %u channel %u: keys differ after the bakes dropped them", path, a, c);
        }
    cb_model_free(file), cb_model_free(memory);
    free(s.all), free(bytes);
}

static void test_dropped_keys_bake_the_same_palettes(void **state)
{
    (void)state;
    char path[1024];
    for (size_t i = 0; i < COUNT_OF(shared_models); ++i) {
        shared_path(path, sizeof path, shared_models[i]);
        expect_same_bakes(path, strstr(path, "robot.glb") != NULL);
    }
    generate_rig(path, sizeof path);
    expect_same_bakes(path, true);
}

/* Releasing every clip gives the key pages back: the mapping's resident size falls by most of
 * the keys' bytes, and they read back as they were. */
static void test_release_drops_the_key_pages(void **state)
{
    (void)state;
    char path[1024];
    generate_rig(path, sizeof path);
    cb_error err = {0};
    cb_model *m = cb_gltf_load(path, NULL, &err);
    if (!m) fail_msg("%s", err.message);
    mapping map;
    assert_true(find_mapping(path, &map));
    size_t key_bytes = 0, keys = 0;
    for (uint32_t a = 0; a < m->animation_count; ++a)
        for (uint32_t c = 0; c < m->animations[a].channel_count; ++c) {
            const cb_channel *ch = &m->animations[a].channels[c];
            key_bytes += channel_values(ch) * sizeof(float) + (c == 0 || ch->times != ch[-1].times ? ch->key_count * sizeof(float) : 0);
            keys += channel_values(ch);
        }
    float *copy = malloc(keys * sizeof(float)), *at = copy;
    assert_non_null(copy);
    for (uint32_t a = 0; a < m->animation_count; ++a)
        for (uint32_t c = 0; c < m->animations[a].channel_count; ++c) {
            const cb_channel *ch = &m->animations[a].channels[c];
            memcpy(at, ch->values, channel_values(ch) * sizeof(float)), at += channel_values(ch);
        }
    long before = resident_kb(map.begin);
    for (uint32_t a = 0; a < m->animation_count; ++a) cb_model_release_clip(m, (int32_t)a);
    long after = resident_kb(map.begin);
    assert_true(key_bytes > (map.end - map.begin) / 2); /* the keys are most of the file */
    if (!(before - after >= (long)(key_bytes * 9 / 10 / 1024)))
        fail_msg("resident %ld kB before, %ld kB after releasing %zu bytes of keys", before, after, key_bytes);
    at = copy;
    for (uint32_t a = 0; a < m->animation_count; ++a)
        for (uint32_t c = 0; c < m->animations[a].channel_count; ++c) {
            const cb_channel *ch = &m->animations[a].channels[c];
            assert_memory_equal(at, ch->values, channel_values(ch) * sizeof(float));
            at += channel_values(ch);
        }
    cb_model_free(m);
    free(copy);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mapped_load_equals_memory_load_and_mapping_is_read_only),
        cmocka_unit_test(test_dropped_keys_bake_the_same_palettes),
        cmocka_unit_test(test_release_drops_the_key_pages),
    };
    return cmocka_run_group_tests_name("load_mapped", tests, NULL, NULL);
}
