/* test_reference.c - crowdbake's sampler against joint matrices sampled by an independent
 * implementation (../shared/reference, see its README for the rules and the tolerance). */
#include "testutil.h"

#include <dirent.h>
#include <math.h>

#include "../../src/core/cb_math.h"

typedef struct ref_row {
    int clip, frame, frames, skin, joint;
    double t, m[16];
} ref_row;

typedef struct ref_file {
    char model[512];
    double fps;
    ref_row *rows;
    size_t count;
    double largest; /* largest |m| over the file: sets the tolerance */
} ref_file;

static void read_reference(const char *path, ref_file *rf)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    memset(rf, 0, sizeof *rf);
    size_t cap = 1024;
    rf->rows = malloc(cap * sizeof *rf->rows);
    char line[4096];
    bool header_seen = false;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == '#') {
            char *p = strstr(line, "model=");
            if (p) sscanf(p, "model=%511s fps=%lf", rf->model, &rf->fps);
            continue;
        }
        if (!header_seen) { /* the column names */
            header_seen = true;
            continue;
        }
        if (rf->count == cap) rf->rows = realloc(rf->rows, (cap *= 2) * sizeof *rf->rows);
        ref_row *r = &rf->rows[rf->count];
        char *p = line;
        r->clip = (int)strtol(p, &p, 10);
        p = strchr(p + 1, ','); /* skip clip_name (may be anything without commas) */
        assert_non_null(p);
        r->frame = (int)strtol(p + 1, &p, 10);
        r->frames = (int)strtol(p + 1, &p, 10);
        r->t = strtod(p + 1, &p);
        r->skin = (int)strtol(p + 1, &p, 10);
        r->joint = (int)strtol(p + 1, &p, 10);
        for (int k = 0; k < 16; ++k) {
            r->m[k] = strtod(p + 1, &p);
            if (fabs(r->m[k]) > rf->largest) rf->largest = fabs(r->m[k]);
        }
        rf->count++;
    }
    fclose(f);
    assert_true(rf->model[0] && rf->fps > 0 && rf->count > 0);
}

/* How crowdbake's matrices compare with one reference file. */
typedef struct comparison {
    double worst;           /* largest |crowdbake - reference| over every element of every row */
    size_t bad_rows;        /* rows with an element off by more than the tolerance */
    const ref_row *at;      /* the row of the worst element, */
    int element;            /* its index m0..m15 */
    double crowdbake_value; /* and what crowdbake computed there */
} comparison;

/* Compares every row; also checks the framing of each row. */
static comparison compare_rows(const ref_file *rf, cb_model *m, bool apply_mesh_node, double tol)
{
    comparison c = {0};
    cb_sampler *samplers[8] = {0};
    double mats[4096 * 16];
    int cached_clip = -1, cached_frame = -1, cached_skin = -1;
    for (size_t i = 0; i < rf->count; ++i) {
        const ref_row *r = &rf->rows[i];
        assert_true(r->skin >= 0 && r->skin < 8 && (uint32_t)r->skin < m->skin_count);
        assert_true(r->clip >= 0 && (uint32_t)r->clip < m->animation_count);
        if (!samplers[r->skin]) {
            cb_error err = {0};
            samplers[r->skin] = cb_sampler_create(m, r->skin, &err);
            assert_non_null(samplers[r->skin]);
        }
        if (r->clip != cached_clip || r->frame != cached_frame || r->skin != cached_skin) {
            const cb_animation *a = &m->animations[r->clip];
            uint32_t steps = cb_clip_step_count(a->t1 - a->t0, rf->fps);
            assert_int_equal(steps + 1, r->frames); /* the framing rule */
            assert_true(fabs(a->t0 + r->frame * (a->t1 - a->t0) / steps - r->t) < 1e-9);
            cb_sample_joint_matrices(samplers[r->skin], r->clip, r->t, mats);
            if (apply_mesh_node) { /* the wrong convention: mesh node transform on top */
                const double *g = cb_sample_globals(samplers[r->skin], r->clip, r->t);
                int32_t node = m->primitives[0].node;
                for (uint32_t j = 0; j < m->skins[r->skin].joint_count; ++j) {
                    double tmp[16];
                    cb_mat4_mul(tmp, g + (size_t)node * 16, mats + (size_t)j * 16);
                    memcpy(mats + (size_t)j * 16, tmp, sizeof tmp);
                }
            }
            cached_clip = r->clip, cached_frame = r->frame, cached_skin = r->skin;
        }
        bool bad = false;
        for (int k = 0; k < 16; ++k) {
            double value = mats[(size_t)r->joint * 16 + k], d = fabs(value - r->m[k]);
            bad |= d > tol;
            if (d > c.worst) c = (comparison){d, c.bad_rows, r, k, value};
        }
        c.bad_rows += bad;
    }
    for (int s = 0; s < 8; ++s) cb_sampler_free(samplers[s]);
    return c;
}

static double compare(const ref_file *rf, cb_model *m, bool apply_mesh_node)
{
    return compare_rows(rf, m, apply_mesh_node, 0).worst;
}

static int is_csv(const struct dirent *e)
{
    size_t len = strlen(e->d_name);
    return len > 4 && strcmp(e->d_name + len - 4, ".csv") == 0;
}

