/* test_gl_conformance.c - the runtime conformance cases (conformance.h: the one set every runtime's
 * test reads) through the shipped GLSL on a real OpenGL, Mesa's llvmpipe: every case's instances,
 * cross-fades included, skinned by cb_skin_position_crossfade (the direct path) and by cb_bone_pass (the bone
 * pass's function, called per vertex) and captured with transform feedback, against the C runtime's expected
 * positions within 1e-5 of the model's height; local rows (CB_LOCAL_ROWS) composed both ways, cross-fades faded
 * before composing (cb_runtime_matrices_crossfade); timed rows (.pal version 7) through their maps; every broken
 * case that GL can express (bones transposed, rows off by one, a shader line broken, local rows not composed, a timed
 * clip's map ignored or its read skipped) misses by far. The bone-pass cases (its textures) are the web runtime's
 * (runtimes/web/crowdbake_bones.mjs) and are run there. */
#define _DEFAULT_SOURCE
#define GL_GLEXT_PROTOTYPES
#include "testutil.h"

#include <math.h>

#include "runtimes/conformance.h"
#include "runtimes/gl_harness.h"

#define TMP TEST_TMP "/gl-conformance"
#define LOCAL_ROWS_DEFINE(p) ((p)->bone_space == CB_BONE_SPACE_LOCAL ? "#define CB_LOCAL_ROWS\n" : "")

/* How a case's vertices are skinned: the direct path (cb_skin_position_crossfade), or each influence's bone from
 * cb_bone_pass (the bone pass's fragment function, called here per vertex: the columns it would write to the bone
 * texture, applied as cb_skin_bone_pass applies them), which composes local rows per bone where the direct path
 * composes them per influence. */
typedef enum { PATH_DIRECT, PATH_BONE_PASS } skin_path;

static const char *const SKIN_DIRECT =
    "    v_skinned = cb_skin_position_crossfade(a_position, a_joints, a_weights, a_from, a_instance, fade, a_time);\n";
static const char *const SKIN_BONE_PASS =
    "    v_skinned = vec3(0.0);\n"
    "    for (int i = 0; i < 4; ++i) {\n"
    "        if (a_weights[i] == 0.0) continue;\n"
    "        vec4 c0, c1, c2;\n"
    "        cb_bone_pass(a_joints[i], a_from, a_instance, fade, a_time, c0, c1, c2);\n"
    "        v_skinned += a_weights[i] * (mat3(c0.xyz, c1.xyz, c2.xyz) * a_position + vec3(c0.w, c1.w, c2.w));\n"
    "    }\n";

static GLuint compile_crossfade(const cb_palette *p, const char *library, skin_path path)
{
    static char src[1 << 17];
    snprintf(src, sizeof src,
             "#version 330 core\n#define %s\n#define %s\n%s%s%s\n"
             "in vec3 a_position; in ivec4 a_joints; in vec4 a_weights; in vec4 a_instance; in float a_time;\n"
             "layout(location = 6) in vec4 a_from; layout(location = 7) in vec2 a_fade;\nout vec3 v_skinned;\n"
             "void main() {\n"
             "    float fade = a_fade.y > 0.0 ? clamp((a_time - a_fade.x) / a_fade.y, 0.0, 1.0) : 1.0;\n%s"
             "    gl_Position = vec4(0.0);\n}\n",
             layout_define[p->layout], precision_define[p->precision],
             p->positions_relative ? "#define CB_POSITIONS_RELATIVE\n" : "", LOCAL_ROWS_DEFINE(p), library,
             path == PATH_BONE_PASS ? SKIN_BONE_PASS : SKIN_DIRECT);
    return link_program(src, false); /* a_from and a_fade at the locations their layout names */
}

/* One vertex attribute of `total` points, `comps` components (ints for location 1, the joints). */
static void attribute(GLuint vbo, GLuint location, int comps, const void *data, uint32_t total)
{
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)total * comps * 4, data, GL_STATIC_DRAW);
    glEnableVertexAttribArray(location);
    if (location == 1) glVertexAttribIPointer(1, comps, GL_INT, 0, 0);
    else glVertexAttribPointer(location, comps, GL_FLOAT, GL_FALSE, 0, 0);
}

/* Every instance of every group of a case, each vertex a point: the skinned positions, in the
 * expected file's order. */
