/* test_gl.c - the shipped GLSL (runtimes/glsl/crowdbake_palette.glsl) run on a real OpenGL:
 * Mesa's llvmpipe through OSMesa, no GPU. Transform feedback captures the skinned positions of
 * many instances at many times; they must match the CPU runtime (src/core/runtime.c, which verify
 * compares with exact skinning). Deliberately broken variants - transposed matrices, rows off
 * by one, a wrong wrap, no hemisphere flip, a timed clip's map ignored - must fail the same comparison. */
#define _DEFAULT_SOURCE
#define GL_GLEXT_PROTOTYPES
#include "testutil.h"

#include <math.h>

#include "runtimes/gl_harness.h"

#include "core/timed_rows.h" /* timed_map_fill: a timed palette made here, before the bake makes them */
#include "crowdbake/mesh.h"
#include "crowdbake/runtime.h"

typedef struct sample {
    cb_instance inst;
    double time;
} sample;

/* Skins every vertex of `prim` for every sample on the GPU; returns 3 floats per (sample, vertex). */
static float *gpu_skin(const cb_palette *p, const cb_primitive *prim, const sample *samples, uint32_t n, GLuint prog,
                       bool transpose, double row_offset)
{
    uint32_t verts = prim->vertex_count, total = verts * n;
    float *pos = malloc(total * 3 * sizeof(float)), *w = malloc(total * 4 * sizeof(float)), *inst = malloc(total * 4 * sizeof(float)),
          *time = malloc(total * sizeof(float));
    int32_t *j = malloc(total * 4 * sizeof(int32_t));
    for (uint32_t s = 0; s < n; ++s)
        for (uint32_t v = 0; v < verts; ++v) {
            uint32_t i = s * verts + v;
            memcpy(pos + i * 3, prim->positions + v * 3, 3 * sizeof(float));
            memcpy(w + i * 4, prim->weights + v * 4, 4 * sizeof(float));
            for (int k = 0; k < 4; ++k) j[i * 4 + k] = prim->joints[v * 4 + k];
            inst[i * 4] = (float)(samples[s].inst.first_row + row_offset);
            inst[i * 4 + 1] = (float)samples[s].inst.frame_count;
            inst[i * 4 + 2] = (float)samples[s].inst.rate;
            inst[i * 4 + 3] = (float)samples[s].inst.phase;
            time[i] = (float)samples[s].time;
        }
    GLuint vao, vbo[5], out, tex[2];
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glGenBuffers(5, vbo);
    const void *data[5] = {pos, j, w, inst, time};
    const int comps[5] = {3, 4, 4, 4, 1};
    for (int a = 0; a < 5; ++a) {
        glBindBuffer(GL_ARRAY_BUFFER, vbo[a]);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)total * comps[a] * 4, data[a], GL_STATIC_DRAW);
        glEnableVertexAttribArray((GLuint)a);
        if (a == 1) glVertexAttribIPointer(1, 4, GL_INT, 0, 0);
        else glVertexAttribPointer((GLuint)a, comps[a], GL_FLOAT, GL_FALSE, 0, 0);
    }
    glGenBuffers(1, &out);
    glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, out);
    glBufferData(GL_TRANSFORM_FEEDBACK_BUFFER, (GLsizeiptr)total * 12, NULL, GL_STATIC_READ);
    glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, out);
    use_palette(p, prog, transpose, tex);
    glEnable(GL_RASTERIZER_DISCARD);
    glBeginTransformFeedback(GL_POINTS);
    glDrawArrays(GL_POINTS, 0, (GLsizei)total);
    glEndTransformFeedback();
    glDisable(GL_RASTERIZER_DISCARD);
    float *result = malloc(total * 12);
    glGetBufferSubData(GL_TRANSFORM_FEEDBACK_BUFFER, 0, (GLsizeiptr)total * 12, result);
    assert_int_equal(glGetError(), GL_NO_ERROR);
    glDeleteBuffers(5, vbo);
    glDeleteBuffers(1, &out);
    glDeleteVertexArrays(1, &vao);
    glDeleteTextures(tex[1] ? 2 : 1, tex);
    free(pos), free(w), free(inst), free(time), free(j);
    return result;
}

