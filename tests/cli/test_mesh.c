/* test_mesh.c - `crowdbake mesh`: the .glb it writes passes the Khronos validator, reads back
 * (through the glTF loader, KHR_mesh_quantization dequantized) with joints that name the same
 * bones as the source's (a LOD's remap applied), the weights and normals it states, and skins
 * within the error it states: re-skinning the written file independently with the palette
 * model's joint matrices gives the same worst error against the source's own 4-influence
 * skinning. Fewer influences cost more (1 > 2 > 4 = 0 on Cow and Fox). A catalog's roster states
 * the same 1- and 2-influence errors (animation_lod) for Cow and Husky. */
#define _GNU_SOURCE /* memmem, M_PI */
#include "testutil.h"

#include <limits.h>
#include <math.h>

#include "catalog/catalog.h"

#define TMP TEST_TMP "/mesh"

static int setup(void **state)
{
    (void)state;
    return system("rm -rf " TMP " && mkdir -p " TMP);
}

/* Runs `crowdbake mesh ARGS --json` and returns the JSON number `key` of its output. */
static double mesh_json(const char *args, const char *key)
{
    char cmd[4096];
    static char out[1 << 14];
    snprintf(cmd, sizeof cmd, "%s mesh %s --json 2>&1", crowdbake_exe(), args);
    int rc = run_command(cmd, out, sizeof out);
    if (rc != 0) fail_msg("crowdbake mesh %s: exit %d: %s", args, rc, out);
    char pattern[128];
    snprintf(pattern, sizeof pattern, "\"%s\": ", key);
    const char *at = strstr(out, pattern);
    if (!at) fail_msg("no %s in %s", key, out);
    return strtod(at + strlen(pattern), NULL);
}

/* The worst distance, over every frame of every clip at 30 fps, between the written mesh and the
 * source's own skinning (joints through `remap`), both with the palette model's joint matrices.
 * Independent of src/core/mesh.c: the file as the glTF loader reads it. */
static double reskin_error(cb_model *palette, cb_model *source, const uint32_t *remap, cb_model *written, double *height)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(palette, 0, &err);
    assert_non_null(s);
    uint32_t bones = palette->skins[0].joint_count;
    double *mats = malloc(bones * 16 * sizeof(double)), worst = 0, lo = INFINITY, hi = -INFINITY;
    cb_sample_joint_matrices(s, -1, 0, mats);
    assert_int_equal(written->primitive_count, source->primitive_count);
    for (int32_t a = -1; a < (int32_t)palette->animation_count; ++a) {
        cb_clip_info info = {0};
        cb_limits limits = cb_default_limits();
        if (a >= 0) assert_int_equal(cb_clip_analyze(s, a, 30, -1, &limits, &info, &err), CB_OK);
        for (uint32_t f = 0; f < (a < 0 ? 1 : info.frames); ++f) {
            if (a >= 0) cb_clip_frame_matrices(s, &info, f, CB_ROOT_MOTION_KEEP, mats);
            for (uint32_t p = 0; p < source->primitive_count; ++p) {
                cb_primitive ref = source->primitives[p], *w = &written->primitives[p];
                uint32_t n = ref.vertex_count;
                assert_int_equal(w->vertex_count, n);
                uint16_t *j = malloc(n * 4 * sizeof(uint16_t));
                for (uint32_t k = 0; k < n * 4; ++k) j[k] = (uint16_t)(remap ? remap[ref.joints[k]] : ref.joints[k]);
                ref.joints = j;
                double *x = malloc(n * 3 * sizeof(double)), *y = malloc(n * 3 * sizeof(double));
                cb_skin_positions(&ref, mats, x);
                cb_skin_positions(w, mats, y);
                for (uint32_t v = 0; v < n; ++v) {
                    double d = 0;
                    for (int k = 0; k < 3; ++k) d += (x[v * 3 + k] - y[v * 3 + k]) * (x[v * 3 + k] - y[v * 3 + k]);
                    worst = fmax(worst, sqrt(d));
                    if (a < 0) lo = fmin(lo, x[v * 3 + 1]), hi = fmax(hi, x[v * 3 + 1]);
                }
                free(j), free(x), free(y);
            }
        }
    }
    *height = hi - lo;
    free(mats);
    cb_sampler_free(s);
    return worst;
}