static float *gpu_case(const conformance *c, const conf_case *k, GLuint prog)
{
    const conf_palette *p = &c->palettes[k->palette];
    const cb_primitive *prim = &p->model->primitives[0];
    uint32_t verts = prim->vertex_count, total = (uint32_t)conf_positions(c, k);
    float *pos = malloc(total * 12), *w = malloc(total * 16), *inst = malloc(total * 16), *from = malloc(total * 16),
          *fade = malloc(total * 8), *time = malloc(total * 4);
    int32_t *j = malloc(total * 16);
    uint32_t at = 0;
    for (int t = 0; t < CONF_TIMES; ++t)
        for (uint32_t cl = 0; cl < p->view.clip_count; ++cl)
            for (int i = 0; i < CONF_PER_CLIP; ++i) {
                float v[16];
                conf_instance(&p->view.clips[cl], conf_times[t], i, k->row_offset, v);
                for (uint32_t x = 0; x < verts; ++x, ++at) {
                    memcpy(pos + at * 3, prim->positions + x * 3, 12);
                    memcpy(w + at * 4, prim->weights + x * 4, 16);
                    for (int q = 0; q < 4; ++q) j[at * 4 + q] = prim->joints[x * 4 + q];
                    memcpy(inst + at * 4, v + 4, 16);
                    memcpy(from + at * 4, v + 8, 16);
                    memcpy(fade + at * 2, v + 12, 8);
                    time[at] = (float)conf_times[t];
                }
            }
    GLuint vao, vbo[7], out, tex[2];
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glGenBuffers(7, vbo);
    attribute(vbo[0], 0, 3, pos, total), attribute(vbo[1], 1, 4, j, total), attribute(vbo[2], 2, 4, w, total);
    attribute(vbo[3], 3, 4, inst, total), attribute(vbo[4], 4, 1, time, total);
    attribute(vbo[5], 6, 4, from, total), attribute(vbo[6], 7, 2, fade, total);
    glGenBuffers(1, &out);
    glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, out);
    glBufferData(GL_TRANSFORM_FEEDBACK_BUFFER, (GLsizeiptr)total * 12, NULL, GL_STATIC_READ);
    glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, out);
    cb_palette view = p->view; /* the view leaves the texels in the file */
    view.texels = (void *)p->pal.texels; /* read only: upload() copies from it */
    use_palette(&view, prog, k->transpose, tex);
    glEnable(GL_RASTERIZER_DISCARD);
    glBeginTransformFeedback(GL_POINTS);
    glDrawArrays(GL_POINTS, 0, (GLsizei)total);
    glEndTransformFeedback();
    glDisable(GL_RASTERIZER_DISCARD);
    float *result = malloc((size_t)total * 12);
    glGetBufferSubData(GL_TRANSFORM_FEEDBACK_BUFFER, 0, (GLsizeiptr)total * 12, result);
    assert_int_equal(glGetError(), GL_NO_ERROR);
    glDeleteBuffers(7, vbo);
    glDeleteBuffers(1, &out);
    glDeleteVertexArrays(1, &vao);
    glDeleteTextures(tex[1] ? 2 : 1, tex);
    free(pos), free(w), free(inst), free(from), free(fade), free(time), free(j);
    return result;
}

/* The GLSL library's cross-fade on Mesa (ctx: the skin_path), its output captured by transform feedback. */
static float *gl_case(const conformance *c, const conf_case *k, const char *source, void *ctx)
{
    GLuint prog = compile_crossfade(&c->palettes[k->palette].view, source, *(const skin_path *)ctx);
    float *got = gpu_case(c, k, prog);
    glDeleteProgram(prog);
    return got;
}

/* Every case that is not broken (nor the web runtime's bone pass) through cb_bone_pass: the same tolerance. */
static void check_bone_pass(const conformance *c, const char *lib)
{
    skin_path path = PATH_BONE_PASS;
    int ran = 0;
    for (int i = 0; i < c->case_count; ++i) {
        const conf_case *k = &c->cases[i];
        if (k->bone_pass || k->broken) continue;
        float *got = gl_case(c, k, lib, &path);
        double units, ratio = conformance_compare(c, k, got, &units);
        printf("  %-26s %7zu positions: cb_bone_pass vs C runtime %.2g (%.2f of the tolerance)\n", k->name,
               conf_positions(c, k), units, ratio);
        assert_true(ratio <= 1);
        ++ran;
        free(got);
    }
    assert_true(ran >= 15);
}

/* The cases of one kind with a line of the library broken (the line holding `marker` replaced by `line`): the
 * direct path and cb_bone_pass must both miss by far, every one. Returns how many cases ran. */
static int check_broken_line(const conformance *c, const char *lib, const char *marker, const char *line, bool timed,
                             const char *what)
{
    static const char *const names[2] = {"direct", "cb_bone_pass"};
    char *broken = break_shader(lib, marker, line);
    int ran = 0;
    for (int i = 0; i < c->case_count; ++i) {
        const conf_case *k = &c->cases[i];
        if (timed ? !k->timed || k->broken : !k->local) continue;
        for (skin_path path = PATH_DIRECT; path <= PATH_BONE_PASS; path = (skin_path)(path + 1)) {
            float *got = gl_case(c, k, broken, &path);
            double units, ratio = conformance_compare(c, k, got, &units);
            printf("  %-18s %-12s %s: %.0f tolerances off\n", k->name, names[path], what, ratio);
            assert_true(ratio > 10);
            free(got);
        }
        ++ran;
    }
    free(broken);
    return ran;
}

static void test_conformance_cases(void **state)
{
    (void)state;
    conformance conf;
    conformance_make(&conf, TMP);
    char *lib = read_whole_file(GLSL_PATH, NULL);
    skin_path direct = PATH_DIRECT;
    conformance_check_shader(&conf, lib, gl_case, &direct); /* local cases too: the library knows CB_LOCAL_ROWS */
    check_bone_pass(&conf, lib);
    /* Local rows (.pal version 6) with the compose line removed (each bone its local row alone): local_qpos_u16,
     * local_qpos_float, local_blocks, timed_local. */
    assert_int_equal(check_broken_line(&conf, lib, "cb:local-compose", "", false, "compose skipped"), 4);
    /* Timed rows (.pal version 7) with the map read replaced by the cell taken as a row (the map ignored, as a
     * runtime that knows no timed rows would play the cells). */
    assert_true(check_broken_line(&conf, lib, "cb:timed-map", "        vec4 m = vec4(cell, cell + 1.0, 0.0, 1.0);", true,
                                  "map skipped") >= 7);
    free(lib);
    conformance_free(&conf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_conformance_cases),
    };
    return cmocka_run_group_tests_name("gl_conformance", tests, setup, teardown);
}