/* Largest |GPU - CPU runtime| over every sample and vertex. */
static double compare(const cb_palette *p, const cb_primitive *prim, const sample *samples, uint32_t n, const float *gpu)
{
    double *mats = malloc(p->bone_count * 16 * sizeof(double)), *cpu = malloc(prim->vertex_count * 3 * sizeof(double)), worst = 0;
    for (uint32_t s = 0; s < n; ++s) {
        cb_runtime_matrices(p, p->texels, &samples[s].inst, (float)samples[s].time, mats);
        cb_skin_positions(prim, mats, cpu);
        for (uint32_t i = 0; i < prim->vertex_count * 3; ++i)
            worst = fmax(worst, fabs(cpu[i] - gpu[(size_t)s * prim->vertex_count * 3 + i]));
    }
    free(mats), free(cpu);
    return worst;
}

/* Instances of every clip at many times: mid-frames, the loop seam, random phases. */
static uint32_t make_samples(const cb_palette *p, sample *out, uint32_t cap)
{
    uint32_t n = 0;
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        const cb_palette_clip *cl = &p->clips[c];
        cb_instance in = cb_instance_of(cl);
        double span = cl->frames / cl->fps;
        double times[] = {0.3 / cl->fps, 2.5 / cl->fps, span * 0.37, span - 0.4 / cl->fps /* the seam */, span * 1.5};
        for (int k = 0; k < 5 && n < cap; ++k) out[n++] = (sample){in, times[k]};
        for (int k = 0; k < 3 && n < cap; ++k) {
            cb_instance phased = in;
            phased.phase = fmod((k + 1) * 0.6180339887, 1.0);
            out[n++] = (sample){phased, 0.77 * (k + 1)};
        }
    }
    return n;
}

typedef struct fixture {
    cb_model *model;
    cb_palette palette;
} fixture;

static void bake(const char *path, cb_layout l, cb_precision pr, fixture *f)
{
    f->model = load_or_fail(path);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(f->model, 0, &err);
    cb_bake_options o = cb_default_bake_options();
    o.layout = l, o.precision = pr, o.root_motion = CB_ROOT_MOTION_IN_PLACE;
    cb_clip_plan step = {0, NULL, -1, 0, false, true, 0, NULL}; /* a STEP-keyed clip: rows held, as bakes plan it */
    bool held = f->model->animation_count == 1 && cb_clip_step_grid(f->model, 0, &step.fps);
    assert_int_equal(cb_palette_bake(s, &o, held ? &step : NULL, held ? 1 : 0, &f->palette, &err), CB_OK);
    cb_sampler_free(s);
}

static void release(fixture *f)
{
    cb_palette_free(&f->palette);
    cb_model_free(f->model);
}

static double tolerance(const fixture *f) { return 1e-5 * fmax(1.0, f->palette.model_height); }

static void test_every_layout_and_precision_matches_the_cpu(void **state)
{
    (void)state;
    char *lib = read_whole_file("runtimes/glsl/crowdbake_palette.glsl", NULL), path[1024];
    snprintf(path, sizeof path, "%s/quadruped.glb", samples_dir());
    sample samples[64];
    for (int l = 0; l < 3; ++l)
        for (int pr = 0; pr < 3; ++pr) {
            fixture f;
            bake(path, (cb_layout)l, (cb_precision)pr, &f);
            uint32_t n = make_samples(&f.palette, samples, 64);
            for (int es = 0; es < 2; ++es) {
                GLuint prog = compile(&f.palette, lib, es);
                float *gpu = gpu_skin(&f.palette, &f.model->primitives[0], samples, n, prog, false, 0);
                double worst = compare(&f.palette, &f.model->primitives[0], samples, n, gpu);
                printf("  %-6s %-5s %-8s %u instances x %u vertices: GPU vs CPU %.2g (tolerance %.2g)\n",
                       cb_layout_name((cb_layout)l), cb_precision_name((cb_precision)pr), es ? "ES 3.00" : "330 core", n,
                       f.model->primitives[0].vertex_count, worst, tolerance(&f));
                assert_true(worst <= tolerance(&f));
                free(gpu);
                glDeleteProgram(prog);
            }
            release(&f);
        }
    free(lib);
}