static void check_influences(const cb_model *m, uint32_t max)
{
    for (uint32_t p = 0; p < m->primitive_count; ++p)
        for (uint32_t v = 0; v < m->primitives[p].vertex_count; ++v) {
            const float *w = m->primitives[p].weights + v * 4;
            float sum = w[0] + w[1] + w[2] + w[3];
            for (uint32_t k = max; k < 4; ++k) assert_true(w[k] == 0);
            assert_true(fabsf(sum - 1) < 1e-5f);
        }
}

/* Cow and Fox at 4, 2 and 1 influences: validator clean, weights as stated, error as stated. */
static void test_fewer_influences_skin_within_their_stated_error(void **state)
{
    (void)state;
    require_node_validators();
    const char *models[] = {"assets/quaternius-cow/Cow.glb", "assets/fox-bevy/Fox.glb"};
    for (int mi = 0; mi < 2; ++mi) {
        char model[1024], args[4096], out_glb[1024], cmd[8192], vout[8192];
        shared_path(model, sizeof model, models[mi]);
        cb_model *src = load_or_fail(model);
        double previous = -1;
        cmd[0] = 0;
        snprintf(cmd, sizeof cmd, "node tests/tools/validator/validate.mjs");
        for (uint32_t inf = 4; inf >= 1; inf /= 2) {
            snprintf(out_glb, sizeof out_glb, TMP "/%d-%u.glb", mi, inf);
            snprintf(args, sizeof args, "%s -o %s --max-influences %u", model, out_glb, inf);
            double stated = mesh_json(args, "error"), height;
            cb_model *w = load_or_fail(out_glb);
            check_influences(w, inf);
            for (uint32_t p = 0; p < src->primitive_count; ++p) { /* positions and texcoords carried as they are */
                const cb_primitive *a = &src->primitives[p], *b = &w->primitives[p];
                assert_memory_equal(a->positions, b->positions, a->vertex_count * 3 * sizeof(float));
                assert_true(!a->texcoords == !b->texcoords);
                if (a->texcoords) assert_memory_equal(a->texcoords, b->texcoords, a->vertex_count * 2 * sizeof(float));
            }
            if (mi == 1) assert_non_null(w->primitives[0].texcoords); /* Fox has them */
            double measured = reskin_error(src, src, NULL, w, &height);
            printf("  %s, %u influence(s): stated %.6g, re-skinned %.6g units (%.3f mm/m)\n", models[mi], inf, stated, measured,
                   cb_mm_per_m(measured, height));
            assert_true(fabs(measured - stated) <= 1e-6 * fmax(1, height));
            if (inf == 4) assert_true(cb_mm_per_m(measured, height) < 1e-3); /* only renormalization */
            else assert_true(measured > previous);                         /* each halving costs more */
            previous = measured;
            cb_model_free(w);
            snprintf(cmd + strlen(cmd), sizeof cmd - strlen(cmd), " %s", out_glb);
        }
        strncat(cmd, " 2>&1", sizeof cmd - strlen(cmd) - 1);
        int rc = run_command(cmd, vout, sizeof vout);
        printf("%s", vout);
        assert_int_equal(rc, 0);
        assert_null(strstr(vout, " 0 errors, 1")); /* no warnings either */
        cb_model_free(src);
    }
}

/* A LOD of the sample quadruped: its joints become the main model's bones. Each written joint
 * names the bone the source vertex used; without --palette-model (no remap) they do not. */
static uint32_t joint_name_mismatches(const cb_model *src, const cb_model *w)
{
    uint32_t bad = 0;
    const cb_primitive *a = &src->primitives[0], *b = &w->primitives[0];
    for (uint32_t k = 0; k < a->vertex_count * 4; ++k) {
        if (b->weights[k] == 0) continue; /* slots are reordered largest first: find the same joint by name */
        const char *name = w->nodes[w->skins[0].joints[b->joints[k]]].name;
        bool found = false;
        for (int i = 0; i < 4; ++i)
            found |= a->weights[k / 4 * 4 + i] != 0 &&
                     strcmp(src->nodes[src->skins[0].joints[a->joints[k / 4 * 4 + i]]].name, name) == 0;
        bad += !found;
    }
    return bad;
}