/* Every row of every file, no exemptions; each file's result is printed before any failure
 * is reported, so one run shows them all. */
static void test_every_reference_file_matches(void **state)
{
    (void)state;
    char dir[1024];
    shared_path(dir, sizeof dir, "reference");
    struct dirent **names;
    int files = scandir(dir, &names, is_csv, alphasort); /* sorted: the same report every run */
    if (files < 0) fail_msg("%s: cannot list the reference files", dir);
    size_t rows = 0;
    int failed_files = 0;
    for (int i = 0; i < files; ++i) {
        char path[2048];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]->d_name);
        ref_file rf;
        read_reference(path, &rf);
        char model_rel[1024];
        snprintf(model_rel, sizeof model_rel, "assets/%s", rf.model);
        cb_model *m = load_shared(model_rel);
        double tol = 1e-5 * fmax(1.0, rf.largest);
        comparison c = compare_rows(&rf, m, false, tol);
        printf("  %-32s %6zu rows compared, worst difference %.3g (tolerance %.3g)%s\n", names[i]->d_name, rf.count,
               c.worst, tol, c.bad_rows ? "" : ", all match");
        if (c.bad_rows) {
            printf("  ERROR: %s: %zu of %zu rows differ by more than %.3g; worst: clip %d frame %d skin %d joint %d "
                   "m%d = %.12g, crowdbake %.12g\n", names[i]->d_name, c.bad_rows, rf.count, tol, c.at->clip,
                   c.at->frame, c.at->skin, c.at->joint, c.element, c.at->m[c.element], c.crowdbake_value);
            ++failed_files;
        }
        rows += rf.count;
        cb_model_free(m);
        free(rf.rows);
        free(names[i]);
    }
    free(names);
    printf("  %d files, %zu rows compared\n", files, rows);
    if (failed_files) fail_msg("%d of %d reference files have rows crowdbake does not match", failed_files, files);
    assert_true(files >= 10);
}

/* The reference tells the two conventions apart: applying the mesh node's own transform
 * (rigged_figure has a rotated parent above its mesh node) must not match. */
static void test_mesh_node_transform_is_ignored(void **state)
{
    (void)state;
    char path[1024];
    shared_path(path, sizeof path, "reference/rigged_figure.fps30.csv");
    ref_file rf;
    read_reference(path, &rf);
    cb_model *m = load_shared("assets/riggedfigure-raylib/rigged_figure.glb");
    double tol = 1e-5 * fmax(1.0, rf.largest);
    assert_true(compare(&rf, m, false) <= tol);
    assert_true(compare(&rf, m, true) > 100 * tol);
    cb_model_free(m);
    free(rf.rows);
}

/* SimpleSkin's rotation keys are not unit length in the file. Python reads the raw keys
 * straight from the file's data URI; sampling with them must miss the reference by more than
 * the tolerance, so the reference test would catch a missing normalization. */
static const char raw_keys_py[] =
    "python3 -c \"import json,base64,struct,sys\n"
    "g=json.load(open(sys.argv[1]));a=g['animations'][0];s=a['samplers'][a['channels'][0]['sampler']]\n"
    "x=g['accessors'][s['output']];v=g['bufferViews'][x['bufferView']]\n"
    "d=base64.b64decode(g['buffers'][v['buffer']]['uri'].split(',',1)[1])\n"
    "print(*struct.unpack_from('<%%df'%%(4*x['count']),d,v.get('byteOffset',0)+x.get('byteOffset',0)))\" %s";

static void test_unnormalized_keys_would_be_caught(void **state)
{
    (void)state;
    char path[1024], model[1024], cmd[2600], out[8192];
    shared_path(path, sizeof path, "reference/SimpleSkin.fps30.csv");
    shared_path(model, sizeof model, "assets/simpleskin-bevy/SimpleSkin.gltf");
    ref_file rf;
    read_reference(path, &rf);
    cb_model *m = load_shared("assets/simpleskin-bevy/SimpleSkin.gltf");
    double tol = 1e-5 * fmax(1.0, rf.largest);
    assert_true(compare(&rf, m, false) <= tol);

    snprintf(cmd, sizeof cmd, raw_keys_py, model);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    cb_channel *ch = &m->animations[0].channels[0];
    assert_int_equal(ch->path, CB_PATH_ROTATION);
    char *at = out;
    double worst_length = 0;
    for (uint32_t i = 0; i < ch->key_count * 4; ++i) ch->values[i] = strtof(at, &at);
    for (uint32_t k = 0; k < ch->key_count; ++k) {
        const float *q = ch->values + k * 4;
        double length = sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3]);
        worst_length = fmax(worst_length, fabs(length - 1));
    }
    assert_true(worst_length > 1e-4); /* the file's keys really are off unit length */
    double raw_error = compare(&rf, m, false);
    printf("  raw keys (|q| off by %.3g): worst %.3g against tolerance %.3g\n", worst_length, raw_error, tol);
    assert_true(raw_error > 2 * tol); /* 5.7x on this file */
    cb_model_free(m);
    free(rf.rows);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_reference_file_matches),
        cmocka_unit_test(test_mesh_node_transform_is_ignored),
        cmocka_unit_test(test_unnormalized_keys_would_be_caught),
    };
    return cmocka_run_group_tests_name("reference", tests, NULL, NULL);
}