static double broken(const char *model, cb_layout l, cb_precision pr, const char *marker, const char *line, bool transpose,
                     double row_offset)
{
    char *lib = read_whole_file("runtimes/glsl/crowdbake_palette.glsl", NULL), path[1024];
    if (marker) {
        char *b = break_shader(lib, marker, line);
        free(lib);
        lib = b;
    }
    if (strchr(model, '/')) snprintf(path, sizeof path, "%s", model);
    else snprintf(path, sizeof path, "%s/%s", samples_dir(), model);
    fixture f;
    bake(path, l, pr, &f);
    sample samples[64];
    uint32_t n = make_samples(&f.palette, samples, 64);
    GLuint prog = compile(&f.palette, lib, false);
    float *gpu = gpu_skin(&f.palette, &f.model->primitives[0], samples, n, prog, transpose, row_offset);
    double worst = compare(&f.palette, &f.model->primitives[0], samples, n, gpu) / tolerance(&f);
    free(gpu), free(lib);
    glDeleteProgram(prog);
    release(&f);
    return worst;
}

static void test_broken_variants_are_caught(void **state)
{
    (void)state;
    double transposed = broken("quadruped.glb", CB_LAYOUT_MAT4, CB_PRECISION_FLOAT, NULL, NULL, true, 0);
    double off_by_one = broken("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_U16, NULL, NULL, false, 1);
    double no_wrap = broken("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_HALF, "cb:wrap", "        f1 = f0 + 1.0;", false, 0);
    char multitrack[1024];
    shared_path(multitrack, sizeof multitrack, "assets/multitrack-luanti/gltf_multi_track_1.glb");
    /* multitrack's bones spin a full turn per loop: their last and first rows are -q apart. */
    double no_flip = broken(multitrack, CB_LAYOUT_QPOS, CB_PRECISION_FLOAT, "cb:hemisphere", "", false, 0);
    /* qpos/half adds each bone's position offset back (version 3); version 2's bind position is wrong now. */
    double bind_offset = broken("quadruped.glb", CB_LAYOUT_QPOS, CB_PRECISION_HALF, "cb:offset -", "    ps.xyz += b;", false, 0);
    double matrix_offset = broken("quadruped.glb", CB_LAYOUT_MAT4, CB_PRECISION_HALF, "cb:offset-matrix",
                                  "    vec3 p = m[3].xyz + b;", false, 0);
    printf("  error / tolerance: transposed %.0f, rows off by one %.0f, no wrap %.0f, no hemisphere flip %.0f, bind position "
           "as offset %.0f (qpos), %.0f (mat4)\n", transposed, off_by_one, no_wrap, no_flip, bind_offset, matrix_offset);
    assert_true(transposed > 10 && off_by_one > 10 && no_wrap > 10 && no_flip > 10 && bind_offset > 10 && matrix_offset > 10);
    /* ...and the same multitrack palette with the shipped shader passes. */
    assert_true(broken(multitrack, CB_LAYOUT_QPOS, CB_PRECISION_FLOAT, NULL, NULL, false, 0) <= 1);
}

/* ---- batches for runtimes without instancing (crowdbake mesh --batch K, CB_BATCH) ---- */

#define BATCH 6

/* Vertex buffers of a mesh part's first `verts` vertices (the joints as ints), attributes 0-2. */
static void mesh_attributes(const cb_mesh_part *part, uint32_t verts, GLuint vbo[3])
{
    int32_t *j = malloc(verts * 4 * sizeof(int32_t));
    for (uint32_t i = 0; i < verts * 4; ++i) j[i] = part->joints[i];
    const void *data[3] = {part->positions, j, part->weights};
    const int comps[3] = {3, 4, 4};
    glGenBuffers(3, vbo);
    for (int a = 0; a < 3; ++a) {
        glBindBuffer(GL_ARRAY_BUFFER, vbo[a]);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)verts * comps[a] * 4, data[a], GL_STATIC_DRAW);
        glEnableVertexAttribArray((GLuint)a);
        if (a == 1) glVertexAttribIPointer(1, 4, GL_INT, 0, 0);
        else glVertexAttribPointer((GLuint)a, comps[a], GL_FLOAT, GL_FALSE, 0, 0);
    }
    free(j);
}