static void test_a_lod_is_remapped_to_palette_bones_and_quantized(void **state)
{
    (void)state;
    require_node_validators();
    char main_model[1024], lod[1024], args[4096], cmd[4096], out[8192];
    sample_path(main_model, sizeof main_model, "quadruped");
    sample_path(lod, sizeof lod, "quadruped_lod1");
    snprintf(args, sizeof args, "%s --palette-model %s -o " TMP "/lod.glb --max-influences 2 --quantize", lod, main_model);
    double stated = mesh_json(args, "error"), normal_deg = mesh_json(args, "normal_error_degrees"), height;
    cb_model *m = load_or_fail(main_model), *l = load_or_fail(lod), *w = load_or_fail(TMP "/lod.glb");
    assert_int_equal(w->skins[0].joint_count, m->skins[0].joint_count); /* joint k = palette bone k */
    for (uint32_t j = 0; j < m->skins[0].joint_count; ++j)
        assert_string_equal(w->nodes[w->skins[0].joints[j]].name, m->nodes[m->skins[0].joints[j]].name);
    assert_true(l->skins[0].joint_count < m->skins[0].joint_count);
    assert_int_equal(joint_name_mismatches(l, w), 0);
    /* Quantized: weights are multiples of 1/255, normals within the stated angle. */
    const cb_primitive *q = &w->primitives[0], *s = &l->primitives[0];
    for (uint32_t k = 0; k < q->vertex_count * 4; ++k) assert_true(fabsf(q->weights[k] * 255 - roundf(q->weights[k] * 255)) < 1e-4f);
    double worst_deg = 0;
    for (uint32_t v = 0; v < q->vertex_count; ++v) {
        double dot = 0, la = 0, lb = 0;
        for (int k = 0; k < 3; ++k)
            dot += q->normals[v * 3 + k] * s->normals[v * 3 + k], la += q->normals[v * 3 + k] * q->normals[v * 3 + k],
                lb += s->normals[v * 3 + k] * s->normals[v * 3 + k];
        worst_deg = fmax(worst_deg, acos(fmin(1, dot / sqrt(la * lb))) * 180 / M_PI);
    }
    uint32_t *remap = calloc(l->skins[0].joint_count, sizeof *remap);
    cb_error err = {0};
    assert_int_equal(cb_lod_remap(m, 0, l, 0, remap, &err), CB_OK);
    double measured = reskin_error(m, l, remap, w, &height);
    printf("  LOD: %u of %u bones, error stated %.6g re-skinned %.6g (%.2f mm/m); normals stated %.3f deg, read %.3f deg\n",
           l->skins[0].joint_count, m->skins[0].joint_count, stated, measured, cb_mm_per_m(measured, height), normal_deg,
           worst_deg);
    assert_true(fabs(measured - stated) <= 1e-6 * fmax(1, height));
    assert_true(worst_deg <= normal_deg + 0.01 && normal_deg > 0 && normal_deg < 1);
    /* Broken variant: the same LOD without its remap names other bones. */
    snprintf(cmd, sizeof cmd, "%s mesh %s -o " TMP "/lod-unmapped.glb 2>&1", crowdbake_exe(), lod);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    cb_model *u = load_or_fail(TMP "/lod-unmapped.glb");
    uint32_t unmapped_wrong = 0;
    for (uint32_t k = 0; k < u->primitives[0].vertex_count * 4; ++k) { /* joint index k as a main-model bone */
        if (u->primitives[0].weights[k] == 0) continue;
        unmapped_wrong += strcmp(m->nodes[m->skins[0].joints[u->primitives[0].joints[k]]].name,
                                 u->nodes[u->skins[0].joints[u->primitives[0].joints[k]]].name) != 0;
    }
    printf("  without the remap, %u joint references name another bone of the palette\n", unmapped_wrong);
    assert_true(unmapped_wrong > 100);
    snprintf(cmd, sizeof cmd, "node tests/tools/validator/validate.mjs " TMP "/lod.glb 2>&1");
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "lod.glb: 0 errors, 0 warnings"));
    free(remap);
    cb_model_free(m), cb_model_free(l), cb_model_free(w), cb_model_free(u);
}