/* Draws with transform feedback on; returns 3 floats per vertex drawn. */
static float *capture(uint32_t total, void (*draw)(uint32_t), uint32_t arg)
{
    GLuint out;
    glGenBuffers(1, &out);
    glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, out);
    glBufferData(GL_TRANSFORM_FEEDBACK_BUFFER, (GLsizeiptr)total * 12, NULL, GL_STATIC_READ);
    glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, out);
    glEnable(GL_RASTERIZER_DISCARD);
    glBeginTransformFeedback(GL_POINTS);
    draw(arg);
    glEndTransformFeedback();
    glDisable(GL_RASTERIZER_DISCARD);
    float *result = malloc(total * 12);
    glGetBufferSubData(GL_TRANSFORM_FEEDBACK_BUFFER, 0, (GLsizeiptr)total * 12, result);
    assert_int_equal(glGetError(), GL_NO_ERROR);
    glDeleteBuffers(1, &out);
    return result;
}

static void draw_instanced(uint32_t verts) { glDrawArraysInstanced(GL_POINTS, 0, (GLsizei)verts, BATCH); }
static void draw_batch(uint32_t total) { glDrawArrays(GL_POINTS, 0, (GLsizei)total); }

/* BATCH instances of the first copy, one instanced draw: a_instance advances per instance. */
static float *gpu_instanced(const cb_palette *p, const cb_mesh_part *part, uint32_t verts, const float *inst, float time,
                            const char *library)
{
    GLuint prog = compile(p, library, false), vao, vbo[4], tex[2];
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    mesh_attributes(part, verts, vbo);
    glGenBuffers(1, &vbo[3]);
    glBindBuffer(GL_ARRAY_BUFFER, vbo[3]);
    glBufferData(GL_ARRAY_BUFFER, BATCH * 16, inst, GL_STATIC_DRAW);
    glEnableVertexAttribArray(3);
    glVertexAttribPointer(3, 4, GL_FLOAT, GL_FALSE, 0, 0);
    glVertexAttribDivisor(3, 1);
    glDisableVertexAttribArray(4);
    glVertexAttrib1f(4, time); /* a_time: the same for every vertex */
    use_palette(p, prog, false, tex);
    float *out = capture(verts * BATCH, draw_instanced, verts);
    glDeleteBuffers(4, vbo);
    glDeleteVertexArrays(1, &vao);
    glDeleteTextures(tex[1] ? 2 : 1, tex);
    glDeleteProgram(prog);
    return out;
}