/* --batch K: K copies, the instance id attribute declared, validator clean; the same through a
 * catalog's LOD and its lod_max_influences. */
static void test_batch_and_catalog_lod(void **state)
{
    (void)state;
    require_node_validators();
    char model[1024], cmd[4096], out[8192];
    sample_path(model, sizeof model, "fish");
    snprintf(cmd, sizeof cmd, "%s mesh %s -o " TMP "/fish-batch.glb --batch 5 --quantize 2>&1", crowdbake_exe(), model);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    cb_model *src = load_or_fail(model), *w = load_or_fail(TMP "/fish-batch.glb");
    assert_int_equal(w->primitives[0].vertex_count, 5 * src->primitives[0].vertex_count);
    assert_int_equal(w->primitives[0].index_count, 5 * src->primitives[0].index_count);
    uint32_t n = src->primitives[0].vertex_count;
    assert_memory_equal(w->primitives[0].positions + 4 * n * 3, src->primitives[0].positions, n * 3 * sizeof(float));
    size_t size, size2;
    char *glb = read_whole_file(TMP "/fish-batch.glb", &size);
    snprintf(cmd, sizeof cmd, "%s mesh %s -o " TMP "/fish-batch2.glb --batch 5 --quantize 2>&1", crowdbake_exe(), model);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    char *again = read_whole_file(TMP "/fish-batch2.glb", &size2); /* deterministic: the same bytes */
    assert_true(size == size2 && memcmp(glb, again, size) == 0);
    free(again);
    assert_non_null(memmem(glb, size, "\"_INSTANCE_ID\"", 14));
    assert_non_null(memmem(glb, size, "\"KHR_mesh_quantization\"", 23));
    free(glb);
    /* The ids as a reader of the .glb sees them: accessor _INSTANCE_ID of the binary chunk, read by Node. */
    snprintf(cmd, sizeof cmd,
             "node -e \"const b = require('fs').readFileSync('" TMP "/fish-batch.glb'); const jl = b.readUInt32LE(12);"
             " const g = JSON.parse(b.subarray(20, 20 + jl)); const bin = 20 + jl + 8;"
             " const a = g.accessors[g.meshes[0].primitives[0].attributes._INSTANCE_ID], v = g.bufferViews[a.bufferView];"
             " const f = new Float32Array(b.buffer.slice(b.byteOffset + bin + v.byteOffset, b.byteOffset + bin + v.byteOffset + 4 * a.count));"
             " let bad = 0; f.forEach((x, i) => { if (x !== Math.floor(i / %u)) bad++; });"
             " console.log(a.componentType + ' ' + a.type + ' ' + a.count + ' ids, ' + bad + ' wrong');\" 2>&1", n);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    printf("  _INSTANCE_ID: %s", out);
    char want[128];
    snprintf(want, sizeof want, "5126 SCALAR %u ids, 0 wrong", 5 * n);
    assert_non_null(strstr(out, want));
    snprintf(cmd, sizeof cmd, "node tests/tools/validator/validate.mjs " TMP "/fish-batch.glb 2>&1");
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "0 errors, 0 warnings"));
    cb_model_free(src), cb_model_free(w);
    /* A catalog: [animal.goat] with lod_max_influences = [1] meshes its LOD 1 at one influence. */
    char main_model[1024], lod[1024], cat[2 * PATH_MAX + 128], lod_abs[PATH_MAX], main_abs[PATH_MAX];
    sample_path(main_model, sizeof main_model, "quadruped");
    sample_path(lod, sizeof lod, "quadruped_lod1");
    assert_non_null(realpath(main_model, main_abs));
    assert_non_null(realpath(lod, lod_abs));
    snprintf(cat, sizeof cat, "[animal.goat]\nmodel = \"%s\"\nlods = [\"%s\"]\nlod_max_influences = [1]\n", main_abs, lod_abs);
    write_text(TMP "/catalog.toml", cat);
    snprintf(cmd, sizeof cmd, "%s mesh " TMP "/catalog.toml --type goat --lod 1 -o " TMP "/goat-lod1.glb 2>&1", crowdbake_exe());
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    printf("  %s", out);
    assert_non_null(strstr(out, "816 vertices, 1 influence,"));
    cb_model *g = load_or_fail(TMP "/goat-lod1.glb");
    check_influences(g, 1);
    cb_model_free(g);
    /* Bad input: one line naming the file and the fix, no output written. */
    snprintf(cat, sizeof cat, "[animal.goat]\nmodel = \"%s\"\nlods = [\"%s\"]\nlod_max_influences = [3]\n", main_abs, lod_abs);
    write_text(TMP "/bad.toml", cat);
    snprintf(cmd, sizeof cmd, "%s mesh " TMP "/bad.toml --type goat --lod 1 -o " TMP "/bad.glb 2>&1", crowdbake_exe());
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_INPUT);
    assert_non_null(strstr(out, "bad.toml:4:23: [animal.goat] lod_max_influences: each LOD keeps 1, 2 or 4 influences"));
    assert_null(fopen(TMP "/bad.glb", "rb"));
}