/* The batch mesh, one plain draw: each vertex finds its copy's numbers by its _INSTANCE_ID. */
static float *gpu_batch(const cb_palette *p, const cb_mesh_part *part, const float *inst, float time, const char *library)
{
    static char src[1 << 16];
    snprintf(src, sizeof src,
             "#version 300 es\n#define %s\n#define %s\n#define CB_BATCH %d\n%s%s\n"
             "in vec3 a_position; in ivec4 a_joints; in vec4 a_weights; in float a_instance_id; uniform float u_time;\n"
             "out vec3 v_skinned;\n"
             "void main() { v_skinned = cb_skin_position(a_position, a_joints, a_weights, cb_batch_instance(a_instance_id), "
             "u_time); gl_Position = vec4(0.0); }\n",
             layout_define[p->layout], precision_define[p->precision], BATCH,
             p->positions_relative ? "#define CB_POSITIONS_RELATIVE\n" : "", library);
    GLuint prog = link_program(src, true), vao, vbo[4], tex[2];
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    mesh_attributes(part, part->vertex_count, vbo);
    glGenBuffers(1, &vbo[3]);
    glBindBuffer(GL_ARRAY_BUFFER, vbo[3]);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)part->vertex_count * 4, part->instance_ids, GL_STATIC_DRAW);
    glEnableVertexAttribArray(5);
    glVertexAttribPointer(5, 1, GL_FLOAT, GL_FALSE, 0, 0);
    use_palette(p, prog, false, tex);
    glUniform4fv(glGetUniformLocation(prog, "cb_batch_instances"), BATCH, inst);
    glUniform1f(glGetUniformLocation(prog, "u_time"), time);
    float *out = capture(part->vertex_count, draw_batch, part->vertex_count);
    glDeleteBuffers(4, vbo);
    glDeleteVertexArrays(1, &vao);
    glDeleteTextures(tex[1] ? 2 : 1, tex);
    glDeleteProgram(prog);
    return out;
}

/* The largest |batch - instanced| over every copy and vertex, and |batch - CPU runtime|. */
static void batch_vs_instanced(const char *library, double *vs_instanced, double *vs_cpu, double *tol)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/quadruped.glb", samples_dir());
    fixture f;
    bake(path, CB_LAYOUT_QPOS, CB_PRECISION_U16, &f);
    cb_mesh mesh;
    cb_error err = {0};
    cb_mesh_options o = {4, false, false, BATCH, NULL, f.palette.bone_count};
    assert_int_equal(cb_mesh_build(f.model, 0, &o, &mesh, &err), CB_OK);
    const cb_mesh_part *part = &mesh.parts[0];
    uint32_t verts = part->vertex_count / BATCH;
    sample samples[64];
    make_samples(&f.palette, samples, 64);
    float inst[BATCH * 4], time = 1.37f;
    for (int i = 0; i < BATCH; ++i) { /* a different clip, phase and rate per copy */
        const cb_instance *in = &samples[(i * 7) % 40].inst;
        float v[4] = {(float)in->first_row, (float)in->frame_count, (float)in->rate, (float)fmod(0.618034 * i, 1.0)};
        memcpy(inst + i * 4, v, sizeof v);
    }
    float *a = gpu_instanced(&f.palette, part, verts, inst, time, library);
    float *b = gpu_batch(&f.palette, part, inst, time, library);
    *vs_instanced = 0;
    for (uint32_t k = 0; k < verts * BATCH * 3; ++k) *vs_instanced = fmax(*vs_instanced, fabs((double)a[k] - b[k]));
    cb_primitive first = {.vertex_count = verts, .positions = part->positions, .joints = part->joints, .weights = part->weights};
    sample s[BATCH];
    for (int i = 0; i < BATCH; ++i) s[i] = (sample){{inst[i * 4], inst[i * 4 + 1], inst[i * 4 + 2], inst[i * 4 + 3]}, time};
    *vs_cpu = compare(&f.palette, &first, s, BATCH, b);
    *tol = tolerance(&f);
    free(a), free(b);
    cb_mesh_free(&mesh);
    release(&f);
}