/* The roster's animation_lod (every runtime's LOD thresholds come from it) states the errors
 * `crowdbake mesh --max-influences 2|1` states for the meshes it writes, which the test above
 * re-skins independently: the same frames (every clip at 30 fps), the same worst vertex. On Cow
 * and Husky (own rig, IK-weighted paws). */
static void test_the_roster_states_the_lod_tiers_errors(void **state)
{
    (void)state;
    const char *models[] = {"assets/quaternius-cow/Cow.glb", "assets/quaternius-husky/Husky.glb"};
    for (int mi = 0; mi < 2; ++mi) {
        char model[1024], abs_model[PATH_MAX], cat[PATH_MAX + 128], cmd[8192], args[4096], out[8192];
        shared_path(model, sizeof model, models[mi]);
        assert_non_null(realpath(model, abs_model));
        snprintf(cat, sizeof cat, "[bake]\nout_dir = \"lod%d\"\nfps = 30\n[animal.a]\nmodel = \"%s\"\n", mi, abs_model);
        snprintf(args, sizeof args, TMP "/lod%d.toml", mi);
        write_text(args, cat);
        snprintf(cmd, sizeof cmd, "%s bake %s -q 2>&1", crowdbake_exe(), args);
        assert_int_equal(run_command(cmd, out, sizeof out), 0);
        snprintf(args, sizeof args, TMP "/lod%d/roster.json", mi);
        size_t size;
        char *manifest = read_whole_file(args, &size);
        double stated[2];
        for (uint32_t inf = 1; inf <= 2; ++inf) {
            snprintf(args, sizeof args, "%s -o " TMP "/lod%d-%u.glb --max-influences %u", model, mi, inf, inf);
            stated[inf - 1] = mesh_json(args, "error");
        }
        double one = json_number_in(manifest, "animation_lod", "one_influence_error");
        double two = json_number_in(manifest, "animation_lod", "two_influences_error");
        printf("  %s: animation_lod one %.6g two %.6g, crowdbake mesh states %.6g and %.6g\n", models[mi], one, two,
               stated[0], stated[1]);
        assert_true(fabs(one - stated[0]) <= 1e-6 * fmax(1, stated[0]));
        assert_true(fabs(two - stated[1]) <= 1e-6 * fmax(1, stated[1]));
        assert_true(one > two && two > 0);
        free(manifest);
    }
}

/* --quantize keeps u8 weights only where they add at most --max-quantization-error: Cow at 4
 * influences loses 1.25 mm/m with u8 weights, so it gets u16 (and 0.004 mm/m) by default. */