static void test_a_batch_in_one_draw_equals_instances(void **state)
{
    (void)state;
    char *lib = read_whole_file("runtimes/glsl/crowdbake_palette.glsl", NULL);
    double vs_instanced, vs_cpu, tol;
    batch_vs_instanced(lib, &vs_instanced, &vs_cpu, &tol);
    printf("  %d copies in one draw: vs %d instances %.2g, vs CPU %.2g (tolerance %.2g)\n", BATCH, BATCH, vs_instanced,
           vs_cpu, tol);
    assert_true(vs_instanced <= tol && vs_cpu <= tol);
    /* Broken variant: every copy reads the first copy's numbers. */
    char *broken_lib = break_shader(lib, "cb:batch-id", "    return cb_batch_instances[0];");
    batch_vs_instanced(broken_lib, &vs_instanced, &vs_cpu, &tol);
    printf("  with the instance id ignored: error / tolerance %.0f\n", vs_instanced / tol);
    assert_true(vs_instanced > 10 * tol && vs_cpu > 10 * tol);
    free(lib), free(broken_lib);
}

/* ---- far LODs: CB_INFLUENCES reads only the first bones of a `mesh --max-influences` mesh ---- */

static void test_fewer_influences_read_fewer_bones(void **state)
{
    (void)state;
    char *lib = read_whole_file("runtimes/glsl/crowdbake_palette.glsl", NULL), path[1024];
    snprintf(path, sizeof path, "%s/quadruped.glb", samples_dir());
    fixture f;
    bake(path, CB_LAYOUT_QPOS, CB_PRECISION_U16, &f);
    sample samples[64];
    uint32_t n = make_samples(&f.palette, samples, 64);
    double tol = tolerance(&f), reduced[3] = {0}, full_mesh_with_one = 0;
    size_t size = strlen(lib) + 64;
    char *with = malloc(size);
    for (uint32_t k = 0; k < 2; ++k) {
        uint32_t inf = k ? 2 : 1;
        cb_mesh mesh;
        cb_error err = {0};
        cb_mesh_options o = {inf, false, false, 1, NULL, f.palette.bone_count};
        assert_int_equal(cb_mesh_build(f.model, 0, &o, &mesh, &err), CB_OK);
        cb_primitive prim = {.vertex_count = mesh.parts[0].vertex_count, .positions = mesh.parts[0].positions,
                             .joints = mesh.parts[0].joints, .weights = mesh.parts[0].weights};
        snprintf(with, size, "#define CB_INFLUENCES %u\n%s", inf, lib);
        GLuint prog = compile(&f.palette, with, true);
        float *gpu = gpu_skin(&f.palette, &prim, samples, n, prog, false, 0);
        reduced[k] = compare(&f.palette, &prim, samples, n, gpu);
        free(gpu);
        if (inf == 1) { /* broken variant: the model's own 4-influence mesh through the 1-bone shader */
            gpu = gpu_skin(&f.palette, &f.model->primitives[0], samples, n, prog, false, 0);
            full_mesh_with_one = compare(&f.palette, &f.model->primitives[0], samples, n, gpu);
            free(gpu);
        }
        glDeleteProgram(prog);
        cb_mesh_free(&mesh);
    }
    printf("  CB_INFLUENCES 1 / 2 on meshes of 1 / 2 influences: GPU vs CPU %.2g / %.2g (tolerance %.2g); a 4-influence "
           "mesh through CB_INFLUENCES 1: error / tolerance %.0f\n", reduced[0], reduced[1], tol, full_mesh_with_one / tol);
    assert_true(reduced[0] <= tol && reduced[1] <= tol && full_mesh_with_one > 10 * tol);
    free(with), free(lib);
    release(&f);
}

/* A STEP-keyed clip's rows are held: the shader takes the row at or before the time alone, as
 * the CPU runtime does (test_bare_bake holds that to the independent reference); blending them,
 * as before version 4, misses by the size of a step. */
static void test_held_rows_match_the_cpu(void **state)
{
    (void)state;
    char path[1024];
    shared_path(path, sizeof path, "assets/simpleskin-step-luanti/gltf_simple_skin_step.gltf");
    double held = broken(path, CB_LAYOUT_QPOS, CB_PRECISION_U16, NULL, NULL, false, 0);
    double blended = broken(path, CB_LAYOUT_QPOS, CB_PRECISION_U16, "cb:held", "", false, 0);
    printf("  STEP SimpleSkin, held rows: GPU vs CPU %.2g tolerances; blended: %.3g\n", held, blended);
    assert_true(held <= 1);
    assert_true(blended > 100);
}

/* ---- timed rows (.pal version 7): each clip's rows on cells of a grid, the map before them says which two blend ---- */

/* A timed copy of `src`: each clip's rows kept at cells 0, 1, 3, 6, 7, 9, 12, ... (steps of 1, 2 and 3 in turn) of a
 * grid at its own rate, a one-shot's last row at its end, with the map rows before them (timed_map_fill), in column
 * blocks of `height` rows (0: one block); `held` marks the first clip's rows held. Its clips and texels are its own;
 * the rest is src's (free with timed_release). */
static void timed_copy(const cb_palette *src, uint32_t height, bool held, cb_palette *dst)
{
    *dst = *src;
    dst->row_travel = NULL;
    dst->clips = calloc(src->clip_count, sizeof *dst->clips);
    uint32_t *cells = calloc(src->rows, sizeof *cells), *from = calloc(src->rows, sizeof *from), rows = 0;
    for (uint32_t c = 0; c < src->clip_count; ++c) {
        cb_palette_clip *k = &dst->clips[c];
        *k = src->clips[c];
        k->timed = true, k->step = held && c == 0, k->cell_rate = k->fps;
        k->cells = k->loops ? k->frames : k->frames - 1;
        k->map_rows = cb_timed_map_rows(k->cells, src->row_texels);
        k->first_row = rows + k->map_rows;
        k->frames = 0;
        for (uint32_t cell = 0, step = 0; cell < k->cells; cell += 1 + step++ % 3) {
            cells[k->first_row + k->frames] = cell;
            from[k->first_row + k->frames++] = src->clips[c].first_row + cell;
        }
        if (!k->loops) { /* a one-shot ends on its last row, at cell `cells` */
            cells[k->first_row + k->frames] = k->cells;
            from[k->first_row + k->frames++] = src->clips[c].first_row + k->cells;
        }
        rows = k->first_row + k->frames;
    }
    dst->rows = rows, dst->height = height ? height : rows, dst->blocks = (rows + dst->height - 1) / dst->height;
    dst->width = dst->blocks * src->row_texels;
    size_t tb = cb_precision_texel_bytes(src->precision);
    dst->texel_bytes = (size_t)dst->width * dst->height * tb;
    dst->texels = calloc(1, dst->texel_bytes);
    for (uint32_t c = 0; c < dst->clip_count; ++c) {
        const cb_palette_clip *k = &dst->clips[c];
        for (uint32_t r = k->first_row; r < k->first_row + k->frames; ++r) {
            uint32_t sx, sy, dx, dy;
            cb_palette_texel_xy(src, from[r], 0, &sx, &sy);
            cb_palette_texel_xy(dst, r, 0, &dx, &dy);
            memcpy((unsigned char *)dst->texels + ((size_t)dy * dst->width + dx) * tb,
                   (const unsigned char *)src->texels + ((size_t)sy * src->width + sx) * tb, src->row_texels * tb);
        }
        timed_map_fill(dst, k, cells + k->first_row);
    }
    free(cells), free(from);
}

static void timed_release(cb_palette *p) { free(p->clips), free(p->texels); }

/* Instances of every timed clip: cell interiors, cell starts, the loop seam, past a one-shot's ends, golden phases,
 * at rates 1 and 1.37. */