static void test_weights_are_quantized_where_the_error_allows(void **state)
{
    (void)state;
    char model[1024], args[2048];
    shared_path(model, sizeof model, "assets/quaternius-cow/Cow.glb");
    snprintf(args, sizeof args, "%s -o " TMP "/cow-q.glb --quantize", model);
    double bits = mesh_json(args, "weight_bits"), mm = mesh_json(args, "error_mm_per_m");
    snprintf(args, sizeof args, "%s -o " TMP "/cow-q8.glb --quantize --max-quantization-error 10", model);
    double bits8 = mesh_json(args, "weight_bits"), mm8 = mesh_json(args, "error_mm_per_m");
    printf("  Cow, 4 influences: u%.0f weights %.4f mm/m (default), u%.0f weights %.4f mm/m (allowed 10)\n", bits, mm, bits8, mm8);
    assert_true(bits == 16 && mm < 0.1 && bits8 == 8 && mm8 > 0.1 && mm8 < 10);
    cb_model *w = load_or_fail(TMP "/cow-q.glb"), *w8 = load_or_fail(TMP "/cow-q8.glb");
    bool off_u8_grid = false; /* the u16 file's weights are not all multiples of 1/255 */
    for (uint32_t k = 0; k < w->primitives[0].vertex_count * 4; ++k) {
        float x = w->primitives[0].weights[k], y = w8->primitives[0].weights[k];
        off_u8_grid |= fabsf(x * 255 - roundf(x * 255)) > 1e-3f;
        assert_true(fabsf(x * 65535 - roundf(x * 65535)) < 1e-2f && fabsf(y * 255 - roundf(y * 255)) < 1e-4f);
    }
    assert_true(off_u8_grid);
    cb_model_free(w), cb_model_free(w8);
}

/* The n-th number after `key` in text, from position `from` on. */
static double number_after(const char *text, const char *key, int n)
{
    const char *at = text;
    for (int i = 0; i <= n; ++i) {
        at = strstr(at, key);
        if (!at) fail_msg("no %d-th %s", n, key);
        at += strlen(key);
    }
    return strtod(at, NULL);
}

/* `report` counts the runtime meshes as `mesh` writes them, the batch and the transitions. */
static void test_report_counts_runtime_meshes_batches_and_transitions(void **state)
{
    (void)state;
    char model[1024], cmd[4096], info[1 << 16];
    static char out[1 << 17];
    shared_path(model, sizeof model, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd, "%s report %s --json --no-fail 2>&1", crowdbake_exe(), model);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    const char *rt = strstr(out, "\"runtime\"");
    assert_non_null(rt);
    for (int k = 0; k < 3; ++k) { /* 4, 2, 1 influences: the same numbers as `mesh --quantize` */
        const unsigned influences[3] = {4, 2, 1}, inf = influences[k];
        char args[2048];
        snprintf(args, sizeof args, "%s -o " TMP "/report-%u.glb --max-influences %u --quantize", model, inf, inf);
        double error = mesh_json(args, "error"), vb = mesh_json(args, "vertex_buffer_bytes");
        printf("  %u influences: report %.9g, mesh %.9g units; %0.f vertex bytes\n", inf, number_after(rt, "\"error\": ", k),
               error, vb);
        assert_int_equal((int)number_after(rt, "\"max_influences\": ", k), (int)inf);
        assert_true(fabs(number_after(rt, "\"error\": ", k) - error) <= 1e-8 * fmax(1, error));
        assert_true(number_after(rt, "\"vertex_bytes\": ", k) == vb);
    }
    assert_true(number_after(rt, "\"error\": ", 2) > number_after(rt, "\"error\": ", 1));
    /* 100 copies: what `mesh --batch 100` writes; instancing: one mesh and 16 bytes a copy. */
    char args[2048];
    snprintf(args, sizeof args, "%s -o " TMP "/report-batch.glb --batch 100 --quantize", model);
    double batch = mesh_json(args, "vertex_buffer_bytes") + mesh_json(args, "index_buffer_bytes");
    double vb = number_after(rt, "\"vertex_bytes\": ", 0), ib = number_after(rt, "\"index_bytes\": ", 0);
    printf("  batch of 100: report %.0f, mesh --batch 100 %.0f bytes\n", number_after(rt, "\"batched_bytes\": ", 0), batch);
    assert_true(number_after(rt, "\"batched_bytes\": ", 0) == batch);
    assert_true(number_after(rt, "\"instanced_bytes\": ", 0) == vb + ib + 1600);
    /* Transitions: one into each loop from every other loop, 0.5 s at the destination's rate (the
     * default bake's, per clip, as `inspect` reads them from the palette) in rows of 84 u16 texels. */
    snprintf(cmd, sizeof cmd, "%s info %s --json 2>&1", crowdbake_exe(), model);
    assert_int_equal(run_command(cmd, info, sizeof info), 0);
    int loops = 0;
    for (const char *p = info; (p = strstr(p, "\"loops\": true")); ++p) ++loops;
    assert_int_equal((int)number_after(rt, "\"loops\": ", 0), loops);
    snprintf(cmd, sizeof cmd,
             "%s bake %s -o " TMP "/report-default.pal -q && %s inspect " TMP "/report-default.pal --json | python3 -c "
             "\"import json, sys; c = [x for x in json.load(sys.stdin)['clips'] if x['loops']]; "
             "print(sum((len(c) - 1) * (int(0.5 * x['fps'] + 0.5) + 1) for x in c))\"",
             crowdbake_exe(), model, crowdbake_exe());
    assert_int_equal(run_command(cmd, info, sizeof info), 0);
    assert_true(number_after(rt, "\"prebaked_transition_bytes\": ", 0) == strtod(info, NULL) * 84 * 8);
}

/* Bad input: one line naming the file or option and the fix, the exit code, no file written. */
static void test_bad_input_is_refused_with_the_fix(void **state)
{
    (void)state;
    char fish[1024], fox[1024], cmd[4096], out[4096];
    sample_path(fish, sizeof fish, "fish");
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    const struct {
        const char *args, *message;
        int rc;
    } cases[] = {
        {"%s -o " TMP "/bad.obj", "the mesh is written as a .glb; name it OUT.glb", EXIT_USAGE},
        {"%s -o " TMP "/bad.glb --max-influences 3", "--max-influences is 1, 2 or 4", EXIT_USAGE},
        {"%s -o " TMP "/bad.glb --batch 0", "--batch wants a count of copies from 1 to 65536", EXIT_USAGE},
        {"%s -o " TMP "/bad.glb --lod 1", "--type and --lod pick a catalog's type and LOD", EXIT_USAGE},
        {"%s -o " TMP "/bad.glb --max-quantization-error 1", "--max-quantization-error goes with --quantize", EXIT_USAGE},
        {"%s -o " TMP "/bad.glb --palette-model %s", "fish.glb: LOD joint 'root' is not a joint of", EXIT_INPUT},
    };
    for (size_t i = 0; i < COUNT_OF(cases); ++i) {
        char args[3072];
        snprintf(args, sizeof args, cases[i].args, fish, fox);
        snprintf(cmd, sizeof cmd, "%s mesh %s 2>&1", crowdbake_exe(), args);
        int rc = run_command(cmd, out, sizeof out);
        printf("  %d: %s", rc, out);
        assert_int_equal(rc, cases[i].rc);
        assert_non_null(strstr(out, cases[i].message));
        assert_ptr_equal(strchr(out, '\n'), out + strlen(out) - 1); /* one line */
    }
    assert_null(fopen(TMP "/bad.glb", "rb"));
    assert_null(fopen(TMP "/bad.obj", "rb"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fewer_influences_skin_within_their_stated_error),
        cmocka_unit_test(test_a_lod_is_remapped_to_palette_bones_and_quantized),
        cmocka_unit_test(test_batch_and_catalog_lod),
        cmocka_unit_test(test_the_roster_states_the_lod_tiers_errors),
        cmocka_unit_test(test_report_counts_runtime_meshes_batches_and_transitions),
        cmocka_unit_test(test_weights_are_quantized_where_the_error_allows),
        cmocka_unit_test(test_bad_input_is_refused_with_the_fix),
    };
    return cmocka_run_group_tests_name("mesh", tests, setup, NULL);
}