static uint32_t timed_samples(const cb_palette *p, sample *out, uint32_t cap)
{
    uint32_t n = 0;
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        const cb_palette_clip *k = &p->clips[c];
        cb_instance in = cb_instance_of(k);
        double cell = 1 / k->cell_rate, span = k->cells * cell;
        double times[] = {0.3 * cell, 2.5 * cell, 4 * cell, span * 0.37, span - 0.4 * cell /* the seam */, span * 1.5,
                          -cell, span};
        for (int t = 0; t < 8 && n < cap; ++t) out[n++] = (sample){in, times[t]};
        for (int t = 0; t < 3 && n < cap; ++t) {
            cb_instance phased = in;
            phased.phase = fmod((t + 1) * 0.6180339887, 1.0), phased.rate *= 1.37;
            out[n++] = (sample){phased, 0.77 * (t + 1)};
        }
    }
    return n;
}

/* |GPU - CPU runtime| / tolerance over a timed copy of the quadruped in `l` x `pr` (the library broken at `marker`). */
static double timed_error(cb_layout l, cb_precision pr, uint32_t height, bool held, const char *marker, const char *line)
{
    char *lib = read_whole_file("runtimes/glsl/crowdbake_palette.glsl", NULL), path[1024];
    if (marker) {
        char *b = break_shader(lib, marker, line);
        free(lib);
        lib = b;
    }
    snprintf(path, sizeof path, "%s/quadruped.glb", samples_dir());
    fixture f;
    bake(path, l, pr, &f);
    cb_palette timed;
    timed_copy(&f.palette, height, held, &timed);
    if (height) assert_true(timed.blocks >= 2);
    sample samples[64];
    uint32_t n = timed_samples(&timed, samples, 64);
    GLuint prog = compile(&timed, lib, false);
    float *gpu = gpu_skin(&timed, &f.model->primitives[0], samples, n, prog, false, 0);
    double worst = compare(&timed, &f.model->primitives[0], samples, n, gpu) / tolerance(&f);
    glDeleteProgram(prog);
    free(gpu), free(lib);
    timed_release(&timed);
    release(&f);
    return worst;
}

/* Timed rows through the shader's cb_frame (the map texel read from the palette texture) against the C runtime's
 * cb_runtime_frame_in, every precision, wrapped into column blocks, held; with the map ignored (the cell taken as
 * the row, as an untimed clip's), far off. */
static void test_timed_rows_match_the_cpu(void **state)
{
    (void)state;
    double worst = 0;
    for (int pr = 0; pr < 3; ++pr) {
        double e = timed_error(CB_LAYOUT_QPOS, (cb_precision)pr, 0, false, NULL, NULL);
        printf("  timed qpos %-5s: GPU vs CPU %.2f of the tolerance\n", cb_precision_name((cb_precision)pr), e);
        worst = fmax(worst, e);
    }
    double mat4 = timed_error(CB_LAYOUT_MAT4, CB_PRECISION_HALF, 0, false, NULL, NULL);
    double blocks = timed_error(CB_LAYOUT_AFFINE, CB_PRECISION_U16, 64, false, NULL, NULL);
    double held = timed_error(CB_LAYOUT_QPOS, CB_PRECISION_U16, 0, true, NULL, NULL);
    double ignored = timed_error(CB_LAYOUT_QPOS, CB_PRECISION_U16, 0, false, "cb:timed-map",
                                 "        vec4 m = vec4(cell, cell + 1.0, 0.0, 1.0);");
    printf("  timed mat4 half %.2f, affine u16 in column blocks of 64 rows %.2f, held %.2f of the tolerance; map "
           "ignored: %.0f\n", mat4, blocks, held, ignored);
    assert_true(worst <= 1 && mat4 <= 1 && blocks <= 1 && held <= 1);
    assert_true(ignored > 10);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_layout_and_precision_matches_the_cpu),
        cmocka_unit_test(test_broken_variants_are_caught),
        cmocka_unit_test(test_a_batch_in_one_draw_equals_instances),
        cmocka_unit_test(test_fewer_influences_read_fewer_bones),
        cmocka_unit_test(test_held_rows_match_the_cpu),
        cmocka_unit_test(test_timed_rows_match_the_cpu),
    };
    return cmocka_run_group_tests_name("gl", tests, setup, teardown);
}
